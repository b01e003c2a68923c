#include "sim/simulation.hpp"

#include <limits>

#include <Kokkos_Timer.hpp>
#include <Teuchos_CommHelpers.hpp>
#include <functional>
#include <iostream>
#include <sstream>

#include "core/collective_check.hpp"
#include "solver/solver_error.hpp"

namespace bfemp {

using View1 = Kokkos::View<double*, MemSpace>;

// System vectors over FEM nodes + active grid nodes; capacity grows, never
// shrinks, so steps do not reallocate.
template <int dim>
struct Simulation<dim>::System {
  View1 x, v, v_old, a, x_hat, target, mass, work, x_ref, weight, x_start, x_lag, lag_r;
  Kokkos::View<int*, MemSpace> prescribed;
  std::size_t n = 0;
  void resize(std::size_t nd) {
    n = nd;
    if (x.extent(0) >= nd) return;
    const std::size_t cap = nd + nd / 4;
    for (View1* w : {&x, &v, &v_old, &a, &x_hat, &target, &mass, &work, &x_ref, &weight, &x_start, &x_lag, &lag_r})
      *w = View1(w->label(), cap);
    prescribed = Kokkos::View<int*, MemSpace>("sys_prescribed", cap);
  }
  template <class V>
  static auto head(const V& view, std::size_t n) { return Kokkos::subview(view, std::make_pair(std::size_t(0), n)); }
};

template <int dim>
Simulation<dim>::Simulation(SimulationSetup<dim> setup, const Teuchos::RCP<const Comm>& comm)
    : setup_(std::move(setup)), mesh_(build_fem_mesh<dim>(setup_.bodies, setup_.materials)) {
  if (!(setup_.dt > 0))
    throw std::invalid_argument("time step dt = " + std::to_string(setup_.dt) + ": expected dt > 0");
  elasticity_ = std::make_unique<DeformationTerm<dim, dim + 1>>("fem elasticity", mesh_.elements);
  if (mesh_.num_cells() > 0) elasticity_->set_coloring(color_stencils<dim + 1>(mesh_.elements.nodes, mesh_.num_nodes()));
  if (setup_.mpm) {
    const auto& ms = *setup_.mpm;
    if (comm->getSize() == 1 && ms.particle_total >= 0 &&
        (ms.particle_first != 0 || static_cast<long long>(ms.particles.size()) != ms.particle_total))
      throw std::logic_error("Simulation: one rank with the particle block " + std::to_string(ms.particle_first) +
                             ".. of " + std::to_string(ms.particle_total) + " (a ParticleBlock of another rank count)");
    mpm_ = std::make_unique<MpmBodies<dim>>(*setup_.mpm, mesh_.elements.materials);
    const auto pm = mpm_->particles().mass;
    double m = std::numeric_limits<double>::infinity();
    Kokkos::parallel_reduce(
        "mpm_min_particle_mass", Kokkos::RangePolicy<ExecSpace>(0, pm.extent(0)),
        KOKKOS_LAMBDA(const std::size_t q, double& acc) { acc = pm(q) < acc ? pm(q) : acc; }, Kokkos::Min<double>(m));
    mpm_min_particle_mass_ = m;  // (+inf without particles here; made finite below)
  }
  comm_ = comm;
  if (comm->getSize() > 1 && setup_.mpm) {
    // Each rank keeps the particles of its box; the grid is shared. FEM
    // bodies: every rank holds the whole mesh and state (its nodes are local
    // everywhere, with their global ids) and assembles the elements Zoltan2
    // gives it; a node is owned by the lowest rank with an element on it.
    mpm_->distribute(comm, mesh_.num_nodes());
    mpm_distributed_ = true;
    if (mesh_.num_nodes() > 0) share_fem_mesh(comm);
    double m = mpm_min_particle_mass_;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MIN, m, Teuchos::outArg(mpm_min_particle_mass_));
  }
  if (!std::isfinite(mpm_min_particle_mass_)) mpm_min_particle_mass_ = 0.0;
  newton_ = std::make_unique<NewtonSolver<dim>>(comm, setup_.linear_solver, setup_.newton);
  sys_ = std::make_unique<System>();
  const bool fem_fem = setup_.contact && setup_.contact->fem_fem;
  if (comm->getSize() > 1 && !setup_.mpm && fem_fem) {
    // FEM only, with FEM-FEM contact: every rank holds the whole mesh (the
    // contact pairs need the whole boundary), assembles its elements and
    // evaluates the pairs of the boundary nodes it owns.
    share_fem_mesh(comm);
    std::vector<GO> ids(static_cast<std::size_t>(mesh_.num_nodes()));
    for (LO v = 0; v < mesh_.num_nodes(); ++v) ids[v] = v;
    newton_->set_partition(std::move(ids), fem_owned_);
    newton_->set_system(mesh_.num_nodes(), {local_elasticity_.get()});
  } else if (comm->getSize() > 1 && !setup_.mpm) {
    // FEM only: cut the elements into the ranks; Newton runs on this rank's piece.
    distributed_ = true;
    part_ = partition_fem_mesh<dim>(mesh_, comm);
    const FemMesh<dim> local = local_fem_mesh<dim>(mesh_, part_);
    local_elasticity_ = std::make_unique<DeformationTerm<dim, dim + 1>>("fem elasticity", local.elements);
    if (local.num_cells() > 0)
      local_elasticity_->set_coloring(color_stencils<dim + 1>(local.elements.nodes, local.num_nodes()));
    const std::size_t nl = part_.nodes.size() * dim;
    local_dof_ = Kokkos::View<LO*, MemSpace>("fem_local_dof", nl);
    auto ld = Kokkos::create_mirror_view(local_dof_);
    for (std::size_t a = 0; a < part_.nodes.size(); ++a)
      for (int c = 0; c < dim; ++c) ld(a * dim + c) = static_cast<LO>(part_.nodes[a] * dim + c);
    Kokkos::deep_copy(local_dof_, ld);
    lx_ = View1("fem_local_x", nl);
    lxhat_ = View1("fem_local_xhat", nl);
    lmass_ = View1("fem_local_mass", nl);
    ltarget_ = View1("fem_local_target", nl);
    lpres_ = Kokkos::View<int*, MemSpace>("fem_local_prescribed", nl);
    newton_->set_partition(part_.nodes, part_.n_owned);
    newton_->set_system(static_cast<LO>(part_.nodes.size()), {local_elasticity_.get()});
  }
  if (setup_.level_sets.size() > static_cast<std::size_t>(kMaxLevelSets))
    throw std::invalid_argument("scene has " + std::to_string(setup_.level_sets.size()) +
                                " level sets; expected at most " + std::to_string(kMaxLevelSets));
  for (const auto& ls : setup_.level_sets) level_sets_.sets[level_sets_.count++] = ls;
  if (!mpm_ && !distributed_ && !fem_shared_) newton_->set_system(mesh_.num_nodes(), {elasticity_.get()});
  const std::size_t n = static_cast<std::size_t>(mesh_.num_nodes()) * dim;
  x_ = View1("fem_x", n);
  v_ = View1("fem_v", n);
  a_ = View1("fem_a", n);
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
  motions_ = device_motions(setup_.motions);
  if (setup_.contact && (mpm_ || setup_.contact->fem_fem) && mesh_.num_nodes() > 0) {
    contact_ = std::make_unique<Contact<dim>>(mesh_, *setup_.contact);
    // FEM-FEM on several ranks: each FEM contact point on the rank owning its node.
    if (fem_shared_ && contact_->num_fem_points() > 0) contact_->keep_fem_points(fem_owned_);
    // (MPI: each rank checks its particles; all stop with the first failing rank's message.)
    if (mpm_) collective_check(*comm, [&] { contact_->check_initial(mpm_->particles(), x_, mpm_->particle_ids()); });
    else contact_->check_initial_fem(x_);
    if (setup_.contact->check_iterates)
      newton_->on_iterate = [this](Kokkos::View<const double*, MemSpace> x) {
        const LO q = contact_->particle_inside_at(x);
        const LO np = mpm_ ? static_cast<LO>(mpm_->particles().size()) : 0;
        if (mpm_distributed_ || fem_shared_) {  // the highest global particle id and FEM node inside, on every rank
          long long mine[2] = {-1, -1}, id[2] = {-1, -1};
          if (q >= 0 && q < np) Kokkos::deep_copy(mine[0], Kokkos::subview(mpm_->particle_ids(), q));
          if (q >= np) mine[1] = contact_->fem_point_node(q - np);
          Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, 2, mine, id);
          if (id[0] >= 0)
            throw SolverError("MPM particle " + std::to_string(id[0]) +
                              " is inside or on an FEM body at a Newton iterate (Contact/check iterates)");
          if (id[1] >= 0)
            throw SolverError("FEM boundary node " + std::to_string(id[1]) +
                              " is inside or on another FEM body at a Newton iterate (Contact/check iterates)");
          return;
        }
        if (q < 0) return;
        long long id = q;  // sorted particles: name the particle by its id
        if (q < np && !mpm_->particles_in_id_order()) Kokkos::deep_copy(id, Kokkos::subview(mpm_->particle_ids(), q));
        if (q >= np)  // named as on several ranks: by its mesh node
          throw SolverError("FEM boundary node " + std::to_string(contact_->fem_point_node(q - np)) +
                            " is inside or on another FEM body at a Newton iterate (Contact/check iterates)");
        throw SolverError("MPM particle " + std::to_string(id) +
                          " is inside or on an FEM body at a Newton iterate (Contact/check iterates)");
      };
  }
  reset_acceleration();
}

