#pragma once
// Runs a 'Solver: explicit' scene (paper 001) to its end time: HDF5 frames
// (bfemp.h5: particle positions, velocities, Cauchy stress, body and material
// class per particle), diagnostics.csv (per step: dt, the CFL limit, contact
// nodes, 3+ nodes, nodes where a law acted, LR iterations mean/max, the
// stress body's and all particles' mean axial stress, momentum, kinetic
// energy, timings) and a summary splitting the step time into P2G (with
// forces), contact passes, stress update and G2P. No restart (refused).
#include <iosfwd>
#include <string>

#include "io/scene.hpp"

namespace bfemp {

struct ExplicitRunSummary {
  long steps = 0;
  int frames = 0;
  double p2g_s = 0, contact_s = 0, stress_s = 0, g2p_s = 0, wall_s = 0;
};

ExplicitRunSummary run_explicit_scene(const Scene& scene, const std::string& output_dir, std::ostream& log);

}  // namespace bfemp
