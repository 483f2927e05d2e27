// rank-count independence: the same LJ liquid integrated by fix pe_jump on
// 1, 2 and 4 MPI ranks (sub-communicators of one 4-rank job) must agree to
// round-off. Run as: mpirun -np 4 test_pe_jump_ranks

#include "pe_jump_systems.h"

#include "comm.h"
#include "force.h"
#include "library.h"
#include "pair_lj_cut.h"

#include "gtest/gtest.h"

#include "utils.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <regex>
#include <tuple>

using namespace PEJumpTest;

namespace {

// a periodic simple-cubic lattice of bonded atoms with a soft repulsive pair
// term, exercising bond forces and newton on/off across subdomain boundaries
void bonded_lattice(Sim &s)
{
  s.cmds({"units lj", "atom_style bond", "atom_modify map array", "lattice sc 0.5",
          "region box block 0 6 0 6 0 6",
          "create_box 1 box bond/types 1 extra/bond/per/atom 6 extra/special/per/atom 30",
          "create_atoms 1 box", "mass 1 1.0", "pair_style lj/cut 1.1225", "pair_coeff 1 1 1.0 1.0",
          "bond_style harmonic", "bond_coeff 1 40.0 1.26", "special_bonds lj 0.0 1.0 1.0",
          "create_bonds many all all 1 1.2 1.32", "comm_modify cutoff 3.0",
          "velocity all create 1.0 4928459 loop geom"});
}

// runs work on a communicator of the first nranks ranks of MPI_COMM_WORLD
// (the other ranks do nothing)
void on_first_ranks(int nranks, const std::function<void(MPI_Comm)> &work)
{
  int me;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  MPI_Comm sub;
  MPI_Comm_split(MPI_COMM_WORLD, me < nranks ? 0 : MPI_UNDEFINED, me, &sub);
  if (sub == MPI_COMM_NULL) return;
  work(sub);
  MPI_Comm_free(&sub);
}

// an fcc LJ crystal in the left 3.5 of 8 lattice cells along x on a grid of
// nranks x 1 x 1 ranks: with 2 ranks, the right one owns no atom
std::vector<std::string> half_filled_box(int nranks)
{
  return {"units lj",
          "atom_style atomic",
          fmt::format("processors {} 1 1", nranks),
          "lattice fcc 0.8442",
          "region box block 0 8 0 4 0 4",
          "create_box 1 box",
          "region half block 0 3.5 INF INF INF INF",
          "create_atoms 1 region half",
          "mass 1 1.0",
          "velocity all create 1.0 4928",
          "pair_style lj/cut 2.5",
          "pair_coeff 1 1 1.0 1.0 2.5"};
}

// positions and velocities after a short run on nranks ranks (200 steps of
// 0.005; for fix pe_jump/async K, whose time step is the coarse step,
// 200/K steps of 0.005 K), ordered by the atoms' initial lattice positions
// (create_atoms numbers atoms differently on different processor grids, so
// atom IDs cannot be used to match atoms); filled on world rank 0 only
std::vector<double> run_on(int nranks, const std::string &fix, bool bonded)
{
  std::smatch async;
  const int K =
      std::regex_search(fix, async, std::regex("pe_jump/async (\\d+)")) ? std::stoi(async[1]) : 1;
  std::vector<double> out;
  on_first_ranks(nranks, [&](MPI_Comm sub) {
    Sim s(sub);
    // fix holds one or more commands separated by newlines; "newton"
    // must precede the box, the others follow the system set-up
    std::vector<std::string> before, after;
    for (const auto &line : LAMMPS_NS::utils::split_lines(fix))
      (LAMMPS_NS::utils::strmatch(line, "^newton") ? before : after).push_back(line);
    s.cmds(before);
    if (bonded)
      bonded_lattice(s);
    else
      lj_liquid(s, 5);
    const int n = static_cast<int>(s.lmp->atom->natoms);
    std::vector<double> x0(3 * n), x(3 * n), v(3 * n);
    lammps_gather_atoms(s.lmp, "x", 1, 3, x0.data());
    s.cmds(after);
    s.cmds({fmt::format("timestep {:.6g}", 0.005 * K), fmt::format("thermo {}", 20 / K),
            fmt::format("run {} post no", std::lround(200.0 / K))});
    lammps_gather_atoms(s.lmp, "x", 1, 3, x.data());
    lammps_gather_atoms(s.lmp, "v", 1, 3, v.data());
    std::vector<int> order(n);
    for (int i = 0; i < n; ++i) order[i] = i;
    const auto key = [&](int i) {
      return std::make_tuple(std::lround(1e6 * x0[3 * i]), std::lround(1e6 * x0[3 * i + 1]),
                             std::lround(1e6 * x0[3 * i + 2]));
    };
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      return key(a) < key(b);
    });
    for (int i : order) out.insert(out.end(), &x[3 * i], &x[3 * i + 3]);
    for (int i : order) out.insert(out.end(), &v[3 * i], &v[3 * i + 3]);
  });
  MPI_Barrier(MPI_COMM_WORLD);
  return out;
}

