// Hostile input and run contexts: each case asserts the exact outcome, a
// specific ERROR or the sensible behaviour, never a crash, hang or NaN

#include "pe_jump_systems.h"

#include "domain.h"
#include "exceptions.h"
#include "group.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <string>
#include <utility>
#include <vector>

using namespace PEJumpTest;
using ::testing::ContainsRegex;
using ::testing::Not;

namespace {

std::vector<double> lj_run(const std::string &fix, int steps = 50)
{
  Sim s;
  lj_liquid(s, 3);
  s.cmds({fix, "timestep 0.005", "thermo 0", "run " + std::to_string(steps) + " post no"});
  return positions(s);
}

}    // namespace

/* ----------------------------------------------------------------------
   a repeated quadrature keyword: the last one wins (quadrature auto used
   to stay on, and crashed with legendre 2)
------------------------------------------------------------------------- */

TEST(PEJumpHostile, LastQuadratureKeywordWins)
{
  for (const std::string rule : {"legendre 2", "lobatto 3", "midpoint"}) {
    const auto plain = lj_run("fix 1 all pe_jump quadrature " + rule);
    const auto after_auto = lj_run("fix 1 all pe_jump quadrature auto 1e-6 quadrature " + rule);
    EXPECT_EQ(max_diff(plain, after_auto), 0.0) << rule;
  }
  const auto plain = lj_run("fix 1 all pe_jump quadrature auto 1e-6");
  const auto after = lj_run("fix 1 all pe_jump quadrature legendre 2 quadrature auto 1e-6");
  EXPECT_EQ(max_diff(plain, after), 0.0);
}

/* ----------------------------------------------------------------------
   time steps: 0 and negative steps are refused with a way out (reverse
   the velocities); adapt starts inside its range; adapt and fix dt/reset
   are not combined
------------------------------------------------------------------------- */

TEST(PEJumpHostile, TimestepsOutsideTheScheme)
{
  const std::vector<std::string> liquid = {"units lj",
                                           "atom_style atomic",
                                           "lattice fcc 0.8442",
                                           "region box block 0 3 0 3 0 3",
                                           "create_box 1 box",
                                           "create_atoms 1 box",
                                           "mass 1 1.0",
                                           "velocity all create 1.0 4928",
                                           "pair_style lj/cut 2.5",
                                           "pair_coeff 1 1 1.0 1.0 2.5",
                                           "region f block 0 1 INF INF INF INF",
                                           "group fast region f",
                                           "thermo 0"};
  auto with = [&](std::vector<std::string> extra) {
    auto all = liquid;
    all.insert(all.end(), extra.begin(), extra.end());
    return all;
  };
  for (const std::string fix :
       {"fix 1 all pe_jump", "fix 1 all pe_jump compensate yes", "fix 1 all pe_jump/async 5 fast",
        "fix 1 all pe_jump adapt 1e-3 1e-4 1e-2"}) {
    EXPECT_THAT(error_of(with({fix, "timestep 0", "run 5"})), ContainsRegex("needs a timestep > 0"))
        << fix;
    EXPECT_THAT(error_of(with({fix, "timestep -0.005", "run 5"})),
                ContainsRegex("needs a timestep > 0, got -0.005: to run backwards in time"))
        << fix;
    // between runs too
    EXPECT_THAT(error_of(with({fix, "timestep 0.005", "run 5", "timestep 0", "run 5"})),
                ContainsRegex("needs a timestep > 0"))
        << fix;
  }
  EXPECT_THAT(error_of(with({"fix 1 all pe_jump adapt 1e-3 1e-4 1e-2",
                             "fix 2 all dt/reset 1 1e-4 1e-2 0.01", "run 5"})),
              ContainsRegex("adapt and fix 2 \\(dt/reset\\) both set the time step"));

  // a timestep above dtmax: the first step is taken at dtmax already
  Sim s;
  s.cmds(with({"fix 1 all pe_jump adapt 1e-3 1e-4 2e-3", "timestep 0.02", "run 1 post no"}));
  EXPECT_LE(s.lmp->update->dt, 2e-3 * 1.05);
  EXPECT_NEAR(s.eval("time"), 2e-3, 1e-15);    // the first step took dtmax
}

/* ----------------------------------------------------------------------
   buffer layers beyond the reach of the interactions stop when a layer
   adds no atom (buffer 100000000 used to hang)
------------------------------------------------------------------------- */

