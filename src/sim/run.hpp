#pragma once
// Runs a loaded scene to its end time: builds the simulation, writes frames and
// diagnostics, prints progress and a summary table.
#include <iosfwd>
#include <string>

#include "io/scene.hpp"

namespace bfemp {

struct RunSummary {
  long steps = 0;
  long newton_iterations = 0;
  long linear_iterations = 0;
  double assembly_s = 0, solve_s = 0, line_search_s = 0, wall_s = 0;
  bool contact = false;
  double contact_broad_phase_s = 0, contact_eval_s = 0, contact_ccd_s = 0;  // parts of the above
  int frames = 0;
};

RunSummary run_scene(const Scene& scene, const std::string& output_dir,
                     const Teuchos::RCP<const Comm>& comm, std::ostream& log);

}  // namespace bfemp
