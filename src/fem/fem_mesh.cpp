#include "fem/fem_mesh.hpp"

#include <sstream>
#include <stdexcept>

namespace bfemp {

template <int dim>
FemMesh<dim> build_fem_mesh(const std::vector<FemBodyInput>& bodies,
                            const std::vector<MaterialParams>& materials) {
  constexpr int nv = dim + 1;
  std::size_t n_nodes = 0, n_cells = 0;
  for (const auto& b : bodies) {
    if (b.mesh.dim != dim)
      throw std::invalid_argument("FEM body '" + b.name + "': mesh dimension " +
                                  std::to_string(b.mesh.dim) + ", expected " +
                                  std::to_string(dim));
    n_nodes += b.mesh.num_nodes();
    n_cells += b.mesh.num_cells();
  }
  FemMesh<dim> m;
  auto& el = m.elements;
  el.nodes = decltype(el.nodes)("fem_cells", n_cells);
  el.g = decltype(el.g)("fem_shape_gradients", n_cells);
  el.volume = decltype(el.volume)("fem_rest_volume", n_cells);
  el.material = decltype(el.material)("fem_material", n_cells);
  el.materials = decltype(el.materials)("fem_materials", materials.size());
  m.node_mass = decltype(m.node_mass)("fem_node_mass", n_nodes);
  m.rest_position = decltype(m.rest_position)("fem_rest_position", n_nodes * dim);
  auto cells = Kokkos::create_mirror_view(el.nodes);
  auto grad_N = Kokkos::create_mirror_view(el.g);
  auto vol = Kokkos::create_mirror_view(el.volume);
  auto mat = Kokkos::create_mirror_view(el.material);
  auto mats = Kokkos::create_mirror_view(el.materials);
  auto mass = Kokkos::create_mirror_view(m.node_mass);
  auto X = Kokkos::create_mirror_view(m.rest_position);
  Kokkos::deep_copy(mass, 0.0);
  for (std::size_t i = 0; i < materials.size(); ++i) mats(i) = materials[i];

  LO node0 = 0, cell0 = 0;
  for (const auto& b : bodies) {
    const auto& md = b.mesh;
    for (std::size_t i = 0; i < md.coords.size(); ++i) X(node0 * dim + i) = md.coords[i];
    const double rho = materials.at(b.material_index).density;
    for (std::size_t e = 0; e < md.num_cells(); ++e) {
      const LO ce = cell0 + static_cast<LO>(e);
      Mat<dim> Dm;
      for (int a = 0; a < nv; ++a) cells(ce, a) = node0 + static_cast<LO>(md.cells[e * nv + a]);
      for (int a = 1; a < nv; ++a)
        for (int c = 0; c < dim; ++c)
          Dm(c, a - 1) = X(cells(ce, a) * dim + c) - X(cells(ce, 0) * dim + c);
      const double det = Dm.determinant();
      const double fact = dim == 2 ? 0.5 : 1.0 / 6.0;
      double scale = Dm.cwiseAbs().maxCoeff();
      if (!(det > 1e-12 * std::pow(scale, dim))) {
        std::ostringstream msg;
        msg << "FEM body '" << b.name << "': element " << e
            << " is inverted or degenerate in the rest mesh (volume " << fact * det
            << "); expected positive volume";
        throw std::invalid_argument(msg.str());
      }
      // grad N_a = row a-1 of Dm^-1 (a >= 1); grad N_0 = -sum of the others.
      const Mat<dim> inv = Dm.inverse();
      for (int j = 0; j < dim; ++j) {
        grad_N(ce, 0, j) = 0;
        for (int a = 1; a < nv; ++a) {
          grad_N(ce, a, j) = inv(a - 1, j);
          grad_N(ce, 0, j) -= inv(a - 1, j);
        }
      }
      vol(ce) = fact * det;
      mat(ce) = b.material_index;
      for (int a = 0; a < nv; ++a) mass(cells(ce, a)) += rho * vol(ce) / nv;
    }
    m.bodies.push_back({b.name, node0, static_cast<LO>(md.num_nodes()), cell0,
                        static_cast<LO>(md.num_cells())});
    node0 += static_cast<LO>(md.num_nodes());
    cell0 += static_cast<LO>(md.num_cells());
  }
  Kokkos::deep_copy(el.nodes, cells);
  Kokkos::deep_copy(el.g, grad_N);
  Kokkos::deep_copy(el.volume, vol);
  Kokkos::deep_copy(el.material, mat);
  Kokkos::deep_copy(el.materials, mats);
  Kokkos::deep_copy(m.node_mass, mass);
  Kokkos::deep_copy(m.rest_position, X);
  return m;
}

template FemMesh<2> build_fem_mesh<2>(const std::vector<FemBodyInput>&,
                                      const std::vector<MaterialParams>&);
template FemMesh<3> build_fem_mesh<3>(const std::vector<FemBodyInput>&,
                                      const std::vector<MaterialParams>&);

}  // namespace bfemp
