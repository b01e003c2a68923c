#pragma once
// Start-up checks shared by the two run drivers (app/run.cpp for the implicit
// stepper, app/explicit_run.cpp for the explicit one): bad input stops before
// the first step with the key, the value and what was expected.
#include <stdexcept>
#include <string>

#include "io/scene.hpp"

namespace bfemp {

// 'Output/checkpoint every' (steps between checkpoints; 0: only at the end and
// on interruption). Throws std::invalid_argument when negative.
inline int checked_checkpoint_every(const Scene& scene) {
  const int every = scene.params.sublist("Output").get<int>("checkpoint every");
  if (every < 0)
    throw std::invalid_argument("scene key 'Output/checkpoint every' = " + std::to_string(every) +
                                ": expected >= 0 (0: checkpoints only at the end and on interruption)");
  return every;
}

// A restart continues a checkpoint of the scene's own dimension.
inline void check_restart_dimension(int checkpoint_dim, int scene_dim) {
  if (checkpoint_dim != scene_dim)
    throw std::invalid_argument("restart: the checkpoint is " + std::to_string(checkpoint_dim) + "D, the scene " +
                                std::to_string(scene_dim) + "D");
}

}  // namespace bfemp
