#include "contact/barrier_term.hpp"

#include <Kokkos_Sort.hpp>
#include <Kokkos_Timer.hpp>
#include <algorithm>
#include <climits>
#include <limits>
#include <type_traits>

#include "contact/pair_couplings.hpp"
#include "contact/particle_expansion.hpp"
#include "kernels/contact/ccd.hpp"
#include "kernels/contact/pair_projection.hpp"

namespace bfemp {

namespace {

// Squared distance of pair (particle q, primitive j) at x.
template <int dim, class Prims>
KOKKOS_INLINE_FUNCTION double pair_distance2(const Prims& prims, const ConstDofView& x, const ConstDofView& xq,
                                             LO q, LO j) {
  double d2 = 0;
  dispatch_nv<dim>(prims.count(j), [&](auto NV) {
    constexpr int nv = decltype(NV)::value;
    Vec<dim> v[nv];
    for (int i = 0; i < nv; ++i) v[i] = load_vec<dim>(x, prims.nodes(j, i));
    d2 = stencil_distance2_value<dim, nv>(load_vec<dim>(xq, q), v);
  });
  return d2;
}

// Drops the pairs of an FEM body's boundary node with the body's own facets.
template <int dim>
struct PairFilter {
  ParticleStencils<dim> ps;
  BoundaryPrimitives<dim> prims;
  KOKKOS_INLINE_FUNCTION bool operator()(LO q, LO j) const { return contact_allowed<dim>(ps, prims, q, j); }
};

constexpr double kCcdStepMax = kStepBoundCap;  // the solver takes 0.9 of the bound, capped at 1

// Adds the seconds of its scope (after a fence) to a counter.
struct ScopeTimer {
  double& acc;
  Kokkos::Timer t;
  explicit ScopeTimer(double& a) : acc(a) {}
  ~ScopeTimer() {
    Kokkos::fence();
    acc += t.seconds();
  }
};

}  // namespace

template <int dim>
BarrierTerm<dim>::BarrierTerm(BoundaryPrimitives<dim> prims, double dhat, double kappa)
    : prims_(prims), dhat_(dhat), kappa_(kappa), ccd_min_(std::numeric_limits<double>::infinity()) {}

template <int dim>
void BarrierTerm<dim>::begin_step(const ParticleStencils<dim>& ps, ConstDofView x, const ParticleCells<dim>* cells) {
  ps_ = ps;
  have_cells_ = cells != nullptr;
  if (cells) {
    if (static_cast<LO>(cells->order.extent(0)) > ps.size())
      throw std::logic_error("BarrierTerm::begin_step: the cells bin more particles than the stencils hold");
    cells_ = *cells;
    sums_.reserve(static_cast<LO>(cells->order.extent(0)));
  }
  const std::size_t n = static_cast<std::size_t>(ps.size()) * dim;
  if (xq_.extent(0) != n) {
    xq_ = Kokkos::View<double*, MemSpace>("contact_xq", n);
    dq_ = Kokkos::View<double*, MemSpace>("contact_dq", n);
  }
  // The graph's pairs: those within (1 + margin) dhat, a superset of the
  // pairs within dhat (energy, gradient and Hessian skip pairs at d >= dhat).
  // Their particles are the step's first candidates.
  find_pairs_all(x, ConstDofView(), dhat_ * (1.0 + graph_margin_));
  {
    ScopeTimer timer(timings_.broad_phase_s);
    keep_candidates(x, dhat_ * (1.0 + graph_margin_));
  }
  // Signature of the couplings: each pair with its particle's stencil base
  // node (the stencil's other nodes follow from it while the MPM cells are
  // unchanged; when they change, the MPM term's version forces a rebuild).
  // The broad phase returns the pairs sorted by (particle, facet), so two
  // signatures are equal iff they are equal entry by entry: compared on the
  // device, no host copy unless the graph must change.
  if (static_cast<LO>(signature_dev_.extent(0)) < n_pairs_)  // grows, not per step
    signature_dev_ = Kokkos::View<long long* [2], MemSpace>("contact_graph_signature", n_pairs_ + n_pairs_ / 4 + 16);
  const auto sig_dev = signature_dev_;
  const auto pairs = pairs_;
  const auto nodes = ps.nodes;
  const long long np = prims_.size();
  Kokkos::parallel_for(
      "contact_graph_signature", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_), KOKKOS_LAMBDA(const LO k) {
        sig_dev(k, 0) = pairs(k, 0) * np + pairs(k, 1);
        sig_dev(k, 1) = nodes(pairs(k, 0), 0);
      });
  // The graph holds exactly these pairs with these stencils only if the last
  // step did not grow it (grown pairs were recorded with that step's stencils).
  if (n_pairs_ == n_signature_ && !grown_) {
    const auto prev = graph_signature_;
    LO differ = 0;
    Kokkos::parallel_reduce(
        "contact_graph_signature_compare", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_),
        KOKKOS_LAMBDA(const LO k, LO& acc) {
          if (sig_dev(k, 0) != prev(k, 0) || sig_dev(k, 1) != prev(k, 1)) ++acc;
        },
        differ);
    if (differ == 0) return;
  }
  grown_ = false;
  if (static_cast<LO>(graph_signature_.extent(0)) < n_pairs_)
    graph_signature_ = Kokkos::View<long long* [2], MemSpace>("contact_graph_signature_kept", signature_dev_.extent(0));
  const auto kept = graph_signature_;
  Kokkos::parallel_for(
      "contact_graph_signature_keep", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_), KOKKOS_LAMBDA(const LO k) {
        kept(k, 0) = sig_dev(k, 0);
        kept(k, 1) = sig_dev(k, 1);
      });
  n_signature_ = n_pairs_;
  ++version_;
  // The graph changes: its pairs' keys, for add_couplings and update().
  graph_keys_dev_ = Kokkos::View<long long*, MemSpace>("contact_graph_keys", static_cast<std::size_t>(n_pairs_));
  const auto keys = graph_keys_dev_;
  Kokkos::parallel_for(
      "contact_graph_keys", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_),
      KOKKOS_LAMBDA(const LO k) { keys(k) = sig_dev(k, 0); });
}

