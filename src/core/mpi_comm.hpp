#pragma once
// The MPI communicator under a Teuchos one (for the exchanges that Tpetra
// does not cover: particle migration, the overlap matrix sum).
// Precondition: comm is a Teuchos::MpiComm (bfemp always runs under MPI).
#include <Teuchos_Comm.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <mpi.h>
#include <stdexcept>

namespace bfemp {

inline MPI_Comm raw_mpi_comm(const Teuchos::Comm<int>& comm) {
  const auto* m = dynamic_cast<const Teuchos::MpiComm<int>*>(&comm);
  if (!m) throw std::logic_error("bfemp: the communicator is not an MPI one");
  return (*m->getRawMpiComm())();
}

}  // namespace bfemp
