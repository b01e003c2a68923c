#include "solver/blas_threads.hpp"

#include <dlfcn.h>
#include <omp.h>
#include <pthread.h>

#include <Kokkos_Core.hpp>

#include <algorithm>
#include <cstdlib>

namespace bfemp {

namespace {
using SetThreads = void (*)(int);
using GetThreads = int (*)();

SetThreads set_fn() { return reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads")); }
GetThreads get_fn() { return reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads")); }
}  // namespace

int blas_threads() {
  const GetThreads get = get_fn();
  return get ? get() : 0;
}

namespace {
bool user_set_threads() {
  for (const char* var : {"OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS"}) {
    const char* user = std::getenv(var);
    if (user && *user) return true;
  }
  return false;
}

// Kokkos' host team size (its OpenMP pool; the caller's own
// omp_get_max_threads() is 1 outside Kokkos' regions).
int team_size() { return Kokkos::DefaultHostExecutionSpace::concurrency(); }

// The union of the CPU masks of Kokkos' OpenMP team's threads (the cores it
// runs on). Kept once the whole team answered (a region that ran on fewer
// threads, e.g. inside CholmodSerialScope, is asked again next time).
bool team_cores(cpu_set_t& out) {
  static cpu_set_t cores;
  static bool known = false;
  if (known) {
    out = cores;
    return true;
  }
  cpu_set_t all;
  CPU_ZERO(&all);
  int answered = 0;
#pragma omp parallel num_threads(team_size())
  {
    cpu_set_t mine;
    CPU_ZERO(&mine);
    if (pthread_getaffinity_np(pthread_self(), sizeof(mine), &mine) == 0) {
#pragma omp critical(bfemp_team_cores)
      {
        CPU_OR(&all, &all, &mine);
        ++answered;
      }
    }
  }
  if (answered != team_size()) return false;
  cores = all;
  known = true;
  out = cores;
  return true;
}
}  // namespace

BlasTeamScope::BlasTeamScope(double flops) {
  if (!(flops >= kTeamFlops) || omp_in_parallel() || team_size() < 2 || user_set_threads()) return;
  const SetThreads set = set_fn();
  if (!set || !get_fn()) return;
  cpu_set_t team;
  if (!team_cores(team)) return;
  const int n = std::min(team_size(), CPU_COUNT(&team));
  if (n < 2 || pthread_getaffinity_np(pthread_self(), sizeof(saved_), &saved_) != 0) return;
  if (pthread_setaffinity_np(pthread_self(), sizeof(team), &team) != 0) return;
  previous_ = blas_threads();
  set(n);
  threads_ = n;
}

BlasTeamScope::~BlasTeamScope() {
  if (threads_ == 0) return;
  set_fn()(previous_);
  pthread_setaffinity_np(pthread_self(), sizeof(saved_), &saved_);
}

std::string configure_blas_threads() {
  const SetThreads set = set_fn();
  if (!set || !get_fn()) return "BLAS: not OpenBLAS (its threads left as they are)";
  for (const char* var : {"OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS"}) {
    const char* user = std::getenv(var);
    if (user && *user) return "BLAS: OpenBLAS, " + std::to_string(blas_threads()) + " thread(s) (" + var + ")";
  }
  set(1);
  return "BLAS: OpenBLAS, " + std::to_string(blas_threads()) + " thread(s)";
}

}  // namespace bfemp
