// MPM particles in boxes (mpm/particle_distribution.hpp: a jagged Cartesian
// decomposition, parts[0] x parts[1] (x parts[2]) ranks), run on 1 and 4
// ranks:
//   - the layout (host, any rank count): R's prime factors given to the axes
//     with the most cells per part; 2 and 3 ranks stay slabs along the axis
//     with the most cells (the layout before boxes); 'MPM/boxes per axis';
//   - balanced_boxes on known particle sets: equal counts in every box, each
//     slab with its own cuts, owner() the box the cuts give;
//   - on 4 ranks (2 x 2 boxes): a 2D block thrown diagonally across both
//     cuts into a resting block, through contact on the grid, equals the same
//     scene on one rank alone; particles migrated, every particle ends in its
//     rank's box, and a grid node is owned by the rank whose box holds it;
//     the same with the boxes rebalanced as the particles crowd (every rank
//     recomputes the jagged cuts from the summed histograms), and a 3D cube
//     thrown across the cuts of 2 x 2 x 1 boxes;
//   - a migration of several chunks of the counting sort keeps each group in
//     order: the particles that stay first, in their order, then those of
//     rank 0, 1, ..., each in its sender's order (reproducible runs; at the
//     tests' one thread a placement by atomics would pass too).
#include <gtest/gtest.h>

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <Tpetra_Core.hpp>
#include <algorithm>
#include <cmath>
#include <mpi.h>

#include "common/mpm_mpi_checks.hpp"
#include "mpm/particle_distribution.hpp"

using namespace bfemp;

namespace {

using fixtures::compare;
using fixtures::Result;
using fixtures::run_steps;
using fixtures::set_velocity;
using fixtures::tight_cg;

template <int dim>
GridSpec<dim> grid_of(const std::array<int, 3>& cells) {
  GridSpec<dim> g;
  g.dx = 0.1;
  for (int d = 0; d < dim; ++d) {
    g.origin(d) = 0.0;
    g.n_cells[d] = cells[d];
  }
  return g;
}

// n^dim particles on a regular lattice in [0, 1]^dim (spacing 1 / n, offset
// half a spacing), x fastest.
template <int dim>
Particles<dim> lattice(int n) {
  const std::size_t total = dim == 2 ? n * n : n * n * n;
  Particles<dim> p = allocate_particles<dim>(total);
  auto x = Kokkos::create_mirror_view(p.x);
  for (std::size_t q = 0; q < total; ++q) {
    std::size_t r = q;
    for (int d = 0; d < dim; ++d) {
      x(q, d) = (static_cast<double>(r % n) + 0.5) / n;
      r /= n;
    }
  }
  Kokkos::deep_copy(p.x, x);
  return p;
}

// Particles per rank of `b` (host).
template <int dim>
std::vector<int> counts(const Particles<dim>& p, const RankBoxes<dim>& b) {
  const auto h = b.mirror();
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  std::vector<int> c(b.nranks, 0);
  for (std::size_t q = 0; q < x.extent(0); ++q) {
    Vec<dim> xq;
    for (int d = 0; d < dim; ++d) xq(d) = x(q, d);
    ++c[h.owner(xq)];
  }
  return c;
}

}  // namespace

