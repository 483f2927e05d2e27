// physics and interface tests of fix pe_jump/async through the LAMMPS C++
// API: classification, equality with fix pe_jump for K = 1, pseudo-energy
// conservation at coarse nodes, convergence orders, evaluation counts
// against the paper's formulas and against the work the force styles see,
// split runs and restarts inside a coarse step, error messages

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

// chain at time T with fix pe_jump/async (K >= 1) or fix pe_jump (K = 0)
std::vector<double> chain_at(double T, double hf, int K, const std::string &rule)
{
  Sim s;
  chain(s);
  const std::string fix = K
      ? fmt::format("fix 1 chain pe_jump/async {} fast quadrature {}", K, rule)
      : "fix 1 chain pe_jump quadrature " + rule;
  const int nsteps = static_cast<int>(std::lround(T / hf));
  s.cmds({fix, fmt::format("timestep {:.17g}", hf), "thermo 0",
          fmt::format("run {} post no", nsteps)});
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
      s.cmds({"fix 1 chain pe_jump/async 10 fast quadrature " + rule, "timestep 2e-3", "thermo 0",
              "run 1000 post no"});
      (use_hybrid ? hybrid : one) = chain_q(s);
    }
    EXPECT_LT(max_diff(one, hybrid), 1e-13) << rule;
    EXPECT_GT(max_diff(one, chain_q_at_start()), 1e-2) << rule;    // the chain moved
  }
}

/* ----------------------------------------------------------------------
   classes on the paper's chain: q_1, q_2 fast, q_3 mixed, q_4..q_6 slow
------------------------------------------------------------------------- */

