// Running the flexfarm binary from a test (any folder's test program: FLEXFARM_SOURCE_DIR and
// FLEXFARM_BINARY are defined for each by flexfarm_tests in cmake/flexfarm.cmake).
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace ff::test {

struct CliResult {
  int exit_code;
  std::string output;  // stdout and stderr together
};

// `flexfarm ARGS`, run from the source tree.
inline CliResult run_flexfarm(const std::string& args) {
  const std::string cmd = "cd '" FLEXFARM_SOURCE_DIR "' && '" FLEXFARM_BINARY "' " + args + " 2>&1";
  CliResult r{0, {}};
  FILE* p = popen(cmd.c_str(), "r");
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p)) r.output += buf;
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// The string value of the first `"key": "..."` in a JSON file written by flexfarm ("" when absent):
// "verdict" is the diagnosis' verdict, "effect" its first-ranked effect.
inline std::string json_field(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  const std::string text = s.str(), k = "\"" + key + "\": \"";
  const auto a = text.find(k);
  return a == std::string::npos ? "" : text.substr(a + k.size(), text.find('"', a + k.size()) - a - k.size());
}

}  // namespace ff::test
