// Benchmark of one Newton iteration of the implicit FEM solver: assembly,
// linear solve and line search timed separately, for a clamped neo-Hookean
// block sagging under gravity (2D square / 3D cube, about 1e3, 1e4, 1e5 DOFs)
// with the Cholmod, KLU2 and CG + Ifpack2 linear solvers. Writes JSON.
//
//   bench_newton [--dims 2,3] [--sizes small,medium,large]
//                [--solvers Cholmod,KLU2,CG] [--cg-preconditioner CHEBYSHEV|SGS|JACOBI|RILUK|MUELU|NONE]
//                [--steps N] [--dt 0.05] [--velocity vx,vy[,vz]] [--out newton.json]
//
// MPI: under mpirun (CG only) the FEM elements are cut into the ranks.
// Threads: Kokkos gets OMP_NUM_THREADS (see perf/run_benchmarks.sh, which runs
// this at 1 and 2 threads and merges the results). See perf/README.md for the
// meaning of every field.
#include <Kokkos_Core.hpp>
#include <Kokkos_Timer.hpp>
#include <Tpetra_Core.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <mpi.h>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "io/shape_mesher.hpp"
#include "bench_json.hpp"
#include "materials/lame.hpp"
#include "materials/material.hpp"
#include "sim/simulation.hpp"
#include "solver/linear_solver.hpp"
#include "solver/solver_error.hpp"

namespace {

using namespace bfemp;
using namespace bfemp::bench;

// ---------------------------------------------------------------- options --

std::vector<std::string> split(const std::string& s, char sep = ',') {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(s);
  while (std::getline(in, item, sep))
    if (!item.empty()) out.push_back(item);
  return out;
}

struct Options {
  std::vector<int> dims{2, 3};
  std::vector<std::string> sizes{"small", "medium", "large"};
  std::vector<std::string> solvers{"Cholmod", "KLU2", "CG"};
  std::string cg_prec = "CHEBYSHEV";
  int steps = 0;            // time steps per configuration; 0: see steps_for()
  double dt = 0.05;
  std::array<double, 3> v0{0.0, 0.0, 0.0};  // initial velocity of the block (m/s)
  bool no_skip = false;     // run the configurations that are skipped by default
  bool mesh_only = false;   // print the mesh sizes and stop (to re-tune element_size)
  std::string out = "newton.json";
};

// Prints the usage (after `msg`, if any) and exits: 0 for --help, 2 otherwise.
[[noreturn]] void usage(const std::string& msg) {
  std::ostream& os = msg.empty() ? std::cout : std::cerr;
  if (!msg.empty()) os << "bench_newton: " << msg << "\n";
  os << "usage: bench_newton [--dims 2,3] [--sizes small,medium,large]\n"
        "                    [--solvers Cholmod,KLU2,CG] [--cg-preconditioner "
        "SGS|JACOBI|CHEBYSHEV|RILUK|MUELU|NONE]\n"
        "                    [--steps N] [--dt SECONDS] [--velocity vx,vy[,vz]]\n"
        "                    [--no-skip] [--mesh-only] [--out FILE]\n";
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
    if (a == "--dims") {
      o.dims.clear();
      for (const auto& d : split(value())) {
        if (d != "2" && d != "3") usage("--dims: '" + d + "', expected 2 or 3");
        o.dims.push_back(std::stoi(d));
      }
    } else if (a == "--sizes") {
      o.sizes = split(value());
      for (const auto& s : o.sizes)
        if (s != "small" && s != "medium" && s != "large")
          usage("--sizes: '" + s + "', expected small, medium or large");
    } else if (a == "--solvers") {
      o.solvers = split(value());
      for (const auto& s : o.solvers)
        if (s != "Cholmod" && s != "KLU2" && s != "CG")
          usage("--solvers: '" + s + "', expected Cholmod, KLU2 or CG");
    } else if (a == "--cg-preconditioner") {
      o.cg_prec = value();
      if (o.cg_prec != "SGS" && o.cg_prec != "JACOBI" && o.cg_prec != "CHEBYSHEV" &&
          o.cg_prec != "RILUK" && o.cg_prec != "MUELU" && o.cg_prec != "NONE")
        usage("--cg-preconditioner: '" + o.cg_prec + "'");
    } else if (a == "--steps") {
      o.steps = std::stoi(value());
      if (o.steps < 1) usage("--steps: expected >= 1");
    } else if (a == "--dt") {
      o.dt = std::stod(value());
      if (!(o.dt > 0)) usage("--dt: expected > 0");
    } else if (a == "--velocity") {
      const auto c = split(value());
      if (c.empty() || c.size() > 3) usage("--velocity: expected vx,vy[,vz]");
      for (std::size_t k = 0; k < c.size(); ++k) o.v0[k] = std::stod(c[k]);
    } else if (a == "--mesh-only") {
      o.mesh_only = true;
    } else if (a == "--no-skip") {
      o.no_skip = true;
    } else if (a == "--out") {
      o.out = value();
    } else if (a == "--help" || a == "-h") {
      usage("");
    } else {
      usage("unknown option '" + a + "'");
    }
  }
  if (o.dims.empty() || o.sizes.empty() || o.solvers.empty()) usage("empty list");
  return o;
}