// Particle positions (and sweeps) of every particle at x (p), for a search.
template <int dim>
void BarrierTerm<dim>::interpolate_all(ConstDofView x, ConstDofView p) {
  interpolate_particles(ps_, x, xq_);
  if (p.extent(0) > 0) interpolate_particles(ps_, p, dq_);
}

template <int dim>
void BarrierTerm<dim>::find_pairs_all(ConstDofView x, ConstDofView p, double pad, bool interpolated) {
  ScopeTimer timer(timings_.broad_phase_s);
  ++timings_.searches_all;
  const bool moving = p.extent(0) > 0;
  if (!interpolated) interpolate_all(x, p);
  point_boxes<dim>(xq_, moving ? ConstDofView(dq_) : ConstDofView(), 0.0, particle_boxes_);
  simplex_boxes<dim, dim>(prims_.nodes, x, p, pad, prim_boxes_);
  hash_.build(prim_boxes_);
  if (prims_.size() == 0 || ps_.size() == 0) {
    n_pairs_ = 0;
  } else if (ps_.fem_body_base == INT_MAX) {  // particles only: every pair may touch
    n_pairs_ = hash_.query(particle_boxes_, pairs_);
  } else {  // FEM points too: not against their own body
    n_pairs_ = hash_.query(particle_boxes_, pairs_, PairFilter<dim>{ps_, prims_});
  }
  find_segments();
}

// The particles of the pairs just found (xq_ holds every particle at x).
template <int dim>
void BarrierTerm<dim>::keep_candidates(ConstDofView x, double reach) {
  if (static_cast<LO>(cand_.extent(0)) < n_segments_)  // grows, not per step
    cand_ = Kokkos::View<LO*, MemSpace>("contact_candidates", n_segments_ + n_segments_ / 4 + 16);
  if (x_cand_.extent(0) < x.extent(0))  // grows with headroom (the active nodes change from step to step)
    x_cand_ = Kokkos::View<double*, MemSpace>("contact_candidates_x", x.extent(0) + x.extent(0) / 4 + 16);
  if (xq_cand_.extent(0) != xq_.extent(0))
    xq_cand_ = Kokkos::View<double*, MemSpace>("contact_candidates_xq", xq_.extent(0));
  n_x_cand_ = x.extent(0);
  const auto cand = cand_;
  const auto pairs = pairs_;
  const auto seg = segments_;
  Kokkos::parallel_for(
      "contact_candidates", Kokkos::RangePolicy<ExecSpace>(0, n_segments_),
      KOKKOS_LAMBDA(const LO s) { cand(s) = pairs(seg(s), 0); });  // pairs sorted by particle: ascending
  n_cand_ = n_segments_;
  Kokkos::deep_copy(Kokkos::subview(x_cand_, std::make_pair(std::size_t(0), n_x_cand_)), x);
  Kokkos::deep_copy(xq_cand_, xq_);
  cand_reach_ = reach;
}