// Several ranks, the whole FEM mesh on each: Zoltan2 RCB of the elements;
// this rank's elements with global node ids; a node is owned by the lowest
// rank with an element on it.
template <int dim>
void Simulation<dim>::share_fem_mesh(const Teuchos::RCP<const Comm>& comm) {
  part_ = partition_fem_mesh<dim>(mesh_, comm);
  FemPartition global_ids = part_;
  global_ids.nodes.resize(mesh_.num_nodes());
  for (LO v = 0; v < mesh_.num_nodes(); ++v) global_ids.nodes[v] = v;
  local_elasticity_ =
      std::make_unique<DeformationTerm<dim, dim + 1>>("fem elasticity", local_fem_mesh<dim>(mesh_, global_ids).elements);
  if (!part_.elements.empty())
    local_elasticity_->set_coloring(color_stencils<dim + 1>(local_elasticity_->stencils().nodes, mesh_.num_nodes()));
  fem_owned_.assign(mesh_.num_nodes(), 0);
  for (LO a = 0; a < part_.n_owned; ++a) fem_owned_[part_.nodes[a]] = 1;
  fem_shared_ = true;
}

template <int dim>
Simulation<dim>::~Simulation() = default;

template <int dim>
std::vector<std::string> Simulation<dim>::term_names() const {
  std::vector<std::string> names;
  if (mesh_.num_nodes() > 0) names.push_back(elasticity_->name());
  if (mpm_) names.push_back(mpm_->term().name());
  if (contact_) {
    names.push_back(contact_->barrier()->name());
    if (contact_->has_friction()) names.push_back(contact_->friction()->name());
  }
  return names;
}

