// GoogleTest main for every bfemp test: brings up MPI, Kokkos and Tpetra once.
#include <gtest/gtest.h>

#include <cstdlib>
#include <mpi.h>

#include <Kokkos_Core.hpp>
#include <Tpetra_Core.hpp>

int main(int argc, char** argv) {
  // Kokkos warns on stdout when OMP_PROC_BIND is unset; gtest_discover_tests
  // (which runs the binaries without the test environment) would read the
  // warning as test names. Tests run unbound unless told otherwise.
  setenv("OMP_PROC_BIND", "false", /*overwrite=*/0);
  // ctest -j2 runs two tests at once: threads that spin at barriers would
  // starve each other; BLAS threads would fight Kokkos' threads.
  setenv("OMP_WAIT_POLICY", "PASSIVE", 0);
  setenv("OPENBLAS_NUM_THREADS", "1", 0);
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  ::testing::InitGoogleTest(&argc, argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  int result = 0;
  {
    Kokkos::ScopeGuard kokkos(argc, argv);
    Tpetra::ScopeGuard tpetra(&argc, &argv);
    result = RUN_ALL_TESTS();
  }
  // A test failing on any rank fails the run on every rank.
  int global = 0;
  MPI_Allreduce(&result, &global, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return global;
}
