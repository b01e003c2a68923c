// FEM-FEM barrier contact in whole simulations (2D, Contact/FEM-FEM, scenes
// of FEM bodies only):
//  - two mirror-image blocks collide head-on (Newmark, no gravity): linear
//    momentum stays zero, the run stays mirror-symmetric (contact is two-
//    sided: each body's nodes against the other's edges), no node ever enters
//    the other body, and the blocks part with reversed velocities;
//  - a block dropped on a fixed plate (backward Euler) comes to rest on it,
//    a positive distance below dhat above it, and the contact force on the
//    plate equals the block's weight;
//  - the same block sliding on the plate with mu decelerates at mu g (Coulomb
//    sliding: the smoothed friction f1 is 1 once |u| > eps_v dt);
//  - the A6 ci scene's first 0.5 s: plate -> FEM ring -> MPM ring.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <iostream>

#include "common/fem_fixtures.hpp"
#include "io/scene.hpp"

using namespace bfemp;
using namespace bfemp::fixtures;

namespace {

constexpr double kRho = 1000.0, kE = 1e5;

// Rectangle [x0, x0 + w] x [y0, y0 + h] meshed with element size es.
MeshData rectangle(double x0, double y0, double w, double h, double es) {
  ShapeSpec spec;
  spec.kind = "rectangle";
  spec.center = {x0 + w / 2, y0 + h / 2};
  spec.size = {w, h};
  spec.element_size = es;
  return mesh_shape(spec, 2);
}

ContactParams fem_contact(double dhat, double kappa, double mu, int n_fem) {
  ContactParams cp;
  cp.dhat = dhat;
  cp.kappa = kappa;
  cp.eps_v = 1e-3;
  cp.fem_fem = true;
  cp.mpm_bodies = 0;
  if (mu > 0) cp.mu.assign(static_cast<std::size_t>(n_fem) * n_fem, mu);
  return cp;
}

SimulationSetup<2> base_setup(double E = kE) {
  auto s = block_setup<2>(0.25, E, 0.3, kRho);
  s.bodies.clear();
  s.newton.eps_d = 1e-7;
  return s;
}

}  // namespace

TEST(ContactFemFemScene, MirrorBlocksCollideSymmetricallyAndKeepMomentum) {
  const double gap = 0.02, v0 = 0.5;
  auto s = base_setup();
  MeshData left = rectangle(0, 0, 1, 1, 0.25);
  MeshData right = left;  // mirror image about x = 1 + gap / 2 (orientation restored)
  for (std::size_t n = 0; n < right.num_nodes(); ++n) right.coords[n * 2] = 2 + gap - right.coords[n * 2];
  for (std::size_t c = 0; c < right.num_cells(); ++c) std::swap(right.cells[c * 3 + 1], right.cells[c * 3 + 2]);
  s.bodies = {{"left", left, 0}, {"right", right, 0}};
  s.initial_velocity = {{v0, 0, 0}, {-v0, 0, 0}};
  s.contact = fem_contact(1e-2, 1e3, 0.0, 2);
  s.integrator = TimeIntegrator::newmark();
  s.dt = 2e-3;
  Simulation<2> sim(s, comm());
  const double m = kRho * 1.0;  // per body (kg/m)
  long contact_steps = 0;
  double max_sym = 0, max_p = 0;
  for (int k = 0; k < 200; ++k) {
    const StepReport r = sim.step();
    ASSERT_EQ(r.bodies.size(), 2u);
    max_p = std::max({max_p, std::abs(r.momentum[0]), std::abs(r.momentum[1])});
    const auto& L = r.bodies[0];
    const auto& R = r.bodies[1];
    max_sym = std::max({max_sym, std::abs(L.velocity[0] + R.velocity[0]), std::abs(L.velocity[1] - R.velocity[1]),
                        std::abs(L.com[0] + R.com[0] - (2 + gap))});
    if (r.contact_pairs > 0) {
      ++contact_steps;
      EXPECT_GT(r.min_distance, 0.0) << "step " << r.step;
    }
    EXPECT_NO_THROW(sim.contact()->check_initial_fem(sim.positions())) << "step " << r.step;
  }
  const StepReport end = sim.diagnostics();
  std::cout << "  contact in " << contact_steps << " of 200 steps; |p| max " << max_p << " kg m/s; symmetry "
            << max_sym << "; final v_x " << end.bodies[0].velocity[0] << ", " << end.bodies[1].velocity[0]
            << " m/s; energy " << end.total_energy() << " J/m (initial " << m * v0 * v0 << ")\n";
  EXPECT_GT(contact_steps, 10);
  EXPECT_LT(max_p, 1e-9 * m * v0);
  EXPECT_LT(max_sym, 1e-8);
  EXPECT_LT(end.bodies[0].velocity[0], 0.0);  // parted, moving apart
  EXPECT_GT(end.bodies[1].velocity[0], 0.0);
  EXPECT_EQ(end.contact_pairs, 0);
}

