// Energy of the colliding rings (paper section 6.1, VALIDATION A1) with
// Newmark (beta 1/4, gamma 1/2) and barrier contact, at the ci size of
// inputs/contact_rings.yaml with the rings started closer (0.2 m gap).
//
// Why the A1 run at the paper's size gains energy (E/E0 = 1.095 at
// separation, paper: -8.57 %), measured per step on the branch energy-gain
// (0.1 m gap, dx 0.1, element size 0.13, dt 2e-4, first 45 steps, in units
// of E0): the change of KE + Psi + B over each Newton solve equals the sum
// over the terms of the trapezoidal-rule error of their work,
//   T(x^{n+1}) - T(x^n) - (x^{n+1} - x^n) . (grad T(x^n) + grad T(x^{n+1})) / 2,
// to round-off (the Newmark update is consistent with the incremental
// potential on the FEM nodes and on the grid: m a^n = -grad V(x^n) exactly).
// Barrier +0.116, FEM elasticity +0.017, MPM elasticity -0.0001, P2G + G2P
// -0.032 (the only dissipation). The barrier and the elastic energies are
// conservative (the path integral of each gradient along x^n -> x^{n+1}
// matches the energy change), the MPM elastic energy of the diagnostics is
// the one Newton minimises. The gain is the trapezoidal rule on a stiff,
// under-resolved barrier: the rings close at 80 m/s, 1.6 cm per step against
// dhat = 1 cm, so a contact pair crosses the barrier layer within one step;
// the barrier force of x^n enters the next step again through a^n, and the
// contacting FEM boundary nodes chatter at the step frequency (+-500 m/s,
// alternating sign every step, 8e5 J in a 6.7 kg node). Release steps from a
// tiny distance return (x^{n+1} - x^n) f^n / 2 >> B(x^n). For a point mass
// hitting an infinitely stiff wall at the fraction s of a step, the
// trapezoidal rule rebounds at (3 - 4 s) times the impact speed (s < 2/3): on
// average 3.4 times the kinetic energy; with this barrier (kappa 1e7, dhat
// 1 cm, omega 4 cm, a 7 kg node at 80 m/s, random phase) the mean rebound
// kinetic energy ratio is 3.0, 2.4, 1.4, 1.0 at 3.2, 1.6, 0.8, 0.2 dhat of
// closing per step. It is chaotic in dt (0.1 m gap, 12 ms: dt 4e-4
// +2.0 %, 2e-4 +9.6 %, 1e-4 +0.8 %), grows with FEM refinement (element size
// 0.13 with dx 0.25: +3.3 %; 0.5 with dx 0.1: -1.4 %), and vanishes when the
// barrier layer is resolved in time: dhat = 5 cm at dt 2e-4 gives a barrier
// error of -0.0015 and -1.2 % total (transfers). Each ring alone keeps its
// energy (FEM, element size 0.13, dt 2e-4: within 1.2e-5 over 0.1 s) or loses
// it (MPM: transfers). This is Eqs. 21-22/33 of the paper as stated, not a
// bug; these tests pin the parts of the budget that must hold.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "common/fem_fixtures.hpp"
#include "io/scene.hpp"

using namespace bfemp;

namespace {

const std::string scene_file = std::string(BFEMP_SOURCE_DIR) + "/inputs/contact_rings.yaml";

// Kinetic plus elastic energy of the MPM particles (1/2 m v^2 + V0 psi(F)).
double mpm_energy(Simulation<2>& sim) {
  const auto& p = sim.mpm()->particles();
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  auto F = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.F);
  auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass);
  auto V0 = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.volume0);
  auto mat = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.material);
  auto mats = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mesh().elements.materials);
  double e = 0;
  for (std::size_t q = 0; q < m.extent(0); ++q) {
    Mat<2> Fq;
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) Fq(i, j) = F(q, i, j);
    e += 0.5 * m(q) * (v(q, 0) * v(q, 0) + v(q, 1) * v(q, 1)) + V0(q) * material_energy<2>(mats(mat(q)), Fq);
  }
  return e;
}