TEST(PEJumpAsync, ClassifiesSlowMixedFast)
{
  Sim s;
  chain(s);
  s.cmds({"fix 1 chain pe_jump/async 10 fast", "timestep 1e-3", "thermo 0", "run 0 post no"});
  EXPECT_EQ(s.vec("1", 6), 3.0);    // slow
  EXPECT_EQ(s.vec("1", 7), 1.0);    // mixed
  EXPECT_EQ(s.vec("1", 8), 2.0);    // fast
  const double *klass = s.lmp->modify->get_fix_by_id("1")->vector_atom;
  const double expected[8] = {-1, 2, 2, 1, 0, 0, 0, -1};
  for (int id = 1; id <= 8; ++id) EXPECT_EQ(klass[s.lmp->atom->map(id)], expected[id - 1]) << id;
  // coarse-node flag: 1 at coarse nodes only
  s.cmd("run 3 post no");
  EXPECT_EQ(s.vec("1", 5), 0.0);
  s.cmd("run 7 post no");
  EXPECT_EQ(s.vec("1", 5), 1.0);
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
   the neighbor lists hold every pair at every node: with a small skin
   (0.15; the fastest slow atoms move about 0.06 over a coarse step of
   K = 5) the run equals one that rebuilds the lists before every step
------------------------------------------------------------------------- */

TEST(PEJumpAsync, ListsHoldEveryPairAtEveryNode)
{
  const auto run = [](const std::string &rule, const std::string &lists) {
    Sim s;
    lj_liquid(s, 3);
    s.cmds({"velocity all scale 0.5", "neighbor 0.15 bin", "neigh_modify " + lists,
            "region slab block 0 1 INF INF INF INF units lattice", "group fast region slab",
            "fix 1 all pe_jump/async 5 fast quadrature " + rule, "timestep 0.005", "thermo 0",
            "run 300"});
    return std::make_pair(unwrapped_positions(s), s.lmp->neighbor->ncalls);
  };
  for (const std::string rule : {"midpoint", "lobatto 3", "legendre 2"}) {
    const auto always = run(rule, "every 1 delay 0 check no");
    // LAMMPS checks the primary nodes every step, or every 20th step: then
    // the fix asks for the rebuilds in between
    for (const std::string every : {"1", "20"}) {
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
// max relative deviation of pe + f_1 at coarse nodes over ncoarse coarse steps
double coarse_node_drift(Sim &s, int K, int ncoarse)
{
  s.cmds({"thermo 0", "run 0 post no"});
  const double h0 = s.eval("c_thermo_pe+f_1");
  double worst = 0.0;
  for (int n = 0; n < ncoarse; ++n) {
    s.cmd(fmt::format("run {} pre no post no", K));
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
    s.cmds({"fix 1 chain pe_jump/async 50 fast quadrature lobatto 3", "timestep 2e-4"});
    const double drift = coarse_node_drift(s, 50, 1000);
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
            "fix 1 all pe_jump/async 7 fast quadrature midpoint", "timestep 0.01"});
    const double drift = coarse_node_drift(s, 7, 1000);
    std::cout << "harmonic ring, midpoint, K=7: " << drift << "\n";
    EXPECT_LT(drift, 3e-12);
  }
  {
    // the midpoint rule is not exact on quartic springs: the pseudo-energy
    // varies, which shows that the test above can fail
    Sim s;
    chain(s);
    s.cmds({"fix 1 chain pe_jump/async 50 fast quadrature midpoint", "timestep 2e-4"});
    EXPECT_GT(coarse_node_drift(s, 50, 200), 1e-9);
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
  for (int K : {40, 80, 160, 320}) {
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
  // T = 1, h_S = 0.01, h_F = 2e-4, lobatto 5 (4 evaluations per step)
  const double T = 1.0, hs = 0.01, hf = 2e-4;
  const int n = 5, nsteps = 5000;
  double count[2];
  for (int k = 0; k < 2; ++k) {
    Sim s;
    (*s.lmp->force->bond_map)["class2/counting"] = &bond_counting_creator;
    chain(s);
    s.cmds({"bond_style class2/counting", "bond_coeff 1 1.5 2.5 0.0 0.0",
            "bond_coeff 2 1.5 0.0 0.0 1.0",
            k ? "fix 1 chain pe_jump/async 50 fast quadrature lobatto 5"
              : "fix 1 chain pe_jump quadrature lobatto 5",
            "timestep 2e-4", "thermo 0", "run 0 post no"});
    BondCounting::computed = 0.0;
    s.cmd(fmt::format("run {} pre no post no", nsteps));
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
          "timestep 0.005", "thermo 0", "neigh_modify every 1 delay 0 check no", "run 0 post no"});
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
  s.cmd("run 100 pre no post no");
  // the split is rebuilt with the lists every step: per step the fine
  // pairs, every 5th step the others, plus the full energy evaluation at the
  // last step; reported and seen by the pair style alike
  const double reported = s.vec("1", 4);
  const double expected = 100 * (fine / all) + 20 * (1.0 - fine / all) + 1.0;
  EXPECT_NEAR(reported, expected, 1e-9 * expected);
  EXPECT_NEAR(reported, PairCounting::computed / all, 1e-9 * expected);
  EXPECT_LT(reported, 0.7 * 101);    // fix pe_jump: 101
}

/* ----------------------------------------------------------------------
   split runs and restarts at any step, including inside a coarse step
------------------------------------------------------------------------- */

TEST(PEJumpAsync, SplitRunsAndRestartsInsideCoarseStepAreExact)
{
  for (const std::string rule : {"midpoint", "lobatto 3", "lobatto 3 buffer 1"}) {
    const std::string fix = "fix 1 chain pe_jump/async 20 fast quadrature " + rule;
    std::vector<double> unbroken, split, restarted;
    {
      Sim s;
      chain(s);
      s.cmds({fix, "timestep 5e-4", "thermo 0", "run 1000 post no"});
      unbroken = chain_q(s);
    }
    {
      Sim s;
      chain(s);
      s.cmds({fix, "timestep 5e-4", "thermo 0", "run 333 post no", "run 667 post no"});
      split = chain_q(s);
    }
    {
      Sim s;
      chain(s);
      s.cmds({fix, "timestep 5e-4", "thermo 0", "run 333 post no"});
      EXPECT_EQ(s.vec("1", 5), 0.0);    // inside a coarse step
      s.cmds({"write_restart pe_jump_async.restart", "clear", "read_restart pe_jump_async.restart",
              "comm_modify cutoff 4.0", fix, "thermo 0", "run 667 post no"});
      restarted = chain_q(s);
      std::remove("pe_jump_async.restart");
    }
    EXPECT_LT(max_diff(unbroken, split), 1e-14) << rule;
    EXPECT_LT(max_diff(unbroken, restarted), 1e-14) << rule;
    EXPECT_GT(max_diff(unbroken, Q0), 1e-2);
  }
}

/* ----------------------------------------------------------------------
   with neigh_modify check no the lists are rebuilt every N steps wherever
   the atoms are, and pairs beyond the skin are missed. A continued run
   builds its lists at the step end (the atoms moving with the fine steps
   there, the slow ones caught up); the unbroken run must build them there
   too, or another set of pairs is missed: LAMMPS' melt example settings
   (T = 3, every 20 check no), K = 3, were 1.1e-3 off for midpoint and
   1.2e-3 for legendre 2 (fix nve 5e-14)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, SplitRunsAndRestartsUnderNeighCheckNoAreExact)
{
  for (const std::string rule : {"midpoint", "legendre 2", "lobatto 3"}) {
    // (the restart file keeps the group)
    const std::vector<std::string> setup = {"neigh_modify every 20 delay 0 check no",
                                            "fix 1 all pe_jump/async 3 fast quadrature " + rule,
                                            "timestep 0.005", "thermo 0"};
    const auto state = [&](const std::vector<std::string> &runs) {
      Sim s;
      lj_liquid(s, 5, "dist gaussian");
      s.cmds({"velocity all scale 3.0", "region left block 0 2.5 INF INF INF INF",
              "group fast region left"});
      s.cmds(setup);
      s.cmds(runs);
      return unwrapped_positions(s);
    };
    const auto unbroken = state({"run 200 post no"});
    for (const int at : {60, 100}) {
      const auto split =
          state({fmt::format("run {} post no", at), fmt::format("run {} post no", 200 - at)});
      std::vector<std::string> restart = {
          fmt::format("run {} post no", at), "write_restart pe_jump_async_checkno.restart", "clear",
          "read_restart pe_jump_async_checkno.restart", "neighbor 0.3 bin"};
      restart.insert(restart.end(), setup.begin(), setup.end());
      restart.push_back(fmt::format("run {} post no", 200 - at));
      const auto restarted = state(restart);
      std::remove("pe_jump_async_checkno.restart");
      EXPECT_LT(max_diff(unbroken, split), 1e-11) << rule << ", split at " << at;
      EXPECT_LT(max_diff(unbroken, restarted), 1e-11) << rule << ", restart at " << at;
    }
  }
}

/* ----------------------------------------------------------------------
   lists built every 5 steps whatever the atoms do (check no), at a
   temperature where no pair leaves the skin in 5 steps, give the
   trajectory of lists checked every step: the atoms moved to the step end
   for the build must all come back (the slow atoms that sit out included;
   when they stayed at the step end, the coarse forces were taken there
   and etotal fell by 6.3e-4 at every build, K = 1 and 3)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, ListsBuiltWhateverTheAtomsDoKeepTheTrajectory)
{
  for (const std::string rule : {"midpoint", "legendre 2", "lobatto 3"})
    for (const int k : {1, 3}) {
      const auto state = [&](const std::string &lists) {
        Sim s;
        lj_liquid(s, 8);    // (slow atoms beyond the cutoff of every fast one)
        s.cmds({lists, "region left block 0 2 INF INF INF INF", "group fast region left",
                fmt::format("fix 1 all pe_jump/async {} fast quadrature {}", k, rule),
                "timestep 0.005", "thermo 0", "run 201 post no"});
        return unwrapped_positions(s);
      };
      const auto checked = state("neigh_modify every 1 delay 0 check yes");
      const auto forced = state("neigh_modify every 5 delay 0 check no");
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
                                        "timestep 0.005", "thermo 0"};
  Sim s;
  lj_liquid(s);
  s.cmds({"compute t all temp", "fix 2 all ave/time 1 1 1 c_t", "fix 3 all nve", "uncompute t"});
  EXPECT_THROW(s.cmd("run 5 post no"), LAMMPS_NS::LAMMPSException);
  s.cmds({"unfix 2", "unfix 3"});
  s.cmds(fix);
  std::string error = "no error";
  try {
    s.cmd("run 20 post no");
  } catch (LAMMPS_NS::LAMMPSException &e) {
    error = e.what();
  }
  EXPECT_EQ(error, "no error");
  Sim fresh;
  lj_liquid(fresh);
  fresh.cmds(fix);
  fresh.cmd("run 20 post no");
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
  s.cmds({"group fast id 1:20", "timestep 0.005", "thermo 0"});
  std::string error = "no error";
  try {
    for (int n = 1; n <= 40; n++)
      s.cmds({fmt::format("fix f{} all pe_jump/async 5 fast buffer 1", n), "run 5 post no",
              fmt::format("unfix f{}", n)});
  } catch (LAMMPS_NS::LAMMPSException &e) {
    error = e.what();
  }
  EXPECT_EQ(error, "no error");
  EXPECT_LT(s.lmp->group->find("f40_fine_clock"), 0);
  s.cmds({"fix kept all pe_jump/async 5 fast buffer 1", "run 5 post no",
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
      error_of(with({"fix 1 all pe_jump/async 5 fast", "fix 2 all addforce 1 0 0"}), "run 1"),
      ContainsRegex("cannot yet be combined with fix 2 \\(addforce\\)"));
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
  // ring of 20, E = 10 (r-1)^2: omega_max = 2 sqrt(20), CFL h < 0.2236
  auto ring = [](Sim &s, int K) {
    harmonic_ring(s, 20, 10.0, 1.0, 7);
    // slow atoms move up to ~0.15 per coarse step: the skin must cover it
    s.cmds({"neighbor 1.0 bin", "group fast id 1:10",
            fmt::format("fix 1 all pe_jump/async {} fast", K), "timestep 0.01", "thermo 100",
            "thermo_style custom step pe f_1[1] f_1[2]"});
  };
  {
    Sim s;
    ring(s, 15);    // h_S = 0.15
    s.cmd("run 20000 post no");
    EXPECT_TRUE(std::isfinite(s.vec("1", 1)));
    EXPECT_LT(s.vec("1", 1), 1.0);    // jump energy stays small
  }
  {
    Sim s(MPI_COMM_WORLD, false);
    ring(s, 30);    // h_S = 0.3
    ::testing::internal::CaptureStdout();
    std::string what;
    try {
      s.cmd("run 20000 post no");
    } catch (LAMMPS_NS::LAMMPSException &e) {
      what = e.what();
    }
    const std::string out = ::testing::internal::GetCapturedStdout();
    EXPECT_THAT(what, ContainsRegex("is unstable at step [0-9]+"));
    EXPECT_THAT(what, ContainsRegex("the coarse step 0.3 \\(slow atoms\\)"));
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
    s.cmds({fmt::format("fix 1 chain pe_jump/async 10 fast buffer {}", layers), "timestep 1e-3",
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
          "neighbor 0.3 bin", "group fast id 55", "fix 2d all enforce2d", "thermo 0"});
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
    s.cmds({"fix 1 all pe_jump/async 5 fast buffer 1 within 1.2", "run 10 post no",
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
   with one buffer layer it is stable and keeps the pseudo-energy
------------------------------------------------------------------------- */

TEST(PEJumpAsync, BufferRemovesTheInterfaceResonanceOfTheWave)
{
  constexpr int N = 250;
  auto wave = [](Sim &s, const std::string &extra) {
    inhomogeneous_wave(s, N);
    s.cmds({"compute epot all pe", "fix 1 chain pe_jump/async 10 fast" + extra,
            fmt::format("timestep {:.17g}", 0.1 / N), "variable Ht equal c_epot+f_1",
            "thermo_style custom step c_epot f_1 f_1[2] v_Ht", "thermo 10"});
  };
  {
    Sim s;
    wave(s, "");
    std::string what;
    try {
      s.cmd("run 20000 post no");
    } catch (LAMMPS_NS::LAMMPSException &e) {
      what = e.what();
    }
    EXPECT_THAT(what, ContainsRegex("is unstable at step [0-9]+"));
  }
  {
    Sim s;
    wave(s, " buffer 1");
    s.cmd("run 0 post no");
    const double ht0 = s.eval("v_Ht");
    double jfirst = 0.0, jlast = 0.0, dht = 0.0;
    for (int block = 0; block < 20; ++block) {
      s.cmd("run 1000 post no");    // coarse nodes: multiples of K
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
   reversing all velocities continues backwards in time at a coarse node;
   inside a coarse step, where the slow atoms have no node velocity, the
   scheme restarts and says so
------------------------------------------------------------------------- */

TEST(PEJumpAsync, VelocityReversalAtCoarseNodesOnly)
{
  for (const int nsteps : {340, 333}) {    // K = 20: a coarse node, and inside a coarse step
    Sim s(MPI_COMM_WORLD, false);
    ::testing::internal::CaptureStdout();
    chain(s);
    s.cmds({"fix 1 chain pe_jump/async 20 fast quadrature lobatto 3", "timestep 5e-4", "thermo 0",
            fmt::format("run {} post no", nsteps)});
    for (int i = 0; i < s.lmp->atom->nlocal; ++i)
      for (int k = 0; k < 3; ++k) s.lmp->atom->v[i][k] = -s.lmp->atom->v[i][k];
    std::string error = "no error";
    try {
      s.cmd(fmt::format("run {} post no", nsteps));
    } catch (LAMMPS_NS::LAMMPSException &e) {
      error = e.what();
    }
    const std::string out = ::testing::internal::GetCapturedStdout();
    if (nsteps == 340) {
      EXPECT_THAT(out, ContainsRegex("all velocities were reversed"));
      EXPECT_LT(max_diff(chain_q(s), Q0), 1e-11);
    } else {    // the slow atoms have no velocity to reverse there
      EXPECT_THAT(error, ContainsRegex("velocities of slow atoms were changed"));
    }
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
    try {
      s.cmd("run 1");
      ADD_FAILURE() << "a pair style with forces outside its lists was not refused";
    } catch (LAMMPS_NS::LAMMPSException &e) {
      EXPECT_THAT(e.what(), ContainsRegex("computes forces that are not in its neighbor lists"));
    }
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
    try {
      s.cmd("run 1");
      ADD_FAILURE() << "a pair style whose pair forces do not add up was not refused";
    } catch (LAMMPS_NS::LAMMPSException &e) {
      EXPECT_THAT(e.what(), ContainsRegex("the force of two pairs of an atom is not the sum"));
    }
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
   fixes that act on the forces are refused with advice that fits them:
   atoms held by fix setforce can be left out of the fix group (frozen
   scenery); an indenter cannot (it was advised to leave held atoms out of
   the fix group), nor can a force that fix addforce adds
------------------------------------------------------------------------- */

TEST(PEJumpAsync, ForceFixesAreRefusedWithAdviceThatFits)
{
  const auto error_with = [](const std::string &other) {
    return error_of({"units lj", "atom_style atomic", "lattice fcc 0.8442",
                     "region box block 0 3 0 3 0 3", "create_box 1 box", "create_atoms 1 box",
                     "mass 1 1.0", "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0 2.5",
                     "region f block 0 1 INF INF INF INF", "group fast region f",
                     "fix 1 all pe_jump/async 5 fast", other, "thermo 0"},
                    "run 1");
  };
  EXPECT_THAT(error_with("fix 2 fast setforce 0.0 0.0 0.0"),
              ContainsRegex("fix 2 \\(setforce\\).*Hold atoms by leaving them out of the fix "
                            "group \\(frozen scenery\\), or use fix pe_jump"));
  const std::string indent = error_with("fix 2 all indent 10.0 sphere 2.5 2.5 2.5 0.4");
  EXPECT_THAT(indent,
              ContainsRegex("fix 2 \\(indent\\): the indenter pushes atoms with a force "
                            "that depends on their positions.*Use fix pe_jump"));
  EXPECT_THAT(indent, Not(ContainsRegex("Hold atoms|out of the fix group")));
  const std::string added = error_with("fix 2 all addforce 0.1 0.0 0.0");
  EXPECT_THAT(added, ContainsRegex("fix 2 \\(addforce\\), which adds forces.*Use fix pe_jump"));
  EXPECT_THAT(added, Not(ContainsRegex("Hold atoms|out of the fix group")));
}

/* ----------------------------------------------------------------------
   velocities changed by other fixes during a run are refused (fix pe_jump
   takes them as impulses); output fixes at the end of a step are fine.
   Fixes made to change velocities (thermostats that rescale them, fix
   momentum, heat and momentum exchanges) are refused at setup, before the
   first step: before, at the first coarse node after their first action
   (temp/berendsen: step 6; fix momentum 100: step 101, and not at all in
   a run of 50 steps)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, VelocityChangesByOtherFixesAreRefused)
{
  const auto run_with = [](const std::string &other) {
    Sim s;
    lj_liquid(s, 3);
    s.cmds({"region f block 0 1 INF INF INF INF", "group fast region f",
            "fix 1 all pe_jump/async 5 fast", other, "timestep 0.004", "thermo 0"});
    s.cmd("run 50 post no");
  };
  EXPECT_NO_THROW(run_with("fix 2 all ave/time 1 10 10 c_thermo_temp"));
  for (const std::string other :
       {"fix 2 all temp/berendsen 1.0 1.0 0.1", "fix 2 all momentum 1 linear 1 1 1",
        "fix 2 all temp/rescale 7 1.0 1.0 0.01 1.0", "fix 2 all temp/csvr 1.0 1.0 0.1 5533",
        "fix 2 all momentum 100 linear 1 1 1", "fix 2 all heat 10 0.1",
        "fix 2 all viscosity 50 x z 10", "fix 2 all thermal/conductivity 50 z 10"}) {
    Sim s;
    lj_liquid(s, 3);
    s.cmds({"region f block 0 1 INF INF INF INF", "group fast region f",
            "fix 1 all pe_jump/async 5 fast", other, "timestep 0.004", "thermo 0"});
    try {
      s.cmd("run 50 post no");
      ADD_FAILURE() << other << " was not refused";
    } catch (LAMMPS_NS::LAMMPSException &e) {
      EXPECT_THAT(e.what(),
                  ContainsRegex("cannot yet be combined with fix 2 \\(.*\\), which "
                                "changes velocities during the run"))
          << other;
      EXPECT_EQ(s.lmp->update->ntimestep, 0) << other;
    }
  }
}

/* ----------------------------------------------------------------------
   fix wall/reflect changes velocities inside a step: refused whether the
   reflected atom is on the fine clock or on the coarse one (whose
   velocity the fix keeps over the coarse step), also when it happens in
   the last coarse step of the run
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
            "fix w all wall/reflect zlo EDGE", "timestep 0.01", "thermo 0"});
    try {
      s.cmd(fmt::format("run {}", steps));
    } catch (LAMMPS_NS::LAMMPSException &e) {
      return std::string(e.what());
    }
    // without the refusal the atom bounced: its velocity points up
    return fmt::format("no error, vz {}", s.lmp->atom->v[s.lmp->atom->map(1)][2]);
  };
  // atom 1 reaches the wall at t = 0.5 (step 50)
  for (const std::string fast : {"1", "2"})
    for (const int steps : {200, 60}) {
      EXPECT_THAT(error_with(fast, steps), ContainsRegex("changed velocities during the run"))
          << "fast group: atom " << fast << ", run " << steps;
    }
}

/* ----------------------------------------------------------------------
   the opt-in "atom_modify first G" + "neigh_modify include G" (G holds
   the atoms on the fine clock): LAMMPS then clears the forces and checks
   the distances of the atoms of G only, the fix those of the others that
   need it. The trajectory is that of the same input without the opt-in:
   bit for bit if the atoms of G are stored first anyway (a band of the
   lowest IDs), to round-off if LAMMPS reorders them (a disc in the
   middle: the order of the force sums changes); the lists are rebuilt at
   the same steps
------------------------------------------------------------------------- */

namespace {

// 2d triangular lattice (spacing 1, 168 atoms) of harmonic bonds, no pair
// style: the atoms in region core are type 2, group stiff (stiff bonds among
// them); region wide is the band core with the rows next to it (periodic)
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
          "region below block INF INF 0 2.6 INF INF",
          "region above block INF INF 6.4 INF INF INF",
          "region wide union 2 below above",
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
          "timestep 0.005"});
}

struct LatticeRun {
  std::vector<double> x;
  LAMMPS_NS::bigint builds;    // neighbor list builds
  int nfirst;                  // owned atoms that LAMMPS clears and checks
};

// include: the group of the opt-in ("" = without it, then without sorting
// too, which atom_modify first turns off)
LatticeRun lattice_run(const std::string &core, const std::string &include,
                       const std::vector<std::string> &run, double skin)
{
  Sim s;
  bonded_lattice(s, core, skin);
  if (include.empty()) {
    s.cmd("atom_modify sort 0 0.0");
  } else {
    s.cmds({"group fine " + include, "atom_modify first fine", "neigh_modify include fine"});
  }
  s.cmds(run);
  return {positions(s), s.lmp->neighbor->ncalls,
          include.empty() ? s.lmp->atom->nlocal : s.lmp->atom->nfirst};
}

}    // namespace

TEST(PEJumpAsync, IncludeGroupKeepsTheTrajectory)
{
  struct Case {
    std::string what, core, include;
    std::vector<std::string> run;
    double skin, tolerance;
  };
  const std::string band = "block INF INF 0 1.6 INF INF", disc = "sphere 6 6 0 3.5 side in";
  const std::string async = "fix 1 all pe_jump/async 10 stiff";
  const std::vector<Case> cases = {
      {"midpoint", band, "type 2", {async, "run 400"}, 0.3, 0.0},
      {"lobatto 3", band, "type 2", {async + " quadrature lobatto 3", "run 400"}, 0.3, 0.0},
      // energy tallies: complete evaluations write forces on every atom
      {"tallies", band, "type 2", {async, "thermo 7", "run 400"}, 0.3, 0.0},
      // a small skin: the slow atoms outside the group trigger rebuilds
      {"rebuilds", band, "type 2", {async + " quadrature lobatto 3", "run 400"}, 0.1, 0.0},
      // two runs, the second inside a coarse step, one without setup
      {"split runs", band, "type 2", {async, "run 203", "run 97 pre no", "run 100"}, 0.1, 0.0},
      // (the row at the top is stored after the others: reordered)
      {"buffer", band, "region wide", {async + " buffer 1", "run 400"}, 0.3, 1e-12},
      {"disc",
       disc,
       "type 2",
       {async + " quadrature lobatto 3", "thermo 50", "run 400"},
       0.1,
       1e-12},
  };
  for (const auto &c : cases) {
    const auto plain = lattice_run(c.core, "", c.run, c.skin);
    const auto first = lattice_run(c.core, c.include, c.run, c.skin);
    // the opt-in took effect: LAMMPS clears and checks a part of the atoms
    EXPECT_LE(first.nfirst, 168 / 2) << c.what;
    EXPECT_GT(first.nfirst, 0) << c.what;
    EXPECT_LE(max_diff(plain.x, first.x), c.tolerance) << c.what;
    EXPECT_EQ(plain.builds, first.builds) << c.what;
    if (c.skin < 0.1) EXPECT_GT(plain.builds, 3) << c.what;
  }
}

/* ----------------------------------------------------------------------
   a midpoint fine step inside a coarse step opens the next one in its
   jump loop, unless something may look at the atoms in between (here a
   timeout, which may end the run after any step, keeps the steps apart):
   the trajectory is the same, bit for bit, through list rebuilds, energy
   tallies, the opt-in and split runs
------------------------------------------------------------------------- */

TEST(PEJumpAsync, OpeningTheNextFineStepAheadKeepsTheTrajectory)
{
  struct Case {
    std::string what, include;
    std::vector<std::string> run;
    double skin;
  };
  const std::string band = "block INF INF 0 1.6 INF INF";
  const std::string async = "fix 1 all pe_jump/async 10 stiff";
  const std::vector<Case> cases = {
      {"rebuilds", "", {async, "thermo 7", "run 400"}, 0.1},
      {"opt-in", "type 2", {async, "thermo 7", "run 400"}, 0.1},
      {"buffer", "", {async + " buffer 1", "thermo 13", "run 203", "run 197 pre no"}, 0.1},
  };
  for (const auto &c : cases) {
    auto looked = c.run;
    looked.insert(looked.begin(), "timer timeout 99:00:00");
    const auto fused = lattice_run(band, c.include, c.run, c.skin);
    const auto stepwise = lattice_run(band, c.include, looked, c.skin);
    ASSERT_EQ(fused.x.size(), 3u * 168u) << c.what;
    EXPECT_EQ(max_diff(fused.x, stepwise.x), 0.0) << c.what;
    EXPECT_EQ(fused.builds, stepwise.builds) << c.what;
    EXPECT_GT(fused.builds, 3) << c.what;
  }
}

/* ----------------------------------------------------------------------
   neigh_modify every N (or delay N) exempts steps from LAMMPS' distance
   check over all atoms; pe_jump/async checks the atoms it moves on those
   steps, so the lists are rebuilt where every 1 delay 0 rebuilds them (the
   slow atoms do not move between coarse nodes). A projectile on the fine
   clock that reaches a slow atom inside a coarse step (without the fix's
   check its pair was missed for up to K - 1 steps: 1.3e-5 off in etotal),
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
          "neighbor 0.3 bin", neigh, "timestep 0.001",
          "fix 1 all pe_jump/async 20 fast quadrature " + rule, "thermo 20", "run 240"});
  return {positions(s), s.lmp->neighbor->ncalls};
}

ListRun liquid_run(const std::string &neigh, const std::string &rule)
{
  Sim s;
  lj_liquid(s);
  s.cmds({neigh, "group fast id 1:24", "velocity fast create 3.0 4711 loop geom",
          "fix 1 all pe_jump/async 4 fast buffer 1 quadrature " + rule, "thermo 40", "run 400"});
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
   what the opt-in cannot work with is refused
------------------------------------------------------------------------- */

TEST(PEJumpAsync, IncludeGroupRefusals)
{
  const auto error_with = [](const std::string &include, const std::vector<std::string> &more) {
    Sim s;
    bonded_lattice(s, "block INF INF 0 1.6 INF INF", 0.3);
    s.cmds({"group fine " + include, "atom_modify first fine", "neigh_modify include fine"});
    try {
      s.cmds(more);
    } catch (LAMMPS_NS::LAMMPSException &e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string async = "fix 1 all pe_jump/async 10 stiff";
  EXPECT_THAT(error_with("type 2", {async, "run 10"}), ContainsRegex("no error"));
  EXPECT_THAT(error_with("id 1:10", {async, "run 0"}),
              ContainsRegex("atoms on the fine clock \\(the fast group\\) are not in the "
                            "neigh_modify include group fine"));
  EXPECT_THAT(error_with("type 2", {async + " buffer 1", "run 0"}),
              ContainsRegex("fast group and its buffer layers\\) are not in the"));
  EXPECT_THAT(error_with("type 2", {"pair_style zero 1.0", "pair_coeff * *", async, "run 0"}),
              ContainsRegex("pair forces of the atoms outside it \\(pair style zero\\) would be "
                            "lost"));
  EXPECT_THAT(error_with("type 2", {"fix 1 all pe_jump", "run 0"}),
              ContainsRegex("moves every atom of its group every step, but 120 of them are not"));
  EXPECT_THAT(error_with("type 2", {"fix 1 stiff pe_jump", "run 5"}), ContainsRegex("no error"));
  EXPECT_THAT(error_with("type 2", {async, "fix 3 all deform 1 x scale 1.01", "run 0"}),
              ContainsRegex("does not support a box or processor subdomains that change"));
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
              dynamic ? "group fast dynamic all region stays every 10" : "group fast region stays",
              "fix 1 all pe_jump/async 10 fast" + rule, "thermo 50", "run 400"});
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

// the lattice with soft bonds only, over which a fast region sweeps
void moving_region(Sim &s, const std::string &rule)
{
  bonded_lattice(s, "block INF INF 0 1.6 INF INF", 0.3);
  s.cmds({"bond_coeff 2 1.0 1.0", "variable xc equal 2.0+0.02*step",
          "region mov sphere v_xc 6.0621778 0 2.5 side in units box",
          "group fast dynamic all region mov every 10", "fix 1 all pe_jump/async 10 fast" + rule,
          "variable px equal mass(all)*vcm(all,x)", "variable py equal mass(all)*vcm(all,y)",
          "thermo 10"});
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
      s.cmd("run 10 post no");
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
   coarse node, K odd: its restarted jump must fit its new step. Positions
   at t = 2 against fix nve at h = 1e-4; second order as h halves (with
   the jumps of the changed atoms shifted by their mean change, the restart
   of a single atom was undone: 3.6e-2 off at every h)
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
          "variable inf atom (id==1)*(step%10<5)",
          "group fast dynamic all var inf every 5",
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
    const double h = 0.002 / (1 << n);
    const auto x = toggled_chain("pe_jump/async 5 fast", h, 1000 << n);
    err[n] = 0.0;
    for (size_t k = 0; k < x.size(); k++) err[n] = std::max(err[n], std::fabs(x[k] - ref[k]));
  }
  EXPECT_LT(err[1], 1.0e-4);
  EXPECT_GT(err[0] / err[1], 3.0);
  EXPECT_GT(err[1] / err[2], 3.0);
}

/* ----------------------------------------------------------------------
   an atom that changes clock at a coarse node starts its new clock with
   the kick of the scheme, [v]^n = h_new F(q^n)/m: its first free flight
   x^n + h (v^n + [v]^n/2) gives the kick, which is compared with the
   forces at the node computed from scratch. With the midpoint rule the forces of the atoms
   that change clock come from two fine subsets, at less than the cost of
   one complete evaluation
------------------------------------------------------------------------- */

TEST(PEJumpAsync, AtomsChangingClockStartWithTheForcesAtTheNode)
{
  const double h = 0.005;
  for (const std::string rule : {"", " quadrature lobatto 3", " buffer 1"}) {
    Sim s(MPI_COMM_WORLD, false);
    moving_region(s, rule);
    // the criterion sees the node's step, as LAMMPS' own update of step 200 would
    s.cmds({"variable xc equal 2.0+3.0*(step==200)", "thermo 0"});
    // the node of step 200 (positions, velocities, classes) and the
    // cumulative evaluations of every step, in one run
    s.cmds({"fix node all store/state 200 x y vx vy f_1", "fix evals all vector 1 f_1[5]"});
    ::testing::internal::CaptureStdout();
    s.cmd("run 201");
    const std::string log = ::testing::internal::GetCapturedStdout();
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

    // the forces at the node, from scratch
    Sim r;
    moving_region(r, "");
    r.cmds({"unfix 1", "fix 1 all nve"});
    for (int id = 1; id <= natoms; id++)
      for (int k = 0; k < 2; k++) r.lmp->atom->x[r.lmp->atom->map(id)][k] = x0[3 * id + k];
    r.cmds({"run 0 post no"});

    const double *prd = s.lmp->domain->prd;
    double spread = 0.0, largest = 0.0;
    int changed = 0;
    for (int id = 1; id <= natoms; id++) {
      if (fine0[id] == fine1[id]) continue;
      const double step = fine1[id] ? h : 10.0 * h;
      for (int k = 0; k < 2; k++) {
        double d = s.x(id, k) - x0[3 * id + k];
        d -= prd[k] * std::round(d / prd[k]);
        const double jump = 2.0 * (d / h - v0[3 * id + k]);
        const double kick = step * r.lmp->atom->f[r.lmp->atom->map(id)][k];
        spread = std::max(spread, std::fabs(jump - kick));
        largest = std::max(largest, std::fabs(kick));
      }
      ++changed;
    }
    EXPECT_GT(changed, 3) << rule;
    // the fix's count of clock changes in the log: those at node 200 and a
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
   LJ liquid from the lattice, T = 1.5, K = 5, fast auto 0.2: at h = 0.01
   the warning at step 96 (+35.8; pe + f_ID changed by +33.7 up to the
   next node, +77 in 200 steps), the error at step 606 (+289, 50.4 %) in
   the run that follows; at h = 0.005 neither (-10.7 in 200 steps)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, PseudoEnergyThatClockChangesAddIsWarnedAbout)
{
  const std::vector<std::string> liquid = {"group none id 0",
                                           "fix 1 all pe_jump/async 5 none fast auto 0.2",
                                           "variable Ht equal pe+f_1",
                                           "thermo_style custom step pe v_Ht",
                                           "thermo_modify norm no format float %.15g",
                                           "thermo 5"};
  for (const double h : {0.01, 0.005}) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s);
    s.cmd(fmt::format("timestep {}", h));
    s.cmds(liquid);
    ::testing::internal::CaptureStdout();
    s.cmd("run 200");
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
    if (h < 0.0075) {
      EXPECT_FALSE(found) << log;
      EXPECT_LT(std::fabs(pseudo.at(200) - pseudo.at(0)), 20.0);
      continue;
    }
    ASSERT_TRUE(found) << log;
    EXPECT_EQ(log.find("clock changes since", warned.position(0) + warned.length(0)),
              std::string::npos);
    const int step = std::stoi(warned[1]);
    const double added = std::stod(warned[2]);
    EXPECT_NEAR(std::stod(warned[3]), 100.0 * std::fabs(added) / std::stod(warned[4]), 1e-2);
    EXPECT_GT(std::stod(warned[3]), 5.0);
    // changed at the node step - 1, seen at the next one
    const double seen = pseudo.at(step - 1 + 5) - pseudo.at(0);
    EXPECT_NEAR(seen, added, 0.1 * std::fabs(added));
    EXPECT_GT(pseudo.at(200) - pseudo.at(0), 50.0);

    // the changes add up over the runs, to the error
    Sim t;
    lj_liquid(t);
    std::string stopped = "no error";
    try {
      t.cmd(fmt::format("timestep {}", h));
      t.cmds(liquid);
      t.cmds({"run 200", "run 600"});
    } catch (LAMMPS_NS::LAMMPSException &e) {
      stopped = e.what();
    }
    std::smatch at;
    ASSERT_TRUE(std::regex_search(stopped, at, warning)) << stopped;
    EXPECT_GT(std::stoi(at[1]), 200);
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
  s.cmds({"variable swap atom (step<=100)*(id==10||id==13)+(step>100)*(id==11||id==12)",
          "group pair dynamic all var swap every 10", "unfix 1", "fix 1 all pe_jump/async 10 pair",
          "run 200"});
  const auto fine = on_fine_clock(s);
  EXPECT_EQ(fine[10] + fine[13], 0);
  EXPECT_EQ(fine[11] + fine[12], 2);
}

/* ----------------------------------------------------------------------
   the clocks follow a dynamic group as often as LAMMPS updates it: at the
   first coarse node after each update (every N steps)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, ClocksFollowADynamicGroupAsOftenAsItIsUpdated)
{
  std::map<int, std::vector<int>> tally;
  for (const int every : {5, 10, 30}) {
    Sim s(MPI_COMM_WORLD, false);
    bonded_lattice(s, "block INF INF 0 1.6 INF INF", 0.3);
    s.cmds({"bond_coeff 2 1.0 1.0", "variable xc equal 2.0+0.02*step",
            "region mov sphere v_xc 6.0621778 0 2.5 side in units box",
            fmt::format("group fast dynamic all region mov every {}", every),
            "fix 1 all pe_jump/async 10 fast", "thermo 0"});
    ::testing::internal::CaptureStdout();
    s.cmd("run 300");
    const std::string log = ::testing::internal::GetCapturedStdout();
    std::smatch count;
    ASSERT_TRUE(std::regex_search(
        log, count,
        std::regex("Fix pe_jump/async: (\\d+) atoms changed clock at (\\d+) of 30 coarse nodes")))
        << every;
    tally[every] = {std::stoi(count[1]), std::stoi(count[2])};
  }
  // every 5 and 10: the group is updated (and followed) at every coarse
  // node; every 30: at the nodes of steps 0, 30, ..., 270
  EXPECT_EQ(tally[5], tally[10]);
  EXPECT_GT(tally[10][1], 15);
  EXPECT_GT(tally[30][1], 3);
  EXPECT_LE(tally[30][1], 10);

  // each run reports its own nodes, also one with "pre no" (no setup)
  Sim s(MPI_COMM_WORLD, false);
  bonded_lattice(s, "block INF INF 0 1.6 INF INF", 0.3);
  s.cmds({"bond_coeff 2 1.0 1.0", "variable xc equal 2.0+0.02*step",
          "region mov sphere v_xc 6.0621778 0 2.5 side in units box",
          "group fast dynamic all region mov every 10", "fix 1 all pe_jump/async 10 fast",
          "thermo 0", "run 100 post no"});
  ::testing::internal::CaptureStdout();
  s.cmd("run 100 pre no post no");
  const std::string log = ::testing::internal::GetCapturedStdout();
  EXPECT_THAT(log, ContainsRegex("atoms changed clock at [0-9]+ of 10 coarse nodes"));
}

/* ----------------------------------------------------------------------
   a criterion that reads the neighbors of an atom (its coordination) is
   evaluated at the coarse node with every atom there, ghost atoms too:
   the clocks and so the trajectory are the same whether or not output at
   the nodes brought the ghost atoms there (the periodic images of the
   one-rank box were still at the last fine step's primary node when
   nothing was written: 3.6e-2 apart after 100 steps)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, NeighborCriterionSeesTheGhostAtomsAtTheNode)
{
  std::vector<double> x[2];
  for (const int written : {0, 1}) {
    Sim s;
    lj_liquid(s, 4);
    s.cmds({"compute crd all coord/atom cutoff 1.3", "variable few atom c_crd<11",
            "group fast dynamic all var few every 5", "fix 1 all pe_jump/async 5 fast",
            written ? "thermo 5" : "thermo 0", "run 100"});
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
            "group fast dynamic all var infast every 5", "variable flag atom " + check,
            "compute ntrue all reduce sum v_flag", "variable off equal abs(count(fast)-c_ntrue)",
            "variable fine equal f_1[8]+f_1[9]", "fix 1 all pe_jump/async 5 fast",
            "fix seen all ave/time 5 1 5 v_off v_fine c_ntrue mode scalar ave running", "thermo 0",
            "run 100"});
    EXPECT_EQ(s.vec("seen", 0), 0.0) << crit;     // mean |count(fast) - criterion|
    EXPECT_GT(s.vec("seen", 1), 20.0) << crit;    // atoms on the fine clock
  }
}

/* ----------------------------------------------------------------------
   a run continued from a restart file written at a coarse node, with the
   region moving on, gives the unbroken run's trajectory: the fine clock
   (a group of the fix) and the clocks' state are in the restart file
------------------------------------------------------------------------- */

TEST(PEJumpAsync, RestartAcrossClockChangesIsExact)
{
  for (const std::string rule : {"", " quadrature lobatto 3", " buffer 1"}) {
    std::vector<double> unbroken, restarted;
    double prd[3];
    {
      Sim s;
      moving_region(s, rule);
      s.cmds({"run 400"});
      unbroken = positions(s);
      for (int k = 0; k < 3; k++) prd[k] = s.lmp->domain->prd[k];
    }
    {
      Sim s;
      moving_region(s, rule);
      s.cmds({"run 200", "write_restart pe_jump_dyn.restart", "clear",
              "read_restart pe_jump_dyn.restart", "comm_modify cutoff 2.5", "neighbor 0.3 bin",
              "neigh_modify every 1 delay 0 check yes", "fix 2d all enforce2d",
              "variable xc equal 2.0+0.02*step",
              "region mov sphere v_xc 6.0621778 0 2.5 side in units box",
              "group fast dynamic all region mov every 10",
              "fix 1 all pe_jump/async 10 fast" + rule, "run 200"});
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
  const std::vector<std::string> fix = {"variable xc equal 2.0+0.001*step",
                                        "region mov sphere v_xc 3.0 3.0 1.5 side in units box",
                                        "group fast dynamic all region mov every 10",
                                        "fix 1 all pe_jump/async 10 fast buffer 1",
                                        "timestep 0.002",
                                        "thermo 10"};
  std::vector<double> unbroken, restarted;
  double prd[3];
  for (const int split : {0, 1}) {
    Sim s;
    lj_liquid(s, 4);
    s.cmds(fix);
    if (split) {
      s.cmds({"run 205", "write_restart pe_jump_still.restart", "clear",
              "read_restart pe_jump_still.restart", "pair_style lj/cut 2.5",
              "pair_coeff 1 1 1.0 1.0 2.5", "neighbor 0.3 bin",
              "neigh_modify every 1 delay 0 check yes"});
      s.cmds(fix);
      s.cmd("run 95");
      std::remove("pe_jump_still.restart");
      restarted = unwrapped_positions(s);
    } else {
      s.cmd("run 300");
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
  const std::vector<std::string> group = {"variable xc equal 2.0+0.01*step",
                                          "region mov sphere v_xc 3.0 3.0 1.5 side in units box",
                                          "group fast dynamic all region mov every 10"};
  for (const bool again : {false, true}) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s, 4);
    s.cmds(group);
    s.cmds({"timestep 0.002", "fix 1 all pe_jump/async 10 fast", "thermo 0", "run 20 post no",
            "write_restart pe_jump_dyn.restart", "clear", "read_restart pe_jump_dyn.restart",
            "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0 2.5", "neighbor 0.3 bin"});
    if (again) s.cmds(group);
    s.cmd("fix 1 all pe_jump/async 10 fast");
    ::testing::internal::CaptureStdout();
    s.cmd("run 10 post no");
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
   built), so a run split at or between coarse nodes, where the next run
   builds new lists, continues the unbroken one (with the lists' pairs:
   9e-4 off)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, BufferAroundADynamicGroupIsTheSameInSplitRuns)
{
  const auto run = [](const std::vector<std::string> &runs) {
    Sim s;
    lj_liquid(s);
    s.cmds({"variable zc equal 2.0+0.02*step",
            "region mov sphere 3.36 3.36 v_zc 1.5 side in units box",
            "group fast dynamic all region mov every 5", "fix 1 all pe_jump/async 5 fast buffer 1",
            "timestep 0.002", "thermo 0"});
    s.cmds(runs);
    return unwrapped_positions(s);
  };
  const auto unbroken = run({"run 60"});
  EXPECT_LT(max_diff(unbroken, run({"run 35 post no", "run 25"})), 1e-12);
  EXPECT_LT(max_diff(unbroken, run({"run 37 post no", "run 23"})), 1e-12);
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
      s.cmd("run 10 post no");
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
    s.cmds({fix, "thermo 10", "run 200"});
    const auto fine0 = on_fine_clock(s);
    s.cmd("run 200");
    const auto fine1 = on_fine_clock(s);
    for (size_t id = 1; id < fine0.size(); id++) changed += (fine0[id] != fine1[id]) ? 1.0 : 0.0;
    unbroken = positions(s);
    for (int k = 0; k < 3; k++) prd[k] = s.lmp->domain->prd[k];
  }
  {
    Sim s;
    setup(s);
    s.cmds({fix, "thermo 10", "run 200", "write_restart pe_jump_auto.restart", "clear",
            "read_restart pe_jump_auto.restart", "comm_modify cutoff 2.5", "neighbor 0.3 bin",
            "neigh_modify every 1 delay 0 check yes", "fix 2d all enforce2d", fix, "run 200"});
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
   the fine step may change inside a coarse step (timestep between runs,
   fix dt/reset): the coarse step is then the sum of its K fine steps, and
   the pseudo-energy stays conserved at the coarse nodes for an exact rule
   (lobatto 3 on the quartic chain, as in PseudoEnergyConservedAtCoarseNodes)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, StepChangesInsideCoarseStepsKeepThePseudoEnergy)
{
  for (const std::string how : {"timestep", "dt/reset"}) {
    Sim s;
    chain(s);
    // compensate no: the jumps are carried over a new time step between runs
    s.cmds({"fix 1 chain pe_jump/async 10 fast quadrature lobatto 3 compensate no", "timestep 2e-4",
            "thermo 0", "run 0 post no"});
    const double h0 = s.eval("c_thermo_pe+f_1");
    if (how == "dt/reset") s.cmd("fix dt all dt/reset 3 1e-4 3e-4 0.00002 units box");
    double worst = 0.0, smallest = 2e-4, largest = 2e-4;
    for (int n = 0; n < 200; ++n) {
      // runs of 7 steps: the changes fall inside coarse steps of 10
      if (how == "timestep") s.cmd(fmt::format("timestep {}", (n % 3 == 0) ? 1.5e-4 : 2.5e-4));
      s.cmd(how == "timestep" ? "run 7 pre no post no" : "run 7 post no");
      smallest = std::min(smallest, s.lmp->update->dt);
      largest = std::max(largest, s.lmp->update->dt);
      if (s.lmp->update->ntimestep % 10 == 0)
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
              "timestep 0.25", "thermo 0"});
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
  s.cmd("run 40 post no");
  EXPECT_NEAR(s.eval("v_px"), p0, 1e-10);
}

/* ----------------------------------------------------------------------
   thermo output between coarse nodes shows the slow atoms' velocities of
   the coarse step's start: a warning, aligned output none, and none when
   every atom is on the fine clock
------------------------------------------------------------------------- */

TEST(PEJumpAsync, OutputBetweenCoarseNodesWarnsOnlyWithSlowAtoms)
{
  struct Case {
    std::string fast;
    int every, steps;
    bool warns;
  };
  // (the last two: every output of the run on a coarse node although the
  // interval is no multiple of K, and a run that ends between nodes)
  for (const Case &c : {Case{"id 1:20", 3, 20, true}, Case{"id 1:20", 10, 20, false},
                        Case{"id 1:256", 3, 20, false}, Case{"id 1:256", 10, 20, false},
                        Case{"id 1:20", 7, 5, false}, Case{"id 1:20", 10, 23, true}}) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s);
    s.cmds({"group fast " + c.fast, "fix 1 all pe_jump/async 5 fast",
            "thermo " + std::to_string(c.every)});
    ::testing::internal::CaptureStdout();
    s.cmd(fmt::format("run {} post no", c.steps));
    const std::string out = ::testing::internal::GetCapturedStdout();
    EXPECT_EQ(std::regex_search(out, std::regex("thermo output on steps that are not coarse")),
              c.warns)
        << c.fast << ", thermo " << c.every << ", run " << c.steps;
  }
}

/* ----------------------------------------------------------------------
   fixes that sample at the end of steps see the same first-order values
   between coarse nodes: fix ave/time every step, K = 4, on an LJ liquid
   averaged vacf 1.35e-2 off the reference, 2.2e-4 when sampling at the
   nodes only (fix nve 1.2e-4), and printed no warning
------------------------------------------------------------------------- */

TEST(PEJumpAsync, SamplingFixesBetweenCoarseNodesWarn)
{
  for (const int every : {1, 3, 5, 10}) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s);
    s.cmds({"group fast id 1:20", "fix 1 all pe_jump/async 5 fast", "thermo 10",
            fmt::format("fix avg all ave/time {} 1 {} c_thermo_temp", every, every)});
    ::testing::internal::CaptureStdout();
    s.cmd("run 20 post no");
    const std::string out = ::testing::internal::GetCapturedStdout();
    EXPECT_EQ(std::regex_search(out,
                                std::regex("fix avg \\(ave/time\\) on steps that are not "
                                           "coarse nodes")),
              (every % 5) != 0)
        << "ave/time every " << every;
  }
  // fix store/state and fix halt sample values at the end of steps too (a
  // slow atom's vx stored every 3 steps with K = 5 was the coarse step's
  // start's, without a word); store/state that stores once is not named
  for (const std::string &sampler :
       {std::string("store/state 3 vx"), std::string("halt 3 v_k > 1e9"),
        std::string("store/state 0 vx")}) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s);
    s.cmds({"group fast id 1:20", "fix 1 all pe_jump/async 5 fast", "thermo 10",
            "variable k equal ke", "fix other all " + sampler});
    ::testing::internal::CaptureStdout();
    s.cmd("run 20 post no");
    const std::string out = ::testing::internal::GetCapturedStdout();
    EXPECT_EQ(std::regex_search(out,
                                std::regex("fix other \\([a-z/]+\\) on steps that are not "
                                           "coarse nodes")),
              sampler.find(" 0 ") == std::string::npos)
        << sampler;
  }
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
                                    "timestep 0.002",
                                    "thermo 0",
                                    "run 8 post no"};
  };
  // (a switch inside the run, a period of 7 steps: found by a sweep)
  for (const std::string scale : {"v_s", "v_r", "v_w", "v_p"})
    EXPECT_THAT(error_of(liquid(scale)), ContainsRegex("forces depend on the time")) << scale;
  EXPECT_EQ(error_of(liquid("0.8")), "no error");
}

