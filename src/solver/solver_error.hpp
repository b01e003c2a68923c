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
}  // namespace bfemp
