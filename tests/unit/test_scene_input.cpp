// Scene input edge cases: --set values typed as the YAML file types them,
// duplicated keys named with their path and lines, parser failures without
// the library's raw text, MPM bodies that start outside the grid or overlap.
#include <gtest/gtest.h>

#include <Teuchos_Array.hpp>

#include "common/fem_fixtures.hpp"
#include "io/scene.hpp"
#include "io/scene_yaml.hpp"

using namespace bfemp;
using Teuchos::Array;

namespace {

// Two MPM boxes and an FEM wall, far apart; contact on.
const std::string kScene = R"(%YAML 1.1
---
# a comment: with a colon
bfemp:
  dimension: 2
  gravity: [0.0, -9.81]
  Time: {dt: 1.0e-3, end time: 2.0e-3}
  Materials:
    soft: {E: 1.0e5, nu: 0.3, density: 1000.0}   # trailing comment
    hard:
      E: 1.0e7
      density: 1000.0
  MPM:
    grid spacing: 0.1
    domain min: [0.0, 0.0]
    domain max: [1.0, 1.0]
  MPM Bodies:
    left: {material: soft, shape: box, center: [0.3, 0.5], size: [0.2, 0.2]}
    right: {material: soft, shape: box, center: [0.7, 0.5], size: [0.2, 0.2]}
  FEM Bodies:
    wall:
      material: hard
      Mesh: {shape: rectangle, center: [2.0, 0.5], size: [0.2, 0.2], element size: 0.1}
  Contact:
    kappa: 1.0e5
    Friction Pairs: {'left : wall': 0.5, 'right:wall': 0.2}
  Linear Solver:
    type: CG
    CG:
      preconditioner: RELAXATION
      Ifpack2: {'relaxation: type': Symmetric Gauss-Seidel}
...
)";

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) s.replace(pos, from.size(), to);
  return s;
}

Scene load(const std::string& yaml, const std::vector<std::string>& sets = {}) {
  return load_scene_from_string(yaml, std::string(BFEMP_SOURCE_DIR) + "/tests/data", sets);
}

// The invalid_argument message of loading and building the scene ("" if none).
std::string error_of(const std::string& yaml, const std::vector<std::string>& sets = {}) {
  try {
    Scene s = load(yaml, sets);
    build_setup<2>(s);
  } catch (const std::invalid_argument& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("OTHER: ") + e.what();
  }
  return "";
}

void expect_message(const std::string& msg, std::initializer_list<const char*> parts) {
  ASSERT_FALSE(msg.empty()) << "the scene was accepted";
  for (const char* p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' missing in: " << msg;
  for (const char* raw : {"Throw number", "Teuchos_", ".cpp:", "ANONYMOUS", "OTHER:"})
    EXPECT_EQ(msg.find(raw), std::string::npos) << "raw library text '" << raw << "' in: " << msg;
}

}  // namespace

TEST(SceneInput, ValidSceneIsAccepted) { EXPECT_EQ(error_of(kScene), ""); }

TEST(SceneInput, SetBooleansAsYamlScalars) {
  for (const char* v : {"true", "True", "TRUE", "yes", "1"})
    EXPECT_TRUE(load(kScene, {std::string("Contact/check iterates=") + v})
                    .params.sublist("Contact").get<bool>("check iterates")) << v;
  for (const char* v : {"false", "False", "no", "0"})
    EXPECT_FALSE(load(kScene, {"Contact/check iterates=true", std::string("Contact/check iterates=") + v})
                     .params.sublist("Contact").get<bool>("check iterates")) << v;
  expect_message(error_of(kScene, {"Contact/check iterates=maybe"}),
                 {"--set 'Contact/check iterates'", "'maybe'", "boolean", "true"});
  expect_message(error_of(kScene, {"Contact/check iterates=2"}), {"Contact/check iterates", "'2'", "boolean"});
}

TEST(SceneInput, SetListsInBracketsAndBraces) {
  const auto g = [](const Scene& s) { return s.params.get<Array<double>>("gravity"); };
  EXPECT_EQ(g(load(kScene, {"gravity=[1000.0, 0.0]"})), Array<double>(std::vector<double>{1000.0, 0.0}));
  EXPECT_EQ(g(load(kScene, {"gravity={1000.0, 0.0}"})), Array<double>(std::vector<double>{1000.0, 0.0}));
  EXPECT_EQ(g(load(kScene, {"gravity=[1, -2]"})), Array<double>(std::vector<double>{1.0, -2.0}));
  EXPECT_TRUE(g(load(kScene, {"gravity=[]"})).empty());
  expect_message(error_of(kScene, {"gravity=[1.0, 0.0, 0.0]"}), {"gravity", "2 components"});
  expect_message(error_of(kScene, {"gravity=[1.0, x]"}), {"--set 'gravity'", "[1.0, x]", "list of real numbers"});
  expect_message(error_of(kScene, {"gravity=[1.0, nan]"}), {"--set 'gravity'", "nan"});
  expect_message(error_of(kScene, {"gravity=[1.0, 0.0"}), {"--set 'gravity'", "[1.0, 0.0", "not a YAML"});
}

