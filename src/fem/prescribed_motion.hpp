#pragma once
// Prescribed (Dirichlet) rigid motion of a node set: a sequence of segments,
// each fixed, constant velocity, or rigid rotation about an axis through a
// centre, applied one after another (the papers' plates and shells).
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <Kokkos_Core.hpp>
#include <algorithm>

#include "core/types.hpp"

namespace bfemp {

enum class MotionType { Fixed, Velocity, Rotation };

struct MotionSegment {
  MotionType type = MotionType::Fixed;
  double duration = 1e300;                   // s; the last segment usually lasts forever
  std::array<double, 3> velocity{0, 0, 0};   // m/s (Velocity)
  double angular_velocity = 0;               // rad/s (Rotation), right-handed about axis
  std::array<double, 3> center{0, 0, 0};     // m (Rotation)
  std::array<double, 3> axis{0, 0, 1};       // unit axis (Rotation; 2D rotates about z)
};

// Position at time t of the point at X0 at t = 0 under segments[0..n), and
// the velocity of the segment active at t (the last one after the end).
// Device-callable: the simulation evaluates them per node in a kernel.
KOKKOS_INLINE_FUNCTION Eigen::Vector3d motion_unit_axis(const MotionSegment& s) {
  return Eigen::Vector3d(s.axis[0], s.axis[1], s.axis[2]).normalized();
}

KOKKOS_INLINE_FUNCTION Eigen::Vector3d motion_apply(const MotionSegment& s, const Eigen::Vector3d& p, double tau) {
  switch (s.type) {
    case MotionType::Fixed: return p;
    case MotionType::Velocity: return p + tau * Eigen::Vector3d(s.velocity[0], s.velocity[1], s.velocity[2]);
    case MotionType::Rotation: {
      const Eigen::Vector3d c(s.center[0], s.center[1], s.center[2]);
      return c + Eigen::AngleAxisd(s.angular_velocity * tau, motion_unit_axis(s)) * (p - c);
    }
  }
  return p;
}

template <int dim>
KOKKOS_INLINE_FUNCTION Vec<dim> motion_position(const MotionSegment* segments, int n, const Vec<dim>& X0, double t) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  p.head<dim>() = X0;
  double t0 = 0;
  for (int k = 0; k < n; ++k) {
    const MotionSegment& s = segments[k];
    const double tau = std::min(std::max(t - t0, 0.0), s.duration);
    p = motion_apply(s, p, tau);
    t0 += s.duration;
    if (t <= t0) break;
  }
  return p.head<dim>();
}

template <int dim>
KOKKOS_INLINE_FUNCTION Vec<dim> motion_velocity(const MotionSegment* segments, int n, const Vec<dim>& X0, double t) {
  const Vec<dim> x = motion_position<dim>(segments, n, X0, t);
  double t0 = 0;
  for (int k = 0; k < n; ++k) {
    const MotionSegment& s = segments[k];
    if (t < t0 + s.duration || k == n - 1) {
      Eigen::Vector3d v = Eigen::Vector3d::Zero();
      if (s.type == MotionType::Velocity) v = Eigen::Vector3d(s.velocity[0], s.velocity[1], s.velocity[2]);
      if (s.type == MotionType::Rotation) {
        Eigen::Vector3d r = Eigen::Vector3d::Zero();
        r.head<dim>() = x;
        v = s.angular_velocity * motion_unit_axis(s).cross(r - Eigen::Vector3d(s.center[0], s.center[1], s.center[2]));
      }
      return v.head<dim>();
    }
    t0 += s.duration;
  }
  return Vec<dim>::Zero();
}

struct PrescribedMotion {
  std::string name;
  std::vector<LO> nodes;   // FEM node ids
  std::vector<MotionSegment> segments;

  // Position at time t of the point that is at X0 at t = 0.
  template <int dim>
  Vec<dim> position(const Vec<dim>& X0, double t) const {
    return motion_position<dim>(segments.data(), static_cast<int>(segments.size()), X0, t);
  }

  // Velocity at time t (of the segment active at t) of the point at X0 at t = 0.
  template <int dim>
  Vec<dim> velocity(const Vec<dim>& X0, double t) const {
    return motion_velocity<dim>(segments.data(), static_cast<int>(segments.size()), X0, t);
  }
};

// All motions of a scene on the device: for each prescribed node its motion's
// segment range (nodes in several motions: the last one wins, as on the host).
struct DeviceMotions {
  Kokkos::View<LO*, MemSpace> node;            // prescribed FEM node ids
  Kokkos::View<int* [2], MemSpace> range;      // per entry: first segment, count
  Kokkos::View<MotionSegment*, MemSpace> segments;
  LO size() const { return static_cast<LO>(node.extent(0)); }
};

inline DeviceMotions device_motions(const std::vector<PrescribedMotion>& motions) {
  // The motion that owns each node: the last one naming it.
  std::vector<int> owner;
  for (std::size_t mi = 0; mi < motions.size(); ++mi)
    for (LO node : motions[mi].nodes) {
      if (node < 0) continue;
      if (static_cast<std::size_t>(node) >= owner.size()) owner.resize(node + 1, -1);
      owner[node] = static_cast<int>(mi);
    }
  std::size_t n = 0, ns = 0;
  for (int o : owner) n += o >= 0;
  for (const auto& m : motions) ns += std::max<std::size_t>(m.segments.size(), 1);
  DeviceMotions d;
  d.node = Kokkos::View<LO*, MemSpace>("fem_motion_node", n);
  d.range = Kokkos::View<int* [2], MemSpace>("fem_motion_range", n);
  d.segments = Kokkos::View<MotionSegment*, MemSpace>("fem_motion_segments", ns);
  auto hn = Kokkos::create_mirror_view(d.node);
  auto hr = Kokkos::create_mirror_view(d.range);
  auto hs = Kokkos::create_mirror_view(d.segments);
  std::size_t k = 0, s0 = 0;
  for (std::size_t mi = 0; mi < motions.size(); ++mi) {
    const auto& m = motions[mi];
    // A motion without segments holds its nodes (one Fixed segment).
    const std::size_t nseg = std::max<std::size_t>(m.segments.size(), 1);
    if (m.segments.empty()) hs(s0) = MotionSegment{};
    for (std::size_t j = 0; j < m.segments.size(); ++j) hs(s0 + j) = m.segments[j];
    for (LO node : m.nodes) {
      if (node < 0 || owner[node] != static_cast<int>(mi)) continue;
      owner[node] = -1;  // once per node
      hn(k) = node;
      hr(k, 0) = static_cast<int>(s0);
      hr(k, 1) = static_cast<int>(nseg);
      ++k;
    }
    s0 += nseg;
  }
  Kokkos::deep_copy(d.node, hn);
  Kokkos::deep_copy(d.range, hr);
  Kokkos::deep_copy(d.segments, hs);
  return d;
}

}  // namespace bfemp
