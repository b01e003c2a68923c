// Clamped log barrier (kernels/contact/barrier.hpp, paper Eq. 27): value and
// derivatives against central finite differences over (0, dhat), C2 clamping
// at dhat, blow-up at 0, infeasible d <= 0, kappa scaling.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "kernels/contact/barrier.hpp"

namespace {

using namespace bfemp;

TEST(ContactBarrier, MatchesEquation27) {
  const double dhat = 1e-3, kappa = 2.5e4;
  for (double x : {0.01, 0.3, 0.5, 0.99}) {
    const double d = x * dhat;
    EXPECT_NEAR(barrier(d, dhat, kappa), -kappa * (x - 1) * (x - 1) * std::log(x),
                1e-15 * kappa * std::abs(std::log(x)));
    EXPECT_GT(barrier(d, dhat, kappa), 0.0);
    EXPECT_LT(barrier_first_derivative(d, dhat, kappa), 0.0);
    EXPECT_GT(barrier_second_derivative(d, dhat, kappa), 0.0);
  }
}

// Central differences with a step relative to the distance to the nearest
// end of (0, dhat), for several dhat scales.
TEST(ContactBarrier, DerivativesMatchFiniteDifferences) {
  double worst1 = 0, worst2 = 0;
  for (double dhat : {1e-4, 1e-2, 1.0, 3.0}) {
    const double kappa = 1e5;
    for (int i = 1; i < 200; ++i) {
      const double d = dhat * i / 200.0;
      const double h = 1e-6 * std::min(d, dhat - d);
      const double fd1 = (barrier(d + h, dhat, kappa) - barrier(d - h, dhat, kappa)) / (2 * h);
      const double fd2 =
          (barrier_first_derivative(d + h, dhat, kappa) - barrier_first_derivative(d - h, dhat, kappa)) / (2 * h);
      const double b1 = barrier_first_derivative(d, dhat, kappa), b2 = barrier_second_derivative(d, dhat, kappa);
      const double e1 = std::abs(b1 - fd1) / std::abs(b1), e2 = std::abs(b2 - fd2) / std::abs(b2);
      worst1 = std::max(worst1, e1);
      worst2 = std::max(worst2, e2);
      EXPECT_LT(e1, 1e-6) << "dhat " << dhat << " d " << d;
      EXPECT_LT(e2, 1e-6) << "dhat " << dhat << " d " << d;
    }
  }
  std::printf("barrier: worst relative FD error b' %.2e, b'' %.2e\n", worst1, worst2);
}

// b, b', b'' -> 0 as d -> dhat from below (C2 clamping) and are exactly 0 at
// and beyond dhat. Near dhat: b ~ kappa (1-x)^3, b' ~ -3 kappa (1-x)^2 / dhat,
// b'' ~ 6 kappa (1-x) / dhat^2.
TEST(ContactBarrier, SmoothClampingAtDhat) {
  const double dhat = 1e-3, kappa = 1e5;
  for (double d : {dhat, 1.5 * dhat, 100 * dhat}) {
    EXPECT_EQ(barrier(d, dhat, kappa), 0.0);
    EXPECT_EQ(barrier_first_derivative(d, dhat, kappa), 0.0);
    EXPECT_EQ(barrier_second_derivative(d, dhat, kappa), 0.0);
  }
  for (double eps : {1e-2, 1e-3, 1e-4}) {
    const double d = (1 - eps) * dhat;
    EXPECT_NEAR(barrier(d, dhat, kappa) / (kappa * eps * eps * eps), 1.0, 2 * eps);
    EXPECT_NEAR(barrier_first_derivative(d, dhat, kappa) / (-3 * kappa * eps * eps / dhat), 1.0, 2 * eps);
    EXPECT_NEAR(barrier_second_derivative(d, dhat, kappa) / (6 * kappa * eps / (dhat * dhat)), 1.0, 2 * eps);
  }
}

TEST(ContactBarrier, BlowsUpAtZero) {
  const double dhat = 1e-2, kappa = 1.0;
  double prev = 0, prev1 = 0;
  for (double x = 1e-1; x > 1e-300; x *= 1e-3) {
    const double b = barrier(x * dhat, dhat, kappa), b1 = barrier_first_derivative(x * dhat, dhat, kappa);
    EXPECT_GT(b, prev);
    EXPECT_LT(b1, prev1);
    EXPECT_TRUE(std::isfinite(b) && std::isfinite(b1));
    prev = b;
    prev1 = b1;
  }
  EXPECT_GT(barrier(1e-300, dhat, kappa), 600.0);  // ~ -ln(1e-298)
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(barrier(0.0, dhat, kappa), inf);
  EXPECT_EQ(barrier(-1e-3, dhat, kappa), inf);
  EXPECT_EQ(barrier_first_derivative(0.0, dhat, kappa), -inf);
  EXPECT_EQ(barrier_second_derivative(0.0, dhat, kappa), inf);
}

TEST(ContactBarrier, LinearInKappa) {
  const double dhat = 2e-3;
  for (double d : {1e-5, 7e-4, 1.9e-3}) {
    EXPECT_NEAR(barrier(d, dhat, 3e6), 3e6 * barrier(d, dhat, 1.0), 1e-12 * barrier(d, dhat, 3e6));
    EXPECT_NEAR(barrier_first_derivative(d, dhat, 3e6), 3e6 * barrier_first_derivative(d, dhat, 1.0),
                1e-12 * std::abs(barrier_first_derivative(d, dhat, 3e6)));
    EXPECT_NEAR(barrier_second_derivative(d, dhat, 3e6), 3e6 * barrier_second_derivative(d, dhat, 1.0),
                1e-12 * barrier_second_derivative(d, dhat, 3e6));
    EXPECT_EQ(barrier(d, dhat, 0.0), 0.0);
  }
}

}  // namespace
