#include "solver/overlap_matrix_sum.hpp"

#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Export.hpp>
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

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

// The local CRS structure of a matrix, on the host.
struct HostCrs {
  Kokkos::View<const std::size_t*, Kokkos::HostSpace> rows;
  Kokkos::View<const LO*, Kokkos::HostSpace> cols;
};

HostCrs host_crs(const Matrix& A) {
  const auto lm = A.getLocalMatrixDevice();
  auto r = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), lm.graph.row_map);
  auto c = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), lm.graph.entries);
  Kokkos::View<std::size_t*, Kokkos::HostSpace> rows("overlap_sum_rows", r.extent(0));
  for (std::size_t i = 0; i < r.extent(0); ++i) rows(i) = static_cast<std::size_t>(r(i));
  return {rows, c};
}

// Offset in A's values of (owned row r, A column c); A's rows are sorted
// (fillComplete sorts them). A missing entry is recorded in `error` (the
// first one) and gives 0: the plan's collectives run to the end on every
// rank, then every rank throws together.
LO offset_of(const HostCrs& a, LO r, LO c, GO grow, GO gcol, std::string& error) {
  if (r != Teuchos::OrdinalTraits<LO>::invalid()) {
    const LO* b = a.cols.data() + a.rows(r);
    const LO* e = a.cols.data() + a.rows(r + 1);
    const LO* it = std::lower_bound(b, e, c);
    if (c >= 0 && it != e && *it == c) return static_cast<LO>(it - a.cols.data());
  }
  if (error.empty())
    error = "OverlapMatrixSum: entry (" + std::to_string(grow) + ", " + std::to_string(gcol) +
            ") of an overlap matrix is not in the owned graph of its row's owner";
  return 0;
}

}  // namespace

OverlapMatrixSum::OverlapMatrixSum(const Matrix& A_ov, const Matrix& A, const Tpetra::Export<LO, GO, Node>& exporter)
    : comm_(raw_mpi_comm(*A.getComm())) {
  int nranks = 1;
  MPI_Comm_size(comm_, &nranks);
  const auto& row_ov = *A_ov.getRowMap();
  const auto& col_ov = *A_ov.getColMap();
  const auto& row = *A.getRowMap();
  const auto& col = *A.getColMap();
  const HostCrs ov = host_crs(A_ov), a = host_crs(A);
  const LO invalid = Teuchos::OrdinalTraits<LO>::invalid();
  const LO n_ov = static_cast<LO>(row_ov.getNodeNumElements());
  std::string error;

  // Owned rows: each entry to its offset in A.
  std::vector<LO> lsrc, ldst;
  for (LO i = 0; i < n_ov; ++i) {
    const GO grow = row_ov.getGlobalElement(i);
    const LO r = row.getLocalElement(grow);
    if (r == invalid) continue;
    for (std::size_t k = ov.rows(i); k < ov.rows(i + 1); ++k) {
      const GO gcol = col_ov.getGlobalElement(ov.cols(k));
      lsrc.push_back(static_cast<LO>(k));
      ldst.push_back(offset_of(a, r, col.getLocalElement(gcol), grow, gcol, error));
    }
  }
  local_src_ = to_device(lsrc, "overlap_sum_local_src");
  local_dst_ = to_device(ldst, "overlap_sum_local_dst");

  // Ghost rows: the Export lists each with its owner.
  const auto lids = exporter.getExportLIDs();
  const auto pids = exporter.getExportPIDs();
  std::vector<std::vector<LO>> src(nranks);
  std::vector<std::vector<long long>> keys(nranks);  // (global row, global column) pairs
  for (decltype(lids.size()) m = 0; m < lids.size(); ++m) {
    const LO i = lids[m];
    const int p = pids[m];
    const GO grow = row_ov.getGlobalElement(i);
    for (std::size_t k = ov.rows(i); k < ov.rows(i + 1); ++k) {
      src[p].push_back(static_cast<LO>(k));
      keys[p].push_back(grow);
      keys[p].push_back(col_ov.getGlobalElement(ov.cols(k)));
    }
  }
  std::vector<int> scount(nranks), rcount(nranks), sdisp(nranks + 1, 0), rdisp(nranks + 1, 0);
  for (int p = 0; p < nranks; ++p) {
    if (src[p].size() > static_cast<std::size_t>(std::numeric_limits<int>::max() / 2))
      error = "OverlapMatrixSum: more than 2^30 values for one rank (MPI counts are int)";
    scount[p] = static_cast<int>(std::min(src[p].size(), static_cast<std::size_t>(std::numeric_limits<int>::max() / 2)));
  }
  MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, comm_);
  std::vector<LO> ssrc;
  std::vector<long long> skeys;
  send_offsets_.assign(1, 0);
  recv_offsets_.assign(1, 0);
  for (int p = 0; p < nranks; ++p) {
    sdisp[p + 1] = sdisp[p] + 2 * scount[p];
    rdisp[p + 1] = rdisp[p] + 2 * rcount[p];
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
  std::vector<int> s2(nranks), r2(nranks);
  for (int p = 0; p < nranks; ++p) {
    s2[p] = 2 * scount[p];
    r2[p] = 2 * rcount[p];
  }
  std::vector<long long> rkeys(static_cast<std::size_t>(rdisp[nranks]));
  MPI_Alltoallv(skeys.data(), s2.data(), sdisp.data(), MPI_LONG_LONG, rkeys.data(), r2.data(), rdisp.data(),
                MPI_LONG_LONG, comm_);
  std::vector<LO> rdst(rkeys.size() / 2);
  for (std::size_t m = 0; m < rdst.size(); ++m) {
    const GO grow = rkeys[2 * m], gcol = rkeys[2 * m + 1];
    rdst[m] = offset_of(a, row.getLocalElement(grow), col.getLocalElement(gcol), grow, gcol, error);
  }
  int bad = error.empty() ? 0 : 1, any = 0;
  MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, comm_);
  if (any) throw std::logic_error(bad ? error : "OverlapMatrixSum: an entry missing from the owned graph on another rank");
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
