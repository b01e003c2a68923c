#pragma once
// Sparse Cholesky of the Newton matrix through SuiteSparse's CHOLMOD directly,
// on the matrix's own CRS arrays: the values array is handed to CHOLMOD as it
// is (no copy, no re-import row by row), the symbolic analysis (fill-reducing
// ordering, elimination tree, supernodes) is done once per graph and kept,
// and each solve runs the numeric factorisation and the two triangular solves.
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

class CholmodDirect {
 public:
  CholmodDirect();
  ~CholmodDirect();
  CholmodDirect(const CholmodDirect&) = delete;
  CholmodDirect& operator=(const CholmodDirect&) = delete;

  // A matrix on a (possibly) new graph: the next solve redoes the analysis.
  void set_matrix(const Teuchos::RCP<const Matrix>& A);
  // Factorises the current values and solves A x = b. Returns true when the
  // symbolic analysis ran in this call.
  bool solve(const Vector& b, Vector& x);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace bfemp
