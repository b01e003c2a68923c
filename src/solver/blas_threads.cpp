#include "solver/blas_threads.hpp"

#include <dlfcn.h>

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
