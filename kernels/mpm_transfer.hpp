#pragma once
// Kokkos kernels of the MPM particle-grid transfers (paper Tables 1-3):
// grid activation (active nodes numbered after the FEM nodes), P2G of mass and
// momentum, the particles' deformation stencils for the elastic energy
// (F_q(x) = sum_i x_i (grad w_iq)^T F_q^n), and G2P of velocity, position, F
// and the APIC affine matrix. Grid quantities of active node k live at system
// node first + k; system vectors are node-interleaved (node*dim + c).
#include <Kokkos_Core.hpp>
#include <Kokkos_ScatterView.hpp>

#include "kernels/deformation_energy.hpp"
#include "kernels/mpm/bspline.hpp"
#include "kernels/mpm/grid.hpp"
#include "kernels/mpm/particles.hpp"
#include "kernels/mpm/transfer_scheme.hpp"

namespace bfemp {

template <int dim>
KOKKOS_INLINE_FUNCTION Vec<dim> particle_position(const Particles<dim>& p, LO q) {
  Vec<dim> x;
  for (int d = 0; d < dim; ++d) x(d) = p.x(q, d);
  return x;
}

// Index of a particle whose stencil leaves the grid (the largest), or -1.
template <int dim>
LO particle_outside(const GridSpec<dim>& grid, const Particles<dim>& p) {
  LO worst = -1;
  Kokkos::parallel_reduce(
      "mpm_outside", Kokkos::RangePolicy<ExecSpace>(0, p.size()),
      KOKKOS_LAMBDA(const LO q, LO& acc) {
        if (!grid.contains(particle_position(p, q)) && q > acc) acc = q;
      },
      Kokkos::Max<LO>(worst));
  return worst < 0 ? -1 : worst;
}

// Marks the nodes touched by particle stencils and numbers them: system_node(n)
// = first + rank among active nodes, or -1. Returns the active count and fills
// grid_node(k) = linear grid index of active node k, k < the returned count
// (grown with headroom when too small; entries past the count are stale).
template <int dim>
LO activate_grid(const GridSpec<dim>& grid, const Particles<dim>& p, LO first,
                 Kokkos::View<LO*, MemSpace> system_node, Kokkos::View<LO*, MemSpace>& grid_node) {
  constexpr int ns = bspline_stencil_size<dim>;
  Kokkos::deep_copy(system_node, 0);
  Kokkos::parallel_for(
      "mpm_mark_nodes", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
        const auto st = bspline_stencil(grid, particle_position(p, q));
        for (int a = 0; a < ns; ++a) system_node(node_index(grid, st, a)) = 1;  // benign race
      });
  LO count = 0;
  Kokkos::parallel_scan(
      "mpm_number_nodes", Kokkos::RangePolicy<ExecSpace>(0, system_node.extent(0)),
      KOKKOS_LAMBDA(const LO n, LO& offset, const bool final) {
        const LO flag = system_node(n);
        if (final) system_node(n) = flag ? first + offset : -1;
        offset += flag;
      },
      count);
  // capacity with headroom: the active set changes most steps
  if (static_cast<LO>(grid_node.extent(0)) < count)
    grid_node = Kokkos::View<LO*, MemSpace>("mpm_grid_node", count + count / 4 + 16);
  auto gn = grid_node;
  Kokkos::parallel_for(
      "mpm_active_list", Kokkos::RangePolicy<ExecSpace>(0, system_node.extent(0)), KOKKOS_LAMBDA(const LO n) {
        if (system_node(n) >= 0) gn(system_node(n) - first) = n;
      });
  return count;
}

// Scatter target of P2G: one private copy of the grid arrays per thread
// (reset before P2G, summed into the target by contribute after it), so the
// adds are plain stores, and the sum order is fixed for a given thread count.
// Atomic adds cost twice as much per particle, also on one thread
// (perf/README.md, "P2G and G2P per particle").
using GridScatter = Kokkos::Experimental::ScatterView<double*, Kokkos::LayoutRight, ExecSpace,
                                                      Kokkos::Experimental::ScatterSum,
                                                      Kokkos::Experimental::ScatterDuplicated,
                                                      Kokkos::Experimental::ScatterNonAtomic>;

