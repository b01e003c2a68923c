#include "io/hdf5_frames.hpp"

#include <hdf5.h>

#include <cstdio>
#include <stdexcept>
#include <type_traits>

static_assert(std::is_same<hid_t, std::int64_t>::value, "hid_t is stored as std::int64_t");

namespace bfemp {
namespace {

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

herr_t collect_error(unsigned n, const H5E_error2_t* err, void* out) {
  std::string& s = *static_cast<std::string*>(out);
  if (n > 0) s += "; ";
  s += std::string(err->func_name ? err->func_name : "?") + ": " + (err->desc ? err->desc : "");
  return 0;
}

// Must run before any other HDF5 call: each API call clears the stack.
[[noreturn]] void fail(const std::string& file, const std::string& what) {
  std::string stack;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collect_error, &stack);
  throw std::runtime_error("HDF5 file '" + file + "': " + what +
                           (stack.empty() ? std::string() : " [" + stack + "]"));
}

template <class T>
T check(T value, const std::string& file, const std::string& what) {
  if (value < 0) fail(file, what);
  return value;
}

// Owning hid_t, closed with its matching H5?close.
class Handle {
 public:
  Handle(hid_t id, herr_t (*closer)(hid_t)) : id_(id), closer_(closer) {}
  ~Handle() {
    if (id_ >= 0) closer_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }

 private:
  hid_t id_;
  herr_t (*closer_)(hid_t);
};

// File access without HDF5 file locking (see the header), through MPI-IO on
// `comm` unless it is MPI_COMM_NULL.
hid_t make_fapl(const std::string& file, MPI_Comm comm = MPI_COMM_NULL) {
  const hid_t fapl = check(H5Pcreate(H5P_FILE_ACCESS), file, "cannot create file access list");
#if H5_VERSION_GE(1, 10, 7)
  if (H5Pset_file_locking(fapl, 0, 1) < 0) {
    H5Pclose(fapl);
    fail(file, "cannot disable file locking");
  }
#endif
  if (comm != MPI_COMM_NULL) {
#ifdef H5_HAVE_PARALLEL
    if (H5Pset_fapl_mpio(fapl, comm, MPI_INFO_NULL) < 0) {
      H5Pclose(fapl);
      fail(file, "cannot select the MPI-IO file driver");
    }
#else
    H5Pclose(fapl);
    throw std::runtime_error("HDF5 file '" + file +
                             "': this HDF5 library has no MPI-IO driver; an MPI run needs parallel HDF5 "
                             "(libhdf5-openmpi-dev)");
#endif
  }
  return fapl;
}

// comm when it has more than one rank, else MPI_COMM_NULL (the serial driver).
MPI_Comm parallel_comm(MPI_Comm comm, int& rank) {
  rank = 0;
  if (comm == MPI_COMM_NULL) return comm;
  int size = 1;
  MPI_Comm_size(comm, &size);
  if (size <= 1) return MPI_COMM_NULL;
  MPI_Comm_rank(comm, &rank);
  return comm;
}

void write_scalar_attribute(hid_t loc, const char* name, hid_t file_type, hid_t mem_type,
                            const void* value, const std::string& file,
                            const std::string& object) {
  const std::string what = "cannot write attribute '" + std::string(name) + "' of '" + object + "'";
  Handle space(check(H5Screate(H5S_SCALAR), file, what), H5Sclose);
  Handle attr(check(H5Acreate2(loc, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                    file, what),
              H5Aclose);
  check(H5Awrite(attr.get(), mem_type, value), file, what);
}

// Read-only id of `file` (close with H5Fclose).
hid_t open_read_only(const std::string& file) {
  Handle fapl(make_fapl(file), H5Pclose);
  return check(H5Fopen(file.c_str(), H5F_ACC_RDONLY, fapl.get()), file, "cannot open for reading");
}

template <class T>
std::vector<T> read_any(const std::string& file, const std::string& path,
                        std::vector<std::size_t>* shape, hid_t mem_type) {
  QuietErrors quiet;
  Handle f(open_read_only(file), H5Fclose);
  const std::string what = "cannot read dataset '" + path + "'";
  Handle d(check(H5Dopen2(f.get(), path.c_str(), H5P_DEFAULT), file, what), H5Dclose);
  Handle space(check(H5Dget_space(d.get()), file, what), H5Sclose);
  const int rank = check(H5Sget_simple_extent_ndims(space.get()), file, what);
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  if (rank > 0) check(H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr), file, what);
  std::size_t total = 1;
  for (hsize_t n : dims) total *= static_cast<std::size_t>(n);
  std::vector<T> out(total);
  if (total > 0)
    check(H5Dread(d.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), file, what);
  if (shape) shape->assign(dims.begin(), dims.end());
  return out;
}

}  // namespace

