// The DOF space and its sink (src/solver/dof_space.*, kernels/dof_sink.hpp):
//  - the sink's block-offset scatter with constraint elimination gives the
//    same gradient, matrix and right-hand side as a plain dense assembly of
//    the same local gradients and Hessians with the elimination written out
//    (the rule the terms used to apply each on their own), entry by entry,
//    for FEM triangles / tetrahedra and MPM particles (per particle with
//    atomics, and by cell and color without), with some DOFs prescribed, with
//    each block found by bisection and through the scatter table; a table
//    whose stencils changed is refused until set_structure rebuilds it;
//  - the MPM term's couplings by cell give the graph of every particle's
//    stencil;
//  - the graph is cached: a scene whose structure does not change builds it
//    once, and a direct solver runs its symbolic phase once;
//  - particle order does not change a run beyond round-off.
#include <gtest/gtest.h>

#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>
#include <algorithm>
#include <random>
#include <stdexcept>

#include "common/mpm_fixtures.hpp"
#include "fem/fem_mesh.hpp"
#include "mpm/mpm_bodies.hpp"
#include "solver/dof_graph.hpp"
#include "solver/dof_space.hpp"

using namespace bfemp;
using namespace bfemp::fixtures;

namespace {

using HostMat = std::vector<double>;

struct Dense {
  std::vector<double> grad, rhs, A;
};

// Dense reference: the local (g, H) of every stencil added with the
// elimination rule written out on the host.
template <int dim, int nv>
Dense dense_reference(const DeformationStencils<dim, nv>& s, Kokkos::View<const double*, MemSpace> x, std::size_t nd,
                      double scale, const std::vector<int>& pres, const std::vector<double>& dxp) {
  constexpr int L = nv * dim;
  Dense d;
  d.grad.assign(nd, 0.0);
  d.rhs.assign(nd, 0.0);
  d.A.assign(nd * nd, 0.0);
  for (LO q = 0; q < s.size(); ++q) {
    Eigen::Matrix<double, L, 1> g = Eigen::Matrix<double, L, 1>::Zero();
    SquareMat<L> H = SquareMat<L>::Zero();
    deformation_local_add<dim, nv>(s, x, q, true, g, H);
    symmetric_from_lower<L>(H);
    for (int r = 0; r < L; ++r) {
      const std::size_t row = s.nodes(q, r / dim) * dim + r % dim;
      d.grad[row] += scale * g(r);
      if (pres[row]) continue;
      for (int c = 0; c < L; ++c) {
        const std::size_t col = s.nodes(q, c / dim) * dim + c % dim;
        if (pres[col]) d.rhs[row] -= scale * H(r, c) * dxp[col];
        else d.A[row * nd + col] += scale * H(r, c);
      }
    }
  }
  return d;
}

// tabled: the sink carries the scatter table of the space's term 0 (as the
// Newton solver hands it over); otherwise every block is found by bisection.
template <int dim>
Dense assemble_with(const DofSpace<dim>& space, std::size_t nd, double scale, const std::vector<int>& pres,
                    const std::vector<double>& dxp, const std::function<void(const Sink<dim>&)>& assemble,
                    bool tabled = false) {
  Kokkos::View<double*, MemSpace> grad("grad", nd), rhs("rhs", nd), dx("dxp", nd);
  Kokkos::View<int*, MemSpace> p("pres", nd);
  for (std::size_t i = 0; i < nd; ++i) {
    p(i) = pres[i];
    dx(i) = dxp[i];
  }
  auto A = space.matrix();
  A->resumeFill();
  A->setAllToScalar(0.0);
  const Sink<dim> sink = space.sink(scale, grad, rhs, p, dx);
  if (tabled) {
    const Sink<dim> ts = space.term_sink(sink, 0);
    EXPECT_GT(ts.table_stencils, 0) << "no scatter table";
    assemble(ts);
  } else {
    assemble(sink);
  }
  Kokkos::fence();
  A->fillComplete();
  Dense d;
  d.grad.assign(grad.data(), grad.data() + nd);
  d.rhs.assign(rhs.data(), rhs.data() + nd);
  d.A.assign(nd * nd, 0.0);
  for (std::size_t i = 0; i < nd; ++i) {
    typename Matrix::local_inds_host_view_type cols;
    typename Matrix::values_host_view_type vals;
    A->getLocalRowView(i, cols, vals);
    for (std::size_t k = 0; k < cols.extent(0); ++k) d.A[i * nd + cols(k)] += vals(k);
  }
  return d;
}

// Entry by entry: |a - b| <= 1e-12 (|a| + |b|) + 1e-14 * (largest |entry| of the row).
void expect_same(const Dense& a, const Dense& b, std::size_t nd, const std::string& what) {
  int bad = 0;
  auto close = [](double u, double v, double floor) { return std::abs(u - v) <= 1e-12 * (std::abs(u) + std::abs(v)) + floor; };
  double gmax = 0;
  for (double v : a.grad) gmax = std::max(gmax, std::abs(v));
  for (std::size_t i = 0; i < nd; ++i) {
    if (!close(a.grad[i], b.grad[i], 1e-14 * gmax) && bad++ < 5)
      ADD_FAILURE() << what << ": grad(" << i << ") " << a.grad[i] << " vs " << b.grad[i];
    double rmax = 0;
    for (std::size_t j = 0; j < nd; ++j) rmax = std::max(rmax, std::abs(a.A[i * nd + j]));
    if (!close(a.rhs[i], b.rhs[i], 1e-14 * rmax) && bad++ < 5)
      ADD_FAILURE() << what << ": rhs(" << i << ") " << a.rhs[i] << " vs " << b.rhs[i];
    for (std::size_t j = 0; j < nd; ++j)
      if (!close(a.A[i * nd + j], b.A[i * nd + j], 1e-14 * rmax) && bad++ < 5)
        ADD_FAILURE() << what << ": A(" << i << ", " << j << ") " << a.A[i * nd + j] << " vs " << b.A[i * nd + j];
  }
  EXPECT_EQ(bad, 0) << what << ": entries differ";
}

// `sink` with a scatter table of wrong positions for `stencils` stencils of k
// nodes: every entry 0 (inside each row, the wrong block for most).
template <int dim>
Sink<dim> with_wrong_table(const Sink<dim>& sink, long stencils, int k) {
  Sink<dim> bad = sink;
  bad.table = Kokkos::View<int*, MemSpace>("wrong_table", static_cast<std::size_t>(stencils) * k * k);  // zeros
  bad.table_stencils = stencils;
  return bad;
}

// Every third DOF prescribed with a random offset; returns the mask.
std::vector<int> some_prescribed(std::size_t nd, std::vector<double>& dxp, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  std::vector<int> pres(nd, 0);
  dxp.assign(nd, 0.0);
  for (std::size_t i = 0; i < nd; i += 3) {
    pres[i] = 1;
    dxp[i] = u(rng);
  }
  return pres;
}

template <int dim>
void fem_case() {
  auto setup = block_setup<dim>(0.25, 1e5, 0.3);
  FemMesh<dim> mesh = build_fem_mesh<dim>(setup.bodies, setup.materials);
  DeformationTerm<dim, dim + 1> term("fem", mesh.elements);
  const LO n = mesh.num_nodes();
  const std::size_t nd = static_cast<std::size_t>(n) * dim;
  Kokkos::View<double*, MemSpace> x("x", nd);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.03, 0.03);
  for (std::size_t i = 0; i < nd; ++i) x(i) = mesh.rest_position(i) + u(rng);
  DofSpace<dim> space(comm());
  ASSERT_TRUE(space.set_structure(n, {&term}));
  std::vector<double> dxp;
  const auto pres = some_prescribed(nd, dxp, 5);
  const double scale = 2.5e-3;
  const Dense ref = dense_reference<dim, dim + 1>(mesh.elements, x, nd, scale, pres, dxp);
  const Dense got = assemble_with<dim>(space, nd, scale, pres, dxp, [&](const Sink<dim>& s) { term.assemble(x, s); });
  expect_same(got, ref, nd, "FEM");
  // Colored: no two elements of a color share a node; same matrix.
  term.set_coloring(color_stencils<dim + 1>(mesh.elements.nodes, n));
  const auto& col = term.coloring();
  ASSERT_GT(col.colors(), 1);
  for (int c = 0; c < col.colors(); ++c) {
    std::vector<int> seen(n, 0);
    for (LO k = col.color_start[c]; k < col.color_start[c + 1]; ++k)
      for (int a = 0; a <= dim; ++a) EXPECT_EQ(seen[mesh.elements.nodes(col.order(k), a)]++, 0) << "color " << c;
  }
  const Dense colored =
      assemble_with<dim>(space, nd, scale, pres, dxp, [&](const Sink<dim>& s) { term.assemble(x, s); });
  expect_same(colored, ref, nd, "FEM colored");
  // Through the scatter table (built by set_structure): the same matrix.
  EXPECT_EQ(space.scatter_table_builds(), 1);
  const Dense tabled =
      assemble_with<dim>(space, nd, scale, pres, dxp, [&](const Sink<dim>& s) { term.assemble(x, s); }, true);
  expect_same(tabled, ref, nd, "FEM colored, scatter table");
  // A table that does not fit the graph (every position 0: in the row, the
  // wrong block for most) is caught by the sink's check: the same matrix.
  const Dense checked = assemble_with<dim>(space, nd, scale, pres, dxp, [&](const Sink<dim>& sk) {
    term.assemble(x, with_wrong_table(sk, mesh.num_cells(), dim + 1));
  });
  expect_same(checked, ref, nd, "FEM, a table of wrong positions");
  // New stencils (here: the same elements in reverse order) without a new
  // set_structure: the stale table is refused; after it, rebuilt and right.
  DeformationStencils<dim, dim + 1> rev = mesh.elements;
  rev.nodes = decltype(rev.nodes)("rev_nodes", mesh.num_cells());
  rev.g = decltype(rev.g)("rev_g", mesh.num_cells());
  rev.volume = decltype(rev.volume)("rev_volume", mesh.num_cells());
  rev.material = decltype(rev.material)("rev_material", mesh.num_cells());
  const LO ne = mesh.num_cells();
  for (LO q = 0; q < ne; ++q) {
    for (int a = 0; a <= dim; ++a) {
      rev.nodes(q, a) = mesh.elements.nodes(ne - 1 - q, a);
      for (int j = 0; j < dim; ++j) rev.g(q, a, j) = mesh.elements.g(ne - 1 - q, a, j);
    }
    rev.volume(q) = mesh.elements.volume(ne - 1 - q);
    rev.material(q) = mesh.elements.material(ne - 1 - q);
  }
  term.set_stencils(rev);
  term.set_coloring(color_stencils<dim + 1>(rev.nodes, n));
  EXPECT_THROW(assemble_with<dim>(space, nd, scale, pres, dxp, [&](const Sink<dim>& s) { term.assemble(x, s); }, true),
               std::logic_error);
  EXPECT_FALSE(space.set_structure(n, {&term}));  // same couplings: the graph serves, the table is rebuilt
  EXPECT_EQ(space.scatter_table_builds(), 2);
  const Dense reversed =
      assemble_with<dim>(space, nd, scale, pres, dxp, [&](const Sink<dim>& s) { term.assemble(x, s); }, true);
  expect_same(reversed, ref, nd, "FEM reversed, scatter table");
  std::cout << "  FEM " << dim << "D: " << mesh.num_cells() << " elements in " << col.colors() << " colors, " << nd
            << " DOFs\n";
}

