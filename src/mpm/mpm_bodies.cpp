#include "mpm/mpm_bodies.hpp"

#include <Tpetra_TieBreak.hpp>

#include <Kokkos_Timer.hpp>

#include "solver/tpetra_types.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Tpetra_Export.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_Map.hpp>
#include <Tpetra_MultiVector.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>

namespace bfemp {

template <int dim>
void MpmElasticityTerm<dim>::add_couplings(NodeGraphBuilder& graph) const {
  constexpr int ns = bspline_stencil_size<dim>;
  if (cells_.order.extent(0) != static_cast<std::size_t>(this->stencils().size())) {
    DeformationTerm<dim, ns>::add_couplings(graph);
    return;
  }
  const auto nodes = this->stencils().nodes;
  const auto cells = cells_.cells;
  const auto start = cells_.start;
  const auto order = cells_.order;
  graph.add_cliques(cells_.n_cells, ns,
                    KOKKOS_LAMBDA(const long k, const int a) { return nodes(order(start(cells(k))), a); });
}

template <int dim>
void MpmElasticityTerm<dim>::assemble(ConstDofView x, const Sink<dim>& sink) const {
  constexpr int ns = bspline_stencil_size<dim>;
  constexpr int nd = ns * dim;
  const auto s = this->stencils();
  const bool project = this->projection() && sink.project;
  const auto cells = cells_.cells;
  const auto start = cells_.start;
  const auto count = cells_.count;
  const auto order = cells_.order;
  if (cells_.order.extent(0) != static_cast<std::size_t>(s.size()))
    throw std::logic_error("MpmElasticityTerm::assemble: particles not binned into cells for these stencils");
  Sink<dim> plain = sink;
  plain.atomic = false;  // the cells of one phase's slabs share no node
  const long n_cells = cells_.n_cells;  // the sink's scatter table, if any, is by cell
  const auto sweep = cells_.sweep;
  const auto phase = cells_.phase;
  auto cell_add = KOKKOS_LAMBDA(const LO k) {
    const LO n = cells(k);
    Eigen::Matrix<double, nd, 1> gl = Eigen::Matrix<double, nd, 1>::Zero();
    SquareMat<nd> Hl = SquareMat<nd>::Zero();
    const LO first = start(n), last = start(n) + count(n);
    for (LO j = first; j < last; ++j) deformation_local_add<dim, ns>(s, x, order(j), project, gl, Hl);
    symmetric_from_lower<nd>(Hl);
    LO nodes[ns];
    for (int a = 0; a < ns; ++a) nodes[a] = s.nodes(order(first), a);
    plain.add_stencil(nodes, ns, gl, &Hl, plain.stencil_positions(k, ns, n_cells));
  };
  // Too few slabs for the threads (a body thin along the last axis): the
  // colors, one after the other, the cells of each in parallel.
  constexpr int kSlabs = ParticleCells<dim>::kSlabs;
  const int threads = ExecSpace().concurrency();
  if (threads > 1 && cells_.slabs < std::max(2, std::min(threads, kSlabs) / 2)) {
    for (int c = 0; c < ParticleCells<dim>::n_colors; ++c) {
      const LO c0 = cells_.color_start(c), c1 = cells_.color_start(c + 1);
      if (c1 > c0) Kokkos::parallel_for("mpm_assemble_cells", Kokkos::RangePolicy<ExecSpace>(c0, c1), cell_add);
    }
    return;
  }
  // The sweep (particle_cells.hpp): phase A, then phase B; within a phase the
  // slabs in parallel, each one's cells in node order on one thread.
  for (int ph = 0; ph < 2; ++ph) {
    Kokkos::parallel_for(
        "mpm_assemble_sweep",
        Kokkos::RangePolicy<ExecSpace, Kokkos::Schedule<Kokkos::Dynamic>>(0, kSlabs, Kokkos::ChunkSize(1)),
        KOKKOS_LAMBDA(const int slab) {
          for (LO i = phase(4 * slab + 2 * ph); i < phase(4 * slab + 2 * ph + 1); ++i) cell_add(sweep(i));
        });
  }
}

template <int dim>
long MpmElasticityTerm<dim>::scatter_table(const LocalMatrix& A, Kokkos::View<int*, MemSpace>& table) const {
  constexpr int ns = bspline_stencil_size<dim>;
  const auto nodes = this->stencils().nodes;
  const auto cells = cells_.cells;
  const auto start = cells_.start;
  const auto order = cells_.order;
  const long n_cells = cells_.n_cells;
  scatter_positions<dim>(
      A.graph, n_cells, ns, KOKKOS_LAMBDA(const long k, const int a) { return nodes(order(start(cells(k))), a); },
      table);
  return n_cells;
}

template <int dim>
struct MpmBodies<dim>::Halo {
  Teuchos::RCP<const Map> overlap, owned;
  Teuchos::RCP<const Tpetra::Export<LO, GO, Node>> exporter;
  Teuchos::RCP<const Tpetra::Import<LO, GO, Node>> importer;
};

template <int dim>
MpmBodies<dim>::MpmBodies(MpmSetup<dim> setup, Kokkos::View<MaterialParams*, MemSpace> materials)
    : setup_(std::move(setup)), materials_(materials) {
  const std::size_t np = setup_.particles.size();
  system_node_ = Kokkos::View<LO*, MemSpace>("mpm_system_node", setup_.grid.num_nodes());
  stencils_.materials = materials_;
  resize_stencils();
  n_total_ = static_cast<long long>(np);
  reset_ids();
  if (setup_.particle_total >= 0) {  // an id block: ids first, first + 1, ...
    n_total_ = setup_.particle_total;
    auto ids = ids_;
    const long long first = setup_.particle_first;
    Kokkos::parallel_for(
        "mpm_ids_from", Kokkos::RangePolicy<ExecSpace>(0, np),
        KOKKOS_LAMBDA(const std::size_t q) { ids(q) += first; });
  }
  term_ = std::make_unique<MpmElasticityTerm<dim>>("mpm elasticity", stencils_);
}

template <int dim>
void MpmBodies<dim>::reset_ids() {  // one rank, particles in scene order: id q at row q
  const std::size_t np = setup_.particles.size();
  if (ids_.extent(0) != np) ids_ = Kokkos::View<long long*, MemSpace>("mpm_particle_ids", np);
  auto ids = ids_;
  Kokkos::parallel_for(
      "mpm_ids", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const std::size_t q) { ids(q) = q; });
  sorted_ = false;
}

