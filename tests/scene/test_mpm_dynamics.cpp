// Implicit MPM on the Newton solver: free fall follows the integrators' exact
// discrete recurrences (no spurious transfer forces), linear momentum is
// conserved by every transfer scheme, APIC + Newmark keeps the angular
// momentum of a spinning block.
#include <gtest/gtest.h>

#include "common/mpm_fixtures.hpp"

using namespace bfemp;
using namespace bfemp::fixtures;

namespace {
constexpr double g = -9.81;

void set_particle_velocity(Simulation<2>& sim, double vx0, double vy0, double omega, Vec<2> c) {
  const auto& p = sim.mpm()->particles();
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  auto v = Kokkos::create_mirror_view(p.v);
  for (std::size_t q = 0; q < x.extent(0); ++q) {
    v(q, 0) = vx0 - omega * (x(q, 1) - c(1));
    v(q, 1) = vy0 + omega * (x(q, 0) - c(0));
  }
  Kokkos::deep_copy(p.v, v);
}
}  // namespace

class MpmFreeFall : public ::testing::TestWithParam<TransferScheme> {};

TEST_P(MpmFreeFall, FollowsDiscreteRecurrence) {
  for (const auto& ti : {TimeIntegrator::backward_euler(), TimeIntegrator::newmark()}) {
    auto s = mpm_block_setup(0.2, Vec<2>(0.5, 0.8), 0.05, 4, 0.0, 1.0, GetParam());
    s.gravity = {0.0, g, 0.0};
    s.integrator = ti;
    s.dt = 0.02;
    Simulation<2> sim(s, fixtures::comm());
    const double y0 = particle_mean(sim.mpm()->particles(), 1);
    double y = 0, v = 0, a = g;
    for (int k = 0; k < 10; ++k) {
      const StepReport r = sim.step();
      EXPECT_NEAR(r.min_J, 1.0, 1e-10);
      const double y1 = y + s.dt * v + ti.predictor_acc_scale(s.dt) * a + ti.potential_scale(s.dt) * g;
      v += s.dt * ((1 - ti.gamma) * a + ti.gamma * g);
      y = y1;
      EXPECT_NEAR(particle_mean(sim.mpm()->particles(), 1) - y0, y, 1e-10) << ti.name << " step " << k + 1;
      EXPECT_NEAR(r.momentum[1] / (1000.0 * 0.04), v, 1e-9) << ti.name << " step " << k + 1;
    }
  }
}

class MpmMomentum : public ::testing::TestWithParam<TransferScheme> {};

TEST_P(MpmMomentum, LinearMomentumConservedWithoutGravityAndBoundaries) {
  auto s = mpm_block_setup(0.3, Vec<2>(0.5, 0.5), 0.05, 4, 0.0, 1.0, GetParam(), 1e5);
  s.integrator = TimeIntegrator::newmark();
  s.dt = 0.01;
  Simulation<2> sim(s, fixtures::comm());
  set_particle_velocity(sim, 0.3, -0.2, 2.0, Vec<2>(0.45, 0.55));
  // A compressive mode on top, so the block deforms.
  {
    const auto& p = sim.mpm()->particles();
    auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
    auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
    for (std::size_t q = 0; q < x.extent(0); ++q) v(q, 0) += -0.5 * (x(q, 0) - 0.5);
    Kokkos::deep_copy(p.v, v);
  }
  const auto p0 = sim.diagnostics().momentum;
  const double scale = std::hypot(p0[0], p0[1]);
  double elastic_max = 0;
  for (int k = 0; k < 20; ++k) {
    const StepReport r = sim.step();
    EXPECT_NEAR(r.momentum[0], p0[0], 1e-10 * scale) << "step " << k + 1;
    EXPECT_NEAR(r.momentum[1], p0[1], 1e-10 * scale) << "step " << k + 1;
    elastic_max = std::max(elastic_max, r.elastic);
  }
  EXPECT_GT(elastic_max, 0.0) << "the block must deform";
}

INSTANTIATE_TEST_SUITE_P(Schemes, MpmFreeFall,
                         ::testing::Values(TransferScheme::APIC, TransferScheme::PIC, TransferScheme::FLIP));
INSTANTIATE_TEST_SUITE_P(Schemes, MpmMomentum,
                         ::testing::Values(TransferScheme::APIC, TransferScheme::PIC, TransferScheme::FLIP));

// One revolution of a freely spinning block: APIC + Newmark keeps the angular
// momentum within 1 %; the drift of PIC, FLIP and backward Euler is reported.
double angular_drift(TransferScheme scheme, const TimeIntegrator& ti) {
  auto s = mpm_block_setup(0.24, Vec<2>(0.5, 0.5), 0.02, 4, 0.0, 1.0, scheme, 1e6);
  s.integrator = ti;
  s.dt = 0.01;
  const double omega = 2 * M_PI;  // one revolution per second
  Simulation<2> sim(s, fixtures::comm());
  set_particle_velocity(sim, 0.0, 0.0, omega, Vec<2>(0.5, 0.5));
  const double L0 = sim.diagnostics().angular_momentum_z;
  double L = L0;
  for (int k = 0; k < 100; ++k) L = sim.step().angular_momentum_z;
  return (L - L0) / L0;
}

TEST(MpmAngularMomentum, ApicNewmarkKeepsSpinOverOneRevolution) {
  const double apic_nm = angular_drift(TransferScheme::APIC, TimeIntegrator::newmark());
  EXPECT_LT(std::abs(apic_nm), 0.01);
  std::cout << "angular momentum drift over one revolution: APIC+Newmark " << apic_nm
            << ", PIC+Newmark " << angular_drift(TransferScheme::PIC, TimeIntegrator::newmark())
            << ", FLIP+Newmark " << angular_drift(TransferScheme::FLIP, TimeIntegrator::newmark())
            << ", APIC+backward Euler " << angular_drift(TransferScheme::APIC, TimeIntegrator::backward_euler())
            << "\n";
}