template <int dim>
void mpm_case(int n_particles) {
  constexpr int ns = bspline_stencil_size<dim>;
  GridSpec<dim> grid = grid_covering<dim>(Vec<dim>::Constant(0.0), Vec<dim>::Constant(1.0), 0.1);
  auto p = allocate_particles<dim>(n_particles);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> pos(0.2, 0.8), pert(-0.05, 0.05);
  MaterialParams mp;
  mp.lame = lame_from_young(1e4, 0.3);
  mp.density = 100;
  Kokkos::View<MaterialParams*, MemSpace> mats("mats", 1);
  mats(0) = mp;
  for (int q = 0; q < n_particles; ++q) {
    for (int d = 0; d < dim; ++d) p.x(q, d) = pos(rng);
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j) p.F(q, i, j) = (i == j) + pert(rng);
    p.volume0(q) = 1e-3;
    p.mass(q) = 0.1;
  }
  Kokkos::View<LO*, MemSpace> system_node("sn", grid.num_nodes());
  Kokkos::View<LO*, MemSpace> grid_node;
  const LO first = 4;  // grid nodes after some (absent) FEM nodes, as in a scene
  const LO n = first + activate_grid<dim>(grid, p, first, system_node, grid_node);
  DeformationStencils<dim, ns> s;
  s.nodes = decltype(s.nodes)("n", n_particles);
  s.g = decltype(s.g)("g", n_particles);
  s.volume = decltype(s.volume)("v", n_particles);
  s.material = decltype(s.material)("m", n_particles);
  s.materials = mats;
  mpm_stencils<dim>(grid, p, system_node, s);
  MpmElasticityTerm<dim> term("mpm", s);
  ParticleCells<dim> cells;
  bin_particles<dim>(grid, p, cells);
  term.set_cells(cells);
  ASSERT_EQ(cells.color_start(ParticleCells<dim>::n_colors), cells.n_cells);
  {  // the couplings by cell (one stencil per cell) = those of every particle's stencil
    DeformationTerm<dim, ns> every("every particle", s);
    auto map = Teuchos::rcp(new Map(static_cast<Tpetra::global_size_t>(n) * dim, 0, Tpetra::getDefaultComm()));
    const auto by_cell = build_dof_graph<dim>({&term}, n, map)->getLocalGraphHost();
    const auto by_particle = build_dof_graph<dim>({&every}, n, map)->getLocalGraphHost();
    ASSERT_EQ(by_cell.row_map.extent(0), by_particle.row_map.extent(0));
    for (std::size_t r = 0; r <= static_cast<std::size_t>(n) * dim; ++r) ASSERT_EQ(by_cell.row_map(r), by_particle.row_map(r));
    for (std::size_t k = 0; k < by_cell.entries.extent(0); ++k) ASSERT_EQ(by_cell.entries(k), by_particle.entries(k));
  }
  const std::size_t nd = static_cast<std::size_t>(n) * dim;
  Kokkos::View<double*, MemSpace> x("x", nd);
  std::uniform_real_distribution<double> disp(-0.003, 0.003);
  for (LO k = 0; k < n - first; ++k) {
    const Vec<dim> xi = grid.node_position(grid_node(k));
    for (int c = 0; c < dim; ++c) x((first + k) * dim + c) = xi(c) + disp(rng);
  }
  DofSpace<dim> space(comm());
  ASSERT_TRUE(space.set_structure(n, {&term}));
  std::vector<double> dxp;
  const auto pres = some_prescribed(nd, dxp, 9);
  const double scale = 1.7e-2;
  const Dense ref = dense_reference<dim, ns>(s, x, nd, scale, pres, dxp);
  const Dense cellwise = assemble_with<dim>(space, nd, scale, pres, dxp, [&](const Sink<dim>& sk) { term.assemble(x, sk); });
  const Dense per_particle =
      assemble_with<dim>(space, nd, scale, pres, dxp, [&](const Sink<dim>& sk) { term.assemble_per_particle(x, sk); });
  expect_same(cellwise, ref, nd, "MPM by cell (the sweep)");
  expect_same(per_particle, ref, nd, "MPM per particle");
  // Through the scatter table (by cell): the same matrix; the per-particle
  // path ignores the cell table.
  EXPECT_EQ(space.scatter_table_builds(), 1);
  const Dense cell_table =
      assemble_with<dim>(space, nd, scale, pres, dxp, [&](const Sink<dim>& sk) { term.assemble(x, sk); }, true);
  expect_same(cell_table, ref, nd, "MPM by cell, scatter table");
  // The per-particle path with a table for as many stencils as particles (as
  // a cell table would be with one particle per cell), of wrong positions:
  // ignored, and the sink's check would catch it anyway.
  const Dense per_particle_junk = assemble_with<dim>(space, nd, scale, pres, dxp, [&](const Sink<dim>& sk) {
    term.assemble_per_particle(x, with_wrong_table(sk, n_particles, ns));
  });
  expect_same(per_particle_junk, ref, nd, "MPM per particle, sink with a table for as many stencils");
  // Every table entry is a real block position (the graph holds every block
  // of every cell).
  {
    DofSpace<dim> probe(comm());
    ASSERT_TRUE(probe.set_structure(n, {&term}));
    Kokkos::View<double*, MemSpace> g0("g0", nd), r0("r0", nd), d0("d0", nd);
    Kokkos::View<int*, MemSpace> p0("p0", nd);
    const Sink<dim> ts = probe.term_sink(probe.sink(1.0, g0, r0, p0, d0), 0);
    ASSERT_EQ(ts.table_stencils, cells.n_cells);
    int missing = 0;
    for (std::size_t i = 0; i < static_cast<std::size_t>(cells.n_cells) * ns * ns; ++i) missing += ts.table(i) < 0;
    EXPECT_EQ(missing, 0);
  }
  // Two tabled terms in one space (an FEM simplex on the first nodes, at
  // rest, beside the MPM cells): each term gets its own table, and the sum
  // is the same as with every block searched.
  {
    DeformationStencils<dim, dim + 1> fs;
    fs.nodes = decltype(fs.nodes)("fem_nodes", 1);
    fs.g = decltype(fs.g)("fem_g", 1);
    fs.volume = decltype(fs.volume)("fem_volume", 1);
    fs.material = decltype(fs.material)("fem_material", 1);
    fs.materials = mats;
    for (int a = 0; a <= dim; ++a) {
      fs.nodes(0, a) = a;
      for (int j = 0; j < dim; ++j) fs.g(0, a, j) = a == 0 ? -1.0 : (j == a - 1 ? 1.0 : 0.0);
    }
    fs.volume(0) = 1e-3;
    fs.material(0) = 0;
    for (int a = 1; a <= dim; ++a) x((a)*dim + (a - 1)) = 1.0 + 0.01 * a;  // node a at (1 + 0.01 a) e_a
    DeformationTerm<dim, dim + 1> fem("fem", fs);
    DofSpace<dim> both(comm());
    ASSERT_TRUE(both.set_structure(n, {&fem, &term}));
    Kokkos::View<double*, MemSpace> g0("g0", nd), r0("r0", nd), d0("d0", nd);
    Kokkos::View<int*, MemSpace> p0("p0", nd);
    const Sink<dim> plain = both.sink(1.0, g0, r0, p0, d0);
    EXPECT_EQ(both.term_sink(plain, 0).table_stencils, 1);
    EXPECT_EQ(both.term_sink(plain, 1).table_stencils, cells.n_cells);
    const Dense searched = assemble_with<dim>(both, nd, scale, pres, dxp, [&](const Sink<dim>& sk) {
      fem.assemble(x, sk);
      term.assemble(x, sk);
    });
    const Dense tabled2 = assemble_with<dim>(both, nd, scale, pres, dxp, [&](const Sink<dim>& sk) {
      fem.assemble(x, both.term_sink(sk, 0));
      term.assemble(x, both.term_sink(sk, 1));
    });
    expect_same(tabled2, searched, nd, "FEM + MPM, a table per term");
  }
  std::cout << "  MPM " << dim << "D: " << n_particles << " particles in " << cells.n_cells << " cells, " << nd
            << " DOFs\n";
}

}  // namespace