template <int dim>
void MpmBodies<dim>::resize_stencils() {
  const std::size_t np = setup_.particles.size();
  if (stencils_.nodes.data() != nullptr && stencils_.nodes.extent(0) == np) return;
  stencils_.nodes = decltype(stencils_.nodes)("mpm_stencil_nodes", np);
  stencils_.g = decltype(stencils_.g)("mpm_stencil_g", np);
  stencils_.volume = decltype(stencils_.volume)("mpm_stencil_volume", np);
  stencils_.material = decltype(stencils_.material)("mpm_stencil_material", np);
}

template <int dim>
double MpmBodies<dim>::all(double v, Teuchos::EReductionType op) const {
  if (!distributed_) return v;
  double g = v;
  Teuchos::reduceAll(*comm_, op, v, Teuchos::outArg(g));
  return g;
}

template <int dim>
void MpmBodies<dim>::distribute(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, GO global_first) {
  comm_ = comm;
  global_first_ = global_first;
  distributed_ = comm->getSize() > 1;
  if (!distributed_) return;
  if (setup_.particle_total >= 0)
    replace_particle_block(setup_.particles, setup_.particle_first, setup_.particle_total);
  else
    replace_particles(setup_.particles);
}

template <int dim>
void MpmBodies<dim>::replace_particles(const Particles<dim>& all) {
  n_total_ = static_cast<long long>(all.size());
  if (!distributed_) {
    setup_.particles = all;
    reset_ids();
    resize_stencils();
    return;
  }
  set_boxes(balanced_boxes(all, setup_.grid, comm_->getSize(), setup_.boxes_per_axis));
  setup_.particles = select_box(all, boxes_, comm_->getRank(), ids_);
  resize_stencils();
}