TEST(SceneInput, SetNumbersWithTheFileTypeChecks) {
  EXPECT_DOUBLE_EQ(load(kScene, {"Time/dt=1e-3"}).params.sublist("Time").get<double>("dt"), 1e-3);
  EXPECT_DOUBLE_EQ(load(kScene, {"Materials/soft/E=2"}).params.sublist("Materials").sublist("soft").get<double>("E"),
                   2.0);
  EXPECT_EQ(load(kScene, {"Newton/max iterations=30"}).params.sublist("Newton").get<int>("max iterations"), 30);
  EXPECT_EQ(load(kScene, {"Newton/max iterations=1e2"}).params.sublist("Newton").get<int>("max iterations"), 100);
  expect_message(error_of(kScene, {"Newton/max iterations=1.5"}),
                 {"--set 'Newton/max iterations'", "'1.5'", "integer"});
  expect_message(error_of(kScene, {"Time/dt=1e-3abc"}), {"--set 'Time/dt'", "'1e-3abc'", "real number"});
  for (const char* v : {"nan", "NaN", "inf", "-inf", "1e400", ".nan", ""})
    expect_message(error_of(kScene, {std::string("Time/dt=") + v}), {"--set 'Time/dt'", "real number"});
  expect_message(error_of(kScene, {"Time/dt=1e400"}), {"'1e400'", "not a finite number"});
  expect_message(error_of(kScene, {"Time/dt=-1e-3"}), {"Time/dt", "-0.001", "dt > 0"});
  expect_message(error_of(kScene, {"Contact/kappa=0"}), {"Contact/kappa", "0", "positive"});
}

TEST(SceneInput, SetStringsAndFreeFormLists) {
  EXPECT_EQ(load(kScene, {"Contact/force body=wall"}).params.sublist("Contact").get<std::string>("force body"),
            "wall");
  EXPECT_EQ(load(kScene, {"Contact/force body='wall'"}).params.sublist("Contact").get<std::string>("force body"),
            "wall");
  expect_message(error_of(kScene, {"Contact/force body=floor"}), {"Contact/force body", "'floor'", "FEM body"});
  const Scene s = load(kScene, {"Contact/Friction Pairs/left : wall=0.25"});
  EXPECT_DOUBLE_EQ(s.params.sublist("Contact").sublist("Friction Pairs").get<double>("left : wall"), 0.25);
  expect_message(error_of(kScene, {"Contact/Friction Pairs/left : wall=-1.0"}),
                 {"Contact/Friction Pairs/left : wall", "-1", "mu >= 0"});
  expect_message(error_of(kScene, {"Contact/Friction Pairs/left : floor=0.1"}),
                 {"Contact/Friction Pairs/left : floor", "naming bodies"});
}

TEST(SceneInput, SetIntoFreeFormSolverLists) {
  const Scene s = load(kScene, {"Linear Solver/CG/Ifpack2/relaxation: sweeps=2"});
  const auto& ifp = s.params.sublist("Linear Solver").sublist("CG").sublist("Ifpack2");
  EXPECT_EQ(ifp.get<int>("relaxation: sweeps"), 2);
  EXPECT_EQ(ifp.get<std::string>("relaxation: type"), "Symmetric Gauss-Seidel");
}

TEST(SceneInput, SetOfASublistOrUnknownKeyIsNamed) {
  expect_message(error_of(kScene, {"Time=5"}), {"--set 'Time'", "is a sublist", "Time/<key>=value"});
  expect_message(error_of(kScene, {"Time/dtt=5"}), {"--set 'Time/dtt'", "unknown key 'dtt'", "'dt'"});
  expect_message(error_of(kScene, {"MPM Bodies/ghost/center=[0.0, 0.0]"}), {"no entry 'ghost'", "MPM Bodies"});
  expect_message(error_of(kScene, {"Time/dt"}), {"--set 'Time/dt'", "path/to/key=value"});
}

TEST(SceneInput, TopLevelKeyIsNamed) {
  expect_message(error_of("simulation:\n  dimension: 2\n"), {"scene: top-level key 'simulation'", "'bfemp'"});
}

