// The bfemp executable gives the same result after 10 steps with 1 and 2
// OpenMP threads (1e-10 relative) and with Cholmod, KLU2 and CG (to the
// solver tolerance). Runs the real executable; compares the HDF5 output.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "io/hdf5_frames.hpp"

namespace {

const std::string exe = std::string(BFEMP_BINARY_DIR) + "/drivers/bfemp";
const std::string scene = std::string(BFEMP_SOURCE_DIR) + "/tests/data/squash_10_steps.yaml";

std::vector<double> run(const std::string& tag, const std::string& env, const std::string& sets,
                        const std::string& scene_file = scene,
                        const std::string& dataset = "/frame_000001/positions") {
  const std::string dir = std::string(BFEMP_BINARY_DIR) + "/test_runs/equivalence_" + tag;
  std::filesystem::remove_all(dir);
  const std::string cmd = env + " OMP_PROC_BIND=false OPENBLAS_NUM_THREADS=1 " + exe + " run " + scene_file +
                          " --output " + dir + " " + sets + " > " + dir + ".log 2>&1";
  std::filesystem::create_directories(std::string(BFEMP_BINARY_DIR) + "/test_runs");
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::vector<std::size_t> shape;
  return bfemp::read_dataset(dir + "/bfemp.h5", dataset, &shape);
}

double rel_diff(const std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& x0) {
  EXPECT_EQ(a.size(), b.size());
  double num = 0, den = 0;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
    num = std::max(num, std::abs(a[i] - b[i]));
    den = std::max(den, std::abs(a[i] - x0[i]));  // displacement scale
  }
  return num / den;
}

}  // namespace

TEST(RunEquivalence, ThreadsAndLinearSolversAgree) {
  std::vector<std::size_t> shape;
  const auto t1 = run("omp1", "OMP_NUM_THREADS=1", "");
  const auto t2 = run("omp2", "OMP_NUM_THREADS=2", "");
  const auto klu = run("klu2", "OMP_NUM_THREADS=2", "--set 'Linear Solver/type=KLU2'");
  const auto cg = run("cg", "OMP_NUM_THREADS=2", "--set 'Linear Solver/type=CG'");
  const auto x0 = bfemp::read_dataset(std::string(BFEMP_BINARY_DIR) + "/test_runs/equivalence_omp1/bfemp.h5",
                                      "/frame_000000/positions", &shape);
  EXPECT_LT(rel_diff(t1, t2, x0), 1e-10) << "1 vs 2 threads";
  // Newton stops at |p|_inf/dt < eps_d = 1e-9 m/s (dt 0.01): positions agree
  // to ~1e-11 m against a displacement of ~0.1 m, whatever the linear solver.
  EXPECT_LT(rel_diff(t2, klu, x0), 1e-8) << "Cholmod vs KLU2";
  EXPECT_LT(rel_diff(t2, cg, x0), 1e-8) << "Cholmod vs CG";
  std::cout << "relative differences: threads " << rel_diff(t1, t2, x0) << ", KLU2 " << rel_diff(t2, klu, x0)
            << ", CG " << rel_diff(t2, cg, x0) << "\n";
}

TEST(RunEquivalence, MpmColumnSameWithOneAndTwoThreads) {
  const std::string col = std::string(BFEMP_SOURCE_DIR) + "/inputs/mpm_column.yaml";
  const std::string sets = "--set 'Time/end time=0.2' --set 'Output/frame every=10'";
  const auto t1 = run("mpm_omp1", "OMP_NUM_THREADS=1", sets, col, "/frame_000001/particle_positions");
  const auto t2 = run("mpm_omp2", "OMP_NUM_THREADS=2", sets, col, "/frame_000001/particle_positions");
  std::vector<std::size_t> shape;
  const auto x0 = bfemp::read_dataset(std::string(BFEMP_BINARY_DIR) + "/test_runs/equivalence_mpm_omp1/bfemp.h5",
                                      "/frame_000000/particle_positions", &shape);
  EXPECT_LT(rel_diff(t1, t2, x0), 1e-10) << "1 vs 2 threads";
  std::cout << "MPM column, 1 vs 2 threads: relative difference " << rel_diff(t1, t2, x0) << "\n";
}