/* ----------------------------------------------------------------------
   inside a coarse step atom->v of a slow atom is its velocity at the
   coarse step's start, without the fine impulses since (held by the fix),
   and its position may lag: a velocity command there acted on those
   (velocity all set 0 0 0 after a run that ended 3 fine steps into a
   coarse step left T = 1.4e-4 and a momentum of 0.6; velocity all scale
   1.0 gave T = 0.998), and a data file got them (continued from it: 1.25e-2
   off, 2.2e-5 for fix pe_jump, first order). Both are refused there; at
   a coarse node they act as with fix pe_jump. Velocities of atoms on the
   fine clock alone restart the scheme
------------------------------------------------------------------------- */

TEST(PEJumpAsync, VelocitiesAndDataFilesInsideACoarseStepAreRefused)
{
  const auto base = [](int steps) {
    return std::vector<std::string>{"units lj",
                                    "atom_style atomic",
                                    "atom_modify map array",
                                    "lattice fcc 0.8442",
                                    "region box block 0 4 0 4 0 4",
                                    "create_box 1 box",
                                    "create_atoms 1 box",
                                    "mass 1 1.0",
                                    "velocity all create 1.5 87287 loop geom",
                                    "pair_style lj/cut 2.5",
                                    "pair_coeff 1 1 1.0 1.0 2.5",
                                    "group fast id 1:50",
                                    "fix 1 all pe_jump/async 5 fast",
                                    "timestep 0.002",
                                    "thermo 0",
                                    fmt::format("run {} post no", steps)};
  };
  for (const std::string cmd :
       {"velocity all set 0 0 0", "velocity all scale 1.5", "velocity all zero linear",
        "velocity all create 1.0 4711 loop geom", "write_data pe_jump_async_midstep.data",
        "write_data pe_jump_async_midstep.data nofix"}) {
    std::vector<std::string> inside = base(73);    // 3 of 5 fine steps done
    inside.push_back(cmd);
    if (cmd[0] == 'v') inside.push_back("run 0 post no");
    EXPECT_THAT(error_of(inside),
                ContainsRegex(cmd[0] == 'v' ? "velocities of slow atoms were changed"
                                            : "write_data inside a coarse step"))
        << cmd;
    std::vector<std::string> node = base(75);
    node.push_back(cmd);
    if (cmd[0] == 'v') node.push_back("run 0 post no");
    EXPECT_EQ(error_of(node), "no error") << cmd;
  }
  std::remove("pe_jump_async_midstep.data");
  // at a coarse node: as set
  Sim s;
  s.cmds(base(75));
  s.cmds({"velocity all set 0 0 0", "run 0 post no"});
  EXPECT_EQ(s.eval("temp"), 0.0);
  // the fine clock alone: the scheme restarts, the slow atoms keep their momentum
  std::vector<std::string> fine = base(73);
  fine.push_back("velocity fast set 0 0 0");
  fine.push_back("run 2 post no");
  EXPECT_EQ(error_of(fine), "no error");
  // every atom on the fine clock: at a fine node, nothing to refuse
  std::vector<std::string> all_fast = base(73);
  all_fast[all_fast.size() - 5] = "group fast id 1:256";
  all_fast.push_back("write_data pe_jump_async_midstep.data");
  EXPECT_EQ(error_of(all_fast), "no error");
  std::remove("pe_jump_async_midstep.data");
}

