// Benchmark of one Newton iteration of implicit MPM (issue 3 "Performance"):
// assembly (particle stencil gradients + PSD Hessians into the Tpetra matrix)
// and linear solve timed separately, for an elastic block of particles
// settling under gravity on a no-slip level-set ground: 2D square with about
// 1e4, 1e5, 1e6 particles (4 per cell), 3D cube with about 1e5 (8 per cell),
// with Cholmod and CG + Ifpack2 (KLU2 on request). Writes JSON in the layout
// of bench_newton, so perf/compare.py compares it with
// perf/baselines/mpm_newton.json.
//
//   bench_mpm_newton [--configs 2d/1e4,2d/1e5,2d/1e6,3d/1e5] [--solvers Cholmod,CG]
//                    [--steps N] [--dt 0.01] [--out mpm_newton.json]
//                    [--linear 'Cholmod/reuse precision=double' ...]  (keys under 'Linear Solver': an A/B)
//
// Threads: Kokkos gets OMP_NUM_THREADS (perf/run_benchmarks.sh --bench
// bench_mpm_newton runs 1 and 2 threads and merges). See perf/README.md.
#include <Kokkos_Core.hpp>
#include <Kokkos_Timer.hpp>
#include <Tpetra_Core.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <mpi.h>
#include <sstream>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "bench_json.hpp"
#include "materials/lame.hpp"
#include "mpm/sampling.hpp"
#include "sim/simulation.hpp"
#include "solver/linear_solver.hpp"

namespace {

using namespace bfemp;
using namespace bfemp::bench;

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) if (!item.empty()) out.push_back(item);
  return out;
}

struct Options {
  std::vector<std::string> configs{"2d/1e4", "2d/1e5", "2d/1e6", "3d/1e5"};
  std::vector<std::string> solvers{"Cholmod", "CG"};
  int steps = 1;
  double dt = 0.01;
  bool no_skip = false;
  std::string out = "mpm_newton.json";
  std::vector<std::string> linear;  // --linear 'SUBLIST/KEY=VALUE' under 'Linear Solver'
};

[[noreturn]] void usage(const std::string& msg) {
  std::ostream& os = msg.empty() ? std::cout : std::cerr;
  if (!msg.empty()) os << "bench_mpm_newton: " << msg << "\n";
  os << "usage: bench_mpm_newton [--configs 2d/1e4,2d/1e5,2d/1e6,3d/1e4,3d/1e5]\n"
        "                        [--solvers Cholmod,KLU2,CG] [--steps N] [--dt S] [--no-skip] [--out FILE]\n"
        "                        [--linear 'Cholmod/reuse precision=double' ...]  (keys under 'Linear Solver')\n";
  std::exit(msg.empty() ? 0 : 2);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage("option " + a + " needs a value");
      return argv[++i];
    };
    if (a == "--configs") {
      o.configs = split(value());
      for (const auto& c : o.configs)
        if (c != "2d/1e4" && c != "2d/1e5" && c != "2d/1e6" && c != "3d/1e4" && c != "3d/1e5")
          usage("--configs: '" + c + "', expected 2d/1e4, 2d/1e5, 2d/1e6, 3d/1e4 or 3d/1e5");
    } else if (a == "--solvers") {
      o.solvers = split(value());
      for (const auto& s : o.solvers)
        if (s != "Cholmod" && s != "KLU2" && s != "CG") usage("--solvers: '" + s + "'");
    } else if (a == "--steps") {
      o.steps = std::stoi(value());
      if (o.steps < 1) usage("--steps: expected >= 1");
    } else if (a == "--dt") {
      o.dt = std::stod(value());
      if (!(o.dt > 0)) usage("--dt: expected > 0");
    } else if (a == "--no-skip") {
      o.no_skip = true;
    } else if (a == "--out") {
      o.out = value();
    } else if (a == "--linear") {
      o.linear.push_back(value());
    } else if (a == "--help" || a == "-h") {
      usage("");
    } else {
      usage("unknown option '" + a + "'");
    }
  }
  if (o.configs.empty() || o.solvers.empty()) usage("empty list");
  return o;
}



