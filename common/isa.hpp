// The vector width the lane kernels run at: SSE2 (x86-64's baseline), AVX2 or AVX-512.
//
// Each hot kernel is compiled once per width (FF_ISA_DISPATCH below) and the copy for the active
// width is called. The active width is the widest the CPU offers, or narrower when asked:
// FLEXFARM_ISA=sse2|avx2|avx512 in the environment, or select_isa() (tests). The results are the same
// bits at every width: the lanes never mix, and no multiply-add is fused (-ffp-contract=off; the
// AVX2 copy is compiled without FMA), so each lane does IEEE's operations in the same order.
#pragma once

#include <atomic>
#include <optional>
#include <string>

namespace ff {

enum class Isa { sse2 = 0, avx2 = 1, avx512 = 2 };

// "sse2", "avx2", "avx512".
const char* isa_name(Isa isa);
std::optional<Isa> parse_isa(const std::string& name);

// The widest width this CPU runs and this build has copies for (a build without multiversioning,
// such as clang's sanitizer build or a non-x86 one, has the baseline only).
Isa available_isa();

namespace detail {
inline std::atomic<int> active_isa{-1};  // -1 until first asked
Isa init_active_isa();
}  // namespace detail

// The width in use: FLEXFARM_ISA's (clamped to available_isa()) or the widest available. The first
// call reads the environment and throws ConfigError naming the variable when FLEXFARM_ISA holds no
// width's name (main asks before any kernel runs); later calls are one relaxed load.
inline Isa active_isa() {
  const int v = detail::active_isa.load(std::memory_order_relaxed);
  return v >= 0 ? static_cast<Isa>(v) : detail::init_active_isa();
}

// Makes `isa`, clamped to available_isa(), the width in use; returns it.
Isa select_isa(Isa isa);

// "avx512 (of avx512)" and the like: the width in use and the widest available, for --version.
std::string describe_isa();

}  // namespace ff

// FF_ISA_DISPATCH(ret, name, (params), (args)) defines `ret name(params)`, which calls the static
// function name##_kernel(args) (defined before it in the same file) compiled for the active width.
// Each width's copy is a wrapper with GCC's target attribute and flatten, so the kernel and
// everything it calls in the same file is inlined into it and compiled for that width.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define FF_ISA_MULTIVERSION 1
#define FF_ISA_DISPATCH(ret, name, params, args)                                                     \
  [[gnu::target("avx512f"), gnu::flatten]] static ret name##_avx512 params { return name##_kernel args; } \
  [[gnu::target("avx2"), gnu::flatten]] static ret name##_avx2 params { return name##_kernel args; }     \
  [[gnu::flatten]] static ret name##_sse2 params { return name##_kernel args; }                          \
  ret name params {                                                                                  \
    switch (::ff::active_isa()) {                                                                    \
      case ::ff::Isa::avx512: return name##_avx512 args;                                             \
      case ::ff::Isa::avx2: return name##_avx2 args;                                                 \
      default: return name##_sse2 args;                                                              \
    }                                                                                                \
  }
#else
#define FF_ISA_MULTIVERSION 0
#define FF_ISA_DISPATCH(ret, name, params, args) \
  ret name params { return name##_kernel args; }
#endif
