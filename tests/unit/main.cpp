// GoogleTest main for the unit tests: MPI must be initialised because MUMPS runs on
// MPI_COMM_WORLD (a single rank here).
#include <gtest/gtest.h>
#include <mpi.h>

int main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  const int result = RUN_ALL_TESTS();
  MPI_Finalize();
  return result;
}
