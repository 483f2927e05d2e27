// fix pe_jump beside other fixes: forces added or replaced by other fixes,
// velocities changed by them, thermostats, other integrators, constraints.
// Every case is measured against fix nve on the same input or refused.

#include "pe_jump_systems.h"

#include "exceptions.h"
#include "fix.h"
#include "modify.h"
#include "update.h"
#include "utils.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iterator>
#include <regex>
#include <string>
#include <utility>
#include <vector>

using namespace PEJumpTest;
using ::testing::ContainsRegex;
using ::testing::Not;

namespace {

const std::vector<std::string> ALL_RULES = {"midpoint",   "lobatto 2",  "lobatto 3",  "lobatto 4",
                                            "lobatto 5",  "legendre 1", "legendre 2", "legendre 3",
                                            "legendre 4", "legendre 5", "auto 1e-8"};

// ideal gas of 20 atoms at rest in a large periodic box (pair_style zero)
void ideal_gas(Sim &s)
{
  s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "boundary p p p",
          "region box block 0 20 0 20 0 20", "create_box 1 box",
          "create_atoms 1 random 20 4711 NULL", "mass 1 2.0", "pair_style zero 1.0",
          "pair_coeff * *", "neighbor 0.3 bin"});
}

// mean temperature and potential energy over one run of n steps (sampled
// every 10 steps): one run, so that nothing between runs can hide what
// happens during a run. Thermostats that rescale velocities at the end of
// a step make the sampled temperature their target whatever the dynamics
// does; the potential energy tells the temperature the atoms really have
std::pair<double, double> mean_temp_pe(Sim &s, int n)
{
  s.cmd("reset_timestep 0");
  s.cmd(fmt::format("fix avt all ave/time 10 {} {} c_thermo_temp c_thermo_pe", n / 10, n));
  s.cmd(fmt::format("run {} post no", n));
  const std::pair<double, double> t = {s.eval("f_avt[1]"),
                                       s.eval("f_avt[2]") / s.lmp->atom->natoms};
  s.cmd("unfix avt");
  return t;
}
double mean_temp(Sim &s, int n)
{
  return mean_temp_pe(s, n).first;
}

// |max - min| of etotal (+ the fix energies) sampled every n steps
double energy_spread(Sim &s, const std::string &energy, int chunks, int steps)
{
  double lo = 1e300, hi = -1e300;
  for (int c = 0; c <= chunks; ++c) {
    if (c) s.cmd("run " + std::to_string(steps) + " post no");
    const double e = s.eval(energy);
    lo = std::min(lo, e);
    hi = std::max(hi, e);
  }
  return hi - lo;
}

}    // namespace

