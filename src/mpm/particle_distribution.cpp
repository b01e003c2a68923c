#include "mpm/particle_distribution.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mpi.h>
#include <sstream>
#include <stdexcept>

#include "core/mpi_comm.hpp"

namespace bfemp {

namespace {

// Doubles per packed particle: id, x, v, mass, volume0, F, C, body, material
// (ids and indices are exact in a double below 2^53).
template <int dim>
constexpr int kFields = 1 + 2 * dim + 2 + 2 * dim * dim + 2;

// buf(k, :) = particle order(k) of p.
template <int dim>
void pack(const Particles<dim>& p, Kokkos::View<const long long*, MemSpace> ids, Kokkos::View<const LO*, MemSpace> order,
          Kokkos::View<double**, Kokkos::LayoutRight, MemSpace> buf) {
  Kokkos::parallel_for(
      "mpm_pack_particles", Kokkos::RangePolicy<ExecSpace>(0, order.extent(0)), KOKKOS_LAMBDA(const LO k) {
        const LO q = order(k);
        int f = 0;
        buf(k, f++) = static_cast<double>(ids(q));
        for (int c = 0; c < dim; ++c) buf(k, f++) = p.x(q, c);
        for (int c = 0; c < dim; ++c) buf(k, f++) = p.v(q, c);
        buf(k, f++) = p.mass(q);
        buf(k, f++) = p.volume0(q);
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j) buf(k, f++) = p.F(q, i, j);
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j) buf(k, f++) = p.C(q, i, j);
        buf(k, f++) = p.body(q);
        buf(k, f++) = p.material(q);
      });
}

// Rows [0, n) of buf into p at rows offset + k (by_id: at row id - offset).
template <int dim>
void unpack(Kokkos::View<const double**, Kokkos::LayoutRight, MemSpace> buf, std::size_t n, const Particles<dim>& p,
            Kokkos::View<long long*, MemSpace> ids, std::size_t offset, bool by_id) {
  Kokkos::parallel_for(
      "mpm_unpack_particles", Kokkos::RangePolicy<ExecSpace>(0, n), KOKKOS_LAMBDA(const std::size_t k) {
        int f = 0;
        const long long id = static_cast<long long>(buf(k, f++));
        const std::size_t q = by_id ? static_cast<std::size_t>(id) - offset : offset + k;
        if (ids.extent(0) > 0) ids(q) = id;
        for (int c = 0; c < dim; ++c) p.x(q, c) = buf(k, f++);
        for (int c = 0; c < dim; ++c) p.v(q, c) = buf(k, f++);
        p.mass(q) = buf(k, f++);
        p.volume0(q) = buf(k, f++);
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j) p.F(q, i, j) = buf(k, f++);
        for (int i = 0; i < dim; ++i)
          for (int j = 0; j < dim; ++j) p.C(q, i, j) = buf(k, f++);
        p.body(q) = static_cast<int>(buf(k, f++));
        p.material(q) = static_cast<int>(buf(k, f++));
      });
}

