// Explicit scenes (Solver: explicit, paper 001): the B1 input files load and
// build; keys of the other stepper and bad Explicit values are refused with a
// message naming the key, the value and what was expected; a fixed dt above
// the CFL limit at t = 0 is refused naming Time/dt and the limit; per-pair
// contact laws (Explicit/Contact Pairs) reach the stepper's law table, change
// the physics of the pair they name, and bad pair entries are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <Kokkos_Core.hpp>

#include "explicit/explicit_simulation.hpp"
#include "io/scene.hpp"
#include "io/scene_explicit.hpp"

using namespace bfemp;

namespace {

const std::string kFile = std::string(BFEMP_SOURCE_DIR) + "/inputs/b1_compress.yaml";

void refused(const std::vector<std::string>& overrides, const std::string& pattern) {
  try {
    const Scene s = load_scene(kFile, overrides);
    ExplicitSimulation<2> sim(build_explicit_setup<2>(s));
    ADD_FAILURE() << "accepted; expected a refusal matching " << pattern;
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(std::regex_search(e.what(), std::regex(pattern))) << e.what() << "\n  vs " << pattern;
  }
}

TEST(ExplicitScene, B1InputsBuild) {
  for (const char* f : {"/inputs/b1_compress.yaml", "/inputs/b1_contact.yaml"}) {
    const Scene s = load_scene(std::string(BFEMP_SOURCE_DIR) + f);
    EXPECT_TRUE(is_explicit(s));
    const ExplicitSetup<2> st = build_explicit_setup<2>(s);
    EXPECT_EQ(st.materials.size(), 2u);
    EXPECT_EQ(st.particles.size(), 640u);
    EXPECT_EQ(st.stress_body, 0);
    ExplicitSimulation<2> sim(st);
    // CFL 0.5 x dx / (c + |v|): c = 1924 m/s, the moving block of b1_contact adds 0.96 m/s
    EXPECT_NEAR(sim.dt_limit(), 0.5 * 0.005 / std::sqrt((2.45e9 + 4.0 / 3 * 9.4e8) / 1000), 1e-9);
  }
}

TEST(ExplicitScene, StrainUpdateReachesTheSetup) {
  EXPECT_EQ(build_explicit_setup<2>(load_scene(kFile)).strain_update, XStrainUpdate::USF);  // the default
  EXPECT_EQ(build_explicit_setup<2>(load_scene(kFile, {"Explicit/strain update=USL"})).strain_update, XStrainUpdate::USL);
  EXPECT_EQ(build_explicit_setup<2>(load_scene(kFile, {"Explicit/strain update=USAVG"})).strain_update,
            XStrainUpdate::USAVG);
}

TEST(ExplicitScene, BadValuesAreRefusedNamingTheKey) {
  refused({"Explicit/XPIC order=0"}, "Explicit/XPIC order' = 0: expected an integer >= 1");
  refused({"Explicit/mu=-0.1"}, "Explicit/mu' = -0.1: expected a friction coefficient >= 0");
  refused({"Time/CFL=1.5"}, "Time/CFL' = 1.5: expected a value in \\(0, 1\\]");
  refused({"Time/CFL=0"}, "Time/CFL' = 0");
  refused({"Explicit/contact passes=3"}, "Explicit/contact passes' = 3: expected 1 or 2");
  refused({"Explicit/strain update=USAVG+"}, "Explicit/strain update' = 'USAVG\\+': expected one of 'USF', 'USL', 'USAVG'");
  refused({"Explicit/law=glue"}, "Explicit/law");
  refused({"Explicit/normals=DF"}, "Explicit/normals");
  refused({"Explicit/stress body=nobody"}, "Explicit/stress body' = 'nobody'");
  refused({"Materials/lower/K=0"}, "Materials/lower/K' = 0: expected K > 0");
  refused({"MPM Bodies/upper/material=lower"}, "Materials/upper' = \\(no MPM body\\): expected a material class with particles");
  refused({"Time/dt=1e-5"}, "Time/dt' = 1e-05: expected <= the CFL limit 1.29");
  refused({"MPM/sort particles every=5"}, "MPM/sort particles every' = \\(given\\): expected no implicit-only key");
}

std::string with(const std::string& insert) {
  std::ifstream in(kFile);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string t = ss.str();
  t.replace(t.find("  Solver: explicit\n"), 18, "  Solver: explicit\n" + insert);
  return t;
}

TEST(ExplicitScene, ImplicitKeysInAnExplicitSceneAndTheReverse) {
  const std::pair<std::string, std::string> keys[] = {
      {"Newton", "eps_d: 1.0e-6"}, {"Linear Solver", "type: CG"}, {"Contact", "dhat: 1.0e-3"}};
  for (const auto& [k, v] : keys) {
    try {
      load_scene_from_string(with("  " + k + ":\n    " + v + "\n"), ".");
      ADD_FAILURE() << k;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("'" + k + "'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("explicit"), std::string::npos) << e.what();
    }
  }
  std::string t = with("");
  t.replace(t.find("  Solver: explicit\n"), 18, "  Solver: implicit\n");
  try {
    load_scene_from_string(t, ".");
    ADD_FAILURE() << "Explicit keys in an implicit scene accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(std::string(e.what()).find("Explicit") != std::string::npos ||
                std::string(e.what()).find("CFL") != std::string::npos ||
                std::string(e.what()).find("hyperelastic-kg") != std::string::npos)
        << e.what();
  }
}

// Three blocks of three materials: 'lower' and 'upper' touch on the grid
// line y = 50 mm, 'side' stands apart; 'upper' slides along x at `vx` m/s.
std::string three_blocks(const std::string& pairs, double vx = 0.0) {
  std::ostringstream t;
  t << R"(bfemp:
  dimension: 2
  Solver: explicit
  Time:
    CFL: 0.5
    end time: 1.0e-3
  Materials:
    lower:
      model: hyperelastic-kg
      K: 2.45e9
      G: 9.4e8
      density: 1000.0
    upper:
      model: hyperelastic-kg
      K: 2.45e9
      G: 9.4e8
      density: 1000.0
    side:
      model: hyperelastic-kg
      K: 2.45e9
      G: 9.4e8
      density: 1000.0
  MPM:
    grid spacing: 0.005
    domain min: [-0.02, -0.02]
    domain max: [0.14, 0.12]
  MPM Bodies:
    lower:
      material: lower
      shape: box
      center: [0.02, 0.025]
      size: [0.04, 0.05]
    upper:
      material: upper
      shape: box
      center: [0.02, 0.075]
      size: [0.04, 0.05]
      initial velocity: [)"
    << vx << R"(, 0.0]
    side:
      material: side
      shape: box
      center: [0.1, 0.025]
      size: [0.02, 0.02]
  Explicit:
    law: coulomb
    mu: 0.2
)" << pairs;
  return t.str();
}

