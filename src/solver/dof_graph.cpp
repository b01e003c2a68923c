#include "solver/dof_graph.hpp"

#include <Tpetra_CrsGraph.hpp>

namespace bfemp {

template <int dim>
Teuchos::RCP<const Graph> build_dof_graph(const NodeGraphBuilder::RowMap& node_rows,
                                          const NodeGraphBuilder::Entries& node_cols,
                                          const Teuchos::RCP<const Map>& dof_map,
                                          Teuchos::RCP<const Map> domain_range) {
  if (domain_range.is_null()) domain_range = dof_map;
  const LO n_nodes = static_cast<LO>(node_rows.extent(0)) - 1;
  const std::size_t n_rows = static_cast<std::size_t>(n_nodes) * dim;
  const std::size_t nnz = node_cols.extent(0) * dim * dim;
  Kokkos::View<std::size_t*, Node::device_type> rowptr("dof_rowptr", n_rows + 1);
  Kokkos::View<LO*, Node::device_type> colind(Kokkos::ViewAllocateWithoutInitializing("dof_colind"), nnz);
  const auto nr = node_rows;
  const auto nc = node_cols;
  // Node row i's block starts at dim^2 nr(i); its DOF row c at dim (dim nr(i) + c deg).
  Kokkos::parallel_for(
      "dof_graph_expand", Kokkos::RangePolicy<ExecSpace>(0, n_nodes), KOKKOS_LAMBDA(const LO i) {
        const std::size_t first = nr(i), deg = nr(i + 1) - first;
        for (int c = 0; c < dim; ++c) {
          std::size_t pos = dim * (dim * first + c * deg);
          rowptr(static_cast<std::size_t>(i) * dim + c) = pos;
          for (std::size_t k = first; k < first + deg; ++k)
            for (int d = 0; d < dim; ++d) colind(pos++) = nc(k) * dim + d;
        }
        if (i == n_nodes - 1) rowptr(n_rows) = nnz;
      });
  auto graph = Teuchos::rcp(new Graph(dof_map, dof_map, rowptr, colind));
  graph->fillComplete(domain_range, domain_range);
  return graph;
}

template <int dim>
Teuchos::RCP<const Graph> build_dof_graph(const std::vector<const EnergyTerm<dim>*>& terms, LO n_nodes,
                                          const Teuchos::RCP<const Map>& dof_map,
                                          Teuchos::RCP<const Map> domain_range) {
  NodeGraphBuilder builder(n_nodes);
  for (const auto* t : terms) t->add_couplings(builder);
  builder.start_fill();
  for (const auto* t : terms) t->add_couplings(builder);
  NodeGraphBuilder::RowMap rows;
  NodeGraphBuilder::Entries cols;
  builder.finish(rows, cols);
  return build_dof_graph<dim>(rows, cols, dof_map, domain_range);
}

#define BFEMP_DOF_GRAPH(dim)                                                                                      \
  template Teuchos::RCP<const Graph> build_dof_graph<dim>(const NodeGraphBuilder::RowMap&,                        \
                                                          const NodeGraphBuilder::Entries&,                       \
                                                          const Teuchos::RCP<const Map>&, Teuchos::RCP<const Map>); \
  template Teuchos::RCP<const Graph> build_dof_graph<dim>(const std::vector<const EnergyTerm<dim>*>&, LO,         \
                                                          const Teuchos::RCP<const Map>&, Teuchos::RCP<const Map>);
BFEMP_DOF_GRAPH(2)
BFEMP_DOF_GRAPH(3)
#undef BFEMP_DOF_GRAPH

}  // namespace bfemp
