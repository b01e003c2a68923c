// The bfemp command line:
//   bfemp run SCENE [--set key=value ...] [--output DIR]
//   bfemp restart DIR [--set key=value ...] [--output DIR2]
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
#include "sim/interrupt.hpp"
#include "sim/run.hpp"
#include "solver/solver_error.hpp"

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
                      "Linear Solver/*, Contact/friction iterations, Contact/check iterates)");
  restart->add_option("--output,-o", restart_output,
                      "write the continuation into a new directory (default: append to DIR)");
  CLI11_PARSE(app, argc, argv);

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
    if (root)
      log << "bfemp: Kokkos " << Kokkos::DefaultExecutionSpace::name() << ", "
          << Kokkos::DefaultExecutionSpace::concurrency() << " thread(s); MPI ranks "
          << comm->getSize() << "\n";
    try {
      bfemp::RunOptions opt;
      opt.handle_signals = true;
      if (run->parsed()) {
        opt.scene_source = read_text(scene_path);
        opt.overrides = sets;
        const bfemp::Scene scene = bfemp::load_scene(scene_path, sets);
        if (root) log << bfemp::scene_summary(scene);
        bfemp::run_scene(scene, output, comm, log, opt);
      } else {
        const bfemp::Checkpoint ck = bfemp::read_checkpoint(restart_dir + "/checkpoint.h5");
        const bfemp::Scene scene = bfemp::checkpoint_scene(ck, sets);
        opt.scene_source = ck.text("scene_source");
        opt.overrides = bfemp::checkpoint_overrides(ck, sets);
        opt.restart = &ck;
        opt.append = restart_output.empty() || same_dir(restart_output, restart_dir);
        if (root) log << bfemp::scene_summary(scene);
        bfemp::run_scene(scene, opt.append ? restart_dir : restart_output, comm, log, opt);
      }
    } catch (const bfemp::Interrupted& e) {
      std::cerr << "bfemp: stopped by " << e.what() << "\n";
      code = e.exit_code();
    } catch (const std::invalid_argument& e) {
      std::cerr << "bfemp: bad input: " << e.what() << "\n";
      code = 2;
    } catch (const bfemp::SolverError& e) {
      std::cerr << "bfemp: solver failure at " << e.what() << "\n";
      code = 3;
    } catch (const std::exception& e) {
      std::cerr << "bfemp: error: " << e.what() << "\n";
      code = 1;
    }
  }
  MPI_Finalize();
  return code;
}
