// The BLAS under CHOLMOD runs on one thread unless the user set
// OPENBLAS_NUM_THREADS (solver/blas_threads.hpp). On a machine whose BLAS is
// not OpenBLAS the call leaves it alone and says so.
#include <gtest/gtest.h>

#include <dlfcn.h>
#include <pthread.h>
#include <sched.h>

#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cstdio>
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

// A large factorisation's scope: OpenBLAS on as many threads as Kokkos'
// team has cores, the calling thread's mask widened to the team's cores, both
// restored on exit; a small factorisation, a user's OPENBLAS_NUM_THREADS or a
// one-thread team leave everything alone.
TEST(BlasThreads, ALargeFactorisationGetsTheTeamsCoresForTheScopeOnly) {
  RestoreEnv restore;
  unsetenv("OPENBLAS_NUM_THREADS");
  if (bfemp::blas_threads() == 0) GTEST_SKIP() << "the BLAS is not OpenBLAS";
  const int team = Kokkos::DefaultHostExecutionSpace::concurrency();
  bfemp::configure_blas_threads();
  ASSERT_EQ(bfemp::blas_threads(), 1);
  cpu_set_t before, inside, after;
  ASSERT_EQ(pthread_getaffinity_np(pthread_self(), sizeof(before), &before), 0);
  {
    bfemp::BlasTeamScope small(0.5 * bfemp::BlasTeamScope::kTeamFlops);
    EXPECT_EQ(small.threads(), 0);
    EXPECT_EQ(bfemp::blas_threads(), 1);
  }
  // The team's cores, as the scope asks for them.
  cpu_set_t cores;
  CPU_ZERO(&cores);
#pragma omp parallel num_threads(team)
  {
    cpu_set_t mine;
    CPU_ZERO(&mine);
    pthread_getaffinity_np(pthread_self(), sizeof(mine), &mine);
#pragma omp critical
    CPU_OR(&cores, &cores, &mine);
  }
  const int expected = std::min(team, CPU_COUNT(&cores));
  // The caller bound to one of the team's cores, as OMP_PROC_BIND binds
  // Kokkos' thread 0: the scope widens its mask and restores the one core.
  cpu_set_t one;
  CPU_ZERO(&one);
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &cores)) {
      CPU_SET(c, &one);
      break;
    }
  ASSERT_EQ(pthread_setaffinity_np(pthread_self(), sizeof(one), &one), 0);
  {
    bfemp::BlasTeamScope big(bfemp::BlasTeamScope::kTeamFlops);
    if (expected < 2) {
      EXPECT_EQ(big.threads(), 0);
    } else {
      EXPECT_EQ(big.threads(), expected);
      EXPECT_EQ(bfemp::blas_threads(), expected);
      ASSERT_EQ(pthread_getaffinity_np(pthread_self(), sizeof(inside), &inside), 0);
      EXPECT_TRUE(CPU_EQUAL(&inside, &cores));
    }
  }
  EXPECT_EQ(bfemp::blas_threads(), 1);
  ASSERT_EQ(pthread_getaffinity_np(pthread_self(), sizeof(after), &after), 0);
  EXPECT_TRUE(CPU_EQUAL(&after, &one));
  ASSERT_EQ(pthread_setaffinity_np(pthread_self(), sizeof(before), &before), 0);
  // The user's count stands.
  setenv("OPENBLAS_NUM_THREADS", "1", 1);
  {
    bfemp::BlasTeamScope big(bfemp::BlasTeamScope::kTeamFlops);
    EXPECT_EQ(big.threads(), 0);
    EXPECT_EQ(bfemp::blas_threads(), 1);
  }
  std::printf("  team of %d thread(s) on %d core(s): OpenBLAS on %d inside the scope\n", team, CPU_COUNT(&cores), expected);
}

}  // namespace
