#pragma once
// Barrier contact between the MPM bodies and the FEM bodies of a scene (paper
// §4, Algorithm 1): the FEM boundary primitives (built once), the particles'
// interpolation stencils (per step), the barrier term and, when any pair of
// bodies has mu > 0, the lagged friction term; the start-up check that no
// particle starts inside or on an FEM body; per-step contact diagnostics.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "contact/friction_term.hpp"
#include "mpm/mpm_bodies.hpp"

namespace bfemp {

struct ContactParams {
  double dhat = 1e-3;    // m, contact activation distance
  double kappa = 1e5;    // Pa, barrier stiffness
  double eps_v = 1e-3;   // m/s, static-friction velocity bound
  // The step's matrix graph holds the pairs within (1 + graph_margin) dhat at
  // x^n, so pairs the Newton iterates bring within dhat are mostly in it
  // already (no rebuild, no new symbolic analysis inside the step).
  double graph_margin = 3.0;
  int friction_max_iterations = 20;  // outer friction loop cap per step
  // The friction loop's passes stop Newton at this multiple of Newton/eps_d
  // until a pass converges within it at its first iteration; the passes
  // after that stop at eps_d (Simulation::minimize_with_friction). 1: every
  // pass at eps_d.
  double friction_pass_tolerance = 10.0;
  // From this pass on the friction loop lags at an Aitken-relaxed point
  // (Simulation::minimize_with_friction); 0: never (plain lagging).
  int friction_relaxation_from = 7;
  std::vector<double> mu;  // [mpm body * n_fem + fem body]; empty: frictionless
  int force_body = -1;     // FEM body whose contact force is reported (-1: all)
  bool check_iterates = false;  // debug: every Newton iterate is checked for penetration
  // FEM-FEM contact (2D): the boundary nodes of every FEM body against the
  // facets of every other FEM body, beside the particles; mu then has
  // (mpm_bodies + n_fem) * n_fem entries, FEM body a against FEM body b at
  // [(mpm_bodies + a) * n_fem + b].
  bool fem_fem = false;
  int mpm_bodies = 0;  // MPM bodies of the scene
};

template <int dim>
class Contact {
 public:
  Contact(const FemMesh<dim>& mesh, ContactParams params);

  // Throws std::invalid_argument naming the particle when one starts inside
  // an FEM element or at distance <= 0 from the FEM boundary (x: FEM nodes).
  // With FEM-FEM contact it also runs check_initial_fem.
  // ids: the particles' scene indices for the message (MPI; empty: p's own).
  void check_initial(const Particles<dim>& p, ConstDofView x_fem,
                     Kokkos::View<const long long*, MemSpace> ids = {}) const;
  // FEM-FEM contact: throws naming the FEM node and its body when a boundary
  // node starts inside or on another FEM body.
  void check_initial_fem(ConstDofView x_fem) const;
  // Largest index of a particle inside or on an FEM element (-1: none), for
  // particle positions xp (node-interleaved) and FEM positions x (the first
  // FEM-node entries of x are read). particle_inside_at interpolates the
  // particles from the system DOFs x of this step (a debug check of iterates).
  LO particle_inside(ConstDofView xp, ConstDofView x) const;
  LO particle_inside_at(ConstDofView x) const;
  // How many particles (xp, node-interleaved) lie inside or on an FEM element.
  LO count_inside(ConstDofView xp, ConstDofView x) const;

