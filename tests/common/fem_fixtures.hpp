#pragma once
// Small FEM set-ups shared by the scene tests.
#include <Tpetra_Core.hpp>
#include <cmath>

#include "io/shape_mesher.hpp"
#include "materials/lame.hpp"
#include "sim/simulation.hpp"
#include "solver/linear_solver.hpp"

namespace bfemp::fixtures {

// A block [0,1]^dim (height `height` along y) meshed with element size h.
template <int dim>
SimulationSetup<dim> block_setup(double h, double E = 1e5, double nu = 0.3, double rho = 1000.0,
                          double height = 1.0, const std::string& solver = "Cholmod") {
  SimulationSetup<dim> s;
  ShapeSpec spec;
  spec.kind = dim == 2 ? "rectangle" : "box";
  spec.center = dim == 2 ? std::vector<double>{0.5, height / 2} : std::vector<double>{0.5, height / 2, 0.5};
  spec.size = dim == 2 ? std::vector<double>{1.0, height} : std::vector<double>{1.0, height, 1.0};
  spec.element_size = h;
  FemBodyInput body;
  body.name = "block";
  body.mesh = mesh_shape(spec, dim);
  s.bodies.push_back(body);
  MaterialParams mp;
  mp.model = MaterialModel::NeoHookean;
  mp.lame = lame_from_young(E, nu);
  mp.density = rho;
  s.materials.push_back(mp);
  s.linear_solver = *linear_solver_schema();
  s.linear_solver.set("type", solver);
  s.newton.eps_d = 1e-9;
  return s;
}

// Prescribes the node set `set` of body 0 with the given segments.
template <int dim>
void prescribe(SimulationSetup<dim>& s, const std::string& set, std::vector<MotionSegment> segments = {MotionSegment{}}) {
  PrescribedMotion m;
  m.name = set;
  for (long long n : s.bodies[0].mesh.node_sets.at(set)) m.nodes.push_back(static_cast<LO>(n));
  m.segments = std::move(segments);
  s.motions.push_back(m);
}

inline Teuchos::RCP<const Comm> comm() { return Tpetra::getDefaultComm(); }

// Mass-weighted mean of component c of a node-interleaved host copy.
template <int dim, class XView, class MView>
double mass_mean(const XView& x, const MView& node_mass, int c) {
  double sm = 0, sx = 0;
  for (std::size_t i = 0; i < node_mass.extent(0); ++i) {
    sm += node_mass(i);
    sx += node_mass(i) * x(i * dim + c);
  }
  return sx / sm;
}

using HostPositions = Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace>;

// The MPM particles' positions, copied to the host (a copy: on an OpenMP
// build a host mirror of the device View would alias it and move on).
template <int dim>
HostPositions particle_positions(const Simulation<dim>& sim) {
  const auto& px = sim.mpm()->particles().x;
  HostPositions x("x", px.extent(0), px.extent(1));
  Kokkos::deep_copy(x, px);
  return x;
}

// max |a - b| over every entry (same extents).
inline double max_abs_difference(const HostPositions& a, const HostPositions& b) {
  double worst = 0;
  for (std::size_t q = 0; q < a.extent(0); ++q)
    for (std::size_t c = 0; c < a.extent(1); ++c) worst = std::fmax(worst, std::fabs(a(q, c) - b(q, c)));
  return worst;
}

}  // namespace bfemp::fixtures
