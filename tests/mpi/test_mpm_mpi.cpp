// MPM bodies on the ranks of the default communicator (particles cut into
// slabs, grid nodes owned by one rank and ghosted by the others, P2G summed
// over the ranks, particles migrating between slabs) equal the same scene run
// by each rank alone (MPI_COMM_SELF):
//   - 2D: a block flying at 3 m/s across the slab cut into a block at rest;
//     they meet on the grid and move on together. Every particle's position
//     and velocity (gathered in id order) after 40 steps, the energies, the
//     momentum (conserved: no gravity, no boundary) and the per-step Newton
//     iterations on every rank; on 2 ranks particles must have migrated.
//   - 3D: a cube thrown across the cut under gravity, 8 steps.
//   - MPM and FEM bodies in barrier contact (each rank: its particles' pairs
//     against the replicated FEM boundary; the FEM elements cut by Zoltan2):
//     the colliding rings (frictionless, 40 steps through the first contact)
//     and the disk thrown on an MPM floor with friction mu 0.5 (the lagged
//     friction loop, 10 steps): particles, FEM nodes, energies, contact pairs
//     and the contact force on every step. These scenes are sampled by id
//     blocks, each rank its own (build_setup with a ParticleBlock), and the
//     blocks then move into the boxes.
//   - A moving slip level set (the A2 sine press in its level-set form).
//   - FEM-FEM contact beside an MPM body (the A6 rings).
//   - The disk-wall impact and the box sliding on the slope with friction.
// On one rank (np1) the same tests compare the scene with itself through the
// same code path (distribute() is a no-op), which keeps them meaningful there.
#include <gtest/gtest.h>

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <Tpetra_Core.hpp>
#include <cmath>
#include <mpi.h>

#include "common/mpm_mpi_checks.hpp"
#include "io/scene.hpp"

using namespace bfemp;

namespace {

using fixtures::compare;
using fixtures::expect_same_on_every_rank;
using fixtures::run_steps;
using fixtures::set_velocity;
using fixtures::tight_cg;
using fixtures::Result;

SimulationSetup<2> two_blocks() {
  return fixtures::two_mpm_blocks(Vec<2>(0.5, 0.4), Vec<2>(1.3, 0.4), Vec<2>(2.4, 0.8), Vec<2>(3.0, 0.0),
                                  {"moving", "resting"});
}

}  // namespace

TEST(MpmMpi, BlockHittingABlockAcrossTheCutEqualsOneRank) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  Simulation<2> dist(two_blocks(), world);
  const Result d = run_steps(dist, 40);
  Simulation<2> alone(two_blocks(), self);
  const Result s = run_steps(alone, 40);
  // Newton stops at |p|_inf / dt < 1e-9 m/s (dt 5e-3): 5e-12 m per step.
  compare<2>(*world, d, s, 1e-9, "2D blocks");
  // No gravity, no boundary: the momentum of the start (3 m/s x the moving
  // block's mass), exactly up to the solver tolerance.
  EXPECT_NEAR(d.momentum[0], d.momentum0[0], 1e-9 * std::abs(d.momentum0[0]));
  EXPECT_NEAR(d.momentum[1], 0.0, 1e-9 * std::abs(d.momentum0[0]));
  if (world->getSize() > 1) {
    EXPECT_GT(d.migrated, 0) << "the moving block never crossed the slab cut: the test tests no migration";
    // Both blocks end on the right of the start cut, yet every rank keeps
    // particles of its slab.
    if (world->getRank() == 0) {
      // The centre of the pair moved right: x_c(t) = 0.9 + 1.5 t, t = 0.2 s.
      double xc = 0;
      for (std::size_t q = 0; q < d.x.size() / 2; ++q) xc += d.x[2 * q];
      xc /= static_cast<double>(d.x.size() / 2);
      EXPECT_NEAR(xc, 0.9 + 1.5 * 0.2, 1e-6);
    }
  }
}

