// Probes (src/probes) on run tables with known answers:
//  - the centre-of-mass acceleration fit recovers a of x = x0 + v0 t + a t^2/2
//    exactly (to round-off) at any time offset, and ignores rows outside the
//    window;
//  - contact start / end, the energy lost during contact, the momentum drift
//    relative to a body, the Hertz slope of F = k a^2 + c and the combined
//    centre of mass of two bodies equal their hand-computed values;
//  - diagnostics.csv of a real run read back equals the table recorded in
//    memory from the same StepReports (every column, every row), and its body
//    columns hold the body's mass and centre of mass;
//  - bad specs (unknown probe, misspelled key, bad axis, unknown body or
//    column) are refused naming what was wrong; a torn last CSV row is
//    dropped, a torn middle row refused.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>

#include "common/fem_fixtures.hpp"
#include "io/hdf5_frames.hpp"
#include "io/run_output.hpp"
#include "io/scene.hpp"
#include "probes/probes.hpp"

using namespace bfemp;

namespace {

// A table for one body "b" with rows at t = t0 + k dt.
RunTable table_of(int n, double t0, double dt, const std::function<void(double, StepReport&)>& fill) {
  RunTable t = RunTable::for_bodies({"b"});
  for (int k = 0; k < n; ++k) {
    StepReport r;
    r.step = k;
    r.time = t0 + k * dt;
    r.bodies.resize(1);
    r.bodies[0].mass = 2.0;
    fill(r.time, r);
    t.record(r);
  }
  return t;
}

std::string error_of(const std::string& spec, const RunTable& t) {
  try {
    evaluate_probe(spec, t);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Probes, AccelerationFitIsExactForAQuadraticAndHonoursTheWindow) {
  const double a = -3.7, v0 = 1.25, x0 = 10.0;
  const RunTable t = table_of(401, 2.0, 1e-3, [&](double time, StepReport& r) {
    const double s = time - 2.0;
    // A different motion before t = 2.1 s: the window must exclude it.
    r.bodies[0].com[1] = time < 2.1 ? 0.0 : x0 + v0 * s + 0.5 * a * s * s;
  });
  EXPECT_NEAR(probe::acceleration(t, "b", 1, 2.1, 2.4), a, 1e-9 * std::abs(a));
  EXPECT_NEAR(evaluate_probe("acceleration:body=b,axis=y,from=2.1,to=2.4", t), a, 1e-9 * std::abs(a));
  // Including the jump changes it: the window matters.
  EXPECT_GT(std::abs(probe::acceleration(t, "b", 1, 2.0, 2.4) - a), 1.0);
  EXPECT_DOUBLE_EQ(evaluate_probe("com:body=b,axis=y,t=2.2", t), x0 + v0 * 0.2 + 0.5 * a * 0.04);
}

TEST(Probes, ContactWindowEnergyLossMomentumDriftAndMaxima) {
  // Contact from t = 0.3 to 0.5; energy 100 before, 91.43 after (8.57 % lost).
  const RunTable t = table_of(11, 0.0, 0.1, [](double time, StepReport& r) {
    const bool in = time > 0.25 && time < 0.55;
    r.contact_pairs = in ? 7 : 0;
    r.kinetic = time < 0.25 ? 100.0 : (in ? 50.0 : 91.43);
    r.elastic = in ? 45.0 : 0.0;
    r.momentum[0] = 80.0 + (time > 0.65 ? 4e-6 : 0.0);
    r.bodies[0].velocity = {40.0, 0.0, 0.0};
    r.newton.iterations = 3;
  });
  EXPECT_DOUBLE_EQ(probe::contact_start(t), 0.3);
  EXPECT_DOUBLE_EQ(probe::contact_end(t), 0.5);
  EXPECT_NEAR(evaluate_probe("energy_lost_pct", t), 8.57, 1e-12);
  EXPECT_NEAR(evaluate_probe("energy_lost_pct:from=0,to=0.4", t), 5.0, 1e-12);
  // |p| of body b at t = 0: 2 kg x 40 m/s.
  // (80 + 4e-6) - 80 carries the round-off of 80 (ulp 1.4e-14): 2 ulp / 80.
  EXPECT_NEAR(evaluate_probe("momentum_drift:axis=x,relative_to=b", t), 4e-6 / 80.0, 3e-14 / 80.0);
  EXPECT_DOUBLE_EQ(evaluate_probe("sum:column=newton_iters", t), 33.0);
  EXPECT_DOUBLE_EQ(evaluate_probe("max:column=contact_pairs,from=0.6", t), 0.0);
  EXPECT_DOUBLE_EQ(evaluate_probe("min:column=kinetic", t), 50.0);
  // No separation yet: the loss during contact is undefined.
  const RunTable open = table_of(4, 0.0, 0.1, [](double time, StepReport& r) { r.contact_pairs = time > 0.15; });
  EXPECT_TRUE(std::isnan(evaluate_probe("energy_lost_pct", open)));
  EXPECT_TRUE(std::isnan(probe::contact_start(table_of(3, 0, 1, [](double, StepReport&) {}))));
}

TEST(Probes, HertzSlopeAndHalfWidth) {
  // a grows linearly; F = k a^2 + c on the bottom plate, pushing down (F_y < 0).
  const double k = 8.6e9, c = 1.5e3;
  const RunTable t = table_of(20, 0.0, 0.01, [&](double time, StepReport& r) {
    const double a = 0.01 * std::round(time / 0.01);
    r.contact_lo = {0.3 - a, 0.0, 0.0};
    r.contact_hi = {0.3 + a, 0.0, 0.0};
    r.contact_force = {0.0, -(k * a * a + c), 0.0};
    if (a == 0) {
      r.contact_lo[0] = r.contact_hi[0] = std::nan("");
      r.contact_force[1] = 0;
    }
  });
  EXPECT_NEAR(evaluate_probe("half_width:t=0.05", t), 0.05, 1e-15);
  EXPECT_TRUE(std::isnan(evaluate_probe("half_width:t=0", t)));
  EXPECT_NEAR(evaluate_probe("hertz_slope", t), k, 1e-9 * k);
  EXPECT_NEAR(evaluate_probe("hertz_slope:a_max=0.1", t), k, 1e-9 * k);
  // Only the first two contact rows (a = 0.01, 0.02) below a_max = 0.025.
  EXPECT_NEAR(probe::fit_slope({1e-4, 4e-4}, {k * 1e-4 + c, k * 4e-4 + c}), k, 1e-9 * k);
}

TEST(Probes, EquilibriumHeightWeighsBodiesByMass) {
  RunTable t = RunTable::for_bodies({"top", "base"});
  StepReport r;
  r.bodies.resize(2);
  r.bodies[0].mass = 2000.0;
  r.bodies[0].com = {0.0, 1.5, 0.0};
  r.bodies[1].mass = 400.0;
  r.bodies[1].com = {0.0, 0.5, 0.0};
  t.record(r);
  EXPECT_NEAR(evaluate_probe("equilibrium_height:bodies=top+base", t), (2000 * 1.5 + 400 * 0.5) / 2400.0, 1e-15);
  EXPECT_DOUBLE_EQ(evaluate_probe("equilibrium_height:bodies=base", t), 0.5);
}

TEST(Probes, BadSpecsAreRefusedNamingTheProblem) {
  const RunTable t = table_of(5, 0.0, 0.1, [](double, StepReport&) {});
  EXPECT_NE(error_of("accel:body=b", t).find("probe 'accel' unknown"), std::string::npos) << error_of("accel", t);
  EXPECT_NE(error_of("acceleration:bdy=b", t).find("bdy"), std::string::npos);
  EXPECT_NE(error_of("acceleration:body=b,axis=w", t).find("x, y or z"), std::string::npos);
  EXPECT_NE(error_of("acceleration:body=nobody", t).find("no body 'nobody'"), std::string::npos);
  EXPECT_NE(error_of("max:column=speed", t).find("no column 'speed'"), std::string::npos);
  EXPECT_NE(error_of("acceleration", t).find("body"), std::string::npos) << "a required key";
  EXPECT_NE(error_of("value:column=time,t=soon", t).find("a number"), std::string::npos);
  // "max" is not a key of hertz_slope even though "a_max" is.
  EXPECT_NE(error_of("hertz_slope:max=1", t).find("max"), std::string::npos);
}

TEST(Probes, CsvOfARealRunEqualsTheRecordedTableAndTornRowsAreHandled) {
  const std::string dir = (std::filesystem::temp_directory_path() / "bfemp_test_probes").string();
  std::filesystem::remove_all(dir);
  const Scene scene = load_scene(std::string(BFEMP_SOURCE_DIR) + "/inputs/contact_slope.yaml",
                                 {"Time/end time=0.005", "Output/frame every=100"});
  Simulation<2> sim(build_setup<2>(scene), fixtures::comm());
  ASSERT_EQ(sim.body_names(), (std::vector<std::string>{"slope", "box"}));
  RunTable mem = RunTable::for_bodies(sim.body_names());
  double M = 0, mx = 0, my = 0;  // the box's particles at t = 0
  {
    const auto& p = sim.mpm()->particles();
    auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
    auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass);
    for (std::size_t q = 0; q < p.size(); ++q) M += m(q), mx += m(q) * x(q, 0), my += m(q) * x(q, 1);
  }
  mem.record(sim.diagnostics());
  {
    RunOutput<2> out(dir, scene, sim);
    for (int n = 0; n < 5; ++n) {
      const StepReport r = sim.step();
      out.write_diagnostics(r);
      mem.record(r);
    }
    out.close();
  }
  const RunTable csv = RunTable::read_csv(dir);
  ASSERT_EQ(csv.columns(), mem.columns());
  ASSERT_EQ(csv.rows(), 5u);
  ASSERT_EQ(mem.rows(), 6u);  // row 0: the initial state
  for (const auto& c : csv.columns())
    for (std::size_t i = 0; i < 5; ++i) {
      const double a = csv.column(c)[i], b = mem.column(c)[i + 1];
      if (std::isnan(b)) {
        EXPECT_TRUE(std::isnan(a)) << c;
      } else {
        EXPECT_EQ(a, b) << c << " row " << i;  // %.17g round-trips doubles
      }
    }
  EXPECT_EQ(csv.bodies(), (std::vector<std::string>{"slope", "box"}));
  // The box: 0.1025 x 0.0225 m at density 100 kg/m^2; its centre of mass.
  EXPECT_NEAR(mem.column("box.mass")[0], 100.0 * 0.1025 * 0.0225, 1e-3 * M);
  EXPECT_NEAR(mem.column("box.mass")[0], M, 1e-12 * M);
  EXPECT_NEAR(probe::com(mem, "box", 0, 0.0), mx / M, 1e-12);
  EXPECT_NEAR(probe::com(mem, "box", 1, 0.0), my / M, 1e-12);
  EXPECT_GT(csv.column("slope.mass")[0], 0.0);
  EXPECT_EQ(csv.column("slope.kinetic")[4], 0.0) << "the slope is fixed";

  // A torn last row (a run still writing) is dropped; a torn middle row is an error.
  std::string text;
  {
    std::ifstream in(dir + "/diagnostics.csv");
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  {
    std::ofstream o(dir + "/torn.csv");
    o << text << "6,0.006,0.001,1.5";
  }
  EXPECT_EQ(RunTable::read_csv(dir + "/torn.csv").rows(), 5u);
  {
    std::ofstream o(dir + "/torn2.csv");
    const auto second = text.find('\n', text.find('\n') + 1);
    o << text.substr(0, second + 1) << "2,0.002\n" << text.substr(second + 1);
  }
  try {
    RunTable::read_csv(dir + "/torn2.csv");
    ADD_FAILURE() << "a torn middle row was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

// The lead_onset probe (A6's buckling onset) on frames with a known motion:
// a crown group follows a plate moving at -1 m/s with a 0.05 m lag until
// t = 1 s, then accelerates ahead (u = -t + 0.05 - 2 (t - 1)^2); a second
// group outside the box runs far ahead from the start and must not count.
// Lead = -(u + t) = 2 (t - 1)^2 - 0.05 exceeds 0.15 first at t > 1.316 s:
// the frame at 1.4 s (frames every 0.2 s).
TEST(Probes, LeadOnsetOfAPointSetAheadOfADrivenTravel) {
  const std::string dir = (std::filesystem::temp_directory_path() / "bfemp_test_probe_lead").string();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  auto write = [&](double late) {  // late: the crown's extra acceleration (0: it never leads)
    Hdf5FrameWriter w(dir + "/bfemp.h5");
    for (int k = 0; k <= 10; ++k) {
      const double t = 0.2 * k;
      const double u = -t + (t > 0 ? 0.05 : 0.0) - (t > 1 ? late * (t - 1) * (t - 1) : 0.0);
      std::vector<double> x;
      for (int q = 0; q < 5; ++q) x.push_back(-0.5 + 0.25 * q), x.push_back(10.0 + 0.1 * q + u);
      x.push_back(5.0), x.push_back(10.0 - 10 * t);  // outside the box, far ahead
      w.begin_frame(k, t, k);
      w.write_array("particle_positions", x.data(), x.size() / 2, 2);
      w.end_frame();
    }
    w.close();
  };
  write(2.0);
  RunTable t = table_of(3, 0.0, 1.0, [](double, StepReport&) {});
  t.set_source_dir(dir);
  const std::string box = "lead_onset:box_min=-1;9.5,box_max=1;11,speed=-1";
  EXPECT_NEAR(evaluate_probe(box, t), 1.4, 1e-12);
  EXPECT_NEAR(evaluate_probe(box + ",threshold=0.5", t), 1.6, 1e-12) << "2 (t - 1)^2 - 0.05 > 0.5 from 1.524 s";
  EXPECT_NEAR(evaluate_probe("lead_onset:box_min=4;-100,box_max=6;11,speed=-1", t), 0.2, 1e-12)
      << "the group running ahead";
  EXPECT_NE(error_of("lead_onset:box_min=-1;9.5,box_max=1;11,speed=0", t).find("nonzero"), std::string::npos);
  EXPECT_NE(error_of("lead_onset:box_min=7;7,box_max=8;8,speed=-1", t).find("no particle"), std::string::npos);
  EXPECT_NE(error_of("lead_onset:box_min=-1;9.5;0,box_max=1;11,speed=-1", t).find("expected 2"), std::string::npos);
  EXPECT_NE(error_of("lead_onset:box_min=-1;9.5,box_max=1;11,speed=-1,threshold=-0.1", t).find("threshold = -0.1"),
            std::string::npos);
  EXPECT_NE(error_of("lead_onset:box_min=-1;9.5,box_max=1;11,speed=-1,axis=z", t).find("2D"), std::string::npos);
  write(0.0);
  EXPECT_TRUE(std::isnan(evaluate_probe(box, t))) << "a crown that never leads";
  std::filesystem::remove_all(dir);
}

// The rotation probe on frames with a known rigid rotation: a ring of points
// (and a point on the axis, skipped) rotated by omega t about z through
// (0.5, 0.5) in 2D, and about x in 3D; a second group outside the box moves
// differently and must not count.
TEST(Probes, RotationOfAPointSetFromTheFrames) {
  const std::string dir = (std::filesystem::temp_directory_path() / "bfemp_test_probe_rotation").string();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const double omega = 0.6283185307179586;  // A7's pi/5 rad/s
  {
    Hdf5FrameWriter w(dir + "/bfemp.h5");
    for (int k = 0; k < 6; ++k) {
      const double t = 0.5 * k, th = omega * t;
      std::vector<double> x;
      for (int q = 0; q < 12; ++q) {
        const double r = 0.1 + 0.02 * q, a0 = 0.3 * q;
        x.push_back(0.5 + r * std::cos(a0 + th));
        x.push_back(0.5 + r * std::sin(a0 + th));
      }
      x.push_back(0.5), x.push_back(0.5);                   // on the axis
      x.push_back(2.0 + 0.1 * k), x.push_back(2.0 - 0.3 * k);  // outside the box
      w.begin_frame(k, t, 10 * k);
      w.write_array("particle_positions", x.data(), x.size() / 2, 2);
      w.end_frame();
    }
    w.close();
  }
  RunTable t = table_of(3, 0.0, 1.0, [](double, StepReport&) {});
  t.set_source_dir(dir);
  const std::string box = "rotation:box_min=0;0,box_max=1;1,center=0.5;0.5";
  EXPECT_NEAR(evaluate_probe(box, t), omega * 2.5, 1e-12) << "last frame";
  EXPECT_NEAR(evaluate_probe(box + ",t=1.1", t), omega * 1.0, 1e-12) << "frame nearest 1.1 s: t = 1 s";
  EXPECT_NEAR(evaluate_probe(box + ",t=0", t), 0.0, 1e-15);
  EXPECT_NEAR(evaluate_probe("peak_rotation:box_min=0;0,box_max=1;1,center=0.5;0.5", t), omega * 2.5, 1e-12)
      << "a steady rotation peaks at the last frame";
  EXPECT_NE(error_of("peak_rotation:box_min=5;5,box_max=6;6,center=0.5;0.5", t).find("no particle"),
            std::string::npos);
  EXPECT_NE(error_of("rotation:box_min=0;0,box_max=1;1,center=0.5;0.5,axis=x", t).find("about z"), std::string::npos);
  EXPECT_NE(error_of("rotation:box_min=5;5,box_max=6;6,center=0.5;0.5", t).find("no particle"), std::string::npos);
  EXPECT_NE(error_of("rotation:box_min=0;0;0,box_max=1;1,center=0.5;0.5", t).find("2 components"), std::string::npos);
  EXPECT_NE(error_of("rotation:box_min=0;a,box_max=1;1,center=0.5;0.5", t).find("numbers joined by ';'"),
            std::string::npos);
  RunTable mem = table_of(3, 0.0, 1.0, [](double, StepReport&) {});
  EXPECT_NE(error_of(box, mem).find("run directory"), std::string::npos);
  // 3D, about x through (0, 1, 1).
  {
    Hdf5FrameWriter w(dir + "/bfemp.h5");
    for (int k = 0; k < 3; ++k) {
      const double th = -0.4 * k;
      std::vector<double> x;
      for (int q = 0; q < 8; ++q) {
        const double r = 0.2 + 0.05 * q, a0 = 0.7 * q;
        x.insert(x.end(), {0.1 * q, 1.0 + r * std::cos(a0 + th), 1.0 + r * std::sin(a0 + th)});
      }
      w.begin_frame(k, 0.1 * k, k);
      w.write_array("particle_positions", x.data(), x.size() / 3, 3);
      w.end_frame();
    }
    w.close();
  }
  EXPECT_NEAR(evaluate_probe("rotation:box_min=-1;0;0,box_max=1;2;2,center=0;1;1,axis=x", t), -0.8, 1e-12);
  // A point set that turns to 0.7 rad and slips back to 0.2 (A7 after a
  // slip): the peak, not the end.
  {
    Hdf5FrameWriter w(dir + "/bfemp.h5");
    const double th[] = {0.0, 0.3, 0.7, 0.5, 0.2};
    for (int k = 0; k < 5; ++k) {
      std::vector<double> x;
      for (int q = 0; q < 8; ++q) {
        const double r = 0.2 + 0.05 * q, a0 = 0.7 * q;
        x.insert(x.end(), {r * std::cos(a0 + th[k]), r * std::sin(a0 + th[k]), 0.9});
      }
      w.begin_frame(k, 0.5 * k, k);
      w.write_array("particle_positions", x.data(), x.size() / 3, 3);
      w.end_frame();
    }
    w.close();
  }
  const std::string top = "box_min=-1;-1;0.8,box_max=1;1;1,center=0;0;0";
  EXPECT_NEAR(evaluate_probe("peak_rotation:" + top, t), 0.7, 1e-12);
  EXPECT_NEAR(evaluate_probe("rotation:" + top, t), 0.2, 1e-12);
  std::filesystem::remove_all(dir);
}
