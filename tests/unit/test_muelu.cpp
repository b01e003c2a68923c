// MueLu as CG's preconditioner (solver/muelu_preconditioner.hpp):
//  - the rigid-body modes handed to it as near-null space are zero-energy
//    modes of the FEM elasticity (E(X + eps r) = O(eps^4) for each mode, O(eps^2)
//    for a stretch), in 2D and 3D;
//  - Newton with CG + MueLu reaches the Cholmod solution of a compressed block
//    to solver tolerance, builds a hierarchy on new rigid-body modes every
//    'MueLu rebuild every' steps and reuses it in between;
//  - a misspelled MueLu key stops at construction, naming the sublist and key.
#include <gtest/gtest.h>

#include <Tpetra_Core.hpp>
#include <Tpetra_MultiVector.hpp>
#include <cmath>

#include "common/fem_fixtures.hpp"
#include "solver/muelu_preconditioner.hpp"

using namespace bfemp;

namespace {

template <int dim>
void modes_are_zero_energy(double h) {
  auto setup = fixtures::block_setup<dim>(h);
  setup.gravity = {0, 0, 0};
  Simulation<dim> sim(setup, fixtures::comm());
  auto x = sim.positions();
  const std::size_t n = x.extent(0);
  Kokkos::View<double*, MemSpace> X("X", n);
  Kokkos::deep_copy(X, x);
  auto map = Teuchos::rcp(new Map(n, 0, Teuchos::rcp(new Teuchos::SerialComm<int>())));
  constexpr int nm = dim == 2 ? 3 : 6;
  MultiVec modes(map, nm);
  rigid_body_modes<dim>(X, modes);
  auto mh = modes.getLocalViewHost(Tpetra::Access::ReadOnly);
  auto Xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), X);
  const double eps = 1e-3;
  auto energy_along = [&](auto&& dir) {
    auto xh = Kokkos::create_mirror_view(x);
    for (std::size_t i = 0; i < n; ++i) xh(i) = Xh(i) + eps * dir(i);
    Kokkos::deep_copy(x, xh);
    return sim.diagnostics().elastic;
  };
  // Reference: a uniform stretch of the same size along x (not a null mode).
  const double stretch = energy_along([&](std::size_t i) { return i % dim == 0 ? Xh(i) : 0.0; });
  ASSERT_GT(stretch, 0.0);
  for (int k = 0; k < nm; ++k) {
    double norm2 = 0;
    for (std::size_t i = 0; i < n; ++i) norm2 += mh(i, k) * mh(i, k);
    ASSERT_GT(norm2, 0.0) << "mode " << k;
    const double e = energy_along([&](std::size_t i) { return mh(i, k); });
    // Translations: exactly 0; rotations: strain O(eps^2) -> energy O(eps^4),
    // against O(eps^2) for the stretch (modes are O(1) like the stretch).
    EXPECT_LT(std::abs(e), 1e-4 * stretch) << dim << "D mode " << k << ": energy " << e << " vs stretch " << stretch;
  }
}

template <int dim>
std::vector<double> squash(const std::string& solver, const std::string& prec, int* setups = nullptr,
                           int* newton_its = nullptr, int rebuild_every = 10) {
  auto setup = fixtures::block_setup<dim>(dim == 2 ? 0.1 : 0.25, 1e5, 0.35, 1000.0, 1.0, solver);
  setup.dt = 1e-2;
  setup.newton.eps_d = 1e-9;
  fixtures::prescribe<dim>(setup, "bottom");
  MotionSegment down;
  down.type = MotionType::Velocity;
  down.velocity = {0.0, -1.0, 0.0};
  fixtures::prescribe<dim>(setup, "top", {down});
  if (solver == "CG") {
    setup.linear_solver.sublist("CG").set("preconditioner", prec);
    setup.linear_solver.sublist("CG").set("tolerance", 1e-13);
    setup.linear_solver.sublist("CG").set("MueLu rebuild every", rebuild_every);
    // A small coarse size, so that these small blocks get a real multilevel
    // hierarchy (by default they would be one level: a direct solve).
    setup.linear_solver.sublist("CG").sublist("MueLu").set("coarse: max size", 60);
  }
  Simulation<dim> sim(setup, fixtures::comm());
  int its = 0;
  for (int s = 0; s < 5; ++s) its += sim.step().newton.iterations;
  if (setups) *setups = sim.newton().linear_solver().preconditioner_setups();
  if (newton_its) *newton_its = its;
  auto xh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.positions());
  return std::vector<double>(xh.data(), xh.data() + xh.extent(0));
}

