#pragma once
// Block-Jacobi preconditioner with an exact Cholesky factor per MPI rank:
//   M^-1 = blockdiag(A_11, ..., A_PP)^-1,   A_pp = A restricted to the rows
//   and columns rank p owns,
// each block factorised by SuiteSparse's CHOLMOD (supernodal LL^T, its
// symbolic analysis kept per graph). On one rank M = A, so CG converges in
// one iteration; on P ranks CG only has to resolve the coupling between the
// blocks (the rank boundaries), which takes far fewer iterations than a
// point relaxation on the stiff, badly scaled Newton matrices of contact
// scenes (shell E 1e10 against a cube E 1e8 on the twist).
//
// Why not Ifpack2 SCHWARZ + AMESOS2: Trilinos 13.2's Amesos2 Cholmod fails
// on Ifpack2's local filter (its KLU2 works but factorises 5-10x slower than
// CHOLMOD on these 3D matrices), and that wrapper copies the values at
// initialize(), not compute() (see linear_solver.cpp).
//
// With overlap 1 (additive Schwarz, still symmetric, so CG applies):
//   M^-1 = sum_p R_p^T A_OpOp^-1 R_p,   O_p = the DOFs rank p owns plus the
//   ghosts its rows couple to (A's column map), R_p the restriction to O_p;
// the ghost rows are imported from their owners once per compute(), the
// residual's ghost entries once per apply(), and each rank's solution on its
// ghosts is added into their owners. The overlap carries the coupling across
// rank boundaries into the local solves, so CG needs fewer iterations than
// with the plain blocks, at the price of a larger factor and two exchanges.
// Overlap level L > 1 grows O_p level by level: the DOFs the previous
// level's rows couple to (Ifpack2's overlap level L). A wider overlap carries
// more of the coupling into a larger factor: fewer CG iterations with a
// fresh factor; with a stale one (block reuse) the iterations may not fall
// (paper twist: perf/README, "The 2-rank block factor").
// A_OpOp is still a principal submatrix of A (the indefiniteness proof
// below holds). On one rank both are M = A.
//
// Preconditions: A symmetric (the DOF space eliminates constraints
// symmetrically), fill-complete, its graph fixed between set_matrix calls
// (values may change; compute() reads them), its domain, range and row maps
// the same (one-to-one: each DOF owned by one rank). A block that is not
// positive definite proves A is not (a principal submatrix of an SPD matrix
// is SPD): compute() throws NotPositiveDefinite, as a direct solve would.
#include <memory>

#include "solver/tpetra_types.hpp"

namespace bfemp {

class BlockCholmod : public Operator {
 public:
  // overlap: 0 (block Jacobi on the owned rows), 1 (see above) or a higher
  // level L (the ghosts of level L-1's rows added, Ifpack2's overlap level L).
  // single:
  // apply() solves with a float copy of the factor in double arithmetic (from
  // the first solve after the factor has served a few, see prepare_solve)
  // (solver/single_factor.hpp: the exact inverse of the rounded factor, so
  // still a fixed symmetric positive definite preconditioner; half the bytes
  // per triangular solve); a simplicial factor keeps CHOLMOD's double solve.
  static constexpr int kMaxOverlap = 4;
  explicit BlockCholmod(const Teuchos::RCP<const Matrix>& A, int overlap = 0, bool single = false);
  ~BlockCholmod() override;
  BlockCholmod(const BlockCholmod&) = delete;
  BlockCholmod& operator=(const BlockCholmod&) = delete;

  // Factorises this rank's block with A's current values (collective only in
  // that a failure on one rank is reported on every rank).
  void compute();

  // Y = alpha M^-1 X + beta Y (each rank solves with its own block).
  void apply(const MultiVec& X, MultiVec& Y, Teuchos::ETransp mode = Teuchos::NO_TRANS,
             double alpha = Teuchos::ScalarTraits<double>::one(),
             double beta = Teuchos::ScalarTraits<double>::zero()) const override;
  Teuchos::RCP<const Map> getDomainMap() const override;
  Teuchos::RCP<const Map> getRangeMap() const override;

  // Cost model (flops, this rank; after the first compute()): one numeric
  // factorisation (CHOLMOD's count from the analysis), and one CG iteration
  // with this preconditioner (two triangular solves, 4 nnz(L), and the
  // product with A's local rows, 2 nnz). Deterministic, unlike timings.
  double factor_flops() const;
  double iteration_flops() const;
  // Seconds of this rank's symbolic analyses and numeric factorisations in
  // all compute() calls so far (its own work: the ghost rows' import and the
  // failure reduction, where a rank waits for the others, are not in it).
  double local_factor_seconds() const;
  // The factor is supernodal (CHOLMOD's choice; dense BLAS 3 on its
  // supernodes), or this rank's block is empty. False before a compute().
  bool supernodal() const;

  // This rank's block: rows (owned, plus ghosts with overlap >= 1) and stored
  // entries (both triangles).
  std::size_t block_rows() const;
  std::size_t block_entries() const;
  // Before a CG solve with this preconditioner: with `single`, copies the
  // factor to float once it has served enough applies to pay for the copy
  // (SingleFactor::worth_copying), so the preconditioner never changes within
  // a CG solve.
  void prepare_solve();
  // A new time step: the float copy's ski rental counts this step only
  // (SingleFactor::new_step), as a restart would.
  void new_step();
  // apply() uses the float copy (single requested, the factor supernodal and
  // prepare_solve() has copied it).
  bool applies_single() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace bfemp