// ------------------------------------------------------------------ scene --

// Target edge lengths giving about 1e3, 1e4, 1e5 DOFs on the unit square /
// cube (measured with Gmsh 4.8.4; the JSON records the actual counts).
double element_size(int dim, const std::string& size) {
  static const std::map<std::string, double> h2 = {
      {"small", 0.0524}, {"medium", 0.01566}, {"large", 0.00484}};
  static const std::map<std::string, double> h3 = {
      {"small", 0.18}, {"medium", 0.069}, {"large", 0.0298}};
  return dim == 2 ? h2.at(size) : h3.at(size);
}

// Configurations that would run for minutes on a 2-core machine are skipped
// unless --no-skip; the reason goes into the JSON.
std::string skip_reason(int dim, const std::string& size, const std::string& solver) {
  if (dim == 3 && size == "large" && solver == "KLU2")
    return "KLU2 (no supernodes, no BLAS-3) on the 3D 1e5-DOF block: its fill and "
           "factorisation time are far beyond the benchmark budget (tens of seconds "
           "to minutes per Newton iteration); use Cholmod or CG at this size";
  return "";
}

Teuchos::ParameterList linear_solver_list(const std::string& solver, const std::string& prec) {
  Teuchos::ParameterList ls = *linear_solver_schema();
  ls.set("type", solver);
  auto& cg = ls.sublist("CG");
  auto& ifp = cg.sublist("Ifpack2");
  if (prec == "SGS") {
    cg.set("preconditioner", "RELAXATION");
    ifp.set("relaxation: type", "Symmetric Gauss-Seidel");
  } else if (prec == "JACOBI") {
    cg.set("preconditioner", "RELAXATION");
    ifp.set("relaxation: type", "Jacobi");
  } else if (prec == "CHEBYSHEV") {
    cg.set("preconditioner", "CHEBYSHEV");
    ifp.set("chebyshev: degree", 3);
  } else if (prec == "RILUK") {
    cg.set("preconditioner", "RILUK");
    ifp.set("fact: iluk level-of-fill", 0);
  } else if (prec == "MUELU") {
    cg.set("preconditioner", "MUELU");  // bfemp's MueLu defaults (smoothed aggregation, rigid-body modes)
  } else {
    cg.set("preconditioner", "NONE");
  }
  return ls;
}

std::string prec_description(const std::string& prec) {
  if (prec == "SGS") return "Ifpack2 RELAXATION, relaxation: type = Symmetric Gauss-Seidel, 1 sweep";
  if (prec == "JACOBI") return "Ifpack2 RELAXATION, relaxation: type = Jacobi, 1 sweep";
  if (prec == "CHEBYSHEV") return "Ifpack2 CHEBYSHEV, chebyshev: degree = 3";
  if (prec == "RILUK") return "Ifpack2 RILUK, fact: iluk level-of-fill = 0";
  if (prec == "MUELU") return "MueLu smoothed aggregation, rigid-body near-null space, bfemp defaults";
  return "none";
}