template <int dim>
void muelu_matches_cholmod() {
  const auto ref = squash<dim>("Cholmod", "NONE");
  int setups = 0, its = 0;
  const auto mg = squash<dim>("CG", "MUELU", &setups, &its, 2);
  ASSERT_EQ(ref.size(), mg.size());
  double err = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) err = std::max(err, std::abs(ref[i] - mg[i]));
  // Both stop at |p|_inf / dt < 1e-9 m/s (dt 1e-2): 1e-11 m per iterate;
  // against a 5 cm squash.
  EXPECT_LT(err, 1e-9) << dim << "D";
  // New modes (a new hierarchy) at steps 1, 3, 5 ('MueLu rebuild every' 2),
  // the hierarchy reused in between (the graph never changes here).
  EXPECT_EQ(setups, 3);
  int setups10 = 0;
  const auto mg10 = squash<dim>("CG", "MUELU", &setups10, nullptr, 10);
  EXPECT_EQ(setups10, 1) << "one hierarchy for 5 steps with 'MueLu rebuild every' 10";
  for (std::size_t i = 0; i < ref.size(); ++i) ASSERT_LT(std::abs(ref[i] - mg10[i]), 1e-9) << i;
  EXPECT_GT(its, 5);
  std::cout << dim << "D squash: |x_MueLu - x_Cholmod|_inf = " << err << " m, " << its
            << " Newton iterations, " << setups << " MueLu set-ups\n";
}

}  // namespace

TEST(MueLu, RigidBodyModesAreZeroEnergyModes2D) { modes_are_zero_energy<2>(0.2); }
TEST(MueLu, RigidBodyModesAreZeroEnergyModes3D) { modes_are_zero_energy<3>(0.34); }

TEST(MueLu, NewtonWithMueLuMatchesCholmod2D) { muelu_matches_cholmod<2>(); }
TEST(MueLu, NewtonWithMueLuMatchesCholmod3D) { muelu_matches_cholmod<3>(); }

TEST(MueLu, MisspelledKeyStopsAtConstruction) {
  Teuchos::ParameterList ls = *linear_solver_schema();
  ls.set("type", std::string("CG"));
  ls.sublist("CG").set("preconditioner", std::string("MUELU"));
  ls.sublist("CG").sublist("MueLu").set("smoother: tipe", std::string("CHEBYSHEV"));
  try {
    LinearSolver s(ls, fixtures::comm());
    FAIL() << "a misspelled MueLu key was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("Linear Solver/CG/MueLu"), std::string::npos) << msg;
    EXPECT_NE(msg.find("smoother: tipe"), std::string::npos) << msg;
  }
  // The right spelling is accepted.
  ls.sublist("CG").sublist("MueLu").remove("smoother: tipe");
  ls.sublist("CG").sublist("MueLu").set("smoother: type", std::string("CHEBYSHEV"));
  EXPECT_NO_THROW(LinearSolver(ls, fixtures::comm()));
}

TEST(MueLu, DefaultForCgAndKeysOfTheOtherPreconditionerRefused) {
  Teuchos::ParameterList ls = *linear_solver_schema();
  EXPECT_EQ(ls.sublist("CG").get<std::string>("preconditioner"), "BLOCK_CHOLMOD") << "CG's default, by measurement";
  ls.set("type", std::string("CG"));
  ls.sublist("CG").set("preconditioner", std::string("MUELU"));
  ls.sublist("CG").sublist("Ifpack2").set("relaxation: sweeps", 2);
  try {
    LinearSolver s(ls, fixtures::comm());
    FAIL() << "Ifpack2 keys accepted with MUELU";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("Linear Solver/CG/Ifpack2"), std::string::npos) << msg;
    EXPECT_NE(msg.find("relaxation: sweeps"), std::string::npos) << msg;
  }
  Teuchos::ParameterList ls2 = *linear_solver_schema();
  ls2.set("type", std::string("CG"));
  ls2.sublist("CG").set("preconditioner", std::string("CHEBYSHEV"));
  ls2.sublist("CG").sublist("MueLu").set("coarse: max size", 100);
  EXPECT_THROW(LinearSolver(ls2, fixtures::comm()), std::invalid_argument);
}