TEST(ExplicitScene, ContactPairsSetTheLawOfTheirPairOnly) {
  const Scene s = load_scene_from_string(three_blocks("    Contact Pairs:\n      'lower : upper': stick\n"
                                                      "      'side: upper': coulomb 0.5\n"),
                                         ".");
  const ExplicitSetup<2> st = build_explicit_setup<2>(s);
  ASSERT_EQ(st.class_names, (std::vector<std::string>{"lower", "upper", "side"}));
  ASSERT_EQ(st.laws.size(), 9u);
  auto law = [&](int a, int b) { return st.laws[a * 3 + b]; };
  for (auto [a, b] : {std::pair{0, 1}, std::pair{1, 0}}) EXPECT_EQ(law(a, b).law, xmpm::ContactLaw::Stick);
  for (auto [a, b] : {std::pair{1, 2}, std::pair{2, 1}}) {
    EXPECT_EQ(law(a, b).law, xmpm::ContactLaw::Coulomb);
    EXPECT_EQ(law(a, b).mu, 0.5);
  }
  for (auto [a, b] : {std::pair{0, 2}, std::pair{2, 0}}) {  // the Explicit/law default
    EXPECT_EQ(law(a, b).law, xmpm::ContactLaw::Coulomb);
    EXPECT_EQ(law(a, b).mu, 0.2);
  }
}

// x momentum of the particles of `body` (kg m/s per m).
double body_px(const ExplicitSimulation<2>& sim, int body) {
  const auto& p = sim.particles();
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.v);
  auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass);
  auto b = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.body);
  double px = 0;
  for (std::size_t q = 0; q < p.size(); ++q)
    if (b(q) == body) px += m(q) * v(q, 0);
  return px;
}

// Runs the three blocks, 'upper' sliding at 1 m/s on 'lower' with no normal
// load, for 40 steps; returns the particle velocities and the x momentum of
// 'lower' and of all particles.
struct Slide {
  std::vector<double> v;
  double lower_px = 0, total_px = 0, p0 = 0;
};

