#include "io/diagnostics_csv.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <fstream>

#include "io/atomic_file.hpp"
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace bfemp {

namespace {
std::vector<std::string> split_commas(const std::string& line) {
  std::vector<std::string> out(1);
  for (const char c : line) {
    if (c == ',') out.emplace_back();
    else out.back() += c;
  }
  return out;
}
}  // namespace

DiagnosticsCsv::DiagnosticsCsv(const std::string& path, std::vector<std::string> columns,
                               const std::set<std::string>& integer_columns)
    : path_(path), columns_(std::move(columns)) {
  check_columns(integer_columns);
  file_ = std::fopen(path_.c_str(), "w");
  if (!file_)
    throw std::runtime_error("diagnostics file '" + path_ + "': cannot open for writing (" + std::strerror(errno) + ")");
  std::string header;
  for (std::size_t i = 0; i < columns_.size(); ++i) header += (i ? "," : "") + columns_[i];
  put(header + "\n");
}

DiagnosticsCsv::DiagnosticsCsv(const std::string& path, std::vector<std::string> columns,
                               const std::set<std::string>& integer_columns, long keep_through_step)
    : path_(path), columns_(std::move(columns)) {
  check_columns(integer_columns);
  const std::string where = "diagnostics file '" + path_ + "': ";
  std::ifstream in(path_);
  if (!in) throw std::runtime_error(where + "cannot open for appending (missing?)");
  std::string header, line, kept;
  std::getline(in, header);
  std::string want;
  for (std::size_t i = 0; i < columns_.size(); ++i) want += (i ? "," : "") + columns_[i];
  // A file of an older version whose columns are all still here (in any
  // order): its rows are rewritten in this version's columns, "nan" in the
  // new ones. Any other header is refused.
  const std::vector<std::string> had = split_commas(header);
  std::vector<long> from(columns_.size(), -1);  // column i of this version <- old column from[i]
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    const auto it = std::find(had.begin(), had.end(), columns_[i]);
    if (it != had.end()) from[i] = it - had.begin();
  }
  const auto found = static_cast<std::size_t>(std::count_if(from.begin(), from.end(), [](long f) { return f >= 0; }));
  if (header != want && found != had.size()) {
    std::string extra;
    for (const std::string& c : had)
      if (std::find(columns_.begin(), columns_.end(), c) == columns_.end()) extra += (extra.empty() ? "'" : ", '") + c + "'";
    throw std::runtime_error(where + "its column(s) " + extra + " are not in this version's columns ('" + want +
                             "'): it cannot be continued");
  }
  kept = want + "\n";
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    char* end = nullptr;
    const double step = std::strtod(line.c_str(), &end);
    const auto commas = static_cast<std::size_t>(std::count(line.begin(), line.end(), ','));
    if (end == line.c_str() || *end != ',' || commas + 1 != had.size()) break;  // a torn last row
    if (step > static_cast<double>(keep_through_step)) break;
    if (header == want) {
      kept += line + "\n";
      continue;
    }
    const std::vector<std::string> old = split_commas(line);
    for (std::size_t i = 0; i < columns_.size(); ++i) kept += (i ? "," : "") + (from[i] >= 0 ? old[from[i]] : "nan");
    kept += "\n";
  }
  in.close();
  write_file_atomically(path_, kept);
  file_ = std::fopen(path_.c_str(), "a");
  if (!file_) throw std::runtime_error(where + "cannot open for appending (" + std::strerror(errno) + ")");
}

void DiagnosticsCsv::check_columns(const std::set<std::string>& integer_columns) {
  const std::string where = "diagnostics file '" + path_ + "': ";
  if (columns_.empty()) throw std::invalid_argument(where + "no columns, expected at least one");
  std::set<std::string> seen;
  for (const std::string& c : columns_) {
    if (c.empty() || c.find_first_of(",\"\r\n") != std::string::npos)
      throw std::invalid_argument(where + "column name '" + c +
                                  "': expected non-empty, without ',', '\"' or line breaks");
    if (!seen.insert(c).second)
      throw std::invalid_argument(where + "column name '" + c + "' repeated");
  }
  for (const std::string& c : integer_columns)
    if (!seen.count(c))
      throw std::invalid_argument(where + "integer column '" + c + "' is not one of the columns");
  for (const std::string& c : columns_) integer_.push_back(integer_columns.count(c) > 0);
}

DiagnosticsCsv::~DiagnosticsCsv() {
  if (file_) std::fclose(file_);
}

void DiagnosticsCsv::write_row(const std::vector<double>& values) {
  if (values.size() != columns_.size())
    throw std::invalid_argument("diagnostics file '" + path_ + "': row has " +
                                std::to_string(values.size()) + " values, expected " +
                                std::to_string(columns_.size()) + " (one per column)");
  std::string row;
  char buf[40];
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double v = values[i];
    const bool integral = std::isfinite(v) && v == std::floor(v) && std::abs(v) < 1e18;
    if (integer_[i] && integral)
      std::snprintf(buf, sizeof buf, "%lld", static_cast<long long>(v));
    else
      std::snprintf(buf, sizeof buf, "%.17g", v);
    row += (i ? "," : "");
    row += buf;
  }
  put(row + "\n");
}

void DiagnosticsCsv::put(const std::string& text) {
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size() || std::fflush(file_) != 0)
    throw std::runtime_error("diagnostics file '" + path_ + "': write failed (" +
                             std::strerror(errno) + ")");
}

}  // namespace bfemp
