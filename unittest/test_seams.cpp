// unit tests of the parts that the two fixes compose, each called directly
// on a small LAMMPS instance (no run of a fix): the clock assignment of
// pe_jump/async (which atoms are fast, slow and moving on fine steps, slow
// and held; the fine clock's change; the restart round trip), the
// two-step scheme's updates and bookkeeping (the jump relation, the atoms
// a set touches, the energies, the velocity fingerprints), the step
// control (compensation of step-size changes, the adaptive step, the first
// step) and the force sampler (analytic forces; which forces an evaluation
// restricted to some atoms clears)

#include "force.h"
#include "group.h"
#include "pe_jump_atom_set.h"
#include "pe_jump_atom_state.h"
#include "pe_jump_clock_assignment.h"
#include "pe_jump_force_sampler.h"
#include "pe_jump_interaction_split.h"
#include "pe_jump_step_control.h"
#include "pe_jump_systems.h"
#include "pe_jump_two_step.h"

#include "gtest/gtest.h"

#include <cmath>
#include <set>
#include <string>
#include <vector>

using namespace PEJumpTest;
using LAMMPS_NS::PEJump::AtomList;
using LAMMPS_NS::PEJump::AtomSet;
using LAMMPS_NS::PEJump::AtomState;
using LAMMPS_NS::PEJump::ClockAssignment;
using LAMMPS_NS::PEJump::ForceSampler;
using LAMMPS_NS::PEJump::InteractionSplit;
using LAMMPS_NS::PEJump::StepControl;
using LAMMPS_NS::PEJump::TwoStep;

namespace {

// per-atom rows (3 values each) in one buffer, as double ** for the parts
struct Rows {
  explicit Rows(int n, double init = 0.0) : buf(3 * n, init), row(n)
  {
    for (int i = 0; i < n; ++i) row[i] = &buf[3 * i];
  }
  double **get() { return row.data(); }
  double *operator[](int i) { return row[i]; }
  std::vector<double> buf;
  std::vector<double *> row;
};

// the atom IDs of a list of local indices
std::set<int> ids(Sim &s, const AtomList &list)
{
  std::set<int> out;
  for (const int i : list) out.insert(static_cast<int>(s.lmp->atom->tag[i]));
  return out;
}

// the stand-in for fix pe_jump/async around a clock assignment: it gives
// the fix group and ID and passes the communication of the clock bit
// (forward) and of flags set on ghosts (reverse) on, as the fix does
class ClockFix : public LAMMPS_NS::Fix {
 public:
  ClockFix(LAMMPS_NS::LAMMPS *lmp, const std::string &id, const std::string &group) :
      Fix(lmp, 3, args(id, group).data())
  {
    comm_forward = comm_reverse = 1;
  }
  int setmask() override { return 0; }
  int pack_forward_comm(int n, int *list, double *buf, int, int *) override
  {
    return clocks->pack_forward(n, list, buf);
  }
  void unpack_forward_comm(int n, int first, double *buf) override
  {
    clocks->unpack_forward(n, first, buf);
  }
  int pack_reverse_comm(int n, int first, double *buf) override
  {
    return clocks->reversing() ? clocks->pack_reverse(n, first, buf) : 0;
  }
  void unpack_reverse_comm(int n, int *list, double *buf) override
  {
    if (clocks->reversing()) clocks->unpack_reverse(n, list, buf);
  }
  ClockAssignment *clocks = nullptr;

 private:
  static std::vector<char *> args(const std::string &id, const std::string &group)
  {
    static std::string keep[2];
    keep[0] = id;
    keep[1] = group;
    return {&keep[0][0], &keep[1][0], const_cast<char *>("seam_stand_in")};
  }
};

// the 3+3 slow/fast chain of pe_jump_systems.h at rest: atoms 1..8 along
// x, walls 1 and 8, fast 2..4, fix group chain = 2..7, bonds i-(i+1); no
// pairs (the neighbor cutoff 1.3 is below the spacing 1.5)
void chain(Sim &s)
{
  const std::vector<double> zero(6, 0.0);
  slow_fast_chain(s, 3, 100.0, zero, zero);
  s.cmd("run 0 post no");
}

}    // namespace

/* ----------------------------------------------------------------------
   on the chain: the fine clock is the fast group (2, 3, 4); the fine
   interactions are the bonds 1-2 .. 4-5, so slow atom 5 moves on fine
   steps and 6, 7 are held; walls 1 and 8 are in no list. With N buffer
   layers the fine clock takes N more atoms of the chain, layer by layer
   along the bonds (the walls stay off it)
------------------------------------------------------------------------- */

TEST(ClockAssignment, SlowAtomsInAFineInteractionMoveOnFineSteps)
{
  Sim s;
  chain(s);
  auto *atom = s.lmp->atom;
  ClockFix fix(s.lmp, "seam", "chain");
  ClockAssignment clocks(s.lmp, &fix, "fast", {0, 0.0}, false);
  fix.clocks = &clocks;
  clocks.find_groups();
  InteractionSplit split(s.lmp, fix.groupbit, clocks.clock_bit());
  split.build();
  clocks.find_slow(split);
  clocks.find_moving(split);
  EXPECT_EQ(ids(s, clocks.fast_atoms), (std::set<int>{2, 3, 4}));
  EXPECT_EQ(ids(s, clocks.slow_moving), (std::set<int>{5}));
  EXPECT_EQ(ids(s, clocks.slow_held), (std::set<int>{6, 7}));
  EXPECT_EQ(ids(s, clocks.slow_atoms), (std::set<int>{5, 6, 7}));
  EXPECT_EQ(ids(s, clocks.moving_atoms), (std::set<int>{2, 3, 4, 5}));
  for (int id = 2; id <= 7; ++id) {
    EXPECT_EQ(clocks.slow()[atom->map(id)], id >= 5 ? 1 : 0) << "atom " << id;
    EXPECT_EQ(clocks.moving()[atom->map(id)], id <= 5 ? 1 : 0) << "atom " << id;
  }

  for (int layers = 1; layers <= 3; ++layers) {
    ClockFix own(s.lmp, "seam" + std::to_string(layers), "chain");
    ClockAssignment buffered(s.lmp, &own, "fast", {layers, 0.0}, false);
    own.clocks = &buffered;
    buffered.create_clock_group();
    buffered.find_groups();
    EXPECT_NE(buffered.clock_bit(), clocks.clock_bit());
    InteractionSplit parts(s.lmp, own.groupbit, buffered.clock_bit());
    EXPECT_TRUE(buffered.assign_buffer(false, parts));
    parts.build();
    buffered.find_slow(parts);
    buffered.find_moving(parts);
    std::set<int> fine, moving, held;
    for (int id = 2; id <= 7; ++id) {
      if (id <= 4 + layers)
        fine.insert(id);
      else if (id == 5 + layers)
        moving.insert(id);
      else
        held.insert(id);
    }
    EXPECT_EQ(ids(s, buffered.fast_atoms), fine) << layers << " layers";
    EXPECT_EQ(ids(s, buffered.slow_moving), moving) << layers << " layers";
    EXPECT_EQ(ids(s, buffered.slow_held), held) << layers << " layers";
    // the clock group holds the fine clock's atoms, not the walls
    for (int id = 1; id <= 8; ++id)
      EXPECT_EQ((atom->mask[atom->map(id)] & buffered.clock_bit()) != 0, fine.count(id) == 1)
          << "atom " << id << ", " << layers << " layers";
  }
}

