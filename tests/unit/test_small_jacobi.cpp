// The fixed-size Jacobi methods of materials/small_jacobi.hpp against
// independent references:
// - jacobi_svd: F = U diag(s) V^T to round-off, U and V orthogonal with
//   det +1, and each singular value within 1e-14 s_max of the ones F was
//   built from (backward stable), also at s_min / s_max = 1e-8 .. 1e-12, where an
//   F^T F eigensolve loses every digit of s_min; repeated singular values, a diagonal
//   F and a permuted one (columns already orthogonal: no rotation), equal
//   column norms (the 45-degree rotation), scales from 1e-150 to 1e150, and
//   at most 6 sweeps everywhere.
// - jacobi_symmetric_eigen: A = W diag(lambda) W^T, W orthogonal, and the
//   eigenvalues equal to long-double characteristic roots of known spectra,
//   indefinite and with repeated eigenvalues.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <Eigen/SVD>
#include <random>

#include "materials/small_jacobi.hpp"
#include "common/random_rotation.hpp"

namespace {

using namespace bfemp;

using bfemp::testing::random_rotation;

template <int dim>
void sorted(Vec<dim>& v) {
  std::sort(v.data(), v.data() + dim);
}

// Checks the SVD of F = R1 diag(s_true) R2 (R1, R2 rotations).
template <int dim>
void check_svd(const Mat<dim>& F, Vec<dim> s_true, const char* what) {
  Mat<dim> U, V;
  Vec<dim> s;
  const int sweeps = jacobi_svd<dim>(F, U, s, V);
  // Quadratic convergence: a slow variant (a wrong angle, a stale norm)
  // would still end orthogonal, at the cap.
  EXPECT_LE(sweeps, 6) << what;
  const Mat<dim> I = Mat<dim>::Identity();
  EXPECT_LT((U.transpose() * U - I).norm(), 1e-14) << what;
  EXPECT_LT((V.transpose() * V - I).norm(), 1e-14) << what;
  EXPECT_NEAR(U.determinant(), 1.0, 1e-14) << what;
  EXPECT_NEAR(V.determinant(), 1.0, 1e-14) << what;
  EXPECT_LT((U * s.asDiagonal() * V.transpose() - F).norm(), 1e-14 * F.norm()) << what;
  sorted<dim>(s);
  sorted<dim>(s_true);
  // Building F rounds it by about eps |F| too: the bound is on s_max.
  for (int i = 0; i < dim; ++i)
    EXPECT_LE(std::fabs(s(i) - s_true(i)), 1e-14 * s_true(dim - 1)) << what << ", singular value " << i;
}

template <int dim>
void svd_families() {
  std::mt19937 rng(5 + dim);
  std::uniform_real_distribution<double> logu(std::log(0.05), std::log(20.0));
  for (int t = 0; t < 500; ++t) {
    Vec<dim> s;
    for (int i = 0; i < dim; ++i) s(i) = std::exp(logu(rng));
    if (t % 5 == 1) s(1) = s(0);               // two equal
    if (t % 5 == 2) s.setConstant(s(0));       // all equal
    if (t % 5 == 3) s(dim - 1) = std::pow(10.0, -8 - t % 3 * 2) * s(0);  // near-inverted: 1e-8, 1e-10, 1e-12
    const Mat<dim> F = random_rotation<dim>(rng) * s.asDiagonal() * random_rotation<dim>(rng);
    check_svd<dim>(F, s, "random");
  }
  // Diagonal (no rotation), and columns already orthogonal but permuted.
  Vec<dim> s;
  for (int i = 0; i < dim; ++i) s(i) = 1.0 + i;
  check_svd<dim>(Mat<dim>(s.asDiagonal()), s, "diagonal");
  Mat<dim> P = Mat<dim>::Zero();
  for (int i = 0; i < dim; ++i) P((i + 1) % dim, i) = s(i);
  if (P.determinant() < 0) P.col(0) *= -1.0;
  check_svd<dim>(P, s, "permutation");
  // Equal column norms, not orthogonal: zeta = 0, the 45-degree rotation.
  Mat<dim> E = Mat<dim>::Identity();
  E(0, 1) = 0.6;
  E(1, 1) = 0.8;
  const Eigen::JacobiSVD<Mat<dim>> ref(E);
  check_svd<dim>(E, ref.singularValues(), "45 degrees");
  // Extreme scales.
  for (double scale : {1e-150, 1e150}) {
    const Vec<dim> ss = scale * s;
    check_svd<dim>(random_rotation<dim>(rng) * ss.asDiagonal() * random_rotation<dim>(rng), ss, "scaled");
  }
}

TEST(SmallJacobi, Svd2D) { svd_families<2>(); }
TEST(SmallJacobi, Svd3D) { svd_families<3>(); }

template <int dim>
void eigen_families() {
  std::mt19937 rng(17 + dim);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  double worst = 0;
  for (int t = 0; t < 500; ++t) {
    Vec<dim> lam;
    for (int i = 0; i < dim; ++i) lam(i) = u(rng);
    if (t % 4 == 1) lam(1) = lam(0);
    if (t % 4 == 2) lam.setConstant(lam(0));
    if (t % 4 == 3) lam(0) = 0.0;  // singular
    const Mat<dim> R = random_rotation<dim>(rng);
    const Mat<dim> A = R * lam.asDiagonal() * R.transpose();
    Vec<dim> got;
    Mat<dim> W;
    EXPECT_LE(jacobi_symmetric_eigen<dim>(A, got, W), 6);
    EXPECT_LT((W.transpose() * W - Mat<dim>::Identity()).norm(), 1e-14);
    EXPECT_LT((W * got.asDiagonal() * W.transpose() - A).norm(), 1e-14 * A.norm() + 1e-300);
    sorted<dim>(got);
    sorted<dim>(lam);
    // Eigenvalues are perturbed by at most |A| eps (Weyl), plus the rounding
    // in building A.
    for (int i = 0; i < dim; ++i) worst = std::max(worst, std::fabs(got(i) - lam(i)) / std::max(A.norm(), 1e-300));
  }
  EXPECT_LT(worst, 1e-14);
}

TEST(SmallJacobi, SymmetricEigen2D) { eigen_families<2>(); }
TEST(SmallJacobi, SymmetricEigen3D) { eigen_families<3>(); }

TEST(SmallJacobi, TangentOverflowSafe) {
  // zeta beyond 1e150: t = 1 / (2 zeta) instead of overflowing zeta^2.
  EXPECT_DOUBLE_EQ(jacobi_tangent(1e200), 0.5e-200);
  EXPECT_DOUBLE_EQ(jacobi_tangent(-1e200), -0.5e-200);
  EXPECT_DOUBLE_EQ(jacobi_tangent(0.0), 1.0);
  // t solves t^2 + 2 zeta t - 1 = 0 (the rotation that zeroes the entry).
  for (double z : {-7.5, -0.3, 0.01, 2.0, 1e6}) {
    const double t = jacobi_tangent(z);
    EXPECT_NEAR(t * t + 2 * z * t - 1.0, 0.0, 1e-15 * (1 + std::fabs(z * t))) << z;
    EXPECT_LE(std::fabs(t), 1.0) << z;
  }
}

TEST(SmallJacobi, CholeskyDefiniteness) {
  EXPECT_TRUE(cholesky_positive_definite<3>(Mat<3>::Identity()));
  Mat<3> A = Mat<3>::Identity();
  A(2, 2) = 0.0;  // PSD, singular: not definite
  EXPECT_FALSE(cholesky_positive_definite<3>(A));
  A(2, 2) = -1e-12;
  EXPECT_FALSE(cholesky_positive_definite<3>(A));
  Mat<2> B;
  B << 1.0, 2.0, 2.0, 1.0;  // eigenvalues 3, -1
  EXPECT_FALSE(cholesky_positive_definite<2>(B));
  B(0, 1) = B(1, 0) = 0.9;
  EXPECT_TRUE(cholesky_positive_definite<2>(B));
}

}  // namespace
