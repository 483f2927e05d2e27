// unit tests of parts of the fixes that need a LAMMPS instance but no run:
// the per-atom state table (values kept through growth, copies, exchange
// and restart packing, new atoms at their init values, memory count), the
// other fixes that the integrators watch for velocity changes, the
// stability guard's bound on how far atoms moved since the list build, and
// the node sampler's guard of positions and forces, the interaction split
// and the energy tally of a node evaluated in two parts

#include "force.h"
#include "group.h"
#include "neighbor.h"
#include "pair.h"
#include "pe_jump_atom_state.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_growth_watch.h"
#include "pe_jump_interaction_split.h"
#include "pe_jump_node_sampler.h"
#include "pe_jump_other_fixes.h"
#include "pe_jump_quadrature.h"
#include "pe_jump_split_tally.h"
#include "pe_jump_stability_guard.h"
#include "pe_jump_systems.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace PEJumpTest;
using LAMMPS_NS::PEJump::AtomState;
using LAMMPS_NS::PEJump::ForceSampler;
using LAMMPS_NS::PEJump::GrowthWatch;
using LAMMPS_NS::PEJump::InteractionSplit;
using LAMMPS_NS::PEJump::NodeSampler;
using LAMMPS_NS::PEJump::OtherFixes;
using LAMMPS_NS::PEJump::SplitTally;
using LAMMPS_NS::PEJump::StabilityGuard;

TEST(AtomState, KeepsValuesThroughGrowthCopyAndPacking)
{
  Sim s;
  AtomState state(s.lmp);
  const int vec = state.add("vec", 3, 0.0);
  const int one = state.add("one", 1, -1.0);
  EXPECT_EQ(state.values(), 4);

  state.ensure(10);
  for (int i = 0; i < 10; ++i) {
    for (int k = 0; k < 3; ++k) state.vec(vec)[i][k] = 100.0 * i + k;
    state.val(one)[i] = 0.5 * i;
  }
  // growth keeps the values and gives the new room the init values
  state.ensure(5000);
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(state.vec(vec)[i][2], 100.0 * i + 2);
    EXPECT_EQ(state.val(one)[i], 0.5 * i);
  }
  EXPECT_EQ(state.vec(vec)[4999][1], 0.0);
  EXPECT_EQ(state.val(one)[4999], -1.0);
  // memory: room for at most a sixteenth more than asked, plus 64 atoms
  const double per_atom = 4 * sizeof(double);
  EXPECT_GE(state.memory_usage(), 5000 * per_atom);
  EXPECT_LE(state.memory_usage(), (5000 + 5000 / 16 + 64) * per_atom);

  // copy (as in atom sorting, into the slot after the last atom)
  state.copy(3, 7000);
  EXPECT_EQ(state.vec(vec)[7000][0], 300.0);
  EXPECT_EQ(state.val(one)[7000], 1.5);

  // exchange and restart packing: the same values in the same order
  std::vector<double> buf(state.values());
  EXPECT_EQ(state.pack(9, buf.data()), 4);
  EXPECT_EQ(buf[0], 900.0);
  EXPECT_EQ(buf[3], 4.5);
  EXPECT_EQ(state.unpack(9000, buf.data()), 4);
  EXPECT_EQ(state.vec(vec)[9000][2], 902.0);
  EXPECT_EQ(state.val(one)[9000], 4.5);

  // a new atom gets the init values; a field added later the init values too
  state.reset(9);
  EXPECT_EQ(state.vec(vec)[9][0], 0.0);
  EXPECT_EQ(state.val(one)[9], -1.0);
  const int late = state.add("late", 3, std::nan(""));
  EXPECT_TRUE(std::isnan(state.vec(late)[9000][1]));
  EXPECT_EQ(state.vec(vec)[9000][2], 902.0);

  // two fields of one width swap their values
  const int other = state.add("other", 3, 7.0);
  state.swap(vec, other);
  EXPECT_EQ(state.vec(vec)[9000][0], 7.0);
  EXPECT_EQ(state.vec(other)[9000][2], 902.0);
}

