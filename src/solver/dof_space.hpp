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
//     Hessian), and each term's scatter table (kernels/dof_sink.hpp: its
//     stencils' block positions in the graph), refreshed after a graph build
//     and when the term's stencils_version() changes; term_sink() hands a
//     term the sink with its table.
// One rank (no partition): local ids == DOF ids.
// Distributed (set_partition): the local nodes are this rank's owned nodes
// (first) and its ghosts, each with a global node id. Every local View (x,
// gradient, rhs, direction) covers all local nodes; the terms assemble into
// an overlap matrix (rows and columns: all local DOFs, local column ids ==
// local DOF ids, so the sink is the same); a value exchange planned with the
// graph (OverlapMatrixSum) sums the overlap matrices into the owned matrix and
// an Export with ADD the right-hand sides into the owned one the linear
// solver sees; the
// solution comes back to the ghosts with one Import. Constraint rows are
// written once, on the owned side. The owned nodes may come first (n_owned)
// or lie anywhere among the local ones (a mask: MPM grid nodes beside a
// replicated FEM mesh). Slip constraints are built on every local node
// (ghosts too) and transformed on each rank's overlap part
// (SlipConstraints::transform_system with the owned mask).
#include <Teuchos_ParameterList.hpp>
#include <Tpetra_Export_decl.hpp>
#include <Tpetra_Import_decl.hpp>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "solver/energy_term.hpp"
#include "solver/overlap_matrix_sum.hpp"
#include "solver/slip_constraints.hpp"
#include "solver/tpetra_types.hpp"

namespace bfemp {

template <int dim>
class DofSpace {
 public:
  explicit DofSpace(const Teuchos::RCP<const Comm>& comm);

  // Distributed numbering: local node a (0 <= a < global_nodes.size()) is
  // global node global_nodes[a]; the first n_owned are owned here, each global
  // node is owned by exactly one rank. Takes effect at the next
  // set_structure (whose n_nodes must be global_nodes.size()).
  void set_partition(std::vector<GO> global_nodes, LO n_owned);
  // The same with the owned nodes anywhere among the local ones (owned[a] !=
  // 0: local node a is owned here). The owned map lists them in local order.
  void set_partition(std::vector<GO> global_nodes, const std::vector<char>& owned);
  bool distributed() const { return n_owned_ >= 0; }
  // Distributed: 1 at the local DOFs this rank owns, and the local DOF of
  // each owned-map row (after set_structure).
  Kokkos::View<const int*, MemSpace> owned_mask() const { return owned_mask_; }
  Kokkos::View<const LO*, MemSpace> owned_dofs() const { return owned_dofs_; }
  // Owned nodes and DOFs of this rank (all nodes without a partition).
  LO num_owned_nodes() const { return n_owned_ >= 0 ? n_owned_ : n_nodes_; }
  std::size_t num_owned_dofs() const { return static_cast<std::size_t>(num_owned_nodes() < 0 ? 0 : num_owned_nodes()) * dim; }

  // Declares the nodes and the terms. Returns true when the map or graph was
  // rebuilt (the matrix is new: its linear solver must be told), false when
  // the cached graph serves (same node count, same terms, same coupling
  // versions).
  bool set_structure(LO n_nodes, const std::vector<EnergyTerm<dim>*>& terms);
  // Rebuilds the graph from the terms' couplings now (a term's update()
  // found couplings the graph lacks), counted under `cause`.
  void rebuild(const std::string& cause = "couplings found mid-solve");

  LO num_nodes() const { return n_nodes_; }
  std::size_t num_dofs() const { return static_cast<std::size_t>(n_nodes_ < 0 ? 0 : n_nodes_) * dim; }
  // The linear system's (owned, one-to-one) DOF map and matrix; the overlap
  // map of all local DOFs (== map() without a partition).
  Teuchos::RCP<const Map> map() const { return map_; }
  Teuchos::RCP<const Map> overlap_map() const { return overlap_map_.is_null() ? map_ : overlap_map_; }
  Teuchos::RCP<Matrix> matrix() const { return A_; }
  // The terms; only a non-const DOF space (the Newton solver's) hands them
  // out to be updated. The const ones are also what the graph builder sees.
  const std::vector<EnergyTerm<dim>*>& terms() { return terms_; }
  std::vector<const EnergyTerm<dim>*> terms() const { return {terms_.begin(), terms_.end()}; }

