#pragma once
// A random rotation (orthogonal, det +1) of size dim: the Q of a Gaussian
// matrix's QR, its first column flipped when det Q = -1.
#include <Eigen/QR>
#include <random>

#include "core/types.hpp"

namespace bfemp::testing {

template <int dim>
Mat<dim> random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Mat<dim> M;
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j) M(i, j) = g(rng);
  Eigen::HouseholderQR<Mat<dim>> qr(M);
  Mat<dim> Q = qr.householderQ();
  if (Q.determinant() < 0) Q.col(0) *= -1.0;
  return Q;
}

}  // namespace bfemp::testing
