#include "io/run_output.hpp"

#include <Teuchos_YamlParameterListHelpers.hpp>
#include <filesystem>
#include <iterator>
#include <set>
#include <sstream>

#include "io/atomic_file.hpp"
#include "mpm/particle_distribution.hpp"

namespace bfemp {

std::vector<std::string> diagnostics_columns(const std::vector<std::string>& bodies) {
  std::vector<std::string> cols = {
      "step", "time", "dt", "kinetic", "elastic", "potential", "total_energy", "momentum_x",
      "momentum_y", "momentum_z", "newton_iters", "linear_iters", "min_J", "assembly_s", "solve_s",
      "step_s", "active_grid_nodes", "contact_pairs", "min_distance", "barrier_energy", "friction_iters",
      "ccd_alpha_min", "contact_force_x", "contact_force_y", "contact_force_z", "contact_lo_x",
      "contact_lo_y", "contact_lo_z", "contact_hi_x", "contact_hi_y", "contact_hi_z", "penetrations",
      "penetration_depth", "penetrations_fem", "penetrations_level_set"};
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
          r.contact_hi[1], r.contact_hi[2], static_cast<double>(r.penetrations), r.penetration_depth,
          static_cast<double>(r.penetrations_fem), static_cast<double>(r.penetrations_level_set)};
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

namespace {
int rank_of(MPI_Comm comm) {
  int r = 0;
  if (comm != MPI_COMM_NULL) MPI_Comm_rank(comm, &r);
  return r;
}
}  // namespace

template <int dim>
RunOutput<dim>::RunOutput(const std::string& dir, const Scene& scene, const Simulation<dim>& sim,
                          const OutputResume* resume, MPI_Comm comm)
    : dir_(prepare_dir(dir)), root_(rank_of(comm) == 0), xdmf_(dir + "/bfemp.xdmf", "bfemp.h5") {
  const std::set<std::string> ints = {"step", "newton_iters", "linear_iters", "active_grid_nodes", "contact_pairs",
                                      "friction_iters", "penetrations", "penetrations_fem",
                                      "penetrations_level_set"};
  const auto columns = diagnostics_columns(sim.body_names());
  if (resume) {
    h5_ = std::make_unique<Hdf5FrameWriter>(dir + "/bfemp.h5", resume->frames, comm);
    if (root_) {
      csv_ = std::make_unique<DiagnosticsCsv>(dir + "/diagnostics.csv", columns, ints, resume->step);
      for (int i = 0; i < resume->frames; ++i) xdmf_.add_frame(xdmf_frame(sim, i, h5_->frame_time(i)), false);
      xdmf_.write();
    }
    frame_ = resume->frames;
  } else {
    h5_ = std::make_unique<Hdf5FrameWriter>(dir + "/bfemp.h5", comm);
    if (root_) csv_ = std::make_unique<DiagnosticsCsv>(dir + "/diagnostics.csv", columns, ints);
  }
  if (root_) {
    std::ostringstream yaml;
    yaml << std::showpoint;
    Teuchos::writeParameterListToYamlOStream(scene.params, yaml);
    write_file_atomically(dir + "/scene.yaml", yaml.str());
  }
  if (resume) return;
  auto cells = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mesh().elements.nodes);
  std::vector<long long> conn(cells.size());
  for (std::size_t e = 0; e < cells.extent(0); ++e)
    for (int a = 0; a <= dim; ++a) conn[e * (dim + 1) + a] = cells(e, a);
  if (!conn.empty()) h5_->write_static("cells", conn.data(), cells.extent(0), dim + 1);
  // Explicit polyvertex connectivity 0 .. np-1: without it ParaView's Xdmf3
  // readers give the particle grid points but no cells (nothing is drawn).
  // Each rank writes its id block of it.
  if (const auto* mpm = sim.mpm()) {
    const long long n = mpm->total_particles();
    int rank = 0, size = 1;
    if (h5_->parallel()) {
      MPI_Comm_rank(comm, &rank);
      MPI_Comm_size(comm, &size);
    }
    const long long lo = id_block_begin(n, rank, size), hi = id_block_begin(n, rank + 1, size);
    std::vector<long long> ids(static_cast<std::size_t>(hi - lo));
    for (std::size_t q = 0; q < ids.size(); ++q) ids[q] = lo + static_cast<long long>(q);
    h5_->write_static_rows("particle_vertices", ids.data(), ids.size(), static_cast<std::size_t>(lo),
                           static_cast<std::size_t>(n), 1);
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
void RunOutput<dim>::write_frame(const Simulation<dim>& sim, const ParticleRows<dim>* rows) {
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
  if (nn > 0) {  // the FEM state (replicated on every rank)
    h5_->write_array("positions", x.data(), nn, dim);
    h5_->write_array("velocities", v.data(), nn, dim);
    h5_->write_array("von_mises", vmh.data(), ne, 1);
    h5_->write_array("J", Jh.data(), ne, 1);
  }
  if (const auto* mpm = sim.mpm()) {
    const auto& p = rows ? rows->particles : mpm->particles();
    const std::size_t np = p.size(), first = rows ? static_cast<std::size_t>(rows->first) : 0;
    const std::size_t total = rows ? static_cast<std::size_t>(mpm->total_particles()) : np;
    Kokkos::View<double*, MemSpace> pJ("frame_particle_J", np), pvm("frame_particle_vm", np);
    mpm_particle_J_von_mises<dim>(p, sim.mesh().elements.materials, pJ, pvm);
    auto px = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
    auto pv = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
    auto pb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.body);
    auto pJh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), pJ);
    auto pvmh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), pvm);
    std::vector<long long> body(pb.data(), pb.data() + np);
    // This rank's rows, or (no rows: every rank has all particles) rank 0 writes.
    auto put = [&](const char* name, const auto* data, std::size_t cols) {
      if (rows)
        h5_->write_rows(name, data, np, first, total, cols);
      else
        h5_->write_array(name, data, np, cols);
    };
    put("particle_positions", px.data(), dim);
    put("particle_velocities", pv.data(), dim);
    put("particle_von_mises", pvmh.data(), 1);
    put("particle_J", pJh.data(), 1);
    put("particle_body", body.data(), 1);
    if (const auto* contact = sim.contact()) {
      Kokkos::View<const double*, MemSpace> f;
      if (rows)
        f = rows->contact_forces;
      else if (contact->particle_forces().extent(0) == np * dim)
        f = contact->particle_forces();
      if (f.extent(0) == np * dim) {
        auto fh = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), f);
        put("particle_contact_force", fh.data(), dim);
      } else {
        const std::vector<double> zero(np * dim, 0.0);  // frame 0: no step solved yet
        put("particle_contact_force", zero.data(), dim);
      }
    }
  }
  h5_->end_frame();
  if (root_) xdmf_.add_frame(xdmf_frame(sim, frame_, sim.time()));
  ++frame_;
}

template class RunOutput<2>;
template class RunOutput<3>;

}  // namespace bfemp
