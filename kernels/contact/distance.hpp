#pragma once
// Squared distances of the contact stencils (paper §4, Eqs. 31-32):
// point-point, point-edge (2D and 3D) and point-triangle (3D), each with the
// closest-feature case analysis, and (below) their gradients and Hessians.
//
// Every case is a squared norm d2 = |w|^2 of a "closest vector"
//   w = sum_i c_i(b) x_i,   x = (p, v_0, v_1, ...) stacked,
// with c_i affine in nb free parameters b (nb = 0 for point-point, 1 for
// point-line, 2 for point-plane) at their unconstrained optimum dd2/db = 0.
// The case decides which features are active; the value returned is always
// the one of the case reported, and the derivatives are those of that value.
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>

#include "core/types.hpp"

namespace bfemp {

// d2 with its gradient and Hessian in the stacked stencil variables, and
// what spans the range of both (see the derivatives below):
//   grad = 2 c (x) w,   hess = 2 (c c^T (x) I) - 2 N G^-1 N^T,
//   N's column k = dc_k (x) w + c (x) u_k,
// so grad and hess (and any f'(d2) hess + f''(d2) grad grad^T) map into
//   span{ c (x) e_k : k < dim } + span{ dc_k (x) w : k < nb },
// at most dim + nb dimensions of the n = nv dim variables (c (x) u_k lies
// in the first part). c and dc hold nv = n / dim stencil coefficients each;
// c[0] = 1 (the point), so w = grad's first block / 2.
template <int n>
struct Distance2 {
  double d2;
  Eigen::Matrix<double, n, 1> grad;
  Eigen::Matrix<double, n, n> hess;
  double c[4] = {0, 0, 0, 0};
  double dc[2][4] = {{0, 0, 0, 0}, {0, 0, 0, 0}};
  int nb = 0;
};

// Closest feature of the edge (e0, e1) to p: an endpoint or the interior.
enum class PointEdgeCase : int { P_E0 = 0, P_E1 = 1, P_E = 2 };
// Closest feature of the triangle (t0, t1, t2) to p: a vertex, an edge
// (E01 = t0->t1, E12 = t1->t2, E20 = t2->t0) or the interior.
enum class PointTriangleCase : int { P_T0, P_T1, P_T2, P_E01, P_E12, P_E20, P_T };

namespace contact_detail {

// A triangle is treated as collinear (zero area) when
// |e1 x e2|^2 <= kDegenerateSin2 |e1|^2 |e2|^2, i.e. sin(angle) <= 1e-8: its
// plane is then too ill-defined for the interior case, and the distance is
// the minimum of the three point-edge distances (error <= 1e-8 * edge length).
constexpr double kDegenerateSin2 = 1e-16;

// Edge parameter beta of the closest point (1 - beta) e0 + beta e1 and the case.
// beta* = (p - e0).e / |e|^2 clamped to [0, 1]; a zero-length edge is P_E0.
template <int dim>
struct PointEdgeClosest {
  PointEdgeCase c;
  double beta;
};

template <int dim>
KOKKOS_INLINE_FUNCTION PointEdgeClosest<dim> point_edge_closest(const Vec<dim>& p, const Vec<dim>& e0,
                                                               const Vec<dim>& e1) {
  const Vec<dim> e = e1 - e0;
  const double ee = e.squaredNorm();
  if (!(ee > 0)) return {PointEdgeCase::P_E0, 0.0};
  const double beta = (p - e0).dot(e) / ee;
  if (!(beta > 0)) return {PointEdgeCase::P_E0, 0.0};  // also catches NaN
  if (beta >= 1) return {PointEdgeCase::P_E1, 1.0};
  return {PointEdgeCase::P_E, beta};
}

// Closest feature of a triangle with the parameters of that feature:
// interior (b1, b2) or, for edge cases, beta along the edge's own direction.
struct PointTriangleClosest {
  PointTriangleCase c;
  double b1, b2;  // closest = (1 - b1 - b2) t0 + b1 t1 + b2 t2
  double beta;    // edge cases: closest = (1 - beta) ta + beta tb
  double d2;
};

// The squared distance of the case in `c`: endpoints exactly |p - e_k|^2,
// interior |p - e0 - beta (e1 - e0)|^2 (the point-line distance, evaluated
// through the closest point: no cancellation as in |r|^2 - (r.e)^2/|e|^2).
template <int dim>
KOKKOS_INLINE_FUNCTION double point_edge_d2_from(const Vec<dim>& p, const Vec<dim>& e0, const Vec<dim>& e1,
                                                 const PointEdgeClosest<dim>& c) {
  switch (c.c) {
    case PointEdgeCase::P_E0: return (p - e0).squaredNorm();
    case PointEdgeCase::P_E1: return (p - e1).squaredNorm();
    default: return (p - (e0 + c.beta * (e1 - e0))).squaredNorm();
  }
}

KOKKOS_INLINE_FUNCTION PointTriangleClosest point_triangle_closest(const Vec<3>& p, const Vec<3>& t0,
                                                                  const Vec<3>& t1, const Vec<3>& t2) {
  const Vec<3> e1 = t1 - t0, e2 = t2 - t0, r = p - t0;
  // Barycentrics are scale-invariant: compute them on the triangle scaled to
  // unit size, so that tiny (or huge) triangles do not under/overflow |n|^2.
  const double L = std::sqrt(std::max(e1.squaredNorm(), e2.squaredNorm()));
  if (L > 0 && std::isfinite(L)) {
    const Vec<3> f1 = e1 / L, f2 = e2 / L, s = r / L;
    const Vec<3> n = f1.cross(f2);
    const double nn = n.squaredNorm();
    if (nn > kDegenerateSin2 * f1.squaredNorm() * f2.squaredNorm()) {
      // Barycentrics of the projection of p on the plane, from
      // s = b1 f1 + b2 f2 + c n:  (s x f2).n = b1 |n|^2,  (f1 x s).n = b2 |n|^2.
      const double b1 = s.cross(f2).dot(n) / nn;
      const double b2 = f1.cross(s).dot(n) / nn;
      if (b1 >= 0 && b2 >= 0 && b1 + b2 <= 1) {
        const Vec<3> w = r - b1 * e1 - b2 * e2;
        return {PointTriangleCase::P_T, b1, b2, 0.0, w.squaredNorm()};
      }
    }
  }
  // Projection outside (or no usable plane): the triangle is convex, so the
  // closest point lies on its boundary: the nearest of the three edges.
  // Ties keep the first edge in the order E01, E12, E20.
  const PointEdgeClosest<3> c01 = point_edge_closest<3>(p, t0, t1);
  const PointEdgeClosest<3> c12 = point_edge_closest<3>(p, t1, t2);
  const PointEdgeClosest<3> c20 = point_edge_closest<3>(p, t2, t0);
  const double d01 = point_edge_d2_from<3>(p, t0, t1, c01);
  const double d12 = point_edge_d2_from<3>(p, t1, t2, c12);
  const double d20 = point_edge_d2_from<3>(p, t2, t0, c20);
  int k = 0;
  double d = d01;
  if (d12 < d) k = 1, d = d12;
  if (d20 < d) k = 2, d = d20;
  PointTriangleClosest out{PointTriangleCase::P_T, 0.0, 0.0, 0.0, d};
  // Vertex cases come from the edge's endpoint cases; (b1, b2) from beta.
  if (k == 0) {
    out.beta = c01.beta;
    out.c = c01.c == PointEdgeCase::P_E0   ? PointTriangleCase::P_T0
            : c01.c == PointEdgeCase::P_E1 ? PointTriangleCase::P_T1
                                           : PointTriangleCase::P_E01;
    out.b1 = c01.beta;  // (1 - beta) t0 + beta t1
    out.b2 = 0;
  } else if (k == 1) {
    out.beta = c12.beta;
    out.c = c12.c == PointEdgeCase::P_E0   ? PointTriangleCase::P_T1
            : c12.c == PointEdgeCase::P_E1 ? PointTriangleCase::P_T2
                                           : PointTriangleCase::P_E12;
    out.b1 = 1 - c12.beta;  // (1 - beta) t1 + beta t2
    out.b2 = c12.beta;
  } else {
    out.beta = c20.beta;
    out.c = c20.c == PointEdgeCase::P_E0   ? PointTriangleCase::P_T2
            : c20.c == PointEdgeCase::P_E1 ? PointTriangleCase::P_T0
                                           : PointTriangleCase::P_E20;
    out.b1 = 0;  // (1 - beta) t2 + beta t0
    out.b2 = 1 - c20.beta;
  }
  return out;
}

}  // namespace contact_detail

// ---------------------------------------------------------------- values

// d2 = |p - q|^2.
template <int dim>
KOKKOS_INLINE_FUNCTION double point_point_distance2(const Vec<dim>& p, const Vec<dim>& q) {
  return (p - q).squaredNorm();
}

template <int dim>
KOKKOS_INLINE_FUNCTION PointEdgeCase point_edge_case(const Vec<dim>& p, const Vec<dim>& e0, const Vec<dim>& e1) {
  return contact_detail::point_edge_closest<dim>(p, e0, e1).c;
}

// beta in [0, 1] of the closest point (1 - beta) e0 + beta e1.
template <int dim>
KOKKOS_INLINE_FUNCTION double point_edge_closest_parameter(const Vec<dim>& p, const Vec<dim>& e0,
                                                           const Vec<dim>& e1) {
  return contact_detail::point_edge_closest<dim>(p, e0, e1).beta;
}

// P_E0: |p - e0|^2, P_E1: |p - e1|^2, P_E: squared point-line distance.
template <int dim>
KOKKOS_INLINE_FUNCTION double point_edge_distance2(const Vec<dim>& p, const Vec<dim>& e0, const Vec<dim>& e1) {
  return contact_detail::point_edge_d2_from<dim>(p, e0, e1, contact_detail::point_edge_closest<dim>(p, e0, e1));
}

KOKKOS_INLINE_FUNCTION PointTriangleCase point_triangle_case(const Vec<3>& p, const Vec<3>& t0, const Vec<3>& t1,
                                                            const Vec<3>& t2) {
  return contact_detail::point_triangle_closest(p, t0, t1, t2).c;
}

// (b1, b2) of the closest point (1 - b1 - b2) t0 + b1 t1 + b2 t2.
KOKKOS_INLINE_FUNCTION Vec<2> point_triangle_closest_barycentric(const Vec<3>& p, const Vec<3>& t0,
                                                                const Vec<3>& t1, const Vec<3>& t2) {
  const auto c = contact_detail::point_triangle_closest(p, t0, t1, t2);
  return Vec<2>(c.b1, c.b2);
}

// Interior: squared distance to the plane; otherwise (and for collinear
// triangles) the nearest edge's point-edge distance.
KOKKOS_INLINE_FUNCTION double point_triangle_distance2(const Vec<3>& p, const Vec<3>& t0, const Vec<3>& t1,
                                                      const Vec<3>& t2) {
  return contact_detail::point_triangle_closest(p, t0, t1, t2).d2;
}

// ---------------------------------------------------------------- derivatives

namespace contact_detail {

// Derivatives of one case, d2(x) = |w|^2 with w = sum_i c_i x_i over the nv
// stencil vertices x = (p, v_0, ...), the c_i constant (point-point) or
// affine in nb free parameters b at their optimum dd2/db = 0:
//   gradient (envelope theorem, dd2/db = 0):   dd2/dx_i = 2 c_i w;
//   Hessian (implicit function theorem):       H = 2 (c c^T (x) I) - 2 N G^-1 N^T
// with u_k = dw/db_k = sum_i (dc_i/db_k) x_i, G_kl = u_k.u_l (so d2d2/db2 = 2G),
// and column k of N, block i: (dc_i/db_k) w + c_i u_k (= (1/2) d2d2/dx_i db_k),
// which follows from db*/dx = -(2G)^-1 (2N)^T.

// nb = 0: point-point in disguise, H = 2 (c c^T (x) I).
template <int dim, int nv>
KOKKOS_INLINE_FUNCTION Distance2<nv * dim> stencil_distance2(const Vec<dim>& w,
                                                             const Eigen::Matrix<double, nv, 1>& c) {
  static_assert(nv <= 4, "at most 4 stencil vertices");
  Distance2<nv * dim> out;
  out.d2 = w.squaredNorm();
  for (int i = 0; i < nv; ++i) out.c[i] = c(i);
  for (int i = 0; i < nv; ++i) {
    out.grad.template segment<dim>(i * dim) = 2 * c(i) * w;
    for (int j = 0; j < nv; ++j)
      out.hess.template block<dim, dim>(i * dim, j * dim) = (2 * c(i) * c(j)) * Mat<dim>::Identity();
  }
  return out;
}

// nb = 1 (point-line) and nb = 2 (point-plane): the correction -2 N G^-1 N^T.
template <int dim, int nv, int nb>
KOKKOS_INLINE_FUNCTION Distance2<nv * dim> stencil_distance2(const Vec<dim>& w,
                                                             const Eigen::Matrix<double, nv, 1>& c,
                                                             const Eigen::Matrix<double, nv, nb>& dc,
                                                             const Eigen::Matrix<double, dim, nb>& U,
                                                             const SquareMat<nb>& Ginv) {
  Distance2<nv * dim> out = stencil_distance2<dim, nv>(w, c);
  Eigen::Matrix<double, nv * dim, nb> N;
  for (int k = 0; k < nb; ++k)
    for (int i = 0; i < nv; ++i) N.template block<dim, 1>(i * dim, k) = dc(i, k) * w + c(i) * U.col(k);
  out.hess -= 2 * N * Ginv * N.transpose();
  for (int k = 0; k < nb; ++k)
    for (int i = 0; i < nv; ++i) out.dc[k][i] = dc(i, k);
  out.nb = nb;
  return out;
}

// The edge case "closest point (1 - beta) x_a + beta x_b" of an nv-vertex
// stencil (slot 0 is the point): w = p - (x_a + beta (x_b - x_a)),
// c_0 = 1, c_a = -(1 - beta), c_b = -beta; dc_a = 1, dc_b = -1; u = x_a - x_b.
template <int dim, int nv>
KOKKOS_INLINE_FUNCTION Distance2<nv * dim> stencil_point_edge(const Vec<dim>& p, const Vec<dim>& xa,
                                                              const Vec<dim>& xb, int a, int b, double beta) {
  Eigen::Matrix<double, nv, 1> c = Eigen::Matrix<double, nv, 1>::Zero();
  Eigen::Matrix<double, nv, 1> dc = Eigen::Matrix<double, nv, 1>::Zero();
  c(0) = 1;
  c(a) = -(1 - beta);
  c(b) = -beta;
  dc(a) = 1;
  dc(b) = -1;
  const Vec<dim> u = xa - xb;
  SquareMat<1> Ginv;
  Ginv(0, 0) = 1 / u.squaredNorm();
  const Vec<dim> w = p - (xa + beta * (xb - xa));
  return stencil_distance2<dim, nv, 1>(w, c, dc, u, Ginv);
}

// The vertex case "closest point x_a": w = p - x_a, c_0 = 1, c_a = -1.
template <int dim, int nv>
KOKKOS_INLINE_FUNCTION Distance2<nv * dim> stencil_point_point(const Vec<dim>& p, const Vec<dim>& xa, int a) {
  Eigen::Matrix<double, nv, 1> c = Eigen::Matrix<double, nv, 1>::Zero();
  c(0) = 1;
  c(a) = -1;
  return stencil_distance2<dim, nv>(p - xa, c);
}

}  // namespace contact_detail

// Variables (p, q).
template <int dim>
KOKKOS_INLINE_FUNCTION Distance2<2 * dim> point_point_distance2_derivatives(const Vec<dim>& p, const Vec<dim>& q) {
  return contact_detail::stencil_point_point<dim, 2>(p, q, 1);
}

// Variables (p, e0, e1); derivatives of the case point_edge_distance2 returns.
template <int dim>
KOKKOS_INLINE_FUNCTION Distance2<3 * dim> point_edge_distance2_derivatives(const Vec<dim>& p, const Vec<dim>& e0,
                                                                          const Vec<dim>& e1) {
  const auto cl = contact_detail::point_edge_closest<dim>(p, e0, e1);
  switch (cl.c) {
    case PointEdgeCase::P_E0: return contact_detail::stencil_point_point<dim, 3>(p, e0, 1);
    case PointEdgeCase::P_E1: return contact_detail::stencil_point_point<dim, 3>(p, e1, 2);
    default: return contact_detail::stencil_point_edge<dim, 3>(p, e0, e1, 1, 2, cl.beta);
  }
}

// Variables (p, t0, t1, t2); derivatives of the case point_triangle_distance2
// returns (collinear triangles: of the nearest edge's case, mapped).
KOKKOS_INLINE_FUNCTION Distance2<12> point_triangle_distance2_derivatives(const Vec<3>& p, const Vec<3>& t0,
                                                                         const Vec<3>& t1, const Vec<3>& t2) {
  namespace cd = contact_detail;
  const cd::PointTriangleClosest cl = cd::point_triangle_closest(p, t0, t1, t2);
  switch (cl.c) {
    case PointTriangleCase::P_T0: return cd::stencil_point_point<3, 4>(p, t0, 1);
    case PointTriangleCase::P_T1: return cd::stencil_point_point<3, 4>(p, t1, 2);
    case PointTriangleCase::P_T2: return cd::stencil_point_point<3, 4>(p, t2, 3);
    case PointTriangleCase::P_E01: return cd::stencil_point_edge<3, 4>(p, t0, t1, 1, 2, cl.beta);
    case PointTriangleCase::P_E12: return cd::stencil_point_edge<3, 4>(p, t1, t2, 2, 3, cl.beta);
    case PointTriangleCase::P_E20: return cd::stencil_point_edge<3, 4>(p, t2, t0, 3, 1, cl.beta);
    default: break;
  }
  // Interior: w = r - b1 e1 - b2 e2, c = (1, -(1 - b1 - b2), -b1, -b2),
  // dc/db = [[0, 0], [1, 1], [-1, 0], [0, -1]], U = (t0 - t1, t0 - t2),
  // G = U^T U (det G = |e1 x e2|^2). G^-1 is formed on the triangle scaled to
  // unit size L (as in the case test) and scaled back by 1/L^2.
  const Vec<3> e1 = t1 - t0, e2 = t2 - t0;
  const double b1 = cl.b1, b2 = cl.b2;
  Eigen::Matrix<double, 4, 1> c(1, -(1 - b1 - b2), -b1, -b2);
  Eigen::Matrix<double, 4, 2> dc;
  dc << 0, 0, 1, 1, -1, 0, 0, -1;
  Eigen::Matrix<double, 3, 2> U;
  U.col(0) = -e1;
  U.col(1) = -e2;
  const double L = std::sqrt(std::max(e1.squaredNorm(), e2.squaredNorm()));
  const Vec<3> f1 = e1 / L, f2 = e2 / L;
  const double det = f1.cross(f2).squaredNorm();
  SquareMat<2> Ginv;
  Ginv << f2.squaredNorm(), -f1.dot(f2), -f1.dot(f2), f1.squaredNorm();
  Ginv /= det * L * L;
  const Vec<3> w = (p - t0) - b1 * e1 - b2 * e2;
  return cd::stencil_distance2<3, 4, 2>(w, c, dc, U, Ginv);
}

}  // namespace bfemp
