#pragma once
// The barrier contact energy between MPM particles and the FEM boundary
// (paper Eqs. 28-32) as a term of the incremental potential:
//   B(x) = sum_{pairs (q, j)} omega_q c_j b(d(x_q, primitive j), dhat)
// over the candidate pairs of a spatial hash (primitives padded by dhat). The
// pair set follows the Newton iterates: update(x) finds the pairs near x
// before each assembly, prepare_direction(x, p) the pairs the segment
// x + t p (t in [0, 1]) can reach, which serve the CCD step bound (max_step)
// and the line-search energies. The system graph holds every pair seen in the
// step; a pair outside it makes update() ask for a rebuild. Those searches
// query only the step's candidate particles (those near the FEM boundary at
// the step's start, within the graph's reach) while the particles and the
// boundary have not moved far enough for others to come near; every
// particle's position is still interpolated at each search, for that test.
// Evaluations (energy, gradient, Hessian, CCD) interpolate only the pairs'
// particles; with MPM cells (begin_step) in 3D, the Hessian's particle
// blocks are expanded cell by cell without atomics (particle_expansion.hpp).
#include <vector>

#include "contact/boundary_primitives.hpp"
#include "contact/particle_expansion.hpp"
#include "kernels/contact/broad_phase.hpp"
#include "kernels/contact/contact_pair.hpp"
#include "solver/energy_term.hpp"

namespace bfemp {

template <int dim>
class BarrierTerm : public EnergyTerm<dim> {
 public:
  BarrierTerm(BoundaryPrimitives<dim> prims, double dhat, double kappa);
  std::string name() const override { return "barrier contact"; }

  // New step: particle stencils of this step, pairs near x^n (the graph's).
  // cells (optional): this step's binning of the MPM particles (the first
  // cells->order.extent(0) points of ps) by cell; with it (and
  // set_cell_expansion), assemble() expands the particles' sums cell by
  // cell, without atomics (particle_expansion.hpp).
  void begin_step(const ParticleStencils<dim>& ps, ConstDofView x, const ParticleCells<dim>* cells = nullptr);
  // The binning begin_step was given (null: none).
  const ParticleCells<dim>* cells() const { return have_cells_ ? &cells_ : nullptr; }
  // Whether assemble() (and the friction term's) expands the particle blocks
  // cell by cell when it has the cells; default: in 3D only. In 3D a particle
  // block reaches 729 3x3 node blocks, and cell by cell halved the contact
  // assembly of the paper twist at 2 threads (barrier 1.81 -> 1.04 s,
  // friction 1.47 -> 0.71 s in its first twisting step); in 2D (81 2x2
  // blocks) the atomic adds cost less than the cell pass: bench_contact at
  // 1e5 particles and 2 threads, 102 -> 118 ms (barrier), 63 -> 78 ms
  // (friction); about even at 1 thread. (The tests turn it on in 2D and
  // compare with begin_step without cells.)
  void set_cell_expansion(bool on) { cell_expansion_ = on; }
  bool cell_expansion() const { return cell_expansion_ && have_cells_; }

  void add_couplings(NodeGraphBuilder& graph) const override;
  // Changes when this step's pairs (with their particles' stencils) differ
  // from those the graph was built with, or update() grew the graph.
  std::uint64_t couplings_version() const override { return version_; }
  double energy(ConstDofView x) const override;
  void gradient(ConstDofView x, double scale, DofView grad) const override;
  void assemble(ConstDofView x, const Sink<dim>& sink) const override;
  double max_step(ConstDofView x, ConstDofView p) const override;
  bool update(ConstDofView x) override;
  void prepare_direction(ConstDofView x, ConstDofView p) override;
  void set_projection(bool project) { project_ = project; }  // false: exact Hessian (tests)
  // begin_step's graph pairs: within (1 + margin) dhat of x^n (default 0).
  void set_graph_margin(double margin) { graph_margin_ = margin; }
  // false: every pair search over all particles, none among the step's
  // candidates (tests and timings; the pairs are the same).
  void set_candidate_search(bool on) { candidate_search_ = on; }

  // Pairs (particle, primitive) near x with d < dhat: their distance and the
  // normal force magnitude lambda = -omega c b'(d) (N in 3D, N/m in 2D).
  // The first `count` entries are valid (the Views are the term's own
  // buffers, capacity >= count, reused by the next call).
  struct ActivePairs {
    Kokkos::View<LO* [2], MemSpace> pairs;
    Kokkos::View<double*, MemSpace> distance, lambda;
    LO count = 0;
  };
  ActivePairs active_pairs(ConstDofView x);
  // Contact force on the particles (-dB/dx_q), node-interleaved per particle.
  void particle_forces(ConstDofView x, DofView f) const;