// largest difference of positions (minimum image in a cubic box) and velocities
double max_difference(const std::vector<double> &a, const std::vector<double> &b, double box)
{
  const size_t npos = a.size() / 2;
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    double d = b[i] - a[i];
    if (i < npos) d -= box * std::round(d / box);
    worst = std::max(worst, std::fabs(d));
  }
  return worst;
}

void check_ranks(const std::vector<std::string> &fixes, bool bonded, size_t natoms, double box)
{
  int nprocs, me;
  MPI_Comm_size(MPI_COMM_WORLD, &nprocs);
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  ASSERT_EQ(nprocs, 4) << "run this test with 4 MPI ranks";

  for (const auto &fix : fixes) {
    std::map<int, std::vector<double>> result;
    for (int n : {1, 2, 4}) result[n] = run_on(n, fix, bonded);
    if (me != 0) continue;
    ASSERT_EQ(result[1].size(), 6 * natoms);
    for (int n : {2, 4}) {
      const double worst = max_difference(result[1], result[n], box);
      // 200 steps amplify summation-order round-off (1e-16) by a few orders
      // of magnitude in a chaotic liquid (fix nve: ~5e-13), no more
      EXPECT_LT(worst, 1e-11) << fix << " on " << n << " ranks";
      std::cout << fix << ": max difference 1 vs " << n << " ranks = " << worst << "\n";
    }
  }
}

}    // namespace

// fix nve is the calibration: its rank-count differences show the round-off
// amplification of the system, which fix pe_jump must not exceed
TEST(PEJumpRanks, LJLiquidSameOn1And2And4Ranks)
{
  const std::string slab = "region slab block 0 2 INF INF INF INF units lattice\n"
                           "group fast region slab\n";
  check_ranks({"fix 1 all nve", "fix 1 all pe_jump", "fix 1 all pe_jump quadrature lobatto 3",
               "fix 1 all pe_jump quadrature legendre 2",
               slab + "fix 1 all pe_jump/async 4 fast quadrature lobatto 3",
               slab + "fix 1 all pe_jump/async 3 fast",
               // buffer layers of a dynamic group, taken at coarse nodes
               // without energy output (4.3e-3 apart on 4 ranks when they
               // were taken with ghost atoms still at the step's midpoint)
               "region rr sphere 4 4 4 2.5 units box\ngroup dg dynamic all region rr every 1\n"
               "fix 1 all pe_jump/async 5 dg buffer 1",
               // a criterion that reads the neighbors, evaluated at coarse
               // nodes (the rank counts differed when the ghost atoms were
               // not brought to the node)
               "compute crd all coord/atom cutoff 1.3\nvariable few atom c_crd<11\n"
               "group dg dynamic all var few every 1\nfix 1 all pe_jump/async 5 dg"},
              false, 500, 5.0 * std::cbrt(4.0 / 0.8442));
}

TEST(PEJumpRanks, BondedLatticeSameOn1And2And4Ranks)
{
  const double box = 6.0 * std::cbrt(1.0 / 0.5);
  const std::string core = "region core block 0 3 0 3 0 6 units lattice\n"
                           "group fast region core\n";
  // a dynamic fast group whose region moves: atoms change clock at coarse
  // nodes (every step with K = 5)
  const std::string moving = "variable xc equal 1.0+0.1*step\n"
                             "region mov sphere v_xc 3 3 2 units lattice\n"
                             "group fast dynamic all region mov every 1\n";
  check_ranks({"fix 1 all nve", "fix 1 all pe_jump quadrature lobatto 3",
               "newton off\nfix 1 all pe_jump quadrature legendre 3",
               core + "fix 1 all pe_jump/async 5 fast quadrature lobatto 3",
               "newton off\n" + core + "fix 1 all pe_jump/async 5 fast",
               moving + "fix 1 all pe_jump/async 5 fast",
               moving + "fix 1 all pe_jump/async 5 fast quadrature lobatto 3 buffer 1",
               core + "fix 1 all pe_jump/async 5 fast fast auto 0.05"},
              true, 216, box);
}

