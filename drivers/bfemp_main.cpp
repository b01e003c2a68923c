// The bfemp command line:  bfemp run SCENE [--set key=value ...] [--output DIR]
#include <CLI/CLI.hpp>
#include <Kokkos_Core.hpp>
#include <Tpetra_Core.hpp>
#include <cstdlib>
#include <iostream>
#include <mpi.h>

#include "io/scene.hpp"
#include "sim/run.hpp"
#include "solver/solver_error.hpp"

int main(int argc, char** argv) {
  CLI::App app{"bfemp: implicit FEM/MPM elastodynamics with barrier contact"};
  app.require_subcommand(1);
  std::string scene_path, output = "out";
  std::vector<std::string> sets;
  auto* run = app.add_subcommand("run", "run a scene to its end time");
  run->add_option("scene", scene_path, "scene file (YAML)")->required();
  run->add_option("--set", sets, "override a scene key: path/to/key=value (repeatable)");
  run->add_option("--output,-o", output, "output directory (default: out)");
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
      const bfemp::Scene scene = bfemp::load_scene(scene_path, sets);
      if (root) log << bfemp::scene_summary(scene);
      bfemp::run_scene(scene, output, comm, log);
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
