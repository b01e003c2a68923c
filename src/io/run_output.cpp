#include "io/run_output.hpp"

#include <Teuchos_YamlParameterListHelpers.hpp>
#include <filesystem>
#include <iterator>
#include <set>
#include <sstream>

#include "io/atomic_file.hpp"

namespace bfemp {

std::vector<std::string> diagnostics_columns(const std::vector<std::string>& bodies) {
  std::vector<std::string> cols = {
      "step", "time", "dt", "kinetic", "elastic", "potential", "total_energy", "momentum_x",
      "momentum_y", "momentum_z", "newton_iters", "linear_iters", "min_J", "assembly_s", "solve_s",
      "step_s", "active_grid_nodes", "contact_pairs", "min_distance", "barrier_energy", "friction_iters",
      "ccd_alpha_min", "contact_force_x", "contact_force_y", "contact_force_z", "contact_lo_x",
      "contact_lo_y", "contact_lo_z", "contact_hi_x", "contact_hi_y", "contact_hi_z", "penetrations",
      "penetration_depth"};
  for (const std::string& b : bodies)
    for (const char* f : body_column_fields()) cols.push_back(b + "." + f);
  return cols;
}

const std::vector<const char*>& body_column_fields() {
  static const std::vector<const char*> f = {"mass",  "com_x", "com_y",   "com_z",  "vel_x",
                                             "vel_y", "vel_z", "kinetic", "elastic"};
  return f;
}

std::vector<double> diagnostics_row(const StepReport& r) {
  std::vector<double> row = {static_cast<double>(r.step), r.time, r.dt, r.kinetic, r.elastic, r.potential,
          r.total_energy(), r.momentum[0], r.momentum[1], r.momentum[2],
          static_cast<double>(r.newton.iterations), static_cast<double>(r.newton.linear_iterations),
          r.min_J, r.newton.assembly_s, r.newton.solve_s, r.step_s, static_cast<double>(r.active_grid_nodes),
          static_cast<double>(r.contact_pairs), r.min_distance, r.barrier_energy,
          static_cast<double>(r.friction_iters), r.ccd_alpha_min, r.contact_force[0], r.contact_force[1],
          r.contact_force[2], r.contact_lo[0], r.contact_lo[1], r.contact_lo[2], r.contact_hi[0],
          r.contact_hi[1], r.contact_hi[2], static_cast<double>(r.penetrations), r.penetration_depth};
  for (const BodyReport& b : r.bodies) {
    const double v[] = {b.mass,        b.com[0],      b.com[1], b.com[2], b.velocity[0],
                        b.velocity[1], b.velocity[2], b.kinetic, b.elastic};
    row.insert(row.end(), std::begin(v), std::end(v));
  }
  return row;
}

namespace {
std::string prepare_dir(const std::string& dir) {
  std::filesystem::create_directories(dir);
  return dir;
}
}  // namespace

template <int dim>
RunOutput<dim>::RunOutput(const std::string& dir, const Scene& scene, const Simulation<dim>& sim,
                          const OutputResume* resume)
    : dir_(prepare_dir(dir)), xdmf_(dir + "/bfemp.xdmf", "bfemp.h5") {
  const std::set<std::string> ints = {"step", "newton_iters", "linear_iters", "active_grid_nodes", "contact_pairs",
                                      "friction_iters", "penetrations"};
  if (resume) {
    h5_ = std::make_unique<Hdf5FrameWriter>(dir + "/bfemp.h5", resume->frames);
    csv_ = std::make_unique<DiagnosticsCsv>(dir + "/diagnostics.csv", diagnostics_columns(sim.body_names()), ints, resume->step);
    for (int i = 0; i < resume->frames; ++i) xdmf_.add_frame(xdmf_frame(sim, i, h5_->frame_time(i)), false);
    xdmf_.write();
    frame_ = resume->frames;
  } else {
    h5_ = std::make_unique<Hdf5FrameWriter>(dir + "/bfemp.h5");
    csv_ = std::make_unique<DiagnosticsCsv>(dir + "/diagnostics.csv", diagnostics_columns(sim.body_names()), ints);
  }
  std::ostringstream yaml;
  yaml << std::showpoint;
  Teuchos::writeParameterListToYamlOStream(scene.params, yaml);
  write_file_atomically(dir + "/scene.yaml", yaml.str());
  auto cells = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mesh().elements.nodes);
  std::vector<long long> conn(cells.size());
  for (std::size_t e = 0; e < cells.extent(0); ++e)
    for (int a = 0; a <= dim; ++a) conn[e * (dim + 1) + a] = cells(e, a);
  if (!conn.empty() && !resume) h5_->write_static("cells", conn.data(), cells.extent(0), dim + 1);
  // Explicit polyvertex connectivity 0 .. np-1: without it ParaView's Xdmf3
  // readers give the particle grid points but no cells (nothing is drawn).
  if (const auto* mpm = sim.mpm(); mpm && !resume) {
    std::vector<long long> ids(static_cast<std::size_t>(mpm->total_particles()));
    for (std::size_t q = 0; q < ids.size(); ++q) ids[q] = static_cast<long long>(q);
    h5_->write_static("particle_vertices", ids.data(), ids.size(), 1);
  }
}