// Particles grouped by destination rank dest(q): order lists the particles
// of rank `first` first, then ranks 0, 1, ... (skipping `first`), each group
// in ascending q (stable, so runs are reproducible); count[r] per rank. A
// counting sort over chunks of particles: per chunk and rank a count, their
// running sums (chunks x ranks, on the host), then each chunk places its
// particles. Two passes over the particles (count, place) whatever the rank
// count: O(np + chunks x ranks). Chunks of 256-4096 particles, about 8 per
// thread, so that the passes use every thread.
Kokkos::View<LO*, MemSpace> group_by_dest(Kokkos::View<const int*, MemSpace> dest, int nranks, int first,
                                          std::vector<long long>& count) {
  const LO np = static_cast<LO>(dest.extent(0));
  Kokkos::View<LO*, MemSpace> order("mpm_particle_order", np);
  count.assign(nranks, 0);
  const long long per = static_cast<long long>(np) / (8LL * ExecSpace().concurrency());
  const LO chunk = static_cast<LO>(std::clamp(per, 256LL, 4096LL));
  const LO chunks = static_cast<LO>((static_cast<long long>(np) + chunk - 1) / chunk);
  if (chunks == 0) return order;
  Kokkos::View<LO**, Kokkos::LayoutRight, MemSpace> at("mpm_group_counts", chunks, nranks);
  Kokkos::parallel_for(
      "mpm_group_count", Kokkos::RangePolicy<ExecSpace>(0, chunks), KOKKOS_LAMBDA(const LO c) {
        const LO begin = c * chunk, end = np - begin > chunk ? begin + chunk : np;  // (no overflow near INT_MAX)
        for (LO q = begin; q < end; ++q) ++at(c, dest(q));
      });
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), at);
  LO offset = 0;  // each chunk's first slot per rank: groups in send order, chunks in order within each
  for (int k = -1; k < nranks; ++k) {
    const int r = k < 0 ? first : k;
    if (k >= 0 && r == first) continue;
    for (LO c = 0; c < chunks; ++c) {
      const LO n = h(c, r);
      h(c, r) = offset;
      offset += n;
      count[r] += n;
    }
  }
  Kokkos::deep_copy(at, h);
  Kokkos::parallel_for(
      "mpm_group_place", Kokkos::RangePolicy<ExecSpace>(0, chunks), KOKKOS_LAMBDA(const LO c) {
        const LO begin = c * chunk, end = np - begin > chunk ? begin + chunk : np;
        for (LO q = begin; q < end; ++q) order(at(c, dest(q))++) = q;
      });
  return order;
}

// The same by the box that holds each particle.
template <int dim>
Kokkos::View<LO*, MemSpace> group_by_owner(const Particles<dim>& p, const RankBoxes<dim>& b, int first,
                                           std::vector<long long>& count) {
  const LO np = static_cast<LO>(p.size());
  Kokkos::View<int*, MemSpace> dest("mpm_particle_dest", np);
  const auto px = p.x;
  Kokkos::parallel_for(
      "mpm_particle_owner", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const LO q) {
        Vec<dim> x;
        for (int c = 0; c < dim; ++c) x(c) = px(q, c);
        dest(q) = b.owner(x);
      });
  return group_by_dest(dest, b.nranks, first, count);
}

// The same by the id block (id_block_begin) that holds each particle's id.
Kokkos::View<LO*, MemSpace> group_by_id_block(Kokkos::View<const long long*, MemSpace> ids, long long n_total,
                                              int nranks, int first, std::vector<long long>& count) {
  const LO np = static_cast<LO>(ids.extent(0));
  Kokkos::View<int*, MemSpace> dest("mpm_particle_dest", np);
  Kokkos::parallel_for(
      "mpm_id_block_owner", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const LO q) {
        const long long id = ids(q);
        const long long guess = n_total > 0 ? id * nranks / n_total : 0;
        int r = static_cast<int>(guess < nranks - 1 ? guess : nranks - 1);
        while (r > 0 && id < id_block_begin(n_total, r, nranks)) --r;
        while (r + 1 < nranks && id >= id_block_begin(n_total, r + 1, nranks)) ++r;
        dest(q) = r;
      });
  return group_by_dest(dest, nranks, first, count);
}

using Buffer = Kokkos::View<double**, Kokkos::LayoutRight, MemSpace>;

// MPI's type of one row of `width` doubles: counts and displacements in rows
// (int), so a rank may send up to 2^31 - 1 particles, not doubles.
struct RowType {
  MPI_Datatype t;
  explicit RowType(int width) {
    MPI_Type_contiguous(width, MPI_DOUBLE, &t);
    MPI_Type_commit(&t);
  }
  ~RowType() { MPI_Type_free(&t); }
  RowType(const RowType&) = delete;
  RowType& operator=(const RowType&) = delete;
};

