// Convergence under refinement (paper section 6.5, VALIDATION A5) at a ci
// size: inputs/a5_refinement.yaml, a soft MPM box coming to rest on a soft
// FEM box under gravity, at N = 2, 4, 6 (dx = element size = 1/N, dhat =
// 1/N^2, 4 particles per cell) against the reference N = 10. The measure is
// the paper's: the height of the centre of mass of both bodies at the end
// (equilibrium; probe equilibrium_height:bodies=box+base). Must show: the
// runs are at rest to within their error (the box's largest speed over the
// last second over the bounce frequency 2 pi / 0.8 s, an amplitude, is below
// a tenth of the error; the reference's below 1e-4 m), the
// error falls with N at every refinement, and the least-squares order of
// log(error) against log(N) is >= 2 (the paper's band for PPC = 16 at N up to
// 20; measured here: about 4 with PPC = 4). Every step: no particle in the
// FEM box (no contact distance <= 0).
#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "common/fem_fixtures.hpp"
#include "io/scene.hpp"
#include "probes/probes.hpp"

using namespace bfemp;

namespace {

struct Level {
  double height = 0, rest_speed = 0, min_distance = 1e300;
  long steps = 0;
};

Level run_level(int N) {
  const double dx = 1.0 / N;
  std::ostringstream a, b, c;
  a.precision(17), b.precision(17), c.precision(17);
  a << "MPM/grid spacing=" << dx;
  b << "FEM Bodies/base/Mesh/element size=" << dx;
  c << "Contact/dhat=" << dx * dx;
  const Scene scene =
      load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/a5_refinement.yaml", {a.str(), b.str(), c.str()});
  Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
  RunTable t = RunTable::for_bodies(sim.body_names());
  const double end = scene.params.sublist("Time").get<double>("end time");
  const long steps = std::lround(end / scene.params.sublist("Time").get<double>("dt"));
  Level L;
  for (long n = 0; n < steps; ++n) {
    const StepReport r = sim.step();
    t.record(r);
    if (r.contact_pairs > 0) L.min_distance = std::min(L.min_distance, r.min_distance);
    ++L.steps;
  }
  L.height = evaluate_probe("equilibrium_height:bodies=box+base", t);
  L.rest_speed = probe::max_speed(t, "box", 1, end - 1.0, end);
  return L;
}

}  // namespace

TEST(ContactRefinement, EquilibriumHeightConvergesWithOrderAtLeastTwo) {
  const Level ref = run_level(10);
  const int Ns[] = {2, 4, 6};
  std::vector<double> logN, logE;
  double prev = 1e300;
  std::cout << std::setprecision(10) << "refinement: reference N = 10 height " << ref.height << " m (rest speed "
            << ref.rest_speed << " m/s)\n";
  const double omega = 2 * M_PI / 0.8;  // the box's bounce on the soft base (scene header)
  EXPECT_LT(ref.rest_speed / omega, 1e-4);
  EXPECT_GT(ref.min_distance, 0.0);
  for (int N : Ns) {
    const Level L = run_level(N);
    const double err = std::abs(L.height - ref.height);
    std::cout << "refinement: N = " << N << " height " << L.height << " m, error " << err << " m, rest speed "
              << L.rest_speed << " m/s, min distance " << L.min_distance << " m\n";
    EXPECT_LT(L.rest_speed / omega, 0.1 * err) << "N = " << N << " not at rest to within its error";
    EXPECT_GT(L.min_distance, 0.0) << "N = " << N;
    EXPECT_LT(err, prev) << "the error must fall with N (N = " << N << ")";
    prev = err;
    logN.push_back(std::log(double(N)));
    logE.push_back(std::log(err));
  }
  const double order = -probe::fit_slope(logN, logE);
  std::cout << "refinement: fitted order " << order << " (paper: 2.75 with PPC 16)\n";
  EXPECT_GE(order, 2.0);
}