// A grid node that several ranks hold is owned by the rank whose slab holds
// its position: one block across the cut(s), after a step, on every rank an
// active node is owned exactly when its position lies in the rank's slab.
// (Tpetra's default, the lowest holder, gives every shared node to the lower
// rank of a cut: rank 0 owned 9 nodes on rank 1's side here at 2 ranks.) The run still
// equals one rank.
TEST(MpmMpi, SharedGridNodesAreOwnedOnTheirSideOfTheCut) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  auto setup = [] {
    auto s = fixtures::mpm_rect_setup(1.2, 0.3, Vec<2>(1.2, 0.4), 0.05, 4, Vec<2>(0.0, 0.0), Vec<2>(2.4, 0.8),
                                      TransferScheme::APIC);
    set_velocity<2>(s.mpm->particles, 0, s.mpm->particles.size(), Vec<2>(0.5, -0.2));
    s.dt = 5e-3;
    s.integrator = TimeIntegrator::backward_euler();
    tight_cg(s);
    return s;
  };
  Simulation<2> dist(setup(), world);
  const Result d = run_steps(dist, 3);
  const auto& mpm = *dist.mpm();
  const auto& grid = mpm.grid();
  const auto boxes = mpm.boxes().mirror();
  const int axis = boxes.axis[0], rank = world->getRank();
  long wrong = 0, shared_owned = 0;
  const auto& g = mpm.global_nodes();  // owned first, then ghosts; no FEM nodes before them (empty on 1 rank)
  // (EXPECT, not ASSERT: every rank must reach compare()'s collective checks)
  const bool numbered = world->getSize() == 1 || static_cast<LO>(g.size()) == mpm.active_nodes();
  EXPECT_TRUE(numbered) << "rank " << rank << ": " << g.size() << " global node ids for " << mpm.active_nodes()
                        << " active nodes";
  for (std::size_t k = 0; numbered && k < g.size(); ++k) {
    Vec<2> c = grid.node_position(static_cast<LO>(g[k]));
    const int side = boxes.owner(c);
    const bool owned = static_cast<LO>(k) < mpm.owned_nodes();
    if (owned != (side == rank)) ++wrong;
    c(axis) -= 2 * grid.dx;  // within two cells of its lower cut
    if (owned && boxes.owner(c) != rank) ++shared_owned;
  }
  EXPECT_EQ(wrong, 0) << "rank " << rank << ": active nodes owned against their side of the cut";
  if (world->getSize() > 1 && rank > 0)
    EXPECT_GT(shared_owned, 0) << "rank " << rank << " owns no node just above its lower cut: the test tests nothing";
  Simulation<2> alone(setup(), self);
  const Result s = run_steps(alone, 3);
  compare<2>(*world, d, s, 1e-9, "2D block across the cut");
}

namespace {
// A 0.3 m cube thrown at 2 m/s across the cut at x = 0.6, under gravity; with
// slip_plane, over a slip plane tilted in x and z just below it.
SimulationSetup<3> thrown_cube(bool slip_plane) {
  auto s = fixtures::cube_setup(Vec<3>(0.45, 0.5, 0.5), Vec<3>(0.3, 0.3, 0.3), 0.1, Vec<3>(0.0, 0.0, 0.0),
                                Vec<3>(1.2, 1.0, 1.0), 8);
  set_velocity<3>(s.mpm->particles, 0, s.mpm->particles.size(), Vec<3>(2.0, 0.0, 0.0));
  s.gravity = {0.0, -9.81, 0.0};
  s.dt = 1e-2;
  tight_cg(s);
  if (slip_plane) {
    LevelSet plane;
    plane.name = "incline";
    plane.slip = true;
    plane.point = {0.45, 0.31, 0.5};
    const double len = std::sqrt(0.15 * 0.15 + 1.0 + 0.1 * 0.1);
    plane.normal = {0.15 / len, 1.0 / len, 0.1 / len};
    s.level_sets.push_back(plane);
  }
  return s;
}
}  // namespace

TEST(MpmMpi, CubeThrownAcrossTheCutEqualsOneRank3D) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  auto setup = [] { return thrown_cube(false); };
  Simulation<3> dist(setup(), world);
  const Result d = run_steps(dist, 8);
  Simulation<3> alone(setup(), self);
  const Result s = run_steps(alone, 8);
  compare<3>(*world, d, s, 1e-9, "3D cube");
  if (world->getSize() > 1) EXPECT_GT(d.migrated, 0);
}

