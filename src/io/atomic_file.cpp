#include "io/atomic_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace bfemp {

void write_file_atomically(const std::string& path, const std::string& contents) {
  const std::string tmp = path + ".tmp";
  auto fail = [&](const std::string& what, int err) {
    std::remove(tmp.c_str());
    throw std::runtime_error("file '" + path + "': " + what + " (" + std::strerror(err) + ")");
  };
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) fail("cannot open temporary '" + tmp + "' for writing", errno);
  const std::size_t written = std::fwrite(contents.data(), 1, contents.size(), f);
  const int write_errno = errno;
  if (written != contents.size()) {
    std::fclose(f);
    fail("short write to '" + tmp + "'", write_errno);
  }
  if (std::fclose(f) != 0) fail("cannot close '" + tmp + "'", errno);
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    fail("cannot rename '" + tmp + "' over it", errno);
}

}  // namespace bfemp