template <int dim>
void Simulation<dim>::reset_acceleration() {
  auto a = a_;
  auto m = mass_;
  auto pres = prescribed_;
  Kokkos::deep_copy(a, 0.0);
  if (distributed_ || (fem_shared_ && !mpm_))
    elasticity_->gradient(x_, -1.0, a);  // the replicated whole mesh (Newton's term is local)
  else newton_->potential_gradient(x_, -1.0, a);
  const auto g = setup_.gravity;
  Kokkos::parallel_for(
      "fem_a0", Kokkos::RangePolicy<ExecSpace>(0, a.extent(0)), KOKKOS_LAMBDA(const LO i) {
        a(i) = pres(i) ? 0.0 : a(i) / m(i) + g[i % dim];
      });
}

template <int dim>
void Simulation<dim>::apply_prescribed_targets(double t, View1 target) const {
  const auto mo = motions_;
  const auto X0 = initial_position_;
  Kokkos::parallel_for(
      "fem_prescribed_targets", Kokkos::RangePolicy<ExecSpace>(0, mo.size()), KOKKOS_LAMBDA(const LO k) {
        const LO node = mo.node(k);
        Vec<dim> X;
        for (int c = 0; c < dim; ++c) X(c) = X0(node * dim + c);
        const Vec<dim> p = motion_position<dim>(&mo.segments(mo.range(k, 0)), mo.range(k, 1), X, t);
        for (int c = 0; c < dim; ++c) target(node * dim + c) = p(c);
      });
}

template <int dim>
void Simulation<dim>::prescribed_velocities(double t1) {
  if (motions_.size() == 0) return;
  const double dt = setup_.dt;
  const auto mo = motions_;
  const auto X0 = initial_position_;
  auto v = v_;
  auto a = a_;
  Kokkos::parallel_for(
      "fem_prescribed_velocities", Kokkos::RangePolicy<ExecSpace>(0, mo.size()), KOKKOS_LAMBDA(const LO k) {
        const LO node = mo.node(k);
        Vec<dim> X;
        for (int c = 0; c < dim; ++c) X(c) = X0(node * dim + c);
        const Vec<dim> vel = motion_velocity<dim>(&mo.segments(mo.range(k, 0)), mo.range(k, 1), X, t1);
        for (int c = 0; c < dim; ++c) {
          a(node * dim + c) = (vel(c) - v(node * dim + c)) / dt;
          v(node * dim + c) = vel(c);
        }
      });
}

// Grid nodes that a particle's stencil reaches with weight 0 (a particle at a
// cell centre is 1.5 dx from the far nodes, where the quadratic B-spline and
// its gradient vanish: 9 particles per cell in 2D, 27 in 3D) carry no mass
// and no stiffness, so the Newton matrix would be singular there. They take
// no part in any transfer; hold them in place (prescribed, v = 0, mass 0).
// "No mass": below 1e-12 of the heaviest node (round-off of a zero weight).
// Nodes just above it (a cell-centre particle that moved by delta dx reaches
// them with weight delta^2 / 2) stay free, so momentum is kept exactly; the
// Newton convergence test weighs them by their mass (IncrementalPotential::
// weight), since their direction is round-off.
namespace {
void hold_massless_grid_nodes(std::size_t first, std::size_t n, View1 x, View1 v, View1 mass, View1 target,
                              Kokkos::View<int*, MemSpace> pres, const Comm& comm) {
  double mmax = 0;
  Kokkos::parallel_reduce(
      "grid_mass_max", Kokkos::RangePolicy<ExecSpace>(first, n),
      KOKKOS_LAMBDA(const std::size_t i, double& m) { m = mass(i) > m ? mass(i) : m; }, Kokkos::Max<double>(mmax));
  if (comm.getSize() > 1) {  // the heaviest node of all ranks (the same floor everywhere)
    const double mine = mmax;
    Teuchos::reduceAll(comm, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(mmax));
  }
  const double floor = 1e-12 * mmax;
  Kokkos::parallel_for(
      "grid_hold_massless", Kokkos::RangePolicy<ExecSpace>(first, n), KOKKOS_LAMBDA(const std::size_t i) {
        if (mass(i) > floor) return;
        pres(i) = 1;
        mass(i) = 0.0;
        v(i) = 0.0;
        target(i) = x(i);
      });
}
}  // namespace

// MPI: the contact report of every rank's pairs.
template <int dim>
void Simulation<dim>::reduce_report(typename Contact<dim>::Report& r) const {
  const Comm& c = *comm_;
  const long long pairs = r.pairs;
  long long all_pairs = 0;
  Teuchos::reduceAll(c, Teuchos::REDUCE_SUM, pairs, Teuchos::outArg(all_pairs));
  r.pairs = static_cast<LO>(all_pairs);
  double sums[4] = {r.barrier_energy, r.force[0], r.force[1], r.force[2]}, s[4];
  Teuchos::reduceAll(c, Teuchos::REDUCE_SUM, 4, sums, s);
  r.barrier_energy = s[0];
  r.force = {s[1], s[2], s[3]};
  double mins[5] = {r.min_distance, r.ccd_alpha_min, r.extent_lo[0], r.extent_lo[1], r.extent_lo[2]}, mn[5];
  Teuchos::reduceAll(c, Teuchos::REDUCE_MIN, 5, mins, mn);
  r.min_distance = mn[0];
  r.ccd_alpha_min = mn[1];
  r.extent_lo = {mn[2], mn[3], mn[4]};
  double maxs[3] = {r.extent_hi[0], r.extent_hi[1], r.extent_hi[2]}, mx[3];
  Teuchos::reduceAll(c, Teuchos::REDUCE_MAX, 3, maxs, mx);
  r.extent_hi = {mx[0], mx[1], mx[2]};
}