// Rows of `width` doubles grouped by destination (group_by_dest with
// first = this rank: count[me] rows that stay, then ranks 0, 1, ... without
// this one) sent to their ranks (collective: one all-to-all of counts, one of
// rows). Returns the rows received from the other ranks, on the device.
Kokkos::View<double**, Kokkos::LayoutRight, MemSpace> exchange_rows(
    Kokkos::View<const double**, Kokkos::LayoutRight, MemSpace> rows, const std::vector<long long>& count,
    const Teuchos::Comm<int>& comm) {
  const int me = comm.getRank(), n = comm.getSize();
  const int width = static_cast<int>(rows.extent(1));
  auto hb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), rows);
  // Counts and displacements in rows: this rank's own rows come first in hb.
  std::vector<int> scount(n, 0), sdisp(n, 0), rcount(n, 0), rdisp(n, 0);
  long long row = count[me];
  for (int r = 0; r < n; ++r) {
    if (r == me) continue;
    scount[r] = static_cast<int>(count[r]);
    sdisp[r] = static_cast<int>(row);
    row += count[r];
  }
  MPI_Comm c = raw_mpi_comm(comm);
  MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, c);
  long long recv = 0;
  for (int r = 0; r < n; ++r) {
    rdisp[r] = static_cast<int>(recv);
    recv += rcount[r];
  }
  Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace> hr("mpm_exchange_recv", recv, width);
  const RowType t(width);
  MPI_Alltoallv(hb.data(), scount.data(), sdisp.data(), t.t, hr.data(), rcount.data(), rdisp.data(), t.t, c);
  return Kokkos::create_mirror_view_and_copy(MemSpace(), hr);
}

// Every rank's n_rows rows of `width` doubles (host, row-major) on `root`,
// rank after rank (collective); the root checks that there are `expected`.
std::vector<double> gather_rows(const double* rows, long long n_rows, int width, const Teuchos::Comm<int>& comm,
                                int root, long long expected, const char* who) {
  const int me = comm.getRank(), n = comm.getSize();
  const RowType row(width);
  const int mine = static_cast<int>(n_rows);
  std::vector<int> counts(n, 0), disp(n, 0);
  MPI_Comm c = raw_mpi_comm(comm);
  MPI_Gather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, root, c);
  long long total = 0;
  for (int r = 0; r < n; ++r) {
    disp[r] = static_cast<int>(total);
    total += counts[r];
  }
  if (me == root && total != expected)
    throw std::logic_error(std::string(who) + ": " + std::to_string(total) + " particles on the ranks, expected " +
                           std::to_string(expected));
  std::vector<double> out(me == root ? static_cast<std::size_t>(total) * width : 0);
  MPI_Gatherv(rows, mine, row.t, out.data(), counts.data(), disp.data(), row.t, root, c);
  return out;
}

}  // namespace

template <int dim>
RankBoxes<dim> box_layout(const GridSpec<dim>& grid, int nranks, const std::array<int, 3>& per_axis) {
  if (nranks < 1) throw std::invalid_argument("box_layout: " + std::to_string(nranks) + " ranks, expected >= 1");
  auto cells = [&](int d) { return static_cast<double>(std::max(grid.n_cells[d], 1)); };
  std::array<int, 3> parts{1, 1, 1};
  bool given_any = false, all_positive = true;
  for (int d = 0; d < dim; ++d) given_any = given_any || per_axis[d] != 0, all_positive = all_positive && per_axis[d] >= 1;
  if (given_any) {
    long long product = 1;
    std::string given;
    for (int d = 0; d < dim; ++d) {
      product *= per_axis[d];
      given += (d ? ", " : "") + std::to_string(per_axis[d]);
      parts[d] = per_axis[d];
    }
    if (!all_positive || product != nranks)
      throw std::invalid_argument("scene key 'MPM/boxes per axis' = [" + given + "]: expected boxes whose product is "
                                  "the number of ranks, " + std::to_string(nranks) + ", each >= 1" +
                                  " (or no key: the layout from the grid)");
  } else {
    std::vector<int> primes;
    for (int n = nranks, f = 2; n > 1;) {
      if (f * f > n) f = n;
      while (n % f == 0) primes.push_back(f), n /= f;
      ++f;
    }
    std::sort(primes.rbegin(), primes.rend());
    for (const int f : primes) {
      int best = 0;
      for (int d = 1; d < dim; ++d)
        if (cells(d) / parts[d] > cells(best) / parts[best]) best = d;
      parts[best] *= f;
    }
  }
  std::array<int, dim> order;
  for (int d = 0; d < dim; ++d) order[d] = d;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    if (parts[a] != parts[b]) return parts[a] > parts[b];
    return cells(a) > cells(b);
  });
  RankBoxes<dim> b;
  b.nranks = nranks;
  b.levels = 0;
  for (int l = 0; l < dim; ++l) {
    b.axis[l] = order[l];
    b.parts[l] = parts[order[l]];
    if (b.parts[l] > 1) b.levels = l + 1;
  }
  b.levels = std::max(b.levels, 1);
  b.cuts = Kokkos::View<double*, MemSpace>("mpm_box_cuts", b.level_offset(b.levels));
  return b;
}

