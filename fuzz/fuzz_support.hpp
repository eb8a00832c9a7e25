// Helpers of the libFuzzer harnesses (docs/fuzzing.md): the input as text, and a scratch directory of
// the process for the readers that take a file.
#pragma once

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace ff::fuzz {

inline std::string text_of(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// A directory of this process under the system's temporary one, removed when the process exits.
class ScratchDir {
 public:
  ScratchDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "flexfarm-fuzz-XXXXXX").string();
    if (!mkdtemp(tmpl.data())) std::abort();
    path_ = tmpl;
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }
  // Writes `text` to the file `name` in the directory (its folders created) and returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    const auto p = path_ / name;
    std::filesystem::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }

 private:
  std::filesystem::path path_;
};

// Beams of many segments are valid but cost O(segments^3) to build (the modes): the harnesses skip
// models of more than kMaxSegments, whose reading is that of 6 segments.
inline constexpr int kMaxSegments = 64;
inline bool too_many_segments(const YAML::Node& model) {
  int segments = 0;
  return model.IsMap() && model["segments"] && model["segments"].IsScalar() &&
         YAML::convert<int>::decode(model["segments"], segments) && segments > kMaxSegments;
}

inline const ScratchDir& scratch() {
  static const ScratchDir dir;
  return dir;
}

}  // namespace ff::fuzz