// fixes that only read the atoms (averages, output, dynamic group updates,
// load balancing) are not watched for velocity changes: watching costs a
// fingerprint of every velocity per step and keeps a midpoint step from
// being begun ahead; a fix that may change velocities is watched
TEST(OtherFixes, FixesThatOnlyReadAreNotWatched)
{
  Sim s;
  lj_liquid(s, 3);
  s.cmds({"fix int all pe_jump", "compute msd all msd", "variable inside atom x<2.0",
          "group near dynamic all var inside every 10",
          "fix avt all ave/time 5 2 10 c_thermo_temp c_msd[4]", "fix ava all ave/atom 2 5 10 vx",
          "compute bins all chunk/atom bin/1d x lower 0.5", "fix avc all ave/chunk 2 5 10 bins vx",
          "fix cor all ave/correlate 2 5 10 c_thermo_temp", "fix vec all vector 5 c_thermo_temp",
          "fix out all print 10 'a line'", "fix kept all store/state 10 vx",
          "variable one equal 1.0", "fix stop all halt 10 v_one > 1e9",
          "fix bal all balance 10 1.1 shift x 5 1.1", "run 0 post no"});
  auto *self = s.lmp->modify->get_fix_by_id("int");
  ForceSampler sampler(s.lmp);
  OtherFixes readers(s.lmp, self);
  readers.sort(sampler);
  EXPECT_FALSE(readers.may_change_velocities(OtherFixes::BETWEEN_STEPS | OtherFixes::INSIDE_STEP));
  for (const char *changer :
       {"fix mom all momentum 10 linear 1 1 1", "fix scale all temp/rescale 10 1.0 1.0 0.1 1.0"}) {
    s.cmd(changer);
    OtherFixes others(s.lmp, self);
    others.sort(sampler);
    EXPECT_TRUE(others.may_change_velocities(OtherFixes::BETWEEN_STEPS)) << changer;
    s.cmd(std::string("unfix ") + (changer[4] == 'm' ? "mom" : "scale"));
  }
}

// the guard skips the measure of how far the nodes are from the positions
// of the last list build where the atoms cannot have come near half the
// skin (each step moves them by at most h times the largest speed): its
// verdict (beyond half the skin or not) is always that of the measure, for
// the set measured every step. Atoms move with random speeds up to the
// largest, one of them straight at it (where the bounds are tight), until
// they pass half the skin; a list build, forgotten speeds and a new run
// measure again.
TEST(StabilityGuard, ExcursionSinceGivesTheVerdictOfTheMeasure)
{
  Sim s;
  lj_liquid(s, 3);
  s.cmds({"neighbor 0.3 bin", "run 0 post no"});
  auto *atom = s.lmp->atom;
  double **xhold = s.lmp->neighbor->get_xhold();
  const int n = atom->nlocal;
  const double limit = 0.15 * 0.15, h = s.lmp->update->dt, speed = 1.0;
  std::vector<double> vbuf(3 * n), jbuf(3 * n, 0.0);
  std::vector<double *> vrow(n), jrow(n);
  for (int i = 0; i < n; ++i) {
    vrow[i] = &vbuf[3 * i];
    jrow[i] = &jbuf[3 * i];
  }
  const LAMMPS_NS::PEJump::FreeFlight flight{vrow.data(), jrow.data(), nullptr, false};
  const LAMMPS_NS::PEJump::AtomSet all{1, nullptr};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);

  StabilityGuard guard(s.lmp);
  guard.start_run(true);
  int early = 0;    // measures in the first 20 steps, far from the limit
  bool passed = false;
  for (int round = 0; round < 3; ++round) {
    // new directions each round; atom 0 flies straight at the largest speed
    for (int i = 0; i < n; ++i) {
      double norm = 0.0;
      for (int k = 0; k < 3; ++k) norm += (vrow[i][k] = uni(rng)) * vrow[i][k];
      const double scale = (i == 0) ? speed / sqrt(norm) : 0.5 * speed * fabs(uni(rng));
      for (int k = 0; k < 3; ++k) vrow[i][k] *= scale;
    }
    guard.set_stats(speed * speed, 0.0);
    for (int step = 0; step < 40; ++step) {
      guard.step(h);
      const double since = guard.excursion_since(all, flight, xhold, 0.0, h);
      const double exact = guard.excursion(all, flight, xhold, 0.0, h);
      EXPECT_EQ(since > limit, exact > limit) << "round " << round << " step " << step;
      if (since != 0.0) {
        if ((round == 0) && (step < 20)) ++early;
        EXPECT_EQ(since, exact);
      }
      passed = passed || (exact > limit);
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) atom->x[i][k] += h * vrow[i][k];
    }
  }
  // the straight flier passed half the skin (0.15 in 30 steps of 0.005);
  // far from it only the first step was measured
  EXPECT_TRUE(passed);
  EXPECT_EQ(early, 1);

  // a list build measures again (the positions there are the new reference)
  s.lmp->neighbor->build(1);
  xhold = s.lmp->neighbor->get_xhold();
  guard.set_stats(speed * speed, 0.0);
  guard.step(h);
  EXPECT_GT(guard.excursion_since(all, flight, xhold, 0.0, h), 0.0);
  guard.step(h);
  EXPECT_EQ(guard.excursion_since(all, flight, xhold, 0.0, h), 0.0);
  // forgotten speeds measure again, as does a new run and an untrusted one
  guard.forget_stats();
  guard.set_stats(speed * speed, 0.0);
  EXPECT_GT(guard.excursion_since(all, flight, xhold, 0.0, h), 0.0);
  guard.start_run(true);
  guard.set_stats(speed * speed, 0.0);
  EXPECT_GT(guard.excursion_since(all, flight, xhold, 0.0, h), 0.0);
  guard.start_run(false);
  guard.set_stats(speed * speed, 0.0);
  for (int step = 0; step < 3; ++step) {
    guard.step(h);
    EXPECT_GT(guard.excursion_since(all, flight, xhold, 0.0, h), 0.0);
  }
}