  // Per step, after the MPM grid is activated: stencils and pairs near x^n
  // (mpm null: a scene of FEM bodies only, in contact with each other).
  void begin_step(const MpmBodies<dim>* mpm, ConstDofView x);
  void begin_step(const MpmBodies<dim>& mpm, ConstDofView x) { begin_step(&mpm, x); }
  // FEM-FEM contact: the boundary nodes taking part as contact points (in the
  // order they follow the particles), and their count.
  LO num_fem_points() const { return static_cast<LO>(fem_point_node_.extent(0)); }
  // The FEM node of contact point np + k (host; for messages).
  LO fem_point_node(LO k) const;
  // Several ranks, each holding the whole FEM mesh (Simulation's fem_shared_): keep
  // only the contact points whose node this rank owns (owned[node] != 0), so
  // that each FEM-FEM pair is evaluated by exactly one rank, as each particle's
  // pairs are by the rank holding the particle. The facets stay whole.
  void keep_fem_points(const std::vector<char>& owned);
  const BarrierTerm<dim>* barrier() const { return barrier_.get(); }
  BarrierTerm<dim>* barrier() { return barrier_.get(); }  // (the Newton solver updates its pairs)
  const FrictionTerm<dim>* friction() const { return friction_.get(); }
  FrictionTerm<dim>* friction() { return friction_.get(); }
  bool has_friction() const { return friction_ != nullptr; }
  // Re-lags friction at x (see FrictionTerm); returns the pairs with friction.
  LO update_friction(ConstDofView x, ConstDofView x_ref, double s, double dt);
  int friction_max_iterations() const { return params_.friction_max_iterations; }
  double friction_pass_tolerance() const { return params_.friction_pass_tolerance; }
  int friction_relaxation_from() const { return params_.friction_relaxation_from; }

  struct Report {
    LO pairs = 0;                   // pairs with d < dhat
    double min_distance = 0;        // over those pairs (inf: none)
    double barrier_energy = 0;      // B(x), J (J/m in 2D)
    double ccd_alpha_min = 0;       // smallest CCD step bound this step (inf: none)
    std::array<double, 3> force{};  // contact force on the FEM body (or all)
    // Bounding box of the particles (at x) in pairs with d < dhat against
    // the reported FEM body's boundary (or any); lo > hi when there is none.
    // Half its width is the Hertz contact half-width of VALIDATION A3.
    std::array<double, 3> extent_lo{0, 0, 0}, extent_hi{0, 0, 0};
    typename BarrierTerm<dim>::Timings timings;  // this step's contact seconds
  };
  // At the step's solution x (system DOFs; the first n_fem_nodes are FEM).
  Report report(ConstDofView x, LO n_fem_nodes);
  // Contact force per particle at the last report (node-interleaved; the
  // particles only, not the FEM points).
  Kokkos::View<const double*, MemSpace> particle_forces() const {
    const std::size_t n = static_cast<std::size_t>(n_particles_) * dim;
    if (particle_force_.extent(0) < n) return particle_force_;  // before the first report
    return Kokkos::subview(particle_force_, std::make_pair(std::size_t(0), n));
  }
  const ContactParams& params() const { return params_; }

 private:
  const FemMesh<dim>& mesh_;
  ContactParams params_;
  std::unique_ptr<BarrierTerm<dim>> barrier_;
  std::unique_ptr<FrictionTerm<dim>> friction_;
  ParticleStencils<dim> ps_;
  Kokkos::View<double*, MemSpace> grad_, particle_force_, report_xp_;
  // Scratch of the const inside-checks (check_initial, particle_inside,
  // count_inside): buffers kept for their capacity; no value outlives a call.
  mutable SpatialHash<dim> element_hash_;
  mutable Boxes<dim> element_boxes_, point_boxes_;
  mutable Kokkos::View<LO* [2], MemSpace> inside_pairs_;
  mutable Kokkos::View<int*, MemSpace> inside_flag_;
  // FEM-FEM: per contact point its FEM node, omega (m) and FEM body; per
  // element its FEM body; the particles of the current step.
  Kokkos::View<LO*, MemSpace> fem_point_node_;
  Kokkos::View<double*, MemSpace> fem_point_omega_;
  Kokkos::View<int*, MemSpace> fem_point_body_, element_body_;
  LO n_particles_ = 0;
  // Largest point of xp inside or on an FEM element, where points from
  // first_fem_point on are FEM nodes (fem_point_body_) that skip their own body.
  LO inside(ConstDofView xp, ConstDofView x, LO first_fem_point) const;
};

}  // namespace bfemp
