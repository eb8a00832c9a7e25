// libFuzzer harness of `--set` expressions: each line of the input is one PATH=VALUE (parse_assignment),
// applied to the reference rig's model (make_model_with, which builds the model).
#include <cstdint>
#include <exception>
#include <sstream>
#include <vector>

#include "fuzz/fuzz_support.hpp"
#include "common/yaml_reader.hpp"
#include "sweep/paths.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string model = std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml";
  static const YAML::Node reference = ff::load_yaml_file(model);
  try {
    std::vector<ff::Assignment> set;
    std::istringstream lines(ff::fuzz::text_of(data, size));
    for (std::string line; std::getline(lines, line);) set.push_back(ff::parse_assignment(line));
    // The model the assignments make, for its size (an assignment that fails here fails below too).
    YAML::Node doc = YAML::Clone(reference);
    try {
      for (const auto& a : set) ff::set_path(doc, a.path, a.value, a.source);
    } catch (const std::exception&) {
    }
    if (ff::fuzz::too_many_segments(doc)) return 0;
    (void)ff::make_model_with(YAML::Clone(reference), model, set);
  } catch (const std::exception&) {
  }
  return 0;
}