std::string Hdf5FrameWriter::frame_group_name(int index) {
  if (index < 0)
    throw std::invalid_argument("HDF5 frame index " + std::to_string(index) +
                                ": expected >= 0");
  char buf[32];
  std::snprintf(buf, sizeof buf, "/frame_%06d", index);
  return buf;
}

Hdf5FrameWriter::Hdf5FrameWriter(const std::string& path, MPI_Comm comm)
    : path_(path), comm_(parallel_comm(comm, rank_)) {
  QuietErrors quiet;
  Handle fapl(make_fapl(path_, comm_), H5Pclose);
  file_ = check(H5Fcreate(path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), path_,
                "cannot create file");
}

Hdf5FrameWriter::Hdf5FrameWriter(const std::string& path, int keep_frames, MPI_Comm comm)
    : path_(path), comm_(parallel_comm(comm, rank_)) {
  QuietErrors quiet;
  Handle fapl(make_fapl(path_, comm_), H5Pclose);
  file_ = check(H5Fopen(path_.c_str(), H5F_ACC_RDWR, fapl.get()), path_, "cannot open for appending");
  try {
    for (int i = 0; i < keep_frames; ++i) {
      const std::string name = frame_group_name(i);
      if (check(H5Lexists(file_, name.c_str() + 1, H5P_DEFAULT), path_, "cannot query '" + name + "'") <= 0)
        throw std::runtime_error("HDF5 file '" + path_ + "': frame '" + name +
                                 "' recorded by the checkpoint is missing");
    }
    for (int i = keep_frames;; ++i) {
      const std::string name = frame_group_name(i);
      if (check(H5Lexists(file_, name.c_str() + 1, H5P_DEFAULT), path_, "cannot query '" + name + "'") <= 0) break;
      check(H5Ldelete(file_, name.c_str(), H5P_DEFAULT), path_, "cannot remove '" + name + "'");
    }
    if (check(H5Lexists(file_, "mesh", H5P_DEFAULT), path_, "cannot query '/mesh'") > 0)
      mesh_ = check(H5Gopen2(file_, "/mesh", H5P_DEFAULT), path_, "cannot open '/mesh'");
    check(H5Fflush(file_, H5F_SCOPE_GLOBAL), path_, "cannot flush");
  } catch (...) {
    close_handles();
    throw;
  }
}

Hdf5FrameWriter::~Hdf5FrameWriter() {
  try {
    close();
  } catch (...) {
    close_handles();
  }
}

void Hdf5FrameWriter::close_handles() noexcept {
  QuietErrors quiet;
  if (frame_ >= 0) H5Gclose(frame_);
  if (mesh_ >= 0) H5Gclose(mesh_);
  if (file_ >= 0) H5Fclose(file_);
  frame_ = mesh_ = file_ = -1;
}

void Hdf5FrameWriter::close() {
  if (file_ < 0) return;
  if (frame_ >= 0) end_frame();
  QuietErrors quiet;
  if (mesh_ >= 0) {
    const hid_t mesh = mesh_;
    mesh_ = -1;
    check(H5Gclose(mesh), path_, "cannot close group '/mesh'");
  }
  const hid_t file = file_;
  file_ = -1;
  check(H5Fclose(file), path_, "cannot close file");
}

void Hdf5FrameWriter::begin_frame(int index, double time, long step) {
  const std::string name = frame_group_name(index);
  if (file_ < 0) throw std::runtime_error("HDF5 file '" + path_ + "': begin_frame after close");
  if (frame_ >= 0)
    throw std::runtime_error("HDF5 file '" + path_ + "': begin_frame('" + name +
                             "') while frame '" + frame_name_ + "' is still open");
  QuietErrors quiet;
  if (check(H5Lexists(file_, name.c_str() + 1, H5P_DEFAULT), path_, "cannot query '" + name + "'") > 0)
    throw std::runtime_error("HDF5 file '" + path_ + "': frame group '" + name + "' already exists");
  frame_ = check(H5Gcreate2(file_, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), path_,
                 "cannot create group '" + name + "'");
  frame_name_ = name;
  const long long step64 = step, index64 = index;
  write_scalar_attribute(frame_, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &time, path_, name);
  write_scalar_attribute(frame_, "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, &step64, path_, name);
  write_scalar_attribute(frame_, "index", H5T_STD_I64LE, H5T_NATIVE_LLONG, &index64, path_, name);
}

double Hdf5FrameWriter::frame_time(int index) const {
  const std::string name = frame_group_name(index);
  const std::string what = "cannot read attribute 'time' of '" + name + "'";
  QuietErrors quiet;
  Handle attr(check(H5Aopen_by_name(file_, name.c_str(), "time", H5P_DEFAULT, H5P_DEFAULT), path_, what),
              H5Aclose);
  double t = 0.0;
  check(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &t), path_, what);
  return t;
}

