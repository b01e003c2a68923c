#pragma once
// Lame parameters of an isotropic elastic material and their conversion from
// Young's modulus and Poisson's ratio (3D / plane-strain formulas).
#include "core/types.hpp"

namespace bfemp {

struct LameParameters {
  double mu = 0.0;      // shear modulus
  double lambda = 0.0;  // first Lame parameter
};

// mu = E / (2 (1 + nu)),  lambda = E nu / ((1 + nu)(1 - 2 nu)).
// Valid for -1 < nu < 1/2 (lambda diverges as nu -> 1/2).
KOKKOS_INLINE_FUNCTION LameParameters lame_from_young(double E, double nu) {
  LameParameters p;
  p.mu = E / (2.0 * (1.0 + nu));
  p.lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  return p;
}

}  // namespace bfemp
