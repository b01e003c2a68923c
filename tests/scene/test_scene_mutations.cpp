// Every key of a small, valid contact scene (an MPM disk next to a
// prescribed FEM wall, a level-set ground, friction) mutated in turn in the
// scene file's text: wrong type, negative, zero, NaN, inf, 1e400, empty
// string, missing, duplicated; plus a few --set cases. Each mutant runs the
// real executable (build/drivers/bfemp) as a child process: it must never
// die of a signal, hang (killed after 60 s) or exit 1; a nonsense value must
// exit 2 with a message naming the key; only the (key, mutation) pairs of the
// table kMayRun below, values the schema documents as fine, may run (exit 0).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "common/child_process.hpp"

namespace {

enum class Kind { Real, Int, Vec, Text, Bool };

struct Leaf {
  std::string path;   // a/b/key
  std::string value;  // as written in the scene
  Kind kind;
};

// The scene, leaf by leaf, in file order. Maps listed in kFlow are written
// {a: 1, b: 2} (so duplicates inside flow maps are tried too).
// Disk: radius 0.1 at (-0.1, 0), its rightmost particles at x = -0.0125,
// moving at 1 m/s; wall: x in [-0.010, 0.090], every node prescribed; they
// start 2.5 mm apart and touch (d < dhat) in step 2, so the two Newmark steps
// run the barrier and friction.
const std::vector<Leaf> kLeaves = {
    {"dimension", "2", Kind::Int},
    {"gravity", "[0.0, -9.81]", Kind::Vec},
    {"Time/dt", "1.0e-3", Kind::Real},
    {"Time/end time", "2.0e-3", Kind::Real},
    {"Time/integrator", "newmark", Kind::Text},
    {"Time/Newmark/alpha", "0.5", Kind::Real},
    {"Time/Newmark/beta", "0.25", Kind::Real},
    {"Time/Newmark/gamma", "0.5", Kind::Real},
    {"Newton/eps_d", "1.0e-4", Kind::Real},
    {"Newton/max iterations", "100", Kind::Int},
    {"Newton/fallback keep", "[0.7, 0.3]", Kind::Vec},
    {"Linear Solver/type", "Cholmod", Kind::Text},
    {"Output/frame every", "1", Kind::Int},
    {"Output/progress every", "1", Kind::Int},
    {"Materials/rubber/model", "neo-hookean", Kind::Text},
    {"Materials/rubber/E", "1.0e6", Kind::Real},
    {"Materials/rubber/nu", "0.3", Kind::Real},
    {"Materials/rubber/density", "1000.0", Kind::Real},
    {"Materials/steel/model", "linear", Kind::Text},
    {"Materials/steel/E", "2.0e9", Kind::Real},
    {"Materials/steel/nu", "0.3", Kind::Real},
    {"Materials/steel/density", "8000.0", Kind::Real},
    {"MPM/grid spacing", "0.05", Kind::Real},
    {"MPM/domain min", "[-0.3, -0.3]", Kind::Vec},
    {"MPM/domain max", "[0.3, 0.3]", Kind::Vec},
    {"MPM/particles per cell", "4", Kind::Int},
    {"MPM/transfer", "APIC", Kind::Text},
    {"MPM/when particles leave", "error", Kind::Text},
    {"MPM Bodies/disk/material", "rubber", Kind::Text},
    {"MPM Bodies/disk/shape", "disk", Kind::Text},
    {"MPM Bodies/disk/center", "[-0.1, 0.0]", Kind::Vec},
    {"MPM Bodies/disk/outer radius", "0.1", Kind::Real},
    {"MPM Bodies/disk/initial velocity", "[1.0, 0.0]", Kind::Vec},
    {"FEM Bodies/wall/material", "steel", Kind::Text},
    {"FEM Bodies/wall/initial velocity", "[0.0, 0.0]", Kind::Vec},
    {"FEM Bodies/wall/Mesh/shape", "rectangle", Kind::Text},
    {"FEM Bodies/wall/Mesh/center", "[0.04, 0.0]", Kind::Vec},
    {"FEM Bodies/wall/Mesh/size", "[0.1, 0.3]", Kind::Vec},
    {"FEM Bodies/wall/Mesh/element size", "0.1", Kind::Real},
    {"FEM Bodies/wall/Boundary Conditions/all/box min", "[-1.0, -1.0]", Kind::Vec},
    {"FEM Bodies/wall/Boundary Conditions/all/box max", "[1.0, 1.0]", Kind::Vec},
    {"FEM Bodies/wall/Boundary Conditions/all/Motion/hold/type", "velocity", Kind::Text},
    {"FEM Bodies/wall/Boundary Conditions/all/Motion/hold/velocity", "[0.0, 0.0]", Kind::Vec},
    {"FEM Bodies/wall/Boundary Conditions/all/Motion/hold/duration", "1.0", Kind::Real},
    {"Level Sets/ground/type", "half-plane", Kind::Text},
    {"Level Sets/ground/point", "[0.0, -0.25]", Kind::Vec},
    {"Level Sets/ground/normal", "[0.0, 1.0]", Kind::Vec},
    {"Level Sets/ground/slip", "false", Kind::Bool},
    {"Level Sets/ground/velocity", "[0.0, 0.0]", Kind::Vec},
    {"Contact/enabled", "true", Kind::Bool},
    {"Contact/dhat", "1.0e-3", Kind::Real},
    {"Contact/kappa", "1.0e5", Kind::Real},
    {"Contact/eps_v", "1.0e-3", Kind::Real},
    {"Contact/friction", "0.1", Kind::Real},
    {"Contact/Friction Pairs/disk : wall", "0.2", Kind::Real},
    {"Contact/friction iterations", "5", Kind::Int},
    {"Contact/friction pass tolerance", "3.0", Kind::Real},
    {"Contact/friction relaxation from", "3", Kind::Int},
    {"Contact/force body", "wall", Kind::Text},
    {"Contact/check iterates", "false", Kind::Bool},
};
const std::set<std::string> kFlow = {"Time/Newmark", "Materials/rubber",
                                     "FEM Bodies/wall/Boundary Conditions/all/Motion/hold",
                                     "Contact/Friction Pairs"};

enum class Mut { WrongType, Negative, Zero, NaN, Inf, Huge, Empty, Missing, Duplicated };
const char* name(Mut m) {
  static const char* n[] = {"wrong type", "negative", "zero", "NaN", "inf", "1e400", "empty string", "missing",
                            "duplicated"};
  return n[static_cast<int>(m)];
}

// The (key, mutation) pairs that may run (exit 0), from the schema's
// documented ranges and defaults; every other mutant must exit 2.
// Keys with a default (README, scene_schema.cpp) may be missing; gravity,
// velocities and level-set points are any finite vectors; nu may be <= 0
// (range (-1, 0.5)); friction and per-pair mu >= 0; 'progress every' 0 means
// none; 'force body' '' means all FEM bodies; a selection box with zero
// corners still selects nodes of the wall (x >= 0 or x <= 0 halves). The
// level set's point moved (negated, zero, missing) puts the disk inside the
// ground's solid: refused.
const std::map<std::string, std::set<Mut>> kMayRun = {
    {"dimension", {Mut::Missing}},
    {"gravity", {Mut::Negative, Mut::Zero, Mut::Missing}},
    {"Time/dt", {Mut::Missing}},           // default 1e-3
    {"Time/end time", {Mut::Missing}},     // default 1e-2: 10 steps
    {"Time/integrator", {Mut::Missing}},   // backward-euler
    {"Time/Newmark/alpha", {Mut::Missing}},
    {"Time/Newmark/beta", {Mut::Missing}},
    {"Time/Newmark/gamma", {Mut::Missing}},
    {"Newton/eps_d", {Mut::Missing}},
    {"Newton/max iterations", {Mut::Missing}},
    {"Newton/fallback keep", {Mut::Missing}},  // [0.7, 0.3]
    {"Linear Solver/type", {Mut::Missing}},  // Cholmod
    {"Output/frame every", {Mut::Missing}},
    {"Output/progress every", {Mut::Zero, Mut::Missing}},
    {"Materials/rubber/model", {Mut::Missing}},
    {"Materials/rubber/E", {Mut::Missing}},
    {"Materials/rubber/nu", {Mut::Negative, Mut::Zero, Mut::Missing}},
    {"Materials/rubber/density", {Mut::Missing}},
    {"Materials/steel/model", {Mut::Missing}},
    {"Materials/steel/E", {Mut::Missing}},
    {"Materials/steel/nu", {Mut::Negative, Mut::Zero, Mut::Missing}},
    {"Materials/steel/density", {Mut::Missing}},
    {"MPM/particles per cell", {Mut::Missing}},
    {"MPM/transfer", {Mut::Missing}},
    {"MPM/when particles leave", {Mut::Missing}},
    {"MPM Bodies/disk/initial velocity", {Mut::Negative, Mut::Zero, Mut::Missing}},
    {"FEM Bodies/wall/initial velocity", {Mut::Negative, Mut::Zero, Mut::Missing}},
    {"FEM Bodies/wall/Mesh/center", {Mut::Negative}},  // [-0.04, -1]: the wall 1 m below the disk
    {"FEM Bodies/wall/Boundary Conditions/all/box min", {Mut::Zero}},
    {"FEM Bodies/wall/Boundary Conditions/all/box max", {Mut::Zero}},
    {"FEM Bodies/wall/Boundary Conditions/all/Motion/hold/type", {Mut::Missing}},  // fixed
    {"FEM Bodies/wall/Boundary Conditions/all/Motion/hold/velocity", {Mut::Negative, Mut::Zero}},
    {"FEM Bodies/wall/Boundary Conditions/all/Motion/hold/duration", {Mut::Missing}},
    {"Level Sets/ground/type", {Mut::Missing}},
    {"Level Sets/ground/slip", {Mut::Missing}},
    {"Level Sets/ground/velocity", {Mut::Negative, Mut::Zero, Mut::Missing}},
    {"Contact/enabled", {Mut::Missing}},
    {"Contact/dhat", {Mut::Missing}},
    {"Contact/kappa", {Mut::Missing}},
    {"Contact/eps_v", {Mut::Missing}},
    {"Contact/friction", {Mut::Zero, Mut::Missing}},
    {"Contact/Friction Pairs/disk : wall", {Mut::Zero, Mut::Missing}},
    {"Contact/friction iterations", {Mut::Missing}},
    {"Contact/friction pass tolerance", {Mut::Missing}},  // 10
    {"Contact/friction relaxation from", {Mut::Zero, Mut::Missing}},  // 0: never relaxed
    {"Contact/force body", {Mut::Empty, Mut::Missing}},
    {"Contact/check iterates", {Mut::Missing}},
};

// Refusals whose message names another key or the body, not the mutated key
// (the mutant is refused for what it does to the scene): substring expected.
const std::map<std::pair<std::string, Mut>, std::string> kNamedOtherwise = {
    // The default shape, box, needs a size.
    {{"MPM Bodies/disk/shape", Mut::Missing}, "MPM Bodies/disk/size"},
    // The disk moves: outside the grid, or onto the wall.
    {{"MPM Bodies/disk/center", Mut::Negative}, "MPM body 'disk': particle at"},
    {{"MPM Bodies/disk/center", Mut::Zero}, "starts inside or on an FEM body"},
    {{"MPM Bodies/disk/center", Mut::Missing}, "starts inside or on an FEM body"},
    // The wall moves onto the disk.
    {{"FEM Bodies/wall/Mesh/center", Mut::Zero}, "starts inside or on an FEM body"},
    {{"FEM Bodies/wall/Mesh/center", Mut::Missing}, "starts inside or on an FEM body"},
    // The ground's solid side covers the disk.
    {{"Level Sets/ground/point", Mut::Negative}, "scene key 'Level Sets/ground'"},
    {{"Level Sets/ground/point", Mut::Zero}, "scene key 'Level Sets/ground'"},
    {{"Level Sets/ground/point", Mut::Missing}, "scene key 'Level Sets/ground'"},
    {{"Level Sets/ground/normal", Mut::Negative}, "scene key 'Level Sets/ground'"},
};

bool may_run(const std::string& path, Mut m) {
  const auto it = kMayRun.find(path);
  return it != kMayRun.end() && it->second.count(m) > 0;
}

// The mutated value text, or "" when the mutation does not apply to the kind
// (numeric mutations of text and boolean keys are wrong types, tried once).
std::string mutated(const Leaf& leaf, Mut m) {
  const bool numeric = leaf.kind == Kind::Real || leaf.kind == Kind::Int || leaf.kind == Kind::Vec;
  auto vec = [](const std::string& component) { return "[" + component + ", " + component + "]"; };  // 2D
  auto negate = [](std::string v) {
    if (v.find_first_not_of("0.e-+") == std::string::npos) return std::string("-1.0");  // zero
    return v[0] == '-' ? v.substr(1) : "-" + v;
  };
  switch (m) {
    case Mut::WrongType:
      return numeric || leaf.kind == Kind::Bool ? "fast" : "[1.0, 2.0]";
    case Mut::Negative:
    case Mut::Zero:
    case Mut::NaN:
    case Mut::Inf:
    case Mut::Huge: {
      if (!numeric) return "";
      const std::string c = m == Mut::Zero ? (leaf.kind == Kind::Int ? "0" : "0.0")
                            : m == Mut::NaN ? ".nan"
                            : m == Mut::Inf ? ".inf"
                                            : "1e400";
      if (m != Mut::Negative) return leaf.kind == Kind::Vec ? vec(c) : c;
      if (leaf.kind != Kind::Vec) return negate(leaf.value);
      std::string out = "[";  // every component negated
      std::string inner = leaf.value.substr(1, leaf.value.size() - 2);
      for (std::size_t a = 0; a <= inner.size();) {
        const std::size_t b = std::min(inner.find(',', a), inner.size());
        std::string comp = inner.substr(a, b - a);
        comp = comp.substr(comp.find_first_not_of(' '));
        out += (a ? ", " : "") + negate(comp);
        a = b + 1;
      }
      return out + "]";
    }
    case Mut::Empty:
      return "''";
    default:
      return leaf.value;
  }
}

// The scene text with leaf `target` changed by `m` (target < 0: unchanged).
std::string scene_text(int target, Mut m) {
  struct Node {
    std::string name;
    std::vector<Node> children;
    std::vector<std::string> values;  // leaf: the value written once, or twice
  };
  Node root;
  for (std::size_t i = 0; i < kLeaves.size(); ++i) {
    const Leaf& leaf = kLeaves[i];
    const bool hit = static_cast<int>(i) == target;
    Node* n = &root;
    std::size_t a = 0;
    while (true) {
      const std::size_t b = leaf.path.find('/', a);
      const std::string part = leaf.path.substr(a, b == std::string::npos ? std::string::npos : b - a);
      Node* child = nullptr;
      for (auto& c : n->children)
        if (c.name == part) child = &c;
      if (!child) {
        n->children.push_back(Node{part, {}, {}});
        child = &n->children.back();
      }
      n = child;
      if (b == std::string::npos) break;
      a = b + 1;
    }
    if (!hit) n->values = {leaf.value};
    else if (m == Mut::Missing) n->values = {};
    else if (m == Mut::Duplicated) n->values = {leaf.value, leaf.value};
    else n->values = {mutated(leaf, m)};
  }
  auto key = [](const std::string& k) { return k.find(':') != std::string::npos ? "'" + k + "'" : k; };
  std::ostringstream out;
  out << "%YAML 1.1\n---\nbfemp:\n";
  std::function<void(const Node&, const std::string&, const std::string&)> emit = [&](const Node& n, const std::string& path, const std::string& indent) {
    for (const auto& c : n.children) {
      const std::string p = path.empty() ? c.name : path + "/" + c.name;
      if (c.children.empty() && c.values.empty() && !kFlow.count(p)) continue;  // a removed leaf
      if (c.children.empty() && !kFlow.count(p)) {
        for (const auto& v : c.values) out << indent << key(c.name) << ": " << v << "\n";
      } else if (kFlow.count(p)) {
        out << indent << key(c.name) << ": {";
        bool first = true;
        for (const auto& g : c.children)
          for (const auto& v : g.values) {
            out << (first ? "" : ", ") << key(g.name) << ": " << v;
            first = false;
          }
        out << "}\n";
      } else {
        out << indent << key(c.name) << ":\n";
        emit(c, p, indent + "  ");
      }
    }
  };
  emit(root, "", "  ");
  out << "...\n";
  return out.str();
}

}  // namespace