/* ----------------------------------------------------------------------
   fix addforce and fix gravity: a constant force gives the exact motion
   of the centre of mass for every rule, in the first run too
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, ConstantForcesGiveExactMotionForEveryRule)
{
  for (const auto &rule : ALL_RULES) {
    for (const std::string force : {"addforce 2.0 0.0 0.0", "gravity 1.0 vector 1 0 0"}) {
      Sim s;
      ideal_gas(s);
      s.cmds({"fix 1 all pe_jump quadrature " + rule, "fix 2 all " + force, "timestep 0.005",
              "variable xc equal xcm(all,x)", "variable vc equal vcm(all,x)", "thermo 0"});
      const double x0 = s.eval("v_xc");
      s.cmd("run 200 post no");    // t = 1, acceleration 1
      EXPECT_NEAR(s.eval("v_vc"), 1.0, 1e-12) << rule << " " << force;
      EXPECT_NEAR(s.eval("v_xc") - x0, 0.5, 1e-12) << rule << " " << force;
    }
  }
}

/* ----------------------------------------------------------------------
   a force that depends on time, fix addforce v_fx with fx = sin(2 time):
   the fix forces are taken with the atoms at the primary node, and there
   the time is that of the node, so that every rule integrates them to
   second order (exact x(1) = 0.5 - sin(2)/4, v(1) = (1 - cos 2)/2); taken
   at the end of the step they would give an error of h F/2
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, TimeDependentForcesAreSecondOrder)
{
  const auto error_at = [](const std::string &fix, double h) {
    Sim s;
    ideal_gas(s);
    s.cmds({"velocity all set 0 0 0", "fix 1 all " + fix, "variable fx equal sin(2*time)",
            "fix 2 all addforce v_fx 0 0", fmt::format("timestep {}", h),
            "variable xc equal xcm(all,x)", "thermo 0"});
    const double x0 = s.eval("v_xc");
    s.cmd(fmt::format("run {} post no", static_cast<int>(std::lround(1.0 / h))));
    // per unit mass: the atoms have mass 2
    const double exact = 0.5 * (0.5 - std::sin(2.0) / 4.0);
    return std::fabs(s.eval("v_xc") - x0 - exact);
  };
  const double nve = error_at("nve", 0.01);
  for (const auto &rule : ALL_RULES) {
    const std::string fix = "pe_jump quadrature " + rule;
    const double coarse = error_at(fix, 0.01), fine = error_at(fix, 0.005);
    EXPECT_LT(coarse, 2.0 * nve) << rule;
    EXPECT_GT(coarse / fine, 3.5) << rule;    // second order: 4
  }

  // beside fix nve on other atoms the time stays the step end's, which the
  // atoms of fix nve need, and they keep the forces of the MD step also on
  // steps that tally energy (thermo 10): they move as with fix nve alone
  std::vector<double> b[2];
  for (const std::string fix : {"nve", "pe_jump"}) {
    Sim s;
    ideal_gas(s);
    s.cmds({"velocity all set 0 0 0", "group a id 1:10", "group b id 11:20", "fix 1 a " + fix,
            "fix 3 b nve", "variable fx equal sin(2*time)", "fix 2 all addforce v_fx 0 0",
            "timestep 0.01", "thermo 10", "run 100 post no"});
    b[fix == "pe_jump"] = {s.eval("xcm(b,x)"), s.eval("vcm(b,x)")};
  }
  EXPECT_NEAR(b[1][0], b[0][0], 1e-12);
  EXPECT_NEAR(b[1][1], b[0][1], 1e-12);
}

/* ----------------------------------------------------------------------
   a force field that changes with time (fix adapt with a variable of
   time, which acts before every force evaluation, also at the extra
   nodes): every node sees its own time, so every rule stays second order
   (the extra nodes saw the step end's time: lobatto 3 and legendre 2 had
   error ratios 2.2 when h was halved)
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, TimeDependentForceFieldIsSecondOrder)
{
  const auto final_x = [](const std::string &fix, double h) {
    Sim s;
    lj_liquid(s, 3);
    s.cmds({"pair_modify shift yes", "variable eps equal 1.0+4.0*time",
            "fix 0 all adapt 1 pair lj/cut epsilon * * v_eps", "fix 1 all " + fix,
            fmt::format("timestep {}", h), "thermo 0"});
    s.cmd(fmt::format("run {} post no", static_cast<int>(std::lround(0.25 / h))));
    return unwrapped_positions(s);
  };
  const auto error = [](const std::vector<double> &a, const std::vector<double> &b) {
    double d = 0.0;
    for (size_t i = 0; i < a.size(); i++) d = std::max(d, std::fabs(a[i] - b[i]));
    return d;
  };
  const auto ref = final_x("nve", 0.005 / 32);
  const double nve = error(final_x("nve", 0.005), ref);
  for (const std::string rule : {"midpoint", "lobatto 3", "legendre 2", "auto 1e-8"}) {
    const std::string fix = "pe_jump quadrature " + rule;
    const double coarse = error(final_x(fix, 0.005), ref), fine = error(final_x(fix, 0.0025), ref);
    EXPECT_LT(coarse, 3.0 * nve) << rule << ": " << coarse << ", nve " << nve;
    EXPECT_GT(coarse / fine, 3.0) << rule << ": " << coarse << " / " << fine;    // second order: 4
  }
}

/* ----------------------------------------------------------------------
   the same ramp written with ramp() (the step number) is sampled with the
   step end's value at every node: first order (error ratio about 2 per
   halving of the step, midpoint), and a warning names the variable and
   the fix. It names nothing for variables of time, for lobatto 2 (whose
   nodes are step ends), for an impulse at the step end (addforce with
   lobatto 3), or when no fix that takes forces from variables is defined
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, ForceFieldOfTheStepNumberWarns)
{
  const auto run = [](const std::vector<std::string> &cmds, double h, std::string *out) {
    Sim s(MPI_COMM_WORLD, out == nullptr);
    lj_liquid(s, 3);
    s.cmds({"pair_modify shift yes", fmt::format("timestep {}", h), "thermo 0"});
    s.cmds(cmds);
    if (out) ::testing::internal::CaptureStdout();
    s.cmd(fmt::format("run {} post no", static_cast<int>(std::lround(0.25 / h))));
    if (out) *out = ::testing::internal::GetCapturedStdout();
    return unwrapped_positions(s);
  };
  const auto error = [](const std::vector<double> &a, const std::vector<double> &b) {
    double d = 0.0;
    for (size_t i = 0; i < a.size(); i++) d = std::max(d, std::fabs(a[i] - b[i]));
    return d;
  };
  const std::string adapt = "fix 0 all adapt 1 pair lj/cut epsilon * * v_eps";
  const auto ramp = [&](const std::string &fix, double h, std::string *out = nullptr) {
    return run({"variable eps equal ramp(1.0,2.0)", adapt, "fix 1 all " + fix}, h, out);
  };
  const auto ramp_ref = ramp("nve", 0.005 / 32);
  std::string out;
  const double coarse = error(ramp("pe_jump", 0.005, &out), ramp_ref);
  const double fine = error(ramp("pe_jump", 0.0025), ramp_ref);
  EXPECT_LT(coarse / fine, 2.5) << coarse << " / " << fine;    // first order: 2
  EXPECT_THAT(out, ContainsRegex("variable\\(s\\) eps read the step number.*fix 0 \\(adapt\\)"));

  struct Case {
    std::vector<std::string> cmds;
    bool warns;
  };
  const std::vector<Case> cases = {
      {{"variable eps equal 1.0+4.0*time", adapt, "fix 1 all pe_jump"}, false},
      {{"variable eps equal ramp(1.0,2.0)", adapt, "fix 1 all pe_jump quadrature lobatto 2"},
       false},
      {{"variable eps equal ramp(1.0,2.0)", adapt, "fix 1 all pe_jump quadrature lobatto 3"}, true},
      {{"variable t equal elapsed*dt", "variable eps equal 1.0+v_t", adapt, "fix 1 all pe_jump"},
       true},
      {{"variable fx equal 0.1*step*dt", "fix 0 all addforce v_fx 0.0 0.0", "fix 1 all pe_jump"},
       true},
      {{"variable fx equal 0.1*step*dt", "fix 0 all addforce v_fx 0.0 0.0",
        "fix 1 all pe_jump quadrature lobatto 3"},
       false},
      {{"variable nstep equal 2*dt", "variable fx equal v_nstep", "fix 0 all addforce v_fx 0.0 0.0",
        "fix 1 all pe_jump"},
       false},
      {{"variable s equal step", "fix 0 all viscous 0.1", "fix 1 all pe_jump"}, false},
      // the keyword last in the formula
      {{"variable fx equal 1e-4*step", "fix 0 all addforce v_fx 0.0 0.0", "fix 1 all pe_jump"},
       true},
      // fix setforce holding atoms with constants is not named
      {{"variable s equal step", "group one id 1", "fix 0 one setforce 0.0 0.0 0.0",
        "fix 1 all pe_jump"},
       false}};
  for (const auto &c : cases) {
    run(c.cmds, 0.005, &out);
    EXPECT_EQ(std::regex_search(out, std::regex("read the step number")), c.warns)
        << c.cmds.front() << " ... " << c.cmds.back();
  }
}

/* ----------------------------------------------------------------------
   the warnings of variables of the step number and of fix energies taken
   inside the step come once, not at every run with the same settings
   (run 0 followed by a run printed each twice); a new setting (another
   such fix and variable) warns again
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, SettingsWarningsComeOnce)
{
  Sim s(MPI_COMM_WORLD, false);
  lj_liquid(s, 3);
  s.cmds({"variable fx equal 1e-4*step", "fix 0 all addforce v_fx 0.0 0.0",
          "fix_modify 0 energy yes", "fix 1 all pe_jump", "timestep 0.005", "thermo 0"});
  const auto count = [](const std::string &text, const std::string &pattern) {
    const std::regex re(pattern);
    return std::distance(std::sregex_iterator(text.begin(), text.end(), re),
                         std::sregex_iterator());
  };
  ::testing::internal::CaptureStdout();
  s.cmds({"run 0", "run 10 post no", "run 10 post no"});
  std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(count(out, "variable\\(s\\) fx read the step number"), 1);
  EXPECT_EQ(count(out, "the energy of fix 0 \\(addforce\\) \\(fix_modify energy yes\\)"), 1);
  ::testing::internal::CaptureStdout();
  s.cmds({"variable fy equal 1e-4*elapsed", "fix 2 all addforce 0.0 v_fy 0.0",
          "fix_modify 2 energy yes", "run 0", "run 10 post no"});
  out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(count(out, "read the step number"), 1);
  EXPECT_EQ(count(out, "variable\\(s\\) fx, fy read the step number"), 1);
  EXPECT_EQ(count(out, "the energy of fix 0 \\(addforce\\), fix 2 \\(addforce\\)"), 1);
}

/* ----------------------------------------------------------------------
   fix langevin inside the step (midpoint): its temperature is high by
   gamma h/2 (256-atom LJ liquid, damping 0.5, h = 0.005, 10^6 steps: mean
   T 0.54 % above fix nve's, lobatto 3 0.11 % below). The log says so, once
   per fix, with the rules that take it at the step end; they say nothing
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, LangevinInsideTheStepWarns)
{
  const auto warnings = [](const std::string &rule) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s, 3);
    s.cmds({"fix 1 all pe_jump quadrature " + rule, "fix 2 all langevin 1.0 1.0 0.5 4711",
            "timestep 0.005", "thermo 0"});
    ::testing::internal::CaptureStdout();
    s.cmds({"run 0", "run 10 post no"});
    const std::string out = ::testing::internal::GetCapturedStdout();
    const std::regex re("fix 2 \\(langevin\\) acts at the centre of the step");
    return std::distance(std::sregex_iterator(out.begin(), out.end(), re), std::sregex_iterator());
  };
  EXPECT_EQ(warnings("midpoint"), 1);
  EXPECT_EQ(warnings("legendre 3"), 1);
  EXPECT_EQ(warnings("lobatto 3"), 0);
  EXPECT_EQ(warnings("lobatto 2"), 0);
}

/* ----------------------------------------------------------------------
   the energy of a force-adding fix with fix_modify energy yes enters pe at
   the primary node: with midpoint (a spring/self on an LJ liquid) f_ss was
   0.23, 0.11, 0.05 off fix nve's at h = 0.004, 0.002, 0.001 (first order,
   etotal alike) without a word. A warning names the fix; none with a
   Lobatto rule or without energy yes
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, EnergyOfForceFixesInsideTheStepWarns)
{
  const auto warned = [](const std::string &rule, bool energy) {
    Sim s(MPI_COMM_WORLD, false);
    lj_liquid(s, 3);
    s.cmds({"fix int all pe_jump quadrature " + rule, "fix ss all spring/self 2.0",
            "fix push all addforce 0.1 0.0 0.0"});
    if (energy) s.cmd("fix_modify ss energy yes");
    ::testing::internal::CaptureStdout();
    s.cmd("run 2 post no");
    const std::string out = ::testing::internal::GetCapturedStdout();
    return std::regex_search(out,
                             std::regex("the energy of fix ss \\(spring/self\\) "
                                        "\\(fix_modify energy yes\\)"));
  };
  EXPECT_TRUE(warned("midpoint", true));
  EXPECT_TRUE(warned("legendre 2", true));
  EXPECT_FALSE(warned("midpoint", false));
  EXPECT_FALSE(warned("lobatto 3", true));
  EXPECT_FALSE(warned("lobatto 2", true));
}

/* ----------------------------------------------------------------------
   forces that depend on the velocities (bond_style bpm/spring with
   damping; the styles that need comm_modify vel yes) drive the
   alternating mode of the jumps, which then grows at any time step
   (measured: midpoint and lobatto 3 stop as unstable with damping 1, 0.1
   and 0.02): refused, except with lobatto 2, which is velocity Verlet for
   them and follows fix nve
------------------------------------------------------------------------- */

