// common/isa.cpp: the vector width's names, the environment's choice and its clamp to the CPU.
#include "common/isa.hpp"

#include <gtest/gtest.h>

#include <cstdlib>

#include "common/errors.hpp"

namespace ff {
namespace {

// Restores the width in use when a test has changed it.
struct KeepIsa {
  Isa was = active_isa();
  ~KeepIsa() { select_isa(was); }
};

TEST(Isa, NamesReadBackAndNothingElseIsAWidth) {
  for (Isa isa : {Isa::sse2, Isa::avx2, Isa::avx512}) EXPECT_EQ(parse_isa(isa_name(isa)), isa);
  for (const char* bad : {"", "AVX2", "avx", "avx512f", "sse", "native"}) EXPECT_FALSE(parse_isa(bad)) << bad;
}

TEST(Isa, AWidthIsClampedToWhatTheCpuRuns) {
  KeepIsa keep;
  EXPECT_EQ(select_isa(Isa::sse2), Isa::sse2);
  EXPECT_EQ(active_isa(), Isa::sse2);
  EXPECT_EQ(select_isa(Isa::avx512), available_isa());
  EXPECT_EQ(active_isa(), available_isa());
}

TEST(Isa, TheEnvironmentNarrowsTheWidthAndABadNameIsRefused) {
  KeepIsa keep;
  ::setenv("FLEXFARM_ISA", "sse2", 1);
  detail::active_isa = -1;
  EXPECT_EQ(active_isa(), Isa::sse2);
  EXPECT_NE(describe_isa().find("sse2 (this CPU and build: up to "), std::string::npos) << describe_isa();
  ::setenv("FLEXFARM_ISA", "avx1024", 1);
  detail::active_isa = -1;
  try {
    active_isa();
    ADD_FAILURE() << "FLEXFARM_ISA=avx1024 was taken";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "environment: FLEXFARM_ISA: 'avx1024' is not a vector width (sse2, avx2 or avx512)");
  }
  ::unsetenv("FLEXFARM_ISA");
  detail::active_isa = -1;
  EXPECT_EQ(active_isa(), available_isa());
}

}  // namespace
}  // namespace ff
