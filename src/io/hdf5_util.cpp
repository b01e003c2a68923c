#include "io/hdf5_util.hpp"

#include <stdexcept>

namespace bfemp::h5 {

namespace {
herr_t collect_error(unsigned n, const H5E_error2_t* err, void* out) {
  std::string& s = *static_cast<std::string*>(out);
  if (n > 0) s += "; ";
  s += std::string(err->func_name ? err->func_name : "?") + ": " + (err->desc ? err->desc : "");
  return 0;
}
}  // namespace

void fail(const std::string& file, const std::string& what) {
  std::string stack;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collect_error, &stack);
  throw std::runtime_error("HDF5 file '" + file + "': " + what + (stack.empty() ? std::string() : " [" + stack + "]"));
}

hid_t make_fapl(const std::string& file, MPI_Comm comm) {
  // (fail() reads the error stack before the Handle closes the list)
  Handle fapl(check(H5Pcreate(H5P_FILE_ACCESS), file, "cannot create file access list"), H5Pclose);
#if H5_VERSION_GE(1, 10, 7)
  if (H5Pset_file_locking(fapl.get(), 0, 1) < 0) fail(file, "cannot disable file locking");
#endif
  if (comm != MPI_COMM_NULL) {
#ifdef H5_HAVE_PARALLEL
    if (H5Pset_fapl_mpio(fapl.get(), comm, MPI_INFO_NULL) < 0) fail(file, "cannot select the MPI-IO file driver");
#else
    throw std::runtime_error("HDF5 file '" + file +
                             "': this HDF5 library has no MPI-IO driver; an MPI run needs parallel HDF5 "
                             "(libhdf5-openmpi-dev)");
#endif
  }
  return fapl.release();
}

MPI_Comm parallel_comm(MPI_Comm comm, int& rank) {
  rank = 0;
  if (comm == MPI_COMM_NULL) return comm;
  int size = 1;
  MPI_Comm_size(comm, &size);
  if (size <= 1) return MPI_COMM_NULL;
  MPI_Comm_rank(comm, &rank);
  return comm;
}

void write_scalar_attribute(hid_t loc, const char* name, hid_t file_type, hid_t mem_type, const void* value,
                            const std::string& file, const std::string& object, const char* on) {
  const std::string what = "cannot write attribute '" + std::string(name) + "' of '" + object + "'";
  Handle space(check(H5Screate(H5S_SCALAR), file, what), H5Sclose);
  Handle attr(check(H5Acreate_by_name(loc, on, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                    file, what),
              H5Aclose);
  check(H5Awrite(attr.get(), mem_type, value), file, what);
}

void agree(MPI_Comm comm, const std::string& file, const std::string& mine, const std::string& what) {
  if (comm == MPI_COMM_NULL) {
    if (!mine.empty()) throw std::runtime_error(mine);
    return;
  }
  int ok = mine.empty() ? 1 : 0, all = 0;
  MPI_Allreduce(&ok, &all, 1, MPI_INT, MPI_MIN, comm);
  if (all) return;
  throw std::runtime_error(mine.empty() ? "HDF5 file '" + file + "': " + what + " failed on another MPI rank" : mine);
}

void write_dataset(hid_t loc, MPI_Comm comm, int rank, const std::string& file, const std::string& loc_name,
                   const std::string& name, hid_t file_type, hid_t mem_type, const void* data, std::size_t rows, std::size_t first_row,
                   std::size_t total_rows, std::size_t cols, bool replicated) {
  const bool parallel = comm != MPI_COMM_NULL;
  const std::string full = loc_name + "/" + name;
  const std::string what = "cannot write dataset '" + full + "'";
  // The collective create needs one shape on every rank: the extremes over
  // the ranks (taken by every rank before any check may throw).
  long long lo[2] = {static_cast<long long>(total_rows), static_cast<long long>(cols)}, hi[2] = {lo[0], lo[1]};
  if (parallel) {  // one allreduce: the minima of (rows, cols, -rows, -cols)
    const long long mine[4] = {lo[0], lo[1], -lo[0], -lo[1]};
    long long least[4];
    MPI_Allreduce(mine, least, 4, MPI_LONG_LONG, MPI_MIN, comm);
    lo[0] = least[0];
    lo[1] = least[1];
    hi[0] = -least[2];
    hi[1] = -least[3];
  }
  std::string bad_args;
  try {
    if (name.empty() || name.find('/') != std::string::npos || name == "." || name == "..")
      throw std::invalid_argument("HDF5 file '" + file + "': dataset name '" + name + "' in '" + loc_name +
                                  "': expected a non-empty name without '/'");
    if (cols == 0 || (data == nullptr && rows > 0))
      throw std::invalid_argument("HDF5 file '" + file + "': dataset '" + full + "' with " + std::to_string(rows) +
                                  "x" + std::to_string(cols) +
                                  (cols == 0 ? " values: expected cols >= 1" : " values and no data"));
    if (first_row + rows > total_rows || (!parallel && rows != total_rows) || (replicated && rows != total_rows))
      throw std::invalid_argument("HDF5 file '" + file + "': dataset '" + full + "': rows " +
                                  std::to_string(first_row) + ".." + std::to_string(first_row + rows) + " of " +
                                  std::to_string(total_rows) +
                                  (!parallel ? ": expected every row (a serial writer writes whole datasets)"
                                   : replicated ? ": expected every row (replicated data)"
                                                : ": expected a block inside the dataset"));
    if (lo[0] != hi[0] || lo[1] != hi[1])
      throw std::invalid_argument("HDF5 file '" + file + "': dataset '" + full + "': the ranks give " +
                                  std::to_string(lo[0]) + ".." + std::to_string(hi[0]) + " rows and " +
                                  std::to_string(lo[1]) + ".." + std::to_string(hi[1]) +
                                  " columns: expected one shape on every rank");
  } catch (const std::invalid_argument& e) {
    if (!parallel) throw;
    bad_args = e.what();
  }
  agree(comm, file, bad_args, what);
  std::string error;
  try {
    QuietErrors quiet;
    if (check(H5Lexists(loc, name.c_str(), H5P_DEFAULT), file, what) > 0)
      throw std::runtime_error("HDF5 file '" + file + "': dataset '" + full + "' already exists");
    const hsize_t dims[2] = {static_cast<hsize_t>(total_rows), static_cast<hsize_t>(cols)};
    const int ndims = cols == 1 ? 1 : 2;
    Handle space(check(H5Screate_simple(ndims, dims, nullptr), file, what), H5Sclose);
    Handle dset(check(H5Dcreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                      file, what),
                H5Dclose);
    // Replicated data: rank 0 transfers them (independent I/O); the others
    // only took part in the collective create.
    const bool transfer = rows > 0 && !(replicated && rank != 0);
    if (transfer && rows == total_rows) {
      check(H5Dwrite(dset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), file, what);
    } else if (transfer) {
      const hsize_t start[2] = {static_cast<hsize_t>(first_row), 0};
      const hsize_t count[2] = {static_cast<hsize_t>(rows), static_cast<hsize_t>(cols)};
      check(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), file, what);
      Handle mem(check(H5Screate_simple(ndims, count, nullptr), file, what), H5Sclose);
      check(H5Dwrite(dset.get(), mem_type, mem.get(), space.get(), H5P_DEFAULT, data), file, what);
    }
  } catch (const std::exception& e) {
    error = e.what();
    if (error.empty()) error = "HDF5 file '" + file + "': " + what;
  }
  agree(comm, file, error, what);
}

}  // namespace bfemp::h5
