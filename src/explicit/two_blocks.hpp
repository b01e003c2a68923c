#pragma once
// The two-block scene of paper 001 Fig. 2A / VALIDATION §B1 as an
// ExplicitSetup (used by the validation tests and perf/bench_explicit; the
// same scene as inputs/b1_*.yaml): plane strain, two blocks of width 40 mm,
// the lower on y in [0, lower_top], the upper on [upper_bottom, upper_top];
// 5 mm cells, 4 particles per cell, uGIMP, Eq. 18 with K = 2450 MPa,
// G = 940 MPa, density 1000 kg/m^3 (the paper gives none); bottom nodes
// (y <= 0) fixed, top pushed down by a slip piston at 0.05 % of the wave
// speed c = sqrt((K + 4G/3) / rho) = 1924 m/s (0.962 m/s). Coulomb mu = 0.2.
// With `upper_moving` the upper block starts at the piston speed (no stress
// wave before contact, so the contact time is exactly gap / v).
#include <cmath>
#include <vector>

#include "explicit/explicit_setup.hpp"
#include "mpm/sampling.hpp"

namespace bfemp {

struct TwoBlocks {
  double width = 0.040, lower_top = 0.050, upper_bottom = 0.050, upper_top = 0.100;  // m
  double dx = 0.005;
  int ppc = 4;
  bool two_classes = true;    // false: one material class (single-material mode)
  bool upper_moving = false;  // upper block starts at the piston velocity
  double speed_fraction = 5e-4;
  // The piston's grip (m): it holds the grid nodes at y >= top(t) - grip.
  // 0: the nodes at or above the moving face only (a level-set wall). dx: the
  // nodes a rigid particle layer on the top face (same particles per cell)
  // reaches with its GIMP support, so the top particles never leave the
  // support of held nodes (with grip 0 they do in the last ~0.5 % strain
  // before each node-row crossing, and the next row then snaps on).
  double piston_grip = 0.0;
  double K = 2450e6, G = 940e6, density = 1000.0;
  xmpm::LawParams law{xmpm::ContactLaw::Coulomb, 0.2};

  double wave_speed() const { return std::sqrt((K + 4.0 * G / 3.0) / density); }
  double piston_speed() const { return speed_fraction * wave_speed(); }

  ExplicitSetup<2> setup() const {
    ExplicitSetup<2> s;
    s.grid.dx = dx;
    s.grid.origin = Vec<2>(-4 * dx, -2 * dx);
    s.grid.n_cells = {static_cast<int>(std::lround(width / dx)) + 8,
                      static_cast<int>(std::ceil(upper_top / dx - 1e-9)) + 4};
    XMaterial m;
    m.model = XModel::HyperelasticKG;
    m.kg = {K, G};
    m.density = density;
    s.materials = two_classes ? std::vector<XMaterial>{m, m} : std::vector<XMaterial>{m};
    s.class_names = two_classes ? std::vector<std::string>{"lower", "upper"} : std::vector<std::string>{"block"};
    s.body_names = {"lower", "upper"};
    std::vector<Particles<2>> parts;
    for (int b = 0; b < 2; ++b) {
      SamplingShape sh;
      sh.kind = "box";
      const double y0 = b == 0 ? 0.0 : upper_bottom, y1 = b == 0 ? lower_top : upper_top;
      sh.center = {0.5 * width, 0.5 * (y0 + y1)};
      sh.size = {width, y1 - y0};
      Particles<2> p = sample_particles<2>(sh, dx, ppc, density, b, two_classes ? b : 0);
      if (b == 1 && upper_moving) Kokkos::deep_copy(Kokkos::subview(p.v, Kokkos::ALL(), 1), -piston_speed());
      parts.push_back(p);
    }
    s.particles = concatenate(parts);
    LevelSet bottom;
    bottom.name = "bottom";
    bottom.point = {0, 0, 0};
    bottom.normal = {0, 1, 0};
    LevelSet piston;
    piston.name = "piston";
    piston.slip = false;  // no-slip like the fixed bottom (a slip piston ejects the top corner particles near 19 % strain)
    piston.point = {0, upper_top - piston_grip, 0};
    piston.normal = {0, -1, 0};
    piston.velocity = {0, -piston_speed(), 0};
    s.level_sets = {bottom, piston};
    const int M = two_classes ? 2 : 1;
    s.laws.assign(M * M, law);
    s.stress_body = -1;
    s.stress_axis = 1;
    return s;
  }
};

}  // namespace bfemp
