// BFEMP barrier contact in a running scene (inputs/contact_disk_wall.yaml):
// an MPM disk thrown at 100 m/s at a fixed FEM wall with dt ~ 25x the MPM
// CFL limit. Every Newton iterate is checked (debug hook): no particle inside
// or on the wall, every contact distance > 0; the disk bounces; the wall
// feels a positive contact force along +x while in contact. A scene whose
// disk starts inside the wall is refused before step 1; bad contact keys are
// named. 1 vs 2 threads through the executable. Two disks against two walls
// in one scene, with a per-pair friction coefficient and the force of one
// named wall, and the debug check of every Newton iterate switched on.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <limits>

#include "common/fem_fixtures.hpp"
#include "io/hdf5_frames.hpp"
#include "io/scene.hpp"

using namespace bfemp;

namespace {

const std::string scene_file = std::string(BFEMP_SOURCE_DIR) + "/inputs/contact_disk_wall.yaml";

}  // namespace

TEST(ContactImpact, DiskBouncesOffWallWithoutPenetratingAtAnyIterate) {
  const Scene scene = load_scene(scene_file);
  Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
  long iterates = 0, inside = 0;
  double dmin = std::numeric_limits<double>::infinity();
  sim.newton().on_iterate = [&](Kokkos::View<const double*, MemSpace> x) {
    ++iterates;
    if (sim.contact()->particle_inside_at(x) >= 0) ++inside;
    const auto act = sim.contact()->barrier()->active_pairs(x);
    auto d = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), act.distance);
    for (LO k = 0; k < act.count; ++k) dmin = std::min(dmin, d(k));
  };
  const double p0 = sim.diagnostics().momentum[0];
  ASSERT_GT(p0, 0.0);
  long contact_steps = 0;
  double fmax = 0, p_end = 0;
  for (int n = 0; n < 20; ++n) {
    const StepReport r = sim.step();
    if (r.contact_pairs > 0) {
      ++contact_steps;
      EXPECT_GT(r.min_distance, 0.0);
      EXPECT_GT(r.contact_force[0], 0.0) << "step " << r.step << ": the disk pushes the wall along +x";
    }
    fmax = std::max(fmax, r.contact_force[0]);
    p_end = r.momentum[0];
  }
  EXPECT_GT(iterates, 20);
  EXPECT_EQ(inside, 0) << "iterates with a particle inside the wall";
  EXPECT_GT(dmin, 0.0);
  EXPECT_GT(contact_steps, 2);
  EXPECT_LT(p_end, -0.1 * p0) << "the disk must bounce back";
  std::cout << "disk-wall: " << iterates << " Newton iterates, min distance over all iterates " << dmin
            << " m, contact during " << contact_steps << " steps, peak force " << fmax << " N/m, momentum "
            << p0 << " -> " << p_end << " kg m/s\n";
}

TEST(ContactImpact, RefusesAnIntersectingStart) {
  const Scene scene = load_scene(scene_file, {"MPM Bodies/disk/center={0.05, 0.0}"});
  try {
    Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
    FAIL() << "an intersecting start was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("starts inside or on an FEM body"), std::string::npos) << e.what();
  }
}

TEST(ContactImpact, BadContactKeysAreNamed) {
  for (const auto& [set, key] : std::vector<std::pair<std::string, std::string>>{
           {"Contact/dhat=-1.0", "Contact/dhat"},
           {"Contact/kappa=0.0", "Contact/kappa"},
           {"Contact/friction=-0.5", "Contact/friction"},
           {"Contact/force body=floor", "Contact/force body"}}) {
    try {
      load_scene(scene_file, {set});
      ADD_FAILURE() << set << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("'" + key + "'"), std::string::npos) << e.what();
    }
  }
  const std::string yaml = R"(bfemp:
  dimension: 2
  Materials: {m: {E: 1.0e6}}
  MPM: {grid spacing: 0.1, domain min: [-1.0, -1.0], domain max: [1.0, 1.0]}
  MPM Bodies: {disk: {material: m, shape: disk, outer radius: 0.2}}
  FEM Bodies: {wall: {material: m, Mesh: {shape: rectangle, center: [0.5, 0.0], size: [0.2, 0.5], element size: 0.1}}}
  Contact: {Friction Pairs: {'disk : floor': 0.3}}
)";
  const Scene s = load_scene_from_string(yaml, ".");
  try {
    build_setup<2>(s);
    ADD_FAILURE() << "a friction pair naming no body was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("Contact/Friction Pairs/disk : floor"), std::string::npos) << e.what();
  }
}