// The same cube falling onto a tilted slip plane (normal with x and z parts)
// while it crosses the cut: the slip constraints of the grid nodes below it
// (owned and ghosts on both sides of the cut) as in 1 rank alone.
TEST(MpmMpi, CubeOnATiltedSlipPlaneAcrossTheCutEqualsOneRank3D) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  auto setup = [] { return thrown_cube(true); };
  Simulation<3> dist(setup(), world);
  const Result d = run_steps(dist, 8);
  int constrained = static_cast<int>(dist.newton().slip_constraints().count()), total = 0;
  Teuchos::reduceAll(*world, Teuchos::REDUCE_SUM, constrained, Teuchos::outArg(total));
  Simulation<3> alone(setup(), self);
  const Result s = run_steps(alone, 8);
  compare<3>(*world, d, s, 1e-9, "3D cube on a slip plane");
  EXPECT_GT(total, 0) << "no grid node under the slip plane: the test tests nothing of it";
  EXPECT_GT(alone.newton().slip_constraints().count(), 0);
  // Owned plus ghost copies: more than one rank's count once some constrained
  // node is held by two ranks (the cut runs through the constrained layer).
  if (world->getSize() > 1) EXPECT_GT(total, static_cast<int>(alone.newton().slip_constraints().count()));
  if (world->getSize() > 1) EXPECT_GT(d.migrated, 0);
}

namespace {

struct SceneResult {
  Result r;
  std::vector<double> fem_x;
  std::vector<long> pairs;
  std::vector<std::array<double, 3>> force;
  int fem_points = 0;  // this rank's FEM-FEM contact points
};

SceneResult run_scene_steps(const std::string& file, const std::vector<std::string>& overrides,
                            const Teuchos::RCP<const Comm>& comm, int steps) {
  std::vector<std::string> o = overrides;
  o.push_back("Linear Solver/type=CG");
  o.push_back("Linear Solver/CG/tolerance=1e-13");
  const Scene scene = load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/" + file, o);
  // Each rank samples its id block of the particles, as `bfemp run` does
  // (alone: every particle).
  Simulation<2> sim(build_setup<2>(scene, particle_block(*comm)), comm);
  SceneResult out;
  out.r.momentum0 = sim.diagnostics().momentum;
  for (int s = 0; s < steps; ++s) {
    const StepReport rep = sim.step();
    out.r.iterations.push_back(rep.newton.iterations);
    out.r.kinetic = rep.kinetic;
    out.r.elastic = rep.elastic;
    out.pairs.push_back(rep.contact_pairs);
    out.force.push_back(rep.contact_force);
  }
  const Particles<2> p = sim.mpm()->gathered_particles();
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  out.r.x.assign(x.data(), x.data() + x.size());
  out.r.v.assign(v.data(), v.data() + v.size());
  auto fx = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.positions());
  out.fem_x.assign(fx.data(), fx.data() + fx.size());
  out.r.migrated = sim.mpm()->migrated_particles();
  if (sim.contact()) out.fem_points = sim.contact()->num_fem_points();
  return out;
}

// The scene on the default communicator's ranks, then on each rank alone.
std::pair<SceneResult, SceneResult> on_world_and_alone(const std::string& file, const std::vector<std::string>& o,
                                                       int steps) {
  SceneResult d = run_scene_steps(file, o, Tpetra::getDefaultComm(), steps);
  SceneResult s = run_scene_steps(file, o, Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF)), steps);
  return {std::move(d), std::move(s)};
}

void compare_scenes(const Comm& world, const SceneResult& d, const SceneResult& s, double x_tol, double f_tol,
                    const std::string& what) {
  compare<2>(world, d.r, s.r, x_tol, what);
  ASSERT_EQ(d.fem_x.size(), s.fem_x.size());
  double ef = 0;
  for (std::size_t i = 0; i < d.fem_x.size(); ++i) ef = std::max(ef, std::abs(d.fem_x[i] - s.fem_x[i]));
  EXPECT_LT(ef, x_tol) << what << ": FEM nodes";
  long touching = 0;
  double fmax = 0;
  for (std::size_t k = 0; k < d.pairs.size(); ++k) {
    EXPECT_EQ(d.pairs[k], s.pairs[k]) << what << ": contact pairs at step " << k + 1;
    touching += d.pairs[k] > 0;
    for (int c = 0; c < 2; ++c) fmax = std::max(fmax, std::abs(s.force[k][c]));
  }
  for (std::size_t k = 0; k < d.force.size(); ++k)
    for (int c = 0; c < 2; ++c) EXPECT_NEAR(d.force[k][c], s.force[k][c], f_tol * fmax) << what << ": force, step " << k + 1;
  EXPECT_GT(touching, 0) << what << ": no contact; the test tests nothing of it";
  if (world.getRank() == 0) std::cout << what << ": |x_fem - alone| = " << ef << " m, " << touching << " steps in contact\n";
}

}  // namespace