void Hdf5FrameWriter::end_frame() {
  if (frame_ < 0)
    throw std::runtime_error("HDF5 file '" + path_ + "': end_frame without an open frame");
  QuietErrors quiet;
  const hid_t group = frame_;
  frame_ = -1;
  check(H5Gclose(group), path_, "cannot close group '" + frame_name_ + "'");
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), path_, "cannot flush after '" + frame_name_ + "'");
}

std::int64_t Hdf5FrameWriter::frame_group(const std::string& dataset) const {
  if (frame_ < 0)
    throw std::runtime_error("HDF5 file '" + path_ + "': dataset '" + dataset +
                             "' written outside begin_frame/end_frame");
  return frame_;
}

void Hdf5FrameWriter::write_array(const std::string& name, const double* data,
                                  std::size_t rows, std::size_t cols) {
  write_dataset(frame_group(name), frame_name_, name, false, data, rows, 0, rows, cols, true);
}

void Hdf5FrameWriter::write_array(const std::string& name, const long long* data,
                                  std::size_t rows, std::size_t cols) {
  write_dataset(frame_group(name), frame_name_, name, true, data, rows, 0, rows, cols, true);
}

void Hdf5FrameWriter::write_rows(const std::string& name, const double* data, std::size_t rows,
                                 std::size_t first_row, std::size_t total_rows, std::size_t cols) {
  write_dataset(frame_group(name), frame_name_, name, false, data, rows, first_row, total_rows, cols, false);
}

void Hdf5FrameWriter::write_rows(const std::string& name, const long long* data, std::size_t rows,
                                 std::size_t first_row, std::size_t total_rows, std::size_t cols) {
  write_dataset(frame_group(name), frame_name_, name, true, data, rows, first_row, total_rows, cols, false);
}

std::int64_t Hdf5FrameWriter::mesh_group() {
  if (file_ < 0) throw std::runtime_error("HDF5 file '" + path_ + "': write after close");
  if (mesh_ < 0) {
    QuietErrors quiet;
    mesh_ = check(H5Gcreate2(file_, "/mesh", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), path_,
                  "cannot create group '/mesh'");
  }
  return mesh_;
}

void Hdf5FrameWriter::flush(const std::string& after) {
  QuietErrors quiet;
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), path_, "cannot flush after '" + after + "'");
}

void Hdf5FrameWriter::write_static(const std::string& name, const double* data,
                                   std::size_t rows, std::size_t cols) {
  write_dataset(mesh_group(), "/mesh", name, false, data, rows, 0, rows, cols, true);
  flush("/mesh/" + name);
}

void Hdf5FrameWriter::write_static(const std::string& name, const long long* data,
                                   std::size_t rows, std::size_t cols) {
  write_dataset(mesh_group(), "/mesh", name, true, data, rows, 0, rows, cols, true);
  flush("/mesh/" + name);
}

void Hdf5FrameWriter::write_static_rows(const std::string& name, const long long* data, std::size_t rows,
                                        std::size_t first_row, std::size_t total_rows, std::size_t cols) {
  write_dataset(mesh_group(), "/mesh", name, true, data, rows, first_row, total_rows, cols, false);
  flush("/mesh/" + name);
}

void Hdf5FrameWriter::agree(const std::string& mine, const std::string& what) const {
  if (!parallel()) {
    if (!mine.empty()) throw std::runtime_error(mine);
    return;
  }
  int ok = mine.empty() ? 1 : 0, all = 0;
  MPI_Allreduce(&ok, &all, 1, MPI_INT, MPI_MIN, comm_);
  if (all) return;
  throw std::runtime_error(mine.empty() ? "HDF5 file '" + path_ + "': " + what + " failed on another MPI rank" : mine);
}