TEST(PEJumpHostile, HugeBufferFinishes)
{
  Sim s;
  lj_liquid(s, 3);
  s.cmds({"region f block 0 1 INF INF INF INF", "group fast region f",
          "fix 1 all pe_jump/async 5 fast buffer 100000000", "timestep 0.025", "thermo 0",
          "run 2 post no"});
  // every atom interacts with the fast ones through some chain of partners
  EXPECT_EQ(s.vec("1", 6), 0.0);    // no slow atom left
}

/* ----------------------------------------------------------------------
   a deleted fast group whose bit another group takes over is not the fast
   group: the fix looks its groups up by name
------------------------------------------------------------------------- */

TEST(PEJumpHostile, DeletedFastGroupIsNotReplacedSilently)
{
  Sim s;
  lj_liquid(s, 3);
  s.cmds({"region f block 0 1 INF INF INF INF", "group fast region f",
          "fix 1 all pe_jump/async 5 fast", "timestep 0.025", "thermo 0", "run 1 post no",
          "group fast delete", "group other id 1:10"});
  EXPECT_THAT(error_in(s, "run 1 post no"), ContainsRegex("its fast group fast was deleted"))
      << "the deleted fast group must be noticed";
}

/* ----------------------------------------------------------------------
   an atom created between runs with a Lobatto rule: its start node and
   the initial kick are taken at the start of the next run, so it moves as
   in a fresh start from the same state (its start-node force used to be
   0: 11% error in its displacement after 5 steps)
------------------------------------------------------------------------- */

TEST(PEJumpHostile, AtomCreatedBetweenRunsWithLobatto)
{
  const std::string rule = "fix 1 all pe_jump quadrature lobatto 3";
  double moved = 0.0, reference = 0.0;
  {
    // the new atom takes the place of a deleted one (ID 109)
    Sim s;
    lj_liquid(s, 3);
    s.cmds({rule, "timestep 0.005", "thermo 0", "run 100 post no"});
    const std::string at = fmt::format("{:.17g} {:.17g} {:.17g}", s.x(5, 0), s.x(5, 1), s.x(5, 2));
    s.cmds({"group one id 5", "delete_atoms group one compress no",
            "create_atoms 1 single " + at + " units box", "write_data pe_jump_new.data nocoeff",
            "run 0 post no"});
    ASSERT_EQ(s.lmp->atom->natoms, 108);
    const double x0 = s.x(109, 0);
    s.cmd("run 5 post no");
    moved = s.x(109, 0) - x0;
  }
  {
    // a fresh start from the same state
    Sim s;
    s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "read_data pe_jump_new.data",
            "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0 2.5", "neighbor 0.3 bin",
            "neigh_modify every 1 delay 0 check yes", rule, "timestep 0.005", "thermo 0",
            "run 0 post no"});
    const double x0 = s.x(109, 0);
    s.cmd("run 5 post no");
    reference = s.x(109, 0) - x0;
  }
  std::remove("pe_jump_new.data");
  ASSERT_GT(std::fabs(reference), 1e-4);
  EXPECT_LT(std::fabs(moved - reference), 1e-4 * std::fabs(reference))
      << "moved " << moved << ", fresh start " << reference;
}

/* ----------------------------------------------------------------------
   a fix command refused by its constructor (an error caught by the
   library caller) leaves nothing behind: no per-atom callbacks (a later
   create_atoms crashed in AtomVec::grow), no compute, no group, and the
   same fix ID can be used again
------------------------------------------------------------------------- */

TEST(PEJumpHostile, RefusedFixLeavesNothingBehind)
{
  for (const std::string bad :
       {"fix 1 all pe_jump/async 0 fast", "fix 1 all pe_jump/async 5 fast quadrature auto 1e-6",
        "fix 1 all pe_jump/async 5 fast buffer 1 adapt 1e-3 1e-4 1e-2",
        "fix 1 all pe_jump quadrature auto 1e-6 sample pair"}) {
    Sim s;
    s.cmds({"units lj", "atom_style atomic", "atom_modify map array",
            "region box block 0 20 0 20 0 20", "create_box 1 box",
            "create_atoms 1 random 100 4711 NULL", "mass 1 1.0", "pair_style zero 1.0",
            "pair_coeff * *", "group fast id 1:10"});
    const int ngroups = s.lmp->group->ngroup;
    EXPECT_THROW(s.cmd(bad), LAMMPS_NS::LAMMPSException) << bad;
    EXPECT_EQ(s.lmp->group->ngroup, ngroups) << bad;
    EXPECT_EQ(s.lmp->modify->get_compute_by_id("1_pe"), nullptr) << bad;
    // enough new atoms to make the per-atom arrays grow
    const int nmax = s.lmp->atom->nmax;
    EXPECT_NO_THROW(s.cmd("create_atoms 1 random 20000 4712 NULL")) << bad;
    EXPECT_GT(s.lmp->atom->nmax, nmax);
    EXPECT_NO_THROW(s.cmds(
        {"fix 1 all pe_jump quadrature auto 1e-6", "timestep 0.001", "thermo 0", "run 2 post no"}))
        << bad;
  }
}