template <int dim>
std::string describe_boxes(const RankBoxes<dim>& b) {
  const auto h = b.mirror();
  std::ostringstream s;
  if (b.levels == 1 || b.parts[1] == 1) {
    s << "slabs along axis " << b.axis[0] << ", cuts at ";
    for (std::size_t k = 0; k < h.cuts.extent(0); ++k) s << (k ? ", " : "") << h.cuts(k);
    s << " m";
    return s.str();
  }
  for (int l = 0; l < b.levels; ++l) s << (l ? " x " : "") << b.parts[l];
  s << " boxes:";
  int groups = 1;
  for (int l = 0; l < b.levels; ++l) {
    const int n = b.parts[l] - 1, off = b.level_offset(l);
    s << (l ? ";" : "") << " axis " << b.axis[l] << " cut at ";
    for (int g = 0; g < groups; ++g) {
      s << (g ? " | " : "");
      for (int k = 0; k < n; ++k) s << (k ? ", " : "") << h.cuts(off + g * n + k);
    }
    groups *= b.parts[l];
  }
  s << " m";
  return s.str();
}

namespace {

// Cuts of one group into `parts` along an axis from the group's sorted
// coordinates: the nearest cell face to each quantile r / parts. An empty
// group gets -inf cuts (a particle entering it goes to its last part);
// histogram_cuts puts an empty group's cuts at the grid's top face (its first
// part). Either is deterministic and the same on every rank.
void quantile_cuts(const std::vector<double>& sorted, int parts, double o, double dx, double* out) {
  double prev = -std::numeric_limits<double>::infinity();
  for (int r = 1; r < parts; ++r) {
    double cut = -std::numeric_limits<double>::infinity();
    if (!sorted.empty()) {
      const std::size_t k = std::min(sorted.size() - 1, sorted.size() * r / parts);
      cut = o + dx * std::round((sorted[k] - o) / dx);  // the nearest cell face
    }
    if (r > 1) cut = std::max(cut, prev);
    out[r - 1] = prev = cut;
  }
}

// Cuts of one group into `parts` at the cell faces whose particle count
// below is nearest r / parts of the group's, from the counts of its bins
// (bin 0: below the grid; 1..layers: the cell layers; layers + 1: above).
// Returns the largest part's count.
long long histogram_cuts(const long long* bins, int layers, int parts, double o, double dx, double* out) {
  // below[f]: particles under face f (coordinate o + f dx), f = 0..layers.
  std::vector<long long> below(layers + 1, bins[0]);
  for (int k = 0; k < layers; ++k) below[k + 1] = below[k] + bins[k + 1];
  const long long n_all = below[layers] + bins[layers + 1];
  const double total = static_cast<double>(n_all);
  int face = 0;
  long long prev = 0, largest = 0;
  for (int r = 1; r < parts; ++r) {
    const double target = total * r / parts;
    while (face < layers && std::abs(static_cast<double>(below[face + 1]) - target) <=
                                std::abs(static_cast<double>(below[face]) - target))
      ++face;
    out[r - 1] = o + dx * face;
    largest = std::max(largest, below[face] - prev);
    prev = below[face];
  }
  return std::max(largest, n_all - prev);
}

}  // namespace

