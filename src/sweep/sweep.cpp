#include "sweep/sweep.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "io/atomic_file.hpp"
#include "io/scene.hpp"
#include "probes/probes.hpp"
#include "app/run.hpp"
#include "solver/solver_error.hpp"

namespace bfemp {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string csv_quote(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += c == '\n' ? ' ' : c;
  }
  return q + "\"";
}

std::string json_string(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    if (c == '\n') {
      q += "\\n";
      continue;
    }
    q += c;
  }
  return q + "\"";
}

std::string num(double v) {
  if (!std::isfinite(v)) return "";
  std::ostringstream s;
  s << std::setprecision(10) << v;
  return s.str();
}

std::string json_num(double v) { return std::isfinite(v) ? num(v) : "null"; }

struct Outcome {
  bool ok = false;
  std::string message;
  RunSummary summary;
  std::vector<double> values;
  double wall_s = 0;
};

// One real run into dir; probes evaluated on what it wrote (also after a failure).
Outcome run_one(const SweepOptions& opt, const std::vector<std::string>& overrides, const std::string& dir,
                const Teuchos::RCP<const Comm>& comm) {
  Outcome o;
  o.values.assign(opt.probes.size(), kNaN);
  std::filesystem::create_directories(dir);
  std::ofstream log(dir + "/log.txt");
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const Scene scene = load_scene(opt.scene, overrides);
    RunOptions ro;
    ro.overrides = overrides;
    o.summary = run_scene(scene, dir, comm, log, ro);
    o.ok = true;
  } catch (const SolverError& e) {
    o.message = std::string("solver failure at ") + e.what();
  } catch (const std::exception& e) {
    o.message = e.what();
  }
  o.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.ok) log << "sweep: run failed: " << o.message << "\n";
  try {
    const RunTable t = RunTable::read_csv(dir);
    for (std::size_t k = 0; k < opt.probes.size(); ++k) o.values[k] = o.ok ? evaluate_probe(opt.probes[k], t) : kNaN;
  } catch (const std::exception& e) {
    if (o.ok) {
      o.ok = false;
      o.message = std::string("probe: ") + e.what();
    }
  }
  return o;
}

}  // namespace

std::vector<std::string> split_amp(const std::string& s) {
  std::vector<std::string> out;
  std::size_t b = 0;
  for (std::size_t e = s.find('&'); ; e = s.find('&', b)) {
    out.push_back(s.substr(b, e == std::string::npos ? std::string::npos : e - b));
    if (e == std::string::npos) break;
    b = e + 1;
  }
  return out;
}

std::pair<std::string, std::vector<std::string>> parse_vary(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw std::invalid_argument("--vary '" + text + "': expected KEY=v1,v2,... (a scene key path, '=', values)");
  std::pair<std::string, std::vector<std::string>> out{text.substr(0, eq), {}};
  std::stringstream ss(text.substr(eq + 1));
  std::string v;
  while (std::getline(ss, v, ','))
    if (!v.empty()) out.second.push_back(v);
  if (out.second.empty()) throw std::invalid_argument("--vary '" + text + "': no values after '='");
  // Keys varied together: K1&K2=a1&b1,a2&b2 (one value per key in each item).
  const std::size_t nk = split_amp(out.first).size();
  for (const auto& k : split_amp(out.first))
    if (k.empty()) throw std::invalid_argument("--vary '" + text + "': an empty key between '&'");
  for (const auto& v : out.second)
    if (split_amp(v).size() != nk)
      throw std::invalid_argument("--vary '" + text + "': value '" + v + "' has " +
                                  std::to_string(split_amp(v).size()) + " parts for " + std::to_string(nk) +
                                  " keys joined by '&'");
  return out;
}

void mark_pareto(std::vector<SweepRow>& rows) {
  for (auto& r : rows) {
    r.pareto = false;
    if (!r.ok || !std::isfinite(r.error)) continue;
    bool dominated = false;
    for (const auto& o : rows) {
      if (&o == &r || !o.ok || !std::isfinite(o.error)) continue;
      if (o.wall_s <= r.wall_s && o.error <= r.error && (o.wall_s < r.wall_s || o.error < r.error)) {
        dominated = true;
        break;
      }
    }
    r.pareto = !dominated;
  }
}

