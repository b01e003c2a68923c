// The bfemp command line:
//   bfemp run SCENE [--set key=value ...] [--output DIR]
//   bfemp restart DIR [--set key=value ...] [--output DIR2]
//   bfemp probe DIR SPEC [SPEC ...]       observables of a finished run
//   bfemp sweep SCENE --vary KEY=v1,v2 --probe SPEC [...]   (see --help)
// Exit codes: 0 done, 2 bad input, 3 solver failure, 130 / 143 stopped by
// SIGINT / SIGTERM after writing a checkpoint, 1 anything else.
#include <CLI/CLI.hpp>
#include <Kokkos_Core.hpp>
#include <Tpetra_Core.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mpi.h>
#include <sstream>

#include "io/checkpoint.hpp"
#include "io/scene.hpp"
#include "solver/blas_threads.hpp"
#include "probes/probes.hpp"
#include "app/interrupt.hpp"
#include "app/run.hpp"
#include "solver/solver_error.hpp"
#include "sweep/sweep.hpp"

namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("scene file '" + path + "' cannot be read");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool same_dir(const std::string& a, const std::string& b) {
  std::error_code ec;
  return std::filesystem::equivalent(a, b, ec);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bfemp: implicit FEM/MPM elastodynamics with barrier contact"};
  app.require_subcommand(1);
  std::string scene_path, restart_dir, output = "out", restart_output;
  std::vector<std::string> sets;
  auto* run = app.add_subcommand("run", "run a scene to its end time");
  run->add_option("scene", scene_path, "scene file (YAML)")->required();
  run->add_option("--set", sets, "override a scene key: path/to/key=value (repeatable)");
  run->add_option("--output,-o", output, "output directory (default: out)");
  auto* restart = app.add_subcommand("restart", "continue a run from DIR/checkpoint.h5");
  restart->add_option("dir", restart_dir, "output directory of the run to continue")->required();
  restart->add_option("--set", sets,
                      "change a key that leaves the state alone (Time/end time, Output/*, Newton/*, "
                      "Linear Solver/*, MPM/boxes per axis, Contact/friction iterations, Contact/friction pass tolerance, "
                      "Contact/check iterates, Contact/eps_v)");
  restart->add_option("--output,-o", restart_output,
                      "write the continuation into a new directory (default: append to DIR)");
  std::string probe_dir;
  std::vector<std::string> probe_specs;
  auto* probe = app.add_subcommand("probe", "print observables of a run from its diagnostics.csv");
  probe->add_option("dir", probe_dir, "output directory of a run (or its diagnostics.csv)")->required();
  probe->add_option("specs", probe_specs, "probes: NAME[:key=value,...] (bfemp sweep --help lists them)")
      ->required();
  bfemp::SweepOptions sw;
  std::string probe_help = "probes (NAME:key=value,...):";
  for (const auto& p : bfemp::probe_list())
    probe_help += "\n  " + p.name + (p.args.empty() ? "" : ":" + p.args) + "\n      " + p.help;
  auto* sweep = app.add_subcommand(
      "sweep", "runs a scene over a grid of key values and measures a probe against a reference per run");
  sweep->footer(probe_help);
  sweep->add_option("scene", sw.scene, "scene file (YAML)")->required();
  sweep->add_option("--vary", sw.vary, "KEY=v1,v2,... (repeatable; the grid is their product; K1&K2=a1&b1,a2&b2 varies keys together)")->required();
  sweep->add_option("--set", sw.sets, "override a scene key in every run: path/to/key=value (repeatable)");
  sweep->add_option("--probe", sw.probes, "NAME[:key=value,...] (repeatable; the first gives the error)")
      ->required();
  auto* ref = sweep->add_option("--reference", sw.reference, "the exact value of the first probe");
  sweep->add_option("--reference-run", sw.reference_run,
                    "KEY=v for an extra reference run (repeatable); default reference: the last run")
      ->excludes(ref);
  sweep->add_option("--out,-o", sw.out, "output directory (default: sweep)");
  CLI11_PARSE(app, argc, argv);
  sw.has_reference = ref->count() > 0;
  sw.plot_script = std::string(BFEMP_SOURCE_DIR) + "/scripts/plot_sweep.py";

  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int code = 0;
  {
    Kokkos::InitArguments ka;
    if (const char* s = std::getenv("OMP_NUM_THREADS")) ka.num_threads = std::atoi(s);
    Kokkos::ScopeGuard kokkos(ka);
    Tpetra::ScopeGuard tpetra(&argc, &argv);
    auto comm = Tpetra::getDefaultComm();
    const bool root = comm->getRank() == 0;
    std::ostream& log = std::cout;
    const std::string blas = bfemp::configure_blas_threads();
    if (root && !probe->parsed())
      log << "bfemp: Kokkos " << Kokkos::DefaultExecutionSpace::name() << ", "
          << Kokkos::DefaultExecutionSpace::concurrency() << " thread(s); MPI ranks "
          << comm->getSize() << "; " << blas << "\n";
    try {
      bfemp::RunOptions opt;
      opt.handle_signals = true;
      if (probe->parsed()) {
        const bfemp::RunTable t = bfemp::RunTable::read_csv(probe_dir);
        std::cout.precision(12);
        for (const auto& spec : probe_specs) std::cout << spec << " = " << bfemp::evaluate_probe(spec, t) << "\n";
      } else if (sweep->parsed()) {
        bfemp::run_sweep(sw, comm, log);
      } else if (run->parsed()) {
        opt.scene_source = read_text(scene_path);
        opt.overrides = sets;
        const bfemp::Scene scene = bfemp::load_scene(scene_path, sets);
        if (root) log << bfemp::scene_summary(scene);
        bfemp::run_scene(scene, output, comm, log, opt);
      } else {
        // (each rank its particle rows)
        const bfemp::Checkpoint ck = bfemp::read_restart_checkpoint(restart_dir + "/checkpoint.h5", *comm);
        const bfemp::Scene scene = bfemp::checkpoint_scene(ck, sets);
        opt.scene_source = ck.text("scene_source");
        opt.overrides = bfemp::checkpoint_overrides(ck, sets);
        opt.restart = &ck;
        opt.append = restart_output.empty() || same_dir(restart_output, restart_dir);
        if (root) log << bfemp::scene_summary(scene);
        bfemp::run_scene(scene, opt.append ? restart_dir : restart_output, comm, log, opt);
      }
    } catch (const bfemp::Interrupted& e) {  // (every rank stops at the same step: rank 0 reports)
      if (root) std::cerr << "bfemp: stopped by " << e.what() << "\n";
      code = e.exit_code();
    } catch (const std::invalid_argument& e) {  // the same input on every rank
      if (root) std::cerr << "bfemp: bad input: " << e.what() << "\n";
      code = 2;
    } catch (const bfemp::SolverError& e) {  // global decisions: every rank fails together
      if (root) std::cerr << "bfemp: solver failure at " << e.what() << "\n";
      code = 3;
    } catch (const std::exception& e) {
      std::cerr << "bfemp: error";
      if (comm->getSize() > 1) std::cerr << " on rank " << comm->getRank();
      std::cerr << ": " << e.what() << "\n";
      code = 1;
    }
  }
  MPI_Finalize();
  return code;
}
