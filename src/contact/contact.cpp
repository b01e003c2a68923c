#include "contact/contact.hpp"

#include <climits>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "kernels/contact/point_in_simplex.hpp"

namespace bfemp {

template <int dim>
Contact<dim>::Contact(const FemMesh<dim>& mesh, ContactParams params) : mesh_(mesh), params_(std::move(params)) {
  barrier_ = std::make_unique<BarrierTerm<dim>>(boundary_primitives(mesh), params_.dhat, params_.kappa);
  barrier_->set_graph_margin(params_.graph_margin);
  bool any_mu = false;
  for (double m : params_.mu) any_mu = any_mu || m > 0;
  if (any_mu)
    friction_ = std::make_unique<FrictionTerm<dim>>(*barrier_, params_.mu, static_cast<int>(mesh.bodies.size()),
                                                    params_.eps_v);
  // Element bodies (for the inside tests of FEM points).
  element_body_ = Kokkos::View<int*, MemSpace>("contact_element_body", mesh.num_cells());
  auto eb = Kokkos::create_mirror_view(element_body_);
  for (std::size_t b = 0; b < mesh.bodies.size(); ++b)
    for (LO e = mesh.bodies[b].first_cell; e < mesh.bodies[b].first_cell + mesh.bodies[b].num_cells; ++e)
      eb(e) = static_cast<int>(b);
  Kokkos::deep_copy(element_body_, eb);
  if (!params_.fem_fem) return;
  if constexpr (dim == 3)
    throw std::invalid_argument("Contact/FEM-FEM: true: contact between FEM bodies runs in 2D only in this version "
                                "(3D needs edge-edge pairs); expected false in a 3D scene");
  // Contact points: the nodes of the boundary facets, omega = half the rest
  // length of the facets at the node (IPC's boundary-node weight).
  const auto& prims = barrier_->primitives();
  auto pn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), prims.nodes);
  auto pb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), prims.body);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.rest_position);
  std::vector<double> w(static_cast<std::size_t>(mesh.num_nodes()), 0.0);
  std::vector<int> body(w.size(), -1);
  for (LO j = 0; j < prims.num_facets; ++j) {
    double len2 = 0;
    for (int c = 0; c < dim; ++c) {
      const double d = X(pn(j, 1) * dim + c) - X(pn(j, 0) * dim + c);
      len2 += d * d;
    }
    for (int a = 0; a < 2; ++a) {
      w[pn(j, a)] += 0.5 * std::sqrt(len2);
      body[pn(j, a)] = pb(j);
    }
  }
  std::vector<LO> nodes;
  for (LO n = 0; n < mesh.num_nodes(); ++n)
    if (w[n] > 0) nodes.push_back(n);
  const std::size_t m = nodes.size();
  fem_point_node_ = Kokkos::View<LO*, MemSpace>("contact_fem_point_node", m);
  fem_point_omega_ = Kokkos::View<double*, MemSpace>("contact_fem_point_omega", m);
  fem_point_body_ = Kokkos::View<int*, MemSpace>("contact_fem_point_body", m);
  auto hn = Kokkos::create_mirror_view(fem_point_node_);
  auto hw = Kokkos::create_mirror_view(fem_point_omega_);
  auto hb = Kokkos::create_mirror_view(fem_point_body_);
  for (std::size_t k = 0; k < m; ++k) {
    hn(k) = nodes[k];
    hw(k) = w[nodes[k]];
    hb(k) = body[nodes[k]];
  }
  Kokkos::deep_copy(fem_point_node_, hn);
  Kokkos::deep_copy(fem_point_omega_, hw);
  Kokkos::deep_copy(fem_point_body_, hb);
}

template <int dim>
LO Contact<dim>::fem_point_node(LO k) const {
  LO n = -1;
  Kokkos::deep_copy(n, Kokkos::subview(fem_point_node_, k));
  return n;
}

