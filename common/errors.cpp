#include "common/errors.hpp"

#include <sstream>

namespace ff {

namespace {
std::string format_error(const std::string& file, int line, const std::string& key, const std::string& message) {
  std::ostringstream out;
  out << file;
  if (line > 0) out << ':' << line;
  if (!key.empty()) out << ": " << key;
  out << ": " << message;
  return out.str();
}
}  // namespace

ConfigError::ConfigError(const std::string& file, int line, const std::string& key, const std::string& message)
    : std::runtime_error(format_error(file, line, key, message)), file_(file), line_(line), key_(key), message_(message) {}

}  // namespace ff
