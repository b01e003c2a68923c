// The contact potentials on the system DOFs (FEM nodes + active MPM grid
// nodes): finite-difference checks of the barrier B (paper Eqs. 31-32, with
// the duplicate compensation, exact Hessian) and of the lagged friction D
// (Eq. 37) through the particles' B-spline weights (Eq. 29), in 2D and 3D;
// the compensated sum reproduces the max form near a corner; the boundary
// primitives' coefficients; particles inside an FEM body are found.
#include <gtest/gtest.h>

#include <random>
#include <tuple>

#include "common/fd_check.hpp"
#include "contact/contact.hpp"
#include "kernels/contact/barrier.hpp"

using namespace bfemp;

namespace {

// A unit square (2 triangles) or unit cube corner tet as the FEM body.
template <int dim>
MeshData fem_block() {
  MeshData m;
  m.dim = dim;
  if constexpr (dim == 2) {
    m.coords = {0, 0, 1, 0, 1, 1, 0, 1};
    m.cells = {0, 1, 2, 0, 2, 3};
  } else {
    m.coords = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    m.cells = {0, 1, 2, 3};
  }
  return m;
}

template <int dim>
struct ContactScene {
  FemMesh<dim> mesh;
  std::unique_ptr<MpmBodies<dim>> mpm;
  std::unique_ptr<Contact<dim>> contact;
  Kokkos::View<double*, MemSpace> x;
  LO n_nodes = 0;
};

// FEM block and particles at `pts`; system x = FEM rest + grid x^n.
template <int dim>
ContactScene<dim> make_scene(const std::vector<Vec<dim>>& pts, ContactParams cp) {
  ContactScene<dim> s;
  MaterialParams mp;
  mp.lame = lame_from_young(1e5, 0.3);
  mp.density = 1000;
  std::vector<FemBodyInput> bodies{{"fem", fem_block<dim>(), 0}};
  s.mesh = build_fem_mesh<dim>(bodies, {mp});
  MpmSetup<dim> m;
  m.grid = grid_covering<dim>(Vec<dim>::Constant(-1.0), Vec<dim>::Constant(2.0), 0.1);
  m.particles = allocate_particles<dim>(pts.size());
  for (std::size_t q = 0; q < pts.size(); ++q) {
    for (int d = 0; d < dim; ++d) m.particles.x(q, d) = pts[q](d);
    m.particles.volume0(q) = std::pow(0.05, dim);
    m.particles.mass(q) = 1.0;
  }
  m.body_names = {"mpm"};
  s.mpm = std::make_unique<MpmBodies<dim>>(m, s.mesh.elements.materials);
  const LO nF = s.mesh.num_nodes();
  const LO nA = s.mpm->begin_step(nF, 1);
  s.n_nodes = nF + nA;
  s.x = Kokkos::View<double*, MemSpace>("x", s.n_nodes * dim);
  Kokkos::View<double*, MemSpace> v("v", s.n_nodes * dim), mass("m", s.n_nodes * dim);
  Kokkos::deep_copy(Kokkos::subview(s.x, std::make_pair(0, nF * dim)), s.mesh.rest_position);
  s.mpm->fill_system(s.x, v, mass);
  s.contact = std::make_unique<Contact<dim>>(s.mesh, cp);
  s.contact->begin_step(*s.mpm, s.x);
  return s;
}

template <int dim>
void perturb(Kokkos::View<double*, MemSpace> x, double amp, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amp, amp);
  for (std::size_t i = 0; i < x.extent(0); ++i) x(i) += u(rng);
}

// Difference step of the derivative checks: 1e-6 (was 1e-7 for the barrier,
// 1e-8 for friction). The check is per entry now, and its round-off floor
// grows like 1/h: at 1e-7 the xx entries under a nearly horizontal edge (a
// force component that is a small difference of coordinates ~ 1) are
// resolved only to ~0.5 %, at 1e-6 to ~1e-5; the truncation error the larger
// step brings is estimated per entry by the check (h against 2h).
constexpr double kFdStep = 1e-6;