template <int dim>
void Contact<dim>::keep_fem_points(const std::vector<char>& owned) {
  const LO m = num_fem_points();
  if (m == 0) return;
  auto hn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), fem_point_node_);
  auto hw = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), fem_point_omega_);
  auto hb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), fem_point_body_);
  LO kept = 0;
  for (LO k = 0; k < m; ++k) {
    const LO n = hn(k);
    if (n < 0 || static_cast<std::size_t>(n) >= owned.size())
      throw std::logic_error("Contact::keep_fem_points: the owned mask does not cover FEM node " + std::to_string(n));
    if (!owned[n]) continue;
    hn(kept) = n;
    hw(kept) = hw(k);
    hb(kept) = hb(k);
    ++kept;
  }
  fem_point_node_ = Kokkos::View<LO*, MemSpace>("contact_fem_point_node", kept);
  fem_point_omega_ = Kokkos::View<double*, MemSpace>("contact_fem_point_omega", kept);
  fem_point_body_ = Kokkos::View<int*, MemSpace>("contact_fem_point_body", kept);
  Kokkos::deep_copy(fem_point_node_, Kokkos::subview(hn, std::make_pair(LO(0), kept)));
  Kokkos::deep_copy(fem_point_omega_, Kokkos::subview(hw, std::make_pair(LO(0), kept)));
  Kokkos::deep_copy(fem_point_body_, Kokkos::subview(hb, std::make_pair(LO(0), kept)));
  ps_ = ParticleStencils<dim>{};  // sized again at the next begin_step
}

namespace {
// Point q against element e: FEM points (q >= first) skip their own body.
struct InsideFilter {
  LO first;
  Kokkos::View<int*, MemSpace> point_body, element_body;
  KOKKOS_INLINE_FUNCTION bool operator()(LO q, LO e) const {
    return q < first || point_body(q - first) != element_body(e);
  }
};
}  // namespace

template <int dim>
LO Contact<dim>::inside(ConstDofView xp, ConstDofView x, LO first_fem_point) const {
  const auto& el = mesh_.elements;
  const LO np = static_cast<LO>(xp.extent(0) / dim);
  if (el.size() == 0 || np == 0) return -1;
  // Hash the elements, query the points; inside or on an element counts.
  simplex_boxes<dim, dim + 1>(el.nodes, x, ConstDofView(), 0.0, element_boxes_);
  point_boxes<dim>(xp, ConstDofView(), 0.0, point_boxes_);
  element_hash_.build(element_boxes_);
  const LO n = first_fem_point >= np
                   ? element_hash_.query(point_boxes_, inside_pairs_)
                   : element_hash_.query(point_boxes_, inside_pairs_,
                                         InsideFilter{first_fem_point, fem_point_body_, element_body_});
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
LO Contact<dim>::particle_inside(ConstDofView xp, ConstDofView x) const {
  return inside(xp, x, static_cast<LO>(xp.extent(0) / dim));
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
  return inside(xp, x, n_particles_);
}

template <int dim>
void Contact<dim>::check_initial(const Particles<dim>& p, ConstDofView x_fem,
                                 Kokkos::View<const long long*, MemSpace> ids) const {
  const LO np = static_cast<LO>(p.size());
  Kokkos::View<double*, MemSpace> xp("contact_check_xp", static_cast<std::size_t>(np) * dim);
  interleaved_positions(p, xp);
  const LO bad = particle_inside(xp, x_fem);
  if (bad >= 0) {
    auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
    std::ostringstream msg;
    long long id = bad;
    if (ids.extent(0) > static_cast<std::size_t>(bad)) Kokkos::deep_copy(id, Kokkos::subview(ids, bad));
    msg << "MPM particle " << id << " at (";
    for (int c = 0; c < dim; ++c) msg << (c ? ", " : "") << h(bad, c);
    msg << ") starts inside or on an FEM body: the MPM and FEM bodies must not intersect or touch at t = 0 "
           "(paper Eq. 15); move the bodies apart";
    throw std::invalid_argument(msg.str());
  }
  check_initial_fem(x_fem);
}

template <int dim>
void Contact<dim>::check_initial_fem(ConstDofView x_fem) const {
  const LO m = num_fem_points();
  if (m == 0) return;
  Kokkos::View<double*, MemSpace> xn("contact_check_fem_points", static_cast<std::size_t>(m) * dim);
  const auto node = fem_point_node_;
  Kokkos::parallel_for(
      "contact_fem_point_positions", Kokkos::RangePolicy<ExecSpace>(0, m), KOKKOS_LAMBDA(const LO k) {
        for (int c = 0; c < dim; ++c) xn(k * dim + c) = x_fem(node(k) * dim + c);
      });
  const LO bad = inside(xn, x_fem, 0);
  if (bad < 0) return;
  auto hn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), fem_point_node_);
  auto hb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), fem_point_body_);
  auto hx = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), xn);
  std::ostringstream msg;
  msg << "FEM node " << hn(bad) << " of body '" << mesh_.bodies[hb(bad)].name << "' at (";
  for (int c = 0; c < dim; ++c) msg << (c ? ", " : "") << hx(bad * dim + c);
  msg << ") starts inside or on another FEM body (Contact/FEM-FEM: true): FEM bodies in contact must not "
         "intersect or touch at t = 0; move them apart";
  throw std::invalid_argument(msg.str());
}

