// DiagnosticsCsv: header, number formatting, flushing, errors.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "io/diagnostics_csv.hpp"

namespace {

using bfemp::DiagnosticsCsv;

std::string scratch(const std::string& name) {
  const std::string dir = std::string(BFEMP_BINARY_DIR) + "/test_scratch/diagnostics_csv";
  std::filesystem::create_directories(dir);
  return dir + "/" + name;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(DiagnosticsCsv, HeaderAndRowsFlushed) {
  const std::string path = scratch("diag.csv");
  DiagnosticsCsv csv(path, {"step", "time", "energy", "newton_iterations"},
                     {"step", "newton_iterations"});
  EXPECT_EQ(slurp(path), "step,time,energy,newton_iterations\n");
  csv.write_row({0, 0.0, 1.5, 3});
  csv.write_row({1, 0.1, -2.0, 4.5});
  csv.write_row({2, 1.0 / 3.0, 12, std::numeric_limits<double>::quiet_NaN()});
  // Read back while the writer is still open: every row is flushed.
  EXPECT_EQ(slurp(path),
            "step,time,energy,newton_iterations\n"
            "0,0,1.5,3\n"
            "1,0.10000000000000001,-2,4.5\n"
            "2,0.33333333333333331,12,nan\n");
  // %.17g round-trips.
  EXPECT_EQ(std::strtod("0.10000000000000001", nullptr), 0.1);
  EXPECT_EQ(csv.columns().size(), 4u);
}

// Restart: the rows after the checkpoint's step go; a file of an older
// version (fewer columns) is rewritten in the new columns with "nan" in the
// added ones; a file with a column this version lacks is refused.
TEST(DiagnosticsCsv, ResumeKeepsRowsThroughTheStepAndUpgradesOlderColumns) {
  const std::string path = scratch("resume.csv");
  {
    std::ofstream f(path);
    f << "step,time,count\n0,0,5\n1,0.5,6\n2,1,7\n3,1.5,8";  // a torn last row
  }
  {
    DiagnosticsCsv csv(path, {"step", "time", "count"}, {"step", "count"}, 1);
    csv.write_row({2, 1.25, 9});
  }
  EXPECT_EQ(slurp(path), "step,time,count\n0,0,5\n1,0.5,6\n2,1.25,9\n");
  {
    DiagnosticsCsv csv(path, {"step", "time", "added", "count"}, {"step", "count"}, 1);
    csv.write_row({2, 1.25, 3, 9});
  }
  EXPECT_EQ(slurp(path), "step,time,added,count\n0,0,nan,5\n1,0.5,nan,6\n2,1.25,3,9\n");
  try {
    DiagnosticsCsv csv(path, {"step", "time", "count"}, {"step"}, 1);
    ADD_FAILURE() << "a file with a column this version lacks was accepted";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("resume.csv"), std::string::npos) << msg;
    EXPECT_NE(msg.find("column(s) 'added'"), std::string::npos) << msg;
  }
}

TEST(DiagnosticsCsv, IntegerColumnsOnlyWhenIntegral) {
  const std::string path = scratch("ints.csv");
  {
    DiagnosticsCsv csv(path, {"n", "x"}, {"n"});
    csv.write_row({123456789012.0, 123456789012.0});
    csv.write_row({-0.0, 2.0});
    csv.write_row({2.5, 3.0});
  }
  EXPECT_EQ(slurp(path), "n,x\n123456789012,123456789012\n0,2\n2.5,3\n");
}

TEST(DiagnosticsCsv, CountMismatchThrowsNamingCounts) {
  DiagnosticsCsv csv(scratch("mismatch.csv"), {"a", "b", "c"});
  try {
    csv.write_row({1.0, 2.0});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("2 values"), std::string::npos) << msg;
    EXPECT_NE(msg.find("expected 3"), std::string::npos) << msg;
    EXPECT_NE(msg.find("mismatch.csv"), std::string::npos) << msg;
  }
  csv.write_row({1, 2, 3});
  EXPECT_EQ(slurp(scratch("mismatch.csv")), "a,b,c\n1,2,3\n");
}

TEST(DiagnosticsCsv, BadColumnsAndPaths) {
  EXPECT_THROW(DiagnosticsCsv(scratch("e1.csv"), {}), std::invalid_argument);
  EXPECT_THROW(DiagnosticsCsv(scratch("e2.csv"), {"a", "a"}), std::invalid_argument);
  EXPECT_THROW(DiagnosticsCsv(scratch("e3.csv"), {"a,b"}), std::invalid_argument);
  EXPECT_THROW(DiagnosticsCsv(scratch("e4.csv"), {"a"}, {"b"}), std::invalid_argument);
  const std::string bad = scratch("no_such_dir/d.csv");
  try {
    DiagnosticsCsv csv(bad, {"a"});
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'" + bad + "': cannot open"), std::string::npos)
        << e.what();
  }
}

}  // namespace
