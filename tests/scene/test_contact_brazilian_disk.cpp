// Brazilian disk (paper section 6.3, VALIDATION A3) at the ci size
// (inputs/a3_brazilian_disk.yaml), the measurement the Hertz band rests on:
//  - the contact half-width probe (half the x range of the particles within
//    dhat of the bottom plate) equals, at the first steps, half the x range of
//    the disk's lowest particle row, computed from the particles themselves
//    (the plates start half a dhat from that row);
//  - the force on the bottom plate pushes down and grows every step while the
//    top plate is driven down at 0.1 m/s;
//  - no particle inside a plate at any Newton iterate; the centre of mass
//    stays on x = 0 (a symmetry check only: the scene is symmetric about
//    x = 0, so this holds with or without friction and tests no friction).
// The Hertz slope itself (F = (pi/4) E/(1-nu^2) a^2/R within 20 %) needs the
// contact to spread over several particle rows, which takes the paper's
// resolution and plate travel: scripts/validate.sh --size paper --scenes A3.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>

#include "common/fem_fixtures.hpp"
#include "io/scene.hpp"
#include "probes/probes.hpp"

using namespace bfemp;

TEST(BrazilianDisk, HalfWidthIsTheLowestParticleRowAndTheForceGrows) {
  const Scene scene = load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/a3_brazilian_disk.yaml",
                                 {"Time/end time=0.04", "Contact/check iterates=true"});
  Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
  long inside = 0;
  sim.newton().on_iterate = [&](Kokkos::View<const double*, MemSpace> x) {
    if (sim.contact()->particle_inside_at(x) >= 0) ++inside;
  };
  // The lowest particle row and its x range.
  double ymin = std::numeric_limits<double>::infinity(), xlo = ymin, xhi = -ymin;
  {
    auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sim.mpm()->particles().x);
    for (std::size_t q = 0; q < x.extent(0); ++q) ymin = std::min(ymin, x(q, 1));
    for (std::size_t q = 0; q < x.extent(0); ++q)
      if (x(q, 1) < ymin + 1e-9) xlo = std::min(xlo, x(q, 0)), xhi = std::max(xhi, x(q, 0));
  }
  EXPECT_NEAR(ymin, -0.9875, 1e-12) << "particles at cell offsets dx/4, 3 dx/4 (scene header)";
  RunTable t = RunTable::for_bodies(sim.body_names());
  double f_prev = 0;
  for (int n = 0; n < 4; ++n) {
    const StepReport r = sim.step();
    t.record(r);
    EXPECT_GT(r.contact_pairs, 0) << "step " << r.step;
    EXPECT_LT(r.contact_force[1], f_prev) << "step " << r.step << ": the bottom plate is pushed down harder";
    f_prev = r.contact_force[1];
  }
  for (std::size_t i = 0; i < t.rows(); ++i)
    EXPECT_NEAR(probe::half_width(t, 0, i), 0.5 * (xhi - xlo), 1e-4) << "row " << i;  // next row: +0.05
  EXPECT_NEAR(0.5 * (xhi - xlo), 0.1375, 1e-12);
  EXPECT_EQ(inside, 0);
  EXPECT_LT(std::abs(probe::com(t, "disk", 0, 1e9)), 1e-9) << "the symmetric disk moved sideways";
  std::cout << "brazilian disk (ci): half-width " << probe::half_width(t, 0, t.rows() - 1) << " m (lowest row "
            << 0.5 * (xhi - xlo) << "), force on the bottom plate " << f_prev << " N/m after " << t.rows()
            << " steps\n";
}
