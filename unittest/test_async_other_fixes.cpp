/* ----------------------------------------------------------------------
   fix pe_jump/async beside other fixes: they act where the MD step has
   every atom at one time (the primary coarse node, the end of the coarse
   step): forces that fixes add as an impulse h_S R/m there, forces that
   fixes replace at every fine and coarse evaluation, velocity changes at
   coarse nodes. Runs on one rank (Sim::x, Sim::v).
------------------------------------------------------------------------- */

#include "pe_jump_systems.h"

#include "atom.h"
#include "exceptions.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

#include <cmath>
#include <string>
#include <vector>

using namespace LAMMPS_NS;
using namespace PEJumpTest;
using ::testing::ContainsRegex;

namespace {

// an LJ liquid of 864 atoms (density 0.8442) in which one atom in ten (or
// light_fraction) is light (mass 1/25, type 2, group fast: 5 times the
// speed of the others),
// on the fine clock of K = 5 with the coarse step 0.005
void light_atoms(Sim &s, const std::string &rule, double light_fraction = 0.1)
{
  s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "lattice fcc 0.8442",
          "region box block 0 6 0 6 0 6", "create_box 2 box", "create_atoms 1 box", "mass 1 1.0",
          "mass 2 0.04", fmt::format("set type 1 type/fraction 2 {} 12345", light_fraction),
          "group fast type 2", "group slow type 1", "velocity all create 1.0 87287 loop geom",
          "pair_style lj/cut 2.5", "pair_coeff * * 1.0 1.0 2.5", "neighbor 0.3 bin",
          "neigh_modify every 1 delay 0 check yes",
          "fix 1 all pe_jump/async 5 fast quadrature " + rule, "timestep 0.005"});
}

}    // namespace

/* ----------------------------------------------------------------------
   a constant force: position Verlet (midpoint) and velocity Verlet (the
   Lobatto rules) are exact for it, so two atoms far apart, one on each
   clock, under fix addforce follow x0 + v0 t + F t^2/(2m) to round-off,
   as they do under fix gravity
------------------------------------------------------------------------- */

TEST(PEJumpAsyncOtherFixes, ConstantForcesMoveAtomsExactly)
{
  for (const std::string rule : {"midpoint", "lobatto 3"}) {
    for (const std::string force : {"addforce 0.3 -0.2 0.1", "gravity 0.5 vector 0.6 -0.8 0.0"}) {
      Sim s;
      s.cmds({"units lj", "atom_style atomic", "atom_modify map array",
              "region box block -50 50 -50 50 -50 50", "create_box 1 box",
              "create_atoms 1 single -20 0 0", "create_atoms 1 single 20 0 0", "mass 1 2.0",
              "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0", "neighbor 3.0 bin",
              "group fast id 1", "velocity all set 0.5 0.25 -0.1",
              "fix 1 all pe_jump/async 5 fast quadrature " + rule, "fix 2 all " + force,
              "timestep 0.01", "thermo 0", "run 200 post no"});
      // the acceleration: addforce F/m on mass 2, gravity its magnitude along
      // its unit vector
      const bool added = (force[0] == 'a');
      const double a[3] = {added ? 0.15 : 0.3, added ? -0.1 : -0.4, added ? 0.05 : 0.0};
      const double t = 2.0, x0[2] = {-20.0, 20.0}, v0[3] = {0.5, 0.25, -0.1};
      for (int id = 1; id <= 2; ++id)
        for (int k = 0; k < 3; ++k) {
          const double expect = (k == 0 ? x0[id - 1] : 0.0) + v0[k] * t + 0.5 * a[k] * t * t;
          EXPECT_NEAR(s.x(id, k), expect, 1e-11) << rule << ", " << force << ", atom " << id;
        }
    }
  }
}

/* ----------------------------------------------------------------------
   fix setforce acts at every fine and coarse evaluation: the ends of the
   inhomogeneous wave held by it (in the fix group, at rest) stay where
   they are, and the wave moves as with the ends left out of the fix group
   (frozen scenery), to round-off. The end at the fine side is a slow atom
   in a fine interaction: it would collect the fine forces otherwise
------------------------------------------------------------------------- */

TEST(PEJumpAsyncOtherFixes, SetforceHoldsTheEnds)
{
  for (const std::string rule : {"midpoint", "lobatto 3"}) {
    const auto wave = [&](bool held) {
      Sim s;
      inhomogeneous_wave(s, 100);
      if (held)
        s.cmds({"fix 1 all pe_jump/async 10 fast quadrature " + rule,
                "fix 2 ends setforce 0.0 0.0 0.0"});
      else
        s.cmd("fix 1 chain pe_jump/async 10 fast quadrature " + rule);
      s.cmds({"timestep 0.005", "thermo 0", "run 400 post no"});
      return unwrapped_positions(s);
    };
    const std::vector<double> held = wave(true), frozen = wave(false);
    EXPECT_EQ(held[0], 0.0) << rule;
    EXPECT_EQ(held[3 * 100], 100.0) << rule;
    EXPECT_LT(max_diff(held, frozen), 1e-12) << rule;
    // the wave did move
    std::vector<double> start;
    for (int i = 0; i <= 100; ++i) start.insert(start.end(), {double(i), 0.0, 0.0});
    EXPECT_GT(max_diff(held, start), 1e-3) << rule;
  }
}

