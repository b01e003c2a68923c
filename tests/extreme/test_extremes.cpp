// Stability at the extremes (VALIDATION section D; ctest label `extreme`).
// Each case is a real scene pushed to one extreme. It either runs to its end
// with finite fields, every Newton iterate penetration-free (Contact/check
// iterates) and every contact distance > 0, or it stops -- before the first
// step or at a named step -- with a message naming the parameter. Which of
// the two happens is asserted per case, so a change of behaviour shows.
//
// Base scenes: inputs/contact_disk_wall.yaml (an MPM rubber disk thrown at a
// fixed FEM steel wall, 20 steps) and inputs/default_contact.yaml (an FEM disk
// rolling on an MPM floor with friction).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>

#include "common/fem_fixtures.hpp"
#include <Teuchos_Array.hpp>

#include "io/scene.hpp"
#include "solver/solver_error.hpp"

using namespace bfemp;

namespace {

const std::string kDiskWall = std::string(BFEMP_SOURCE_DIR) + "/inputs/contact_disk_wall.yaml";
const std::string kRolling = std::string(BFEMP_SOURCE_DIR) + "/inputs/default_contact.yaml";

struct Outcome {
  bool refused = false;    // std::invalid_argument before the first step
  bool failed = false;     // SolverError during a step
  std::string message;
  long steps = 0;          // steps completed
  long contact_steps = 0;
  long penetrating_iterates = 0, iterates = 0;
  double min_distance = std::numeric_limits<double>::infinity();
  bool finite = true;      // every particle and FEM node position and velocity
  double seconds = 0;
};

template <int dim>
bool finite_fields(const Simulation<dim>& sim) {
  auto ok = [](auto v) {
    auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
    for (std::size_t i = 0; i < h.size(); ++i)
      if (!std::isfinite(h.data()[i])) return false;
    return true;
  };
  bool f = ok(sim.positions()) && ok(sim.velocities());
  if (sim.mpm()) f = f && ok(sim.mpm()->particles().x) && ok(sim.mpm()->particles().v) && ok(sim.mpm()->particles().F);
  return f;
}

template <int dim = 2>
Outcome run_case(const std::string& file, std::vector<std::string> sets, long max_steps = -1) {
  Outcome o;
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<Simulation<dim>> sim;
  try {
    sets.push_back("Contact/check iterates=true");
    const Scene scene = load_scene(file, sets);
    sim = std::make_unique<Simulation<dim>>(build_setup<dim>(scene), fixtures::comm());
  } catch (const std::invalid_argument& e) {
    o.refused = true;
    o.message = e.what();
    return o;
  }
  Simulation<dim>& s = *sim;
  if (s.contact())
    s.newton().on_iterate = [&](Kokkos::View<const double*, MemSpace> x) {
      ++o.iterates;
      if (s.contact()->particle_inside_at(x) >= 0) ++o.penetrating_iterates;
    };
  const Scene scene = load_scene(file, sets);
  const double dt = scene.params.sublist("Time").get<double>("dt");
  long steps = std::lround(scene.params.sublist("Time").get<double>("end time") / dt);
  if (max_steps > 0) steps = std::min(steps, max_steps);
  try {
    for (long n = 0; n < steps; ++n) {
      const StepReport r = s.step();
      ++o.steps;
      if (r.contact_pairs > 0) {
        ++o.contact_steps;
        o.min_distance = std::min(o.min_distance, r.min_distance);
      }
    }
  } catch (const SolverError& e) {
    o.failed = true;
    o.message = e.what();
  }
  o.finite = finite_fields(s);
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return o;
}

void print(const std::string& name, const Outcome& o) {
  std::cout << "extreme " << name << ": " << (o.refused ? "refused" : o.failed ? "stopped" : "completed") << " after "
            << o.steps << " steps (" << o.contact_steps << " in contact), min distance " << o.min_distance << ", "
            << o.penetrating_iterates << "/" << o.iterates << " penetrating iterates, finite " << o.finite << ", "
            << o.seconds << " s" << (o.message.empty() ? "" : "; message: " + o.message) << "\n";
}

// Ran to the end: finite, in contact, never through the wall.
void expect_completed(const std::string& name, const Outcome& o, long steps, bool contact = true) {
  print(name, o);
  EXPECT_FALSE(o.refused) << o.message;
  EXPECT_FALSE(o.failed) << o.message;
  EXPECT_EQ(o.steps, steps);
  EXPECT_TRUE(o.finite) << "non-finite positions or velocities";
  EXPECT_EQ(o.penetrating_iterates, 0) << "Newton iterates with a particle inside the FEM body";
  if (contact) {
    EXPECT_GT(o.contact_steps, 0) << "the case never reached contact";
    EXPECT_GT(o.min_distance, 0.0);
  }
}

void expect_refused(const std::string& name, const Outcome& o, const std::string& names) {
  print(name, o);
  EXPECT_TRUE(o.refused) << "expected a refusal before the first step";
  EXPECT_EQ(o.steps, 0);
  EXPECT_NE(o.message.find(names), std::string::npos) << o.message;
}

}  // namespace

