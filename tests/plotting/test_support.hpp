// Helpers shared by the plotting tests: pixel access to RGB buffers, colour comparison, temp dirs.
#pragma once

#include "plotting/plot.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace ff::test {

// Read access to an RGB buffer (row-major, 3 bytes per pixel).
struct Image {
  int width, height;
  std::vector<unsigned char> rgb;
  ff::Rgb at(int x, int y) const {
    const size_t i = (size_t(y) * width + x) * 3;
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
};

inline bool near(ff::Rgb a, ff::Rgb b, int tol = 12) {
  return std::abs(a.r - b.r) <= tol && std::abs(a.g - b.g) <= tol && std::abs(a.b - b.b) <= tol;
}

inline bool is_white(ff::Rgb c) { return c.r == 255 && c.g == 255 && c.b == 255; }

// A fresh directory under the system temp dir, removed at the end of the test.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    path = std::filesystem::temp_directory_path() /
           ("ff_plot_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            std::to_string(reinterpret_cast<uintptr_t>(this)));
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

}  // namespace ff::test
