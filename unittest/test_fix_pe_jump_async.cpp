// physics and interface tests of fix pe_jump/async through the LAMMPS C++
// API: classification, equality with fix pe_jump for K = 1, pseudo-energy
// conservation at coarse nodes, convergence orders, evaluation counts
// against the paper's formulas and against the work the force styles see,
// split runs and restarts, error messages. Every LAMMPS step is one coarse
// step: the time step is h_S, the fine step h_F = h_S/K

#include "pe_jump_systems.h"

#include "bond_class2.h"
#include "domain.h"
#include "exceptions.h"
#include "force.h"
#include "group.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "pair_lj_cut.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <regex>
#include <sstream>
#include <tuple>

using namespace PEJumpTest;
using ::testing::ContainsRegex;
using ::testing::Not;

namespace {

constexpr int M = 3;
constexpr double OMEGA2 = 10.0;
const std::vector<double> Q0 = {0.1, -0.05, 0.02, 0.3, -0.2, 0.1};
const std::vector<double> P0 = {0.5, 0.0, 0.0, 0.0, 1.0, 0.0};

void chain(Sim &s)
{
  slow_fast_chain(s, M, OMEGA2, Q0, P0);
}

// positions q_1..q_2m of the chain (x minus the lattice site)
std::vector<double> chain_q(Sim &s)
{
  std::vector<double> q;
  for (int id = 2; id <= 2 * M + 1; ++id) q.push_back(s.x(id, 0) - (id - 1) * FPU_SPACING);
  return q;
}

// chain at time T with fix pe_jump/async (K >= 1: fine step hf, time step
// the coarse step K hf) or fix pe_jump (K = 0: time step hf)
std::vector<double> chain_at(double T, double hf, int K, const std::string &rule)
{
  Sim s;
  chain(s);
  const std::string fix = K
      ? fmt::format("fix 1 chain pe_jump/async {} fast quadrature {}", K, rule)
      : "fix 1 chain pe_jump quadrature " + rule;
  const double h = K ? K * hf : hf;
  const int nsteps = static_cast<int>(std::lround(T / h));
  s.cmds(
      {fix, fmt::format("timestep {:.17g}", h), "thermo 0", fmt::format("run {} post no", nsteps)});
  return chain_q(s);
}

std::vector<double> chain_q_at_start()
{
  Sim s;
  chain(s);
  return chain_q(s);
}

}    // namespace

/* ----------------------------------------------------------------------
   hybrid styles are split like plain ones: the paper's slow/fast chain
   with bond_style hybrid harmonic class2 (stiff springs harmonic) and
   pair_style hybrid equals the chain with one bond style
------------------------------------------------------------------------- */

TEST(PEJumpAsync, HybridStylesEqualOneStyle)
{
  for (const std::string rule : {"midpoint", "lobatto 3"}) {
    std::vector<double> one, hybrid;
    for (const bool use_hybrid : {false, true}) {
      Sim s;
      chain(s);
      if (use_hybrid)
        s.cmds({"bond_style hybrid harmonic class2",
                fmt::format("bond_coeff 1 harmonic {:.17g} 1.5", 0.25 * OMEGA2),
                "bond_coeff 2 class2 1.5 0.0 0.0 1.0", "pair_style hybrid zero 1.0",
                "pair_coeff * * zero"});
      s.cmds({"fix 1 chain pe_jump/async 10 fast quadrature " + rule, "timestep 0.02", "thermo 0",
              "run 100 post no"});
      (use_hybrid ? hybrid : one) = chain_q(s);
    }
    EXPECT_LT(max_diff(one, hybrid), 1e-13) << rule;
    EXPECT_GT(max_diff(one, chain_q_at_start()), 1e-2) << rule;    // the chain moved
  }
}

/* ----------------------------------------------------------------------
   classes on the paper's chain: q_1, q_2 fast, q_3 mixed, q_4..q_6 slow;
   the step size f_ID[3] is the coarse step (the time step), and every
   step ends at a coarse node (f_ID[6] = 1)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, ClassifiesSlowMixedFast)
{
  Sim s;
  chain(s);
  s.cmds({"fix 1 chain pe_jump/async 10 fast", "timestep 1e-2", "thermo 0", "run 0 post no"});
  EXPECT_EQ(s.vec("1", 6), 3.0);    // slow
  EXPECT_EQ(s.vec("1", 7), 1.0);    // mixed
  EXPECT_EQ(s.vec("1", 8), 2.0);    // fast
  const double *klass = s.lmp->modify->get_fix_by_id("1")->vector_atom;
  const double expected[8] = {-1, 2, 2, 1, 0, 0, 0, -1};
  for (int id = 1; id <= 8; ++id) EXPECT_EQ(klass[s.lmp->atom->map(id)], expected[id - 1]) << id;
  for (const int steps : {3, 7}) {
    s.cmd(fmt::format("run {} post no", steps));
    EXPECT_EQ(s.vec("1", 2), 1e-2) << steps;    // h_S
    EXPECT_EQ(s.vec("1", 5), 1.0) << steps;     // at a coarse node
  }
}

/* ----------------------------------------------------------------------
   K = 1: every step is a coarse step, the scheme is fix pe_jump
------------------------------------------------------------------------- */

TEST(PEJumpAsync, OneFineStepPerCoarseStepIsTheSynchronousScheme)
{
  for (const std::string rule : {"midpoint", "lobatto 3", "legendre 2", "lobatto 5"}) {
    const auto sync = chain_at(5.0, 1e-3, 0, rule);
    const auto async = chain_at(5.0, 1e-3, 1, rule);
    EXPECT_LT(max_diff(sync, async), 1e-13) << rule;
  }
  // with pairs: an LJ liquid, a slab of it on the fine clock
  std::vector<double> out[2];
  for (int k = 0; k < 2; ++k) {
    Sim s;
    lj_liquid(s);
    s.cmds({"region slab block 0 2 INF INF INF INF units lattice", "group fast region slab",
            k ? "fix 1 all pe_jump/async 1 fast quadrature lobatto 3"
              : "fix 1 all pe_jump quadrature lobatto 3",
            "timestep 0.005", "thermo 0", "run 100 post no"});
    out[k] = unwrapped_positions(s);
  }
  EXPECT_LT(max_diff(out[0], out[1]), 1e-11);
}

/* ----------------------------------------------------------------------
   the neighbor lists hold every pair at every node, fine and coarse: with
   a small skin (0.15; the fastest slow atoms move about 0.06 over a coarse
   step of K = 5) the run equals one that rebuilds the lists at every step
------------------------------------------------------------------------- */

TEST(PEJumpAsync, ListsHoldEveryPairAtEveryNode)
{
  const auto run = [](const std::string &rule, const std::string &lists) {
    Sim s;
    lj_liquid(s, 3);
    s.cmds({"velocity all scale 0.5", "neighbor 0.15 bin", "neigh_modify " + lists,
            "region slab block 0 1 INF INF INF INF units lattice", "group fast region slab",
            "fix 1 all pe_jump/async 5 fast quadrature " + rule, "timestep 0.025", "thermo 0",
            "run 60"});
    return std::make_pair(unwrapped_positions(s), s.lmp->neighbor->ncalls);
  };
  for (const std::string rule : {"midpoint", "lobatto 3", "legendre 2"}) {
    const auto always = run(rule, "every 1 delay 0 check no");
    // LAMMPS checks the distances every step, or every 4th step: then the
    // fix asks for the rebuilds in between
    for (const std::string every : {"1", "4"}) {
      const auto checked = run(rule, "every " + every + " delay 0 check yes");
      const std::string what = rule + ", every " + every;
      EXPECT_GT(checked.second, 20) << what;               // the checks rebuild
      EXPECT_LT(checked.second, always.second) << what;    // but not every step
      EXPECT_LT(max_diff(checked.first, always.first), 1e-9) << what;
    }
  }
}

/* ----------------------------------------------------------------------
   pseudo-energy conserved at coarse nodes for exact quadrature: the quartic
   springs have cubic forces along straight lines, exact for lobatto 3
------------------------------------------------------------------------- */

namespace {
// max relative deviation of pe + f_1 at coarse nodes (the step ends) over
// ncoarse coarse steps
double coarse_node_drift(Sim &s, int ncoarse)
{
  s.cmds({"thermo 0", "run 0 post no"});
  const double h0 = s.eval("c_thermo_pe+f_1");
  double worst = 0.0;
  for (int n = 0; n < ncoarse; ++n) {
    s.cmd("run 1 pre no post no");
    EXPECT_EQ(s.vec("1", 5), 1.0);
    worst = std::max(worst, std::fabs(s.eval("c_thermo_pe+f_1") - h0));
  }
  return worst / std::fabs(h0);
}
}    // namespace

TEST(PEJumpAsync, PseudoEnergyConservedAtCoarseNodes)
{
  {
    Sim s;
    chain(s);
    s.cmds({"fix 1 chain pe_jump/async 50 fast quadrature lobatto 3", "timestep 1e-2"});
    const double drift = coarse_node_drift(s, 1000);
    std::cout << "slow/fast quartic chain, lobatto 3, K=50: " << drift << "\n";
    // 50000 fine steps, coordinates of order 10, energy 0.08: round-off of
    // the energy is ~1e-14 relative per step, a random walk of it ~3e-12
    // (fix pe_jump at h_F over the same time: 1e-12)
    EXPECT_LT(drift, 3e-12);
  }
  {
    // a harmonic ring (periodic), half of it fast, stiff springs there
    Sim s;
    harmonic_ring(s, 20, 10.0, 1.0, 7);
    s.cmds({"bond_coeff 1 10.0 1.0", "group fast id 1:10",
            "fix 1 all pe_jump/async 7 fast quadrature midpoint", "timestep 0.07"});
    const double drift = coarse_node_drift(s, 1000);
    std::cout << "harmonic ring, midpoint, K=7: " << drift << "\n";
    EXPECT_LT(drift, 3e-12);
  }
  {
    // the midpoint rule is not exact on quartic springs: the pseudo-energy
    // varies, which shows that the test above can fail
    Sim s;
    chain(s);
    s.cmds({"fix 1 chain pe_jump/async 50 fast quadrature midpoint", "timestep 1e-2"});
    EXPECT_GT(coarse_node_drift(s, 200), 1e-9);
  }
}

/* ----------------------------------------------------------------------
   second order: in h_S at fixed h_F (error against the synchronous scheme
   at h_F, as in the paper), and with h_S/h_F = 25 fixed (error against a
   converged reference)
------------------------------------------------------------------------- */