TEST(RankBoxes, LayoutGivesTheRanksToTheAxesWithTheMostCellsPerPart) {
  auto parts_of = [](const RankBoxes<3>& b) {
    std::array<int, 3> p{1, 1, 1};
    for (int l = 0; l < b.levels; ++l) p[b.axis[l]] = b.parts[l];
    return p;
  };
  const auto twist = grid_of<3>({32, 32, 28});  // the A7 twist's grid
  for (int r : {1, 2, 3}) {  // slabs along the first axis with the most cells, as before boxes
    const auto b = box_layout<3>(twist, r);
    EXPECT_EQ(b.levels, 1) << r;
    EXPECT_EQ(b.axis[0], 0) << r;
    EXPECT_EQ(b.parts[0], r) << r;
    EXPECT_EQ(static_cast<int>(b.cuts.extent(0)), r - 1) << r;
  }
  EXPECT_EQ(box_layout<3>(grid_of<3>({10, 30, 20}), 2).axis[0], 1);
  EXPECT_EQ(parts_of(box_layout<3>(twist, 4)), (std::array<int, 3>{2, 2, 1}));
  EXPECT_EQ(parts_of(box_layout<3>(twist, 8)), (std::array<int, 3>{2, 2, 2}));
  EXPECT_EQ(parts_of(box_layout<3>(twist, 6)), (std::array<int, 3>{3, 2, 1}));
  EXPECT_EQ(parts_of(box_layout<3>(twist, 64)), (std::array<int, 3>{4, 4, 4}));
  const auto b12 = box_layout<2>(grid_of<2>({48, 16, 1}), 12);  // 3 to x, 2 to x (16 = 16), 2 to y
  EXPECT_EQ(b12.levels, 2);
  EXPECT_EQ(b12.axis[0], 0);
  EXPECT_EQ(b12.parts[0], 6);
  EXPECT_EQ(b12.parts[1], 2);
  EXPECT_EQ(static_cast<int>(b12.cuts.extent(0)), 5 + 6 * 1);
  // distance: rank digits (i, j) of 2 x 2 boxes
  const auto b4 = box_layout<2>(grid_of<2>({20, 20, 1}), 4);
  EXPECT_EQ(b4.distance(0, 3), 2);
  EXPECT_EQ(b4.distance(1, 2), 2);
  EXPECT_EQ(b4.distance(0, 1), 1);
  EXPECT_EQ(b4.distance(2, 0), 1);
  EXPECT_EQ(b4.distance(3, 3), 0);
  EXPECT_THROW(box_layout<2>(grid_of<2>({20, 20, 1}), 0), std::invalid_argument);
  // 3 x 2 boxes: rank = 2 i + j; distance sums the digits' differences
  const auto b6 = box_layout<2>(grid_of<2>({20, 20, 1}), 6, {3, 2, 0});
  EXPECT_EQ(b6.distance(1, 2), 2);  // (0, 1) and (1, 0)
  EXPECT_EQ(b6.distance(0, 5), 3);  // (0, 0) and (2, 1)
  EXPECT_EQ(b6.distance(4, 1), 3);  // (2, 0) and (0, 1)
  EXPECT_THROW(box_layout<2>(grid_of<2>({20, 20, 1}), 4, {4, -1, 0}), std::invalid_argument);
  EXPECT_THROW(box_layout<2>(grid_of<2>({20, 20, 1}), 4, {0, 4, 0}), std::invalid_argument);
  // 'MPM/boxes per axis': slabs along y on 4 ranks; 2 x 3 x 1 on 6; a product
  // other than the rank count refused, naming the key
  const auto forced = box_layout<2>(grid_of<2>({20, 20, 1}), 4, {1, 4, 0});
  EXPECT_EQ(forced.levels, 1);
  EXPECT_EQ(forced.axis[0], 1);
  EXPECT_EQ(forced.parts[0], 4);
  EXPECT_EQ(parts_of(box_layout<3>(twist, 6, {2, 3, 1})), (std::array<int, 3>{2, 3, 1}));
  EXPECT_EQ(box_layout<3>(twist, 6, {2, 3, 1}).axis[0], 1);  // the level with more parts first
  try {
    box_layout<2>(grid_of<2>({20, 20, 1}), 2, {2, 2, 0});
    ADD_FAILURE() << "boxes for 4 ranks accepted on 2";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'MPM/boxes per axis' = [2, 2]"), std::string::npos) << e.what();
  }
}