ContactParams params(double dhat, double mu = 0.0, int n_mpm = 1) {
  ContactParams cp;
  cp.dhat = dhat;
  cp.kappa = 1e3;
  cp.eps_v = 1e-2;
  if (mu > 0) cp.mu.assign(n_mpm, mu);
  return cp;
}

}  // namespace

TEST(ContactPrimitives, CompensationCoefficients) {
  MaterialParams mp;
  mp.lame = lame_from_young(1e5, 0.3);
  {
    std::vector<FemBodyInput> b{{"sq", fem_block<2>(), 0}};
    const auto bp = boundary_primitives<2>(build_fem_mesh<2>(b, {mp}));
    auto c = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), bp.count);
    auto k = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), bp.coef);
    int edges = 0, nodes = 0;
    for (LO j = 0; j < bp.size(); ++j) {
      if (c(j) == 2) { ++edges; EXPECT_EQ(k(j), 1.0); }
      if (c(j) == 1) { ++nodes; EXPECT_EQ(k(j), -1.0); }  // eta = 2 on a closed polygon
    }
    EXPECT_EQ(edges, 4);  // the diagonal is interior
    EXPECT_EQ(nodes, 4);
  }
  {
    std::vector<FemBodyInput> b{{"tet", fem_block<3>(), 0}};
    const auto bp = boundary_primitives<3>(build_fem_mesh<3>(b, {mp}));
    auto c = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), bp.count);
    auto k = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), bp.coef);
    int tris = 0, edges = 0, nodes = 0;
    for (LO j = 0; j < bp.size(); ++j) {
      if (c(j) == 3) { ++tris; EXPECT_EQ(k(j), 1.0); }
      if (c(j) == 2) { ++edges; EXPECT_EQ(k(j), -1.0); }  // eta_e = 2
      if (c(j) == 1) { ++nodes; EXPECT_EQ(k(j), 1.0); }   // closed surface: c_v = 1
    }
    EXPECT_EQ(tris, 4);
    EXPECT_EQ(edges, 6);
    EXPECT_EQ(nodes, 4);
  }
}

TEST(ContactPotentials, CompensatedSumEqualsTheClosestFeatureBarrier) {
  const double dhat = 0.1;
  // Above the top edge's interior, and in the vertex region of corner (1, 1).
  const Vec<2> above(0.5, 1.04), corner(1.03, 1.02);
  for (const Vec<2>& p : {above, corner}) {
    auto s = make_scene<2>({p}, params(dhat));
    const double d = p == above ? 0.04 : std::hypot(0.03, 0.02);
    const double omega = particle_contact_weight<2>(std::pow(0.05, 2));
    EXPECT_NEAR(s.contact->barrier()->energy(s.x), omega * barrier(d, dhat, 1e3), 1e-12 * omega * barrier(d, dhat, 1e3));
  }
}

TEST(ContactPotentials, BarrierDerivatives2D) {
  // Above an edge, near a corner (vertex compensation active) and beside the
  // right edge.
  auto s = make_scene<2>({Vec<2>(0.5, 1.03), Vec<2>(1.02, 1.03), Vec<2>(1.04, 0.4), Vec<2>(0.97, 1.06)},
                         params(0.1));
  perturb<2>(s.x, 2e-3, 3);
  auto& barrier = *s.contact->barrier();
  // Exact derivatives, also through a sink with project = false (b' grad^2 d
  // makes the local Hessians indefinite: the projection changes them).
  fixtures::check_exact_term<2>(barrier, s.n_nodes, s.x, kFdStep, 1e-5);
}