// a rank that owns no atom when a restart is read must take the same
// decisions as the others (restart data that does not fit the fix made only
// the ranks with atoms start the scheme anew, and the collective calls of
// the two groups of ranks then hung)
TEST(PEJumpRanks, RestartWithAnEmptyRank)
{
  int me;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  std::vector<double> ke;
  for (const int nranks : {1, 2})
    on_first_ranks(nranks, [&](MPI_Comm sub) {
      const std::string file = fmt::format("pe_jump_empty_rank{}.restart", nranks);
      {
        Sim s(sub);
        s.cmds(half_filled_box(nranks));
        s.cmds({"fix 1 all pe_jump", "timestep 0.005", "thermo 0", "run 10 post no",
                "write_restart " + file, "clear", fmt::format("processors {} 1 1", nranks),
                "read_restart " + file, "fix 1 all pe_jump compensate no", "thermo 0",
                "run 20 post no"});
        ke.push_back(s.eval("ke"));
      }
      MPI_Barrier(sub);
      if (me == 0) std::remove(file.c_str());
    });
  if (me == 0) {
    ASSERT_EQ(ke.size(), 2u);
    EXPECT_NEAR(ke[1], ke[0], 1e-12 * ke[0]);
  }
}

// quadrature auto with a rank that owns no atom (and so has no per-atom
// arrays): the rank decided from its arrays to evaluate forces at a node
// while the others reduced the step's energy defect, and the run hung in
// its first step
TEST(PEJumpRanks, AutoQuadratureWithAnEmptyRank)
{
  int me;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  std::vector<double> ke;
  for (const int nranks : {1, 2})
    on_first_ranks(nranks, [&](MPI_Comm sub) {
      Sim s(sub);
      s.cmds(half_filled_box(nranks));
      s.cmds({"fix 1 all pe_jump quadrature auto 1e-8", "timestep 0.005", "thermo 0",
              "run 20 post no"});
      ke.push_back(s.eval("ke"));
    });
  if (me == 0) {
    ASSERT_EQ(ke.size(), 2u);
    EXPECT_NEAR(ke[1], ke[0], 1e-12 * ke[0]);
  }
}

int main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  int me;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  if (me != 0) {
    auto &listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int rv = RUN_ALL_TESTS();
  int any = rv;
  MPI_Allreduce(&rv, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any;
}

/* ----------------------------------------------------------------------
   pe_jump/async probes the pair style at setup (one pair per atom type,
   two pairs of one atom, the time): every rank must evaluate it equally
   often, since a style may communicate inside compute(). With the atoms
   of type 2 on some ranks only, the ranks probed a different number of
   pairs, and a style that communicates (pair_style local/density) hung
   on 4 ranks. A toy lj/cut that does a forward communication per compute
------------------------------------------------------------------------- */

namespace {
class PairCommunicating : public LAMMPS_NS::PairLJCut {
 public:
  explicit PairCommunicating(LAMMPS_NS::LAMMPS *lmp) : PairLJCut(lmp) { comm_forward = 1; }
  void compute(int eflag, int vflag) override
  {
    comm->forward_comm(this);
    PairLJCut::compute(eflag, vflag);
  }
  int pack_forward_comm(int n, int *list, double *buf, int, int *) override
  {
    for (int i = 0; i < n; i++) buf[i] = atom->x[list[i]][0];
    return n;
  }
  void unpack_forward_comm(int, int, double *) override {}
};
LAMMPS_NS::Pair *pair_communicating_creator(LAMMPS_NS::LAMMPS *lmp)
{
  return new PairCommunicating(lmp);
}
}    // namespace

TEST(PEJumpRanks, PairStyleProbesAreCollective)
{
  Sim s;
  (*s.lmp->force->pair_map)["lj/cut/comm"] = &pair_communicating_creator;
  s.cmds({"units lj", "atom_style atomic", "atom_modify map array", "processors 4 1 1",
          "lattice fcc 0.8442", "region box block 0 8 0 3 0 3", "create_box 2 box",
          "create_atoms 1 box", "mass * 1.0", "region left block 0 2 INF INF INF INF",
          "set region left type 2", "velocity all create 1.0 4928", "pair_style lj/cut/comm 2.5",
          "pair_coeff * * 1.0 1.0 2.5", "group fast type 2", "fix 1 all pe_jump/async 4 fast",
          "timestep 0.02", "thermo 0", "run 2 post no"});
  EXPECT_EQ(s.lmp->update->ntimestep, 2);
}
