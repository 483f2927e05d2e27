// fix pe_jump and fix pe_jump/async with the accelerator styles of the
// OPENMP (1 and 2 threads) and OPT packages: the same trajectory as with
// the plain styles, for every sample subset

#include "pe_jump_systems.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <regex>
#include <string>
#include <vector>

using namespace PEJumpTest;

namespace {

// runs a system: accelerator commands first, then the system, the fix and
// a run of the given number of steps of the system's time step (fix
// pe_jump/async K: steps/K coarse steps of K times the system's time
// step); positions of all atoms by atom ID
using Builder = std::function<void(Sim &)>;

std::vector<double> accelerated_run(const std::string &accelerator, const Builder &system,
                                    const std::string &fix, int steps)
{
  Sim s;
  if (accelerator == "opt")
    s.cmd("suffix opt");
  else if (!accelerator.empty())
    s.cmds({"package " + accelerator, "suffix omp"});
  system(s);
  std::smatch async;
  const int K =
      std::regex_search(fix, async, std::regex("pe_jump/async (\\d+)")) ? std::stoi(async[1]) : 1;
  s.cmds({fix, fmt::format("timestep {:.17g}", K * s.lmp->update->dt), "thermo 0",
          fmt::format("run {} post no", steps / K)});
  return positions(s);
}

// bonded fcc crystal: pair lj/cut and harmonic bonds to the 12 neighbours
void bonded_crystal(Sim &s)
{
  s.cmds({"units lj", "atom_style bond", "atom_modify map array", "lattice fcc 0.8442",
          "region box block 0 4 0 4 0 4",
          "create_box 1 box bond/types 1 extra/bond/per/atom 14 extra/special/per/atom 50",
          "create_atoms 1 box", "mass 1 1.0", "velocity all create 1.0 87287 loop geom",
          "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0 2.5", "bond_style harmonic",
          "bond_coeff 1 20.0 1.09", "special_bonds lj 0.0 1.0 1.0",
          "create_bonds many all all 1 1.0 1.2", "neighbor 0.3 bin",
          "region fast block 0 1.5 INF INF INF INF", "group fast region fast", "timestep 0.002"});
}

void liquid(Sim &s)
{
  lj_liquid(s, 3);
  s.cmds({"region fast block 0 1 INF INF INF INF", "group fast region fast", "timestep 0.005"});
}

// the paper's Fermi-Pasta-Ulam chain (bond_style hybrid harmonic class2)
void fpu(Sim &s)
{
  double q[6], p[6];
  fpu_gni_values(50.0, q, p);
  fpu_chain(s, 50.0, q, p);
  s.cmds({"group fast id 2:4", "timestep 0.001"});
}

}    // namespace

TEST(PEJumpAccelerators, SameTrajectoryWithOmpAndOptStyles)
{
  struct Case {
    std::string name;
    Builder system;
    std::vector<std::string> fixes;
    int steps;
  };
  const std::vector<Case> cases = {
      {"bonded crystal",
       bonded_crystal,
       {"fix 1 all pe_jump", "fix 1 all pe_jump quadrature lobatto 3",
        "fix 1 all pe_jump quadrature lobatto 3 sample pair",
        "fix 1 all pe_jump quadrature lobatto 3 sample bond",
        "fix 1 all pe_jump quadrature legendre 2 sample pair", "fix 1 all pe_jump/async 5 fast",
        "fix 1 all pe_jump/async 5 fast quadrature lobatto 3"},
       200},
      {"LJ liquid",
       liquid,
       {"fix 1 all pe_jump", "fix 1 all pe_jump quadrature lobatto 3",
        "fix 1 all pe_jump/async 4 fast quadrature lobatto 3"},
       200},
      {"FPU chain",
       fpu,
       {"fix 1 chain pe_jump quadrature lobatto 3",
        "fix 1 chain pe_jump quadrature lobatto 3 sample bond",
        "fix 1 chain pe_jump/async 10 fast quadrature lobatto 5"},
       2000}};
  for (const auto &c : cases) {
    for (const auto &fix : c.fixes) {
      const auto plain = accelerated_run("", c.system, fix, c.steps);
      for (const std::string accelerator : {"omp 1", "omp 2", "opt"}) {
        const auto accelerated = accelerated_run(accelerator, c.system, fix, c.steps);
        // the thread count changes the order of the force sums: round-off only
        EXPECT_LT(max_diff(plain, accelerated), 1e-10)
            << c.name << ": " << fix << " with " << accelerator;
      }
    }
  }
}