template <int dim>
void MpmBodies<dim>::replace_particle_block(const Particles<dim>& mine, long long first, long long total) {
  if (!distributed_) {
    if (first != 0 || static_cast<long long>(mine.size()) != total)
      throw std::logic_error("MpmBodies::replace_particle_block: rows " + std::to_string(first) + ".. of " +
                             std::to_string(total) + " on one rank");
    replace_particles(mine);
    return;
  }
  // The blocks must tile [0, total) in rank order (a checkpoint read whole
  // on every rank would otherwise put each particle on every rank): one
  // scan and one reduction, the verdict the same on every rank.
  const long long np_mine = static_cast<long long>(mine.size());
  long long upto = 0;
  Teuchos::scan(*comm_, Teuchos::REDUCE_SUM, np_mine, Teuchos::outArg(upto));
  const long long wrong_here = upto - np_mine != first || (comm_->getRank() == comm_->getSize() - 1 && upto != total);
  long long wrong = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, wrong_here, Teuchos::outArg(wrong));
  if (wrong)
    throw std::invalid_argument("the ranks' particle rows do not tile the " +
                                std::to_string(total) + " particles (rank " + std::to_string(comm_->getRank()) +
                                ": ids " + std::to_string(first) + ".." + std::to_string(first + np_mine) + ")");
  n_total_ = total;
  setup_.particles = mine;
  sorted_ = false;
  const std::size_t np = mine.size();
  ids_ = Kokkos::View<long long*, MemSpace>("mpm_particle_ids", np);
  auto ids = ids_;
  Kokkos::parallel_for(
      "mpm_ids_block", Kokkos::RangePolicy<ExecSpace>(0, np),
      KOKKOS_LAMBDA(const std::size_t q) { ids(q) = first + static_cast<long long>(q); });
  long long largest = 0;
  const RankBoxes<dim> layout = box_layout(setup_.grid, comm_->getSize(), setup_.boxes_per_axis);
  set_boxes(rebalanced_boxes(setup_.particles, layout, setup_.grid, *comm_, largest));
  migrate_particles(setup_.particles, ids_, boxes_, *comm_, largest);
  resize_stencils();
}

template <int dim>
Particles<dim> MpmBodies<dim>::id_block_particles(long long& first) const {
  first = 0;
  if (!distributed_) return gathered_particles();
  first = id_block_begin(n_total_, comm_->getRank(), comm_->getSize());
  return particles_in_id_block(setup_.particles, ids_, n_total_, *comm_);
}

template <int dim>
void MpmBodies<dim>::restore_order(const std::vector<long long>& order) {
  const std::size_t np = setup_.particles.size();
  if (distributed_) throw std::logic_error("MpmBodies::restore_order on several ranks");
  std::vector<char> seen(np, 0);
  bool ok = order.size() == np;
  for (std::size_t k = 0; ok && k < np; ++k) {
    ok = order[k] >= 0 && order[k] < static_cast<long long>(np) && !seen[order[k]];
    if (ok) seen[order[k]] = 1;
  }
  if (!ok)
    throw std::invalid_argument("restart: checkpoint field 'particle_order' (" + std::to_string(order.size()) +
                                " values) is not a permutation of the " + std::to_string(np) + " particles");
  Kokkos::View<LO*, Kokkos::HostSpace> h("mpm_restored_order", np);
  for (std::size_t k = 0; k < np; ++k) h(k) = static_cast<LO>(order[k]);
  auto d = Kokkos::create_mirror_view_and_copy(MemSpace(), h);
  // ids are 0..n-1 after replace_particles: row k gets particle order[k].
  permute_particles(setup_.particles, ids_, Kokkos::View<const LO*, MemSpace>(d));
  sorted_ = true;
}

template <int dim>
long long MpmBodies<dim>::migrate() {
  if (!distributed_) return 0;
  Kokkos::Timer timer;
  long long largest = 0;
  long long moved = migrate_particles(setup_.particles, ids_, boxes_, *comm_, largest);
  moved += rebalance(largest);
  if (moved > 0) resize_stencils();
  migrated_ += moved;
  migration_s_ += timer.seconds();
  return moved;
}