// With every particle interpolated at x (and p): whether the candidates hold
// every pair of a search with this pad, by the particles' own displacements
// since the candidates were found and sweeps, and the primitives' vertices'.
template <int dim>
bool BarrierTerm<dim>::candidates_cover(ConstDofView x, ConstDofView p, double pad) const {
  if (!(cand_reach_ >= 0.0) || n_x_cand_ != x.extent(0) || xq_cand_.extent(0) != xq_.extent(0)) return false;
  const bool moving = p.extent(0) > 0;
  const auto xq = xq_, dq = dq_, xqc = xq_cand_, xc = x_cand_;
  double particles = 0, vertices = 0;  // max over each of displacement + sweep (inf-norm)
  Kokkos::parallel_reduce(
      "contact_candidates_particles", Kokkos::RangePolicy<ExecSpace>(0, ps_.size()),
      KOKKOS_LAMBDA(const LO q, double& acc) {
        double d = 0, w = 0;
        for (int c = 0; c < dim; ++c) {
          d = std::fmax(d, std::fabs(xq(q * dim + c) - xqc(q * dim + c)));
          if (moving) w = std::fmax(w, std::fabs(dq(q * dim + c)));
        }
        acc = std::fmax(acc, d + w);
      },
      Kokkos::Max<double>(particles));
  const auto nodes = prims_.nodes;
  Kokkos::parallel_reduce(
      "contact_candidates_vertices", Kokkos::RangePolicy<ExecSpace>(0, prims_.size()),
      KOKKOS_LAMBDA(const LO j, double& acc) {
        for (int i = 0; i < dim; ++i) {
          const LO n = nodes(j, i);  // a primitive's unused slots repeat its first vertex
          double d = 0, w = 0;
          for (int c = 0; c < dim; ++c) {
            d = std::fmax(d, std::fabs(x(n * dim + c) - xc(n * dim + c)));
            if (moving) w = std::fmax(w, std::fabs(p(n * dim + c)));
          }
          acc = std::fmax(acc, d + w);
        }
      },
      Kokkos::Max<double>(vertices));
  // A relative 1e-12 of the reach for the rounding of boxes. (fmax skips a
  // NaN; the Newton solver stops on a direction that is not finite before
  // any search along it.)
  return particles + vertices <= (cand_reach_ - pad) - 1e-12 * cand_reach_;
}

// Maps a candidate's index to its particle for the pair filter.
template <int dim>
struct CandidateFilter {
  Kokkos::View<LO*, MemSpace> cand;
  PairFilter<dim> f;
  KOKKOS_INLINE_FUNCTION bool operator()(LO c, LO j) const { return f(cand(c), j); }
};

template <int dim>
void BarrierTerm<dim>::find_pairs(ConstDofView x, ConstDofView p, double pad_in) {
  const double pad = pad_in < 0 ? dhat_ : pad_in;
  const bool moving = p.extent(0) > 0;
  {
    ScopeTimer timer(timings_.broad_phase_s);
    interpolate_all(x, p);
  }
  if (!candidate_search_) {
    find_pairs_all(x, p, pad, true);
    return;
  }
  bool covered;
  {
    ScopeTimer timer(timings_.broad_phase_s);
    covered = candidates_cover(x, p, pad);
  }
  if (!covered) {
    // New candidates: a search over all particles with this call's sweep and
    // the primitives padded by reach R > pad. Its particles hold this call's
    // pairs, and (its boxes holding the positions at x) those of later
    // searches as the header says.
    const double reach = pad + dhat_ * std::fmax(graph_margin_, 1.0);
    find_pairs_all(x, p, reach, true);
    ScopeTimer timer(timings_.broad_phase_s);
    keep_candidates(x, reach);
  }
  ScopeTimer timer(timings_.broad_phase_s);
  ++timings_.searches;
  const LO nc = n_cand_;
  const auto cand = cand_;
  const auto xq = xq_, dq = dq_;
  particle_boxes_.resize(nc);
  const auto lo = particle_boxes_.lo, hi = particle_boxes_.hi;
  Kokkos::parallel_for(
      "contact_candidate_boxes", Kokkos::RangePolicy<ExecSpace>(0, nc), KOKKOS_LAMBDA(const LO c) {
        const LO q = cand(c);
        for (int d = 0; d < dim; ++d) {
          const double a = xq(q * dim + d), b = moving ? a + dq(q * dim + d) : a;
          lo(c, d) = std::fmin(a, b);
          hi(c, d) = std::fmax(a, b);
        }
      });
  simplex_boxes<dim, dim>(prims_.nodes, x, p, pad, prim_boxes_);
  hash_.build(prim_boxes_);
  if (prims_.size() == 0 || nc == 0) {
    n_pairs_ = 0;
  } else if (ps_.fem_body_base == INT_MAX) {
    n_pairs_ = hash_.query(particle_boxes_, pairs_);
  } else {
    n_pairs_ = hash_.query(particle_boxes_, pairs_, CandidateFilter<dim>{cand, PairFilter<dim>{ps_, prims_}});
  }
  // candidate index -> particle (ascending: the pairs stay sorted by particle, then primitive)
  const auto pairs = pairs_;
  Kokkos::parallel_for(
      "contact_candidate_pairs", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_),
      KOKKOS_LAMBDA(const LO k) { pairs(k, 0) = cand(pairs(k, 0)); });
  find_segments();
}