TEST(ContactImpact, SameWithOneAndTwoThreads) {
  const std::string exe = std::string(BFEMP_BINARY_DIR) + "/drivers/bfemp";
  auto run = [&](const std::string& threads) {
    const std::string dir = std::string(BFEMP_BINARY_DIR) + "/test_runs/contact_omp" + threads;
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(std::string(BFEMP_BINARY_DIR) + "/test_runs");
    const std::string cmd = "OMP_NUM_THREADS=" + threads + " OMP_PROC_BIND=false OPENBLAS_NUM_THREADS=1 " + exe +
                            " run " + scene_file + " --set 'Time/end time=0.01' --set 'Output/frame every=10' --output " +
                            dir + " > " + dir + ".log 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::vector<std::size_t> shape;
    return read_dataset(dir + "/bfemp.h5", "/frame_000001/particle_positions", &shape);
  };
  const auto a = run("1"), b = run("2");
  ASSERT_EQ(a.size(), b.size());
  double diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) diff = std::max(diff, std::abs(a[i] - b[i]));
  EXPECT_LT(diff, 1e-9) << "max particle position difference (m) after 10 contact steps";
  std::cout << "disk-wall, 1 vs 2 threads: max position difference " << diff << " m\n";
}

TEST(ContactImpact, TwoDisksTwoWallsPerPairFrictionAndNamedForceBody) {
  const std::string yaml = R"(bfemp:
  dimension: 2
  Time: {dt: 1.0e-3, end time: 2.0e-2}
  Newton: {eps_d: 1.0e-4, max iterations: 300}
  Materials:
    rubber: {E: 1.0e7, nu: 0.3, density: 1000.0}
    steel: {E: 2.0e9, nu: 0.3, density: 8000.0}
  MPM: {grid spacing: 0.05, domain min: [-1.0, -0.6], domain max: [1.0, 0.6], particles per cell: 4}
  MPM Bodies:
    a: {material: rubber, shape: disk, center: [-0.3, 0.0], outer radius: 0.15, initial velocity: [-100.0, 20.0]}
    b: {material: rubber, shape: disk, center: [0.3, 0.0], outer radius: 0.15, initial velocity: [100.0, 20.0]}
  FEM Bodies:
    west:
      material: steel
      Mesh: {shape: rectangle, center: [-0.65, 0.0], size: [0.2, 0.8], element size: 0.1}
      Boundary Conditions: {all: {box min: [-1.0, -1.0], box max: [0.0, 1.0]}}
    east:
      material: steel
      Mesh: {shape: rectangle, center: [0.65, 0.0], size: [0.2, 0.8], element size: 0.1}
      Boundary Conditions: {all: {box min: [0.0, -1.0], box max: [1.0, 1.0]}}
  Contact:
    dhat: 1.0e-3
    kappa: 1.0e6
    eps_v: 1.0e-3
    Friction Pairs: {'a : west': 0.5}
    force body: east
    check iterates: true
)";
  const Scene scene = load_scene_from_string(yaml, ".");
  Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
  ASSERT_TRUE(sim.contact()->has_friction());
  auto body_velocity = [&](int body) {
    const auto& p = sim.mpm()->particles();
    auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
    auto b = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.body);
    Vec<2> s = Vec<2>::Zero();
    int n = 0;
    for (std::size_t q = 0; q < b.extent(0); ++q)
      if (b(q) == body) {
        s += Vec<2>(v(q, 0), v(q, 1));
        ++n;
      }
    return Vec<2>(s / n);
  };
  long east_contact = 0;
  int max_friction_iters = 0;
  for (int n = 0; n < 20; ++n) {
    const StepReport r = sim.step();  // check iterates: a penetrating iterate throws
    if (r.contact_force[0] > 0) ++east_contact;
    EXPECT_GE(r.contact_force[0], 0.0) << "step " << r.step << ": only the east wall's force is reported";
    max_friction_iters = std::max(max_friction_iters, r.friction_iters);
  }
  const Vec<2> va = body_velocity(0), vb = body_velocity(1);
  EXPECT_GT(va(0), 10.0) << "disk a bounces off the west wall";
  EXPECT_LT(vb(0), -10.0) << "disk b bounces off the east wall";
  EXPECT_GT(east_contact, 2);
  EXPECT_GE(max_friction_iters, 2) << "the friction loop runs while a touches the west wall";
  // Friction (mu 0.5) on a against the west wall only: a loses tangential
  // velocity, b (frictionless) keeps it.
  EXPECT_LT(va(1), vb(1) - 1.0);
  EXPECT_NEAR(vb(1), 20.0, 1.0);
  std::cout << "two disks: a (mu 0.5) v = (" << va.transpose() << "), b (mu 0) v = (" << vb.transpose()
            << "), east-wall contact steps " << east_contact << ", max friction iterations " << max_friction_iters
            << "\n";
}
