// A benchmark run at one vector width (common/isa.hpp): kernel_bench's Width benchmarks and fp_peak.
#pragma once

#include <benchmark/benchmark.h>

#include "common/isa.hpp"

namespace ff::bench {

// Makes `isa` the width in use for the benchmark's lifetime, or marks the benchmark skipped when the
// CPU lacks it (ok() false); the width in use before is restored at the end.
class WidthScope {
 public:
  WidthScope(benchmark::State& state, Isa isa) : was_(active_isa()), ok_(select_isa(isa) == isa) {
    if (!ok_) state.SkipWithError("this CPU lacks the width");
  }
  ~WidthScope() { select_isa(was_); }
  WidthScope(const WidthScope&) = delete;
  WidthScope& operator=(const WidthScope&) = delete;
  bool ok() const { return ok_; }

 private:
  Isa was_;
  bool ok_;
};

}  // namespace ff::bench