template <int dim>
void BarrierTerm<dim>::find_segments() {
  n_segments_ = particle_segments(pairs_, n_pairs_, segments_);
}

template <int dim>
bool BarrierTerm<dim>::update(ConstDofView x) {
  find_pairs(x, ConstDofView());
  ScopeTimer timer(timings_.broad_phase_s);
  const auto keys = graph_keys_dev_;
  const auto pairs = pairs_;
  const long long np = prims_.size();
  const long long nk = static_cast<long long>(keys.extent(0));
  LO missing = 0;
  Kokkos::parallel_reduce(
      "contact_graph_check", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_),
      KOKKOS_LAMBDA(const LO k, LO& acc) {
        const long long key = pairs(k, 0) * np + pairs(k, 1);
        long long lo = 0, hi = nk;  // lower bound
        while (lo < hi) {
          const long long mid = (lo + hi) / 2;
          if (keys(mid) < key) lo = mid + 1;
          else hi = mid;
        }
        if (lo == nk || keys(lo) != key) ++acc;
      },
      missing);
  if (missing == 0) return false;
  // The graph's keys and these pairs', sorted (Kokkos::sort: std::sort on a
  // host execution space), without repeats (a parallel scan).
  const long long n_all = nk + n_pairs_;
  Kokkos::View<long long*, MemSpace> all(Kokkos::ViewAllocateWithoutInitializing("contact_graph_keys_all"), n_all);
  Kokkos::parallel_for(
      "contact_graph_keys_all", Kokkos::RangePolicy<ExecSpace>(0, n_all), KOKKOS_LAMBDA(const long long i) {
        all(i) = i < nk ? keys(i) : pairs(i - nk, 0) * np + pairs(i - nk, 1);
      });
  Kokkos::sort(all);
  Kokkos::View<long long*, MemSpace> merged(Kokkos::ViewAllocateWithoutInitializing("contact_graph_keys"), n_all);
  long long n_merged = 0;
  Kokkos::parallel_scan(
      "contact_graph_keys_unique", Kokkos::RangePolicy<ExecSpace>(0, n_all),
      KOKKOS_LAMBDA(const long long i, long long& at, const bool final) {
        if (i > 0 && all(i) == all(i - 1)) return;
        if (final) merged(at) = all(i);
        ++at;
      },
      n_merged);
  graph_keys_dev_ = Kokkos::subview(merged, std::make_pair(0LL, n_merged));
  ++version_;
  grown_ = true;
  return true;
}

template <int dim>
void BarrierTerm<dim>::prepare_direction(ConstDofView x, ConstDofView p) {
  find_pairs(x, p);
}

template <int dim>
void BarrierTerm<dim>::add_couplings(NodeGraphBuilder& graph) const {
  const auto keys = graph_keys_dev_;  // sorted: by particle
  const long long np = prims_.size();
  add_pair_couplings(
      graph, static_cast<long>(keys.extent(0)), KOKKOS_LAMBDA(const long k) { return static_cast<LO>(keys(k) / np); },
      KOKKOS_LAMBDA(const long k) { return static_cast<LO>(keys(k) % np); }, ps_.nodes, prims_.nodes, prims_.count);
}

