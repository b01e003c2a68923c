#pragma once
// The explicit multimaterial MPM stepper (paper 001 §3.2-3.4), beside the
// implicit Simulation: per-material grid fields (allocated once for the
// classes the scene has), two contact passes, FLIP / PIC / XPIC(m) with the
// multimaterial correction, CFL time step, grid constraints from level sets.
// One step (Eq. numbers of paper 001):
//   1. bin particles by cell; P2G per material of mass and momentum (Eq. 5),
//      volume gradients (Eq. 11, AG) and mass-weighted positions (CP);
//   2. contact nodes: nodes with >= 2 classes; normal and separation per node
//      (LR Eqs. 19-25 or AG Eq. 13 with Eq. 14 / Eq. 16), 3+ nodes lumped (Eq. 50);
//   3. contact pass 1 on p^{alpha 0}: Delta p^alpha, stored as Delta v^alpha (Eq. 26)
//      (skipped with 'contact passes: 1', the paper's single pass (§4.1): then
//      v^alpha = v^{alpha 0}, a USF step 4 strains with uncorrected velocities,
//      and pass 2 finds Delta p^alpha + Delta p^{alpha+}, so that a^alpha of
//      step 7 holds f^{alpha C,0} of Eq. 33; with USF this is unstable in
//      B1(b), see tests/scene/test_explicit_b1_strain.cpp);
//   4. grid constraints; strain update before the forces (setup.strain_update):
//      L = sum_i v_i^alpha (x) G_pi (Eq. 28), F <- (I + h L) F, sigma from F,
//      with h = dt (USF), h = dt/2 (USAVG) or not at all (USL);
//   5. forces per material (Eq. 29) from that sigma,
//      p^{alpha 0+} = p^alpha + f^{alpha 0} dt (Eq. 30);
//   6. contact pass 2: p^{alpha +} (Eq. 31); grid constraints; strain update
//      after the momentum update: Eq. 28 with v^{alpha+} instead of v^alpha,
//      F <- (I + h L+) F, sigma from F, with h = dt (USL) or dt/2 (USAVG);
//      both at the particle positions of step 1 (before step 7 moves them);
//   7. particle update with a^alpha = (v^{alpha+} - v^alpha)/dt (Eqs. 32-34):
//      FLIP: V += dt S a, X += dt S v^+;  PIC: V = S v^+;
//      XPIC(m): V = m S (v^alpha - v*^alpha) + dt S a (Eqs. 41-44);
//      PIC / XPIC positions: X += dt (S v^{alpha+} - dt/2 S a) = dt S (v^alpha + dt/2 a),
//      the lumped grid velocity that also updates F (steps 4, 6), not the XPIC
//      particle velocity (a sharpened field F never sees: positions and F
//      drift apart; single-material XPIC(5) in B1(b) blew up at 16.6 % strain).
// Strain update orderings ('Explicit/strain update'; paper 001 §3.2: codes
// differ, after Eq. 27; with two passes the contact calculations work for any
// of them, after Eq. 34):
//   USF   (default): dt L from v^alpha (Eq. 26) before the forces, which then
//         come from the stress of this step's start velocities;
//   USL:  dt L from v^{alpha+} (Eq. 31) after pass 2; this step's forces come
//         from the stress of the previous step's final velocities;
//   USAVG: dt/2 from v^alpha before the forces, dt/2 from v^{alpha+} after.
// USL and USAVG here are NairnMPM's USL- / USAVG-: the second half uses the
// grid velocities v^{alpha+} as they are, without the second particle-to-grid
// extrapolation of NairnMPM's '+' variants (its default is USAVG+, which
// bfemp does not implement). With one pass, v^alpha = v^{alpha 0}: USF then
// strains with uncorrected velocities only (the paper's second flaw, §4.1);
// USL never uses v^{alpha 0} and USAVG only for half of each increment.
// Contact acts when the materials approach (Eq. 14) AND are touching
// (d_LR < 0, or Eq. 16 for CP; the velocity-only AG method tests approach
// alone); the stick law always acts.
// Threading: Kokkos OpenMP; per-thread duplicated scatter (deterministic for
// a fixed thread count); no allocation per step.
#include <memory>
#include <vector>

#include "explicit/explicit_setup.hpp"
#include "kernels/explicit/fields.hpp"

namespace bfemp {

// What a restart needs to continue bit for bit (host copies, row-major):
// particle positions x and velocities v (np x dim, m and m/s), deformation
// gradients F (np x dim x dim); the stress is recomputed from F, the particle
// size from the scene. Time (s), step count and the fixed-dt steps that
// exceeded the CFL limit.
struct ExplicitState {
  double time = 0;
  long step = 0;
  long over_limit = 0;
  std::vector<double> x, v, F;
};

template <int dim>
class ExplicitSimulation {
 public:
  // Throws std::invalid_argument when a fixed dt exceeds the CFL limit at
  // t = 0 (message names 'Time/dt', its value and the limit), when a particle
  // is outside the grid, or for more than kMaxClasses classes.
  explicit ExplicitSimulation(ExplicitSetup<dim> setup);
  ~ExplicitSimulation();
  ExplicitSimulation(const ExplicitSimulation&) = delete;
  ExplicitSimulation& operator=(const ExplicitSimulation&) = delete;

  static constexpr int kMaxClasses = 32;

  ExplicitReport step();             // throws std::runtime_error when a particle leaves the grid
  ExplicitReport diagnostics() const;  // momentum, kinetic energy, stresses of the current state
  double time() const;
  long step_index() const;
  // CFL * dx / max_p (c_p + |v_p|) of the current state (s). After a step it
  // is the value of the step's closing reduction, kept until the next step or
  // restore(): particle data written through particles()' Views between steps
  // is not seen (nothing in bfemp does that).
  double dt_limit() const;
  long steps_over_limit() const;     // fixed dt steps that exceeded the limit
  int num_classes() const;
  const ExplicitSetup<dim>& setup() const;
  const xmpm::XParticles<dim>& particles() const;
  const GridSpec<dim>& grid() const;

  ExplicitState state() const;
  // Continues from `s` (a state of a simulation built from the same scene).
  // Throws std::invalid_argument naming the array when a size differs from
  // this simulation's particle count.
  void restore(const ExplicitState& s);

  struct Impl;  // implementation detail (explicit_simulation.cpp), public for its kernels

 private:
  // The state's diagnostics; with cmax and bad (the step's closing pass) also
  // max_p (c_p + |v_p|) and the largest index of a particle outside the grid
  // (-1: none), in the same pass.
  ExplicitReport reduce_state(double* cmax, LO* bad) const;
  std::unique_ptr<Impl> impl_;
};

}  // namespace bfemp
