#pragma once
// The barrier contact energy between MPM particles and the FEM boundary
// (paper Eqs. 28-32) as a term of the incremental potential:
//   B(x) = sum_{pairs (q, j)} omega_q c_j b(d(x_q, primitive j), dhat)
// over the candidate pairs of a spatial hash (primitives padded by dhat). The
// pair set follows the Newton iterates: update(x) finds the pairs near x
// before each assembly, prepare_direction(x, p) the pairs the segment
// x + t p (t in [0, 1]) can reach, which serve the CCD step bound (max_step)
// and the line-search energies. The system graph holds every pair seen in the
// step; a pair outside it makes update() ask for a rebuild.
#include <vector>

#include "contact/boundary_primitives.hpp"
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
  void begin_step(const ParticleStencils<dim>& ps, ConstDofView x);

  void add_couplings(NodeGraphBuilder& graph) const override;
  // Changes when this step's pairs (with their particles' stencils) differ
  // from those the graph was built with, or update() grew the graph.
  std::uint64_t couplings_version() const override { return version_; }
  double energy(ConstDofView x) const override;
  void gradient(ConstDofView x, double scale, DofView grad) const override;
  void assemble(ConstDofView x, const Sink<dim>& sink) const override;
  double max_step(ConstDofView x, ConstDofView p) const override;
  bool update(ConstDofView x) const override;
  void prepare_direction(ConstDofView x, ConstDofView p) const override;
  void set_projection(bool project) { project_ = project; }  // false: exact Hessian (tests)
  // begin_step's graph pairs: within (1 + margin) dhat of x^n (default 0).
  void set_graph_margin(double margin) { graph_margin_ = margin; }

  // Pairs (particle, primitive) near x with d < dhat: their distance and the
  // normal force magnitude lambda = -omega c b'(d) (N in 3D, N/m in 2D).
  // The first `count` entries are valid (the Views are the term's own
  // buffers, capacity >= count, reused by the next call).
  struct ActivePairs {
    Kokkos::View<LO* [2], MemSpace> pairs;
    Kokkos::View<double*, MemSpace> distance, lambda;
    LO count = 0;
  };
  ActivePairs active_pairs(ConstDofView x) const;
  // Contact force on the particles (-dB/dx_q), node-interleaved per particle.
  void particle_forces(ConstDofView x, DofView f) const;

  // Smallest CCD bound returned since the last call (inf if none); resets.
  double take_ccd_min() const;
  // Seconds spent since the last call (resets): broad phase (pair finding and
  // graph checks), pair evaluation (energy, gradient, Hessian), CCD.
  struct Timings { double broad_phase_s = 0, evaluation_s = 0, ccd_s = 0; };
  Timings take_timings() const;
  const BoundaryPrimitives<dim>& primitives() const { return prims_; }
  const ParticleStencils<dim>& particles() const { return ps_; }
  double dhat() const { return dhat_; }
  double kappa() const { return kappa_; }
  LO candidate_pairs() const { return n_pairs_; }

 private:
  // Pairs whose boxes (primitives padded by pad, default dhat) overlap; p empty: static.
  void find_pairs(ConstDofView x, ConstDofView p, double pad = -1.0) const;
  template <class Body>
  void for_each_pair(ConstDofView x, const Body& body) const;
  // Segment starts of the (particle-sorted) pairs: one segment per particle.
  void find_segments() const;
  // Gradient (and with hessian the PSD-projected Hessian) of every pair, one
  // particle's pairs at a time: their particle blocks are summed first and
  // expanded through the particle's stencil once.
  void assemble_by_particle(ConstDofView x, const Sink<dim>& sink, bool hessian) const;

  BoundaryPrimitives<dim> prims_;
  double dhat_, kappa_;
  bool project_ = true;
  double graph_margin_ = 0.0;
  ParticleStencils<dim> ps_;
  mutable SpatialHash<dim> hash_;
  mutable Boxes<dim> prim_boxes_, particle_boxes_;
  mutable Kokkos::View<double*, MemSpace> xq_, dq_;
  mutable Kokkos::View<LO* [2], MemSpace> pairs_;
  mutable LO n_pairs_ = 0;
  mutable Kokkos::View<LO*, MemSpace> segments_;  // n_segments_ + 1 starts into pairs_ (capacity grows)
  mutable LO n_segments_ = 0;
  mutable Kokkos::View<long long*, MemSpace> graph_keys_dev_;  // the graph's pairs: q * n_prims + j, sorted
  // (pair key, stencil base) of each begin_step pair, in the broad phase's
  // (sorted) order: this step's, and those the graph was last asked for.
  Kokkos::View<long long* [2], MemSpace> signature_dev_, graph_signature_;
  LO n_signature_ = 0;
  mutable Kokkos::View<double*, MemSpace> pair_distance_;
  mutable std::uint64_t version_ = 0;
  mutable bool grown_ = false;  // update() added pairs in this step
  mutable ActivePairs active_;  // buffers of active_pairs()
  mutable double ccd_min_;
  mutable Timings timings_;
};

}  // namespace bfemp
