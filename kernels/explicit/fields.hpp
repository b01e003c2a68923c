#pragma once
// Plain-data views of the explicit multimaterial MPM (paper 001 §3.2) and the
// kernels shared by the stepper and the tests: particle binning by cell, the
// particles' stencils of a step, the per-material grid operator S^{+alpha} S
// of XPIC(m) and the v*^alpha task of Eqs. 42-44.
//
// Grid fields are per (node, material class): slot = node * M + a for M
// classes; vector fields hold dim doubles per slot (slot * dim + c). Units:
// mass kg (kg/m in 2D plane strain), momentum kg m/s, velocity m/s.
#include <Kokkos_Core.hpp>
#include <Kokkos_UniqueToken.hpp>

#include "core/types.hpp"
#include "kernels/mpm/grid.hpp"
#include "kernels/small_loops.hpp"

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

// A grid field summed from a particle loop without atomics: one private copy
// per thread (rows of `copies`), zeroed by reset() before the loop, written
// through access() inside it, and summed into the field in thread order by
// contribute() after it: field(i) = copies(0, i) + copies(1, i) + ... (the
// field's old values are overwritten, so it needs no zeroing). The same sums
// in the same order as a duplicated Kokkos::ScatterView contributed into a
// zeroed field, with reset and contribute as short loops (small_loops.hpp)
// instead of two parallel launches each. The rows are indexed as
// ScatterView's are: by the global-scope UniqueToken (OpenMP: the hardware
// thread id, release a no-op, so a loop-scoped acquire needs no release).
struct Scatter {
  using Token = Kokkos::Experimental::UniqueToken<ExecSpace, Kokkos::Experimental::UniqueTokenScope::Global>;
  Token token;  // before copies: sizes them
  Kokkos::View<double**, Kokkos::LayoutRight, MemSpace> copies;  // (threads, n)
  Kokkos::View<double*, MemSpace> field;

  Scatter() = default;
  explicit Scatter(Kokkos::View<double*, MemSpace> f)
      : token(),
        copies(Kokkos::view_alloc("xmpm_scatter", Kokkos::WithoutInitializing), token.size(), f.extent(0)),
        field(f) {}

  void reset() const { small_fill(copies, 0.0); }

  // Within a particle loop on ExecSpace: this thread's copy.
  struct Access {
    double* row;
    KOKKOS_INLINE_FUNCTION double& operator()(LO i) const { return row[i]; }
  };
  KOKKOS_INLINE_FUNCTION Access access() const {
    return Access{copies.data() + static_cast<std::size_t>(token.acquire()) * copies.stride(0)};
  }

