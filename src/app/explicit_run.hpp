#pragma once
// Runs a 'Solver: explicit' scene (paper 001) to its end time on one rank.
// Output (explicit_output.hpp): bfemp.h5 + bfemp.xdmf frames of the particles
// (positions, velocities, Cauchy stress, von Mises, pressure, J, body and
// material class), diagnostics.csv (per step: dt, the CFL limit, contact
// nodes, 3+ nodes, nodes where a law acted, LR iterations mean/max, the
// stress body's and all particles' mean axial stress, momentum, kinetic
// energy, step time), scene.yaml, and checkpoint.h5 (every 'Output/checkpoint
// every' steps, at the end, and on SIGINT/SIGTERM with handle_signals, after
// which Interrupted is thrown). A restart continues bit for bit (same thread
// count). The summary splits the step time into P2G (with forces), contact
// passes, stress update and G2P.
#include <iosfwd>
#include <map>
#include <string>

#include "io/checkpoint.hpp"
#include "io/scene.hpp"

namespace bfemp {

struct ExplicitRunSummary {
  long steps = 0;
  int frames = 0;
  int checkpoints = 0;
  double p2g_s = 0, contact_s = 0, stress_s = 0, g2p_s = 0, wall_s = 0;
};

struct ExplicitRunOptions {
  std::map<std::string, std::string> checkpoint_texts;  // stored in every checkpoint (the scene, its overrides)
  const Checkpoint* restart = nullptr;                   // continue from this state
  bool append = false;                                   // restart into the checkpoint's own directory
  bool handle_signals = false;                           // SIGINT / SIGTERM: frame, checkpoint, Interrupted
};

ExplicitRunSummary run_explicit_scene(const Scene& scene, const std::string& output_dir, std::ostream& log,
                                      const ExplicitRunOptions& options = {});

// True for a checkpoint written by an explicit run.
bool is_explicit_checkpoint(const Checkpoint& c);

}  // namespace bfemp
