// Output files are written whole or not at all: to "<path>.tmp", then renamed.
#pragma once

#include <string>

namespace ff {

// Writes `text` to `path` atomically. Throws std::runtime_error naming the path on failure.
void write_file_atomic(const std::string& path, const std::string& text);

// Creates a directory and its parents. Throws std::runtime_error naming the path on failure.
void make_directories(const std::string& path);

}  // namespace ff