template <int dim>
StepReport Simulation<dim>::step() {
  Kokkos::Timer timer;
  const double dt = setup_.dt;
  const double t1 = time_ + dt;
  newton_->new_time_step();
  const TimeIntegrator& ti = setup_.integrator;
  const double h = ti.potential_scale(dt);
  const double ca = ti.predictor_acc_scale(dt);
  const auto g = setup_.gravity;
  const LO nF = mesh_.num_nodes();
  const LO nA = mpm_ ? mpm_->begin_step(nF, step_ + 1) : 0;
  const std::size_t nfd = static_cast<std::size_t>(nF) * dim;
  const std::size_t nd = nfd + static_cast<std::size_t>(nA) * dim;
  System& S = *sys_;
  S.resize(nd);
  auto x = System::head(S.x, nd);
  auto v = System::head(S.v, nd);
  auto v_old = System::head(S.v_old, nd);
  auto a = System::head(S.a, nd);
  auto xhat = System::head(S.x_hat, nd);
  auto target = System::head(S.target, nd);
  auto mass = System::head(S.mass, nd);
  auto pres = System::head(S.prescribed, nd);
  auto fem = std::make_pair(std::size_t(0), nfd);
  Kokkos::deep_copy(Kokkos::subview(x, fem), x_);
  Kokkos::deep_copy(Kokkos::subview(v, fem), v_);
  Kokkos::deep_copy(Kokkos::subview(a, fem), a_);
  Kokkos::deep_copy(Kokkos::subview(mass, fem), mass_);
  Kokkos::deep_copy(Kokkos::subview(pres, fem), prescribed_);
  std::vector<EnergyTerm<dim>*> terms;
  bool graph_rebuilt = false;
  if (nF > 0) terms.push_back(fem_shared_ ? local_elasticity_.get() : elasticity_.get());
  if (mpm_) {
    auto grid_part = std::make_pair(nfd, nd);
    Kokkos::deep_copy(Kokkos::subview(pres, grid_part), 0);
    mpm_->fill_system(x, v, mass);
    hold_massless_grid_nodes(nfd, nd, x, v, mass, target, pres, *comm_);
    apply_level_sets<dim>(level_sets_, time_, dt, nfd, nd, x, v, target, pres);
    newton_->slip_constraints().build(level_sets_, time_, dt, nfd, nd, x, v, pres);  // slip: n . v = n . v_b
    terms.push_back(&mpm_->term());
    if (contact_) {
      contact_->begin_step(*mpm_, x);
      terms.push_back(contact_->barrier());
      if (contact_->has_friction()) terms.push_back(contact_->friction());
    }
    if (mpm_distributed_) {  // FEM nodes (global ids 0..nF-1) then this rank's grid nodes
      std::vector<GO> ids(static_cast<std::size_t>(nF));
      for (LO v = 0; v < nF; ++v) ids[v] = v;
      ids.insert(ids.end(), mpm_->global_nodes().begin(), mpm_->global_nodes().end());
      std::vector<char> owned = fem_owned_;
      owned.resize(ids.size(), 0);
      for (LO k = 0; k < mpm_->owned_nodes(); ++k) owned[nF + k] = 1;
      newton_->set_partition(std::move(ids), owned);
    }
    graph_rebuilt = newton_->set_system(nF + nA, terms);
    // Grid a^n = g - M^-1 grad Psi(x^n): the Newmark predictor and velocity
    // update need it; backward Euler (no a^n term in either) does not.
    const std::size_t off = nfd;
    if (ca != 0.0 || ti.gamma != 1.0) {
      auto work = System::head(S.work, nd);
      Kokkos::deep_copy(work, 0.0);
      newton_->potential_gradient(x, -1.0, work);
      newton_->sum_shared(work);  // MPI: this rank's particles' share, summed at shared nodes
      Kokkos::parallel_for(
          "grid_a0", Kokkos::RangePolicy<ExecSpace>(off, nd),
          KOKKOS_LAMBDA(const std::size_t i) { a(i) = mass(i) > 0 ? work(i) / mass(i) + g[i % dim] : 0.0; });
    } else {
      Kokkos::deep_copy(Kokkos::subview(a, std::make_pair(off, nd)), 0.0);
    }
    Kokkos::deep_copy(v_old, v);
  } else if (contact_) {  // FEM bodies only, in contact with each other
    contact_->begin_step(nullptr, x);
    terms.push_back(contact_->barrier());
    if (contact_->has_friction()) terms.push_back(contact_->friction());
    graph_rebuilt = newton_->set_system(nF, terms);
  }
  Kokkos::parallel_for(
      "predictor", Kokkos::RangePolicy<ExecSpace>(0, nd), KOKKOS_LAMBDA(const std::size_t i) {
        xhat(i) = x(i) + dt * v(i) + ca * a(i) + h * g[i % dim];
      });
  if (motions_.size() > 0) apply_prescribed_targets(t1, target);

  IncrementalPotential ip{xhat, mass, pres, target, h, dt};
  if (mpm_) {
    auto w = System::head(S.weight, nd);
    const double m_ref = mpm_min_particle_mass_;
    Kokkos::parallel_for(
        "newton_weight", Kokkos::RangePolicy<ExecSpace>(0, nd), KOKKOS_LAMBDA(const std::size_t i) {
          w(i) = i < nfd ? 1.0 : (mass(i) >= m_ref ? 1.0 : mass(i) / m_ref);
        });
    ip.weight = w;
  }
  NewtonStats ns;
  int friction_iters = 0;
  auto minimize_step = [&]() {
    if (contact_ && contact_->has_friction()) {
      // dt v^{n+1} = s (x - x_ref) for the integrator's velocity update.
      const double gm = ti.gamma, s = gm * dt * dt / h;
      auto xref = System::head(S.x_ref, nd);
      Kokkos::parallel_for(
          "friction_x_ref", Kokkos::RangePolicy<ExecSpace>(0, nd), KOKKOS_LAMBDA(const std::size_t i) {
            xref(i) = xhat(i) - h * g[i % dim] - (dt * v(i) + dt * dt * (1.0 - gm) * a(i)) / s;
          });
      ns = minimize_with_friction(ip, x, xref, s, friction_iters);
    } else {
      ns = distributed_ ? minimize_distributed(ip, x, System::head(S.work, nd)) : newton_->minimize(ip, x);
      friction_iters = 1;
    }
  };
  // Newton on the exact Hessian can stall where it is nearly singular (A6:
  // a period-5 cycle through one direction, each visit accepted with a step
  // of 4e-3). A step that fails so is redone from its start with the
  // projected Hessian, which converges there.
  const bool can_retry = newton_->hessian_mode() == HessianMode::ExactIfDefinite &&
                         newton_->linear_solver().kind() == LinearSolverKind::Cholmod && !distributed_ && !fem_shared_ &&
                         !mpm_distributed_;
  auto x_start = System::head(S.x_start, nd);
  if (can_retry) Kokkos::deep_copy(x_start, x);
  try {
    try {
      minimize_step();
    } catch (const NewtonStalled& e) {  // not a failed check ('Contact/check iterates') or a linear-solver error
      if (!can_retry) throw;
      Kokkos::deep_copy(x, x_start);
      newton_->new_time_step();
      struct ProjectedForThisStep {  // the mode comes back whatever the redo throws
        NewtonSolver<dim>& n;
        explicit ProjectedForThisStep(NewtonSolver<dim>& s) : n(s) { n.set_hessian_mode(HessianMode::Projected); }
        ~ProjectedForThisStep() { n.set_hessian_mode(HessianMode::ExactIfDefinite); }
      };
      {
        ProjectedForThisStep projected(*newton_);
        try {
          minimize_step();
        } catch (const SolverError& e2) {
          throw SolverError(std::string(e.what()) + "; redone with the projected Hessian: " + e2.what());
        }
      }
      ns.projected_retries = 1;
      if (comm_->getRank() == 0)
        std::cerr << "warning: step " << step_ + 1 << " (t = " << t1 << " s): " << e.what()
                  << " with the exact Hessian; redone with the projected Hessian (" << ns.iterations
                  << " iterations)\n";
    }
  } catch (const SolverError& e) {
    std::ostringstream msg;
    msg << "step " << step_ + 1 << " (t = " << t1 << " s): " << e.what();
    throw SolverError(msg.str());
  }
  if (graph_rebuilt) ++ns.graph_builds;
  typename Contact<dim>::Report contact_report;
  if (contact_) contact_report = contact_->report(x, nF);
  if (contact_ && (mpm_distributed_ || fem_shared_)) reduce_report(contact_report);
  if (contact_ && mpm_ && !mpm_->particles_in_id_order()) {
    // The particle contact forces follow this step's particle order, which
    // migration below (and the next step's sort) changes: keep their ids
    // for the output.
    const auto ids = mpm_->particle_ids();
    if (force_ids_.extent(0) != ids.extent(0)) force_ids_ = Kokkos::View<long long*, MemSpace>("contact_force_ids", ids.extent(0));
    Kokkos::deep_copy(force_ids_, ids);
    contact_reported_ = true;  // on every rank, with or without particles
  }

  const double gamma = ti.gamma;
  Kokkos::parallel_for(
      "velocity_update", Kokkos::RangePolicy<ExecSpace>(0, nd), KOKKOS_LAMBDA(const std::size_t i) {
        if (pres(i)) return;
        const double a1 = (x(i) - xhat(i)) / h + g[i % dim];
        v(i) += dt * ((1.0 - gamma) * a(i) + gamma * a1);
        a(i) = a1;
      });
  if (mpm_) newton_->slip_constraints().project_velocities(v);
  Kokkos::deep_copy(x_, Kokkos::subview(x, fem));
  Kokkos::deep_copy(v_, Kokkos::subview(v, fem));
  Kokkos::deep_copy(a_, Kokkos::subview(a, fem));
  prescribed_velocities(t1);
  if (mpm_) {
    mpm_->end_step(x, v, v_old);
    mpm_->migrate();  // MPI: particles that left this rank's box
  }
  time_ = t1;
  ++step_;
  StepReport r = diagnostics();
  r.newton = ns;
  if (contact_) {
    r.contact_pairs = contact_report.pairs;
    r.min_distance = contact_report.min_distance;
    r.barrier_energy = contact_report.barrier_energy;
    r.ccd_alpha_min = contact_report.ccd_alpha_min;
    r.contact_force = contact_report.force;
    for (int c = 0; c < 3; ++c) {
      const bool none = !(contact_report.extent_lo[c] <= contact_report.extent_hi[c]);
      r.contact_lo[c] = none ? std::numeric_limits<double>::quiet_NaN() : contact_report.extent_lo[c];
      r.contact_hi[c] = none ? std::numeric_limits<double>::quiet_NaN() : contact_report.extent_hi[c];
    }
    r.friction_iters = friction_iters;
    r.contact_broad_phase_s = contact_report.timings.broad_phase_s;
    r.contact_eval_s = contact_report.timings.evaluation_s;
    r.contact_ccd_s = contact_report.timings.ccd_s;
    r.contact_searches = contact_report.timings.searches;
    r.contact_searches_all = contact_report.timings.searches_all;
  }
  if (setup_.count_penetrations && mpm_) count_penetrations(r);
  r.step_s = timer.seconds();
  return r;
}

