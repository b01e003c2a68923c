// The implicit step on distributed DOFs: an FEM block cut by Zoltan2 RCB into
// the ranks (fem/fem_partition.hpp), each rank assembling only its elements
// into the overlap matrix of its DOF space, one Export into the owned system,
// Belos CG (Ifpack2 or MueLu), global reductions in the Newton loop. On every
// rank count the result equals, node by node, a 1-rank Cholmod solve of the
// whole block that each rank runs on its own (a SerialComm): the same
// minimiser to the Newton tolerance. Also: the partition covers every node
// and element exactly once, and 2 ranks without a partition are refused.
#include <gtest/gtest.h>

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_DefaultSerialComm.hpp>
#include <Tpetra_Core.hpp>
#include <cmath>
#include <map>

#include "fem/fem_mesh.hpp"
#include "fem/fem_partition.hpp"
#include "common/fem_fixtures.hpp"
#include "solver/dof_space.hpp"
#include "solver/newton.hpp"

using namespace bfemp;

namespace {

using View1 = Kokkos::View<double*, MemSpace>;

// One backward-Euler-like minimisation on `mesh` (local or whole):
// x_hat = X + dt v0 + dt^2 g with v0 = (sin 3y, -2, 0), bottom nodes fixed.
template <int dim>
struct Problem {
  View1 xhat, mass, target, x;
  Kokkos::View<int*, MemSpace> pres;
};

template <int dim>
Problem<dim> make_problem(const FemMesh<dim>& mesh, const std::vector<GO>& global_ids,
                          const std::vector<char>& bottom) {
  const std::size_t n = mesh.num_nodes(), nd = n * dim;
  Problem<dim> p{View1("xhat", nd), View1("mass", nd), View1("target", nd), View1("x", nd),
                 Kokkos::View<int*, MemSpace>("pres", nd)};
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.rest_position);
  auto M = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.node_mass);
  auto xh = Kokkos::create_mirror_view(p.xhat);
  auto mh = Kokkos::create_mirror_view(p.mass);
  auto th = Kokkos::create_mirror_view(p.target);
  auto ph = Kokkos::create_mirror_view(p.pres);
  const double dt = 0.02, g = -9.81;
  for (std::size_t a = 0; a < n; ++a) {
    const double y = X(a * dim + 1);
    const double v0[3] = {std::sin(3 * y), -2.0, 0.0};
    for (int c = 0; c < dim; ++c) {
      const std::size_t i = a * dim + c;
      xh(i) = X(i) + dt * v0[c] + (c == 1 ? dt * dt * g : 0.0);
      mh(i) = M(a);
      const bool fixed = bottom[global_ids[a]] != 0;
      ph(i) = fixed ? 1 : 0;
      th(i) = X(i);
    }
  }
  Kokkos::deep_copy(p.xhat, xh);
  Kokkos::deep_copy(p.mass, mh);
  Kokkos::deep_copy(p.target, th);
  Kokkos::deep_copy(p.pres, ph);
  Kokkos::deep_copy(p.x, mesh.rest_position);
  return p;
}

template <int dim>
NewtonStats minimize(const FemMesh<dim>& mesh, Problem<dim>& p, const Teuchos::RCP<const Comm>& comm,
                     const Teuchos::ParameterList& ls, const FemPartition* part) {
  NewtonParams np;
  np.eps_d = 1e-10;
  NewtonSolver<dim> newton(comm, ls, np);
  DeformationTerm<dim, dim + 1> term("fem", mesh.elements);
  if (part) newton.set_partition(part->nodes, part->n_owned);
  newton.set_system(mesh.num_nodes(), {&term});
  IncrementalPotential ip;
  ip.x_hat = p.xhat;
  ip.mass = p.mass;
  ip.prescribed = p.pres;
  ip.target = p.target;
  ip.dt = 0.02;
  ip.h = ip.dt * ip.dt;
  return newton.minimize(ip, p.x);
}

Teuchos::ParameterList cg_list(const std::string& prec) {
  Teuchos::ParameterList ls = *linear_solver_schema();
  ls.set("type", std::string("CG"));
  ls.sublist("CG").set("preconditioner", prec);
  ls.sublist("CG").set("tolerance", 1e-12);
  if (prec == "RELAXATION") ls.sublist("CG").sublist("Ifpack2").set("relaxation: type", std::string("Symmetric Gauss-Seidel"));
  return ls;
}

