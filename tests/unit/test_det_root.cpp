// smallest_positive_det_root: exactly known roots (2D quadratic, 3D cubic),
// degenerate leading coefficients, double/triple roots, tangency, element
// inversion, scale invariance and random cases against an eigenvalue reference
// and extended-precision sampling.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <random>

#include "kernels/fem/det_root.hpp"

namespace {

using namespace bfemp;
constexpr double kInf = std::numeric_limits<double>::infinity();

template <int dim>
Mat<dim> diag(double a, double b, double c = 0.0) {
  Mat<dim> M = Mat<dim>::Zero();
  M(0, 0) = a;
  M(1, 1) = b;
  if constexpr (dim == 3) M(2, 2) = c;
  return M;
}

template <int dim>
Mat<dim> random_matrix(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Mat<dim> A;
  for (int j = 0; j < dim; ++j)
    for (int i = 0; i < dim; ++i) A(i, j) = u(rng);
  return A;
}

// det(T + a dT) in extended precision (reference sign tests).
template <int dim>
long double det_ld(const Mat<dim>& T, const Mat<dim>& dT, long double a) {
  long double M[3][3];
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j) M[i][j] = (long double)T(i, j) + a * (long double)dT(i, j);
  if constexpr (dim == 2) return M[0][0] * M[1][1] - M[0][1] * M[1][0];
  return M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) -
         M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
         M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]);
}

// Returned alpha must lie in [root (1 - below), root (1 + 1e-10)].
void expect_root(double alpha, double root, double below = 1e-12) {
  EXPECT_LE(alpha, root * (1.0 + 1e-10)) << "root " << root;
  EXPECT_GE(alpha, root * (1.0 - below)) << "root " << root;
}

template <class T>
class DetRootTest : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(DetRootTest, Dims);

TYPED_TEST(DetRootTest, DiagonalCases) {
  constexpr int d = TypeParam::value;
  const Mat<d> I = Mat<d>::Identity();
  expect_root(smallest_positive_det_root<d>(I, -diag<d>(2, 1, 1)), 0.5);
  expect_root(smallest_positive_det_root<d>(diag<d>(1, 2, 3), -I), 1.0);
  expect_root(smallest_positive_det_root<d>(diag<d>(3, 2, 1), -diag<d>(1, 1, 4)), d == 2 ? 2.0 : 0.25);
  EXPECT_EQ(smallest_positive_det_root<d>(I, I), kInf);                   // expansion
  EXPECT_EQ(smallest_positive_det_root<d>(I, Mat<d>::Zero()), kInf);      // no motion
  expect_root(smallest_positive_det_root<d>(I, diag<d>(1, -1, 0)), 1.0);   // (1 + a)(1 - a)
}

TYPED_TEST(DetRootTest, ShearNeverInverts) {
  constexpr int d = TypeParam::value;
  Mat<d> S = Mat<d>::Zero();
  S(0, d - 1) = 5.0;  // nilpotent: det(I + a S) = 1 for all a
  EXPECT_EQ(smallest_positive_det_root<d>(Mat<d>::Identity(), S), kInf);
  EXPECT_EQ(smallest_positive_det_root<d>(Mat<d>::Identity(), -S), kInf);
}

TYPED_TEST(DetRootTest, ScaledStepMultipleRoot) {
  constexpr int d = TypeParam::value;
  std::mt19937 rng(11);
  expect_root(smallest_positive_det_root<d>(Mat<d>::Identity(), -Mat<d>::Identity()), 1.0);
  for (int t = 0; t < 50; ++t) {
    Mat<d> T = random_matrix<d>(rng);
    if (T.determinant() < 0) T.col(0) *= -1.0;
    // dT = -2T: det(T + a dT) = (1 - 2a)^d det T, root 0.5 of multiplicity d.
    expect_root(smallest_positive_det_root<d>(T, -2.0 * T), 0.5);
    // Inexact scaling: root 0.7 up to the rounding of dT.
    expect_root(smallest_positive_det_root<d>(T, T / -0.7), 0.7, 1e-9);
  }
}

