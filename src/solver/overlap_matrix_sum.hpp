#pragma once
// The sum of every rank's overlap matrix into the owned matrix,
//   A(R, C) = sum over ranks p of A_ov^p(R, C)      (R, C global DOF ids),
// as a precomputed value exchange. Tpetra's CrsMatrix Export does the same sum
// but looks every entry up by its global ids on every call (85-140 ms per
// Newton iteration at 5e3 DOFs per rank); the graphs are fixed between
// rebuilds, so the plan is made once per graph:
//   - an entry k of an owned row of A_ov goes to a fixed offset of A's values
//     (distinct offsets: each local row has distinct columns);
//   - the entries of ghost rows are sent, in a fixed order, to the rows'
//     owners; each owner knows the offset of every value it receives.
// A sum is then: A's values set to zero, one device gather of the outgoing
// values, one nonblocking exchange with the neighbouring ranks only, device
// adds of the local and received values (received ones atomically: several
// ranks may send to one entry).
// Preconditions: A's graph holds every entry of every rank's A_ov (built by
// exporting the overlap graph with INSERT); the Export goes from A_ov's row
// map to A's; A is fill-active when sum() is called. Construction is
// collective (host work and one all-to-all of counts); so is sum().
#include <Tpetra_Export_decl.hpp>
#include <mpi.h>
#include <vector>

#include "solver/tpetra_types.hpp"

namespace bfemp {

class OverlapMatrixSum {
 public:
  OverlapMatrixSum(const Matrix& A_ov, const Matrix& A, const Tpetra::Export<LO, GO, Node>& exporter);
  // A's values <- the sum over the ranks of their A_ov values.
  void sum(const Matrix& A_ov, Matrix& A);

  std::size_t sent_values() const { return send_src_.extent(0); }
  std::size_t received_values() const { return recv_dst_.extent(0); }

 private:
  MPI_Comm comm_;
  Kokkos::View<LO*, MemSpace> local_src_, local_dst_;  // A_ov value -> A value, owned rows
  Kokkos::View<LO*, MemSpace> send_src_;               // outgoing value m is A_ov value send_src_(m)
  Kokkos::View<LO*, MemSpace> recv_dst_;               // incoming value m is added to A value recv_dst_(m)
  Kokkos::View<double*, MemSpace> send_buf_, recv_buf_;
  std::vector<int> send_ranks_, send_offsets_, recv_ranks_, recv_offsets_;  // offsets: one more than ranks
  std::vector<MPI_Request> requests_;
};

}  // namespace bfemp