namespace {
void damped_bpm_block(Sim &s)
{
  s.cmds({"units lj",
          "atom_style bond",
          "atom_modify map array",
          "boundary f f f",
          "special_bonds lj 0.0 1.0 1.0 coul 0.0 1.0 1.0",
          "newton on off",
          "comm_modify vel yes cutoff 2.6",
          "lattice fcc 1.0",
          "region box block -4 4 -4 4 -4 4",
          "create_box 1 box bond/types 1 extra/bond/per/atom 20 extra/special/per/atom 50",
          "region blk block -2 2 -2 2 -2 2",
          "create_atoms 1 region blk",
          "displace_atoms all random 0.05 0.05 0.05 134598738",
          "mass 1 1.0",
          "neighbor 1.0 bin",
          "pair_style bpm/spring",
          "pair_coeff 1 1 1.0 1.0 1.0",
          "create_bonds many all all 1 0.0 1.5",
          "neighbor 0.3 bin",
          "special_bonds lj 0.0 1.0 1.0 coul 1.0 1.0 1.0",
          "bond_style bpm/spring",
          "bond_coeff 1 1.0 0.5 1.0",
          "velocity all create 0.05 4711",
          "timestep 0.05",
          "thermo 0"});
}
}    // namespace

TEST(PEJumpOtherFixes, VelocityDependentForcesNeedLobatto2)
{
  for (const std::string fix : {"pe_jump", "pe_jump quadrature lobatto 3",
                                "pe_jump quadrature auto 1e-8", "pe_jump/async 2 all"}) {
    const std::string err = [&]() {
      Sim s;
      damped_bpm_block(s);
      return error_from([&] {
        s.cmds({"fix 1 all " + fix, "run 1"});
      });
    }();
    EXPECT_THAT(err,
                ContainsRegex("comm_modify vel yes is set \\(forces that depend on "
                              "velocities grow the jumps\\)"))
        << fix;
  }
  std::vector<double> x[2];
  for (const int which : {0, 1}) {
    Sim s;
    damped_bpm_block(s);
    s.cmds({which ? "fix 1 all pe_jump quadrature lobatto 2" : "fix 1 all nve", "run 200"});
    x[which] = unwrapped_positions(s);
  }
  EXPECT_LT(max_diff(x[0], x[1]), 1e-10);
}

/* ----------------------------------------------------------------------
   fix setforce and fix freeze hold atoms exactly for every rule
------------------------------------------------------------------------- */