TEST(ContactPotentials, BarrierDerivatives3D) {
  // Below the z = 0 face, beside the x = 0 face, near the edge on the x axis
  // and near vertex 0 (edge and vertex compensation terms).
  auto s = make_scene<3>({Vec<3>(0.2, 0.2, -0.03), Vec<3>(-0.04, 0.3, 0.2), Vec<3>(0.5, -0.03, -0.02),
                          Vec<3>(-0.02, -0.03, -0.02)},
                         params(0.1));
  perturb<3>(s.x, 2e-3, 5);
  auto& barrier = *s.contact->barrier();
  fixtures::check_exact_term<3>(barrier, s.n_nodes, s.x, kFdStep, 1e-5);
}

// The graph's pairs grow mid-step: update() at an iterate where a particle
// came within reach of an edge that begin_step did not pair it with. The
// merged pairs are sorted and without repeats (a second update at the same
// x finds none missing), and a graph built from the couplings then holds
// every block the assembly writes (gradient and exact Hessian against
// differences, entry by entry).
TEST(ContactPotentials, GraphGrowsByTheMissingPairs) {
  // particle 1 within dhat (0.1) of the top edge; particle 0 0.6 above it,
  // beyond the graph's reach at the step's start (Contact's margin: 4 dhat),
  // its stencil (nodes y = 1.5 .. 1.7) apart from particle 1's (0.9 .. 1.1).
  // The new pairs (particle 0) sort before the graph's (particle 1).
  auto s = make_scene<2>({Vec<2>(0.3, 1.6), Vec<2>(0.5, 1.03)}, params(0.1));
  auto& barrier = *s.contact->barrier();
  const auto v0 = barrier.couplings_version();
  EXPECT_FALSE(barrier.update(s.x));
  EXPECT_EQ(barrier.couplings_version(), v0);
  // the grid nodes above y = 1.45 move down by 0.55: particle 0 to y = 1.05
  Kokkos::View<double*, MemSpace> x2("x2", s.x.extent(0));
  Kokkos::deep_copy(x2, s.x);
  const LO nF = s.mesh.num_nodes();
  for (LO i = nF; i < s.n_nodes; ++i)
    if (x2(2 * i + 1) > 1.45) x2(2 * i + 1) -= 0.55;
  perturb<2>(x2, 1e-3, 13);
  EXPECT_TRUE(barrier.update(x2));
  EXPECT_NE(barrier.couplings_version(), v0);
  const auto v1 = barrier.couplings_version();
  EXPECT_FALSE(barrier.update(x2)) << "the grown keys do not hold this iterate's pairs (unsorted or lost)";
  EXPECT_EQ(barrier.couplings_version(), v1);
  EXPECT_FALSE(barrier.update(s.x)) << "the pairs of the step's start are missing";
  EXPECT_FALSE(barrier.update(x2));
  barrier.set_projection(false);
  ASSERT_GT(barrier.energy(x2), 0.0);
  fixtures::check_energy_term<2>(barrier, s.n_nodes, x2, kFdStep, 1e-5);
  barrier.set_projection(true);
}

// Scene with friction (mu 0.4) lagged at a perturbed x, against a reference
// perturbed by `slide` (the step's sliding displacement x - x_ref).
template <int dim>
ContactScene<dim> lagged_friction_scene(const std::vector<Vec<dim>>& pts, double slide) {
  auto s = make_scene<dim>(pts, params(0.1, 0.4));
  perturb<dim>(s.x, 1e-3, 7);
  Kokkos::View<double*, MemSpace> xref("xref", s.x.extent(0));
  Kokkos::deep_copy(xref, s.x);
  perturb<dim>(xref, slide, 9);
  EXPECT_TRUE(s.contact->has_friction());
  EXPECT_GT(s.contact->update_friction(s.x, xref, 1.0, 1.0), 0);
  return s;
}