namespace {

namespace fs = std::filesystem;
using bfemp::testing::ChildJob;
using bfemp::testing::ChildResult;

const std::string kExe = std::string(BFEMP_BINARY_DIR) + "/drivers/bfemp";

// A mutant and what it must do.
struct Case {
  std::string label;               // for failure messages
  std::string yaml;
  std::vector<std::string> sets;   // --set arguments
  bool may_run = false;
  std::vector<std::string> named;  // substrings of the refusal (one of them)
};

// Child environment: 1 OpenMP thread, no BLAS threads; Open MPI as a
// single-rank singleton without network transports (its start-up otherwise
// dominates a refused run).
const std::vector<std::string> kEnv = {
    "OMP_NUM_THREADS=1", "OMP_PROC_BIND=false", "OMP_WAIT_POLICY=PASSIVE", "OPENBLAS_NUM_THREADS=1",
    "OMPI_MCA_pml=ob1", "OMPI_MCA_btl=self", "OMPI_MCA_ess_singleton_isolated=1", "OMPI_MCA_osc=^ucx"};

std::string refusal_line(const std::string& output) {
  const auto a = output.find("bfemp: bad input:");
  if (a == std::string::npos) return "";
  return output.substr(a, output.find('\n', a) - a);
}

// Runs the cases (3 children at a time: a refused run mostly waits) and
// checks each; returns the total wall time of the children.
double run_cases(const std::vector<Case>& cases, const std::string& tag) {
  const fs::path dir = fs::path(BFEMP_BINARY_DIR) / "scene_mutations" / tag;
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<ChildJob> jobs;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const std::string file = (dir / ("case_" + std::to_string(i) + ".yaml")).string();
    std::ofstream(file) << cases[i].yaml;
    ChildJob job;
    job.argv = {kExe, "run", file, "--output", (dir / ("out_" + std::to_string(i))).string()};
    for (const auto& s : cases[i].sets) {
      job.argv.push_back("--set");
      job.argv.push_back(s);
    }
    // Each child its own temporary directory: concurrent Open MPI
    // singletons otherwise race on one session directory under /tmp.
    const fs::path tmp = dir / ("tmp_" + std::to_string(i));
    fs::create_directories(tmp);
    job.env = kEnv;
    job.env.push_back("TMPDIR=" + tmp.string());
    job.env.push_back("OMPI_MCA_orte_tmpdir_base=" + tmp.string());
    job.output_file = (dir / ("case_" + std::to_string(i) + ".log")).string();
    jobs.push_back(job);
  }
  const std::vector<ChildResult> res = bfemp::testing::run_children(jobs, 3, 60.0);
  double total = 0;
  int ran = 0, refused = 0;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const ChildResult& r = res[i];
    total += r.wall_s;
    const std::string where = c.label + " (" + jobs[i].output_file + ")";
    EXPECT_FALSE(r.timed_out) << where << ": still running after 60 s";
    EXPECT_EQ(r.signal, 0) << where << ": killed by signal " << r.signal << "\n" << r.output;
    EXPECT_NE(r.exit_code, 1) << where << ": exit 1 (an unexpected error)\n" << r.output;
    for (const char* raw : {"Throw number", "Teuchos_", ".cpp:", "ANONYMOUS"})
      EXPECT_EQ(r.output.find(raw), std::string::npos) << where << ": raw library text '" << raw << "'\n" << r.output;
    if (r.exit_code == 0) ++ran;
    if (r.exit_code == 2) ++refused;
    if (c.may_run) {
      EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 2) << where << ": exit " << r.exit_code << "\n" << r.output;
    } else {
      EXPECT_EQ(r.exit_code, 2) << where << ": a nonsense value must be refused\n" << r.output;
    }
    if (std::getenv("BFEMP_MUTATIONS_VERBOSE"))  // every outcome, to read the messages
      std::cout << c.label << " -> exit " << r.exit_code << ": " << refusal_line(r.output) << "\n";
    if (r.exit_code == 2) {
      const std::string line = refusal_line(r.output);
      bool named = false;
      for (const auto& n : c.named) named = named || line.find(n) != std::string::npos;
      EXPECT_TRUE(named) << where << ": the refusal names none of the expected keys (first: '" << c.named.at(0)
                         << "'): " << line;
    }
  }
  std::cout << tag << ": " << cases.size() << " runs, " << ran << " ran, " << refused << " refused, children "
            << total << " s in all\n";
  fs::remove_all(dir);
  return total;
}