// The FEM block of element size h, its bottom nodes (flags) and the identity
// numbering of its nodes (the whole block on one rank).
template <int dim>
struct Block {
  FemMesh<dim> mesh;
  std::vector<char> bottom;
  std::vector<GO> all;
};

template <int dim>
Block<dim> make_block(double h) {
  auto setup = fixtures::block_setup<dim>(h);
  Block<dim> b{build_fem_mesh<dim>(setup.bodies, setup.materials), {}, {}};
  const LO nn = b.mesh.num_nodes();
  b.bottom.assign(nn, 0);
  for (long long v : setup.bodies[0].mesh.node_sets.at("bottom")) b.bottom[v] = 1;
  b.all.resize(nn);
  for (LO a = 0; a < nn; ++a) b.all[a] = a;
  return b;
}

template <int dim>
void distributed_equals_serial(const std::string& prec, double h) {
  auto comm = Tpetra::getDefaultComm();
  const Block<dim> block = make_block<dim>(h);
  const FemMesh<dim>& mesh = block.mesh;
  const std::vector<char>& bottom = block.bottom;
  const std::vector<GO>& all = block.all;
  const LO nn = mesh.num_nodes();

  // Reference: the whole block on this rank alone, Cholmod.
  Problem<dim> ref = make_problem<dim>(mesh, all, bottom);
  Teuchos::ParameterList direct = *linear_solver_schema();
  const NewtonStats st_ref = minimize<dim>(mesh, ref, Teuchos::rcp(new Teuchos::SerialComm<int>()), direct, nullptr);

  // Distributed.
  const FemPartition part = partition_fem_mesh<dim>(mesh, comm);
  const FemMesh<dim> local = local_fem_mesh<dim>(mesh, part);
  Problem<dim> dist = make_problem<dim>(local, part.nodes, bottom);
  const NewtonStats st = minimize<dim>(local, dist, comm, cg_list(prec), &part);

  auto xr = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), ref.x);
  auto xd = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), dist.x);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.rest_position);
  double err = 0, disp = 0;
  for (std::size_t a = 0; a < part.nodes.size(); ++a)
    for (int c = 0; c < dim; ++c) {
      const GO i = part.nodes[a] * dim + c;
      err = std::max(err, std::abs(xd(a * dim + c) - xr(i)));
      disp = std::max(disp, std::abs(xr(i) - X(i)));
    }
  double gerr = 0;
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, err, Teuchos::outArg(gerr));
  // Both stop at |p|_inf / dt < 1e-10 m/s: 2e-12 m per coordinate, against
  // displacements of ~4 cm.
  EXPECT_LT(gerr, 1e-9) << dim << "D, " << prec << ", " << comm->getSize() << " ranks";
  EXPECT_GT(disp, 1e-2);
  EXPECT_GE(st.iterations, 2);
  // Every rank took the same iterations (the loop's decisions are global).
  int its_min = 0, its_max = 0;
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_MIN, st.iterations, Teuchos::outArg(its_min));
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, st.iterations, Teuchos::outArg(its_max));
  EXPECT_EQ(its_min, its_max);
  if (comm->getRank() == 0)
    std::cout << dim << "D block, " << nn << " nodes, " << comm->getSize() << " rank(s), CG + " << prec
              << ": |x - x_serial|_inf = " << gerr << " m; Newton " << st.iterations << " (serial Cholmod "
              << st_ref.iterations << "), CG iterations " << st.linear_iterations << "\n";
}

// The assembled system of the deformation term at x (the mesh's node
// positions plus a shear), bottom DOFs prescribed with dxp = 1e-3 sin(global
// DOF): matrix rows and b by global DOF id, for this rank's owned rows.
struct RowSystem {
  std::map<GO, std::map<GO, double>> rows;
  std::map<GO, double> b;
};

