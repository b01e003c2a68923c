#pragma once
// Set-up, settings and per-step report of the explicit multimaterial MPM
// stepper (paper 001 §3.2). A scene with 'Solver: explicit' builds one of
// these (io/scene_explicit.cpp); the stepper builds no Newton solver, Tpetra
// matrix or contact hash.
//
// Material classes: each scene material used by an MPM body is one class with
// its own grid velocity field; bodies sharing a material share a field (the
// single-material mode of the paper's comparisons). Contact laws are given per
// unordered pair of classes.
#include <array>
#include <string>
#include <vector>

#include "kernels/explicit/contact_law.hpp"
#include "kernels/explicit/logistic_regression.hpp"
#include "materials/hyperelastic_kg.hpp"
#include "materials/lame.hpp"
#include "kernels/mpm/grid.hpp"
#include "kernels/level_set.hpp"
#include "kernels/mpm/particles.hpp"

namespace bfemp {

enum class XShape { UGimp, QuadraticBSpline };
enum class XUpdate { FLIP, PIC, XPIC };
enum class XNormals { LR, AG };
// AG separation: Velocity (Eq. 14 alone) or CP (Eq. 16 with delta_c).
enum class XSeparation { Velocity, CP };
// When F and sigma are updated (Eq. 28 with v^alpha or v^{alpha+}): before the
// forces (USF), after the momentum update (USL), or half of the increment each
// (USAVG). See explicit_simulation.hpp.
enum class XStrainUpdate { USF, USL, USAVG };
enum class XModel : int { HyperelasticKG = 0, NeoHookean = 1, Linear = 2 };

struct XMaterial {
  XModel model = XModel::HyperelasticKG;
  HyperelasticKG kg;    // Eq. 18 (K, G in Pa)
  LameParameters lame;  // neo-Hookean / linear
  double density = 0;   // rest density, kg/m^3 (kg/m^2 in 2D)
  // P-wave modulus at rest (Pa): K + 4G/3 or lambda + 2 mu.
  double wave_modulus() const { return model == XModel::HyperelasticKG ? kg.K + 4.0 * kg.G / 3.0 : lame.lambda + 2.0 * lame.mu; }
};

template <int dim>
struct ExplicitSetup {
  GridSpec<dim> grid;
  Particles<dim> particles;  // particles.material = class index (0..M-1)
  std::vector<std::string> body_names, class_names;
  std::vector<XMaterial> materials;  // per class
  std::vector<LevelSet> level_sets;  // grid constraints: no-slip all components, slip the normal one
  std::array<double, 3> gravity{0, 0, 0};
  XShape shape = XShape::UGimp;
  XUpdate update = XUpdate::FLIP;
  int xpic_order = 5;
  bool xpic_corrected = true;  // false: the uncorrected XPIC (no Delta v^alpha term, v^{alpha 0})
  int contact_passes = 2;      // 1: the single-pass variant (pass 2 only)
  XStrainUpdate strain_update = XStrainUpdate::USF;
  XNormals normals = XNormals::LR;
  XSeparation separation = XSeparation::Velocity;  // AG only
  double cp_delta = 0.8;                           // CP: delta_c in cells
  xmpm::LRSettings lr;
  std::vector<xmpm::LawParams> laws;  // M * M, symmetric; empty: Coulomb mu = 0 for all pairs
  double cfl = 0.5;
  double fixed_dt = 0;    // > 0: this dt (refused above the CFL limit at t = 0)
  int stress_body = -1;   // body whose mean axial stress is reported (-1: all particles)
  int stress_axis = dim - 1;
};

struct ExplicitReport {
  long step = 0;
  double time = 0, dt = 0, dt_limit = 0;
  long contact_nodes = 0;  // nodes with two or more classes
  long multi_nodes = 0;    // nodes with three or more classes
  long active_nodes = 0;   // nodes where a law changed momenta (pass 2)
  double lr_iter_mean = 0;
  int lr_iter_max = 0;
  double stress_body = 0;  // mean sigma_axis,axis of the stress body's particles (Pa)
  double stress_all = 0;   // the same over all particles
  std::array<double, 3> momentum{0, 0, 0};
  double kinetic = 0;
  double p2g_s = 0, contact_s = 0, stress_s = 0, g2p_s = 0, step_s = 0;
};

}  // namespace bfemp