/* ----------------------------------------------------------------------
   in a periodic LJ liquid (fix group: IDs 1..200 of 256, fast: 1..4) a
   slow atom moves on fine steps exactly when a fast atom is within the
   neighbor cutoff (2.5 + skin 0.3) of it, through the periodic boundary
   too (the pair is then found by a ghost, whose flag goes to its owner);
   the lists are disjoint and cover the fix group's atoms
------------------------------------------------------------------------- */

TEST(ClockAssignment, MovingAtomsAreThePartnersOfTheFastOnes)
{
  Sim s;
  lj_liquid(s, 4);
  s.cmds({"group fast id 1:4", "group mobile id 1:200",
          "displace_atoms all random 0.05 0.05 0.05 4811 units box", "run 0 post no"});
  auto *atom = s.lmp->atom;
  const int n = atom->nlocal;
  ASSERT_EQ(n, 256);
  ClockFix fix(s.lmp, "seam", "mobile");
  ClockAssignment clocks(s.lmp, &fix, "fast", {0, 0.0}, false);
  fix.clocks = &clocks;
  clocks.find_groups();
  InteractionSplit split(s.lmp, fix.groupbit, clocks.clock_bit());
  split.build();
  clocks.find_slow(split);
  clocks.find_moving(split);

  const double cutneigh = 2.5 + 0.3;
  std::set<int> fast, moving, held;
  int across = 0;    // slow partners reached through the boundary only
  for (int i = 0; i < n; ++i) {
    const int id = atom->tag[i];
    if (id > 200) continue;
    if (id <= 4) {
      fast.insert(id);
      continue;
    }
    double nearest = 1e300, direct = 1e300;
    for (int f = 1; f <= 4; ++f) {
      const int j = atom->map(f);
      double d[3], r2 = 0.0;
      for (int k = 0; k < 3; ++k) {
        d[k] = atom->x[i][k] - atom->x[j][k];
        r2 += d[k] * d[k];
      }
      direct = std::min(direct, std::sqrt(r2));
      s.lmp->domain->minimum_image(d);
      nearest = std::min(nearest, std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    }
    ASSERT_GT(std::fabs(nearest - cutneigh), 1e-6) << "atom " << id << " on the cutoff";
    if (nearest < cutneigh) {
      moving.insert(id);
      if (direct >= cutneigh) ++across;
    } else {
      held.insert(id);
    }
  }
  EXPECT_EQ(ids(s, clocks.fast_atoms), fast);
  EXPECT_EQ(ids(s, clocks.slow_moving), moving);
  EXPECT_EQ(ids(s, clocks.slow_held), held);
  EXPECT_GT(across, 0);
  EXPECT_GT(held.size(), 10u);
  EXPECT_GT(moving.size(), 10u);

  // disjoint, and together the fix group; moving = fast + slow moving,
  // slow = slow moving + slow held
  std::set<int> all;
  std::size_t listed = 0;
  for (const AtomList *list : {&clocks.fast_atoms, &clocks.slow_moving, &clocks.slow_held}) {
    listed += list->size();
    for (const int id : ids(s, *list)) all.insert(id);
  }
  EXPECT_EQ(listed, 200u);
  EXPECT_EQ(all.size(), 200u);
  EXPECT_EQ(*all.rbegin(), 200);
  std::set<int> fast_and_moving(fast), slow(moving);
  fast_and_moving.insert(moving.begin(), moving.end());
  slow.insert(held.begin(), held.end());
  EXPECT_EQ(ids(s, clocks.moving_atoms), fast_and_moving);
  EXPECT_EQ(ids(s, clocks.slow_atoms), slow);
}

/* ----------------------------------------------------------------------
   changed(): the atoms of the fix group on the fine clock, told by their
   number and IDs: a first look and every change of them report a change
   (one atom more; as many atoms but one other), a second look and a
   change outside the fix group none
------------------------------------------------------------------------- */

TEST(ClockAssignment, ChangedTellsANewFineClock)
{
  Sim s;
  lj_liquid(s, 3);
  s.cmds({"group fast id 1:20", "group mobile id 1:100", "run 0 post no"});
  ClockFix fix(s.lmp, "seam", "mobile");
  ClockAssignment clocks(s.lmp, &fix, "fast", {0, 0.0}, false);
  fix.clocks = &clocks;
  EXPECT_TRUE(clocks.changed());
  EXPECT_FALSE(clocks.changed());
  s.cmd("group fast id 21");
  EXPECT_TRUE(clocks.changed());
  EXPECT_FALSE(clocks.changed());
  s.cmds({"group fast clear", "group fast id 1:20 22"});    // 21 atoms again, 22 for 21
  EXPECT_TRUE(clocks.changed());
  EXPECT_FALSE(clocks.changed());
  s.cmd("group fast id 105");    // outside the fix group
  EXPECT_FALSE(clocks.changed());
  s.cmd("velocity all scale 2.0");    // not a change of clocks
  EXPECT_FALSE(clocks.changed());
}

/* ----------------------------------------------------------------------
   save() and restore(): the buffer of the last assignment (layers and
   reach), the fine clock (number and IDs) and the fast group seen go
   through the restart values; a restored assignment finds the same clock
   unchanged, does not assign the same buffer again but does assign
   another reach, and a fast auto assignment finds the fast group as it
   was (and a chosen atom more a change); a fresh one without them does
   assign and finds changes
------------------------------------------------------------------------- */

TEST(ClockAssignment, SaveAndRestoreRoundTrip)
{
  Sim s;
  chain(s);
  ClockFix fix(s.lmp, "seam", "chain");
  ClockAssignment first(s.lmp, &fix, "fast", {2, 1.3}, false);
  fix.clocks = &first;
  first.create_clock_group();
  first.find_groups();
  InteractionSplit split(s.lmp, fix.groupbit, first.clock_bit());
  EXPECT_TRUE(first.assign_buffer(false, split));
  EXPECT_TRUE(first.changed());
  double list[3], seen[2], reach = -1.0;
  first.save(list, seen, &reach);
  EXPECT_EQ(list[0], 2.0);    // layers
  EXPECT_EQ(reach, 1.3);
  EXPECT_EQ(list[1], 5.0);    // atoms 2..6 on the fine clock
  EXPECT_EQ(seen[0], 3.0);    // fast group 2, 3, 4
  EXPECT_NE(list[2], seen[1]);

  ClockAssignment again(s.lmp, &fix, "fast", {2, 1.3}, false);
  fix.clocks = &again;
  again.restore(list, seen, &reach);
  again.find_groups();
  double list2[3], seen2[2], reach2 = -1.0;
  again.save(list2, seen2, &reach2);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(list2[k], list[k]) << k;
  for (int k = 0; k < 2; ++k) EXPECT_EQ(seen2[k], seen[k]) << k;
  EXPECT_EQ(reach2, reach);
  EXPECT_FALSE(again.changed());
  EXPECT_FALSE(again.assign_buffer(true, split));

  ClockAssignment wider(s.lmp, &fix, "fast", {2, 2.0}, false);
  fix.clocks = &wider;
  wider.restore(list, seen, &reach);
  wider.find_groups();
  EXPECT_TRUE(wider.assign_buffer(true, split));

  ClockAssignment fresh(s.lmp, &fix, "fast", {2, 1.3}, false);
  fix.clocks = &fresh;
  fresh.find_groups();
  EXPECT_TRUE(fresh.changed());
  EXPECT_TRUE(fresh.assign_buffer(true, split));

  ClockAssignment picking(s.lmp, &fix, "fast", {2, 1.3}, true);
  fix.clocks = &picking;
  picking.restore(list, seen, &reach);
  EXPECT_FALSE(picking.due(nullptr, 10, 1));
  std::vector<int> chosen(s.lmp->atom->nlocal, 0);
  chosen[s.lmp->atom->map(7)] = 1;
  EXPECT_TRUE(picking.due(&chosen, 10, 1));
  ClockAssignment unrestored(s.lmp, &fix, "fast", {2, 1.3}, true);
  EXPECT_TRUE(unrestored.due(nullptr, 10, 1));
}

namespace {

// atoms in a large non-periodic box, metal units (ftm2v and mvv2e not 1):
// type 1 mass 2, type 2 mass 5; velocities and jumps set by the tests
void free_atoms(Sim &s, const std::vector<int> &types)
{
  s.cmds({"units metal", "atom_style atomic", "atom_modify map array", "boundary f f f",
          "region box block -50 50 -50 50 -50 50", "create_box 2 box", "mass 1 2.0", "mass 2 5.0"});
  for (std::size_t n = 0; n < types.size(); ++n)
    s.cmd(fmt::format("create_atoms {} single {} {} {}", types[n], 0.5 + n, -1.0 + 0.25 * n,
                      2.0 - 0.5 * n));
  s.cmds({"pair_style zero 1.0", "pair_coeff * *", "run 0 post no"});
}

// a TwoStep (no start node kept) over free atoms of the given types, with
// its per-atom state sized for them
struct FreeAtoms {
  FreeAtoms(Sim &s, const std::vector<int> &types) { free_atoms(s, types); }
};
struct TwoStepRig {
  Sim s;
  FreeAtoms made;
  AtomState state;
  TwoStep two;
  explicit TwoStepRig(const std::vector<int> &types) :
      made(s, types), state(s.lmp), two(s.lmp, state, false)
  {
    state.ensure(s.lmp->atom->nlocal);
    two.init("pe_jump");
  }
};

}    // namespace

/* ----------------------------------------------------------------------
   one atom under a constant force F over steps of h: the jump relation
   [v]^{n+1} = 2 h F/m - [v]^n, the free flight v^{n+3/2} = v^{n+1/2} +
   [v]^{n+1}, the node velocity v^{n+1} = v^{n+1/2} + [v]^{n+1}/2 and the
   move q^{n+1} = q^n + h v^{n+1/2}; over two steps v^{n+5/2} - v^{n+1/2} =
   2 h F/m; a step that begins the next one ahead leaves v^{n+3/2} and
   moves by rest v^{n+1/2} + ahead v^{n+3/2}; with rest 0 nothing moves
------------------------------------------------------------------------- */

TEST(TwoStep, JumpLoopFollowsTheJumpRelation)
{
  TwoStepRig rig({1});
  Sim &s = rig.s;
  AtomState &state = rig.state;
  TwoStep &two = rig.two;
  auto *atom = s.lmp->atom;
  const AtomSet all{1, nullptr};
  const double m = 2.0, h = 0.002, ftm2v = s.lmp->force->ftm2v;
  ASSERT_NEAR(ftm2v, 1.0 / 1.0364269e-4, 1e-6 * ftm2v);
  const double vn[3] = {1.5, -0.25, 0.75}, jn[3] = {0.125, 0.5, -0.375};
  const double F[3] = {3.0, -1.5, 0.25};
  double x0[3], a[3];
  for (int k = 0; k < 3; ++k) {
    x0[k] = atom->x[0][k];
    atom->v[0][k] = vn[k];
    two.jump()[0][k] = jn[k];
    a[k] = ftm2v * F[k] / m;
  }
  Rows favg(atom->nlocal);
  for (int k = 0; k < 3; ++k) favg[0][k] = F[k];

  // the step begins: v^{n+1/2} = v^n + [v]^n/2
  two.open(all, false);
  double vh[3], j1[3], v32[3], node[3];
  for (int k = 0; k < 3; ++k) {
    vh[k] = vn[k] + 0.5 * jn[k];
    EXPECT_DOUBLE_EQ(atom->v[0][k], vh[k]) << k;
    j1[k] = 2.0 * h * a[k] - jn[k];
    v32[k] = vh[k] + j1[k];
    node[k] = vh[k] + 0.5 * j1[k];
  }
  double mag[2] = {0.0, 0.0};
  two.jump_loop(all, favg.get(), {h, h, -1.0, false}, mag);
  const double tol = 1e-12;
  double vv = 0.0, jj = 0.0;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(two.jump()[0][k], j1[k], tol * std::fabs(j1[k])) << k;
    EXPECT_NEAR(atom->v[0][k], node[k], tol * std::fabs(node[k])) << k;
    EXPECT_NEAR(atom->x[0][k], x0[k] + h * vh[k], 1e-14) << k;
    vv += v32[k] * v32[k];
    jj += j1[k] * j1[k];
  }
  EXPECT_NEAR(mag[0], vv, tol * vv);
  EXPECT_NEAR(mag[1], jj, tol * jj);

  // the next step: v^{n+3/2} back from the node velocity and the jump;
  // two steps of a constant force change the free flight by 2 h F/m
  two.open(all, false);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(atom->v[0][k], v32[k], tol * std::fabs(v32[k])) << k;
  two.jump_loop(all, favg.get(), {h, h, -1.0, false}, mag);
  two.open(all, false);
  double v52[3], j2[3];
  for (int k = 0; k < 3; ++k) {
    j2[k] = 2.0 * h * a[k] - j1[k];
    v52[k] = v32[k] + j2[k];
    EXPECT_NEAR(atom->v[0][k], vh[k] + 2.0 * h * a[k], tol * std::fabs(v52[k])) << k;
    EXPECT_NEAR(two.jump()[0][k], j2[k], tol * std::fabs(j1[k])) << k;
    EXPECT_NEAR(atom->x[0][k], x0[k] + h * vh[k] + h * v32[k], 1e-13) << k;
  }

  // a step that moves rest = h/2 and begins the next ahead by h/4
  double x2[3];
  for (int k = 0; k < 3; ++k) x2[k] = atom->x[0][k];
  two.jump_loop(all, favg.get(), {h, 0.5 * h, 0.25 * h, false}, mag);
  for (int k = 0; k < 3; ++k) {
    const double j3 = 2.0 * h * a[k] - j2[k], v72 = v52[k] + j3;
    EXPECT_NEAR(two.jump()[0][k], j3, tol * std::fabs(j1[k])) << k;
    EXPECT_NEAR(atom->v[0][k], v72, tol * std::fabs(v72)) << k;
    EXPECT_NEAR(atom->x[0][k], x2[k] + 0.5 * h * v52[k] + 0.25 * h * v72, 1e-13) << k;
  }

  // rest 0 (a Lobatto rule's primary node is the step end): no move
  for (int k = 0; k < 3; ++k) x2[k] = atom->x[0][k];
  two.jump_loop(all, favg.get(), {h, 0.0, -1.0, false}, mag);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(atom->x[0][k], x2[k]) << k;
}

