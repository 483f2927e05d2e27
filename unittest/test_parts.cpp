// unit tests of parts of the fixes that need a LAMMPS instance but no run:
// the per-atom state table (values kept through growth, copies, exchange
// and restart packing, new atoms at their init values, memory count)

#include "pe_jump_atom_state.h"
#include "pe_jump_systems.h"

#include "gtest/gtest.h"

#include <cmath>
#include <vector>

using namespace PEJumpTest;
using LAMMPS_NS::PEJump::AtomState;

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