/* ----------------------------------------------------------------------
   accelerator packages whose styles compute forces on a device or into
   buffers of their own, which only LAMMPS' MD loop collects, are refused
   by both fixes: GPU and INTEL are found by the fix that their package
   command makes. Neither package is in this build, so a fix without
   hooks (property/atom) stands in for the package's fix, renamed to its
   style; without the rename the same input runs
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, DeviceAcceleratorsAreRefused)
{
  for (const std::string package : {"GPU", "INTEL", ""})
    for (const std::string fix : {"pe_jump", "pe_jump/async 2 all"}) {
      Sim s;
      ideal_gas(s);
      s.cmds({"fix package all property/atom i_stand_in", "fix 1 all " + fix, "timestep 0.01"});
      if (!package.empty()) {
        LAMMPS_NS::Fix *stand_in = s.lmp->modify->get_fix_by_id("package");
        delete[] stand_in->style;
        stand_in->style = LAMMPS_NS::utils::strdup(package);
      }
      const std::string err = error_in(s, "run 2");
      if (package.empty())
        EXPECT_EQ(err, "no error") << fix;
      else
        EXPECT_THAT(err,
                    ContainsRegex("Fix " + LAMMPS_NS::utils::split_words(fix)[0] +
                                  " does not support the " + package + " package; see"))
            << fix;
    }
}

TEST(PEJumpOtherFixes, SetforceHoldsAtomsForEveryRule)
{
  for (const auto &rule : ALL_RULES) {
    Sim s;
    lj_liquid(s, 3);
    s.cmds({"region wall block INF INF INF INF 0 1.2", "group wall region wall",
            "group mobile subtract all wall", "velocity wall set 0 0 0",
            "fix 1 all pe_jump quadrature " + rule, "fix 2 wall setforce 0.0 0.0 0.0",
            "compute dx wall displace/atom", "compute dmax wall reduce max c_dx[4]",
            "timestep 0.005", "thermo 0", "run 200 post no"});
    EXPECT_EQ(s.eval("c_dmax"), 0.0) << rule;
  }
}

/* ----------------------------------------------------------------------
   position-dependent forces of other fixes: the energy including the
   fix's own energy is kept as well as fix nve keeps it
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, PositionDependentFixForcesConserveLikeNve)
{
  // fix (as ID 2 on all atoms, with fix_modify energy yes), z boundary
  const std::vector<std::pair<std::string, std::string>> fixes = {
      {"spring/self 5.0", "p"},
      {"spring tether 50.0 3.4 3.4 3.4 0.0", "p"},
      {"indent 10.0 sphere 2.25 2.25 2.25 0.4", "p"},
      {"wall/lj93 zlo EDGE 1.0 1.0 2.5 zhi EDGE 1.0 1.0 2.5", "f"}};
  for (const auto &fix : fixes) {
    const auto spread = [&](const std::string &integrator) {
      Sim s;
      s.cmds({"units lj",
              "atom_style atomic",
              "atom_modify map array",
              "boundary p p " + fix.second,
              "lattice fcc 0.8442",
              "region box block 0 4 0 4 -0.5 4.5",
              "create_box 1 box",
              "region inside block 0 4 0 4 0 4",
              "create_atoms 1 region inside",
              "mass 1 1.0",
              "velocity all create 1.0 87287 loop geom",
              "pair_style lj/cut 2.5",
              "pair_coeff 1 1 1.0 1.0 2.5",
              "neighbor 0.3 bin",
              "neigh_modify every 1 delay 0 check yes",
              "fix 1 all " + integrator,
              "fix 2 all " + fix.first,
              "fix_modify 2 energy yes",
              "timestep 0.004",
              "thermo 0"});
      s.cmd("run 0 post no");
      return energy_spread(s, "etotal", 20, 50);
    };
    const double nve = spread("nve");
    double worst = 0.0;
    for (const auto &rule : ALL_RULES) {
      const double pj = spread("pe_jump quadrature " + rule);
      worst = std::max(worst, pj / nve);
      EXPECT_LT(pj, 2.0 * nve) << fix.first << " " << rule << ": nve " << nve << ", pe_jump " << pj;
    }
    std::printf("%-52s etotal spread: nve %.3g, largest pe_jump/nve %.2f\n", fix.first.c_str(), nve,
                worst);
  }
}

/* ----------------------------------------------------------------------
   fix viscous: v(t) of a single atom as with fix nve
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, ViscousDampsLikeNve)
{
  const auto speed = [](const std::string &integrator) {
    Sim s;
    ideal_gas(s);
    s.cmds({"velocity all set 1.0 0.0 0.0", "fix 1 all " + integrator, "fix 2 all viscous 2.0",
            "variable vc equal vcm(all,x)", "timestep 0.005", "thermo 0", "run 200 post no"});
    return s.eval("v_vc");
  };
  const double exact = std::exp(-1.0);    // gamma/m = 1, t = 1
  const double nve = speed("nve");
  for (const auto &rule : ALL_RULES) {
    const double pj = speed("pe_jump quadrature " + rule);
    EXPECT_LT(std::fabs(pj - exact), 2.0 * std::fabs(nve - exact) + 1e-12)
        << rule << ": nve " << nve << ", pe_jump " << pj << ", exact " << exact;
  }
}

/* ----------------------------------------------------------------------
   thermostats: fix langevin reaches its target like fix nve + langevin,
   without pumping the parasitic mode; temp/berendsen and temp/rescale
   change the velocities that the scheme goes on with
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, LangevinReachesTargetTemperature)
{
  for (const std::string integrator : {"nve", "pe_jump", "pe_jump quadrature lobatto 3"}) {
    Sim s;
    lj_liquid(s);
    s.cmds({"fix 1 all " + integrator, "fix 2 all langevin 1.0 1.0 0.5 48279", "timestep 0.005",
            "thermo 0", "run 1000 post no"});
    const double jump0 = (integrator != "nve") ? s.vec("1", 1) : 0.0;
    const double t = mean_temp(s, 10000);
    EXPECT_NEAR(t, 1.0, 0.025) << integrator;
    if (integrator != "nve") {
      // the jump energy stays that of a smooth jump h F/m: it does not grow
      EXPECT_LT(s.vec("1", 1), 2.0 * jump0) << integrator;
      EXPECT_LT(s.vec("1", 1), 0.01 * s.eval("ke") * s.lmp->atom->natoms) << integrator;
    }
  }
}

/* ----------------------------------------------------------------------
   a perfect crystal at rest that a thermostat heats (as in LAMMPS'
   examples/ttm): the jumps begin at round-off size and grow by many orders
   of magnitude as the thermostat's forces set in, which is no instability
   (the stability guard stopped every rule but the Lobatto ones at step 3,
   "jumps grew 8.5e12-fold")
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, CrystalAtRestHeatedByAThermostatRuns)
{
  double t_nve = 0.0;
  for (const std::string integrator :
       {"nve", "pe_jump", "pe_jump quadrature legendre 2", "pe_jump quadrature lobatto 3"}) {
    Sim s;
    s.cmds({"units lj", "atom_style atomic", "lattice fcc 0.8442", "region box block 0 4 0 4 0 4",
            "create_box 1 box", "create_atoms 1 box", "mass 1 1.0", "pair_style lj/cut 2.5",
            "pair_coeff 1 1 1.0 1.0 2.5", "fix 1 all " + integrator,
            "fix 2 all langevin 1.0 1.0 0.5 4711", "timestep 0.005", "thermo 0",
            "run 500 post no"});
    const double t = mean_temp(s, 4000);
    if (integrator == "nve") t_nve = t;
    EXPECT_NEAR(t, 1.0, 0.04) << integrator;
    EXPECT_NEAR(t, t_nve, 0.04) << integrator;
  }
}

TEST(PEJumpOtherFixes, VelocityRescalingThermostatsAct)
{
  for (const std::string thermostat :
       {"temp/berendsen 1.0 1.0 0.1", "temp/rescale 10 1.0 1.0 0.02 1.0",
        "temp/csvr 1.0 1.0 0.1 5533"}) {
    double pe_nve = 0.0;
    for (const std::string integrator : {"nve", "pe_jump", "pe_jump quadrature lobatto 3"}) {
      Sim s;
      lj_liquid(s);
      s.cmds({"velocity all scale 2.0", "fix 1 all " + integrator, "fix 2 all " + thermostat,
              "timestep 0.005", "thermo 0", "run 1000 post no"});
      const auto tpe = mean_temp_pe(s, 2000);
      EXPECT_NEAR(tpe.first, 1.0, 0.03) << thermostat << " " << integrator;
      if (integrator == "nve")
        pe_nve = tpe.second;
      else    // per atom; at T = 1.64 it is 0.4 higher
        EXPECT_NEAR(tpe.second, pe_nve, 0.03) << thermostat << " " << integrator;
    }
  }
}

/* ----------------------------------------------------------------------
   fix momentum stops the centre of mass; fix wall/reflect reflects;
   atoms inserted by fix deposit keep their velocity
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, MomentumStopsCentreOfMass)
{
  for (const auto &rule : ALL_RULES) {
    Sim s;
    lj_liquid(s);
    s.cmds({"velocity all set 0.5 0.0 0.0 sum yes", "fix 1 all pe_jump quadrature " + rule,
            "fix 2 all momentum 1 linear 1 1 1", "variable xc equal xcm(all,x)",
            "variable vc equal vcm(all,x)", "timestep 0.005", "thermo 0", "run 0 post no"});
    const double x0 = s.eval("v_xc"), v0 = s.eval("v_vc");
    s.cmd("run 100 post no");
    // stopped at the end of the first step, as with fix nve: it moved by h v_cm
    EXPECT_NEAR(s.eval("v_vc"), 0.0, 1e-12) << rule;
    EXPECT_NEAR(s.eval("v_xc") - x0, 0.005 * v0, 1e-12) << rule;
  }
}

TEST(PEJumpOtherFixes, WallReflectKeepsAtomsInside)
{
  for (const auto &rule : ALL_RULES) {
    const std::vector<std::string> setup = {"units lj",
                                            "atom_style atomic",
                                            "atom_modify map array",
                                            "boundary p p f",
                                            "region box block 0 10 0 10 0 10",
                                            "create_box 1 box",
                                            "create_atoms 1 single 5 5 1",
                                            "mass 1 1.0",
                                            "pair_style zero 1.0",
                                            "pair_coeff * *",
                                            "velocity all set 0.0 0.0 -1.0",
                                            "fix 1 all pe_jump quadrature " + rule,
                                            "fix 2 all wall/reflect zlo EDGE",
                                            "timestep 0.01",
                                            "thermo 0"};
    // the reflection acts at the primary node: refused where that lies
    // inside the step (midpoint, Legendre rules)
    if ((rule == "midpoint") || (rule.rfind("legendre", 0) == 0)) {
      EXPECT_THAT(error_of(setup, "run 300 post no"), ContainsRegex("reflects atoms at the node"))
          << rule;
      continue;
    }
    Sim s;
    s.cmds(setup);
    s.cmd("run 300 post no");
    // bounced at t = 1 with speed 1: at t = 3 it is at z = 2, moving up
    EXPECT_NEAR(s.v(1, 2), 1.0, 1e-12) << rule;
    EXPECT_NEAR(s.x(1, 2), 2.0, 1e-9) << rule;
  }
}

/* ----------------------------------------------------------------------
   an LJ liquid between reflecting walls that fix oneway drives down: fix
   nve and lobatto 2 run, lobatto 3 grows on the reversed velocities until
   the guard stops it (step 1565). The error names the other fixes' velocity
   changes and lobatto 2, not only the time step (which is 4x below the
   liquid's limit)
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, InstabilityBesideReflectingFixesNamesThem)
{
  const auto input = [](const std::string &rule) {
    return std::vector<std::string>{"units lj",
                                    "atom_style atomic",
                                    "boundary p p f",
                                    "lattice fcc 0.8442",
                                    "region box block 0 6 0 6 0 6",
                                    "create_box 1 box",
                                    "create_atoms 1 box",
                                    "mass 1 1.0",
                                    "velocity all create 1.5 4928459 loop geom",
                                    "pair_style lj/cut 2.5",
                                    "pair_coeff 1 1 1.0 1.0 2.5",
                                    "region half block INF INF INF INF INF 5 units box",
                                    "fix 1 all pe_jump quadrature " + rule,
                                    "fix 2 all wall/reflect zlo EDGE zhi EDGE",
                                    "fix 3 all oneway 10 half -z",
                                    "timestep 0.005",
                                    "thermo 0"};
  };
  const std::string error = error_of(input("lobatto 3"), "run 2000 post no");
  EXPECT_THAT(error, ContainsRegex("is unstable at step [0-9]+"));
  EXPECT_THAT(error,
              ContainsRegex("Velocities reversed by fix 2 \\(wall/reflect\\), fix 3 "
                            "\\(oneway\\) can also make the scheme grow with this rule: "
                            "use quadrature lobatto 2"));
  Sim s;
  s.cmds(input("lobatto 2"));
  s.cmd("run 2000 post no");
  EXPECT_EQ(s.lmp->update->ntimestep, 2000);

  // a thermostat that rescales velocities, at a time step too large for
  // the hot liquid: only the time step is advised
  const std::string hot =
      error_of({"units lj", "atom_style atomic", "lattice fcc 0.8442",
                "region box block 0 5 0 5 0 5", "create_box 1 box", "create_atoms 1 box",
                "mass 1 1.0", "velocity all create 3.0 87287 loop geom", "pair_style lj/cut 2.5",
                "pair_coeff 1 1 1.0 1.0 2.5", "timestep 0.02", "fix 1 all pe_jump",
                "fix 2 all temp/berendsen 3.0 3.0 0.5", "thermo 0"},
               "run 2000 post no");
  EXPECT_THAT(hot, ContainsRegex("is unstable at step [0-9]+|atoms move more than half"));
  EXPECT_THAT(hot, Not(ContainsRegex("reversed")));
}

/* ----------------------------------------------------------------------
   lobatto 2 (velocity Verlet) reflects at the step end as fix nve does: a
   free atom that left a collision keeps its speed through the bounce
   exactly (midpoint, whose reflection came inside the step, changed it by
   the size of the atom's jump, 0.992010 -> 0.991833, and is refused)
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, ReflectedAtomKeepsItsSpeed)
{
  Sim s;
  s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "boundary p p f",
          "region box block 0 10 0 10 0 20", "create_box 1 box",
          "create_atoms 1 single 5.0 5.0 10.0 units box",
          "create_atoms 1 single 5.3 5.2 10.9 units box", "mass 1 1.0", "pair_style lj/cut 2.5",
          "pair_coeff 1 1 1.0 1.0 2.5", "timestep 0.005", "fix 1 all pe_jump quadrature lobatto 2",
          "fix 2 all wall/reflect zlo EDGE zhi EDGE", "thermo 0", "run 1800 post no"});
  // atom 1 flies freely towards the wall z = 0 and bounces at t ~ 10
  const auto speed = [&]() {
    return std::sqrt(s.v(1, 0) * s.v(1, 0) + s.v(1, 1) * s.v(1, 1) + s.v(1, 2) * s.v(1, 2));
  };
  const double before = speed();
  ASSERT_LT(s.v(1, 2), -0.5);
  s.cmd("run 600 post no");
  ASSERT_GT(s.v(1, 2), 0.5);
  EXPECT_NEAR(speed(), before, 1e-13);
  // midpoint reflects inside the step: refused
  EXPECT_THROW(s.cmds({"unfix 1", "fix 1 all pe_jump", "run 1 post no"}),
               LAMMPS_NS::LAMMPSException);
}

TEST(PEJumpOtherFixes, DepositedAtomsKeepTheirVelocity)
{
  std::vector<std::string> integrators = {"nve"};
  for (const auto &rule : ALL_RULES) integrators.push_back("pe_jump quadrature " + rule);
  for (const auto &integrator : integrators) {
    Sim s;
    s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "boundary p p f",
            "region box block 0 10 0 10 0 20", "create_box 1 box", "mass 1 1.0",
            "pair_style zero 1.0", "pair_coeff * *", "region slab block 0 10 0 10 15 16",
            "fix 1 all " + integrator, "fix 2 all deposit 1 1 10 12345 region slab vz -1.0 -1.0",
            "timestep 0.01", "thermo 0", "run 11 post no"});
    // inserted at step 10 inside the slab, moving down at speed 1 since then
    ASSERT_EQ(s.lmp->atom->natoms, 1) << integrator;
    EXPECT_NEAR(s.v(1, 2), -1.0, 1e-12) << integrator;
    const double z1 = s.x(1, 2);
    s.cmd("run 100 post no");
    EXPECT_NEAR(s.x(1, 2), z1 - 1.0, 1e-9) << integrator;
  }
}

/* ----------------------------------------------------------------------
   an atom that fix deposit inserts where a force acts starts as with fix
   nve: LAMMPS inserts it after initial_integrate, at the step end, with
   its velocity as the half-step velocity, and fix nve gives it half a
   kick there. The fix starts its jump with the kick h F/m of its force
   there, and the midpoint rule leaves it at its insertion point. Before,
   the atom started without a jump: lobatto 2 gave it a whole kick (vz
   0.02 off here, 1.4e-3 in z after 30 steps) and midpoint moved it h v/2
   on from its insertion point (1.25e-3)
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, DepositedAtomsStartAsWithNve)
{
  // z and vz of the deposited atom after its insertion step (the first
  // step of the run), and z 30 steps later
  const auto run = [](const std::string &integrator) {
    Sim s;
    s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "boundary p p f",
            "region box block 0 10 0 10 0 20", "create_box 2 box", "mass * 1.0",
            "create_atoms 2 single 5 5 10", "group mobile type 1", "pair_style lj/cut 2.5",
            "pair_coeff * * 1.0 1.0 2.5", "region slab block 4.9 5.1 4.9 5.1 11.03 11.07",
            "fix 1 mobile " + integrator,
            "fix 2 mobile deposit 1 1 100 12345 region slab vz -0.5 -0.5", "timestep 0.005",
            "thermo 0", "run 1 post no"});
    EXPECT_EQ(s.lmp->atom->natoms, 2) << integrator;
    std::vector<double> out = {s.x(2, 2), s.v(2, 2)};
    s.cmd("run 30 post no");
    out.push_back(s.x(2, 2));
    return out;
  };
  const auto nve = run("nve");
  EXPECT_GT(std::fabs(nve[1] + 0.5), 0.01) << "the force acts at the insertion point";
  for (const std::string &rule : ALL_RULES) {
    const auto pj = run("pe_jump quadrature " + rule);
    // midpoint and lobatto 2 take the force at the insertion point for
    // the kick, as fix nve; the other rules average it over the step
    const bool one_node = (rule == "midpoint") || (rule == "lobatto 2");
    EXPECT_NEAR(pj[0], nve[0], 1e-12) << rule << ": z after the insertion step";
    EXPECT_NEAR(pj[1], nve[1], one_node ? 1e-12 : 5e-3) << rule << ": vz after it";
    EXPECT_NEAR(pj[2], nve[2], (rule == "lobatto 2") ? 1e-10 : 2e-4)
        << rule << ": z 30 steps later";
  }
}

/* ----------------------------------------------------------------------
   other time integrators and a second fix pe_jump: refused where their
   atoms interact with this fix's atoms at mixed times, correct otherwise
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, OtherIntegratorsOnInteractingAtoms)
{
  const auto spread = [](const std::string &second, const std::string &first) {
    Sim s;
    lj_liquid(s);
    s.cmds({"region half block 0 2 INF INF INF INF", "group left region half",
            "group right subtract all left", "fix 1 left " + first, "fix 3 right " + second,
            "timestep 0.005", "thermo 0", "run 0 post no"});
    return energy_spread(s, "etotal", 10, 50);
  };
  const double nve = spread("nve", "nve");
  for (const std::string second : {"nve", "pe_jump"}) {
    for (const std::string rule : {"midpoint", "lobatto 3", "legendre 2"}) {
      EXPECT_THROW(spread(second, "pe_jump quadrature " + rule), LAMMPS_NS::LAMMPSException)
          << second << " + " << rule;
    }
  }
  for (const std::string second : {"nve", "pe_jump quadrature lobatto 2"}) {
    const double lob2 = spread(second, "pe_jump quadrature lobatto 2");
    EXPECT_LT(lob2, 2.0 * nve) << second << " + lobatto 2: " << lob2 << " nve " << nve;
  }
}

/* ----------------------------------------------------------------------
   two integrators on atoms that do not interact: the atoms of fix nve move
   as with fix nve on all atoms, also on steps with output (thermo 10),
   whatever the rule of fix pe_jump (with lobatto 3 they got the fix's
   start-node forces, which it keeps for its own atoms only: NaN)
------------------------------------------------------------------------- */