/* ----------------------------------------------------------------------
   a set of listed atoms (or of a group) begins and takes its steps with
   each atom's own mass; the others keep position, velocity and jump
------------------------------------------------------------------------- */

TEST(TwoStep, OnlyTheAtomsOfTheSetMove)
{
  TwoStepRig rig({1, 2, 1});
  Sim &s = rig.s;
  AtomState &state = rig.state;
  TwoStep &two = rig.two;
  s.cmd("group middle id 2");
  auto *atom = s.lmp->atom;
  const int n = atom->nlocal;
  ASSERT_EQ(n, 3);
  const double h = 0.001, ftm2v = s.lmp->force->ftm2v;
  Rows favg(n);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      atom->v[i][k] = 0.5 * (i + 1) - 0.3 * k;
      two.jump()[i][k] = 0.01 * (k + 1) * (i % 2 ? -1 : 1);
      favg[i][k] = 1.0 + i - 0.7 * k;
    }
  const std::vector<double> x0(&atom->x[0][0], &atom->x[0][0] + 3 * n);
  const std::vector<double> v0(&atom->v[0][0], &atom->v[0][0] + 3 * n);
  const std::vector<double> j0(&two.jump()[0][0], &two.jump()[0][0] + 3 * n);

  const auto check = [&](const AtomSet &set, const std::set<int> &in, const char *what) {
    two.open(set, false);
    double mag[2] = {0.0, 0.0};
    two.jump_loop(set, favg.get(), {h, h, -1.0, false}, mag);
    for (int i = 0; i < n; ++i) {
      const double m = (atom->type[i] == 1) ? 2.0 : 5.0;
      for (int k = 0; k < 3; ++k) {
        const int c = 3 * i + k;
        if (in.count(i) == 0) {
          EXPECT_EQ(atom->x[i][k], x0[c]) << what << ": atom " << i;
          EXPECT_EQ(atom->v[i][k], v0[c]) << what << ": atom " << i;
          EXPECT_EQ(two.jump()[i][k], j0[c]) << what << ": atom " << i;
          continue;
        }
        const double vh = v0[c] + 0.5 * j0[c];
        const double jump = 2.0 * h * ftm2v * favg[i][k] / m - j0[c];
        EXPECT_NEAR(two.jump()[i][k], jump, 1e-12 * std::fabs(jump)) << what << ": atom " << i;
        EXPECT_NEAR(atom->v[i][k], vh + 0.5 * jump, 1e-12) << what << ": atom " << i;
        EXPECT_NEAR(atom->x[i][k], x0[c] + h * vh, 1e-14) << what << ": atom " << i;
      }
    }
    // back to the start for the next set
    std::copy(x0.begin(), x0.end(), &atom->x[0][0]);
    std::copy(v0.begin(), v0.end(), &atom->v[0][0]);
    std::copy(j0.begin(), j0.end(), &two.jump()[0][0]);
  };
  const AtomList ends = {0, 2};
  check(AtomSet{1, &ends}, {0, 2}, "list");
  const int middle = s.lmp->group->bitmask[s.lmp->group->find("middle")];
  check(AtomSet{middle, nullptr}, {atom->map(2)}, "group");
  check(AtomSet{1, nullptr}, {0, 1, 2}, "all");
}

