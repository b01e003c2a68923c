#include "contact/contact.hpp"

#include <limits>
#include <sstream>
#include <stdexcept>

#include "kernels/contact/point_in_simplex.hpp"

namespace bfemp {

template <int dim>
Contact<dim>::Contact(const FemMesh<dim>& mesh, ContactParams params) : mesh_(mesh), params_(std::move(params)) {
  barrier_ = std::make_unique<BarrierTerm<dim>>(boundary_primitives(mesh), params_.dhat, params_.kappa);
  bool any_mu = false;
  for (double m : params_.mu) any_mu = any_mu || m > 0;
  if (any_mu)
    friction_ = std::make_unique<FrictionTerm<dim>>(*barrier_, params_.mu, static_cast<int>(mesh.bodies.size()),
                                                    params_.eps_v);
}

template <int dim>
LO Contact<dim>::particle_inside(ConstDofView xp, ConstDofView x) const {
  const auto& el = mesh_.elements;
  const LO np = static_cast<LO>(xp.extent(0) / dim);
  if (el.size() == 0 || np == 0) return -1;
  // Hash the elements, query the particles; inside or on an element counts.
  simplex_boxes<dim, dim + 1>(el.nodes, x, ConstDofView(), 0.0, element_boxes_);
  point_boxes<dim>(xp, ConstDofView(), 0.0, point_boxes_);
  element_hash_.build(element_boxes_);
  const LO n = element_hash_.query(point_boxes_, inside_pairs_);
  const auto pairs = inside_pairs_;
  const auto nodes = el.nodes;
  LO bad = -1;
  Kokkos::parallel_reduce(
      "contact_inside", Kokkos::RangePolicy<ExecSpace>(0, n),
      KOKKOS_LAMBDA(const LO k, LO& acc) {
        Vec<dim> v[dim + 1];
        for (int a = 0; a <= dim; ++a) v[a] = load_vec<dim>(x, nodes(pairs(k, 1), a));
        if (point_in_simplex<dim>(load_vec<dim>(xp, pairs(k, 0)), v, 0.0) && pairs(k, 0) > acc) acc = pairs(k, 0);
      },
      Kokkos::Max<LO>(bad));
  return bad;
}

template <int dim>
LO Contact<dim>::count_inside(ConstDofView xp, ConstDofView x) const {
  const auto& el = mesh_.elements;
  const LO np = static_cast<LO>(xp.extent(0) / dim);
  if (el.size() == 0 || np == 0) return 0;
  simplex_boxes<dim, dim + 1>(el.nodes, x, ConstDofView(), 0.0, element_boxes_);
  point_boxes<dim>(xp, ConstDofView(), 0.0, point_boxes_);
  element_hash_.build(element_boxes_);
  const LO n = element_hash_.query(point_boxes_, inside_pairs_);
  if (static_cast<LO>(inside_flag_.extent(0)) != np) inside_flag_ = Kokkos::View<int*, MemSpace>("contact_inside_flag", np);
  Kokkos::deep_copy(inside_flag_, 0);
  const auto pairs = inside_pairs_;
  const auto nodes = el.nodes;
  const auto flag = inside_flag_;
  Kokkos::parallel_for(
      "contact_inside_flag", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const LO k) {
        Vec<dim> v[dim + 1];
        for (int a = 0; a <= dim; ++a) v[a] = load_vec<dim>(x, nodes(pairs(k, 1), a));
        if (point_in_simplex<dim>(load_vec<dim>(xp, pairs(k, 0)), v, 0.0)) flag(pairs(k, 0)) = 1;  // same value: no race
      });
  LO count = 0;
  Kokkos::parallel_reduce(
      "contact_inside_count", Kokkos::RangePolicy<ExecSpace>(0, np),
      KOKKOS_LAMBDA(const LO q, LO& acc) { acc += flag(q); }, count);
  return count;
}

template <int dim>
LO Contact<dim>::particle_inside_at(ConstDofView x) const {
  Kokkos::View<double*, MemSpace> xp("contact_inside_xp", static_cast<std::size_t>(ps_.size()) * dim);
  interpolate_particles(ps_, x, xp);
  return particle_inside(xp, x);
}

template <int dim>
void Contact<dim>::check_initial(const Particles<dim>& p, ConstDofView x_fem) const {
  const LO np = static_cast<LO>(p.size());
  Kokkos::View<double*, MemSpace> xp("contact_check_xp", static_cast<std::size_t>(np) * dim);
  interleaved_positions(p, xp);
  const LO bad = particle_inside(xp, x_fem);
  if (bad < 0) return;
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  std::ostringstream msg;
  msg << "MPM particle " << bad << " at (";
  for (int c = 0; c < dim; ++c) msg << (c ? ", " : "") << h(bad, c);
  msg << ") starts inside or on an FEM body: the MPM and FEM bodies must not intersect or touch at t = 0 "
         "(paper Eq. 15); move the bodies apart";
  throw std::invalid_argument(msg.str());
}

