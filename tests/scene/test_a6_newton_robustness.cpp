// A step whose Newton solve fails with the exact Hessian is redone from its
// start with the projected one (sim/simulation.cpp). VALIDATION A6 at the ci
// size with mu = 0.2 between the rings: at step 585 (t = 5.85 s, the inner
// ring collapsed) Newton on the exact Hessian cycles with period 5 through one
// nearly singular direction and reaches the 300-iteration cap; the projected
// Hessian converges there (17 iterations). Before the retry the run stopped
// there with exit 3. With the default Wolfe line search (solver/newton.hpp)
// that step converges with the exact Hessian, so the retry is tested with
// `Newton/line search: backtracking`, and the Wolfe line search on A6 with
// mu = 0.5, whose step 708 failed with both Hessians under backtracking
// (cycles of period 3 at a friction kink, line-search steps 1/32..1/8).
// The cycle needs the exact solves it was found with: every Newton direction
// solved to the reuse tolerance ('Linear Solver/Cholmod/forcing term: fixed')
// and every friction pass at eps_d ('Contact/friction pass tolerance: 1').
// With the defaults (inexact directions, loose passes, and an indefinite
// Hessian met by the confirming solve handled by the projection fallback)
// step 585 converges on the exact Hessian and no step is redone.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/fem_fixtures.hpp"
#include "io/scene.hpp"

using namespace bfemp;

TEST(ProjectedRetry, A6WithFrictionPassesTheStepWhereExactNewtonCycles) {
  const Scene scene = load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/a6_semiring_buckling.yaml",
                                 {"Contact/Friction Pairs/inner : outer=0.2", "Newton/line search=backtracking",
                                  "Linear Solver/Cholmod/forcing term=fixed", "Contact/friction pass tolerance=1"});
  Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
  long retries = 0, retry_step = -1;
  StepReport r;
  int exact_after = -1;
  while (r.step < 586) {
    r = sim.step();  // a failure here (exit 3 in bfemp) fails the test
    if (r.newton.projected_retries > 0) {
      retries += r.newton.projected_retries;
      if (retry_step < 0) retry_step = r.step;
    } else if (retry_step > 0 && exact_after < 0) {
      exact_after = r.newton.exact_hessian_iterations;  // the step after the redo
    }
  }
  EXPECT_GT(exact_after, 0) << "the step after the redo must be back on the exact Hessian";
  // Measured: one retry, at step 585. If a change to the solver removes the
  // cycle, this test no longer reaches the retry: find another case for it.
  EXPECT_GE(retries, 1);
  EXPECT_TRUE(std::isfinite(r.kinetic + r.elastic));
  EXPECT_GT(r.min_J, 0.0);
  std::printf("  retries %ld (step %ld); t = %.2f s, min J %.3f\n", retries, retry_step, r.time, r.min_J);
}

// Measured before the Wolfe line search (backtracking): steps 705 and 707
// redone with the projected Hessian, step 708 failed with both (also with
// 1000 iterations). Now: no step redone through step 710 (the run reaches the
// scene's end, 8 m of plate travel, the same way).
TEST(WolfeLineSearch, A6WithMu05PassesStep708WithoutRedo) {
  const Scene scene = load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/a6_semiring_buckling.yaml",
                                 {"Contact/Friction Pairs/inner : outer=0.5"});
  Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
  long retries = 0, wolfe = 0;
  StepReport r;
  while (r.step < 710) {
    r = sim.step();  // a failure here (exit 3 in bfemp) fails the test
    retries += r.newton.projected_retries;
    wolfe += r.newton.wolfe_steps;
  }
  EXPECT_EQ(retries, 0);
  EXPECT_GT(wolfe, 0);
  EXPECT_TRUE(std::isfinite(r.kinetic + r.elastic));
  EXPECT_GT(r.min_J, 0.0);
  std::printf("  Wolfe steps %ld; t = %.2f s, min J %.3f\n", wolfe, r.time, r.min_J);
}

// A6 at the paper's size (inputs/paper/a6_semiring_buckling.yaml: 9898
// particles, 2777 FEM nodes; the plate 1e-3 above the outer ring, 1 m/s
// down, mu 10 plate : outer). In step 4 the plate's prescribed motion is
// blocked by the ring in its first Newton iteration (bounded step 0.49).
// While prescribed DOFs are short of their targets the line search does not
// guard the energy, and the directions were solved only to the inexact
// Newton forcing term's cap (relative residual 0.1): taken 0.9 of the way to
// the bound each time, they drove the ring into the plate, |rhs| 3e3 -> 9e25
// in 63 iterations, then "Cholmod solve is inaccurate: relative residual
// -nan" (exit 3). The same run passed with 'Linear Solver/Cholmod/forcing
// term: fixed', with the projected Hessian, or without the plate's friction.
// Since then a lift that falls short is solved at the tightest tolerance
// until the prescribed DOFs arrive (solver/newton.cpp, lift_blocked).
// Measured after: 30 steps in 190 Newton iterations.
TEST(BlockedLift, A6PaperSizePassesTheStepWhereThePlateIsHeldBack) {
  const Scene scene = load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/paper/a6_semiring_buckling.yaml", {});
  Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
  StepReport r;
  long iterations = 0;
  while (r.step < 8) {
    r = sim.step();  // step 4 threw a SolverError before the fix
    iterations += r.newton.iterations;
    EXPECT_LT(r.newton.iterations, 60) << "step " << r.step;
    EXPECT_GT(r.min_distance, 0.0) << "step " << r.step;
  }
  EXPECT_TRUE(std::isfinite(r.kinetic + r.elastic));
  EXPECT_GT(r.min_J, 0.0);
  EXPECT_GT(r.contact_pairs, 0);  // the plate is on the ring
  std::printf("  8 steps, %ld Newton iterations; min distance %.3e m, min J %.3f\n", iterations, r.min_distance,
              r.min_J);
}
