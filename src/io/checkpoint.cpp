#include "io/checkpoint.hpp"

#include <fcntl.h>
#include <hdf5.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace bfemp {

void Checkpoint::put(const std::string& name, std::vector<double> v, std::size_t cols) {
  CheckpointArray a;
  a.cols = cols;
  a.rows = cols ? v.size() / cols : 0;
  a.real = std::move(v);
  arrays[name] = std::move(a);
}

void Checkpoint::put(const std::string& name, std::vector<long long> v, std::size_t cols) {
  CheckpointArray a;
  a.cols = cols;
  a.rows = cols ? v.size() / cols : 0;
  a.integer = true;
  a.ints = std::move(v);
  arrays[name] = std::move(a);
}

namespace {

const CheckpointArray& field(const Checkpoint& c, const std::string& name, long rows, bool integer) {
  const auto it = c.arrays.find(name);
  if (it == c.arrays.end())
    throw std::invalid_argument("checkpoint field '" + name + "' is missing: the checkpoint does not match the scene");
  if (it->second.integer != integer)
    throw std::invalid_argument("checkpoint field '" + name + "' has the wrong type");
  if (rows >= 0 && static_cast<long>(it->second.rows) != rows)
    throw std::invalid_argument("checkpoint field '" + name + "' has " + std::to_string(it->second.rows) +
                                " rows, expected " + std::to_string(rows) +
                                " (the scene does not produce the checkpoint's state)");
  return it->second;
}

// Owning hid_t.
struct H {
  hid_t id;
  herr_t (*close)(hid_t);
  ~H() {
    if (id >= 0) close(id);
  }
};

class Quiet {
 public:
  Quiet() {
    H5Eget_auto2(H5E_DEFAULT, &f_, &d_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~Quiet() { H5Eset_auto2(H5E_DEFAULT, f_, d_); }

 private:
  H5E_auto2_t f_ = nullptr;
  void* d_ = nullptr;
};

hid_t ok(hid_t v, const std::string& file, const std::string& what) {
  if (v < 0) throw std::runtime_error("checkpoint '" + file + "': " + what);
  return v;
}

hid_t fapl_no_locking() {
  const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
#if H5_VERSION_GE(1, 10, 7)
  if (fapl >= 0) H5Pset_file_locking(fapl, 0, 1);
#endif
  return fapl;
}

void write_array(hid_t g, const std::string& file, const std::string& name, hid_t file_type, hid_t mem_type,
                 const void* data, std::size_t rows, std::size_t cols) {
  const std::string what = "cannot write '" + name + "'";
  const hsize_t dims[2] = {rows, cols};
  H space{ok(H5Screate_simple(cols == 1 ? 1 : 2, dims, nullptr), file, what), H5Sclose};
  H d{ok(H5Dcreate2(g, name.c_str(), file_type, space.id, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), file, what),
      H5Dclose};
  if (rows * cols > 0) ok(H5Dwrite(d.id, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), file, what);
}

template <class T>
void write_attr(hid_t g, const std::string& file, const char* name, hid_t file_type, hid_t mem_type, T value) {
  const std::string what = "cannot write attribute '" + std::string(name) + "'";
  H space{ok(H5Screate(H5S_SCALAR), file, what), H5Sclose};
  H a{ok(H5Acreate2(g, name, file_type, space.id, H5P_DEFAULT, H5P_DEFAULT), file, what), H5Aclose};
  ok(H5Awrite(a.id, mem_type, &value), file, what);
}

template <class T>
T read_attr(hid_t g, const std::string& file, const char* name, hid_t mem_type) {
  T v{};
  H a{H5Aopen(g, name, H5P_DEFAULT), H5Aclose};
  if (a.id < 0 || H5Aread(a.id, mem_type, &v) < 0)
    throw std::invalid_argument("checkpoint '" + file + "': attribute '" + name +
                                "' missing: not a bfemp checkpoint");
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

void write_unsynced(const std::string& tmp, const Checkpoint& c) {
  {
    Quiet quiet;
    H fapl{fapl_no_locking(), H5Pclose};
    H f{ok(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.id), tmp, "cannot create"), H5Fclose};
    H g{ok(H5Gcreate2(f.id, "/checkpoint", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), tmp, "cannot create group"),
        H5Gclose};
    write_attr(g.id, tmp, "format", H5T_STD_I64LE, H5T_NATIVE_LLONG, Checkpoint::kFormat);
    write_attr(g.id, tmp, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, c.time);
    write_attr(g.id, tmp, "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, static_cast<long long>(c.step));
    write_attr(g.id, tmp, "frames", H5T_STD_I64LE, H5T_NATIVE_LLONG, static_cast<long long>(c.frames));
    write_attr(g.id, tmp, "dim", H5T_STD_I64LE, H5T_NATIVE_LLONG, static_cast<long long>(c.dim));
    {
      H t{ok(H5Gcreate2(g.id, "text", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), tmp, "cannot create group"), H5Gclose};
      for (const auto& [name, text] : c.texts)
        write_array(t.id, tmp, name, H5T_STD_U8LE, H5T_NATIVE_UCHAR, text.data(), text.size(), 1);
    }
    for (const auto& [name, a] : c.arrays) {
      if (name == "text") throw std::logic_error("checkpoint field name 'text' is reserved");
      if (a.integer)
        write_array(g.id, tmp, name, H5T_STD_I64LE, H5T_NATIVE_LLONG, a.ints.data(), a.rows, a.cols);
      else
        write_array(g.id, tmp, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, a.real.data(), a.rows, a.cols);
    }
    ok(H5Fflush(f.id, H5F_SCOPE_GLOBAL), tmp, "flush failed");
    H5Gclose(g.id);
    g.id = -1;
    const hid_t file = f.id;
    f.id = -1;
    ok(H5Fclose(file), tmp, "close failed");
  }
}

}  // namespace

void write_checkpoint(const std::string& path, const Checkpoint& c) {
  const std::string tmp = path + ".tmp";
  try {
    write_unsynced(tmp, c);
    fsync_path(tmp);
  } catch (...) {
    std::remove(tmp.c_str());  // a failed write (disk full, ...) leaves the old checkpoint and no .tmp
    throw;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string err = std::strerror(errno);
    std::remove(tmp.c_str());
    throw std::runtime_error("checkpoint '" + path + "': rename from " + tmp + " failed (" + err + ")");
  }
  // The rename itself survives a power loss only once the directory is synced.
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}


namespace {
Checkpoint read_checkpoint_unchecked(const std::string& path);
}

// Any failure to read the file is bad input (exit 2), naming the file.
Checkpoint read_checkpoint(const std::string& path) {
  try {
    return read_checkpoint_unchecked(path);
  } catch (const std::invalid_argument&) {
    throw;
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string(e.what()) + " (a damaged or foreign checkpoint)");
  }
}

namespace {
Checkpoint read_checkpoint_unchecked(const std::string& path) {
  if (!std::filesystem::is_regular_file(path))
    throw std::invalid_argument("checkpoint '" + path + "' does not exist (a run writes it at its end, on SIGINT/SIGTERM "
                                "and every 'Output/checkpoint every' steps)");
  Quiet quiet;
  H fapl{fapl_no_locking(), H5Pclose};
  H f{H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.id), H5Fclose};
  if (f.id < 0) throw std::invalid_argument("checkpoint '" + path + "' is not a readable HDF5 file");
  H g{H5Gopen2(f.id, "/checkpoint", H5P_DEFAULT), H5Gclose};
  if (g.id < 0) throw std::invalid_argument("checkpoint '" + path + "' has no /checkpoint group: not a bfemp checkpoint");
  Checkpoint c;
  const long long format = read_attr<long long>(g.id, path, "format", H5T_NATIVE_LLONG);
  if (format != Checkpoint::kFormat)
    throw std::invalid_argument("checkpoint '" + path + "' has format " + std::to_string(format) + ", expected " +
                                std::to_string(Checkpoint::kFormat));
  c.time = read_attr<double>(g.id, path, "time", H5T_NATIVE_DOUBLE);
  c.step = static_cast<long>(read_attr<long long>(g.id, path, "step", H5T_NATIVE_LLONG));
  c.frames = static_cast<int>(read_attr<long long>(g.id, path, "frames", H5T_NATIVE_LLONG));
  c.dim = static_cast<int>(read_attr<long long>(g.id, path, "dim", H5T_NATIVE_LLONG));
  // Lists the datasets of group `loc` and calls f(name, dataset id).
  auto each = [&](hid_t loc, auto&& f) {
    H5G_info_t info;
    ok(H5Gget_info(loc, &info), path, "cannot list a group");
    for (hsize_t i = 0; i < info.nlinks; ++i) {
      char name[256];
      const ssize_t len = H5Lget_name_by_idx(loc, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
      if (len < 0 || len >= static_cast<ssize_t>(sizeof name)) ok(-1, path, "bad field name");
      if (std::string(name) != "text") f(std::string(name));  // the only subgroup
    }
  };
  auto read = [&](hid_t loc, const std::string& name, CheckpointArray& a, std::string* text) {
    const std::string what = "cannot read '" + name + "'";
    H d{ok(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), path, what), H5Dclose};
    H space{ok(H5Dget_space(d.id), path, what), H5Sclose};
    H type{ok(H5Dget_type(d.id), path, what), H5Tclose};
    const int rank = H5Sget_simple_extent_ndims(space.id);
    hsize_t dims[2] = {0, 1};
    if (rank < 1 || rank > 2 || H5Sget_simple_extent_dims(space.id, dims, nullptr) < 0) ok(-1, path, what);
    const std::size_t n = static_cast<std::size_t>(dims[0] * (rank == 2 ? dims[1] : 1));
    if (text) {
      text->assign(n, '\0');
      if (n) ok(H5Dread(d.id, H5T_NATIVE_UCHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, text->data()), path, what);
      return;
    }
    a.rows = dims[0];
    a.cols = rank == 2 ? dims[1] : 1;
    a.integer = H5Tget_class(type.id) == H5T_INTEGER;
    if (a.integer) {
      a.ints.resize(n);
      if (n) ok(H5Dread(d.id, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, a.ints.data()), path, what);
    } else {
      a.real.resize(n);
      if (n) ok(H5Dread(d.id, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, a.real.data()), path, what);
    }
  };
  each(g.id, [&](const std::string& name) { read(g.id, name, c.arrays[name], nullptr); });
  H t{H5Gopen2(g.id, "text", H5P_DEFAULT), H5Gclose};
  if (t.id >= 0) {
    CheckpointArray unused;
    each(t.id, [&](const std::string& name) { read(t.id, name, unused, &c.texts[name]); });
  }
  return c;
}
}  // namespace

}  // namespace bfemp
