// Errors raised at the boundary: bad input files get one clear message naming file, line and key.
#pragma once

#include <stdexcept>
#include <string>

namespace ff {

// A bad configuration or data file. what() reads "FILE:LINE: KEY: MESSAGE" (line 0 = unknown).
class ConfigError : public std::runtime_error {
 public:
  ConfigError(const std::string& file, int line, const std::string& key, const std::string& message);
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& key() const { return key_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_;
  std::string key_;
  std::string message_;
};

}  // namespace ff