template <int dim>
RowSystem assemble_rows(const FemMesh<dim>& mesh, const std::vector<GO>& global_ids, LO n_owned,
                        const std::vector<char>& bottom, const Teuchos::RCP<const Comm>& comm, bool distributed,
                        int assemblies) {
  const std::size_t n = mesh.num_nodes(), nd = n * dim;
  View1 x("x", nd), grad("grad", nd), rhs("rhs", nd), dxp("dxp", nd);
  Kokkos::View<int*, MemSpace> pres("pres", nd);
  auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.rest_position);
  auto xh = Kokkos::create_mirror_view(x);
  auto dh = Kokkos::create_mirror_view(dxp);
  auto ph = Kokkos::create_mirror_view(pres);
  for (std::size_t a = 0; a < n; ++a)
    for (int c = 0; c < dim; ++c) {
      const std::size_t i = a * dim + c;
      const GO gi = global_ids[a] * dim + c;
      xh(i) = X(i) + (c == 0 ? 0.2 * X(a * dim + 1) * X(a * dim + 1) : 0.05 * std::sin(7.0 * X(a * dim)));
      ph(i) = bottom[global_ids[a]] ? 1 : 0;
      dh(i) = ph(i) ? 1e-3 * std::sin(static_cast<double>(gi)) : 0.0;
    }
  Kokkos::deep_copy(x, xh);
  Kokkos::deep_copy(dxp, dh);
  Kokkos::deep_copy(pres, ph);
  DeformationTerm<dim, dim + 1> term("fem", mesh.elements);
  DofSpace<dim> dofs(comm);
  if (distributed) dofs.set_partition(global_ids, n_owned);
  dofs.set_structure(static_cast<LO>(n), {&term});
  Vector b(dofs.map());
  for (int k = 0; k < assemblies; ++k) {  // the later ones reuse the graph and the exchange plan
    Kokkos::deep_copy(grad, 0.0);
    Kokkos::deep_copy(rhs, 0.0);
    dofs.begin_assembly();
    term.assemble(x, dofs.sink(0.5, grad, rhs, pres, dxp));
    dofs.end_assembly(pres, dxp, rhs, b);
  }
  RowSystem s;
  const auto A = dofs.matrix();
  const auto& map = *dofs.map();
  auto bv = b.getLocalViewHost(Tpetra::Access::ReadOnly);
  std::size_t len = A->getNodeMaxNumRowEntries();
  std::vector<GO> cols(len);
  std::vector<double> vals(len);
  for (LO r = 0; r < static_cast<LO>(map.getNodeNumElements()); ++r) {
    const GO g = map.getGlobalElement(r);
    std::size_t nr = 0;
    A->getGlobalRowCopy(g, cols, vals, nr);
    for (std::size_t k = 0; k < nr; ++k) s.rows[g][cols[k]] += vals[k];
    s.b[g] = bv(r, 0);
  }
  return s;
}

// The owned rows of the distributed system equal the serial system's rows,
// entry by entry (prescribed rows and columns included): the overlap matrices
// of all ranks sum into the owned matrix, on the first assembly of a graph and
// on the following ones (the value exchange planned once).
template <int dim>
void distributed_system_equals_serial(double h) {
  auto comm = Tpetra::getDefaultComm();
  const Block<dim> block = make_block<dim>(h);
  const FemMesh<dim>& mesh = block.mesh;
  const std::vector<char>& bottom = block.bottom;
  const LO nn = mesh.num_nodes();
  const RowSystem ref = assemble_rows<dim>(mesh, block.all, nn, bottom, Teuchos::rcp(new Teuchos::SerialComm<int>()), false, 1);
  const FemPartition part = partition_fem_mesh<dim>(mesh, comm);
  const FemMesh<dim> local = local_fem_mesh<dim>(mesh, part);
  for (int assemblies : {1, 3}) {
    const RowSystem d = assemble_rows<dim>(local, part.nodes, part.n_owned, bottom, comm, true, assemblies);
    double scale = 0, err = 0, berr = 0;
    long entries = 0, prescribed_rows = 0;
    for (const auto& [g, row] : d.rows) {
      const auto& rr = ref.rows.at(g);
      EXPECT_EQ(row.size(), rr.size()) << "row " << g;
      for (const auto& [c, v] : rr) {
        const auto it = row.find(c);
        const double got = it == row.end() ? 0.0 : it->second;
        err = std::max(err, std::abs(got - v));
        scale = std::max(scale, std::abs(v));
        ++entries;
      }
      berr = std::max(berr, std::abs(d.b.at(g) - ref.b.at(g)));
      if (bottom[g / dim]) ++prescribed_rows;
    }
    long total = 0, total_prescribed = 0;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, entries, Teuchos::outArg(total));
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, prescribed_rows, Teuchos::outArg(total_prescribed));
    long ref_entries = 0;
    for (const auto& [g, row] : ref.rows) ref_entries += static_cast<long>(row.size());
    EXPECT_EQ(total, ref_entries) << "the owned rows of all ranks cover the serial matrix";
    EXPECT_GT(total_prescribed, 0);
    EXPECT_LE(err, 1e-13 * scale) << dim << "D, " << assemblies << " assemblies, " << comm->getSize() << " ranks";
    double bscale = 0;
    for (const auto& [g, v] : ref.b) bscale = std::max(bscale, std::abs(v));
    EXPECT_GT(bscale, 0.0);
    EXPECT_LE(berr, 1e-13 * bscale);
  }
}

}  // namespace