template <int dim>
NewtonStats Simulation<dim>::minimize_distributed(const IncrementalPotential& ip, View1 x, View1 work) {
  const auto ld = local_dof_;
  auto lx = lx_, lxh = lxhat_, lm = lmass_, lt = ltarget_;
  auto lp = lpres_;
  const auto xh = ip.x_hat, m = ip.mass, t = ip.target;
  const auto p = ip.prescribed;
  Kokkos::parallel_for(
      "fem_gather_local", Kokkos::RangePolicy<ExecSpace>(0, ld.extent(0)), KOKKOS_LAMBDA(const LO k) {
        const LO i = ld(k);
        lx(k) = x(i);
        lxh(k) = xh(i);
        lm(k) = m(i);
        lt(k) = t(i);
        lp(k) = p(i);
      });
  IncrementalPotential lip{lxhat_, lmass_, lpres_, ltarget_, ip.h, ip.dt};
  const NewtonStats st = newton_->minimize(lip, lx_);
  // Each rank's owned DOFs into the replicated x (a sum: every DOF has one owner).
  const LO n_own = static_cast<LO>(part_.n_owned) * dim;
  Kokkos::deep_copy(work, 0.0);
  Kokkos::parallel_for(
      "fem_scatter_owned", Kokkos::RangePolicy<ExecSpace>(0, n_own),
      KOKKOS_LAMBDA(const LO k) { work(ld(k)) = lx(k); });
  Kokkos::fence();
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, static_cast<int>(x.extent(0)), work.data(), x.data());
  return st;
}

