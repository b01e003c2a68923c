#include "io/hdf5_frames.hpp"

#include "io/hdf5_util.hpp"

#include <cstdio>
#include <stdexcept>
#include <type_traits>

static_assert(std::is_same<hid_t, std::int64_t>::value, "hid_t is stored as std::int64_t");

namespace bfemp {
namespace {

using h5::check;
using h5::Handle;
using h5::make_fapl;
using h5::QuietErrors;

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
    : path_(path), comm_(h5::parallel_comm(comm, rank_)) {
  QuietErrors quiet;
  Handle fapl(make_fapl(path_, comm_), H5Pclose);
  file_ = check(H5Fcreate(path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), path_,
                "cannot create file");
}

Hdf5FrameWriter::Hdf5FrameWriter(const std::string& path, int keep_frames, MPI_Comm comm)
    : path_(path), comm_(h5::parallel_comm(comm, rank_)) {
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
  h5::write_scalar_attribute(frame_, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &time, path_, name);
  h5::write_scalar_attribute(frame_, "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, &step64, path_, name);
  h5::write_scalar_attribute(frame_, "index", H5T_STD_I64LE, H5T_NATIVE_LLONG, &index64, path_, name);
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

void Hdf5FrameWriter::write_dataset(std::int64_t loc, const std::string& loc_name, const std::string& name,
                                    bool integer, const void* data, std::size_t rows, std::size_t first_row,
                                    std::size_t total_rows, std::size_t cols, bool replicated) {
  h5::write_dataset(loc, comm_, rank_, path_, loc_name, name, integer ? H5T_STD_I64LE : H5T_IEEE_F64LE,
                    integer ? H5T_NATIVE_LLONG : H5T_NATIVE_DOUBLE, data, rows, first_row, total_rows, cols,
                    replicated);
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
