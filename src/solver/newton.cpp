#include "solver/newton.hpp"

#include <cstdio>

#include <Kokkos_Timer.hpp>
#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Vector.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "solver/muelu_preconditioner.hpp"
#include "solver/solver_error.hpp"

namespace bfemp {

namespace {
std::string fmt_g(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}
}  // namespace

using View1 = Kokkos::View<double*, MemSpace>;
using CView1 = Kokkos::View<const double*, MemSpace>;

template <int dim>
struct NewtonSolver<dim>::Impl {
  Teuchos::RCP<const Comm> comm;
  NewtonParams params;
  LinearSolver solver;
  DofSpace<dim> dofs;
  Teuchos::RCP<Vector> b, p;
  Teuchos::RCP<MultiVec> modes;  // MueLu: rigid-body modes on the DOF map
  bool modes_stale = true;       // MueLu: the matrix changed since the modes were set
  int solves_since_modes = 0;    // minimisations on the current modes
  View1 grad, rhs, dx_prescribed, dir, trial;
  View1 trial_grad;  // line search: the potential's gradient at a trial point
  std::map<std::string, double> term_s;  // assembly seconds per term name

  Impl(const Teuchos::RCP<const Comm>& c, const Teuchos::ParameterList& ls, NewtonParams np)
      : comm(c), params(np), solver(ls, c), dofs(c) {}

  // Global reductions (every rank takes the same step and stops together).
  double all(double v, Teuchos::EReductionType op) const {
    if (comm->getSize() == 1) return v;
    double g = v;
    Teuchos::reduceAll(*comm, op, v, Teuchos::outArg(g));
    return g;
  }
  double all_max(double v) const { return all(v, Teuchos::REDUCE_MAX); }
  double all_min(double v) const { return all(v, Teuchos::REDUCE_MIN); }
  double all_sum(double v) const { return all(v, Teuchos::REDUCE_SUM); }

  // phi'(alpha) = grad E(xt) . p over the free DOFs, xt = x + alpha p, summed
  // over ranks: each rank's local gradient holds its own stencils' parts, p is
  // alike at shared DOFs, and the inertia counts at the owner.
  double directional_derivative(const IncrementalPotential& ip, CView1 xt, CView1 p) {
    auto g = trial_grad;
    Kokkos::deep_copy(g, 0.0);
    for (const auto* t : dofs.terms()) t->gradient(xt, ip.h, g);
    auto mass = ip.mass;
    auto xhat = ip.x_hat;
    auto pres = ip.prescribed;
    const bool dist = dofs.distributed();
    const auto own = dofs.owned_mask();
    double d = 0;
    Kokkos::parallel_reduce(
        "newton_directional_derivative", Kokkos::RangePolicy<ExecSpace>(0, xt.extent(0)),
        KOKKOS_LAMBDA(const LO i, double& acc) {
          if (pres(i)) return;
          const double inertia = (!dist || own(i)) ? mass(i) * (xt(i) - xhat(i)) : 0.0;
          acc += (g(i) + inertia) * p(i);
        },
        d);
    return all_sum(d);
  }

  // Vectors for a new node count (grow only when the count changes).
  void resize_vectors() {
    const std::size_t ndof = dofs.num_dofs();  // local (owned + ghost) DOFs
    if (grad.extent(0) == ndof && !b.is_null() && b->getMap() == dofs.map()) return;
    b = Teuchos::rcp(new Vector(dofs.map()));
    p = Teuchos::rcp(new Vector(dofs.map()));
    grad = View1("newton_grad", ndof);
    rhs = View1("newton_rhs", ndof);
    dx_prescribed = View1("newton_dx_prescribed", ndof);
    dir = View1("newton_dir", ndof);
    trial = View1("newton_trial", ndof);
    trial_grad = View1("newton_trial_grad", ndof);
  }

  void matrix_changed() {
    solver.set_matrix(dofs.matrix());
    resize_vectors();
    modes_stale = true;
  }

