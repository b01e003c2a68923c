#pragma once
// The MPM particles cut into the ranks of a communicator: boxes of a jagged
// Cartesian decomposition (Zoltan2's "multi-jagged" layout), each rank owning
// the particles whose position lies in its box. The R ranks are
// parts[0] x parts[1] (x parts[2]) boxes, cut level by level:
//   level 0: parts[0] - 1 cuts along axis[0] split the particles into slabs;
//   level 1: each slab i gets its own parts[1] - 1 cuts along axis[1];
//   level 2: each column (i, j) its own parts[2] - 1 cuts along axis[2];
// and the box (i, j, k) is rank (i parts[1] + j) parts[2] + k. A level of
// parts 1 has no cuts. Within a group a part holds
//   x_axis in [cut_{k-1}, cut_k)   (cut_{-1} = -inf, cut_{last} = +inf),
// with the cuts at cell faces (origin + dx k) chosen so that every part of a
// group holds about the same number of particles when the cuts are made. The
// cuts are fixed in space, not in grid index (they survive grid extensions);
// a particle that leaves its box migrates to the owning rank at the end of
// the step (migrate_particles: one all-to-all exchange, fields packed on
// device).
// parts: R's prime factors, largest first, each given to the axis with the
// most grid cells per part so far (the first such axis), so the boxes come
// out about cubic in cells; the levels go in decreasing parts (ties: the axis
// with more cells, then the lower axis). R prime (2, 3, 5, ...): one level of
// slabs along the axis with the most cells. Why not Zoltan2's RCB on the
// particles: the owner of a position is then a kernel-side lookup of at most
// three short cut lists, and the boxes' faces are cell faces. Why boxes and
// not slabs only: a slab's halo is the body's whole cross-section, and a body
// of n cells per edge has at most n / 2 slabs of two cells (the B-spline
// halo); boxes keep the halo to a box's surface (perf/README, the projection
// to 64 ranks).
//
// Every particle has a global id (its index in the scene's particle list),
// carried through every migration. Output frames redistribute the particles
// into contiguous id blocks (particles_in_id_block), one per rank, which the
// ranks write into one HDF5 file with MPI-IO; checkpoints too. So a run on R
// ranks writes the same files as one on 1 rank. One rank: nothing moves, ids
// are 0..n-1.
#include <Kokkos_Core.hpp>
#include <Teuchos_Comm.hpp>
#include <array>
#include <string>
#include <vector>

#include "kernels/mpm/grid.hpp"
#include "kernels/mpm/particles.hpp"

namespace bfemp {

// The layout and cuts of the boxes. Space: where `cuts` lives (a host copy
// for host-side lookups: mirror()).
template <int dim, class Space = MemSpace>
struct RankBoxes {
  int nranks = 1;
  int levels = 1;                     // cut levels (1: slabs)
  Kokkos::Array<int, 3> axis{{0, 1, 2}};   // axis of level l
  Kokkos::Array<int, 3> parts{{1, 1, 1}};  // parts of level l (their product: nranks)
  // Level 0's parts[0] - 1 cuts, then level 1's parts[1] - 1 cuts of each of
  // the parts[0] slabs, then level 2's parts[2] - 1 of each of the
  // parts[0] parts[1] columns; ascending within a group.
  Kokkos::View<double*, Space> cuts;

  // The group (rank, at l = levels) that holds x after the first l levels.
  template <class X>
  KOKKOS_INLINE_FUNCTION int group(const X& x, int l) const {
    int g = 0, offset = 0, groups = 1;
    for (int k = 0; k < l; ++k) {
      const int n = parts[k] - 1, start = offset + g * n;
      const double c = x[axis[k]];
      int i = 0;
      while (i < n && c >= cuts(start + i)) ++i;
      offset += groups * n;
      groups *= parts[k];
      g = g * parts[k] + i;
    }
    return g;
  }
  // The rank whose box holds position x (x[a]: coordinate a).
  template <class X>
  KOKKOS_INLINE_FUNCTION int owner(const X& x) const { return group(x, levels); }
  // Index of the first cut of level l (the cuts of its group g follow at g (parts[l] - 1)).
  KOKKOS_INLINE_FUNCTION int level_offset(int l) const {
    int offset = 0, groups = 1;
    for (int k = 0; k < l; ++k) offset += groups * (parts[k] - 1), groups *= parts[k];
    return offset;
  }
  // Sum over the levels of |index of a's part - index of b's part| (rank
  // digits in the mixed radix of parts): how far apart two ranks' boxes lie
  // in the layout (for slabs, |a - b|).
  KOKKOS_INLINE_FUNCTION int distance(int a, int b) const {
    int d = 0;
    for (int l = levels - 1; l >= 0; --l) {
      const int ia = a % parts[l], ib = b % parts[l];
      d += ia > ib ? ia - ib : ib - ia;
      a /= parts[l];
      b /= parts[l];
    }
    return d;
  }
  RankBoxes<dim, Kokkos::HostSpace> mirror() const {
    RankBoxes<dim, Kokkos::HostSpace> h;
    h.nranks = nranks;
    h.levels = levels;
    h.axis = axis;
    h.parts = parts;
    h.cuts = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), cuts);
    return h;
  }
};