template <int dim>
long long MpmBodies<dim>::rebalance(long long largest_count) {
  const double largest = static_cast<double>(largest_count);
  const double mean = static_cast<double>(n_total_) / comm_->getSize();
  imbalance_ = mean > 0 ? largest / mean : 1.0;
  const double above = setup_.rebalance_above;
  if (imbalance_ <= above) retry_above_ = 0.0;  // balanced again: the next excess may be splittable
  if (!(above > 0) || imbalance_ <= above || imbalance_ <= retry_above_) return 0;
  long long new_largest = 0;
  RankBoxes<dim> s = rebalanced_boxes(setup_.particles, boxes_, setup_.grid, *comm_, new_largest);
  if (static_cast<double>(new_largest) > 0.95 * largest) {  // a cell layer too crowded to split better
    retry_above_ = 1.05 * imbalance_;
    return 0;
  }
  set_boxes(s);
  retry_above_ = 0.0;
  ++rebalances_;
  long long after = 0;
  const long long moved = migrate_particles(setup_.particles, ids_, boxes_, *comm_, after);
  imbalance_ = mean > 0 ? static_cast<double>(after) / mean : 1.0;
  return moved;
}

template <int dim>
Particles<dim> MpmBodies<dim>::gathered_particles() const {
  if (!distributed_) return sorted_ ? particles_by_id(setup_.particles, ids_) : setup_.particles;
  return gather_particles(setup_.particles, ids_, n_total_, *comm_);
}

// The step's first check: every particle's stencil inside the grid, or the
// grid grown to hold them all (a decision every rank takes together).
template <int dim>
void MpmBodies<dim>::check_inside_grid(long step) {
  const auto& grid = setup_.grid;
  const auto& p = setup_.particles;
  const LO out = particle_outside(grid, p);
  double out_id = -1;
  std::array<double, dim> pos{};
  if (out >= 0) {
    long long id = 0;
    Kokkos::deep_copy(id, Kokkos::subview(ids_, out));
    out_id = static_cast<double>(id);
    auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), Kokkos::subview(p.x, out, Kokkos::ALL()));
    for (int d = 0; d < dim; ++d) pos[d] = x(d);
  }
  if (distributed_) {  // the highest id outside, its position from its rank
    const double mine = out_id;
    out_id = all(mine, Teuchos::REDUCE_MAX);
    for (int d = 0; d < dim; ++d) pos[d] = all(mine == out_id && out_id >= 0 ? pos[d] : 0.0, Teuchos::REDUCE_SUM);
  }
  if (out_id < 0) return;
  std::string where;
  bool finite = true;
  for (int d = 0; d < dim; ++d) {
    where += (d ? ", " : "") + std::to_string(pos[d]);
    finite = finite && std::isfinite(pos[d]);
  }
  const std::string who = "step " + std::to_string(step) + ": MPM particle " +
                          std::to_string(static_cast<long long>(out_id)) + " at (" + where + ")";
  if (!setup_.extend_domain)
    throw std::runtime_error(who + " left the grid domain (its B-spline stencil needs half a cell "
                             "inside the grid); enlarge the scene's MPM grid domain or set "
                             "'MPM/when particles leave: extend'");
  if (!finite) throw std::runtime_error(who + " has a non-finite position; the grid cannot be extended to it");
  // Bounding box of the particles (all ranks), and the highest id of a
  // particle with a non-finite coordinate.
  Vec<dim> lo, hi;
  double bad = -1;
  const auto ids = ids_;
  for (int d = 0; d < dim; ++d) {
    double l = std::numeric_limits<double>::infinity(), h = -l, b = -1;
    const auto px = p.x;
    Kokkos::parallel_reduce(
        "mpm_bounding_box", Kokkos::RangePolicy<ExecSpace>(0, p.size()),
        KOKKOS_LAMBDA(const LO q, double& a, double& z, double& nb) {
          const double c = px(q, d);
          if (!std::isfinite(c)) {
            nb = static_cast<double>(ids(q)) > nb ? static_cast<double>(ids(q)) : nb;
            return;
          }
          a = c < a ? c : a;
          z = c > z ? c : z;
        },
        Kokkos::Min<double>(l), Kokkos::Max<double>(h), Kokkos::Max<double>(b));
    lo(d) = all(l, Teuchos::REDUCE_MIN);
    hi(d) = all(h, Teuchos::REDUCE_MAX);
    bad = std::max(bad, all(b, Teuchos::REDUCE_MAX));
  }
  if (bad >= 0)
    throw std::runtime_error("step " + std::to_string(step) + ": MPM particle " +
                             std::to_string(static_cast<long long>(bad)) +
                             " has a non-finite position; the grid cannot be extended to it");
  int margin = 2;
  for (int d = 0; d < dim; ++d) margin = std::max(margin, grid.n_cells[d] / 4);
  try {
    setup_.grid = grid_extended(grid, lo, hi, margin);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(who + " left the grid domain and extending it failed: " + e.what());
  }
  ++extensions_;
  system_node_ = Kokkos::View<LO*, MemSpace>("mpm_system_node", setup_.grid.num_nodes());
}

