#include "io/checkpoint.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <type_traits>

#include "io/hdf5_util.hpp"

namespace bfemp {

using h5::Handle;
using h5::QuietErrors;

namespace {

template <class T>
CheckpointArray make_array(std::vector<T> v, std::size_t cols, bool blocked, std::size_t first_row,
                           std::size_t total_rows) {
  CheckpointArray a;
  a.cols = cols;
  a.rows = cols ? v.size() / cols : 0;
  a.blocked = blocked;
  a.first_row = first_row;
  a.total_rows = blocked ? total_rows : a.rows;
  if constexpr (std::is_same_v<T, double>) {
    a.real = std::move(v);
  } else {
    a.integer = true;
    a.ints = std::move(v);
  }
  if (blocked && first_row + a.rows > total_rows)
    throw std::logic_error("checkpoint rows " + std::to_string(first_row) + ".." + std::to_string(first_row + a.rows) +
                           " of " + std::to_string(total_rows));
  return a;
}

}  // namespace

void Checkpoint::put(const std::string& name, std::vector<double> v, std::size_t cols) {
  arrays[name] = make_array(std::move(v), cols, false, 0, 0);
}
void Checkpoint::put(const std::string& name, std::vector<long long> v, std::size_t cols) {
  arrays[name] = make_array(std::move(v), cols, false, 0, 0);
}
void Checkpoint::put_rows(const std::string& name, std::vector<double> v, std::size_t cols, std::size_t first_row,
                          std::size_t total_rows) {
  arrays[name] = make_array(std::move(v), cols, true, first_row, total_rows);
}
void Checkpoint::put_rows(const std::string& name, std::vector<long long> v, std::size_t cols,
                          std::size_t first_row, std::size_t total_rows) {
  arrays[name] = make_array(std::move(v), cols, true, first_row, total_rows);
}

const CheckpointArray& Checkpoint::array(const std::string& name) const {
  const auto it = arrays.find(name);
  if (it == arrays.end())
    throw std::invalid_argument("checkpoint field '" + name + "' is missing: the checkpoint does not match the scene");
  return it->second;
}

namespace {

const CheckpointArray& field(const Checkpoint& c, const std::string& name, long rows, bool integer) {
  const CheckpointArray& a = c.array(name);
  if (a.integer != integer) throw std::invalid_argument("checkpoint field '" + name + "' has the wrong type");
  if (rows >= 0 && static_cast<long>(a.rows) != rows)
    throw std::invalid_argument("checkpoint field '" + name + "' has " + std::to_string(a.rows) + " rows, expected " +
                                std::to_string(rows) + " (the scene does not produce the checkpoint's state)");
  return a;
}

template <class T>
T read_attr(hid_t g, const std::string& file, const char* name, hid_t mem_type) {
  T v{};
  Handle a(H5Aopen(g, name, H5P_DEFAULT), H5Aclose);
  if (a.get() < 0 || H5Aread(a.get(), mem_type, &v) < 0)
    throw std::invalid_argument("checkpoint '" + file + "': attribute '" + name + "' missing: not a bfemp checkpoint");
  return v;
}

void fsync_path(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw std::runtime_error("checkpoint '" + path + "': cannot reopen (" + std::strerror(errno) + ")");
  const int r = ::fsync(fd);
  ::close(fd);
  if (r != 0) throw std::runtime_error("checkpoint '" + path + "': fsync failed (" + std::strerror(errno) + ")");
}

}  // namespace

const std::string& Checkpoint::text(const std::string& name) const {
  const auto it = texts.find(name);
  if (it == texts.end()) throw std::invalid_argument("checkpoint text '" + name + "' is missing");
  return it->second;
}

const std::vector<double>& Checkpoint::real(const std::string& name, long rows) const {
  return field(*this, name, rows, false).real;
}
const std::vector<long long>& Checkpoint::ints(const std::string& name, long rows) const {
  return field(*this, name, rows, true).ints;
}

namespace {

// Collective over comm (MPI_COMM_NULL: serial). Each object is created by
// every rank in the same order (std::map order); each step's failure is
// agreed on, so every rank throws at the same point. (A create that fails on
// some ranks only would leave the file open on the others; MPI_File_open is
// collective and fails alike on every rank in practice.)
void write_unsynced(const std::string& tmp, const Checkpoint& c, MPI_Comm comm, int rank) {
  QuietErrors quiet;
  std::string error;
  hid_t file = -1;
  try {
    Handle fapl(h5::make_fapl(tmp, comm), H5Pclose);
    file = h5::check(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), tmp, "cannot create");
  } catch (const std::exception& e) {
    error = e.what();
  }
  h5::agree(comm, tmp, error, "create");
  Handle f(file, H5Fclose);
  hid_t group = -1;
  try {
    group = h5::check(H5Gcreate2(f.get(), "/checkpoint", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), tmp,
                      "cannot create group '/checkpoint'");
    const long long format = Checkpoint::kFormat, step = c.step, frames = c.frames, dim = c.dim;
    h5::write_scalar_attribute(group, "format", H5T_STD_I64LE, H5T_NATIVE_LLONG, &format, tmp, "/checkpoint");
    h5::write_scalar_attribute(group, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &c.time, tmp, "/checkpoint");
    h5::write_scalar_attribute(group, "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, &step, tmp, "/checkpoint");
    h5::write_scalar_attribute(group, "frames", H5T_STD_I64LE, H5T_NATIVE_LLONG, &frames, tmp, "/checkpoint");
    h5::write_scalar_attribute(group, "dim", H5T_STD_I64LE, H5T_NATIVE_LLONG, &dim, tmp, "/checkpoint");
  } catch (const std::exception& e) {
    error = e.what();
  }
  Handle g(group, H5Gclose);
  h5::agree(comm, tmp, error, "the '/checkpoint' group");
  {
    hid_t tg = -1;
    try {
      tg = h5::check(H5Gcreate2(g.get(), "text", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), tmp,
                       "cannot create group '/checkpoint/text'");
    } catch (const std::exception& e) {
      error = e.what();
    }
    Handle t(tg, H5Gclose);
    h5::agree(comm, tmp, error, "the '/checkpoint/text' group");
    for (const auto& [name, text] : c.texts)
      h5::write_dataset(t.get(), comm, rank, tmp, "/checkpoint/text", name, H5T_STD_U8LE, H5T_NATIVE_UCHAR,
                        text.data(), text.size(), 0, text.size(), 1, true);
  }
  for (const auto& [name, a] : c.arrays) {
    if (name == "text") throw std::logic_error("checkpoint field name 'text' is reserved");
    const void* data = a.integer ? static_cast<const void*>(a.ints.data()) : a.real.data();
    h5::write_dataset(g.get(), comm, rank, tmp, "/checkpoint", name, a.integer ? H5T_STD_I64LE : H5T_IEEE_F64LE,
                      a.integer ? H5T_NATIVE_LLONG : H5T_NATIVE_DOUBLE, data, a.rows, a.first_row, a.total_rows,
                      a.cols, !a.blocked);
    if (a.blocked) {  // (the same on every rank: write_dataset agreed on the shapes)
      try {
        const long long one = 1;
        h5::write_scalar_attribute(g.get(), "blocked", H5T_STD_I64LE, H5T_NATIVE_LLONG, &one, tmp,
                                   "/checkpoint/" + name, name.c_str());
      } catch (const std::exception& e) {
        error = e.what();
      }
      h5::agree(comm, tmp, error, "the attribute 'blocked' of '/checkpoint/" + name + "'");
    }
  }
  h5::check(H5Fflush(f.get(), H5F_SCOPE_GLOBAL), tmp, "flush failed");
  H5Gclose(g.release());
  h5::check(H5Fclose(f.release()), tmp, "close failed");
}

}  // namespace

void write_checkpoint(const std::string& path, const Checkpoint& c, MPI_Comm comm) {
  int rank = 0;
  comm = h5::parallel_comm(comm, rank);
  const std::string tmp = path + ".tmp";
  std::string error;
  try {
    write_unsynced(tmp, c, comm, rank);
    if (rank == 0) fsync_path(tmp);
  } catch (const std::exception& e) {
    error = e.what();
    if (error.empty()) error = "checkpoint '" + path + "': write failed";
  }
  if (!error.empty() && rank == 0) std::remove(tmp.c_str());  // the old checkpoint stays; no .tmp is left
  h5::agree(comm, tmp, error, "the checkpoint write");
  if (rank == 0) {
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
      error = "checkpoint '" + path + "': rename from " + tmp + " failed (" + std::strerror(errno) + ")";
      std::remove(tmp.c_str());
    } else {
      // The rename itself survives a power loss only once the directory is synced.
      const std::string dir = std::filesystem::path(path).parent_path().string();
      const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY);
      if (fd >= 0) {
        ::fsync(fd);
        ::close(fd);
      }
    }
  }
  h5::agree(comm, path, error, "the checkpoint rename");  // (every rank returns once the file is in place)
}