template <int dim>
RankBoxes<dim> balanced_boxes(const Particles<dim>& all, const GridSpec<dim>& grid, int nranks,
                              const std::array<int, 3>& per_axis) {
  RankBoxes<dim> b = box_layout(grid, nranks, per_axis);
  auto x = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), all.x);
  auto h = Kokkos::create_mirror_view(b.cuts);
  std::vector<std::vector<std::size_t>> groups(1);
  for (std::size_t q = 0; q < x.extent(0); ++q) groups[0].push_back(q);
  for (int l = 0; l < b.levels; ++l) {
    const int a = b.axis[l], parts = b.parts[l], n = parts - 1, off = b.level_offset(l);
    std::vector<std::vector<std::size_t>> next;
    for (std::size_t g = 0; g < groups.size(); ++g) {
      std::vector<double> c;
      c.reserve(groups[g].size());
      for (const std::size_t q : groups[g]) c.push_back(x(q, a));
      // NaN dropped (std::sort needs a strict weak order; the lookup below and
      // owner() put NaN in part 0)
      c.erase(std::remove_if(c.begin(), c.end(), [](double v) { return std::isnan(v); }), c.end());
      std::sort(c.begin(), c.end());
      double* cut = h.data() + off + g * n;
      quantile_cuts(c, parts, grid.origin(a), grid.dx, cut);
      std::vector<std::vector<std::size_t>> children(parts);
      for (const std::size_t q : groups[g]) {
        int i = 0;
        while (i < n && x(q, a) >= cut[i]) ++i;
        children[i].push_back(q);
      }
      for (auto& ch : children) next.push_back(std::move(ch));
    }
    groups = std::move(next);
  }
  Kokkos::deep_copy(b.cuts, h);
  return b;
}

template <int dim>
RankBoxes<dim> rebalanced_boxes(const Particles<dim>& p, const RankBoxes<dim>& old, const GridSpec<dim>& grid,
                                const Teuchos::Comm<int>& comm, long long& largest) {
  if (old.nranks != comm.getSize())
    throw std::logic_error("rebalanced_boxes: a layout for " + std::to_string(old.nranks) + " ranks on " +
                           std::to_string(comm.getSize()));
  RankBoxes<dim> s = old;
  s.cuts = Kokkos::View<double*, MemSpace>("mpm_box_cuts", old.cuts.extent(0));
  auto ch = Kokkos::create_mirror_view(s.cuts);
  const auto x = p.x;
  largest = 0;
  int groups = 1;
  for (int l = 0; l < s.levels; ++l) {
    const int a = s.axis[l], parts = s.parts[l], n = parts - 1, off = s.level_offset(l);
    const int layers = std::max(grid.n_cells[a], 1), width = layers + 2;
    const double o = grid.origin(a), dx = grid.dx;
    Kokkos::deep_copy(s.cuts, ch);  // the levels above are final: they pick each particle's group
    Kokkos::View<long long*, MemSpace> hist("mpm_box_histogram", static_cast<std::size_t>(groups) * width);
    const RankBoxes<dim> sd = s;
    Kokkos::parallel_for(
        "mpm_box_histogram", Kokkos::RangePolicy<ExecSpace>(0, p.size()), KOKKOS_LAMBDA(const LO q) {
          Vec<dim> xq;
          for (int d = 0; d < dim; ++d) xq(d) = x(q, d);
          const double layer = std::floor((xq(a) - o) / dx);
          const int k = !(layer >= 0.0) ? 0 : layer >= layers ? layers + 1 : 1 + static_cast<int>(layer);  // NaN: bin 0
          Kokkos::atomic_add(&hist(sd.group(xq, l) * width + k), 1LL);
        });
    auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), hist);
    std::vector<long long> all(h.extent(0), 0);
    Teuchos::reduceAll(comm, Teuchos::REDUCE_SUM, static_cast<int>(all.size()), h.data(), all.data());
    for (int g = 0; g < groups; ++g) {
      const long long most = histogram_cuts(all.data() + static_cast<std::size_t>(g) * width, layers, parts, o, dx,
                                            ch.data() + off + g * n);
      if (l == s.levels - 1) largest = std::max(largest, most);
    }
    groups *= parts;
  }
  Kokkos::deep_copy(s.cuts, ch);
  return s;
}

