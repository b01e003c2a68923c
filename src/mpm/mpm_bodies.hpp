#pragma once
// The MPM part of a scene: particles, background grid, transfer scheme, and the
// per-step grid state that joins the Newton system (active grid nodes numbered
// after the FEM nodes). One step: begin_step (activation, P2G, stencils),
// fill_system (grid x^n, v^n, mass), the Newton solve, end_step (G2P).
//
// MPI (distribute() on more than one rank): each rank holds the particles of
// its box (mpm/particle_distribution.hpp) and activates the grid nodes its
// particles touch. A grid node touched by several ranks is owned by one of
// them (Tpetra::createOneToOne; the rank whose box holds the node's position
// when it holds the node) and a ghost on the others; the active nodes
// are numbered owned first, then ghosts (the order DofSpace::set_partition
// expects), and P2G's partial sums at shared nodes are added at the owner
// (Export, ADD) and copied back to every holder (Import), so every rank sees
// the whole mass and momentum of each of its nodes. G2P then needs only local
// nodes; particles that left the box migrate at the end of the step.
#include <Kokkos_ScatterView.hpp>
#include <memory>
#include <string>
#include <vector>

#include <Teuchos_Comm.hpp>
#include <Teuchos_EReductionType.hpp>
#include <Teuchos_RCP.hpp>

#include "kernels/mpm_transfer.hpp"
#include "mpm/particle_cells.hpp"
#include "mpm/particle_distribution.hpp"
#include "solver/energy_term.hpp"

namespace bfemp {

template <int dim>
struct MpmSetup {
  GridSpec<dim> grid;
  Particles<dim> particles;
  TransferScheme scheme = TransferScheme::APIC;
  std::vector<std::string> body_names;
  // particle_total < 0: `particles` is every particle (each rank the whole
  // set; distribute() keeps its box). Otherwise `particles` is this rank's
  // id block [particle_first, particle_first + size) of particle_total,
  // in id order, and distribute() moves the blocks into the boxes (the
  // blocks must tile the ids in rank order; build_setup with a
  // ParticleBlock).
  long long particle_first = 0;
  long long particle_total = -1;
  // A particle whose stencil leaves the grid: false: an error naming the
  // particle and step; true: the grid grows by whole cells before the step
  // (scene key 'MPM/when particles leave: extend').
  bool extend_domain = false;
  // MPI: new box cuts when, after a step's migration, the largest box holds
  // more than rebalance_above x the mean particle count (0: never; scene key
  // 'MPM/rebalance above').
  double rebalance_above = 1.2;
  // MPI: the ranks' boxes along each axis, their product the rank count
  // (scene key 'MPM/boxes per axis'); all 0: automatic (box_layout).
  std::array<int, 3> boxes_per_axis{0, 0, 0};
  // Particles reordered by cell (the base node of their B-spline stencil,
  // x fastest; within a cell by global id) at the start of steps 1,
  // 1 + sort_every, 1 + 2 sort_every, ..., so that neighbouring particles
  // touch neighbouring grid rows (0: never; scene key 'MPM/sort particles
  // every'). The run is the same to round-off (summation orders change). In
  // contact a sort renames the barrier's pairs (keyed by particle index):
  // the Newton graph is rebuilt at that step.
  int sort_every = 0;
};

// MPM elasticity: deformation stencils of the particles; the graph couplings
// come from one particle per distinct stencil (particles in a cell share it).
// Assembly is by cell, in the cells' sweep (mpm/particle_cells.hpp): the
// particles of a cell sum their local gradient and Hessian in a local stencil
// matrix, the cell adds it once; the slabs of one phase run in parallel
// without atomics, each one's cells in node order (consecutive cells share
// most of their matrix rows, so these stay in the caches). The
// couplings change only when the set of occupied cells does.
template <int dim>
class MpmElasticityTerm : public DeformationTerm<dim, bspline_stencil_size<dim>> {
 public:
  using DeformationTerm<dim, bspline_stencil_size<dim>>::DeformationTerm;
  // One clique per occupied cell (its first particle's stencil); one per
  // particle when the cells do not match the stencils (before set_cells).
  void add_couplings(NodeGraphBuilder& graph) const override;
  std::uint64_t couplings_version() const override { return cells_.version; }
  void assemble(ConstDofView x, const Sink<dim>& sink) const override;
  // The stencil-by-stencil assembly with atomics (the generic path; tests
  // compare the two).
  void assemble_per_particle(ConstDofView x, const Sink<dim>& sink) const {
    Sink<dim> searching = sink;  // the table is by cell
    searching.table_stencils = 0;
    DeformationTerm<dim, bspline_stencil_size<dim>>::assemble(x, searching);
  }
  // By cell: stencil k is cells().cells(k), the nodes of its first particle.
  long scatter_table(const LocalMatrix& A, Kokkos::View<int*, MemSpace>& table) const override;
  std::uint64_t stencils_version() const override {
    return cells_version_ + DeformationTerm<dim, bspline_stencil_size<dim>>::stencils_version();
  }
  void set_cells(const ParticleCells<dim>& c) {
    cells_ = c;
    ++cells_version_;
  }
  const ParticleCells<dim>& cells() const { return cells_; }

