#pragma once
// One contact pair: an MPM particle q and an FEM boundary primitive (a node, an
// edge or a triangle with nv = 1, 2, 3 vertices). Local variables are the
// particle position and the vertex positions, stacked: L = (1 + nv) * dim.
// The particle position is linear in the grid DOFs (paper Eq. 29):
//   x_q = sum_a w_qa x_{n(q,a)},   w the B-spline weights at x_q^n,
// so a local gradient g and (PSD) Hessian H reach the system as W^T g and
// W^T H W, where W maps the expanded DOFs (3^dim grid nodes, nv vertices) to
// the local ones (scatter_pair hands them to the DOF space's sink, which
// eliminates prescribed DOFs).
#include <Kokkos_Core.hpp>
#include <climits>
#include <cmath>
#include <type_traits>

#include "kernels/contact/barrier.hpp"
#include "kernels/contact/distance.hpp"
#include "kernels/mpm/bspline.hpp"
#include "kernels/small_loops.hpp"

namespace bfemp {

// Per step: the particles' interpolation stencils into the system DOFs, and
// their contact weights omega_q (paper §4.2: 2 sqrt(V0/pi) in 2D,
// pi (3 V0 / (4 pi))^(2/3) in 3D).
template <int dim>
struct ParticleStencils {
  static constexpr int ns = bspline_stencil_size<dim>;
  Kokkos::View<LO* [ns], MemSpace> nodes;  // system node ids
  Kokkos::View<double* [ns], MemSpace> w;  // weights, sum 1
  Kokkos::View<double*, MemSpace> omega;   // m (2D) or m^2 (3D)
  Kokkos::View<int*, MemSpace> body;       // MPM body index; FEM points: fem_body_base + FEM body
  // FEM-FEM contact (2D): the boundary nodes of the FEM bodies join the
  // points after the particles, each with a one-node stencil (weight 1 on
  // its own system node, 0 on the others) and omega = half the rest length
  // of its boundary edges; body(q) = fem_body_base + its FEM body, so that
  // pairs of a body with itself can be dropped (fem_body_base = the number of
  // MPM bodies; without FEM points, INT_MAX).
  int fem_body_base = INT_MAX;
  LO size() const { return static_cast<LO>(omega.extent(0)); }
};

// Whether point q and primitive j may form a pair: not when q is a node of
// an FEM body and j belongs to the same body (a node lies on its own facets).
template <int dim, class Prims>
KOKKOS_INLINE_FUNCTION bool contact_allowed(const ParticleStencils<dim>& ps, const Prims& prims, LO q, LO j) {
  const int b = ps.body(q);
  return b < ps.fem_body_base || b - ps.fem_body_base != prims.body(j);
}

template <int dim>
KOKKOS_INLINE_FUNCTION double particle_contact_weight(double volume0) {
  if constexpr (dim == 2) return 2.0 * std::sqrt(volume0 / M_PI);
  else return M_PI * std::pow(3.0 * volume0 / (4.0 * M_PI), 2.0 / 3.0);
}

// x_q = sum_a w_a x_{n_a} for every particle (node-interleaved output).
template <int dim>
void interpolate_particles(const ParticleStencils<dim>& ps, Kokkos::View<const double*, MemSpace> x,
                           Kokkos::View<double*, MemSpace> xq) {
  small_for(
      "contact_interpolate", ps.size(),
      KOKKOS_LAMBDA(const LO q) {
        for (int c = 0; c < dim; ++c) {
          double s = 0;
          for (int a = 0; a < ParticleStencils<dim>::ns; ++a) s += ps.w(q, a) * x(ps.nodes(q, a) * dim + c);
          xq(q * dim + c) = s;
        }
      },
      kSerialBelow / 16);  // a 20-60 ns body
}

// The same for the particles of a pair list only: pairs(seg(s), 0) for
// s < n_seg (the runs of particle_segments below). Pairs sorted by particle
// (one run per particle) write each particle once; the other particles' xq
// entries are left as they were.
template <int dim>
void interpolate_pair_particles(const ParticleStencils<dim>& ps, const Kokkos::View<LO* [2], MemSpace>& pairs,
                                const Kokkos::View<LO*, MemSpace>& seg, LO n_seg,
                                Kokkos::View<const double*, MemSpace> x, Kokkos::View<double*, MemSpace> xq) {
  small_for(
      "contact_interpolate_pairs", n_seg,
      KOKKOS_LAMBDA(const LO s) {
        const LO q = pairs(seg(s), 0);
        for (int c = 0; c < dim; ++c) {
          double v = 0;
          for (int a = 0; a < ParticleStencils<dim>::ns; ++a) v += ps.w(q, a) * x(ps.nodes(q, a) * dim + c);
          xq(q * dim + c) = v;
        }
      },
      kSerialBelow / 16);
}

// Runs of equal particle in a pair list (pairs(k, 0) = particle): seg(s) is
// the first pair of run s, seg(count) = n; returns count. Pairs sorted by
// particle (as the broad phase returns them) give one run per particle;
// unsorted ones only more runs. seg grows (with headroom) when too small.
inline LO particle_segments(const Kokkos::View<LO* [2], MemSpace>& pairs, LO n, Kokkos::View<LO*, MemSpace>& seg) {
  if (static_cast<LO>(seg.extent(0)) < n + 1) seg = Kokkos::View<LO*, MemSpace>("pair_segments", n + n / 4 + 16);
  const auto out = seg;
  LO count = 0;
  small_scan(
      "pair_segments", n, KOKKOS_LAMBDA(const LO k, LO& offset, const bool final) {
        const bool first = k == 0 || pairs(k, 0) != pairs(k - 1, 0);
        if (first && final) out(offset) = k;
        offset += first ? 1 : 0;
      },
      count);
  out(count) = n;  // host memory (small_loops.hpp asserts it); the scan has finished
  return count;
}

template <int dim>
KOKKOS_INLINE_FUNCTION Vec<dim> load_vec(const Kokkos::View<const double*, MemSpace>& x, LO node) {
  Vec<dim> v;
  for (int c = 0; c < dim; ++c) v(c) = x(node * dim + c);
  return v;
}

// Squared distance of the pair's stencil with derivatives (nv = 1, 2, 3).
template <int dim, int nv>
KOKKOS_INLINE_FUNCTION Distance2<(1 + nv) * dim> stencil_distance2(const Vec<dim>& p, const Vec<dim>* v) {
  if constexpr (nv == 1) return point_point_distance2_derivatives<dim>(p, v[0]);
  else if constexpr (nv == 2) return point_edge_distance2_derivatives<dim>(p, v[0], v[1]);
  else return point_triangle_distance2_derivatives(p, v[0], v[1], v[2]);
}

template <int dim, int nv>
KOKKOS_INLINE_FUNCTION double stencil_distance2_value(const Vec<dim>& p, const Vec<dim>* v) {
  if constexpr (nv == 1) return point_point_distance2<dim>(p, v[0]);
  else if constexpr (nv == 2) return point_edge_distance2<dim>(p, v[0], v[1]);
  else return point_triangle_distance2(p, v[0], v[1], v[2]);
}

// Barrier b(d) of a pair as a function of s = d^2, with gradient and Hessian
// in the local variables: db/ds = b'/(2d), d2b/ds2 = (b'' - b'/d) / (4 s).
template <int L>
KOKKOS_INLINE_FUNCTION void barrier_of_distance2(const Distance2<L>& s, double dhat, double kappa, double w,
                                                 Eigen::Matrix<double, L, 1>& g, SquareMat<L>& H) {
  const double d = std::sqrt(s.d2);
  const double b1 = barrier_first_derivative(d, dhat, kappa);
  const double b2 = barrier_second_derivative(d, dhat, kappa);
  const double dbds = b1 / (2.0 * d);
  const double d2bds2 = (b2 - b1 / d) / (4.0 * s.d2);
  g = (w * dbds) * s.grad;
  H = (w * d2bds2) * (s.grad * s.grad.transpose()) + (w * dbds) * s.hess;
}

// Expanded DOF r of a pair (grid stencil nodes first, then the vertices).
template <int dim>
struct PairDofs {
  static constexpr int ns = bspline_stencil_size<dim>;
  LO node[ns + dim];  // system nodes: ns grid nodes, then up to dim vertices
  double w[ns];
  int nv;
  KOKKOS_INLINE_FUNCTION int expanded_nodes() const { return ns + nv; }
};

// Calls f(std::integral_constant<int, nv>) for a primitive with nv vertices.
template <int dim, class F>
KOKKOS_INLINE_FUNCTION void dispatch_nv(int nv, const F& f) {
  if (nv == 1) f(std::integral_constant<int, 1>{});
  else if (nv == 2) f(std::integral_constant<int, 2>{});
  else if constexpr (dim == 3) f(std::integral_constant<int, 3>{});
}

// The pair's expanded DOFs: particle q's stencil, then primitive j's vertices.
template <int dim, class Prims>
KOKKOS_INLINE_FUNCTION void fill_pair_dofs(const ParticleStencils<dim>& ps, const Prims& prims, LO q, LO j, int nv,
                                           PairDofs<dim>& pd) {
  constexpr int ns = ParticleStencils<dim>::ns;
  for (int a = 0; a < ns; ++a) {
    pd.node[a] = ps.nodes(q, a);
    pd.w[a] = ps.w(q, a);
  }
  for (int i = 0; i < nv; ++i) pd.node[ns + i] = prims.nodes(j, i);
  pd.nv = nv;
}

// The pair's local gradient and (when H is given) Hessian, expanded through
// W, into the sink: W^T g and the blocks w_e w_f H(block e, block f), where a
// grid node's block is the particle's and a vertex's its own. The sink scales
// them and eliminates prescribed DOFs.
template <int dim, int L, class Sink>
KOKKOS_INLINE_FUNCTION void scatter_pair(const PairDofs<dim>& pd, const Eigen::Matrix<double, L, 1>& g,
                                         const SquareMat<L>* H, const Sink& sink) {
  constexpr int ns = PairDofs<dim>::ns;
  const int ne = pd.expanded_nodes();
  auto block = [&](int e) { return e < ns ? 0 : e - ns + 1; };
  auto weight = [&](int e) { return e < ns ? pd.w[e] : 1.0; };
  for (int e = 0; e < ne; ++e)
    for (int c = 0; c < dim; ++c) sink.add_gradient(pd.node[e], c, weight(e) * g(block(e) * dim + c));
  if (!H || !sink.has_matrix()) return;
  for (int e = 0; e < ne; ++e)
    for (int f = 0; f < ne; ++f) {
      const double wef = weight(e) * weight(f);
      if (wef == 0.0) continue;  // a B-spline weight of 0 adds nothing
      const int be = block(e) * dim, bf = block(f) * dim;
      sink.add_block(pd.node[e], pd.node[f], [&](int i, int j) { return wef * (*H)(be + i, bf + j); });
    }
}

}  // namespace bfemp