namespace {
double order(const std::vector<double> &h, const std::vector<double> &err)
{
  // least-squares slope of log(err) against log(h)
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = h.size();
  for (size_t i = 0; i < h.size(); ++i) {
    const double x = std::log(h[i]), y = std::log(err[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}
}    // namespace

TEST(PEJumpAsync, SecondOrderInCoarseStepAndAtFixedRatio)
{
  const double T = 2.0, hf = 1e-4;
  const auto ref = chain_at(T, hf, 0, "lobatto 5");
  std::vector<double> hs, err;
  for (int K : {25, 50, 100, 200}) {
    hs.push_back(K * hf);
    err.push_back(max_diff(ref, chain_at(T, hf, K, "lobatto 5")));
  }
  const double p1 = order(hs, err);
  std::cout << "errors in h_S at h_F = 1e-4:";
  for (double e : err) std::cout << " " << e;
  std::cout << "\norder in h_S at h_F = 1e-4: " << p1 << "\n";
  EXPECT_NEAR(p1, 2.0, 0.1);

  const auto exact = chain_at(T, 2e-5, 0, "lobatto 5");
  std::vector<double> hs2, err2;
  for (double h : {1e-2, 5e-3, 2.5e-3, 1.25e-3}) {
    hs2.push_back(h);
    err2.push_back(max_diff(exact, chain_at(T, h / 25, 25, "lobatto 5")));
  }
  const double p2 = order(hs2, err2);
  std::cout << "order at h_S/h_F = 25: " << p2 << "\n";
  EXPECT_NEAR(p2, 2.0, 0.1);

  // a buffer layer changes the partition, not the order
  std::vector<double> err3;
  for (double h : hs2)
    err3.push_back(max_diff(exact, chain_at(T, h / 25, 25, "lobatto 5 buffer 1")));
  const double p3 = order(hs2, err3);
  std::cout << "order at h_S/h_F = 25 with buffer 1: " << p3 << "\n";
  EXPECT_NEAR(p3, 2.0, 0.1);
}

/* ----------------------------------------------------------------------
   cost: the paper's N_a and N_s on the slow/fast chain, and the reported
   counts equal the interactions the force styles actually computed
------------------------------------------------------------------------- */

namespace {
class BondCounting : public LAMMPS_NS::BondClass2 {
 public:
  using BondClass2::BondClass2;
  static double computed;
  void compute(int eflag, int vflag) override
  {
    computed += neighbor->nbondlist;
    BondClass2::compute(eflag, vflag);
  }
};
double BondCounting::computed = 0.0;
LAMMPS_NS::Bond *bond_counting_creator(LAMMPS_NS::LAMMPS *lmp)
{
  return new BondCounting(lmp);
}

class PairCounting : public LAMMPS_NS::PairLJCut {
 public:
  using PairLJCut::PairLJCut;
  static double computed;
  void compute(int eflag, int vflag) override
  {
    for (int ii = 0; ii < list->inum; ++ii) computed += list->numneigh[list->ilist[ii]];
    PairLJCut::compute(eflag, vflag);
  }
};
double PairCounting::computed = 0.0;
LAMMPS_NS::Pair *pair_counting_creator(LAMMPS_NS::LAMMPS *lmp)
{
  return new PairCounting(lmp);
}
}    // namespace

TEST(PEJumpAsync, EvaluationCountsMatchThePaperAndTheWorkDone)
{
  // T = 1, h_S = 0.01, h_F = 2e-4, lobatto 5 (4 evaluations per step):
  // fix pe_jump takes T/h_F steps of h_F, pe_jump/async T/h_S of h_S
  const double T = 1.0, hs = 0.01, hf = 2e-4;
  const int n = 5;
  double count[2];
  for (int k = 0; k < 2; ++k) {
    Sim s;
    (*s.lmp->force->bond_map)["class2/counting"] = &bond_counting_creator;
    chain(s);
    const double h = k ? hs : hf;
    s.cmds({"bond_style class2/counting", "bond_coeff 1 1.5 2.5 0.0 0.0",
            "bond_coeff 2 1.5 0.0 0.0 1.0",
            k ? "fix 1 chain pe_jump/async 50 fast quadrature lobatto 5"
              : "fix 1 chain pe_jump quadrature lobatto 5",
            fmt::format("timestep {}", h), "thermo 0", "run 0 post no"});
    BondCounting::computed = 0.0;
    s.cmd(fmt::format("run {} pre no post no", std::lround(T / h)));
    count[k] = s.vec("1", 4);
    // reported evaluations x 7 springs = spring evaluations the bond style did
    EXPECT_NEAR(count[k] * 7.0, BondCounting::computed, 1e-6) << k;
  }
  // the energy output at the last step costs async one full evaluation
  // (fix pe_jump with a Lobatto rule has the energies at the end node)
  count[1] -= 1.0;
  const double Ns = (n - 1) * T * (2 * M + 1) / hf;
  const double Na = (n - 1) * T * ((M + 1) / hf + M / hs);
  EXPECT_NEAR(count[0] * 7.0, Ns, 1e-6);
  EXPECT_NEAR(count[1] * 7.0, Na, 1e-6);
  EXPECT_NEAR(count[1] / count[0], 0.58, 1e-12);

  // pairs: an LJ liquid with a fast slab, K = 5: only the fine subset on
  // fine steps, the slow-slow pairs once per coarse step
  Sim s;
  (*s.lmp->force->pair_map)["lj/cut/counting"] = &pair_counting_creator;
  lj_liquid(s);
  // a cold crystal keeps its pair count, so that the count is exact
  s.cmds({"velocity all scale 0.001", "pair_style lj/cut/counting 2.5",
          "pair_coeff 1 1 1.0 1.0 2.5", "region slab block 0 1 INF INF INF INF units lattice",
          "group fast region slab", "fix 1 all pe_jump/async 5 fast quadrature midpoint",
          "timestep 0.025", "thermo 0", "neigh_modify every 1 delay 0 check no", "run 0 post no"});
  // fine fraction: pairs of the (full) list that involve a fast atom
  auto *list = s.lmp->force->pair->list;
  const int *mask = s.lmp->atom->mask;
  const int fastbit = s.lmp->group->bitmask[s.lmp->group->find("fast")];
  double all = 0.0, fine = 0.0;
  for (int ii = 0; ii < list->inum; ++ii) {
    const int i = list->ilist[ii];
    for (int jj = 0; jj < list->numneigh[i]; ++jj) {
      const int j = list->firstneigh[i][jj] & NEIGHMASK;
      all += 1.0;
      if ((mask[i] | mask[j]) & fastbit) fine += 1.0;
    }
  }
  EXPECT_GT(fine / all, 0.2);
  EXPECT_LT(fine / all, 0.6);
  PairCounting::computed = 0.0;
  s.cmd("run 20 pre no post no");
  // the split is rebuilt with the lists every step: per fine step (5 in
  // each of the 20 steps) the fine pairs, per step the others, plus the
  // full energy evaluation at the last step; reported and seen by the pair
  // style alike
  const double reported = s.vec("1", 4);
  const double expected = 100 * (fine / all) + 20 * (1.0 - fine / all) + 1.0;
  EXPECT_NEAR(reported, expected, 1e-9 * expected);
  EXPECT_NEAR(reported, PairCounting::computed / all, 1e-9 * expected);
  EXPECT_LT(reported, 0.7 * 101);    // fix pe_jump at h_F: 101
}

/* ----------------------------------------------------------------------
   lobatto 2 ends its fine and coarse steps at the step end, where the last
   fine step and the MD step evaluate the fine and the coarse interactions:
   energy output adds their tallies up instead of evaluating everything
   once more. Output that needs the virial (compute pressure) still takes
   the evaluation of everything: the energies of both runs agree to
   round-off, the trajectories exactly, and the energy-only run saves one
   evaluation per output step
------------------------------------------------------------------------- */

TEST(PEJumpAsync, LobattoTwoTalliesTheStepEndEnergyFromItsEvaluations)
{
  constexpr int NSTEPS = 20, EVERY = 2;
  std::vector<double> pe[2], x[2];
  double evals[2];
  for (int virial = 0; virial < 2; ++virial) {
    Sim s;
    lj_liquid(s);
    s.cmds({"region slab block 0 1 INF INF INF INF units lattice", "group fast region slab",
            "fix 1 all pe_jump/async 5 fast quadrature lobatto 2", "timestep 0.025", "thermo 0",
            "thermo_style custom step pe", fmt::format("fix pe all vector {} c_thermo_pe", EVERY)});
    if (virial)
      s.cmds({"compute p all pressure thermo_temp", fmt::format("fix p all vector {} c_p", EVERY)});
    s.cmd(fmt::format("run {} post no", NSTEPS));
    evals[virial] = s.vec("1", 4);
    auto *kept = s.lmp->modify->get_fix_by_id("pe");
    for (int n = 0; n < kept->size_vector; ++n) pe[virial].push_back(kept->compute_vector(n));
    for (int id = 1; id <= s.lmp->atom->natoms; ++id)
      for (int k = 0; k < 3; ++k) x[virial].push_back(s.x(id, k));
  }
  ASSERT_EQ(pe[0].size(), pe[1].size());
  ASSERT_EQ(pe[0].size(), static_cast<size_t>(NSTEPS / EVERY + 1));
  for (size_t n = 0; n < pe[0].size(); ++n)
    EXPECT_NEAR(pe[0][n], pe[1][n], 1e-12 * std::fabs(pe[1][n])) << n;
  EXPECT_EQ(x[0], x[1]);
  EXPECT_NEAR(evals[1] - evals[0], NSTEPS / EVERY, 1e-9);
}

/* ----------------------------------------------------------------------
   compute pair reads the tally of one sub-style of a hybrid pair style,
   which the added-up tallies of the step end do not reach: beside it the
   energy output of lobatto 2 evaluates everything at the step end again,
   and the sub-style's energy is that of the output with the virial (it
   read the coarse interactions' part only, -1.44 for -2.77, before)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, ComputePairOfAHybridSubStyleSeesAllItsPairs)
{
  std::vector<double> sub[2];
  for (int virial = 0; virial < 2; ++virial) {
    Sim s;
    lj_liquid(s);
    s.cmds({"pair_style hybrid/overlay lj/cut 2.5 soft 1.0", "pair_coeff * * lj/cut 1.0 1.0 2.5",
            "pair_coeff * * soft 0.5", "region slab block 0 1 INF INF INF INF units lattice",
            "group fast region slab", "fix 1 all pe_jump/async 5 fast quadrature lobatto 2",
            "timestep 0.025", "thermo 0", "thermo_style custom step pe",
            "compute plj all pair lj/cut", "fix e all vector 5 c_plj"});
    if (virial) s.cmds({"compute p all pressure thermo_temp", "fix p all vector 5 c_p"});
    s.cmd("run 20 post no");
    auto *kept = s.lmp->modify->get_fix_by_id("e");
    for (int n = 0; n < kept->size_vector; ++n) sub[virial].push_back(kept->compute_vector(n));
  }
  ASSERT_EQ(sub[0].size(), 5u);
  ASSERT_EQ(sub[1].size(), 5u);
  for (size_t n = 0; n < sub[0].size(); ++n)
    EXPECT_NEAR(sub[0][n], sub[1][n], 1e-12 * std::fabs(sub[1][n])) << n;
}

/* ----------------------------------------------------------------------
   split runs and restarts at any step (every step ends at a coarse node)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, SplitRunsAndRestartsAreExact)
{
  for (const std::string rule :
       {"midpoint", "lobatto 3", "lobatto 3 buffer 1", "midpoint damp 0.05"}) {
    const std::string fix = "fix 1 chain pe_jump/async 20 fast quadrature " + rule;
    std::vector<double> unbroken, split, restarted;
    {
      Sim s;
      chain(s);
      s.cmds({fix, "timestep 1e-2", "thermo 0", "run 50 post no"});
      unbroken = chain_q(s);
    }
    {
      Sim s;
      chain(s);
      s.cmds({fix, "timestep 1e-2", "thermo 0", "run 17 post no", "run 33 post no"});
      split = chain_q(s);
    }
    {
      Sim s;
      chain(s);
      s.cmds({fix, "timestep 1e-2", "thermo 0", "run 17 post no"});
      EXPECT_EQ(s.vec("1", 5), 1.0);    // at a coarse node
      s.cmds({"write_restart pe_jump_async.restart", "clear", "read_restart pe_jump_async.restart",
              "comm_modify cutoff 4.0", fix, "thermo 0", "run 33 post no"});
      restarted = chain_q(s);
      std::remove("pe_jump_async.restart");
    }
    EXPECT_LT(max_diff(unbroken, split), 1e-14) << rule;
    EXPECT_LT(max_diff(unbroken, restarted), 1e-14) << rule;
    EXPECT_GT(max_diff(unbroken, Q0), 1e-2);
  }
}

/* ----------------------------------------------------------------------
   the parasitic mode is damped on each clock. Started with init paper
   ([v]^0 = 0 instead of the smooth jump h F/m), the jumps alternate about
   the smooth jump, which the undamped scheme keeps: the mean jump energy
   of a disordered LJ crystal stays about 1.4 times that of the smooth
   start (init kick). With damp tau the alternating part decays as (1 -
   h/tau)^n and the jump energy comes back to the smooth start's. Fine
   clock: every atom fast (one mass); coarse clock: light fast atoms
   whose jump energy is a fourth of the slow atoms' (K 10)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, DampingRemovesTheParasiticModeOnEachClock)
{
  struct Clock {
    std::string fast;
    int K;
    double dt, light_mass;
  };
  const auto mean_jump_energy = [](const Clock &c, const std::string &start) {
    Sim s;
    s.cmds({"units lj",
            "atom_style atomic",
            "atom_modify map array",
            "lattice fcc 0.8442",
            "region box block 0 6 0 6 0 6",
            "create_box 2 box",
            "create_atoms 1 box",
            "mass 1 1.0",
            fmt::format("mass 2 {}", c.light_mass),
            "set type 1 type/fraction 2 0.1 12345",
            "group light type 2",
            "velocity all create 1.0 87287 loop geom",
            "displace_atoms all random 0.05 0.05 0.05 4711",
            "pair_style lj/cut 2.5",
            "pair_coeff * * 1.0 1.0 2.5",
            "neighbor 0.3 bin",
            "neigh_modify every 1 delay 0 check yes",
            fmt::format("fix 1 all pe_jump/async {} {} quadrature midpoint {}", c.K, c.fast, start),
            fmt::format("timestep {}", c.dt),
            "fix ave all ave/time 10 30 500 f_1[2]",
            "thermo 0",
            "run 500 post no"});
    return s.eval("f_ave");
  };
  for (const Clock &c : {Clock{"all", 5, 0.025, 1.0}, Clock{"light", 10, 0.005, 0.04}}) {
    const double smooth = mean_jump_energy(c, "init kick damp 0");
    const double parasitic = mean_jump_energy(c, "init paper damp 0");
    const double damped = mean_jump_energy(c, "init paper damp 0.25");
    EXPECT_GT(parasitic, 1.25 * smooth) << c.fast;
    EXPECT_NEAR(damped / smooth, 1.0, 0.1) << c.fast;
  }
}

/* ----------------------------------------------------------------------
   with neigh_modify check no the lists are rebuilt every N steps wherever
   the atoms are, and pairs beyond the skin are missed. A continued run
   builds its lists at setup, at the coarse node where it begins; the
   unbroken run must build them at the coarse nodes too, or another set of
   pairs is missed (LAMMPS' melt example settings, T = 3, lists every 21
   fine steps, K = 3). The runs are split at steps where the unbroken run
   builds its lists
------------------------------------------------------------------------- */

TEST(PEJumpAsync, SplitRunsAndRestartsUnderNeighCheckNoAreExact)
{
  for (const std::string rule : {"midpoint", "legendre 2", "lobatto 3"}) {
    // (the restart file keeps the group)
    const std::vector<std::string> setup = {"neigh_modify every 7 delay 0 check no",
                                            "fix 1 all pe_jump/async 3 fast quadrature " + rule,
                                            "timestep 0.015", "thermo 0"};
    const auto state = [&](const std::vector<std::string> &runs) {
      Sim s;
      lj_liquid(s, 5, "dist gaussian");
      s.cmds({"velocity all scale 3.0", "region left block 0 2.5 INF INF INF INF",
              "group fast region left"});
      s.cmds(setup);
      s.cmds(runs);
      return unwrapped_positions(s);
    };
    const auto unbroken = state({"run 70 post no"});
    for (const int at : {21, 35}) {
      const auto split =
          state({fmt::format("run {} post no", at), fmt::format("run {} post no", 70 - at)});
      std::vector<std::string> restart = {
          fmt::format("run {} post no", at), "write_restart pe_jump_async_checkno.restart", "clear",
          "read_restart pe_jump_async_checkno.restart", "neighbor 0.3 bin"};
      restart.insert(restart.end(), setup.begin(), setup.end());
      restart.push_back(fmt::format("run {} post no", 70 - at));
      const auto restarted = state(restart);
      std::remove("pe_jump_async_checkno.restart");
      EXPECT_LT(max_diff(unbroken, split), 1e-11) << rule << ", split at " << at;
      EXPECT_LT(max_diff(unbroken, restarted), 1e-11) << rule << ", restart at " << at;
    }
  }
}

/* ----------------------------------------------------------------------
   lists built every few steps whatever the atoms do (check no: every 5
   fine steps for K = 1, every 6 for K = 3), at a temperature where no pair
   leaves the skin in as many fine steps, give the trajectory of lists
   checked every step: a build must leave every atom where the scheme has
   it, the slow atoms held during the fine steps included (where they were
   left elsewhere, the coarse forces were taken there and etotal fell by
   6.3e-4 at every build, K = 1 and 3)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, ListsBuiltWhateverTheAtomsDoKeepTheTrajectory)
{
  for (const std::string rule : {"midpoint", "legendre 2", "lobatto 3"})
    for (const int k : {1, 3}) {
      // 201 fine steps of 0.005
      const int steps = 201 / k;
      const auto state = [&](const std::string &lists) {
        Sim s;
        lj_liquid(s, 8);    // (slow atoms beyond the cutoff of every fast one)
        s.cmds({lists, "region left block 0 2 INF INF INF INF", "group fast region left",
                fmt::format("fix 1 all pe_jump/async {} fast quadrature {}", k, rule),
                fmt::format("timestep {:.6g}", 0.005 * k), "thermo 0",
                fmt::format("run {} post no", steps)});
        return unwrapped_positions(s);
      };
      const auto checked = state("neigh_modify every 1 delay 0 check yes");
      const auto forced =
          state(fmt::format("neigh_modify every {} delay 0 check no", (k == 1) ? 5 : 2));
      EXPECT_LT(max_diff(checked, forced), 1e-9) << rule << ", K = " << k;
    }
}

/* ----------------------------------------------------------------------
   a run stopped by an error (caught, as the library interface and Python
   do) leaves LAMMPS with a second perpetual list of the pair style, a
   copy of the first, of which the style uses one: the pair probes cut the
   other and took lj/cut for a style whose forces act beyond the pair (a
   refusal at the next run). The next run equals that of a fresh instance
------------------------------------------------------------------------- */

TEST(PEJumpAsync, RunAfterACaughtErrorIsNotRefused)
{
  const std::vector<std::string> fix = {"group fast id 1:20", "fix 1 all pe_jump/async 5 fast",
                                        "timestep 0.025", "thermo 0"};
  Sim s;
  lj_liquid(s);
  s.cmds({"compute t all temp", "fix 2 all ave/time 1 1 1 c_t", "fix 3 all nve", "uncompute t"});
  EXPECT_THROW(s.cmd("run 5 post no"), LAMMPS_NS::LAMMPSException);
  s.cmds({"unfix 2", "unfix 3"});
  s.cmds(fix);
  const std::string error = error_from([&] {
    s.cmd("run 4 post no");
  });
  EXPECT_EQ(error, "no error");
  Sim fresh;
  lj_liquid(fresh);
  fresh.cmds(fix);
  fresh.cmd("run 4 post no");
  EXPECT_LT(max_diff(unwrapped_positions(s), unwrapped_positions(fresh)), 1e-13);
}

/* ----------------------------------------------------------------------
   the fine-clock group of a fix with buffer layers goes with the fix: 40
   cycles of fix, run, unfix with new fix IDs stopped at the 31st with
   "Too many groups" (LAMMPS has 32). A group that something else uses
   stays
------------------------------------------------------------------------- */

TEST(PEJumpAsync, FineClockGroupGoesWithTheFix)
{
  Sim s;
  lj_liquid(s);
  s.cmds({"group fast id 1:20", "timestep 0.025", "thermo 0"});
  const std::string error = error_from([&] {
    for (int n = 1; n <= 40; n++)
      s.cmds({fmt::format("fix f{} all pe_jump/async 5 fast buffer 1", n), "run 1 post no",
              fmt::format("unfix f{}", n)});
  });
  EXPECT_EQ(error, "no error");
  EXPECT_LT(s.lmp->group->find("f40_fine_clock"), 0);
  s.cmds({"fix kept all pe_jump/async 5 fast buffer 1", "run 1 post no",
          "compute t kept_fine_clock temp", "unfix kept"});
  EXPECT_GE(s.lmp->group->find("kept_fine_clock"), 0);
}

/* ----------------------------------------------------------------------
   bad input
------------------------------------------------------------------------- */

TEST(PEJumpAsync, BadInputGivesClearErrors)
{
  const std::vector<std::string> base = {"units lj",
                                         "atom_style bond",
                                         "region box block 0 10 0 10 0 10",
                                         "create_box 2 box bond/types 1 extra/bond/per/atom 2",
                                         "create_atoms 1 single 1 1 1",
                                         "create_atoms 1 single 2 1 1",
                                         "create_atoms 2 single 5 5 5",
                                         "mass * 1.0",
                                         "pair_style lj/cut 2.5",
                                         "pair_coeff * * 1.0 1.0",
                                         "group fast type 1",
                                         "group empty type 3",
                                         "group one id 1"};
  EXPECT_THAT(error_of(base, "fix 1 all pe_jump/async 0 fast"), ContainsRegex("K >= 1"));
  EXPECT_THAT(error_of(base, "fix 1 all pe_jump/async 5 fast buffer -1"),
              ContainsRegex("buffer needs N >= 0"));
  EXPECT_THAT(error_of(base, "fix 1 all pe_jump buffer 1"),
              ContainsRegex("buffer keyword belongs to fix pe_jump/async"));
  EXPECT_THAT(error_of(base, "fix 1 all pe_jump/async 5"),
              ContainsRegex("Illegal fix pe_jump/async command: missing argument"));
  EXPECT_THAT(error_of(base, "fix 1 all pe_jump/async 5 nosuchgroup"),
              ContainsRegex("fast group nosuchgroup does not exist"));
  EXPECT_THAT(error_of(base, "fix 1 all pe_jump/async 5 fast adapt 1e-3 1e-4 1e-2"),
              ContainsRegex("does not support the adapt keyword"));
  EXPECT_THAT(error_of(base, "fix 1 all pe_jump/async 5 fast sample pair"),
              ContainsRegex("remove the sample keyword"));
  EXPECT_THAT(error_of(base, "fix 1 all pe_jump/async 5 fast compensate yes"),
              ContainsRegex("does not support compensate yes"));
  EXPECT_THAT(error_of(base, "fix 1 all pe_jump/async 5 fast quadrature auto 1e-6"),
              ContainsRegex("does not support quadrature auto"));
  EXPECT_THAT(error_of(base, "fix 1 all pe_jump/async 5 fast quadrature lobatto 7"),
              ContainsRegex("lobatto needs 2 to 5 points"));
  auto with = [&](std::vector<std::string> extra) {
    auto all = base;
    all.insert(all.end(), extra.begin(), extra.end());
    return all;
  };
  EXPECT_THAT(error_of(with({"fix 1 all pe_jump/async 5 empty"}), "run 1"),
              ContainsRegex("the fast group has no atoms in the fix group"));
  EXPECT_THAT(error_of(with({"fix 1 one pe_jump/async 5 fast"}), "run 1"),
              ContainsRegex("1 atoms of the fast group are not in the fix group"));
  EXPECT_THAT(
      error_of(with({"group two id 2", "fix 1 one pe_jump/async 5 one", "fix 2 two nve"}), "run 1"),
      ContainsRegex("must be the only time integration fix \\(found fix 2 nve\\)"));
  EXPECT_THAT(error_of(with({"fix 1 all pe_jump/async 5 fast", "run_style respa 2 2"}), "run 1"),
              ContainsRegex("does not support run_style respa"));
  EXPECT_THAT(
      error_of(with({"fix 1 all pe_jump/async 5 fast", "fix 2 all recenter INIT INIT INIT"}),
               "run 1"),
      ContainsRegex("cannot yet be combined with fix 2 \\(recenter\\), which acts on the atoms "
                    "in initial_integrate"));
  const std::string sw = std::string(PEJUMP_LAMMPS_POTENTIALS) + "/Si.sw";
  const std::vector<std::string> silicon = {"units metal",
                                            "lattice diamond 5.431",
                                            "region box block 0 2 0 2 0 2",
                                            "create_box 1 box",
                                            "create_atoms 1 box",
                                            "mass 1 28.06",
                                            "pair_style sw",
                                            "pair_coeff * * " + sw + " Si",
                                            "group fast id 1:10",
                                            "fix 1 all pe_jump/async 5 fast"};
  EXPECT_THAT(error_of(silicon, "run 1"),
              ContainsRegex("cannot split the many-body pair style sw"));
  const std::vector<std::string> charged = {"units lj",
                                            "atom_style charge",
                                            "region box block 0 10 0 10 0 10",
                                            "create_box 2 box",
                                            "create_atoms 1 single 1 1 1",
                                            "create_atoms 2 single 5 5 5",
                                            "mass * 1.0",
                                            "set type 1 charge 0.5",
                                            "set type 2 charge -0.5",
                                            "pair_style lj/cut/coul/long 2.5",
                                            "pair_coeff * * 1.0 1.0",
                                            "kspace_style ewald 1e-4",
                                            "group fast type 1",
                                            "fix 1 all pe_jump/async 5 fast"};
  EXPECT_THAT(error_of(charged, "run 1"), ContainsRegex("cannot split k-space \\(ewald\\)"));
}

/* ----------------------------------------------------------------------
   a coarse step beyond the stability limit of the slow springs stops with
   the instability error before non-finite numbers appear; below it, runs
------------------------------------------------------------------------- */

TEST(PEJumpAsync, CoarseStepBeyondStabilityLimitIsDetected)
{
  // ring of 20, E = 10 (r-1)^2: omega_max = 2 sqrt(20), CFL h < 0.2236;
  // h_F = 0.01, runs of 200 time units
  auto ring = [](Sim &s, int K) {
    harmonic_ring(s, 20, 10.0, 1.0, 7);
    // slow atoms move up to ~0.15 per coarse step: the skin must cover it
    s.cmds({"neighbor 1.0 bin", "group fast id 1:10",
            fmt::format("fix 1 all pe_jump/async {} fast", K),
            fmt::format("timestep {:.6g}", 0.01 * K), "thermo 5",
            "thermo_style custom step pe f_1[1] f_1[2]"});
  };
  {
    Sim s;
    ring(s, 15);    // h_S = 0.15
    s.cmd("run 1333 post no");
    EXPECT_TRUE(std::isfinite(s.vec("1", 1)));
    EXPECT_LT(s.vec("1", 1), 1.0);    // jump energy stays small
  }
  {
    Sim s(MPI_COMM_WORLD, false);
    ring(s, 30);    // h_S = 0.3
    ::testing::internal::CaptureStdout();
    const std::string what = error_from([&] {
      s.cmd("run 667 post no");
    });
    const std::string out = ::testing::internal::GetCapturedStdout();
    EXPECT_THAT(what, ContainsRegex("is unstable at step [0-9]+"));
    EXPECT_THAT(what, ContainsRegex("the coarse step 0.3 \\(slow atoms, the time step\\)"));
    EXPECT_THAT(out, ::testing::Not(ContainsRegex("[^a-z](nan|inf)[^a-z]")));
  }
}

/* ----------------------------------------------------------------------
   buffer N: N layers of slow partners join the fine clock
------------------------------------------------------------------------- */

TEST(PEJumpAsync, BufferLayersJoinTheFineClock)
{
  for (int layers : {1, 2}) {
    Sim s;
    chain(s);
    s.cmds({fmt::format("fix 1 chain pe_jump/async 10 fast buffer {}", layers), "timestep 1e-2",
            "thermo 0", "run 0 post no"});
    // q_1..q_3 were fast (q_3 mixed), q_4..q_6 slow: each layer moves the
    // interface one atom on
    EXPECT_EQ(s.vec("1", 6), 3.0 - layers);    // slow
    EXPECT_EQ(s.vec("1", 7), 1.0);             // mixed
    EXPECT_EQ(s.vec("1", 8), 2.0 + layers);    // fast
    const double *klass = s.lmp->modify->get_fix_by_id("1")->vector_atom;
    for (int id = 2; id <= 7; ++id) {
      const int q = id - 1;    // chain coordinate q_1..q_6
      const double expected = (q < 3 + layers) ? 2 : ((q == 3 + layers) ? 1 : 0);
      EXPECT_EQ(klass[s.lmp->atom->map(id)], expected) << layers << " " << id;
    }
    EXPECT_GE(s.lmp->group->find("1_fine_clock"), 0);
  }
}

/* ----------------------------------------------------------------------
   buffer N within D: the layers take the pair partners closer than D only
   (one atom of a 2d hex lattice, spacing 1.114, lj/cut 2.5: its 6 nearest
   neighbours, against 18 within the cutoff); a restart file tells the
   reach, and a fix defined with another one takes the layers anew
------------------------------------------------------------------------- */

namespace {
void hex_lattice(Sim &s)
{
  s.cmds({"units lj", "dimension 2", "atom_style atomic", "atom_modify map array",
          "lattice hex 0.93", "region box block 0 10 0 6 -0.5 0.5", "create_box 1 box",
          "create_atoms 1 box", "mass 1 1.0", "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0",
          "neighbor 0.3 bin", "group fast id 55", "fix 2d all enforce2d", "timestep 0.025",
          "thermo 0"});
}
}    // namespace

TEST(PEJumpAsync, BufferWithinAReachTakesTheNearPartnersOnly)
{
  const auto fine_clock = [](Sim &s) {
    return s.vec("1", 7) + s.vec("1", 8);
  };
  for (const std::string within : {"", " within 1.2", " within 2.0", " within 9.0"}) {
    Sim s;
    hex_lattice(s);
    s.cmds({"fix 1 all pe_jump/async 5 fast buffer 1" + within, "run 0 post no"});
    const double expected = within.empty() ? 19.0 : (within == " within 1.2") ? 7.0 : 13.0;
    // (a reach beyond the cutoff is the cutoff)
    EXPECT_EQ(fine_clock(s), (within == " within 9.0") ? 19.0 : expected) << within;
  }
  // the reach goes with the restart file
  for (const std::string within : {" within 1.2", ""}) {
    Sim s;
    hex_lattice(s);
    s.cmds({"fix 1 all pe_jump/async 5 fast buffer 1 within 1.2", "run 2 post no",
            "write_restart pe_jump_reach.restart", "clear", "read_restart pe_jump_reach.restart",
            "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0", "neighbor 0.3 bin",
            "fix 2d all enforce2d", "thermo 0", "fix 1 all pe_jump/async 5 fast buffer 1" + within,
            "run 0 post no"});
    std::remove("pe_jump_reach.restart");
    EXPECT_EQ(fine_clock(s), within.empty() ? 19.0 : 7.0) << within;
  }
}

/* ----------------------------------------------------------------------
   the paper's wave setting h_S = dx, K = 10 resonates at the interface
   (the period-2 mode of the first slow atom grows 5.4 % per coarse step);
   with one buffer layer it is stable and keeps the pseudo-energy over
   2000 coarse steps
------------------------------------------------------------------------- */

TEST(PEJumpAsync, BufferRemovesTheInterfaceResonanceOfTheWave)
{
  constexpr int N = 250;
  auto wave = [](Sim &s, const std::string &extra) {
    inhomogeneous_wave(s, N);
    s.cmds({"compute epot all pe", "fix 1 chain pe_jump/async 10 fast" + extra,
            fmt::format("timestep {:.17g}", 1.0 / N), "variable Ht equal c_epot+f_1",
            "thermo_style custom step c_epot f_1 f_1[2] v_Ht", "thermo 1"});
  };
  {
    Sim s;
    wave(s, "");
    const std::string what = error_from([&] {
      s.cmd("run 2000 post no");
    });
    EXPECT_THAT(what, ContainsRegex("is unstable at step [0-9]+"));
  }
  {
    Sim s;
    wave(s, " buffer 1");
    s.cmd("run 0 post no");
    const double ht0 = s.eval("v_Ht");
    double jfirst = 0.0, jlast = 0.0, dht = 0.0;
    for (int block = 0; block < 20; ++block) {
      s.cmd("run 100 post no");
      const double j = s.vec("1", 1);
      if (block < 2) jfirst = std::max(jfirst, j);
      if (block >= 18) jlast = std::max(jlast, j);
      dht = std::max(dht, std::fabs(s.eval("v_Ht") - ht0) / std::fabs(ht0));
    }
    EXPECT_GT(jfirst, 0.0);
    EXPECT_LT(jlast, 2.0 * jfirst);    // no growth over 2000 coarse steps
    EXPECT_LT(dht, 1e-8);
  }
}

/* ----------------------------------------------------------------------
   a weak resonance of the clocks (the wave at h_S = 0.5 dx, K = 20: the
   amplitude grows 0.66 % per coarse step, the guard stops the run at
   coarse step 2508) is warned of while the run goes on; the stable
   neighbour K = 10 stays silent
------------------------------------------------------------------------- */

TEST(PEJumpAsync, SlowGrowthOfTheJumpsIsWarnedBeforeTheRunStops)
{
  constexpr int N = 250;
  auto wave_output = [](int K, int steps) {
    Sim s(MPI_COMM_WORLD, false);
    inhomogeneous_wave(s, N);
    s.cmds({fmt::format("fix 1 chain pe_jump/async {} fast", K),
            fmt::format("timestep {:.17g}", 0.5 / N), "thermo 1000"});
    ::testing::internal::CaptureStdout();
    s.cmd(fmt::format("run {} post no", steps));
    return ::testing::internal::GetCapturedStdout();
  };
  const std::string resonant = wave_output(20, 2400);
  EXPECT_THAT(resonant,
              ContainsRegex("WARNING: Fix pe_jump/async: the jump energy's share of the "
                            "kinetic energy grew from 0\\.0[0-9]+ to 0\\.[1-9][0-9]* by "
                            "step 2[0-3][0-9]0: a slow instability"));
  const std::string stable = wave_output(10, 4000);
  EXPECT_THAT(stable, Not(ContainsRegex("share of the kinetic energy")));
}

/* ----------------------------------------------------------------------
   reversing all velocities after a run (which ends at a coarse node,
   where every atom has its node velocity) continues backwards in time:
   as many steps again bring the chain back to its start
------------------------------------------------------------------------- */

TEST(PEJumpAsync, VelocityReversalContinuesBackwardsInTime)
{
  for (const int nsteps : {17, 6}) {    // K = 20
    Sim s(MPI_COMM_WORLD, false);
    ::testing::internal::CaptureStdout();
    chain(s);
    s.cmds({"fix 1 chain pe_jump/async 20 fast quadrature lobatto 3", "timestep 1e-2", "thermo 0",
            fmt::format("run {} post no", nsteps)});
    EXPECT_GT(max_diff(chain_q(s), Q0), 1e-2) << nsteps;    // the chain moved
    for (int i = 0; i < s.lmp->atom->nlocal; ++i)
      for (int k = 0; k < 3; ++k) s.lmp->atom->v[i][k] = -s.lmp->atom->v[i][k];
    const std::string error = error_from([&] {
      s.cmd(fmt::format("run {} post no", nsteps));
    });
    const std::string out = ::testing::internal::GetCapturedStdout();
    EXPECT_EQ(error, "no error") << nsteps;
    EXPECT_THAT(out, ContainsRegex("all velocities were reversed")) << nsteps;
    EXPECT_LT(max_diff(chain_q(s), Q0), 1e-11) << nsteps;
  }
}

/* ----------------------------------------------------------------------
   force fields that cannot be split are refused by what they do, not by
   their names: a pair style that computes forces outside its neighbor
   lists, bonds that can break (bond style partial_flag), peridynamic
   partner lists (atom style peri), a topology that changes during the run
------------------------------------------------------------------------- */

namespace {
// lj/cut plus a force on the first owned atom that is in no neighbor list
class PairOffList : public LAMMPS_NS::PairLJCut {
 public:
  using PairLJCut::PairLJCut;
  void compute(int eflag, int vflag) override
  {
    PairLJCut::compute(eflag, vflag);
    if (atom->nlocal) atom->f[0][0] += 1.0;
  }
};
LAMMPS_NS::Pair *pair_offlist_creator(LAMMPS_NS::LAMMPS *lmp)
{
  return new PairOffList(lmp);
}
// lj/cut whose pair forces grow with the number of neighbors in the list of
// atom i (a local density, as pair_style local/density has) and that does
// not call itself many-body
class PairDensity : public LAMMPS_NS::PairLJCut {
 public:
  using PairLJCut::PairLJCut;
  void compute(int eflag, int vflag) override
  {
    const int n = 3 * (atom->nlocal + atom->nghost);
    std::vector<double> before(&atom->f[0][0], &atom->f[0][0] + n);
    PairLJCut::compute(eflag, vflag);
    int pairs = 0;
    for (int ii = 0; ii < list->inum; ii++) pairs += list->numneigh[list->ilist[ii]];
    const double scale = 1.0 + 0.1 * pairs;
    for (int k = 0; k < n; k++)
      (&atom->f[0][0])[k] = before[k] + scale * ((&atom->f[0][0])[k] - before[k]);
  }
};
LAMMPS_NS::Pair *pair_density_creator(LAMMPS_NS::LAMMPS *lmp)
{
  return new PairDensity(lmp);
}
}    // namespace

TEST(PEJumpAsync, UnsplittableForceFieldsAreRefused)
{
  {
    Sim s;
    (*s.lmp->force->pair_map)["lj/cut/offlist"] = &pair_offlist_creator;
    lj_liquid(s, 3);
    s.cmds({"pair_style lj/cut/offlist 2.5", "pair_coeff 1 1 1.0 1.0 2.5",
            "region f block 0 1 INF INF INF INF", "group fast region f",
            "fix 1 all pe_jump/async 5 fast"});
    EXPECT_THAT(error_of({}, ""), ContainsRegex("no error"));    // the helper itself
    EXPECT_THAT(error_in(s, "run 1"),
                ContainsRegex("computes forces that are not in its neighbor lists"))
        << "a pair style with forces outside its lists must be refused";
  }
  {
    // (found with pair_style local/density: K = 1 ended 3.1e-3 off fix
    // pe_jump after 40 steps, with no order of convergence)
    Sim s;
    (*s.lmp->force->pair_map)["lj/cut/density"] = &pair_density_creator;
    lj_liquid(s, 3);
    s.cmds({"pair_style lj/cut/density 2.5", "pair_coeff 1 1 1.0 1.0 2.5",
            "region f block 0 1 INF INF INF INF", "group fast region f",
            "fix 1 all pe_jump/async 5 fast"});
    EXPECT_THAT(error_in(s, "run 1"),
                ContainsRegex("the force of two pairs of an atom is not the sum"))
        << "a pair style whose pair forces do not add up must be refused";
  }
  const std::vector<std::string> chain_box = {"units lj",
                                              "atom_style bond",
                                              "region box block 0 10 0 10 0 10",
                                              "create_box 1 box bond/types 1 extra/bond/per/atom 2",
                                              "create_atoms 1 single 1 1 1",
                                              "create_atoms 1 single 2 1 1",
                                              "create_atoms 1 single 3 1 1",
                                              "mass * 1.0",
                                              "pair_style zero 2.5",
                                              "pair_coeff * *",
                                              "create_bonds single/bond 1 1 2",
                                              "create_bonds single/bond 1 2 3",
                                              "group fast id 1"};
  auto with = [&](std::vector<std::string> extra) {
    auto all = chain_box;
    all.insert(all.end(), extra.begin(), extra.end());
    return all;
  };
  EXPECT_THAT(error_of(with({"bond_style quartic", "bond_coeff 1 1200 -0.55 0.25 1.3 34.6878",
                             "special_bonds lj 1 1 1", "pair_style lj/cut 1.12",
                             "pair_coeff * * 1.0 1.0", "fix 1 all pe_jump/async 5 fast"}),
                       "run 1"),
              ContainsRegex("cannot split bond style quartic: its bonds can break"));
  EXPECT_THAT(
      error_of({"units si", "atom_style peri", "atom_modify map array", "lattice sc 0.0005",
                "region target block 0 4 0 4 0 4", "create_box 1 target",
                "create_atoms 1 region target", "pair_style peri/pmb",
                "pair_coeff * * 1.6863e22 0.0015001 0.0005 0.25", "set group all density 2200",
                "set group all volume 1.25e-10", "region f block 0 1 INF INF INF INF",
                "group fast region f", "fix 1 all pe_jump/async 5 fast", "timestep 1e-7"},
               "run 1"),
      ContainsRegex("cannot split peridynamic interactions"));
  // bonds deleted between runs are split anew at the next run
  EXPECT_THAT(error_of(with({"bond_style harmonic", "bond_coeff 1 1.0 1.0",
                             "fix 1 all pe_jump/async 5 fast", "run 2 post no",
                             "delete_bonds all bond 1 remove special"}),
                       "run 2 post no"),
              ContainsRegex("no error"));
}

/* ----------------------------------------------------------------------
   fix wall/reflect reverses velocities inside a coarse step: refused at
   setup, whether the reflected atom is on the fine clock or on the coarse
   one, also where it would reach the wall in the last step of the run
------------------------------------------------------------------------- */

TEST(PEJumpAsync, WallReflectOnEitherClockIsRefused)
{
  const auto error_with = [](const std::string &fast, int steps) {
    Sim s;
    s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "boundary p p f",
            "region box block 0 10 0 10 0 10", "create_box 1 box", "create_atoms 1 single 5 5 0.5",
            "create_atoms 1 single 2 2 8", "mass 1 1.0", "pair_style lj/cut 1.0",
            "pair_coeff 1 1 1.0 1.0 1.0", "neighbor 0.3 bin", "group fast id " + fast,
            "velocity all set 0 0 0", "set atom 1 vz -1.0", "fix int all pe_jump/async 10 fast",
            "fix w all wall/reflect zlo EDGE", "timestep 0.1", "thermo 0"});
    const std::string error = error_in(s, fmt::format("run {}", steps));
    if (error != "no error") return error;
    // without the refusal the atom bounced: its velocity points up
    return fmt::format("no error, vz {}", s.lmp->atom->v[s.lmp->atom->map(1)][2]);
  };
  // atom 1 reaches the wall at t = 0.5 (the end of step 5)
  for (const std::string fast : {"1", "2"})
    for (const int steps : {20, 6}) {
      EXPECT_THAT(error_with(fast, steps),
                  ContainsRegex("cannot yet be combined with fix w \\(wall/reflect\\), which "
                                "reverses velocities inside the coarse step"))
          << "fast group: atom " << fast << ", run " << steps;
    }
}

namespace {

// 2d triangular lattice (spacing 1, 168 atoms) of harmonic bonds, no pair
// style: the atoms in region core are type 2, group stiff (stiff bonds among
// them). The time step 0.05 is the coarse step of K = 10 (h_F = 0.005)
void bonded_lattice(Sim &s, const std::string &core, double skin)
{
  s.cmds({"units lj",
          "dimension 2",
          "atom_style bond",
          "atom_modify map array",
          "boundary p p p",
          "lattice hex 1.1547005383792515",
          "region box block 0 12 0 7 -0.5 0.5",
          "create_box 2 box bond/types 2 extra/bond/per/atom 6 extra/special/per/atom 20",
          "create_atoms 1 box",
          "mass * 1.0",
          "region core " + core,
          "set region core type 2",
          "group stiff type 2",
          "group soft subtract all stiff",
          "bond_style harmonic",
          "bond_coeff 1 1.0 1.0",
          "bond_coeff 2 400.0 1.0",
          "pair_style zero 1.5",
          "pair_coeff * *",
          "create_bonds many stiff stiff 2 0.9 1.1",
          "create_bonds many soft all 1 0.9 1.1",
          "pair_style none",
          "comm_modify cutoff 2.5",
          fmt::format("neighbor {} bin", skin),
          "neigh_modify every 1 delay 0 check yes",
          "velocity all create 0.05 4711 dist gaussian",
          "fix 2d all enforce2d",
          "timestep 0.05"});
}

}    // namespace

/* ----------------------------------------------------------------------
   neigh_modify every N (or delay N) exempts steps from LAMMPS' distance
   check over all atoms; pe_jump/async checks at every step whether its
   atoms can stay within half the skin of the last build until the next
   step, over the fine steps too, and asks for a build where they cannot,
   so the lists are rebuilt where every 1 delay 0 rebuilds them. A
   projectile on the fine clock that reaches a slow atom inside a coarse
   step (K = 4, h_F = 0.001: 0.08 per coarse step against the skin 0.3),
   and an LJ liquid with a hot light fast group and buffer layers
------------------------------------------------------------------------- */

namespace {

struct ListRun {
  std::vector<double> x;
  LAMMPS_NS::bigint builds;
};

ListRun projectile_run(const std::string &neigh, const std::string &rule)
{
  Sim s;
  s.cmds({"units lj", "atom_style atomic", "atom_modify map array",
          "region box block -10 10 -10 10 -10 10", "create_box 1 box",
          "create_atoms 1 single -6.0 0.0 0.0", "create_atoms 1 single 0.0 0.3 0.0",
          "create_atoms 1 single 0.0 -2.0 0.0", "mass 1 1.0", "group fast id 1",
          "velocity fast set 20.0 0.0 0.0", "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0 2.5",
          "neighbor 0.3 bin", neigh, "timestep 0.004",
          "fix 1 all pe_jump/async 4 fast quadrature " + rule, "thermo 5", "run 60"});
  return {positions(s), s.lmp->neighbor->ncalls};
}

ListRun liquid_run(const std::string &neigh, const std::string &rule)
{
  Sim s;
  lj_liquid(s);
  s.cmds({neigh, "group fast id 1:24", "velocity fast create 3.0 4711 loop geom",
          "fix 1 all pe_jump/async 4 fast buffer 1 quadrature " + rule, "timestep 0.02",
          "thermo 10", "run 100"});
  return {positions(s), s.lmp->neighbor->ncalls};
}

}    // namespace

TEST(PEJumpAsync, NeighborCheckIntervalsKeepTheListsOfEveryStep)
{
  const std::string every1 = "neigh_modify every 1 delay 0 check yes";
  for (const std::string rule : {"midpoint", "lobatto 3", "legendre 2"}) {
    const auto ref = projectile_run(every1, rule);
    for (const std::string neigh :
         {"neigh_modify every 7 delay 0 check yes", "neigh_modify every 1000 delay 0 check yes",
          "neigh_modify every 1 delay 5 check yes"}) {
      const auto other = projectile_run(neigh, rule);
      EXPECT_EQ(max_diff(ref.x, other.x), 0.0) << rule << ", " << neigh;
      EXPECT_EQ(ref.builds, other.builds) << rule << ", " << neigh;
    }
    EXPECT_GE(ref.builds, 10) << rule;
  }
  for (const std::string rule : {"midpoint", "lobatto 3"}) {
    const auto ref = liquid_run(every1, rule);
    const auto other = liquid_run("neigh_modify every 1000 delay 0 check yes", rule);
    EXPECT_LE(max_diff(ref.x, other.x), 1e-10) << rule;
    EXPECT_EQ(ref.builds, other.builds) << rule;
    EXPECT_GE(ref.builds, 20) << rule;
  }
}

/* ----------------------------------------------------------------------
   neigh_modify include (with atom_modify first, which LAMMPS requires)
   leaves the atoms outside the group out of the lists, whose pairs
   pe_jump/async splits for every atom: refused at setup, whether the group
   holds the fast group or not. Fix pe_jump takes it where the include
   group holds its fix group; atom_modify first alone is fine
------------------------------------------------------------------------- */

TEST(PEJumpAsync, NeighModifyIncludeIsRefused)
{
  const auto error_with = [](const std::string &include, const std::vector<std::string> &more) {
    Sim s;
    bonded_lattice(s, "block INF INF 0 1.6 INF INF", 0.3);
    s.cmds({"group fine " + include, "atom_modify first fine", "neigh_modify include fine"});
    const std::string error = error_from([&] {
      s.cmds(more);
    });
    if (error != "no error") return error;
    return fmt::format("no error at step {}", s.lmp->update->ntimestep);
  };
  const std::string async = "fix 1 all pe_jump/async 10 stiff";
  for (const std::string &include : {std::string("type 2"), std::string("id 1:10")})
    EXPECT_THAT(error_with(include, {async, "run 2"}),
                ContainsRegex("Fix pe_jump/async does not support neigh_modify include"))
        << include;
  EXPECT_THAT(error_with("type 2", {async + " buffer 1", "run 2"}),
              ContainsRegex("Fix pe_jump/async does not support neigh_modify include"));
  EXPECT_THAT(error_with("type 2", {"fix 1 all pe_jump", "run 0"}),
              ContainsRegex("moves every atom of its group every step, but 120 of them are not"));
  EXPECT_EQ(error_with("type 2", {"fix 1 stiff pe_jump", "timestep 0.005", "run 5"}),
            "no error at step 5");
  Sim s;
  bonded_lattice(s, "block INF INF 0 1.6 INF INF", 0.3);
  s.cmds({"group fine type 2", "atom_modify first fine", async, "thermo 0", "run 2"});
  EXPECT_EQ(s.lmp->update->ntimestep, 2);
}

/* ----------------------------------------------------------------------
   dynamic fast groups: atoms change clock at coarse nodes only. A dynamic
   group whose region does not move gives the static group's trajectory
   (the region keeps a margin around the stiff band, which its atoms do
   not cross, and covers the band's images across the periodic boundary)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, DynamicFastGroupEqualsStaticWhenItsRegionStays)
{
  const std::string band = "block INF INF 0 1.6 INF INF";
  for (const std::string rule : {"", " quadrature lobatto 3", " buffer 1"}) {
    std::vector<double> x[2];
    for (const int dynamic : {0, 1}) {
      Sim s;
      bonded_lattice(s, band, 0.3);
      s.cmds({"region low block INF INF -0.25 1.75 INF INF",
              "region high block INF INF 6.75 INF INF INF", "region stays union 2 low high",
              dynamic ? "group fast dynamic all region stays every 1" : "group fast region stays",
              "fix 1 all pe_jump/async 10 fast" + rule, "thermo 5", "run 40"});
      x[dynamic] = positions(s);
      EXPECT_EQ(s.eval("count(fast)"), 48.0) << rule;
      EXPECT_GT(s.vec("1", 8), 10.0) << rule;    // atoms of the class fast
    }
    EXPECT_EQ(max_diff(x[0], x[1]), 0.0) << rule;
  }
}

/* ----------------------------------------------------------------------
   a fast region that moves over the lattice: atoms change clock at coarse
   nodes, the total momentum stays what it was, and the atoms do change
   clock (per-atom classes at the start and the end)
------------------------------------------------------------------------- */

namespace {

// the lattice with soft bonds only, over which a fast region sweeps (4 per
// unit of time, 0.2 per step); the group is updated at every step
void moving_region(Sim &s, const std::string &rule)
{
  bonded_lattice(s, "block INF INF 0 1.6 INF INF", 0.3);
  s.cmds({"bond_coeff 2 1.0 1.0", "variable xc equal 2.0+0.2*step",
          "region mov sphere v_xc 6.0621778 0 2.5 side in units box",
          "group fast dynamic all region mov every 1", "fix 1 all pe_jump/async 10 fast" + rule,
          "variable px equal mass(all)*vcm(all,x)", "variable py equal mass(all)*vcm(all,y)",
          "thermo 1"});
}

// per atom ID: 1 if on the fine clock (class mixed or fast), serial runs
std::vector<int> on_fine_clock(Sim &s)
{
  const auto *klass = s.lmp->modify->get_fix_by_id("1")->vector_atom;
  std::vector<int> fine(s.lmp->atom->natoms + 1, 0);
  for (int i = 0; i < s.lmp->atom->nlocal; i++)
    fine[s.lmp->atom->tag[i]] = (klass[i] > 0.0) ? 1 : 0;
  return fine;
}

}    // namespace

TEST(PEJumpAsync, ClockChangesConserveMomentum)
{
  for (const std::string rule : {"", " quadrature lobatto 3", " buffer 1"}) {
    Sim s;
    moving_region(s, rule);
    s.cmds({"run 0"});
    const double p0[2] = {s.eval("v_px"), s.eval("v_py")};
    const auto fine0 = on_fine_clock(s);
    double worst = 0.0;
    for (int block = 1; block <= 40; block++) {
      s.cmd("run 1 post no");
      worst =
          std::max({worst, std::fabs(s.eval("v_px") - p0[0]), std::fabs(s.eval("v_py") - p0[1])});
    }
    const auto fine1 = on_fine_clock(s);
    int joined = 0, left = 0;
    for (size_t id = 1; id < fine0.size(); id++) {
      joined += (!fine0[id] && fine1[id]) ? 1 : 0;
      left += (fine0[id] && !fine1[id]) ? 1 : 0;
    }
    EXPECT_GT(joined, 10) << rule;
    EXPECT_GT(left, 10) << rule;
    EXPECT_LT(worst, 1e-13) << rule;
  }
}

/* ----------------------------------------------------------------------
   an end atom of a 3-atom chain of springs that changes clock at every
   coarse node (it is in the fast group at even steps), K odd: its
   restarted jump must fit its new step. Positions at t = 2 against fix
   nve at h = 1e-4; second order as h_S halves (with the jumps of the
   changed atoms shifted by their mean change, the restart of a single
   atom was undone: 3.6e-2 off at every h)
------------------------------------------------------------------------- */

namespace {
std::vector<double> toggled_chain(const std::string &integrator, double h, int steps)
{
  Sim s;
  s.cmds({"units lj",
          "atom_style bond",
          "boundary f f f",
          "region box block -10 10 -10 10 -10 10",
          "create_box 1 box bond/types 1 extra/bond/per/atom 2",
          "mass 1 1.0",
          "create_atoms 1 single 0.0 0.0 0.0",
          "create_atoms 1 single 1.2 0.1 0.0",
          "create_atoms 1 single 2.1 0.9 0.3",
          "create_bonds single/bond 1 1 2",
          "create_bonds single/bond 1 2 3",
          "bond_style harmonic",
          "bond_coeff 1 5.0 1.0",
          "velocity all set 0.0 0.0 0.0",
          "set atom 1 vx 0.1",
          "set atom 2 vx -0.2 vy 0.3",
          "set atom 3 vx 0.05 vy -0.1 vz 0.2",
          "comm_modify cutoff 3.0",
          "neighbor 0.5 bin",
          "variable inf atom (id==1)*(step%2==0)",
          "group fast dynamic all var inf every 1",
          "timestep " + std::to_string(h),
          "fix 1 all " + integrator,
          "thermo 0",
          "run " + std::to_string(steps)});
  std::vector<double> x;
  for (int id = 1; id <= 3; id++)
    for (int k = 0; k < 3; k++) x.push_back(s.x(id, k));
  return x;
}
}    // namespace

TEST(PEJumpAsync, AnAtomChangingClockAtEveryNodeConvergesAtSecondOrder)
{
  const auto ref = toggled_chain("nve", 1.0e-4, 20000);
  double err[3];
  for (int n = 0; n < 3; n++) {
    const double h = 0.01 / (1 << n);    // h_S, K = 5
    const auto x = toggled_chain("pe_jump/async 5 fast", h, 200 << n);
    err[n] = 0.0;
    for (size_t k = 0; k < x.size(); k++) err[n] = std::max(err[n], std::fabs(x[k] - ref[k]));
  }
  EXPECT_LT(err[1], 1.0e-4);
  EXPECT_GT(err[0] / err[1], 3.0);
  EXPECT_GT(err[1] / err[2], 3.0);
}

/* ----------------------------------------------------------------------
   an atom that changes clock at a coarse node starts its new clock with
   the kick of the scheme, [v]^n = h_new F(q^n)/m, which its first free
   flight x^n + c h_new (v^n + [v]^n/2) shows: for an atom that left the
   fine clock the coarse step itself (c = 1, seen at the step end), for
   one that joined it the first fine step up to its first node (c = 1/2:
   the midpoint rule's node, lobatto 3's middle node), seen by a bond style
   that records the positions
   at every evaluation of the step. The kicks are compared with the forces
   at the node computed from scratch. With the midpoint rule the forces of
   the atoms that change clock come from two fine subsets, at less than
   the cost of one complete evaluation
------------------------------------------------------------------------- */

namespace {
// class2 bonds (as harmonic ones with K3 = K4 = 0) that record the (x, y)
// of the owned atoms, by atom ID, at every evaluation during one step
class BondRecording : public LAMMPS_NS::BondClass2 {
 public:
  using BondClass2::BondClass2;
  static LAMMPS_NS::bigint step;
  static std::vector<std::map<int, std::pair<double, double>>> seen;
  void compute(int eflag, int vflag) override
  {
    if (update->ntimestep == step) {
      seen.emplace_back();
      for (int i = 0; i < atom->nlocal; i++)
        seen.back()[static_cast<int>(atom->tag[i])] = {atom->x[i][0], atom->x[i][1]};
    }
    BondClass2::compute(eflag, vflag);
  }
};
LAMMPS_NS::bigint BondRecording::step = -1;
std::vector<std::map<int, std::pair<double, double>>> BondRecording::seen;
LAMMPS_NS::Bond *bond_recording_creator(LAMMPS_NS::LAMMPS *lmp)
{
  return new BondRecording(lmp);
}

// the soft bonds of moving_region() as recording class2 bonds
void recorded_bonds(Sim &s)
{
  (*s.lmp->force->bond_map)["class2/recording"] = &bond_recording_creator;
  s.cmds({"bond_style class2/recording", "bond_coeff * 1.0 1.0 0.0 0.0"});
}
}    // namespace

TEST(PEJumpAsync, AtomsChangingClockStartWithTheForcesAtTheNode)
{
  const double hs = 0.05, hf = hs / 10;    // bonded_lattice(), K = 10
  for (const std::string rule : {"", " quadrature lobatto 3", " buffer 1"}) {
    // the first node inside the first fine step: the midpoint rule's node,
    // and the middle node that lobatto 3 evaluates on the way to the end
    const double first_node = 0.5;
    Sim s(MPI_COMM_WORLD, false);
    moving_region(s, rule);
    recorded_bonds(s);
    // the criterion sees the node's step, as LAMMPS' own update of step 20 would
    s.cmds({"variable xc equal 2.0+3.0*(step==20)", "thermo 0"});
    // the node of step 20 (positions, velocities, classes) and the
    // cumulative evaluations of every step, in one run; the positions at
    // the evaluations of step 21
    s.cmds({"fix node all store/state 20 x y vx vy f_1", "fix evals all vector 1 f_1[5]"});
    BondRecording::step = 21;
    BondRecording::seen.clear();
    ::testing::internal::CaptureStdout();
    s.cmd("run 21");
    const std::string log = ::testing::internal::GetCapturedStdout();
    BondRecording::step = -1;
    const int natoms = static_cast<int>(s.lmp->atom->natoms);
    const auto *atom = s.lmp->atom;
    double **node = s.lmp->modify->get_fix_by_id("node")->array_atom;
    std::vector<double> x0(3 * (natoms + 1)), v0(3 * (natoms + 1));
    std::vector<int> fine0(natoms + 1);
    for (int i = 0; i < atom->nlocal; i++) {
      const int id = static_cast<int>(atom->tag[i]);
      for (int k = 0; k < 2; k++) {
        x0[3 * id + k] = node[i][k];
        v0[3 * id + k] = node[i][2 + k];
      }
      fine0[id] = (node[i][4] > 0.0) ? 1 : 0;
    }
    auto *cumulative = s.lmp->modify->get_fix_by_id("evals");
    const int stored = cumulative->size_vector;
    const double evals =
        cumulative->compute_vector(stored - 1) - cumulative->compute_vector(stored - 2);
    const auto fine1 = on_fine_clock(s);

    const double *prd = s.lmp->domain->prd;
    const auto apart = [&](double a, double b, int k) {
      const double d = a - b;
      return d - prd[k] * std::round(d / prd[k]);
    };
    // the first evaluation of step 21 away from the node: the first fine
    // step's first node (those before: forces at the node)
    const std::map<int, std::pair<double, double>> *first = nullptr;
    for (const auto &seen : BondRecording::seen) {
      double moved = 0.0;
      for (const auto &[id, xy] : seen)
        moved = std::max({moved, std::fabs(apart(xy.first, x0[3 * id], 0)),
                          std::fabs(apart(xy.second, x0[3 * id + 1], 1))});
      if (moved > 0.0) {
        first = &seen;
        break;
      }
    }
    ASSERT_NE(first, nullptr) << rule;

    // the forces at the node, from scratch
    Sim r;
    moving_region(r, "");
    recorded_bonds(r);
    r.cmds({"unfix 1", "fix 1 all nve"});
    for (int id = 1; id <= natoms; id++)
      for (int k = 0; k < 2; k++) r.lmp->atom->x[r.lmp->atom->map(id)][k] = x0[3 * id + k];
    r.cmds({"run 0 post no"});

    double spread = 0.0, largest = 0.0;
    int changed = 0, joined = 0;
    for (int id = 1; id <= natoms; id++) {
      if (fine0[id] == fine1[id]) continue;
      // free flight of c h: seen at the first node of the first fine
      // step (joined) or at the end of the coarse step (left)
      const double h = fine1[id] ? hf : hs, c = fine1[id] ? first_node : 1.0;
      for (int k = 0; k < 2; k++) {
        const double x = fine1[id] ? ((k == 0) ? first->at(id).first : first->at(id).second)
                                   : s.x(id, k);
        const double d = apart(x, x0[3 * id + k], k);
        const double jump = 2.0 * (d / (c * h) - v0[3 * id + k]);
        const double kick = h * r.lmp->atom->f[r.lmp->atom->map(id)][k];
        spread = std::max(spread, std::fabs(jump - kick));
        largest = std::max(largest, std::fabs(kick));
      }
      ++changed;
      joined += fine1[id];
    }
    EXPECT_GT(joined, 3) << rule;
    EXPECT_GT(changed - joined, 3) << rule;
    // the fix's count of clock changes in the log: those at node 20 and a
    // few of thermal motion at the region's boundary before
    std::smatch count;
    ASSERT_TRUE(std::regex_search(
        log, count,
        std::regex("Fix pe_jump/async: (\\d+) atoms changed clock at (\\d+) of 21 coarse nodes")))
        << rule;
    EXPECT_GE(std::stoi(count[1]), changed) << rule;
    EXPECT_LE(std::stoi(count[1]), changed + 5) << rule;
    EXPECT_GE(std::stoi(count[2]), 1) << rule;
    EXPECT_GT(largest, 1e-4) << rule;
    EXPECT_LT(spread, 1e-10) << rule;
    // the forces at the node cost less than a complete evaluation on top
    // of the step's own
    if (rule.find("lobatto") == std::string::npos) EXPECT_LT(evals - s.vec("1", 3), 1.0) << rule;
  }
}

/* ----------------------------------------------------------------------
   an atom that changes clock restarts its jump: the pseudo-energy pe +
   f_ID changes by the jump energy the atom had less the one it starts
   with. Atoms that change clock at every node at a coarse step with large
   jumps add this up while every atom's step stays small, where the
   stability guard sees nothing (a liquid of chains in real units with
   fast auto 0.05 at K = 4 went from 239 to 1014 kcal/mol in 2000 fs, fix
   nve at the fine step to 243). The fix warns when the changes since it
   was defined have changed the pseudo-energy by more than 5 % of the
   group's kinetic energy, with the change, which is that of pe + f_ID at
   the nodes up to the quadrature error, and stops beyond 50 %. 256-atom
   LJ liquid from the lattice, T = 1.5, K = 5, fast auto 0.2: at h_S = 0.05
   the warning at step 20 (+35.8; pe + f_ID changed by +33.7 up to the
   next node, +77 in 40 steps), the error at step 122 (+289, 50.4 %) in the
   run that follows; at h_S = 0.025 neither (-10.7 in 40 steps)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, PseudoEnergyThatClockChangesAddIsWarnedAbout)
{
  const std::vector<std::string> liquid = {"group none id 0",
                                           "fix 1 all pe_jump/async 5 none fast auto 0.2",
                                           "variable Ht equal pe+f_1",
                                           "thermo_style custom step pe v_Ht",
                                           "thermo_modify norm no format float %.15g",
                                           "thermo 1"};
  for (const double h : {0.05, 0.025}) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s);
    s.cmd(fmt::format("timestep {}", h));
    s.cmds(liquid);
    ::testing::internal::CaptureStdout();
    s.cmd("run 40");
    const std::string log = ::testing::internal::GetCapturedStdout();
    std::map<int, double> pseudo;    // at the coarse nodes
    const std::regex row("^\\s*(\\d+)\\s+\\S+\\s+(\\S+)\\s*$");
    std::istringstream lines(log);
    for (std::string line; std::getline(lines, line);) {
      std::smatch m;
      if (std::regex_match(line, m, row)) pseudo[std::stoi(m[1])] = std::stod(m[2]);
    }
    ASSERT_EQ(pseudo.size(), 41U) << h;
    const std::regex warning("by step (\\d+) the clock changes since the fix was defined have "
                             "changed the pseudo-energy by (\\S+), (\\S+) % of the kinetic "
                             "energy of the group \\((\\S+)\\)");
    std::smatch warned;
    const bool found = std::regex_search(log, warned, warning);
    if (h < 0.0375) {
      EXPECT_FALSE(found) << log;
      EXPECT_LT(std::fabs(pseudo.at(40) - pseudo.at(0)), 20.0);
      continue;
    }
    ASSERT_TRUE(found) << log;
    EXPECT_EQ(log.find("clock changes since", warned.position(0) + warned.length(0)),
              std::string::npos);
    const int step = std::stoi(warned[1]);
    const double added = std::stod(warned[2]);
    EXPECT_NEAR(std::stod(warned[3]), 100.0 * std::fabs(added) / std::stod(warned[4]), 1e-2);
    EXPECT_GT(std::stod(warned[3]), 5.0);
    // changed at the node step - 1 (as step begins), seen at the next one
    const double seen = pseudo.at(step) - pseudo.at(0);
    EXPECT_NEAR(seen, added, 0.1 * std::fabs(added));
    EXPECT_GT(pseudo.at(40) - pseudo.at(0), 50.0);

    // the changes add up over the runs, to the error
    Sim t;
    lj_liquid(t);
    const std::string stopped = error_from([&] {
      t.cmd(fmt::format("timestep {}", h));
      t.cmds(liquid);
      t.cmds({"run 40", "run 120"});
    });
    std::smatch at;
    ASSERT_TRUE(std::regex_search(stopped, at, warning)) << stopped;
    EXPECT_GT(std::stoi(at[1]), 40);
    EXPECT_GT(std::stod(at[3]), 50.0);
    EXPECT_THAT(stopped, ContainsRegex("the fix stops where this exceeds 50 %"));
  }
}

/* ----------------------------------------------------------------------
   a dynamic fast group that swaps atoms for others with the same number
   and the same sum of IDs (10 and 13 for 11 and 12) changes the clocks
------------------------------------------------------------------------- */

TEST(PEJumpAsync, ClocksFollowAGroupThatKeepsItsSizeAndIDSum)
{
  Sim s;
  moving_region(s, "");
  s.cmds({"variable swap atom (step<=10)*(id==10||id==13)+(step>10)*(id==11||id==12)",
          "group pair dynamic all var swap every 1", "unfix 1", "fix 1 all pe_jump/async 10 pair",
          "run 20"});
  const auto fine = on_fine_clock(s);
  EXPECT_EQ(fine[10] + fine[13], 0);
  EXPECT_EQ(fine[11] + fine[12], 2);
}

/* ----------------------------------------------------------------------
   the clocks follow a dynamic group as often as LAMMPS updates it: at the
   coarse node that ends each step it is updated in (every N steps)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, ClocksFollowADynamicGroupAsOftenAsItIsUpdated)
{
  std::map<int, std::vector<int>> tally;
  for (const int every : {1, 3}) {
    Sim s(MPI_COMM_WORLD, false);
    bonded_lattice(s, "block INF INF 0 1.6 INF INF", 0.3);
    s.cmds({"bond_coeff 2 1.0 1.0", "variable xc equal 2.0+0.2*step",
            "region mov sphere v_xc 6.0621778 0 2.5 side in units box",
            fmt::format("group fast dynamic all region mov every {}", every),
            "fix 1 all pe_jump/async 10 fast", "thermo 0"});
    ::testing::internal::CaptureStdout();
    s.cmd("run 30");
    const std::string log = ::testing::internal::GetCapturedStdout();
    std::smatch count;
    ASSERT_TRUE(std::regex_search(
        log, count,
        std::regex("Fix pe_jump/async: (\\d+) atoms changed clock at (\\d+) of 30 coarse nodes")))
        << every;
    tally[every] = {std::stoi(count[1]), std::stoi(count[2])};
  }
  // every 1: the group is updated (and followed) at every coarse node;
  // every 3: at the nodes of steps 0, 3, ..., 27
  EXPECT_GT(tally[1][1], 15);
  EXPECT_GT(tally[3][1], 3);
  EXPECT_LE(tally[3][1], 10);

  // each run reports its own nodes, also one with "pre no" (no setup)
  Sim s(MPI_COMM_WORLD, false);
  bonded_lattice(s, "block INF INF 0 1.6 INF INF", 0.3);
  s.cmds({"bond_coeff 2 1.0 1.0", "variable xc equal 2.0+0.2*step",
          "region mov sphere v_xc 6.0621778 0 2.5 side in units box",
          "group fast dynamic all region mov every 1", "fix 1 all pe_jump/async 10 fast",
          "thermo 0", "run 10 post no"});
  ::testing::internal::CaptureStdout();
  s.cmd("run 10 pre no post no");
  const std::string log = ::testing::internal::GetCapturedStdout();
  EXPECT_THAT(log, ContainsRegex("atoms changed clock at [0-9]+ of 10 coarse nodes"));
}

/* ----------------------------------------------------------------------
   a criterion that reads the neighbors of an atom (its coordination) is
   evaluated at the coarse node with every atom there, ghost atoms too:
   the clocks and so the trajectory are the same whether or not output at
   the nodes brought the ghost atoms there (the periodic images of the
   one-rank box are otherwise where the last fine step's evaluation left
   them: 3.6e-2 apart after 100 fine steps)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, NeighborCriterionSeesTheGhostAtomsAtTheNode)
{
  std::vector<double> x[2];
  for (const int written : {0, 1}) {
    Sim s;
    lj_liquid(s, 4);
    s.cmds({"compute crd all coord/atom cutoff 1.3", "variable few atom c_crd<11",
            "group fast dynamic all var few every 1", "fix 1 all pe_jump/async 5 fast",
            "timestep 0.025", written ? "thermo 1" : "thermo 0", "run 20"});
    x[written] = unwrapped_positions(s);
    EXPECT_GT(s.vec("1", 7) + s.vec("1", 8), 20.0);    // atoms on the fine clock
  }
  // thermo output makes its steps tally energies: round-off only
  EXPECT_LT(max_diff(x[0], x[1]), 1e-10);
}

/* ----------------------------------------------------------------------
   the dynamic fast group as output at the coarse nodes where it is
   updated is its criterion at the node (as with fix nve), also for a
   criterion of per-atom energies, which the force evaluation inside a
   step tallies for the fine interactions only. LAMMPS' own update, during
   the step, counted 864 of 864 atoms where the criterion at the node
   holds for 40 (potential energy), and 137 for 189 (kinetic energy). The
   check evaluates the criterion with computes of its own (a compute
   evaluated once in a step gives its cached values to every reader)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, DynamicGroupAsWrittenIsItsCriterionAtTheNode)
{
  for (const std::string crit : {"c_pea>-5.5", "c_kea>1.5", "x>5.0"}) {
    Sim s;
    lj_liquid(s, 6);
    const std::string check = std::regex_replace(crit, std::regex("c_(pea|kea)"), "c_$1_check");
    s.cmds({"compute pea all pe/atom", "compute kea all ke/atom", "compute pea_check all pe/atom",
            "compute kea_check all ke/atom", "variable infast atom " + crit,
            "group fast dynamic all var infast every 1", "variable flag atom " + check,
            "compute ntrue all reduce sum v_flag", "variable off equal abs(count(fast)-c_ntrue)",
            "variable fine equal f_1[8]+f_1[9]", "fix 1 all pe_jump/async 5 fast", "timestep 0.025",
            "fix seen all ave/time 1 1 1 v_off v_fine c_ntrue mode scalar ave running", "thermo 0",
            "run 20"});
    EXPECT_EQ(s.vec("seen", 0), 0.0) << crit;     // mean |count(fast) - criterion|
    EXPECT_GT(s.vec("seen", 1), 20.0) << crit;    // atoms on the fine clock
  }
}

/* ----------------------------------------------------------------------
   a run continued from a restart file, with the region moving on, gives
   the unbroken run's trajectory: the fine clock (a group of the fix) and
   the clocks' state are in the restart file
------------------------------------------------------------------------- */

TEST(PEJumpAsync, RestartAcrossClockChangesIsExact)
{
  for (const std::string rule : {"", " quadrature lobatto 3", " buffer 1"}) {
    std::vector<double> unbroken, restarted;
    double prd[3];
    {
      Sim s;
      moving_region(s, rule);
      s.cmds({"run 40"});
      unbroken = positions(s);
      for (int k = 0; k < 3; k++) prd[k] = s.lmp->domain->prd[k];
    }
    {
      Sim s;
      moving_region(s, rule);
      s.cmds({"run 20", "write_restart pe_jump_dyn.restart", "clear",
              "read_restart pe_jump_dyn.restart", "comm_modify cutoff 2.5", "neighbor 0.3 bin",
              "neigh_modify every 1 delay 0 check yes", "fix 2d all enforce2d",
              "variable xc equal 2.0+0.2*step",
              "region mov sphere v_xc 6.0621778 0 2.5 side in units box",
              "group fast dynamic all region mov every 1", "fix 1 all pe_jump/async 10 fast" + rule,
              "run 20"});
      restarted = positions(s);
      std::remove("pe_jump_dyn.restart");
    }
    // (the restart wraps atoms back into the periodic box)
    double worst = 0.0;
    for (size_t n = 0; n < unbroken.size(); n++) {
      const double box = prd[n % 3];
      const double d = restarted[n] - unbroken[n];
      worst = std::max(worst, std::fabs(d - box * std::round(d / box)));
    }
    EXPECT_LT(worst, 1e-13) << rule;    // the restart sorts the atoms: round-off
  }
}

/* ----------------------------------------------------------------------
   a restart across nodes where the dynamic group is evaluated but has not
   changed: the fix takes the buffer layers anew only when the group
   changed since its last assignment, which the restart file must tell
   (without it the continued run took other layers at the first node after
   the restart: 3.5e-3 off the unbroken run)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, RestartWithBufferAroundAStillGroupIsExact)
{
  const std::vector<std::string> fix = {"variable xc equal 2.0+0.01*step",
                                        "region mov sphere v_xc 3.0 3.0 1.5 side in units box",
                                        "group fast dynamic all region mov every 1",
                                        "fix 1 all pe_jump/async 10 fast buffer 1",
                                        "timestep 0.02",
                                        "thermo 1"};
  std::vector<double> unbroken, restarted;
  double prd[3];
  for (const int split : {0, 1}) {
    Sim s;
    lj_liquid(s, 4);
    s.cmds(fix);
    if (split) {
      s.cmds({"run 21", "write_restart pe_jump_still.restart", "clear",
              "read_restart pe_jump_still.restart", "pair_style lj/cut 2.5",
              "pair_coeff 1 1 1.0 1.0 2.5", "neighbor 0.3 bin",
              "neigh_modify every 1 delay 0 check yes"});
      s.cmds(fix);
      s.cmd("run 9");
      std::remove("pe_jump_still.restart");
      restarted = unwrapped_positions(s);
    } else {
      s.cmd("run 30");
      unbroken = unwrapped_positions(s);
    }
  }
  double worst = 0.0;
  for (size_t n = 0; n < unbroken.size(); n++)
    worst = std::max(worst, std::fabs(restarted[n] - unbroken[n]));
  EXPECT_LT(worst, 1e-12);    // the restart sorts the atoms: round-off
}

/* ----------------------------------------------------------------------
   read_restart restores a dynamic group as a static one: the fine clock
   would stop following it without a word (3.4e-3 off the unbroken run in
   a sweep), so the fix warns unless the group command is given again
------------------------------------------------------------------------- */

TEST(PEJumpAsync, DynamicGroupLostInARestartIsWarnedAbout)
{
  const std::vector<std::string> group = {"variable xc equal 2.0+0.1*step",
                                          "region mov sphere v_xc 3.0 3.0 1.5 side in units box",
                                          "group fast dynamic all region mov every 1"};
  for (const bool again : {false, true}) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s, 4);
    s.cmds(group);
    s.cmds({"timestep 0.02", "fix 1 all pe_jump/async 10 fast", "thermo 0", "run 2 post no",
            "write_restart pe_jump_dyn.restart", "clear", "read_restart pe_jump_dyn.restart",
            "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0 2.5", "neighbor 0.3 bin"});
    if (again) s.cmds(group);
    s.cmd("fix 1 all pe_jump/async 10 fast");
    ::testing::internal::CaptureStdout();
    s.cmd("run 1 post no");
    const std::string out = ::testing::internal::GetCapturedStdout();
    std::remove("pe_jump_dyn.restart");
    const bool warned =
        out.find("was dynamic when the restart file was written") != std::string::npos;
    EXPECT_EQ(warned, !again) << out;
  }
}

