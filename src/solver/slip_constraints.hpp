#pragma once
// Slip boundaries as exact linear constraints of the Newton system (paper
// §6.2 "level set based slip": the normal velocity of every grid node inside
// the level set is prescribed, the tangential motion is free).
//
// A constrained node k has the orthogonal projector Q_k onto the span of the
// unit normals of the slip level sets containing it (one normal: Q = n n^T),
// P_k = I - Q_k, and a target T_k = x_k^n + U_k with U_k in range(Q_k),
// n_s . U_k = dt n_s . v_s for each of those sets (moving boundaries); the
// constraint is Q_k (x_k - T_k) = 0, i.e. n . v = n . v_boundary. Each Newton
// iteration solves for p = u + w, where w_k = Q_k (T_k - x_k) is the remaining
// offset and u is tangential at constrained nodes, via the transformed system
//   (P A P + Q) p = P (r - A w) + w
// (P = I, Q = 0 at free nodes): the reduced Newton system P A P u = P (r - A w)
// on the tangent space, symmetric positive definite when A is, so Cholmod,
// KLU2 and CG solve it unchanged. The direction is then cleaned to exactly
// p_k = P_k p_k + w_k, so x + p meets the constraint up to round-off.
#include <Kokkos_Core.hpp>

#include "kernels/level_set.hpp"
#include "solver/energy_term.hpp"

namespace bfemp {

template <int dim>
class SlipConstraints {
 public:
  using NodeMats = Kokkos::View<double* [dim][dim], MemSpace>;
  using NodeVecs = Kokkos::View<double* [dim], MemSpace>;

  // The constraints of one step: every system node in [first_dof/dim, n/dim)
  // inside a slip level set at time t and with no prescribed DOF is
  // constrained with the normals of the slip sets containing it at x (x^n);
  // the Q-part of its velocity v is set to the boundary's, U / dt. Replaces
  // the previous step's constraints. n is the system's DOF count.
  void build(const LevelSetList& ls, double t, double dt, std::size_t first_dof, std::size_t n, DofView x,
             DofView v, MaskView prescribed);
  void clear() { count_ = 0; has_offset_ = false; }
  LO count() const { return count_; }

  // Newton hooks (called by NewtonSolver when count() > 0).
  // w_k = Q_k (T_k - x_k), zeroed below round-off; returns max |w|_inf.
  double update_offsets(ConstDofView x);
  // A <- P A P + Q on the (not yet fill-completed) local matrix, rhs <-
  // P (rhs - A w) + w. The graph must be node-blocked (build_dof_graph).
  // Distributed (owned: 1 at the local DOFs this rank owns, as DofSpace's
  // owned_mask): A and rhs are this rank's overlap parts, whose sum over the
  // ranks is the system. P A^r P and P (rhs^r - A^r w) are linear in the
  // parts, so every rank transforms its own; Q and w are added at owned nodes
  // only, so that the summed system is the 1-rank one (added by every holder
  // they would sum to k Q and k w: the same solution, another matrix, and a
  // CG run that differs from one rank's). The constraints must then cover the
  // ghost nodes too (build over all local nodes: a node's P, T and w depend
  // on its x^n, v and x alone, which every rank holding it has alike).
  void transform_system(const LocalMatrix& A, DofView rhs,
                        Kokkos::View<const int*, MemSpace> owned = {}) const;
  // p_k <- P_k p_k + w_k at constrained nodes.
  void fix_direction(DofView p) const;

  // After the velocity update: v_k <- P_k v_k + U_k / dt (Newmark's update does
  // not keep the normal velocity by itself).
  void project_velocities(DofView v) const;

  // max_k |Q_k (x_k - T_k)|_inf: the constraint violation of x (tests).
  double violation(ConstDofView x) const;
  // Per constraint: system node, Q, target T (device views, first count()).
  Kokkos::View<const LO*, MemSpace> nodes() const { return node_; }
  NodeMats projectors() const { return Q_; }
  NodeVecs targets() const { return T_; }

 private:
  Kokkos::View<LO*, MemSpace> slot_;  // per system node: constraint index or -1
  Kokkos::View<LO*, MemSpace> node_;  // per constraint: system node
  NodeMats Q_;
  NodeVecs T_, U_, w_;
  Kokkos::View<double*, MemSpace> aw_;  // A w, per DOF
  LO count_ = 0;
  double dt_ = 1;
  bool has_offset_ = false;
};

}  // namespace bfemp