/* ----------------------------------------------------------------------
   energies(): pseudo-kinetic energy (1/2) sum m v^{n-1/2}.v^{n+1/2} and
   jump energy (1/8) sum m |[v]^n|^2 of a known state (metal units), which
   add up to the kinetic energy of the node velocities; the values are
   kept through a time step (forget_energies() or the next step computes
   them anew), energies_now() computes them at once; a list sums its atoms
------------------------------------------------------------------------- */

TEST(TwoStep, EnergiesOfAKnownState)
{
  TwoStepRig rig({1, 2, 1});
  Sim &s = rig.s;
  AtomState &state = rig.state;
  TwoStep &two = rig.two;
  auto *atom = s.lmp->atom;
  const int n = atom->nlocal;
  const double vn[3][3] = {{1.0, -2.0, 0.5}, {0.25, 0.0, -1.5}, {-0.75, 1.25, 2.0}};
  const double jn[3][3] = {{0.2, 0.1, -0.4}, {-0.3, 0.05, 0.0}, {0.0, -0.6, 0.35}};
  double mass[3];
  for (int i = 0; i < n; ++i) mass[i] = (atom->type[i] == 1) ? 2.0 : 5.0;
  const double mvv2e = s.lmp->force->mvv2e;
  ASSERT_NEAR(mvv2e, 1.0364269e-4, 1e-12);
  const auto expected = [&](const std::vector<int> &atoms, double *e) {
    e[0] = e[1] = 0.0;
    for (const int i : atoms)
      for (int k = 0; k < 3; ++k) {
        const double before = vn[i][k] - 0.5 * jn[i][k], after = vn[i][k] + 0.5 * jn[i][k];
        e[0] += 0.5 * mass[i] * before * after;
        e[1] += 0.125 * mass[i] * jn[i][k] * jn[i][k];
      }
    e[0] *= mvv2e;
    e[1] *= mvv2e;
  };
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      atom->v[i][k] = vn[i][k];
      two.jump()[i][k] = jn[i][k];
    }
  const AtomSet all{1, nullptr};
  double want[2];
  expected({0, 1, 2}, want);
  const double *e = two.energies(all);
  EXPECT_NEAR(e[0], want[0], 1e-14 * std::fabs(want[0]));
  EXPECT_NEAR(e[1], want[1], 1e-14 * want[1]);
  double kinetic = 0.0;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) kinetic += 0.5 * mvv2e * mass[i] * vn[i][k] * vn[i][k];
  EXPECT_NEAR(e[0] + e[1], kinetic, 1e-14 * kinetic);
  const double first = e[0];

  // a change within the time step is seen after forget_energies()
  atom->v[1][0] += 1.0;
  EXPECT_EQ(two.energies(all)[0], first);
  double now[2];
  two.energies_now(all, now);
  EXPECT_NEAR(now[0] - first, 0.5 * mvv2e * mass[1] * (2.0 * vn[1][0] + 1.0), 1e-12);
  two.forget_energies();
  EXPECT_EQ(two.energies(all)[0], now[0]);
  atom->v[1][0] -= 1.0;
  EXPECT_EQ(two.energies(all)[0], now[0]);
  s.lmp->update->ntimestep += 1;    // the next step computes anew
  EXPECT_NEAR(two.energies(all)[0], first, 1e-15);

  const AtomList one = {2};
  two.energies_now(AtomSet{1, &one}, now);
  expected({2}, want);
  EXPECT_NEAR(now[0], want[0], 1e-14 * std::fabs(want[0]));
  EXPECT_NEAR(now[1], want[1], 1e-14 * want[1]);
}