template <int dim>
void MpmBodies<dim>::set_boxes(const RankBoxes<dim>& b) {
  boxes_ = b;
  boxes_host_ = b.mirror();
}

namespace {

// The owner of a grid node that several ranks hold: the rank whose box
// holds the node's position, or, when that rank does not hold the node, the
// holder whose box is nearest to it in the layout (RankBoxes::distance; for
// slabs, in slab order), then the lower rank. Each rank then owns the nodes
// on its side of a cut, so the ranks' parts of the system mirror each other
// across a cut. With the lowest holder (Tpetra's default) the lower rank of
// a cut owned every shared node: on the 3D twist at the ci size the two
// ranks' BLOCK_CHOLMOD blocks had 3800 and 4500 rows and 0.55e9 and 1.45e9
// factorisation flops (this rule: 4100 / 4200 rows, 0.78e9 / 1.13e9); on the
// paper-size twist the DOF exchanges sent 442 MB instead of 702 in 5 steps
// (perf/README).
template <int dim>
struct BoxOwner : Tpetra::Details::TieBreak<LO, GO> {
  GridSpec<dim> grid;
  const RankBoxes<dim, Kokkos::HostSpace>* boxes = nullptr;
  GO first = 0;
  bool mayHaveSideEffects() const override { return false; }
  std::size_t selectedIndex(GO gid, const std::vector<std::pair<int, LO>>& holders) const override {
    const Vec<dim> c = grid.node_position(static_cast<LO>(gid - first));
    const int want = boxes->owner(c);
    std::size_t best = 0;
    for (std::size_t k = 1; k < holders.size(); ++k) {
      const int dk = boxes->distance(holders[k].first, want), db = boxes->distance(holders[best].first, want);
      if (dk < db || (dk == db && holders[k].first < holders[best].first)) best = k;
    }
    return best;
  }
};

}  // namespace

// Distributed: the active nodes renumbered owned first (in ascending global
// id, the order activate_grid gives), then ghosts; the halo maps of the step.
template <int dim>
void MpmBodies<dim>::number_owned_first(LO first) {
  using gsize = Tpetra::global_size_t;
  const gsize invalid = Teuchos::OrdinalTraits<gsize>::invalid();
  auto gn = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(),
                                                Kokkos::subview(grid_node_, std::make_pair(LO(0), active_)));
  std::vector<GO> gids(active_);
  for (LO k = 0; k < active_; ++k) gids[k] = global_first_ + gn(k);
  auto overlap0 = Teuchos::rcp(new Map(invalid, Teuchos::ArrayView<const GO>(gids), 0, comm_));
  BoxOwner<dim> tie;
  tie.grid = setup_.grid;
  tie.boxes = &boxes_host_;
  tie.first = global_first_;
  auto one = Tpetra::createOneToOne(Teuchos::RCP<const Map>(overlap0), tie);
  global_nodes_.clear();
  global_nodes_.reserve(active_);
  for (GO g : gids)
    if (one->isNodeGlobalElement(g)) global_nodes_.push_back(g);
  owned_ = static_cast<LO>(global_nodes_.size());
  for (GO g : gids)
    if (!one->isNodeGlobalElement(g)) global_nodes_.push_back(g);
  for (LO k = 0; k < active_; ++k) gn(k) = static_cast<LO>(global_nodes_[k] - global_first_);
  auto gnd = Kokkos::subview(grid_node_, std::make_pair(LO(0), active_));
  Kokkos::deep_copy(gnd, gn);
  auto sn = system_node_;
  Kokkos::parallel_for(
      "mpm_number_owned_first", Kokkos::RangePolicy<ExecSpace>(0, active_),
      KOKKOS_LAMBDA(const LO k) { sn(gnd(k)) = first + k; });
  if (!halo_) halo_ = std::make_shared<Halo>();
  Halo& h = *halo_;
  h.overlap = Teuchos::rcp(new Map(invalid, Teuchos::ArrayView<const GO>(global_nodes_), 0, comm_));
  h.owned = Teuchos::rcp(new Map(invalid, Teuchos::ArrayView<const GO>(global_nodes_.data(), owned_), 0, comm_));
  h.exporter = Teuchos::rcp(new Tpetra::Export<LO, GO, Node>(h.overlap, h.owned));
  h.importer = Teuchos::rcp(new Tpetra::Import<LO, GO, Node>(h.owned, h.overlap));
}