TEST(MpmMpi, CollidingRingsMpmFemContactEqualsOneRank) {
  const auto [d, s] = on_world_and_alone("contact_rings.yaml", {"Time/end time=0.04", "Newton/eps_d=1e-9"}, 40);
  // Newton stops at |p|/dt < 1e-9 m/s (dt 1e-3): 1e-12 m per step; the
  // barrier's stiffness amplifies it through contact (measured 1e-12 m).
  compare_scenes(*Tpetra::getDefaultComm(), d, s, 1e-9, 1e-6, "rings");
}

// With every friction pass at eps_d ('Contact/friction pass tolerance' 1)
// both runs take the same Newton path and agree to round-off (velocities to
// 1e-6 of their largest, 1e-10 m/s measured). With the default (10), the
// passes before the loop settles stop at 10 eps_d, which leaves the end
// state less pinned between two runs whose sums differ in the last bits
// (measured 1.7e-8 m/s on 2 ranks, 1e-6 relative would be 1e-8): there the
// runs must agree to the Newton tolerance, |v - v_alone| < eps_d = 1e-4 m/s.
TEST(MpmMpi, DiskOnMpmFloorWithFrictionEqualsOneRank) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  const std::vector<std::string> o = {"Time/end time=0.02", "Contact/friction pass tolerance=1"};
  const SceneResult d = run_scene_steps("default_contact.yaml", o, world, 10);
  const SceneResult s = run_scene_steps("default_contact.yaml", o, self, 10);
  compare_scenes(*world, d, s, 1e-8, 1e-5, "disk with friction");

  const std::vector<std::string> od = {"Time/end time=0.02"};
  const SceneResult dd = run_scene_steps("default_contact.yaml", od, world, 10);
  const SceneResult sd = run_scene_steps("default_contact.yaml", od, self, 10);
  expect_same_on_every_rank(*world, dd.r.iterations);
  if (world->getRank() != 0) return;
  ASSERT_EQ(dd.r.v.size(), sd.r.v.size());
  double ev = 0, ex = 0;
  for (std::size_t i = 0; i < dd.r.v.size(); ++i) {
    ev = std::max(ev, std::abs(dd.r.v[i] - sd.r.v[i]));
    ex = std::max(ex, std::abs(dd.r.x[i] - sd.r.x[i]));
  }
  EXPECT_LT(ev, 1e-4) << "m/s: the scene's eps_d";
  EXPECT_LT(ex, 10 * 2e-3 * 1e-4) << "m: eps_d dt per step over 10 steps";
  std::cout << "disk with friction, default friction pass tolerance, " << world->getSize()
            << " rank(s): |x - x_alone| = " << ex << " m, |v - v_alone| = " << ev << " m/s\n";
}

// The disk-wall impact (an MPM rubber disk at 100 m/s into a fixed FEM steel
// wall: 8 of the 20 steps in contact) and the box on the slope (VALIDATION
// A4's scene: a stiff MPM box on a tilted-gravity FEM slope, with friction
// mu 0.1, below the critical 0.2, so that the lagged friction loop runs on
// every step in contact).
TEST(MpmMpi, DiskWallImpactEqualsOneRank) {
  const auto [d, s] = on_world_and_alone("contact_disk_wall.yaml", {"Newton/eps_d=1e-9"}, 20);
  compare_scenes(*Tpetra::getDefaultComm(), d, s, 1e-9, 1e-6, "disk-wall impact");
}

TEST(MpmMpi, BoxSlidingOnTheSlopeWithFrictionEqualsOneRank) {
  const auto [d, s] = on_world_and_alone(
      "contact_slope.yaml", {"Time/end time=0.04", "Contact/friction=0.1", "Contact/friction pass tolerance=1"}, 40);
  compare_scenes(*Tpetra::getDefaultComm(), d, s, 1e-9, 1e-6, "box on the slope, mu 0.1");
}

