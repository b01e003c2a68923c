// The BLAS under CHOLMOD runs on one thread unless the user set
// OPENBLAS_NUM_THREADS (solver/blas_threads.hpp). On a machine whose BLAS is
// not OpenBLAS the call leaves it alone and says so.
#include <gtest/gtest.h>

#include <dlfcn.h>

#include <cstdlib>
#include <string>

#include "solver/blas_threads.hpp"

namespace {

using SetThreads = void (*)(int);

struct RestoreEnv {  // the test main's OPENBLAS_NUM_THREADS=1
  ~RestoreEnv() { setenv("OPENBLAS_NUM_THREADS", "1", 1); }
};

TEST(BlasThreads, OneUnlessTheUserSetOpenblasNumThreads) {
  RestoreEnv restore;
  unsetenv("OPENBLAS_NUM_THREADS");
  if (bfemp::blas_threads() == 0) {
    const std::string line = bfemp::configure_blas_threads();
    EXPECT_NE(line.find("not OpenBLAS"), std::string::npos) << line;
    GTEST_SKIP() << "the BLAS is not OpenBLAS: " << line;
  }
  // Whatever OpenBLAS started with (one per core), bfemp's call leaves one.
  const auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  ASSERT_NE(set, nullptr);
  set(2);
  EXPECT_EQ(bfemp::configure_blas_threads(), "BLAS: OpenBLAS, 1 thread(s)");
  EXPECT_EQ(bfemp::blas_threads(), 1);

  // GOTO_NUM_THREADS, which OpenBLAS also reads, is kept too.
  set(2);
  setenv("GOTO_NUM_THREADS", "2", 1);
  EXPECT_EQ(bfemp::configure_blas_threads(), "BLAS: OpenBLAS, 2 thread(s) (GOTO_NUM_THREADS)");
  unsetenv("GOTO_NUM_THREADS");

  // The user's OPENBLAS_NUM_THREADS wins: the count is left as it is.
  set(2);
  setenv("OPENBLAS_NUM_THREADS", "2", 1);
  const std::string kept = bfemp::configure_blas_threads();
  EXPECT_EQ(bfemp::blas_threads(), 2) << kept;
  EXPECT_EQ(kept, "BLAS: OpenBLAS, 2 thread(s) (OPENBLAS_NUM_THREADS)");
  set(1);
}

}  // namespace
