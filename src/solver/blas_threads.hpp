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
//
// Large factorisations (BlasTeamScope): where one numeric factorisation is
// large (kTeamFlops and more: the 3D twist at the paper's size, 5.4e10 flops
// at first contact and 6.3e10 at t = 1.0, against 6.7e7 for the 2D rings), its dense BLAS 3 work is worth the second
// core, which Kokkos' team leaves idle while CHOLMOD runs on the calling
// thread. For the scope's lifetime OpenBLAS gets as many threads as Kokkos'
// OpenMP team has cores, and the calling thread's CPU mask is widened to the
// cores of the team's threads, so that a worker OpenBLAS creates inside it
// (it creates them lazily, with its creator's mask) may run on them; the
// count and the mask are restored on exit. Measured on the paper twist at
// t = 1.0 (6.3e10 flops per factorisation; 1 rank, 2 threads,
// `OMP_PROC_BIND=spread`, 5 twisting steps, 16 factorisations, two
// alternations): analysis + factorisation 31.8-34.4 s -> 22.4-23.9 s; without
// the widened mask the worker shared core 0 with the caller and nothing was
// gained. The triangular solves (CG on the previous factor, BLAS 2 bound by
// memory) stay on one thread: two made them slower (19.3 -> 22-24 s in two
// twisting steps).
// A no-op when OPENBLAS_NUM_THREADS or GOTO_NUM_THREADS is set (the user's
// choice stands), when the BLAS is not OpenBLAS, when the team has one core,
// or inside a parallel region. Open it on the host thread, outside any
// parallel region and before CholmodSerialScope (it asks the OpenMP team
// for its threads' masks once).
#include <sched.h>

#include <string>

namespace bfemp {

// One OpenBLAS thread unless OPENBLAS_NUM_THREADS or GOTO_NUM_THREADS is set; returns a line for
// the start banner, e.g. "BLAS: OpenBLAS, 1 thread(s)" or
// "BLAS: OpenBLAS, 2 thread(s) (OPENBLAS_NUM_THREADS)".
std::string configure_blas_threads();

// OpenBLAS' current thread count, or 0 when the BLAS is not OpenBLAS.
int blas_threads();

class BlasTeamScope {
 public:
  static constexpr double kTeamFlops = 1e9;  // a factorisation this large (flops) gets the team's cores
  // `flops`: the factorisation's flop count (CHOLMOD's Common->fl).
  explicit BlasTeamScope(double flops);
  ~BlasTeamScope();
  BlasTeamScope(const BlasTeamScope&) = delete;
  BlasTeamScope& operator=(const BlasTeamScope&) = delete;
  int threads() const { return threads_; }  // OpenBLAS threads inside the scope (0: the scope changed nothing)

 private:
  int threads_ = 0;
  int previous_ = 1;  // OpenBLAS' count before the scope, restored on exit
  cpu_set_t saved_{};
};

}  // namespace bfemp