// Distributed: node mass and momentum summed over the ranks holding the node.
template <int dim>
void MpmBodies<dim>::sum_shared_nodes() {
  Halo& h = *halo_;
  MultiVec ov(h.overlap, dim + 1), own(h.owned, dim + 1);
  auto m = mass_;
  auto mv = momentum_;
  {
    auto v = ov.getLocalViewDevice(Tpetra::Access::OverwriteAll);
    Kokkos::parallel_for(
        "mpm_halo_pack", Kokkos::RangePolicy<ExecSpace>(0, active_), KOKKOS_LAMBDA(const LO k) {
          v(k, 0) = m(k);
          for (int c = 0; c < dim; ++c) v(k, 1 + c) = mv(k * dim + c);
        });
  }
  own.doExport(ov, *h.exporter, Tpetra::ADD);
  ov.doImport(own, *h.importer, Tpetra::INSERT);
  auto v = ov.getLocalViewDevice(Tpetra::Access::ReadOnly);
  Kokkos::parallel_for(
      "mpm_halo_unpack", Kokkos::RangePolicy<ExecSpace>(0, active_), KOKKOS_LAMBDA(const LO k) {
        m(k) = v(k, 0);
        for (int c = 0; c < dim; ++c) mv(k * dim + c) = v(k, 1 + c);
      });
}

template <int dim>
void MpmBodies<dim>::sort_by_cell() {
  // Within a cell by id: the sorted order depends on the positions and ids
  // alone, so a restarted run sorts as the uninterrupted one did.
  bin_particles(setup_.grid, setup_.particles, cells_, Kokkos::View<const long long*, MemSpace>(ids_));
  permute_particles(setup_.particles, ids_, Kokkos::View<const LO*, MemSpace>(cells_.order));
  sorted_ = true;
  ++sorts_;
}

template <int dim>
LO MpmBodies<dim>::begin_step(LO first, long step) {
  check_inside_grid(step);
  if (setup_.sort_every > 0 && (step - 1) % setup_.sort_every == 0) sort_by_cell();
  resize_stencils();
  const auto& grid = setup_.grid;
  const auto& p = setup_.particles;
  first_ = first;
  active_ = activate_grid(grid, p, first, system_node_, grid_node_);
  if (distributed_) number_owned_first(first);
  if (static_cast<LO>(mass_.extent(0)) < active_) {
    const std::size_t cap = static_cast<std::size_t>(active_) * 5 / 4 + 16;  // grow, not per step
    mass_ = Kokkos::View<double*, MemSpace>("mpm_grid_mass", cap);
    momentum_ = Kokkos::View<double*, MemSpace>("mpm_grid_momentum", cap * dim);
    mass_scatter_ = GridScatter(mass_);
    momentum_scatter_ = GridScatter(momentum_);
  }
  Kokkos::deep_copy(Kokkos::subview(mass_, std::make_pair(0, active_)), 0.0);
  Kokkos::deep_copy(Kokkos::subview(momentum_, std::make_pair(0, active_ * dim)), 0.0);
  mass_scatter_.reset();
  momentum_scatter_.reset();
  p2g(grid, p, setup_.scheme, system_node_, first, mass_scatter_, momentum_scatter_);
  Kokkos::Experimental::contribute(mass_, mass_scatter_);  // the per-thread copies into mass_
  Kokkos::Experimental::contribute(momentum_, momentum_scatter_);
  if (distributed_) sum_shared_nodes();
  mpm_stencils(grid, p, system_node_, stencils_);
  bin_particles(grid, p, cells_);
  term_->set_stencils(stencils_);
  term_->set_cells(cells_);
  return active_;
}

