#pragma once
// Projected Newton on the incremental potential (paper Algorithm 2):
//   E(x) = 1/2 |x - x_hat|_M^2 + h Psi(x),   h = 2 alpha beta dt^2,
// with PSD-projected element Hessians summed into a Tpetra CrsMatrix on a graph
// built once, a line search starting at min(1, 0.9 * largest step keeping every
// det F > 0) (see LineSearch), and the stop test |p|_inf / dt < eps_d.
// Prescribed DOFs are driven toward their targets inside the same iterations:
// their part of p is the remaining offset, so the filter also guards them.
// Psi is a sum of EnergyTerms (FEM elements, MPM particles, contact); the DOF
// space (solver/dof_space.hpp) owns the graph, its cache and the constraints.
#include <Teuchos_ParameterList.hpp>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "solver/dof_space.hpp"
#include "solver/energy_term.hpp"
#include "solver/linear_solver.hpp"
#include "solver/slip_constraints.hpp"
#include "solver/tpetra_types.hpp"

namespace bfemp {

// Which Hessian the Newton direction solves with.
//   Projected: every stencil's local Hessian projected onto the PSD cone
//     (the paper's projected Newton; always a descent direction).
//   ExactIfDefinite: the exact Hessian first; when its Cholesky factorisation
//     meets a non-positive pivot, the projected one for that iteration. A
//     positive definite exact Hessian still gives a descent direction, and
//     near the minimum it converges quadratically where the projection (of
//     the barrier's b' grad^2 d, of compressed neo-Hookean twist modes) makes
//     the convergence linear. Needs a solver that certifies definiteness
//     (Cholmod); with another the projected Hessian is used.
enum class HessianMode { Projected, ExactIfDefinite };

// The line search along p from alpha_0 = min(1, 0.9 * the CCD/inversion bound),
// phi(alpha) = E(x + alpha p), phi'(0) = grad E . p < 0:
//   Backtracking: halve alpha until phi(alpha) <= phi(0) (+ the energy sums'
//     round-off, 1e-13 (|inertia| + |elastic|)).
//   Wolfe: when phi(alpha_0) > phi(0) and phi'(alpha_0) > 0, first bisect the
//     bracket (0, alpha_0) on the sign of phi' (one gradient evaluation each)
//     until |phi'(alpha)| <= 0.1 |phi'(0)| (the strong Wolfe curvature
//     condition), and take that alpha if phi(alpha) <= phi(0) (the same
//     no-rise test as halving, not Armijo's sufficient decrease); otherwise
//     (no sign change, a bracket narrower than the stall test's 1e-3 eps_d dt
//     along p, 50 bisections, or the energy rose) backtracking.
// Why Wolfe: the lagged friction energy mu lambda f0(|u_t|) is a rounded V of
// width eps_v h about u_t = 0. On the slip side its Hessian has no curvature
// along a 1D tangent (2D), so the Newton step overshoots the stick zone; halving
// lands on either side and the iterates cycle (A6 with mu 0.5, step 708: period
// 3, |p|/dt 7e-4..5e-3 m/s for 300 iterations). The zero of phi' lies inside
// the stick zone, where the next Hessian sees its stiffness mu lambda /
// (eps_v h). phi' is resolved where phi's differences are round-off.
enum class LineSearch { Backtracking, Wolfe };

struct NewtonParams {
  double eps_d = 1e-6;     // m/s
  int max_iterations = 100;
  HessianMode hessian = HessianMode::Projected;
  LineSearch line_search = LineSearch::Wolfe;
  bool log_iterations = false;  // one line per iteration on stderr (rank 0)
  // ExactIfDefinite: when the exact Hessian is indefinite, the contact pairs'
  // local Hessians keep these fractions of their negative curvature in turn
  // (Sink::contact_keep), before the full projection. Less stiffness added
  // than by the projection: where the energy is non-convex along a contact
  // surface (particles sliding over the facets' edges), the projected Newton
  // takes short steps and converges linearly.
  std::vector<double> fallback_keep{0.7, 0.3};
};

struct NewtonStats {
  int iterations = 0;
  int linear_iterations = 0;
  double assembly_s = 0, solve_s = 0, line_search_s = 0;
  double min_step = 1.0;   // smallest accepted line-search step
  double first_p_dt = 0;   // |p|_inf / dt of the first Newton direction (m/s); a step's friction loop:
                           // that of its last pass (the loop's end test: below eps_d)
  int graph_builds = 0;            // graph rebuilds inside the solve (contact pairs outside the graph)
  int symbolic_factorizations = 0; // direct solvers: symbolic phases run
  int numeric_factorizations = 0;  // direct solvers: numeric factorisations run (failed ones too)
  double factor_s = 0, reuse_cg_s = 0;  // Cholmod (factor_s also BLOCK_CHOLMOD, this rank's): within solve_s (successful solves)
  int reuse_cg_iterations = 0;          // Cholmod: CG iterations on the previous factor
  int stale_retries = 0;           // CG + BLOCK_CHOLMOD: solves redone on a fresh factor after the kept one failed
  int projected_retries = 0;       // the step failed with the exact Hessian and was redone projected
  int exact_hessian_iterations = 0; // iterations solved with the exact Hessian
  int projection_fallbacks = 0;     // exact Hessian not positive definite: projected instead
  int partial_projections = 0;      // of those, solved with a partial projection (fallback_keep > 0)
  int wolfe_steps = 0;              // line searches ended by the strong Wolfe bisection
  int wolfe_gradients = 0;          // gradient evaluations of those bisections (failed ones too)
};

// Inputs of one minimisation; all Views node-interleaved, length n_nodes*dim.
struct IncrementalPotential {
  Kokkos::View<const double*, MemSpace> x_hat;   // predictor, gravity included
  Kokkos::View<const double*, MemSpace> mass;    // lumped mass per DOF
  Kokkos::View<const int*, MemSpace> prescribed; // 1 where the DOF is prescribed
  Kokkos::View<const double*, MemSpace> target;  // prescribed DOF positions at t^{n+1}
  double h = 0;                                  // 2 alpha beta dt^2
  double dt = 0;
  // Optional per-DOF weights of the convergence test |p|_inf / dt < eps_d:
  // DOF i counts as weight(i) |p_i| (empty: 1 everywhere). The MPM grid uses
  // min(1, m_i / m_particle,min), a bound of the largest particle weight node
  // i carries: a node reached by particles only with weights of 1e-12..1e-8
  // (9 / 27 per cell, particles just off the cell centre) has so little mass
  // and stiffness that its direction is round-off, and it moves no particle.
  Kokkos::View<const double*, MemSpace> weight;
};

template <int dim>
class NewtonSolver {
 public:
  NewtonSolver(const Teuchos::RCP<const Comm>& comm, const Teuchos::ParameterList& linear_solver,
               NewtonParams params);
  ~NewtonSolver();

