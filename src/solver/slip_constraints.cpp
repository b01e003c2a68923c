#include "solver/slip_constraints.hpp"

#include <limits>
#include <stdexcept>

namespace bfemp {

template <int dim>
void SlipConstraints<dim>::build(const LevelSetList& ls, double t, double dt, std::size_t first_dof,
                                 std::size_t n, DofView x, DofView v, MaskView prescribed) {
  count_ = 0;
  has_offset_ = false;
  dt_ = dt;
  const LO n_nodes = static_cast<LO>(n / dim);
  bool any_slip = false;
  for (int k = 0; k < ls.count; ++k) any_slip = any_slip || ls.sets[k].slip;
  if (!any_slip || n_nodes == 0) return;
  if (static_cast<LO>(slot_.extent(0)) < n_nodes)
    slot_ = Kokkos::View<LO*, MemSpace>("slip_slot", static_cast<std::size_t>(n_nodes) * 5 / 4 + 16);
  auto slot = slot_;
  const LO first = static_cast<LO>(first_dof / dim);
  // Flag the nodes inside a slip set with no prescribed DOF, then number them.
  Kokkos::parallel_for(
      "slip_flag", Kokkos::RangePolicy<ExecSpace>(0, n_nodes), KOKKOS_LAMBDA(const LO node) {
        slot(node) = 0;
        if (node < first) return;
        for (int c = 0; c < dim; ++c)
          if (prescribed(node * dim + c)) return;
        Vec<dim> xi;
        for (int c = 0; c < dim; ++c) xi(c) = x(node * dim + c);
        for (int k = 0; k < ls.count; ++k)
          if (ls.sets[k].slip && ls.sets[k].template phi<dim>(xi, t) <= 0) slot(node) = 1;
      });
  LO count = 0;
  Kokkos::parallel_scan(
      "slip_number", Kokkos::RangePolicy<ExecSpace>(0, n_nodes),
      KOKKOS_LAMBDA(const LO node, LO& offset, const bool final) {
        const LO flag = slot(node);
        if (final) slot(node) = flag ? offset : -1;
        offset += flag;
      },
      count);
  count_ = count;
  if (count == 0) return;
  if (static_cast<LO>(node_.extent(0)) < count) {
    const std::size_t cap = static_cast<std::size_t>(count) * 5 / 4 + 16;
    node_ = Kokkos::View<LO*, MemSpace>("slip_node", cap);
    Q_ = NodeMats("slip_Q", cap);
    T_ = NodeVecs("slip_T", cap);
    U_ = NodeVecs("slip_U", cap);
    w_ = NodeVecs("slip_w", cap);
  }
  auto node_of = node_;
  auto Q = Q_;
  auto T = T_;
  auto U = U_;
  Kokkos::parallel_for(
      "slip_build", Kokkos::RangePolicy<ExecSpace>(0, n_nodes), KOKKOS_LAMBDA(const LO node) {
        const LO k = slot(node);
        if (k < 0) return;
        node_of(k) = node;
        Vec<dim> xi;
        for (int c = 0; c < dim; ++c) xi(c) = x(node * dim + c);
        // Orthonormal basis e_0..e_{r-1} of the normals (Gram-Schmidt; nearly
        // dependent normals dropped), and the minimum-norm displacement
        // u = sum c_j e_j with n_s . u = dt n_s . v_s for the kept sets.
        Vec<dim> e[dim];
        double coef[dim];
        int r = 0;
        for (int s = 0; s < ls.count; ++s) {
          const LevelSet& set = ls.sets[s];
          if (!set.slip || set.template phi<dim>(xi, t) > 0 || r == dim) continue;
          const Vec<dim> nrm = set.template unit_normal<dim>(xi, t);
          double ds = 0;
          for (int c = 0; c < dim; ++c) ds += dt * nrm(c) * set.step_velocity(c, t, dt);
          Vec<dim> res = nrm;
          double known = 0;
          for (int j = 0; j < r; ++j) {
            const double a = e[j].dot(nrm);
            res -= a * e[j];
            known += a * coef[j];
          }
          const double len = res.norm();
          if (len < 1e-6) continue;
          e[r] = res / len;
          coef[r] = (ds - known) / len;
          ++r;
        }
        Mat<dim> q = Mat<dim>::Zero();
        Vec<dim> u = Vec<dim>::Zero();
        for (int j = 0; j < r; ++j) {
          q += e[j] * e[j].transpose();
          u += coef[j] * e[j];
        }
        // v <- P v + u / dt: the boundary's normal velocity.
        Vec<dim> vi;
        for (int c = 0; c < dim; ++c) vi(c) = v(node * dim + c);
        const Vec<dim> vn = vi - q * vi + u / dt;
        for (int i = 0; i < dim; ++i) {
          for (int j = 0; j < dim; ++j) Q(k, i, j) = q(i, j);
          U(k, i) = u(i);
          T(k, i) = xi(i) + u(i);
          v(node * dim + i) = vn(i);
        }
      });
  Kokkos::fence();
}

template <int dim>
double SlipConstraints<dim>::update_offsets(ConstDofView x) {
  if (count_ == 0) return 0.0;
  auto node_of = node_;
  auto Q = Q_;
  auto T = T_;
  auto w = w_;
  double wmax = 0;
  Kokkos::parallel_reduce(
      "slip_offsets", Kokkos::RangePolicy<ExecSpace>(0, count_),
      KOKKOS_LAMBDA(const LO k, double& acc) {
        const LO node = node_of(k);
        double d[dim], scale = 0;
        for (int c = 0; c < dim; ++c) {
          d[c] = T(k, c) - x(node * dim + c);
          scale = std::fmax(scale, std::fabs(T(k, c)) + std::fabs(x(node * dim + c)));
        }
        double wk[dim], m = 0;
        for (int i = 0; i < dim; ++i) {
          wk[i] = 0;
          for (int j = 0; j < dim; ++j) wk[i] += Q(k, i, j) * d[j];
          m = std::fmax(m, std::fabs(wk[i]));
        }
        // Round-off of x + p and of Q (T - x) is a few ulps of the positions:
        // below that the constraint holds.
        const bool met = m <= 64 * std::numeric_limits<double>::epsilon() * scale;
        for (int i = 0; i < dim; ++i) w(k, i) = met ? 0.0 : wk[i];
        acc = std::fmax(acc, met ? 0.0 : m);
      },
      Kokkos::Max<double>(wmax));
  has_offset_ = wmax > 0;
  return wmax;
}

template <int dim>
void SlipConstraints<dim>::transform_system(const LocalMatrix& A, DofView rhs,
                                            Kokkos::View<const int*, MemSpace> owned) const {
  if (count_ == 0) return;
  auto rows = A.graph.row_map;
  auto cols = A.graph.entries;
  auto vals = A.values;
  auto slot = slot_;
  auto Q = Q_;
  auto w = w_;
  const LO n_nodes = static_cast<LO>(rows.extent(0) - 1) / dim;
  const bool all_owned = owned.extent(0) == 0;
  if (!all_owned && static_cast<LO>(owned.extent(0)) < n_nodes * dim)
    throw std::logic_error("SlipConstraints: the owned mask is shorter than the system");
  if (static_cast<LO>(slot.extent(0)) < n_nodes)
    throw std::logic_error("SlipConstraints: the system has more nodes than the constraints were built for");
  if (has_offset_) {  // rhs -= A w (before A is transformed)
    Kokkos::parallel_for(
        "slip_rhs_Aw", Kokkos::RangePolicy<ExecSpace>(0, n_nodes * dim), KOKKOS_LAMBDA(const LO r) {
          double s = 0;
          for (auto e = rows(r); e < rows(r + 1); ++e) {
            const LO c = cols(e);
            const LO k = slot(c / dim);
            if (k >= 0) s += vals(e) * w(k, c % dim);
          }
          rhs(r) -= s;
        });
  }
  int bad = 0;
  Kokkos::parallel_reduce(
      "slip_transform", Kokkos::RangePolicy<ExecSpace>(0, n_nodes),
      KOKKOS_LAMBDA(const LO i, int& err) {
        const LO si = slot(i);
        const auto len = rows(i * dim + 1) - rows(i * dim);
        for (int a = 1; a < dim; ++a)
          if (rows(i * dim + a + 1) - rows(i * dim + a) != len) { err = 1 > err ? 1 : err; return; }
        if (len % dim != 0) { err = 1 > err ? 1 : err; return; }
        const bool own = all_owned || owned(i * dim) != 0;  // Q and w once, at the owner
        Mat<dim> Pi = Mat<dim>::Identity();
        if (si >= 0)
          for (int a = 0; a < dim; ++a)
            for (int b = 0; b < dim; ++b) Pi(a, b) -= Q(si, a, b);
        for (std::size_t blk = 0; blk < len / dim; ++blk) {
          const auto e0 = rows(i * dim) + blk * dim;
          const LO j = cols(e0) / dim;
          for (int d = 0; d < dim; ++d)
            if (cols(e0 + d) != j * dim + d) { err = 1 > err ? 1 : err; return; }
          const LO sj = slot(j);
          if (si < 0 && sj < 0) continue;
          Mat<dim> B;
          for (int a = 0; a < dim; ++a)
            for (int d = 0; d < dim; ++d) B(a, d) = vals(rows(i * dim + a) + blk * dim + d);
          Mat<dim> Pj = Mat<dim>::Identity();
          if (sj >= 0)
            for (int a = 0; a < dim; ++a)
              for (int b = 0; b < dim; ++b) Pj(a, b) -= Q(sj, a, b);
          Mat<dim> Bn = Pi * B * Pj;
          if (i == j && own)
            for (int a = 0; a < dim; ++a)
              for (int b = 0; b < dim; ++b) Bn(a, b) += Q(si, a, b);
          for (int a = 0; a < dim; ++a)
            for (int d = 0; d < dim; ++d) vals(rows(i * dim + a) + blk * dim + d) = Bn(a, d);
        }
        if (si >= 0) {
          Vec<dim> r;
          for (int a = 0; a < dim; ++a) r(a) = rhs(i * dim + a);
          const Vec<dim> rn = Pi * r;
          for (int a = 0; a < dim; ++a) rhs(i * dim + a) = rn(a) + (own ? w(si, a) : 0.0);
        }
      },
      Kokkos::Max<int>(bad));
  if (bad > 0)
    throw std::logic_error("SlipConstraints: the system matrix is not node-blocked (expected build_dof_graph's layout)");
}

template <int dim>
void SlipConstraints<dim>::fix_direction(DofView p) const {
  if (count_ == 0) return;
  auto node_of = node_;
  auto Q = Q_;
  auto w = w_;
  Kokkos::parallel_for(
      "slip_fix_direction", Kokkos::RangePolicy<ExecSpace>(0, count_), KOKKOS_LAMBDA(const LO k) {
        const LO node = node_of(k);
        double pk[dim], qp[dim];
        for (int c = 0; c < dim; ++c) pk[c] = p(node * dim + c);
        for (int a = 0; a < dim; ++a) {
          qp[a] = 0;
          for (int b = 0; b < dim; ++b) qp[a] += Q(k, a, b) * pk[b];
        }
        for (int a = 0; a < dim; ++a) p(node * dim + a) = pk[a] - qp[a] + w(k, a);
      });
}

template <int dim>
void SlipConstraints<dim>::project_velocities(DofView v) const {
  if (count_ == 0) return;
  auto node_of = node_;
  auto Q = Q_;
  auto U = U_;
  const double inv_dt = 1.0 / dt_;
  Kokkos::parallel_for(
      "slip_project_velocity", Kokkos::RangePolicy<ExecSpace>(0, count_), KOKKOS_LAMBDA(const LO k) {
        const LO node = node_of(k);
        double vk[dim], qv[dim];
        for (int c = 0; c < dim; ++c) vk[c] = v(node * dim + c);
        for (int a = 0; a < dim; ++a) {
          qv[a] = 0;
          for (int b = 0; b < dim; ++b) qv[a] += Q(k, a, b) * vk[b];
        }
        for (int a = 0; a < dim; ++a) v(node * dim + a) = vk[a] - qv[a] + U(k, a) * inv_dt;
      });
}

template <int dim>
double SlipConstraints<dim>::violation(ConstDofView x) const {
  if (count_ == 0) return 0.0;
  auto node_of = node_;
  auto Q = Q_;
  auto T = T_;
  double vmax = 0;
  Kokkos::parallel_reduce(
      "slip_violation", Kokkos::RangePolicy<ExecSpace>(0, count_),
      KOKKOS_LAMBDA(const LO k, double& acc) {
        const LO node = node_of(k);
        for (int a = 0; a < dim; ++a) {
          double s = 0;
          for (int b = 0; b < dim; ++b) s += Q(k, a, b) * (x(node * dim + b) - T(k, b));
          acc = std::fmax(acc, std::fabs(s));
        }
      },
      Kokkos::Max<double>(vmax));
  return vmax;
}

template class SlipConstraints<2>;
template class SlipConstraints<3>;

}  // namespace bfemp