TEST(DofSpace, FemTrianglesMatchDenseElimination) { fem_case<2>(); }
TEST(DofSpace, FemTetrahedraMatchDenseElimination) { fem_case<3>(); }
TEST(DofSpace, MpmParticles2DMatchDenseElimination) { mpm_case<2>(400); }
TEST(DofSpace, MpmParticles3DMatchDenseElimination) { mpm_case<3>(150); }

// Cells of one color never share a grid node (what makes the colored assembly
// free of atomics), and every particle is in exactly one cell.
TEST(DofSpace, CellsOfOneColorShareNoNode) {
  constexpr int dim = 3;
  GridSpec<dim> grid = grid_covering<dim>(Vec<dim>::Constant(0.0), Vec<dim>::Constant(1.0), 0.1);
  const int np = 2000;
  auto p = allocate_particles<dim>(np);
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> pos(0.15, 0.85);
  for (int q = 0; q < np; ++q)
    for (int d = 0; d < dim; ++d) p.x(q, d) = pos(rng);
  ParticleCells<dim> cells;
  bin_particles<dim>(grid, p, cells);
  std::vector<int> seen(np, 0);
  for (int c = 0; c < ParticleCells<dim>::n_colors; ++c) {
    std::vector<int> touched(grid.num_nodes(), 0);
    for (LO k = cells.color_start(c); k < cells.color_start(c + 1); ++k) {
      const LO n = cells.cells(k);
      const GridIndex<dim> b = grid.node_multi_index(n);
      for (int a = 0; a < 27; ++a) {
        GridIndex<dim> i = b;
        i[0] += a % 3;
        i[1] += (a / 3) % 3;
        i[2] += a / 9;
        EXPECT_EQ(touched[grid.node_index(i)]++, 0) << "color " << c << ": node shared by two cells";
      }
      for (LO s = cells.start(n); s < cells.start(n) + cells.count(n); ++s) {
        ++seen[cells.order(s)];
        if (s > cells.start(n)) EXPECT_LT(cells.order(s - 1), cells.order(s)) << "cell order not increasing";
        const auto st = bspline_stencil(grid, particle_position(p, cells.order(s)));
        EXPECT_EQ(node_index(grid, st, 0), n);
      }
    }
  }
  for (int q = 0; q < np; ++q) EXPECT_EQ(seen[q], 1) << "particle " << q;
}

