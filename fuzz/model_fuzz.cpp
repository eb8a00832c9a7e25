// libFuzzer harness of the model YAML reader: the input is a model file's text (load_yaml_text, then
// parse_model, which builds the model). Every rejection must be a std::exception.
#include <cstdint>
#include <exception>

#include "fuzz/fuzz_support.hpp"
#include "kernel/model_io.hpp"
#include "common/yaml_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const YAML::Node doc = ff::load_yaml_text(ff::fuzz::text_of(data, size), "fuzz.yaml");
    if (ff::fuzz::too_many_segments(doc)) return 0;
    (void)ff::parse_model(doc, "fuzz.yaml");
  } catch (const std::exception&) {
  }
  return 0;
}
