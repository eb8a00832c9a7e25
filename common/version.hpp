// The flexfarm version and the git commit it was built from (cmake/version.cmake writes them at each
// build): what a run's provenance, the run history and `flexfarm --version` report.
#pragma once

#include <string>

namespace ff {

const char* flexfarm_version();  // the project version, "0.1.0"
const char* flexfarm_commit();   // the commit, "3f2a9c1d0b7e" or "3f2a9c1d0b7e-dirty"; "" when not built from git

// A build as the run records and the history write it: "0.1.0 (3f2a9c1d0b7e)", or "0.1.0" when the
// commit is not known.
inline std::string format_build(const std::string& version, const std::string& commit) {
  return version + (commit.empty() ? "" : " (" + commit + ")");
}

// This build: format_build of flexfarm_version() and flexfarm_commit().
inline std::string describe_version() { return format_build(flexfarm_version(), flexfarm_commit()); }

}  // namespace ff