// 2D: 40 x 40 particles in [0, 1]^2 on a 10 x 10 grid, 4 ranks: 2 x 2 boxes
// of 400 each, cuts at 0.5; 3D: 20^3 in 8 boxes of 1000. A lattice that is
// denser in the left half (x < 0.5: its points doubled) gets a slab cut that
// halves the count, then each slab its own y cut.
TEST(RankBoxes, BalancedBoxesHoldEqualCountsAndEachSlabHasItsOwnCuts) {
  const auto g2 = grid_of<2>({10, 10, 1});
  const auto p2 = lattice<2>(40);
  const auto b = balanced_boxes<2>(p2, g2, 4);
  ASSERT_EQ(b.levels, 2);
  EXPECT_EQ(counts<2>(p2, b), (std::vector<int>{400, 400, 400, 400}));
  const auto h = b.mirror();
  ASSERT_EQ(h.cuts.extent(0), 3u);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(h.cuts(k), 0.5, 1e-12) << k;
  EXPECT_EQ(h.owner(Vec<2>(0.2, 0.7)), 1);  // (i, j) = (0, 1)
  EXPECT_EQ(h.owner(Vec<2>(0.7, 0.2)), 2);
  EXPECT_EQ(h.owner(Vec<2>(0.5, 0.5)), 3);  // on the cuts: the upper part
  EXPECT_EQ(h.owner(Vec<2>(-5.0, 9.0)), 1);  // outside the grid: the nearest part

  const auto p3 = lattice<3>(20);
  const auto b3 = balanced_boxes<3>(p3, grid_of<3>({10, 10, 10}), 8);
  EXPECT_EQ(counts<3>(p3, b3), std::vector<int>(8, 1000));

  // 3D, three levels with distinct cuts: the lattice's z scaled by 1, 0.5,
  // 0.25, 0.75 in the columns (x < 0.5, y < 0.5), (x < 0.5, y > 0.5),
  // (x > 0.5, y < 0.5), (x > 0.5, y > 0.5): each column's median z (the
  // particle at z = 0.525 s) at its nearest face: 0.5, 0.3, 0.1, 0.4.
  Particles<3> r = lattice<3>(20);
  {
    auto xr = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), r.x);
    for (std::size_t k = 0; k < xr.extent(0); ++k) {
      const int i = xr(k, 0) > 0.5, j = xr(k, 1) > 0.5;
      const double scale[2][2] = {{1.0, 0.5}, {0.25, 0.75}};
      xr(k, 2) *= scale[i][j];
    }
    Kokkos::deep_copy(r.x, xr);
  }
  const auto br = balanced_boxes<3>(r, grid_of<3>({10, 10, 10}), 8);
  ASSERT_EQ(br.levels, 3);
  const auto hr = br.mirror();
  ASSERT_EQ(hr.cuts.extent(0), 7u);  // 1 (x) + 2 (y, one per slab) + 4 (z, one per column)
  ASSERT_EQ(br.level_offset(2), 3);
  const double want_z[4] = {0.5, 0.3, 0.1, 0.4};
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(hr.cuts(k), 0.5, 1e-12) << k;
  for (int g = 0; g < 4; ++g) EXPECT_NEAR(hr.cuts(3 + g), want_z[g], 1e-12) << "column " << g;
  EXPECT_EQ(hr.owner(Vec<3>(0.7, 0.2, 0.15)), 5);  // column (1, 0), above its cut 0.1
  EXPECT_EQ(hr.owner(Vec<3>(0.7, 0.2, 0.05)), 4);
  EXPECT_EQ(hr.owner(Vec<3>(0.2, 0.7, 0.35)), 3);  // column (0, 1), above 0.3
  EXPECT_EQ(hr.owner(Vec<3>(0.2, 0.7, 0.25)), 2);
  EXPECT_EQ(hr.owner(Vec<3>(0.9, 0.9, 0.45)), 7);  // column (1, 1), above 0.4

  // Uneven: the left slab (x < 0.5) has its particles in y < 0.3 only.
  Particles<2> q = allocate_particles<2>(800);
  auto x = Kokkos::create_mirror_view(q.x);
  for (int k = 0; k < 400; ++k) {
    x(k, 0) = 0.025 + 0.05 * (k % 10);  // x in (0, 0.5)
    x(k, 1) = 0.0075 * (k / 10) + 0.001;  // y in (0, 0.3)
    x(400 + k, 0) = 0.525 + 0.05 * (k % 10);  // x in (0.5, 1)
    x(400 + k, 1) = 0.025 * (k / 10) + 0.001;  // y in (0, 1)
  }
  Kokkos::deep_copy(q.x, x);
  const auto bu = balanced_boxes<2>(q, g2, 4);
  const auto hu = bu.mirror();
  EXPECT_NEAR(hu.cuts(0), 0.5, 1e-12);
  EXPECT_NEAR(hu.cuts(1), 0.2, 1e-12);  // the left slab's median y (0.15), at the nearest face
  EXPECT_NEAR(hu.cuts(2), 0.5, 1e-12);  // the right slab's
  const auto cu = counts<2>(q, bu);
  EXPECT_EQ(cu[2], 400 / 2);
  EXPECT_EQ(cu[3], 400 / 2);
  EXPECT_EQ(cu[0] + cu[1], 400);
}