/* ----------------------------------------------------------------------
   the atoms on the fine clock change between runs (the fast group
   redefined, a restart read with other buffer layers): the scheme
   restarts with a message after a run of any length (every run ends at a
   coarse node); the same atoms redefined are no change (they used to
   change silently, or the buffer was not assigned at all)
------------------------------------------------------------------------- */

TEST(PEJumpHostile, FineClockChangesBetweenRuns)
{
  const std::vector<std::string> liquid = {"group fast id 1:10", "timestep 0.025", "thermo 0"};
  for (const int first : {2, 3}) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s, 3);
    s.cmds(liquid);
    s.cmds({"fix 1 all pe_jump/async 5 fast", fmt::format("run {} post no", first),
            "group fast clear", "group fast id 1:10"});
    ::testing::internal::CaptureStdout();
    s.cmd("run 1 post no");    // the same atoms: nothing changed
    EXPECT_THAT(::testing::internal::GetCapturedStdout(),
                Not(ContainsRegex("the atoms on the fine clock changed")))
        << first;
    s.cmd("group fast id 11:20");
    ::testing::internal::CaptureStdout();
    s.cmd("run 1 post no");
    EXPECT_THAT(::testing::internal::GetCapturedStdout(),
                ContainsRegex("the atoms on the fine clock changed since the last run"))
        << first;
  }
  // a restart written without buffer, read with buffer 1
  double slow_without = 0.0, slow_with = 0.0;
  {
    Sim s;
    lj_liquid(s, 3);
    s.cmds(liquid);
    s.cmds({"fix 1 all pe_jump/async 5 fast", "run 2 post no"});
    slow_without = s.vec("1", 6);
    s.cmds({"write_restart pe_jump_buffer.restart", "clear", "read_restart pe_jump_buffer.restart",
            "neighbor 0.3 bin", "fix 1 all pe_jump/async 5 fast buffer 1", "thermo 0",
            "run 1 post no"});
    slow_with = s.vec("1", 6);
    std::remove("pe_jump_buffer.restart");
  }
  EXPECT_GT(slow_without, 0.0);
  EXPECT_LT(slow_with, slow_without);
}

/* ----------------------------------------------------------------------
   a run that becomes unstable stops with an ERROR before any NaN reaches
   the output, and what was written before (the log) is intact
------------------------------------------------------------------------- */

TEST(PEJumpHostile, InstabilityStopsBeforeNaNWithOutputIntact)
{
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"fix 1 all pe_jump", "0.03"},
      {"fix 1 all pe_jump quadrature lobatto 3", "0.03"},
      {"fix 1 all pe_jump/async 4 fast", "0.036"}};    // h_S (h_F = 0.009)
  const std::regex thermo("^ +[0-9]+ +[-0-9.e+]+ +");
  const std::regex not_finite("(^|[^A-Za-z])([Nn][Aa][Nn]|[Ii][Nn][Ff])([^A-Za-z]|$)");
  for (const auto &[fix, dt] : cases) {
    const std::string log = "pe_jump_unstable.log";
    std::string error;
    {
      Sim s;
      lj_liquid(s, 3);
      s.cmds({"region f block 0 1 INF INF INF INF", "group fast region f", "log " + log, fix,
              "timestep " + dt, "thermo 1", "thermo_modify flush yes"});
      error = error_in(s, "run 2000 post no");
    }
    EXPECT_THAT(error, ContainsRegex("is unstable at step [0-9]+|atoms move more than half"))
        << fix;
    std::ifstream in(log);
    std::string line;
    int lines = 0;
    while (std::getline(in, line))
      if (std::regex_search(line, thermo)) {
        ++lines;
        EXPECT_FALSE(std::regex_search(line, not_finite)) << fix << ": " << line;
      }
    EXPECT_GT(lines, 1) << fix;    // the thermo lines written before the stop
    std::remove(log.c_str());
  }
}