/* ----------------------------------------------------------------------
   buffer layers around a dynamic fast group in a liquid: the layers are
   the partners within the pair cutoff at the node, not the pairs of the
   neighbor lists (which hold the skin too and depend on when they were
   built), so a run split at any step, where the next run builds new
   lists, continues the unbroken one (with the lists' pairs: 9e-4 off)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, BufferAroundADynamicGroupIsTheSameInSplitRuns)
{
  const auto run = [](const std::vector<std::string> &runs) {
    Sim s;
    lj_liquid(s);
    s.cmds({"variable zc equal 2.0+0.1*step",
            "region mov sphere 3.36 3.36 v_zc 1.5 side in units box",
            "group fast dynamic all region mov every 1", "fix 1 all pe_jump/async 5 fast buffer 1",
            "timestep 0.01", "thermo 0"});
    s.cmds(runs);
    return unwrapped_positions(s);
  };
  const auto unbroken = run({"run 12"});
  EXPECT_LT(max_diff(unbroken, run({"run 7 post no", "run 5"})), 1e-12);
  EXPECT_LT(max_diff(unbroken, run({"run 4 post no", "run 8"})), 1e-12);
}

/* ----------------------------------------------------------------------
   fast auto TOL: an atom shot through a lattice of soft bonds at rest goes
   on the fine clock by itself (the fast group is empty); the choice stays
   local, and the momentum stays exact
------------------------------------------------------------------------- */