// The sweep (particle_cells.hpp): every occupied cell once, in node order;
// within a phase, two slabs never share a grid node (what makes the sweep's
// parallel assembly free of atomics); the slabs hold similar particle counts.
template <int dim>
void sweep_case() {
  GridSpec<dim> grid = grid_covering<dim>(Vec<dim>::Constant(0.0), Vec<dim>::Constant(1.0), 0.04);
  const int np = dim == 2 ? 6000 : 20000;
  auto p = allocate_particles<dim>(np);
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> pos(0.1, 0.9);
  for (int q = 0; q < np; ++q)
    for (int d = 0; d < dim; ++d) p.x(q, d) = d == dim - 1 ? 0.1 + 0.8 * std::pow(pos(rng), 2) : pos(rng);
  ParticleCells<dim> cells;
  bin_particles<dim>(grid, p, cells);
  constexpr int S = ParticleCells<dim>::kSlabs;
  auto phase = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), cells.phase);
  std::vector<int> seen(cells.n_cells, 0);
  int slabs = 0;
  std::vector<LO> particles_in(S, 0);
  for (int ph = 0; ph < 2; ++ph) {
    std::vector<int> owner(grid.num_nodes(), -1);
    for (int s = 0; s < S; ++s) {
      if (ph == 0 && phase(4 * s + 1) > phase(4 * s)) ++slabs;
      for (LO i = phase(4 * s + 2 * ph); i < phase(4 * s + 2 * ph + 1); ++i) {
        const LO k = cells.sweep(i);
        ASSERT_GE(k, 0);
        ASSERT_LT(k, cells.n_cells);
        ++seen[k];
        if (i > 0) EXPECT_LT(cells.cells(cells.sweep(i - 1)), cells.cells(k)) << "node order";
        particles_in[s] += cells.count(cells.cells(k));
        const GridIndex<dim> b = grid.node_multi_index(cells.cells(k));
        for (int a = 0; a < bspline_stencil_size<dim>; ++a) {
          GridIndex<dim> n = b;
          for (int d = 0, m = a; d < dim; ++d, m /= 3) n[d] += m % 3;
          int& o = owner[grid.node_index(n)];
          EXPECT_TRUE(o == -1 || o == s) << "phase " << ph << ": a node of slabs " << o << " and " << s;
          o = s;
        }
      }
    }
  }
  for (LO k = 0; k < cells.n_cells; ++k) EXPECT_EQ(seen[k], 1) << "cell " << k;
  EXPECT_GE(slabs, S / 2) << "the particles span " << grid.nodes_along(dim - 1) << " layers";
  EXPECT_EQ(slabs, cells.slabs);
  for (int s = 0; s < slabs; ++s) {  // about np / slabs each (whole layers; the density falls along the axis)
    std::cout << "slab " << s << ": " << particles_in[s] << " particles\n";
    EXPECT_GT(particles_in[s], np / slabs / 2) << "slab " << s;
    EXPECT_LT(particles_in[s], 2 * np / slabs) << "slab " << s;
  }
}

