#pragma once
// Runs a loaded scene to its end time: builds the simulation, writes frames,
// diagnostics and restart checkpoints, prints progress and a summary table.
// Restart: the same loop continued from a checkpoint (bfemp restart).
// Interruption: with RunOptions::handle_signals, SIGINT/SIGTERM finish the
// current step, write a frame and a checkpoint, close the files and throw
// Interrupted (the driver exits 130 / 143).
#include <iosfwd>
#include <string>
#include <utility>
#include <vector>

#include "io/checkpoint.hpp"
#include "io/scene.hpp"

namespace bfemp {

struct RunSummary {
  long steps = 0;
  long newton_iterations = 0;
  long linear_iterations = 0;
  double assembly_s = 0, solve_s = 0, line_search_s = 0, wall_s = 0;
  bool contact = false;
  double contact_broad_phase_s = 0, contact_eval_s = 0, contact_ccd_s = 0;  // parts of the above
  long contact_searches = 0, contact_searches_all = 0;  // pair searches; those over every particle
  int frames = 0;
  int checkpoints = 0;
  double output_s = 0;  // frames and checkpoints (the slowest rank)
  // MPI: seconds in the DOF exchanges between ranks (the overlap sum after
  // assembly, the import of owned values; DofSpace::exchange_seconds) and in
  // particle migration, waiting included (the slowest rank).
  double exchange_s = 0, migration_s = 0;
  double exchange_mb = 0;  // MB the busiest rank sent in the DOF exchanges
  double graph_build_s = 0;  // DofSpace graph builds (the slowest rank)
  long graph_builds = 0, symbolic_factorizations = 0, numeric_factorizations = 0;
  long scatter_tables = 0;  // DofSpace scatter tables built (rank 0's), and their seconds
  double scatter_table_s = 0;
  double factor_s = 0, reuse_cg_s = 0;  // Cholmod, BLOCK_CHOLMOD's factorisations (within solve_s; rank 0's)
  // MPI: the spread over the ranks of each rank's own work, in seconds.
  struct Spread {
    double min = 0, max = 0, mean = 0;
  };
  Spread rank_assembly_s, rank_factor_s;  // the terms' assembly kernels; factorisations
  long reuse_cg_iterations = 0;
  long stale_retries = 0;  // CG + BLOCK_CHOLMOD solves redone after the kept factor failed
  std::vector<std::pair<std::string, long>> graph_build_causes;  // DofSpace::build_causes (rank 0's)
  long projected_retries = 0;  // steps redone with the projected Hessian
  long exact_hessian_iterations = 0, projection_fallbacks = 0;  // Newton/hessian: exact-if-definite
  long partial_projections = 0;  // fallbacks solved with a partial projection (Newton/fallback keep)
  long wolfe_steps = 0, wolfe_gradients = 0;  // Newton/line search: wolfe (NewtonStats)
  std::vector<std::pair<std::string, double>> term_assembly_s;  // per energy term
  // MPI, MPM bodies in boxes: ranks, particle migrations, box rebalances and
  // the particle imbalance (largest / mean per rank) at the end.
  int mpm_ranks = 1, rebalances = 0;
  int ranks = 1;  // MPI ranks of the run
  long long migrations = 0;
  double imbalance = 1.0;
  int particle_sorts = 0, sort_every = 0;  // MPM/sort particles every
};

struct RunOptions {
  // The scene file's text and the --set overrides applied to it: stored in
  // checkpoints so that a restart rebuilds exactly this scene (empty source:
  // the resolved scene is written out instead).
  std::string scene_source;
  std::vector<std::string> overrides;
  const Checkpoint* restart = nullptr;  // continue from this state
  bool append = false;                  // restart into the checkpoint's own directory
  bool handle_signals = false;          // SIGINT / SIGTERM: checkpoint, then Interrupted
};

RunSummary run_scene(const Scene& scene, const std::string& output_dir,
                     const Teuchos::RCP<const Comm>& comm, std::ostream& log, const RunOptions& options = {});

// The keys `bfemp restart --set` may change: those that leave the state's
// shape alone (end time, output, Newton and linear-solver settings, the
// friction-loop cap and the iterate check). Throws std::invalid_argument
// naming the key otherwise.
void check_restart_override(const std::string& assignment);

// `bfemp restart`: read_checkpoint(path, rank, ranks) on every rank of comm
// (each its particle rows); a failure on any rank throws std::invalid_argument
// on every rank (the failing rank's message, elsewhere one that points to it;
// a rank other than 0 prints its own to std::cerr), so no rank goes on alone.
Checkpoint read_restart_checkpoint(const std::string& path, const Comm& comm);

// The scene a checkpoint was written from, with `extra` overrides applied
// after its own (each checked by check_restart_override).
Scene checkpoint_scene(const Checkpoint& c, const std::vector<std::string>& extra);
// The checkpoint's own overrides followed by `extra` (what a restart applies
// and stores in its next checkpoint).
std::vector<std::string> checkpoint_overrides(const Checkpoint& c, const std::vector<std::string>& extra);

}  // namespace bfemp