 private:
  ParticleCells<dim> cells_;
  std::uint64_t cells_version_ = 0;  // set_cells calls (the cell list is rebuilt every step)
};

template <int dim>
class MpmBodies {
 public:
  static constexpr int ns = bspline_stencil_size<dim>;
  MpmBodies(MpmSetup<dim> setup, Kokkos::View<MaterialParams*, MemSpace> materials);

  // Activates the grid for this step's particles, P2G, builds the stencils.
  // Returns the number of active nodes (system nodes first .. first+count-1).
  // Throws std::runtime_error naming the particle and step when a particle's
  // stencil leaves the grid domain, unless extend_domain: then the grid grows
  // (origin and n_cells by whole cells, a quarter of the axis' cells or 2 more
  // on each side that grows) to cover every particle.
  LO begin_step(LO first, long step);
  // Grid x^n (node positions), v^n = (m v)/m, and per-DOF mass into system
  // vectors at the active nodes.
  void fill_system(Kokkos::View<double*, MemSpace> x, Kokkos::View<double*, MemSpace> v,
                   Kokkos::View<double*, MemSpace> mass) const;
  // G2P from the solved grid positions/velocities (v_old: grid v^n).
  void end_step(Kokkos::View<const double*, MemSpace> x_new, Kokkos::View<const double*, MemSpace> v_new,
                Kokkos::View<const double*, MemSpace> v_old);

  const MpmElasticityTerm<dim>& term() const { return *term_; }
  MpmElasticityTerm<dim>& term() { return *term_; }  // (the Newton solver's term list)
  // This rank's particles (all of them on one rank).
  const Particles<dim>& particles() const { return setup_.particles; }

  // MPI: the particles into boxes, each rank keeping its box's: from every
  // rank's id block (MpmSetup::particle_total >= 0: replace_particle_block)
  // or from the whole set on every rank (particle_total < 0:
  // replace_particles). Grid nodes get the global system ids global_first +
  // grid index. No-op on one rank (where an id block must be every particle:
  // the Simulation checks it).
  void distribute(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, GO global_first);
  bool distributed() const { return distributed_; }
  // Restart: the whole particle set of a checkpoint (re-cut when distributed).
  void replace_particles(const Particles<dim>& all);
  // This rank's id block of the particles, from a checkpoint or the scene's
  // sampling (ids first .. first + mine.size() - 1 of total; collective). Several ranks: the blocks must
  // tile 0..total-1 in rank order (std::invalid_argument on every rank
  // otherwise); boxes cut from the cell-layer counts summed over the ranks
  // (rebalanced_boxes on the scene's layout: 'MPM/boxes per axis' or the
  // automatic one) and every particle sent to its box, so no rank reads the
  // whole set. One rank: mine is the whole set (std::logic_error otherwise).
  void replace_particle_block(const Particles<dim>& mine, long long first, long long total);
  // Restart on one rank, after replace_particles: the checkpoint's particle
  // order (the id at each array position; std::invalid_argument unless it is
  // a permutation of 0..n-1).
  void restore_order(const std::vector<long long>& order);
  // Particles that left this rank's box go to their owners (collective; at
  // the end of a step); then, when the boxes' counts differ more than
  // rebalance_above allows, new cuts (rebalanced_boxes) and a second exchange.
  // A rebalance that would not lower the largest box by 5 % is not made, and
  // not tried again until the imbalance has grown by 5 %. Returns the number
  // moved over all ranks.
  long long migrate();
  long long migrated_particles() const { return migrated_; }  // since construction, all ranks
  // Seconds in migrate() since construction on this rank (the exchange, the
  // wait for the other ranks in it, and any rebalance).
  double migration_seconds() const { return migration_s_; }
  int rebalances() const { return rebalances_; }
  // max / mean of the ranks' particle counts after the last migrate() (1 on one rank).
  double imbalance() const { return imbalance_; }
  // Particles on all ranks; each particle's global id (its scene index).
  long long total_particles() const { return n_total_; }
  // One rank, never sorted: particle q has id q (outputs may skip the ids).
  bool particles_in_id_order() const { return !distributed_ && !sorted_; }
  int particle_sorts() const { return sorts_; }  // on this rank, since construction
  int sort_every() const { return setup_.sort_every; }
  Kokkos::View<const long long*, MemSpace> particle_ids() const { return ids_; }
  // All particles in id order on rank 0 (collective; empty elsewhere; on one
  // rank the particles themselves, or a copy in id order when sorted).
  Particles<dim> gathered_particles() const;
  // This rank's id block of the particles (ids [first, first + size) with
  // first = id_block_begin), in id order (collective; one rank: every
  // particle, first = 0).
  Particles<dim> id_block_particles(long long& first) const;
  // Active nodes owned by this rank (the first ones) and the global system
  // id of every active node (distributed; empty on one rank).
  LO owned_nodes() const { return distributed_ ? owned_ : active_; }
  const std::vector<GO>& global_nodes() const { return global_nodes_; }
  const RankBoxes<dim>& boxes() const { return boxes_; }
  const GridSpec<dim>& grid() const { return setup_.grid; }
  TransferScheme scheme() const { return setup_.scheme; }
  LO active_nodes() const { return active_; }
  int domain_extensions() const { return extensions_; }  // times the grid grew
  // Restart: the grid as a checkpoint recorded it (after its extensions).
  void restore_grid(const GridSpec<dim>& grid, int extensions);
  // System node of each grid node this step (-1: inactive).
  Kokkos::View<const LO*, MemSpace> system_node() const { return system_node_; }