template <int dim>
XdmfFrame RunOutput<dim>::xdmf_frame(const Simulation<dim>& sim, int index, double time) const {
  const auto& mesh = sim.mesh();
  const std::size_t nn = mesh.num_nodes(), ne = mesh.num_cells();
  XdmfFrame frame{time, {}};
  if (nn > 0) {
    XdmfGrid g;
    g.name = "fem";
    g.group = Hdf5FrameWriter::frame_group_name(index);
    g.topology = {dim == 2 ? "Triangle" : "Tetrahedron", ne, dim + 1, "/mesh/cells"};
    g.num_nodes = nn;
    g.dim = dim;
    g.node_attributes = {{"velocity", "velocities", dim}};
    g.cell_attributes = {{"von_mises", "von_mises", 1}, {"J", "J", 1}};
    frame.grids.push_back(g);
  }
  if (const auto* mpm = sim.mpm()) {
    XdmfGrid g = xdmf_particle_grid(index, static_cast<std::size_t>(mpm->total_particles()), dim);
    g.node_attributes = {{"velocity", "particle_velocities", dim},
                         {"von_mises", "particle_von_mises", 1},
                         {"J", "particle_J", 1},
                         {"body", "particle_body", 1, true}};
    if (sim.contact()) g.node_attributes.push_back({"contact_force", "particle_contact_force", dim});
    frame.grids.push_back(g);
  }
  return frame;
}

template <int dim>
void RunOutput<dim>::write_frame(const Simulation<dim>& sim, const Particles<dim>* gathered,
                                 const std::vector<double>* gathered_forces) {
  const auto& mesh = sim.mesh();
  const std::size_t nn = mesh.num_nodes(), ne = mesh.num_cells();
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.positions());
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.velocities());
  Kokkos::View<double*, MemSpace> J("frame_J", ne), vm("frame_vm", ne);
  sim.element_J(J);
  sim.element_von_mises(vm);
  auto Jh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), J);
  auto vmh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), vm);
  h5_->begin_frame(frame_, sim.time(), sim.step_index());
  if (nn > 0) {
    h5_->write_array("positions", x.data(), nn, dim);
    h5_->write_array("velocities", v.data(), nn, dim);
    h5_->write_array("von_mises", vmh.data(), ne, 1);
    h5_->write_array("J", Jh.data(), ne, 1);
  }
  if (const auto* mpm = sim.mpm()) {
    const auto& p = gathered ? *gathered : mpm->particles();
    const std::size_t np = p.size();
    Kokkos::View<double*, MemSpace> pJ("frame_particle_J", np), pvm("frame_particle_vm", np);
    mpm_particle_J_von_mises<dim>(p, sim.mesh().elements.materials, pJ, pvm);
    auto px = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
    auto pv = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
    auto pb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.body);
    auto pJh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), pJ);
    auto pvmh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), pvm);
    std::vector<long long> body(pb.data(), pb.data() + np);
    h5_->write_array("particle_positions", px.data(), np, dim);
    h5_->write_array("particle_velocities", pv.data(), np, dim);
    h5_->write_array("particle_von_mises", pvmh.data(), np, 1);
    h5_->write_array("particle_J", pJh.data(), np, 1);
    h5_->write_array("particle_body", body.data(), np, 1);
    const auto* contact = sim.contact();
    if (contact && gathered_forces && gathered_forces->size() == np * dim) {
      h5_->write_array("particle_contact_force", gathered_forces->data(), np, dim);
    } else if (contact && !gathered && contact->particle_forces().extent(0) == np * dim) {
      auto f = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), contact->particle_forces());
      h5_->write_array("particle_contact_force", f.data(), np, dim);
    } else if (contact) {
      const std::vector<double> zero(np * dim, 0.0);  // frame 0: no step solved yet
      h5_->write_array("particle_contact_force", zero.data(), np, dim);
    }
  }
  h5_->end_frame();
  xdmf_.add_frame(xdmf_frame(sim, frame_, sim.time()));
  ++frame_;
}

template class RunOutput<2>;
template class RunOutput<3>;

}  // namespace bfemp
