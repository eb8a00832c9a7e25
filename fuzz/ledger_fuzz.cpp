// libFuzzer harness of the model ledger's read-back: the input is the bytes of a database file, opened
// by report_ledger (the ledger's tables made if absent, the versions fitted to one record read back as
// a table and a plot).
#include <cstdint>
#include <exception>

#include "fuzz/fuzz_support.hpp"
#include "validate/ledger.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto dir = ff::fuzz::scratch().path() / "ledger";
  std::filesystem::remove_all(dir);  // with any -journal or -wal file SQLite left
  const std::string path = ff::fuzz::scratch().write("ledger/ledger.sqlite", ff::fuzz::text_of(data, size));
  try {
    (void)ff::report_ledger(path, "rec.csv", ff::ReplayMode::kInverseDynamics);
  } catch (const std::exception&) {
  }
  return 0;
}
