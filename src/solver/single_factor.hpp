#pragma once
// A single-precision copy of a supernodal CHOLMOD factor, applied with double
// arithmetic: the preconditioner of CG on the previous factor
// (CholmodDirect's reuse).
//
// Math. CHOLMOD's supernodal factor is L L^T = P A P^T (LL', never LDL'),
// P the fill-reducing permutation: row i of P A P^T is row Perm[i] of A.
// solve(b) returns z = P^T L^-T L^-1 P b, as cholmod_solve2(CHOLMOD_A) does,
// but with L's entries rounded to float on the copy (assign). Every product
// and sum is done in double, so the operator applied is the exact inverse of
// L_f L_f^T (L_f: L rounded to float) up to double round-off: symmetric and
// positive definite like the double factor's, so CG's theory holds for it. It
// differs from (L L^T)^-1 by the rounding of L (relative 6e-8 per entry);
// for the stale factor CG preconditions with, the Newton matrix's own change
// since the factorisation is the larger difference.
//
// Why. The triangular solves of CG on the previous factor read the whole
// factor twice per iteration and are bound by memory bandwidth (3D twist at
// the paper's size: 3.7e7 stored entries, 38 ms per iteration against 1.4 s
// per factorisation, 2 threads); float entries halve the bytes read.
//
// Layout (CHOLMOD's): supernode k holds columns super[k] .. super[k+1]-1;
// its rows are s[pi[k]] .. s[pi[k+1]-1] (the first nscol of them are its own
// columns), its entries a column-major nsrow x nscol block at x[px[k]].
// Preconditions: the factor is numeric, supernodal and real (assign returns
// false otherwise and keeps nothing); it is not changed between assign and
// the solves that use the copy (assign again after each factorisation).
// b and z may be the same array.
//
// Threads. solve(b, z, threads) shares the supernodes among `threads` host
// threads (SupernodeSchedule: disjoint subtrees per thread, the top of the
// tree by panels; one OpenMP team per solve, outside any Kokkos kernel). Its
// result differs from the one-thread solve only in the order of the sums into
// the top's rows and of the partial dot products of the shared supernodes
// (round-off); it depends on `threads` alone, not on the size of the team
// OpenMP actually gives (a smaller team takes the missing threads' shares). threads = 0 means Kokkos' host concurrency, on the calling thread
// alone for a factor under kThreadedEntries stored entries; 1 means the
// calling thread; more means that many, whatever the size. A factor whose
// supernodes are not in postorder is solved on the calling thread.
#include <cholmod.h>

#include "solver/supernode_schedule.hpp"

#include <cstddef>
#include <vector>

namespace bfemp {

class SingleFactor {
 public:
  // Whether L, which has served `served` solves in double, is worth copying
  // now (ski rental: the solves it has served pay for the copy, so a factor
  // used once or twice is never copied). A copy reads 8 and writes 4 bytes
  // per entry: 21 ms for 4.7e7 entries at 2 threads, where a double solve
  // pair takes ~45 ms and a float one ~25 (a 3D block of 52728 DOFs); but
  // 118 ms when its buffer must grow (new pages). So kWorthAfter solves when
  // the copy fits the room this time step's copies have made (the largest
  // one plus a quarter), kWorthAfterGrowing otherwise. The room counts this
  // step's copies only (new_step() empties it; the memory itself is kept),
  // so the decisions do not depend on earlier steps: a restarted run copies
  // where the run it continues did. The paper twist's factors serve ~65 CG
  // iterations each, bench_mpm_newton's 2-3.
  static constexpr int kWorthAfter = 2;
  static constexpr int kWorthAfterGrowing = 8;
  bool worth_copying(const cholmod_factor& L, int served) const {
    return served >= (L.xsize <= step_room_ ? kWorthAfter : kWorthAfterGrowing);
  }
  void new_step() { step_room_ = 0; }
  // The copy of the current factor L, made at most once: at the first call
  // where worth_copying(L, served) holds (later calls do nothing, also after
  // assign refused L). forget() drops the copy and the attempt, for a new
  // factor (after each factorisation).
  void copy_if_worth(const cholmod_factor& L, int served) {
    if (tried_ || !worth_copying(L, served)) return;
    assign(L);  // (refused: the solves stay in double)
    tried_ = true;
  }
  void forget() {
    clear();
    tried_ = false;
  }

  // Copies L's entries rounded to float (and its pattern). false, and the
  // copy emptied, when L is not a numeric real supernodal factor.
  bool assign(const cholmod_factor& L);
  bool ready() const { return n_ > 0; }
  void clear();
  // z = P^T L^-T L^-1 P b on the copy. Precondition: ready().
  void solve(const double* b, double* z, int threads = 0);
  static constexpr std::size_t kThreadedEntries = 1 << 20;
  // The schedule of the last threaded solve (threads == 0 when none).
  const SupernodeSchedule& schedule() const { return schedule_; }
  std::size_t entries() const { return n_ > 0 ? x_.size() : 0; }  // stored factor entries (L->xsize)

 private:
  std::size_t n_ = 0;
  std::vector<SuiteSparse_long> perm_, super_, pi_, px_, s_;
  std::vector<float> x_;
  std::size_t step_room_ = 0;  // entries this step's copies have made room for (worth_copying)
  bool tried_ = false;          // copy_if_worth ran assign on the current factor
  std::vector<double> w_;  // the permuted right-hand side, solved in place
  std::vector<double> v_;  // one supernode's rows
  SuiteSparse_long max_rows_ = 0;
  SupernodeSchedule schedule_;  // built at the first threaded solve of a copy
  std::vector<double> vt_;      // per thread: one supernode's rows
  std::vector<double> buf_;     // per thread: its subtrees' updates of the top's rows
  std::vector<double> part_;    // per thread: partial dot products of a shared panel
  int schedule_tried_ = 0;       // the thread count schedule_ was last built for (0: none since the copy)
  using Long = SuiteSparse_long;
  void forward_one(std::size_t k, double* w, double* v, Long col_end, double* buf) const;
  void backward_one(std::size_t k, double* w, double* v) const;
  void forward_shared(std::size_t k, double* w, double* v, int t, int team) const;
  void backward_shared(std::size_t k, double* w, double* v, int t, int team);
  void solve_serial(double* w);
  void solve_threaded(double* w);
};

}  // namespace bfemp