template <int dim>
SimulationSetup<dim> make_setup(const MeshData& mesh, const Teuchos::ParameterList& ls, double dt,
                                const std::array<double, 3>& v0) {
  SimulationSetup<dim> s;
  s.bodies.push_back(FemBodyInput{"block", mesh, 0});
  s.materials.push_back(MaterialParams{MaterialModel::NeoHookean, lame_from_young(1e6, 0.3), 1000.0});
  PrescribedMotion clamp;
  clamp.name = "bottom";
  for (long long n : mesh.node_sets.at("bottom")) clamp.nodes.push_back(static_cast<LO>(n));
  clamp.segments.push_back(MotionSegment{});  // fixed
  s.motions.push_back(clamp);
  s.initial_velocity.push_back(v0);
  s.integrator = TimeIntegrator::backward_euler();
  s.gravity = {0.0, 0.0, 0.0};
  s.gravity[1] = -9.81;  // y is "up": "bottom" is y = min
  s.dt = dt;
  s.linear_solver = ls;
  return s;
}

// ------------------------------------------------------------------- JSON --




// -------------------------------------------------------------- benchmark --


double loadavg1() {  // 1-minute load average (other users of the machine)
  double l = -1;
  if (std::FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &l) != 1) l = -1;
    std::fclose(f);
  }
  return l;
}


// Time steps per configuration (each takes 3 Newton iterations in this
// scene): more where an iteration is cheap, to average out noise; one for the
// large cases and for KLU2 on the 3D medium case, whose iterations take seconds.
int steps_for(const Options& o, int dim, const std::string& size, const std::string& solver) {
  if (o.steps > 0) return o.steps;
  if (size == "large" || (dim == 3 && size != "small" && solver == "KLU2")) return 1;
  return size == "small" ? 3 : 2;
}

