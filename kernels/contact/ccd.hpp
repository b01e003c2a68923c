#pragma once
// Conservative continuous collision detection along linear motion (paper §5):
// every vertex moves as x(t) = x + t dx, t in [0, t_max]; the functions return
// a step t in (0, t_max] over which the stencil's distance stays > 0 (t_max
// when no contact is found before t_max), or 0 when it is 0 already.
//
// Additive CCD (conservative advancement, Li et al. 2021, "Codimensional
// IPC"). Subtracting the mean displacement m (distances are invariant under a
// common translation), the distance d(t) between the point and the closest
// point sum_i b_i v_i(t) of the facet (sum_i b_i = 1, b_i >= 0) changes at most at
//   l_p = |dp - m| + max_i |dv_i - m|     (|d'(t)| <= |dp - sum_i b_i dv_i| <= l_p).
// From a time t with distance d, advancing by (1 - s) d / l_p therefore keeps
// d >= s d > 0 over the whole advance. Steps are taken until the distance
// falls below s d(0); the time before that last advance is returned. After
// max_iterations advances (grazing motion at a tiny distance) the time reached
// so far is returned: still conservative, only shorter.
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>

#include "core/types.hpp"
#include "kernels/contact/distance.hpp"

namespace bfemp {

constexpr double kCcdDefaultSFrac = 0.1;
constexpr int kCcdDefaultMaxIterations = 1000000;

namespace contact_detail {

// The advancement loop on a distance functor dist(t) (unsquared) with
// Lipschitz bound lp of d(t).
template <class Dist>
KOKKOS_INLINE_FUNCTION double additive_ccd(const Dist& dist, double lp, double t_max, double s_frac,
                                           int max_iterations) {
  const double d0 = dist(0.0);
  if (!(d0 > 0)) return 0.0;               // touching already (or NaN input)
  if (!(lp > 0)) return t_max;             // no relative motion: d(t) = d0
  const double gap = s_frac * d0;
  double t = 0.0, d = d0;
  for (int it = 0; it < max_iterations; ++it) {
    const double step = (1 - s_frac) * d / lp;  // d stays >= s_frac * d over it
    if (t + step >= t_max) {
      // No contact before t_max; confirm the end point in floating point
      // (a 0 there is round-off at the limit of resolution: stay short of it).
      return dist(t_max) > 0 ? t_max : (t > 0 ? t : 0.5 * t_max);
    }
    const double tn = t + step;
    const double dn = dist(tn);
    if (t > 0 && !(dn >= gap)) return t;  // approaching: stop before this advance
    t = tn;
    d = dn;
  }
  return t;
}

template <int dim, int nv>
struct StencilMotion {
  Vec<dim> x[nv];   // x[0] the point, x[1..] the facet's vertices
  Vec<dim> dx[nv];  // displacements minus their mean
  double lp;        // |dx[0]| + max_{i>0} |dx[i]|

  KOKKOS_INLINE_FUNCTION StencilMotion(const Vec<dim>* x0, const Vec<dim>* d) {
    Vec<dim> m = Vec<dim>::Zero();
    for (int i = 0; i < nv; ++i) m += d[i];
    m /= nv;
    double facet = 0;
    for (int i = 0; i < nv; ++i) {
      x[i] = x0[i];
      dx[i] = d[i] - m;
      if (i > 0) facet = std::max(facet, dx[i].norm());
    }
    lp = dx[0].norm() + facet;
  }
  KOKKOS_INLINE_FUNCTION Vec<dim> at(int i, double t) const { return x[i] + t * dx[i]; }
};

template <int dim>
struct PointPointDistance {
  StencilMotion<dim, 2> s;
  KOKKOS_INLINE_FUNCTION double operator()(double t) const {
    return std::sqrt(point_point_distance2<dim>(s.at(0, t), s.at(1, t)));
  }
};

template <int dim>
struct PointEdgeDistance {
  StencilMotion<dim, 3> s;
  KOKKOS_INLINE_FUNCTION double operator()(double t) const {
    return std::sqrt(point_edge_distance2<dim>(s.at(0, t), s.at(1, t), s.at(2, t)));
  }
};

struct PointTriangleDistance {
  StencilMotion<3, 4> s;
  KOKKOS_INLINE_FUNCTION double operator()(double t) const {
    return std::sqrt(point_triangle_distance2(s.at(0, t), s.at(1, t), s.at(2, t), s.at(3, t)));
  }
};

}  // namespace contact_detail

template <int dim>
KOKKOS_INLINE_FUNCTION double point_point_ccd(const Vec<dim>& p, const Vec<dim>& q, const Vec<dim>& dp,
                                              const Vec<dim>& dq, double t_max,
                                              double s_frac = kCcdDefaultSFrac,
                                              int max_iterations = kCcdDefaultMaxIterations) {
  const Vec<dim> x[2] = {p, q}, d[2] = {dp, dq};
  const contact_detail::PointPointDistance<dim> dist{contact_detail::StencilMotion<dim, 2>(x, d)};
  return contact_detail::additive_ccd(dist, dist.s.lp, t_max, s_frac, max_iterations);
}

template <int dim>
KOKKOS_INLINE_FUNCTION double point_edge_ccd(const Vec<dim>& p, const Vec<dim>& e0, const Vec<dim>& e1,
                                             const Vec<dim>& dp, const Vec<dim>& de0, const Vec<dim>& de1,
                                             double t_max, double s_frac = kCcdDefaultSFrac,
                                             int max_iterations = kCcdDefaultMaxIterations) {
  const Vec<dim> x[3] = {p, e0, e1}, d[3] = {dp, de0, de1};
  const contact_detail::PointEdgeDistance<dim> dist{contact_detail::StencilMotion<dim, 3>(x, d)};
  return contact_detail::additive_ccd(dist, dist.s.lp, t_max, s_frac, max_iterations);
}

KOKKOS_INLINE_FUNCTION double point_triangle_ccd(const Vec<3>& p, const Vec<3>& t0, const Vec<3>& t1,
                                                 const Vec<3>& t2, const Vec<3>& dp, const Vec<3>& dt0,
                                                 const Vec<3>& dt1, const Vec<3>& dt2, double t_max,
                                                 double s_frac = kCcdDefaultSFrac,
                                                 int max_iterations = kCcdDefaultMaxIterations) {
  const Vec<3> x[4] = {p, t0, t1, t2}, d[4] = {dp, dt0, dt1, dt2};
  const contact_detail::PointTriangleDistance dist{contact_detail::StencilMotion<3, 4>(x, d)};
  return contact_detail::additive_ccd(dist, dist.s.lp, t_max, s_frac, max_iterations);
}

}  // namespace bfemp