template <int dim>
void friction_case(const std::vector<Vec<dim>>& pts, double slide) {
  auto s = lagged_friction_scene<dim>(pts, slide);
  ASSERT_FALSE(::testing::Test::HasFailure());
  const auto& friction = *s.contact->friction();
  ASSERT_GT(friction.energy(s.x), 0.0);
  fixtures::check_energy_term<dim>(friction, s.n_nodes, s.x, kFdStep, 1e-5);
}

// Particles over facet interiors only (no compensation pair within dhat, so
// every lagged lambda is positive and the Hessian is exact). eps_v dt = 1e-2:
// slides of 3e-3 stay in the static (mollified) branch; slides up to 2.5e-2
// put some pairs in the sliding branch (whose 1D tangent Hessian is zero) and
// keep others static.
TEST(ContactPotentials, FrictionDerivatives2DStatic) {
  friction_case<2>({Vec<2>(0.4, 1.03), Vec<2>(0.6, 1.05), Vec<2>(1.04, 0.5)}, 3e-3);
}
TEST(ContactPotentials, FrictionDerivatives2DStaticAndSliding) {
  friction_case<2>({Vec<2>(0.4, 1.03), Vec<2>(0.6, 1.05), Vec<2>(1.04, 0.5), Vec<2>(0.3, 1.02)}, 2.5e-2);
}
TEST(ContactPotentials, FrictionDerivatives3D) {
  friction_case<3>({Vec<3>(0.25, 0.25, -0.03), Vec<3>(0.3, 0.4, -0.05)}, 3e-3);
  friction_case<3>({Vec<3>(0.25, 0.25, -0.03), Vec<3>(0.3, 0.4, -0.05)}, 5e-2);
}

// Particles near corners and edges: several lagged pairs per particle, among
// them compensation pairs (mu lambda < 0), which the friction term sums per
// particle before expanding them through the stencil. With the projection off
// (Newton's exact-if-definite) their negative Hessians are kept: gradient and
// Hessian against differences of the energy, entry by entry, prescribed DOFs
// included. Projected, each compensation pair's Hessian is dropped, so the
// projected matrix must differ (check_exact_term asserts it). Dropping them
// in the exact Hessian too made it twice too stiff at shared edges (T + 1
// times at a 3D vertex of T triangles), and the A7 twist's friction passes
// converged linearly (rate 0.65).
template <int dim>
void friction_exact_case(const std::vector<Vec<dim>>& pts, double slide) {
  auto s = lagged_friction_scene<dim>(pts, slide);
  ASSERT_FALSE(::testing::Test::HasFailure());
  auto& friction = *s.contact->friction();
  ASSERT_GT(friction.pairs(), static_cast<LO>(2 * pts.size())) << "expected several pairs per particle";
  fixtures::check_exact_term<dim>(friction, s.n_nodes, s.x, kFdStep, 1e-5);
  // Newton's fallback (sink.contact_keep = k): a compensation pair keeps the
  // fraction k of its curvature, so the matrix is the projected one (k = 0)
  // plus k times what the projection removed; the gradient is the same.
  using fixtures::fd_detail::assemble_dense;
  const auto none = assemble_dense<dim>(friction, s.n_nodes, s.x, 1.0, {}, {}, true, 0.0);
  const auto kept = assemble_dense<dim>(friction, s.n_nodes, s.x, 1.0, {}, {}, true, 0.3);
  const auto exact = assemble_dense<dim>(friction, s.n_nodes, s.x, 1.0, {}, {}, false);
  double a_max = 0, g_max = 0;
  for (double v : exact.A) a_max = std::max(a_max, std::abs(v));
  for (double v : exact.grad) g_max = std::max(g_max, std::abs(v));
  std::size_t wrong = 0;
  for (std::size_t k = 0; k < exact.A.size(); ++k)
    wrong += std::abs(kept.A[k] - (none.A[k] + 0.3 * (exact.A[k] - none.A[k]))) > 1e-12 * a_max;
  for (std::size_t i = 0; i < exact.grad.size(); ++i) wrong += std::abs(kept.grad[i] - exact.grad[i]) > 1e-13 * g_max;
  EXPECT_EQ(wrong, 0u) << "contact_keep 0.3 is not 0.3 of the compensation pairs' curvature";
}

