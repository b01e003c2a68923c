// The explicit multimaterial MPM step (src/explicit, paper 001 §3.2) on the
// B1 two-block scene (src/explicit/two_blocks.hpp: plane strain, uGIMP, Eq. 18,
// Coulomb mu = 0.2, bottom fixed, piston on top) with two contact passes, LR
// normals and XPIC(5): time per particle-step at the paper's size (5 mm
// cells, 4 particles per cell: 640 particles) and at 4x and 16x the particle
// count (2.5 mm and 1.25 mm cells, the same blocks), with the share of the
// step spent in contact (LR normals and separations, both passes) and the
// other phases of ExplicitReport. Each size runs a warm-up of 20 steps, then
// `steps` timed steps (the blocks start in contact, so every step has
// contact nodes); wall time around ExplicitSimulation::step (which includes
// the grid-containment check and the diagnostics) and the stepper's own
// step time are both reported.
//   bench_explicit [--out explicit.json] [--quick]
// Run at 1 and 2 threads with perf/run_benchmarks.sh --bench bench_explicit;
// compare with perf/compare.py --baseline <file> --fields per_particle_step_s.
#include <Kokkos_Core.hpp>
#include <Kokkos_Timer.hpp>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "bench_json.hpp"
#include "explicit/explicit_simulation.hpp"
#include "explicit/two_blocks.hpp"

using namespace bfemp;
using namespace bfemp::bench;

namespace {

Json run(int refine, int steps) {
  TwoBlocks tb;
  tb.dx = 0.005 / refine;
  ExplicitSetup<2> s = tb.setup();
  s.normals = XNormals::LR;
  s.contact_passes = 2;
  s.update = XUpdate::XPIC;
  s.xpic_order = 5;
  ExplicitSimulation<2> sim(s);
  const long np = static_cast<long>(sim.particles().size());
  for (int n = 0; n < 20; ++n) sim.step();
  double p2g = 0, contact = 0, stress = 0, g2p = 0, inner = 0, lr_it = 0;
  long cnodes = 0;
  Kokkos::Timer wall;
  for (int n = 0; n < steps; ++n) {
    const ExplicitReport r = sim.step();
    p2g += r.p2g_s;
    contact += r.contact_s;
    stress += r.stress_s;
    g2p += r.g2p_s;
    inner += r.step_s;
    lr_it += r.lr_iter_mean;
    cnodes += r.contact_nodes;
  }
  const double total = wall.seconds();
  const double items = double(np) * steps;
  const int threads = Kokkos::DefaultExecutionSpace::concurrency();
  std::cout << "  " << np << " particles (dx " << tb.dx * 1e3 << " mm), " << steps << " steps: " << total / items * 1e9
            << " ns per particle-step (stepper " << inner / items * 1e9 << "), contact " << 100 * contact / inner
            << " % of the step, " << double(cnodes) / steps << " contact nodes, LR iterations " << lr_it / steps
            << "\n"
            << std::flush;
  return Json()
      .integer("dim", 2)
      .str("size", std::to_string(np))
      .str("solver", "explicit_lr_2pass_xpic5")
      .integer("threads", threads)
      .integer("particles", np)
      .integer("steps", steps)
      .num("cell_m", tb.dx)
      .num("total_s", total)
      .num("step_s", inner)
      .num("per_particle_step_s", total / items)
      .num("stepper_per_particle_step_s", inner / items)
      .num("contact_s", contact)
      .num("p2g_forces_s", p2g)
      .num("stress_s", stress)
      .num("g2p_xpic_s", g2p)
      .num("contact_share", contact / inner)
      .num("contact_nodes_mean", double(cnodes) / steps)
      .num("lr_iterations_mean", lr_it / steps);
}

}  // namespace

int main(int argc, char** argv) {
  BenchArgs args{"explicit.json"};
  if (const int bad = parse_bench_args(argc, argv, "bench_explicit", args)) return bad;
  const bool quick = args.quick;
  int code = 0;
  {
    Kokkos::ScopeGuard kokkos(kokkos_args_from_env());
    const int threads = Kokkos::DefaultExecutionSpace::concurrency();
    std::cout << "bench_explicit: Kokkos " << Kokkos::DefaultExecutionSpace::name() << ", " << threads
              << " thread(s)\n";
    std::vector<Json> results;
    results.push_back(run(1, quick ? 100 : 1000));
    results.push_back(run(2, quick ? 25 : 250));
    results.push_back(run(4, quick ? 6 : 60));
    Json top;
    top.str("benchmark", "explicit")
        .integer("threads", threads)
        .str("kokkos_backend", Kokkos::DefaultExecutionSpace::name())
        .raw("scene", Json()
                          .str("scene", "B1 two blocks 40 x 100 mm in contact on a grid line, piston at 0.05 % of c")
                          .str("method", "uGIMP, LR normals, two contact passes, Coulomb mu = 0.2, XPIC(5)")
                          .str("sizes", "5 mm, 2.5 mm, 1.25 mm cells; 4 particles per cell")
                          .dump(2))
        .raw("results", jarray(results, 4));
    code = write_json(top, args.out, "bench_explicit");
  }
  return code;
}