Slide slide(const std::string& law, const std::string& pairs) {
  std::string t = three_blocks(pairs, 1.0);
  t.replace(t.find("    law: coulomb\n"), 17, "    law: " + law + "\n");
  ExplicitSimulation<2> sim(build_explicit_setup<2>(load_scene_from_string(t, ".")));
  Slide r;
  r.p0 = body_px(sim, 1);
  for (int n = 0; n < 40; ++n) sim.step();
  auto v = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.particles().v);
  r.v.assign(v.data(), v.data() + v.size());
  r.lower_px = body_px(sim, 0);
  r.total_px = r.lower_px + body_px(sim, 1) + body_px(sim, 2);
  return r;
}

TEST(ExplicitScene, APairOverrideActsAsThatLawForItsPairAndNowhereElse) {
  // Only 'lower' and 'upper' touch. Overriding their pair with a law gives
  // bit for bit the run with that law for every pair; overriding the pair of
  // blocks that never touch changes nothing. Stick drags 'lower' along; the
  // default Coulomb law (no normal load: only the block corners, where the LR
  // normal tilts, see an approach) moves it far less. Momentum is conserved.
  const Slide coulomb = slide("coulomb", "");
  const Slide stick = slide("stick", "");
  const Slide stick_pair = slide("coulomb", "    Contact Pairs:\n      'upper : lower': stick\n");
  const Slide coulomb_pair = slide("stick", "    Contact Pairs:\n      'lower : upper': coulomb 0.2\n");
  const Slide other_pair = slide("coulomb", "    Contact Pairs:\n      'side : upper': stick\n");
  EXPECT_EQ(stick_pair.v, stick.v);
  EXPECT_EQ(coulomb_pair.v, coulomb.v);
  EXPECT_EQ(other_pair.v, coulomb.v);
  for (const Slide* s : {&coulomb, &stick}) EXPECT_NEAR(s->total_px, s->p0, 1e-12 * s->p0);
  EXPECT_GT(stick.lower_px, 0.02 * stick.p0);
  EXPECT_LT(std::fabs(coulomb.lower_px), 0.1 * stick.lower_px);
  std::printf("x momentum of 'lower' after 40 steps / upper's initial: stick %.4g, coulomb mu 0.2 %.4g\n",
              stick.lower_px / stick.p0, coulomb.lower_px / coulomb.p0);
}

TEST(ExplicitScene, BadContactPairsAreRefusedNamingTheKey) {
  auto refused_pairs = [](const std::string& pairs, const std::string& pattern) {
    try {
      const Scene s = load_scene_from_string(three_blocks("    Contact Pairs:\n" + pairs), ".");
      build_explicit_setup<2>(s);
      ADD_FAILURE() << "accepted: " << pairs;
    } catch (const std::invalid_argument& e) {
      EXPECT_TRUE(std::regex_search(e.what(), std::regex(pattern))) << e.what() << "\n  vs " << pattern;
    }
  };
  const std::string what = "expected 'frictionless', 'stick' or 'coulomb <mu>' with mu >= 0";
  refused_pairs("      'lower : steel': stick\n",
                "'Explicit/Contact Pairs/lower : steel' = 'lower : steel': expected a key '<material> : <material>' "
                "naming two different materials used by MPM bodies");
  refused_pairs("      'lower : lower': stick\n", "Contact Pairs/lower : lower' = 'lower : lower': expected a key");
  refused_pairs("      lower upper: stick\n", "Contact Pairs/lower upper'");
  refused_pairs("      'lower : upper': glue\n", "Contact Pairs/lower : upper' = 'glue': " + what);
  refused_pairs("      'lower : upper': coulomb\n", "'coulomb': " + what);
  refused_pairs("      'lower : upper': coulomb -0.1\n", "'coulomb -0.1': " + what);
  refused_pairs("      'lower : upper': coulomb 0.2x\n", "'coulomb 0.2x': " + what);
  refused_pairs("      'lower : upper': stick 0.3\n", "'stick 0.3': " + what + " \\(no mu after 'stick'\\)");
  refused_pairs("      'lower : upper': 0.3\n", "Contact Pairs/lower : upper' = 0.3: " + what);
  refused_pairs("      'lower : upper': stick\n      'upper : lower': frictionless\n",
                "Contact Pairs/upper : lower' = \\(given\\): expected each pair of materials once "
                "\\('lower : upper' is given twice\\)");
}

}  // namespace