/* ----------------------------------------------------------------------
   inside a coarse step the slow atoms keep the node velocity of its start
   and the impulses of the fine interactions on them wait in the fix until
   the coarse node. When the scheme restarts there (moved atoms, a new time
   step between runs) or the fix is removed, they get those impulses, so
   the total momentum stays what it was (it was off by 0.03 to 0.4 for good
   after any of these)
------------------------------------------------------------------------- */

TEST(PEJumpAsync, RestartInsideACoarseStepKeepsTheMomentum)
{
  const std::vector<std::vector<std::string>> between = {
      {"displace_atoms one move 1e-6 0 0 units box"},
      {"timestep 0.0021"},
      {"unfix 1", "fix 1 all pe_jump/async 10 fast"},
      {"unfix 1", "fix 2 all nve"}};
  for (const auto &cmds : between) {
    Sim s;
    lj_liquid(s, 4);
    s.cmds({"region slab block 0 1.5 INF INF INF INF", "group fast region slab", "group one id 7",
            "variable px equal mass(all)*vcm(all,x)", "variable py equal mass(all)*vcm(all,y)",
            "fix 1 all pe_jump/async 5 fast", "timestep 0.002", "thermo 0", "run 0 post no"});
    const double p0[2] = {s.eval("v_px"), s.eval("v_py")};
    s.cmd("run 102 post no");    // two fine steps into a coarse step
    s.cmds(cmds);
    s.cmd("run 20 post no");    // to a coarse node (the clocks begin anew at the break)
    const double p1[2] = {s.eval("v_px"), s.eval("v_py")};
    EXPECT_NEAR(p1[0], p0[0], 1e-10) << cmds.back();
    EXPECT_NEAR(p1[1], p0[1], 1e-10) << cmds.back();
  }
}

