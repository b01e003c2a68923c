#include "app/run.hpp"

#include <Kokkos_Timer.hpp>
#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_YamlParameterListHelpers.hpp>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <ostream>
#include <sstream>

#include "app/explicit_run.hpp"
#include "core/mpi_comm.hpp"
#include "io/run_output.hpp"
#include "mpm/particle_distribution.hpp"
#include "io/scene_explicit.hpp"
#include "app/interrupt.hpp"
#include "app/run_checks.hpp"
#include "solver/solver_error.hpp"

namespace bfemp {

namespace {

const char* kRestartKeys[] = {"Time/end time", "Output/", "Newton/", "Linear Solver/", "MPM/boxes per axis",
                              "Contact/friction iterations",
                              "Contact/friction pass tolerance", "Contact/friction relaxation from",
                              "Contact/check iterates", "Contact/eps_v"};

std::string join_lines(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += x + "\n";
  return s;
}

std::vector<std::string> split_lines(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) out.push_back(line);
  return out;
}

// The texts every checkpoint stores: the scene as read, its overrides, the
// resolved scene and the base directory (a restart rebuilds the scene from them).
std::map<std::string, std::string> checkpoint_texts(const Scene& scene, const RunOptions& opt) {
  std::map<std::string, std::string> t;
  std::ostringstream resolved;
  resolved << std::showpoint << std::setprecision(17);
  Teuchos::writeParameterListToYamlOStream(scene.params, resolved);
  t["scene_resolved"] = resolved.str();
  t["scene_source"] = opt.scene_source.empty() ? resolved.str() : opt.scene_source;
  t["overrides"] = opt.scene_source.empty() ? std::string() : join_lines(opt.overrides);
  t["base_dir"] = std::filesystem::absolute(scene.base_dir.empty() ? "." : scene.base_dir).string();
  return t;
}

template <int dim>
Checkpoint make_checkpoint(const Scene& scene, const RunOptions& opt, const Simulation<dim>& sim, int frames) {
  const SimulationState<dim> st = sim.state();
  Checkpoint c;
  c.time = st.time;
  c.step = st.step;
  c.frames = frames;
  c.dim = dim;
  c.texts = checkpoint_texts(scene, opt);
  {  // the rest mesh, so that a restart refuses a mesh file changed since
    auto X0 = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mesh().rest_position);
    auto cells = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mesh().elements.nodes);
    c.put("fem_rest_position", std::vector<double>(X0.data(), X0.data() + X0.size()), dim);
    std::vector<long long> conn(cells.size());
    for (std::size_t e = 0; e < cells.extent(0); ++e)
      for (int a = 0; a <= dim; ++a) conn[e * (dim + 1) + a] = cells(e, a);
    c.put("fem_cells", std::move(conn), dim + 1);
  }
  c.put("fem_x", st.fem_x, dim);
  c.put("fem_v", st.fem_v, dim);
  c.put("fem_a", st.fem_a, dim);
  if (st.has_mpm) {
    // This rank's id block of every particle field (MPI-IO: one file, no
    // gather); the rest is replicated, written by rank 0.
    const std::size_t first = static_cast<std::size_t>(st.particle_first),
                      total = static_cast<std::size_t>(st.particle_total);
    c.put_rows("particle_x", st.x, dim, first, total);
    c.put_rows("particle_v", st.v, dim, first, total);
    c.put_rows("particle_mass", st.mass, 1, first, total);
    c.put_rows("particle_volume0", st.volume0, 1, first, total);
    c.put_rows("particle_F", st.F, dim * dim, first, total);
    c.put_rows("particle_C", st.C, dim * dim, first, total);
    c.put_rows("particle_body", st.body, 1, first, total);
    c.put_rows("particle_material", st.material, 1, first, total);
    // (one rank only; a row block, so that a restart on R ranks, which does
    // not use it, reads 1/R of it)
    if (!st.particle_order.empty()) c.put_rows("particle_order", st.particle_order, 1, 0, st.particle_order.size());
    c.put("grid_origin", std::vector<double>(st.grid_origin.begin(), st.grid_origin.end()));
    c.put("grid_cells", std::vector<long long>(st.grid_cells.begin(), st.grid_cells.end()));
    c.put("grid_dx", std::vector<double>{st.grid_dx});
    c.put("grid_extensions", std::vector<long long>{st.grid_extensions});
  }
  return c;
}

