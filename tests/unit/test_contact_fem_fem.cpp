// FEM-FEM barrier contact (2D, Contact/FEM-FEM): the boundary nodes of each
// FEM body are contact points (one-node stencils, omega = half the rest
// length of their boundary edges) against the other bodies' boundary
// primitives, never against their own. Checked: the energy of one vertex
// above an edge against the closed form; a body alone has no pair (its nodes
// lie on its own edges at d = 0); finite-difference checks of the barrier
// (exact Hessian, entry by entry, prescribed DOFs included) and of the lagged
// friction with points of both bodies in pairs; the start-up refusal of
// touching FEM bodies, naming the node and its body.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/fd_check.hpp"
#include "contact/contact.hpp"
#include "kernels/contact/barrier.hpp"

using namespace bfemp;

namespace {

// A unit square of 2 triangles, shifted by (sx, sy).
MeshData square(double sx, double sy) {
  MeshData m;
  m.dim = 2;
  m.coords = {sx, sy, sx + 1, sy, sx + 1, sy + 1, sx, sy + 1};
  m.cells = {0, 1, 2, 0, 2, 3};
  return m;
}

// One triangle with vertices a, b, c (counter-clockwise).
MeshData triangle(const Vec<2>& a, const Vec<2>& b, const Vec<2>& c) {
  MeshData m;
  m.dim = 2;
  m.coords = {a(0), a(1), b(0), b(1), c(0), c(1)};
  m.cells = {0, 1, 2};
  return m;
}

struct FemScene {
  FemMesh<2> mesh;
  std::unique_ptr<Contact<2>> contact;
  Kokkos::View<double*, MemSpace> x;
  LO n_nodes = 0;
};

ContactParams fem_params(double dhat, double mu = 0.0) {
  ContactParams cp;
  cp.dhat = dhat;
  cp.kappa = 1e3;
  cp.eps_v = 1e-2;
  cp.fem_fem = true;
  cp.mpm_bodies = 0;
  if (mu > 0) cp.mu.assign(2 * 2, mu);  // (0 MPM + 2 FEM) x 2 FEM
  return cp;
}

FemScene make_scene(std::vector<MeshData> meshes, const ContactParams& cp) {
  FemScene s;
  MaterialParams mp;
  mp.lame = lame_from_young(1e5, 0.3);
  mp.density = 1000;
  std::vector<FemBodyInput> bodies;
  for (std::size_t b = 0; b < meshes.size(); ++b) bodies.push_back({"body" + std::to_string(b), meshes[b], 0});
  s.mesh = build_fem_mesh<2>(bodies, {mp});
  s.n_nodes = s.mesh.num_nodes();
  s.x = Kokkos::View<double*, MemSpace>("x", s.n_nodes * 2);
  Kokkos::deep_copy(s.x, s.mesh.rest_position);
  s.contact = std::make_unique<Contact<2>>(s.mesh, cp);
  s.contact->begin_step(nullptr, s.x);
  return s;
}

void perturb(Kokkos::View<double*, MemSpace> x, double amp, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amp, amp);
  for (std::size_t i = 0; i < x.extent(0); ++i) x(i) += u(rng);
}

constexpr double kFdStep = 1e-6;  // as in test_contact_potentials (round-off vs truncation)

}  // namespace

TEST(ContactFemFem, OneVertexAboveAnEdgeHasTheClosedFormEnergy) {
  // The triangle's lowest vertex 0.04 above the square's top edge; every
  // other feature is farther than dhat from the other body.
  const double dhat = 0.1, d = 0.04;
  const Vec<2> a(0.5, 1.0 + d), b(1.5, 2.0), c(-0.5, 2.0);
  auto s = make_scene({square(0, 0), triangle(a, b, c)}, fem_params(dhat));
  EXPECT_EQ(s.contact->num_fem_points(), 7);  // 4 square corners + 3 triangle vertices
  const double omega = 0.5 * ((b - a).norm() + (c - a).norm());
  const double expected = omega * barrier(d, dhat, 1e3);
  EXPECT_NEAR(s.contact->barrier()->energy(s.x), expected, 1e-12 * expected);
  // The pair's force pushes the vertex up and the square's top nodes down,
  // equal and opposite (the sum over all nodes vanishes).
  Kokkos::View<double*, MemSpace> g("g", s.x.extent(0));
  s.contact->barrier()->gradient(s.x, 1.0, g);
  double sum_y = 0;
  for (LO n = 0; n < s.n_nodes; ++n) sum_y += g(n * 2 + 1);
  EXPECT_NEAR(sum_y, 0.0, 1e-12 * std::abs(g(4 * 2 + 1)));
  EXPECT_LT(g(4 * 2 + 1), 0.0);  // b decreases with d: the force -dB/dy on the vertex (node 4) points up
}

