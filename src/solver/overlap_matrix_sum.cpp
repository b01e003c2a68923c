#include "solver/overlap_matrix_sum.hpp"

#include <Tpetra_CrsGraph.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Export.hpp>
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/mpi_comm.hpp"

namespace bfemp {

static_assert(Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemSpace>::accessible,
              "OverlapMatrixSum hands its device buffers to MPI: host-accessible memory expected");

namespace {

template <class T>
Kokkos::View<T*, MemSpace> to_device(const std::vector<T>& v, const char* name) {
  Kokkos::View<T*, MemSpace> d(std::string(name), v.size());
  auto h = Kokkos::create_mirror_view(d);
  for (std::size_t i = 0; i < v.size(); ++i) h(i) = v[i];
  Kokkos::deep_copy(d, h);
  return d;
}

}  // namespace

OverlapMatrixSum::OverlapMatrixSum(const Graph& G_ov, const Tpetra::Export<LO, GO, Node>& exporter)
    : comm_(raw_mpi_comm(*G_ov.getComm())) {
  int nranks = 1, me = 0;
  MPI_Comm_size(comm_, &nranks);
  MPI_Comm_rank(comm_, &me);
  if (G_ov.getColMap().get() != G_ov.getRowMap().get())
    throw std::logic_error("OverlapMatrixSum: the overlap graph's column map must be its row map");
  const auto row_map = exporter.getTargetMap();
  const auto& row = *row_map;
  const auto& row_ov = *G_ov.getRowMap();
  const auto lg = G_ov.getLocalGraphHost();
  const auto& ov_rows = lg.row_map;
  const auto& ov_cols = lg.entries;
  const LO invalid = Teuchos::OrdinalTraits<LO>::invalid();
  const LO n_ov = static_cast<LO>(row_ov.getNodeNumElements());
  const LO n_own = static_cast<LO>(row.getNodeNumElements());

  // Per overlap DOF (row = column): its owned row, else its owner's rank.
  std::vector<LO> own_of(n_ov);
  std::vector<int> owner(n_ov, me);
  for (LO i = 0; i < n_ov; ++i) own_of[i] = row.getLocalElement(row_ov.getGlobalElement(i));
  const auto lids = exporter.getExportLIDs();
  const auto pids = exporter.getExportPIDs();
  for (decltype(lids.size()) m = 0; m < lids.size(); ++m) owner[lids[m]] = pids[m];

  // Ghost rows to their owners: (row, column, column's owner) per entry.
  std::vector<std::vector<LO>> src(nranks);
  std::vector<std::vector<long long>> keys(nranks);
  for (decltype(lids.size()) m = 0; m < lids.size(); ++m) {
    const LO i = lids[m];
    const int p = pids[m];
    const GO grow = row_ov.getGlobalElement(i);
    for (std::size_t k = ov_rows(i); k < ov_rows(i + 1); ++k) {
      const LO c = ov_cols(k);
      src[p].push_back(static_cast<LO>(k));
      keys[p].push_back(grow);
      keys[p].push_back(row_ov.getGlobalElement(c));
      keys[p].push_back(owner[c]);
    }
  }
  std::string error;
  // Each value travels as 3 keys, and MPI's counts and displacements are
  // int: a rank's sent and received values must each total at most kMax
  // (checked on every rank before the exchange; all throw together).
  const std::size_t kMax = static_cast<std::size_t>(std::numeric_limits<int>::max() / 3);
  std::vector<int> scount(nranks), rcount(nranks), sdisp(nranks + 1, 0), rdisp(nranks + 1, 0);
  std::size_t sent_total = 0, received_total = 0;
  for (int p = 0; p < nranks; ++p) {
    sent_total += src[p].size();
    scount[p] = static_cast<int>(std::min(src[p].size(), kMax));
  }
  MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, comm_);
  for (int p = 0; p < nranks; ++p) received_total += static_cast<std::size_t>(rcount[p]);
  {
    int big = sent_total > kMax || received_total > kMax ? 1 : 0, any_big = 0;
    MPI_Allreduce(&big, &any_big, 1, MPI_INT, MPI_MAX, comm_);
    if (any_big)
      throw std::length_error("OverlapMatrixSum: a rank sends or receives more than " + std::to_string(kMax) +
                              " matrix values (this rank: " + std::to_string(sent_total) + " sent, " +
                              std::to_string(received_total) + " received; MPI counts are int)");
  }
  std::vector<LO> ssrc;
  std::vector<long long> skeys;
  send_offsets_.assign(1, 0);
  recv_offsets_.assign(1, 0);
  std::vector<int> s3(nranks), r3(nranks);
  for (int p = 0; p < nranks; ++p) {
    s3[p] = 3 * scount[p];
    r3[p] = 3 * rcount[p];
    sdisp[p + 1] = sdisp[p] + s3[p];
    rdisp[p + 1] = rdisp[p] + r3[p];
    ssrc.insert(ssrc.end(), src[p].begin(), src[p].end());
    skeys.insert(skeys.end(), keys[p].begin(), keys[p].end());
    if (scount[p] > 0) {
      send_ranks_.push_back(p);
      send_offsets_.push_back(send_offsets_.back() + scount[p]);
    }
    if (rcount[p] > 0) {
      recv_ranks_.push_back(p);
      recv_offsets_.push_back(recv_offsets_.back() + rcount[p]);
    }
  }
  std::vector<long long> rkeys(static_cast<std::size_t>(rdisp[nranks]));
  MPI_Alltoallv(skeys.data(), s3.data(), sdisp.data(), MPI_LONG_LONG, rkeys.data(), r3.data(), rdisp.data(),
                MPI_LONG_LONG, comm_);
  const std::size_t n_recv = rkeys.size() / 3;