template <int dim>
void Contact<dim>::begin_step(const MpmBodies<dim>* mpm, ConstDofView x) {
  constexpr int ns = ParticleStencils<dim>::ns;
  const LO np = mpm ? static_cast<LO>(mpm->particles().size()) : 0;
  const LO nfp = num_fem_points();
  const LO n = np + nfp;
  n_particles_ = np;
  if (ps_.size() != n) {
    ps_.nodes = decltype(ps_.nodes)("contact_particle_nodes", n);
    ps_.w = decltype(ps_.w)("contact_particle_w", n);
    ps_.omega = Kokkos::View<double*, MemSpace>("contact_omega", n);
    ps_.body = nfp > 0 || !mpm ? Kokkos::View<int*, MemSpace>("contact_point_body", n) : mpm->particles().body;
    ps_.fem_body_base = nfp > 0 ? params_.mpm_bodies : INT_MAX;
  }
  // The particles' own body View: new after a restart or an MPI migration
  // (which may keep the count), so taken every step.
  if (mpm && nfp == 0) ps_.body = mpm->particles().body;
  const auto ps = ps_;
  if (mpm) {
    const auto& p = mpm->particles();
    const auto grid = mpm->grid();
    const auto sys = mpm->system_node();
    const bool copy_body = nfp > 0;
    Kokkos::parallel_for(
        "contact_particle_stencils", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const LO q) {
          const auto st = bspline_stencil(grid, particle_position(p, q));
          for (int a = 0; a < ns; ++a) {
            ps.nodes(q, a) = sys(node_index(grid, st, a));
            ps.w(q, a) = weight(st, a);
          }
          ps.omega(q) = particle_contact_weight<dim>(p.volume0(q));
          if (copy_body) ps.body(q) = p.body(q);
        });
  }
  if (nfp > 0) {
    const auto node = fem_point_node_;
    const auto omega = fem_point_omega_;
    const auto body = fem_point_body_;
    const int base = ps_.fem_body_base;
    Kokkos::parallel_for(
        "contact_fem_point_stencils", Kokkos::RangePolicy<ExecSpace>(0, nfp), KOKKOS_LAMBDA(const LO k) {
          const LO q = np + k;
          for (int a = 0; a < ns; ++a) {  // the node itself, weight 1 (the other slots add nothing)
            ps.nodes(q, a) = node(k);
            ps.w(q, a) = a == 0 ? 1.0 : 0.0;
          }
          ps.omega(q) = omega(k);
          ps.body(q) = base + body(k);
        });
  }
  barrier_->begin_step(ps_, x, mpm ? &mpm->term().cells() : nullptr);
  if (friction_) friction_->clear();
}

template <int dim>
LO Contact<dim>::update_friction(ConstDofView x, ConstDofView x_ref, double s, double dt) {
  return friction_ ? friction_->update_lagged(x, barrier_->active_pairs(x), x_ref, s, dt) : 0;
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
  r.timings = barrier_->take_timings();  // of the step (with the report's own pair search and energy above)
  // the system size follows the active grid nodes (it changes most steps): capacity with headroom
  if (grad_.extent(0) < x.extent(0)) grad_ = Kokkos::View<double*, MemSpace>("contact_grad", x.extent(0) + x.extent(0) / 4 + 16);
  const Kokkos::View<double*, MemSpace> gx = Kokkos::subview(grad_, std::make_pair(std::size_t(0), x.extent(0)));
  Kokkos::deep_copy(gx, 0.0);
  barrier_->gradient(x, 1.0, gx);
  if (friction_) friction_->gradient(x, 1.0, gx);
  LO first = 0, count = n_fem_nodes;
  if (params_.force_body >= 0) {
    first = mesh_.bodies[params_.force_body].first_node;
    count = mesh_.bodies[params_.force_body].num_nodes;
  }
  const auto g = gx;
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
    const LO npart = n_particles_;  // the box of particles only (FEM-FEM points are not particles)
    for (int c = 0; c < dim; ++c) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      Kokkos::parallel_reduce(
          "contact_extent", Kokkos::RangePolicy<ExecSpace>(0, act.count),
          KOKKOS_LAMBDA(const LO k, double& a, double& b) {
            if (pr(k, 0) >= npart || (fb >= 0 && pbody(pr(k, 1)) != fb)) return;
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