template <int dim>
double BarrierTerm<dim>::energy(ConstDofView x) const {
  if (n_pairs_ == 0) return 0.0;
  ScopeTimer timer(timings_.evaluation_s);
  interpolate_pair_particles(ps_, pairs_, segments_, n_segments_, x, xq_);
  const auto pairs = pairs_;
  const auto prims = prims_;
  const auto ps = ps_;
  const ConstDofView xq = xq_;
  const double dhat = dhat_, kappa = kappa_;
  double e = 0;
  Kokkos::parallel_reduce(
      "barrier_energy", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_),
      KOKKOS_LAMBDA(const LO k, double& acc) {
        const LO q = pairs(k, 0), j = pairs(k, 1);
        const double d2 = pair_distance2<dim>(prims, x, xq, q, j);
        if (d2 < dhat * dhat) acc += ps.omega(q) * prims.coef(j) * barrier(std::sqrt(d2), dhat, kappa);
      },
      e);
  return e;
}

template <int dim>
template <class Body>
void BarrierTerm<dim>::for_each_pair(ConstDofView x, const Body& body) const {
  ScopeTimer timer(timings_.evaluation_s);
  interpolate_pair_particles(ps_, pairs_, segments_, n_segments_, x, xq_);
  const auto pairs = pairs_;
  const auto prims = prims_;
  const auto ps = ps_;
  const ConstDofView xq = xq_;
  const double dhat = dhat_, kappa = kappa_;
  Kokkos::parallel_for(
      "barrier_pairs", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_), KOKKOS_LAMBDA(const LO k) {
        const LO q = pairs(k, 0), j = pairs(k, 1);
        dispatch_nv<dim>(prims.count(j), [&](auto NV) {
          constexpr int nv = decltype(NV)::value;
          constexpr int L = (1 + nv) * dim;
          Vec<dim> v[nv];
          for (int i = 0; i < nv; ++i) v[i] = load_vec<dim>(x, prims.nodes(j, i));
          const Vec<dim> p = load_vec<dim>(xq, q);
          if (!(stencil_distance2_value<dim, nv>(p, v) < dhat * dhat)) return;
          const Distance2<L> s = stencil_distance2<dim, nv>(p, v);
          Eigen::Matrix<double, L, 1> g;
          SquareMat<L> H;
          barrier_of_distance2<L>(s, dhat, kappa, ps.omega(q) * prims.coef(j), g, H);
          PairDofs<dim> pd;
          fill_pair_dofs<dim>(ps, prims, q, j, nv, pd);
          body(q, pd, g, H);
        });
      });
}