TEST(PEJumpAsync, FastAutoTakesAHotAtomOnTheFineClock)
{
  for (const std::string rule : {"", " quadrature lobatto 3"}) {
    Sim s;
    bonded_lattice(s, "block INF INF 0 1.6 INF INF", 0.5);
    s.cmds({"bond_coeff 2 1.0 1.0", "group fast id 100000", "velocity all set 0 0 0",
            "group hot id 90", "velocity hot set 2.0 1.0 0.0",
            "fix 1 all pe_jump/async 10 fast fast auto 0.1" + rule,
            "variable px equal mass(all)*vcm(all,x)", "variable py equal mass(all)*vcm(all,y)",
            "run 0"});
    const double p0[2] = {s.eval("v_px"), s.eval("v_py")};
    double worst = 0.0, most = 0.0;
    for (int block = 1; block <= 20; block++) {
      s.cmd("run 1 post no");
      worst =
          std::max({worst, std::fabs(s.eval("v_px") - p0[0]), std::fabs(s.eval("v_py") - p0[1])});
      most = std::max(most, s.vec("1", 7) + s.vec("1", 8));
      if (block == 1) EXPECT_EQ(on_fine_clock(s)[90], 1) << rule;
    }
    EXPECT_GE(most, 1.0) << rule;
    EXPECT_LT(most, 40.0) << rule;    // of 168: the choice is local
    EXPECT_LT(worst, 1e-13) << rule;
  }
}