TEST(SceneInput, DuplicateBlockKeyNamesPathAndLines) {
  const std::string yaml = replaced(kScene, "    kappa: 1.0e5\n", "    kappa: 1.0e5\n    dhat: 1.0e-3\n    kappa: 2.0e5\n");
  // kScene's 'kappa' is on line 25.
  expect_message(error_of(yaml), {"scene line 27", "key 'Contact/kappa' appears twice", "first at line 25"});
  const std::string top = replaced(kScene, "  dimension: 2\n", "  dimension: 2\n  dimension: 3\n");
  expect_message(error_of(top), {"line 6", "key 'dimension'", "line 5"});
  const std::string body = replaced(kScene, "      density: 1000.0\n  MPM:", "      density: 1000.0\n      E: 3.0\n  MPM:");
  expect_message(error_of(body), {"key 'Materials/hard/E' appears twice", "first at line 11"});
}

TEST(SceneInput, DuplicateFlowKeyNamesPathAndLine) {
  expect_message(error_of(replaced(kScene, "{E: 1.0e5, nu: 0.3,", "{E: 1.0e5, nu: 0.3, E: 2.0,")),
                 {"line 9", "key 'Materials/soft/E' appears twice"});
  expect_message(error_of(replaced(kScene, "'right:wall': 0.2", "'right:wall': 0.2, 'left : wall': 0.1")),
                 {"key 'Contact/Friction Pairs/left : wall' appears twice"});
  // The same name in different maps, flow or block, is no duplicate.
  EXPECT_EQ(error_of(replaced(kScene, "size: [0.2, 0.2]}\n    right", "size: [0.2, 0.2]}\n    right")), "");
}

TEST(SceneInput, DuplicateScanIgnoresCommentsQuotesAndBlockScalars) {
  EXPECT_NO_THROW(check_duplicate_keys("a:\n  b: 1 # b: 2\n  'c: d': 1\n  c: 2\n  e: |\n    b: 3\n    b: 4\n", "x"));
  EXPECT_NO_THROW(check_duplicate_keys("a: {b: 'x, b: y', c: [1, 2]}\nb: {b: 1}\n", "x"));
  EXPECT_NO_THROW(check_duplicate_keys("a:\n  - b: 1\n  - b: 2\n", "x"));
  EXPECT_THROW(check_duplicate_keys("a: {b: {c: 1,\n  c: 2}}\n", "x"), std::invalid_argument);
  try {
    check_duplicate_keys("a: {b: {c: 1,\n  c: 2}}\n", "scene file 'f.yaml'");
  } catch (const std::invalid_argument& e) {
    expect_message(e.what(), {"scene file 'f.yaml' line 2", "key 'a/b/c'", "first at line 1"});
  }
}

TEST(SceneInput, ParserFailuresNameTheLineWithoutLibraryText) {
  expect_message(error_of(replaced(kScene, "domain max: [1.0, 1.0]", "domain max: [1.0, 1.0")),
                 {"scene line", "not valid YAML"});
  expect_message(error_of(replaced(kScene, "    domain min", "     domain min")),
                 {"scene line 15", "domain min", "not valid YAML"});
  expect_message(error_of(replaced(kScene, "  dimension: 2", "\tdimension: 2")), {"line 5", "tab"});
  expect_message(error_of("# only a comment\n"), {"scene is empty", "bfemp"});
  expect_message(error_of("bfemp: 3\n"), {"not valid YAML"});
}

TEST(SceneInput, MissingValueAndOutOfRangeNumbersInTheFile) {
  expect_message(error_of(replaced(kScene, "kappa: 1.0e5", "kappa:")), {"Contact/kappa", "no value", "real number"});
  expect_message(error_of(replaced(kScene, "kappa: 1.0e5", "kappa: 1e400")),
                 {"Contact/kappa", "1e400", "not a finite number"});
  expect_message(error_of(replaced(kScene, "kappa: 1.0e5", "kappa: .nan")), {"Contact/kappa", ".nan", "real number"});
  expect_message(error_of(replaced(kScene, "kappa: 1.0e5", "kappa: ''")), {"Contact/kappa", "empty string"});
}

TEST(SceneInput, ParticlesOutsideTheGridAreRefusedNamingTheBody) {
  const std::string out = replaced(kScene, "center: [0.3, 0.5]", "center: [-0.1, 0.5]");
  expect_message(error_of(out), {"MPM body 'left'", "outside the MPM grid domain", "MPM/domain min",
                                 "when particles leave: extend"});
  EXPECT_EQ(error_of(out, {"MPM/when particles leave=extend"}), "");
  // Inside the domain box but past it by less than the grid's margin: usable.
  EXPECT_EQ(error_of(replaced(kScene, "center: [0.3, 0.5]", "center: [0.05, 0.5]")), "");
}

