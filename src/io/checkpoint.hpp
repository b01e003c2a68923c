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
#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace bfemp {

struct CheckpointArray {
  std::size_t rows = 0, cols = 1;
  bool integer = false;
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
  bool has(const std::string& name) const { return arrays.count(name) > 0; }
  // texts[name]; throws std::invalid_argument naming it when missing.
  const std::string& text(const std::string& name) const;
  // The array's values; throws std::invalid_argument naming the field when it
  // is missing, of the other kind, or its row count differs from `rows`
  // (rows < 0: any).
  const std::vector<double>& real(const std::string& name, long rows = -1) const;
  const std::vector<long long>& ints(const std::string& name, long rows = -1) const;
};

// Writes atomically (see above). Throws std::runtime_error naming the file.
void write_checkpoint(const std::string& path, const Checkpoint& c);
// Reads a checkpoint; throws std::invalid_argument naming the file when it is
// missing, not a bfemp checkpoint or of another format version.
Checkpoint read_checkpoint(const std::string& path);

}  // namespace bfemp
