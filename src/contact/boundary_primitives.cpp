#include "contact/boundary_primitives.hpp"

#include <algorithm>
#include <array>
#include <map>

namespace bfemp {

template <int dim>
BoundaryPrimitives<dim> boundary_primitives(const FemMesh<dim>& mesh) {
  constexpr int nv = dim + 1;
  auto cells = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.elements.nodes);
  // Faces (dim nodes, sorted) counted over the elements; boundary: count 1.
  std::map<std::array<LO, dim>, int> faces;
  for (std::size_t e = 0; e < cells.extent(0); ++e)
    for (int skip = 0; skip < nv; ++skip) {
      std::array<LO, dim> f{};
      int k = 0;
      for (int a = 0; a < nv; ++a)
        if (a != skip) f[k++] = cells(e, a);
      std::sort(f.begin(), f.end());
      ++faces[f];
    }
  struct Prim { std::array<LO, dim> n; int count; double coef; };
  std::vector<Prim> prims;
  std::map<LO, int> facets_at_node;                 // eta_k (2D) or T_v (3D)
  std::map<std::array<LO, 2>, int> facets_at_edge;  // eta_e (3D)
  for (const auto& [f, c] : faces) {
    if (c != 1) continue;
    prims.push_back({f, dim, 1.0});
    for (LO n : f) ++facets_at_node[n];
    if constexpr (dim == 3)
      for (int a = 0; a < 3; ++a) {
        std::array<LO, 2> e{f[a], f[(a + 1) % 3]};
        std::sort(e.begin(), e.end());
        ++facets_at_edge[e];
      }
  }
  const LO num_facets = static_cast<LO>(prims.size());
  std::map<LO, double> node_coef;
  if constexpr (dim == 2) {
    for (const auto& [n, eta] : facets_at_node) node_coef[n] = -(eta - 1.0);
  } else {
    for (const auto& [n, T] : facets_at_node) node_coef[n] = 1.0 - T;
    for (const auto& [e, eta] : facets_at_edge) {
      if (eta != 1) prims.push_back({{e[0], e[1], e[0]}, 2, -(eta - 1.0)});
      node_coef[e[0]] += eta - 1.0;
      node_coef[e[1]] += eta - 1.0;
    }
  }
  for (const auto& [n, c] : node_coef) {
    if (c == 0) continue;
    std::array<LO, dim> a;
    a.fill(n);
    prims.push_back({a, 1, c});
  }
  BoundaryPrimitives<dim> bp;
  const std::size_t np = prims.size();
  bp.nodes = decltype(bp.nodes)("contact_prim_nodes", np);
  bp.count = decltype(bp.count)("contact_prim_count", np);
  bp.coef = decltype(bp.coef)("contact_prim_coef", np);
  bp.body = decltype(bp.body)("contact_prim_body", np);
  bp.num_facets = num_facets;
  auto hn = Kokkos::create_mirror_view(bp.nodes);
  auto hc = Kokkos::create_mirror_view(bp.count);
  auto hk = Kokkos::create_mirror_view(bp.coef);
  auto hb = Kokkos::create_mirror_view(bp.body);
  for (std::size_t j = 0; j < np; ++j) {
    for (int a = 0; a < dim; ++a) hn(j, a) = prims[j].n[a];
    hc(j) = prims[j].count;
    hk(j) = prims[j].coef;
    int b = 0;
    for (std::size_t r = 0; r < mesh.bodies.size(); ++r)
      if (prims[j].n[0] >= mesh.bodies[r].first_node) b = static_cast<int>(r);
    hb(j) = b;
  }
  Kokkos::deep_copy(bp.nodes, hn);
  Kokkos::deep_copy(bp.count, hc);
  Kokkos::deep_copy(bp.coef, hk);
  Kokkos::deep_copy(bp.body, hb);
  return bp;
}

template BoundaryPrimitives<2> boundary_primitives<2>(const FemMesh<2>&);
template BoundaryPrimitives<3> boundary_primitives<3>(const FemMesh<3>&);

}  // namespace bfemp