bool numeric(Kind k) { return k == Kind::Real || k == Kind::Int || k == Kind::Vec; }

}  // namespace

TEST(SceneMutations, TheSceneRuns) {
  Case c{"the unmutated scene", scene_text(-1, Mut::Missing), {}, true, {"(none)"}};
  const fs::path dir = fs::path(BFEMP_BINARY_DIR) / "scene_mutations" / "valid";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "scene.yaml") << c.yaml;
  ChildJob job{{kExe, "run", (dir / "scene.yaml").string(), "--output", (dir / "out").string()}, kEnv,
               (dir / "log").string()};
  const ChildResult r = bfemp::testing::run_children({job}, 1, 60.0).at(0);
  ASSERT_EQ(r.exit_code, 0) << r.output << "\n" << c.yaml;
  EXPECT_NE(r.output.find("contact: barrier"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("steps               2"), std::string::npos) << r.output;
  // The bodies touch: some step has contact pairs.
  std::ifstream csv(dir / "out" / "diagnostics.csv");
  std::string header, row;
  std::getline(csv, header);
  std::vector<std::string> cols;
  for (std::stringstream h(header); std::getline(h, row, ',');) cols.push_back(row);
  const auto col = std::find(cols.begin(), cols.end(), "contact_pairs") - cols.begin();
  ASSERT_LT(col, static_cast<long>(cols.size())) << header;
  double pairs = 0;
  while (std::getline(csv, row)) {
    std::stringstream r(row);
    std::string cell;
    for (long k = 0; k <= col; ++k) std::getline(r, cell, ',');
    pairs = std::max(pairs, std::stod(cell));
  }
  EXPECT_GT(pairs, 0) << "the disk must reach the wall within the two steps";
}

