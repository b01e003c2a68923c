#pragma once
// Whole-file replacement that readers never see half-written.
#include <string>

namespace bfemp {

// Writes `contents` to `path` + ".tmp", closes it, then std::rename()s it over
// `path` (atomic on POSIX file systems when both lie in the same directory).
// Throws std::runtime_error naming the path and the OS error on any failure;
// the temporary file is removed on failure.
void write_file_atomically(const std::string& path, const std::string& contents);

}  // namespace bfemp