TEST(DofSpace, SweepSlabsOfOnePhaseShareNoNode2D) { sweep_case<2>(); }
TEST(DofSpace, SweepSlabsOfOnePhaseShareNoNode3D) { sweep_case<3>(); }

// A block at rest without gravity: the occupied cells never change, so the
// graph is built once and Cholmod's symbolic phase runs once over 5 steps.
TEST(DofSpace, UnchangedStructureBuildsTheGraphOnce) {
  auto s = mpm_block_setup(0.3, Vec<2>(0.5, 0.5), 0.05, 4, 0.0, 1.0, TransferScheme::APIC);
  s.dt = 1e-3;
  Simulation<2> sim(s, comm());
  int symbolic = 0;
  for (int k = 0; k < 5; ++k) symbolic += sim.step().newton.symbolic_factorizations;
  EXPECT_EQ(sim.newton().dof_space().graph_builds(), 1);
  EXPECT_EQ(sim.newton().dof_space().graph_reuses(), 4);
  EXPECT_EQ(symbolic, 1);
  const auto& why = sim.newton().dof_space().build_causes();
  ASSERT_EQ(why.size(), 1u);
  EXPECT_EQ(why[0].first, "first");
  EXPECT_EQ(why[0].second, 1);
}

// A block thrown across cells: the graph is rebuilt when, and only when, the
// set of occupied cells changes (counted per step and in the DOF space).
TEST(DofSpace, MovingBlockRebuildsOnlyWhenCellsChange) {
  auto s = mpm_block_setup(0.2, Vec<2>(0.4, 0.5), 0.05, 4, 0.0, 1.0, TransferScheme::APIC);
  s.dt = 2e-3;
  s.gravity = {0.0, -9.81, 0.0};
  auto& v = s.mpm->particles.v;
  for (std::size_t q = 0; q < v.extent(0); ++q) v(q, 0) = 3.0;  // 6 mm per step: a cell every ~8 steps
  Simulation<2> sim(s, comm());
  long builds = 0;
  const int steps = 20;
  for (int k = 0; k < steps; ++k) builds += sim.step().newton.graph_builds;
  const long total = sim.newton().dof_space().graph_builds();
  EXPECT_EQ(total, builds);
  EXPECT_GE(total, 2);
  EXPECT_LT(total, steps / 2);
  // Every build has its cause: the first, then the node set or the cells.
  long counted = 0;
  for (const auto& [cause, n] : sim.newton().dof_space().build_causes()) {
    counted += n;
    EXPECT_TRUE(cause == "first" || cause == "nodes" || cause == sim.newton().dof_space().terms().back()->name())
        << cause;
  }
  EXPECT_EQ(counted, total);
  EXPECT_EQ(sim.newton().dof_space().build_causes().front().first, "first");
  std::cout << "  graph builds: " << total << " in " << steps << " steps\n";
}