/* ----------------------------------------------------------------------
   fast auto across a restart: the fix chooses the same atoms from the
   restored state, so the continued run is the unbroken one
------------------------------------------------------------------------- */

TEST(PEJumpAsync, FastAutoRestartIsExact)
{
  const std::string fix = "fix 1 all pe_jump/async 10 none fast auto 0.03";
  const auto setup = [](Sim &s) {
    bonded_lattice(s, "block INF INF 0 1.6 INF INF", 0.3);
    s.cmds({"bond_coeff 2 1.0 1.0", "group none id 0", "velocity all create 0.2 8191"});
  };
  std::vector<double> unbroken, restarted;
  double prd[3], changed = 0.0;
  {
    Sim s;
    setup(s);
    s.cmds({fix, "thermo 1", "run 20"});
    const auto fine0 = on_fine_clock(s);
    s.cmd("run 20");
    const auto fine1 = on_fine_clock(s);
    for (size_t id = 1; id < fine0.size(); id++) changed += (fine0[id] != fine1[id]) ? 1.0 : 0.0;
    unbroken = positions(s);
    for (int k = 0; k < 3; k++) prd[k] = s.lmp->domain->prd[k];
  }
  {
    Sim s;
    setup(s);
    s.cmds({fix, "thermo 1", "run 20", "write_restart pe_jump_auto.restart", "clear",
            "read_restart pe_jump_auto.restart", "comm_modify cutoff 2.5", "neighbor 0.3 bin",
            "neigh_modify every 1 delay 0 check yes", "fix 2d all enforce2d", fix, "run 20"});
    restarted = positions(s);
    std::remove("pe_jump_auto.restart");
  }
  EXPECT_GT(changed, 5.0);    // the choice changed across the restart
  double worst = 0.0;
  for (size_t n = 0; n < unbroken.size(); n++) {
    const double d = restarted[n] - unbroken[n];
    worst = std::max(worst, std::fabs(d - prd[n % 3] * std::round(d / prd[n % 3])));
  }
  EXPECT_LT(worst, 1e-13);    // the restart sorts the atoms: round-off
}