// 'SUBLIST/.../KEY=VALUE' into the linear solver list (an A/B of a solver
// key), VALUE read as the schema's type of KEY.
void set_linear_key(Teuchos::ParameterList& ls, const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos) usage("--linear '" + kv + "': expected KEY=VALUE");
  std::string path = kv.substr(0, eq);
  const std::string value = kv.substr(eq + 1);
  Teuchos::ParameterList* pl = &ls;
  for (auto slash = path.find('/'); slash != std::string::npos; slash = path.find('/')) {
    if (!pl->isSublist(path.substr(0, slash))) usage("--linear '" + kv + "': no sublist '" + path.substr(0, slash) + "'");
    pl = &pl->sublist(path.substr(0, slash));
    path = path.substr(slash + 1);
  }
  if (!pl->isParameter(path)) usage("--linear '" + kv + "': no key '" + path + "'");
  if (pl->isType<int>(path)) pl->set(path, std::stoi(value));
  else if (pl->isType<double>(path)) pl->set(path, std::stod(value));
  else if (pl->isType<bool>(path)) pl->set(path, value == "true");
  else pl->set(path, value);
}

// The block: unit square/cube [0,1]^dim, ppc 4 (2D) / 8 (3D), dx giving about
// `target` particles, on a no-slip half-plane ground at y = 0.
template <int dim>
SimulationSetup<dim> mpm_block(double target, const std::string& solver, double dt, double& dx) {
  const int ppc = dim == 2 ? 4 : 8;
  dx = 1.0 / std::round(std::pow(target / ppc, 1.0 / dim));
  SimulationSetup<dim> s;
  s.materials.push_back(MaterialParams{MaterialModel::NeoHookean, lame_from_young(1e6, 0.3), 1000.0});
  SamplingShape shape;
  shape.kind = "box";
  shape.center = std::vector<double>(dim, 0.5);
  shape.size = std::vector<double>(dim, 1.0);
  MpmSetup<dim> m;
  m.particles = sample_particles<dim>(shape, dx, ppc, 1000.0, 0, 0);
  m.grid = grid_covering<dim>(Vec<dim>::Constant(-0.1), Vec<dim>::Constant(1.2), dx);
  m.scheme = TransferScheme::APIC;
  m.body_names = {"block"};
  s.mpm = m;
  LevelSet ground;
  ground.name = "ground";
  s.level_sets.push_back(ground);
  s.gravity = {0.0, -9.81, 0.0};
  s.integrator = TimeIntegrator::backward_euler();
  s.dt = dt;
  s.linear_solver = *linear_solver_schema();
  s.linear_solver.set("type", solver);
  auto& cg = s.linear_solver.sublist("CG");
  cg.set("preconditioner", "CHEBYSHEV");
  cg.sublist("Ifpack2").set("chebyshev: degree", 3);
  return s;
}

// Configurations far beyond the budget of a 2-core machine, skipped unless --no-skip.
std::string skip_reason(int dim, const std::string& size, const std::string& solver) {
  if (dim == 2 && size == "1e6" && solver != "Cholmod")
    return "CG + Chebyshev(3) needs about 300 iterations per solve at 1e5 particles and ~3x more at 1e6 "
           "(~5e5 DOFs, 5e7 nonzeros): several minutes per Newton iteration; Cholmod is measured instead";
  if (dim == 3 && size == "1e5" && solver == "KLU2") return "KLU2 (no supernodes) on the 3D MPM stencil graph";
  return "";
}

