#include "sim/run.hpp"

#include <Kokkos_Timer.hpp>
#include <cmath>
#include <iomanip>
#include <ostream>

#include "io/run_output.hpp"

namespace bfemp {

namespace {

template <int dim>
RunSummary run_dim(const Scene& scene, const std::string& dir, const Teuchos::RCP<const Comm>& comm,
                   std::ostream& log) {
  Kokkos::Timer wall;
  const RunControl rc = scene.run_control();
  Simulation<dim> sim(build_setup<dim>(scene), comm);
  const auto& mesh = sim.mesh();
  log << "FEM: " << mesh.num_nodes() << " nodes, " << mesh.num_cells() << " elements, "
      << mesh.num_nodes() * dim << " DOFs";
  if (const auto* mpm = sim.mpm())
    log << "; MPM: " << mpm->particles().size() << " particles, " << transfer_scheme_name(mpm->scheme())
        << ", grid " << mpm->grid().num_nodes() << " nodes (dx " << mpm->grid().dx << ")";
  log << "; linear solver: " << sim.newton().linear_solver().describe() << "\n";
  RunOutput<dim> out(dir, scene, sim);
  out.write_frame(sim);
  const double dt = scene.params.sublist("Time").get<double>("dt");
  const long n_steps = static_cast<long>(std::ceil(rc.end_time / dt - 1e-9));
  RunSummary s;
  for (long n = 0; n < n_steps; ++n) {
    const StepReport r = sim.step();
    out.write_diagnostics(r);
    s.steps++;
    s.newton_iterations += r.newton.iterations;
    s.linear_iterations += r.newton.linear_iterations;
    s.assembly_s += r.newton.assembly_s;
    s.solve_s += r.newton.solve_s;
    s.line_search_s += r.newton.line_search_s;
    s.contact = sim.contact() != nullptr;
    s.contact_broad_phase_s += r.contact_broad_phase_s;
    s.contact_eval_s += r.contact_eval_s;
    s.contact_ccd_s += r.contact_ccd_s;
    if ((n + 1) % rc.output_every == 0 || n + 1 == n_steps) out.write_frame(sim);
    if (rc.progress_every > 0 && ((n + 1) % rc.progress_every == 0 || n + 1 == n_steps)) {
      const double el = wall.seconds();
      log << "step " << std::setw(6) << r.step << "/" << n_steps << "  t " << std::setw(10) << r.time
          << "  newton " << std::setw(3) << r.newton.iterations << "  E " << std::setw(12)
          << r.total_energy() << "  min J " << std::setw(8) << r.min_J << "  wall " << el
          << " s  eta " << el / (n + 1) * (n_steps - n - 1) << " s\n"
          << std::flush;
    }
  }
  out.close();
  s.frames = out.frames_written();
  s.wall_s = wall.seconds();
  return s;
}

}  // namespace

RunSummary run_scene(const Scene& scene, const std::string& dir, const Teuchos::RCP<const Comm>& comm,
                     std::ostream& log) {
  RunSummary s = scene.dim() == 2 ? run_dim<2>(scene, dir, comm, log) : run_dim<3>(scene, dir, comm, log);
  log << "\nsummary\n"
      << "  steps               " << s.steps << "\n"
      << "  Newton iterations   " << s.newton_iterations << " (" << std::setprecision(3)
      << (s.steps ? double(s.newton_iterations) / s.steps : 0.0) << " per step)\n"
      << "  linear iterations   " << s.linear_iterations << "\n"
      << "  assembly time       " << s.assembly_s << " s\n"
      << "  linear-solve time   " << s.solve_s << " s\n"
      << "  line-search time    " << s.line_search_s << " s\n";
  if (s.contact)
    log << "  contact: broad phase " << s.contact_broad_phase_s << " s, pair evaluation " << s.contact_eval_s
        << " s, CCD " << s.contact_ccd_s << " s (within the times above)\n";
  log
      << "  wall time           " << s.wall_s << " s\n"
      << "  frames written      " << s.frames << " (" << dir << "/bfemp.xdmf)\n";
  return s;
}

}  // namespace bfemp
