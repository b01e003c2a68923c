#pragma once
// Restart checkpoints: one HDF5 file holding everything a run needs to
// continue bit-for-bit, written atomically.
//
//   /checkpoint            attributes: format (int64, kFormat), time (s),
//                          step, frames (frames written so far), dim
//   /checkpoint/text/<name> text (uint8 bytes): the scene as read, the --set
//                          overrides, the resolved scene, the base directory
//   /checkpoint/<field>    float64 or int64 arrays, rows x cols
//
// The file is first written to `path + ".tmp"`, flushed and fsync'ed, then
// renamed over `path`, so a reader sees either the previous checkpoint or the
// new one, never a half-written file (POSIX rename within one directory).
// This layer knows nothing of the simulation: fields are named arrays.
//
// Several ranks (MPI): write_checkpoint is collective and writes one file
// through MPI-IO. An array is either replicated (the same on every rank; rank
// 0 writes it) or a row block (put_rows: each rank writes its rows of a
// dataset of total_rows; the dataset carries the int64 attribute "blocked" =
// 1). read_checkpoint(path, rank, nranks) reads replicated arrays whole and
// rank's part of each blocked one: rows [total * rank / nranks, total *
// (rank + 1) / nranks). No rank ever holds another rank's rows, so a
// checkpoint of 1e7 particles costs each of R ranks 1/R of it. Files without
// "blocked" attributes (written before 2026-12-07) read whole on every rank.
#include <mpi.h>

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace bfemp {

struct CheckpointArray {
  std::size_t rows = 0, cols = 1;
  bool integer = false;
  // A row block: rows [first_row, first_row + rows) of total_rows.
  bool blocked = false;
  std::size_t first_row = 0, total_rows = 0;
  std::vector<double> real;         // rows * cols when !integer
  std::vector<long long> ints;      // rows * cols when integer
};

struct Checkpoint {
  static constexpr long long kFormat = 1;
  double time = 0;
  long step = 0;
  int frames = 0;  // output frames written before the checkpoint
  int dim = 0;
  std::map<std::string, std::string> texts;
  std::map<std::string, CheckpointArray> arrays;

  void put(const std::string& name, std::vector<double> v, std::size_t cols = 1);
  void put(const std::string& name, std::vector<long long> v, std::size_t cols = 1);
  // A row block (see above); every rank puts the same names, cols and
  // total_rows. first_row + v.size() / cols <= total_rows.
  void put_rows(const std::string& name, std::vector<double> v, std::size_t cols, std::size_t first_row,
                std::size_t total_rows);
  void put_rows(const std::string& name, std::vector<long long> v, std::size_t cols, std::size_t first_row,
                std::size_t total_rows);
  bool has(const std::string& name) const { return arrays.count(name) > 0; }
  // The array; throws std::invalid_argument naming it when missing.
  const CheckpointArray& array(const std::string& name) const;
  // texts[name]; throws std::invalid_argument naming it when missing.
  const std::string& text(const std::string& name) const;
  // The array's values; throws std::invalid_argument naming the field when it
  // is missing, of the other kind, or its row count differs from `rows`
  // (rows < 0: any).
  const std::vector<double>& real(const std::string& name, long rows = -1) const;
  const std::vector<long long>& ints(const std::string& name, long rows = -1) const;
};

// Writes atomically (see above). Throws std::runtime_error naming the file
// (on every rank when it fails on one). comm: MPI_COMM_NULL or one rank, the
// serial driver (every array whole); more ranks, collective over comm, with
// the same texts, attributes and array names, shapes and replicated values on
// every rank.
void write_checkpoint(const std::string& path, const Checkpoint& c, MPI_Comm comm = MPI_COMM_NULL);
// Reads a checkpoint (rank's blocks of the blocked arrays, see above; not
// collective); throws std::invalid_argument naming the file when it is
// missing, not a bfemp checkpoint or of another format version.
Checkpoint read_checkpoint(const std::string& path, int rank = 0, int nranks = 1);

}  // namespace bfemp
