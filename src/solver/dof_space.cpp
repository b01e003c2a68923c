#include "solver/dof_space.hpp"

#include <Kokkos_Timer.hpp>
#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Export.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_Vector.hpp>
#include <algorithm>
#include <stdexcept>
#include <utility>

#include "solver/dof_graph.hpp"

namespace bfemp {

template <int dim>
DofSpace<dim>::DofSpace(const Teuchos::RCP<const Comm>& comm) : comm_(comm), dropped_("dof_dropped_blocks") {
  fill_params_ = Teuchos::parameterList();
  fill_params_->set("No Nonlocal Changes", true);
}

template <int dim>
void DofSpace<dim>::set_partition(std::vector<GO> global_nodes, LO n_owned) {
  if (n_owned < 0 || n_owned > static_cast<LO>(global_nodes.size()))
    throw std::invalid_argument("DofSpace::set_partition: n_owned outside [0, local nodes]");
  std::vector<char> owned(global_nodes.size(), 0);
  for (LO a = 0; a < n_owned; ++a) owned[a] = 1;
  set_partition(std::move(global_nodes), owned);
}

template <int dim>
void DofSpace<dim>::set_partition(std::vector<GO> global_nodes, const std::vector<char>& owned) {
  if (owned.size() != global_nodes.size())
    throw std::invalid_argument("DofSpace::set_partition: an owned flag per local node expected");
  // The same nodes as before (an MPM step whose active set did not change):
  // the maps, graph and factorisation may serve again.
  if (n_owned_ >= 0 && global_nodes == global_nodes_ && owned == owned_nodes_) return;
  global_nodes_ = std::move(global_nodes);
  owned_nodes_ = owned;
  n_owned_ = static_cast<LO>(std::count_if(owned.begin(), owned.end(), [](char c) { return c != 0; }));
  maps_stale_ = true;
}

template <int dim>
void DofSpace<dim>::build_maps() {
  using gsize = Tpetra::global_size_t;
  const gsize invalid = Teuchos::OrdinalTraits<gsize>::invalid();
  std::vector<GO> owned, all(global_nodes_.size() * dim);
  owned.reserve(static_cast<std::size_t>(n_owned_) * dim);
  const std::size_t nl = global_nodes_.size() * dim;
  owned_mask_ = Kokkos::View<int*, MemSpace>("dof_owned_mask", nl);
  owned_dofs_ = Kokkos::View<LO*, MemSpace>("dof_owned_dofs", static_cast<std::size_t>(n_owned_) * dim);
  auto mask = Kokkos::create_mirror_view(owned_mask_);
  auto od = Kokkos::create_mirror_view(owned_dofs_);
  for (std::size_t a = 0; a < global_nodes_.size(); ++a)
    for (int c = 0; c < dim; ++c) {
      all[a * dim + c] = global_nodes_[a] * dim + c;
      mask(a * dim + c) = owned_nodes_[a] ? 1 : 0;
      if (!owned_nodes_[a]) continue;
      od(owned.size()) = static_cast<LO>(a * dim + c);
      owned.push_back(global_nodes_[a] * dim + c);
    }
  Kokkos::deep_copy(owned_mask_, mask);
  Kokkos::deep_copy(owned_dofs_, od);
  map_ = Teuchos::rcp(new Map(invalid, Teuchos::ArrayView<const GO>(owned), 0, comm_));
  overlap_map_ = Teuchos::rcp(new Map(invalid, Teuchos::ArrayView<const GO>(all), 0, comm_));
  export_ = Teuchos::rcp(new Tpetra::Export<LO, GO, Node>(overlap_map_, map_));
  import_ = Teuchos::rcp(new Tpetra::Import<LO, GO, Node>(map_, overlap_map_));
  rhs_overlap_ = Teuchos::rcp(new Vector(overlap_map_));
  x_overlap_ = Teuchos::rcp(new Vector(overlap_map_));
  owned_tmp_ = Teuchos::rcp(new Vector(map_));
  maps_stale_ = false;
}

template <int dim>
bool DofSpace<dim>::set_structure(LO n_nodes, const std::vector<EnergyTerm<dim>*>& terms) {
  std::vector<std::uint64_t> versions;
  versions.reserve(terms.size());
  for (const auto* t : terms) versions.push_back(t->couplings_version());
  if (distributed() && n_nodes != static_cast<LO>(global_nodes_.size()))
    throw std::invalid_argument("DofSpace::set_structure: " + std::to_string(n_nodes) +
                                " nodes, but the partition has " + std::to_string(global_nodes_.size()));
  bool same = !A_.is_null() && !maps_stale_ && n_nodes == n_nodes_ && terms == terms_ && versions == versions_;
  std::string cause = "another rank";  // what changed here, if anything
  if (A_.is_null()) {
    cause = "first";
  } else if (maps_stale_ || n_nodes != n_nodes_) {
    cause = "nodes";
  } else if (terms != terms_) {
    cause = "terms";
  } else {
    for (std::size_t k = 0; k < terms.size(); ++k)
      if (versions[k] != versions_[k]) {
        cause = terms[k]->name();
        break;
      }
  }
  if (distributed()) {  // maps and graph are built collectively: every rank decides alike
    const int mine[2] = {same ? 0 : 1, maps_stale_ || map_.is_null() ? 1 : 0};
    int any[2] = {0, 0};
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, 2, mine, any);
    same = any[0] == 0;
    maps_stale_ = any[1] != 0;
  }
  terms_ = terms;
  versions_ = std::move(versions);
  if (same) {
    ++graph_reuses_;
    refresh_tables(false);
    return false;
  }
  if (distributed()) {
    n_nodes_ = n_nodes;
    if (maps_stale_ || map_.is_null()) build_maps();
  } else if (n_nodes != n_nodes_) {
    map_ = Teuchos::rcp(new Map(static_cast<Tpetra::global_size_t>(n_nodes) * dim, 0, comm_));
    n_nodes_ = n_nodes;
  }
  rebuild(cause);
  return true;
}

