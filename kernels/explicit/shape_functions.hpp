#pragma once
// Shape-function policies of the explicit multimaterial MPM (paper 001 §2.1,
// Eqs. 2 and 12): S_pi = int chi_p N_i / V_p and G_pi = int chi_p grad N_i / V_p.
// A policy is a type with
//   static constexpr int per_axis;                    // stencil nodes per axis
//   template <int dim> struct Stencil { int base[dim]; double w[dim][per_axis], dw[dim][per_axis]; };
//   template <int dim> static Stencil<dim> stencil(grid, x_p, l_p);   // l_p: particle half-width (m)
//   template <int dim> static bool contains(grid, x_p, l_p);          // whole stencil on the grid
// with w the 1D weights of nodes base+0..per_axis-1 and dw their derivative
// d w / d x_p (1/m). The tensor-product weight is prod_d w[d][a_d].
//
// UGimp: linear grid functions N (hat of half-width h = dx) convolved with a
// particle of half-width l = l_p (uGIMP: the undeformed particle size, 0 < l <= h/2),
// r = x_p - x_i:
//   |r| < l          : S = 1 - (r^2 + l^2) / (2 h l),  dS/dr = -r / (h l)
//   l <= |r| < h - l : S = 1 - |r| / h,                dS/dr = -sign(r) / h
//   h-l <= |r| < h+l : S = (h + l - |r|)^2 / (4 h l),  dS/dr = -sign(r) (h + l - |r|) / (2 h l)
//   else 0.   Support: nodes floor(s - l/h) .. +2, s = (x_p - origin)/dx.
// QuadraticBSpline: point-sampled quadratic B-spline (l_p unused), nodes
// floor(s - 1/2) .. +2 (the same stencil as kernels/mpm/bspline.hpp).
// Both give sum_i S_pi = 1 and sum_i G_pi = 0 for a particle inside the grid.
#include <Kokkos_Core.hpp>
#include <cmath>

#include "core/types.hpp"
#include "kernels/mpm/grid.hpp"

namespace bfemp::xmpm {

template <int dim, int per_axis>
struct TensorStencil {
  int base[dim];
  double w[dim][per_axis];
  double dw[dim][per_axis];
  static constexpr int size = dim == 2 ? per_axis * per_axis : per_axis * per_axis * per_axis;

  // Per-axis offset of stencil entry a (x fastest).
  KOKKOS_INLINE_FUNCTION static int offset(int a, int d) {
    for (int k = 0; k < d; ++k) a /= per_axis;
    return a % per_axis;
  }
  KOKKOS_INLINE_FUNCTION double weight(int a) const {
    double s = 1.0;
    for (int d = 0; d < dim; ++d) s *= w[d][offset(a, d)];
    return s;
  }
  KOKKOS_INLINE_FUNCTION Vec<dim> gradient(int a) const {
    Vec<dim> g;
    for (int d = 0; d < dim; ++d) {
      double s = 1.0;
      for (int e = 0; e < dim; ++e) s *= e == d ? dw[e][offset(a, e)] : w[e][offset(a, e)];
      g(d) = s;
    }
    return g;
  }
  KOKKOS_INLINE_FUNCTION LO node(const GridSpec<dim>& g, int a) const {
    GridIndex<dim> i{};
    for (int d = 0; d < dim; ++d) i[d] = base[d] + offset(a, d);
    return g.node_index(i);
  }
};

struct UGimp {
  static constexpr int per_axis = 3;
  static constexpr const char* name = "uGIMP";
  template <int dim>
  using Stencil = TensorStencil<dim, 3>;

  // 1D weight and derivative of a node at signed distance r = x_p - x_i.
  KOKKOS_INLINE_FUNCTION static void weight_1d(double r, double h, double l, double& w, double& dw) {
    const double a = std::fabs(r), sg = r < 0 ? -1.0 : 1.0;
    if (a < l) {
      w = 1.0 - (r * r + l * l) / (2.0 * h * l);
      dw = -r / (h * l);
    } else if (a < h - l) {
      w = 1.0 - a / h;
      dw = -sg / h;
    } else if (a < h + l) {
      const double b = h + l - a;
      w = b * b / (4.0 * h * l);
      dw = -sg * b / (2.0 * h * l);
    } else {
      w = 0.0;
      dw = 0.0;
    }
  }

  // 1D weight of a node at r = x_p - x_i.
  KOKKOS_INLINE_FUNCTION static double node_weight_1d(double r, double h, double l) {
    double w, dw;
    weight_1d(r, h, l, w, dw);
    return w;
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION static Stencil<dim> stencil(const GridSpec<dim>& g, const Vec<dim>& x, double l) {
    Stencil<dim> s;
    for (int d = 0; d < dim; ++d) {
      const double sc = (x(d) - g.origin[d]) / g.dx;
      s.base[d] = static_cast<int>(std::floor(sc - l / g.dx));
      for (int k = 0; k < 3; ++k) {
        const double r = x(d) - (g.origin[d] + g.dx * (s.base[d] + k));
        weight_1d(r, g.dx, l, s.w[d][k], s.dw[d][k]);
      }
    }
    return s;
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION static bool contains(const GridSpec<dim>& g, const Vec<dim>& x, double l) {
    for (int d = 0; d < dim; ++d) {
      const double b = std::floor((x(d) - g.origin[d]) / g.dx - l / g.dx);
      if (!(b >= 0.0 && b + 2.0 <= g.n_cells[d])) return false;
    }
    return true;
  }
};

struct QuadraticBSpline {
  static constexpr int per_axis = 3;
  static constexpr const char* name = "quadratic B-spline";
  template <int dim>
  using Stencil = TensorStencil<dim, 3>;

  KOKKOS_INLINE_FUNCTION static double node_weight_1d(double r, double h, double) {
    const double a = std::fabs(r) / h;
    if (a < 0.5) return 0.75 - a * a;
    if (a < 1.5) return 0.5 * (1.5 - a) * (1.5 - a);
    return 0.0;
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION static Stencil<dim> stencil(const GridSpec<dim>& g, const Vec<dim>& x, double) {
    Stencil<dim> s;
    const double inv = 1.0 / g.dx;
    for (int d = 0; d < dim; ++d) {
      const double sc = (x(d) - g.origin[d]) * inv;
      s.base[d] = static_cast<int>(std::floor(sc - 0.5));
      const double f = sc - s.base[d];  // in [0.5, 1.5)
      const double a = 1.5 - f, b = f - 1.0, c = f - 0.5;
      s.w[d][0] = 0.5 * a * a;
      s.w[d][1] = 0.75 - b * b;
      s.w[d][2] = 0.5 * c * c;
      s.dw[d][0] = -a * inv;
      s.dw[d][1] = -2.0 * b * inv;
      s.dw[d][2] = c * inv;
    }
    return s;
  }

  template <int dim>
  KOKKOS_INLINE_FUNCTION static bool contains(const GridSpec<dim>& g, const Vec<dim>& x, double) {
    return g.contains(x);
  }
};

}  // namespace bfemp::xmpm