/* ----------------------------------------------------------------------
   "run N pre no" skips the fixes' init() and setup(), where they check
   what changed since the last run: a change is refused at the first step
   (a mass changed before it was integrated with the old one, lobatto 2
   then equalled fix nve with the old mass, 0.14 off the real one after 60
   steps; a fast group redefined at a coarse node kept the old split of
   the interactions, and the total momentum jumped from 1e-13 to 1.9); a
   run without changes continues exactly
------------------------------------------------------------------------- */

namespace {
struct Continued {
  std::vector<double> x;
  std::string error;
};
// (fix pe_jump/async 4: its time step is the coarse step of 4 fine steps
// of 0.005, the runs take as many fine steps)
Continued changed_then_run(const std::string &fix, const std::vector<std::string> &change,
                           const std::string &pre)
{
  const int K = (fix.find("pe_jump/async 4 ") != std::string::npos) ? 4 : 1;
  Sim s;
  lj_liquid(s, 3);
  s.cmds({"region slab block INF 2.0 INF INF INF INF units box", "group fast region slab",
          "region slab2 block 4.0 6.0 INF INF INF INF units box", fix,
          fmt::format("timestep {}", 0.005 * K), "thermo 0",
          fmt::format("run {} post no", 40 / K)});
  s.cmds(change);
  const std::string error = error_in(s, fmt::format("run {} post no pre ", 60 / K) + pre);
  if (error != "no error") return {{}, error};
  return {unwrapped_positions(s), ""};
}
}    // namespace

TEST(PEJumpHostile, RunWithPreNoRefusesChangesSinceTheLastRun)
{
  const std::vector<std::pair<std::vector<std::string>, std::string>> changes = {
      {{"mass 1 1.5"}, "masses of atoms of the group changed"},
      {{"displace_atoms all move 0.1 0 0 units box"}, "atoms of the group were moved"},
      {{"velocity all scale 1.1"}, "velocities were changed"},
      {{"group fast clear", "group fast region slab2"}, "atoms on the fine clock changed"}};
  for (const std::string fix : {"fix 1 all pe_jump quadrature lobatto 2", "fix 1 all pe_jump",
                                "fix 1 all pe_jump/async 4 fast quadrature lobatto 3"}) {
    const bool async = fix.find("async") != std::string::npos;
    for (const auto &change : changes) {
      if (!async && (change.second.find("fine clock") != std::string::npos)) continue;
      EXPECT_EQ(changed_then_run(fix, change.first, "yes").error, "") << fix;
      EXPECT_THAT(changed_then_run(fix, change.first, "no").error,
                  ContainsRegex(change.second + ".*this run starts with 'pre no'"))
          << fix;
    }
    // nothing changed: pre no continues as pre yes, to the round-off of the
    // lists that pre yes builds again
    const auto yes = changed_then_run(fix, {"thermo 10"}, "yes");
    const auto no = changed_then_run(fix, {"thermo 10"}, "no");
    EXPECT_EQ(no.error, "") << fix;
    EXPECT_LT(max_diff(yes.x, no.x), 1e-10) << fix;
  }
}

/* ----------------------------------------------------------------------
   pe_jump/async restarted between runs, which end at coarse nodes: a new
   time step or the fix defined anew restart the scheme with no warning
   (the time step with a log line), and a restart file read with another
   quadrature or another K restarts it with a log line, after a run of any
   length
------------------------------------------------------------------------- */

namespace {
std::string output_of(Sim &s, const std::vector<std::string> &commands)
{
  ::testing::internal::CaptureStdout();
  const std::string error = error_from([&] {
    s.cmds(commands);
  });
  const std::string out = ::testing::internal::GetCapturedStdout();
  if (error != "no error") return "ERROR: " + error;
  return out;
}
}    // namespace