// a fine step that begins in the jump loop of the one before (nothing
// looks in between) is the step begun at its start: the same positions
// and the same list builds. A timeout keeps the fixes from beginning steps
// ahead (the run may end before the next step) and changes nothing else.
// With neigh_modify once yes (LAMMPS checks no distances) a Lobatto step
// begun ahead measured its nodes from the step end and asked for list
// builds that the step begun at its start does not (13 against 11).
TEST(PEJumpAsync, StepsBegunAheadCheckTheListsAsStepsBegunAtTheirStart)
{
  for (const std::string fix :
       {"pe_jump/async 10 fast quadrature lobatto 3", "pe_jump/async 10 fast quadrature midpoint",
        "pe_jump quadrature lobatto 3"})
    for (const std::string lists : {"once yes", "once no"}) {
      std::vector<double> x[2];
      LAMMPS_NS::bigint builds[2];
      for (int timeout = 0; timeout < 2; ++timeout) {
        Sim s;
        lj_liquid(s, 5);
        s.cmds({"neigh_modify " + lists, "region rfast block 0 2.5 INF INF INF INF units lattice",
                "group fast region rfast", "fix int all " + fix, "timestep 0.002", "thermo 10"});
        if (timeout) s.cmd("timer timeout 10:00:00 every 1");
        s.cmd("run 300");
        x[timeout] = positions(s);
        builds[timeout] = s.lmp->neighbor->ncalls;
      }
      EXPECT_EQ(max_diff(x[0], x[1]), 0.0) << fix << ", " << lists;
      EXPECT_EQ(builds[0], builds[1]) << fix << ", " << lists;
    }
}