/* ----------------------------------------------------------------------
   the same through an angle alone (no bond or pair between the two
   integrators' atoms): three atoms, one angle, fix nve on the third
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, OtherIntegratorsLinkedByAnAngleOnly)
{
  const auto outcome = [](const std::string &rule) {
    Sim s;
    s.cmds({"units lj",
            "atom_style angle",
            "atom_modify map array",
            "boundary f f f",
            "region box block -5 5 -5 5 -5 5",
            "create_box 1 box angle/types 1 extra/angle/per/atom 1",
            "create_atoms 1 single -1.0 0.0 0.0",
            "create_atoms 1 single 0.0 0.1 0.0",
            "create_atoms 1 single 1.0 0.0 0.0",
            "mass 1 1.0",
            "angle_style harmonic",
            "angle_coeff 1 10.0 120.0",
            "create_bonds single/angle 1 1 2 3",
            "neighbor 0.3 bin",
            "comm_modify cutoff 3.0",
            "group mine id 1 2",
            "group theirs id 3",
            "fix 1 mine pe_jump quadrature " + rule,
            "fix 2 theirs nve",
            "timestep 0.005",
            "thermo 0"});
    return error_in(s, "run 10");
  };
  for (const std::string rule : {"midpoint", "lobatto 3"})
    EXPECT_THAT(outcome(rule),
                ContainsRegex("atoms of another time integrator interact with its "
                              "atoms at step"))
        << rule;
  EXPECT_EQ(outcome("lobatto 2"), "no error");
}

TEST(PEJumpOtherFixes, OtherIntegratorsOnSeparateAtomsAreAllowed)
{
  auto c1_positions = [](const std::string &second) {
    Sim s;
    s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "lattice fcc 0.8442",
            "region box block 0 4 0 4 0 4", "create_box 2 box", "create_atoms 1 box",
            "create_atoms 2 box", "mass * 1.0", "group c1 type 1", "group c2 type 2",
            "velocity all create 1.0 4928", "pair_style lj/cut 2.5", "pair_coeff * * 1.0 1.0 2.5",
            "neigh_modify exclude type 1 2", "fix 1 c1 nve", "fix 2 c2 " + second, "timestep 0.005",
            "thermo 10"});
    EXPECT_NO_THROW(s.cmd("run 50 post no")) << second;
    std::vector<double> x;
    for (int id = 1; id <= 256; id++)    // the atoms of type 1
      for (int k = 0; k < 3; k++) x.push_back(s.x(id, k));
    return x;
  };
  const std::vector<double> alone = c1_positions("nve");
  for (const std::string rule : {"midpoint", "lobatto 2", "lobatto 3", "legendre 2"}) {
    const std::vector<double> beside = c1_positions("pe_jump quadrature " + rule);
    double worst = 0.0;
    for (std::size_t n = 0; n < alone.size(); n++)
      worst = std::isfinite(beside[n]) ? std::max(worst, std::fabs(beside[n] - alone[n]))
                                       : HUGE_VAL;
    EXPECT_LT(worst, 1e-12) << rule;
  }
}

/* ----------------------------------------------------------------------
   where the input decides that atoms of another time integrator will
   interact with this fix's atoms (fix deposit inserting into a group that
   another integrator moves, or into this fix's group beside another
   integrator), or that two integrators will integrate the same atoms
   (inserted atoms in both groups, a dynamic group, whose atoms LAMMPS
   assigns only at setup), the run is refused at setup, before its first
   step. Before, the interaction was refused when the first deposited atom
   reached the substrate (step 625 here), and shared atoms went unseen
   until the next run
------------------------------------------------------------------------- */