// The scene's FEM rest mesh must be the checkpoint's, bit for bit (a mesh
// file regenerated between the run and the restart is refused).
template <int dim>
void check_same_mesh(const Checkpoint& c, const Simulation<dim>& sim) {
  if (!c.has("fem_rest_position")) return;  // written by every run; kept optional for the reader
  auto X0 = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mesh().rest_position);
  auto cells = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mesh().elements.nodes);
  const auto& x = c.real("fem_rest_position");
  const auto& conn = c.ints("fem_cells");
  bool same = x.size() == X0.size() && conn.size() == cells.size();
  for (std::size_t i = 0; same && i < x.size(); ++i) same = x[i] == X0.data()[i];
  for (std::size_t e = 0; same && e < cells.extent(0); ++e)
    for (int a = 0; a <= dim; ++a) same = same && conn[e * (dim + 1) + a] == cells(e, a);
  if (!same)
    throw std::invalid_argument("restart: the scene's FEM mesh differs from the checkpoint's (a mesh file changed "
                                "since the run?); restart needs the run's own mesh");
}

template <int dim>
SimulationState<dim> checkpoint_state(const Checkpoint& c) {
  SimulationState<dim> st;
  st.time = c.time;
  st.step = c.step;
  st.fem_x = c.real("fem_x");
  st.fem_v = c.real("fem_v");
  st.fem_a = c.real("fem_a");
  st.has_mpm = c.has("particle_x");
  if (st.has_mpm) {
    // This rank's rows (read_checkpoint's block; every row from a checkpoint
    // written before row blocks), the same block of every field. The fields
    // are checked by what every rank reads alike (blocked, total rows,
    // columns, type), so that all ranks refuse a damaged file together
    // (a refusal on one rank alone would leave the others waiting in the
    // restore's collectives).
    const CheckpointArray& m = c.array("particle_mass");
    const long rows = static_cast<long>(m.rows);
    st.particle_block = m.blocked;
    st.particle_first = static_cast<long long>(m.first_row);
    st.particle_total = static_cast<long long>(m.total_rows);
    struct Field {
      const char* name;
      std::size_t cols;
      bool integer;
    };
    const Field fields[] = {{"particle_x", dim, false},       {"particle_v", dim, false},
                            {"particle_mass", 1, false},     {"particle_volume0", 1, false},
                            {"particle_F", dim * dim, false}, {"particle_C", dim * dim, false},
                            {"particle_body", 1, true},      {"particle_material", 1, true}};
    for (const auto& [name, cols, integer] : fields) {
      const CheckpointArray& a = c.array(name);
      if (a.blocked != m.blocked || a.total_rows != m.total_rows || a.cols != cols || a.integer != integer)
        throw std::invalid_argument(std::string("restart: checkpoint field '") + name + "' has " +
                                    std::to_string(a.total_rows) + " x " + std::to_string(a.cols) +
                                    (a.integer ? " integers" : " reals") + ", expected " +
                                    std::to_string(m.total_rows) + " x " + std::to_string(cols) +
                                    (integer ? " integers" : " reals") + " (a damaged or foreign checkpoint)");
    }
    st.x = c.real("particle_x", rows);
    st.v = c.real("particle_v", rows);
    st.mass = c.real("particle_mass", rows);
    st.volume0 = c.real("particle_volume0", rows);
    st.F = c.real("particle_F", rows);
    st.C = c.real("particle_C", rows);
    st.body = c.ints("particle_body", rows);
    st.material = c.ints("particle_material", rows);
    if (c.has("particle_order")) st.particle_order = c.ints("particle_order");
    const auto& o = c.real("grid_origin", dim);
    const auto& n = c.ints("grid_cells", dim);
    for (int d = 0; d < dim; ++d) {
      st.grid_origin[d] = o[d];
      st.grid_cells[d] = static_cast<int>(n[d]);
    }
    st.grid_dx = c.real("grid_dx", 1)[0];
    st.grid_extensions = static_cast<int>(c.ints("grid_extensions", 1)[0]);
  }
  return st;
}