template <int dim>
void Contact<dim>::begin_step(const MpmBodies<dim>& mpm, ConstDofView x) {
  constexpr int ns = ParticleStencils<dim>::ns;
  const auto& p = mpm.particles();
  const LO np = static_cast<LO>(p.size());
  if (ps_.size() != np) {
    ps_.nodes = decltype(ps_.nodes)("contact_particle_nodes", np);
    ps_.w = decltype(ps_.w)("contact_particle_w", np);
    ps_.omega = Kokkos::View<double*, MemSpace>("contact_omega", np);
    ps_.body = p.body;
  }
  const auto grid = mpm.grid();
  const auto sys = mpm.system_node();
  const auto ps = ps_;
  Kokkos::parallel_for(
      "contact_particle_stencils", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const LO q) {
        const auto st = bspline_stencil(grid, particle_position(p, q));
        for (int a = 0; a < ns; ++a) {
          ps.nodes(q, a) = sys(node_index(grid, st, a));
          ps.w(q, a) = weight(st, a);
        }
        ps.omega(q) = particle_contact_weight<dim>(p.volume0(q));
      });
  barrier_->begin_step(ps_, x);
  if (friction_) friction_->clear();
}

template <int dim>
LO Contact<dim>::update_friction(ConstDofView x, ConstDofView x_ref, double s, double dt) {
  return friction_ ? friction_->update_lagged(x, x_ref, s, dt) : 0;
}

template <int dim>
typename Contact<dim>::Report Contact<dim>::report(ConstDofView x, LO n_fem_nodes) {
  Report r;
  const auto act = barrier_->active_pairs(x);
  r.pairs = act.count;
  double dmin = std::numeric_limits<double>::infinity();
  const auto d = act.distance;
  Kokkos::parallel_reduce(
      "contact_min_distance", Kokkos::RangePolicy<ExecSpace>(0, act.count),
      KOKKOS_LAMBDA(const LO k, double& acc) { acc = d(k) < acc ? d(k) : acc; }, Kokkos::Min<double>(dmin));
  r.min_distance = act.count > 0 ? dmin : std::numeric_limits<double>::infinity();
  r.barrier_energy = barrier_->energy(x);
  r.ccd_alpha_min = barrier_->take_ccd_min();
  r.timings = barrier_->take_timings();  // of the solve (the report's own work is not counted)
  if (grad_.extent(0) != x.extent(0)) grad_ = Kokkos::View<double*, MemSpace>("contact_grad", x.extent(0));
  Kokkos::deep_copy(grad_, 0.0);
  barrier_->gradient(x, 1.0, grad_);
  if (friction_) friction_->gradient(x, 1.0, grad_);
  LO first = 0, count = n_fem_nodes;
  if (params_.force_body >= 0) {
    first = mesh_.bodies[params_.force_body].first_node;
    count = mesh_.bodies[params_.force_body].num_nodes;
  }
  const auto g = grad_;
  double f[3] = {0, 0, 0};
  for (int c = 0; c < dim; ++c)
    Kokkos::parallel_reduce(
        "contact_fem_force", Kokkos::RangePolicy<ExecSpace>(first, first + count),
        KOKKOS_LAMBDA(const LO n, double& acc) { acc -= g(n * dim + c); }, f[c]);
  r.force = {f[0], f[1], f[2]};
  const std::size_t nq = static_cast<std::size_t>(ps_.size()) * dim;
  {
    if (report_xp_.extent(0) != nq) report_xp_ = Kokkos::View<double*, MemSpace>("contact_report_xp", nq);
    interpolate_particles(ps_, x, report_xp_);
    const auto xp = report_xp_;
    const auto pr = act.pairs;
    const auto pbody = barrier_->primitives().body;
    const int fb = params_.force_body;
    for (int c = 0; c < dim; ++c) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      Kokkos::parallel_reduce(
          "contact_extent", Kokkos::RangePolicy<ExecSpace>(0, act.count),
          KOKKOS_LAMBDA(const LO k, double& a, double& b) {
            if (fb >= 0 && pbody(pr(k, 1)) != fb) return;
            const double v = xp(pr(k, 0) * dim + c);
            a = v < a ? v : a;
            b = v > b ? v : b;
          },
          Kokkos::Min<double>(lo), Kokkos::Max<double>(hi));
      r.extent_lo[c] = lo;
      r.extent_hi[c] = hi;
    }
  }
  if (particle_force_.extent(0) != nq) particle_force_ = Kokkos::View<double*, MemSpace>("contact_particle_force", nq);
  barrier_->particle_forces(x, particle_force_);
  if (friction_) friction_->add_particle_forces(x, particle_force_);
  return r;
}

template class Contact<2>;
template class Contact<3>;

}  // namespace bfemp
