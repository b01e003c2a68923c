// Simulation::state / restore: the host copy of the state that carries over
// between steps (restart). One-off host work, never inside a step.
#include <stdexcept>

#include "sim/simulation.hpp"

namespace bfemp {

namespace {

template <class V>
std::vector<double> to_host(const V& view) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), view);
  const double* p = h.data();
  return std::vector<double>(p, p + h.size());  // contiguous (LayoutRight)
}

template <class V>
std::vector<long long> to_host_int(const V& view) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), view);
  return std::vector<long long>(h.data(), h.data() + h.size());
}

template <class V, class T>
void from_host(const V& view, const std::vector<T>& data, const std::string& field) {
  if (data.size() != view.size())
    throw std::invalid_argument("restart: checkpoint field '" + field + "' has " + std::to_string(data.size()) +
                                " values, the scene's state has " + std::to_string(view.size()) +
                                " (is this the checkpoint's scene?)");
  auto h = Kokkos::create_mirror_view(view);
  auto* p = h.data();
  for (std::size_t i = 0; i < data.size(); ++i) p[i] = static_cast<typename V::non_const_value_type>(data[i]);
  Kokkos::deep_copy(view, h);
}

}  // namespace

template <int dim>
SimulationState<dim> Simulation<dim>::state() const {
  SimulationState<dim> s;
  s.time = time_;
  s.step = step_;
  s.fem_x = to_host(x_);
  s.fem_v = to_host(v_);
  s.fem_a = to_host(a_);
  if (mpm_) {
    // MPI: this rank's id block of the particles (collective; nothing passes
    // through one rank). One rank: every particle, in id order.
    const Particles<dim> p = mpm_->id_block_particles(s.particle_first);
    s.has_mpm = true;
    s.particle_block = true;
    s.particle_total = mpm_->total_particles();
    s.x = to_host(p.x);
    s.v = to_host(p.v);
    s.mass = to_host(p.mass);
    s.volume0 = to_host(p.volume0);
    s.F = to_host(p.F);
    s.C = to_host(p.C);
    s.body = to_host_int(p.body);
    s.material = to_host_int(p.material);
    const auto& g = mpm_->grid();
    for (int d = 0; d < dim; ++d) {
      s.grid_origin[d] = g.origin(d);
      s.grid_cells[d] = g.n_cells[d];
    }
    s.grid_dx = g.dx;
    s.grid_extensions = mpm_->domain_extensions();
    if (!mpm_->distributed() && !mpm_->particles_in_id_order()) {
      auto ids = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mpm_->particle_ids());
      s.particle_order.assign(ids.data(), ids.data() + ids.extent(0));
    }
  }
  return s;
}

template <int dim>
void Simulation<dim>::restore(const SimulationState<dim>& s) {
  if (s.has_mpm != (mpm_ != nullptr))
    throw std::invalid_argument(std::string("restart: the checkpoint ") + (s.has_mpm ? "has" : "has no") +
                                " MPM particles and the scene " + (mpm_ ? "has" : "has none"));
  from_host(x_, s.fem_x, "fem_x");
  from_host(v_, s.fem_v, "fem_v");
  from_host(a_, s.fem_a, "fem_a");
  if (mpm_) {
    // The checkpoint's whole particle set, or this rank's id block of it (MPI:
    // each rank then keeps its box).
    const std::size_t np = s.mass.size();
    const long long total = s.particle_block ? s.particle_total : static_cast<long long>(np);
    if (total != mpm_->total_particles())
      throw std::invalid_argument("restart: checkpoint field 'particle_mass' has " + std::to_string(total) +
                                  " values, the scene's state has " + std::to_string(mpm_->total_particles()) +
                                  " (is this the checkpoint's scene?)");
    const Particles<dim> p = allocate_particles<dim>(np);
    from_host(p.x, s.x, "particle_x");
    from_host(p.v, s.v, "particle_v");
    from_host(p.mass, s.mass, "particle_mass");
    from_host(p.volume0, s.volume0, "particle_volume0");
    from_host(p.F, s.F, "particle_F");
    from_host(p.C, s.C, "particle_C");
    from_host(p.body, s.body, "particle_body");
    from_host(p.material, s.material, "particle_material");
    Kokkos::fence();
    GridSpec<dim> g;
    for (int d = 0; d < dim; ++d) {
      g.origin(d) = s.grid_origin[d];
      g.n_cells[d] = s.grid_cells[d];
    }
    g.dx = s.grid_dx;
    mpm_->restore_grid(g, s.grid_extensions);
    if (s.particle_block) {
      try {
        mpm_->replace_particle_block(p, s.particle_first, total);  // (MPI: boxes cut on the checkpoint's grid)
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(std::string("restart: ") + e.what());
      }
    }
    else
      mpm_->replace_particles(p);
    if (!s.particle_order.empty() && !mpm_->distributed()) mpm_->restore_order(s.particle_order);
  }
  time_ = s.time;
  step_ = s.step;
  Kokkos::fence();
}

template class SimulationState<2>;
template class SimulationState<3>;
template SimulationState<2> Simulation<2>::state() const;
template SimulationState<3> Simulation<3>::state() const;
template void Simulation<2>::restore(const SimulationState<2>&);
template void Simulation<3>::restore(const SimulationState<3>&);

}  // namespace bfemp