namespace {
Checkpoint read_checkpoint_unchecked(const std::string& path, int rank, int nranks);
}

// Any failure to read the file is bad input (exit 2), naming the file.
Checkpoint read_checkpoint(const std::string& path, int rank, int nranks) {
  if (nranks < 1 || rank < 0 || rank >= nranks)
    throw std::logic_error("read_checkpoint: rank " + std::to_string(rank) + " of " + std::to_string(nranks));
  try {
    return read_checkpoint_unchecked(path, rank, nranks);
  } catch (const std::invalid_argument&) {
    throw;
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string(e.what()) + " (a damaged or foreign checkpoint)");
  }
}

namespace {
Checkpoint read_checkpoint_unchecked(const std::string& path, int rank, int nranks) {
  if (!std::filesystem::is_regular_file(path))
    throw std::invalid_argument("checkpoint '" + path + "' does not exist (a run writes it at its end, on SIGINT/SIGTERM "
                                "and every 'Output/checkpoint every' steps)");
  QuietErrors quiet;
  Handle fapl(h5::make_fapl(path), H5Pclose);
  Handle f(H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get()), H5Fclose);
  if (f.get() < 0) throw std::invalid_argument("checkpoint '" + path + "' is not a readable HDF5 file");
  Handle g(H5Gopen2(f.get(), "/checkpoint", H5P_DEFAULT), H5Gclose);
  if (g.get() < 0)
    throw std::invalid_argument("checkpoint '" + path + "' has no /checkpoint group: not a bfemp checkpoint");
  Checkpoint c;
  const long long format = read_attr<long long>(g.get(), path, "format", H5T_NATIVE_LLONG);
  if (format != Checkpoint::kFormat)
    throw std::invalid_argument("checkpoint '" + path + "' has format " + std::to_string(format) + ", expected " +
                                std::to_string(Checkpoint::kFormat));
  c.time = read_attr<double>(g.get(), path, "time", H5T_NATIVE_DOUBLE);
  c.step = static_cast<long>(read_attr<long long>(g.get(), path, "step", H5T_NATIVE_LLONG));
  c.frames = static_cast<int>(read_attr<long long>(g.get(), path, "frames", H5T_NATIVE_LLONG));
  c.dim = static_cast<int>(read_attr<long long>(g.get(), path, "dim", H5T_NATIVE_LLONG));
  // Lists the datasets of group `loc` and calls f(name).
  auto each = [&](hid_t loc, auto&& f) {
    H5G_info_t info;
    h5::check(H5Gget_info(loc, &info), path, "cannot list a group");
    for (hsize_t i = 0; i < info.nlinks; ++i) {
      char name[256];
      const ssize_t len = H5Lget_name_by_idx(loc, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
      if (len < 0 || len >= static_cast<ssize_t>(sizeof name)) h5::fail(path, "bad field name");
      if (std::string(name) != "text") f(std::string(name));  // the only subgroup
    }
  };
  auto read = [&](hid_t loc, const std::string& name, CheckpointArray& a, std::string* text) {
    const std::string what = "cannot read '" + name + "'";
    Handle d(h5::check(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), path, what), H5Dclose);
    Handle space(h5::check(H5Dget_space(d.get()), path, what), H5Sclose);
    Handle type(h5::check(H5Dget_type(d.get()), path, what), H5Tclose);
    const int ndims = H5Sget_simple_extent_ndims(space.get());
    hsize_t dims[2] = {0, 1};
    if (ndims < 1 || ndims > 2 || H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0) h5::fail(path, what);
    const std::size_t cols = ndims == 2 ? dims[1] : 1;
    if (text) {
      const std::size_t n = dims[0] * cols;
      text->assign(n, '\0');
      if (n) h5::check(H5Dread(d.get(), H5T_NATIVE_UCHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, text->data()), path, what);
      return;
    }
    a.cols = cols;
    a.total_rows = dims[0];
    a.blocked = h5::check(H5Aexists(d.get(), "blocked"), path, what) > 0;
    a.first_row = a.blocked ? a.total_rows * rank / nranks : 0;
    a.rows = a.blocked ? a.total_rows * (rank + 1) / nranks - a.first_row : a.total_rows;
    a.integer = H5Tget_class(type.get()) == H5T_INTEGER;
    const std::size_t n = a.rows * cols;
    void* out = nullptr;
    if (a.integer) {
      a.ints.resize(n);
      out = a.ints.data();
    } else {
      a.real.resize(n);
      out = a.real.data();
    }
    if (n == 0) return;
    const hid_t mem_type = a.integer ? H5T_NATIVE_LLONG : H5T_NATIVE_DOUBLE;
    if (a.rows == a.total_rows) {
      h5::check(H5Dread(d.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out), path, what);
      return;
    }
    const hsize_t start[2] = {a.first_row, 0}, count[2] = {a.rows, cols};
    h5::check(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), path, what);
    Handle mem(h5::check(H5Screate_simple(ndims, count, nullptr), path, what), H5Sclose);
    h5::check(H5Dread(d.get(), mem_type, mem.get(), space.get(), H5P_DEFAULT, out), path, what);
  };
  each(g.get(), [&](const std::string& name) { read(g.get(), name, c.arrays[name], nullptr); });
  Handle t(H5Gopen2(g.get(), "text", H5P_DEFAULT), H5Gclose);
  if (t.get() >= 0) {
    CheckpointArray unused;
    each(t.get(), [&](const std::string& name) { read(t.get(), name, unused, &c.texts[name]); });
  }
  return c;
}
}  // namespace

}  // namespace bfemp