void Hdf5FrameWriter::write_dataset(std::int64_t loc, const std::string& loc_name,
                                    const std::string& name, bool integer, const void* data,
                                    std::size_t rows, std::size_t first_row, std::size_t total_rows,
                                    std::size_t cols, bool replicated) {
  const std::string full = loc_name + "/" + name;
  const std::string what = "cannot write dataset '" + full + "'";
  // Arguments checked, and (parallel) agreed on, before the collective create.
  std::string bad_args;
  try {
    if (name.empty() || name.find('/') != std::string::npos || name == "." || name == "..")
      throw std::invalid_argument("HDF5 file '" + path_ + "': dataset name '" + name +
                                  "' in '" + loc_name + "': expected a non-empty name without '/'");
    if (cols == 0 || (data == nullptr && rows > 0))
      throw std::invalid_argument("HDF5 file '" + path_ + "': dataset '" + full + "' with " +
                                  std::to_string(rows) + "x" + std::to_string(cols) +
                                  (cols == 0 ? " values: expected cols >= 1" : " values and no data"));
    if (first_row + rows > total_rows || (!parallel() && rows != total_rows))
      throw std::invalid_argument("HDF5 file '" + path_ + "': dataset '" + full + "': rows " +
                                  std::to_string(first_row) + ".." + std::to_string(first_row + rows) + " of " +
                                  std::to_string(total_rows) +
                                  (parallel() ? ": expected a block inside the dataset"
                                              : ": expected every row (a serial writer writes whole datasets)"));
  } catch (const std::invalid_argument& e) {
    if (!parallel()) throw;
    bad_args = e.what();
  }
  agree(bad_args, what);
  std::string error;
  try {
    QuietErrors quiet;
    if (check(H5Lexists(loc, name.c_str(), H5P_DEFAULT), path_, what) > 0)
      throw std::runtime_error("HDF5 file '" + path_ + "': dataset '" + full + "' already exists");
    const hsize_t dims[2] = {static_cast<hsize_t>(total_rows), static_cast<hsize_t>(cols)};
    const int ndims = cols == 1 ? 1 : 2;
    Handle space(check(H5Screate_simple(ndims, dims, nullptr), path_, what), H5Sclose);
    const hid_t file_type = integer ? H5T_STD_I64LE : H5T_IEEE_F64LE;
    const hid_t mem_type = integer ? H5T_NATIVE_LLONG : H5T_NATIVE_DOUBLE;
    Handle dset(check(H5Dcreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT,
                                 H5P_DEFAULT, H5P_DEFAULT),
                      path_, what),
                H5Dclose);
    // Replicated data: rank 0 transfers them (independent I/O); the others
    // only took part in the collective create.
    const bool transfer = rows > 0 && !(replicated && rank_ != 0);
    if (transfer && rows == total_rows) {
      check(H5Dwrite(dset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), path_, what);
    } else if (transfer) {
      const hsize_t start[2] = {static_cast<hsize_t>(first_row), 0};
      const hsize_t count[2] = {static_cast<hsize_t>(rows), static_cast<hsize_t>(cols)};
      check(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), path_, what);
      Handle mem(check(H5Screate_simple(ndims, count, nullptr), path_, what), H5Sclose);
      check(H5Dwrite(dset.get(), mem_type, mem.get(), space.get(), H5P_DEFAULT, data), path_, what);
    }
  } catch (const std::exception& e) {
    error = e.what();
    if (error.empty()) error = "HDF5 file '" + path_ + "': " + what;
  }
  agree(error, what);
}

std::vector<double> read_dataset(const std::string& file, const std::string& path,
                                 std::vector<std::size_t>* shape) {
  return read_any<double>(file, path, shape, H5T_NATIVE_DOUBLE);
}

std::vector<long long> read_dataset_int(const std::string& file, const std::string& path,
                                        std::vector<std::size_t>* shape) {
  return read_any<long long>(file, path, shape, H5T_NATIVE_LLONG);
}

double read_attribute(const std::string& file, const std::string& object,
                      const std::string& name) {
  QuietErrors quiet;
  Handle f(open_read_only(file), H5Fclose);
  const std::string what = "cannot read attribute '" + name + "' of '" + object + "'";
  Handle attr(check(H5Aopen_by_name(f.get(), object.c_str(), name.c_str(), H5P_DEFAULT,
                                    H5P_DEFAULT),
                    file, what),
              H5Aclose);
  Handle space(check(H5Aget_space(attr.get()), file, what), H5Sclose);
  if (check(H5Sget_simple_extent_npoints(space.get()), file, what) != 1)
    throw std::runtime_error("HDF5 file '" + file + "': attribute '" + name + "' of '" + object +
                             "' is not a scalar");
  double value = 0.0;
  check(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &value), file, what);
  return value;
}

bool dataset_exists(const std::string& file, const std::string& path) {
  QuietErrors quiet;
  Handle f(open_read_only(file), H5Fclose);
  Handle d(H5Dopen2(f.get(), path.c_str(), H5P_DEFAULT), H5Dclose);
  return d.get() >= 0;
}

}  // namespace bfemp
