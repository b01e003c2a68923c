#include "solver/dof_graph.hpp"

#include <Tpetra_CrsGraph.hpp>
#include <algorithm>
#include <vector>

namespace bfemp {

template <int dim>
Teuchos::RCP<const Graph> build_dof_graph(std::vector<long long>& keys, LO n_nodes,
                                          const Teuchos::RCP<const Map>& dof_map,
                                          Teuchos::RCP<const Map> domain_range) {
  if (domain_range.is_null()) domain_range = dof_map;
  for (LO i = 0; i < n_nodes; ++i) keys.push_back(static_cast<long long>(i) * n_nodes + i);
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());

  std::vector<std::size_t> node_ptr(n_nodes + 1, 0);
  for (long long k : keys) ++node_ptr[k / n_nodes + 1];
  for (LO i = 0; i < n_nodes; ++i) node_ptr[i + 1] += node_ptr[i];

  const std::size_t n_rows = static_cast<std::size_t>(n_nodes) * dim;
  Kokkos::View<std::size_t*, Node::device_type> rowptr("dof_rowptr", n_rows + 1);
  Kokkos::View<LO*, Node::device_type> colind("dof_colind", keys.size() * dim * dim);
  auto rp = Kokkos::create_mirror_view(rowptr);
  auto ci = Kokkos::create_mirror_view(colind);
  std::size_t pos = 0;
  for (LO i = 0; i < n_nodes; ++i)
    for (int c = 0; c < dim; ++c) {
      rp(i * dim + c) = pos;
      for (std::size_t k = node_ptr[i]; k < node_ptr[i + 1]; ++k) {
        const LO j = static_cast<LO>(keys[k] % n_nodes);
        for (int d = 0; d < dim; ++d) ci(pos++) = j * dim + d;
      }
    }
  rp(n_rows) = pos;
  Kokkos::deep_copy(rowptr, rp);
  Kokkos::deep_copy(colind, ci);
  auto graph = Teuchos::rcp(new Graph(dof_map, dof_map, rowptr, colind));
  graph->fillComplete(domain_range, domain_range);
  return graph;
}

template Teuchos::RCP<const Graph> build_dof_graph<2>(std::vector<long long>&, LO, const Teuchos::RCP<const Map>&,
                                                      Teuchos::RCP<const Map>);
template Teuchos::RCP<const Graph> build_dof_graph<3>(std::vector<long long>&, LO, const Teuchos::RCP<const Map>&,
                                                      Teuchos::RCP<const Map>);

}  // namespace bfemp