namespace {

// A fixed plate [-1, 2] x [-0.25, 0] (body 0) and a unit block above it
// (body 1) at height y0, at rest; backward Euler. E = 1e7 (and kappa 1e6):
// the bounce of the block on the barrier and its own vibration are damped
// by backward Euler within a few tenths of a second (with E = 1e5 and kappa
// 1e4 the block still bounced at 0.1 m/s after 1 s, and the normal force
// swung between 0.02 and 1.5 times the weight).
SimulationSetup<2> block_on_plate(double y0, double mu) {
  auto s = base_setup(1e7);
  MeshData plate = rectangle(-1, -0.25, 3, 0.25, 0.25);
  MeshData block = rectangle(0, y0, 1, 1, 0.25);
  PrescribedMotion fix;
  fix.name = "plate";
  for (std::size_t n = 0; n < plate.num_nodes(); ++n) fix.nodes.push_back(static_cast<LO>(n));
  fix.segments = {MotionSegment{}};
  s.motions.push_back(fix);
  s.bodies = {{"plate", plate, 0}, {"block", block, 0}};
  s.contact = fem_contact(1e-2, 1e6, mu, 2);
  s.contact->force_body = 0;
  s.gravity = {0, -9.81, 0};
  s.integrator = TimeIntegrator::backward_euler();
  s.dt = 1e-2;
  return s;
}

}  // namespace

TEST(ContactFemFemScene, BlockComesToRestOnAPlateAndPressesWithItsWeight) {
  Simulation<2> sim(block_on_plate(0.02, 0.0), comm());
  StepReport r;
  for (int k = 0; k < 100; ++k) {
    r = sim.step();
    EXPECT_NO_THROW(sim.contact()->check_initial_fem(sim.positions())) << "step " << r.step;
  }
  const double weight = kRho * 1.0 * 9.81;
  std::cout << "  at t = " << r.time << " s: contact force " << r.contact_force[0] << ", " << r.contact_force[1]
            << " N/m (weight " << weight << "), min distance " << r.min_distance << " m, block v_y "
            << r.bodies[1].velocity[1] << " m/s\n";
  EXPECT_GT(r.contact_pairs, 0);
  EXPECT_GT(r.min_distance, 0.0);
  EXPECT_LT(r.min_distance, 1e-2);
  EXPECT_LT(std::abs(r.bodies[1].velocity[1]), 1e-4);
  EXPECT_NEAR(r.contact_force[1], -weight, 1e-3 * weight);  // the plate is pushed down
  EXPECT_NEAR(r.contact_force[0], 0.0, 1e-6 * weight);
  EXPECT_TRUE(std::isnan(r.contact_lo[0])) << "the contact box covers particles only (there are none)";
}