template <int dim>
void DofSpace<dim>::count_cause(const std::string& cause) {
  for (auto& c : causes_)
    if (c.first == cause) {
      ++c.second;
      return;
    }
  causes_.emplace_back(cause, 1);
}

template <int dim>
void DofSpace<dim>::rebuild(const std::string& cause) {
  count_cause(cause);
  Kokkos::Timer timer;
  if (!distributed()) {
    A_ = Teuchos::rcp(new Matrix(build_dof_graph<dim>(std::as_const(*this).terms(), n_nodes_, map_)));
    A_->fillComplete();
  } else {
    // Overlap graph (local ids), then the owned graph: each owned row holds the
    // union of its rows on all ranks (built with the value-sum plan).
    auto G_ov = build_dof_graph<dim>(std::as_const(*this).terms(), n_nodes_, overlap_map_, map_);
    matrix_sum_ = std::make_unique<OverlapMatrixSum>(*G_ov, *export_);
    A_overlap_ = Teuchos::rcp(new Matrix(G_ov));
    A_overlap_->fillComplete(map_, map_);
    A_ = Teuchos::rcp(new Matrix(matrix_sum_->graph()));
    A_->fillComplete(map_, map_);
    const LO n_own = static_cast<LO>(map_->getNodeNumElements());
    diag_col_ = Kokkos::View<LO*, MemSpace>("dof_diag_col", n_own);
    auto dh = Kokkos::create_mirror_view(diag_col_);
    const auto col = A_->getColMap();
    for (LO i = 0; i < n_own; ++i) dh(i) = col->getLocalElement(map_->getGlobalElement(i));
    Kokkos::deep_copy(diag_col_, dh);
  }
  versions_.clear();
  for (const auto* t : terms_) versions_.push_back(t->couplings_version());
  ++graph_builds_;
  graph_build_s_ = timer.seconds();
  graph_build_total_s_ += graph_build_s_;
  refresh_tables(true);
}

template <int dim>
void DofSpace<dim>::refresh_tables(bool graph_rebuilt) {
  if (tables_.size() != terms_.size()) {
    tables_.resize(terms_.size());
    graph_rebuilt = true;
  }
  const auto lcl = (distributed() ? *A_overlap_ : *A_).getLocalMatrixDevice();
  for (std::size_t k = 0; k < terms_.size(); ++k) {
    Table& t = tables_[k];
    const std::uint64_t v = terms_[k]->stencils_version();
    if (!use_tables_) {
      t = Table{};
      continue;
    }
    if (!graph_rebuilt && t.built && v == t.version) continue;
    Kokkos::Timer timer;
    t.stencils = terms_[k]->scatter_table(lcl, t.positions);
    t.version = v;
    t.built = true;
    Kokkos::fence();
    if (t.stencils > 0) {
      ++table_builds_;
      table_s_ += timer.seconds();
    }
  }
}

template <int dim>
Sink<dim> DofSpace<dim>::term_sink(const Sink<dim>& sink, std::size_t k) const {
  Sink<dim> s = sink;
  if (k >= tables_.size() || tables_[k].stencils == 0) {
    s.table_stencils = 0;
    return s;
  }
  if (terms_[k]->stencils_version() != tables_[k].version)
    throw std::logic_error("DofSpace::term_sink: the stencils of term '" + terms_[k]->name() +
                           "' changed after the scatter table was built (call set_structure first)");
  s.table = tables_[k].positions;
  s.table_stencils = tables_[k].stencils;
  return s;
}

template <int dim>
void DofSpace<dim>::begin_assembly() {
  Kokkos::deep_copy(dropped_, 0);
  Matrix& A = distributed() ? *A_overlap_ : *A_;
  A.resumeFill();
  A.setAllToScalar(0.0);
}

