#include "sim/fem_simulation.hpp"

#include <Kokkos_Timer.hpp>
#include <sstream>

#include "solver/solver_error.hpp"

namespace bfemp {

using View1 = Kokkos::View<double*, MemSpace>;

template <int dim>
FemSimulation<dim>::FemSimulation(FemSetup<dim> setup, const Teuchos::RCP<const Comm>& comm)
    : setup_(std::move(setup)), mesh_(build_fem_mesh<dim>(setup_.bodies, setup_.materials)) {
  if (!(setup_.dt > 0))
    throw std::invalid_argument("time step dt = " + std::to_string(setup_.dt) + ": expected dt > 0");
  elasticity_ = std::make_unique<DeformationTerm<dim, dim + 1>>("fem elasticity", mesh_.elements);
  newton_ = std::make_unique<NewtonSolver<dim>>(comm, setup_.linear_solver, setup_.newton);
  newton_->set_system(mesh_.num_nodes(), {elasticity_.get()}, true);
  const std::size_t n = static_cast<std::size_t>(mesh_.num_nodes()) * dim;
  x_ = View1("fem_x", n);
  v_ = View1("fem_v", n);
  a_ = View1("fem_a", n);
  x_hat_ = View1("fem_x_hat", n);
  target_ = View1("fem_target", n);
  mass_ = View1("fem_mass_dof", n);
  initial_position_ = View1("fem_x0", n);
  prescribed_ = Kokkos::View<int*, MemSpace>("fem_prescribed", n);
  Kokkos::deep_copy(x_, mesh_.rest_position);
  Kokkos::deep_copy(initial_position_, mesh_.rest_position);
  auto nm = mesh_.node_mass;
  auto md = mass_;
  Kokkos::parallel_for(
      "fem_mass_dof", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const LO i) { md(i) = nm(i / dim); });

  auto v = Kokkos::create_mirror_view(v_);
  Kokkos::deep_copy(v, 0.0);
  for (std::size_t b = 0; b < mesh_.bodies.size() && b < setup_.initial_velocity.size(); ++b) {
    const auto& r = mesh_.bodies[b];
    for (LO i = r.first_node; i < r.first_node + r.num_nodes; ++i)
      for (int c = 0; c < dim; ++c) v(i * dim + c) = setup_.initial_velocity[b][c];
  }
  auto pres = Kokkos::create_mirror_view(prescribed_);
  Kokkos::deep_copy(pres, 0);
  auto X0 = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), initial_position_);
  for (const auto& mo : setup_.motions)
    for (LO node : mo.nodes) {
      if (node < 0 || node >= mesh_.num_nodes())
        throw std::invalid_argument("prescribed motion '" + mo.name + "': node " +
                                    std::to_string(node) + " out of range");
      Vec<dim> X;
      for (int c = 0; c < dim; ++c) X(c) = X0(node * dim + c);
      const Vec<dim> vel = mo.template velocity<dim>(X, 0.0);
      for (int c = 0; c < dim; ++c) {
        pres(node * dim + c) = 1;
        v(node * dim + c) = vel(c);
      }
    }
  Kokkos::deep_copy(v_, v);
  Kokkos::deep_copy(prescribed_, pres);
  reset_acceleration();
}

template <int dim>
FemSimulation<dim>::~FemSimulation() = default;

template <int dim>
void FemSimulation<dim>::reset_acceleration() {
  auto a = a_;
  auto m = mass_;
  auto pres = prescribed_;
  Kokkos::deep_copy(a, 0.0);
  newton_->potential_gradient(x_, -1.0, a);
  const auto g = setup_.gravity;
  Kokkos::parallel_for(
      "fem_a0", Kokkos::RangePolicy<ExecSpace>(0, a.extent(0)), KOKKOS_LAMBDA(const LO i) {
        a(i) = pres(i) ? 0.0 : a(i) / m(i) + g[i % dim];
      });
}

template <int dim>
void FemSimulation<dim>::apply_prescribed_targets(double t, View1 target) const {
  auto tgt = Kokkos::create_mirror_view(target);
  auto X0 = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), initial_position_);
  for (const auto& mo : setup_.motions)
    for (LO node : mo.nodes) {
      Vec<dim> X;
      for (int c = 0; c < dim; ++c) X(c) = X0(node * dim + c);
      const Vec<dim> p = mo.template position<dim>(X, t);
      for (int c = 0; c < dim; ++c) tgt(node * dim + c) = p(c);
    }
  Kokkos::deep_copy(target, tgt);
}

