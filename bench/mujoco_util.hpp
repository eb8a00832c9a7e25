// What every bench that runs MuJoCo beside flexfarm shares (bench/mujoco_compare.cpp,
// bench/tree_mujoco.cpp, bench/realtime_arm.cpp, bench/work_precision.cpp, bench/run_vs_mujoco.cpp):
// MJCF compiled from memory, MuJoCo's warnings kept out of the output, the timing helpers, and
// comma-separated option values.
#pragma once

#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <functional>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace ff::bench {

// Compiles MJCF text through MuJoCo's virtual file system (no temporary file).
inline mjModel* load_mjcf(const std::string& xml) {
  auto vfs = std::make_unique<mjVFS>();  // ~2 MB: heap, not stack
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), "model.xml", static_cast<int>(xml.size())) != 0)
    throw std::runtime_error("mj_makeEmptyFileVFS failed");
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), "model.xml")], xml.data(), xml.size());
  char err[1000] = "";
  mjModel* m = mj_loadXML("model.xml", vfs.get(), err, sizeof err);
  mj_deleteVFS(vfs.get());
  if (!m) throw std::runtime_error(std::string("mj_loadXML: ") + err);
  return m;
}

// MuJoCo's warnings are checked per run in mjData::warning instead of printed.
inline void quiet_warning(const char*) {}

// Wall seconds of one call of f.
inline double time_it(const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

inline double median(std::vector<double> x) {
  std::sort(x.begin(), x.end());
  const std::size_t n = x.size();
  return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

// "6,24,48" -> {6, 24, 48}.
inline std::vector<double> parse_list(const std::string& s) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string tok;
  while (std::getline(ss, tok, ',')) out.push_back(std::stod(tok));
  return out;
}

}  // namespace ff::bench