// The same with the friction loop lagged at Aitken-relaxed points from its
// third pass (Contact/friction relaxation from = 3; 3 of the 40 steps' loops
// reach a third pass): omega comes from dot products over the owned DOFs
// summed over the ranks, so every rank lags at the same point and the run
// equals one rank.
TEST(MpmMpi, BoxSlidingOnTheSlopeWithRelaxedFrictionPassesEqualsOneRank) {
  const auto [d, s] = on_world_and_alone("contact_slope.yaml",
                                         {"Time/end time=0.04", "Contact/friction=0.1",
                                          "Contact/friction pass tolerance=1", "Contact/friction relaxation from=3"},
                                         40);
  compare_scenes(*Tpetra::getDefaultComm(), d, s, 1e-9, 1e-6, "box on the slope, mu 0.1, relaxed passes");
}

// A moving slip level set (VALIDATION A2's sine press, level-set form): the
// sine boundary presses the box down for 0.04 s, then drags left, as an exact
// constraint on the grid nodes inside it (n . v = the boundary's, tangent
// free; SlipConstraints). On 2 ranks each rank builds the constraints of its
// owned and ghost nodes and transforms its overlap part of the system; the
// run equals one rank alone. Checked to mean something: the press moves the
// box down (its particles' mean height falls; nothing else moves it).
TEST(MpmMpi, MovingSlipLevelSetEqualsOneRank) {
  auto world = Tpetra::getDefaultComm();
  const auto [d, s] = on_world_and_alone("a2_sine_press_levelset.yaml", {"Time/end time=0.06", "Newton/eps_d=1e-9"}, 30);
  // Newton stops at |p|_inf / dt < 1e-9 m/s (dt 2e-3): 2e-12 m per step.
  compare<2>(*world, d.r, s.r, 1e-9, "sine press, slip level set");
  if (world->getRank() != 0) return;
  // Start: the box [0, 0.5]^2 at rest, no gravity: its particles' mean y is
  // 0.25, and only the boundary moves it. The sine's troughs reach
  // y = 0.535 - 0.025 - 0.04 = 0.47 at 0.04 s, 0.024 m into the box.
  double mean_y = 0;
  for (std::size_t i = 1; i < d.r.x.size(); i += 2) mean_y += d.r.x[i];
  mean_y /= static_cast<double>(d.r.x.size() / 2);
  EXPECT_LT(mean_y, 0.25 - 1e-3) << "the slip boundary did not press the box";
  std::cout << "sine press (slip level set), " << world->getSize() << " rank(s): particles' mean y = " << mean_y
            << " m (0.25 at the start)\n";
}

// FEM-FEM contact beside MPM bodies (VALIDATION A6 at the ci size: an FEM
// plate pressing an FEM outer ring with mu 10, FEM-FEM, which presses the MPM
// inner ring through MPM-FEM contact, with mu 0.2 between the rings, and a
// slip box under the middle). Each FEM contact point lives on the rank owning
// its node (Contact::keep_fem_points), each particle on its slab's rank: every
// pair once. 60 steps (0.6 m of plate travel): the plate-ring pairs from the
// first steps, the ring-ring pairs once the 0.01 m gap has closed.
TEST(MpmMpi, FemFemContactBesideMpmEqualsOneRank) {
  auto world = Tpetra::getDefaultComm();
  const auto [d, s] = on_world_and_alone("a6_semiring_buckling.yaml",
                                         {"Time/end time=0.6", "Newton/eps_d=1e-9",
                                          "Contact/Friction Pairs/inner : outer=0.2",
                                          "Contact/friction pass tolerance=1"},
                                         60);
  compare_scenes(*world, d, s, 1e-8, 1e-6, "A6 rings (FEM-FEM + MPM-FEM)");
  // Every FEM boundary node is a contact point on exactly one rank, and (the
  // plate and ring cut by RCB) every rank holds some.
  int points = 0, fewest = 0;
  Teuchos::reduceAll(*world, Teuchos::REDUCE_SUM, d.fem_points, Teuchos::outArg(points));
  Teuchos::reduceAll(*world, Teuchos::REDUCE_MIN, d.fem_points, Teuchos::outArg(fewest));
  EXPECT_EQ(points, s.fem_points);
  EXPECT_GT(fewest, 0);
  // The plate presses the outer ring into the inner one: the MPM ring's
  // crown has moved down by then.
  if (world->getRank() != 0) return;
  double top = 0;
  for (std::size_t i = 0; i + 1 < d.r.x.size(); i += 2)
    if (std::abs(d.r.x[i]) < 1.0) top = std::max(top, d.r.x[i + 1]);
  EXPECT_LT(top, 11.99 - 0.1) << "the inner ring's crown did not move down: no ring-ring contact";
  std::cout << "A6 rings, " << world->getSize() << " rank(s): the inner ring's crown top at y = " << top << " m\n";
}

