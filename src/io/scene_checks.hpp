#pragma once
// Checks of a scene that its schema's types cannot express, all before the
// first step: value ranges (dt > 0, nu in (-1, 0.5), Newmark beta in
// (0, 0.5], ...), component counts, names that must refer to entries, and the
// start state of the MPM bodies (every particle usable on the grid unless the
// grid may extend, no two bodies sampling the same place). Each throws
// std::invalid_argument naming the key path (or body), the value and what was
// expected.
#include <Teuchos_ParameterList.hpp>
#include <string>
#include <vector>

#include "kernels/level_set.hpp"
#include "mpm/mpm_bodies.hpp"

namespace bfemp {

// The scene-wide checks, on a list already validated against the schema
// (types right, defaults filled).
void check_scene_values(const Teuchos::ParameterList& scene);

// The keys of 'Contact/Friction Pairs' ('<MPM body> : <FEM body>' naming
// bodies of the scene) and their mu (a finite number >= 0), whether or not
// contact is enabled; checked when the set-up is built.
void check_friction_pairs(const Teuchos::ParameterList& scene);

// At most this many steps (end time / dt) are run; more is refused.
constexpr double kMaxSteps = 1e9;

// The particles of `mpm` (bodies named by mpm.body_names): refuses the
// first particle that is not usable on mpm.grid unless mpm.extend_domain,
// naming the body. (Overlapping bodies are refused from their shapes:
// first_shared_point in mpm/sampling.hpp.)
template <int dim>
void check_mpm_start(const MpmSetup<dim>& mpm);

// Refuses the first particle (in row order) that starts inside the solid of
// a level set (phi < 0 at t = 0), naming the body and the level set: its
// grid nodes would be constrained to the boundary's motion from the first step.
template <int dim>
void check_level_set_start(const MpmSetup<dim>& mpm, const std::vector<LevelSet>& level_sets);

}  // namespace bfemp
