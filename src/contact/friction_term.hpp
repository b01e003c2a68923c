#pragma once
// Lagged friction pseudo-potential of paper Eq. 37 between MPM particles and
// the FEM boundary:
//   D(x) = sum_k mu_k lambda_k f0(|u_k(x)|, eps_v dt),
//   u_k = T_k^T sum_i c_ki (dt v_i^{n+1}(x)),   dt v^{n+1} = s (x - x_ref),
// over the pairs active (d < dhat) at the lagged iterate x^j, with lambda_k,
// the tangent basis T_k and the closest-point coefficients c_k (particle +1,
// facet vertices minus their barycentric weights) frozen there. The
// particle's velocity is the grid velocity interpolated at the particle
// (paper §4.3), never the particle's own. s = gamma dt^2 / h and x_ref make
// dt v^{n+1} of the integrator affine in x (backward Euler: s = 1, x_ref =
// x^n). Its Hessian mu lambda s^2 c c^T (x) T H_u T^T is PSD for lambda > 0
// and NSD for the compensation pairs (lambda < 0). The exact Hessian (a sink
// with project = false, Newton's exact-if-definite) keeps them: near an edge
// or vertex they cancel the duplicate curvature of the facets sharing it. A
// Hessian without them is too stiff there: twice at an edge shared by two
// facets, T + 1 times at a 3D vertex of T triangles (Newton then converges
// linearly: the A7 twist's friction passes). Projected, each pair is projected
// alone: a compensation pair's Hessian becomes 0, or keeps the fraction
// sink.contact_keep of its curvature (Newton's fallback keep).
#include "contact/barrier_term.hpp"

namespace bfemp {

template <int dim>
struct FrictionSliding;

template <int dim>
class FrictionTerm : public EnergyTerm<dim> {
 public:
  // mu(mpm body, fem body) as a row-major table [n_mpm x n_fem].
  FrictionTerm(const BarrierTerm<dim>& barrier, std::vector<double> mu, int n_fem_bodies, double eps_v);
  std::string name() const override { return "friction"; }

  // Lags lambda, T, c at x from the barrier's active pairs there (`act`, from
  // BarrierTerm::active_pairs(x)); x_ref, s as above. Returns the number of
  // pairs with mu lambda != 0.
  LO update_lagged(ConstDofView x, const typename BarrierTerm<dim>::ActivePairs& act, ConstDofView x_ref, double s,
                   double dt);
  void clear() { n_ = 0; }
  LO pairs() const { return n_; }

  void add_couplings(NodeGraphBuilder& graph) const override;
  double energy(ConstDofView x) const override;
  void gradient(ConstDofView x, double scale, DofView grad) const override;
  void assemble(ConstDofView x, const Sink<dim>& sink) const override;
  double max_step(ConstDofView, ConstDofView) const override { return std::numeric_limits<double>::infinity(); }
  void set_projection(bool project) { project_ = project; }  // false: exact Hessian (tests)
  // Friction force on the particles (-dD/dx_q), added into f.
  void add_particle_forces(ConstDofView x, DofView f) const;

 private:
  // Gradient (and with `hessian` the matrix) into the sink, one particle's
  // pairs at a time (as BarrierTerm::assemble_by_particle).
  void assemble_by_particle(ConstDofView x, const Sink<dim>& sink, bool hessian) const;
  FrictionSliding<dim> sliding(ConstDofView x) const;

  const BarrierTerm<dim>& barrier_;
  Kokkos::View<double*, MemSpace> mu_;  // [n_mpm * n_fem]
  int n_fem_;
  double eps_v_;
  double s_ = 1, eh_ = 1;
  ConstDofView x_ref_;
  Kokkos::View<LO* [2], MemSpace> pair_;          // (q, primitive)
  Kokkos::View<double* [dim + 1], MemSpace> c_;   // particle, vertices
  Kokkos::View<double* [dim][dim - 1], MemSpace> T_;
  Kokkos::View<double*, MemSpace> ml_;            // mu * lambda
  LO n_ = 0;
  bool project_ = true;
  Kokkos::View<LO*, MemSpace> seg_;  // n_seg_ + 1 starts of each particle's pairs (capacity grows)
  LO n_seg_ = 0;
  // Scratch of the evaluations (kept for its capacity; every call writes
  // what it reads): the pairs' particles at x and x_ref, and assemble()'s
  // per-particle sums (with the barrier's cells; their marks are all zero
  // between calls).
  mutable Kokkos::View<double*, MemSpace> xq_, xq_ref_;
  mutable ParticleSums<dim> sums_;
};

}  // namespace bfemp