/* ----------------------------------------------------------------------
   the coarse step (and with it the fine step) may change from one step to
   the next (timestep between runs, fix dt/reset): the pseudo-energy stays
   conserved at the coarse nodes for an exact rule (lobatto 3 on the
   quartic chain, as in PseudoEnergyConservedAtCoarseNodes)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, StepChangesBetweenCoarseStepsKeepThePseudoEnergy)
{
  for (const std::string how : {"timestep", "dt/reset"}) {
    Sim s;
    chain(s);
    // compensate no: the jumps are carried over a new time step between runs
    s.cmds({"fix 1 chain pe_jump/async 10 fast quadrature lobatto 3 compensate no", "timestep 2e-3",
            "thermo 0", "run 0 post no"});
    const double h0 = s.eval("c_thermo_pe+f_1");
    if (how == "dt/reset") s.cmd("fix dt all dt/reset 1 1e-3 3e-3 0.0002 units box");
    double worst = 0.0, smallest = 2e-3, largest = 2e-3;
    for (int n = 0; n < 140; ++n) {
      // runs of one step: a new step at every coarse node
      if (how == "timestep") s.cmd(fmt::format("timestep {}", (n % 3 == 0) ? 1.5e-3 : 2.5e-3));
      s.cmd(how == "timestep" ? "run 1 pre no post no" : "run 1 post no");
      smallest = std::min(smallest, s.lmp->update->dt);
      largest = std::max(largest, s.lmp->update->dt);
      worst = std::max(worst, std::fabs(s.eval("c_thermo_pe+f_1") - h0));
    }
    EXPECT_LT(largest / smallest, 10.0) << how;
    EXPECT_GT(largest / smallest, 1.4) << how;    // the step did change
    // 1400 fine steps; the constant step gives 1.2e-14
    EXPECT_LT(worst / std::fabs(h0), 1e-13) << how;
  }
}

/* ----------------------------------------------------------------------
   pair styles whose pair forces act on other atoms than the two of the
   pair (TIP4P: the M site of an oxygen is made of its hydrogens; hydrogen
   bonds: the hydrogen) cannot be split by pair: checked by evaluating
   each style on one pair for each atom type. Without the check the total
   momentum of 128 flexible TIP4P waters drifted by 0.14 in 200 steps
   (the same waters with lj/cut/coul/cut: constant)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, PairForcesOnOtherAtomsAreRefused)
{
  const auto waters = [](const std::string &pair) {
    std::vector<std::string> c = {"units real",
                                  "atom_style full",
                                  "atom_modify map array",
                                  "region box block 0 10 0 10 0 10",
                                  "create_box 2 box bond/types 1 angle/types 1 "
                                  "extra/bond/per/atom 2 extra/angle/per/atom 1 "
                                  "extra/special/per/atom 2",
                                  "mass 1 1.008",
                                  "mass 2 15.9994"};
    int id = 0;
    for (int m = 0; m < 8; m++) {
      const double x = 1.0 + 5.0 * (m % 2), y = 1.0 + 5.0 * ((m / 2) % 2), z = 1.0 + 5.0 * (m / 4);
      c.push_back(fmt::format("create_atoms 2 single {} {} {} units box", x, y, z));
      c.push_back(fmt::format("create_atoms 1 single {} {} {} units box", x + 0.9572, y, z));
      c.push_back(fmt::format("create_atoms 1 single {} {} {} units box", x - 0.24, y + 0.927, z));
      c.push_back(fmt::format("set atom {}*{} mol {}", id + 1, id + 3, m + 1));
      c.push_back(fmt::format("set atom {} charge -1.0484", id + 1));
      c.push_back(fmt::format("set atom {}*{} charge 0.5242", id + 2, id + 3));
      c.push_back(fmt::format("create_bonds single/bond 1 {} {} special no", id + 1, id + 2));
      c.push_back(fmt::format("create_bonds single/bond 1 {} {} special no", id + 1, id + 3));
      c.push_back(
          fmt::format("create_bonds single/angle 1 {} {} {} special no", id + 2, id + 1, id + 3));
      id += 3;
    }
    c.insert(c.end(),
             {"special_bonds lj/coul 0.0 0.0 0.5", pair, "pair_coeff 2 2 0.1852 3.1589",
              "pair_coeff 1 * 0.0 0.0", "bond_style harmonic", "bond_coeff 1 450 0.9572",
              "angle_style harmonic", "angle_coeff 1 55 104.52",
              "velocity all create 300 4711 mom yes", "neighbor 2.0 bin", "group fast id 1:3",
              "variable px equal mass(all)*vcm(all,x)", "fix 1 all pe_jump/async 4 fast",
              "timestep 1.0", "thermo 0"});
    return c;
  };
  EXPECT_THAT(error_of(waters("pair_style lj/cut/tip4p/cut 2 1 1 1 0.1546 8.0"), "run 1"),
              ContainsRegex("cannot split pair style lj/cut/tip4p/cut: the force of a pair "
                            "acts on other atoms"));
  Sim s;
  s.cmds(waters("pair_style lj/cut/coul/cut 8.0"));
  s.cmd("special_bonds lj/coul 0.0 0.0 0.5");
  s.cmd("run 0 post no");
  const double p0 = s.eval("v_px");
  s.cmd("run 10 post no");
  EXPECT_NEAR(s.eval("v_px"), p0, 1e-10);
}

/* ----------------------------------------------------------------------
   every step is a coarse step and ends at a coarse node: the log tells
   both steps at every run, output and sampling fixes at any interval and
   runs of any length see every atom at its node, with no warning. The
   total momentum (node velocities) sampled at every step stays what it
   was, a temperature set by the velocity command after a run of 13 steps
   is the one output at the next
------------------------------------------------------------------------- */