// rebalanced_boxes from the histograms summed over the ranks, on known
// particles spread over the ranks by index (grid [0, 1]^2, dx 0.1): 400 in
// x < 0.5 with y in (0, 0.3) (140, 130, 130 in the three lowest cell
// layers), 400 in x > 0.5 with y in (0, 1) (40 per layer). On 4 ranks
// (2 x 2): the x cut at 0.5; each slab its own y cut, at the face whose count
// below is nearest half the slab's: 0.1 (140 below) and 0.5; the largest box
// 260 (the left slab's upper part).
TEST(MpmBoxes, RebalancedCutsComeFromEachGroupsOwnHistogram) {
  auto world = Tpetra::getDefaultComm();
  const int me = world->getRank(), n = world->getSize();
  std::vector<std::array<double, 2>> xs;
  for (int k = 0; k < 800; ++k) {
    const int c = k % 400;
    const std::array<double, 2> x = k < 400 ? std::array<double, 2>{0.025 + 0.05 * (c % 10), 0.0075 * (c / 10) + 0.001}
                                           : std::array<double, 2>{0.525 + 0.05 * (c % 10), 0.025 * (c / 10) + 0.001};
    if (k % n == me) xs.push_back(x);
  }
  Particles<2> p = allocate_particles<2>(xs.size());
  auto xh = Kokkos::create_mirror_view(p.x);
  for (std::size_t q = 0; q < xs.size(); ++q) xh(q, 0) = xs[q][0], xh(q, 1) = xs[q][1];
  Kokkos::deep_copy(p.x, xh);
  const auto grid = grid_of<2>({10, 10, 1});
  long long largest = 0;
  const auto b = rebalanced_boxes<2>(p, box_layout<2>(grid, n), grid, *world, largest);
  const auto h = b.mirror();
  if (n == 1) {
    EXPECT_EQ(largest, 800);
  } else if (n == 4) {
    ASSERT_EQ(h.cuts.extent(0), 3u);
    EXPECT_NEAR(h.cuts(0), 0.5, 1e-12);
    EXPECT_NEAR(h.cuts(1), 0.1, 1e-12);  // the left slab's
    EXPECT_NEAR(h.cuts(2), 0.5, 1e-12);  // the right slab's
    EXPECT_EQ(largest, 260);
  }
}