template <int dim>
void Simulation<dim>::count_penetrations(StepReport& r) {
  const auto& p = mpm_->particles();
  const LO np = static_cast<LO>(p.size());
  if (penetration_xp_.extent(0) != static_cast<std::size_t>(np) * dim)
    penetration_xp_ = Kokkos::View<double*, MemSpace>("penetration_xp", static_cast<std::size_t>(np) * dim);
  const auto xp = penetration_xp_;
  interleaved_positions(p, xp);
  auto px = p.x;
  long fem_count = 0;
  if (contact_) fem_count = contact_->count_inside(xp, x_);
  const LevelSetList ls = level_sets_;
  const double t = time_;
  long ls_count = 0;
  double depth = 0;
  Kokkos::parallel_reduce(
      "penetration_level_sets", Kokkos::RangePolicy<ExecSpace>(0, np),
      KOKKOS_LAMBDA(const LO q, long& n, double& d) {
        Vec<dim> xq;
        for (int c = 0; c < dim; ++c) xq(c) = px(q, c);
        double phi = 1e300;
        for (int k = 0; k < ls.count; ++k) phi = std::fmin(phi, ls.sets[k].template phi<dim>(xq, t));
        if (phi < 0) {
          ++n;
          d = -phi > d ? -phi : d;
        }
      },
      ls_count, Kokkos::Max<double>(depth));
  if (mpm_distributed_) {  // every rank's particles
    const long n[2] = {ls_count, fem_count};
    long sum[2] = {0, 0};
    const double d = depth;
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, 2, n, sum);
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, d, Teuchos::outArg(depth));
    ls_count = sum[0];
    fem_count = sum[1];
  }
  r.penetrations = fem_count + ls_count;
  r.penetrations_fem = fem_count;
  r.penetrations_level_set = ls_count;
  r.penetration_depth = ls_count > 0 ? depth : 0.0;  // (the Max reducer starts at -DBL_MAX)
}