/* ----------------------------------------------------------------------
   the fingerprints of the velocities: a velocity changed in one component
   is found (by the sets that hold it only), a reversal of all velocities
   is told from other changes and taken as the scheme's when it may be;
   the fingerprints of open() are those of the free-flight velocities
------------------------------------------------------------------------- */

TEST(TwoStep, VelocityChangesAreFound)
{
  TwoStepRig rig({1, 2, 1});
  Sim &s = rig.s;
  AtomState &state = rig.state;
  TwoStep &two = rig.two;
  auto *atom = s.lmp->atom;
  const int n = atom->nlocal;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      atom->v[i][k] = 0.3 * (i + 1) + 0.1 * k;
      two.jump()[i][k] = 0.01 * (k - 1);
    }
  const AtomSet all{1, nullptr};
  const AtomList others = {0, 2};
  const AtomSet not_one{1, &others};
  two.mark_all(all);
  EXPECT_FALSE(two.any_changed(all));
  EXPECT_EQ(two.velocity_change(all, true), 0);

  const double kept = atom->v[1][2];
  atom->v[1][2] = std::nextafter(kept, 1.0);    // the smallest change
  EXPECT_TRUE(two.any_changed(all));
  EXPECT_FALSE(two.any_changed(not_one));
  EXPECT_EQ(two.velocity_change(all, true), 2);
  EXPECT_EQ(two.velocity_change(not_one, true), 0);
  two.mark(1);    // taken as the scheme's
  EXPECT_FALSE(two.any_changed(all));
  atom->v[1][2] = kept;
  EXPECT_TRUE(two.any_changed(all));
  two.mark(1);

  // all reversed: told apart from other changes, marked if allowed
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) atom->v[i][k] = -atom->v[i][k];
  EXPECT_TRUE(two.any_changed(all));
  EXPECT_EQ(two.velocity_change(all, false), 2);
  EXPECT_EQ(two.velocity_change(all, true), 1);
  EXPECT_EQ(two.velocity_change(all, true), 0);
  EXPECT_FALSE(two.any_changed(all));
  // one reversed only: a change
  for (int k = 0; k < 3; ++k) atom->v[0][k] = -atom->v[0][k];
  EXPECT_EQ(two.velocity_change(all, true), 2);
  two.mark_all(all);

  // open() with fingerprints: those of v^{n+1/2}
  two.open(all, true);
  EXPECT_FALSE(two.any_changed(all));
  atom->v[2][0] *= 1.5;
  EXPECT_TRUE(two.any_changed(all));
}

namespace {

// atoms at rest in a non-periodic lj box, of types with masses 1, 2, 3
void lj_atoms(Sim &s, int n)
{
  s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "boundary f f f",
          "region box block -20 20 -20 20 -20 20", "create_box 3 box", "mass 1 1.0", "mass 2 2.0",
          "mass 3 3.0"});
  for (int i = 0; i < n; ++i)
    s.cmd(fmt::format("create_atoms {} single {} 0 0", i % 3 + 1, 2.0 * i));
  s.cmds({"pair_style zero 1.0", "pair_coeff * *", "timestep 0.01", "run 0 post no"});
}

}    // namespace

/* ----------------------------------------------------------------------
   compensate: with steps h_{n-1}, h_n, h_{n+1} the jump falls short of the
   smooth one by d = (h_{n+1} - h_n)/2 a(t_{n+1}) - (h_n - h_{n-1})/2
   a(t_n), a(t) interpolated linearly between the averages A_{n-1}, A_n of
   the last two steps at their mid-step times. d is added to the jump and
   to the free-flight velocity u of the step that begins, less its part
   alpha w along the peculiar velocities w = u_last - V_cm of the last
   step's free flight u_last = u - [v] (which stays), so that the
   pseudo-kinetic energy (1/2) sum m u_last.u and the momentum stay.
   By hand (two atoms of mass 1, h = 0.01, 0.01, 0.02, A_{n-1} = +-1,
   A_n = +-2 along x): d = +-0.0125 x; u_last = (2,1,0), (0,-1,0), so
   V_cm = (1,0,0), w = +-(1,1,0), alpha = 0.025/4 and the added jump is
   +-(0.00625, -0.00625, 0). Then three atoms of masses 1, 2, 3 and three
   different steps: d and alpha from the formulas, and the pseudo-kinetic
   energy and the momentum unchanged
------------------------------------------------------------------------- */

