#include "probes/run_table.hpp"

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "io/run_output.hpp"

namespace bfemp {

RunTable::RunTable(std::vector<std::string> columns) : names_(std::move(columns)) {
  for (std::size_t i = 0; i < names_.size(); ++i) {
    if (!index_.emplace(names_[i], i).second)
      throw std::invalid_argument("run table: column '" + names_[i] + "' repeated");
  }
  data_.resize(names_.size());
}

RunTable RunTable::for_bodies(const std::vector<std::string>& bodies) {
  return RunTable(diagnostics_columns(bodies));
}

void RunTable::record(const StepReport& r) { add_row(diagnostics_row(r)); }

void RunTable::add_row(const std::vector<double>& row) {
  if (row.size() != names_.size())
    throw std::invalid_argument("run table: a row of " + std::to_string(row.size()) + " values for " +
                                std::to_string(names_.size()) + " columns");
  for (std::size_t i = 0; i < row.size(); ++i) data_[i].push_back(row[i]);
  ++rows_;
}

RunTable RunTable::read_csv(const std::string& path_in) {
  std::string path = path_in;
  if (std::filesystem::is_directory(path)) path += "/diagnostics.csv";
  const std::string dir = std::filesystem::path(path).parent_path().string();
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("run table: '" + path + "' cannot be read (expected a diagnostics.csv)");
  std::string line;
  if (!std::getline(in, line) || line.empty())
    throw std::invalid_argument("run table: '" + path + "' has no header line");
  std::vector<std::string> names;
  {
    std::stringstream ss(line);
    std::string name;
    while (std::getline(ss, name, ',')) names.push_back(name);
  }
  RunTable t(names);
  std::vector<std::string> lines;
  while (std::getline(in, line))
    if (!line.empty()) lines.push_back(line);
  for (std::size_t l = 0; l < lines.size(); ++l) {
    std::vector<double> row;
    const char* s = lines[l].c_str();
    bool ok = true;
    while (true) {
      char* end = nullptr;
      errno = 0;
      const double v = std::strtod(s, &end);
      if (end == s) {
        ok = false;
        break;
      }
      row.push_back(v);
      if (*end == ',') {
        s = end + 1;
      } else {
        ok = *end == '\0';
        break;
      }
    }
    if (ok && row.size() == names.size()) {
      t.add_row(row);
    } else if (l + 1 < lines.size()) {
      throw std::invalid_argument("run table: '" + path + "' line " + std::to_string(l + 2) + " has " +
                                  std::to_string(row.size()) + " numbers, expected " +
                                  std::to_string(names.size()) + " (one per column)");
    }  // else: a torn last row of a run still writing or killed
  }
  t.set_source_dir(dir.empty() ? "." : dir);
  return t;
}

const std::vector<double>& RunTable::column(const std::string& name) const {
  const auto it = index_.find(name);
  if (it == index_.end()) {
    std::string list;
    for (const auto& n : names_) list += (list.empty() ? "" : ", ") + n;
    throw std::invalid_argument("run table: no column '" + name + "' (columns: " + list + ")");
  }
  return data_[it->second];
}

std::vector<std::string> RunTable::bodies() const {
  std::vector<std::string> out;
  const std::string suffix = ".com_x";
  for (const auto& n : names_)
    if (n.size() > suffix.size() && n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0)
      out.push_back(n.substr(0, n.size() - suffix.size()));
  return out;
}

}  // namespace bfemp