// A particle starting inside the FEM ring is found by the rank holding it;
// every rank stops before the first step with that rank's message (rank 0
// prints it), instead of the others waiting in the next collective call.
TEST(MpmMpi, ParticleStartingInsideAnFemBodyStopsEveryRank) {
  auto world = Tpetra::getDefaultComm();
  const Scene scene = load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/contact_rings.yaml",
                                 {"MPM Bodies/left/center=[1.5, 0.0]", "Linear Solver/type=CG"});
  std::string msg;
  try {
    Simulation<2> sim(build_setup<2>(scene), world);
  } catch (const std::invalid_argument& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("MPM particle"), std::string::npos) << "'" << msg << "'";
  int len = static_cast<int>(msg.size()), lo = 0, hi = 0;
  Teuchos::reduceAll(*world, Teuchos::REDUCE_MIN, len, Teuchos::outArg(lo));
  Teuchos::reduceAll(*world, Teuchos::REDUCE_MAX, len, Teuchos::outArg(hi));
  EXPECT_EQ(lo, hi) << "the ranks stopped with different messages";
}

// A scene of 2 particles sampled by id blocks: on 3 ranks rank 0's block is
// empty (and on 2 ranks each holds one); the particles fall under gravity
// and the run equals one rank alone.
TEST(MpmMpi, SceneWithEmptyParticleBlocksEqualsOneRank) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  const std::string yaml = R"(bfemp:
  dimension: 2
  gravity: [0.0, -10.0]
  Time: {dt: 1.0e-2, end time: 0.05, integrator: backward-euler}
  Newton: {eps_d: 1.0e-9}
  Materials:
    soft: {E: 1.0e4, nu: 0.3, density: 1000.0}
  MPM: {grid spacing: 0.1, domain min: [0.0, 0.0], domain max: [1.0, 1.0], particles per cell: 1}
  MPM Bodies:
    pair: {material: soft, shape: box, center: [0.5, 0.6], size: [0.1, 0.2]}
  Linear Solver: {type: CG, CG: {tolerance: 1.0e-13}}
)";
  const Scene scene = load_scene_from_string(yaml, ".");
  auto run = [&](const Teuchos::RCP<const Comm>& comm) {
    SimulationSetup<2> setup = build_setup<2>(scene, particle_block(*comm));
    EXPECT_EQ(static_cast<long long>(setup.mpm->particles.size()),
              2LL * (comm->getRank() + 1) / comm->getSize() - 2LL * comm->getRank() / comm->getSize());
    Simulation<2> sim(std::move(setup), comm);
    EXPECT_EQ(sim.mpm()->total_particles(), 2);
    return run_steps(sim, 5);
  };
  const Result d = run(world);
  const Result s = run(self);
  compare<2>(*world, d, s, 1e-9, "2 particles");
  if (world->getRank() == 0) {
    ASSERT_EQ(d.x.size(), 4u);
    // Free fall over 5 backward-Euler steps: y drops by g dt^2 (1 + ... + 5).
    EXPECT_NEAR(d.x[1], 0.55 - 10.0 * 1e-4 * 15, 1e-6);
  }
}