TEST(PEJumpAsync, EveryStepEndsAtACoarseNode)
{
  Sim s(MPI_COMM_WORLD, false);
  lj_liquid(s);
  s.cmds({"group fast id 1:20", "fix 1 all pe_jump/async 5 fast", "timestep 0.025", "thermo 3",
          "variable px equal mass(all)*vcm(all,x)", "variable py equal mass(all)*vcm(all,y)",
          "fix avg all ave/time 1 1 1 c_thermo_temp", "fix px all vector 1 v_px v_py",
          "fix other all store/state 3 vx", "run 0 post no"});
  const double p0[2] = {s.eval("v_px"), s.eval("v_py")};
  ::testing::internal::CaptureStdout();
  s.cmd("run 13 post no");
  s.cmd("timestep 0.02");
  s.cmd("run 7 post no");
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_THAT(out,
              ContainsRegex("Fix pe_jump/async: coarse step h_S = 0.025 \\(the time step\\), "
                            "fine step h_F = h_S/K = 0.005 \\(K = 5\\)"));
  EXPECT_THAT(out,
              ContainsRegex("Fix pe_jump/async: coarse step h_S = 0.02 \\(the time step\\), "
                            "fine step h_F = h_S/K = 0.004 \\(K = 5\\)"));
  EXPECT_THAT(out, Not(ContainsRegex("WARNING")));
  EXPECT_EQ(s.vec("1", 2), 0.02);    // h_S
  EXPECT_EQ(s.vec("1", 5), 1.0);     // at a coarse node
  auto *sampled = s.lmp->modify->get_fix_by_id("px");
  ASSERT_EQ(sampled->size_array_rows, 21);    // step 0 and the 20 steps
  double worst = 0.0;
  for (int n = 0; n < sampled->size_array_rows; n++)
    for (int k = 0; k < 2; k++)
      worst = std::max(worst, std::fabs(sampled->compute_array(n, k) - p0[k]));
  EXPECT_LT(worst, 1e-12);
  s.cmds({"unfix px", "unfix avg", "unfix other", "velocity all scale 1.25", "run 0 post no"});
  EXPECT_NEAR(s.eval("temp"), 1.25, 1e-12);
}