TEST(StepControl, CompensationAddsTheMissingJump)
{
  {
    Sim s;
    lj_atoms(s, 2);
    s.cmd("mass 2 1.0");
    auto *atom = s.lmp->atom;
    AtomState state(s.lmp);
    StepControl steps(s.lmp, state, 0.0, 0.0, 0.0, true);
    EXPECT_TRUE(steps.keeps_history());
    EXPECT_FALSE(steps.adapts());
    state.ensure(2);
    double **older = steps.next_history();
    for (int k = 0; k < 3; ++k) older[0][k] = older[1][k] = 0.0;
    older[0][0] = 1.0;
    older[1][0] = -1.0;
    double **newer = steps.next_history();
    for (int k = 0; k < 3; ++k) newer[0][k] = newer[1][k] = 0.0;
    newer[0][0] = 2.0;
    newer[1][0] = -2.0;
    const double before[2][3] = {{2.0, 1.0, 0.0}, {0.0, -1.0, 0.0}};    // u_last
    Rows jump(2), scratch(2);
    for (int i = 0; i < 2; ++i)
      for (int k = 0; k < 3; ++k) {
        jump[i][k] = 0.1 * (k + 1);
        atom->v[i][k] = before[i][k] + jump[i][k];
      }
    const std::vector<double> j0 = jump.buf;
    const std::vector<double> v0(&atom->v[0][0], &atom->v[0][0] + 6);
    const AtomSet all{1, nullptr};
    // without two steps, or with equal steps, nothing to compensate
    EXPECT_FALSE(steps.compensate(0.02, all, atom->v, jump.get(), scratch.get()));
    steps.step_done(0.01);
    EXPECT_FALSE(steps.compensate(0.02, all, atom->v, jump.get(), scratch.get()));
    steps.step_done(0.01);
    EXPECT_FALSE(steps.compensate(0.01, all, atom->v, jump.get(), scratch.get()));
    EXPECT_EQ(jump.buf, j0);
    EXPECT_TRUE(steps.compensate(0.02, all, atom->v, jump.get(), scratch.get()));
    const double added[2][3] = {{0.00625, -0.00625, 0.0}, {-0.00625, 0.00625, 0.0}};
    for (int i = 0; i < 2; ++i)
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(jump[i][k] - j0[3 * i + k], added[i][k], 1e-15) << i << " " << k;
        EXPECT_NEAR(atom->v[i][k] - v0[3 * i + k], added[i][k], 1e-15) << i << " " << k;
      }
    // compensate no: nothing
    StepControl off(s.lmp, state, 0.0, 0.0, 0.0, false);
    EXPECT_FALSE(off.keeps_history());
    off.step_done(0.01);
    off.step_done(0.01);
    EXPECT_FALSE(off.compensate(0.02, all, atom->v, jump.get(), scratch.get()));
  }

  Sim s;
  lj_atoms(s, 3);
  auto *atom = s.lmp->atom;
  AtomState state(s.lmp);
  StepControl steps(s.lmp, state, 0.0, 0.0, 0.0, true);
  state.ensure(3);
  double mass[3];
  for (int i = 0; i < 3; ++i) mass[i] = atom->type[i];    // types 1, 2, 3 have masses 1, 2, 3
  // forces that add up to zero, as an isolated system's
  const double fold[3][3] = {{1.0, -0.5, 0.25}, {-2.0, 1.5, 0.5}, {1.0, -1.0, -0.75}};
  const double fnew[3][3] = {{1.5, -0.25, 0.5}, {-2.5, 1.0, 1.0}, {1.0, -0.75, -1.5}};
  const double before[3][3] = {{0.3, -0.2, 1.1}, {-0.4, 0.7, 0.2}, {0.9, 0.1, -0.5}};
  double **hist = steps.next_history();
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) hist[i][k] = fold[i][k];
  hist = steps.next_history();
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) hist[i][k] = fnew[i][k];
  const double h0 = 0.01, h1 = 0.012, h2 = 0.009;
  steps.step_done(h0);
  steps.step_done(h1);
  Rows jump(3), scratch(3);
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      jump[i][k] = 0.05 * (i - k);
      atom->v[i][k] = before[i][k] + jump[i][k];
    }
  const std::vector<double> j0 = jump.buf;
  const std::vector<double> v0(&atom->v[0][0], &atom->v[0][0] + 9);
  EXPECT_TRUE(steps.compensate(h2, AtomSet{1, nullptr}, atom->v, jump.get(), scratch.get()));

  // the expected addition, from the formulas
  double d[3][3], vcm[3] = {0.0, 0.0, 0.0}, total = 0.0;
  for (int i = 0; i < 3; ++i) {
    total += mass[i];
    for (int k = 0; k < 3; ++k) {
      const double A0 = fold[i][k] / mass[i], A1 = fnew[i][k] / mass[i];
      // mid-step times: t_n - h0/2 and t_n + h1/2 (t_n = 0)
      const double slope = (A1 - A0) / (0.5 * h1 + 0.5 * h0);
      const double at_n = A1 - 0.5 * h1 * slope, at_n1 = A1 + 0.5 * h1 * slope;
      d[i][k] = 0.5 * (h2 - h1) * at_n1 - 0.5 * (h1 - h0) * at_n;
      vcm[k] += mass[i] * before[i][k];
    }
  }
  double wd = 0.0, ww = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      const double w = before[i][k] - vcm[k] / total;
      wd += mass[i] * w * d[i][k];
      ww += mass[i] * w * w;
    }
  const double alpha = wd / ww;
  EXPECT_GT(std::fabs(alpha), 1e-3);    // the projection takes part
  double momentum[3] = {0.0, 0.0, 0.0}, pseudo_change = 0.0, size = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      const double want = d[i][k] - alpha * (before[i][k] - vcm[k] / total);
      const double got = jump[i][k] - j0[3 * i + k];
      EXPECT_NEAR(got, want, 1e-15) << i << " " << k;
      EXPECT_NEAR(atom->v[i][k] - v0[3 * i + k], want, 1e-15) << i << " " << k;
      momentum[k] += mass[i] * got;
      // u_last = u - [v] stays, u gains got
      pseudo_change += mass[i] * (atom->v[i][k] - jump[i][k]) * got;
      size += std::fabs(got);
    }
  EXPECT_GT(size, 1e-4);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(momentum[k], 0.0, 1e-16) << k;
  EXPECT_NEAR(pseudo_change, 0.0, 1e-16);
}

/* ----------------------------------------------------------------------
   the adaptive step: the largest next step h' whose predicted jump
   [v]^{n+2} = 2 h' a' - [v]^{n+1} has a jump energy (1/8) sum m |.|^2 of
   at most half of eps E (E: the larger of |E0| and the kinetic energy;
   here one atom, m = 1, |v| = 1: E = 0.5, eps = 0.01, bound 0.0025), a'
   extrapolated to the next step's middle from this step's and the last
   one's averages, within a growth of 5 % per step and [dtmin, dtmax];
   where no step meets the bound, the step of the smallest predicted jump
------------------------------------------------------------------------- */

