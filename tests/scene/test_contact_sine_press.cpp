// Irregular FEM boundary pressing an MPM box (paper section 6.2, Fig. 8;
// VALIDATION A2) at a ci size: inputs/contact_sine_press.yaml. A fully
// prescribed FEM strip whose lower contour is y = 0.535 + (1/40) cos(2 pi x / 0.1)
// moves 1 m/s down (0.04 s), left (0.05 s: half a wavelength) and up (0.08 s)
// on a 0.5 x 0.5 MPM box resting on a no-slip ground, frictionless barrier
// contact, no gravity (the initial state is the rest state).
//
// BFEMP: no particle inside the FEM body at any Newton iterate or step. No
// adhesion, measured in ways a sticky boundary would fail:
//  - the contact force on the FEM body never points down (fy >= 0 every step):
//    the box only ever pushes the boundary, it is never pulled by it;
//  - while the boundary moves up, the box's energy (particle kinetic + elastic
//    + barrier) drops at every step: the power the boundary delivers is
//    -F_fem . v_fem = -fy <= 0 and backward Euler only dissipates, whereas a
//    boundary that pulls the box up does positive work on it (the level-set
//    run below does);
//  - the boundary separates (contact_pairs drops to 0 while it rises and
//    stays 0), and no particle rises above its rest height by more than in
//    the elastic rebound + dhat, the rebound measured by a free release of
//    the box from the state at the start of the up phase (no FEM body),
//    stepped alongside; the rising boundary also leaves the box less energy
//    than the free release. A sticky boundary drags the top particles up with
//    it (0.08 m of travel while rising).
// Level-set comparison: the same motion with a slip level set of the same
// sine shape (solid above) on the grid, moving down, left and up in one run
// (piecewise level-set motion, the scene key Level Sets/<name>/Motion). It penetrates
// (particles inside the level-set solid: count and depth reported, asserted
// > 0 during the press) and the rising level set does positive work on the
// box in some step (reported, asserted > 0): the grid constraint
// n . v = n . v_boundary pulls as well as pushes.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>

#include "common/fem_fixtures.hpp"
#include "io/scene.hpp"

using namespace bfemp;

namespace {

const std::string scene_file = std::string(BFEMP_SOURCE_DIR) + "/inputs/contact_sine_press.yaml";
constexpr double kDown = 0.04, kLeft = 0.05, kUp = 0.08;  // s, the scene's motion segments
constexpr double kY0 = 0.535, kA = 1.0 / 40.0, kWave = 0.1;  // the FEM body's lower contour
constexpr double kDhat = 1e-3;

struct HostParticles {
  Kokkos::View<double* [2], MemSpace>::HostMirror x, v;
  Kokkos::View<double*, MemSpace>::HostMirror m;
};

HostParticles host_particles(const Particles<2>& p) {
  return {Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x),
          Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v),
          Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass)};
}

double particle_kinetic(const HostParticles& h) {
  double ke = 0;
  for (std::size_t q = 0; q < h.m.extent(0); ++q) ke += 0.5 * h.m(q) * (h.v(q, 0) * h.v(q, 0) + h.v(q, 1) * h.v(q, 1));
  return ke;
}

// Phase of the prescribed motion at the end of a step at time t.
enum Phase { Down, Left, Up };
Phase phase_at(double t) { return t <= kDown + 1e-9 ? Down : t <= kDown + kLeft + 1e-9 ? Left : Up; }

// Lowest point of the FEM contour at time t (rigid motion).
double contour_low(double t) {
  if (t <= kDown) return kY0 - kA - t;
  if (t <= kDown + kLeft) return kY0 - kA - kDown;
  return kY0 - kA - kDown + (t - kDown - kLeft);
}

}  // namespace

