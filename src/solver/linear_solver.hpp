#pragma once
// The linear-solver layer: Cholmod (SuiteSparse directly, on the matrix's own
// arrays: solver/cholmod_direct.hpp), KLU2 (Amesos2) or Belos CG with an
// Ifpack2 or a MueLu (solver/muelu_preconditioner.hpp) preconditioner,
// configured by the scene's "Linear Solver" sublist.
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>
#include <memory>
#include <string>

#include "solver/tpetra_types.hpp"

namespace bfemp {

enum class LinearSolverKind { Cholmod, KLU2, CG };

struct LinearSolveStats {
  int iterations = 0;        // Krylov iterations (1 for a direct solve; Cholmod: CG
                             // iterations on the previous factor, + 1 if it factorised)
  double achieved_tol = 0;   // relative residual reported by the solver
  bool refactored = false;   // a symbolic factorisation happened in this call
  bool factorised = false;   // a numeric factorisation happened in this call (direct solvers)
  double tolerance = 0;      // relative residual the solve was asked for (0: exact, a factorisation's;
                             // Cholmod's CG on the previous factor: the tolerance it stopped at)
  double factor_s = 0;       // Cholmod, BLOCK_CHOLMOD (this rank's block): seconds in analysis + numeric factorisation
  double reuse_cg_s = 0;     // Cholmod: seconds in CG on the previous factor
  int reuse_cg_iterations = 0;  // Cholmod: CG iterations on the previous factor
  int stale_retries = 0;     // CG + BLOCK_CHOLMOD: solves that did not converge on the
                             // kept (stale) factor and were redone on a fresh one
};

// Schema of the "Linear Solver" sublist with defaults and documentation.
Teuchos::RCP<const Teuchos::ParameterList> linear_solver_schema();
LinearSolverKind linear_solver_kind(const Teuchos::ParameterList& resolved);
const char* linear_solver_name(LinearSolverKind kind);

class LinearSolver {
 public:
  // `params` is a resolved (validated) "Linear Solver" list. Throws
  // std::invalid_argument when a direct solver is asked for on > 1 rank or
  // when Belos/Ifpack2 keys are misspelled.
  LinearSolver(const Teuchos::ParameterList& params, const Teuchos::RCP<const Comm>& comm);
  ~LinearSolver();
  LinearSolver(const LinearSolver&) = delete;
  LinearSolver& operator=(const LinearSolver&) = delete;

  // Declare the matrix whose values will change between solves. A matrix on
  // a new graph triggers a new symbolic factorisation / preconditioner set-up.
  void set_matrix(const Teuchos::RCP<const Matrix>& A);
  // Solve A x = b with the current values of A. Throws SolverError on a failed
  // factorisation or a Krylov solve that does not reach the tolerance.
  // `forcing` > 0 (CG, or Cholmod's CG on the previous factor, with 'forcing
  // term: adaptive'): the relative residual to reach, clamped to
  // [tolerance (Cholmod: reuse tolerance), 0.1]; KLU2 and Cholmod's
  // factorisations ignore it (exact).
  // `from_x`: x holds a starting iterate, an earlier looser solution of this
  // system (Newton's confirming solve goes on from its inexact direction):
  // CG and Cholmod's CG on the previous factor start there; the tolerance
  // stays relative to |b|. Without it x is output only (CG starts from 0).
  LinearSolveStats solve(const Vector& b, Vector& x, double forcing = 0.0, bool from_x = false);
  // Cholmod: the next solve factorises instead of reusing the previous factor
  // (called at the start of each time step); a no-op for the others.
  void forget_factor();

  // MueLu: the caller should pass the rigid-body modes of the DOFs' nodes
  // (rigid_body_modes in solver/muelu_preconditioner.hpp) after every
  // set_matrix and every near_null_space_every() minimisations; a new null
  // space means a new hierarchy at the next solve.
  bool wants_near_null_space() const;
  int near_null_space_every() const;
  void set_near_null_space(const Teuchos::RCP<MultiVec>& modes, int block_size);
  // MueLu hierarchies created from scratch (0 for the others).
  int preconditioner_setups() const;

  LinearSolverKind kind() const { return kind_; }
  // Whether a solve with an indefinite matrix throws NotPositiveDefinite (so
  // Newton may try the exact Hessian first): Cholmod (a non-positive pivot),
  // and CG with BLOCK_CHOLMOD (a block's pivot, or p^T A p <= 0 met by CG
  // under that SPD preconditioner). CG may converge on an indefinite matrix
  // without meeting negative curvature; the line search still demands descent.
  bool detects_indefinite() const;
  // The tolerance of a solve with forcing 0 ('CG/tolerance'; Cholmod: 'reuse
  // tolerance'; 0 for KLU2).
  double tightest_tolerance() const;
  std::string describe() const;

 private:
  struct Impl;
  LinearSolverKind kind_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace bfemp