template <int dim>
Json run_case(const MeshData& mesh, const std::string& size, const std::string& solver,
              const Options& o, double mesh_s, const Teuchos::RCP<const Comm>& comm) {
  Json j;
  const long long dofs = static_cast<long long>(mesh.num_nodes()) * dim;
  const int threads = Kokkos::DefaultExecutionSpace::concurrency();
  j.str("config", std::to_string(dim) + "d/" + size + "/" + solver)
      .integer("dim", dim)
      .str("size", size)
      .str("solver", solver)
      .integer("threads", threads)
      .integer("dofs", dofs)
      .integer("nodes", static_cast<long long>(mesh.num_nodes()))
      .integer("elements", static_cast<long long>(mesh.num_cells()))
      .num("element_size", element_size(dim, size))
      .integer("clamped_nodes", static_cast<long long>(mesh.node_sets.at("bottom").size()));
  if (solver == "CG") j.str("preconditioner", prec_description(o.cg_prec));
  const std::string skip = o.no_skip ? "" : skip_reason(dim, size, solver);
  if (!skip.empty()) {
    j.str("skipped", skip);
    std::cout << "  " << dim << "D " << size << " " << solver << ": skipped\n" << std::flush;
    return j;
  }
  const bool direct = solver != "CG";
  try {
    const double load0 = loadavg1();
    Kokkos::Timer timer;
    Simulation<dim> sim(make_setup<dim>(mesh, linear_solver_list(solver, o.cg_prec), o.dt, o.v0), comm);
    Kokkos::fence();
    const double setup_s = timer.seconds();
    j.str("linear_solver", sim.newton().linear_solver().describe());

    // Wall time of every Newton iteration (each ends with a fence before the
    // callback), to separate the one-time cost hidden in the first iteration.
    std::vector<double> walls;
    Kokkos::Timer it_timer;
    sim.newton().on_iterate = [&](Kokkos::View<const double*, MemSpace>) {
      walls.push_back(it_timer.seconds());
      it_timer.reset();
    };
    const int nsteps = steps_for(o, dim, size, solver);
    NewtonStats m;
    double step_s = 0;
    std::vector<double> per_step_iterations;
    const double cpu0 = cpu_seconds();
    Kokkos::Timer run_timer;
    StepReport last;
    for (int s = 0; s < nsteps; ++s) {
      it_timer.reset();
      last = sim.step();
      const NewtonStats& n = last.newton;
      m.iterations += n.iterations;
      m.linear_iterations += n.linear_iterations;
      m.assembly_s += n.assembly_s;
      m.solve_s += n.solve_s;
      m.line_search_s += n.line_search_s;
      m.min_step = std::min(m.min_step, n.min_step);
      step_s += last.step_s;
      per_step_iterations.push_back(n.iterations);
    }
    const double run_wall = run_timer.seconds();
    const double cpu = cpu_seconds() - cpu0;
    sim.newton().on_iterate = nullptr;

    // The first iteration of the run carries the one-time costs: the direct
    // solvers' symbolic factorisation (Amesos2 does it in the first solve)
    // and first touch of the factor's memory. Estimated as the excess of
    // iteration 1's wall time over iteration 2's (both have a line search
    // when step 1 takes >= 3 iterations) and, for the direct solvers,
    // removed from the per-iteration solve time.
    const double first_extra = walls.size() >= 2 ? std::max(0.0, walls[0] - walls[1]) : 0.0;
    const double it = std::max(1, m.iterations);
    const double solve_steady = direct ? std::max(0.0, m.solve_s - first_extra) : m.solve_s;
    j.num("setup_s", setup_s)
        .num("graph_build_s", sim.newton().last_graph_build_s())
        .num("first_iteration_extra_s", first_extra)
        .num("setup_total_s", setup_s + (direct ? first_extra : 0.0))
        .num("mesh_s", mesh_s)
        .integer("steps", nsteps)
        .integer("iterations", m.iterations)
        .raw("iterations_per_step", jlist(per_step_iterations))
        .num("linear_iterations_per_newton", m.linear_iterations / it)
        .num("assembly_s", m.assembly_s / it)
        .num("solve_s", solve_steady / it)
        .num("line_search_s", m.line_search_s / it)
        .num("iteration_s", (m.assembly_s + solve_steady + m.line_search_s) / it)
        .num("min_step", m.min_step)
        .num("step_s", step_s / nsteps)
        .num("min_J", last.min_J)
        .raw("raw_totals", Json()
                               .num("assembly_s", m.assembly_s)
                               .num("solve_s", m.solve_s)
                               .num("line_search_s", m.line_search_s)
                               .integer("linear_iterations", m.linear_iterations)
                               .dump(6))
        .raw("iteration_wall_s", jlist(walls))
        .num("cpu_utilisation", run_wall > 0 ? cpu / (run_wall * threads) : 0.0)
        .raw("loadavg_1min", jlist({load0, loadavg1()}));
    std::cout << std::fixed << std::setprecision(4) << "  " << dim << "D " << size << " "
              << solver << ": " << dofs << " DOFs, " << mesh.num_cells() << " elements, set-up "
              << setup_s << " s (+" << first_extra << " s in iteration 1), " << m.iterations
              << " Newton its in " << nsteps << " step(s); per iteration: assembly "
              << m.assembly_s / it << " s, solve " << solve_steady / it << " s ("
              << m.linear_iterations / it << " lin its), line search " << m.line_search_s / it
              << " s; cpu use " << (run_wall > 0 ? cpu / (run_wall * threads) : 0.0) << "\n"
              << std::defaultfloat << std::flush;
  } catch (const std::exception& e) {
    j.str("failed", e.what());
    std::cout << "  " << dim << "D " << size << " " << solver << ": FAILED: " << e.what() << "\n"
              << std::flush;
  }
  return j;
}