// P2G: node mass and momentum (m v) of active node k = system id - first via
// ScatterViews (persistent, created by the caller on the target views; a
// GridScatter must be reset before and contributed after).
template <int dim, class MassScatter, class MomentumScatter>
void p2g(const GridSpec<dim>& grid, const Particles<dim>& p, TransferScheme scheme,
         Kokkos::View<const LO*, MemSpace> system_node, LO first, MassScatter mass, MomentumScatter momentum) {
  const bool apic = scheme == TransferScheme::APIC;
  Kokkos::parallel_for(
      "mpm_p2g", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
        auto m_acc = mass.access();
        auto p_acc = momentum.access();
        const Vec<dim> xp = particle_position(p, q);
        const auto st = bspline_stencil(grid, xp);
        const double mp = p.mass(q);
        Vec<dim> vp;
        Mat<dim> C = Mat<dim>::Zero();
        for (int c = 0; c < dim; ++c) {
          vp(c) = p.v(q, c);
          if (apic)
            for (int d = 0; d < dim; ++d) C(c, d) = p.C(q, c, d);
        }
        for_each_stencil_node<dim>(grid, st, xp, [&](int, LO gnode, double w, const Vec<dim>&, const Vec<dim>& dxi) {
          const LO k = system_node(gnode) - first;
          const double wm = w * mp;
          m_acc(k) += wm;
          for (int c = 0; c < dim; ++c) {
            double v = vp(c);
            if (apic)
              for (int d = 0; d < dim; ++d) v += C(c, d) * dxi(d);
            p_acc(k * dim + c) += wm * v;
          }
        });
      });
}

// Deformation stencils of the particles: nodes = system ids of the stencil,
// g_a = F_q^n^T grad w_a, volume = rest volume.
template <int dim>
void mpm_stencils(const GridSpec<dim>& grid, const Particles<dim>& p, Kokkos::View<const LO*, MemSpace> system_node,
                  const DeformationStencils<dim, bspline_stencil_size<dim>>& s) {
  constexpr int ns = bspline_stencil_size<dim>;
  Kokkos::parallel_for(
      "mpm_stencils", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
        const auto st = bspline_stencil(grid, particle_position(p, q));
        for (int a = 0; a < ns; ++a) {
          s.nodes(q, a) = system_node(node_index(grid, st, a));
          const Vec<dim> gw = weight_gradient(st, a);
          for (int j = 0; j < dim; ++j) {
            double v = 0;
            for (int i = 0; i < dim; ++i) v += p.F(q, i, j) * gw(i);
            s.g(q, a, j) = v;
          }
        }
        s.volume(q) = p.volume0(q);
        s.material(q) = p.material(q);
      });
}

