// libFuzzer harness of the study YAML reader: the input is a study file's text, written to
// studies/fuzz.yaml in a scratch directory that holds the three models of configs/ one level up (so the
// seeds' `model: ../fbtb.yaml` resolves). read_study, then check_models as load_study does, and the
// models of the first 16 variants as the runner builds them (an override is checked the same way in
// every variant; 81 models of up to 24 segments take 11 s under the sanitizers).
#include <cstdint>
#include <exception>

#include "fuzz/fuzz_support.hpp"
#include "common/errors.hpp"
#include "common/yaml_reader.hpp"
#include "sweep/study.hpp"

namespace {

// At most 256 variants read, 16 built, so one input costs about a second at most.
constexpr int kVariants = 256;
constexpr std::size_t kBuilt = 16;

const std::string& study_path() {
  static const std::string path = [] {
    for (const char* model : {"fbtb.yaml", "fbtb_hydraulic.yaml", "emps.yaml"})
      std::filesystem::copy_file(std::string(FLEXFARM_SOURCE_DIR) + "/configs/" + model,
                                 ff::fuzz::scratch().path() / model);
    return (ff::fuzz::scratch().path() / "studies" / "fuzz.yaml").string();
  }();
  return path;
}

// True when some variant's model would have more than kMaxSegments segments.
bool too_large(const ff::Study& st) {
  for (const auto& v : st.variants) {
    YAML::Node doc = YAML::Load(st.model_text);
    try {
      for (const auto& a : ff::make_variant_set(st, v)) ff::set_path(doc, a.path, a.value, a.source);
    } catch (const std::exception&) {
      continue;  // make_variant_model reports it
    }
    if (ff::fuzz::too_many_segments(doc)) return true;
  }
  return false;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = study_path();
  ff::fuzz::scratch().write("studies/fuzz.yaml", ff::fuzz::text_of(data, size));
  try {
    ff::Study st = ff::read_study(path, kVariants);
    if (st.variants.size() > kBuilt) st.variants.resize(kBuilt);
    if (too_large(st)) return 0;
    ff::check_models(st);
    for (const auto& v : st.variants) {
      try {
        ff::make_variant_model(st, v);
      } catch (const ff::ConfigError&) {  // a drawn value the model rejects: the variant runs as `invalid`
      }
    }
  } catch (const std::exception&) {
  }
  return 0;
}