/* ----------------------------------------------------------------------
   a node sum inside the caller's Keep (pe_jump/async's coarse node): the
   sum of the first node replaces what the accumulator held, and equals the
   sum of a node sum with its own Keep onto zeros; forces_back() puts the
   forces back at once and not again as the Keep ends; after
   positions_taken() the Keep leaves the positions the caller set (from the
   kept ones) and puts nothing back
------------------------------------------------------------------------- */

TEST(NodeSampler, SumInTheCallersKeep)
{
  Sim s;
  lj_liquid(s, 3);
  s.cmds({"run 0 post no"});
  auto *atom = s.lmp->atom;
  const int n = atom->nlocal;
  ASSERT_GT(n, 10);
  std::vector<double> x0(3 * n), f0(3 * n), vbuf(3 * n), jbuf(3 * n, 0.0);
  std::vector<double> with_own(3 * n, 0.0), in_callers(3 * n, 7.0);
  std::vector<double *> vrow(n), jrow(n), own_row(n), callers_row(n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      x0[3 * i + k] = atom->x[i][k];
      f0[3 * i + k] = atom->f[i][k];
      vbuf[3 * i + k] = atom->v[i][k];
    }
    vrow[i] = &vbuf[3 * i];
    jrow[i] = &jbuf[3 * i];
    own_row[i] = &with_own[3 * i];
    callers_row[i] = &in_callers[3 * i];
  }
  std::vector<int> listed;
  for (int i = 0; i < n; i += 2) listed.push_back(i);
  const LAMMPS_NS::PEJump::FreeFlight flight{vrow.data(), jrow.data(), nullptr, false};
  const LAMMPS_NS::PEJump::AtomSet set{1, &listed};
  const LAMMPS_NS::PEJump::Quadrature rule(LAMMPS_NS::PEJump::Quadrature::LEGENDRE, 2);
  const double h = 0.01;
  ForceSampler forces(s.lmp);
  NodeSampler nodes(s.lmp, &forces);
  const auto same_as_start = [&](double **a, const std::vector<double> &start, const char *what) {
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) ASSERT_EQ(a[i][k], start[3 * i + k]) << what << " of atom " << i;
  };

  EXPECT_EQ(
      nodes.sum_nodes(rule, 0, -1, h, 0.0, flight, set, ForceSampler::ALL, own_row.data(), nullptr),
      2);
  same_as_start(atom->x, x0, "position");
  same_as_start(atom->f, f0, "force");

  {
    NodeSampler::Keep keep(nodes, NodeSampler::positions_for(set), set.list);
    EXPECT_EQ(nodes.sum_nodes_in(keep, rule, 0, -1, h, 0.0, flight, set, ForceSampler::ALL,
                                 callers_row.data(), nullptr, false),
              2);
    keep.forces_back();
    same_as_start(atom->f, f0, "force put back");
    atom->f[1][0] = 12345.0;    // not to be put back again
    double **kept = keep.positions();
    for (const int i : listed)
      for (int k = 0; k < 3; ++k) atom->x[i][k] = kept[i][k] + 1.0;
    keep.positions_taken();
  }
  EXPECT_EQ(atom->f[1][0], 12345.0);
  for (int i = 0; i < n; ++i) {
    const double moved = (i % 2 == 0) ? 1.0 : 0.0;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(atom->x[i][k], x0[3 * i + k] + moved) << "atom " << i;
      if (i % 2 == 0)
        EXPECT_EQ(in_callers[3 * i + k], with_own[3 * i + k]) << "atom " << i;
      else
        EXPECT_EQ(in_callers[3 * i + k], 7.0) << "unlisted atom " << i;
    }
  }
  // the sums are the forces at the nodes: not the start's
  double change = 0.0;
  for (const int i : listed)
    for (int k = 0; k < 3; ++k) change += fabs(with_own[3 * i + k] - f0[3 * i + k]);
  EXPECT_GT(change, 1e-6);
}

