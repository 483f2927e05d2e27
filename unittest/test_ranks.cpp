// rank-count independence: the same LJ liquid integrated by fix pe_jump on
// 1, 2 and 4 MPI ranks (sub-communicators of one 4-rank job) must agree to
// round-off. Run as: mpirun -np 4 test_pe_jump_ranks

#include "pe_jump_systems.h"

#include "library.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <map>

using namespace PEJumpTest;

namespace {

// positions and velocities ordered by atom ID after a short run on nranks ranks;
// filled on world rank 0 only
std::vector<double> run_on(int nranks, const std::string &fix)
{
  int me;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  MPI_Comm sub;
  MPI_Comm_split(MPI_COMM_WORLD, me < nranks ? 0 : MPI_UNDEFINED, me, &sub);
  std::vector<double> out;
  if (sub != MPI_COMM_NULL) {
    {
      Sim s(sub);
      lj_liquid(s, 5);
      s.cmds({fix, "timestep 0.005", "thermo 20", "run 200 post no"});
      const int n = static_cast<int>(s.lmp->atom->natoms);
      std::vector<double> x(3 * n), v(3 * n);
      lammps_gather_atoms(s.lmp, "x", 1, 3, x.data());
      lammps_gather_atoms(s.lmp, "v", 1, 3, v.data());
      out = x;
      out.insert(out.end(), v.begin(), v.end());
    }
    MPI_Comm_free(&sub);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return out;
}

}    // namespace

TEST(PEJumpRanks, SameTrajectoryOn1And2And4Ranks)
{
  int nprocs, me;
  MPI_Comm_size(MPI_COMM_WORLD, &nprocs);
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  ASSERT_EQ(nprocs, 4) << "run this test with 4 MPI ranks";

  for (const std::string fix : {"fix 1 all pe_jump", "fix 1 all pe_jump quadrature lobatto 3",
                                "fix 1 all pe_jump quadrature legendre 2"}) {
    std::map<int, std::vector<double>> result;
    for (int n : {1, 2, 4}) result[n] = run_on(n, fix);
    if (me != 0) continue;
    ASSERT_EQ(result[1].size(), 6u * 500u);
    for (int n : {2, 4}) {
      // positions are wrapped into the periodic box (5 fcc cells at 0.8442)
      // at different times on different rank counts: compare minimum images
      const double box = 5.0 * std::cbrt(4.0 / 0.8442);
      const size_t npos = result[1].size() / 2;
      double worst = 0.0;
      for (size_t i = 0; i < result[1].size(); ++i) {
        double d = result[n][i] - result[1][i];
        if (i < npos) d -= box * std::round(d / box);
        worst = std::max(worst, std::fabs(d));
      }
      // 200 steps of a chaotic liquid amplify summation-order round-off
      // (1e-16) by a few orders of magnitude, no more
      EXPECT_LT(worst, 1e-11) << fix << " on " << n << " ranks";
      std::cout << fix << ": max difference 1 vs " << n << " ranks = " << worst << "\n";
    }
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