// Per particle q with stencil weights w_a at nodes n_a, over its pairs with
// local gradient g = (g_p, g_v1..) and Hessian H = [H_pp H_pv; H_vp H_vv]:
// sum_a w_a sum_pairs g_p into node a, and the blocks w_a w_b sum_pairs H_pp
// into (n_a, n_b), once per particle; the vertex parts (g_v, w_a H_pv, H_vv)
// per pair. The same sums as expanding each pair alone (scatter_pair), in
// another order: a particle with P pairs adds ns^2 + P (2 ns nv + nv^2)
// blocks instead of P (ns + nv)^2. On one thread the adds are plain (no
// other thread to race with; an atomic add on a double is a locked
// compare-and-swap loop on x86), in the same order, so the sums are the same.
template <int dim>
void BarrierTerm<dim>::assemble_by_particle(ConstDofView x, const Sink<dim>& sink_in, bool hessian) const {
  ScopeTimer timer(timings_.evaluation_s);
  Sink<dim> sink = sink_in;
  if (ExecSpace().concurrency() == 1) sink.atomic = false;
  interpolate_pair_particles(ps_, pairs_, segments_, n_segments_, x, xq_);
  const auto pairs = pairs_;
  const auto seg = segments_;
  const auto prims = prims_;
  const auto ps = ps_;
  const ConstDofView xq = xq_;
  const double dhat = dhat_, kappa = kappa_;
  const bool matrix = hessian && sink.has_matrix();
  const bool project = project_ && sink.project;
  const double keep = sink.contact_keep;
  constexpr int ns = ParticleStencils<dim>::ns;
  // With the cells, an assembly's particle sums are expanded cell by cell
  // after this pass (the gradient alone is cheap enough straight away).
  const bool by_cell = matrix && cell_expansion();
  const LO n_cell_points = by_cell ? sums_.capacity() : 0;
  const auto sums = sums_;
  Kokkos::parallel_for(
      "barrier_pairs_by_particle", Kokkos::RangePolicy<ExecSpace>(0, n_segments_), KOKKOS_LAMBDA(const LO s) {
        const LO q = pairs(seg(s), 0);
        const Vec<dim> p = load_vec<dim>(xq, q);
        Vec<dim> gp = Vec<dim>::Zero();
        Mat<dim> Hpp = Mat<dim>::Zero();
        bool any = false;
        for (LO k = seg(s); k < seg(s + 1); ++k) {
          const LO j = pairs(k, 1);
          dispatch_nv<dim>(prims.count(j), [&](auto NV) {
            constexpr int nv = decltype(NV)::value;
            constexpr int L = (1 + nv) * dim;
            Vec<dim> v[nv];
            LO vn[nv];
            for (int i = 0; i < nv; ++i) {
              vn[i] = prims.nodes(j, i);
              v[i] = load_vec<dim>(x, vn[i]);
            }
            if (!(stencil_distance2_value<dim, nv>(p, v) < dhat * dhat)) return;
            const Distance2<L> d = stencil_distance2<dim, nv>(p, v);
            Eigen::Matrix<double, L, 1> g;
            SquareMat<L> H;
            barrier_of_distance2<L>(d, dhat, kappa, ps.omega(q) * prims.coef(j), g, H);
            any = true;
            for (int c = 0; c < dim; ++c) gp(c) += g(c);
            for (int i = 0; i < nv; ++i)
              for (int c = 0; c < dim; ++c) sink.add_gradient(vn[i], c, g((1 + i) * dim + c));
            if (!matrix) return;
            if (project) project_pair_hessian<dim, L>(d, H, keep);
            for (int r = 0; r < dim; ++r)
              for (int c = 0; c < dim; ++c) Hpp(r, c) += H(r, c);
            for (int i = 0; i < nv; ++i) {
              const int bi = (1 + i) * dim;
              for (int l = 0; l < nv; ++l) {
                const int bl = (1 + l) * dim;
                sink.add_block(vn[i], vn[l], [&](int r, int c) { return H(bi + r, bl + c); });
              }
              for (int a = 0; a < ns; ++a) {
                const double w = ps.w(q, a);
                if (w == 0.0) continue;  // a B-spline weight of 0 adds nothing
                const LO na = ps.nodes(q, a);
                sink.add_block(na, vn[i], [&](int r, int c) { return w * H(r, bi + c); });
                sink.add_block(vn[i], na, [&](int r, int c) { return w * H(bi + r, c); });
              }
            }
          });
        }
        if (!any) return;
        if (q < n_cell_points) sums.store(q, gp, Hpp);
        else expand_particle_sums<dim>(ps, q, gp, Hpp, matrix, sink);
      });
  if (by_cell) expand_by_cell<dim>(cells_, ps_, sums_, sink);
}

template <int dim>
void BarrierTerm<dim>::gradient(ConstDofView x, double scale, DofView grad) const {
  if (n_pairs_ == 0) return;
  Sink<dim> sink;  // gradient only
  sink.grad = grad;
  sink.scale = scale;
  assemble_by_particle(x, sink, false);
}

template <int dim>
void BarrierTerm<dim>::assemble(ConstDofView x, const Sink<dim>& sink) const {
  if (n_pairs_ == 0) return;
  assemble_by_particle(x, sink, true);
}

template <int dim>
void BarrierTerm<dim>::particle_forces(ConstDofView x, DofView f) const {
  Kokkos::deep_copy(f, 0.0);
  if (n_pairs_ == 0) return;
  for_each_pair(x, [=](LO q, const PairDofs<dim>&, const auto& g, const auto&) {
    for (int c = 0; c < dim; ++c) Kokkos::atomic_add(&f(q * dim + c), -g(c));
  });
}

