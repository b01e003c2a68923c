#pragma once
// Implicit elastodynamics of FEM bodies and MPM bodies in one Newton system
// (paper Algorithm 1 without contact): the unknowns are FEM node positions
// followed by the positions of the grid nodes the particles touch this step.
// Predictor, Newton minimisation of the incremental potential, Newmark /
// backward-Euler update, prescribed motion, P2G/G2P, per-step diagnostics.
#include <Teuchos_ParameterList.hpp>
#include <array>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "fem/fem_mesh.hpp"
#include "fem/fem_partition.hpp"
#include "contact/contact.hpp"
#include "fem/prescribed_motion.hpp"
#include "kernels/level_set.hpp"
#include "mpm/mpm_bodies.hpp"
#include "solver/newton.hpp"
#include "time/integrator.hpp"

namespace bfemp {

template <int dim>
struct SimulationSetup {
  std::vector<FemBodyInput> bodies;                     // FEM bodies
  std::vector<MaterialParams> materials;                // shared by FEM and MPM
  std::vector<std::array<double, 3>> initial_velocity;  // per FEM body (empty: at rest)
  std::vector<PrescribedMotion> motions;                // node ids are global FEM ids
  std::optional<MpmSetup<dim>> mpm;                     // MPM particles and grid
  std::vector<LevelSet> level_sets;                     // grid boundaries (MPM)
  std::optional<ContactParams> contact;                 // MPM-FEM barrier contact
  TimeIntegrator integrator = TimeIntegrator::backward_euler();
  std::array<double, 3> gravity{0, 0, 0};
  double dt = 1e-3;
  NewtonParams newton;
  Teuchos::ParameterList linear_solver;                 // resolved "Linear Solver" list
  bool count_penetrations = false;                      // StepReport::penetrations each step
};

// One body's share of a StepReport: mass, centre of mass (mass-weighted mean
// of node / particle positions, m), its velocity (m/s), kinetic and elastic
// energy (J, per unit thickness in 2D).
struct BodyReport {
  double mass = 0, kinetic = 0, elastic = 0;
  std::array<double, 3> com{0, 0, 0}, velocity{0, 0, 0};
};

struct StepReport {
  long step = 0;
  double time = 0, dt = 0;
  double kinetic = 0, elastic = 0, potential = 0;
  std::array<double, 3> momentum{0, 0, 0};
  double angular_momentum_z = 0;  // about the origin (FEM nodes + MPM particles)
  NewtonStats newton;
  double min_J = 0;
  long active_grid_nodes = 0;
  // Contact (zero without contact): pairs with d < dhat, their smallest
  // distance, B(x), outer friction iterations, the smallest CCD step bound,
  // the contact force on the reported FEM body.
  long contact_pairs = 0;
  double min_distance = 0, barrier_energy = 0, ccd_alpha_min = 0;
  int friction_iters = 0;
  std::array<double, 3> contact_force{0, 0, 0};
  // Box of the particles in contact with that body (NaN without pairs).
  std::array<double, 3> contact_lo{0, 0, 0}, contact_hi{0, 0, 0};
  // With SimulationSetup::count_penetrations: particles inside an FEM element
  // or inside a level set's solid at the end of the step, and the deepest
  // level-set penetration (m); -1 and NaN when not counted. The count split:
  // particles inside an FEM element, inside a level set's solid.
  long penetrations = -1;
  long penetrations_fem = -1, penetrations_level_set = -1;
  double penetration_depth = std::numeric_limits<double>::quiet_NaN();
  double contact_broad_phase_s = 0, contact_eval_s = 0, contact_ccd_s = 0;
  // pair searches, and those over every particle (BarrierTerm::Timings)
  long contact_searches = 0, contact_searches_all = 0;
  double step_s = 0;
  std::vector<BodyReport> bodies;  // in the order of Simulation::body_names()
  double total_energy() const { return kinetic + elastic + potential; }
};

// Everything that carries over from one step to the next, on the host (restart
// checkpoints): FEM node-interleaved x, v, a; every particle field row-major
// (x, v: np x dim; F, C: np x dim*dim); the MPM grid as extended; t and n.
// Everything else (graph, stencils, contact pairs, lagged friction) is rebuilt
// from these at the start of each step.
template <int dim>
struct SimulationState {
  double time = 0;
  long step = 0;
  std::vector<double> fem_x, fem_v, fem_a;
  bool has_mpm = false;
  // The particles' rows, in id order: ids [particle_first, particle_first +
  // mass.size()) of particle_total (state(): this rank's id block, every
  // particle on one rank), or, particle_block false (restore() from a
  // checkpoint written before row blocks), every particle.
  std::vector<double> x, v, mass, volume0, F, C;
  std::vector<long long> body, material;
  bool particle_block = false;
  long long particle_first = 0, particle_total = 0;
  // One rank, particles sorted by cell ('MPM/sort particles every'): the id
  // at each array position, so that a restart continues in the same order
  // (empty: id order; never written on several ranks).
  std::vector<long long> particle_order;
  std::array<double, dim> grid_origin{};
  std::array<int, dim> grid_cells{};
  double grid_dx = 0;
  int grid_extensions = 0;
};

template <int dim>
class Simulation {
 public:
  Simulation(SimulationSetup<dim> setup, const Teuchos::RCP<const Comm>& comm);
  ~Simulation();

  StepReport step();                 // advance by dt; throws SolverError naming the step
  StepReport diagnostics() const;    // energies, momentum, min J of the current state

