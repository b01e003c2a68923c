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
  int friction_max_iterations = 20;  // outer friction loop cap per step
  std::vector<double> mu;  // [mpm body * n_fem + fem body]; empty: frictionless
  int force_body = -1;     // FEM body whose contact force is reported (-1: all)
  bool check_iterates = false;  // debug: every Newton iterate is checked for penetration
};

template <int dim>
class Contact {
 public:
  Contact(const FemMesh<dim>& mesh, ContactParams params);

  // Throws std::invalid_argument naming the particle when one starts inside
  // an FEM element or at distance <= 0 from the FEM boundary (x: FEM nodes).
  void check_initial(const Particles<dim>& p, ConstDofView x_fem) const;
  // Largest index of a particle inside or on an FEM element (-1: none), for
  // particle positions xp (node-interleaved) and FEM positions x (the first
  // FEM-node entries of x are read). particle_inside_at interpolates the
  // particles from the system DOFs x of this step (a debug check of iterates).
  LO particle_inside(ConstDofView xp, ConstDofView x) const;
  LO particle_inside_at(ConstDofView x) const;
  // How many particles (xp, node-interleaved) lie inside or on an FEM element.
  LO count_inside(ConstDofView xp, ConstDofView x) const;

  // Per step, after the MPM grid is activated: stencils and pairs near x^n.
  void begin_step(const MpmBodies<dim>& mpm, ConstDofView x);
  const BarrierTerm<dim>* barrier() const { return barrier_.get(); }
  const FrictionTerm<dim>* friction() const { return friction_.get(); }
  bool has_friction() const { return friction_ != nullptr; }
  // Re-lags friction at x (see FrictionTerm); returns the pairs with friction.
  LO update_friction(ConstDofView x, ConstDofView x_ref, double s, double dt);
  int friction_max_iterations() const { return params_.friction_max_iterations; }

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
  // Contact force per particle at the last report (node-interleaved).
  Kokkos::View<const double*, MemSpace> particle_forces() const { return particle_force_; }
  const ContactParams& params() const { return params_; }

 private:
  const FemMesh<dim>& mesh_;
  ContactParams params_;
  std::unique_ptr<BarrierTerm<dim>> barrier_;
  std::unique_ptr<FrictionTerm<dim>> friction_;
  ParticleStencils<dim> ps_;
  Kokkos::View<double*, MemSpace> grad_, particle_force_, report_xp_;
  mutable SpatialHash<dim> element_hash_;
  mutable Boxes<dim> element_boxes_, point_boxes_;
  mutable Kokkos::View<LO* [2], MemSpace> inside_pairs_;
  mutable Kokkos::View<int*, MemSpace> inside_flag_;
};

}  // namespace bfemp
