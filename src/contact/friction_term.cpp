#include "contact/friction_term.hpp"

#include <limits>
#include <type_traits>

#include "contact/pair_couplings.hpp"
#include "contact/particle_expansion.hpp"
#include "kernels/contact/friction.hpp"

namespace bfemp {

template <int dim>
FrictionTerm<dim>::FrictionTerm(const BarrierTerm<dim>& barrier, std::vector<double> mu, int n_fem_bodies,
                                double eps_v)
    : barrier_(barrier), n_fem_(n_fem_bodies), eps_v_(eps_v) {
  mu_ = Kokkos::View<double*, MemSpace>("friction_mu", mu.size());
  Kokkos::deep_copy(mu_, Kokkos::View<const double*, Kokkos::HostSpace>(mu.data(), mu.size()));
}

template <int dim>
LO FrictionTerm<dim>::update_lagged(ConstDofView x, const typename BarrierTerm<dim>::ActivePairs& act,
                                    ConstDofView x_ref, double s, double dt) {
  const auto& ps = barrier_.particles();
  const auto& prims = barrier_.primitives();
  s_ = s;
  eh_ = eps_v_ * dt;
  x_ref_ = x_ref;
  n_ = act.count;
  if (static_cast<LO>(ml_.extent(0)) < n_) {  // capacity grows; outer iterations reuse it
    const std::size_t cap = static_cast<std::size_t>(n_) * 5 / 4 + 16;
    pair_ = Kokkos::View<LO* [2], MemSpace>("friction_pairs", cap);
    c_ = decltype(c_)("friction_c", cap);
    T_ = decltype(T_)("friction_T", cap);
    ml_ = Kokkos::View<double*, MemSpace>("friction_mu_lambda", cap);
  }
  const std::size_t nq = static_cast<std::size_t>(ps.size()) * dim;
  if (xq_.extent(0) != nq) {
    xq_ = Kokkos::View<double*, MemSpace>("friction_xq", nq);
    xq_ref_ = Kokkos::View<double*, MemSpace>("friction_xq_ref", nq);
  }
  interpolate_particles(ps, x, xq_);
  const ConstDofView xq = xq_;
  auto pair = pair_;
  auto c = c_;
  auto T = T_;
  auto ml = ml_;
  const auto mu = mu_;
  const int nf = n_fem_;
  LO nonzero = 0;
  Kokkos::parallel_reduce(
      "friction_lag", Kokkos::RangePolicy<ExecSpace>(0, n_),
      KOKKOS_LAMBDA(const LO k, LO& acc) {
        const LO q = act.pairs(k, 0), j = act.pairs(k, 1);
        pair(k, 0) = q;
        pair(k, 1) = j;
        const int nv = prims.count(j);
        const Vec<dim> p = load_vec<dim>(xq, q);
        Vec<dim> v[dim];
        for (int i = 0; i < nv; ++i) v[i] = load_vec<dim>(x, prims.nodes(j, i));
        double bary[dim] = {};
        if (nv == 1) {
          bary[0] = 1;
        } else if (nv == 2) {
          const double beta = point_edge_closest_parameter<dim>(p, v[0], v[1]);
          bary[0] = 1 - beta;
          bary[1] = beta;
        } else if constexpr (dim == 3) {
          const Vec<2> b = point_triangle_closest_barycentric(p, v[0], v[1], v[2]);
          bary[0] = 1 - b(0) - b(1);
          bary[1] = b(0);
          bary[2] = b(1);
        }
        Vec<dim> closest = Vec<dim>::Zero();
        for (int i = 0; i < nv; ++i) closest += bary[i] * v[i];
        const Vec<dim> n = (p - closest).normalized();
        const auto Tk = tangent_basis_of_normal<dim>(n);
        for (int a = 0; a < dim; ++a)
          for (int b = 0; b < dim - 1; ++b) T(k, a, b) = Tk(a, b);
        c(k, 0) = 1.0;
        for (int i = 0; i < dim; ++i) c(k, 1 + i) = i < nv ? -bary[i] : 0.0;
        ml(k) = mu(ps.body(q) * nf + prims.body(j)) * act.lambda(k);
        acc += ml(k) != 0 ? 1 : 0;
      },
      nonzero);
  n_seg_ = particle_segments(pair_, n_, seg_);
  return nonzero;
}

template <int dim>
void FrictionTerm<dim>::add_couplings(NodeGraphBuilder& graph) const {
  const auto& ps = barrier_.particles();
  const auto& prims = barrier_.primitives();
  const auto pair = pair_;  // the barrier's order: by particle
  add_pair_couplings(
      graph, n_, KOKKOS_LAMBDA(const long k) { return pair(k, 0); }, KOKKOS_LAMBDA(const long k) { return pair(k, 1); },
      ps.nodes, prims.nodes, prims.count);
}

// The sliding displacement u_k = T_k^T sum_i c_ki s (x_i - x_ref,i) of each
// lagged pair at x (particle positions interpolated from the grid).
template <int dim>
struct FrictionSliding {
  ConstDofView x, xq, xr, xref;
  BoundaryPrimitives<dim> prims;
  Kokkos::View<LO* [2], MemSpace> pair;
  Kokkos::View<double* [dim + 1], MemSpace> c;
  Kokkos::View<double* [dim][dim - 1], MemSpace> T;
  double s;
  KOKKOS_INLINE_FUNCTION void operator()(LO k, Eigen::Matrix<double, dim, dim - 1>& Tk,
                                         Eigen::Matrix<double, dim - 1, 1>& u) const {
    const LO q = pair(k, 0), j = pair(k, 1);
    for (int a = 0; a < dim; ++a)
      for (int b = 0; b < dim - 1; ++b) Tk(a, b) = T(k, a, b);
    Vec<dim> rel = c(k, 0) * s * (load_vec<dim>(xq, q) - load_vec<dim>(xr, q));
    for (int i = 0; i < prims.count(j); ++i) {
      const LO n = prims.nodes(j, i);
      rel += c(k, 1 + i) * s * (load_vec<dim>(x, n) - load_vec<dim>(xref, n));
    }
    u = Tk.transpose() * rel;
  }
};

template <int dim>
FrictionSliding<dim> FrictionTerm<dim>::sliding(ConstDofView x) const {
  const auto& ps = barrier_.particles();
  interpolate_pair_particles(ps, pair_, seg_, n_seg_, x, xq_);  // the lagged pairs' particles only
  interpolate_pair_particles(ps, pair_, seg_, n_seg_, x_ref_, xq_ref_);
  return {x, xq_, xq_ref_, x_ref_, barrier_.primitives(), pair_, c_, T_, s_};
}

// The lagged pair's friction force direction times its magnitude,
// mu lambda (f1(|u|)/|u|) T u (its gradient in the sliding displacement).
template <int dim>
KOKKOS_INLINE_FUNCTION Vec<dim> friction_pair_force(double ml, double eh, const Eigen::Matrix<double, dim - 1, 1>& u,
                                                    const Eigen::Matrix<double, dim, dim - 1>& T) {
  return ml * friction_f1_over_y(u.norm(), eh) * (T * u);
}

template <int dim>
double FrictionTerm<dim>::energy(ConstDofView x) const {
  if (n_ == 0) return 0.0;
  const FrictionSliding<dim> sl = sliding(x);
  const auto ml = ml_;
  const double eh = eh_;
  double e = 0;
  Kokkos::parallel_reduce(
      "friction_energy", Kokkos::RangePolicy<ExecSpace>(0, n_),
      KOKKOS_LAMBDA(const LO k, double& acc) {
        Eigen::Matrix<double, dim, dim - 1> Tk;
        Eigen::Matrix<double, dim - 1, 1> u;
        sl(k, Tk, u);
        acc += ml(k) * friction_f0(u.norm(), eh);
      },
      e);
  return e;
}

// Per particle q with stencil weights w_a at nodes n_a, over its lagged
// pairs k with coefficients c_k0 (particle), c_ki (vertices):
//   pair force     f_k = mu lambda_k (f1/y) T_k u_k,
//   pair Hessian   Hx_k = share_k mu lambda_k s^2 T_k H_u T_k^T,
// share_k = 1, except for a compensation pair (mu lambda_k < 0) when projecting:
// share_k = sink.contact_keep (0 unless Newton's fallback keeps some curvature),
// the particle's sums s sum_k c_k0 f_k and sum_k c_k0^2 Hx_k are expanded
// through the stencil once; the vertex parts (s c_ki f_k, c_ki c_kl Hx_k,
// w_a c_k0 c_ki Hx_k) go per pair. The same sums as expanding each pair's
// local gradient s c_i f and Hessian c_i c_l Hx through the stencil, in
// another order. On one thread the adds are plain (see the barrier term).
template <int dim>
void FrictionTerm<dim>::assemble_by_particle(ConstDofView x, const Sink<dim>& sink_in, bool hessian) const {
  Sink<dim> sink = sink_in;
  if (ExecSpace().concurrency() == 1) sink.atomic = false;
  const FrictionSliding<dim> sl = sliding(x);
  const auto ps = barrier_.particles();
  const auto seg = seg_;
  const auto c = c_;
  const auto ml = ml_;
  const double s = s_, eh = eh_;
  const bool matrix = hessian && sink.has_matrix();
  const double negative_kept = project_ && sink.project ? sink.contact_keep : 1.0;
  constexpr int ns = ParticleStencils<dim>::ns;
  // As the barrier term: with the cells, the particle sums are expanded cell by cell.
  const ParticleCells<dim>* cells = barrier_.cells();
  const bool by_cell = matrix && barrier_.cell_expansion();
  if (by_cell) sums_.reserve(static_cast<LO>(cells->order.extent(0)));
  const LO n_cell_points = by_cell ? sums_.capacity() : 0;
  const auto sums = sums_;
  Kokkos::parallel_for(
      "friction_pairs_by_particle", Kokkos::RangePolicy<ExecSpace>(0, n_seg_), KOKKOS_LAMBDA(const LO r) {
        const LO q = sl.pair(seg(r), 0);
        Vec<dim> gp = Vec<dim>::Zero();
        Mat<dim> Hpp = Mat<dim>::Zero();
        for (LO k = seg(r); k < seg(r + 1); ++k) {
          const LO j = sl.pair(k, 1);
          const int nv = sl.prims.count(j);
          Eigen::Matrix<double, dim, dim - 1> T;
          Eigen::Matrix<double, dim - 1, 1> u;
          sl(k, T, u);
          const Vec<dim> f = friction_pair_force<dim>(ml(k), eh, u, T);
          gp += (s * c(k, 0)) * f;
          LO vn[dim];
          for (int i = 0; i < nv; ++i) {
            vn[i] = sl.prims.nodes(j, i);
            for (int d = 0; d < dim; ++d) sink.add_gradient(vn[i], d, s * c(k, 1 + i) * f(d));
          }
          if (!matrix || ml(k) == 0.0) continue;
          // A compensation pair (mu lambda < 0) projected alone: a fraction of its curvature, or none.
          const double share = ml(k) > 0 ? 1.0 : negative_kept;
          if (share == 0.0) continue;
          const Mat<dim> Hx = (share * ml(k) * s * s) * (T * friction_f0_hessian<dim - 1>(u, eh) * T.transpose());
          const double c0 = c(k, 0);
          Hpp += (c0 * c0) * Hx;
          for (int i = 0; i < nv; ++i) {
            const double ci = c(k, 1 + i);
            for (int l = 0; l < nv; ++l) {
              const double cil = ci * c(k, 1 + l);
              sink.add_block(vn[i], vn[l], [&](int a, int b) { return cil * Hx(a, b); });
            }
            for (int a = 0; a < ns; ++a) {
              const double w = ps.w(q, a) * c0 * ci;
              if (w == 0.0) continue;  // a B-spline weight of 0 adds nothing
              const LO na = ps.nodes(q, a);
              sink.add_block(na, vn[i], [&](int ra, int cb) { return w * Hx(ra, cb); });
              sink.add_block(vn[i], na, [&](int ra, int cb) { return w * Hx(ra, cb); });
            }
          }
        }
        if (q < n_cell_points) sums.store(q, gp, Hpp);
        else expand_particle_sums<dim>(ps, q, gp, Hpp, matrix, sink);
      });
  if (by_cell) expand_by_cell<dim>(*cells, ps, sums_, sink);
}

template <int dim>
void FrictionTerm<dim>::gradient(ConstDofView x, double scale, DofView grad) const {
  if (n_ == 0) return;
  Sink<dim> sink;  // gradient only
  sink.grad = grad;
  sink.scale = scale;
  assemble_by_particle(x, sink, false);
}

template <int dim>
void FrictionTerm<dim>::assemble(ConstDofView x, const Sink<dim>& sink) const {
  if (n_ == 0) return;
  assemble_by_particle(x, sink, true);
}

template <int dim>
void FrictionTerm<dim>::add_particle_forces(ConstDofView x, DofView f) const {
  if (n_ == 0) return;
  const FrictionSliding<dim> sl = sliding(x);
  const auto c = c_;
  const auto ml = ml_;
  const double s = s_, eh = eh_;
  Kokkos::parallel_for(
      "friction_particle_forces", Kokkos::RangePolicy<ExecSpace>(0, n_), KOKKOS_LAMBDA(const LO k) {
        Eigen::Matrix<double, dim, dim - 1> T;
        Eigen::Matrix<double, dim - 1, 1> u;
        sl(k, T, u);
        const Vec<dim> fk = friction_pair_force<dim>(ml(k), eh, u, T);
        const LO q = sl.pair(k, 0);
        for (int d = 0; d < dim; ++d) Kokkos::atomic_add(&f(q * dim + d), -s * c(k, 0) * fk(d));
      });
}

template class FrictionTerm<2>;
template class FrictionTerm<3>;

}  // namespace bfemp
