#pragma once
// Level-set boundaries on the MPM grid (paper §6.2 baseline, §6.6 feet): a
// half-plane (solid where (x - point) . normal < 0), a box (solid inside), or
// an analytic sine contour y = y0 + A cos(2 pi x / wavelength) (extruded along
// z in 3D; solid below or above it), each optionally moving: with a constant
// velocity, or piecewise-constant velocity segments (scene Level Sets/<name>/
// Motion: A2's down, left, up), at rest after the last segment. Grid nodes inside are constrained: no-slip fixes every component
// to the boundary's motion (apply_level_sets below); slip fixes only the
// velocity along the level set's normal at the node, n . v = n . v_boundary,
// as a constraint of the Newton system (solver/slip_constraints.hpp).
#include <Kokkos_Core.hpp>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace bfemp {

enum class LevelSetKind { HalfPlane, Box, Sine };

struct LevelSet {
  std::string name;
  LevelSetKind kind = LevelSetKind::HalfPlane;
  bool slip = false;
  std::array<double, 3> point{0, 0, 0};     // half-plane: a point on the plane
  std::array<double, 3> normal{0, 1, 0};    // half-plane: unit normal into the free side
  std::array<double, 3> box_min{0, 0, 0}, box_max{0, 0, 0};
  std::array<double, 3> velocity{0, 0, 0};  // m/s, constant (when segments == 0)
  // Removed at this time (s): in the steps that start at t >= until (to a
  // relative 1e-9, as t accumulates dt) no node is inside and no particle
  // counts as penetrating (A4's support plane, taken away after the box has
  // settled). 1e300: never.
  double until = 1e300;
  // Piecewise-constant motion: velocity seg_velocity[k] until seg_end[k] (s,
  // increasing), at rest after the last.
  static constexpr int kMaxSegments = 8;
  int segments = 0;
  double seg_end[kMaxSegments] = {};
  double seg_velocity[kMaxSegments][3] = {};

  // Displacement of the boundary along axis d from t = 0 to t (m).
  KOKKOS_INLINE_FUNCTION double offset(int d, double t) const {
    if (segments == 0) return velocity[d] * t;
    double u = 0, t0 = 0;
    for (int k = 0; k < segments && t0 < t; ++k) {
      const double t1 = t < seg_end[k] ? t : seg_end[k];
      u += seg_velocity[k][d] * (t1 - t0);
      t0 = seg_end[k];
    }
    return u;
  }
  // Mean velocity over [t, t + dt]: the boundary's motion in one step / dt
  // (exact across a segment change inside the step).
  KOKKOS_INLINE_FUNCTION double step_velocity(int d, double t, double dt) const {
    return segments == 0 ? velocity[d] : (offset(d, t + dt) - offset(d, t)) / dt;
  }
  // sine: contour y = height + amplitude cos(2 pi x / wavelength) at t = 0;
  // solid below it (solid_above false) or above it.
  double height = 0, amplitude = 0, wavelength = 1;
  bool solid_above = false;

  // Signed value at time t, < 0 inside the solid (a signed distance for the
  // half-plane and the box; for the sine its first-order estimate
  // (y - y_c(x)) / |grad (y - y_c(x))|).
  template <int dim>
  KOKKOS_INLINE_FUNCTION double phi(const Vec<dim>& x, double t) const {
    if (t >= until * (1.0 - 1e-9)) return 1e300;  // removed (1e-9: t is a sum of time steps)
    if (kind == LevelSetKind::HalfPlane) {
      double s = 0;
      for (int d = 0; d < dim; ++d) s += (x(d) - point[d] - offset(d, t)) * normal[d];
      return s;
    }
    if (kind == LevelSetKind::Sine) {
      double dfdx = 0;
      const double f = sine_function(x(0), x(1), t, dfdx);
      return (solid_above ? -f : f) / std::sqrt(1.0 + dfdx * dfdx);
    }
    double s = -1e300;  // box: negative inside (max over faces of the outside distance)
    for (int d = 0; d < dim; ++d) {
      const double lo = box_min[d] + offset(d, t), hi = box_max[d] + offset(d, t);
      s = std::fmax(s, std::fmax(lo - x(d), x(d) - hi));
    }
    return s;
  }

  // Unit normal at x pointing out of the solid (into the free side):
  // half-plane: its normal; sine: the normalised gradient of the contour
  // function s (y - y_c(x)); box: the outward normal of the nearest face.
  template <int dim>
  KOKKOS_INLINE_FUNCTION Vec<dim> unit_normal(const Vec<dim>& x, double t) const {
    Vec<dim> n = Vec<dim>::Zero();
    if (kind == LevelSetKind::HalfPlane) {
      for (int d = 0; d < dim; ++d) n(d) = normal[d];
    } else if (kind == LevelSetKind::Sine) {
      double dfdx = 0;
      sine_function(x(0), x(1), t, dfdx);
      const double s = (solid_above ? -1.0 : 1.0) / std::sqrt(1.0 + dfdx * dfdx);
      n(0) = s * dfdx;
      n(1) = s;
    } else {
      double best = -1e300;
      int axis = 0;
      double sign = 1;
      for (int d = 0; d < dim; ++d) {
        const double lo = box_min[d] + offset(d, t), hi = box_max[d] + offset(d, t);
        if (lo - x(d) > best) { best = lo - x(d); axis = d; sign = -1; }
        if (x(d) - hi > best) { best = x(d) - hi; axis = d; sign = 1; }
      }
      n(axis) = sign;
    }
    return n;
  }

  // Sine: f = y - y_c(x, t) and df/dx, with the contour moved by offset(t).
  KOKKOS_INLINE_FUNCTION double sine_function(double x, double y, double t, double& dfdx) const {
    const double k = 2.0 * M_PI / wavelength;
    const double xs = x - offset(0, t);
    dfdx = amplitude * k * std::sin(k * xs);
    return y - (height + offset(1, t) + amplitude * std::cos(k * xs));
  }
};

constexpr int kMaxLevelSets = 8;

struct LevelSetList {
  LevelSet sets[kMaxLevelSets];
  int count = 0;
};

// No-slip level sets: constrains every DOF of the grid nodes [first_dof, n)
// that lie inside a no-slip level set at time t: prescribed = 1, target =
// x + dt * v_boundary, v = v_boundary (v_boundary: the mean over [t, t + dt]). Slip level sets are left to
// SlipConstraints::build (solver/slip_constraints.hpp).
template <int dim, class XV, class PV>
void apply_level_sets(const LevelSetList& ls, double t, double dt, std::size_t first_dof, std::size_t n,
                      const XV& x, const XV& v, const XV& target, const PV& prescribed) {
  if (ls.count == 0) return;
  Kokkos::parallel_for(
      "mpm_level_sets", Kokkos::RangePolicy<ExecSpace>(first_dof / dim, n / dim), KOKKOS_LAMBDA(const std::size_t node) {
        Vec<dim> xi;
        for (int c = 0; c < dim; ++c) xi(c) = x(node * dim + c);
        for (int k = 0; k < ls.count; ++k) {
          const LevelSet& s = ls.sets[k];
          if (s.slip || s.phi<dim>(xi, t) > 0) continue;
          for (int c = 0; c < dim; ++c) {
            const std::size_t i = node * dim + c;
            const double vb = s.step_velocity(c, t, dt);
            prescribed(i) = 1;
            target(i) = x(i) + dt * vb;
            v(i) = vb;
          }
        }
      });
}

}  // namespace bfemp