// Reversing the particle order changes only the order of sums within a cell:
// the run agrees to round-off.
TEST(DofSpace, ParticleOrderChangesOnlyRoundOff) {
  auto s = mpm_block_setup(0.2, Vec<2>(0.5, 0.5), 0.05, 4, 0.0, 1.0, TransferScheme::APIC);
  s.dt = 2e-3;
  s.gravity = {0.0, -9.81, 0.0};
  for (std::size_t q = 0; q < s.mpm->particles.size(); ++q) {
    const double y = s.mpm->particles.x(q, 1) - 0.5;
    s.mpm->particles.v(q, 0) = 2.0 * y;  // spinning and shearing
    s.mpm->particles.v(q, 1) = -1.0 * (s.mpm->particles.x(q, 0) - 0.5);
  }
  auto r = s;
  const std::size_t np = s.mpm->particles.size();
  r.mpm->particles = allocate_particles<2>(np);
  auto& a = s.mpm->particles;
  auto& b = r.mpm->particles;
  for (std::size_t q = 0; q < np; ++q) {
    const std::size_t k = np - 1 - q;
    for (int c = 0; c < 2; ++c) {
      b.x(k, c) = a.x(q, c);
      b.v(k, c) = a.v(q, c);
      for (int d = 0; d < 2; ++d) {
        b.F(k, c, d) = a.F(q, c, d);
        b.C(k, c, d) = a.C(q, c, d);
      }
    }
    b.mass(k) = a.mass(q);
    b.volume0(k) = a.volume0(q);
    b.body(k) = a.body(q);
    b.material(k) = a.material(q);
  }
  Simulation<2> sa(s, comm()), sb(r, comm());
  for (int k = 0; k < 10; ++k) {
    sa.step();
    sb.step();
  }
  const auto& pa = sa.mpm()->particles();
  const auto& pb = sb.mpm()->particles();
  double worst = 0, scale = 0;
  for (std::size_t q = 0; q < np; ++q)
    for (int c = 0; c < 2; ++c) {
      worst = std::max(worst, std::abs(pa.x(q, c) - pb.x(np - 1 - q, c)));
      scale = std::max(scale, std::abs(pa.x(q, c)));
      worst = std::max(worst, std::abs(pa.v(q, c) - pb.v(np - 1 - q, c)) * s.dt);
    }
  EXPECT_LT(worst, 1e-12 * scale) << "reversed particle order changed the run by " << worst;
  std::cout << "  reversed order: largest difference " << worst << " m (positions, dt * velocities)\n";
}