TEST(SceneInput, OverlappingBodiesAreRefusedNamingBoth) {
  expect_message(error_of(replaced(kScene, "center: [0.7, 0.5]", "center: [0.4, 0.5]")),
                 {"MPM body 'right'", "MPM body 'left'", "overlap"});
  // Touching boxes (sharing the edge x = 0.4) are apart.
  EXPECT_EQ(error_of(replaced(kScene, "center: [0.7, 0.5]", "center: [0.5, 0.5]")), "");
}

// Each MPI rank samples its id block of the scene's particles
// (build_setup with a ParticleBlock): for any block count, 0-particle blocks
// included, the blocks in rank order are the whole sampling bit for bit
// (positions, initial velocities, masses, bodies, materials), the block
// starts are id_block_begin and the total is the whole count.
TEST(SceneInput, ParticleBlocksTileTheScenesParticlesInIdOrder) {
  // Three bodies of 16, 24 and 12 particles (dx 0.1, 4 per cell): a block
  // edge falls inside each, and their offsets differ.
  const std::string three =
      replaced(kScene, "    right: {material: soft, shape: box, center: [0.7, 0.5], size: [0.2, 0.2]}\n",
               "    right: {material: soft, shape: box, center: [0.7, 0.5], size: [0.2, 0.3]}\n"
               "    top: {material: soft, shape: disk, center: [0.5, 0.85], outer radius: 0.1}\n");
  const Scene scene = load(three, {"MPM Bodies/right/initial velocity=[1.5, -2.0]", "MPM Bodies/right/material=hard",
                                   "MPM Bodies/top/initial velocity=[0.0, 3.0]"});
  const SimulationSetup<2> whole = build_setup<2>(scene);
  const Particles<2>& w = whole.mpm->particles;
  const long long n = static_cast<long long>(w.size());
  ASSERT_EQ(whole.mpm->body_names.size(), 3u);
  ASSERT_EQ(n, 16 + 24 + 12);
  EXPECT_EQ(whole.mpm->particle_total, -1);
  auto wx = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), w.x);
  auto wv = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), w.v);
  auto wm = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), w.mass);
  auto wb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), w.body);
  auto wmat = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), w.material);
  ASSERT_NE(wmat(0), wmat(20));
  ASSERT_EQ(wb(15), 0);
  ASSERT_EQ(wb(16), 1);
  ASSERT_EQ(wb(40), 2);
  ASSERT_EQ(wv(45, 1), 3.0);
  for (int R : {2, 3, 5, 7, 16, 60}) {
    long long row = 0;
    for (int r = 0; r < R; ++r) {
      const SimulationSetup<2> part = build_setup<2>(scene, ParticleBlock{r, R, {}});
      const Particles<2>& p = part.mpm->particles;
      EXPECT_EQ(part.mpm->particle_total, n);
      EXPECT_EQ(part.mpm->particle_first, n * r / R) << "R " << R << " r " << r;
      ASSERT_EQ(static_cast<long long>(p.size()), n * (r + 1) / R - n * r / R) << "R " << R << " r " << r;
      EXPECT_EQ(part.mpm->body_names, whole.mpm->body_names);
      auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
      auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
      auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass);
      auto b = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.body);
      auto mat = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.material);
      for (std::size_t q = 0; q < p.size(); ++q, ++row) {
        for (int d = 0; d < 2; ++d) {
          ASSERT_EQ(x(q, d), wx(row, d)) << "R " << R << " row " << row;
          ASSERT_EQ(v(q, d), wv(row, d)) << "R " << R << " row " << row;
        }
        ASSERT_EQ(m(q), wm(row));
        ASSERT_EQ(b(q), wb(row));
        ASSERT_EQ(mat(q), wmat(row));
      }
    }
    EXPECT_EQ(row, n) << "R " << R;
  }
  EXPECT_THROW(build_setup<2>(scene, ParticleBlock{2, 2, {}}), std::logic_error);
}

TEST(SceneInput, EmptyMaterialAndNewmarkAndStepCount) {
  expect_message(error_of(replaced(kScene, "    hard:\n      E: 1.0e7\n      density: 1000.0\n",
                                   "    hard: {}\n    other:\n      E: 1.0e7\n")),
                 {"Materials/hard", "a material with its keys"});
  expect_message(error_of(kScene, {"Time/Newmark/beta=0"}), {"Time/Newmark/beta", "(0, 0.5]"});
  expect_message(error_of(kScene, {"Time/Newmark/gamma=0.2"}), {"Time/Newmark/gamma", "[0.5, 1]"});
  expect_message(error_of(kScene, {"Time/Newmark/alpha=-0.5"}), {"Time/Newmark/alpha", "> 0"});
  expect_message(error_of(kScene, {"Output/progress every=-1"}), {"Output/progress every", ">= 0"});
  expect_message(error_of(kScene, {"Time/end time=1e300"}), {"Time/end time", "steps"});
}