namespace {

// Two 0.3 x 0.3 blocks on a square grid [0, 1.6]^2 (32 x 32 cells: 2 x 2
// boxes on 4 ranks): one at (0.45, 0.45) thrown at (2.5, 2.5) m/s into one at
// rest at (1.1, 1.1). The x cut falls between the blocks, each slab's y cut
// through its block's middle: the thrown block starts on ranks 0 and 1 and
// crosses into 2 and 3.
SimulationSetup<2> diagonal_blocks(double rebalance_above) {
  auto s = fixtures::two_mpm_blocks(Vec<2>(0.45, 0.45), Vec<2>(1.1, 1.1), Vec<2>(1.6, 1.6), Vec<2>(2.5, 2.5),
                                    {"thrown", "resting"});
  s.mpm->rebalance_above = rebalance_above;
  return s;
}

// Every local particle in this rank's box (bad[0] counts the others), and
// the owners of the last step's active nodes (bad[1] counts the violations):
// a node held by the rank whose box of that step holds its position
// (`step_boxes`: the boxes before the step's migration, which may rebalance
// them) is owned by that rank; a node that rank does not hold is owned by
// one of its holders. Collective: every rank's active node ids to every rank.
template <int dim>
std::array<long, 2> outside_own_box(const MpmBodies<dim>& mpm, const Comm& world,
                                    const RankBoxes<dim, Kokkos::HostSpace>& step_boxes) {
  const int rank = world.getRank(), n = world.getSize();
  const auto b = mpm.boxes().mirror();
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), mpm.particles().x);
  std::array<long, 2> bad{0, 0};
  for (std::size_t q = 0; q < x.extent(0); ++q) {
    Vec<dim> xq;
    for (int d = 0; d < dim; ++d) xq(d) = x(q, d);
    if (b.owner(xq) != rank) ++bad[0];
  }
  // held[r]: rank r's active node ids (sorted)
  const std::vector<GO>& g = mpm.global_nodes();
  std::vector<long long> mine(g.begin(), g.end());
  int count = static_cast<int>(mine.size());
  std::vector<int> counts(n), disp(n, 0);
  MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  for (int r = 1; r < n; ++r) disp[r] = disp[r - 1] + counts[r - 1];
  std::vector<long long> all(disp[n - 1] + counts[n - 1]);
  MPI_Allgatherv(mine.data(), count, MPI_LONG_LONG, all.data(), counts.data(), disp.data(), MPI_LONG_LONG,
                 MPI_COMM_WORLD);
  std::vector<std::vector<long long>> held(n);
  for (int r = 0; r < n; ++r) {
    held[r].assign(all.begin() + disp[r], all.begin() + disp[r] + counts[r]);
    std::sort(held[r].begin(), held[r].end());
  }
  for (std::size_t k = 0; k < g.size(); ++k) {
    const int want = step_boxes.owner(mpm.grid().node_position(static_cast<LO>(g[k])));
    const bool owned = static_cast<LO>(k) < mpm.owned_nodes();
    const bool want_holds = std::binary_search(held[want].begin(), held[want].end(), static_cast<long long>(g[k]));
    if (want == rank && !owned) ++bad[1];
    if (owned && want != rank && want_holds) ++bad[1];
  }
  return bad;
}

}  // namespace

TEST(MpmBoxes, MigrationKeepsEachSendersOrderAcrossChunks) {
  auto comm = Tpetra::getDefaultComm();
  const int me = comm->getRank(), R = comm->getSize();
  const long long n = 3 * 4096 + 17;  // several chunks of the counting sort (256-4096 particles each)
  Particles<2> p = allocate_particles<2>(n);
  Kokkos::View<long long*, MemSpace> ids("ids", n);
  {
    auto x = Kokkos::create_mirror_view(p.x);
    auto ih = Kokkos::create_mirror_view(ids);
    for (long long k = 0; k < n; ++k) {  // ids me n .. me n + n - 1, scattered over [0, 1)^2
      const long long id = me * n + k;
      ih(k) = id;
      x(k, 0) = std::fmod(0.6180339887 * (id + 1), 1.0);
      x(k, 1) = std::fmod(0.7548776662 * (id + 1) * (id % 5 + 1), 1.0);
    }
    Kokkos::deep_copy(p.x, x);
    Kokkos::deep_copy(ids, ih);
  }
  const GridSpec<2> grid = grid_of<2>({10, 10, 1});
  long long largest = 0;
  const RankBoxes<2> boxes = rebalanced_boxes(p, box_layout(grid, R), grid, *comm, largest);
  const long long moved = migrate_particles(p, ids, boxes, *comm, largest);
  if (R > 1) EXPECT_GT(moved, (R - 1) * n / 2);  // (about (R - 1) n leave: scattered, equal boxes)
  auto ih = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), ids);
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.x);
  const auto h = boxes.mirror();
  long long mine = static_cast<long long>(ih.extent(0)), all = 0;
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, mine, Teuchos::outArg(all));
  EXPECT_EQ(all, R * n);
  // Sender rank id / n; the expected order: (sender == me ? -1 : sender, id) ascending.
  auto key = [&](long long id) { return std::make_pair(id / n == me ? -1LL : id / n, id); };
  int out_of_order = 0, outside = 0;
  for (std::size_t q = 0; q < ih.extent(0); ++q) {
    if (q > 0 && !(key(ih(q - 1)) < key(ih(q)))) ++out_of_order;
    Vec<2> xq;
    for (int d = 0; d < 2; ++d) xq(d) = x(q, d);
    if (h.owner(xq) != me) ++outside;
  }
  EXPECT_EQ(out_of_order, 0) << "rank " << me;
  EXPECT_EQ(outside, 0) << "rank " << me;
}

