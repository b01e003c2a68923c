// An FEM-only Simulation on the ranks of the default communicator (its
// elements cut by Zoltan2 RCB, the Newton step distributed, the FEM state
// replicated) equals the same scene run by each rank alone (MPI_COMM_SELF):
// positions, velocities and energies after 6 steps of a squashed neo-Hookean
// block with gravity, in 2D and 3D, with CG + Ifpack2 and CG + MueLu; and
// every rank reports the same Newton iterations. A one-triangle body, so that
// on 2 ranks one rank owns no element at all, equals the same on one rank.
// (Slip level sets on several ranks: test_mpm_mpi, MovingSlipLevelSet...)
#include <gtest/gtest.h>

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <Tpetra_Core.hpp>
#include <cmath>
#include <mpi.h>

#include "common/fem_fixtures.hpp"
#include "common/mpi_checks.hpp"
#include "common/mpm_fixtures.hpp"

using namespace bfemp;

namespace {

struct Result {
  std::vector<double> x, v;
  std::vector<int> iterations;
  double kinetic = 0, elastic = 0;
};

using fixtures::expect_same_on_every_rank;

// Six steps: the Newton iterations of each, the final energies and state.
template <int dim>
Result six_steps(Simulation<dim>& sim) {
  Result r;
  for (int s = 0; s < 6; ++s) {
    const StepReport rep = sim.step();
    r.iterations.push_back(rep.newton.iterations);
    r.kinetic = rep.kinetic;
    r.elastic = rep.elastic;
  }
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.positions());
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.velocities());
  r.x.assign(x.data(), x.data() + x.extent(0));
  r.v.assign(v.data(), v.data() + v.extent(0));
  return r;
}

template <int dim>
Result run(const Teuchos::RCP<const Comm>& comm, const std::string& prec) {
  auto setup = fixtures::block_setup<dim>(dim == 2 ? 0.08 : 0.25, 1e5, 0.35, 1000.0, 1.0, "CG");
  setup.dt = 1e-2;
  setup.gravity = {0.0, -9.81, 0.0};
  setup.newton.eps_d = 1e-9;
  setup.linear_solver.sublist("CG").set("preconditioner", prec);
  setup.linear_solver.sublist("CG").set("tolerance", 1e-13);
  if (prec == "RELAXATION")
    setup.linear_solver.sublist("CG").sublist("Ifpack2").set("relaxation: type", std::string("Symmetric Gauss-Seidel"));
  fixtures::prescribe<dim>(setup, "bottom");
  MotionSegment down;
  down.type = MotionType::Velocity;
  down.velocity = {0.0, -1.0, 0.0};
  fixtures::prescribe<dim>(setup, "top", {down});
  Simulation<dim> sim(setup, comm);
  return six_steps(sim);
}

template <int dim>
void distributed_equals_alone(const std::string& prec) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  const Result d = run<dim>(world, prec);
  const Result s = run<dim>(self, prec);
  ASSERT_EQ(d.x.size(), s.x.size());
  double ex = 0, ev = 0, vs = 0;
  for (std::size_t i = 0; i < d.x.size(); ++i) {
    ex = std::max(ex, std::abs(d.x[i] - s.x[i]));
    ev = std::max(ev, std::abs(d.v[i] - s.v[i]));
    vs = std::max(vs, std::abs(s.v[i]));
  }
  // Newton stops at |p|_inf / dt < 1e-9 m/s (dt 1e-2): 1e-11 m per coordinate.
  EXPECT_LT(ex, 1e-9) << dim << "D " << prec;
  EXPECT_LT(ev, 1e-7 * vs) << dim << "D " << prec;
  EXPECT_NEAR(d.kinetic, s.kinetic, 1e-8 * s.kinetic);
  EXPECT_NEAR(d.elastic, s.elastic, 1e-8 * s.elastic);
  expect_same_on_every_rank(*world, d.iterations);
  if (world->getRank() == 0) {
    int total = 0;
    for (int it : d.iterations) total += it;
    std::cout << dim << "D squash, " << world->getSize() << " rank(s), CG + " << prec << ": |x - x_alone| = " << ex
              << " m, |v - v_alone| = " << ev << " m/s, " << total << " Newton iterations in 6 steps\n";
  }
}

}  // namespace

TEST(SimulationMpi, FemSquash2DRelaxationEqualsOneRank) { distributed_equals_alone<2>("RELAXATION"); }
TEST(SimulationMpi, FemSquash2DMueLuEqualsOneRank) { distributed_equals_alone<2>("MUELU"); }
TEST(SimulationMpi, FemSquash3DMueLuEqualsOneRank) { distributed_equals_alone<3>("MUELU"); }

// One triangle (0,0), (1,0), (0,1): its bottom edge fixed, its top node
// falling under gravity. On 2 ranks RCB gives the element to one rank; the
// other owns no element and no DOF, and must still take every collective
// step (reductions, Export, Import) with the same result.
Result one_triangle(const Teuchos::RCP<const Comm>& comm) {
  SimulationSetup<2> setup = fixtures::block_setup<2>(0.5, 1e5, 0.3, 1000.0, 1.0, "CG");
  MeshData& m = setup.bodies[0].mesh;
  m.coords = {0.0, 0.0, 1.0, 0.0, 0.0, 1.0};
  m.cells = {0, 1, 2};
  m.node_sets = {{"bottom", {0, 1}}, {"top", {2}}};
  setup.dt = 1e-2;
  setup.gravity = {0.0, -9.81, 0.0};
  setup.linear_solver.sublist("CG").set("tolerance", 1e-13);
  fixtures::prescribe<2>(setup, "bottom");
  Simulation<2> sim(setup, comm);
  return six_steps(sim);
}

TEST(SimulationMpi, ARankWithoutElementsEqualsOneRank) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  const Result d = one_triangle(world);
  const Result s = one_triangle(self);
  ASSERT_EQ(d.x.size(), 6u);
  ASSERT_EQ(s.x.size(), 6u);
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_NEAR(d.x[i], s.x[i], 1e-10) << i;
    EXPECT_NEAR(d.v[i], s.v[i], 1e-8) << i;
  }
  EXPECT_LT(s.x[5], 1.0 - 1e-4) << "the top node should have fallen";
  EXPECT_NEAR(d.elastic, s.elastic, 1e-8 * s.elastic);
  expect_same_on_every_rank(*world, d.iterations);
}
