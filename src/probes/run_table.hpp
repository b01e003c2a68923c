#pragma once
// A run's per-step record as named columns: what diagnostics.csv holds (one
// row per step, the columns of io/run_output.hpp's diagnostics_columns), read
// back from the file or recorded in memory from StepReports while a
// Simulation steps. Probes (probes.hpp) read observables from it, so a test,
// the validation report and `bfemp sweep` measure a run the same way.
//
// Units are those of the columns (SI; 2D energies and forces per unit
// thickness). Missing values (no contact) are NaN.
#include <map>
#include <string>
#include <vector>

namespace bfemp {

struct StepReport;

class RunTable {
 public:
  RunTable() = default;
  explicit RunTable(std::vector<std::string> columns);

  // diagnostics.csv of a run (a file path, or a run directory holding one).
  // Throws std::invalid_argument naming the file when it is missing, has no
  // header, or a row has the wrong number of fields (a torn last row, from a
  // run still writing or killed, is dropped instead).
  static RunTable read_csv(const std::string& path);
  // The columns a run of a simulation with these bodies writes (FEM bodies,
  // then MPM bodies: Simulation::body_names()), with rows added by record().
  static RunTable for_bodies(const std::vector<std::string>& bodies);
  void record(const StepReport& r);  // one row, as diagnostics.csv would get it
  void add_row(const std::vector<double>& row);  // std::invalid_argument on a size mismatch

  std::size_t rows() const { return rows_; }
  const std::vector<std::string>& columns() const { return names_; }
  bool has(const std::string& column) const { return index_.count(column) > 0; }
  // Throws std::invalid_argument naming the column and listing the ones there are.
  const std::vector<double>& column(const std::string& name) const;
  // The body names of "<body>.com_x" columns, in column order.
  std::vector<std::string> bodies() const;
  // The run directory the table was read from ("" when recorded in memory):
  // probes of the frames (bfemp.h5) read there.
  const std::string& source_dir() const { return dir_; }
  void set_source_dir(const std::string& dir) { dir_ = dir; }

 private:
  std::vector<std::string> names_;
  std::map<std::string, std::size_t> index_;
  std::vector<std::vector<double>> data_;  // per column
  std::size_t rows_ = 0;
  std::string dir_;
};

}  // namespace bfemp