void accumulate(RunSummary& s, const StepReport& r) {
  s.steps++;
  s.newton_iterations += r.newton.iterations;
  s.linear_iterations += r.newton.linear_iterations;
  s.assembly_s += r.newton.assembly_s;
  s.solve_s += r.newton.solve_s;
  s.line_search_s += r.newton.line_search_s;
  s.contact_broad_phase_s += r.contact_broad_phase_s;
  s.contact_eval_s += r.contact_eval_s;
  s.contact_ccd_s += r.contact_ccd_s;
  s.contact_searches += r.contact_searches;
  s.contact_searches_all += r.contact_searches_all;
  s.symbolic_factorizations += r.newton.symbolic_factorizations;
  s.numeric_factorizations += r.newton.numeric_factorizations;
  s.factor_s += r.newton.factor_s;
  s.reuse_cg_s += r.newton.reuse_cg_s;
  s.reuse_cg_iterations += r.newton.reuse_cg_iterations;
  s.stale_retries += r.newton.stale_retries;
  s.projected_retries += r.newton.projected_retries;
  s.exact_hessian_iterations += r.newton.exact_hessian_iterations;
  s.projection_fallbacks += r.newton.projection_fallbacks;
  s.partial_projections += r.newton.partial_projections;
  s.wolfe_steps += r.newton.wolfe_steps;
  s.wolfe_gradients += r.newton.wolfe_gradients;
}

// The signal any rank received (every rank stops after the same step).
int global_signal(const Teuchos::RCP<const Comm>& comm) {
  int mine = pending_signal(), any = mine;
  if (comm->getSize() > 1) Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(any));
  return any;
}