TEST(Extreme, StiffMaterialAgainstSoftBarrier) {
  // E = 4e12 Pa against kappa = 1 Pa: a barrier 12 orders softer than the body.
  expect_completed("E=4e12,kappa=1", run_case(kDiskWall, {"Materials/rubber/E=4.0e12", "Contact/kappa=1.0"}), 20);
}

TEST(Extreme, TinyContactDistance) {
  expect_completed("dhat=1e-6", run_case(kDiskWall, {"Contact/dhat=1.0e-6"}), 20);
}

TEST(Extreme, TimeStepTenTimesTheMpmCflLimit) {
  // Rubber: c = sqrt(E (1 - nu) / (rho (1 + nu)(1 - 2 nu))) = 116 m/s; dx = 0.05: dx / c = 4.3e-4 s.
  expect_completed("dt=10 CFL", run_case(kDiskWall, {"Time/dt=4.3e-3", "Time/end time=4.3e-2"}), 10);
}

TEST(Extreme, ImpactAtOneThousandMetresPerSecond) {
  // The disk crosses its 0.15 m gap in 0.15 ms: contact inside the first step of 1 ms.
  expect_completed("v=1000", run_case(kDiskWall, {"MPM Bodies/disk/initial velocity=[1000.0, 0.0]",
                                                  "Time/end time=5.0e-3"}), 5);
}

TEST(Extreme, ParticleStartingExactlyDhatFromTheBoundary) {
  // The rightmost particles sit at x = 0.0375 (dx = 0.05, offsets dx/4 and
  // 3 dx/4 from -0.6); the wall's face at x = 0.0385 is dhat = 1e-3 from them.
  expect_completed("d0=dhat", run_case(kDiskWall, {"FEM Bodies/wall/Mesh/center=[0.1385, 0.0]",
                                                   "MPM Bodies/disk/initial velocity=[1.0, 0.0]"}), 20);
}

TEST(Extreme, FrictionCoefficientTen) {
  expect_completed("mu=10", run_case(kRolling, {"Contact/friction=10.0", "Time/end time=4.0e-2"}), 20);
}

// Largest distance of a particle coordinate (axis c) from the nearest grid line.
double off_line(const std::vector<std::string>& sets, int c) {
  const Scene scene = load_scene(kDiskWall, sets);
  const auto& mpm = scene.params.sublist("MPM");
  const double dx = mpm.get<double>("grid spacing");
  const double lo = mpm.get<Teuchos::Array<double>>("domain min")[c];
  Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mpm()->particles().x);
  double worst = 0;
  for (std::size_t q = 0; q < x.extent(0); ++q) {
    const double s = (x(q, c) - lo) / dx;
    worst = std::max(worst, std::abs(s - std::round(s)) * dx);
  }
  return worst;
}

// One particle per cell sits on the lattice (m + 1/2) dx = 0.025 + 0.05 m;
// grids shifted to start at -0.625 have nodes (or lines) exactly there.
TEST(Extreme, ParticlesOnGridNodes) {
  const std::vector<std::string> sets = {"MPM/particles per cell=1", "MPM/domain min=[-0.625, -0.625]",
                                         "MPM/domain max=[0.625, 0.625]"};
  EXPECT_LT(off_line(sets, 0), 1e-12);
  EXPECT_LT(off_line(sets, 1), 1e-12);
  expect_completed("particles on nodes",
                   run_case(kDiskWall, {"MPM/particles per cell=1", "MPM/domain min=[-0.625, -0.625]",
                                        "MPM/domain max=[0.625, 0.625]"}), 20);
}