template <int dim>
Sink<dim> DofSpace<dim>::sink(double scale, DofView grad, DofView rhs, MaskView prescribed,
                              ConstDofView dx_prescribed) const {
  const Matrix& A = distributed() ? *A_overlap_ : *A_;
  Sink<dim> s = make_sink<dim>(A.getLocalMatrixDevice(), scale, grad, rhs, prescribed, dx_prescribed);
  s.dropped = dropped_;
  return s;
}

template <int dim>
int DofSpace<dim>::dropped_blocks() const {
  int n = 0;
  Kokkos::deep_copy(n, dropped_);
  if (distributed()) {
    int g = 0;
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, n, Teuchos::outArg(g));
    n = g;
  }
  return n;
}

template <int dim>
void DofSpace<dim>::end_assembly(MaskView prescribed, ConstDofView dx_prescribed, DofView rhs, Vector& b) {
  if (!distributed()) {
    auto lcl = A_->getLocalMatrixDevice();
    Kokkos::parallel_for(
        "dof_space_prescribed_rows", Kokkos::RangePolicy<ExecSpace>(0, num_dofs()), KOKKOS_LAMBDA(const LO i) {
          if (!prescribed(i)) return;
          const double one = 1.0;
          lcl.replaceValues(i, &i, 1, &one, false, false);
          rhs(i) = dx_prescribed(i);
        });
    slip_.transform_system(lcl, rhs);
    A_->fillComplete(fill_params_);
    auto bv = Kokkos::subview(b.getLocalViewDevice(Tpetra::Access::OverwriteAll), Kokkos::ALL(), 0);
    Kokkos::deep_copy(bv, rhs);
    return;
  }
  // The slip transform on this rank's part (Q and w at owned nodes), then
  // sum the overlap matrix and rhs into the owned ones.
  slip_.transform_system(A_overlap_->getLocalMatrixDevice(), rhs, owned_mask_);
  A_overlap_->fillComplete(map_, map_, fill_params_);
  Kokkos::Timer timer;
  {
    auto rv = Kokkos::subview(rhs_overlap_->getLocalViewDevice(Tpetra::Access::OverwriteAll), Kokkos::ALL(), 0);
    Kokkos::deep_copy(rv, rhs);
  }
  b.putScalar(0.0);
  b.doExport(*rhs_overlap_, *export_, Tpetra::ADD);
  A_->resumeFill();
  matrix_sum_->sum(*A_overlap_, *A_);
  exchange_s_ += timer.seconds();
  exchange_bytes_ += 8.0 * (static_cast<double>(matrix_sum_->sent_values()) + export_->getNumExportIDs());
  // Constraint rows on the owned side (owned row r is local DOF owned_dofs(r)).
  auto lcl = A_->getLocalMatrixDevice();
  auto bv = Kokkos::subview(b.getLocalViewDevice(Tpetra::Access::ReadWrite), Kokkos::ALL(), 0);
  const auto dcol = diag_col_;
  const auto od = owned_dofs_;
  Kokkos::parallel_for(
      "dof_space_prescribed_rows_owned", Kokkos::RangePolicy<ExecSpace>(0, num_owned_dofs()), KOKKOS_LAMBDA(const LO r) {
        const LO i = od(r);
        if (!prescribed(i)) return;
        const double one = 1.0;
        const LO c = dcol(r);
        lcl.replaceValues(r, &c, 1, &one, false, false);
        bv(r) = dx_prescribed(i);
      });
  A_->fillComplete(map_, map_, fill_params_);
}

template <int dim>
void DofSpace<dim>::to_local(const Vector& owned, DofView local) {
  if (!distributed()) {
    auto v = Kokkos::subview(owned.getLocalViewDevice(Tpetra::Access::ReadOnly), Kokkos::ALL(), 0);
    Kokkos::deep_copy(local, v);
    return;
  }
  Kokkos::Timer timer;
  x_overlap_->doImport(owned, *import_, Tpetra::INSERT);
  exchange_s_ += timer.seconds();
  exchange_bytes_ += 8.0 * import_->getNumExportIDs();
  auto v = Kokkos::subview(x_overlap_->getLocalViewDevice(Tpetra::Access::ReadOnly), Kokkos::ALL(), 0);
  Kokkos::deep_copy(local, v);
}

template <int dim>
void DofSpace<dim>::sum_shared(DofView local) {
  if (!distributed()) return;
  {
    auto rv = Kokkos::subview(rhs_overlap_->getLocalViewDevice(Tpetra::Access::OverwriteAll), Kokkos::ALL(), 0);
    Kokkos::deep_copy(rv, local);
  }
  owned_tmp_->putScalar(0.0);
  owned_tmp_->doExport(*rhs_overlap_, *export_, Tpetra::ADD);
  to_local(*owned_tmp_, local);
}

template class DofSpace<2>;
template class DofSpace<3>;

}  // namespace bfemp