// 'MPM/when particles leave: extend' on 2 ranks: both blocks move right
// (3 and 2 m/s) and leave a tight grid on one rank's side; every rank grows the grid alike (bounding box
// of all ranks' particles), and the run equals one rank alone, the same
// number of extensions included.
TEST(MpmMpi, GridExtendedAlikeOnEveryRankEqualsOneRank) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  auto setup = [] {
    auto s = two_blocks();
    s.mpm->grid = grid_covering<2>(Vec<2>(0.3, 0.2), Vec<2>(1.5, 0.6), 0.05);  // the blocks just fit
    s.mpm->extend_domain = true;
    const std::size_t n = s.mpm->particles.size();  // the right block (second half) moves too
    set_velocity<2>(s.mpm->particles, n / 2, n, Vec<2>(2.0, 0.0));
    return s;
  };
  Simulation<2> dist(setup(), world);
  const Result d = run_steps(dist, 40);
  Simulation<2> alone(setup(), self);
  const Result s = run_steps(alone, 40);
  EXPECT_GT(alone.mpm()->domain_extensions(), 0) << "the grid never grew: the test tests nothing";
  EXPECT_EQ(dist.mpm()->domain_extensions(), alone.mpm()->domain_extensions());
  compare<2>(*world, d, s, 1e-9, "2D blocks, growing grid");
}

// Slab rebalancing ('MPM/rebalance above'): both blocks fly right at 2 m/s
// for 0.3 s; the left one crosses the start cut (x = 1.15, between them), so
// that without new cuts the right slab ends with 2/3 of the particles
// (imbalance 1.33). With 1.2 the cuts move and no step ends above 1.2; with 0
// they never move. Both runs equal one rank alone.
TEST(MpmMpi, SlabsRebalanceWhenParticlesCrowdOneRank) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  auto setup = [](double rebalance_above) {
    auto s = two_blocks();
    s.mpm->rebalance_above = rebalance_above;
    set_velocity<2>(s.mpm->particles, 0, s.mpm->particles.size(), Vec<2>(2.0, 0.0));
    return s;
  };
  Simulation<2> alone(setup(1.2), self);
  const Result s = run_steps(alone, 60);
  for (double above : {1.2, 0.0}) {
    Simulation<2> dist(setup(above), world);
    const Result d = run_steps(dist, 60);
    compare<2>(*world, d, s, 1e-9, above > 0 ? "2D blocks, rebalanced slabs" : "2D blocks, fixed slabs");
    if (world->getSize() == 1) continue;
    if (above > 0) {
      EXPECT_GE(dist.mpm()->rebalances(), 1);
      EXPECT_LE(d.worst_imbalance, 1.2);
    } else {
      EXPECT_EQ(dist.mpm()->rebalances(), 0);
      EXPECT_GT(dist.mpm()->imbalance(), 1.25);
    }
    if (world->getRank() == 0)
      std::cout << "rebalance above " << above << ": " << dist.mpm()->rebalances() << " rebalance(s), worst imbalance "
                << d.worst_imbalance << ", at the end " << dist.mpm()->imbalance() << "\n";
  }
}

// rebalanced_boxes (slabs) on a known histogram: grid covering [0, 1]^2, dx 0.1
// (faces -0.1 .. 1.1 along x); of 20 particles, 6 lie below the grid
// (x = -0.5), 4 inside (x = 0.25) and 10 above it (x = 1.5), spread over the
// ranks by index. On 2 ranks the cut that
// halves them is the grid's top face (10 below it, 10 above), the largest
// slab 10, on every rank alike; particles outside the grid are counted on
// their own side of the faces.
TEST(MpmMpi, RebalancedCutsCountParticlesOutsideTheGridOnTheirSide) {
  auto world = Tpetra::getDefaultComm();
  const int me = world->getRank(), n = world->getSize();
  const GridSpec<2> grid = grid_covering<2>(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), 0.1);
  std::vector<double> xs;
  for (int q = 0; q < 20; ++q)
    if (q % n == me) xs.push_back(q < 6 ? -0.5 : q < 10 ? 0.25 : 1.5);
  Particles<2> p = allocate_particles<2>(xs.size());
  auto xh = Kokkos::create_mirror_view(p.x);
  for (std::size_t q = 0; q < xs.size(); ++q) {
    xh(q, 0) = xs[q];
    xh(q, 1) = 0.5;
  }
  Kokkos::deep_copy(p.x, xh);
  const RankBoxes<2> old = box_layout<2>(grid, n);
  ASSERT_EQ(old.axis[0], 0);
  ASSERT_EQ(old.levels, 1);  // slabs on 1-3 ranks
  long long largest = 0;
  const RankBoxes<2> s = rebalanced_boxes<2>(p, old, grid, *world, largest);
  auto cuts = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), s.cuts);
  ASSERT_EQ(static_cast<int>(cuts.extent(0)), n - 1);
  if (n == 1) {
    EXPECT_EQ(largest, 20);
  } else if (n == 2) {
    EXPECT_NEAR(cuts(0), grid.origin(0) + grid.n_cells[0] * grid.dx, 1e-12);
    EXPECT_EQ(largest, 10);
  }
  for (std::size_t k = 0; k + 1 < cuts.extent(0); ++k) EXPECT_LE(cuts(k), cuts(k + 1));
  std::vector<double> mine(cuts.data(), cuts.data() + cuts.extent(0)), lo(mine.size() + 1), hi(mine.size() + 1);
  mine.push_back(static_cast<double>(largest));
  const int k = static_cast<int>(mine.size());
  Teuchos::reduceAll(*world, Teuchos::REDUCE_MIN, k, mine.data(), lo.data());
  Teuchos::reduceAll(*world, Teuchos::REDUCE_MAX, k, mine.data(), hi.data());
  EXPECT_EQ(lo, hi) << "the ranks computed different cuts";
}