/* ----------------------------------------------------------------------
   a pair style whose forces depend on the time or the step (pair_style
   hybrid/scaled with a variable of time) was taken at the step end at
   every node: first order (two LJ atoms, K = 1, every atom fast: error
   ratio 2.1 per halving of the step, 46 times fix pe_jump's error at the
   smallest step). Refused; a constant scale runs
------------------------------------------------------------------------- */

TEST(PEJumpAsync, PairStyleThatDependsOnTimeIsRefused)
{
  const auto liquid = [](const std::string &scale) {
    return std::vector<std::string>{"units lj",
                                    "atom_style atomic",
                                    "lattice fcc 0.8442",
                                    "region box block 0 3 0 3 0 3",
                                    "create_box 1 box",
                                    "create_atoms 1 box",
                                    "mass 1 1.0",
                                    "velocity all create 1.0 4711 loop geom",
                                    "variable s equal 1.0+0.5*sin(20*time)",
                                    "variable r equal ramp(1.0,2.0)",
                                    "variable w equal 0.6+0.4*(time>0.015)",
                                    "variable p equal 0.6+0.1*((step%7)>0)",
                                    "pair_style hybrid/scaled " + scale + " lj/cut 2.5",
                                    "pair_coeff 1 1 lj/cut 1.0 1.0",
                                    "group fast id 1:20",
                                    "fix 1 all pe_jump/async 4 fast",
                                    "timestep 0.008",
                                    "thermo 0",
                                    "run 2 post no"};
  };
  // (a switch inside the run, a period of 7 steps: found by a sweep)
  for (const std::string scale : {"v_s", "v_r", "v_w", "v_p"})
    EXPECT_THAT(error_of(liquid(scale)), ContainsRegex("forces depend on the time")) << scale;
  EXPECT_EQ(error_of(liquid("0.8")), "no error");
}

/* ----------------------------------------------------------------------
   after a run of any length every atom is at its node with its node
   velocity: the velocity command acts on these (velocity all set, scale,
   zero linear and create give exactly the temperature and momentum they
   set, from a liquid with a momentum), velocities changed for the fast
   group alone restart the scheme, and a data file holds the node: a run
   continued from it is the run continued with the fix defined anew
   (which starts the scheme from the same state)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, VelocitiesAndDataFilesAfterARunAreTheNode)
{
  const std::vector<std::string> system = {"units lj", "atom_style atomic",
                                           "atom_modify map array"};
  const std::vector<std::string> integrate = {
      "group fast id 1:50", "fix 1 all pe_jump/async 5 fast", "timestep 0.01", "thermo 0"};
  const auto base = [&](Sim &s) {
    s.cmds(system);
    s.cmds({"lattice fcc 0.8442", "region box block 0 4 0 4 0 4", "create_box 1 box",
            "create_atoms 1 box", "mass 1 1.0", "velocity all create 1.5 87287 loop geom mom no",
            "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0 2.5"});
    s.cmds(integrate);
    s.cmds({"variable px equal mass(all)*vcm(all,x)", "variable py equal mass(all)*vcm(all,y)",
            "run 13 post no"});
  };
  // the temperature set (< 0: not set) and the factor of the momentum
  const std::vector<std::tuple<std::string, double, double>> velocities = {
      {"velocity all set 0 0 0", 0.0, 0.0},
      {"velocity all scale 1.25", 1.25, -1.0},
      {"velocity all zero linear", -1.0, 0.0},
      {"velocity all create 1.0 4711 loop geom", 1.0, 0.0}};
  for (const auto &[cmd, temp, factor] : velocities) {
    Sim s;
    base(s);
    const double p0[2] = {s.eval("v_px"), s.eval("v_py")};
    const double t0 = s.eval("temp");
    EXPECT_GT(std::fabs(p0[0]), 1e-3) << cmd;
    s.cmds({cmd, "run 0 post no"});
    if (temp >= 0.0) EXPECT_NEAR(s.eval("temp"), temp, 1e-12) << cmd;
    const double f = (factor >= 0.0) ? factor : std::sqrt(temp / t0);
    EXPECT_NEAR(s.eval("v_px"), f * p0[0], 1e-12) << cmd;
    EXPECT_NEAR(s.eval("v_py"), f * p0[1], 1e-12) << cmd;
    s.cmd("run 2 post no");
    EXPECT_EQ(s.lmp->update->ntimestep, 15) << cmd;
  }
  {
    // the fine clock alone: the scheme restarts, the momentum of the slow
    // atoms stays theirs
    Sim s(MPI_COMM_WORLD, false);
    base(s);
    s.cmd("velocity fast set 0 0 0");
    ::testing::internal::CaptureStdout();
    s.cmd("run 2 post no");
    const std::string out = ::testing::internal::GetCapturedStdout();
    EXPECT_THAT(out, ContainsRegex("velocities were changed since the last run"));
  }
  // the data file against the fix defined anew
  std::vector<double> refixed, continued;
  {
    Sim s;
    base(s);
    s.cmds({"unfix 1", integrate[1], "run 10 post no"});
    refixed = unwrapped_positions(s);
  }
  {
    Sim s;
    base(s);
    s.cmd("write_data pe_jump_async_node.data");
    Sim t;
    t.cmds(system);
    t.cmds({"pair_style lj/cut 2.5", "read_data pe_jump_async_node.data"});
    t.cmds(integrate);
    t.cmd("run 10 post no");
    continued = unwrapped_positions(t);
    std::remove("pe_jump_async_node.data");
  }
  EXPECT_LT(max_diff(refixed, continued), 1e-10);
}

/* ----------------------------------------------------------------------
   the scheme restarts between runs (moved atoms, a new time step, the fix
   defined anew) from the node positions and velocities, and the total
   momentum stays what it was; fix nve after the fix takes the node
   velocities on
------------------------------------------------------------------------- */

TEST(PEJumpAsync, RestartBetweenRunsKeepsTheMomentum)
{
  const std::vector<std::vector<std::string>> between = {
      {"displace_atoms one move 1e-6 0 0 units box"},
      {"timestep 0.0105"},
      {"unfix 1", "fix 1 all pe_jump/async 5 fast"},
      {"unfix 1", "fix 2 all nve"}};
  for (const auto &cmds : between) {
    Sim s;
    lj_liquid(s, 4);
    s.cmds({"region slab block 0 1.5 INF INF INF INF", "group fast region slab", "group one id 7",
            "variable px equal mass(all)*vcm(all,x)", "variable py equal mass(all)*vcm(all,y)",
            "fix 1 all pe_jump/async 5 fast", "timestep 0.01", "thermo 0", "run 0 post no"});
    const double p0[2] = {s.eval("v_px"), s.eval("v_py")};
    s.cmd("run 20 post no");
    s.cmds(cmds);
    s.cmd("run 4 post no");
    const double p1[2] = {s.eval("v_px"), s.eval("v_py")};
    EXPECT_NEAR(p1[0], p0[0], 1e-10) << cmds.back();
    EXPECT_NEAR(p1[1], p0[1], 1e-10) << cmds.back();
  }
}
