#include "common/text.hpp"

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/exceptions.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdarg>
#include <map>
#include <stdexcept>

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

std::string md_cell(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    if (c == '|') out += "\\|";
    else if (c == '\n' || c == '\r') out += ' ';
    else out += c;
  }
  return out;
}

std::string terminal_safe(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    const bool c1 = c == 0xC2 && i + 1 < text.size() && static_cast<unsigned char>(text[i + 1]) >= 0x80 &&
                    static_cast<unsigned char>(text[i + 1]) <= 0x9F;
    if ((c < 0x20 && c != '\n' && c != '\t') || c == 0x7F) {
      out += '?';
    } else if (c1) {
      out += '?';
      ++i;
    } else {
      out += text[i];
    }
  }
  return out;
}

std::string fill_template(std::string_view page, const std::vector<std::pair<std::string, std::string>>& parts) {
  std::vector<std::pair<std::size_t, std::size_t>> at;  // position in the template, part
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const std::size_t p = page.find(parts[k].first);
    if (p == std::string_view::npos) throw std::logic_error("the page template lacks " + parts[k].first);
    at.emplace_back(p, k);
  }
  std::sort(at.begin(), at.end());
  std::string out;
  std::size_t from = 0;
  for (const auto& [p, k] : at) {
    out.append(page.substr(from, p - from));
    out += parts[k].second;
    from = p + parts[k].first.size();
  }
  out.append(page.substr(from));
  return out;
}

void print_safe(std::FILE* out, const char* format, ...) {
  std::va_list args, again;
  va_start(args, format);
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, format, args);
  va_end(args);
  std::vector<char> text(static_cast<std::size_t>(n > 0 ? n : 0) + 1);
  std::vsnprintf(text.data(), text.size(), format, again);
  va_end(again);
  std::fputs(terminal_safe(std::string(text.data(), text.size() - 1)).c_str(), out);
}

}  // namespace ff