namespace {
// a substrate (type 1) onto which fix dep deposits atoms of type 2 (group
// addatoms) every 50 steps, falling at unit speed
void deposition(Sim &s)
{
  s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "boundary p p m",
          "lattice fcc 1.0", "region box block 0 3 0 3 0 8", "create_box 2 box",
          "region substrate block INF INF INF INF INF 2", "create_atoms 1 region substrate",
          "pair_style lj/cut 2.5", "pair_coeff * * 1.0 1.0", "mass * 1.0", "neigh_modify delay 0",
          "group addatoms type 2", "group substrate type 1", "region slab block 0 3 0 3 6 7",
          "fix dep addatoms deposit 20 2 50 12345 region slab near 1.0 vz -1.0 -1.0",
          "timestep 0.005", "thermo 0"});
}

struct Outcome {
  std::string error;
  LAMMPS_NS::bigint step;
};

Outcome outcome_of(const std::function<void(Sim &)> &system, const std::vector<std::string> &cmds)
{
  Sim s;
  system(s);
  const std::string error = error_from([&] {
    s.cmds(cmds);
  });
  return {error, s.lmp->update->ntimestep};
}
}    // namespace

TEST(PEJumpOtherFixes, InsertedAndDynamicGroupAtomsAreRefusedAtSetup)
{
  struct Case {
    std::function<void(Sim &)> system;
    std::vector<std::string> cmds;
    std::string error;    // "" if the run goes through
  };
  const auto liquid = [](Sim &s) {
    lj_liquid(s, 3);
    s.cmds({"timestep 0.005", "thermo 0"});
  };
  const std::vector<Case> cases = {
      // the deposited atoms with fix nve, the substrate with pe_jump
      {deposition,
       {"fix 1 addatoms nve", "fix 2 substrate pe_jump quadrature lobatto 3", "run 1500"},
       "fix dep \\(deposit\\) inserts atoms that fix 1 \\(nve\\) integrates and that will "
       "interact with this fix's atoms"},
      // the deposited atoms with pe_jump, the substrate with fix nve
      {deposition,
       {"fix 1 addatoms pe_jump", "fix 2 substrate nve", "run 1500"},
       "fix dep \\(deposit\\) inserts atoms into its group that will interact with the atoms "
       "of fix 2 \\(nve\\)"},
      // both integrate the deposited atoms (lobatto 2 too)
      {deposition,
       {"fix 1 all pe_jump quadrature lobatto 2", "fix 2 addatoms nve", "run 200"},
       "must be the only time integration fix acting on its atoms: fix dep \\(deposit\\) "
       "inserts atoms into its group and into that of fix 2 \\(nve\\)"},
      // a dynamic group of fix nve inside the group of fix pe_jump
      {liquid,
       {"variable l atom x<2", "group g dynamic all var l every 5",
        "fix 1 all pe_jump quadrature lobatto 2", "fix 2 g nve", "run 20"},
       "must be the only time integration fix acting on its atoms: [0-9]+ of them are "
       "integrated by fix 2 \\(nve\\)"},
      // lobatto 2 takes other integrators' atoms (forces at the step ends)
      {deposition,
       {"fix 1 addatoms nve", "fix 2 substrate pe_jump quadrature lobatto 2", "run 1500"},
       ""},
      {deposition,
       {"fix 1 addatoms pe_jump quadrature lobatto 2", "fix 2 substrate nve", "run 1500"},
       ""},
      // inserted into the group of this fix, one integrator
      {deposition, {"fix 1 all pe_jump quadrature lobatto 3", "run 1500"}, ""},
      // kept apart by neigh_modify exclude: not refused
      {deposition,
       {"neigh_modify exclude type 1 2", "fix 1 addatoms nve",
        "fix 2 substrate pe_jump quadrature lobatto 3", "run 1500"},
       ""},
      {deposition,
       {"neigh_modify exclude group addatoms substrate", "fix 1 addatoms nve",
        "fix 2 substrate pe_jump quadrature lobatto 3", "run 1500"},
       ""}};
  for (const auto &c : cases) {
    const auto [error, step] = outcome_of(c.system, c.cmds);
    if (c.error.empty()) {
      EXPECT_EQ(error, "no error") << c.cmds[c.cmds.size() - 2];
      continue;
    }
    EXPECT_THAT(error, ContainsRegex(c.error)) << c.cmds[c.cmds.size() - 2];
    EXPECT_EQ(step, 0) << c.cmds[c.cmds.size() - 2] << ": " << error;
  }
}

