#pragma once
// One term of the incremental potential's elastic part (FEM elements, MPM
// particles, barrier and friction contact), seen by the Newton solver through
// value, gradient, PSD Hessian assembly, line-search step bound and the node
// couplings its Hessian needs in the system graph.
// A term computes local quantities only: its assemble() hands each stencil's
// (nodes, gradient, Hessian) to the DOF space's sink (kernels/dof_sink.hpp),
// which applies the constraints and adds into the matrix.
#include <cstdint>
#include <string>
#include <vector>

#include "kernels/deformation_energy.hpp"
#include "solver/stencil_coloring.hpp"
#include "kernels/dof_sink.hpp"
#include "kernels/node_graph.hpp"
#include "solver/tpetra_types.hpp"

namespace bfemp {

using LocalMatrix = Matrix::local_matrix_device_type;
using DofView = Kokkos::View<double*, MemSpace>;
using ConstDofView = Kokkos::View<const double*, MemSpace>;
using MaskView = Kokkos::View<const int*, MemSpace>;
template <int dim>
using Sink = DofSink<dim, LocalMatrix>;

// A sink on a matrix the caller built (tests, benchmarks); the simulation's
// comes from its DofSpace.
template <int dim>
Sink<dim> make_sink(const LocalMatrix& A, double scale, Kokkos::View<double*, MemSpace> grad,
                    Kokkos::View<double*, MemSpace> rhs, Kokkos::View<const int*, MemSpace> prescribed,
                    Kokkos::View<const double*, MemSpace> dx_prescribed) {
  Sink<dim> s;
  s.A = A;
  s.grad = grad;
  s.rhs = rhs;
  s.prescribed = prescribed;
  s.dx_prescribed = dx_prescribed;
  s.scale = scale;
  return s;
}

// The Newton solver takes a step of at most min(1, 0.9 a_max), a_max the
// smallest of the terms' max_step bounds: a bound of kStepBoundCap or more
// gives the full step, like inf.
constexpr double kStepBoundFraction = 0.9;
constexpr double kStepBoundCap = 1.0 / kStepBoundFraction;

template <int dim>
class EnergyTerm {
 public:
  virtual ~EnergyTerm() = default;
  virtual std::string name() const = 0;
  // Declares the node pairs (both orders) the Hessian may touch, as products
  // of stencils (kernels/node_graph.hpp), on the device. Called twice per
  // graph build (the builder's counting and filling passes): it must declare
  // the same both times. Every node's diagonal block is there without it.
  virtual void add_couplings(NodeGraphBuilder& graph) const = 0;
  // Changes whenever the couplings add_couplings would give change (the DOF
  // space rebuilds its graph only then).
  virtual std::uint64_t couplings_version() const { return 0; }
  virtual double energy(ConstDofView x) const = 0;
  // grad += scale * dE/dx
  virtual void gradient(ConstDofView x, double scale, DofView grad) const = 0;
  // Each stencil's local gradient and PSD Hessian into the sink (which scales
  // them and applies the constraints).
  virtual void assemble(ConstDofView x, const Sink<dim>& sink) const = 0;
  // Largest step along p keeping the term defined (inf if unbounded). A term
  // may return inf for any bound beyond kStepBoundCap: the Newton solver
  // steps at most min(1, 0.9 bound), so bounds from 1/0.9 on act alike.
  virtual double max_step(ConstDofView x, ConstDofView p) const = 0;
  // Scatter table (kernels/dof_sink.hpp): the block positions of this term's
  // stencils in A's graph, written into `table` (reallocated only when too
  // small); returns the number of stencils, or 0 when the term finds its
  // blocks itself (contact pairs, which change within a step). The DOF space
  // calls it after each graph build and whenever stencils_version() changes,
  // and hands the table to assemble() in the sink (DofSpace::term_sink).
  virtual long scatter_table(const LocalMatrix& /*A*/, Kokkos::View<int*, MemSpace>& /*table*/) const { return 0; }
  // Changes whenever the nodes of the term's stencils may have changed. A
  // term whose stencil Views are rewritten in place by their owner (the MPM
  // bodies refill theirs every step) must be told (DeformationTerm::
  // set_stencils, MpmElasticityTerm::set_cells) before the next set_structure.
  virtual std::uint64_t stencils_version() const { return 0; }
  // The two calls that change a term's state (contact: its pair set), so
  // the only non-const ones; the evaluations above read that state and may
  // use scratch buffers, but carry no value from one call to the next
  // (statistics aside, such as the contact term's CCD minimum and timings).
  // Called at every Newton iterate x before its assembly (contact: the pairs
  // near x). Returns true when the term now needs couplings the current graph
  // lacks; the solver then rebuilds the graph (add_couplings is asked again).
  virtual bool update(ConstDofView /*x*/) { return false; }
  // Called once the Newton direction p is known, before max_step and the
  // energies of the line search along x + t p, t in [0, 1] (contact: the pairs
  // the segment can bring within reach).
  virtual void prepare_direction(ConstDofView /*x*/, ConstDofView /*p*/) {}
};

// Elasticity over deformation stencils (FEM elements or MPM particles).
template <int dim, int nv>
class DeformationTerm : public EnergyTerm<dim> {
 public:
  DeformationTerm(std::string name, DeformationStencils<dim, nv> s) : name_(std::move(name)), s_(s) {}
  std::string name() const override { return name_; }
  void set_stencils(DeformationStencils<dim, nv> s) {
    s_ = s;
    ++stencils_version_;
  }
  std::uint64_t stencils_version() const override { return stencils_version_; }
  long scatter_table(const LocalMatrix& A, Kokkos::View<int*, MemSpace>& table) const override {
    const auto nodes = s_.nodes;
    scatter_positions<dim>(A.graph, s_.size(), nv, KOKKOS_LAMBDA(const long q, const int a) { return nodes(q, a); },
                           table);
    return s_.size();
  }
  const DeformationStencils<dim, nv>& stencils() const { return s_; }

