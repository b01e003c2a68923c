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
// The plan also builds A's graph: each owned row holds the union of that
// row's columns on every rank (this rank's overlap row, and the ghost rows
// the other ranks send), its column map the owned DOFs first (in row order),
// then the others sorted by owning rank and id (Tpetra groups its remote
// columns by rank too, but within a rank not always by id: the same set,
// possibly in another order; tests/mpi/test_overlap_matrix_sum.cpp). This
// replaces an Export of the overlap graph with INSERT (plus its
// fillComplete), which inserted every entry by global id: 0.4-0.7 s per
// graph on the paper twist at 2 ranks. Each column's owner comes with it
// (the exporter names the owner of each ghost row, and the overlap graph's
// columns are its rows), so no directory lookup is needed for them.
// Preconditions: the overlap graph is fill-complete with its column map the
// same Map object as its row map (build_dof_graph); the Export goes from
// that map to the owned one-to-one map (A's row, domain and range map); A is
// made from graph() and is fill-active when sum() is called. Construction is
// collective (host work; an all-to-all of counts and one of the keys, two
// all-reduces, the column Map and the graph's fillComplete, which builds its
// Import); so is sum().
#include <Tpetra_Export_decl.hpp>
#include <mpi.h>
#include <vector>

#include "solver/tpetra_types.hpp"

namespace bfemp {

class OverlapMatrixSum {
 public:
  OverlapMatrixSum(const Graph& G_ov, const Tpetra::Export<LO, GO, Node>& exporter);
  // A's graph, fill-complete on the exporter's target map.
  Teuchos::RCP<const Graph> graph() const { return graph_; }
  // A's values <- the sum over the ranks of their A_ov values.
  void sum(const Matrix& A_ov, Matrix& A);

  std::size_t sent_values() const { return send_src_.extent(0); }
  std::size_t received_values() const { return recv_dst_.extent(0); }

 private:
  MPI_Comm comm_;
  Teuchos::RCP<const Graph> graph_;
  Kokkos::View<LO*, MemSpace> local_src_, local_dst_;  // A_ov value -> A value, owned rows
  Kokkos::View<LO*, MemSpace> send_src_;               // outgoing value m is A_ov value send_src_(m)
  Kokkos::View<LO*, MemSpace> recv_dst_;               // incoming value m is added to A value recv_dst_(m)
  Kokkos::View<double*, MemSpace> send_buf_, recv_buf_;
  std::vector<int> send_ranks_, send_offsets_, recv_ranks_, recv_offsets_;  // offsets: one more than ranks
  std::vector<MPI_Request> requests_;
};

}  // namespace bfemp