std::vector<SweepRow> run_sweep(const SweepOptions& opt, const Teuchos::RCP<const Comm>& comm, std::ostream& log) {
  if (opt.probes.empty()) throw std::invalid_argument("sweep: no --probe given (see bfemp sweep --help)");
  if (opt.vary.empty()) throw std::invalid_argument("sweep: no --vary given (KEY=v1,v2,...)");
  std::vector<std::pair<std::string, std::vector<std::string>>> axes;
  for (const auto& v : opt.vary) axes.push_back(parse_vary(v));
  for (const auto& p : opt.probes) (void)check_probe_spec(p);  // names and keys, before any run
  // The grid, first axis slowest; every combination loaded (validated) up front.
  std::vector<std::vector<std::string>> grid(1);
  for (const auto& ax : axes) {
    std::vector<std::vector<std::string>> next;
    const auto keys = split_amp(ax.first);
    for (const auto& g : grid)
      for (const auto& v : ax.second) {
        auto h = g;
        const auto vals = split_amp(v);
        for (std::size_t k = 0; k < keys.size(); ++k) h.push_back(keys[k] + "=" + vals[k]);
        next.push_back(h);
      }
    grid = next;
  }
  auto overrides_of = [&](const std::vector<std::string>& a) {
    std::vector<std::string> o = opt.sets;
    o.insert(o.end(), a.begin(), a.end());
    return o;
  };
  for (const auto& g : grid) {
    try {
      (void)load_scene(opt.scene, overrides_of(g));
    } catch (const std::invalid_argument& e) {
      std::string label;
      for (const auto& a : g) label += (label.empty() ? "" : "; ") + a;
      throw std::invalid_argument("sweep: run [" + label + "]: " + e.what());
    }
  }
  if (!opt.reference_run.empty()) (void)load_scene(opt.scene, overrides_of(opt.reference_run));
  std::filesystem::create_directories(opt.out);

  double reference = opt.reference;
  bool have_ref = opt.has_reference;
  std::string ref_note = have_ref ? "given value" : "";
  if (!have_ref && !opt.reference_run.empty()) {
    std::string label;
    for (const auto& a : opt.reference_run) label += (label.empty() ? "" : "; ") + a;
    log << "sweep: reference run [" << label << "] ..." << std::flush;
    const Outcome o = run_one(opt, overrides_of(opt.reference_run), opt.out + "/reference", comm);
    if (!o.ok) throw std::runtime_error("sweep: the reference run [" + label + "] failed: " + o.message);
    reference = o.values[0];
    have_ref = true;
    ref_note = "reference run [" + label + "]";
    log << " " << o.wall_s << " s, " << opt.probes[0] << " = " << reference << "\n";
  }

  std::vector<SweepRow> rows;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    SweepRow row;
    row.assignments = grid[i];
    for (const auto& a : grid[i]) row.label += (row.label.empty() ? "" : "; ") + a;
    char name[32];
    std::snprintf(name, sizeof name, "run_%03zu", i);
    log << "sweep: run " << i + 1 << "/" << grid.size() << " [" << row.label << "] ..." << std::flush;
    const Outcome o = run_one(opt, overrides_of(grid[i]), opt.out + "/" + name, comm);
    row.ok = o.ok;
    row.message = o.message;
    row.wall_s = o.wall_s;
    row.assembly_s = o.summary.assembly_s;
    row.solve_s = o.summary.solve_s;
    row.steps = o.summary.steps;
    row.newton_iterations = o.summary.newton_iterations;
    row.linear_iterations = o.summary.linear_iterations;
    row.values = o.values;
    if (o.ok)
      log << " " << std::setprecision(4) << o.wall_s << " s, " << o.summary.steps << " steps, "
          << o.summary.newton_iterations << " Newton iterations, " << opt.probes[0] << " = "
          << std::setprecision(8) << o.values[0] << "\n";
    else
      log << " FAILED after " << o.wall_s << " s: " << o.message << "\n";
    rows.push_back(row);
  }
  if (!have_ref) {  // the last run of the grid
    for (std::size_t i = rows.size(); i-- > 0;)
      if (rows[i].ok) {
        reference = rows[i].values[0];
        have_ref = true;
        ref_note = "last run of the grid [" + rows[i].label + "]";
        break;
      }
  }
  for (auto& r : rows) r.error = have_ref && r.ok ? std::abs(r.values[0] - reference) : kNaN;
  mark_pareto(rows);

  // sweep.csv
  std::ostringstream csv;
  csv << "run";
  for (const auto& ax : axes)
    for (const auto& k : split_amp(ax.first)) csv << "," << csv_quote(k);
  csv << ",ok,wall_s,steps,newton_iters,linear_iters,assembly_s,solve_s";
  for (const auto& p : opt.probes) csv << "," << csv_quote(p);
  csv << ",error,pareto,message\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    csv << i;
    for (const auto& a : r.assignments) csv << "," << csv_quote(a.substr(a.find('=') + 1));
    csv << "," << (r.ok ? 1 : 0) << "," << num(r.wall_s) << "," << r.steps << "," << r.newton_iterations << ","
        << r.linear_iterations << "," << num(r.assembly_s) << "," << num(r.solve_s);
    for (double v : r.values) csv << "," << num(v);
    csv << "," << num(r.error) << "," << (r.pareto ? 1 : 0) << "," << csv_quote(r.message) << "\n";
  }
  write_file_atomically(opt.out + "/sweep.csv", csv.str());

  // sweep.json
  std::ostringstream js;
  js << "{\n  \"scene\": " << json_string(opt.scene) << ",\n  \"sets\": [";
  for (std::size_t k = 0; k < opt.sets.size(); ++k) js << (k ? ", " : "") << json_string(opt.sets[k]);
  js << "],\n  \"probes\": [";
  for (std::size_t k = 0; k < opt.probes.size(); ++k) js << (k ? ", " : "") << json_string(opt.probes[k]);
  js << "],\n  \"reference\": " << (have_ref ? json_num(reference) : "null")
     << ",\n  \"reference_source\": " << json_string(ref_note) << ",\n  \"threads\": "
     << json_string(std::getenv("OMP_NUM_THREADS") ? std::getenv("OMP_NUM_THREADS") : "") << ",\n  \"runs\": [\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    js << "    {\"run\": " << i << ", \"label\": " << json_string(r.label) << ", \"ok\": " << (r.ok ? "true" : "false")
       << ", \"wall_s\": " << json_num(r.wall_s) << ", \"steps\": " << r.steps
       << ", \"newton_iters\": " << r.newton_iterations << ", \"linear_iters\": " << r.linear_iterations
       << ", \"assembly_s\": " << json_num(r.assembly_s) << ", \"solve_s\": " << json_num(r.solve_s)
       << ", \"values\": [";
    for (std::size_t k = 0; k < r.values.size(); ++k) js << (k ? ", " : "") << json_num(r.values[k]);
    js << "], \"error\": " << json_num(r.error) << ", \"pareto\": " << (r.pareto ? "true" : "false")
       << ", \"message\": " << json_string(r.message) << "}" << (i + 1 < rows.size() ? "," : "") << "\n";
  }
  js << "  ]\n}\n";
  write_file_atomically(opt.out + "/sweep.json", js.str());

  if (!opt.plot_script.empty() && std::filesystem::exists(opt.plot_script)) {
    // A Python with matplotlib: $BFEMP_PYTHON, else the system one (Debian's
    // python3-matplotlib), else python3 on the PATH.
    std::string py = std::getenv("BFEMP_PYTHON") ? std::getenv("BFEMP_PYTHON") : "";
    if (py.empty()) py = std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
    const std::string cmd = "'" + py + "' '" + opt.plot_script + "' '" + opt.out + "/sweep.json' '" +
                            opt.out + "/sweep.png' > '" + opt.out + "/plot.log' 2>&1";
    const int rc = std::system(cmd.c_str());
    log << "sweep: " << (rc == 0 ? "wrote " + opt.out + "/sweep.png" : "no plot (see " + opt.out + "/plot.log)") << "\n";
  }
  int ok = 0;
  for (const auto& r : rows) ok += r.ok ? 1 : 0;
  log << "sweep: " << ok << "/" << rows.size() << " runs finished; reference " << (have_ref ? num(reference) : "none")
      << " (" << ref_note << "); wrote " << opt.out << "/sweep.csv and sweep.json\n";
  return rows;
}

}  // namespace bfemp
