#pragma once
// CHOLMOD settings shared by CholmodDirect and BlockCholmod, and the scope
// every CHOLMOD call runs in.
//
// Settings (start_cholmod):
//   - errors come back as the status, nothing is printed;
//   - simplicial factors as LL', not LDL': LDL' reports only an exactly zero
//     pivot, so an indefinite exact Hessian would pass as definite
//     (supernodal factors are always LL');
//   - relaxed supernodal amalgamation nrelax = {16, 64, 128} (CHOLMOD's
//     default {4, 16, 48}; zrelax left at {0.8, 0.1, 0.05}): supernodes of
//     up to 16 columns always merge, up to 64 while under 80 % of their
//     entries are fill, up to 128 under 10 %. Fewer, larger supernodes mean
//     fewer BLAS calls and scatter passes. Measured on the rings at the
//     paper's size (9418 DOFs, 6.7e7 flops per factorisation before
//     amalgamation, 1 thread): 760 supernodes -> 281, 16-20 ms -> 10-13 ms
//     per numeric factorisation (with the serial scope below); the stored
//     factor grows from 8.3e5 to 1.2e6 entries (L->xsize: the explicit zeros
//     of the merged supernodes; CHOLMOD's Common->fl and lnz are counted
//     before amalgamation and do not show it).
//
// Serial scope (CholmodSerialScope): Debian's SuiteSparse 5 builds CHOLMOD
// with OpenMP and a fixed team of 4 threads (CHOLMOD_OMP_NUM_THREADS) for its
// supernodal scatter loops, whatever OMP_NUM_THREADS says: a fork and join of
// 4 threads per supernode, on 2 cores beside Kokkos' own OpenMP threads. On
// the same matrix that made a numeric factorisation 35-40 ms instead of
// 16-20 ms (OMP_THREAD_LIMIT=1 gives the same 16-20 ms). The scope sets the
// OpenMP max-active-levels to 0 for its lifetime, so every parallel region
// opened inside it (CHOLMOD's) runs on the calling thread, and restores the
// previous value on exit. The BLAS under CHOLMOD here is OpenBLAS' pthreads
// build (solver/blas_threads.hpp), whose threads are not OpenMP's and are not
// affected; an OpenMP build of a BLAS would run on one thread in the scope
// too (slower, not wrong).
// Preconditions: opened on the host thread outside any parallel region (a
// no-op inside one), and no Kokkos kernel launched while it is open (a
// Kokkos OpenMP kernel would then run its whole range split for the pool on
// one thread: only thread 0's share would be done).
#include <cholmod.h>

namespace bfemp {

void start_cholmod(cholmod_common& c);

class CholmodSerialScope {
 public:
  CholmodSerialScope();
  ~CholmodSerialScope();
  CholmodSerialScope(const CholmodSerialScope&) = delete;
  CholmodSerialScope& operator=(const CholmodSerialScope&) = delete;

 private:
  int saved_ = -1;  // -1: nothing to restore
};

}  // namespace bfemp