// G2P (Tables 1-3): x_p = sum w x~_i, v_p (PIC/APIC: sum w v~_i; FLIP: v_p +
// sum w (v~_i - v_i^n)), F_p = sum x~_i grad w^T F_p^n, APIC B_p (Table 1)
// stored as C_p = B_p D_p^-1 with D_p = dx^2/4 I.
namespace detail {
template <int dim, TransferScheme scheme>  // the scheme a compile-time constant: no branch per node
void g2p(const GridSpec<dim>& grid, const Particles<dim>& p, Kokkos::View<const LO*, MemSpace> system_node,
         Kokkos::View<const double*, MemSpace> x_new, Kokkos::View<const double*, MemSpace> v_new,
         Kokkos::View<const double*, MemSpace> v_old) {
  const double inv_D = 4.0 / (grid.dx * grid.dx);
  Kokkos::parallel_for(
      "mpm_g2p", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
        const Vec<dim> xp = particle_position(p, q);
        const auto st = bspline_stencil(grid, xp);
        Vec<dim> xn = Vec<dim>::Zero(), vn = Vec<dim>::Zero(), dv = Vec<dim>::Zero();
        Mat<dim> G = Mat<dim>::Zero();  // sum x~_i grad w^T
        // APIC (Table 1): B = 1/2 sum w [v_i (x_i - x_p + x~_i - x~_p)^T + (x_i - x_p - x~_i + x~_p) v_i^T]
        // with x~_p = sum w x~_i = xn and sum w v_i = vn. With u_i = w v_i and
        // r_i = x_i - x_p: B = 1/2 (M + M^T + K - vn xn^T + xn vn^T), where
        // M = sum u_i r_i^T and K = sum (u_i x~_i^T - x~_i u_i^T) is
        // antisymmetric: K_jk = eps_jkl k_l with k = sum u_i x x~_i (3D), or
        // K = [0 k; -k 0] with k = sum (u_0 x~_1 - u_1 x~_0) (2D). One pass;
        // per node B costs dim^2 products for M and 6 (3D) / 2 (2D) for k, where
        // the two sums S1, S2 of Table 1 cost 2 dim^2 (+ 2 dim).
        Mat<dim> M = Mat<dim>::Zero();
        constexpr int nk = dim == 3 ? 3 : 1;
        double k[nk] = {};
        constexpr bool apic = scheme == TransferScheme::APIC, flip = scheme == TransferScheme::FLIP;
        for_each_stencil_node<dim>(grid, st, xp, [&](int, LO gnode, double w, const Vec<dim>& gw, const Vec<dim>& r) {
          const LO n = system_node(gnode);
          Vec<dim> xt, u;
          for (int c = 0; c < dim; ++c) {
            xt(c) = x_new(n * dim + c);
            const double vi = v_new(n * dim + c);
            u(c) = w * vi;
            if constexpr (flip) dv(c) += w * (vi - v_old(n * dim + c));  // v^n is read only by FLIP
          }
          for (int i = 0; i < dim; ++i) {
            xn(i) += w * xt(i);
            vn(i) += u(i);
            for (int j = 0; j < dim; ++j) {
              G(i, j) += xt(i) * gw(j);
              if constexpr (apic) M(i, j) += u(i) * r(j);
            }
          }
          if constexpr (apic) {
            if constexpr (dim == 3) {
              k[0] += u(1) * xt(2) - u(2) * xt(1);
              k[1] += u(2) * xt(0) - u(0) * xt(2);
              k[2] += u(0) * xt(1) - u(1) * xt(0);
            } else {
              k[0] += u(0) * xt(1) - u(1) * xt(0);
            }
          }
        });
        if constexpr (apic) {
          Mat<dim> K;
          if constexpr (dim == 3) {
            K << 0, k[2], -k[1], -k[2], 0, k[0], k[1], -k[0], 0;
          } else {
            K << 0, k[0], -k[0], 0;
          }
          for (int i = 0; i < dim; ++i)
            for (int j = 0; j < dim; ++j)
              p.C(q, i, j) = 0.5 * (M(i, j) + M(j, i) + K(i, j) - vn(i) * xn(j) + xn(i) * vn(j)) * inv_D;
        }
        Mat<dim> Fn;
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j) Fn(i, j) = p.F(q, i, j);
        const Mat<dim> F1 = G * Fn;
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j) p.F(q, i, j) = F1(i, j);
        for (int c = 0; c < dim; ++c) {
          p.v(q, c) = flip ? p.v(q, c) + dv(c) : vn(c);
          p.x(q, c) = xn(c);
        }
      });
}
}  // namespace detail

template <int dim>
void g2p(const GridSpec<dim>& grid, const Particles<dim>& p, TransferScheme scheme,
         Kokkos::View<const LO*, MemSpace> system_node, Kokkos::View<const double*, MemSpace> x_new,
         Kokkos::View<const double*, MemSpace> v_new, Kokkos::View<const double*, MemSpace> v_old) {
  switch (scheme) {
    case TransferScheme::APIC:
      return detail::g2p<dim, TransferScheme::APIC>(grid, p, system_node, x_new, v_new, v_old);
    case TransferScheme::FLIP:
      return detail::g2p<dim, TransferScheme::FLIP>(grid, p, system_node, x_new, v_new, v_old);
    case TransferScheme::PIC:
      return detail::g2p<dim, TransferScheme::PIC>(grid, p, system_node, x_new, v_new, v_old);
  }
}

// Per-particle J = det F_p and von Mises stress.
template <int dim>
void mpm_particle_J_von_mises(const Particles<dim>& p, Kokkos::View<const MaterialParams*, MemSpace> mats,
                              Kokkos::View<double*, MemSpace> J, Kokkos::View<double*, MemSpace> vm) {
  Kokkos::parallel_for(
      "mpm_J_von_mises", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
        Mat<dim> F;
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j) F(i, j) = p.F(q, i, j);
        J(q) = F.determinant();
        vm(q) = von_mises_of<dim>(mats(p.material(q)), F);
      });
}

// Smallest det F_p over the particles (1 when there are none).
template <int dim>
double mpm_particle_min_J(const Particles<dim>& p) {
  double jmin = 1;
  Kokkos::parallel_reduce(
      "mpm_min_J", Kokkos::RangePolicy<ExecSpace>(0, p.size()),
      KOKKOS_LAMBDA(const LO q, double& acc) {
        Mat<dim> F;
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j) F(i, j) = p.F(q, i, j);
        const double j = F.determinant();
        if (j < acc) acc = j;
      },
      Kokkos::Min<double>(jmin));
  return jmin;
}

}  // namespace bfemp
