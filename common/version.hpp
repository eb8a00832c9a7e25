// The flexfarm version and the git commit it was built from (cmake/version.cmake writes them at each
// build): what a run's provenance, the run history and `flexfarm --version` report.
#pragma once

#include <string>

namespace ff {

const char* flexfarm_version();  // the project version, "0.1.0"
const char* flexfarm_commit();   // the commit, "3f2a9c1d0b7e" or "3f2a9c1d0b7e-dirty"; "" when not built from git

// "0.1.0 (3f2a9c1d0b7e)", or "0.1.0" when the commit is not known.
inline std::string describe_version() {
  const std::string c = flexfarm_commit();
  return std::string(flexfarm_version()) + (c.empty() ? "" : " (" + c + ")");
}

}  // namespace ff