/* ----------------------------------------------------------------------
   fix langevin's force is an impulse at the primary coarse node on every
   atom: the light atoms on the fine clock and the heavy ones on the coarse
   clock both reach the target (lobatto 3: the impulse split about the end
   node, velocity Verlet, has no h_S/(2 damp) term), and damp auto keeps
   the jumps that its random impulses drive bounded. Three light atoms in
   ten (259), temperatures without the centre-of-mass correction of
   compute temp (a group's centre of mass is free: with it the 86 light
   atoms of one in ten read 1.2 % hot). Mean over 6000 coarse steps after
   500 (four seeds: within 0.007 of T = 1); the jump energy of the last
   tenth against that of the first
------------------------------------------------------------------------- */

TEST(PEJumpAsyncOtherFixes, LangevinHeatsBothClocksToTheTarget)
{
  Sim s;
  light_atoms(s, "lobatto 3", 0.3);
  s.cmds({"velocity all create 0.5 4928 loop geom", "fix 2 all langevin 1.0 1.0 0.5 48279",
          "compute tfast fast temp", "compute tslow slow temp", "compute_modify tfast extra/dof 0",
          "compute_modify tslow extra/dof 0", "thermo 0", "run 500 post no", "reset_timestep 0",
          "fix ave all ave/time 10 600 6000 c_tfast c_tslow",
          "fix jump all ave/time 10 60 600 f_1[2] mode scalar ave window 1", "run 600 post no"});
  const double early = s.eval("f_jump");
  s.cmd("run 5400 post no");
  const double fast = s.eval("f_ave[1]"), slow = s.eval("f_ave[2]");
  EXPECT_NEAR(fast, 1.0, 0.02);
  EXPECT_NEAR(slow, 1.0, 0.02);
  // the jumps stay bounded (undamped they grow 2.2-fold here)
  EXPECT_NEAR(s.eval("f_jump") / early, 1.0, 0.2) << s.eval("f_jump") / early;
}

/* ----------------------------------------------------------------------
   the midpoint rule takes fix langevin's force at the centre of the coarse
   step, with the velocity that CentreVelocity shows there: the free flight
   plus half the last step's impulse of the fix. For free atoms (an ideal
   gas: pair coefficient epsilon 0) the velocity then follows
   v' = v - 2a (v + [v - v_last]/2) + noise, a = h_S/(2 damp), whose
   stationary temperature is (1 - a)/((1 + a)(1 - 2a)) T exactly: 1.0370
   at a = 1/8. Taken with the free flight alone (an Euler step) it would be
   T/(1 - a) = 1.1429 (measured before: 1.149, 1.143). Mean over 2000
   coarse steps after 500, light atoms on the fine clock and heavy ones
------------------------------------------------------------------------- */

TEST(PEJumpAsyncOtherFixes, LangevinDragSeesTheCentreVelocity)
{
  Sim s;
  light_atoms(s, "midpoint", 0.3);
  const double a = 0.125, damp = 0.005 / (2.0 * a);
  s.cmds({"pair_coeff * * 0.0 1.0 2.5", fmt::format("fix 2 all langevin 1.0 1.0 {} 48279", damp),
          "compute tfast fast temp", "compute tslow slow temp", "compute_modify tfast extra/dof 0",
          "compute_modify tslow extra/dof 0", "thermo 0", "run 500 post no", "reset_timestep 0",
          "fix ave all ave/time 5 400 2000 c_tfast c_tslow", "run 2000 post no"});
  const double expected = (1.0 - a) / ((1.0 + a) * (1.0 - 2.0 * a));
  EXPECT_NEAR(s.eval("f_ave[1]"), expected, 0.01);
  EXPECT_NEAR(s.eval("f_ave[2]"), expected, 0.01);
}

/* ----------------------------------------------------------------------
   a thermostat that rescales velocities at the end of the step acts at
   the coarse node, where every atom has its node velocity: with a window
   of 0 fix temp/rescale sets the temperature there exactly at every step
------------------------------------------------------------------------- */

TEST(PEJumpAsyncOtherFixes, RescaleActsAtCoarseNodes)
{
  Sim s;
  light_atoms(s, "midpoint");
  s.cmds({"fix 2 all temp/rescale 1 0.8 0.8 0.0 1.0", "thermo 0", "run 50 post no"});
  EXPECT_NEAR(s.eval("temp"), 0.8, 1e-12);
  const std::vector<double> before = positions(s);
  s.cmd("run 50 post no");
  EXPECT_NEAR(s.eval("temp"), 0.8, 1e-12);
  EXPECT_GT(max_diff(positions(s), before), 1e-3);
}

/* ----------------------------------------------------------------------
   what the coarse step cannot take is refused at setup with an ERROR
------------------------------------------------------------------------- */

TEST(PEJumpAsyncOtherFixes, InsertionAndReflectionAreRefused)
{
  {
    Sim s;
    light_atoms(s, "midpoint");
    s.cmds({"region top block 0 6 0 6 5 6", "fix 2 all deposit 10 1 5 4321 region top"});
    EXPECT_THAT(error_in(s, "run 10"),
                ContainsRegex("cannot yet be combined with fix 2 "
                              "\\(deposit\\), which inserts atoms"));
  }
  {
    Sim s;
    light_atoms(s, "midpoint");
    s.cmds({"change_box all boundary p p f", "fix 2 all wall/reflect zlo EDGE"});
    EXPECT_THAT(error_in(s, "run 10"),
                ContainsRegex("fix 2 \\(wall/reflect\\), which reverses velocities"));
  }
}