  // A's columns: the owned DOFs (local id = row id), then the others by (owner, id).
  std::vector<std::pair<int, GO>> remote;
  for (LO i = 0; i < n_ov; ++i) {
    if (own_of[i] == invalid) continue;
    for (std::size_t k = ov_rows(i); k < ov_rows(i + 1); ++k)
      if (owner[ov_cols(k)] != me) remote.emplace_back(owner[ov_cols(k)], row_ov.getGlobalElement(ov_cols(k)));
  }
  std::vector<LO> recv_row(n_recv);
  for (std::size_t m = 0; m < n_recv; ++m) {
    recv_row[m] = row.getLocalElement(rkeys[3 * m]);
    if (recv_row[m] == invalid && error.empty())
      error = "OverlapMatrixSum: row " + std::to_string(rkeys[3 * m]) + " was sent to a rank that does not own it";
    if (rkeys[3 * m + 2] != me) remote.emplace_back(static_cast<int>(rkeys[3 * m + 2]), rkeys[3 * m + 1]);
  }
  std::sort(remote.begin(), remote.end());
  remote.erase(std::unique(remote.begin(), remote.end()), remote.end());
  const auto remote_col = [&](int p, GO g) {
    const auto it = std::lower_bound(remote.begin(), remote.end(), std::make_pair(p, g));
    return it != remote.end() && *it == std::make_pair(p, g) ? static_cast<LO>(n_own + (it - remote.begin()))
                                                             : invalid;
  };
  std::vector<LO> col_of(n_ov);  // A's local column of each overlap column
  for (LO i = 0; i < n_ov; ++i)
    col_of[i] = own_of[i] != invalid ? own_of[i] : owner[i] == me ? invalid : remote_col(owner[i], row_ov.getGlobalElement(i));
  std::vector<GO> col_gids(static_cast<std::size_t>(n_own) + remote.size());
  for (LO r = 0; r < n_own; ++r) col_gids[r] = row.getGlobalElement(r);
  for (std::size_t k = 0; k < remote.size(); ++k) col_gids[n_own + k] = remote[k].second;

  // The received entries by owned row (counting sort).
  std::vector<std::size_t> rstart(static_cast<std::size_t>(n_own) + 1, 0);
  for (std::size_t m = 0; m < n_recv; ++m)
    if (recv_row[m] != invalid) ++rstart[recv_row[m] + 1];
  for (LO r = 0; r < n_own; ++r) rstart[r + 1] += rstart[r];
  std::vector<std::size_t> rorder(n_recv), fill(rstart.begin(), rstart.end() - 1);
  for (std::size_t m = 0; m < n_recv; ++m)
    if (recv_row[m] != invalid) rorder[fill[recv_row[m]]++] = m;