  // MueLu's near-null space: the rigid-body modes of the nodes at x, after a
  // graph rebuild and every near_null_space_every() minimisations (a new
  // hierarchy follows; in between it is reused).
  void refresh_modes(CView1 x) {
    if (!solver.wants_near_null_space()) return;
    modes_stale = false;
    solves_since_modes = 0;
    constexpr int nm = dim == 2 ? 3 : 6;
    if (modes.is_null() || modes->getMap() != dofs.map()) modes = Teuchos::rcp(new MultiVec(dofs.map(), nm));
    if (dofs.distributed()) {  // the owned rows' positions, in the owned map's order
      const auto od = dofs.owned_dofs();
      View1 xo("newton_owned_x", od.extent(0));
      Kokkos::parallel_for(
          "newton_owned_x", Kokkos::RangePolicy<ExecSpace>(0, od.extent(0)), KOKKOS_LAMBDA(const LO r) { xo(r) = x(od(r)); });
      rigid_body_modes<dim>(xo, *modes);
    } else {
      rigid_body_modes<dim>(x, *modes);
    }
    solver.set_near_null_space(modes, dim);
  }

  // Gradient, Hessian (PSD-projected per stencil when `project`, exact
  // otherwise; with `project`, contact pairs keep the fraction `contact_keep`
  // of their negative curvature) and right-hand side at x.
  void assemble(const IncrementalPotential& ip, CView1 x, bool project, double contact_keep = 0.0) {
    auto g = grad;
    auto r = rhs;
    auto dxp = dx_prescribed;
    Kokkos::deep_copy(g, 0.0);
    Kokkos::deep_copy(r, 0.0);
    dofs.begin_assembly();
    Sink<dim> sink = dofs.sink(ip.h, g, r, ip.prescribed, dxp);
    sink.project = project;
    sink.contact_keep = project ? contact_keep : 0.0;
    for (std::size_t k = 0; k < dofs.terms().size(); ++k) {
      const auto* t = dofs.terms()[k];
      Kokkos::Timer timer;
      t->assemble(x, dofs.term_sink(sink, k));
      Kokkos::fence();
      term_s[t->name()] += timer.seconds();
    }
    auto lcl = sink.A;
    auto mass = ip.mass;
    auto xhat = ip.x_hat;
    auto pres = ip.prescribed;
    const bool dist = dofs.distributed();  // inertia once, at the owner
    const auto own = dofs.owned_mask();
    Kokkos::parallel_for(
        "newton_inertia", Kokkos::RangePolicy<ExecSpace>(0, g.extent(0)), KOKKOS_LAMBDA(const LO i) {
          const bool owned = !dist || own(i);
          if (owned) g(i) += mass(i) * (x(i) - xhat(i));
          if (pres(i)) return;  // the DOF space writes the constraint row
          r(i) -= g(i);
          if (!owned) return;
          const double diag = mass(i);
          lcl.sumIntoValues(i, &i, 1, &diag, false, true);
        });
    dofs.end_assembly(pres, dxp, r, *b);  // (export,) prescribed rows, slip transform
  }
};

template <int dim>
NewtonSolver<dim>::NewtonSolver(const Teuchos::RCP<const Comm>& comm, const Teuchos::ParameterList& ls,
                                NewtonParams params)
    : impl_(new Impl(comm, ls, params)) {}

template <int dim>
NewtonSolver<dim>::~NewtonSolver() = default;

template <int dim>
void NewtonSolver<dim>::set_partition(std::vector<GO> global_nodes, LO n_owned) {
  impl_->dofs.set_partition(std::move(global_nodes), n_owned);
}

template <int dim>
void NewtonSolver<dim>::set_partition(std::vector<GO> global_nodes, const std::vector<char>& owned) {
  impl_->dofs.set_partition(std::move(global_nodes), owned);
}

template <int dim>
bool NewtonSolver<dim>::set_system(LO n_nodes, std::vector<EnergyTerm<dim>*> terms) {
  if (impl_->comm->getSize() > 1 && !impl_->dofs.distributed())
    throw std::invalid_argument(
        "the Newton solver runs on " + std::to_string(impl_->comm->getSize()) +
        " MPI ranks only with a node partition (set_partition); this scene's DOFs are not "
        "distributed yet: run without mpirun or with -np 1");
  const bool rebuilt = impl_->dofs.set_structure(n_nodes, terms);
  if (rebuilt) impl_->matrix_changed();
  return rebuilt;
}

template <int dim>
SlipConstraints<dim>& NewtonSolver<dim>::slip_constraints() {
  return impl_->dofs.slip();
}

template <int dim>
const DofSpace<dim>& NewtonSolver<dim>::dof_space() const {
  return impl_->dofs;
}

template <int dim>
HessianMode NewtonSolver<dim>::hessian_mode() const {
  return impl_->params.hessian;
}

template <int dim>
void NewtonSolver<dim>::set_hessian_mode(HessianMode mode) {
  impl_->params.hessian = mode;
}

template <int dim>
void NewtonSolver<dim>::new_time_step() {
  impl_->solver.forget_factor();
}

template <int dim>
const LinearSolver& NewtonSolver<dim>::linear_solver() const {
  return impl_->solver;
}

template <int dim>
Teuchos::RCP<const Map> NewtonSolver<dim>::dof_map() const {
  return impl_->dofs.map();
}

template <int dim>
const std::map<std::string, double>& NewtonSolver<dim>::term_assembly_seconds() const {
  return impl_->term_s;
}

template <int dim>
double NewtonSolver<dim>::last_graph_build_s() const {
  return impl_->dofs.last_graph_build_s();
}

template <int dim>
double NewtonSolver<dim>::potential(CView1 x) const {
  double e = 0;
  for (const auto* t : impl_->dofs.terms()) e += t->energy(x);
  return impl_->all_sum(e);  // each stencil lives on one rank
}

template <int dim>
void NewtonSolver<dim>::potential_gradient(CView1 x, double scale, View1 grad) const {
  for (const auto* t : impl_->dofs.terms()) t->gradient(x, scale, grad);
}

template <int dim>
void NewtonSolver<dim>::sum_shared(View1 v) {
  impl_->dofs.sum_shared(v);
}

template <int dim>
typename NewtonSolver<dim>::Energy NewtonSolver<dim>::energy(const IncrementalPotential& ip,
                                                             CView1 x) const {
  Energy E;
  auto mass = ip.mass;
  auto xhat = ip.x_hat;
  const bool dist = impl_->dofs.distributed();  // each DOF once, at its owner
  const auto own = impl_->dofs.owned_mask();
  Kokkos::parallel_reduce(
      "newton_inertia_energy", Kokkos::RangePolicy<ExecSpace>(0, impl_->dofs.num_dofs()),
      KOKKOS_LAMBDA(const LO i, double& acc) {
        if (dist && !own(i)) return;
        const double d = x(i) - xhat(i);
        acc += 0.5 * mass(i) * d * d;
      },
      E.inertia);
  E.inertia = impl_->all_sum(E.inertia);
  E.elastic = ip.h * potential(x);
  return E;
}

template <int dim>
NewtonStats NewtonSolver<dim>::minimize(const IncrementalPotential& ip, View1 x, double eps_d) {
  auto& m = *impl_;
  const double eps = eps_d > 0 ? eps_d : m.params.eps_d;
  NewtonStats st;
  Kokkos::Timer timer;
  auto dxp = m.dx_prescribed;
  auto pres = ip.prescribed;
  auto target = ip.target;
  auto dir = m.dir;
  auto trial = m.trial;
  double r0_norm = 0;
  bool lifted = false;  // the previous iteration still moved prescribed DOFs
  // While prescribed DOFs are still on their way the line search does not
  // guard the energy (below): the step is the bounded (CCD, inversion) one.
  // Such an iteration's direction is solved only to the forcing term's cap
  // (0.1: r_0 is taken after the lift). Once a lifting step fell short of its
  // targets, the next ones are solved at the solver's tightest tolerance
  // until the prescribed DOFs arrive: 10 %-accurate directions, each taken
  // 0.9 of the way to the bound, drove A6's ring into the held-back plate at
  // the paper's size (|rhs| 3e3 -> 9e25 in 63 iterations, then a NaN solve).
  bool lift_blocked = false;
  const bool try_exact =
      m.params.hessian == HessianMode::ExactIfDefinite && m.solver.detects_indefinite();
  if (m.modes_stale || ++m.solves_since_modes >= m.solver.near_null_space_every()) m.refresh_modes(x);
  for (int it = 0; it < m.params.max_iterations; ++it) {
    // Remaining offset of the prescribed DOFs.
    double pres_left = 0;
    Kokkos::parallel_reduce(
        "newton_prescribed_offset", Kokkos::RangePolicy<ExecSpace>(0, x.extent(0)),
        KOKKOS_LAMBDA(const LO i, double& acc) {
          dxp(i) = pres(i) ? target(i) - x(i) : 0.0;
          acc = std::fmax(acc, std::fabs(dxp(i)));
        },
        Kokkos::Max<double>(pres_left));
    pres_left = std::max(pres_left, m.dofs.slip().update_offsets(x));  // remaining slip offsets
    pres_left = m.all_max(pres_left);

    timer.reset();
    bool grow = false;
    for (auto* t : m.dofs.terms()) grow = t->update(x) || grow;
    grow = m.all_max(grow ? 1.0 : 0.0) > 0;
    if (grow) {
      m.dofs.rebuild("pairs found mid-solve");
      m.matrix_changed();
      m.refresh_modes(x);
      ++st.graph_builds;
    }
    if (pres_left == 0.0) lift_blocked = false;
    bool project = !try_exact;
    m.assemble(ip, x, project);
    if (m.dofs.dropped_blocks() > 0) {
      // A term's couplings were not in the cached graph: never drop them.
      m.dofs.rebuild("blocks missing from the graph");
      m.matrix_changed();
      m.refresh_modes(x);
      m.dofs.count_missing_block_rebuild();
      ++st.graph_builds;
      m.assemble(ip, x, project);
      if (m.dofs.dropped_blocks() > 0)
        throw std::logic_error("DOF space: a term assembles blocks its add_couplings does not declare");
    }
    Kokkos::fence();
    st.assembly_s += timer.seconds();

    timer.reset();
    m.p->putScalar(0.0);
    const double r_norm = m.b->norm2();
    // Inexact Newton (CG, and CG on Cholmod's previous factor): relative
    // residual eta_k = |r_k| / |r_0| (clamped by the linear solver to
    // [tolerance, 0.1]): loose far from the minimum, tight near it, where |p|
    // decides convergence. r_0 is the residual of the first iteration whose
    // prescribed DOFs are at their targets: while they still move, |r| is
    // mostly their lift (the twist's first iteration: 4.5e3 against 9 after
    // it), and eta would come out hundreds of times too tight.
    const bool first = it == 0 || lifted;
    lifted = pres_left > 0.0;
    if (first) r0_norm = r_norm;
    const double forcing = lift_blocked ? 0.0 : r0_norm > 0 ? r_norm / r0_norm : 0.0;
    bool fallback = false;
    double kept = 0.0;       // contact curvature kept by the fallback's projection
    std::size_t next_keep = 0;  // the next fallback projection to try (m.params.fallback_keep, then 0)
    // Solves for the direction at relative residual eta (0: the solver's
    // tightest). An exact Hessian found indefinite (a non-positive pivot, or
    // negative curvature in CG) is replaced for this iteration by partial
    // projections (contact pairs keep a fraction of their negative
    // curvature), then the full one; so is a partial projection found
    // indefinite, by the next one; a failure of the full projection throws.
    // The loose solve may pass where the confirming tight one meets the
    // indefiniteness: both go through here.
    // `from_p`: the solve goes on from m.p (the confirming solve from the
    // loose direction); the fallback's solves of other matrices start at 0.
    auto solve_direction = [&](double eta, bool from_p) {
      const double f = eta > 0 ? eta : 1e-300;
      try {
        return m.solver.solve(*m.b, *m.p, f, from_p);
      } catch (const NotPositiveDefinite&) {
        if (project && kept == 0.0) throw;
        st.solve_s += timer.seconds();
        if (!project) ++st.projection_fallbacks;
        if (m.solver.kind() != LinearSolverKind::CG) ++st.numeric_factorizations;  // the one that failed
        fallback = true;
        project = true;
        const std::vector<double>& keeps = m.params.fallback_keep;
        for (std::size_t k = next_keep; k <= keeps.size(); ++k) {
          const double keep = k < keeps.size() ? keeps[k] : 0.0;
          timer.reset();
          m.assemble(ip, x, project, keep);
          Kokkos::fence();
          st.assembly_s += timer.seconds();
          timer.reset();
          m.p->putScalar(0.0);
          try {
            const LinearSolveStats r = m.solver.solve(*m.b, *m.p, f);
            kept = keep;
            next_keep = k + 1;
            return r;
          } catch (const SolverError&) {
            // A partial projection may be indefinite, or so nearly singular
            // that the solve is inaccurate: the next, stiffer one. The full
            // projection's failure is the step's.
            if (k == keeps.size()) throw;
            st.solve_s += timer.seconds();
            if (m.solver.kind() != LinearSolverKind::CG) ++st.numeric_factorizations;  // the one that failed
          }
        }
        throw std::logic_error("Newton: fallback projections exhausted without a throw");
      }
    };
    auto count_solve = [&](const LinearSolveStats& r) {
      st.linear_iterations += r.iterations;
      if (r.refactored) ++st.symbolic_factorizations;
      if (r.factorised) ++st.numeric_factorizations;
      st.factor_s += r.factor_s;
      st.reuse_cg_s += r.reuse_cg_s;
      st.reuse_cg_iterations += r.reuse_cg_iterations;
      st.stale_retries += r.stale_retries;
    };
    const auto wgt = ip.weight;
    const bool has_w = wgt.extent(0) > 0;
    // The solved direction into dir, with the exact prescribed and slip-normal
    // parts (not the solver's rounding of them); returns its weighted max
    // norm over all ranks.
    auto take_direction = [&]() {
      m.dofs.to_local(*m.p, dir);
      double norm = 0;
      Kokkos::parallel_reduce(
          "newton_dir_norm", Kokkos::RangePolicy<ExecSpace>(0, x.extent(0)),
          KOKKOS_LAMBDA(const LO i, double& acc) {
            if (pres(i)) dir(i) = dxp(i);
            acc = std::fmax(acc, std::fabs(dir(i)) * (has_w ? wgt(i) : 1.0));
          },
          Kokkos::Max<double>(norm));
      if (m.dofs.slip().count() > 0) {
        m.dofs.slip().fix_direction(dir);
        Kokkos::parallel_reduce(
            "newton_dir_norm_slip", Kokkos::RangePolicy<ExecSpace>(0, x.extent(0)),
            KOKKOS_LAMBDA(const LO i, double& acc) { acc = std::fmax(acc, std::fabs(dir(i)) * (has_w ? wgt(i) : 1.0)); },
            Kokkos::Max<double>(norm));
      }
      norm = m.all_max(norm);
      if (!std::isfinite(norm)) throw SolverError("Newton direction is not finite (linear solve produced NaN/Inf)");
      return norm;
    };
    // The largest step along dir the terms allow (CCD, inversion), all ranks.
    auto step_bound = [&]() {
      for (auto* t : m.dofs.terms()) t->prepare_direction(x, dir);
      double bound = std::numeric_limits<double>::infinity();
      for (const auto* t : m.dofs.terms()) bound = std::min(bound, t->max_step(x, dir));
      return m.all_min(bound);
    };

    const LinearSolveStats ls = solve_direction(forcing, false);
    count_solve(ls);
    double p_inf = take_direction();
    st.solve_s += timer.seconds();

    timer.reset();
    double a_max = step_bound();
    double alpha = std::min(1.0, kStepBoundFraction * a_max);
    bool converged = p_inf / ip.dt < eps && pres_left == 0.0;
    if (it == 0) st.first_p_dt = pres_left == 0.0 ? p_inf / ip.dt : std::numeric_limits<double>::infinity();
    if (converged && ls.tolerance > m.solver.tightest_tolerance()) {
      // An inexact (forcing-term) direction may underestimate |p|: decide
      // convergence on a direction solved to the full tolerance, going on
      // from the loose one (m.p still holds it: the same matrix and b).
      timer.reset();
      count_solve(solve_direction(0.0, true));
      p_inf = take_direction();
      converged = p_inf / ip.dt < eps;
      if (it == 0) st.first_p_dt = p_inf / ip.dt;
      st.solve_s += timer.seconds();
      timer.reset();
      a_max = step_bound();
      alpha = std::min(1.0, kStepBoundFraction * a_max);
    }
    if (!project) ++st.exact_hessian_iterations;
    if (kept > 0) ++st.partial_projections;
    // Armijo-type backtracking on E while the prescribed DOFs are at their
    // targets; while they still move, E may rise and the filtered step is taken.
    bool wolfe_ended = false;  // this iteration's step from the Wolfe bisection (log)
    if (pres_left == 0.0 && !converged) {
      const Energy E0 = energy(ip, x);
      const double scale = std::abs(E0.inertia) + std::abs(E0.elastic);
      const double tol = 1e-13 * scale;  // round-off of the energy sums
      auto grad = m.grad;
      double gp = 0;  // directional derivative of E along p (< 0)
      if (!m.dofs.distributed()) {
        Kokkos::parallel_reduce(
            "newton_grad_dot_p", Kokkos::RangePolicy<ExecSpace>(0, x.extent(0)),
            KOKKOS_LAMBDA(const LO i, double& acc) { acc += pres(i) ? 0.0 : grad(i) * dir(i); }, gp);
      } else {
        // The local gradient holds this rank's part only; the owned rhs is the
        // summed -grad at free rows.
        auto bv = Kokkos::subview(m.b->getLocalViewDevice(Tpetra::Access::ReadOnly), Kokkos::ALL(), 0);
        const auto od = m.dofs.owned_dofs();
        Kokkos::parallel_reduce(
            "newton_grad_dot_p_owned", Kokkos::RangePolicy<ExecSpace>(0, m.dofs.num_owned_dofs()),
            KOKKOS_LAMBDA(const LO r, double& acc) {
              const LO i = od(r);
              acc -= pres(i) ? 0.0 : bv(r) * dir(i);
            },
            gp);
        gp = m.all_sum(gp);
      }
      auto move_trial = [&](double a) {
        Kokkos::parallel_for(
            "newton_trial", Kokkos::RangePolicy<ExecSpace>(0, x.extent(0)),
            KOKKOS_LAMBDA(const LO i) { trial(i) = x(i) + a * dir(i); });
      };
      bool wolfe = m.params.line_search == LineSearch::Wolfe;
      while (true) {
        move_trial(alpha);
        const double E1 = energy(ip, trial).total();
        if (E1 <= E0.total() + tol) break;
        if (wolfe) {  // once, from alpha_0 (LineSearch)
          wolfe = false;
          // Bracket (a, b) with phi'(a) < 0 < phi'(b); bisect on the sign of phi'.
          auto derivative = [&](double a) {
            move_trial(a);
            ++st.wolfe_gradients;
            return m.directional_derivative(ip, trial, dir);
          };
          double a = 0, b = alpha, found = -1;
          if (derivative(b) > 0) {
            for (int k = 0; k < 50; ++k) {
              const double c = 0.5 * (a + b);
              const double dc = derivative(c);
              if (std::fabs(dc) <= 0.1 * std::fabs(gp)) {
                found = c;
                break;
              }
              (dc < 0 ? a : b) = c;
              if ((b - a) * p_inf < 1e-3 * m.params.eps_d * ip.dt) break;  // below the stall test's resolution
            }
          }
          if (found > 0) {
            move_trial(found);
            if (energy(ip, trial).total() <= E0.total() + tol) {
              alpha = found;
              ++st.wolfe_steps;
              wolfe_ended = true;
              break;
            }
          }
        }
        // Near the minimum the predicted decrease alpha |g.p| falls below what
        // the energy sums resolve; the energy cannot judge the step there, and
        // the (filtered) Newton step is taken.
        if (alpha * std::abs(gp) < 1e-11 * scale) break;
        alpha *= 0.5;
        // (The stall test is the scene's eps_d, also in a loose friction pass:
        // it judges the energy's resolution, not convergence.)
        if (alpha * p_inf < 1e-3 * m.params.eps_d * ip.dt) {
          std::ostringstream msg;
          msg << "line search stalled at Newton iteration " << it + 1 << " (step " << alpha
              << ", |p|_inf/dt = " << p_inf / ip.dt << " m/s, eps_d = " << m.params.eps_d << ")";
          throw NewtonStalled(msg.str());
        }
      }
    }
    Kokkos::parallel_for(
        "newton_update", Kokkos::RangePolicy<ExecSpace>(0, x.extent(0)), KOKKOS_LAMBDA(const LO i) {
          x(i) = (pres(i) && alpha == 1.0) ? target(i) : x(i) + alpha * dir(i);
        });
    Kokkos::fence();
    st.line_search_s += timer.seconds();
    st.min_step = std::min(st.min_step, alpha);
    if (pres_left > 0.0 && alpha < 1.0) lift_blocked = true;
    if (m.params.log_iterations && m.comm->getRank() == 0)
      std::fprintf(stderr,
                   "  newton %3d  |p|/dt %.3e m/s  step %.3e%s  (bound %.3e)  |rhs| %.3e  %s Hessian%s  linear %d "
                   "it%s%s\n",
                   it + 1, p_inf / ip.dt, alpha, wolfe_ended ? " (Wolfe)" : "", kStepBoundFraction * a_max, r_norm,
                   project ? "projected" : "exact", kept > 0 ? (" (contact keep " + fmt_g(kept) + ")").c_str() : "",
                   ls.iterations, ls.factorised ? " (factorised)" : "", fallback ? " after a non-positive pivot" : "");
    st.iterations = it + 1;
    if (on_iterate) on_iterate(x);
    if (converged) return st;
  }
  std::ostringstream msg;
  msg << "Newton did not converge in " << m.params.max_iterations
      << " iterations (raise 'Newton/max iterations' or reduce dt)";
  throw NewtonStalled(msg.str());
}

template class NewtonSolver<2>;
template class NewtonSolver<3>;

}  // namespace bfemp
