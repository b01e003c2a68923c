// bfemp sweep (src/sweep) on short real runs of the slope scene
// (inputs/contact_slope.yaml, a few steps each):
//  - the grid is the product of the --vary lists, the first slowest; keys
//    joined by '&' vary together;
//  - each row holds its run's steps and Newton iterations (equal to the sums
//    of the run's own diagnostics.csv) and the probe value read from it; the
//    error is against the given reference;
//  - a run that fails (Newton capped at 1 iteration) becomes a row with the
//    solver's message naming the step, and the sweep goes on;
//  - a bad key or probe stops the sweep before any run, naming it;
//  - sweep.csv and sweep.json have one row per run; Pareto marks the
//    non-dominated rows.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/fem_fixtures.hpp"
#include "probes/probes.hpp"
#include "sweep/sweep.hpp"

using namespace bfemp;

namespace {

const std::string kScene = std::string(BFEMP_SOURCE_DIR) + "/inputs/contact_slope.yaml";

std::string temp_dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(d);
  return d.string();
}

std::size_t lines_of(const std::string& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string l; std::getline(in, l);) n += !l.empty();
  return n;
}

}  // namespace

TEST(Sweep, GridOfRealRunsWithAFailedRowAndTheErrorAgainstAReference) {
  SweepOptions opt;
  opt.scene = kScene;
  opt.out = temp_dir("bfemp_test_sweep");
  opt.sets = {"Output/frame every=1000"};
  // 3 and 5 steps; the second axis: Newton capped at 1 iteration (fails at step 1) or not.
  opt.vary = {"Time/end time=0.003,0.005", "Newton/max iterations&Newton/eps_d=1&1.0e-8,300&1.0e-8"};
  opt.probes = {"com:body=box,axis=x", "sum:column=newton_iters"};
  opt.has_reference = true;
  opt.reference = 0.05125;
  std::ostringstream log;
  const auto rows = run_sweep(opt, fixtures::comm(), log);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].assignments,
            (std::vector<std::string>{"Time/end time=0.003", "Newton/max iterations=1", "Newton/eps_d=1.0e-8"}));
  EXPECT_EQ(rows[3].label, "Time/end time=0.005; Newton/max iterations=300; Newton/eps_d=1.0e-8");
  for (int i : {0, 2}) {
    EXPECT_FALSE(rows[i].ok) << rows[i].label;
    EXPECT_NE(rows[i].message.find("step 1"), std::string::npos) << rows[i].message;
    EXPECT_TRUE(std::isnan(rows[i].error));
    EXPECT_FALSE(rows[i].pareto);
  }
  for (int i : {1, 3}) {
    ASSERT_TRUE(rows[i].ok) << rows[i].message;
    EXPECT_EQ(rows[i].steps, i == 1 ? 3 : 5);
    // The probe read the run's own diagnostics.csv.
    char name[16];
    std::snprintf(name, sizeof name, "run_%03d", i);
    const RunTable t = RunTable::read_csv(opt.out + "/" + name);
    EXPECT_EQ(static_cast<long>(t.rows()), rows[i].steps);
    EXPECT_EQ(rows[i].values[1], static_cast<double>(rows[i].newton_iterations));
    EXPECT_EQ(rows[i].values[0], probe::com(t, "box", 0, 1e9));
    EXPECT_DOUBLE_EQ(rows[i].error, std::abs(rows[i].values[0] - 0.05125));
    EXPECT_GT(rows[i].wall_s, 0.0);
  }
  // The box slides along +x: the longer run is further from its start (the reference).
  EXPECT_GT(rows[3].error, rows[1].error);
  // Both successful rows are on the front: one faster, one more accurate.
  EXPECT_TRUE(rows[1].pareto);
  EXPECT_EQ(rows[3].pareto, rows[3].wall_s < rows[1].wall_s);
  EXPECT_EQ(lines_of(opt.out + "/sweep.csv"), 5u);
  EXPECT_TRUE(std::filesystem::exists(opt.out + "/sweep.json"));
  EXPECT_NE(log.str().find("FAILED"), std::string::npos) << log.str();
  std::filesystem::remove_all(opt.out);
}

TEST(Sweep, BadKeyOrProbeStopsBeforeAnyRun) {
  auto refused = [](SweepOptions opt) {
    opt.out = temp_dir("bfemp_test_sweep_bad");
    std::ostringstream log;
    try {
      run_sweep(opt, fixtures::comm(), log);
    } catch (const std::invalid_argument& e) {
      EXPECT_FALSE(std::filesystem::exists(opt.out + "/run_000")) << "a run started";
      return std::string(e.what());
    }
    return std::string("(not refused)");
  };
  SweepOptions opt;
  opt.scene = kScene;
  opt.probes = {"com:body=box"};
  opt.vary = {"Time/dt=1.0e-3,-1.0"};
  EXPECT_NE(refused(opt).find("Time/dt"), std::string::npos) << refused(opt);
  opt.vary = {"Time/dtt=1.0e-3"};
  EXPECT_NE(refused(opt).find("dtt"), std::string::npos) << refused(opt);
  opt.vary = {"Time/dt=1.0e-3"};
  opt.probes = {"com:bod=box"};
  EXPECT_NE(refused(opt).find("bod"), std::string::npos) << refused(opt);
  opt.probes = {"com:body=box"};
  opt.vary = {"Time/dt&Time/end time=1.0e-3"};
  EXPECT_NE(refused(opt).find("2 keys"), std::string::npos) << refused(opt);
  opt.vary = {"Time/dt"};
  EXPECT_NE(refused(opt).find("KEY=v1,v2"), std::string::npos) << refused(opt);
}

TEST(Sweep, ParetoFrontKeepsOnlyNonDominatedRows) {
  std::vector<SweepRow> rows(4);
  const double wall[] = {1, 2, 3, 4}, err[] = {0.5, 0.6, 0.1, 0.1};
  for (int i = 0; i < 4; ++i) rows[i].ok = true, rows[i].wall_s = wall[i], rows[i].error = err[i];
  mark_pareto(rows);
  EXPECT_TRUE(rows[0].pareto);
  EXPECT_FALSE(rows[1].pareto) << "slower and less accurate than row 0";
  EXPECT_TRUE(rows[2].pareto);
  EXPECT_FALSE(rows[3].pareto) << "as accurate as row 2 but slower";
}
