// Putting a finished file in place so that a crash never leaves a half-written one where a good one
// was: data flushed to disk, atomic rename, folder flushed (shared by the writers of the io layer).
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace sinew::io_detail {

namespace fs = std::filesystem;

// fsync a file or folder by path.
inline void sync_path(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) throw std::runtime_error("cannot open " + path + " to flush it to disk");
  const int r = ::fsync(fd);
  ::close(fd);
  if (r != 0 && !directory) throw std::runtime_error("flushing " + path + " to disk failed");
}

// Puts a finished file in place durably: its data on disk first, then the rename, then the folder.
inline void replace_durably(const std::string& tmp, const std::string& path) {
  sync_path(tmp, false);
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) throw std::runtime_error("cannot rename " + tmp + " to " + path + ": " + ec.message());
  const fs::path dir = fs::path(path).parent_path();
  sync_path(dir.empty() ? "." : dir.string(), true);
}

// Writes a file aside (PATH.tmp, opened with fopen's `mode`) with write(FILE*) (returning false when
// a write came up short), checks the stream, and puts it in place durably. Throws std::runtime_error
// naming the file when it cannot be written.
template <class Write>
void write_durably(const std::string& path, const char* mode, Write&& write) {
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), mode);
  if (!f) throw std::runtime_error("cannot write " + tmp);
  bool ok = false;
  try {
    ok = write(f) && std::ferror(f) == 0;
  } catch (...) {
    std::fclose(f);
    throw;
  }
  if (std::fclose(f) != 0 || !ok) throw std::runtime_error("writing " + tmp + " failed (disk full?)");
  replace_durably(tmp, path);
}

}  // namespace sinew::io_detail
