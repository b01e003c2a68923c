#pragma once
// Time-series output in one HDF5 file (HDF5 C API):
//
//   /mesh/<name>            static datasets (e.g. "cells"), written once
//   /frame_000000/<name>    per-frame datasets (e.g. "positions", "velocity")
//     attributes: time (float64), step (int64), index (int64)
//
// Arrays are row-major, `rows x cols` (a 1-D dataset when cols == 1); doubles
// are stored as IEEE float64 LE, integers as int64 LE.
//
// Parallel use (MPI): a writer built with a communicator of R > 1 ranks opens
// the file with HDF5's MPI-IO driver on every rank of it. Every call is then
// collective (all ranks, same order, same names and shapes); data go with
// independent transfers:
//   write_array / write_static   the same data on every rank (replicated FEM
//                                state); rank 0 writes them, the others only
//                                take part in creating the dataset;
//   write_rows / write_static_rows  each rank its block of rows at first_row
//                                of total_rows (particles in id order).
// A failed transfer on one rank is agreed on (one allreduce per dataset), so
// every rank throws and none is left waiting in the next collective call.
// Why MPI-IO and not a gather to rank 0: measured cheaper at 1e6 particles
// (perf/README "One output frame from P ranks") and no rank holds the frame.
// R = 1 (or MPI_COMM_NULL): the serial file driver, as without MPI.
//
// Durability: end_frame() and write_static() call H5Fflush, so the file on
// disk is complete and readable after every finished frame even while the
// writer stays open (a crash loses at most the frame in progress). The file
// is created without HDF5 file locking so that a viewer can open it while the
// simulation is still running.
//
// Every failing HDF5 call becomes a std::runtime_error naming the file, the
// object and the HDF5 error stack; HDF5's automatic error printing is
// suppressed for the duration of each call.
#include <mpi.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace bfemp {

class Hdf5FrameWriter {
 public:
  // Creates (or truncates) the file; collective over comm (see above).
  explicit Hdf5FrameWriter(const std::string& path, MPI_Comm comm = MPI_COMM_NULL);
  // Restart: opens the existing file for writing, keeps frames 0 ..
  // keep_frames - 1 and /mesh, and unlinks later frame groups (written after
  // the checkpoint the run continues from). Throws std::runtime_error naming
  // the file when it is missing or a kept frame is absent.
  Hdf5FrameWriter(const std::string& path, int keep_frames, MPI_Comm comm = MPI_COMM_NULL);
  // Closes any open frame and the file; errors are swallowed (call close() to
  // see them).
  ~Hdf5FrameWriter();
  Hdf5FrameWriter(const Hdf5FrameWriter&) = delete;
  Hdf5FrameWriter& operator=(const Hdf5FrameWriter&) = delete;

  // Creates group frame_group_name(index) with attributes time, step, index.
  // Throws if a frame is already open, index < 0 or the group exists.
  void begin_frame(int index, double time, long step);
  // Datasets in the open frame; throws if no frame is open or name exists.
  void write_array(const std::string& name, const double* data, std::size_t rows,
                   std::size_t cols);
  void write_array(const std::string& name, const long long* data, std::size_t rows,
                   std::size_t cols);
  // This rank's rows [first_row, first_row + rows) of a dataset of total_rows
  // x cols in the open frame (parallel writer: every rank calls it with the
  // same name, total_rows and cols; serial: first_row 0, rows == total_rows).
  void write_rows(const std::string& name, const double* data, std::size_t rows, std::size_t first_row,
                  std::size_t total_rows, std::size_t cols);
  void write_rows(const std::string& name, const long long* data, std::size_t rows, std::size_t first_row,
                  std::size_t total_rows, std::size_t cols);
  // Datasets in "/mesh" (created on first use), flushed immediately.
  void write_static(const std::string& name, const double* data, std::size_t rows,
                    std::size_t cols);
  void write_static(const std::string& name, const long long* data, std::size_t rows,
                    std::size_t cols);
  void write_static_rows(const std::string& name, const long long* data, std::size_t rows,
                         std::size_t first_row, std::size_t total_rows, std::size_t cols);
  // Closes the frame group and flushes the file.
  void end_frame();
  // Ends an open frame and closes the file, throwing on error. Idempotent.
  void close();

  const std::string& path() const { return path_; }
  // Attribute "time" of frame `index` (restart rebuilds the XDMF index).
  double frame_time(int index) const;
  bool frame_open() const { return frame_ >= 0; }
  // True when the file is open with MPI-IO on more than one rank.
  bool parallel() const { return comm_ != MPI_COMM_NULL; }
  // "/frame_%06d".
  static std::string frame_group_name(int index);

 private:
  // Rows [first_row, first_row + rows) of a total_rows x cols dataset; with
  // replicated = true (parallel) only rank 0 transfers (rows == total_rows).
  void write_dataset(std::int64_t loc, const std::string& loc_name, const std::string& name,
                     bool integer, const void* data, std::size_t rows, std::size_t first_row,
                     std::size_t total_rows, std::size_t cols, bool replicated);
  void close_handles() noexcept;
  std::int64_t mesh_group();  // "/mesh", created on first use
  std::int64_t frame_group(const std::string& dataset) const;  // throws if none open
  void flush(const std::string& after);

  std::string path_;
  MPI_Comm comm_ = MPI_COMM_NULL;  // set when parallel (R > 1)
  int rank_ = 0;
  std::int64_t file_ = -1;   // hid_t
  std::int64_t frame_ = -1;  // open frame group
  std::int64_t mesh_ = -1;   // "/mesh" group
  std::string frame_name_;
};

// Read helpers (tests, post-processing). `path` is the absolute object path in
// the file, e.g. "/frame_000001/positions". The shape (1 or 2 entries) is
// returned through `shape` when non-null. Integer data are converted.
std::vector<double> read_dataset(const std::string& file, const std::string& path,
                                 std::vector<std::size_t>* shape);
std::vector<long long> read_dataset_int(const std::string& file, const std::string& path,
                                        std::vector<std::size_t>* shape);
// Scalar numeric attribute `name` of the object (group or dataset) `object`.
double read_attribute(const std::string& file, const std::string& object,
                      const std::string& name);
// True if `path` names an existing dataset in `file`.
bool dataset_exists(const std::string& file, const std::string& path);

}  // namespace bfemp