// Algorithm 1 lines 5-10: lag friction at x^n, minimise, re-lag at the
// result, repeat until the first Newton direction of a re-solve is below
// eps_d (the friction update no longer moves the solution) or the cap.
// Passes whose lagged values will change again need not be minimised to
// eps_d: while the loop has not settled, Newton stops at
// 'Contact/friction pass tolerance' x eps_d; once a pass converges within
// that at its first iteration, and from the pass before the cap on, the
// passes stop at eps_d, as does every pass without lagged friction pairs
// (so the no-pairs exit below follows a pass at eps_d). The loop's end test
// is the paper's, at eps_d, either way. Caps of 1 or 2 run every pass at
// eps_d (the pass before the cap would be the first).
template <int dim>
NewtonStats Simulation<dim>::minimize_with_friction(const IncrementalPotential& ip, View1 x, View1 x_ref, double s,
                                                    int& iterations) {
  NewtonStats total;
  const int cap = contact_->friction_max_iterations();
  // Lagged friction is a fixed-point iteration x_{j+1} = G(x_j) (each pass
  // minimises with friction lagged at x_j). Where it oscillates (A6 at the
  // paper's size: the outer ring's top nodes under the mu = 10 plate slide
  // back and forth by ~5e-4 m between passes, never converging in 60), the
  // passes from pass relax_from on (from the third at the earliest: Aitken
  // needs two residuals) are lagged at an Aitken-relaxed point,
  //   x_lag <- x_lag + omega_j r_j,   r_j = G(x_lag) - x_lag,
  //   omega_j = -omega_{j-1} r_{j-1}.(r_j - r_{j-1}) / |r_j - r_{j-1}|^2,
  // clamped to [0.05, 1] (plain lagging is omega = 1); the fixed point is
  // the same. The loop then ends only when x_lag is within eps_d dt of x.
  // Dot products over owned DOFs, summed over the ranks.
  const int relax_from = contact_->friction_relaxation_from() > 0 ? contact_->friction_relaxation_from() : 1 << 30;
  const std::size_t nd = x.extent(0);
  auto xl = System::head(sys_->x_lag, nd);
  auto rp = System::head(sys_->lag_r, nd);
  Kokkos::deep_copy(xl, x);
  double omega = 1.0, lag_gap = 0.0;
  int pass = 0;
  // The lag point of the next pass: x (plain lagging), or from pass
  // relax_from on x_lag + omega (x - x_lag) with Aitken's omega.
  auto next_lag_point = [&] {
    ++pass;
    const bool dist = newton_->dof_space().distributed();
    const auto own = newton_->dof_space().owned_mask();
    const auto xx = x;
    const auto l = xl;
    const auto r_prev = rp;
    double sums[2] = {0, 0};  // r_prev . (r - r_prev), |r - r_prev|^2
    if (pass + 1 >= relax_from && pass >= 2) {  // the lag point of pass `pass + 1`
      Kokkos::parallel_reduce(
          "friction_aitken", Kokkos::RangePolicy<ExecSpace>(0, nd),
          KOKKOS_LAMBDA(const std::size_t i, double& a, double& b) {
            if (dist && !own(i)) return;
            const double d = (xx(i) - l(i)) - r_prev(i);
            a += r_prev(i) * d;
            b += d * d;
          },
          sums[0], sums[1]);
      if (comm_->getSize() > 1) {
        double all[2];
        Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, 2, sums, all);
        sums[0] = all[0];
        sums[1] = all[1];
      }
      omega = sums[1] > 0 ? -omega * sums[0] / sums[1] : omega;
      omega = std::min(1.0, std::max(0.05, omega));
    } else {
      omega = 1.0;
    }
    const double w = omega;
    double gap = 0;
    Kokkos::parallel_reduce(
        "friction_lag_point", Kokkos::RangePolicy<ExecSpace>(0, nd),
        KOKKOS_LAMBDA(const std::size_t i, double& g) {
          const double r = xx(i) - l(i);
          r_prev(i) = r;
          l(i) += w * r;
          const double left = std::fabs((1.0 - w) * r);
          g = left > g ? left : g;
        },
        Kokkos::Max<double>(gap));
    if (comm_->getSize() > 1) {
      double all = 0;
      Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, gap, Teuchos::outArg(all));
      gap = all;
    }
    lag_gap = gap;
  };
  auto update = [&] {  // pairs with friction, over all ranks
    LO n = contact_->update_friction(xl, x_ref, s, ip.dt);
    if (mpm_distributed_ || fem_shared_) {
      const LO mine = n;
      Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, mine, Teuchos::outArg(n));
    }
    return n;
  };
  LO lagged = update();  // line 5: lagged at x^n
  const double eps_d = setup_.newton.eps_d, loose_eps = contact_->friction_pass_tolerance() * eps_d;
  bool loose = loose_eps > eps_d && cap > 2;
  for (iterations = 1;; ++iterations) {
    if (iterations >= cap - 1) loose = false;
    const NewtonStats st = newton_->minimize(ip, x, loose && lagged > 0 ? loose_eps : 0.0);
    total.iterations += st.iterations;
    total.linear_iterations += st.linear_iterations;
    total.assembly_s += st.assembly_s;
    total.solve_s += st.solve_s;
    total.line_search_s += st.line_search_s;
    total.min_step = std::min(total.min_step, st.min_step);
    total.first_p_dt = st.first_p_dt;
    total.graph_builds += st.graph_builds;
    total.symbolic_factorizations += st.symbolic_factorizations;
    total.numeric_factorizations += st.numeric_factorizations;
    total.factor_s += st.factor_s;
    total.reuse_cg_s += st.reuse_cg_s;
    total.reuse_cg_iterations += st.reuse_cg_iterations;
    total.stale_retries += st.stale_retries;
    total.exact_hessian_iterations += st.exact_hessian_iterations;
    total.projection_fallbacks += st.projection_fallbacks;
    total.partial_projections += st.partial_projections;
    total.wolfe_steps += st.wolfe_steps;
    total.wolfe_gradients += st.wolfe_gradients;
    if (iterations > 1 && st.first_p_dt < eps_d && lag_gap < eps_d * ip.dt) break;  // converged at the lagged update
    if (loose && iterations > 1 && st.iterations == 1) loose = false;  // settled: the last passes at eps_d
    next_lag_point();
    const LO relagged = update();
    if (lagged == 0 && relagged == 0) break;  // no friction pairs before or after
    lagged = relagged;
    if (iterations == cap) {
      if (comm_->getRank() == 0) std::cerr << "warning: step " << step_ + 1 << ": friction not converged in " << cap
                << " outer iterations ('Contact/friction iterations')\n";
      break;
    }
  }
  return total;
}