  // MPI: this rank's nodes (owned first, then ghosts) and their global ids
  // (DofSpace::set_partition); before set_system. Every View of minimize()
  // then covers all local nodes, ghosts included; each term holds only this
  // rank's stencils (each stencil on one rank), and ip.mass is the global
  // lumped mass at every local DOF. Without it the solver runs on 1 rank.
  void set_partition(std::vector<GO> global_nodes, LO n_owned);
  void set_partition(std::vector<GO> global_nodes, const std::vector<char>& owned);

  // Declares the unknowns (n_nodes * dim DOFs) and the terms of Psi. The DOF
  // space rebuilds the graph (and the linear solver its symbolic phase) only
  // when the node count or a term's couplings changed; returns true then. The
  // terms must outlive the next minimize().
  bool set_system(LO n_nodes, std::vector<EnergyTerm<dim>*> terms);

  // A new time step: the linear solver's next solve factorises (Cholmod
  // reuses a factor only within one step, so a restarted run takes the same
  // path as the run it continues).
  void new_time_step();
  HessianMode hessian_mode() const;
  void set_hessian_mode(HessianMode mode);

  // Minimises E from the initial guess in `x` (overwritten with the result).
  // Throws SolverError when the linear solve fails, the line search stalls or
  // the iteration cap is reached.
  // `eps_d` > 0 replaces NewtonParams::eps_d for this call.
  NewtonStats minimize(const IncrementalPotential& ip, Kokkos::View<double*, MemSpace> x, double eps_d = 0.0);

  // Energy E(x) and its parts; exposed for tests and diagnostics.
  struct Energy { double inertia = 0, elastic = 0; double total() const { return inertia + elastic; } };
  Energy energy(const IncrementalPotential& ip, Kokkos::View<const double*, MemSpace> x) const;
  // Psi(x) (unscaled) and grad += scale * dPsi/dx over all terms.
  double potential(Kokkos::View<const double*, MemSpace> x) const;
  void potential_gradient(Kokkos::View<const double*, MemSpace> x, double scale,
                          Kokkos::View<double*, MemSpace> grad) const;
  // Distributed: a rank-by-rank assembled vector (potential_gradient) summed
  // at every DOF over the ranks holding it (DofSpace::sum_shared).
  void sum_shared(Kokkos::View<double*, MemSpace> v);

  // Called after every accepted Newton iterate (debug checks, tests).
  std::function<void(Kokkos::View<const double*, MemSpace>)> on_iterate;

  // Slip boundaries: exact linear constraints on grid nodes, rebuilt by the
  // caller each step (SlipConstraints::build); empty by default.
  SlipConstraints<dim>& slip_constraints();

  const LinearSolver& linear_solver() const;
  const DofSpace<dim>& dof_space() const;
  Teuchos::RCP<const Map> dof_map() const;
  double last_graph_build_s() const;
  // Seconds each term (by name) has spent in assemble() since construction.
  const std::map<std::string, double>& term_assembly_seconds() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace bfemp