TYPED_TEST(DetRootTest, RankOneStep) {
  constexpr int d = TypeParam::value;
  std::mt19937 rng(12);
  int found = 0;
  for (int t = 0; t < 100; ++t) {
    Mat<d> T = random_matrix<d>(rng) + 2.0 * Mat<d>::Identity();
    if (T.determinant() <= 0) continue;
    const Vec<d> u = random_matrix<d>(rng).col(0), v = random_matrix<d>(rng).col(1);
    // det(T + a u v^T) = det T (1 + a v^T T^{-1} u): linear in a.
    const double s = v.dot(T.partialPivLu().solve(u));
    const double alpha = smallest_positive_det_root<d>(T, u * v.transpose());
    if (s < 0) { expect_root(alpha, -1.0 / s, 1e-10); ++found; }
    else EXPECT_EQ(alpha, kInf);
  }
  EXPECT_GT(found, 10);
}

TYPED_TEST(DetRootTest, TangentDoubleRoot) {
  constexpr int d = TypeParam::value;
  // Exact data: det(I + a D) = (1 - a)^2 (1 + 2a in 3D), touching zero at 1
  // without a sign change; D is a Jordan block on the first two axes.
  Mat<d> D = diag<d>(-1, -1, 2);
  D(0, 1) = 3.0;
  expect_root(smallest_positive_det_root<d>(Mat<d>::Identity(), D), 1.0);
  // Near-tangency: det(I + a D) = 1 - 2a + (1 -+ 1e-6) a^2.
  Mat<d> Dhit = diag<d>(-1, -1, 0), Dmiss = Dhit;
  Dhit(0, 1) = 1.0;  Dhit(1, 0) = 1e-6;    // two roots (1 -+ 1e-3) / (1 - 1e-6)
  Dmiss(0, 1) = 1.0; Dmiss(1, 0) = -1e-6;  // minimum 1e-6 / (1 + 1e-6) > 0
  expect_root(smallest_positive_det_root<d>(Mat<d>::Identity(), Dhit), (1.0 - 1e-3) / (1.0 - 1e-6));
  EXPECT_EQ(smallest_positive_det_root<d>(Mat<d>::Identity(), Dmiss), kInf);
  // Tangency through inexact data: T = A B, dT = A diag(-1, -1, 0.5) B. Rounding
  // moves the double root by ~sqrt(u); the answer must stay conservative.
  std::mt19937 rng(13);
  for (int t = 0; t < 50; ++t) {
    Mat<d> A = random_matrix<d>(rng) + 2.0 * Mat<d>::Identity();
    const Mat<d> B = random_matrix<d>(rng) + 2.0 * Mat<d>::Identity();
    if (A.determinant() * B.determinant() < 0) A.col(0) *= -1.0;
    const Mat<d> T = A * B, dT = A * diag<d>(-1, -1, 0.5) * B;
    const double alpha = smallest_positive_det_root<d>(T, dT);
    EXPECT_LE(alpha, 1.0 + 1e-7);
    EXPECT_GE(alpha, 1.0 - 1e-6);
  }
}

TYPED_TEST(DetRootTest, InvertingElementStep) {
  constexpr int d = TypeParam::value;
  // Last vertex moves through the opposite facet (the plane x_{d-1} = 0 of
  // the other vertices); only its own edge column changes.
  Mat<d> T = Mat<d>::Identity();
  Mat<d> dT = Mat<d>::Zero();
  if constexpr (d == 2) { T.col(1) << 0.3, 1.0; dT.col(1) << 0.2, -3.0; }   // crosses at 1/3
  else { T.col(2) << 0.2, 0.3, 1.0; dT.col(2) << 0.1, 0.1, -2.5; }         // crosses at 0.4
  expect_root(smallest_positive_det_root<d>(T, dT), d == 2 ? 1.0 / 3.0 : 0.4);
  // The same element scaled to a millimetre mesh with a micrometre-sized step.
  expect_root(smallest_positive_det_root<d>(1e-3 * T, 1e-9 * dT), (d == 2 ? 1.0 / 3.0 : 0.4) * 1e6, 1e-12);
}