// Both rings at rest as a whole, each with the velocity field
// v = rate * (x - cx, -(y - cy)) (a stretching mode: they deform and vibrate).
void stretch_rings(Simulation<2>& sim, double rate) {
  const auto& p = sim.mpm()->particles();
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  auto v = Kokkos::create_mirror_view(p.v);
  for (std::size_t q = 0; q < x.extent(0); ++q) {
    v(q, 0) = rate * (x(q, 0) + 5.0);
    v(q, 1) = -rate * x(q, 1);
  }
  Kokkos::deep_copy(p.v, v);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.positions());
  auto V = Kokkos::create_mirror_view(sim.velocities());
  for (std::size_t n = 0; n < X.extent(0) / 2; ++n) {
    V(2 * n) = rate * (X(2 * n) - 5.0);
    V(2 * n + 1) = -rate * X(2 * n + 1);
  }
  Kokkos::deep_copy(sim.velocities(), V);
}

}  // namespace

// The rings collide with the barrier layer resolved in time (closing 2 cm per
// step against dhat = 5 cm): KE + Psi + B never rises above its initial value
// (the MPM transfers dissipate, Newmark and the barrier conserve); at dt 1e-3
// (8 cm per step, the paper's ratio 1.6 of closing per step to dhat) the same
// collision gains up to +7 % (printed, not asserted: chaotic).
TEST(ContactRingsEnergy, NoGainWhenTheBarrierLayerIsResolvedInTime) {
  const std::vector<std::string> common = {"MPM Bodies/left/center=[-4.1, 0.0]",
                                           "FEM Bodies/right/Mesh/center=[4.1, 0.0]", "Contact/dhat=0.05"};
  auto run = [&](double dt, double end, bool check) {
    auto o = common;
    o.push_back("Time/dt=" + std::to_string(dt));
    Simulation<2> sim(build_setup<2>(load_scene(scene_file, o)), fixtures::comm());
    const double e0 = sim.diagnostics().total_energy();
    const double m0 = mpm_energy(sim);
    double emax = e0, e = e0;
    long contact_steps = 0;
    const long steps = std::lround(end / dt);
    for (long n = 0; n < steps; ++n) {
      const StepReport r = sim.step();
      e = r.total_energy() + r.barrier_energy;
      emax = std::max(emax, e);
      if (r.contact_pairs > 0) ++contact_steps;
      if (check) {
        EXPECT_LE(e, e0 * (1 + 1e-4)) << "dt " << dt << " step " << r.step << ": energy " << e / e0 << " E0";
      }
    }
    const double m1 = mpm_energy(sim);
    std::cout << "rings energy, dhat 0.05, dt " << dt << ": closing " << 80 * dt / 0.05 << " dhat per step, "
              << contact_steps << " contact steps, max E/E0 " << emax / e0 << ", end " << e / e0
              << " (MPM ring " << m1 / m0 << ", FEM ring " << (e - m1) / (e0 - m0) << ")\n";
    return std::make_pair(contact_steps, e / e0);
  };
  const auto [contact_steps, end_ratio] = run(2.5e-4, 0.02, true);
  EXPECT_GT(contact_steps, 30);
  EXPECT_GT(end_ratio, 0.9) << "the transfers lose about 4 % here";
  run(1e-3, 0.02, false);
}

// No contact: each ring vibrates freely. The FEM ring (Newmark, neo-Hookean)
// keeps its energy; the MPM ring (APIC + Newmark on the grid) never gains,
// it loses energy in the transfers.
TEST(ContactRingsEnergy, FreeRingsFemKeepsMpmNeverGains) {
  const double dt = 1e-3;
  Simulation<2> sim(build_setup<2>(load_scene(scene_file, {"Time/dt=1e-3"})), fixtures::comm());
  stretch_rings(sim, 5.0);
  const double e0 = sim.diagnostics().total_energy();
  const double m0 = mpm_energy(sim), f0 = e0 - m0;
  ASSERT_GT(m0, 0.0);
  ASSERT_GT(f0, 0.0);
  double mmax = m0, m = m0, f = f0, fdev = 0;
  for (long n = 0; n < std::lround(0.1 / dt); ++n) {
    const StepReport r = sim.step();
    EXPECT_EQ(r.contact_pairs, 0);
    m = mpm_energy(sim);
    f = r.total_energy() - m;
    mmax = std::max(mmax, m);
    fdev = std::max(fdev, std::abs(f / f0 - 1));
    EXPECT_LE(m, m0 * (1 + 1e-6)) << "step " << r.step << ": the MPM ring gained energy";
    EXPECT_LT(std::abs(f / f0 - 1), 1e-3) << "step " << r.step << ": FEM ring energy " << f / f0 << " of its initial";
  }
  EXPECT_LT(m, 0.99 * m0) << "the MPM transfers dissipate";
  std::cout << "free rings: FEM ring energy within " << fdev << " of its initial, MPM ring " << m / m0
            << " at 0.1 s (max " << mmax / m0 << ")\n";
}
