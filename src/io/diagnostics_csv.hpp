#pragma once
// Per-step diagnostics as a CSV file (one header line, one row per call),
// flushed after every row so that a crashed run keeps everything written.
#include <cstdio>
#include <set>
#include <string>
#include <vector>

namespace bfemp {

class DiagnosticsCsv {
 public:
  // Creates/truncates `path` and writes the header line `columns` joined by
  // ','. Values of the columns named in `integer_columns` are printed without
  // decimals when integral ("12", not "12.0"); everything else with %.17g.
  // Throws std::invalid_argument for no columns, an empty/repeated name, a
  // name containing ',', '"' or a line break, or an integer column that is not
  // in `columns`; std::runtime_error if the file cannot be written.
  DiagnosticsCsv(const std::string& path, std::vector<std::string> columns,
                 const std::set<std::string>& integer_columns = {});
  // Restart: continues an existing file whose header must equal `columns`,
  // or list only columns that `columns` has (a file of an older version: its
  // rows are rewritten in `columns`' order, "nan" in the added columns);
  // rows whose first column (the step) exceeds `keep_through_step` are dropped
  // first (the file is rewritten atomically), then rows are appended. Throws
  // std::runtime_error naming the file when it is missing or its header has a
  // column `columns` lacks.
  DiagnosticsCsv(const std::string& path, std::vector<std::string> columns,
                 const std::set<std::string>& integer_columns, long keep_through_step);
  ~DiagnosticsCsv();
  DiagnosticsCsv(const DiagnosticsCsv&) = delete;
  DiagnosticsCsv& operator=(const DiagnosticsCsv&) = delete;

  // One row in column order; throws std::invalid_argument when
  // values.size() != columns().size() (naming both counts).
  void write_row(const std::vector<double>& values);

  const std::vector<std::string>& columns() const { return columns_; }
  const std::string& path() const { return path_; }

 private:
  void put(const std::string& text);  // write + flush, throws on error
  void check_columns(const std::set<std::string>& integer_columns);

  std::string path_;
  std::vector<std::string> columns_;
  std::vector<bool> integer_;  // per column
  std::FILE* file_ = nullptr;
};

}  // namespace bfemp
