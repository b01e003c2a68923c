#pragma once
// Level-set boundaries on the MPM grid (paper §6.2 baseline, §6.6 feet): a
// half-plane (solid where (x - point) . normal < 0) or a box (solid inside),
// optionally moving with a constant velocity. Grid nodes inside are
// constrained: no-slip fixes every component to the boundary's motion; slip
// fixes only the normal component (axis-aligned normals in this version).
#include <Kokkos_Core.hpp>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace bfemp {

enum class LevelSetKind { HalfPlane, Box };

struct LevelSet {
  std::string name;
  LevelSetKind kind = LevelSetKind::HalfPlane;
  bool slip = false;
  std::array<double, 3> point{0, 0, 0};     // half-plane: a point on the plane
  std::array<double, 3> normal{0, 1, 0};    // half-plane: unit normal into the free side
  std::array<double, 3> box_min{0, 0, 0}, box_max{0, 0, 0};
  std::array<double, 3> velocity{0, 0, 0};  // m/s, constant
  int normal_axis = 1;                      // slip: the axis of the normal

  // Signed distance-like value at time t: < 0 inside the solid.
  template <int dim>
  KOKKOS_INLINE_FUNCTION double phi(const Vec<dim>& x, double t) const {
    if (kind == LevelSetKind::HalfPlane) {
      double s = 0;
      for (int d = 0; d < dim; ++d) s += (x(d) - point[d] - velocity[d] * t) * normal[d];
      return s;
    }
    double s = -1e300;  // box: negative inside (max over faces of the outside distance)
    for (int d = 0; d < dim; ++d) {
      const double lo = box_min[d] + velocity[d] * t, hi = box_max[d] + velocity[d] * t;
      s = std::fmax(s, std::fmax(lo - x(d), x(d) - hi));
    }
    return s;
  }
};

constexpr int kMaxLevelSets = 8;

struct LevelSetList {
  LevelSet sets[kMaxLevelSets];
  int count = 0;
};

// Constrains the grid DOFs [first_dof, n) whose node is inside a level set at
// time t: prescribed = 1, target = x + dt * v_boundary, v = v_boundary.
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
          if (s.phi<dim>(xi, t) > 0) continue;
          for (int c = 0; c < dim; ++c) {
            if (s.slip && c != s.normal_axis) continue;
            const std::size_t i = node * dim + c;
            prescribed(i) = 1;
            target(i) = x(i) + dt * s.velocity[c];
            v(i) = s.velocity[c];
          }
        }
      });
}

}  // namespace bfemp