TEST(ContactPotentials, FrictionExactNearCorners2D) {
  friction_exact_case<2>({Vec<2>(1.04, 1.03), Vec<2>(-0.03, 1.05), Vec<2>(1.02, -0.04)}, 3e-3);
  friction_exact_case<2>({Vec<2>(1.04, 1.03), Vec<2>(-0.03, 1.05), Vec<2>(1.02, -0.04)}, 2.5e-2);
}
TEST(ContactPotentials, FrictionExactNearCorners3D) {
  friction_exact_case<3>({Vec<3>(-0.02, -0.03, -0.02), Vec<3>(0.5, -0.03, -0.02)}, 3e-3);
  friction_exact_case<3>({Vec<3>(-0.02, -0.03, -0.02), Vec<3>(0.5, -0.03, -0.02)}, 5e-2);
}

// The particles' sums expanded cell by cell (particle_expansion.hpp, the
// path with MPM cells) against particle by particle (the path without
// cells): the same gradient, matrix and rhs to round-off, for the barrier
// and the lagged friction term, with several contact particles per cell
// (a lattice 3 per cell and axis under the FEM body), some DOFs prescribed
// and scale != 1.
template <int dim>
void by_cell_case() {
  std::vector<Vec<dim>> pts;
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < (dim == 3 ? 7 : 1); ++j)
      for (int l = 0; l < 2; ++l) {
        Vec<dim> p;
        if constexpr (dim == 2) p << 0.1 + 0.033 * i, -0.015 - 0.033 * l;
        else p << 0.05 + 0.033 * i, 0.05 + 0.033 * j, -0.015 - 0.033 * l;
        pts.push_back(p);
      }
  auto s = lagged_friction_scene<dim>(pts, 3e-3);
  ASSERT_FALSE(::testing::Test::HasFailure());
  auto& barrier = *s.contact->barrier();
  const auto& friction = *s.contact->friction();
  ASSERT_NE(barrier.cells(), nullptr);
  const ParticleCells<dim> cells = *barrier.cells();
  barrier.set_cell_expansion(true);  // the default in 3D only
  ASSERT_TRUE(barrier.cell_expansion());
  const std::size_t nd = s.x.extent(0);
  std::vector<int> mask(nd, 0);
  fixtures::fd_detail::HostVec dxp(nd, 0.0);
  for (std::size_t i = 0; i < nd; i += 7) {
    mask[i] = 1;
    dxp[i] = 1e-3 * std::sin(1.0 + i);
  }
  const auto by_cell_b = fixtures::fd_detail::assemble_dense<dim>(barrier, s.n_nodes, s.x, 2.5, mask, dxp);
  const auto by_cell_f = fixtures::fd_detail::assemble_dense<dim>(friction, s.n_nodes, s.x, 2.5, mask, dxp);
  // The same pairs, particle by particle (friction follows the barrier's cells).
  barrier.begin_step(barrier.particles(), s.x, nullptr);
  ASSERT_EQ(barrier.cells(), nullptr);
  ASSERT_FALSE(barrier.cell_expansion());
  const auto direct_b = fixtures::fd_detail::assemble_dense<dim>(barrier, s.n_nodes, s.x, 2.5, mask, dxp);
  const auto direct_f = fixtures::fd_detail::assemble_dense<dim>(friction, s.n_nodes, s.x, 2.5, mask, dxp);
  for (const auto& [a, b, name] : {std::tuple{&by_cell_b, &direct_b, "barrier"}, std::tuple{&by_cell_f, &direct_f, "friction"}}) {
    double amax = 0, gmax = 0, rmax = 0, nonzero = 0;
    for (double v : b->A) amax = std::max(amax, std::abs(v)), nonzero += v != 0.0;
    for (double v : b->grad) gmax = std::max(gmax, std::abs(v));
    for (double v : b->rhs) rmax = std::max(rmax, std::abs(v));
    ASSERT_GT(rmax, 0.0) << name;
    ASSERT_GT(nonzero, 100) << name;
    for (std::size_t i = 0; i < nd; ++i) {
      EXPECT_NEAR(a->grad[i], b->grad[i], 1e-13 * gmax) << name << " grad " << i;
      EXPECT_NEAR(a->rhs[i], b->rhs[i], 1e-13 * rmax) << name << " rhs " << i;
      for (std::size_t j = 0; j < nd; ++j) {
        EXPECT_NEAR(a->A[i * nd + j], b->A[i * nd + j], 1e-13 * amax) << name << " A(" << i << ", " << j << ")";
        if (mask[i] || mask[j]) EXPECT_EQ(a->A[i * nd + j], 0.0) << name << " prescribed (" << i << ", " << j << ")";
      }
    }
  }
  // The barrier, cell by cell at x, then at x2 where the lower row has left
  // dhat (the grid 0.06 further from the body), against particle by particle
  // at x2: a mark the first assembly left set would add a stale block.
  Kokkos::View<double*, MemSpace> x2("x2", nd);
  Kokkos::deep_copy(x2, s.x);
  for (LO i = s.mesh.num_nodes(); i < s.n_nodes; ++i) x2(dim * i + dim - 1) -= 0.06;
  barrier.begin_step(barrier.particles(), s.x, &cells);
  ASSERT_TRUE(barrier.cell_expansion());
  barrier.update(s.x);
  const LO pairs_x = barrier.candidate_pairs();
  fixtures::fd_detail::assemble_dense<dim>(barrier, s.n_nodes, s.x, 2.5, mask, dxp);
  barrier.update(x2);
  ASSERT_LT(barrier.candidate_pairs(), pairs_x) << "no particle left";
  const auto cell_x2 = fixtures::fd_detail::assemble_dense<dim>(barrier, s.n_nodes, x2, 2.5, mask, dxp);
  barrier.begin_step(barrier.particles(), x2, nullptr);
  barrier.update(x2);
  const auto direct_x2 = fixtures::fd_detail::assemble_dense<dim>(barrier, s.n_nodes, x2, 2.5, mask, dxp);
  double amax = 0;
  for (double v : direct_x2.A) amax = std::max(amax, std::abs(v));
  ASSERT_GT(amax, 0.0);
  for (std::size_t i = 0; i < nd * nd; ++i) EXPECT_NEAR(cell_x2.A[i], direct_x2.A[i], 1e-13 * amax) << "at x2, entry " << i;
}

