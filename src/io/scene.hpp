#pragma once
// Scene files: YAML read into a Teuchos::ParameterList, validated against the
// full schema (unknown keys, wrong types and bad values stop the run before the
// first step with a message naming the key, the value and what was expected),
// defaults filled in, and turned into the solver's set-up structures.
#include <Teuchos_Comm.hpp>
#include <Teuchos_ParameterList.hpp>
#include <functional>
#include <string>
#include <vector>

#include "sim/simulation.hpp"

namespace bfemp {

struct RunControl {
  double end_time = 0;
  int output_every = 1;     // steps between output frames
  int progress_every = 10;  // steps between progress lines
};

struct Scene {
  std::string path;                 // scene file ("" for strings)
  std::string base_dir;             // directory mesh paths are relative to
  Teuchos::ParameterList params;    // resolved: validated, defaults filled
  int dim() const { return params.get<int>("dimension"); }
  RunControl run_control() const;
};

// The schema with every key, default and doc string (top list "bfemp").
Teuchos::RCP<const Teuchos::ParameterList> scene_schema();

// Reads a YAML scene, applies `overrides` ("Time/dt=1e-3": path/to/key=value,
// the value parsed as the existing key's type), validates it. Throws
// std::invalid_argument with a message naming key, value and expectation.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {});
Scene load_scene_from_string(const std::string& yaml, const std::string& base_dir,
                             const std::vector<std::string>& overrides = {});

// Which particles build_setup samples: with count > 1, only the id block
// [id_block_begin(N, rank, count), id_block_begin(N, rank + 1, count)) of
// the N particles of all MPM bodies (MpmSetup::particle_first/_total set),
// so that no MPI rank holds the whole set; count 1: every particle.
// The start checks of the block's particles (inside the grid, outside the
// level-set solids) run through `check` (empty: called directly). Their
// verdict differs between ranks, so an MPI run must agree on it:
// particle_block(comm) sets check to collective_check. Every other check of
// build_setup is the same on every rank.
struct ParticleBlock {
  int rank = 0;
  int count = 1;
  std::function<void(const std::function<void()>&)> check;
};

// This rank's block of comm, its start checks agreed over comm (collective
// inside build_setup; comm must outlive the block).
ParticleBlock particle_block(const Teuchos::Comm<int>& comm);

// Builds meshes (files or Gmsh shapes), materials, motions and solver settings.
// On several ranks (a ParticleBlock of count > 1) every rank gives the error,
// and the same one, that one rank would give with the whole scene: the
// checks before a block's are the same everywhere, and the first particle in
// id order that fails a check is the lowest failing rank's.
template <int dim>
SimulationSetup<dim> build_setup(const Scene& scene, ParticleBlock block = {});

// A one-paragraph summary for the start of a run.
std::string scene_summary(const Scene& scene);

}  // namespace bfemp
