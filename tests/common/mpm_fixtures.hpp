#pragma once
// Small MPM set-ups shared by the scene tests.
#include "common/fem_fixtures.hpp"
#include "mpm/sampling.hpp"

namespace bfemp::fixtures {

// A rectangular block of MPM particles (size w x h, centred at `center`) on a
// grid of spacing dx covering [lo, hi].
inline SimulationSetup<2> mpm_rect_setup(double w, double h, Vec<2> center, double dx, int ppc, Vec<2> lo,
                                         Vec<2> hi, TransferScheme scheme, double E = 1e6, double nu = 0.3,
                                         double rho = 1000.0) {
  SimulationSetup<2> s;
  MaterialParams mp;
  mp.model = MaterialModel::NeoHookean;
  mp.lame = lame_from_young(E, nu);
  mp.density = rho;
  s.materials.push_back(mp);
  SamplingShape shape;
  shape.kind = "box";
  shape.center = {center(0), center(1)};
  shape.size = {w, h};
  MpmSetup<2> m;
  m.particles = sample_particles<2>(shape, dx, ppc, rho, 0, 0);
  m.grid = grid_covering<2>(lo, hi, dx);
  m.scheme = scheme;
  m.body_names = {"block"};
  s.mpm = m;
  s.linear_solver = *linear_solver_schema();
  s.newton.eps_d = 1e-9;
  return s;
}

// A square block (side `side`) on a grid covering [lo, hi]^2.
inline SimulationSetup<2> mpm_block_setup(double side, Vec<2> center, double dx, int ppc, double lo, double hi,
                                          TransferScheme scheme, double E = 1e6, double nu = 0.3,
                                          double rho = 1000.0) {
  return mpm_rect_setup(side, side, center, dx, ppc, Vec<2>(lo, lo), Vec<2>(hi, hi), scheme, E, nu, rho);
}

// A neo-Hookean MPM box (E 1e6, nu 0.3, rho 1000, `ppc` particles per cell,
// APIC) on a grid of spacing dx covering [lo, hi].
inline SimulationSetup<3> cube_setup(Vec<3> center, Vec<3> size, double dx, Vec<3> lo, Vec<3> hi, int ppc = 8) {
  SimulationSetup<3> s;
  MaterialParams mp;
  mp.model = MaterialModel::NeoHookean;
  mp.lame = lame_from_young(1e6, 0.3);
  mp.density = 1000.0;
  s.materials.push_back(mp);
  SamplingShape shape;
  shape.kind = "box";
  shape.center = {center(0), center(1), center(2)};
  shape.size = {size(0), size(1), size(2)};
  MpmSetup<3> m;
  m.particles = sample_particles<3>(shape, dx, ppc, 1000.0, 0, 0);
  m.grid = grid_covering<3>(lo, hi, dx);
  m.scheme = TransferScheme::APIC;
  m.body_names = {"cube"};
  s.mpm = m;
  s.linear_solver = *linear_solver_schema();
  s.newton.eps_d = 1e-9;
  return s;
}

// Mass-weighted mean of particle coordinate c.
template <int dim>
double particle_mean(const Particles<dim>& p, int c) {
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.mass);
  double sm = 0, sx = 0;
  for (std::size_t q = 0; q < m.extent(0); ++q) {
    sm += m(q);
    sx += m(q) * x(q, c);
  }
  return sx / sm;
}

}  // namespace bfemp::fixtures
