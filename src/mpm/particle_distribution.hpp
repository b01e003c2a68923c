#pragma once
// The MPM particles cut into the ranks of a communicator: slabs along one
// axis of the grid (the one with the most cells), each rank owning the
// particles whose coordinate on that axis lies in its slab,
//   rank r owns x_axis in [cut_{r-1}, cut_r)   (cut_{-1} = -inf, cut_{R-1} = +inf),
// with the cuts at cell faces (origin + dx k) chosen so that every slab holds
// about the same number of particles when the cuts are made. A slab keeps its
// cuts (fixed in space, not in grid index: they survive grid extensions); a
// particle that leaves its slab migrates to the owning rank at the end of the
// step (migrate_particles: one all-to-all exchange, fields packed on device).
// Why slabs and not Zoltan2 boxes: one cut coordinate per rank pair makes the
// owner of a position a kernel-side comparison, and for the 2-64 ranks of the
// scenes in view a slab's halo (one node layer each side) stays small; the
// cost is a halo that grows with the cross-section instead of the surface.
//
// Every particle has a global id (its index in the scene's particle list),
// carried through every migration. Output frames redistribute the particles
// into contiguous id blocks (particles_in_id_block), one per rank, which the
// ranks write into one HDF5 file with MPI-IO; checkpoints gather them to
// rank 0 in id order. Either way a run on R ranks writes the same files as
// one on 1 rank. One rank: nothing moves, ids are 0..n-1.
#include <Kokkos_Core.hpp>
#include <Teuchos_Comm.hpp>
#include <vector>

#include "kernels/mpm/grid.hpp"
#include "kernels/mpm/particles.hpp"

namespace bfemp {

template <int dim>
struct ParticleSlabs {
  int axis = 0;
  int nranks = 1;
  Kokkos::View<double*, MemSpace> cuts;  // nranks - 1 ascending cut coordinates

  KOKKOS_INLINE_FUNCTION int owner(double coordinate) const {
    int r = 0;
    while (r < nranks - 1 && coordinate >= cuts(r)) ++r;
    return r;
  }
};

// Cuts for `nranks` slabs of about equal particle counts (every rank passes
// the same `all`; no communication). One-off host work (setup, restart).
template <int dim>
ParticleSlabs<dim> balanced_slabs(const Particles<dim>& all, const GridSpec<dim>& grid, int nranks);

// Cuts along old.axis at cell faces that split the particles of all ranks
// (p: this rank's) into slabs of about equal counts, from the particle count
// of every cell layer summed over the ranks (collective: one sum of
// grid.n_cells[axis] + 2 counts; particles below or above the grid, not yet
// in an extended grid, have a bin each: they stay on the first or last slab).
// largest: the most particles a new slab holds. Work O(particles / ranks +
// layers); for a rebalance, not for every step.
template <int dim>
ParticleSlabs<dim> rebalanced_slabs(const Particles<dim>& p, const ParticleSlabs<dim>& old, const GridSpec<dim>& grid,
                                    const Teuchos::Comm<int>& comm, long long& largest);

// The particles of `all` in slab `rank`, and their indices in `all` (ids).
template <int dim>
Particles<dim> select_slab(const Particles<dim>& all, const ParticleSlabs<dim>& slabs, int rank,
                           Kokkos::View<long long*, MemSpace>& ids);

// Sends every particle outside this rank's slab to its owner and receives
// those entering (collective). p and ids are replaced when anything moved
// anywhere. Returns the number of particles that moved, summed over ranks,
// and sets `largest` to the largest rank's particle count after the exchange:
// both come from one allreduce of the per-destination counts.
template <int dim>
long long migrate_particles(Particles<dim>& p, Kokkos::View<long long*, MemSpace>& ids, const ParticleSlabs<dim>& slabs,
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