template <int dim>
StepReport FemSimulation<dim>::step() {
  Kokkos::Timer timer;
  const double dt = setup_.dt;
  const double t1 = time_ + dt;
  const TimeIntegrator& ti = setup_.integrator;
  const double h = ti.potential_scale(dt);
  const double ca = ti.predictor_acc_scale(dt);
  const auto g = setup_.gravity;
  auto x = x_;
  auto v = v_;
  auto a = a_;
  auto xhat = x_hat_;
  Kokkos::parallel_for(
      "fem_predictor", Kokkos::RangePolicy<ExecSpace>(0, x.extent(0)), KOKKOS_LAMBDA(const LO i) {
        xhat(i) = x(i) + dt * v(i) + ca * a(i) + h * g[i % dim];
      });
  if (!setup_.motions.empty()) apply_prescribed_targets(t1, target_);

  IncrementalPotential ip{x_hat_, mass_, prescribed_, target_, h, dt};
  NewtonStats ns;
  try {
    ns = newton_->minimize(ip, x_);
  } catch (const SolverError& e) {
    std::ostringstream msg;
    msg << "step " << step_ + 1 << " (t = " << t1 << " s): " << e.what();
    throw SolverError(msg.str());
  }

  const double gamma = ti.gamma;
  auto pres = prescribed_;
  auto x0 = initial_position_;
  Kokkos::parallel_for(
      "fem_velocity_update", Kokkos::RangePolicy<ExecSpace>(0, x.extent(0)), KOKKOS_LAMBDA(const LO i) {
        if (pres(i)) return;
        const double a1 = (x(i) - xhat(i)) / h + g[i % dim];
        v(i) += dt * ((1.0 - gamma) * a(i) + gamma * a1);
        a(i) = a1;
      });
  if (!setup_.motions.empty()) {
    auto vh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v_);
    auto ah = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), a_);
    auto X0 = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), initial_position_);
    for (const auto& mo : setup_.motions)
      for (LO node : mo.nodes) {
        Vec<dim> X;
        for (int c = 0; c < dim; ++c) X(c) = X0(node * dim + c);
        const Vec<dim> vel = mo.template velocity<dim>(X, t1);
        for (int c = 0; c < dim; ++c) {
          ah(node * dim + c) = (vel(c) - vh(node * dim + c)) / dt;
          vh(node * dim + c) = vel(c);
        }
      }
    Kokkos::deep_copy(v_, vh);
    Kokkos::deep_copy(a_, ah);
  }
  time_ = t1;
  ++step_;
  StepReport r = diagnostics();
  r.newton = ns;
  r.step_s = timer.seconds();
  return r;
}

template <int dim>
StepReport FemSimulation<dim>::diagnostics() const {
  StepReport r;
  r.step = step_;
  r.time = time_;
  r.dt = setup_.dt;
  auto x = x_;
  auto v = v_;
  auto m = mass_;
  const auto g = setup_.gravity;
  struct Sums { double ke, pe, p[3]; };
  double ke = 0, pe = 0, p0 = 0, p1 = 0, p2 = 0;
  Kokkos::parallel_reduce(
      "fem_energy_momentum", Kokkos::RangePolicy<ExecSpace>(0, x.extent(0)),
      KOKKOS_LAMBDA(const LO i, double& k, double& u, double& q0, double& q1, double& q2) {
        const int c = i % dim;
        k += 0.5 * m(i) * v(i) * v(i);
        u -= m(i) * g[c] * x(i);
        const double pi = m(i) * v(i);
        if (c == 0) q0 += pi;
        if (c == 1) q1 += pi;
        if (c == 2) q2 += pi;
      },
      ke, pe, p0, p1, p2);
  r.kinetic = ke;
  r.potential = pe;
  r.momentum = {p0, p1, p2};
  r.elastic = newton_->potential(x_);
  r.min_J = deformation_min_J(mesh_.elements, x_);
  return r;
}

template <int dim>
void FemSimulation<dim>::element_J(View1 J) const {
  deformation_J_von_mises(mesh_.elements, x_, J, View1());
}

template <int dim>
void FemSimulation<dim>::element_von_mises(View1 s) const {
  View1 J("fem_J_tmp", mesh_.num_cells());
  deformation_J_von_mises(mesh_.elements, x_, J, s);
}

template class FemSimulation<2>;
template class FemSimulation<3>;

}  // namespace bfemp
