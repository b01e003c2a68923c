#pragma once
#include <stdexcept>
#include <string>

namespace bfemp {
// A numerical failure (factorisation, Krylov non-convergence, Newton cap).
// Never caught and ignored: the driver reports it with the step number.
class SolverError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// A Cholesky factorisation met a non-positive pivot: the matrix is not
// positive definite (the Newton solver's exact-Hessian iterations fall back
// to the projected Hessian on it).
class NotPositiveDefinite : public SolverError {
 public:
  using SolverError::SolverError;
};
// Newton stopped without converging: the iteration cap or a stalled line
// search (not a failed check or a linear-solver error). A step that fails so
// with the exact Hessian is redone with the projected one.
class NewtonStalled : public SolverError {
 public:
  using SolverError::SolverError;
};
}  // namespace bfemp
