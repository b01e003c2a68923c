#include "solver/dof_space.hpp"

#include <Kokkos_Timer.hpp>
#include <Tpetra_CrsMatrix.hpp>

#include "solver/dof_graph.hpp"

namespace bfemp {

template <int dim>
DofSpace<dim>::DofSpace(const Teuchos::RCP<const Comm>& comm) : comm_(comm), dropped_("dof_dropped_blocks") {
  fill_params_ = Teuchos::parameterList();
  fill_params_->set("No Nonlocal Changes", true);
}

template <int dim>
bool DofSpace<dim>::set_structure(LO n_nodes, const std::vector<const EnergyTerm<dim>*>& terms) {
  std::vector<std::uint64_t> versions;
  versions.reserve(terms.size());
  for (const auto* t : terms) versions.push_back(t->couplings_version());
  const bool same = !A_.is_null() && n_nodes == n_nodes_ && terms == terms_ && versions == versions_;
  terms_ = terms;
  versions_ = std::move(versions);
  if (same) {
    ++graph_reuses_;
    return false;
  }
  if (n_nodes != n_nodes_) {
    map_ = Teuchos::rcp(new Map(static_cast<Tpetra::global_size_t>(n_nodes) * dim, 0, comm_));
    n_nodes_ = n_nodes;
  }
  rebuild();
  return true;
}

template <int dim>
void DofSpace<dim>::rebuild() {
  Kokkos::Timer timer;
  std::vector<long long> keys;
  for (const auto* t : terms_) t->add_couplings(keys, n_nodes_);
  A_ = Teuchos::rcp(new Matrix(build_dof_graph<dim>(keys, n_nodes_, map_)));
  A_->fillComplete();
  versions_.clear();
  for (const auto* t : terms_) versions_.push_back(t->couplings_version());
  ++graph_builds_;
  graph_build_s_ = timer.seconds();
}

template <int dim>
void DofSpace<dim>::begin_assembly() {
  Kokkos::deep_copy(dropped_, 0);
  A_->resumeFill();
  A_->setAllToScalar(0.0);
}

template <int dim>
Sink<dim> DofSpace<dim>::sink(double scale, DofView grad, DofView rhs, MaskView prescribed,
                              ConstDofView dx_prescribed) const {
  Sink<dim> s = make_sink<dim>(A_->getLocalMatrixDevice(), scale, grad, rhs, prescribed, dx_prescribed);
  s.dropped = dropped_;
  return s;
}

template <int dim>
int DofSpace<dim>::dropped_blocks() const {
  int n = 0;
  Kokkos::deep_copy(n, dropped_);
  return n;
}

template <int dim>
void DofSpace<dim>::end_assembly(MaskView prescribed, ConstDofView dx_prescribed, DofView rhs) {
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
}

template class DofSpace<2>;
template class DofSpace<3>;

}  // namespace bfemp
