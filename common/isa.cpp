#include "common/isa.hpp"

#include <algorithm>
#include <cstdlib>

#include "common/errors.hpp"

namespace ff {

const char* isa_name(Isa isa) {
  switch (isa) {
    case Isa::avx512: return "avx512";
    case Isa::avx2: return "avx2";
    default: return "sse2";
  }
}

std::optional<Isa> parse_isa(const std::string& name) {
  for (Isa isa : {Isa::sse2, Isa::avx2, Isa::avx512})
    if (name == isa_name(isa)) return isa;
  return std::nullopt;
}

Isa available_isa() {
#if FF_ISA_MULTIVERSION
  // The CPU's flags, with the operating system's support for the wider registers (GCC checks XGETBV).
  if (__builtin_cpu_supports("avx512f")) return Isa::avx512;
  if (__builtin_cpu_supports("avx2")) return Isa::avx2;
#endif
  return Isa::sse2;
}

Isa select_isa(Isa isa) {
  const Isa use = std::min(isa, available_isa());
  detail::active_isa.store(static_cast<int>(use), std::memory_order_relaxed);
  return use;
}

Isa detail::init_active_isa() {
  const char* env = std::getenv("FLEXFARM_ISA");
  if (env == nullptr || *env == '\0') return select_isa(available_isa());
  const std::optional<Isa> asked = parse_isa(env);
  if (!asked)
    throw ConfigError("environment", 0, "FLEXFARM_ISA",
                      "'" + std::string(env) + "' is not a vector width (sse2, avx2 or avx512)");
  return select_isa(*asked);
}

std::string describe_isa() {
  return std::string(isa_name(active_isa())) + " (this CPU and build: up to " + isa_name(available_isa()) + ")";
}

}  // namespace ff