  // Restart: the state after the last step, and its restoration into a
  // simulation built from the same scene (std::invalid_argument naming the
  // field when the sizes do not match: the scene is not the checkpoint's).
  // Both are collective on several ranks.
  SimulationState<dim> state() const;
  void restore(const SimulationState<dim>& s);

  double time() const { return time_; }
  long step_index() const { return step_; }
  const FemMesh<dim>& mesh() const { return mesh_; }
  // MPI (more than one rank; FEM-only scenes): the element partition the
  // Newton step runs on (nullptr on 1 rank). The FEM state (positions,
  // velocities, the mesh) stays replicated on every rank in this version;
  // each rank assembles and solves only its piece.
  const FemPartition* partition() const { return distributed_ || fem_shared_ ? &part_ : nullptr; }
  MpmBodies<dim>* mpm() { return mpm_.get(); }
  const MpmBodies<dim>* mpm() const { return mpm_.get(); }
  NewtonSolver<dim>& newton() { return *newton_; }
  const Contact<dim>* contact() const { return contact_.get(); }
  Contact<dim>* contact() { return contact_.get(); }
  // MPI (MPM distributed): the global particle id of each entry of
  // contact()->particle_forces() (the step's particle order, before migration).
  // contact_reported(): a step has reported contact forces (the same on every rank).
  Kokkos::View<const long long*, MemSpace> contact_force_ids() const { return force_ids_; }
  bool contact_reported() const { return contact_reported_; }
  // The energy terms this scene built (names, in assembly order): only what
  // it needs (no MPM, contact or friction term unless the scene has them).
  std::vector<std::string> term_names() const;
  // FEM bodies in scene order, then MPM bodies: the order of StepReport::bodies.
  std::vector<std::string> body_names() const;
  // FEM node-interleaved state; tests may set initial velocities before step().
  Kokkos::View<double*, MemSpace> positions() const { return x_; }
  Kokkos::View<double*, MemSpace> velocities() const { return v_; }
  Kokkos::View<double*, MemSpace> accelerations() const { return a_; }
  // Recompute the FEM a^n = g - M^{-1} grad Psi(x^n) (call after changing x).
  void reset_acceleration();
  void element_J(Kokkos::View<double*, MemSpace> J) const;
  void element_von_mises(Kokkos::View<double*, MemSpace> s) const;

 private:
  struct System;
  void apply_prescribed_targets(double t, Kokkos::View<double*, MemSpace> target) const;
  void prescribed_velocities(double t1);
  void count_penetrations(StepReport& r);
  void reduce_report(typename Contact<dim>::Report& r) const;
  // MPI: Newton on this rank's nodes, the result summed into every rank's x.
  NewtonStats minimize_distributed(const IncrementalPotential& ip, Kokkos::View<double*, MemSpace> x,
                                   Kokkos::View<double*, MemSpace> work);
  NewtonStats minimize_with_friction(const IncrementalPotential& ip, Kokkos::View<double*, MemSpace> x,
                                     Kokkos::View<double*, MemSpace> x_ref, double s, int& iterations);

  SimulationSetup<dim> setup_;
  FemMesh<dim> mesh_;
  std::unique_ptr<DeformationTerm<dim, dim + 1>> elasticity_;
  std::unique_ptr<MpmBodies<dim>> mpm_;
  std::unique_ptr<NewtonSolver<dim>> newton_;
  std::unique_ptr<Contact<dim>> contact_;
  std::unique_ptr<System> sys_;
  LevelSetList level_sets_;
  Kokkos::View<double*, MemSpace> x_, v_, a_, mass_, initial_position_;
  Kokkos::View<int*, MemSpace> prescribed_;
  Kokkos::View<double*, MemSpace> penetration_xp_;  // count_penetrations: particle positions, kept
  DeviceMotions motions_;  // prescribed nodes and their segments, on the device
  double time_ = 0;
  long step_ = 0;
  double mpm_min_particle_mass_ = 0;  // the weight scale of the Newton convergence test
  // MPI: the partition, this rank's elasticity (local node ids), the global
  // DOF of each local DOF, and the local copies of the step's inputs.
  Teuchos::RCP<const Comm> comm_;
  bool distributed_ = false;      // FEM bodies only (no FEM-FEM contact), elements cut into the ranks
  bool mpm_distributed_ = false;  // MPM bodies only, particles cut into boxes (MpmBodies::distribute)
  // Several ranks, each holding the whole FEM mesh and state, assembling the
  // elements Zoltan2 gives it (local_elasticity_) and owning fem_owned_: MPM +
  // FEM scenes, and FEM-only scenes with FEM-FEM contact (whose pairs need the
  // whole boundary on every rank).
  bool fem_shared_ = false;
  void share_fem_mesh(const Teuchos::RCP<const Comm>& comm);
  FemPartition part_;
  std::unique_ptr<DeformationTerm<dim, dim + 1>> local_elasticity_;  // MPM + FEM: this rank's elements, global node ids
  std::vector<char> fem_owned_;                   // fem_shared_: the FEM nodes owned here
  Kokkos::View<long long*, MemSpace> force_ids_;  // contact_force_ids()
  bool contact_reported_ = false;
  Kokkos::View<LO*, MemSpace> local_dof_;
  Kokkos::View<double*, MemSpace> lx_, lxhat_, lmass_, ltarget_;
  Kokkos::View<int*, MemSpace> lpres_;
};

}  // namespace bfemp