TEST(StepControl, ChoosesTheLargestStepWithinTheBound)
{
  Sim s;
  lj_atoms(s, 1);
  auto *atom = s.lmp->atom;
  auto *update = s.lmp->update;
  for (int k = 0; k < 3; ++k) atom->v[0][k] = (k == 0) ? 1.0 : 0.0;
  const double eps = 0.01, bound = 0.5 * eps * 0.5;
  const AtomSet all{1, nullptr};
  Rows favg(1), jump(1);
  // the step whose predicted jump 2 h a has the bound's jump energy
  const double a = 10.0;
  const double wanted = std::sqrt(8.0 * bound) / (2.0 * a);
  {
    AtomState state(s.lmp);
    StepControl steps(s.lmp, state, eps, 1e-4, 0.1, false);
    EXPECT_TRUE(steps.adapts());
    EXPECT_TRUE(steps.keeps_history());
    state.ensure(1);
    steps.start_run("pe_jump", 0.0);
    EXPECT_EQ(update->dt, 0.01);
    steps.step_done(0.01);
    favg[0][0] = a;
    steps.choose_next(all, favg.get(), jump.get());
    EXPECT_NEAR(update->dt, wanted, 1e-12);
    EXPECT_LT(update->dt, 0.0075);
    // a small force: 5 % more per step
    update->dt = 0.01;
    favg[0][0] = 0.1;
    steps.choose_next(all, favg.get(), jump.get());
    EXPECT_DOUBLE_EQ(update->dt, 0.0105);
    // ... up to dtmax
    update->dt = 0.099;
    steps.choose_next(all, favg.get(), jump.get());
    EXPECT_EQ(update->dt, 0.1);
    // no step meets the bound ([v]^{n+1} has a part the force cannot
    // cancel): the step of the smallest predicted jump, 2 h' a = 0.1,
    // among the steps tried (64 between dtmin and the growth limit)
    update->dt = 0.1;
    favg[0][0] = 1.0;
    jump[0][0] = 0.1;
    jump[0][1] = 0.5;
    AtomState wide_state(s.lmp);
    StepControl wide(s.lmp, wide_state, eps, 1e-4, 1.0, false);
    wide_state.ensure(1);
    wide.step_done(0.1);
    wide.start_run("pe_jump", 0.0);
    wide.choose_next(all, favg.get(), jump.get());
    EXPECT_NEAR(update->dt, 0.05, 0.005);
    jump[0][0] = jump[0][1] = 0.0;
  }
  {
    // extrapolated: a = 10 now, 8 the step before (h = h_prev = 0.01):
    // a' = a + (h' + h)/(h + h_prev) (a - a_prev), 2 h' a' = sqrt(8 bound)
    update->dt = 0.01;
    AtomState state(s.lmp);
    StepControl steps(s.lmp, state, eps, 1e-4, 0.1, false);
    state.ensure(1);
    steps.start_run("pe_jump", 0.0);
    double **hist = steps.next_history();
    for (int k = 0; k < 3; ++k) hist[0][k] = (k == 0) ? 8.0 : 0.0;
    hist = steps.next_history();
    for (int k = 0; k < 3; ++k) hist[0][k] = favg[0][k] = (k == 0) ? a : 0.0;
    steps.step_done(0.01);
    steps.step_done(0.01);
    steps.choose_next(all, favg.get(), jump.get());
    const double h = 0.01, da = (a - 8.0) / (h + h);
    // 2 da t^2 + 2 (a + h da) t - sqrt(8 bound) = 0
    const double qa = 2.0 * da, qb = 2.0 * (a + h * da), qc = -std::sqrt(8.0 * bound);
    const double root = (-qb + std::sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa);
    EXPECT_NEAR(update->dt, root, 1e-12);
    EXPECT_LT(update->dt, wanted - 5e-4);    // the growing force asks for less
  }
  // start_run: the time step into [dtmin, dtmax]
  AtomState state(s.lmp);
  StepControl steps(s.lmp, state, eps, 1e-4, 0.1, false);
  update->dt = 1.0;
  steps.start_run("pe_jump", 0.0);
  EXPECT_EQ(update->dt, 0.1);
  update->dt = 1e-6;
  steps.start_run("pe_jump", 0.0);
  EXPECT_EQ(update->dt, 1e-4);
}

/* ----------------------------------------------------------------------
   the first step: the initial kick [v]^0 = h F/m has jump energy
   (1/8) m |h F/m|^2, which is kept to half of eps E (E the larger of
   |pe + kinetic| and the kinetic energy): one atom, m = 2, |v| = 1
   (kinetic energy 1), F = 4 along x: h^2 = 0.5 eps E
------------------------------------------------------------------------- */

TEST(StepControl, FirstStepKeepsTheKickWithinTheBound)
{
  Sim s;
  lj_atoms(s, 1);
  s.cmd("mass 1 2.0");
  auto *atom = s.lmp->atom;
  auto *update = s.lmp->update;
  ASSERT_EQ(atom->nlocal, 1);
  atom->v[0][0] = 1.0;
  atom->v[0][1] = atom->v[0][2] = 0.0;
  AtomState state(s.lmp);
  const double eps = 0.01;
  StepControl steps(s.lmp, state, eps, 1e-4, 1.0, false);
  state.ensure(1);
  Rows f(1);
  f[0][0] = 4.0;
  const AtomSet all{1, nullptr};
  const auto first = [&](double pe, double dt) {
    update->dt = dt;
    steps.first_step("pe_jump", all, f.get(), pe);
    return update->dt;
  };
  // (1/8) 2 (4 h / 2)^2 = h^2 against 0.5 eps E
  EXPECT_NEAR(first(0.5, 0.1), std::sqrt(0.5 * eps * 1.5), 1e-14);     // E = pe + kinetic
  EXPECT_NEAR(first(-3.0, 0.1), std::sqrt(0.5 * eps * 2.0), 1e-14);    // E = |pe + kinetic|
  EXPECT_NEAR(first(-1.5, 0.1), std::sqrt(0.5 * eps * 1.0), 1e-14);    // E = kinetic
  EXPECT_EQ(first(0.5, 0.05), 0.05);                                   // small enough
  // above dtmax: brought into range, then cut
  EXPECT_NEAR(first(0.5, 5.0), std::sqrt(0.5 * eps * 1.5), 1e-14);
  f[0][0] = 0.01;
  EXPECT_EQ(first(0.5, 5.0), 1.0);
  f[0][0] = 4.0e4;    // no less than dtmin
  EXPECT_EQ(first(0.5, 0.1), 1e-4);
  // no adapt: nothing
  AtomState other(s.lmp);
  StepControl fixed(s.lmp, other, 0.0, 1e-4, 1.0, false);
  update->dt = 0.1;
  fixed.first_step("pe_jump", all, f.get(), 0.5);
  EXPECT_EQ(update->dt, 0.1);
}