template <int dim>
Particles<dim> select_box(const Particles<dim>& all, const RankBoxes<dim>& boxes, int rank,
                          Kokkos::View<long long*, MemSpace>& ids) {
  const LO np = static_cast<LO>(all.size());
  Kokkos::View<long long*, MemSpace> all_ids("mpm_particle_ids_all", np);
  Kokkos::parallel_for(
      "mpm_ids_identity", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const LO q) { all_ids(q) = q; });
  std::vector<long long> count;
  auto order = group_by_owner(all, boxes, rank, count);
  const LO mine = static_cast<LO>(count[rank]);
  Buffer buf("mpm_select_buffer", mine, kFields<dim>);
  pack<dim>(all, all_ids, Kokkos::subview(order, std::make_pair(LO(0), mine)), buf);
  Particles<dim> out = allocate_particles<dim>(mine);
  ids = Kokkos::View<long long*, MemSpace>("mpm_particle_ids", mine);
  unpack<dim>(buf, mine, out, ids, 0, false);
  Kokkos::fence();
  return out;
}

template <int dim>
long long migrate_particles(Particles<dim>& p, Kokkos::View<long long*, MemSpace>& ids, const RankBoxes<dim>& boxes,
                            const Teuchos::Comm<int>& comm, long long& largest) {
  const int me = comm.getRank(), n = comm.getSize();
  largest = static_cast<long long>(p.size());
  if (n == 1) return 0;
  std::vector<long long> count;
  auto order = group_by_owner(p, boxes, me, count);
  const long long np = static_cast<long long>(p.size());
  // One allreduce: summed over the senders, count[r] is rank r's particle
  // count after the exchange, and the appended entry (this rank's leavers)
  // the number that move.
  std::vector<long long> mine(count.begin(), count.end()), all(n + 1, 0);
  mine.push_back(np - count[me]);
  Teuchos::reduceAll(comm, Teuchos::REDUCE_SUM, n + 1, mine.data(), all.data());
  largest = *std::max_element(all.begin(), all.begin() + n);
  const long long moved = all[n];
  if (moved == 0) return 0;
  constexpr int nf = kFields<dim>;
  Buffer buf("mpm_migrate_buffer", np, nf);
  pack<dim>(p, ids, order, buf);
  const auto rb = exchange_rows(buf, count, comm);
  const std::size_t kept = static_cast<std::size_t>(count[me]), arrived = rb.extent(0);
  Particles<dim> out = allocate_particles<dim>(kept + arrived);
  Kokkos::View<long long*, MemSpace> out_ids("mpm_particle_ids", kept + arrived);
  unpack<dim>(Kokkos::subview(buf, std::make_pair(std::size_t(0), kept), Kokkos::ALL()), kept, out, out_ids, 0, false);
  if (arrived > 0) unpack<dim>(rb, arrived, out, out_ids, kept, false);
  Kokkos::fence();
  p = out;
  ids = out_ids;
  return moved;
}

template <int dim>
Particles<dim> gather_particles(const Particles<dim>& p, Kokkos::View<const long long*, MemSpace> ids,
                                long long n_total, const Teuchos::Comm<int>& comm, int root) {
  const int me = comm.getRank();
  constexpr int nf = kFields<dim>;
  const LO np = static_cast<LO>(p.size());
  Kokkos::View<LO*, MemSpace> order("mpm_gather_order", np);
  Kokkos::parallel_for(
      "mpm_gather_identity", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const LO q) { order(q) = q; });
  Buffer buf("mpm_gather_buffer", np, nf);
  pack<dim>(p, ids, order, buf);
  auto hb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), buf);
  const std::vector<double> all = gather_rows(hb.data(), np, nf, comm, root, n_total, "gather_particles");
  Kokkos::View<const double**, Kokkos::LayoutRight, Kokkos::HostSpace> hr(all.data(), me == root ? n_total : 0, nf);
  if (me != root) return allocate_particles<dim>(0);
  Particles<dim> out = allocate_particles<dim>(n_total);
  auto rb = Kokkos::create_mirror_view_and_copy(MemSpace(), hr);
  unpack<dim>(rb, n_total, out, Kokkos::View<long long*, MemSpace>(), 0, true);
  Kokkos::fence();
  return out;
}