template <int dim>
void run_dim(const Options& o, const Teuchos::RCP<const Comm>& comm, std::vector<Json>& out) {
  for (const auto& size : o.sizes) {
    ShapeSpec spec;
    spec.kind = dim == 2 ? "rectangle" : "box";
    spec.center = std::vector<double>(dim, 0.5);
    spec.size = std::vector<double>(dim, 1.0);
    spec.element_size = element_size(dim, size);
    Kokkos::Timer timer;
    const MeshData mesh = mesh_shape(spec, dim);
    const double mesh_s = timer.seconds();
    if (o.mesh_only) {
      std::cout << "  " << dim << "D " << size << ": h = " << spec.element_size << ", "
                << mesh.num_nodes() << " nodes, " << mesh.num_nodes() * dim << " DOFs, "
                << mesh.num_cells() << " elements (" << mesh_s << " s)\n" << std::flush;
      continue;
    }
    for (const auto& solver : o.solvers) out.push_back(run_case<dim>(mesh, size, solver, o, mesh_s, comm));
  }
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
    const bool root = comm->getRank() == 0;
    bool only_cg = true;
    for (const auto& s : opts.solvers) only_cg = only_cg && s == "CG";
    if (comm->getSize() > 1 && !only_cg) {
      if (root) std::cerr << "bench_newton: on " << comm->getSize() << " MPI ranks only --solvers CG runs "
                          << "(the direct solvers are 1-rank tools)\n";
      code = 2;
    } else {
      // On several ranks the FEM elements are cut into the ranks (Simulation's
      // MPI path); rank 0 prints and writes the JSON.
      if (!root) std::cout.setstate(std::ios::failbit);
      const int threads = Kokkos::DefaultExecutionSpace::concurrency();
      std::cout << "bench_newton: Kokkos " << Kokkos::DefaultExecutionSpace::name() << ", "
                << threads << " thread(s), " << comm->getSize() << " MPI rank(s)\n"
                << std::flush;
      std::vector<Json> results;
      for (int d : opts.dims) {
        if (d == 2) run_dim<2>(opts, comm, results);
        else run_dim<3>(opts, comm, results);
      }
      Json top;
      std::string arr = "[\n";
      for (std::size_t i = 0; i < results.size(); ++i)
        arr += "    " + results[i].dump(4) + (i + 1 < results.size() ? ",\n" : "\n");
      arr += "  ]";
      const char* obt = std::getenv("OPENBLAS_NUM_THREADS");
      top.str("benchmark", "newton_iteration")
          .integer("threads", threads)
          .integer("mpi_ranks", comm->getSize())
          .str("kokkos_backend", Kokkos::DefaultExecutionSpace::name())
          .str("openblas_num_threads", obt ? obt : "")
          .raw("scene", Json()
                            .str("shape", "unit square (2D, plane strain) / unit cube (3D), "
                                          "simplex mesh from Gmsh")
                            .str("material", "neo-Hookean, E = 1e6 Pa, nu = 0.3, density 1000 kg/m^3")
                            .str("boundary", "node set 'bottom' (y = 0) fixed")
                            .num("gravity_y", -9.81)
                            .str("integrator", "backward Euler")
                            .num("dt", opts.dt)
                            .num("newton_eps_d", NewtonParams{}.eps_d)
                            .raw("initial_velocity", jlist({opts.v0[0], opts.v0[1], opts.v0[2]}))
                            .str("steps", opts.steps > 0 ? std::to_string(opts.steps)
                                                         : "small 3, medium 2, large 1; KLU2 on 3D medium 1")
                            .dump(2))
          .str("cg_preconditioner", prec_description(opts.cg_prec))
          .raw("results", arr);
      if (!root) {
        // rank 0 writes
      } else if (std::ofstream f(opts.out); !(f << top.dump(0) << "\n")) {
        std::cerr << "bench_newton: cannot write " << opts.out << "\n";
        code = 1;
      } else {
        std::cout << "bench_newton: wrote " << opts.out << "\n";
      }
      for (const auto& r : results)
        for (const auto& kv : r.kv)
          if (kv.first == "failed") code = 3;
    }
  }
  MPI_Finalize();
  return code;
}
