// LAMMPS' own example inputs (copied, shortened, into unittest/inputs/
// with their origin noted) with fix nve swapped for fix pe_jump: the
// atoms held or moved by other fixes do exactly what they do under fix
// nve, and the others follow the same trajectory to within the
// integration error of fix nve at the same step

#include "pe_jump_systems.h"

#include "domain.h"
#include "exceptions.h"
#include "group.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

using namespace PEJumpTest;

namespace {

struct Positions {
  std::map<LAMMPS_NS::tagint, std::vector<double>> x;    // unwrapped, by atom ID
  std::map<LAMMPS_NS::tagint, int> held;                 // 1 if in the held group
};

Positions run_example(const std::string &file, const std::string &integrator, int scale, int steps,
                      const std::string &held)
{
  Sim s;
  s.cmds({"variable integrator string \"" + integrator + "\"",
          "variable scale equal " + std::to_string(scale),
          "variable steps equal " + std::to_string(steps), "log none"});
  s.lmp->input->file((std::string(PEJUMP_INPUTS) + "/" + file).c_str());
  Positions p;
  auto *atom = s.lmp->atom;
  const int bit = s.lmp->group->bitmask[s.lmp->group->find(held)];
  for (int i = 0; i < atom->nlocal; i++) {
    double u[3];
    s.lmp->domain->unmap(atom->x[i], atom->image[i], u);
    p.x[atom->tag[i]] = {u[0], u[1], u[2]};
    p.held[atom->tag[i]] = (atom->mask[i] & bit) ? 1 : 0;
  }
  return p;
}

// largest difference of the position components from first on between
// the atoms (held ones or the others) of two runs
double distance(const Positions &a, const Positions &b, int held, int first = 0)
{
  double d = 0.0;
  for (const auto &[id, xa] : a.x) {
    if (a.held.at(id) != held) continue;
    const auto &xb = b.x.at(id);
    for (int k = first; k < 3; k++) d = std::max(d, std::fabs(xa[k] - xb[k]));
  }
  return d;
}

}    // namespace

TEST(PEJumpLammpsExamples, SameMotionAsFixNve)
{
  struct Example {
    std::string file, held;    // held: atoms that only other fixes move ...
    int first;                 // ... in the components from this one on
    int steps;
  };
  for (const Example &e :
       {Example{"in.crack", "boundary", 1, 150}, Example{"in.flow.pois", "lower", 0, 150},
        Example{"in.flow.couette", "boundary", 0, 150}, Example{"in.indent", "lower", 0, 150}}) {
    const auto reference = run_example(e.file, "nve", 4, e.steps, e.held);
    const auto nve = run_example(e.file, "nve", 1, e.steps, e.held);
    const double nve_error = distance(nve, reference, 0);
    for (const std::string rule : {"midpoint", "lobatto 2", "lobatto 3", "legendre 2"}) {
      const auto pj = run_example(e.file, "pe_jump quadrature " + rule, 1, e.steps, e.held);
      // held and driven walls: exactly as with fix nve
      EXPECT_LT(distance(pj, nve, 1, e.first), 1e-10) << e.file << " " << rule;
      // the others: second order like fix nve; the midpoint rule's position
      // error constant is about 3 times that of velocity Verlet
      const double error = distance(pj, reference, 0);
      EXPECT_LT(error, 4.0 * nve_error)
          << e.file << " " << rule << ": pe_jump " << error << ", nve " << nve_error;
      std::printf("%-16s %-11s position error %.3g (fix nve %.3g)\n", e.file.c_str(), rule.c_str(),
                  error, nve_error);
    }
  }
}

TEST(PEJumpLammpsExamples, DepositWithTwoIntegrators)
{
  // the example integrates the substrate and the deposited atoms with two
  // fixes: with fix pe_jump both take lobatto 2 (forces at the step ends)
  const auto count = [](const std::string &integrator) {
    Sim s;
    s.cmds({"variable integrator string \"" + integrator + "\"",
            "variable deposited string \"" + integrator + "\"", "log none"});
    s.lmp->input->file((std::string(PEJUMP_INPUTS) + "/in.deposit").c_str());
    double zmax_new = -1e300;
    for (int i = 0; i < s.lmp->atom->nlocal; i++)
      if (s.lmp->atom->type[i] == 2) zmax_new = std::max(zmax_new, s.lmp->atom->x[i][2]);
    return std::make_pair(s.lmp->atom->natoms, zmax_new);
  };
  const auto nve = count("nve");
  const auto pj = count("pe_jump quadrature lobatto 2");
  EXPECT_EQ(pj.first, nve.first);    // the same 6 atoms deposited
  // the highest deposited atom falls as with fix nve
  EXPECT_NEAR(pj.second, nve.second, 1e-6);
  EXPECT_THROW(count("pe_jump"), LAMMPS_NS::LAMMPSException);
}

/* ----------------------------------------------------------------------
   the example as a user swaps fix nve of the substrate (fix 3) only: the
   deposited atoms stay with fix nve (fix 1), and they will interact with
   the substrate, which a rule with nodes inside the step cannot take.
   Refused at setup, before the first step (it stopped at step 400, where
   the first deposited atom reached the substrate); lobatto 2 runs to the
   end and deposits the atoms of fix nve
------------------------------------------------------------------------- */

TEST(PEJumpLammpsExamples, DepositBesideAnotherIntegratorIsRefusedAtSetup)
{
  const auto run = [](const std::string &rule, std::string &error) {
    Sim s;
    s.cmds({"variable integrator string \"pe_jump quadrature " + rule + "\"",
            "variable deposited string nve", "log none"});
    const std::string caught = error_from([&] {
      s.lmp->input->file((std::string(PEJUMP_INPUTS) + "/in.deposit").c_str());
    });
    if (caught != "no error") error = caught;
    return std::make_pair(s.lmp->update->ntimestep, s.lmp->atom->natoms);
  };
  // (midpoint and Legendre rules are refused at init beside fix 5, wall/reflect)
  for (const std::string rule : {"lobatto 3", "lobatto 5", "auto 1e-6"}) {
    std::string error;
    EXPECT_EQ(run(rule, error).first, 0) << rule;
    EXPECT_THAT(error,
                ::testing::ContainsRegex("fix 4 \\(deposit\\) inserts atoms that fix 1 \\(nve\\) "
                                         "integrates and that will interact with this fix's "
                                         "atoms"))
        << rule;
  }
  std::string error;
  const auto end = run("lobatto 2", error);
  EXPECT_EQ(error, "");
  EXPECT_EQ(end.first, 600);
  EXPECT_EQ(end.second, 356);    // 350 atoms of the substrate, 6 deposited
}