template <int dim>
Particles<dim> particles_in_id_block(const Particles<dim>& p, Kokkos::View<const long long*, MemSpace> ids,
                                     long long n_total, const Teuchos::Comm<int>& comm) {
  const int me = comm.getRank(), n = comm.getSize();
  const long long lo = id_block_begin(n_total, me, n), hi = id_block_begin(n_total, me + 1, n);
  std::vector<long long> count;
  const auto order = group_by_id_block(ids, n_total, n, me, count);
  Buffer buf("mpm_id_block_buffer", p.size(), kFields<dim>);
  pack<dim>(p, ids, order, buf);
  const auto rb = exchange_rows(buf, count, comm);
  const std::size_t kept = static_cast<std::size_t>(count[me]), arrived = rb.extent(0);
  if (static_cast<long long>(kept + arrived) != hi - lo)
    throw std::logic_error("particles_in_id_block: rank " + std::to_string(me) + " received " +
                           std::to_string(kept + arrived) + " particles for ids " + std::to_string(lo) + ".." +
                           std::to_string(hi) + " (ids not unique or out of range)");
  Particles<dim> out = allocate_particles<dim>(hi - lo);
  const Kokkos::View<long long*, MemSpace> none;
  const auto lo_z = static_cast<std::size_t>(lo);
  unpack<dim>(Kokkos::subview(buf, std::make_pair(std::size_t(0), kept), Kokkos::ALL()), kept, out, none, lo_z, true);
  if (arrived > 0) unpack<dim>(rb, arrived, out, none, lo_z, true);
  Kokkos::fence();
  return out;
}

template <int dim>
Particles<dim> particles_by_id(const Particles<dim>& p, Kokkos::View<const long long*, MemSpace> ids) {
  const LO np = static_cast<LO>(p.size());
  if (static_cast<LO>(ids.extent(0)) != np) throw std::logic_error("particles_by_id: one id per particle expected");
  Kokkos::View<LO*, MemSpace> order("mpm_by_id_order", np);
  Kokkos::parallel_for(
      "mpm_by_id_identity", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const LO q) { order(q) = q; });
  Buffer buf("mpm_by_id_buffer", np, kFields<dim>);
  pack<dim>(p, ids, order, buf);
  Particles<dim> out = allocate_particles<dim>(np);
  unpack<dim>(buf, np, out, Kokkos::View<long long*, MemSpace>(), 0, true);
  Kokkos::fence();
  return out;
}

template <int dim>
void permute_particles(Particles<dim>& p, Kokkos::View<long long*, MemSpace>& ids, Kokkos::View<const LO*, MemSpace> order) {
  const std::size_t np = p.size();
  if (order.extent(0) != np || ids.extent(0) != np)
    throw std::logic_error("permute_particles: one order entry and one id per particle expected");
  Buffer buf("mpm_permute_buffer", np, kFields<dim>);
  pack<dim>(p, ids, order, buf);
  Particles<dim> out = allocate_particles<dim>(np);
  Kokkos::View<long long*, MemSpace> out_ids("mpm_particle_ids", np);
  unpack<dim>(buf, np, out, out_ids, 0, false);
  Kokkos::fence();
  p = out;
  ids = out_ids;
}