/* ----------------------------------------------------------------------
   constraints assume velocity Verlet: refused
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, ShakeAndRattleAreRefused)
{
  for (const std::string constraint : {"shake", "rattle"}) {
    Sim s;
    s.cmds({"units real", "atom_style full", "atom_modify map array", "boundary p p p",
            "region box block 0 20 0 20 0 20",
            "create_box 1 box bond/types 1 extra/bond/per/atom 1", "mass 1 1.0",
            "create_atoms 1 single 5 5 5", "create_atoms 1 single 6 5 5",
            "create_bonds single/bond 1 1 2", "pair_style zero 3.0", "pair_coeff * *",
            "bond_style harmonic", "bond_coeff 1 450.0 1.0", "fix 1 all pe_jump",
            "fix 2 all " + constraint + " 1e-6 20 0 b 1", "thermo 0"});
    EXPECT_THAT(error_in(s, "run 10 post no"), ContainsRegex("constraints of fix 2"))
        << constraint << " must be refused";
  }
}

/* ----------------------------------------------------------------------
   fix rigid on other atoms: a rigid cluster in an LJ liquid keeps working
   beside fix pe_jump lobatto 2 (energy as with fix nve), and a rule that
   evaluates forces inside the step is refused
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, RigidBodyBesideLobatto2)
{
  const auto spread = [](const std::string &integrator) {
    Sim s;
    lj_liquid(s);
    s.cmds({"region ball sphere 2.8 2.8 2.8 0.9", "group ball region ball",
            "group liquid subtract all ball", "fix 1 liquid " + integrator,
            "fix 2 ball rigid single", "timestep 0.004", "thermo 0", "run 0 post no"});
    EXPECT_GT(s.eval("count(ball)"), 3.0);
    return energy_spread(s, "etotal", 10, 50);
  };
  const double nve = spread("nve");
  const double lob2 = spread("pe_jump quadrature lobatto 2");
  EXPECT_LT(lob2, 2.0 * nve) << "pe_jump lobatto 2 " << lob2 << ", nve " << nve;
  EXPECT_THROW(spread("pe_jump"), LAMMPS_NS::LAMMPSException);
}

/* ----------------------------------------------------------------------
   the damping of the parasitic mode acts on the alternating jump: on a
   smooth trajectory its pull is even in time and acts where the jump it
   changes acts, so it changes the energy of a mode of frequency omega by
   beta O((h omega)^6) per step. A ring of harmonic springs (omega up to
   28, h omega up to 0.28) damped over tau = 1 (beta = 0.01) without a
   thermostat: the mean energy of the last 500 of 10000 steps within 1e-3
   of the first 500's (3.7e-4; it grew 4.3-fold with the jump pulled
   towards the step's own impulse, a negative drag of rate
   beta h omega^2/2 that ran fix langevin 3 % too hot on LAMMPS'
   bench/in.chain). Started with the paper's
   [v]^0 = 0, which puts an alternating jump as large as the smooth one
   into the mode (mean jump energy 2.8 times the smooth jump's, undamped),
   the mean jump energy ends within 5 % of the smooth jump's (1.03)
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, DampingNeitherPumpsNorDrainsEnergy)
{
  // mean etotal over the first and the last 500 steps, mean jump energy
  // over the last 500
  const auto run = [](const std::string &rule, const std::string &extra) {
    Sim s;
    harmonic_ring(s, 64, 100.0, 0.2, 4711);
    s.cmds({"fix 1 all pe_jump quadrature " + rule + extra, "timestep 0.01", "thermo 0",
            "variable e equal etotal*atoms", "variable j equal f_1[2]",
            "fix avg all ave/time 1 500 500 v_e v_j"});
    s.cmd("run 500 post no");
    const double first = s.vec("avg", 0);
    s.cmd("run 9000 post no");
    s.cmd("run 500 post no");
    return std::vector<double>{first, s.vec("avg", 0), s.vec("avg", 1)};
  };
  for (const std::string rule : {"midpoint", "lobatto 3", "legendre 2"}) {
    const auto damped = run(rule, " damp 1.0");
    EXPECT_NEAR(damped[1] / damped[0], 1.0, 1e-3)
        << rule << ": mean energy " << damped[0] << " then " << damped[1];
    const auto smooth = run(rule, " damp 0");
    const auto excited = run(rule, " damp 1.0 init paper");
    const auto kept = run(rule, " damp 0 init paper");
    EXPECT_GT(kept[2], 2.0 * smooth[2]) << rule << ": init paper excites the mode";
    EXPECT_NEAR(excited[2] / smooth[2], 1.0, 0.05)
        << rule << ": mean jump energy " << excited[2] << ", of the smooth jump " << smooth[2];
  }
}

/* ----------------------------------------------------------------------
   damp auto switches the parasitic damping on once another fix changes
   velocities (temp/csvr, temp/berendsen, ...), not for fixes that only
   look (fix ave/time)
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, DampingFollowsVelocityChanges)
{
  const auto final_x = [](const std::string &other, const std::string &damp) {
    Sim s;
    lj_liquid(s, 3);
    s.cmds(
        {"fix 1 all pe_jump damp " + damp, other, "timestep 0.005", "thermo 0", "run 200 post no"});
    std::vector<double> x;
    for (int id = 1; id <= s.lmp->atom->natoms; id++) x.push_back(s.x(id, 0));
    return x;
  };
  const auto differ = [](const std::vector<double> &a, const std::vector<double> &b) {
    double d = 0.0;
    for (size_t i = 0; i < a.size(); i++) d = std::max(d, std::fabs(a[i] - b[i]));
    return d;
  };
  const std::string look = "fix 2 all ave/time 1 10 10 c_thermo_temp";
  const std::string rescale = "fix 2 all temp/berendsen 1.0 1.0 0.5";
  EXPECT_EQ(differ(final_x(look, "auto"), final_x(look, "0")), 0.0);
  EXPECT_GT(differ(final_x(rescale, "auto"), final_x(rescale, "0")), 1e-8);
}

/* ----------------------------------------------------------------------
   damp auto damps the parasitic mode beside thermostats only: fixes that
   change velocities or add forces in a run that conserves energy (fix
   momentum, heat exchange, momentum swaps, external forces) must leave
   the energy as fix nve does. With damping over 1000 steps the energy of
   an LJ liquid with fix momentum drifted by +0.025 per atom in 7000 steps
   (nve: -3e-5), first order in h
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, NoDampingInRunsThatConserveEnergy)
{
  const auto drift = [](const std::string &integrator, const std::string &other) {
    Sim s;
    lj_liquid(s, 4);
    // (thermo normalises etotal per atom in lj units)
    s.cmds({"pair_modify shift yes", "fix 1 all " + integrator, other, "timestep 0.005", "thermo 0",
            "variable e equal etotal", "run 500 post no"});
    const double e0 = s.eval("v_e");
    s.cmd("run 3000 post no");
    return s.eval("v_e") - e0;
  };
  for (const std::string other :
       {"fix 2 all momentum 100 linear 1 1 1", "fix 2 all addforce 0.0 0.0 0.0"}) {
    const double nve = drift("nve", other);
    for (const std::string rule : {"midpoint", "lobatto 2", "lobatto 3"}) {
      const double d = drift("pe_jump quadrature " + rule, other);
      EXPECT_LT(std::fabs(d), std::max(10.0 * std::fabs(nve), 1e-3))
          << rule << " beside " << other << ": drift per atom " << d << ", nve " << nve;
    }
  }
}

/* ----------------------------------------------------------------------
   quadrature lobatto 2 is velocity Verlet: its jump relation keeps the
   smooth jump h a exactly, so it has no parasitic mode to damp, and damp
   auto leaves it undamped beside a thermostat too. It then follows fix
   nve under fix langevin (same random numbers) to round-off, and so does
   the energy that fix langevin tallies; damped over 1000 steps it was
   1.5e-4 off in temperature after 200 steps
------------------------------------------------------------------------- */

TEST(PEJumpOtherFixes, Lobatto2BesideLangevinIsVelocityVerlet)
{
  const auto final_state = [](const std::string &integrator) {
    Sim s;
    lj_liquid(s, 4);
    s.cmds({"fix 1 all " + integrator, "fix 2 all langevin 1.0 1.0 0.5 48279 tally yes",
            "timestep 0.005", "thermo 0", "run 600 post no"});
    auto x = unwrapped_positions(s);
    x.push_back(s.eval("ecouple"));
    return x;
  };
  const auto nve = final_state("nve");
  const auto lob2 = final_state("pe_jump quadrature lobatto 2");
  double d = 0.0;
  for (size_t i = 0; i < nve.size(); i++) d = std::max(d, std::fabs(nve[i] - lob2[i]));
  EXPECT_LT(d, 1e-8) << "largest difference of positions and tallied energy";
}