template <int dim>
void MpmBodies<dim>::restore_grid(const GridSpec<dim>& grid, int extensions) {
  if (!(grid.dx > 0)) throw std::invalid_argument("restart: MPM grid spacing " + std::to_string(grid.dx) + ", expected > 0");
  setup_.grid = grid;
  extensions_ = extensions;
  system_node_ = Kokkos::View<LO*, MemSpace>("mpm_system_node", setup_.grid.num_nodes());
}

template <int dim>
void MpmBodies<dim>::fill_system(Kokkos::View<double*, MemSpace> x, Kokkos::View<double*, MemSpace> v,
                                 Kokkos::View<double*, MemSpace> mass) const {
  const auto grid = setup_.grid;
  auto gn = grid_node_;
  auto m = mass_;
  auto mv = momentum_;
  const LO first = first_;
  Kokkos::parallel_for(
      "mpm_fill_system", Kokkos::RangePolicy<ExecSpace>(0, active_), KOKKOS_LAMBDA(const LO k) {
        const Vec<dim> xi = grid.node_position(gn(k));
        const LO s = first + k;
        for (int c = 0; c < dim; ++c) {
          x(s * dim + c) = xi(c);
          v(s * dim + c) = mv(k * dim + c) / m(k);
          mass(s * dim + c) = m(k);
        }
      });
}

template <int dim>
void MpmBodies<dim>::end_step(Kokkos::View<const double*, MemSpace> x_new, Kokkos::View<const double*, MemSpace> v_new,
                              Kokkos::View<const double*, MemSpace> v_old) {
  g2p(setup_.grid, setup_.particles, setup_.scheme, system_node_, x_new, v_new, v_old);
}

template <int dim>
typename MpmBodies<dim>::Diagnostics MpmBodies<dim>::diagnostics(const std::array<double, 3>& g, int body) const {
  const auto& p = setup_.particles;
  auto mats = materials_;
  const bool apic = setup_.scheme == TransferScheme::APIC;
  const double D = setup_.grid.dx * setup_.grid.dx / 4.0;
  double ke = 0, el = 0, pe = 0, p0 = 0, p1 = 0, p2 = 0, L = 0, M = 0, X0 = 0, X1 = 0, X2 = 0;
  Kokkos::parallel_reduce(
      "mpm_diagnostics", Kokkos::RangePolicy<ExecSpace>(0, p.size()),
      KOKKOS_LAMBDA(const LO q, double& k, double& e, double& u, double& q0, double& q1, double& q2, double& l,
                    double& mm, double& x0, double& x1, double& x2) {
        if (body >= 0 && p.body(q) != body) return;
        const double m = p.mass(q);
        Mat<dim> F;
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j) F(i, j) = p.F(q, i, j);
        e += p.volume0(q) * material_energy<dim>(mats(p.material(q)), F);
        double v2 = 0;
        for (int c = 0; c < dim; ++c) {
          v2 += p.v(q, c) * p.v(q, c);
          u -= m * g[c] * p.x(q, c);
        }
        k += 0.5 * m * v2;
        q0 += m * p.v(q, 0);
        q1 += m * p.v(q, 1);
        if constexpr (dim == 3) q2 += m * p.v(q, 2);
        mm += m;
        x0 += m * p.x(q, 0);
        x1 += m * p.x(q, 1);
        if constexpr (dim == 3) x2 += m * p.x(q, 2);
        // z angular momentum: x v_y - y v_x, plus the APIC affine part
        // m (B^T)_{xy} - m (B^T)_{yx} with B = C D.
        l += m * (p.x(q, 0) * p.v(q, 1) - p.x(q, 1) * p.v(q, 0));
        if (apic) l += m * D * (p.C(q, 1, 0) - p.C(q, 0, 1));
      },
      ke, el, pe, p0, p1, p2, L, M, X0, X1, X2);
  if (distributed_) {  // every rank's particles
    double loc[11] = {ke, el, pe, p0, p1, p2, L, M, X0, X1, X2}, glob[11];
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, 11, loc, glob);
    ke = glob[0], el = glob[1], pe = glob[2], p0 = glob[3], p1 = glob[4], p2 = glob[5];
    L = glob[6], M = glob[7], X0 = glob[8], X1 = glob[9], X2 = glob[10];
  }
  Diagnostics d;
  d.kinetic = ke;
  d.elastic = el;
  d.potential = pe;
  d.momentum[0] = p0;
  d.momentum[1] = p1;
  d.momentum[2] = p2;
  d.angular = L;
  d.mass = M;
  d.first_moment[0] = X0;
  d.first_moment[1] = X1;
  d.first_moment[2] = X2;
  return d;
}