TEST(ContactFemFem, ABodyDoesNotContactItself) {
  // Every node of a body lies on two of its own edges (d = 0): a self pair
  // would make B infinite. The other body is far away.
  auto s = make_scene({square(0, 0), square(5, 0)}, fem_params(0.1));
  EXPECT_EQ(s.contact->barrier()->candidate_pairs(), 0);
  EXPECT_EQ(s.contact->barrier()->energy(s.x), 0.0);
}

TEST(ContactFemFem, BarrierDerivatives) {
  // Two squares 0.03 apart, the upper one shifted half a width: corners of
  // each above/below the other's edge interior, and corner-corner regions.
  auto s = make_scene({square(0, 0), square(0.5, 1.03)}, fem_params(0.1));
  perturb(s.x, 2e-3, 11);
  fixtures::check_exact_term<2>(*s.contact->barrier(), s.n_nodes, s.x, kFdStep, 1e-5);
}

TEST(ContactFemFem, FrictionDerivatives) {
  // Corners of each square over the other's edge interior only.
  auto s = make_scene({square(0, 0), square(0.5, 1.03)}, fem_params(0.1, 0.4));
  perturb(s.x, 1e-3, 13);
  Kokkos::View<double*, MemSpace> xref("xref", s.x.extent(0));
  Kokkos::deep_copy(xref, s.x);
  perturb(xref, 3e-3, 17);
  ASSERT_TRUE(s.contact->has_friction());
  s.contact->begin_step(nullptr, s.x);
  ASSERT_GT(s.contact->update_friction(s.x, xref, 1.0, 1.0), 0);
  const auto& friction = *s.contact->friction();
  ASSERT_GT(friction.energy(s.x), 0.0);
  fixtures::check_energy_term<2>(friction, s.n_nodes, s.x, kFdStep, 1e-5);
}

TEST(ContactFemFem, RefusesTouchingOrOverlappingBodiesAtTheStart) {
  auto ok = make_scene({square(0, 0), square(0.5, 1.01)}, fem_params(0.1));
  EXPECT_NO_THROW(ok.contact->check_initial_fem(ok.x));
  for (double sy : {1.0, 0.9}) {  // touching, overlapping
    auto s = make_scene({square(0, 0), square(0.5, sy)}, fem_params(0.1));
    try {
      s.contact->check_initial_fem(s.x);
      ADD_FAILURE() << "square at y = " << sy << " accepted";
    } catch (const std::invalid_argument& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find("FEM node"), std::string::npos) << w;
      EXPECT_NE(w.find("of body 'body"), std::string::npos) << w;
      EXPECT_NE(w.find("inside or on another FEM body"), std::string::npos) << w;
    }
  }
}

TEST(ContactFemFem, RefusedIn3D) {
  MeshData m;
  m.dim = 3;
  m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  m.cells = {0, 1, 2, 3};
  MaterialParams mp;
  mp.lame = lame_from_young(1e5, 0.3);
  const auto mesh = build_fem_mesh<3>({{"a", m, 0}}, {mp});
  ContactParams cp;
  cp.fem_fem = true;
  try {
    Contact<3> c(mesh, cp);
    ADD_FAILURE() << "3D FEM-FEM contact accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("Contact/FEM-FEM"), std::string::npos) << e.what();
  }
}
