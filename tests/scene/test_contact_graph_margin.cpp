// Contact/graph margin: the step's matrix graph holds the pairs within
// (1 + margin) dhat at x^n, so the pairs that the Newton iterates bring
// within dhat are already in it. The colliding rings at the ci size, started
// touching, the particles one quarter cell (0.0625 m) from the FEM ring (pairs
// within dhat from step 1 on, at the end of 6 of the 8 steps): with the default margin the graph
// is built fewer times than with margin 0, and the run is the same to the
// Newton tolerance (the extra couplings are explicit zeros; only the
// factorisation's round-off differs).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/fem_fixtures.hpp"
#include "io/scene.hpp"

using namespace bfemp;

namespace {

struct RingsRun {
  long builds = 0, newton = 0, contact_steps = 0;
  double com_x = 0, kinetic = 0, barrier = 0;
};

RingsRun run_rings(const std::string& margin) {
  const Scene scene = load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/contact_rings.yaml",
                                 {"MPM Bodies/left/center=[-4.0, 0.0]", "FEM Bodies/right/Mesh/center=[4.0, 0.0]",
                                  "Contact/graph margin=" + margin});
  Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
  RingsRun r;
  for (int n = 0; n < 8; ++n) {
    const StepReport s = sim.step();
    if (s.contact_pairs > 0) ++r.contact_steps;
    r.builds += s.newton.graph_builds;
    r.newton += s.newton.iterations;
    r.kinetic = s.kinetic;
    r.barrier = s.barrier_energy;
  }
  r.com_x = sim.diagnostics().momentum[0];
  return r;
}

TEST(ContactGraphMargin, FewerGraphBuildsSameRun) {
  const RingsRun none = run_rings("0");
  const RingsRun dflt = run_rings("3");
  std::printf("  graph builds in 8 steps: margin 0: %ld, margin 3: %ld; Newton iterations %ld / %ld\n",
              none.builds, dflt.builds, none.newton, dflt.newton);
  EXPECT_GE(none.contact_steps, 5);  // pairs within dhat at the end of the step (coarse rings: not every step)
  EXPECT_EQ(dflt.contact_steps, none.contact_steps);
  EXPECT_LT(dflt.builds, none.builds);
  EXPECT_LE(dflt.builds, 8 + 1);  // at most about one per step (the occupied cells move)
  EXPECT_EQ(dflt.newton, none.newton);
  EXPECT_NEAR(dflt.kinetic, none.kinetic, 1e-9 * none.kinetic);
  EXPECT_NEAR(dflt.barrier, none.barrier, 1e-6 * none.barrier + 1e-12);
  EXPECT_NEAR(dflt.com_x, none.com_x, 1e-9 * std::fabs(none.kinetic) + 1e-9);
}

TEST(ContactGraphMargin, NegativeMarginRefused) {
  try {
    load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/contact_rings.yaml", {"Contact/graph margin=-1"});
    FAIL() << "a negative graph margin was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("Contact/graph margin"), std::string::npos) << m;
    EXPECT_NE(m.find("-1"), std::string::npos) << m;
  }
}

}  // namespace
