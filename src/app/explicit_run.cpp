#include "app/explicit_run.hpp"

#include <Kokkos_Timer.hpp>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <ostream>
#include <vector>

#include "app/explicit_output.hpp"
#include "explicit/explicit_simulation.hpp"
#include "io/scene_explicit.hpp"
#include "app/interrupt.hpp"
#include "app/run_checks.hpp"

namespace bfemp {

namespace {

template <int dim>
Checkpoint make_checkpoint(const ExplicitRunOptions& opt, const ExplicitSimulation<dim>& sim, int frames) {
  ExplicitState st = sim.state();
  Checkpoint c;
  c.time = st.time;
  c.step = st.step;
  c.frames = frames;
  c.dim = dim;
  c.texts = opt.checkpoint_texts;
  c.texts["stepper"] = "explicit";
  c.put("particle_x", std::move(st.x), dim);
  c.put("particle_v", std::move(st.v), dim);
  c.put("particle_F", std::move(st.F), dim * dim);
  auto body = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.particles().body);
  c.put("particle_body", std::vector<long long>(body.data(), body.data() + body.size()));
  c.put("steps_over_cfl_limit", std::vector<long long>{st.over_limit});
  return c;
}

template <int dim>
void restore(ExplicitSimulation<dim>& sim, const Checkpoint& c) {
  const long np = static_cast<long>(sim.particles().size());
  auto body = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.particles().body);
  const auto& cb = c.ints("particle_body", np);
  for (long q = 0; q < np; ++q)
    if (cb[q] != body(q))
      throw std::invalid_argument("restart: particle " + std::to_string(q) +
                                  " belongs to another body in the checkpoint than in the scene (the scene does not "
                                  "produce the checkpoint's particles)");
  ExplicitState s;
  s.time = c.time;
  s.step = c.step;
  s.over_limit = c.ints("steps_over_cfl_limit", 1)[0];
  s.x = c.real("particle_x", np);
  s.v = c.real("particle_v", np);
  s.F = c.real("particle_F", np);
  sim.restore(s);
}

template <int dim>
ExplicitRunSummary run_dim(const Scene& scene, const std::string& dir, std::ostream& log,
                           const ExplicitRunOptions& opt) {
  Kokkos::Timer wall;
  const RunControl rc = scene.run_control();
  const int checkpoint_every = checked_checkpoint_every(scene);
  if (opt.restart) check_restart_dimension(opt.restart->dim, dim);
  ExplicitSimulation<dim> sim(build_explicit_setup<dim>(scene));
  if (opt.restart) restore(sim, *opt.restart);
  const auto& st = sim.setup();
  log << "explicit MPM: " << sim.particles().size() << " particles, " << sim.num_classes() << " material classes, grid "
      << sim.grid().num_nodes() << " nodes (dx " << sim.grid().dx << "), dt "
      << (st.fixed_dt > 0 ? st.fixed_dt : sim.dt_limit()) << (st.fixed_dt > 0 ? " (fixed)" : " (CFL)") << "\n";
  const bool append = opt.restart && opt.append;
  // A new output must not keep an older run's checkpoint.
  if (!append) {
    std::filesystem::create_directories(dir);
    std::filesystem::remove(dir + "/checkpoint.h5");
  }
  ExplicitResume resume;
  if (append) resume = {opt.restart->frames, opt.restart->step};
  ExplicitOutput<dim> out(dir, scene, sim, append ? &resume : nullptr);
  if (!append) out.write_frame(sim);
  if (opt.restart)
    log << "restart: from step " << opt.restart->step << " (t = " << opt.restart->time << " s), "
        << (append ? "appending to " : "new output in ") << dir << "\n";
  ExplicitRunSummary s;
  const std::string ck_path = dir + "/checkpoint.h5";
  auto checkpoint = [&] {
    write_checkpoint(ck_path, make_checkpoint(opt, sim, out.frames_written()));
    s.checkpoints++;
  };
  std::unique_ptr<InterruptGuard> guard;
  if (opt.handle_signals) guard = std::make_unique<InterruptGuard>();
  auto done = [&] { return sim.time() >= rc.end_time * (1 - 1e-12); };
  bool warned = false;
  while (!done()) {
    const ExplicitReport r = sim.step();
    s.steps++;
    s.p2g_s += r.p2g_s;
    s.contact_s += r.contact_s;
    s.stress_s += r.stress_s;
    s.g2p_s += r.g2p_s;
    out.write_diagnostics(r);
    if (!warned && sim.steps_over_limit() > 0) {
      log << "warning: step " << r.step << ": the fixed dt " << r.dt << " s exceeds the CFL limit " << r.dt_limit
          << " s\n";
      warned = true;
    }
    const bool last = done();
    const int sig = guard && !last ? pending_signal() : 0;
    if (r.step % rc.output_every == 0 || last || sig) out.write_frame(sim);
    if (sig || (checkpoint_every > 0 && r.step % checkpoint_every == 0 && !last)) checkpoint();
    if (rc.progress_every > 0 && (r.step % rc.progress_every == 0 || last))
      log << "step " << std::setw(7) << r.step << "  t " << std::setw(10) << r.time << "  dt " << r.dt
          << "  contact nodes " << r.contact_nodes << "  stress " << r.stress_body << " Pa  wall " << wall.seconds()
          << " s\n"
          << std::flush;
    if (sig) stop_after_signal(sig, r.step, r.time, dir, log, [&] { out.close(); });
  }
  checkpoint();
  out.close();
  s.frames = out.frames_written();
  s.wall_s = wall.seconds();
  if (sim.steps_over_limit() > 0)
    log << "warning: " << sim.steps_over_limit() << " steps ran with the fixed dt above the CFL limit\n";
  return s;
}

}  // namespace

bool is_explicit_checkpoint(const Checkpoint& c) {
  const auto it = c.texts.find("stepper");
  return it != c.texts.end() && it->second == "explicit";
}

ExplicitRunSummary run_explicit_scene(const Scene& scene, const std::string& dir, std::ostream& log,
                                      const ExplicitRunOptions& opt) {
  ExplicitRunSummary s = scene.dim() == 2 ? run_dim<2>(scene, dir, log, opt) : run_dim<3>(scene, dir, log, opt);
  const double total = s.p2g_s + s.contact_s + s.stress_s + s.g2p_s;
  auto share = [&](double x) { return total > 0 ? 100.0 * x / total : 0.0; };
  log << "\nsummary (explicit)\n" << std::setprecision(4)
      << "  steps               " << s.steps << "\n"
      << "  P2G + forces        " << s.p2g_s << " s (" << share(s.p2g_s) << " %)\n"
      << "  contact passes      " << s.contact_s << " s (" << share(s.contact_s) << " %)\n"
      << "  stress update       " << s.stress_s << " s (" << share(s.stress_s) << " %)\n"
      << "  G2P (+ XPIC)        " << s.g2p_s << " s (" << share(s.g2p_s) << " %)\n"
      << "  wall time           " << s.wall_s << " s\n"
      << "  frames written      " << s.frames << " (" << dir << "/bfemp.xdmf)\n"
      << "  checkpoint          " << dir << "/checkpoint.h5 (continue with: bfemp restart " << dir << ")\n"
      << std::setprecision(6);
  return s;
}

}  // namespace bfemp
