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
}  // namespace bfemp