// The mutants of the leaves in one group of sections (five groups, so ctest
// can run and report them apart; every leaf belongs to exactly one).
int group_of(const std::string& path) {
  for (const auto& [prefix, g] : std::vector<std::pair<std::string, int>>{
           {"Materials/", 1}, {"MPM", 2}, {"FEM Bodies/", 3}, {"Level Sets/", 4}, {"Contact/", 4}})
    if (path.rfind(prefix, 0) == 0) return g;
  return 0;  // dimension, gravity, Time, Newton, Linear Solver, Output
}

void run_file_mutations(int group) {
  std::vector<Case> cases;
  for (std::size_t i = 0; i < kLeaves.size(); ++i) {
    const Leaf& leaf = kLeaves[i];
    if (group_of(leaf.path) != group) continue;
    for (int k = 0; k <= static_cast<int>(Mut::Duplicated); ++k) {
      const Mut m = static_cast<Mut>(k);
      if (!numeric(leaf.kind) && (m == Mut::Negative || m == Mut::Zero || m == Mut::NaN || m == Mut::Inf ||
                                  m == Mut::Huge))
        continue;  // for text and booleans these are the wrong type, tried once
      Case c;
      c.label = "'" + leaf.path + "' " + name(m);
      if (m != Mut::Missing && m != Mut::Duplicated) c.label += " (" + mutated(leaf, m) + ")";
      c.yaml = scene_text(static_cast<int>(i), m);
      c.may_run = may_run(leaf.path, m);
      c.named = {m == Mut::Duplicated ? "key '" + leaf.path + "' appears twice" : leaf.path};
      const auto other = kNamedOtherwise.find({leaf.path, m});
      if (other != kNamedOtherwise.end()) c.named.push_back(other->second);
      cases.push_back(c);
    }
  }
  ASSERT_FALSE(cases.empty());
  run_cases(cases, "file" + std::to_string(group));
}

