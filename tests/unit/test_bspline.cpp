// Quadratic B-spline stencils on the MPM grid, 2D and 3D: partition of unity,
// linear and gradient reproduction, non-negativity, derivatives against
// central finite differences of the global nodal functions, exact values on
// grid nodes and on the cell-centre planes where the stencil switches, the
// contains() margin, grid numbering and grid_covering.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <random>
#include <type_traits>
#include <vector>

#include "kernels/mpm/bspline.hpp"
#include "kernels/mpm/grid.hpp"

namespace {

using namespace bfemp;

template <class T>
class BSpline : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(BSpline, Dims);

// dx = 0.1 with an arbitrary origin (rounding everywhere), or dx = 1/8 with a
// binary origin (node and cell-centre positions exactly representable).
template <int dim>
GridSpec<dim> test_grid(bool binary) {
  GridSpec<dim> g;
  const double o[3] = {-0.3, 0.7, 0.1}, ob[3] = {-0.25, 0.5, 0.125};
  const int n[3] = {10, 12, 8};
  for (int d = 0; d < dim; ++d) {
    g.origin[d] = binary ? ob[d] : o[d];
    g.n_cells[d] = n[d];
  }
  g.dx = binary ? 0.125 : 0.1;
  return g;
}

// Cell coordinates (per axis): random, on a node, or on a cell-centre plane,
// all inside the usable range [1/2, n - 1/2).
template <int dim>
std::vector<Vec<dim>> test_positions(const GridSpec<dim>& g, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec<dim>> xs;
  for (int k = 0; k < 600; ++k) {
    Vec<dim> x;
    for (int d = 0; d < dim; ++d) {
      const int kind = (k / 200 + d) % 3;
      double s = 0.5 + u(rng) * (g.n_cells[d] - 1.0 - 1e-9);
      // Snapped positions stay off the usable range's ends s = 1/2 and
      // n - 1/2, where rounding of x decides (tested on their own below).
      if (kind == 1) s = std::floor(std::max(s, 1.0) - 0.5) + 1.0;  // node
      if (kind == 2) s = std::floor(std::max(s, 1.5) - 0.5) + 0.5;  // cell centre, >= 1.5
      x[d] = g.origin[d] + g.dx * s;
    }
    xs.push_back(x);
  }
  return xs;
}

// Global nodal function N_i(x): 0 outside the stencil of x.
template <int dim>
double node_weight(const GridSpec<dim>& g, const Vec<dim>& x, const GridIndex<dim>& i) {
  const auto s = bspline_stencil<dim>(g, x);
  for (int a = 0; a < bspline_stencil_size<dim>; ++a)
    if (stencil_node<dim>(s, a) == i) return weight<dim>(s, a);
  return 0.0;
}

TYPED_TEST(BSpline, ReproductionIdentities) {
  constexpr int dim = TypeParam::value;
  std::mt19937 rng(7);
  for (bool binary : {false, true}) {
    const auto g = test_grid<dim>(binary);
    for (const Vec<dim>& xp : test_positions<dim>(g, rng)) {
      ASSERT_TRUE(g.contains(xp)) << std::setprecision(17) << (xp - g.origin).transpose() / g.dx;
      const auto s = bspline_stencil<dim>(g, xp);
      double sum_w = 0.0;
      Vec<dim> sum_wx = Vec<dim>::Zero(), sum_g = Vec<dim>::Zero();
      Mat<dim> sum_xg = Mat<dim>::Zero();
      for (int a = 0; a < bspline_stencil_size<dim>; ++a) {
        const double w = weight<dim>(s, a);
        const Vec<dim> gw = weight_gradient<dim>(s, a);
        const Vec<dim> xa = g.node_position(node_index<dim>(g, s, a));
        EXPECT_GE(w, 0.0);
        sum_w += w;
        sum_wx += w * xa;
        sum_g += gw;
        sum_xg += xa * gw.transpose();
      }
      EXPECT_NEAR(sum_w, 1.0, 1e-14);
      EXPECT_LT((sum_wx - xp).norm(), 1e-14 * (1.0 + xp.norm()));
      EXPECT_LT(sum_g.norm() * g.dx, 1e-13);
      EXPECT_LT((sum_xg - Mat<dim>::Identity()).norm(), 1e-13 * (1.0 + xp.norm() / g.dx));
    }
  }
}

TYPED_TEST(BSpline, GradientMatchesFiniteDifferences) {
  constexpr int dim = TypeParam::value;
  std::mt19937 rng(11);
  for (bool binary : {false, true}) {
    const auto g = test_grid<dim>(binary);
    const double h = 1e-7 * g.dx;
    for (const Vec<dim>& xp : test_positions<dim>(g, rng)) {
      const auto s = bspline_stencil<dim>(g, xp);
      for (int a = 0; a < bspline_stencil_size<dim>; ++a) {
        const GridIndex<dim> i = stencil_node<dim>(s, a);
        const Vec<dim> gw = weight_gradient<dim>(s, a);
        for (int k = 0; k < dim; ++k) {
          Vec<dim> xm = xp, xq = xp;
          xm[k] -= h;
          xq[k] += h;
          const double fd = (node_weight<dim>(g, xq, i) - node_weight<dim>(g, xm, i)) / (2.0 * h);
          // Central differences are exact for the quadratic pieces; across a
          // knot the error is at most h |jump N''| = 3 h / dx^2.
          EXPECT_NEAR(gw[k] * g.dx, fd * g.dx, 1e-6) << "node " << a << " axis " << k;
        }
      }
    }
  }
}

TYPED_TEST(BSpline, ExactValuesOnNodesAndCellCentres) {
  constexpr int dim = TypeParam::value;
  const auto g = test_grid<dim>(true);
  Vec<dim> on_node, on_centre;
  for (int d = 0; d < dim; ++d) {
    on_node[d] = g.origin[d] + 3.0 * g.dx;    // stencil nodes 2, 3, 4
    on_centre[d] = g.origin[d] + 3.5 * g.dx;  // stencil nodes 3, 4, 5
  }
  const auto sn = bspline_stencil<dim>(g, on_node);
  const auto sc = bspline_stencil<dim>(g, on_centre);
  for (int d = 0; d < dim; ++d) {
    EXPECT_EQ(sn.base[d], 2);
    EXPECT_EQ(sn.w[d][0], 0.125);
    EXPECT_EQ(sn.w[d][1], 0.75);
    EXPECT_EQ(sn.w[d][2], 0.125);
    EXPECT_EQ(sn.dw[d][0] * g.dx, -0.5);
    EXPECT_EQ(sn.dw[d][1], 0.0);
    EXPECT_EQ(sn.dw[d][2] * g.dx, 0.5);
    EXPECT_EQ(sc.base[d], 3);
    EXPECT_EQ(sc.w[d][0], 0.5);
    EXPECT_EQ(sc.w[d][1], 0.5);
    EXPECT_EQ(sc.w[d][2], 0.0);
    EXPECT_EQ(sc.dw[d][0] * g.dx, -1.0);
    EXPECT_EQ(sc.dw[d][1] * g.dx, 1.0);
    EXPECT_EQ(sc.dw[d][2], 0.0);
  }
  // Just below the cell-centre plane the stencil starts one node lower; the
  // nodal functions are continuous across the switch.
  Vec<dim> below = on_centre;
  below[0] -= 1e-12;
  EXPECT_EQ(bspline_stencil<dim>(g, below).base[0], 2);
  for (int a = 0; a < bspline_stencil_size<dim>; ++a) {
    const GridIndex<dim> i = stencil_node<dim>(sc, a);
    EXPECT_NEAR(node_weight<dim>(g, below, i), weight<dim>(sc, a), 1e-10);
  }
  GridIndex<dim> low = stencil_node<dim>(bspline_stencil<dim>(g, below), 0);
  EXPECT_NEAR(node_weight<dim>(g, below, low), 0.0, 1e-10);
}

TYPED_TEST(BSpline, ContainsIsExactlyTheStencilMargin) {
  constexpr int dim = TypeParam::value;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (bool binary : {false, true}) {
    const auto g = test_grid<dim>(binary);
    int inside = 0, outside = 0;
    for (int k = 0; k < 20000; ++k) {
      Vec<dim> x;
      for (int d = 0; d < dim; ++d) {
        // Mostly near the two ends of the axis, where the margin matters.
        const double s = (k % 2 ? 0.5 : g.n_cells[d] - 0.5) + u(rng);
        x[d] = g.origin[d] + g.dx * (k % 7 == 0 ? 0.5 * g.n_cells[d] : s);
      }
      const auto st = bspline_stencil<dim>(g, x);
      bool in_range = true;
      for (int a = 0; a < bspline_stencil_size<dim>; ++a) {
        const GridIndex<dim> i = stencil_node<dim>(st, a);
        for (int d = 0; d < dim; ++d) in_range = in_range && i[d] >= 0 && i[d] <= g.n_cells[d];
      }
      EXPECT_EQ(g.contains(x), in_range) << "x = " << x.transpose();
      (in_range ? inside : outside) += 1;
    }
    EXPECT_GT(inside, 1000);
    EXPECT_GT(outside, 1000);
    // Exact ends on the binary grid: s = 1/2 is usable, s = n - 1/2 is not.
    if (binary) {
      Vec<dim> lo, hi;
      for (int d = 0; d < dim; ++d) {
        lo[d] = g.origin[d] + 0.5 * g.dx;
        hi[d] = g.origin[d] + (g.n_cells[d] - 0.5) * g.dx;
      }
      EXPECT_TRUE(g.contains(lo));
      EXPECT_FALSE(g.contains(hi));
      Vec<dim> nan = lo;
      nan[dim - 1] = std::nan("");
      EXPECT_FALSE(g.contains(nan));
    }
  }
}

TYPED_TEST(BSpline, GridNumberingIsXFastest) {
  constexpr int dim = TypeParam::value;
  const auto g = test_grid<dim>(false);
  LO expected = 1;
  for (int d = 0; d < dim; ++d) expected *= g.n_cells[d] + 1;
  ASSERT_EQ(g.num_nodes(), expected);
  GridIndex<dim> e{};
  e[0] = 1;
  EXPECT_EQ(g.node_index(e), 1);
  e[0] = 0;
  e[1] = 1;
  EXPECT_EQ(g.node_index(e), g.n_cells[0] + 1);
  for (LO n = 0; n < g.num_nodes(); ++n) {
    const GridIndex<dim> i = g.node_multi_index(n);
    ASSERT_EQ(g.node_index(i), n);
    for (int d = 0; d < dim; ++d) {
      ASSERT_TRUE(i[d] >= 0 && i[d] <= g.n_cells[d]);
      EXPECT_DOUBLE_EQ(g.node_position(n)[d], g.origin[d] + g.dx * i[d]);
    }
  }
}

TYPED_TEST(BSpline, GridCoveringIsMinimalAndLatticeAligned) {
  constexpr int dim = TypeParam::value;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (double dx : {0.1, 0.125, 0.0625, 0.3}) {
    for (int k = 0; k < 200; ++k) {
      Vec<dim> lo, hi;
      for (int d = 0; d < dim; ++d) {
        lo[d] = k % 5 == 0 ? dx * std::round(u(rng) / dx) : u(rng);  // some on nodes
        hi[d] = lo[d] + (k % 11 == 0 ? 0.0 : std::abs(u(rng)));
      }
      const GridSpec<dim> g = grid_covering<dim>(lo, hi, dx);
      EXPECT_TRUE(g.contains(lo));
      EXPECT_TRUE(g.contains(hi));
      for (int d = 0; d < dim; ++d) {
        EXPECT_NEAR(g.origin[d] / dx, std::round(g.origin[d] / dx), 1e-9);
        // One cell less at either end would lose a corner.
        GridSpec<dim> shrunk = g;
        shrunk.n_cells[d] -= 1;
        EXPECT_FALSE(shrunk.contains(hi));
        shrunk.origin[d] += dx;
        EXPECT_FALSE(shrunk.contains(lo));
      }
    }
  }
  EXPECT_THROW(grid_covering<dim>(Vec<dim>::Zero(), Vec<dim>::Ones(), 0.0), std::invalid_argument);
  EXPECT_THROW(grid_covering<dim>(Vec<dim>::Ones(), Vec<dim>::Zero(), 0.1), std::invalid_argument);
  EXPECT_THROW(grid_covering<dim>(Vec<dim>::Zero(), Vec<dim>::Ones(), 1e-9), std::invalid_argument);
}

// The helpers run inside a Kokkos kernel.
TYPED_TEST(BSpline, IdentitiesHoldInsideKernels) {
  constexpr int dim = TypeParam::value;
  const auto g = test_grid<dim>(false);
  std::mt19937 rng(13);
  const auto pos = test_positions<dim>(g, rng);
  Kokkos::View<double* [dim], MemSpace> x("x", pos.size());
  auto xh = Kokkos::create_mirror_view(x);
  for (std::size_t q = 0; q < pos.size(); ++q)
    for (int d = 0; d < dim; ++d) xh(q, d) = pos[q][d];
  Kokkos::deep_copy(x, xh);
  double err = 0.0;
  Kokkos::parallel_reduce(
      "bspline_test", Kokkos::RangePolicy<ExecSpace>(0, pos.size()),
      KOKKOS_LAMBDA(const int q, double& acc) {
        Vec<dim> xp;
        for (int d = 0; d < dim; ++d) xp[d] = x(q, d);
        if (!g.contains(xp)) { acc = 1e300; return; }
        const auto s = bspline_stencil<dim>(g, xp);
        double sw = -1.0;
        Mat<dim> sxg = -Mat<dim>::Identity();
        for (int a = 0; a < bspline_stencil_size<dim>; ++a) {
          sw += weight<dim>(s, a);
          sxg += g.node_position(node_index<dim>(g, s, a)) * weight_gradient<dim>(s, a).transpose();
        }
        const double e = std::max(std::abs(sw), sxg.cwiseAbs().maxCoeff());
        if (e > acc) acc = e;
      },
      Kokkos::Max<double>(err));
  EXPECT_LT(err, 1e-12);
}

// for_each_stencil_node (the transfers' one-pass visit) gives, node by node
// and in stencil order, the same node, weight, gradient and x_i - x_p as
// node_index, weight, weight_gradient and node_position.
TYPED_TEST(BSpline, ForEachStencilNodeMatchesTheIndexedQueries) {
  constexpr int dim = TypeParam::value;
  std::mt19937 rng(7);
  for (bool binary : {false, true}) {
    const auto g = test_grid<dim>(binary);
    for (const auto& x : test_positions<dim>(g, rng)) {
      const auto st = bspline_stencil<dim>(g, x);
      int visited = 0;
      for_each_stencil_node<dim>(g, st, x, [&](int a, LO node, double w, const Vec<dim>& gw, const Vec<dim>& r) {
        EXPECT_EQ(a, visited);
        ++visited;
        EXPECT_EQ(node, node_index<dim>(g, st, a));
        EXPECT_NEAR(w, weight<dim>(st, a), 1e-15);
        const Vec<dim> ge = weight_gradient<dim>(st, a);
        const Vec<dim> re = g.node_position(node) - x;
        for (int d = 0; d < dim; ++d) {
          EXPECT_NEAR(gw[d], ge[d], 1e-12 * (1.0 + std::fabs(ge[d])));
          EXPECT_NEAR(r[d], re[d], 1e-14);
        }
      });
      EXPECT_EQ(visited, bspline_stencil_size<dim>);
    }
  }
}

}  // namespace
