#pragma once
// Sparse Cholesky of the Newton matrix through SuiteSparse's CHOLMOD directly,
// on the matrix's own CRS arrays: the values array is handed to CHOLMOD as it
// is (no copy, no re-import row by row), the symbolic analysis (fill-reducing
// ordering, elimination tree, supernodes) is done once per graph and kept,
// and each solve runs the numeric factorisation and the two triangular solves.
//
// Factor reuse (Newton iterations within a time step): a solve on the same
// graph may first run preconditioned conjugate gradients on the new values
// with the previous numeric factor as the preconditioner, M = L_old L_old^T.
// Where the Hessian changed little (the later Newton iterations) CG reaches
// |b - A x| <= tol |b| in a few iterations, each one triangular-solve pair
// (2 lnz multiply-adds) and one product with A, instead of a factorisation
// (rings at the paper's size: 6.4e7 flops per factorisation against 1.3e6 per
// CG iteration; measured 2-15 iterations to 1e-10 in the iterations after the
// first). CG stops and the matrix is factorised instead when it has not
// reached tol after `max_iterations`, when its residual falls too slowly to
// reach tol within them (rate test after 4 iterations), or on a direction of
// zero curvature (round-off, a semi-definite A). Negative curvature,
// p^T A p < -1e-8 |p| |A p|, proves A indefinite: the solve throws
// NotPositiveDefinite as a failed factorisation would. CG may also converge
// on an indefinite A without meeting negative curvature; its x then solves
// A x = b like the factorisation's would, but an exact-Hessian Newton
// iteration is not told that A is indefinite (the line search still demands
// descent). Once a factorisation has failed on a non-positive pivot, later
// factorisations of that time step go into a spare factor, so the last good one survives the
// next failure (memory: twice the factor). With CholmodReuse::single (the default) CG
// applies a float copy of a supernodal factor, in double arithmetic
// (solver/single_factor.hpp; made between CG solves once the factor has
// served a few iterations, SingleFactor::worth_copying; up to 1.6x the
// factor's memory in all, with the copy's headroom): the iterations stay
// those of the double factor (paper twist: 1039 in 5 twisting steps either
// way), each costs about half the bytes (CG on the old factor 40.3 -> 24.5 s
// there). The budget by cost below still
// prices an iteration at the double factor's bytes: halving that price
// raised the paper twist's CG iterations 1039 -> 1232 with the same 16
// factorisations, so it was not done. solve() reports the relative
// residual CG stopped at (the reuse tolerance, or the looser one the caller
// allows: an inexact Newton direction), 0 after a factorisation (exact).
//
// The matrix is symmetric (the DOF space eliminates constraints
// symmetrically), so its CRS arrays read as compressed columns are A itself;
// CHOLMOD is told stype = 1 and reads one triangle. Preconditions: one rank,
// sorted column indices, a graph that does not change between set_matrix
// calls (values may). Errors (not positive definite, out of memory) are
// SolverError naming CHOLMOD's status.
#include <memory>

#include "solver/tpetra_types.hpp"

namespace bfemp {

struct CholmodReuse {
  int max_iterations = 0;    // CG iterations on the previous factor; 0: always factorise
  double tolerance = 1e-10;  // relative residual CG must reach
  // With max_iterations > 0: raise the budget to what one factorisation of
  // the analysed graph costs in CG iterations, estimated from the symbolic
  // analysis as
  //   F / (kBlas3Advantage (4 |L| + 2 |A|))     (at most kMaxByCost = 40),
  // F CHOLMOD's flop count, |L| the stored factor (L->xsize: two triangular
  // solves), |A| A's stored entries, both triangles (the product with A).
  // kBlas3Advantage: a flop of the supernodal factorisation (dense BLAS 3 on
  // large fronts) is that much faster than a flop of CG's memory-bound
  // triangular solves. Measured at 2 threads on this VM: 3D twist at the
  // paper's size (F 5.4e10, |L| 3.7e7, |A| 6.6e6): 2.1 s per factorisation
  // against 33 ms per CG iteration, a ratio of 64, the estimate 84; 2D rings
  // (F 6.7e7, |L| 1.2e6, |A| 3.1e5): 11 ms against 0.9 ms, a ratio of 12,
  // the estimate 3 (the budget stays max_iterations there). Only counts
  // enter, so a run's decisions do not depend on the machine's timing.
  // Supernodal factors only: a simplicial one (CHOLMOD's choice for sparse
  // factors, flops / nnz(L) < 40) keeps max_iterations. The cap: the
  // estimate prices one solve, but a factor that needs many CG iterations
  // will need them again at the next Newton iterations, so a new one pays
  // back sooner than the estimate says. Paper twist at 2 threads, 5 steps
  // from t = 2.1 (perf/README "A later window"): budget 84 (the estimate)
  // 50.1 s per step, 20: 44.8, 40: 41.5; from t = 1.0: 84: 15.6 and 16.6
  // s, 40: 16.0 and 16.7 (within the noise). It was 200.
  bool by_cost = false;
  // LinearSolver: CG on the previous factor may stop at the Newton forcing
  // term (solve()'s `tolerance`), not at `tolerance` ('forcing term').
  bool adaptive = true;
  // CG on the previous factor preconditions with a float copy of it, applied
  // in double arithmetic (solver/single_factor.hpp): half the bytes per
  // triangular solve. Supernodal factors only (a simplicial one, or one with
  // entries outside float's range, is applied in double as before).
  bool single = true;
  static constexpr double kBlas3Advantage = 4.0;
  static constexpr int kMaxByCost = 40;
};

class CholmodDirect {
 public:
  ~CholmodDirect();
  CholmodDirect(const CholmodDirect&) = delete;
  CholmodDirect& operator=(const CholmodDirect&) = delete;

  using Reuse = CholmodReuse;
  struct Result {
    bool analysed = false;    // the symbolic analysis ran in this call
    bool factorised = false;  // the numeric factorisation ran in this call
    int cg_iterations = 0;    // CG iterations on the previous factor (also when CG gave up)
    int cg_budget = 0;        // the iteration budget CG had (CholmodReuse::by_cost)
    bool cg_single = false;   // CG was preconditioned by the factor's float copy (CholmodReuse::single)
    double factor_s = 0;      // seconds in the symbolic analysis and numeric factorisation
    double cg_s = 0;          // seconds in CG on the previous factor (also when it gave up)
    double tolerance = 0;     // relative residual the result was solved to (0: factorised, exact)
  };

  explicit CholmodDirect(Reuse reuse = {});

  // A matrix on a (possibly) new graph: the next solve redoes the analysis.
  void set_matrix(const Teuchos::RCP<const Matrix>& A);
  // Solves A x = b with the current values: CG on the previous factor where
  // reuse allows it, else a numeric factorisation and the triangular solves.
  // `tolerance` > the reuse tolerance: CG on the previous factor may stop
  // there (an inexact Newton direction); the factorisation's solve is exact.
  // `from_x`: CG on the previous factor starts from x (an earlier, looser
  // solution of this system: the Newton step's confirming solve) instead of
  // 0; the stop stays relative to |b|. Without it x is output only.
  Result solve(const Vector& b, Vector& x, double tolerance = 0.0, bool from_x = false);
  // The next solve factorises (a new time step: runs and their restarts then
  // take the same path).
  void forget_factor();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace bfemp