  // Each stencil's nodes, all pairs.
  void add_couplings(NodeGraphBuilder& graph) const override {
    const auto nodes = s_.nodes;
    graph.add_cliques(s_.size(), nv, KOKKOS_LAMBDA(const long q, const int a) { return nodes(q, a); });
  }
  double energy(ConstDofView x) const override { return deformation_energy(s_, x); }
  void gradient(ConstDofView x, double scale, DofView grad) const override {
    deformation_gradient(s_, x, scale, grad);
  }
  // Colored (set_coloring): color by color, without atomics; otherwise all
  // stencils at once with atomic adds. On one thread: all stencils in index
  // order without atomics (no other thread to race with; the colors' jumps
  // through the mesh cost 10 % at 1 thread, perf/README.md "Assembly per stencil").
  void assemble(ConstDofView x, const Sink<dim>& sink) const override {
    Sink<dim> plain = sink;
    plain.atomic = false;
    if (ExecSpace().concurrency() == 1) {
      deformation_assemble(s_, x, plain, project_ && sink.project);
      return;
    }
    if (coloring_.colors() == 0) {
      deformation_assemble(s_, x, sink, project_ && sink.project);
      return;
    }
    // the stencils of one color share no node
    for (int c = 0; c < coloring_.colors(); ++c)
      deformation_assemble(s_, x, plain, project_ && sink.project, coloring_.order, coloring_.color_start[c],
                           coloring_.color_start[c + 1]);
  }
  // Stencils grouped so that none of one color shares a node (solver/stencil_coloring.hpp).
  void set_coloring(StencilColoring c) { coloring_ = std::move(c); }
  const StencilColoring& coloring() const { return coloring_; }
  // false: assemble the exact (unprojected) Hessian, for derivative tests.
  void set_projection(bool project) { project_ = project; }
  bool projection() const { return project_; }
  double max_step(ConstDofView x, ConstDofView p) const override {
    return deformation_max_step(s_, x, p, kStepBoundCap);
  }

 private:
  std::string name_;
  DeformationStencils<dim, nv> s_;
  bool project_ = true;
  StencilColoring coloring_;
  std::uint64_t stencils_version_ = 0;
};

}  // namespace bfemp
