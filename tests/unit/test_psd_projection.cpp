// project_psd: symmetric PSD result, untouched PSD input, kept positive
// eigenpairs, and Frobenius-optimality against random PSD competitors.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <type_traits>

#include "materials/psd_projection.hpp"

namespace {

using namespace bfemp;

template <int n>
SquareMat<n> random_symmetric(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  SquareMat<n> A;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i <= j; ++i) A(i, j) = A(j, i) = g(rng);
  return A;
}

template <int n>
SquareMat<n> random_psd(std::mt19937& rng, int rank) {
  std::normal_distribution<double> g(0.0, 1.0);
  SquareMat<n> Q = SquareMat<n>::Zero();
  for (int r = 0; r < rank; ++r) {
    Eigen::Matrix<double, n, 1> v;
    for (int i = 0; i < n; ++i) v(i) = g(rng);
    Q += v * v.transpose();
  }
  return 0.5 * (Q + Q.transpose());
}

template <class T>
class PsdProjectionTest : public ::testing::Test {};
using Sizes = ::testing::Types<std::integral_constant<int, 4>, std::integral_constant<int, 9>,
                               std::integral_constant<int, 12>>;
TYPED_TEST_SUITE(PsdProjectionTest, Sizes);

TYPED_TEST(PsdProjectionTest, ResultIsSymmetricPsd) {
  constexpr int n = TypeParam::value;
  std::mt19937 rng(1 + n);
  for (int t = 0; t < 50; ++t) {
    SquareMat<n> A = random_symmetric<n>(rng);
    project_psd<n>(A);
    EXPECT_TRUE((A.array() == A.transpose().array()).all());
    Eigen::SelfAdjointEigenSolver<SquareMat<n>> es(A);
    EXPECT_GE(es.eigenvalues()(0), -1e-12 * A.norm());
  }
}

TYPED_TEST(PsdProjectionTest, PsdInputIsBitwiseUnchanged) {
  constexpr int n = TypeParam::value;
  std::mt19937 rng(2 + n);
  for (int t = 0; t < 20; ++t) {
    SquareMat<n> A = random_psd<n>(rng, n) + 0.1 * SquareMat<n>::Identity();
    const SquareMat<n> before = A;
    project_psd<n>(A);
    EXPECT_TRUE((A.array() == before.array()).all());
  }
  SquareMat<n> D = SquareMat<n>::Zero();  // diagonal, with exact zeros
  for (int i = 0; i < n; i += 2) D(i, i) = 1.0 + i;
  const SquareMat<n> before = D;
  project_psd<n>(D);
  EXPECT_TRUE((D.array() == before.array()).all());
}

TYPED_TEST(PsdProjectionTest, KeepsPositiveEigenpairsAndZeroesNegativeOnes) {
  constexpr int n = TypeParam::value;
  std::mt19937 rng(3 + n);
  for (int t = 0; t < 20; ++t) {
    const SquareMat<n> A = random_symmetric<n>(rng);
    Eigen::SelfAdjointEigenSolver<SquareMat<n>> es(A);
    SquareMat<n> P = A;
    project_psd<n>(P);
    const double tol = 1e-12 * A.norm();
    double removed = 0.0;
    for (int k = 0; k < n; ++k) {
      const double lam = es.eigenvalues()(k);
      const Eigen::Matrix<double, n, 1> v = es.eigenvectors().col(k);
      if (lam > 0.0) EXPECT_LE((P * v - lam * v).norm(), tol);
      else { EXPECT_LE((P * v).norm(), tol); removed += lam * lam; }
    }
    // ||A - P||_F^2 = sum of the squared negative eigenvalues.
    EXPECT_NEAR((A - P).squaredNorm(), removed, 1e-12 * A.squaredNorm());
  }
}

// Partial projection (Newton/fallback keep): each negative eigenvalue is
// scaled by keep, positive eigenpairs stay; keep 0 is the projection bit for
// bit, and A(keep) is monotone in keep (A(0) - A(keep) PSD, A(keep) - A PSD).
TYPED_TEST(PsdProjectionTest, PartialProjectionScalesNegativeEigenvalues) {
  constexpr int n = TypeParam::value;
  std::mt19937 rng(11 + n);
  for (int t = 0; t < 20; ++t) {
    const SquareMat<n> A = random_symmetric<n>(rng);
    Eigen::SelfAdjointEigenSolver<SquareMat<n>> es(A);
    const double tol = 1e-12 * A.norm();
    SquareMat<n> P0 = A, Pz = A;
    project_psd<n>(P0);
    project_psd<n>(Pz, 0.0);
    EXPECT_EQ((P0 - Pz).cwiseAbs().maxCoeff(), 0.0) << "keep 0 must be the projection itself";
    SquareMat<n> prev = P0;
    for (const double keep : {0.3, 0.7}) {
      SquareMat<n> P = A;
      project_psd<n>(P, keep);
      for (int k = 0; k < n; ++k) {
        const double lam = es.eigenvalues()(k);
        const Eigen::Matrix<double, n, 1> v = es.eigenvectors().col(k);
        EXPECT_LE((P * v - (lam > 0.0 ? lam : keep * lam) * v).norm(), tol) << "keep " << keep << ", k " << k;
      }
      // Less stiff than the stronger projection, stiffer than A.
      Eigen::SelfAdjointEigenSolver<SquareMat<n>> d1(prev - P), d2(P - A);
      EXPECT_GE(d1.eigenvalues()(0), -tol);
      EXPECT_GE(d2.eigenvalues()(0), -tol);
      prev = P;
    }
  }
}

TYPED_TEST(PsdProjectionTest, IsNearestPsdMatrixInFrobeniusNorm) {
  constexpr int n = TypeParam::value;
  std::mt19937 rng(4 + n);
  for (int t = 0; t < 20; ++t) {
    const SquareMat<n> A = random_symmetric<n>(rng);
    SquareMat<n> P = A;
    project_psd<n>(P);
    const double dist = (A - P).norm();
    for (int c = 0; c < 10; ++c) {
      // Competitors: P plus a small PSD perturbation (still PSD), and an
      // unrelated random PSD matrix.
      const double s = std::ldexp(1.0, -c);
      const SquareMat<n> Q1 = P + s * random_psd<n>(rng, 1 + c % n);
      const SquareMat<n> Q2 = random_psd<n>(rng, n) * (0.1 * s);
      EXPECT_LE(dist, (A - Q1).norm() * (1.0 + 1e-14));
      EXPECT_LE(dist, (A - Q2).norm() * (1.0 + 1e-14));
    }
  }
}

TEST(PsdProjection, KnownSmallCases) {
  SquareMat<2> A;
  A << 1.0, 0.0, 0.0, -1.0;
  project_psd<2>(A);
  EXPECT_NEAR((A - (SquareMat<2>() << 1.0, 0.0, 0.0, 0.0).finished()).norm(), 0.0, 1e-15);
  // Non-symmetric input is symmetrized first: [[0, 2], [0, 0]] -> sym [[0,1],[1,0]],
  // eigenvalues +-1, projection 0.5 [[1, 1], [1, 1]].
  SquareMat<2> B;
  B << 0.0, 2.0, 0.0, 0.0;
  project_psd<2>(B);
  EXPECT_NEAR((B - SquareMat<2>::Constant(0.5)).norm(), 0.0, 1e-15);
  // Negative definite -> zero.
  SquareMat<4> N = -SquareMat<4>::Identity();
  project_psd<4>(N);
  EXPECT_EQ(N.norm(), 0.0);
}

}  // namespace