  // Each owned row: its overlap row's columns (in order where the mapping
  // keeps it: owned columns keep the overlap order, the others come after),
  // merged with the received ones; every source's offset recorded.
  Kokkos::View<std::size_t*, Node::device_type> rowptr("overlap_sum_rowptr", static_cast<std::size_t>(n_own) + 1);
  std::vector<LO> cols;
  std::vector<LO> lsrc, ldst;
  std::vector<LO> rdst(n_recv, 0);
  std::vector<std::pair<LO, long long>> row_items;  // (A column, source: k >= 0 overlap entry, -1 - m received)
  cols.reserve(ov_cols.extent(0));
  lsrc.reserve(ov_cols.extent(0));
  ldst.reserve(ov_cols.extent(0));
  std::vector<LO> row_of_ov(n_own, invalid);
  for (LO i = 0; i < n_ov; ++i)
    if (own_of[i] != invalid) row_of_ov[own_of[i]] = i;
  for (LO r = 0; r < n_own; ++r) {
    rowptr(r) = cols.size();
    const LO i = row_of_ov[r];
    row_items.clear();
    bool sorted = true;
    LO last = -1;
    if (i != invalid)
      for (std::size_t k = ov_rows(i); k < ov_rows(i + 1); ++k) {
        const LO c = col_of[ov_cols(k)];
        sorted = sorted && c > last;
        last = c;
        row_items.emplace_back(c, static_cast<long long>(k));
      }
    for (std::size_t q = rstart[r]; q < rstart[r + 1]; ++q) {
      const std::size_t m = rorder[q];
      const GO g = rkeys[3 * m + 1];
      const int p = static_cast<int>(rkeys[3 * m + 2]);
      row_items.emplace_back(p == me ? row.getLocalElement(g) : remote_col(p, g), -1 - static_cast<long long>(m));
      sorted = false;
    }
    if (!sorted) std::sort(row_items.begin(), row_items.end());
    for (const auto& [c, s] : row_items) {
      if (c == invalid || c < 0) {
        if (error.empty()) error = "OverlapMatrixSum: a column owned by no rank in row " + std::to_string(row.getGlobalElement(r));
        continue;
      }
      if (cols.size() == rowptr(r) || cols.back() != c) cols.push_back(c);
      const LO at = static_cast<LO>(cols.size() - 1);
      if (s >= 0) {
        lsrc.push_back(static_cast<LO>(s));
        ldst.push_back(at);
      } else {
        rdst[static_cast<std::size_t>(-1 - s)] = at;
      }
    }
  }
  rowptr(n_own) = cols.size();
  int bad = error.empty() ? 0 : 1, any = 0;
  MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, comm_);
  if (any) throw std::logic_error(bad ? error : "OverlapMatrixSum: a bad entry on another rank");
  Kokkos::View<LO*, Node::device_type> colind(Kokkos::ViewAllocateWithoutInitializing("overlap_sum_colind"),
                                              cols.size());
  for (std::size_t k = 0; k < cols.size(); ++k) colind(k) = cols[k];
  auto col_map = Teuchos::rcp(new Map(Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid(),
                                      Teuchos::ArrayView<const GO>(col_gids), 0, row.getComm()));
  auto graph = Teuchos::rcp(new Graph(row_map, col_map, rowptr, colind));
  graph->fillComplete(row_map, row_map);
  graph_ = graph;

  local_src_ = to_device(lsrc, "overlap_sum_local_src");
  local_dst_ = to_device(ldst, "overlap_sum_local_dst");
  send_src_ = to_device(ssrc, "overlap_sum_send_src");
  recv_dst_ = to_device(rdst, "overlap_sum_recv_dst");
  send_buf_ = Kokkos::View<double*, MemSpace>("overlap_sum_send", ssrc.size());
  recv_buf_ = Kokkos::View<double*, MemSpace>("overlap_sum_recv", rdst.size());
  requests_.resize(send_ranks_.size() + recv_ranks_.size());
}

void OverlapMatrixSum::sum(const Matrix& A_ov, Matrix& A) {
  const auto vov = A_ov.getLocalMatrixDevice().values;
  const auto v = A.getLocalMatrixDevice().values;
  const auto ssrc = send_src_;
  const auto sbuf = send_buf_;
  Kokkos::parallel_for(
      "overlap_sum_pack", Kokkos::RangePolicy<ExecSpace>(0, ssrc.extent(0)),
      KOKKOS_LAMBDA(const LO m) { sbuf(m) = vov(ssrc(m)); });
  Kokkos::fence();
  constexpr int tag = 7301;
  std::size_t q = 0;
  for (std::size_t k = 0; k < recv_ranks_.size(); ++k)
    MPI_Irecv(recv_buf_.data() + recv_offsets_[k], recv_offsets_[k + 1] - recv_offsets_[k], MPI_DOUBLE,
              recv_ranks_[k], tag, comm_, &requests_[q++]);
  for (std::size_t k = 0; k < send_ranks_.size(); ++k)
    MPI_Isend(send_buf_.data() + send_offsets_[k], send_offsets_[k + 1] - send_offsets_[k], MPI_DOUBLE,
              send_ranks_[k], tag, comm_, &requests_[q++]);
  // The local part while the values travel.
  Kokkos::deep_copy(v, 0.0);
  const auto lsrc = local_src_;
  const auto ldst = local_dst_;
  Kokkos::parallel_for(
      "overlap_sum_local", Kokkos::RangePolicy<ExecSpace>(0, lsrc.extent(0)),
      KOKKOS_LAMBDA(const LO k) { v(ldst(k)) += vov(lsrc(k)); });
  MPI_Waitall(static_cast<int>(q), requests_.data(), MPI_STATUSES_IGNORE);
  const auto rdst = recv_dst_;
  const auto rbuf = recv_buf_;
  Kokkos::parallel_for(
      "overlap_sum_received", Kokkos::RangePolicy<ExecSpace>(0, rdst.extent(0)),
      KOKKOS_LAMBDA(const LO m) { Kokkos::atomic_add(&v(rdst(m)), rbuf(m)); });
  Kokkos::fence();
}

}  // namespace bfemp