TEST(ContactPotentials, CellExpansionEqualsParticleExpansion2D) { by_cell_case<2>(); }
TEST(ContactPotentials, CellExpansionEqualsParticleExpansion3D) { by_cell_case<3>(); }

// Pair searches among the step's candidate particles (those within the
// graph's reach, (1 + 3) dhat = 0.4, of the FEM body at the step's start)
// find the same pairs as searches over all particles while the nodes stay
// within the candidates' reach, and search all particles again when they
// move beyond it: static searches at iterates that bring particles from
// 0.15-0.35 above the square into reach, swept searches along directions,
// the energies and the CCD bounds over the pairs found. Particles 0.6 and
// more above start outside the candidates and come within dhat only after
// the large moves (which must search all particles), one of them made by
// both the particles and the body.
TEST(ContactPotentials, CandidateSearchesFindTheSamePairsAsSearchesOverAllParticles) {
  std::vector<Vec<2>> pts;
  for (int i = 0; i < 9; ++i)
    for (const double y : {1.03, 1.15, 1.25, 1.35, 1.65, 1.75}) pts.push_back(Vec<2>(0.1 + 0.1 * i, y));
  auto s = make_scene<2>(pts, params(0.1));
  auto& cand = *s.contact->barrier();
  BarrierTerm<2> all(cand.primitives(), cand.dhat(), cand.kappa());
  all.set_graph_margin(3.0);
  all.set_candidate_search(false);
  all.begin_step(cand.particles(), s.x, cand.cells());
  cand.take_timings();
  all.take_timings();
  const LO nF = s.mesh.num_nodes();
  Kokkos::View<double*, MemSpace> x("x", s.x.extent(0)), p("p", s.x.extent(0));
  auto check = [&](double down, const char* what, double up = 0.0, double sweep = -0.04) {
    Kokkos::deep_copy(x, s.x);
    for (LO i = nF; i < s.n_nodes; ++i) x(2 * i + 1) -= down;  // the grid nodes down
    for (LO i = 0; i < nF; ++i) x(2 * i + 1) += up;            // the square up
    perturb<2>(x, 2e-3, 21);
    for (std::size_t i = 0; i < p.extent(0); ++i) p(i) = i >= static_cast<std::size_t>(2 * nF) && i % 2 ? sweep : 0.0;
    cand.update(x);
    all.update(x);
    EXPECT_EQ(cand.candidate_pairs(), all.candidate_pairs()) << what;
    EXPECT_EQ(cand.energy(x), all.energy(x)) << what;
    cand.prepare_direction(x, p);
    all.prepare_direction(x, p);
    EXPECT_EQ(cand.candidate_pairs(), all.candidate_pairs()) << what << " (swept)";
    EXPECT_EQ(cand.max_step(x, p), all.max_step(x, p)) << what;
    EXPECT_EQ(cand.energy(x), all.energy(x)) << what << " (swept)";
  };
  LO before = 0;
  check(0.0, "at the start");
  before = cand.candidate_pairs();
  check(0.1, "0.1 down");
  EXPECT_GT(cand.candidate_pairs(), before) << "the move brought no new pairs: the case tests nothing";
  check(0.08, "0.08 down");
  EXPECT_EQ(cand.take_timings().searches_all, 0) << "moves within reach searched all particles";
  // A sweep beyond reach: the particles 0.65 above reach dhat along p only.
  check(0.1, "0.1 down, swept 0.5 down", 0.0, -0.5);
  EXPECT_GT(cand.take_timings().searches_all, 0) << "a sweep beyond reach kept the step's candidates";
  check(0.0, "back at the start");
  // Both sides move, 0.28 each: the particles 0.65 above come within dhat
  // although neither side moved beyond half the reach (the gap closes by both).
  check(0.28, "0.28 down, 0.28 up", 0.28);
  EXPECT_GT(cand.take_timings().searches_all, 0) << "an approach beyond reach kept the step's candidates";
  check(0.6, "0.6 down");
  EXPECT_GT(cand.take_timings().searches_all, 0) << "a move beyond reach kept the step's candidates";
  check(0.61, "0.61 down");
}

TEST(ContactInitialCheck, RefusesAParticleInsideOrOnTheFemBody) {
  auto ok = make_scene<2>({Vec<2>(0.5, 1.01)}, params(0.1));
  EXPECT_NO_THROW(ok.contact->check_initial(ok.mpm->particles(), ok.mesh.rest_position));
  for (const Vec<2>& p : {Vec<2>(0.5, 0.5), Vec<2>(0.5, 1.0), Vec<2>(1.0, 1.0)}) {
    auto s = make_scene<2>({Vec<2>(-0.5, -0.5), p}, params(0.1));
    try {
      s.contact->check_initial(s.mpm->particles(), s.mesh.rest_position);
      ADD_FAILURE() << "particle at (" << p.transpose() << ") accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("MPM particle 1"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("inside or on an FEM body"), std::string::npos) << e.what();
    }
  }
}
