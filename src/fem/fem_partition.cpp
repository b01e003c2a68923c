#include "fem/fem_partition.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Zoltan2_BasicVectorAdapter.hpp>
#include <Zoltan2_PartitioningProblem.hpp>
#include <algorithm>
#include <climits>

namespace bfemp {

template <int dim>
FemPartition partition_fem_mesh(const FemMesh<dim>& mesh, const Teuchos::RCP<const Teuchos::Comm<int>>& comm) {
  constexpr int nv = dim + 1;
  const int nranks = comm->getSize(), rank = comm->getRank();
  const LO ne = mesh.num_cells(), nn = mesh.num_nodes();
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.elements.nodes);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.rest_position);
  FemPartition part;
  part.element_rank.assign(ne, 0);
  if (nranks > 1 && ne > 0 && ne < nranks) {
    // Fewer elements than ranks (Zoltan's RCB refuses to cut them): element e
    // goes to rank e, the other ranks own no element.
    for (LO e = 0; e < ne; ++e) part.element_rank[e] = static_cast<int>(e);
  } else if (nranks > 1 && ne > 0) {
    // Each rank hands Zoltan2 a contiguous slice of the elements.
    const LO e0 = static_cast<LO>(static_cast<long long>(ne) * rank / nranks);
    const LO e1 = static_cast<LO>(static_cast<long long>(ne) * (rank + 1) / nranks);
    const LO n = e1 - e0;
    // At least one entry each: the adapter counts the coordinates it is given
    // by their non-null pointers, and an empty std::vector may hand out null;
    // a rank with no elements (fewer elements than ranks) would then join
    // RCB's reductions with another dimension (MPI_ERR_TRUNCATE).
    std::vector<long long> ids(std::max<LO>(n, 1));
    std::vector<double> c[3];
    for (auto& v : c) v.assign(std::max<LO>(n, 1), 0.0);
    for (LO k = 0; k < n; ++k) {
      ids[k] = e0 + k;
      for (int a = 0; a < nv; ++a)
        for (int d = 0; d < dim; ++d) c[d][k] += X(conn(e0 + k, a) * dim + d) / nv;
    }
    using Adapter = Zoltan2::BasicVectorAdapter<Zoltan2::BasicUserTypes<double, int, long long>>;
    Adapter adapter(n, ids.data(), c[0].data(), c[1].data(), dim == 3 ? c[2].data() : nullptr);
    Teuchos::ParameterList params("zoltan2");
    params.set("algorithm", "rcb");
    params.set("num_global_parts", nranks);
    params.sublist("zoltan_parameters").set("DEBUG_LEVEL", "0");
    Zoltan2::PartitioningProblem<Adapter> problem(&adapter, &params, comm);
    problem.solve();
    const auto* parts = problem.getSolution().getPartListView();
    std::vector<int> mine(ne, 0);
    for (LO k = 0; k < n; ++k) mine[e0 + k] = static_cast<int>(parts[k]);
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, ne, mine.data(), part.element_rank.data());
  }
  // Node owners: the lowest rank touching the node.
  std::vector<int> owner(nn, INT_MAX);
  std::vector<char> touched(nn, 0);
  for (LO e = 0; e < ne; ++e) {
    const int r = part.element_rank[e];
    if (r == rank) part.elements.push_back(e);
    for (int a = 0; a < nv; ++a) {
      const LO v = conn(e, a);
      owner[v] = std::min(owner[v], r);
      if (r == rank) touched[v] = 1;
    }
  }
  std::vector<GO> ghosts;
  for (LO v = 0; v < nn; ++v) {
    if (owner[v] == INT_MAX) owner[v] = 0;  // a node of no element
    if (owner[v] == rank) part.nodes.push_back(v);
    else if (touched[v]) ghosts.push_back(v);
  }
  part.n_owned = static_cast<LO>(part.nodes.size());
  part.nodes.insert(part.nodes.end(), ghosts.begin(), ghosts.end());
  return part;
}

template <int dim>
FemMesh<dim> local_fem_mesh(const FemMesh<dim>& mesh, const FemPartition& part) {
  constexpr int nv = dim + 1;
  const LO nl = static_cast<LO>(part.nodes.size()), ne = static_cast<LO>(part.elements.size());
  std::vector<LO> local(mesh.num_nodes(), -1);
  for (LO a = 0; a < nl; ++a) local[part.nodes[a]] = a;
  FemMesh<dim> out;
  auto& E = out.elements;
  E.nodes = decltype(E.nodes)("fem_local_nodes", ne);
  E.g = decltype(E.g)("fem_local_g", ne);
  E.volume = decltype(E.volume)("fem_local_volume", ne);
  E.material = decltype(E.material)("fem_local_material", ne);
  E.materials = mesh.elements.materials;
  auto cn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.elements.nodes);
  auto cg = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.elements.g);
  auto cv = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.elements.volume);
  auto cm = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.elements.material);
  auto hn = Kokkos::create_mirror_view(E.nodes);
  auto hg = Kokkos::create_mirror_view(E.g);
  auto hv = Kokkos::create_mirror_view(E.volume);
  auto hm = Kokkos::create_mirror_view(E.material);
  for (LO k = 0; k < ne; ++k) {
    const LO e = part.elements[k];
    for (int a = 0; a < nv; ++a) {
      hn(k, a) = local[cn(e, a)];
      for (int d = 0; d < dim; ++d) hg(k, a, d) = cg(e, a, d);
    }
    hv(k) = cv(e);
    hm(k) = cm(e);
  }
  Kokkos::deep_copy(E.nodes, hn);
  Kokkos::deep_copy(E.g, hg);
  Kokkos::deep_copy(E.volume, hv);
  Kokkos::deep_copy(E.material, hm);
  out.node_mass = Kokkos::View<double*, MemSpace>("fem_local_mass", nl);
  out.rest_position = Kokkos::View<double*, MemSpace>("fem_local_rest", static_cast<std::size_t>(nl) * dim);
  auto gm = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.node_mass);
  auto gx = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.rest_position);
  auto lm = Kokkos::create_mirror_view(out.node_mass);
  auto lx = Kokkos::create_mirror_view(out.rest_position);
  for (LO a = 0; a < nl; ++a) {
    lm(a) = gm(part.nodes[a]);
    for (int d = 0; d < dim; ++d) lx(a * dim + d) = gx(part.nodes[a] * dim + d);
  }
  Kokkos::deep_copy(out.node_mass, lm);
  Kokkos::deep_copy(out.rest_position, lx);
  return out;
}

template FemPartition partition_fem_mesh<2>(const FemMesh<2>&, const Teuchos::RCP<const Teuchos::Comm<int>>&);
template FemPartition partition_fem_mesh<3>(const FemMesh<3>&, const Teuchos::RCP<const Teuchos::Comm<int>>&);
template FemMesh<2> local_fem_mesh<2>(const FemMesh<2>&, const FemPartition&);
template FemMesh<3> local_fem_mesh<3>(const FemMesh<3>&, const FemPartition&);

}  // namespace bfemp
