// unit tests of parts of the fixes that need a LAMMPS instance but no run:
// the per-atom state table (values kept through growth, copies, exchange
// and restart packing, new atoms at their init values, memory count), and
// which other fixes the integrators watch for velocity changes

#include "pe_jump_atom_state.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_other_fixes.h"
#include "pe_jump_systems.h"

#include "gtest/gtest.h"

#include <cmath>
#include <vector>

using namespace PEJumpTest;
using LAMMPS_NS::PEJump::AtomState;
using LAMMPS_NS::PEJump::ForceSampler;
using LAMMPS_NS::PEJump::OtherFixes;

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