namespace {

// four atoms in a periodic box of 6: 1 and 2 bonded (harmonic, K 5, r0 1)
// across the boundary, 3 within the LJ cutoff 2.5 of both, 4 of none
void bonded_four(Sim &s)
{
  s.cmds({"units lj", "atom_style bond", "atom_modify map array", "boundary p p p",
          "region box block 0 6 0 6 0 6", "create_box 1 box bond/types 1 extra/bond/per/atom 1",
          "mass 1 1.0", "create_atoms 1 single 0.3 3.0 3.0", "create_atoms 1 single 5.5 3.2 3.0",
          "create_atoms 1 single 1.3 3.9 3.4", "create_atoms 1 single 3.0 0.5 0.5",
          "pair_style lj/cut 2.5", "pair_coeff 1 1 1.0 1.0 2.5", "bond_style harmonic",
          "bond_coeff 1 5.0 1.0", "create_bonds single/bond 1 1 2", "run 0 post no"});
}

// forces (by local index) and energies of the bond and of the LJ pairs
// (not the bonded pair: special_bonds lj 0), from the minimum images
struct Analytic {
  std::vector<double> bond, pair;
  double ebond = 0.0, epair = 0.0;
  int pairs = 0;
};

Analytic analytic(Sim &s)
{
  auto *atom = s.lmp->atom;
  const int n = atom->nlocal;
  Analytic out;
  out.bond.assign(3 * n, 0.0);
  out.pair.assign(3 * n, 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      double d[3];
      for (int k = 0; k < 3; ++k) d[k] = atom->x[i][k] - atom->x[j][k];
      s.lmp->domain->minimum_image(d);
      const double r = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      const std::set<int> both = {static_cast<int>(atom->tag[i]), static_cast<int>(atom->tag[j])};
      double fpair = 0.0;    // force on i along d/r
      if (both == std::set<int>{1, 2}) {
        out.ebond += 5.0 * (r - 1.0) * (r - 1.0);
        fpair = -2.0 * 5.0 * (r - 1.0);
        for (int k = 0; k < 3; ++k) {
          out.bond[3 * i + k] += fpair * d[k] / r;
          out.bond[3 * j + k] -= fpair * d[k] / r;
        }
      } else if (r < 2.5) {
        const double s6 = std::pow(1.0 / r, 6);
        out.epair += 4.0 * (s6 * s6 - s6);
        fpair = 24.0 * (2.0 * s6 * s6 - s6) / r;
        ++out.pairs;
        for (int k = 0; k < 3; ++k) {
          out.pair[3 * i + k] += fpair * d[k] / r;
          out.pair[3 * j + k] -= fpair * d[k] / r;
        }
      }
    }
  return out;
}

}    // namespace

/* ----------------------------------------------------------------------
   the sampler's forces and energies of each contribution and of all
   agree with the analytic ones: the bond across the periodic boundary
   (harmonic, E = K (r - r0)^2) and the LJ pairs 1-3 and 2-3
------------------------------------------------------------------------- */

TEST(ForceSampler, ForcesOfABondAndPairsAreTheAnalyticOnes)
{
  Sim s;
  bonded_four(s);
  auto *atom = s.lmp->atom;
  const int n = atom->nlocal;
  ASSERT_EQ(n, 4);
  const Analytic exact = analytic(s);
  EXPECT_EQ(exact.pairs, 2);
  ForceSampler sampler(s.lmp);
  EXPECT_EQ(sampler.present(), ForceSampler::PAIR | ForceSampler::BOND);
  const auto agree = [&](int mask, const char *what) {
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        const double want = ((mask & ForceSampler::BOND) ? exact.bond[3 * i + k] : 0.0) +
            ((mask & ForceSampler::PAIR) ? exact.pair[3 * i + k] : 0.0);
        EXPECT_NEAR(atom->f[i][k], want, 1e-12 * (1.0 + std::fabs(want)))
            << what << ": atom " << atom->tag[i] << " component " << k;
      }
  };
  sampler.compute(ForceSampler::ALL, 1, 0);
  agree(ForceSampler::ALL, "all");
  EXPECT_NEAR(sampler.energy(ForceSampler::BOND), exact.ebond, 1e-12);
  EXPECT_NEAR(sampler.energy(ForceSampler::PAIR), exact.epair, 1e-12);
  double magnitude = 0.0;
  EXPECT_NEAR(sampler.energy(ForceSampler::ALL, &magnitude), exact.ebond + exact.epair, 1e-12);
  EXPECT_NEAR(magnitude, std::fabs(exact.ebond) + std::fabs(exact.epair), 1e-12);
  sampler.compute(ForceSampler::BOND, 1, 0);
  agree(ForceSampler::BOND, "bond");
  sampler.compute(ForceSampler::PAIR, 1, 0);
  agree(ForceSampler::PAIR, "pair");
  // the bond is not zero and the pairs not negligible
  EXPECT_GT(std::fabs(exact.bond[3 * atom->map(1)]), 0.1);
  EXPECT_GT(std::fabs(exact.pair[3 * atom->map(3)]), 0.1);
}

/* ----------------------------------------------------------------------
   only_touch(): an evaluation clears the forces of the touched atoms
   (listed, or the first nfirst) and evaluates theirs; an untouched atom
   in no interaction keeps its force, one in an evaluated interaction
   (atom 3 in the pairs) gets the interaction's force added to what it
   had; without only_touch() every force is cleared
------------------------------------------------------------------------- */

TEST(ForceSampler, OnlyTouchedAtomsAreCleared)
{
  Sim s;
  bonded_four(s);
  auto *atom = s.lmp->atom;
  const int n = atom->nlocal;
  const Analytic exact = analytic(s);
  ForceSampler sampler(s.lmp);
  const auto stale = [&](int i, int k) {
    return 100.0 * (i + 1) + k;
  };
  const auto fill = [&] {
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) atom->f[i][k] = stale(i, k);
  };
  const int i1 = atom->map(1), i2 = atom->map(2), i3 = atom->map(3), i4 = atom->map(4);
  const std::vector<int> bonded = {i1, i2};
  const ForceSampler::Touched listed{0, &bonded, nullptr};
  sampler.only_touch(&listed);
  EXPECT_EQ(sampler.touches(), &listed);

  fill();
  sampler.compute(ForceSampler::BOND, 0, 0);
  for (int k = 0; k < 3; ++k) {
    for (const int i : bonded) EXPECT_NEAR(atom->f[i][k], exact.bond[3 * i + k], 1e-12);
    EXPECT_EQ(atom->f[i3][k], stale(i3, k));
    EXPECT_EQ(atom->f[i4][k], stale(i4, k));
  }

  fill();
  sampler.compute(ForceSampler::PAIR, 0, 0);
  for (int k = 0; k < 3; ++k) {
    for (const int i : bonded) EXPECT_NEAR(atom->f[i][k], exact.pair[3 * i + k], 1e-12);
    EXPECT_NEAR(atom->f[i3][k], stale(i3, k) + exact.pair[3 * i3 + k], 1e-12);
    EXPECT_NE(exact.pair[3 * i3 + k], 0.0);
    EXPECT_EQ(atom->f[i4][k], stale(i4, k));
  }

  // the first two local atoms, by count
  const std::vector<int> none;
  const ForceSampler::Touched first_two{2, &none, nullptr};
  sampler.only_touch(&first_two);
  fill();
  sampler.compute(ForceSampler::ALL, 0, 0);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const double fresh = exact.bond[3 * i + k] + exact.pair[3 * i + k];
      EXPECT_NEAR(atom->f[i][k], (i < 2 ? 0.0 : stale(i, k)) + fresh, 1e-12) << "atom " << i;
    }

  sampler.only_touch(nullptr);
  fill();
  sampler.compute(ForceSampler::ALL, 0, 0);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(atom->f[i][k], exact.bond[3 * i + k] + exact.pair[3 * i + k], 1e-12);
}
