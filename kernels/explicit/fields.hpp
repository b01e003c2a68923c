#pragma once
// Plain-data views of the explicit multimaterial MPM (paper 001 §3.2) and the
// kernels shared by the stepper and the tests: particle binning by cell, the
// per-material grid operator S^{+alpha} S of XPIC(m) and the v*^alpha task of
// Eqs. 42-44.
//
// Grid fields are per (node, material class): slot = node * M + a for M
// classes; vector fields hold dim doubles per slot (slot * dim + c). Units:
// mass kg (kg/m in 2D plane strain), momentum kg m/s, velocity m/s.
#include <Kokkos_Core.hpp>
#include <Kokkos_ScatterView.hpp>

#include "core/types.hpp"
#include "kernels/mpm/grid.hpp"

namespace bfemp::xmpm {

// Particles as the explicit kernels see them (every View one entry per particle).
template <int dim>
struct XParticles {
  Kokkos::View<double* [dim], MemSpace> x, v;
  Kokkos::View<double*, MemSpace> mass, volume0;
  Kokkos::View<double*, MemSpace> lp;             // half-width of the undeformed particle (uGIMP; R0 of Eq. 25), m
  Kokkos::View<double* [dim][dim], MemSpace> F;
  Kokkos::View<double* [dim][dim], MemSpace> sigma;  // Cauchy stress, Pa
  Kokkos::View<int*, MemSpace> cls;               // material class 0..M-1
  Kokkos::View<int*, MemSpace> body;
  std::size_t size() const { return mass.extent(0); }
};

using Scatter = Kokkos::Experimental::ScatterView<double*, Kokkos::LayoutRight, ExecSpace>;

template <int dim>
KOKKOS_INLINE_FUNCTION Vec<dim> pos(const XParticles<dim>& p, LO q) {
  Vec<dim> x;
  for (int d = 0; d < dim; ++d) x(d) = p.x(q, d);
  return x;
}

// Cell bins: cell c holds particles sorted(start(c)) .. sorted(start(c+1)-1),
// in increasing particle index (deterministic for any thread count).
struct CellBins {
  Kokkos::View<LO*, MemSpace> start;   // n_cells + 1
  Kokkos::View<LO*, MemSpace> fill;    // n_cells (scratch)
  Kokkos::View<LO*, MemSpace> sorted;  // n_particles
};

template <int dim>
KOKKOS_INLINE_FUNCTION LO cell_of(const GridSpec<dim>& g, const Vec<dim>& x) {
  LO c = 0;
  for (int d = dim - 1; d >= 0; --d) {
    int i = static_cast<int>(std::floor((x(d) - g.origin[d]) / g.dx));
    i = i < 0 ? 0 : (i >= g.n_cells[d] ? g.n_cells[d] - 1 : i);
    c = c * g.n_cells[d] + i;
  }
  return c;
}

template <int dim>
LO num_cells(const GridSpec<dim>& g) {
  LO n = 1;
  for (int d = 0; d < dim; ++d) n *= g.n_cells[d];
  return n;
}

// Counting sort of the particles by cell (allocates only when sizes grow).
template <int dim>
void bin_particles(const GridSpec<dim>& g, const XParticles<dim>& p, CellBins& bins) {
  const LO nc = num_cells(g), np = static_cast<LO>(p.size());
  if (static_cast<LO>(bins.start.extent(0)) != nc + 1) {
    bins.start = Kokkos::View<LO*, MemSpace>("xmpm_cell_start", nc + 1);
    bins.fill = Kokkos::View<LO*, MemSpace>("xmpm_cell_fill", nc);
  }
  if (static_cast<LO>(bins.sorted.extent(0)) != np) bins.sorted = Kokkos::View<LO*, MemSpace>("xmpm_sorted", np);
  auto start = bins.start, fill = bins.fill, sorted = bins.sorted;
  Kokkos::deep_copy(fill, 0);
  Kokkos::parallel_for(
      "xmpm_bin_count", Kokkos::RangePolicy<ExecSpace>(0, np),
      KOKKOS_LAMBDA(const LO q) { Kokkos::atomic_increment(&fill(cell_of(g, pos(p, q)))); });
  Kokkos::parallel_scan(
      "xmpm_bin_scan", Kokkos::RangePolicy<ExecSpace>(0, nc + 1),
      KOKKOS_LAMBDA(const LO c, LO& off, const bool final) {
        const LO n = c < nc ? fill(c) : 0;
        if (final) start(c) = off;
        off += n;
      });
  Kokkos::deep_copy(fill, 0);
  Kokkos::parallel_for(
      "xmpm_bin_fill", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const LO q) {
        const LO c = cell_of(g, pos(p, q));
        sorted(start(c) + Kokkos::atomic_fetch_add(&fill(c), 1)) = q;
      });
  Kokkos::parallel_for(
      "xmpm_bin_order", Kokkos::RangePolicy<ExecSpace>(0, nc), KOKKOS_LAMBDA(const LO c) {
        for (LO i = start(c) + 1; i < start(c + 1); ++i) {  // insertion sort: a few particles per cell
          const LO v = sorted(i);
          LO j = i - 1;
          while (j >= start(c) && sorted(j) > v) {
            sorted(j + 1) = sorted(j);
            --j;
          }
          sorted(j + 1) = v;
        }
      });
}

// Grid velocity constraints of one step: flag(node*dim + c) = 1 where
// component c is prescribed to value(node*dim + c) (m/s).
struct GridConstraints {
  Kokkos::View<unsigned char*, MemSpace> flag;
  Kokkos::View<double*, MemSpace> value;
};