TEST(SceneMutations, EveryTableEntryNamesALeafAndAMutationThatApplies) {
  std::set<std::string> paths;
  for (const auto& l : kLeaves) paths.insert(l.path);
  for (const auto& [path, muts] : kMayRun) EXPECT_TRUE(paths.count(path)) << path;
  for (const auto& [key, text] : kNamedOtherwise) EXPECT_TRUE(paths.count(key.first)) << key.first;
}

TEST(SceneMutations, FileTopTimeNewtonSolverOutput) { run_file_mutations(0); }
TEST(SceneMutations, FileMaterials) { run_file_mutations(1); }
TEST(SceneMutations, FileMpmGridAndBodies) { run_file_mutations(2); }
TEST(SceneMutations, FileFemBodies) { run_file_mutations(3); }
TEST(SceneMutations, FileLevelSetsAndContact) { run_file_mutations(4); }

TEST(SceneMutations, SetValuesOnTheCommandLine) {
  const std::string yaml = scene_text(-1, Mut::Missing);
  auto set = [&](const std::string& s, bool may_run, const std::string& named) {
    return Case{"--set '" + s + "'", yaml, {s}, may_run, {named}};
  };
  const std::vector<Case> cases = {
      set("Contact/check iterates=true", true, ""),
      set("Contact/check iterates=True", true, ""),
      set("Contact/check iterates=1", true, ""),
      set("gravity=[0.0, -1.0]", true, ""),
      set("gravity={0.0, -1.0}", true, ""),
      set("Contact/kappa=2e5", true, ""),
      set("Contact/check iterates=maybe", false, "--set 'Contact/check iterates' = 'maybe'"),
      set("Newton/max iterations=1.5", false, "--set 'Newton/max iterations' = '1.5'"),
      set("Time/dt=1e-3abc", false, "--set 'Time/dt' = '1e-3abc'"),
      set("Time/dt=nan", false, "--set 'Time/dt' = 'nan'"),
      set("Time/dt=inf", false, "--set 'Time/dt' = 'inf'"),
      set("Time/dt=1e400", false, "--set 'Time/dt' = '1e400'"),
      set("Time/dt=", false, "--set 'Time/dt' = ''"),
      set("Contact/dhat=-1e-3", false, "Contact/dhat"),
      set("gravity=[0.0, -1.0, 0.0]", false, "gravity"),
      set("gravity=[0.0, .inf]", false, "--set 'gravity'"),
      set("MPM/domain max=[-0.1, 0.3]", false, "MPM body 'disk'"),
  };
  run_cases(cases, "set");
}
