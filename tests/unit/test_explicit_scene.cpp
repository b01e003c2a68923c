// Explicit scenes (Solver: explicit, paper 001): the B1 input files load and
// build; keys of the other stepper and bad Explicit values are refused with a
// message naming the key, the value and what was expected; a fixed dt above
// the CFL limit at t = 0 is refused naming Time/dt and the limit.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

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

TEST(ExplicitScene, BadValuesAreRefusedNamingTheKey) {
  refused({"Explicit/XPIC order=0"}, "Explicit/XPIC order' = 0: expected an integer >= 1");
  refused({"Explicit/mu=-0.1"}, "Explicit/mu' = -0.1: expected a friction coefficient >= 0");
  refused({"Time/CFL=1.5"}, "Time/CFL' = 1.5: expected a value in \\(0, 1\\]");
  refused({"Time/CFL=0"}, "Time/CFL' = 0");
  refused({"Explicit/contact passes=3"}, "Explicit/contact passes' = 3: expected 1 or 2");
  refused({"Explicit/law=glue"}, "Explicit/law");
  refused({"Explicit/normals=DF"}, "Explicit/normals");
  refused({"Explicit/stress body=nobody"}, "Explicit/stress body' = 'nobody'");
  refused({"Materials/lower/K=0"}, "Materials/lower/K' = 0: expected K > 0");
  refused({"MPM Bodies/upper/material=lower"}, "Materials/upper' = \\(no MPM body\\): expected a material class with particles");
  refused({"Time/dt=1e-5"}, "Time/dt' = 1e-05: expected <= the CFL limit 1.29");
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

}  // namespace