/* ----------------------------------------------------------------------
   the interaction split: the FINE subset (pairs and bonds that involve a
   fine-clock atom) and the COARSE subset (the others) give the complete
   forces and energy between them, for a pair style and a bond style, and
   their fractions add up to the whole; the energies that SplitTally adds
   up from the two evaluations are those of one complete evaluation
------------------------------------------------------------------------- */

TEST(InteractionSplit, SubsetsAddUpToTheWhole)
{
  Sim s;
  lj_liquid(s, 3);
  s.cmds({"group fast id 1:30", "displace_atoms all random 0.1 0.1 0.1 4811 units box",
          "run 0 post no"});
  auto *lmp = s.lmp;
  const int nlocal = lmp->atom->nlocal;
  const int fastbit = lmp->group->bitmask[lmp->group->find("fast")];
  InteractionSplit split(lmp, 1, fastbit);
  split.build();
  EXPECT_NEAR(split.fraction(InteractionSplit::FINE) + split.fraction(InteractionSplit::COARSE),
              1.0, 1e-12);
  EXPECT_GT(split.fraction(InteractionSplit::FINE), 0.05);

  ForceSampler sampler(lmp);
  SplitTally tally(lmp);
  const auto forces = [&](InteractionSplit::Subset which, int eflag) {
    if (which != InteractionSplit::ALL) split.activate(which);
    sampler.compute(ForceSampler::ALL, eflag, 0);
    split.restore();
    return std::vector<double>(&lmp->atom->f[0][0], &lmp->atom->f[0][0] + 3 * nlocal);
  };
  const auto all = forces(InteractionSplit::ALL, 1);
  const double energy = lmp->force->pair->eng_vdwl;
  tally.expect(true);
  const auto fine = forces(InteractionSplit::FINE, 1);
  tally.keep();
  const auto coarse = forces(InteractionSplit::COARSE, 1);
  tally.add();
  ASSERT_TRUE(tally.complete());
  double worst = 0.0, scale = 0.0;
  for (int n = 0; n < 3 * nlocal; ++n) {
    worst = std::max(worst, std::fabs(fine[n] + coarse[n] - all[n]));
    scale = std::max(scale, std::fabs(all[n]));
  }
  EXPECT_LT(worst, 1e-12 * scale);
  EXPECT_NEAR(lmp->force->pair->eng_vdwl, energy, 1e-12 * std::fabs(energy));
}

/* ----------------------------------------------------------------------
   the growth watch: a share that holds (after the first window, where
   the jumps build up) is silent; a share that grows by 1.6 per window is
   caught once it is above MIN_SHARE and FACTOR times the share LAG
   windows back; a share that stays below MIN_SHARE is silent however it
   grows
------------------------------------------------------------------------- */

TEST(GrowthWatch, CatchesASustainedGrowthOfTheJumpShareOnly)
{
  // one window of samples with jump energy j and pseudo-kinetic energy
  // 1 - j (their sum, the kinetic energy, is 1): the window's share is j
  auto window = [](GrowthWatch &w, double j) {
    for (int n = 0; n < GrowthWatch::WINDOW; n++) w.sample(1.0 - j, j);
  };
  GrowthWatch held;
  window(held, 0.001);    // the first window is no reference
  for (int k = 0; k < 40; k++) window(held, (k % 2) ? 0.07 : 0.09);
  EXPECT_FALSE(held.growth());

  GrowthWatch growing;
  window(growing, 0.05);
  double share = 0.05;
  int caught = -1;
  for (int k = 1; (k < 20) && (caught < 0); k++) {
    window(growing, share);
    if (growing.growth()) caught = k;
    share *= 1.6;
  }
  // windows 1, 2, 3 hold 0.05, 0.08, 0.128: window 3 is the first above
  // 0.1 and above 2 x window 1 (LAG = 2 windows back)
  EXPECT_EQ(caught, 3);
  EXPECT_NEAR(growing.latest_share(), 0.128, 1e-12);
  EXPECT_NEAR(growing.reference_share(), 0.05, 1e-12);

  GrowthWatch small;
  share = 1e-4;
  for (int k = 0; k < 12; k++, share *= 1.6) window(small, share);
  EXPECT_LT(small.latest_share(), GrowthWatch::MIN_SHARE);
  EXPECT_FALSE(small.growth());
}