TEST(PEJumpHostile, AsyncRestartsBetweenRunsAreTold)
{
  const std::vector<std::string> setup = {
      "region slab block INF 2.0 INF INF INF INF units box", "group fast region slab",
      "fix 1 all pe_jump/async 4 fast", "timestep 0.02", "thermo 0"};
  // the output of the commands after a run of `first` steps
  const auto told = [&](int first, const std::vector<std::string> &then) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s, 3);
    s.cmds(setup);
    output_of(s, {"run " + std::to_string(first) + " post no"});
    return output_of(s, then);
  };
  for (const int first : {10, 11}) {
    const std::string step = told(first, {"timestep 0.01", "run 2 post no"});
    EXPECT_THAT(step,
                ContainsRegex("the time step changed since the last run \\(from 0.02 to "
                              "0.01;.*the two-step scheme restarts"))
        << first;
    const std::string refixed = told(first, {"unfix 1", setup[2], "run 2 post no"});
    for (const auto &out : {step, refixed})
      EXPECT_THAT(out, Not(ContainsRegex("WARNING|ERROR"))) << first;
  }
  for (const int first : {10, 11})
    for (const std::string other : {"quadrature lobatto 3", "quadrature legendre 2", "K"}) {
      const std::string file = "pe_jump_rule.restart";
      Sim s(MPI_COMM_WORLD, false);
      lj_liquid(s, 3);
      s.cmds(setup);
      output_of(s,
                {"run " + std::to_string(first) + " post no", "write_restart " + file, "clear",
                 "read_restart " + file, "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0 2.5"});
      const std::string out = output_of(s,
                                        {(other == "K") ? "fix 1 all pe_jump/async 2 fast"
                                                        : "fix 1 all pe_jump/async 4 fast " + other,
                                         "run 2 post no"});
      std::remove(file.c_str());
      EXPECT_THAT(out,
                  ContainsRegex((other == "K") ? "K differs from the restart file"
                                               : "quadrature differs from the restart file"))
          << first << " " << other;
      EXPECT_THAT(out, Not(ContainsRegex("WARNING|ERROR"))) << first << " " << other;
    }
}

/* ----------------------------------------------------------------------
   fine-clock atoms lost through a fixed boundary during a run are no
   change since that run: "run N pre no" goes on (it was refused, "the
   atoms on the fine clock changed"), as a run with pre yes does, and
   equals the unbroken run
------------------------------------------------------------------------- */

TEST(PEJumpHostile, FineClockAtomsLostInARunAreNoChangeAfterIt)
{
  const auto shot_out = [](const std::vector<std::string> &runs) {
    Sim s;
    s.cmds({"units lj",
            "atom_style atomic",
            "atom_modify map array",
            "boundary f p p",
            "lattice fcc 0.8442",
            "region box block 0 4 0 4 0 4",
            "create_box 1 box",
            "create_atoms 1 box",
            "mass 1 1.0",
            "velocity all create 1.0 4928",
            "pair_style lj/cut 2.5",
            "pair_coeff 1 1 1.0 1.0 2.5",
            "neighbor 0.3 bin",
            "region edge block 5.6 INF INF INF INF INF units box",
            "group fast region edge",
            "velocity fast set 5.0 NULL NULL",
            "fix 1 all pe_jump/async 5 fast",
            "thermo_modify lost ignore",
            "timestep 0.02",
            "thermo 0"});
    const std::string error = error_from([&] {
      s.cmds(runs);
    });
    std::vector<double> x;
    for (int id = 1; id <= 256; id++) {
      const int i = s.lmp->atom->map(id);
      for (int k = 0; k < 3; k++) x.push_back((i >= 0) ? s.lmp->atom->x[i][k] : -1.0);
    }
    return std::make_pair(s.lmp->atom->natoms, std::make_pair(x, error));
  };
  const auto unbroken = shot_out({"run 20 post no"});
  const auto pieces = shot_out({"run 4 post no", "run 4 pre no post no", "run 4 pre no post no",
                                "run 4 pre no post no", "run 4 pre no post no"});
  EXPECT_LT(unbroken.first, 256);    // atoms were lost
  EXPECT_EQ(pieces.second.second, "no error");
  EXPECT_EQ(pieces.first, unbroken.first);
  EXPECT_LT(max_diff(pieces.second.first, unbroken.second.first), 1e-12);
}

/* ----------------------------------------------------------------------
   write_data and write_restart between runs rebuild the ghost atoms; a
   run with "pre no" after them kept the lists of the last build, and on
   this liquid (864 atoms, from a sweep) fix pe_jump midpoint ended 5.8e-2
   and lobatto 3 9.6e-2 off the unbroken run 50 steps later (fix nve
   exact; run 80 pre no every 20 "write_restart ...": 7.5e-2). The
   fixes now build the lists at the first step of such a run
------------------------------------------------------------------------- */

