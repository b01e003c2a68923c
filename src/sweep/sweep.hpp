#pragma once
// `bfemp sweep`: the speed-accuracy trade of one scene, measured. The grid of
// runs is the Cartesian product of the --vary lists (KEY=v1,v2,...), each a
// real run (run_scene, one Simulation each, into OUT/run_NNN/) with the
// --set overrides applied first. Per run: wall time, steps, Newton and linear
// iterations, assembly and linear-solve time, the probes' values (probes.hpp)
// read from the run's diagnostics.csv, and the first probe's error against the
// reference: a given value, the value of an extra reference run (the scene
// with --reference-run overrides), or else the last run of the grid (list
// values coarse to fine). A run that fails (Newton cap, solver failure, bad
// value) becomes a row with its message; the sweep goes on.
//
// Writes OUT/sweep.csv, OUT/sweep.json and, when a Python with matplotlib is
// found, OUT/sweep.png (error against wall time, the Pareto front drawn).
// Every combination is loaded (and checked) before the first run, so a bad
// key or value stops the sweep before any run, naming it.
#include <iosfwd>
#include <string>
#include <vector>

#include "solver/tpetra_types.hpp"

namespace bfemp {

struct SweepOptions {
  std::string scene;                      // scene file
  std::vector<std::string> vary;          // "KEY=v1,v2,..."
  std::vector<std::string> sets;          // "KEY=v", applied to every run
  std::vector<std::string> probes;        // probe specs; the first gives the error
  bool has_reference = false;
  double reference = 0;                   // --reference VALUE
  std::vector<std::string> reference_run; // --reference-run KEY=v (repeatable)
  std::string out = "sweep";
  std::string plot_script;                // scripts/plot_sweep.py ("" : no plot)
};

struct SweepRow {
  std::string label;                     // "KEY=v; KEY2=w"
  std::vector<std::string> assignments;  // the --vary values of this run
  bool ok = false;
  std::string message;                   // failure text
  double wall_s = 0, assembly_s = 0, solve_s = 0;
  long steps = 0, newton_iterations = 0, linear_iterations = 0;
  std::vector<double> values;  // per probe (NaN when failed)
  double error = 0;            // |value - reference| of the first probe (NaN: none)
  bool pareto = false;         // on the error-wall time front
};

// Parses "KEY=v1,v2,..." into KEY and its values; std::invalid_argument
// naming the text when it has no '=' or no value. Keys that vary together
// are joined by '&', and so are their values in each item:
// "MPM/grid spacing&Contact/dhat=0.5&0.25,0.25&0.0625".
std::pair<std::string, std::vector<std::string>> parse_vary(const std::string& text);
std::vector<std::string> split_amp(const std::string& s);  // "a&b" -> {a, b}

// Runs the sweep; the rows in grid order (the first --vary varies slowest).
std::vector<SweepRow> run_sweep(const SweepOptions& opt, const Teuchos::RCP<const Comm>& comm, std::ostream& log);

// Marks the rows on the Pareto front of (wall_s, error): no other successful
// row is at least as fast and at least as accurate and better in one.
void mark_pareto(std::vector<SweepRow>& rows);

}  // namespace bfemp