template <int dim>
Json run_case(const std::string& size, const std::string& solver, const Options& o,
              const Teuchos::RCP<const Comm>& comm) {
  Json j;
  const int threads = Kokkos::DefaultExecutionSpace::concurrency();
  j.str("config", std::to_string(dim) + "d/" + size + "/" + solver)
      .integer("dim", dim)
      .str("size", size)
      .str("solver", solver)
      .integer("threads", threads);
  const std::string skip = o.no_skip ? "" : skip_reason(dim, size, solver);
  if (!skip.empty()) {
    j.str("skipped", skip);
    std::cout << "  " << dim << "D " << size << " " << solver << ": skipped\n" << std::flush;
    return j;
  }
  try {
    double dx = 0;
    Kokkos::Timer timer;
    auto setup = mpm_block<dim>(std::stod(size), solver, o.dt, dx);
    for (const std::string& kv : o.linear) set_linear_key(setup.linear_solver, kv);
    const long long np = static_cast<long long>(setup.mpm->particles.size());
    Simulation<dim> sim(setup, comm);
    Kokkos::fence();
    const double setup_s = timer.seconds();
    std::vector<double> walls;
    Kokkos::Timer it_timer;
    sim.newton().on_iterate = [&](Kokkos::View<const double*, MemSpace>) {
      walls.push_back(it_timer.seconds());
      it_timer.reset();
    };
    NewtonStats m;
    double step_s = 0, graph_s = 0, pre_s = 0, first_extra = 0;
    long long active = 0;
    std::vector<double> per_step, all_walls;
    const double cpu0 = cpu_seconds();
    Kokkos::Timer run, step_timer;
    StepReport last;
    for (int s = 0; s < o.steps; ++s) {
      walls.clear();
      step_timer.reset();
      it_timer.reset();
      last = sim.step();
      // Before Newton: activation, P2G, stencils, level sets, graph + matrix;
      // after it: velocity update, G2P, diagnostics.
      // Newton's own timers cover its iterations; the rest of iteration 1's
      // wall time (the callback clock starts with the step) is the part before.
      const double post = it_timer.seconds(), total = step_timer.seconds();
      const NewtonStats& ns = last.newton;
      const double pre = std::max(0.0, total - (ns.assembly_s + ns.solve_s + ns.line_search_s) - post);
      pre_s += pre;
      // Iteration 1 (minus the pre-Newton part) over iteration 2: the direct
      // solvers' symbolic factorisation, redone every step (the graph changes).
      if (walls.size() >= 2) first_extra += std::max(0.0, walls[0] - pre - walls[1]);
      all_walls.insert(all_walls.end(), walls.begin(), walls.end());
      const NewtonStats& n = last.newton;
      m.iterations += n.iterations;
      m.linear_iterations += n.linear_iterations;
      m.assembly_s += n.assembly_s;
      m.solve_s += n.solve_s;
      m.line_search_s += n.line_search_s;
      m.wolfe_steps += n.wolfe_steps;
      m.wolfe_gradients += n.wolfe_gradients;
      step_s += last.step_s;
      graph_s += sim.newton().last_graph_build_s();
      active = last.active_grid_nodes;
      per_step.push_back(n.iterations);
    }
    const double wall = run.seconds(), cpu = cpu_seconds() - cpu0;
    sim.newton().on_iterate = nullptr;
    const bool direct = solver != "CG";
    const double it = std::max(1, m.iterations);
    const double solve_steady = direct ? std::max(0.0, m.solve_s - first_extra) : m.solve_s;
    const long long dofs = active * dim;
    j.integer("particles", np)
        .integer("elements", np)
        .integer("dofs", dofs)
        .integer("active_grid_nodes", active)
        .num("dx", dx)
        .str("linear_solver", sim.newton().linear_solver().describe())
        .num("setup_s", setup_s)
        .integer("steps", o.steps)
        .integer("iterations", m.iterations)
        .raw("iterations_per_step", jlist(per_step))
        .num("linear_iterations_per_newton", m.linear_iterations / it)
        .num("assembly_s", m.assembly_s / it)
        .num("solve_s", solve_steady / it)
        .num("line_search_s", m.line_search_s / it)
        .integer("wolfe_steps", m.wolfe_steps)          // Newton/line search: steps from the bisection
        .integer("wolfe_gradients", m.wolfe_gradients)  // and its gradient evaluations (in line_search_s)
        .num("iteration_s", (m.assembly_s + solve_steady + m.line_search_s) / it)
        .num("symbolic_per_step_s", direct ? first_extra / o.steps : 0.0)
        .num("pre_newton_per_step_s", pre_s / o.steps)
        .num("graph_build_per_step_s", graph_s / o.steps)
        .num("step_s", step_s / o.steps)
        .num("min_J", last.min_J)
        .raw("iteration_wall_s", jlist(all_walls))
        .num("cpu_utilisation", wall > 0 ? cpu / (wall * threads) : 0.0);
    std::cout << std::fixed << std::setprecision(4) << "  " << dim << "D " << size << " " << solver << ": "
              << np << " particles, " << dofs << " DOFs, " << m.iterations << " Newton its; per iteration: "
              << "assembly " << m.assembly_s / it << " s, solve " << solve_steady / it << " s ("
              << m.linear_iterations / it << " lin its), line search " << m.line_search_s / it
              << " s; per step: graph " << graph_s / o.steps << " s, before Newton " << pre_s / o.steps << " s, symbolic " << (direct ? first_extra / o.steps : 0.0)
              << " s, step " << step_s / o.steps << " s\n"
              << std::defaultfloat << std::flush;
  } catch (const std::exception& e) {
    j.str("failed", e.what());
    std::cout << "  " << dim << "D " << size << " " << solver << ": FAILED: " << e.what() << "\n" << std::flush;
  }
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  const Options opts = parse(argc, argv);
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int code = 0;
  {
    Kokkos::ScopeGuard kokkos(kokkos_args_from_env());
    Tpetra::ScopeGuard tpetra(&argc, &argv);
    auto comm = Tpetra::getDefaultComm();
    const int threads = Kokkos::DefaultExecutionSpace::concurrency();
    std::cout << "bench_mpm_newton: Kokkos " << Kokkos::DefaultExecutionSpace::name() << ", " << threads
              << " thread(s)\n" << std::flush;
    std::vector<Json> results;
    for (const auto& c : opts.configs)
      for (const auto& s : opts.solvers) {
        const std::string size = c.substr(3);
        results.push_back(c[0] == '2' ? run_case<2>(size, s, opts, comm) : run_case<3>(size, s, opts, comm));
      }
    std::string arr = "[\n";
    for (std::size_t i = 0; i < results.size(); ++i)
      arr += "    " + results[i].dump(4) + (i + 1 < results.size() ? ",\n" : "\n");
    arr += "  ]";
    const char* obt = std::getenv("OPENBLAS_NUM_THREADS");
    Json top;
    top.str("benchmark", "mpm_newton_iteration")
        .integer("threads", threads)
        .str("kokkos_backend", Kokkos::DefaultExecutionSpace::name())
        .str("openblas_num_threads", obt ? obt : "")
        .raw("scene", Json()
                          .str("shape", "unit square (2D, 4 particles per cell) / unit cube (3D, 8 per cell)")
                          .str("material", "neo-Hookean, E = 1e6 Pa, nu = 0.3, density 1000 kg/m^3")
                          .str("boundary", "no-slip level-set half-plane y < 0 (the block rests on it)")
                          .str("transfer", "APIC")
                          .num("gravity_y", -9.81)
                          .str("integrator", "backward Euler")
                          .num("dt", opts.dt)
                          .num("newton_eps_d", NewtonParams{}.eps_d)
                          .integer("steps", opts.steps)
                          .dump(2))
        .str("cg_preconditioner", "Ifpack2 CHEBYSHEV, chebyshev: degree = 3")
        .raw("results", arr);
    std::ofstream f(opts.out);
    f << top.dump(0) << "\n";
    if (!f) {
      std::cerr << "bench_mpm_newton: cannot write " << opts.out << "\n";
      code = 1;
    } else {
      std::cout << "bench_mpm_newton: wrote " << opts.out << "\n";
    }
    for (const auto& r : results)
      for (const auto& kv : r.kv)
        if (kv.first == "failed") code = 3;
  }
  MPI_Finalize();
  return code;
}
