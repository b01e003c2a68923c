// The BLAS under CHOLMOD gets Kokkos' thread count unless the user set
// OPENBLAS_NUM_THREADS (solver/blas_threads.hpp). On a machine whose BLAS is
// not OpenBLAS both calls leave it alone and say so.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "solver/blas_threads.hpp"

namespace {

struct RestoreBlas {
  ~RestoreBlas() {  // back to the test main's OPENBLAS_NUM_THREADS=1
    unsetenv("OPENBLAS_NUM_THREADS");
    bfemp::match_blas_threads(1);
    setenv("OPENBLAS_NUM_THREADS", "1", 1);
  }
};

TEST(BlasThreads, FollowKokkosUnlessTheUserSetOpenblasNumThreads) {
  RestoreBlas restore;
  unsetenv("OPENBLAS_NUM_THREADS");
  const std::string two = bfemp::match_blas_threads(2);
  if (bfemp::blas_threads() == 0) {
    EXPECT_NE(two.find("not OpenBLAS"), std::string::npos) << two;
    GTEST_SKIP() << "the BLAS is not OpenBLAS: " << two;
  }
  EXPECT_EQ(bfemp::blas_threads(), 2) << two;
  EXPECT_NE(two.find("2 thread(s) (as Kokkos)"), std::string::npos) << two;
  EXPECT_EQ(bfemp::match_blas_threads(1), "BLAS: OpenBLAS, 1 thread(s) (as Kokkos)");
  EXPECT_EQ(bfemp::blas_threads(), 1);

  // The user's OPENBLAS_NUM_THREADS wins: the count is left as it is.
  setenv("OPENBLAS_NUM_THREADS", "1", 1);
  const std::string kept = bfemp::match_blas_threads(2);
  EXPECT_EQ(bfemp::blas_threads(), 1) << kept;
  EXPECT_NE(kept.find("(OPENBLAS_NUM_THREADS)"), std::string::npos) << kept;
}

}  // namespace
