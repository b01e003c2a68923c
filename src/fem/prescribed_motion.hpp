#pragma once
// Prescribed (Dirichlet) rigid motion of a node set: a sequence of segments,
// each fixed, constant velocity, or rigid rotation about an axis through a
// centre, applied one after another (the papers' plates and shells).
#include <array>
#include <cmath>
#include <string>
#include <vector>

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

struct PrescribedMotion {
  std::string name;
  std::vector<LO> nodes;   // FEM node ids
  std::vector<MotionSegment> segments;

  // Position at time t of the point that is at X0 at t = 0.
  template <int dim>
  Vec<dim> position(const Vec<dim>& X0, double t) const {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    p.head<dim>() = X0;
    double t0 = 0;
    for (const auto& s : segments) {
      const double tau = std::min(std::max(t - t0, 0.0), s.duration);
      p = apply(s, p, tau);
      t0 += s.duration;
      if (t <= t0) break;
    }
    return p.head<dim>();
  }

  // Velocity at time t (of the segment active at t) of the point at X0 at t = 0.
  template <int dim>
  Vec<dim> velocity(const Vec<dim>& X0, double t) const {
    const Vec<dim> x = position<dim>(X0, t);
    double t0 = 0;
    for (const auto& s : segments) {
      if (t < t0 + s.duration || &s == &segments.back()) {
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        if (s.type == MotionType::Velocity) v = Eigen::Vector3d(s.velocity.data());
        if (s.type == MotionType::Rotation) {
          Eigen::Vector3d r = Eigen::Vector3d::Zero();
          r.head<dim>() = x;
          v = s.angular_velocity * unit_axis(s).cross(r - Eigen::Vector3d(s.center.data()));
        }
        return v.head<dim>();
      }
      t0 += s.duration;
    }
    return Vec<dim>::Zero();
  }

 private:
  static Eigen::Vector3d unit_axis(const MotionSegment& s) {
    return Eigen::Vector3d(s.axis.data()).normalized();
  }
  static Eigen::Vector3d apply(const MotionSegment& s, const Eigen::Vector3d& p, double tau) {
    switch (s.type) {
      case MotionType::Fixed: return p;
      case MotionType::Velocity: return p + tau * Eigen::Vector3d(s.velocity.data());
      case MotionType::Rotation: {
        const Eigen::Vector3d c(s.center.data());
        return c + Eigen::AngleAxisd(s.angular_velocity * tau, unit_axis(s)) * (p - c);
      }
    }
    return p;
  }
};

}  // namespace bfemp