TYPED_TEST(DetRootTest, DegenerateLeadingCoefficients) {
  constexpr int d = TypeParam::value;
  const Mat<d> I = Mat<d>::Identity();
  // Tiny leading coefficient: det = (1 - a)(1 - 1e-9 a)^(d-1), root 1.
  expect_root(smallest_positive_det_root<d>(I, -diag<d>(1, 1e-9, 1e-9)), 1.0);
  // Huge roots: det = (1 - 1e-12 a)^d.
  expect_root(smallest_positive_det_root<d>(I, -1e-12 * I), 1e12);
  // Inexact rank-1 dT = u v^T (det dT and the mixed terms are rounding noise):
  // det(I + a u v^T) = 1 + a v.u. The rounded u v^T is not exactly rank 1,
  // and at these large steps (|v.u| small, roots up to ~100) the certified
  // answer may sit up to ~1e-10 below -1/(v.u); it must never be above.
  std::mt19937 rng(14);
  for (int t = 0; t < 50; ++t) {
    const Vec<d> u = random_matrix<d>(rng).col(0);
    Vec<d> v;
    for (int j = 0; j < d; ++j) v(j) = 0.1 * (j + 1) + 0.3;
    const Mat<d> dT = u * v.transpose();
    const double s = v.dot(u);
    const double alpha = smallest_positive_det_root<d>(I, dT);
    if (s < 0) expect_root(alpha, -1.0 / s, 1e-9);
    else EXPECT_EQ(alpha, kInf);
  }
  // Inverted or degenerate start: 0.
  EXPECT_EQ(smallest_positive_det_root<d>(diag<d>(-1, 1, 1), I), 0.0);
  EXPECT_EQ(smallest_positive_det_root<d>(Mat<d>::Zero(), I), 0.0);
}

TYPED_TEST(DetRootTest, RandomAgainstEigenvaluesAndSampling) {
  constexpr int d = TypeParam::value;
  std::mt19937 rng(15);
  int finite = 0;
  for (int t = 0; t < 300; ++t) {
    Mat<d> T = random_matrix<d>(rng);
    if (std::abs(T.determinant()) < 1e-2) continue;
    if (T.determinant() < 0) T.col(0) *= -1.0;
    const Mat<d> dT = 3.0 * random_matrix<d>(rng);
    const double alpha = smallest_positive_det_root<d>(T, dT);
    // Reference: the roots are a = -1/mu for the real eigenvalues mu < 0 of T^{-1} dT.
    Eigen::EigenSolver<Mat<d>> es(T.inverse() * dT);
    double ref = kInf;
    for (int k = 0; k < d; ++k) {
      const auto mu = es.eigenvalues()(k);
      if (std::abs(mu.imag()) <= 1e-12 * std::abs(mu) && mu.real() < 0) ref = std::fmin(ref, -1.0 / mu.real());
    }
    if (ref == kInf) { EXPECT_EQ(alpha, kInf); continue; }
    ++finite;
    EXPECT_NEAR(alpha, ref, 1e-8 * ref);
    // Extended precision: no sign change before alpha, crossing just after.
    long double scale = 1.0L;  // Hadamard bound of |T| + alpha |dT|
    for (int j = 0; j < d; ++j) scale *= (T.col(j).cwiseAbs() + alpha * dT.col(j).cwiseAbs()).norm();
    for (int s = 0; s <= 1000; ++s)
      EXPECT_GT(det_ld<d>(T, dT, alpha * (s / 1000.0L)), -1e-15L * scale);
    EXPECT_LT(det_ld<d>(T, dT, alpha * (1.0L + 1e-7L)), 0.0L);
  }
  EXPECT_GT(finite, 50);
}

// With a cap: the uncapped answer when the root lies below the cap, inf when
// it lies beyond (certified positive on [0, cap]); never inf for a root the
// cap covers. Caps near each random root, below and above it, and on the
// exactly known cases.
TYPED_TEST(DetRootTest, CapReturnsTheRootBelowItAndInfBeyond) {
  constexpr int d = TypeParam::value;
  std::mt19937 rng(16);
  int below = 0, beyond = 0;
  for (int t = 0; t < 300; ++t) {
    Mat<d> T = random_matrix<d>(rng);
    if (std::abs(T.determinant()) < 1e-2) continue;
    if (T.determinant() < 0) T.col(0) *= -1.0;
    const Mat<d> dT = 3.0 * random_matrix<d>(rng);
    const double root = smallest_positive_det_root<d>(T, dT);
    for (const double f : {0.5, 0.999, 1.001, 2.0}) {
      const double cap = std::isfinite(root) ? f * root : f;
      const double capped = smallest_positive_det_root<d>(T, dT, cap);
      if (std::isfinite(root) && root <= cap) {
        EXPECT_EQ(capped, root) << "cap " << cap;
        ++below;
      } else {
        EXPECT_EQ(capped, kInf) << "root " << root << " cap " << cap;
        ++beyond;
      }
    }
  }
  EXPECT_GT(below, 100);
  EXPECT_GT(beyond, 100);
  const Mat<d> I = Mat<d>::Identity();
  // (1 + a)(1 - a) (2D) or with a third factor 1: root 1.
  expect_root(smallest_positive_det_root<d>(I, diag<d>(1, -1, 0), 1.0 / 0.9), 1.0);
  EXPECT_EQ(smallest_positive_det_root<d>(I, diag<d>(1, -1, 0), 0.9), kInf);
  // Huge root, small cap; a step along -T reaches 0 at exactly 1.
  EXPECT_EQ(smallest_positive_det_root<d>(I, -1e-12 * I, 1.0 / 0.9), kInf);
  expect_root(smallest_positive_det_root<d>(I, -I, 1.0), 1.0);
  // Already inverted: 0 whatever the cap.
  EXPECT_EQ(smallest_positive_det_root<d>(diag<d>(-1, 1, 1), I, 1.0), 0.0);
}