// out^alpha = (S^{+alpha} S) in^alpha for two fields at once (Eq. 43-44):
// (S in)_p = sum_i S_pi in_i^{cls p}, out_i^alpha = sum_{p in alpha} S_pi m_p (S in)_p / m_i^alpha
// (zero where m_i^alpha = 0). acc: scatter over a scratch View of the same size.
template <int dim, class Shape>
void sps_apply2(const GridSpec<dim>& g, int M, const XParticles<dim>& p, Kokkos::View<const double*, MemSpace> gmass,
                Kokkos::View<const double*, MemSpace> in1, Kokkos::View<const double*, MemSpace> in2,
                Kokkos::View<double*, MemSpace> out1, Kokkos::View<double*, MemSpace> out2, Scatter& acc1,
                Scatter& acc2) {
  using St = typename Shape::template Stencil<dim>;
  Kokkos::deep_copy(out1, 0.0);
  Kokkos::deep_copy(out2, 0.0);
  acc1.reset();
  acc2.reset();
  auto a1 = acc1, a2 = acc2;
  Kokkos::parallel_for(
      "xmpm_sps", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
        const St st = Shape::template stencil<dim>(g, pos(p, q), p.lp(q));
        const int a = p.cls(q);
        double v1[dim] = {}, v2[dim] = {};
        for (int k = 0; k < St::size; ++k) {
          const double w = st.weight(k);
          const LO s = (st.node(g, k) * M + a) * dim;
          for (int c = 0; c < dim; ++c) {
            v1[c] += w * in1(s + c);
            v2[c] += w * in2(s + c);
          }
        }
        auto o1 = a1.access();
        auto o2 = a2.access();
        for (int k = 0; k < St::size; ++k) {
          const double wm = st.weight(k) * p.mass(q);
          const LO s = (st.node(g, k) * M + a) * dim;
          for (int c = 0; c < dim; ++c) {
            o1(s + c) += wm * v1[c];
            o2(s + c) += wm * v2[c];
          }
        }
      });
  Kokkos::Experimental::contribute(out1, acc1);
  Kokkos::Experimental::contribute(out2, acc2);
  const LO nslot = static_cast<LO>(gmass.extent(0));
  Kokkos::parallel_for(
      "xmpm_sps_divide", Kokkos::RangePolicy<ExecSpace>(0, nslot), KOKKOS_LAMBDA(const LO s) {
        const double m = gmass(s);
        for (int c = 0; c < dim; ++c) {
          out1(s * dim + c) = m > 0 ? out1(s * dim + c) / m : 0.0;
          out2(s * dim + c) = m > 0 ? out2(s * dim + c) / m : 0.0;
        }
      });
}

// Scratch of the XPIC task (sized like a vector grid field).
struct XpicScratch {
  Kokkos::View<double*, MemSpace> vk, dvk, vk1, dvk1;
  Scatter acc1, acc2;
  void ensure(std::size_t n) {
    if (vk.extent(0) == n) return;
    vk = Kokkos::View<double*, MemSpace>("xpic_vk", n);
    dvk = Kokkos::View<double*, MemSpace>("xpic_dvk", n);
    vk1 = Kokkos::View<double*, MemSpace>("xpic_vk1", n);
    dvk1 = Kokkos::View<double*, MemSpace>("xpic_dvk1", n);
    acc1 = Scatter(vk1);
    acc2 = Scatter(dvk1);
  }
};

// Multimaterial XPIC(m) (Eqs. 41-44): vstar = v*^alpha from v1 = v^alpha and
// dv1 = Delta v^alpha (dv1 = 0 and v1 = v^{alpha 0}: the uncorrected XPIC):
//   v*_1 = v1, Dv*_1 = dv1, v*_k = (m+1-k)/k S+S v*_{k-1}, Dv*_k = (m-k)/k S+S Dv*_{k-1},
//   v* = sum_{k=2}^m (-1)^k (v*_k + (m-1)/m Dv*_{k-1}).
// Constrained grid components keep their own value scaled by the same factors
// (a prescribed velocity field is reproduced: P V = S v_bc). m >= 1 (m = 1: v* = 0).
template <int dim, class Shape>
void xpic_vstar(const GridSpec<dim>& g, int M, const XParticles<dim>& p, Kokkos::View<const double*, MemSpace> gmass,
                Kokkos::View<const double*, MemSpace> v1, Kokkos::View<const double*, MemSpace> dv1, int m,
                const GridConstraints& bc, Kokkos::View<double*, MemSpace> vstar, XpicScratch& s) {
  s.ensure(v1.extent(0));
  Kokkos::deep_copy(vstar, 0.0);
  Kokkos::deep_copy(s.vk, v1);
  Kokkos::deep_copy(s.dvk, dv1);
  const LO n = static_cast<LO>(v1.extent(0));
  for (int k = 2; k <= m; ++k) {
    sps_apply2<dim, Shape>(g, M, p, gmass, s.vk, s.dvk, s.vk1, s.dvk1, s.acc1, s.acc2);
    const double fv = double(m + 1 - k) / k, fd = double(m - k) / k, fm = double(m - 1) / m;
    const double sign = k % 2 == 0 ? 1.0 : -1.0;
    auto vk = s.vk, dvk = s.dvk, vk1 = s.vk1, dvk1 = s.dvk1;
    auto flag = bc.flag;
    const bool has_bc = flag.extent(0) > 0;
    Kokkos::parallel_for(
        "xpic_step", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const LO i) {
          const LO node = i / (dim * M), c = i % dim;
          double nv, nd;
          if (has_bc && flag(node * dim + c)) {
            nv = fv * vk(i);
            nd = fd * dvk(i);
          } else {
            nv = fv * vk1(i);
            nd = fd * dvk1(i);
          }
          vstar(i) += sign * (nv + fm * dvk(i));
          vk(i) = nv;
          dvk(i) = nd;
        });
  }
}

}  // namespace bfemp::xmpm
