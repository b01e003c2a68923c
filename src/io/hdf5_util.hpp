#pragma once
// HDF5 C API helpers shared by the frame writer and the checkpoints (io/
// only; not a public interface).
//
// Serial and parallel writes: a file opened with make_fapl(file, comm) and a
// communicator of R > 1 ranks uses HDF5's MPI-IO driver; every object
// creation is then collective (all ranks, same order, same names, shapes and
// attribute values), and data go with independent transfers. write_dataset
// writes either a replicated dataset (every rank has the same data; rank 0
// transfers them) or each rank's block of rows. A failure on one rank is
// agreed on (one allreduce per dataset), so every rank throws and none waits
// in the next collective call. comm == MPI_COMM_NULL: the serial driver.
//
// Files are opened without HDF5 file locking (a viewer may read a file a run
// is still writing; several ranks read one checkpoint).
#include <hdf5.h>
#include <mpi.h>

#include <cstddef>
#include <string>

namespace bfemp::h5 {

// Suppresses HDF5's automatic error printing while alive, then restores it.
class QuietErrors {
 public:
  QuietErrors() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietErrors() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }
  QuietErrors(const QuietErrors&) = delete;
  QuietErrors& operator=(const QuietErrors&) = delete;

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
};

// Throws std::runtime_error "HDF5 file 'file': what [HDF5 error stack]".
// Must run before any other HDF5 call: each API call clears the stack.
[[noreturn]] void fail(const std::string& file, const std::string& what);

template <class T>
T check(T value, const std::string& file, const std::string& what) {
  if (value < 0) fail(file, what);
  return value;
}

// Owning hid_t, closed with its matching H5?close (release() hands it back).
class Handle {
 public:
  Handle(hid_t id, herr_t (*closer)(hid_t)) : id_(id), closer_(closer) {}
  ~Handle() {
    if (id_ >= 0) closer_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  hid_t release() {
    const hid_t id = id_;
    id_ = -1;
    return id;
  }

 private:
  hid_t id_;
  herr_t (*closer_)(hid_t);
};

// A file access list without file locking, through MPI-IO on `comm` unless it
// is MPI_COMM_NULL (a library without the MPI-IO driver: runtime_error).
hid_t make_fapl(const std::string& file, MPI_Comm comm = MPI_COMM_NULL);

// comm when it has more than one rank (rank set), else MPI_COMM_NULL (rank 0).
MPI_Comm parallel_comm(MPI_Comm comm, int& rank);

// A scalar attribute `name` on the object `on` (relative to loc; "." = loc).
void write_scalar_attribute(hid_t loc, const char* name, hid_t file_type, hid_t mem_type, const void* value,
                            const std::string& file, const std::string& object, const char* on = ".");

// Parallel (comm != MPI_COMM_NULL): every rank learns whether all succeeded:
// throws `mine` where it failed, a message naming `what` elsewhere. Serial:
// throws `mine` unless it is empty.
void agree(MPI_Comm comm, const std::string& file, const std::string& mine, const std::string& what);

// Creates dataset loc_name/name of total_rows x cols (1-D when cols == 1) of
// file_type in `loc` and writes rows [first_row, first_row +
// rows) from `data` (row-major). replicated: the same data on every rank,
// rows == total_rows, rank 0 transfers. data: rows x cols of mem_type.
// Parallel: one allreduce checks that every rank gives the same total_rows
// and cols, one more agrees on the result of the write. Serial: rows == total_rows. Arguments
// are checked and agreed on before the collective create; every failure
// becomes a runtime_error (invalid_argument for bad arguments, serial) on
// every rank (see agree).
void write_dataset(hid_t loc, MPI_Comm comm, int rank, const std::string& file, const std::string& loc_name,
                   const std::string& name, hid_t file_type, hid_t mem_type, const void* data, std::size_t rows, std::size_t first_row,
                   std::size_t total_rows, std::size_t cols, bool replicated);

}  // namespace bfemp::h5