  void contribute() const {
    const auto c = copies;
    const auto f = field;
    const LO nt = static_cast<LO>(copies.extent(0));
    small_for(
        "xmpm_scatter_sum", static_cast<long>(field.extent(0)), KOKKOS_LAMBDA(const LO i) {
          double s = 0.0;
          for (LO t = 0; t < nt; ++t) s += c(t, i);
          f(i) = s;
        });
  }
};

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
  small_fill(fill, 0);
  small_for(
      "xmpm_bin_count", np,
      KOKKOS_LAMBDA(const LO q) { Kokkos::atomic_increment(&fill(cell_of(g, pos(p, q)))); });
  LO total = 0;
  small_scan(
      "xmpm_bin_scan", nc + 1,
      KOKKOS_LAMBDA(const LO c, LO& off, const bool final) {
        const LO n = c < nc ? fill(c) : 0;
        if (final) start(c) = off;
        off += n;
      },
      total);
  small_fill(fill, 0);
  small_for(
      "xmpm_bin_fill", np, KOKKOS_LAMBDA(const LO q) {
        const LO c = cell_of(g, pos(p, q));
        sorted(start(c) + Kokkos::atomic_fetch_add(&fill(c), 1)) = q;
      });
  small_for(
      "xmpm_bin_order", nc, KOKKOS_LAMBDA(const LO c) {
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

// Each particle's shape-function stencil (base node, per-axis weights and
// derivatives), computed once per step: positions do not move between P2G
// and G2P, so every kernel of the step (P2G, stress, forces, the XPIC
// sweeps, G2P) reads the same stencil instead of evaluating it again.
// Allocates only when the particle count changes.
template <int dim, class Shape>
using StencilView = Kokkos::View<typename Shape::template Stencil<dim>*, MemSpace>;

template <int dim, class Shape>
void compute_stencils(const GridSpec<dim>& g, const XParticles<dim>& p, StencilView<dim, Shape>& st) {
  if (st.extent(0) != p.size()) st = StencilView<dim, Shape>(Kokkos::view_alloc("xmpm_stencils", Kokkos::WithoutInitializing), p.size());
  const auto out = st;
  Kokkos::parallel_for(
      "xmpm_stencils", Kokkos::RangePolicy<ExecSpace>(0, p.size()),
      KOKKOS_LAMBDA(const LO q) { out(q) = Shape::template stencil<dim>(g, pos(p, q), p.lp(q)); });
}

// The sums of (S^{+alpha} S) in^alpha for two fields at once (Eq. 43-44),
// before the division by the node mass:
// (S in)_p = sum_i S_pi in_i^{cls p}, sum1_i^alpha = sum_{p in alpha} S_pi m_p (S in)_p;
// out_i^alpha = sum_i^alpha / m_i^alpha (zero where m_i^alpha = 0) is left to
// the caller (xpic_vstar fuses it with the series update). acc1, acc2: the
// scatters onto the two sums (acc1.field, acc2.field). second = false: the
// first field only (acc2 untouched).
template <int dim, class Shape>
void sps_sums2(const GridSpec<dim>& g, int M, const XParticles<dim>& p,
               Kokkos::View<const typename Shape::template Stencil<dim>*, MemSpace> sts,
               Kokkos::View<const double*, MemSpace> in1, Kokkos::View<const double*, MemSpace> in2,
               const Scatter& acc1, const Scatter& acc2, bool second = true) {
  using St = typename Shape::template Stencil<dim>;
  acc1.reset();
  if (second) acc2.reset();
  auto a1 = acc1, a2 = acc2;
  Kokkos::parallel_for(
      "xmpm_sps", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
        const St& st = sts(q);
        const int a = p.cls(q);
        // weights and slots in registers: the scatter's stores may alias the stencil's memory
        double w[St::size];
        LO sl[St::size];
        for (int k = 0; k < St::size; ++k) {
          w[k] = st.weight(k);
          sl[k] = (st.node(g, k) * M + a) * dim;
        }
        const double mq = p.mass(q);
        // (S in)_p, then S_pi m_p (S in)_p into the scatter
        auto sweep = [&](const Kokkos::View<const double*, MemSpace>& in, const Scatter& acc) {
          double vp[dim] = {};
          for (int k = 0; k < St::size; ++k)
            for (int c = 0; c < dim; ++c) vp[c] += w[k] * in(sl[k] + c);
          auto o = acc.access();
          for (int k = 0; k < St::size; ++k) {
            const double wm = w[k] * mq;
            for (int c = 0; c < dim; ++c) o(sl[k] + c) += wm * vp[c];
          }
        };
        sweep(in1, a1);
        if (second) sweep(in2, a2);
      });
  acc1.contribute();
  if (second) acc2.contribute();
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
// sts: the particles' stencils at their current positions (compute_stencils).
template <int dim, class Shape>
void xpic_vstar(const GridSpec<dim>& g, int M, const XParticles<dim>& p,
                Kokkos::View<const typename Shape::template Stencil<dim>*, MemSpace> sts,
                Kokkos::View<const double*, MemSpace> gmass, Kokkos::View<const double*, MemSpace> v1,
                Kokkos::View<const double*, MemSpace> dv1, int m, const GridConstraints& bc,
                Kokkos::View<double*, MemSpace> vstar, XpicScratch& s) {
  s.ensure(v1.extent(0));
  const LO n = static_cast<LO>(v1.extent(0));
  {
    auto vs = vstar, vk = s.vk, dvk = s.dvk;
    small_for(
        "xpic_start", n, KOKKOS_LAMBDA(const LO i) {
          vs(i) = 0.0;
          vk(i) = v1(i);
          dvk(i) = dv1(i);
        });
  }
  for (int k = 2; k <= m; ++k) {
    // Dv*_k is needed up to k = m - 1 (its factor (m - k)/k is 0 at k = m): the last sweep is v's alone.
    const bool dv_sweep = k < m;
    sps_sums2<dim, Shape>(g, M, p, sts, s.vk, s.dvk, s.acc1, s.acc2, dv_sweep);
    const double fv = double(m + 1 - k) / k, fd = double(m - k) / k, fm = double(m - 1) / m;
    const double sign = k % 2 == 0 ? 1.0 : -1.0;
    auto vk = s.vk, dvk = s.dvk, vk1 = s.vk1, dvk1 = s.dvk1;
    auto flag = bc.flag;
    const bool has_bc = flag.extent(0) > 0;
    small_for(
        "xpic_step", n, KOKKOS_LAMBDA(const LO i) {
          const LO node = i / (dim * M), c = i % dim;
          double nv, nd;
          if (has_bc && flag(node * dim + c)) {
            nv = fv * vk(i);
            nd = fd * dvk(i);
          } else {
            const double mi = gmass(i / dim);  // S+S in = sums / m_i^alpha
            nv = fv * (mi > 0 ? vk1(i) / mi : 0.0);
            nd = dv_sweep ? fd * (mi > 0 ? dvk1(i) / mi : 0.0) : 0.0;  // fd = 0 at k = m
          }
          vstar(i) += sign * (nv + fm * dvk(i));
          vk(i) = nv;
          dvk(i) = nd;
        });
  }
}

}  // namespace bfemp::xmpm
