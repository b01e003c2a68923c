#pragma once
// Scenes with 'Solver: explicit' (paper 001): the refusal of keys that belong
// to the other stepper, the checks of the Explicit keys, and the ExplicitSetup.
#include <Teuchos_ParameterList.hpp>

#include "explicit/explicit_setup.hpp"
#include "io/scene.hpp"

namespace bfemp {

// On the raw scene (before defaults are filled): an explicit scene with an
// implicit-only key (Newton, Linear Solver, Contact, FEM Bodies, Time/integrator,
// Time/Newmark, MPM/transfer) or an implicit scene with an explicit-only key
// (Explicit, Time/CFL, a hyperelastic-kg material) is refused naming the key.
// For an explicit scene that gives Time/dt, sets Explicit/fixed dt.
void check_solver_keys(Teuchos::ParameterList& raw);

// Value checks of an explicit scene (after validation): XPIC order >= 1,
// contact passes 1 or 2, CFL in (0, 1], mu >= 0, CP > 0, K, G > 0 of
// hyperelastic-kg materials, stress axis, stress body.
void check_explicit_values(const Teuchos::ParameterList& p);

bool is_explicit(const Scene& scene);

// Particles, grid and level sets as build_setup makes them; material classes
// = the materials that MPM bodies use (a material used by none is refused:
// a class with no particles); slip level sets need an axis-aligned normal.
template <int dim>
ExplicitSetup<dim> build_explicit_setup(const Scene& scene);

}  // namespace bfemp