// The constraint rows the DOF space writes (end_assembly): a prescribed DOF's
// row is the identity with rhs = dx_prescribed, and no free row keeps an entry
// in a prescribed column (the sink moved it to the rhs).
TEST(DofSpace, EndAssemblyWritesIdentityRowsForPrescribedDofs) {
  auto setup = block_setup<2>(0.25, 1e5, 0.3);
  FemMesh<2> mesh = build_fem_mesh<2>(setup.bodies, setup.materials);
  DeformationTerm<2, 3> term("fem", mesh.elements);
  const LO n = mesh.num_nodes();
  const std::size_t nd = static_cast<std::size_t>(n) * 2;
  Kokkos::View<double*, MemSpace> x("x", nd), grad("grad", nd), rhs("rhs", nd), dx("dxp", nd);
  Kokkos::View<int*, MemSpace> p("pres", nd);
  for (std::size_t i = 0; i < nd; ++i) x(i) = mesh.rest_position(i) * (i % 2 ? 1.03 : 0.97);
  std::vector<double> dxp;
  const auto pres = some_prescribed(nd, dxp, 13);
  for (std::size_t i = 0; i < nd; ++i) {
    p(i) = pres[i];
    dx(i) = dxp[i];
  }
  DofSpace<2> space(comm());
  ASSERT_TRUE(space.set_structure(n, {&term}));
  space.begin_assembly();
  term.assemble(x, space.sink(0.5, grad, rhs, p, dx));
  Vector b(space.map());
  space.end_assembly(p, dx, rhs, b);
  auto A = space.matrix();
  auto bh = b.getLocalViewHost(Tpetra::Access::ReadOnly);
  long prescribed_rows = 0;
  for (std::size_t i = 0; i < nd; ++i) {
    typename Matrix::local_inds_host_view_type cols;
    typename Matrix::values_host_view_type vals;
    A->getLocalRowView(i, cols, vals);
    for (std::size_t k = 0; k < cols.extent(0); ++k) {
      const std::size_t j = cols(k);
      if (pres[i]) EXPECT_EQ(vals(k), j == i ? 1.0 : 0.0) << "prescribed row " << i << ", column " << j;
      else if (pres[j]) EXPECT_EQ(vals(k), 0.0) << "free row " << i << " keeps prescribed column " << j;
    }
    if (pres[i]) {
      ++prescribed_rows;
      EXPECT_EQ(rhs(i), dxp[i]) << "rhs of prescribed DOF " << i;
    }
    EXPECT_EQ(bh(i, 0), rhs(i)) << "b, DOF " << i;
  }
  EXPECT_GT(prescribed_rows, 10);
}