template <int dim>
RunSummary run_dim(const Scene& scene, const std::string& dir, const Teuchos::RCP<const Comm>& comm,
                   std::ostream& log_root, const RunOptions& opt) {
  Kokkos::Timer wall;
  const RunControl rc = scene.run_control();
  const int checkpoint_every = checked_checkpoint_every(scene);
  if (opt.restart) check_restart_dimension(opt.restart->dim, dim);
  const bool root = comm->getRank() == 0;
  std::ostream null_log(nullptr);
  std::ostream& log = root ? log_root : null_log;  // one banner, one summary
  // Each rank samples its id block of the particles (its start checks agreed).
  Simulation<dim> sim(build_setup<dim>(scene, particle_block(*comm)), comm);
  if (opt.restart) {
    check_same_mesh(*opt.restart, sim);
    sim.restore(checkpoint_state<dim>(*opt.restart));
  }
  const auto& mesh = sim.mesh();
  log << "FEM: " << mesh.num_nodes() << " nodes, " << mesh.num_cells() << " elements, "
      << mesh.num_nodes() * dim << " DOFs";
  if (const auto* mpm = sim.mpm())
    log << "; MPM: " << mpm->total_particles() << " particles, " << transfer_scheme_name(mpm->scheme())
        << ", grid " << mpm->grid().num_nodes() << " nodes (dx " << mpm->grid().dx << ")"
        << (mpm->sort_every() > 0 ? ", sorted by cell every " + std::to_string(mpm->sort_every()) + " steps" : "");
  log << "; linear solver: " << sim.newton().linear_solver().describe() << "\n";
  if (const FemPartition* part = sim.partition()) {
    // Per-rank work: elements (assembly) and owned DOFs (solve); imbalance = max / mean.
    const double mine[2] = {static_cast<double>(part->elements.size()), static_cast<double>(part->n_owned) * dim};
    double lo[2], hi[2], sum[2];
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MIN, 2, mine, lo);
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, 2, mine, hi);
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, 2, mine, sum);
    const int n = comm->getSize();
    log << "MPI: " << n << " ranks (Zoltan2 RCB of the elements; FEM state replicated): elements per rank "
        << lo[0] << ".." << hi[0] << " (imbalance " << std::setprecision(3) << hi[0] / (sum[0] / n)
        << "), owned DOFs per rank " << lo[1] << ".." << hi[1] << " (imbalance " << hi[1] / (sum[1] / n)
        << ")\n" << std::setprecision(6);
  }
  if (const auto* mpm = sim.mpm(); mpm && mpm->distributed()) {
    // Per-rank particles (assembly, transfers); imbalance = max / mean.
    const double mine = static_cast<double>(mpm->particles().size());
    double lo = 0, hi = 0, sum = 0;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MIN, mine, Teuchos::outArg(lo));
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(hi));
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, mine, Teuchos::outArg(sum));
    const int n = comm->getSize();
    log << "MPI: " << n << " ranks (MPM particles in " << describe_boxes(mpm->boxes())
        << "; particles migrate between them): particles per rank " << lo << ".." << hi << " (imbalance "
        << std::setprecision(3) << hi / (sum / n) << ")\n" << std::setprecision(6);
  }
  {
    std::string names;
    for (const auto& n : sim.term_names()) names += (names.empty() ? "" : ", ") + n;
    log << "energy terms: inertia, " << names << "\n";
  }
  OutputResume resume;
  if (opt.restart && opt.append) resume = {opt.restart->frames, opt.restart->step};
  // A new output must not keep an older run's checkpoint: restarting from it
  // would mix that run's state with this run's frames.
  // MPI: every rank writes its id block of the particles into bfemp.h5 and
  // checkpoint.h5 (MPI-IO; the FEM state is replicated and rank 0 writes it),
  // rank 0 the text files.
  if (root && !(opt.restart && opt.append)) std::filesystem::remove(dir + "/checkpoint.h5");
  if (comm->getSize() > 1) comm->barrier();  // the old checkpoint is gone before any rank goes on
  const MPI_Comm out_comm = comm->getSize() > 1 ? raw_mpi_comm(*comm) : MPI_COMM_NULL;
  RunOutput<dim> out(dir, scene, sim, opt.restart && opt.append ? &resume : nullptr, out_comm);
  if (opt.restart)
    log << "restart: from step " << opt.restart->step << " (t = " << opt.restart->time << " s), "
        << (opt.append ? "appending to " : "new output in ") << dir << "\n";
  const std::string ck_path = dir + "/checkpoint.h5";
  RunSummary s;
  s.contact = sim.contact() != nullptr;
  Kokkos::Timer output_timer;
  auto checkpoint = [&] {  // collective (MPI-IO: each rank its id block of the particles)
    output_timer.reset();
    const Checkpoint c = make_checkpoint(scene, opt, sim, out.frames_written());
    write_checkpoint(ck_path, c, out_comm);
    s.checkpoints++;
    s.output_s += output_timer.seconds();
  };
  auto write_frame = [&] {  // collective
    output_timer.reset();
    const auto* mpm = sim.mpm();
    if (!mpm || mpm->particles_in_id_order()) {
      out.write_frame(sim);
      s.output_s += output_timer.seconds();
      return;
    }
    // This rank's id block of the particles and of their contact forces.
    ParticleRows<dim> rows;
    const long long n = mpm->total_particles();
    rows.particles = particles_in_id_block(mpm->particles(), mpm->particle_ids(), n, *comm);
    rows.first = id_block_begin(n, comm->getRank(), comm->getSize());
    // (The branch is the same on every rank: contact_reported() is. Before
    // the first report, frame 0, there is no force yet: zeros are written.)
    if (const auto* contact = sim.contact(); contact && sim.contact_reported())
      rows.contact_forces = particle_values_in_id_block(contact->particle_forces(), dim, sim.contact_force_ids(), n, *comm);
    out.write_frame(sim, &rows);
    s.output_s += output_timer.seconds();
  };
  if (!(opt.restart && opt.append)) write_frame();  // frame 0: the initial state
  const double dt = scene.params.sublist("Time").get<double>("dt");
  const long n_steps = static_cast<long>(std::ceil(rc.end_time / dt - 1e-9));
  const long first = sim.step_index();
  std::unique_ptr<InterruptGuard> guard;
  if (opt.handle_signals) guard = std::make_unique<InterruptGuard>();
  for (long n = first; n < n_steps; ++n) {
    StepReport r;
    try {
      r = sim.step();
    } catch (const SolverError& e) {
      // A failed step leaves the state of the last completed one (the step
      // works on copies until Newton returns): checkpoint it, so that the run
      // can continue with other Newton or linear-solver settings.
      checkpoint();
      out.close();
      std::ostringstream msg;
      msg << e.what() << "\n  the state after step " << sim.step_index() << " (t = " << sim.time()
          << " s) is checkpointed; continue with other solver settings, e.g.: bfemp restart " << dir
          << " --set 'Newton/max iterations=1000' (a restart may change Newton/*, Linear Solver/*, Output/*)";
      throw SolverError(msg.str());
    }
    out.write_diagnostics(r);
    accumulate(s, r);
    // A signal during the last step: the run is complete; finish normally.
    const int sig = guard && n + 1 < n_steps ? global_signal(comm) : 0;
    const bool framed = (n + 1) % rc.output_every == 0 || n + 1 == n_steps || sig;
    if (framed) write_frame();
    if (sig || (checkpoint_every > 0 && (n + 1) % checkpoint_every == 0 && n + 1 < n_steps)) checkpoint();
    if (rc.progress_every > 0 && ((n + 1) % rc.progress_every == 0 || n + 1 == n_steps)) {
      const double el = wall.seconds();
      const long done = n + 1 - first;
      log << "step " << std::setw(6) << r.step << "/" << n_steps << "  t " << std::setw(10) << r.time
          << "  newton " << std::setw(3) << r.newton.iterations << "  E " << std::setw(12)
          << r.total_energy() << "  min J " << std::setw(8) << r.min_J << "  wall " << el
          << " s  eta " << el / done * (n_steps - n - 1) << " s\n"
          << std::flush;
    }
    if (sig)
      stop_after_signal(sig, r.step, r.time, dir, log, [&] {
        out.close();
      });
  }
  checkpoint();
  out.close();
  s.frames = out.frames_written();
  s.wall_s = wall.seconds();
  for (const auto& [name, sec] : sim.newton().term_assembly_seconds()) s.term_assembly_s.emplace_back(name, sec);
  s.graph_builds = sim.newton().dof_space().graph_builds();
  s.graph_build_causes = sim.newton().dof_space().build_causes();
  s.scatter_tables = sim.newton().dof_space().scatter_table_builds();
  s.scatter_table_s = sim.newton().dof_space().scatter_table_seconds();
  s.ranks = comm->getSize();
  s.exchange_s = sim.newton().dof_space().exchange_seconds();
  s.exchange_mb = 1e-6 * sim.newton().dof_space().exchange_bytes();
  s.graph_build_s = sim.newton().dof_space().graph_build_seconds();
  if (const auto* mpm = sim.mpm()) s.migration_s = mpm->migration_seconds();
  if (comm->getSize() > 1) {  // the slowest (busiest) rank's
    const double mine[5] = {s.exchange_s, s.migration_s, s.output_s, s.exchange_mb, s.graph_build_s};
    double most[5];
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, 5, mine, most);
    s.exchange_s = most[0];
    s.migration_s = most[1];
    s.output_s = most[2];
    s.exchange_mb = most[3];
    s.graph_build_s = most[4];
    // Each rank's own work: the spread shows a load imbalance that counts of
    // particles, elements and DOFs do not (contact pairs, factor fill).
    // The assembly: its terms' local kernels only (no term communicates), so
    // no rank's wait for another is in it.
    double terms_s = 0;
    for (const auto& [name, sec] : s.term_assembly_s) terms_s += sec;
    const double work[2] = {terms_s, s.factor_s};
    double lo[2], hi[2], sum[2];
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MIN, 2, work, lo);
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, 2, work, hi);
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, 2, work, sum);
    const double n = comm->getSize();
    s.rank_assembly_s = {lo[0], hi[0], sum[0] / n};
    s.rank_factor_s = {lo[1], hi[1], sum[1] / n};
  }
  if (const auto* mpm = sim.mpm()) {
    s.particle_sorts = mpm->particle_sorts();
    s.sort_every = mpm->sort_every();
  }
  if (const auto* mpm = sim.mpm(); mpm && mpm->distributed()) {
    s.mpm_ranks = comm->getSize();
    s.migrations = mpm->migrated_particles();
    s.rebalances = mpm->rebalances();
    s.imbalance = mpm->imbalance();
  }
  return s;
}

}  // namespace

