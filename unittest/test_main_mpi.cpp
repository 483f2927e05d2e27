// main() of the single-process GoogleTest programs that drive LAMMPS

#include "gmock/gmock.h"
#include "gtest/gtest.h"

#include <mpi.h>

int main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleMock(&argc, argv);
  const int rv = RUN_ALL_TESTS();
  MPI_Finalize();
  return rv;
}