// det_root_detail::positive_up_to, the cheap clearance tried before the
// polynomial: it must never clear a cap at or beyond a root (random T, also
// nearly singular, with steps dT from 1e-6 to 10 times T's size, and steps
// along -T whose root is known exactly), and it must clear most small steps,
// which is what it is for.
TYPED_TEST(DetRootTest, CheapClearanceNeverCoversARootAndServesSmallSteps) {
  constexpr int d = TypeParam::value;
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int cleared = 0, small = 0, small_cleared = 0;
  for (int t = 0; t < 2000; ++t) {
    Mat<d> T = random_matrix<d>(rng);
    if (t % 4 == 1) T.col(1) = T.col(0) + 1e-6 * T.col(1);  // nearly singular
    if (T.determinant() < 0) T.col(0) *= -1.0;
    if (!(T.determinant() > 0)) continue;
    const double s = std::pow(10.0, -6.0 + 7.0 * u(rng));
    const Mat<d> dT = s * random_matrix<d>(rng);
    const double root = smallest_positive_det_root<d>(T, dT);
    for (const double f : {0.25, 0.5, 0.9, 0.999, 1.0, 1.001, 1.5, 2.0, 4.0}) {
      const double cap = std::isfinite(root) ? f * root : f;
      if (!det_root_detail::positive_up_to<d>(T, dT, cap)) continue;
      ++cleared;
      EXPECT_TRUE(!(root <= cap)) << "cleared cap " << cap << " at or beyond the root " << root << " (s " << s << ")";
    }
    if (s < 1e-3 && t % 4 != 1) {
      ++small;
      if (det_root_detail::positive_up_to<d>(T, dT, 1.0 / 0.9)) ++small_cleared;
    }
  }
  EXPECT_GT(cleared, 1000);
  EXPECT_GT(small_cleared, 0.9 * small) << small_cleared << " of " << small;
  // Along -sigma T the root is 1 / sigma exactly and ||T^-1 dT|| = sigma.
  for (const double sigma : {1e-8, 0.3, 1.0, 7.0}) {
    Mat<d> T = diag<d>(1, 2, 3);
    T(0, 1) = 0.7;  // not symmetric: adj(T) and its transpose differ
    T(d - 1, 0) = -0.4;
    const Mat<d> dT = -sigma * T;
    EXPECT_TRUE(det_root_detail::positive_up_to<d>(T, dT, 0.4 / sigma)) << sigma;
    for (const double f : {1.0, 1.5, 1.9, 3.0})
      EXPECT_FALSE(det_root_detail::positive_up_to<d>(T, dT, f / sigma)) << sigma << " cap x " << f;
  }
  // det T zero up to rounding (a column a multiple of another, each entry
  // rounded) and a step of nothing: the computed det T may come out positive
  // while the true one is not, so it is not cleared on det T's sign alone.
  for (int t = 0; t < 200; ++t) {
    Mat<d> T = random_matrix<d>(rng);
    T.col(1) = (0.7 + 0.001 * t) * T.col(0);
    const Mat<d> dT = 1e-30 * random_matrix<d>(rng);
    if (det_root_detail::positive_up_to<d>(T, dT, 1.0)) {
      EXPECT_GT(det_ld<d>(T, dT, 0.0L), 0.0L) << "cleared a singular T, case " << t;
    }
  }
  // Through smallest_positive_det_root, which tries the clearance on raw T
  // and dT and scales them to O(1) for the polynomial: scaling both by
  // 2^+-240 or 2^+-300 changes no answer, and inputs at the edges of the
  // double range are not cleared wrongly (an already inverted T near
  // underflow: det -2^-1080; entries near 1e100 whose products overflow in
  // the unscaled clearance, with a root at 1e-9).
  std::mt19937 rng2(31);
  for (int t = 0; t < 300; ++t) {
    Mat<d> T = random_matrix<d>(rng2);
    if (T.determinant() < 0) T.col(0) *= -1.0;
    const Mat<d> dT = std::pow(10.0, -4.0 + 4.0 * u(rng2)) * random_matrix<d>(rng2);
    const double ref = smallest_positive_det_root<d>(T, dT, 1.0 / 0.9);
    for (const int e : {-300, -240, 240, 300})
      EXPECT_EQ(smallest_positive_det_root<d>(std::ldexp(1.0, e) * T, std::ldexp(1.0, e) * dT, 1.0 / 0.9), ref)
          << "scale 2^" << e << ", case " << t;
  }
  if constexpr (d == 3) {
    Mat<d> T;
    T << 1, 1, -81, 1, -1, 0, 1, 0, -40;  // det -1
    EXPECT_EQ(smallest_positive_det_root<d>(std::ldexp(1.0, -360) * T, std::ldexp(1.0, -380) * Mat<d>::Identity(), 1.0),
              0.0);
    Mat<d> A, B;
    A << 1, 1, 0, -1, 1, 0, 0, 0, 1;
    B << 1, 1, 0, 1, -1, 0, 0, 0, 0;  // det(A + s B) = 2 (1 + s)(1 - s): s = 1e9 a reaches 0 at a = 1e-9
    expect_root(smallest_positive_det_root<d>(1e100 * A, 1e109 * B, 1.0), 1e-9, 1e-6);
    // An inverted T (det -1e201) whose cofactor product T(2,1) T(0,2)
    // overflows while the permanent stays finite: the computed det is +inf.
    Mat<d> O;
    O << 1, 1, 1e200, 1e-200, 1, 10, 1, 1e200, 1;
    EXPECT_FALSE(det_root_detail::positive_up_to<d>(O, Mat<d>::Constant(1e-3), 1.0 / 0.9));
    EXPECT_EQ(smallest_positive_det_root<d>(O, Mat<d>::Constant(1e-3), 1.0 / 0.9), 0.0);
    // An inverted T (det -0.48 2^-774) whose cofactor T(1,1) T(2,2) - T(1,2)
    // T(2,1) is subnormal and rounds to +2^-1073 (true 1.02 2^-1074), then
    // multiplied by T(0,0) = 2^300: the computed det comes out positive.
    Mat<d> U = Mat<d>::Zero();
    U(0, 0) = std::ldexp(1.0, 300);
    U(1, 1) = std::ldexp(1.0, -537), U(2, 2) = std::ldexp(1.51, -537);
    U(1, 2) = std::ldexp(1.0, -537), U(2, 1) = std::ldexp(0.49, -537);
    U(0, 1) = std::ldexp(1.0, -118), U(1, 0) = std::ldexp(0.75 / 1.51, -118);
    EXPECT_LT(det_ld<d>(U, Mat<d>::Zero(), 0.0L), 0.0L);
    EXPECT_FALSE(det_root_detail::positive_up_to<d>(U, Mat<d>::Zero(), 1.0));
    EXPECT_EQ(smallest_positive_det_root<d>(U, Mat<d>::Zero()), 0.0);  // no step: det T's sign alone
    Mat<d> dU = Mat<d>::Zero();
    dU(1, 1) = std::ldexp(1.0, -1074);
    EXPECT_EQ(smallest_positive_det_root<d>(U, dU, std::ldexp(1.0, -260)), 0.0);
  }
  // Not positive, not finite: never cleared.
  EXPECT_FALSE(det_root_detail::positive_up_to<d>(diag<d>(-1, 1, 1), 1e-9 * Mat<d>::Identity(), 1.0));
  EXPECT_FALSE(det_root_detail::positive_up_to<d>(Mat<d>::Identity(), Mat<d>::Constant(NAN), 1.0));
}

}  // namespace