TEST(ContactFemFemScene, SlidingBlockDeceleratesAtMuG) {
  const double mu = 0.2;
  Simulation<2> sim(block_on_plate(0.005, mu), comm());
  for (int k = 0; k < 50; ++k) sim.step();  // settle on the plate (0.5 s)
  // Push the block: v_x = 1 m/s at every block node.
  {
    const auto& b = sim.mesh().bodies[1];
    auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.velocities());
    for (LO n = b.first_node; n < b.first_node + b.num_nodes; ++n) v(n * 2) += 1.0;
    Kokkos::deep_copy(sim.velocities(), v);
  }
  // Least-squares slope of the block's v_x over the next 0.05 .. 0.35 s (it
  // stops after about 0.5 s).
  const double t0 = sim.time();
  double st = 0, sv = 0, stt = 0, stv = 0;
  int n = 0;
  for (int k = 0; k < 35; ++k) {
    const StepReport r = sim.step();
    EXPECT_GT(r.friction_iters, 0);
    if (std::getenv("BFEMP_TRACE"))
      std::cout << r.time << " vx " << r.bodies[1].velocity[0] << " vy " << r.bodies[1].velocity[1] << " fx "
                << r.contact_force[0] << " fy " << r.contact_force[1] << " friction loops " << r.friction_iters
                << "\n";
    if (r.time - t0 < 0.05 - 1e-12) continue;
    const double t = r.time, v = r.bodies[1].velocity[0];
    st += t, sv += v, stt += t * t, stv += t * v;
    ++n;
  }
  const double a = (n * stv - st * sv) / (n * stt - st * st);
  std::cout << "  sliding deceleration " << -a << " m/s^2 (mu g = " << mu * 9.81 << ")\n";
  EXPECT_NEAR(-a, mu * 9.81, 1e-4 * mu * 9.81);  // the slope test's band (A4: 0.01 %)
}

// VALIDATION A6 at its ci size (inputs/a6_semiring_buckling.yaml), first
// 0.5 s: the plate (prescribed, FEM) presses the FEM outer semi-ring through
// FEM-FEM contact (mu 10), which presses the MPM inner semi-ring through
// MPM-FEM contact. The inner ring's crown follows the plate down (within the
// first 0.1 s the gaps close: 1e-3 plate-outer, 1e-2 outer-inner), no
// particle enters an FEM body, no FEM node enters another FEM body, and the
// deformation stays symmetric (no buckling this early).
TEST(ContactFemFemScene, A6PlateDrivesBothRingsThroughContact) {
  Scene scene = load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/a6_semiring_buckling.yaml", {});
  auto setup = build_setup<2>(scene);
  setup.count_penetrations = true;
  Simulation<2> sim(setup, comm());
  const auto& p = sim.mpm()->particles();
  auto x0 = Kokkos::create_mirror(Kokkos::HostSpace(), p.x);  // a copy (a mirror view would alias on the host)
  Kokkos::deep_copy(x0, p.x);
  std::vector<std::size_t> crown;
  for (std::size_t q = 0; q < x0.extent(0); ++q)
    if (std::abs(x0(q, 0)) < 1.0 && x0(q, 1) > 9.5) crown.push_back(q);
  ASSERT_GT(crown.size(), 10u);
  auto crown_shift = [&](int c) {
    auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
    double s = 0;
    for (std::size_t q : crown) s += x(q, c) - x0(q, c);
    return s / crown.size();
  };
  long contact_steps = 0;
  for (int k = 0; k < 50; ++k) {
    const StepReport r = sim.step();
    EXPECT_EQ(r.penetrations, 0) << "step " << r.step;
    EXPECT_NO_THROW(sim.contact()->check_initial_fem(sim.positions())) << "step " << r.step;
    contact_steps += r.contact_pairs > 0 ? 1 : 0;
  }
  const double uy = crown_shift(1), ux = crown_shift(0);
  std::cout << "  after 0.5 m of plate travel: inner crown moved " << uy << " m down, " << ux << " m sideways\n";
  EXPECT_GT(contact_steps, 40);
  EXPECT_LT(uy, -0.4);   // plate travel 0.5 m minus the closing of the gaps and the outer ring's squeeze
  EXPECT_GT(uy, -0.5);   // it cannot pass the plate
  EXPECT_LT(std::abs(ux), 1e-3);
}