TEST(SceneInput, DeeplyNestedFlowCollectionIsRefusedNotACrash) {
  // 1e5 nested '[' would overflow the stack of a recursive scan.
  const std::string yaml = "bfemp:\n  dimension: 2\n  gravity: " + std::string(100000, '[') + "\n";
  try {
    load_scene_from_string(yaml, ".");
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nested deeper"), std::string::npos) << e.what();
  }
}

// Contact/FEM-FEM: FEM body pairs in Friction Pairs only with it on, a
// symmetric mu table after the MPM rows, refused in 3D and with one FEM body.
TEST(SceneInput, FemFemContactKeys) {
  const std::string two_walls = replaced(kScene, "  Contact:\n",
                                         "    wall2:\n      material: hard\n      Mesh: {shape: rectangle, center: "
                                         "[2.5, 0.5], size: [0.2, 0.2], element size: 0.1}\n  Contact:\n");
  expect_message(error_of(two_walls, {"Contact/Friction Pairs/wall : wall2=0.3"}),
                 {"Contact/Friction Pairs/wall : wall2", "Contact/FEM-FEM: true"});
  const Scene s = load(two_walls, {"Contact/FEM-FEM=true", "Contact/Friction Pairs/wall : wall2=0.3"});
  const auto setup = build_setup<2>(s);
  ASSERT_TRUE(setup.contact.has_value());
  EXPECT_TRUE(setup.contact->fem_fem);
  EXPECT_EQ(setup.contact->mpm_bodies, 2);
  ASSERT_EQ(setup.contact->mu.size(), (2u + 2u) * 2u);  // (MPM left, right, FEM wall, wall2) x (wall, wall2)
  EXPECT_EQ(setup.contact->mu[0 * 2 + 0], 0.5);        // left : wall
  EXPECT_EQ(setup.contact->mu[1 * 2 + 0], 0.2);        // right : wall
  EXPECT_EQ(setup.contact->mu[(2 + 0) * 2 + 1], 0.3);  // wall : wall2
  EXPECT_EQ(setup.contact->mu[(2 + 1) * 2 + 0], 0.3);  // wall2 : wall (symmetric)
  expect_message(error_of(two_walls, {"Contact/FEM-FEM=true", "Contact/Friction Pairs/wall : wall=0.3"}),
                 {"Contact/Friction Pairs/wall : wall"});
  expect_message(error_of(kScene, {"Contact/FEM-FEM=true"}), {"Contact/FEM-FEM", "at least two FEM bodies"});
}

TEST(SceneInput, TheA6SceneBuildsWithFemFemContact) {
  const Scene s = load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/a6_semiring_buckling.yaml", {});
  const auto setup = build_setup<2>(s);
  ASSERT_TRUE(setup.contact.has_value());
  EXPECT_TRUE(setup.contact->fem_fem);
  // FEM bodies outer (0) and plate (1) after one MPM body: plate : outer = 10.
  EXPECT_EQ(setup.contact->mu[(1 + 1) * 2 + 0], 10.0);
  EXPECT_EQ(setup.contact->mu[(1 + 0) * 2 + 1], 10.0);
  EXPECT_EQ(setup.contact->mu[0 * 2 + 0], 0.0);  // inner : outer
}

// Level Sets/<name>/until: > 0 removes the level set at that time, 0 never;
// negative or non-finite values are refused naming the key.
TEST(SceneInput, LevelSetUntil) {
  const std::string column = std::string(BFEMP_SOURCE_DIR) + "/inputs/mpm_column.yaml";
  auto until_of = [&](const std::vector<std::string>& sets) {
    const auto setup = build_setup<2>(load_scene(column, sets));
    return setup.level_sets.at(0).until;
  };
  EXPECT_EQ(until_of({}), 1e300);
  EXPECT_EQ(until_of({"Level Sets/ground/until=0.25"}), 0.25);
  for (const char* v : {"-1.0", "nan", "inf"}) {
    try {
      until_of({std::string("Level Sets/ground/until=") + v});
      ADD_FAILURE() << "until = " << v << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("Level Sets/ground/until"), std::string::npos) << e.what();
    }
  }
}
