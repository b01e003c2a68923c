#include "explicit/explicit_run.hpp"

#include <Kokkos_Timer.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <vector>

#include "explicit/explicit_simulation.hpp"
#include "io/hdf5_frames.hpp"
#include "io/scene_explicit.hpp"

namespace bfemp {

namespace {

template <int dim>
void write_frame(Hdf5FrameWriter& h5, int index, const ExplicitSimulation<dim>& sim) {
  const auto& p = sim.particles();
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  auto s = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.sigma);
  auto b = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.body);
  auto c = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.cls);
  const std::size_t n = x.extent(0);
  std::vector<double> xs(n * dim), vs(n * dim), ss(n * dim * dim);
  std::vector<long long> bs(n), cs(n);
  for (std::size_t q = 0; q < n; ++q) {
    for (int d = 0; d < dim; ++d) {
      xs[q * dim + d] = x(q, d);
      vs[q * dim + d] = v(q, d);
      for (int e = 0; e < dim; ++e) ss[(q * dim + d) * dim + e] = s(q, d, e);
    }
    bs[q] = b(q);
    cs[q] = c(q);
  }
  h5.begin_frame(index, sim.time(), sim.step_index());
  h5.write_array("particle_x", xs.data(), n, dim);
  h5.write_array("particle_v", vs.data(), n, dim);
  h5.write_array("particle_stress", ss.data(), n, dim * dim);
  h5.write_array("particle_body", bs.data(), n, 1);
  h5.write_array("particle_material_class", cs.data(), n, 1);
  h5.end_frame();
}

template <int dim>
ExplicitRunSummary run_dim(const Scene& scene, const std::string& dir, std::ostream& log) {
  Kokkos::Timer wall;
  const RunControl rc = scene.run_control();
  ExplicitSimulation<dim> sim(build_explicit_setup<dim>(scene));
  const auto& st = sim.setup();
  log << "explicit MPM: " << sim.particles().size() << " particles, " << sim.num_classes() << " material classes, grid "
      << sim.grid().num_nodes() << " nodes (dx " << sim.grid().dx << "), dt "
      << (st.fixed_dt > 0 ? st.fixed_dt : sim.dt_limit()) << (st.fixed_dt > 0 ? " (fixed)" : " (CFL)") << "\n";
  std::filesystem::create_directories(dir);
  std::filesystem::remove(dir + "/checkpoint.h5");
  Hdf5FrameWriter h5(dir + "/bfemp.h5");
  std::ofstream csv(dir + "/diagnostics.csv");
  csv << "step,time,dt,dt_limit,contact_nodes,multi_nodes,active_nodes,lr_iter_mean,lr_iter_max,"
         "stress_body_Pa,stress_all_Pa,momentum_x,momentum_y,momentum_z,kinetic,step_s\n";
  csv << std::setprecision(12);
  ExplicitRunSummary s;
  write_frame(h5, s.frames++, sim);
  bool warned = false;
  while (sim.time() < rc.end_time * (1 - 1e-12)) {
    const ExplicitReport r = sim.step();
    s.steps++;
    s.p2g_s += r.p2g_s;
    s.contact_s += r.contact_s;
    s.stress_s += r.stress_s;
    s.g2p_s += r.g2p_s;
    csv << r.step << "," << r.time << "," << r.dt << "," << r.dt_limit << "," << r.contact_nodes << ","
        << r.multi_nodes << "," << r.active_nodes << "," << r.lr_iter_mean << "," << r.lr_iter_max << ","
        << r.stress_body << "," << r.stress_all << "," << r.momentum[0] << "," << r.momentum[1] << ","
        << r.momentum[2] << "," << r.kinetic << "," << r.step_s << "\n";
    if (!warned && sim.steps_over_limit() > 0) {
      log << "warning: step " << r.step << ": the fixed dt " << r.dt << " s exceeds the CFL limit " << r.dt_limit
          << " s\n";
      warned = true;
    }
    const bool last = sim.time() >= rc.end_time * (1 - 1e-12);
    if (s.steps % rc.output_every == 0 || last) write_frame(h5, s.frames++, sim);
    if (rc.progress_every > 0 && (s.steps % rc.progress_every == 0 || last))
      log << "step " << std::setw(7) << r.step << "  t " << std::setw(10) << r.time << "  dt " << r.dt
          << "  contact nodes " << r.contact_nodes << "  stress " << r.stress_body << " Pa  wall " << wall.seconds()
          << " s\n"
          << std::flush;
  }
  h5.close();
  s.wall_s = wall.seconds();
  return s;
}

}  // namespace

ExplicitRunSummary run_explicit_scene(const Scene& scene, const std::string& dir, std::ostream& log) {
  ExplicitRunSummary s = scene.dim() == 2 ? run_dim<2>(scene, dir, log) : run_dim<3>(scene, dir, log);
  log << "\nsummary (explicit)\n"
      << "  steps               " << s.steps << "\n"
      << "  P2G + forces        " << s.p2g_s << " s\n"
      << "  contact passes      " << s.contact_s << " s\n"
      << "  stress update       " << s.stress_s << " s\n"
      << "  G2P (+ XPIC)        " << s.g2p_s << " s\n"
      << "  wall time           " << s.wall_s << " s\n"
      << "  frames written      " << s.frames << " (" << dir << "/bfemp.h5; diagnostics.csv)\n";
  return s;
}

}  // namespace bfemp
