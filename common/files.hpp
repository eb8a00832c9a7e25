// Output files are written whole or not at all: to "<path>.tmp", then renamed.
#pragma once

#include <string>

namespace ff {

// Writes `text` to `path` atomically. Throws std::runtime_error naming the path on failure.
void write_file_atomic(const std::string& path, const std::string& text);

// A file name made from a name read from an input (a parameter path, a case label, a channel):
// letters, digits, '_' and '-' kept, anything else '_', so it cannot leave its directory.
std::string make_file_stem(const std::string& name);

// The whole text of a file. Throws std::runtime_error "<path>: cannot open" when it cannot be read.
std::string read_file(const std::string& path);

// Creates a directory and its parents. Throws std::runtime_error naming the path on failure.
void make_directories(const std::string& path);

// An exclusive lock on `path` (flock; the file is created if missing), held until destruction, so that
// two processes never write the same output. Throws std::runtime_error, naming `what`, when another
// process holds it: it refuses at once rather than wait.
class FileLock {
 public:
  FileLock(const std::string& path, const std::string& what);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace ff