TEST(PEJumpHostile, CheckpointsBetweenRunsWithPreNoContinueExactly)
{
  // (fix pe_jump/async 5: its time step is the coarse step of 5 fine steps
  // of 0.004, the runs and intervals take as many fine steps)
  for (const auto &[fix, K] :
       std::vector<std::pair<std::string, int>>{{"fix 1 all pe_jump", 1},
                                                {"fix 1 all pe_jump quadrature lobatto 3", 1},
                                                {"fix 1 all pe_jump/async 5 fast", 5}}) {
    const auto liquid = [&, K = K](const std::vector<std::string> &runs) {
      Sim s;
      s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "pair_style lj/cut 2.5",
              std::string("read_data ") + PEJUMP_INPUTS + "/lj_liquid_864.data",
              "pair_coeff 1 1 1.0 1.0 2.5", "pair_modify shift yes", "neighbor 0.3 bin",
              "group fast id <= 100", fmt::format("timestep {}", 0.004 * K), fix,
              fmt::format("thermo {}", 20 / K)});
      s.cmds(runs);
      return unwrapped_positions(s);
    };
    const auto steps = [K = K](int fine) {
      return fine / K;
    };
    const auto unbroken = liquid({fmt::format("run {} post no", steps(100))});
    for (const std::string between :
         {"write_data pe_jump_checkpoint.data", "write_restart pe_jump_checkpoint.restart"}) {
      const auto pieces = liquid({fmt::format("run {} post no", steps(50)), between,
                                  fmt::format("run {} pre no post no", steps(50))});
      EXPECT_LT(max_diff(unbroken, pieces), 1e-10) << fix << " / " << between;
    }
    // the checkpoints of run every (7.5e-2 off for midpoint before)
    const auto every = liquid(
        {fmt::format("run {} post no", steps(20)),
         fmt::format("run {} pre no post no every {} \"write_restart pe_jump_checkpoint.restart\"",
                     steps(80), steps(20))});
    EXPECT_LT(max_diff(unbroken, every), 1e-10) << fix << " / run every";
  }
  std::remove("pe_jump_checkpoint.data");
  std::remove("pe_jump_checkpoint.restart");
}

/* ----------------------------------------------------------------------
   rerun reads a snapshot and calls setup() for each, integrating
   nothing: each snapshot starts the scheme afresh, without a word. The
   log said "velocities were changed since the last run" at every snapshot
   after the first, beside a thermostat also "damp auto damps ..." at
   every one. A run after the rerun goes on from the last snapshot as a
   fix defined there (fix pe_jump/async 5 at its coarse step 0.025, over
   as many fine steps)
------------------------------------------------------------------------- */

TEST(PEJumpHostile, RerunStartsTheSchemeAtEachSnapshotWithoutAWord)
{
  const std::string dump = "pe_jump_rerun.dump";
  {
    Sim s;
    lj_liquid(s, 3);
    s.cmds({"fix 1 all nve", "timestep 0.005", "thermo 0",
            "dump d all custom 10 " + dump + " id type x y z vx vy vz ix iy iz",
            "dump_modify d format float %22.16g", "run 50 post no"});
  }
  const std::vector<std::string> fast = {"region f block 0 1 INF INF INF INF",
                                         "group fast region f"};
  for (const std::string fix : {"fix 1 all pe_jump", "fix 1 all pe_jump quadrature lobatto 3",
                                "fix 1 all pe_jump/async 5 fast"}) {
    for (const std::string thermostat : {"", "fix 2 all langevin 1.0 1.0 0.5 4711"}) {
      const bool async = fix.find("async") != std::string::npos;
      if (!thermostat.empty() && async) continue;
      const std::string dt = async ? "0.025" : "0.005";
      const std::string after = async ? "run 4 post no" : "run 20 post no";
      Sim s(MPI_COMM_WORLD, false);
      lj_liquid(s, 3);
      s.cmds(fast);
      s.cmds({fix, "timestep " + dt, "thermo 10"});
      if (!thermostat.empty()) s.cmd(thermostat);
      s.cmd("run 7 post no");    // a state of its own
      ::testing::internal::CaptureStdout();
      s.cmd("rerun " + dump + " dump x y z vx vy vz ix iy iz");
      const std::string out = ::testing::internal::GetCapturedStdout();
      EXPECT_THAT(out, Not(ContainsRegex("Fix pe_jump|WARNING"))) << fix << " " << thermostat;
      if (!thermostat.empty()) continue;
      s.cmd(after);
      Sim fresh;
      lj_liquid(fresh, 3);
      fresh.cmds(fast);
      fresh.cmds({"read_dump " + dump + " 50 x y z vx vy vz ix iy iz", fix, "timestep " + dt,
                  "thermo 0", after});
      EXPECT_LT(max_diff(unwrapped_positions(s), unwrapped_positions(fresh)), 1e-12) << fix;
    }
  }
  std::remove(dump.c_str());
}
