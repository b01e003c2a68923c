#pragma once
// Threads of the BLAS under CHOLMOD's supernodal factorisation.
//
// Debian links SuiteSparse against the system BLAS (an alternative: OpenBLAS,
// pthreads build, on the reference machines). OpenBLAS starts as many threads
// as OPENBLAS_NUM_THREADS, GOTO_NUM_THREADS or OMP_NUM_THREADS say (else one
// per core), and its workers are created by the main thread, so with
// OMP_PROC_BIND they inherit its one-core mask and all share core 0 with
// Kokkos' thread 0. bfemp therefore runs the BLAS on one thread, unless
// OPENBLAS_NUM_THREADS or GOTO_NUM_THREADS says otherwise. (On an OpenMP
// build of OpenBLAS, openblas_set_num_threads sets OpenMP's thread count
// too; Debian's default is the pthreads build.)
//
// Measured on the rings at the paper's size (9408 DOFs, 6.4e7 flops per
// numeric factorisation), Kokkos at 2 threads on this 2-core VM:
// - unbound OpenMP threads: 45 ms per factorisation with one BLAS thread,
//   28 ms with two;
// - OMP_PROC_BIND=spread OMP_PLACES=threads (as README and the scripts set
//   it): `perf/run_scenes.sh --threads 2 --steps 25`, three alternations,
//   0.59-0.63 s per contact step with one BLAS thread, 0.65-0.84 s with two,
//   even with the second BLAS thread moved onto core 1 (Kokkos' spinning
//   thread is there);
// - wall time, unbound with two BLAS threads against bound with one: no
//   difference beyond this VM's noise.
// Another BLAS (reference, BLIS, MKL) is left as it is: the functions are
// looked up at run time, nothing links against OpenBLAS.
#include <string>

namespace bfemp {

// One OpenBLAS thread unless OPENBLAS_NUM_THREADS or GOTO_NUM_THREADS is set; returns a line for
// the start banner, e.g. "BLAS: OpenBLAS, 1 thread(s)" or
// "BLAS: OpenBLAS, 2 thread(s) (OPENBLAS_NUM_THREADS)".
std::string configure_blas_threads();

// OpenBLAS' current thread count, or 0 when the BLAS is not OpenBLAS.
int blas_threads();

}  // namespace bfemp