// The layout for nranks boxes over `grid` (see the file's comment), or, when
// any of per_axis[0..dim) is not 0, per_axis[d] boxes along axis d (scene key
// 'MPM/boxes per axis'; std::invalid_argument naming it unless each is >= 1
// and their product is nranks).
template <int dim>
RankBoxes<dim> box_layout(const GridSpec<dim>& grid, int nranks, const std::array<int, 3>& per_axis = {0, 0, 0});

// "slabs along axis 0, cuts at 0.5, 1 m" or "2 x 2 boxes: axis 0 cut at 0.5;
// axis 1 cut at 0.3 | 0.4 m" (the banner of a run).
template <int dim>
std::string describe_boxes(const RankBoxes<dim>& b);

// Cuts for box_layout(grid, nranks) with about equal particle counts per
// part at every level (every rank passes the same `all`; no communication).
// One-off host work (setup, restart).
template <int dim>
RankBoxes<dim> balanced_boxes(const Particles<dim>& all, const GridSpec<dim>& grid, int nranks,
                              const std::array<int, 3>& per_axis = {0, 0, 0});

// New cuts in old's layout at cell faces that split the particles of all
// ranks (p: this rank's) into parts of about equal counts, level by level,
// from the particle count of every cell layer of every group summed over the
// ranks (collective: per level one sum of groups x (grid.n_cells[axis] + 2)
// counts; particles below or above the grid, not yet in an extended grid,
// have a bin each: they stay in the first or last part). largest: the most
// particles a new box holds. Work O(particles / ranks + groups x layers);
// for a rebalance, not for every step.
template <int dim>
RankBoxes<dim> rebalanced_boxes(const Particles<dim>& p, const RankBoxes<dim>& old, const GridSpec<dim>& grid,
                                const Teuchos::Comm<int>& comm, long long& largest);

// The particles of `all` in box `rank`, and their indices in `all` (ids).
template <int dim>
Particles<dim> select_box(const Particles<dim>& all, const RankBoxes<dim>& boxes, int rank,
                          Kokkos::View<long long*, MemSpace>& ids);

// Sends every particle outside this rank's box to its owner and receives
// those entering (collective). p and ids are replaced when anything moved
// anywhere. Returns the number of particles that moved, summed over ranks,
// and sets `largest` to the largest rank's particle count after the exchange:
// both come from one allreduce of the per-destination counts.
template <int dim>
long long migrate_particles(Particles<dim>& p, Kokkos::View<long long*, MemSpace>& ids, const RankBoxes<dim>& boxes,
                            const Teuchos::Comm<int>& comm, long long& largest);

// All ranks' particles on rank `root`, placed by id (0..n_total-1); other
// ranks get an empty set (collective).
template <int dim>
Particles<dim> gather_particles(const Particles<dim>& p, Kokkos::View<const long long*, MemSpace> ids,
                                long long n_total, const Teuchos::Comm<int>& comm, int root = 0);

// Local reorders of this rank's particles (no communication), for the
// periodic sort by cell (MpmBodies, 'MPM/sort particles every'):
//  - particles_by_id: a copy with particle q at row ids(q) (ids must be a
//    permutation of 0..np-1: one rank, every particle here);
//  - permute_particles: p and ids replaced by their rows order(0), order(1),
//    ... (order a permutation of 0..np-1).
// Both pass every field once through a packed buffer (allocated per call).
template <int dim>
Particles<dim> particles_by_id(const Particles<dim>& p, Kokkos::View<const long long*, MemSpace> ids);
template <int dim>
void permute_particles(Particles<dim>& p, Kokkos::View<long long*, MemSpace>& ids,
                       Kokkos::View<const LO*, MemSpace> order);

// The output blocks: rank r of R holds the particles with ids in
// [id_block_begin(n, r, R), id_block_begin(n, r + 1, R)).
KOKKOS_INLINE_FUNCTION long long id_block_begin(long long n_total, int rank, int nranks) {
  return n_total * rank / nranks;
}

// All ranks' particles redistributed so that this rank holds its id block,
// in id order (row q = id id_block_begin + q; ids must be 0..n_total-1, each
// on one rank). Collective: one all-to-all of counts, one of packed particles;
// nothing passes through one rank.
template <int dim>
Particles<dim> particles_in_id_block(const Particles<dim>& p, Kokkos::View<const long long*, MemSpace> ids,
                                     long long n_total, const Teuchos::Comm<int>& comm);

// A per-particle field (k values per particle, particle-major; particle q of
// this rank has id ids(q)) redistributed the same way: this rank's id block,
// k values per particle, in id order (collective).
Kokkos::View<double*, MemSpace> particle_values_in_id_block(Kokkos::View<const double*, MemSpace> values, int k,
                                                            Kokkos::View<const long long*, MemSpace> ids,
                                                            long long n_total, const Teuchos::Comm<int>& comm);

}  // namespace bfemp