  // Particle diagnostics: kinetic, elastic (sum V0 psi(F_p)), gravity potential,
  // linear momentum, angular momentum about the origin (z; APIC adds the
  // affine part m_p (B_p)^T term).
  // With body >= 0 only that body's particles count. mass and first_moment
  // (sum m x) give the centre of mass.
  struct Diagnostics {
    double kinetic = 0, elastic = 0, potential = 0;
    double momentum[3] = {0, 0, 0};
    double angular = 0;
    double mass = 0, first_moment[3] = {0, 0, 0};
  };
  Diagnostics diagnostics(const std::array<double, 3>& gravity, int body = -1) const;
  // Every body's Diagnostics in one pass over the particles (index = body);
  // their sum is diagnostics(gravity) up to summation order.
  std::vector<Diagnostics> body_diagnostics(const std::array<double, 3>& gravity) const;
  const std::vector<std::string>& body_names() const { return setup_.body_names; }

 private:
  MpmSetup<dim> setup_;
  Kokkos::View<MaterialParams*, MemSpace> materials_;
  Kokkos::View<LO*, MemSpace> system_node_;  // per grid node
  Kokkos::View<LO*, MemSpace> grid_node_;    // per active node
  Kokkos::View<double*, MemSpace> mass_, momentum_;  // per active node (capacity grows)
  GridScatter mass_scatter_, momentum_scatter_;
  DeformationStencils<dim, ns> stencils_;
  ParticleCells<dim> cells_;
  std::unique_ptr<MpmElasticityTerm<dim>> term_;
  LO first_ = 0, active_ = 0;
  int extensions_ = 0;
  // MPI
  Teuchos::RCP<const Teuchos::Comm<int>> comm_;
  bool distributed_ = false;
  GO global_first_ = 0;
  RankBoxes<dim> boxes_;
  RankBoxes<dim, Kokkos::HostSpace> boxes_host_;  // boxes_ on the host, for the node owners' tie-break
  Kokkos::View<long long*, MemSpace> ids_;
  long long n_total_ = 0, migrated_ = 0;
  bool sorted_ = false;  // reordered by cell since construction or replace_particles
  int sorts_ = 0;
  void sort_by_cell();
  void reset_ids();
  double migration_s_ = 0;
  int rebalances_ = 0;
  double imbalance_ = 1.0, retry_above_ = 0.0;  // retry_above_: a failed rebalance waits for more imbalance
  long long rebalance(long long largest_count);  // largest_count: from the migration's reduction
  LO owned_ = 0;
  std::vector<GO> global_nodes_;
  struct Halo;
  std::shared_ptr<Halo> halo_;
  void resize_stencils();
  void check_inside_grid(long step);
  void number_owned_first(LO first);
  void set_boxes(const RankBoxes<dim>& b);  // boxes_ and its host copy
  void sum_shared_nodes();
  double all(double v, Teuchos::EReductionType op) const;  // over the ranks (distributed)
};

}  // namespace bfemp
