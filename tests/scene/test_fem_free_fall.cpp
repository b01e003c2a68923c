// Free fall of an unconstrained body: rigid translation leaves F = I, so each
// integrator must follow its exact discrete free-fall recurrence, and converge
// to g t^2 / 2 (backward Euler at first order; mid-point Newmark is exact).
#include <gtest/gtest.h>

#include "common/fem_fixtures.hpp"

using namespace bfemp;
using namespace bfemp::fixtures;

namespace {

constexpr double g = -9.81;

// Centre-of-mass drop after n steps of the simulation.
double simulated_drop(const TimeIntegrator& ti, double dt, int n, double* recurrence) {
  auto s = block_setup<2>(0.25);
  s.integrator = ti;
  s.gravity = {0.0, g, 0.0};
  s.dt = dt;
  Simulation<2> sim(s, comm());
  auto mass = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mesh().node_mass);
  auto x0 = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.positions());
  const double y0 = mass_mean<2>(x0, mass, 1);
  // Exact discrete recurrence of the Newmark family with a^0 = g.
  double y = 0, v = 0, a = g;
  const double h = ti.potential_scale(dt), ca = ti.predictor_acc_scale(dt);
  for (int k = 0; k < n; ++k) {
    const StepReport r = sim.step();
    EXPECT_GT(r.min_J, 0.999999);
    const double yhat = y + dt * v + ca * a;
    const double y1 = yhat + h * g;
    const double a1 = g;
    v += dt * ((1 - ti.gamma) * a + ti.gamma * a1);
    y = y1;
    a = a1;
  }
  *recurrence = y;
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.positions());
  return mass_mean<2>(x, mass, 1) - y0;
}

}  // namespace

TEST(FemFreeFall, BackwardEulerFollowsRecurrenceAndConvergesFirstOrder) {
  const double T = 0.2;
  double err_prev = 0;
  for (int level = 0; level < 3; ++level) {
    const int n = 5 << level;
    const double dt = T / n;
    double rec = 0;
    const double drop = simulated_drop(TimeIntegrator::backward_euler(), dt, n, &rec);
    EXPECT_NEAR(drop, rec, 1e-10 * std::abs(rec)) << "dt " << dt;
    // Backward Euler: y_n = g dt^2 n (n+1) / 2.
    EXPECT_NEAR(rec, g * dt * dt * n * (n + 1) / 2.0, 1e-12);
    const double err = std::abs(drop - 0.5 * g * T * T);
    if (level > 0) {
      EXPECT_NEAR(err_prev / err, 2.0, 0.1) << "first order: error halves with dt";
    }
    err_prev = err;
  }
}

TEST(FemFreeFall, NewmarkFollowsRecurrenceAndIsExactForConstantGravity) {
  const double T = 0.2;
  for (int level = 0; level < 3; ++level) {
    const int n = 5 << level;
    double rec = 0;
    const double drop = simulated_drop(TimeIntegrator::newmark(), T / n, n, &rec);
    EXPECT_NEAR(drop, rec, 1e-10 * std::abs(rec));
    // Mid-point Newmark integrates constant acceleration exactly: the error
    // against g t^2 / 2 is at round-off at every dt (beyond second order).
    EXPECT_NEAR(drop, 0.5 * g * T * T, 1e-10);
  }
}