TEST(NewtonMpi, DistributedSystemEqualsSerialEntryByEntry2D) { distributed_system_equals_serial<2>(0.05); }
TEST(NewtonMpi, DistributedSystemEqualsSerialEntryByEntry3D) { distributed_system_equals_serial<3>(0.2); }

TEST(NewtonMpi, PartitionCoversEveryNodeAndElementOnce) {
  auto comm = Tpetra::getDefaultComm();
  auto setup = fixtures::block_setup<3>(0.25);
  const FemMesh<3> mesh = build_fem_mesh<3>(setup.bodies, setup.materials);
  const FemPartition part = partition_fem_mesh<3>(mesh, comm);
  const LO nn = mesh.num_nodes(), ne = mesh.num_cells();
  std::vector<int> owned(nn, 0), owned_sum(nn, 0), elems(ne, 0), elems_sum(ne, 0);
  for (LO a = 0; a < part.n_owned; ++a) owned[part.nodes[a]] = 1;
  for (LO e : part.elements) elems[e] = 1;
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, nn, owned.data(), owned_sum.data());
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, ne, elems.data(), elems_sum.data());
  for (LO a = 0; a < nn; ++a) ASSERT_EQ(owned_sum[a], 1) << "node " << a;
  for (LO e = 0; e < ne; ++e) ASSERT_EQ(elems_sum[e], 1) << "element " << e;
  // Local nodes = the nodes of the rank's elements (and its owned ones).
  auto conn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mesh.elements.nodes);
  std::vector<char> local(nn, 0);
  for (GO v : part.nodes) local[v] = 1;
  for (LO e : part.elements)
    for (int a = 0; a < 4; ++a) EXPECT_TRUE(local[conn(e, a)]);
  // RCB balances the element counts.
  const int mine = static_cast<int>(part.elements.size());
  int lo = 0, hi = 0;
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_MIN, mine, Teuchos::outArg(lo));
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(hi));
  EXPECT_LE(hi - lo, 1 + ne / 50) << "elements per rank " << lo << ".." << hi;
  if (comm->getSize() > 1) {
    EXPECT_LT(static_cast<LO>(part.nodes.size()), nn) << "a rank holds the whole mesh";
    // Rank 0 owns every node it touches; the others ghost the shared ones.
    const int ghosts = static_cast<int>(part.nodes.size()) - part.n_owned;
    int most = 0;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_MAX, ghosts, Teuchos::outArg(most));
    EXPECT_GT(most, 0) << "no ghost nodes on a cut mesh";
    if (comm->getRank() == 0) {
      EXPECT_EQ(ghosts, 0);
    }
  }
}

TEST(NewtonMpi, DistributedFemMinimisationEqualsSerial2DRelaxation) { distributed_equals_serial<2>("RELAXATION", 0.05); }
TEST(NewtonMpi, DistributedFemMinimisationEqualsSerial2DMueLu) { distributed_equals_serial<2>("MUELU", 0.05); }
TEST(NewtonMpi, DistributedFemMinimisationEqualsSerial3DMueLu) { distributed_equals_serial<3>("MUELU", 0.2); }
TEST(NewtonMpi, DistributedFemMinimisationEqualsSerial3DChebyshev) { distributed_equals_serial<3>("CHEBYSHEV", 0.2); }

TEST(NewtonMpi, SeveralRanksWithoutPartitionRefused) {
  auto comm = Tpetra::getDefaultComm();
  if (comm->getSize() == 1) GTEST_SKIP() << "needs 2 ranks";
  auto setup = fixtures::block_setup<2>(0.25);
  const FemMesh<2> mesh = build_fem_mesh<2>(setup.bodies, setup.materials);
  NewtonSolver<2> newton(comm, cg_list("NONE"), NewtonParams{});
  DeformationTerm<2, 3> term("fem", mesh.elements);
  try {
    newton.set_system(mesh.num_nodes(), {&term});
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("MPI ranks"), std::string::npos) << e.what();
  }
}