void check_restart_override(const std::string& assignment) {
  const std::string key = assignment.substr(0, assignment.find('='));
  for (const char* allowed : kRestartKeys) {
    const std::string a = allowed;
    if (a.back() == '/' ? key.rfind(a, 0) == 0 : key == a) return;
  }
  std::string list;
  for (const char* allowed : kRestartKeys) list += std::string(list.empty() ? "" : ", ") + allowed;
  throw std::invalid_argument("restart: --set '" + key + "' would change the checkpointed state or its shape; " +
                              "a restart may change only " + list);
}

Checkpoint read_restart_checkpoint(const std::string& path, const Comm& comm) {
  Checkpoint c;
  std::string error;
  try {
    c = read_checkpoint(path, comm.getRank(), comm.getSize());
  } catch (const std::exception& e) {
    error = e.what();
    if (error.empty()) error = "checkpoint '" + path + "' could not be read";
  }
  const int ok = error.empty() ? 1 : 0;
  int all = ok;
  if (comm.getSize() > 1) Teuchos::reduceAll(comm, Teuchos::REDUCE_MIN, ok, Teuchos::outArg(all));
  if (all) return c;
  if (!ok && comm.getRank() != 0) std::cerr << "bfemp: rank " << comm.getRank() << ": " << error << "\n";
  throw std::invalid_argument(ok ? "checkpoint '" + path + "' could not be read on another rank (its message above)"
                                 : error);
}

