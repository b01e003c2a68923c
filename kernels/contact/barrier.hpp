#pragma once
// Clamped log barrier of the paper's Eq. 27 in the (unsquared) distance d:
//   b(d) = -kappa (d/dhat - 1)^2 ln(d/dhat)   for 0 < d < dhat,
//   b(d) = 0                                  for d >= dhat,
// with dhat the activation distance (m) and kappa the stiffness (Pa).
// With x = d/dhat (0 < x < 1):
//   b'(d)  = -kappa [ 2 (x - 1) ln(x) / dhat + (x - 1)^2 / d ],
//   b''(d) = -kappa [ 2 ln(x) / dhat^2 + 4 (x - 1) / (dhat d) - (x - 1)^2 / d^2 ].
// b, b' and b'' all vanish as d -> dhat (b is C2 at dhat: b'' -> 0 because
// ln(x) and (x - 1) both vanish there), and b -> +inf as d -> 0.
#include <Kokkos_Core.hpp>
#include <cmath>
#include <limits>

namespace bfemp {

// +inf for d <= 0 (contact or intersection is infeasible).
KOKKOS_INLINE_FUNCTION double barrier(double d, double dhat, double kappa) {
  if (d >= dhat) return 0.0;
  if (!(d > 0)) return std::numeric_limits<double>::infinity();
  const double x = d / dhat, xm1 = x - 1;
  return -kappa * xm1 * xm1 * std::log(x);
}

// db/dd (negative inside (0, dhat): the barrier pushes apart).
KOKKOS_INLINE_FUNCTION double barrier_first_derivative(double d, double dhat, double kappa) {
  if (d >= dhat) return 0.0;
  if (!(d > 0)) return -std::numeric_limits<double>::infinity();
  const double x = d / dhat, xm1 = x - 1;
  return -kappa * (2 * xm1 * std::log(x) / dhat + xm1 * xm1 / d);
}

// d2b/dd2 (positive inside (0, dhat)).
KOKKOS_INLINE_FUNCTION double barrier_second_derivative(double d, double dhat, double kappa) {
  if (d >= dhat) return 0.0;
  if (!(d > 0)) return std::numeric_limits<double>::infinity();
  const double x = d / dhat, xm1 = x - 1;
  return -kappa * (2 * std::log(x) / (dhat * dhat) + 4 * xm1 / (dhat * d) - xm1 * xm1 / (d * d));
}

}  // namespace bfemp