namespace {

// Array reduction: kBodyFields sums per body, laid out [body * kBodyFields + f].
constexpr int kBodyFields = 12;  // ke, el, pe, p0..2, L, M, X0..2, (pad)

template <int dim>
struct BodyDiagnosticsSum {
  using value_type = double[];
  using size_type = std::size_t;
  size_type value_count;
  Particles<dim> p;
  Kokkos::View<const MaterialParams*, MemSpace> mats;
  std::array<double, 3> g;
  bool apic;
  double D;

  KOKKOS_INLINE_FUNCTION void operator()(const LO q, value_type acc) const {
    double* a = acc + static_cast<std::size_t>(p.body(q)) * kBodyFields;
    const double m = p.mass(q);
    Mat<dim> F;
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j) F(i, j) = p.F(q, i, j);
    a[1] += p.volume0(q) * material_energy<dim>(mats(p.material(q)), F);
    double v2 = 0;
    for (int c = 0; c < dim; ++c) {
      v2 += p.v(q, c) * p.v(q, c);
      a[2] -= m * g[c] * p.x(q, c);
      a[3 + c] += m * p.v(q, c);
      a[9 + c] += m * p.x(q, c);
    }
    a[0] += 0.5 * m * v2;
    a[6] += m * (p.x(q, 0) * p.v(q, 1) - p.x(q, 1) * p.v(q, 0));
    if (apic) a[6] += m * D * (p.C(q, 1, 0) - p.C(q, 0, 1));
    a[8] += m;
  }
  KOKKOS_INLINE_FUNCTION void join(volatile value_type dst, const volatile value_type src) const {
    for (size_type i = 0; i < value_count; ++i) dst[i] += src[i];
  }
  KOKKOS_INLINE_FUNCTION void init(value_type v) const {
    for (size_type i = 0; i < value_count; ++i) v[i] = 0.0;
  }
};

}  // namespace

template <int dim>
std::vector<typename MpmBodies<dim>::Diagnostics> MpmBodies<dim>::body_diagnostics(
    const std::array<double, 3>& g) const {
  const std::size_t nb = std::max<std::size_t>(1, setup_.body_names.size());
  BodyDiagnosticsSum<dim> f{nb * kBodyFields, setup_.particles, materials_, g,
                            setup_.scheme == TransferScheme::APIC, setup_.grid.dx * setup_.grid.dx / 4.0};
  std::vector<double> sums(nb * kBodyFields, 0.0);
  Kokkos::parallel_reduce("mpm_body_diagnostics", Kokkos::RangePolicy<ExecSpace>(0, setup_.particles.size()), f,
                          sums.data());
  if (distributed_) {  // every rank's particles
    std::vector<double> local = sums;
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, static_cast<int>(sums.size()), local.data(), sums.data());
  }
  std::vector<Diagnostics> out(nb);  // (one entry for an unnamed set of particles)
  for (std::size_t b = 0; b < out.size(); ++b) {
    const double* a = sums.data() + b * kBodyFields;
    Diagnostics& d = out[b];
    d.kinetic = a[0];
    d.elastic = a[1];
    d.potential = a[2];
    for (int c = 0; c < 3; ++c) d.momentum[c] = a[3 + c], d.first_moment[c] = a[9 + c];
    d.angular = a[6];
    d.mass = a[8];
  }
  return out;
}

template class MpmElasticityTerm<2>;
template class MpmElasticityTerm<3>;
template class MpmBodies<2>;
template class MpmBodies<3>;

}  // namespace bfemp
