#include "apps/verbs.hpp"
#include "kernel/model_io.hpp"
#include "kernel/simulate.hpp"
#include "kernel/yaml_reader.hpp"
#include "sweep/paths.hpp"

namespace ff {

Model load_model_with(const std::string& path, const std::vector<std::string>& sets) {
  std::vector<Assignment> assignments;
  for (const auto& s : sets) assignments.push_back(parse_assignment(s));
  return make_model_with(load_yaml_file(path), path, assignments);
}

}  // namespace ff