  // Smallest CCD bound returned since the last call (inf if none); resets.
  double take_ccd_min();
  // Seconds spent since the last call (resets): broad phase (pair finding and
  // graph checks), pair evaluation (energy, gradient, Hessian), CCD.
  // searches: pair searches among the step's candidate particles;
  // searches_all: those over every particle (begin_step's, new candidates
  // when the particles or the boundary moved too far for the step's, and
  // every search with set_candidate_search(false)).
  struct Timings { double broad_phase_s = 0, evaluation_s = 0, ccd_s = 0; long searches = 0, searches_all = 0; };
  Timings take_timings();
  const BoundaryPrimitives<dim>& primitives() const { return prims_; }
  const ParticleStencils<dim>& particles() const { return ps_; }
  double dhat() const { return dhat_; }
  double kappa() const { return kappa_; }
  LO candidate_pairs() const { return n_pairs_; }

 private:
  // Pairs whose boxes (primitives padded by pad, default dhat) overlap; p
  // empty: static. Among this step's candidate particles (below) while they
  // are sure to hold every such pair, else among all particles after new
  // candidates are found.
  void find_pairs(ConstDofView x, ConstDofView p, double pad = -1.0);
  void interpolate_all(ConstDofView x, ConstDofView p);
  // The same over every particle (begin_step, and the candidates' search);
  // interpolated: xq_ (dq_) already hold every particle at x (p).
  void find_pairs_all(ConstDofView x, ConstDofView p, double pad, bool interpolated = false);
  // Candidates: the particles of the pairs of a search over all particles at
  // x_c (swept or not) with the primitives padded by reach R. A particle q
  // outside them has, on some axis, a gap > R between its position x_q(x_c)
  // and every primitive's box at x_c. If since then the particles moved by
  // at most D_p (their own positions, interpolated) and the primitives'
  // vertices by at most D_v, and a search sweeps them by P_p and P_v, the gap
  // shrinks by at most D_p + P_p + D_v + P_v (each the largest of a
  // displacement plus a sweep), so a search with pad r needs no particle
  // outside them while that is <= R - r. Otherwise new candidates are found
  // by that search itself, over all particles, with R = r + the graph's
  // margin (at least dhat). Particle displacements, not grid-node ones: a
  // node that weighs next to nothing may move by kilometres in a direction.
  void keep_candidates(ConstDofView x, double reach);
  bool candidates_cover(ConstDofView x, ConstDofView p, double pad) const;
  template <class Body>
  void for_each_pair(ConstDofView x, const Body& body) const;
  // Segment starts of the (particle-sorted) pairs: one segment per particle.
  void find_segments();
  // Gradient (and with hessian the PSD-projected Hessian) of every pair, one
  // particle's pairs at a time: their particle blocks are summed first and
  // expanded through the particle's stencil once.
  void assemble_by_particle(ConstDofView x, const Sink<dim>& sink, bool hessian) const;

  BoundaryPrimitives<dim> prims_;
  double dhat_, kappa_;
  bool project_ = true;
  double graph_margin_ = 0.0;
  bool candidate_search_ = true;
  bool cell_expansion_ = dim == 3;
  ParticleStencils<dim> ps_;
  ParticleCells<dim> cells_;
  bool have_cells_ = false;
  // State: the pair set and what its searches keep, changed only by
  // begin_step, update, prepare_direction and active_pairs.
  SpatialHash<dim> hash_;
  Boxes<dim> prim_boxes_, particle_boxes_;
  Kokkos::View<LO*, MemSpace> cand_;       // candidate particles, ascending (capacity grows)
  LO n_cand_ = 0;
  Kokkos::View<double*, MemSpace> x_cand_;  // x where they were found (first n_x_cand_ entries)
  Kokkos::View<double*, MemSpace> xq_cand_;  // every particle's position there
  std::size_t n_x_cand_ = 0;
  double cand_reach_ = -1.0;               // their reach R (< 0: none this step)
  Kokkos::View<LO* [2], MemSpace> pairs_;
  LO n_pairs_ = 0;
  Kokkos::View<LO*, MemSpace> segments_;  // n_segments_ + 1 starts into pairs_ (capacity grows)
  LO n_segments_ = 0;
  Kokkos::View<long long*, MemSpace> graph_keys_dev_;  // the graph's pairs: q * n_prims + j, sorted
  // (pair key, stencil base) of each begin_step pair, in the broad phase's
  // (sorted) order: this step's, and those the graph was last asked for.
  Kokkos::View<long long* [2], MemSpace> signature_dev_, graph_signature_;
  LO n_signature_ = 0;
  Kokkos::View<double*, MemSpace> pair_distance_;
  std::uint64_t version_ = 0;
  bool grown_ = false;  // update() added pairs in this step
  ActivePairs active_;  // buffers of active_pairs()
  // Scratch of the evaluations (energy, gradient, assemble, max_step) and the
  // searches: positions (and sweeps) of the particles at the call's x (p),
  // and the particles' summed blocks. Kept for their capacity only: every
  // call writes what it reads first, so no value passes from one call to the
  // next (the sums' particle marks are all zero between calls: each
  // assemble() clears those it set, particle_expansion.hpp).
  mutable Kokkos::View<double*, MemSpace> xq_, dq_;
  mutable ParticleSums<dim> sums_;
  // Statistics for the step's report, never read by a computation.
  mutable double ccd_min_;
  mutable Timings timings_;
};

}  // namespace bfemp