TEST(ContactSinePress, NoPenetrationAndNoAdhesion) {
  const auto t0 = std::chrono::steady_clock::now();
  const Scene scene = load_scene(scene_file);
  SimulationSetup<2> setup = build_setup<2>(scene);
  const double dt = setup.dt;
  const int steps = static_cast<int>(std::lround((kDown + kLeft + kUp) / dt));
  Simulation<2> sim(std::move(setup), fixtures::comm());
  ASSERT_NE(sim.contact(), nullptr);
  const std::size_t np = sim.mpm()->particles().size();
  const HostParticles rest = host_particles(sim.mpm()->particles());
  std::vector<double> y_rest(np);
  double top_rest = -1e300;
  for (std::size_t q = 0; q < np; ++q) top_rest = std::max(top_rest, y_rest[q] = rest.x(q, 1));

  // Elastic rebound reference: the same box released freely (no FEM body) from
  // the state at the start of the up phase, stepped alongside.
  std::unique_ptr<Simulation<2>> free_sim;
  double rise_free = -1e300, rise_up = -1e300, e_free_end = 0;
  auto start_free_release = [&]() {
    SimulationSetup<2> s = build_setup<2>(scene);
    s.bodies.clear();
    s.initial_velocity.clear();
    s.motions.clear();
    s.contact.reset();
    free_sim = std::make_unique<Simulation<2>>(std::move(s), fixtures::comm());
    const Particles<2>& p = free_sim->mpm()->particles();
    const Particles<2>& q = sim.mpm()->particles();
    Kokkos::deep_copy(p.x, q.x);
    Kokkos::deep_copy(p.v, q.v);
    Kokkos::deep_copy(p.F, q.F);
    Kokkos::deep_copy(p.C, q.C);
  };

  long iterates = 0, inside_iterates = 0;
  sim.newton().on_iterate = [&](Kokkos::View<const double*, MemSpace> x) {
    ++iterates;
    if (sim.contact()->particle_inside_at(x) >= 0) ++inside_iterates;
  };

  long inside_steps = 0, contact_steps = 0, recontact_steps = 0, energy_up_steps = 0;
  double fy_min = std::numeric_limits<double>::infinity(), dmin = std::numeric_limits<double>::infinity();
  double max_indent = 0;                 // max over steps of (top rest height - lowest top-row particle)
  double e_up_start = 0, e_prev = 0, e_end = 0, max_energy_rise = -1e300;
  int separation_step = -1;              // first up-phase step with no contact pair, none after it
  double rise_after_sep = -1e300, vy_after_sep = -1e300, vy_up_contact = -1e300;
  double low_at_sep = 0;
  for (int n = 0; n < steps; ++n) {
    const StepReport r = sim.step();
    const HostParticles h = host_particles(sim.mpm()->particles());
    {
      Kokkos::View<const double*, MemSpace> xp(sim.mpm()->particles().x.data(), 2 * np);
      if (sim.contact()->particle_inside(xp, sim.positions()) >= 0) ++inside_steps;
    }
    const Phase ph = phase_at(r.time);
    const double e_box = particle_kinetic(h) + r.elastic + r.barrier_energy;
    if (r.contact_pairs > 0) {
      ++contact_steps;
      dmin = std::min(dmin, r.min_distance);
    }
    fy_min = std::min(fy_min, r.contact_force[1]);
    double y_top_low = 1e300, rise = -1e300, vy = -1e300;
    for (std::size_t q = 0; q < np; ++q) {
      if (y_rest[q] > top_rest - 1e-9) y_top_low = std::min(y_top_low, h.x(q, 1));
      rise = std::max(rise, h.x(q, 1) - y_rest[q]);
      vy = std::max(vy, h.v(q, 1));
    }
    max_indent = std::max(max_indent, top_rest - y_top_low);
    if (ph != Up) {
      e_up_start = e_prev = e_box;  // the state the up phase starts from
      if (phase_at(r.time + dt) == Up) start_free_release();
    } else {
      rise_up = std::max(rise_up, rise);
      {
        const StepReport rf = free_sim->step();
        const HostParticles hf = host_particles(free_sim->mpm()->particles());
        for (std::size_t q = 0; q < np; ++q) rise_free = std::max(rise_free, hf.x(q, 1) - y_rest[q]);
        e_free_end = particle_kinetic(hf) + rf.elastic;
      }
      max_energy_rise = std::max(max_energy_rise, e_box - e_prev);
      if (e_box > e_prev * (1 + 1e-9)) ++energy_up_steps;
      e_prev = e_end = e_box;
      if (r.contact_pairs == 0 && separation_step < 0) {
        separation_step = static_cast<int>(r.step);
        low_at_sep = contour_low(r.time);
      }
      if (separation_step >= 0) {
        if (r.contact_pairs > 0) ++recontact_steps;
        rise_after_sep = std::max(rise_after_sep, rise);
        vy_after_sep = std::max(vy_after_sep, vy);
      } else {
        vy_up_contact = std::max(vy_up_contact, vy);
      }
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  EXPECT_GT(iterates, steps);
  EXPECT_EQ(inside_iterates, 0) << "Newton iterates with a particle inside the FEM body";
  EXPECT_EQ(inside_steps, 0) << "steps with a particle inside the FEM body";
  EXPECT_GT(contact_steps, 20);
  EXPECT_GT(dmin, 0.0);
  EXPECT_GT(max_indent, 0.01) << "the contour must indent the box by centimetres";
  // No adhesion.
  EXPECT_GE(fy_min, 0.0) << "the box pulled the FEM boundary down (a sticky contact force)";
  EXPECT_EQ(energy_up_steps, 0) << "up-phase steps in which the rising boundary did positive work on the box";
  EXPECT_LT(e_end, e_up_start);
  ASSERT_GE(separation_step, 0) << "the boundary never separated from the box while rising";
  EXPECT_EQ(recontact_steps, 0) << "contact again after separation";
  EXPECT_LT(rise_up, rise_free + kDhat) << "a particle rose higher than in the free elastic rebound";
  EXPECT_LT(e_end, e_free_end) << "the rising boundary left the box more energy than a free release";
  std::cout << "sine press (BFEMP): " << np << " particles, " << steps << " steps of " << dt << " s, " << iterates
            << " Newton iterates, iterates/steps with a particle inside the FEM body " << inside_iterates << "/"
            << inside_steps << ", contact during " << contact_steps << " steps, min distance " << dmin
            << " m, max indentation of the top row " << max_indent << " m\n"
            << "  no adhesion: min contact force y on the FEM body " << fy_min
            << " N/m; box energy (KE + elastic + barrier) " << e_up_start << " J at the start of the up phase -> "
            << e_end << " J at the end, largest per-step change while rising " << max_energy_rise
            << " J; separation at step " << separation_step << " (contour's lowest point "
            << low_at_sep - top_rest << " m above the top particles' rest height), contact again after it: "
            << recontact_steps << " steps; after separation max particle rise above rest " << rise_after_sep
            << " m, max particle vy " << vy_after_sep << " m/s (boundary 1 m/s); max vy while rising in contact "
            << vy_up_contact << " m/s\n"
            << "  elastic rebound reference (free release at the start of the up phase): max particle rise above rest "
            << "over the up phase " << rise_free << " m (BFEMP " << rise_up << " m), box energy at the end " << e_free_end
            << " J (BFEMP " << e_end << " J)\n"
            << "  wall time " << seconds << " s\n";
}

TEST(ContactSinePress, LevelSetSlipSinePenetratesAndAdheres) {
  const auto t0 = std::chrono::steady_clock::now();
  const Scene scene = load_scene(scene_file);
  const double dt = build_setup<2>(scene).dt;
  // The same scene without the FEM body, the boundary a slip level set of the
  // same shape on the grid, moving down, left and up in one simulation
  // (piecewise level-set motion; left by half a wavelength turns A cos(k x)
  // into -A cos(k x) through the offset).
  SimulationSetup<2> setup = build_setup<2>(scene);
  setup.bodies.clear();
  setup.initial_velocity.clear();
  setup.motions.clear();
  setup.contact.reset();
  LevelSet ls;
  ls.name = "sine";
  ls.kind = LevelSetKind::Sine;
  ls.slip = true;
  ls.solid_above = true;
  ls.height = kY0;
  ls.amplitude = kA;
  ls.wavelength = kWave;
  ls.segments = 3;
  const double ends[3] = {kDown, kDown + kLeft, kDown + kLeft + kUp};
  const double vel[3][3] = {{0.0, -1.0, 0.0}, {-1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}};
  for (int k = 0; k < 3; ++k) {
    ls.seg_end[k] = ends[k];
    for (int c = 0; c < 3; ++c) ls.seg_velocity[k][c] = vel[k][c];
  }
  setup.level_sets.push_back(ls);
  setup.count_penetrations = true;  // the diagnostics columns, checked against the count below
  auto sim = std::make_unique<Simulation<2>>(std::move(setup), fixtures::comm());
  const Particles<2>& p = sim->mpm()->particles();
  std::vector<double> y_rest;
  {
    const HostParticles h = host_particles(p);
    for (std::size_t i = 0; i < p.size(); ++i) y_rest.push_back(h.x(i, 1));
  }
  long max_inside[3] = {0, 0, 0}, inside_end = 0, dragged_end = 0;
  double max_depth[3] = {0, 0, 0};
  double rise_end = -1e300, e_up_start = 0, e_up_end = 0, max_energy_rise = -1e300, e_prev = 0, vy_up_max = -1e300;
  const long n_steps = std::lround(ends[2] / dt);
  const long up_from = std::lround(ends[1] / dt);
  for (long n = 0; n < n_steps; ++n) {
    const int seg = n < std::lround(ends[0] / dt) ? 0 : n < up_from ? 1 : 2;
    if (n == up_from) e_prev = e_up_start = particle_kinetic(host_particles(p)) + sim->diagnostics().elastic;
    const StepReport r = sim->step();
    const HostParticles h = host_particles(p);
    long inside = 0, dragged = 0;
    double depth = 0, rise = -1e300, vy = -1e300;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double phi = ls.phi<2>(Vec<2>(h.x(i, 0), h.x(i, 1)), sim->time());
      if (phi < 0) {
        ++inside;
        depth = std::max(depth, -phi);
      }
      rise = std::max(rise, h.x(i, 1) - y_rest[i]);
      if (h.x(i, 1) - y_rest[i] > 0.01) ++dragged;
      vy = std::max(vy, h.v(i, 1));
    }
    max_inside[seg] = std::max(max_inside[seg], inside);
    max_depth[seg] = std::max(max_depth[seg], depth);
    // Output/count penetrations reports the same (no particle is in the ground).
    EXPECT_EQ(r.penetrations, inside) << "step " << r.step;
    EXPECT_EQ(r.penetrations_level_set, inside) << "step " << r.step;
    EXPECT_EQ(r.penetrations_fem, 0) << "step " << r.step;  // the level-set run has no FEM body
    EXPECT_NEAR(r.penetration_depth, depth, 1e-15) << "step " << r.step;
    if (seg == 2) {
      const double e = particle_kinetic(h) + r.elastic;
      max_energy_rise = std::max(max_energy_rise, e - e_prev);
      e_prev = e_up_end = e;
      vy_up_max = std::max(vy_up_max, vy);
      inside_end = inside;
      dragged_end = dragged;
      rise_end = std::max(rise_end, rise);
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << "sine press (level-set slip sine): particles inside the solid, max count / max depth: down "
            << max_inside[0] << " / " << max_depth[0] << " m, left " << max_inside[1] << " / " << max_depth[1]
            << " m, up " << max_inside[2] << " / " << max_depth[2] << " m\n"
            << "  adhesion while rising: at the end " << inside_end << " particles still inside the solid, "
            << dragged_end << " particles more than 0.01 m above their rest height, max rise above rest over the up phase "
            << rise_end << " m, max particle vy " << vy_up_max
            << " m/s; box energy (KE + elastic) " << e_up_start << " -> " << e_up_end
            << " J, largest per-step change " << max_energy_rise << " J\n"
            << "  wall time " << seconds << " s\n";
  EXPECT_GT(max_inside[0], 0) << "the level-set press is expected to let particles into the solid";
  EXPECT_GT(max_depth[0], 0.0);
  EXPECT_GT(max_energy_rise, 0.0) << "the rising level set is expected to do positive work on the box";
}
