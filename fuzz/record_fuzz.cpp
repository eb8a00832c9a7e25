// libFuzzer harness of the measurement-record reader: the input is a record CSV, written to a scratch
// file and read by read_record_csv (no required columns beyond t: every check of the reader runs).
#include <cstdint>
#include <exception>

#include "fuzz/fuzz_support.hpp"
#include "validate/record.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = ff::fuzz::scratch().write("record.csv", ff::fuzz::text_of(data, size));
  try {
    (void)ff::read_record_csv(path, {});
  } catch (const std::exception&) {
  }
  return 0;
}