Kokkos::View<double*, MemSpace> particle_values_in_id_block(Kokkos::View<const double*, MemSpace> values, int k,
                                                            Kokkos::View<const long long*, MemSpace> ids,
                                                            long long n_total, const Teuchos::Comm<int>& comm) {
  const int me = comm.getRank(), n = comm.getSize();
  const long long lo = id_block_begin(n_total, me, n), hi = id_block_begin(n_total, me + 1, n);
  const std::size_t np = ids.extent(0);
  if (values.extent(0) < np * k) throw std::logic_error("particle_values_in_id_block: fewer values than particles");
  std::vector<long long> count;
  const auto order = group_by_id_block(ids, n_total, n, me, count);
  // Rows (id, k values) grouped by destination.
  Buffer buf("mpm_id_block_values", np, k + 1);
  Kokkos::parallel_for(
      "mpm_pack_values", Kokkos::RangePolicy<ExecSpace>(0, np), KOKKOS_LAMBDA(const std::size_t r) {
        const LO q = order(r);
        buf(r, 0) = static_cast<double>(ids(q));
        for (int j = 0; j < k; ++j) buf(r, 1 + j) = values(q * k + j);
      });
  const auto rb = exchange_rows(buf, count, comm);
  const std::size_t kept = static_cast<std::size_t>(count[me]), arrived = rb.extent(0);
  if (static_cast<long long>(kept + arrived) != hi - lo)
    throw std::logic_error("particle_values_in_id_block: rank " + std::to_string(me) + " received " +
                           std::to_string(kept + arrived) + " particles for ids " + std::to_string(lo) + ".." +
                           std::to_string(hi));
  Kokkos::View<double*, MemSpace> out("mpm_id_block_values_out", static_cast<std::size_t>(hi - lo) * k);
  auto place = [&](Kokkos::View<const double**, Kokkos::LayoutRight, MemSpace> rows, std::size_t m) {
    Kokkos::parallel_for(
        "mpm_place_values", Kokkos::RangePolicy<ExecSpace>(0, m), KOKKOS_LAMBDA(const std::size_t r) {
          const auto q = static_cast<std::size_t>(static_cast<long long>(rows(r, 0)) - lo);
          for (int j = 0; j < k; ++j) out(q * k + j) = rows(r, 1 + j);
        });
  };
  place(Kokkos::subview(buf, std::make_pair(std::size_t(0), kept), Kokkos::ALL()), kept);
  if (arrived > 0) place(rb, arrived);
  Kokkos::fence();
  return out;
}

#define BFEMP_INSTANTIATE(D)                                                                                        \
  template RankBoxes<D> box_layout<D>(const GridSpec<D>&, int, const std::array<int, 3>&);                         \
  template std::string describe_boxes<D>(const RankBoxes<D>&);                                                     \
  template RankBoxes<D> balanced_boxes<D>(const Particles<D>&, const GridSpec<D>&, int, const std::array<int, 3>&); \
  template RankBoxes<D> rebalanced_boxes<D>(const Particles<D>&, const RankBoxes<D>&, const GridSpec<D>&,          \
                                            const Teuchos::Comm<int>&, long long&);                                 \
  template Particles<D> select_box<D>(const Particles<D>&, const RankBoxes<D>&, int,                               \
                                      Kokkos::View<long long*, MemSpace>&);                                         \
  template long long migrate_particles<D>(Particles<D>&, Kokkos::View<long long*, MemSpace>&,                      \
                                          const RankBoxes<D>&, const Teuchos::Comm<int>&, long long&);              \
  template Particles<D> gather_particles<D>(const Particles<D>&, Kokkos::View<const long long*, MemSpace>, long long, \
                                            const Teuchos::Comm<int>&, int);                                        \
  template Particles<D> particles_in_id_block<D>(const Particles<D>&, Kokkos::View<const long long*, MemSpace>,     \
                                                 long long, const Teuchos::Comm<int>&);                               \
  template Particles<D> particles_by_id<D>(const Particles<D>&, Kokkos::View<const long long*, MemSpace>);           \
  template void permute_particles<D>(Particles<D>&, Kokkos::View<long long*, MemSpace>&,                            \
                                     Kokkos::View<const LO*, MemSpace>);
BFEMP_INSTANTIATE(2)
BFEMP_INSTANTIATE(3)
#undef BFEMP_INSTANTIATE

}  // namespace bfemp
