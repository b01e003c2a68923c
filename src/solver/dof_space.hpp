#pragma once
// The DOF space of the implicit step: n_nodes nodes with dim DOFs each,
// node-interleaved (DOF = node dim + c; FEM nodes first, then this step's
// active grid nodes, as the simulation numbers them). It owns
//   - the map, the matrix graph and the matrix, built from the couplings the
//     energy terms declare and cached: rebuilt only when the node count or
//     some term's couplings_version() changes, or a term asks mid-solve (a
//     contact pair outside the graph). A rebuilt graph means a new symbolic
//     factorisation; a cached one keeps it (LinearSolver::set_matrix is called
//     only on a rebuild);
//   - the constraints: prescribed DOFs (their rows become p_i = dxp_i, their
//     columns move to the right-hand side in the sink, kernels/dof_sink.hpp)
//     and slip constraints on grid nodes (SlipConstraints), applied here only;
//   - the sink through which every term adds its local (nodes, gradient,
//     Hessian).
// One rank: local ids == DOF ids. The MPI issue gives this object owned and
// overlap maps; everything that depends on the numbering is behind it.
#include <Teuchos_ParameterList.hpp>
#include <cstdint>
#include <vector>

#include "solver/energy_term.hpp"
#include "solver/slip_constraints.hpp"
#include "solver/tpetra_types.hpp"

namespace bfemp {

template <int dim>
class DofSpace {
 public:
  explicit DofSpace(const Teuchos::RCP<const Comm>& comm);

  // Declares the nodes and the terms. Returns true when the map or graph was
  // rebuilt (the matrix is new: its linear solver must be told), false when
  // the cached graph serves (same node count, same terms, same coupling
  // versions).
  bool set_structure(LO n_nodes, const std::vector<const EnergyTerm<dim>*>& terms);
  // Rebuilds the graph from the terms' couplings now (a term's update()
  // found couplings the graph lacks).
  void rebuild();

  LO num_nodes() const { return n_nodes_; }
  std::size_t num_dofs() const { return static_cast<std::size_t>(n_nodes_ < 0 ? 0 : n_nodes_) * dim; }
  Teuchos::RCP<const Map> map() const { return map_; }
  Teuchos::RCP<Matrix> matrix() const { return A_; }
  const std::vector<const EnergyTerm<dim>*>& terms() const { return terms_; }

  // Assembly: zero the matrix values, hand out the sink, close.
  void begin_assembly();
  Sink<dim> sink(double scale, DofView grad, DofView rhs, MaskView prescribed, ConstDofView dx_prescribed) const;
  // Constraint rows: A(i, i) = 1 and rhs(i) = dxp(i) at prescribed DOFs (the
  // caller has added the free rows' own diagonal), then the slip transform
  // A <- P A P + Q, rhs <- P (rhs - A w) + w on slip nodes; fillComplete.
  void end_assembly(MaskView prescribed, ConstDofView dx_prescribed, DofView rhs);

  SlipConstraints<dim>& slip() { return slip_; }
  const SlipConstraints<dim>& slip() const { return slip_; }

  // Counters since construction, and the time of the last rebuild.
  long graph_builds() const { return graph_builds_; }
  // Blocks the last assembly found missing from the graph (0 when the cached
  // graph held every coupling), and how often that forced a rebuild.
  int dropped_blocks() const;
  long missing_block_rebuilds() const { return missing_rebuilds_; }
  void count_missing_block_rebuild() { ++missing_rebuilds_; }
  long graph_reuses() const { return graph_reuses_; }
  double last_graph_build_s() const { return graph_build_s_; }

 private:
  Teuchos::RCP<const Comm> comm_;
  Teuchos::RCP<Teuchos::ParameterList> fill_params_;
  LO n_nodes_ = -1;
  Teuchos::RCP<const Map> map_;
  Teuchos::RCP<Matrix> A_;
  std::vector<const EnergyTerm<dim>*> terms_;
  std::vector<std::uint64_t> versions_;
  SlipConstraints<dim> slip_;
  long graph_builds_ = 0, graph_reuses_ = 0, missing_rebuilds_ = 0;
  Kokkos::View<int, MemSpace> dropped_;
  double graph_build_s_ = 0;
};

}  // namespace bfemp