  // Assembly: zero the matrix values, hand out the sink, close.
  void begin_assembly();
  Sink<dim> sink(double scale, DofView grad, DofView rhs, MaskView prescribed, ConstDofView dx_prescribed) const;
  // `sink` with the scatter table of terms()[k] (none for a term without
  // one, e.g. contact); throws when a tabled term's stencils changed after
  // the last set_structure / rebuild.
  Sink<dim> term_sink(const Sink<dim>& sink, std::size_t k) const;
  // false: no scatter tables (every block found by bisection; tests compare
  // the two). Takes effect at the next set_structure or rebuild.
  void use_scatter_tables(bool on) { use_tables_ = on; }
  long scatter_table_builds() const { return table_builds_; }
  double scatter_table_seconds() const { return table_s_; }
  // Constraint rows: A(i, i) = 1 and rhs(i) = dxp(i) at prescribed DOFs (the
  // caller has added the free rows' own diagonal), then the slip transform
  // A <- P A P + Q, rhs <- P (rhs - A w) + w on slip nodes; fillComplete.
  // Then copies (1 rank) or exports with ADD (distributed) rhs into b (on
  // map()); distributed: the owned matrix is the sum of all ranks' overlap
  // matrices, then its constraint rows are written.
  void end_assembly(MaskView prescribed, ConstDofView dx_prescribed, DofView rhs, Vector& b);
  // The owned vector's values at every local DOF (owned and ghost).
  void to_local(const Vector& owned, DofView local);
  // Distributed: each DOF's values summed over the ranks that hold it, the
  // sum at every holder (a term's gradient assembled rank by rank). No-op on
  // one rank. After set_structure.
  void sum_shared(DofView local);

  SlipConstraints<dim>& slip() { return slip_; }
  const SlipConstraints<dim>& slip() const { return slip_; }

  // Counters since construction, and the time of the last rebuild.
  long graph_builds() const { return graph_builds_; }
  // Blocks the last assembly found missing from the graph on any rank (0 when
  // the cached graph held every coupling), and how often that forced a rebuild.
  int dropped_blocks() const;
  long missing_block_rebuilds() const { return missing_rebuilds_; }
  void count_missing_block_rebuild() { ++missing_rebuilds_; }
  long graph_reuses() const { return graph_reuses_; }
  // Why the graph was built, with counts, in order of first occurrence:
  // "first", "nodes" (the node set changed), a term's name (its couplings
  // changed), "terms" (another term list), "another rank" (distributed: only
  // elsewhere), or rebuild()'s cause.
  const std::vector<std::pair<std::string, long>>& build_causes() const { return causes_; }
  double last_graph_build_s() const { return graph_build_s_; }
  // All graph builds since construction on this rank (graph, matrices, the
  // exchange plan between ranks, set_matrix).
  double graph_build_seconds() const { return graph_build_total_s_; }
  // Seconds since construction on this rank in the exchanges between ranks:
  // end_assembly's sum of the overlap matrix and right-hand side into the
  // owned ones, and to_local's import of owned values into the overlap
  // (waiting for the other ranks included). 0 on one rank.
  double exchange_seconds() const { return exchange_s_; }
  // Bytes this rank has sent in those exchanges since construction (matrix
  // values and vector entries, 8 bytes each).
  double exchange_bytes() const { return exchange_bytes_; }

 private:
  Teuchos::RCP<const Comm> comm_;
  Teuchos::RCP<Teuchos::ParameterList> fill_params_;
  LO n_nodes_ = -1;
  std::vector<GO> global_nodes_;  // distributed: global id of each local node
  std::vector<char> owned_nodes_; // distributed: owned flag of each local node
  LO n_owned_ = -1;               // distributed: owned nodes
  Kokkos::View<int*, MemSpace> owned_mask_;  // per local DOF
  Kokkos::View<LO*, MemSpace> owned_dofs_;   // per owned-map row: its local DOF
  bool maps_stale_ = false;
  Teuchos::RCP<const Map> map_, overlap_map_;
  Teuchos::RCP<Matrix> A_, A_overlap_;  // A_overlap_: the terms' sink (distributed)
  Teuchos::RCP<const Tpetra::Export<LO, GO, Node>> export_;
  std::unique_ptr<OverlapMatrixSum> matrix_sum_;  // A_overlap_ of all ranks -> A_, planned per graph
  Teuchos::RCP<const Tpetra::Import<LO, GO, Node>> import_;
  Teuchos::RCP<Vector> rhs_overlap_, x_overlap_, owned_tmp_;  // owned_tmp_: sum_shared
  Kokkos::View<LO*, MemSpace> diag_col_;  // distributed: column id of each owned row's diagonal
  void build_maps();
  std::vector<EnergyTerm<dim>*> terms_;
  std::vector<std::uint64_t> versions_;
  // Scatter tables, per term: positions, stencil count, stencils_version().
  struct Table {
    Kokkos::View<int*, MemSpace> positions;
    long stencils = 0;
    std::uint64_t version = 0;
    bool built = false;
  };
  std::vector<Table> tables_;
  bool use_tables_ = true;
  long table_builds_ = 0;
  double table_s_ = 0;
  // Refreshes the tables of terms whose stencils changed (all after a graph build).
  void refresh_tables(bool graph_rebuilt);
  SlipConstraints<dim> slip_;
  long graph_builds_ = 0, graph_reuses_ = 0, missing_rebuilds_ = 0;
  std::vector<std::pair<std::string, long>> causes_;
  void count_cause(const std::string& cause);
  Kokkos::View<int, MemSpace> dropped_;
  double graph_build_s_ = 0, graph_build_total_s_ = 0;
  double exchange_s_ = 0, exchange_bytes_ = 0;
};

}  // namespace bfemp