TEST(MpmBoxes, DiagonalThrowAcrossBothCutsEqualsOneRank) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  const int n = world->getSize(), rank = world->getRank();
  Simulation<2> alone(diagonal_blocks(0.0), self);
  const Result s = run_steps(alone, 40);
  for (double above : {0.0, 1.1}) {
    Simulation<2> dist(diagonal_blocks(above), world);
    const auto& b = dist.mpm()->boxes();
    if (n == 4) {
      ASSERT_EQ(b.levels, 2);
      ASSERT_EQ(b.parts[0] * b.parts[1], 4);
    }
    RankBoxes<2, Kokkos::HostSpace> last_step_boxes;  // the boxes the last step numbered its nodes by
    const Result d = run_steps(dist, 40, [&](int step) {
      if (step == 39) last_step_boxes = dist.mpm()->boxes().mirror();
    });
    const std::string what = above > 0 ? "2D blocks in boxes, rebalanced" : "2D blocks in boxes";
    compare<2>(*world, d, s, 1e-9, what);
    if (n == 1) continue;
    EXPECT_GT(d.migrated, 0) << what;
    const auto bad = outside_own_box(*dist.mpm(), *world, last_step_boxes);
    EXPECT_EQ(bad[0], 0) << what << ": rank " << rank << " holds particles of other boxes";
    EXPECT_EQ(bad[1], 0) << what << ": rank " << rank << " owns nodes against their box";
    if (above > 0) {
      EXPECT_GE(dist.mpm()->rebalances(), 1) << what;
      if (rank == 0)
        std::cout << what << ": " << dist.mpm()->rebalances() << " rebalance(s), worst imbalance "
                  << d.worst_imbalance << "; " << describe_boxes(dist.mpm()->boxes()) << "\n";
    } else {
      EXPECT_EQ(dist.mpm()->rebalances(), 0) << what;
    }
  }
}

TEST(MpmBoxes, CubeThrownAcrossTheBoxCutsEqualsOneRank3D) {
  auto world = Tpetra::getDefaultComm();
  Teuchos::RCP<const Comm> self = Teuchos::rcp(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  auto setup = [] {
    auto s = fixtures::cube_setup(Vec<3>(0.45, 0.45, 0.3), Vec<3>(0.3, 0.3, 0.3), 0.1, Vec<3>(0.0, 0.0, 0.0),
                                  Vec<3>(1.2, 1.2, 0.8));
    set_velocity<3>(s.mpm->particles, 0, s.mpm->particles.size(), Vec<3>(2.0, 1.5, 0.0));
    s.gravity = {0.0, 0.0, -9.81};  // down z, along no cut
    s.mpm->rebalance_above = 0.0;    // fixed boxes (the 2D test rebalances)
    s.dt = 1e-2;
    s.integrator = TimeIntegrator::backward_euler();
    tight_cg(s);
    return s;
  };
  Simulation<3> dist(setup(), world);
  if (world->getSize() == 4) ASSERT_EQ(dist.mpm()->boxes().levels, 2);
  const Result d = run_steps(dist, 8);
  Simulation<3> alone(setup(), self);
  const Result s = run_steps(alone, 8);
  compare<3>(*world, d, s, 1e-9, "3D cube in boxes");
  if (world->getSize() > 1) {
    EXPECT_GT(d.migrated, 0);
    EXPECT_EQ(dist.mpm()->rebalances(), 0);
    const auto bad = outside_own_box(*dist.mpm(), *world, dist.mpm()->boxes().mirror());
    EXPECT_EQ(bad[0], 0);
    EXPECT_EQ(bad[1], 0);
  }
}