template <int dim>
StepReport Simulation<dim>::diagnostics() const {
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
  // FEM elastic energy: the sum of the bodies' (computed below) when the
  // bodies cover every element, else one pass over the whole mesh.
  LO body_cells = 0;
  for (const auto& b : mesh_.bodies) body_cells += b.num_cells;
  const bool bodies_cover = body_cells == mesh_.num_cells();
  r.elastic = bodies_cover ? 0.0 : deformation_energy(mesh_.elements, x_);
  r.min_J = mesh_.num_cells() > 0 ? deformation_min_J(mesh_.elements, x_) : 1.0;
  {
    auto X = x_;
    double L = 0;
    Kokkos::parallel_reduce(
        "fem_angular_momentum", Kokkos::RangePolicy<ExecSpace>(0, mesh_.num_nodes()),
        KOKKOS_LAMBDA(const LO n, double& l) {
          l += m(n * dim) * (X(n * dim) * v(n * dim + 1) - X(n * dim + 1) * v(n * dim));
        },
        L);
    r.angular_momentum_z = L;
  }
  // MPM: every body's sums in one pass over the particles; the totals are
  // their sum.
  std::vector<typename MpmBodies<dim>::Diagnostics> mpm_bodies;
  if (mpm_) {
    mpm_bodies = mpm_->body_diagnostics(setup_.gravity);
    for (const auto& d : mpm_bodies) {
      r.kinetic += d.kinetic;
      r.elastic += d.elastic;
      r.potential += d.potential;
      for (int c = 0; c < 3; ++c) r.momentum[c] += d.momentum[c];
      r.angular_momentum_z += d.angular;
    }
    double mpm_J = mpm_particle_min_J(mpm_->particles());
    long long grid_nodes = mpm_->owned_nodes();
    if (mpm_distributed_) {  // all ranks' particles; each grid node counted at its owner
      const double j = mpm_J;
      const long long g = grid_nodes;
      Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MIN, j, Teuchos::outArg(mpm_J));
      Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, g, Teuchos::outArg(grid_nodes));
    }
    r.min_J = std::min(r.min_J, mpm_J);
    r.active_grid_nodes = grid_nodes;
  }
  for (const auto& b : mesh_.bodies) {
    BodyReport br;
    double M = 0, k = 0, X[3] = {0, 0, 0}, P[3] = {0, 0, 0};
    const LO i0 = b.first_node * dim, i1 = (b.first_node + b.num_nodes) * dim;
    Kokkos::parallel_reduce(
        "fem_body_diagnostics", Kokkos::RangePolicy<ExecSpace>(i0, i1),
        KOKKOS_LAMBDA(const LO i, double& mm, double& kk, double& x0, double& x1, double& x2, double& q0,
                      double& q1, double& q2) {
          const int c = i % dim;
          if (c == 0) mm += m(i);
          kk += 0.5 * m(i) * v(i) * v(i);
          const double mx = m(i) * x(i), mv = m(i) * v(i);
          if (c == 0) x0 += mx, q0 += mv;
          if (c == 1) x1 += mx, q1 += mv;
          if (c == 2) x2 += mx, q2 += mv;
        },
        M, k, X[0], X[1], X[2], P[0], P[1], P[2]);
    br.mass = M;
    br.kinetic = k;
    br.elastic = deformation_energy(mesh_.elements, x_, b.first_cell, b.first_cell + b.num_cells);
    if (bodies_cover) r.elastic += br.elastic;
    for (int c = 0; c < dim; ++c) {
      br.com[c] = M > 0 ? X[c] / M : 0.0;
      br.velocity[c] = M > 0 ? P[c] / M : 0.0;
    }
    r.bodies.push_back(br);
  }
  if (mpm_) {
    for (std::size_t b = 0; b < mpm_->body_names().size(); ++b) {
      const auto& d = mpm_bodies[b];
      BodyReport br;
      br.mass = d.mass;
      br.kinetic = d.kinetic;
      br.elastic = d.elastic;
      for (int c = 0; c < dim; ++c) {
        br.com[c] = d.mass > 0 ? d.first_moment[c] / d.mass : 0.0;
        br.velocity[c] = d.mass > 0 ? d.momentum[c] / d.mass : 0.0;
      }
      r.bodies.push_back(br);
    }
  }
  return r;
}

template <int dim>
std::vector<std::string> Simulation<dim>::body_names() const {
  std::vector<std::string> names;
  for (const auto& b : mesh_.bodies) names.push_back(b.name);
  if (mpm_)
    for (const auto& n : mpm_->body_names()) names.push_back(n);
  return names;
}

template <int dim>
void Simulation<dim>::element_J(View1 J) const {
  deformation_J_von_mises(mesh_.elements, x_, J, View1());
}

template <int dim>
void Simulation<dim>::element_von_mises(View1 s) const {
  View1 J("fem_J_tmp", mesh_.num_cells());
  deformation_J_von_mises(mesh_.elements, x_, J, s);
}

template class Simulation<2>;
template class Simulation<3>;

}  // namespace bfemp
