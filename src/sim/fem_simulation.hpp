#pragma once
// Implicit FEM elastodynamics: state (x, v, a per node), predictor, Newton
// minimisation of the incremental potential, Newmark/backward-Euler update,
// prescribed motion, and the per-step diagnostics.
#include <Teuchos_ParameterList.hpp>
#include <array>
#include <memory>
#include <vector>

#include "fem/fem_mesh.hpp"
#include "fem/prescribed_motion.hpp"
#include "solver/newton.hpp"
#include "time/integrator.hpp"

namespace bfemp {

template <int dim>
struct FemSetup {
  std::vector<FemBodyInput> bodies;
  std::vector<MaterialParams> materials;
  std::vector<std::array<double, 3>> initial_velocity;  // per body (empty: at rest)
  std::vector<PrescribedMotion> motions;                // node ids are global FEM ids
  TimeIntegrator integrator = TimeIntegrator::backward_euler();
  std::array<double, 3> gravity{0, 0, 0};
  double dt = 1e-3;
  NewtonParams newton;
  Teuchos::ParameterList linear_solver;                 // resolved "Linear Solver" list
};

struct StepReport {
  long step = 0;
  double time = 0, dt = 0;
  double kinetic = 0, elastic = 0, potential = 0;
  std::array<double, 3> momentum{0, 0, 0};
  NewtonStats newton;
  double min_J = 0;
  double step_s = 0;
  double total_energy() const { return kinetic + elastic + potential; }
};

template <int dim>
class FemSimulation {
 public:
  FemSimulation(FemSetup<dim> setup, const Teuchos::RCP<const Comm>& comm);
  ~FemSimulation();

  StepReport step();                 // advance by dt; throws SolverError naming the step
  StepReport diagnostics() const;    // energies, momentum, min J of the current state

  double time() const { return time_; }
  long step_index() const { return step_; }
  const FemMesh<dim>& mesh() const { return mesh_; }
  NewtonSolver<dim>& newton() { return *newton_; }
  // Node-interleaved state; tests may set initial velocities before step().
  Kokkos::View<double*, MemSpace> positions() const { return x_; }
  Kokkos::View<double*, MemSpace> velocities() const { return v_; }
  Kokkos::View<double*, MemSpace> accelerations() const { return a_; }
  // Recompute a^n = g - M^{-1} grad Psi(x^n) (call after changing x).
  void reset_acceleration();
  void element_J(Kokkos::View<double*, MemSpace> J) const;
  void element_von_mises(Kokkos::View<double*, MemSpace> s) const;

 private:
  void apply_prescribed_targets(double t, Kokkos::View<double*, MemSpace> target) const;

  FemSetup<dim> setup_;
  FemMesh<dim> mesh_;
  std::unique_ptr<DeformationTerm<dim, dim + 1>> elasticity_;
  std::unique_ptr<NewtonSolver<dim>> newton_;
  Kokkos::View<double*, MemSpace> x_, v_, a_, x_hat_, target_, mass_, initial_position_;
  Kokkos::View<int*, MemSpace> prescribed_;
  double time_ = 0;
  long step_ = 0;
};

}  // namespace bfemp