// migrate_particles' counts from its one reduction: 12 particles at x = 0.05,
// 0.15, ..., 1.15 (ids 0..11), all starting on rank 0, in slabs cut at
// 0.4, 0.8, ... (2 ranks: at 0.4 only). Every rank must report the same moved
// total (the particles outside slab 0) and the largest slab's count after
// the exchange, and hold exactly the particles of its own slab.
TEST(MpmMpi, MigrationReportsMovedAndLargestFromOneReduction) {
  auto world = Tpetra::getDefaultComm();
  const int me = world->getRank(), n = world->getSize();
  const int np = me == 0 ? 12 : 0;
  Particles<2> p = allocate_particles<2>(np);
  Kokkos::View<long long*, MemSpace> ids("ids", np);
  auto xh = Kokkos::create_mirror_view(p.x);
  auto ih = Kokkos::create_mirror_view(ids);
  for (int q = 0; q < np; ++q) {
    xh(q, 0) = 0.05 + 0.1 * q;
    xh(q, 1) = 0.5;
    ih(q) = q;
  }
  Kokkos::deep_copy(p.x, xh);
  Kokkos::deep_copy(ids, ih);
  RankBoxes<2> slabs;
  slabs.axis[0] = 0;
  slabs.parts[0] = n;
  slabs.nranks = n;
  slabs.cuts = decltype(slabs.cuts)("cuts", n - 1);
  auto ch = Kokkos::create_mirror_view(slabs.cuts);
  for (int k = 0; k + 1 < n; ++k) ch(k) = 0.4 * (k + 1);
  Kokkos::deep_copy(slabs.cuts, ch);
  long long largest = -1;
  const long long moved = migrate_particles<2>(p, ids, slabs, *world, largest);
  // Slab counts: x < 0.4: 4 particles; 0.4 <= x < 0.8: 4; the rest 4 (3 ranks).
  if (n == 1) {
    EXPECT_EQ(moved, 0);
    EXPECT_EQ(largest, 12);
  } else if (n == 2) {
    EXPECT_EQ(moved, 8);
    EXPECT_EQ(largest, 8);
    EXPECT_EQ(static_cast<int>(p.size()), me == 0 ? 4 : 8);
  } else if (n == 3) {
    EXPECT_EQ(moved, 8);
    EXPECT_EQ(largest, 4);
    EXPECT_EQ(static_cast<int>(p.size()), 4);
  }
  long long total = 0, mine = static_cast<long long>(p.size());
  Teuchos::reduceAll(*world, Teuchos::REDUCE_SUM, mine, Teuchos::outArg(total));
  EXPECT_EQ(total, 12);
  long long largest_seen = 0;
  Teuchos::reduceAll(*world, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(largest_seen));
  EXPECT_EQ(largest, largest_seen);
  auto xa = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  for (std::size_t q = 0; q < p.size(); ++q) {
    const double x = xa(q, 0);
    if (me > 0) EXPECT_GE(x, ch(me - 1));
    if (me + 1 < n) EXPECT_LT(x, ch(me));
  }
}