Scene checkpoint_scene(const Checkpoint& c, const std::vector<std::string>& extra) {
  for (const auto& e : extra) check_restart_override(e);
  return load_scene_from_string(c.text("scene_source"), c.text("base_dir"), checkpoint_overrides(c, extra));
}

std::vector<std::string> checkpoint_overrides(const Checkpoint& c, const std::vector<std::string>& extra) {
  std::vector<std::string> overrides = split_lines(c.text("overrides"));
  overrides.insert(overrides.end(), extra.begin(), extra.end());
  return overrides;
}

RunSummary run_scene(const Scene& scene, const std::string& dir, const Teuchos::RCP<const Comm>& comm,
                     std::ostream& log, const RunOptions& options) {
  if (options.restart && is_explicit_checkpoint(*options.restart) != is_explicit(scene))
    throw std::invalid_argument(std::string("restart: the checkpoint was written by the ") +
                                (is_explicit(scene) ? "implicit" : "explicit") + " stepper, the scene is " +
                                (is_explicit(scene) ? "explicit" : "implicit"));
  if (is_explicit(scene)) {  // the explicit stepper: no Newton solver, Tpetra matrix or contact hash
    if (comm->getSize() > 1)
      throw std::invalid_argument("scene key 'Solver' = 'explicit': the explicit stepper runs on 1 MPI rank (this run has " +
                                  std::to_string(comm->getSize()) + "); run it without mpirun");
    ExplicitRunOptions eo;
    eo.checkpoint_texts = checkpoint_texts(scene, options);
    eo.restart = options.restart;
    eo.append = options.append;
    eo.handle_signals = options.handle_signals;
    const ExplicitRunSummary e = run_explicit_scene(scene, dir, log, eo);
    RunSummary s;
    s.steps = e.steps;
    s.frames = e.frames;
    s.checkpoints = e.checkpoints;
    s.wall_s = e.wall_s;
    return s;
  }
  RunSummary s = scene.dim() == 2 ? run_dim<2>(scene, dir, comm, log, options)
                                  : run_dim<3>(scene, dir, comm, log, options);
  if (comm->getRank() != 0) return s;
  log << "\nsummary\n"
      << "  steps               " << s.steps << "\n"
      << "  Newton iterations   " << s.newton_iterations << " (" << std::setprecision(3)
      << (s.steps ? double(s.newton_iterations) / s.steps : 0.0) << " per step)\n"
      << "  linear iterations   " << s.linear_iterations << "\n"
      << "  assembly time       " << s.assembly_s << " s\n";
  for (const auto& [name, sec] : s.term_assembly_s)
    log << "    " << std::left << std::setw(18) << name << std::right << sec << " s ("
        << std::setprecision(3) << (s.assembly_s > 0 ? 100.0 * sec / s.assembly_s : 0.0) << " %)\n";
  log << "  graph builds        " << s.graph_builds << " (symbolic factorisations " << s.symbolic_factorizations
      << "; " << s.graph_build_s << " s, within the step time)\n";
  if (!s.graph_build_causes.empty()) {
    log << "    built because     ";
    for (std::size_t k = 0; k < s.graph_build_causes.size(); ++k)
      log << (k ? ", " : "") << s.graph_build_causes[k].first << " " << s.graph_build_causes[k].second;
    log << (s.ranks > 1 ? " (on rank 0)" : "") << "\n";
  }
  if (s.scatter_tables > 0)
    log << "  scatter tables      " << s.scatter_tables << " built (" << s.scatter_table_s
        << " s; block positions of the elements' and MPM cells' stencils" << (s.ranks > 1 ? ", on rank 0" : "") << ")\n";
  log
      << "  linear-solve time   " << s.solve_s << " s\n";
  if (s.numeric_factorizations > 0)
    log << "  factorisations      " << s.numeric_factorizations << " numeric, for " << s.newton_iterations
        << " Newton iterations (the others: CG on the previous factor)"
        << (s.stale_retries > 0 ? "; " + std::to_string(s.stale_retries) + " solve(s) redone on a fresh factor" : std::string())
        << "\n";
  if (s.factor_s + s.reuse_cg_s > 0) {
    log << "    of the solve time " << s.factor_s << " s analysis + factorisation" << (s.ranks > 1 ? " (rank 0's)" : "");
    if (s.reuse_cg_iterations > 0)
      log << ", " << s.reuse_cg_s << " s in " << s.reuse_cg_iterations << " CG iterations on the previous factor";
    log << "\n";
  }
  if (s.exact_hessian_iterations + s.projection_fallbacks > 0)
    log << "  exact Hessian       " << s.exact_hessian_iterations << " of " << s.newton_iterations
        << " iterations (" << s.projection_fallbacks << " not positive definite: projected";
  if (s.partial_projections > 0)
    log << ", " << s.partial_projections << " of them keeping part of the contact curvature";
  if (s.exact_hessian_iterations + s.projection_fallbacks > 0) log << ")\n";
  if (s.projected_retries > 0)
    log << "  steps redone        " << s.projected_retries
        << " (Newton failed with the exact Hessian; the projected one converged)\n";
  log << "  line-search time    " << s.line_search_s << " s";
  if (s.wolfe_gradients > 0)
    log << " (" << s.wolfe_steps << " step(s) from the Wolfe bisection, " << s.wolfe_gradients
        << " gradient evaluations)";
  log << "\n";
  if (s.contact) {
    log << "  contact: broad phase " << s.contact_broad_phase_s << " s, pair evaluation " << s.contact_eval_s
        << " s, CCD " << s.contact_ccd_s << " s (within the times above)\n";
    log << "  pair searches       " << s.contact_searches << " among the step's candidate particles, "
        << s.contact_searches_all << " over all particles (at each step's start, and when the nodes moved "
        << "beyond the candidates' reach)\n";
  }
  if (s.sort_every > 0)
    log << "  particle sorts      " << s.particle_sorts << " (by grid cell, every " << s.sort_every << " steps)\n";
  if (s.mpm_ranks > 1)
    log << "  MPM on " << s.mpm_ranks << " ranks      " << s.migrations << " particle migrations, " << s.rebalances
        << " box rebalance(s); particle imbalance at the end " << std::setprecision(3) << s.imbalance
        << " (largest / mean per rank)\n";
  if (s.ranks > 1) {
    const auto digits = log.precision();
    auto spread = [&](const RunSummary::Spread& w) {
      log << std::setprecision(4) << w.min << ".." << w.max << " s (max / mean " << std::setprecision(3)
          << (w.mean > 0 ? w.max / w.mean : 1.0) << ")";
    };
    log << "  work per rank       assembly ";
    spread(s.rank_assembly_s);
    log << " (its energy terms' local kernels)";
    if (s.rank_factor_s.max > 0) {
      log << ", factorisations ";
      spread(s.rank_factor_s);
    }
    log << "\n";
    log.precision(digits);
  }
  if (comm->getSize() > 1)
    log << "  MPI exchanges       " << s.exchange_s << " s DOF export/import (within the times above; "
        << s.exchange_mb << " MB sent), " << s.migration_s
        << " s particle migration (slowest rank, waiting included)\n";
  log << "  output time         " << s.output_s << " s (" << s.frames << " frames, " << s.checkpoints
      << " checkpoint(s))\n";
  log << "  wall time           " << s.wall_s << " s\n"
      << "  frames written      " << s.frames << " (" << dir << "/bfemp.xdmf)\n"
      << "  checkpoint          " << dir << "/checkpoint.h5 (continue with: bfemp restart " << dir << ")\n";
  return s;
}

}  // namespace bfemp