template <int dim>
double BarrierTerm<dim>::max_step(ConstDofView x, ConstDofView p) const {
  if (n_pairs_ == 0) return std::numeric_limits<double>::infinity();
  ScopeTimer timer(timings_.ccd_s);
  interpolate_pair_particles(ps_, pairs_, segments_, n_segments_, x, xq_);
  interpolate_pair_particles(ps_, pairs_, segments_, n_segments_, p, dq_);
  const auto pairs = pairs_;
  const auto prims = prims_;
  const ConstDofView xq = xq_, dq = dq_;
  double tmin = kCcdStepMax;
  Kokkos::parallel_reduce(
      "barrier_ccd", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_),
      KOKKOS_LAMBDA(const LO k, double& acc) {
        const LO q = pairs(k, 0), j = pairs(k, 1);
        if (prims.count(j) != dim) return;  // nodes and edges lie on the facets
        Vec<dim> v[dim], dv[dim];
        for (int i = 0; i < dim; ++i) {
          v[i] = load_vec<dim>(x, prims.nodes(j, i));
          dv[i] = load_vec<dim>(p, prims.nodes(j, i));
        }
        const Vec<dim> xp = load_vec<dim>(xq, q), dp = load_vec<dim>(dq, q);
        double t;
        if constexpr (dim == 2) t = point_edge_ccd<2>(xp, v[0], v[1], dp, dv[0], dv[1], kCcdStepMax);
        else t = point_triangle_ccd(xp, v[0], v[1], v[2], dp, dv[0], dv[1], dv[2], kCcdStepMax);
        if (t < acc) acc = t;
      },
      Kokkos::Min<double>(tmin));
  if (tmin >= kCcdStepMax) return std::numeric_limits<double>::infinity();
  ccd_min_ = std::min(ccd_min_, tmin);
  return tmin;
}

template <int dim>
typename BarrierTerm<dim>::Timings BarrierTerm<dim>::take_timings() {
  const Timings t = timings_;
  timings_ = Timings{};
  return t;
}

template <int dim>
double BarrierTerm<dim>::take_ccd_min() {
  const double t = ccd_min_;
  ccd_min_ = std::numeric_limits<double>::infinity();
  return t;
}

template <int dim>
typename BarrierTerm<dim>::ActivePairs BarrierTerm<dim>::active_pairs(ConstDofView x) {
  find_pairs(x, ConstDofView());
  ActivePairs out;
  // Buffers grow and are kept (not per call): capacity >= count.
  if (static_cast<LO>(pair_distance_.extent(0)) < n_pairs_)
    pair_distance_ = Kokkos::View<double*, MemSpace>("contact_pair_distance", n_pairs_ + n_pairs_ / 4 + 16);
  const auto dist = pair_distance_;
  const auto pairs = pairs_;
  const auto prims = prims_;
  const auto ps = ps_;
  const ConstDofView xq = xq_;
  const double dhat = dhat_, kappa = kappa_;
  Kokkos::parallel_for(
      "contact_pair_distance", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_), KOKKOS_LAMBDA(const LO k) {
        dist(k) = std::sqrt(pair_distance2<dim>(prims, x, xq, pairs(k, 0), pairs(k, 1)));
      });
  LO count = 0;
  Kokkos::parallel_reduce(
      "contact_active_count", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_),
      KOKKOS_LAMBDA(const LO k, LO& acc) { acc += dist(k) < dhat ? 1 : 0; }, count);
  out.count = count;
  if (static_cast<LO>(active_.distance.extent(0)) < count) {
    const LO cap = count + count / 4 + 16;
    active_.pairs = Kokkos::View<LO* [2], MemSpace>("contact_active_pairs", cap);
    active_.distance = Kokkos::View<double*, MemSpace>("contact_active_distance", cap);
    active_.lambda = Kokkos::View<double*, MemSpace>("contact_active_lambda", cap);
  }
  out.pairs = active_.pairs;
  out.distance = active_.distance;
  out.lambda = active_.lambda;
  auto op = out.pairs;
  auto od = out.distance;
  auto ol = out.lambda;
  Kokkos::parallel_scan(
      "contact_active_compact", Kokkos::RangePolicy<ExecSpace>(0, n_pairs_),
      KOKKOS_LAMBDA(const LO k, LO& offset, const bool final) {
        if (!(dist(k) < dhat)) return;
        if (final) {
          const LO q = pairs(k, 0), j = pairs(k, 1);
          op(offset, 0) = q;
          op(offset, 1) = j;
          od(offset) = dist(k);
          ol(offset) = -ps.omega(q) * prims.coef(j) * barrier_first_derivative(dist(k), dhat, kappa);
        }
        ++offset;
      });
  return out;
}

template class BarrierTerm<2>;
template class BarrierTerm<3>;

}  // namespace bfemp