TEST(Extreme, ParticlesOnGridLines) {
  // On vertical grid lines, at mid-cell in y.
  EXPECT_LT(off_line({"MPM/particles per cell=1", "MPM/domain min=[-0.625, -0.6]"}, 0), 1e-12);
  EXPECT_NEAR(off_line({"MPM/particles per cell=1", "MPM/domain min=[-0.625, -0.6]"}, 1), 0.025, 1e-12);
  expect_completed("particles on lines",
                   run_case(kDiskWall, {"MPM/particles per cell=1", "MPM/domain min=[-0.625, -0.6]",
                                        "MPM/domain max=[0.625, 0.6]"}), 20);
}

TEST(Extreme, NineParticlesPerCellInContact) {
  // A particle at each cell centre: grid nodes at 1.5 dx with weight 0.
  expect_completed("ppc=9", run_case(kDiskWall, {"MPM/particles per cell=9"}), 20);
}

TEST(Extreme, NineParticlesPerCellTightToleranceConverges) {
  // The Brazilian disk (A3) at 9 per cell with eps_d = 1e-8: after step 1 the
  // cell-centre particles have moved by ~1e-6 dx and reach the far nodes with
  // weights 1e-12..1e-8; Newton stalled at |p|/dt ~ 5e-7 m/s in step 2 (300
  // iterations: the direction at those nodes is round-off) until the
  // convergence test weighed grid nodes by their mass.
  const std::string disk = std::string(BFEMP_SOURCE_DIR) + "/inputs/a3_brazilian_disk.yaml";
  const Outcome o = run_case(disk, {"MPM/particles per cell=9", "Time/end time=0.04",
                                    "FEM Bodies/bottom/Mesh/center=[0.0, -1.0417167]",
                                    "FEM Bodies/top/Mesh/center=[0.0, 1.0417167]"});
  expect_completed("ppc=9, eps_d=1e-8", o, 4);
  EXPECT_LT(o.iterates, 4 * 30) << "Newton must converge in a few iterations per step, not stall";
}

TEST(Extreme, NearDegenerateWallElement) {
  // tests/data/sliver_wall.msh: the wall (x in [0.1, 0.3], y in [-0.4, 0.4])
  // as 4 triangles, one a sliver along the face the disk hits: (0.1, -0.4),
  // (0.1001, 0), (0.1, 0.4), height 1e-4 on a base of 0.8 (smallest angle
  // 2.5e-4 rad); the contact face is its two nearly collinear edges.
  expect_completed("sliver element",
                   run_case(kDiskWall, {"FEM Bodies/wall/Mesh/shape=none",
                                        "FEM Bodies/wall/Mesh/file=../tests/data/sliver_wall.msh"}), 20);
}

TEST(Extreme, TwentySevenParticlesPerCell3DInContact) {
  // The 3D twist scene (A7) at dx 0.25 with 27 particles per cell (a particle
  // at each cell centre: weight 0 at 1.5 dx), the shell lowered to 5 mm above
  // the top particles (z = 1 - dx / 6) so that it presses from step 1.
  const std::string twist = std::string(BFEMP_SOURCE_DIR) + "/inputs/a7_twist.yaml";
  expect_completed("ppc=27 (3D)",
                   run_case<3>(twist, {"MPM/grid spacing=0.25", "MPM/particles per cell=27",
                                       "FEM Bodies/shell/Mesh/center=[0.0, 0.0, 1.4633]",
                                       "FEM Bodies/shell/Mesh/element size=0.15", "Time/end time=0.03"}),
                   3);
}

TEST(Extreme, BodiesThatStartIntersectingAreRefused) {
  // The disk (radius 0.2) centred 0.1 m left of the wall's face overlaps it.
  expect_refused("intersecting", run_case(kDiskWall, {"MPM Bodies/disk/center=[0.05, 0.0]"}), "MPM particle");
}
