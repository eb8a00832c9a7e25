// A plain SplitMix64 stream (Vigna's splitmix64.c) for test data: uniforms in [0, 1) from its top
// 53 bits. Independent of the code under test on purpose.
#pragma once

#include <cmath>
#include <cstdint>

namespace ff::test {

struct TestRng {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double exponential() { return -std::log1p(-uniform()); }  // mean 1
};

}  // namespace ff::test
