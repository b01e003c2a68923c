#pragma once
// Threads of the BLAS under CHOLMOD's supernodal factorisation.
//
// Debian links SuiteSparse against the system BLAS (an alternative: OpenBLAS,
// pthreads build, on the reference machines). OpenBLAS starts as many threads
// as the machine has cores, whatever OMP_NUM_THREADS says, so a 1-thread run
// would still factorise on every core, and a benchmark that pins
// OPENBLAS_NUM_THREADS=1 times a slower solver than the user gets. bfemp gives
// the BLAS the same thread count as Kokkos: the factorisation runs between
// Kokkos kernels, never beside them, so the two pools do not compete.
// Measured (rings at the paper's size, 9408 DOFs, 6.4e7 flops per
// factorisation, 2 threads): 45 ms per numeric factorisation with one BLAS
// thread, 28 ms with two.
//
// An OPENBLAS_NUM_THREADS (or OMP_NUM_THREADS for an OpenMP-built OpenBLAS)
// that the user set is kept. Another BLAS (reference, BLIS, MKL) is left as it
// is: the functions are looked up at run time, nothing links against OpenBLAS.
#include <string>

namespace bfemp {

// Sets OpenBLAS' thread count to `threads` unless OPENBLAS_NUM_THREADS is set;
// returns a one-line description for the start banner, e.g.
// "BLAS: OpenBLAS, 2 thread(s)" or "BLAS: not OpenBLAS (threads left as they are)".
std::string match_blas_threads(int threads);

// OpenBLAS' current thread count, or 0 when the BLAS is not OpenBLAS.
int blas_threads();

}  // namespace bfemp
