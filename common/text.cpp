#include "common/text.hpp"

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/exceptions.h>

#include <charconv>
#include <cmath>
#include <map>

#include "common/errors.hpp"

namespace ff {

std::string yaml_error_message(const YAML::Exception& e) {
  if (const auto* deep = dynamic_cast<const YAML::DeepRecursion*>(&e))
    return "lists and maps nested more than " + std::to_string(deep->depth() - 1) + " deep (yaml-cpp's limit)";
  return e.msg;
}

std::optional<long long> parse_integer(std::string_view text, long long lo, long long hi) {
  const auto x = parse_integer(text);
  if (!x || *x < lo || *x > hi) return std::nullopt;
  return x;
}

std::optional<double> parse_finite(std::string_view text) {
  double x = 0.0;
  const char* end = text.data() + text.size();
  const auto [at, ec] = std::from_chars(text.data(), end, x);
  if (text.empty() || ec != std::errc() || at != end || !std::isfinite(x)) return std::nullopt;
  return x;
}

std::string strip_bom(std::string line) {
  if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
  return line;
}

void check_csv_header(const std::vector<std::string>& names, const std::string& source, int line) {
  std::map<std::string, std::size_t> seen;  // name -> its column, 1-based
  for (std::size_t c = 0; c < names.size(); ++c) {
    if (names[c].empty()) throw ConfigError(source, line, "", "column " + std::to_string(c + 1) + " has no name");
    const auto [it, fresh] = seen.emplace(names[c], c + 1);
    if (!fresh)
      throw ConfigError(source, line, names[c],
                        "columns " + std::to_string(it->second) + " and " + std::to_string(c + 1) + " are both named '" +
                            names[c] + "': each column needs its own name");
  }
}

}  // namespace ff
