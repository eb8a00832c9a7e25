// The command line's end-to-end fixture (tests/apps): each test runs the flexfarm binary in its own
// fresh working directory, `work`, inside `base`, with the given source files copied there first.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace ff::test {

namespace fs = std::filesystem;

inline const std::string kSource = FLEXFARM_SOURCE_DIR;
inline const std::string kBinary = FLEXFARM_BINARY;

inline std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

// Single-quoted for /bin/sh.
inline std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Whether `program` is on PATH.
inline bool on_path(const std::string& program) {
  return std::system(("command -v " + program + " > /dev/null 2>&1").c_str()) == 0;
}

// `mpirun -np RANKS ` for a shell command. As root in a container: OpenMPI refuses root unless told
// twice (--allow-run-as-root and the two OMPI_ALLOW_RUN_AS_ROOT* variables; harmless for other
// users). --oversubscribe: more ranks than cores (OpenMPI counts cores as slots and refuses -np
// above them). --mca btl self,vader: shared memory only, no probing of the container's network
// interfaces; the vader single-copy mechanism (CMA, process_vm_readv) needs ptrace rights containers
// often lack, so it is turned off. `timeout`: a rank stuck in a barrier must not hang the test suite.
inline std::string mpirun(int ranks) {
  return "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 timeout 300 mpirun -np " + std::to_string(ranks) +
         " --oversubscribe --allow-run-as-root --mca btl self,vader --mca btl_vader_single_copy_mechanism none ";
}

struct Result {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
  std::vector<std::string> lines() const { return split_lines(output); }
};

class CliFixture : public ::testing::Test {
 protected:
  // `inputs`: source-tree paths and where each goes under `work`; `prefix` names the directory.
  CliFixture(std::string prefix, std::vector<std::pair<std::string, std::string>> inputs)
      : prefix_(std::move(prefix)), inputs_(std::move(inputs)) {}

  fs::path base, work;

  void SetUp() override {
    base = fs::temp_directory_path() / (prefix_ + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(base);
    work = base / "work";
    fs::create_directories(work / "configs");
    for (const auto& [from, to] : inputs_) fs::copy_file(kSource + "/" + from, work / to);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(base, ec);
  }

  // Runs `flexfarm ARGS` (ARGS already quoted as needed) in `work`.
  Result run(const std::string& args) const { return run_shell(quote(kBinary) + " " + args); }

  // Runs a shell command line in `work`, e.g. flexfarm under mpirun.
  Result run_shell(const std::string& command) const {
    const fs::path log = base / "output.txt";
    const std::string cmd = "cd " + quote(work.string()) + " && " + command + " > " + quote(log.string()) + " 2>&1";
    const int status = std::system(cmd.c_str());
    Result r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.output = read_text(log);
    return r;
  }

  void write(const std::string& name, const std::string& text) const { std::ofstream(work / name) << text; }

  // A rejected command: non-zero exit, exactly one line "flexfarm: error: <prefix>...".
  static void expect_one_error_line(const Result& r, const std::string& prefix) {
    EXPECT_NE(r.exit_code, 0) << r.output;
    const auto lines = r.lines();
    ASSERT_EQ(lines.size(), 1u) << r.output;
    EXPECT_EQ(lines[0].rfind("flexfarm: error: " + prefix, 0), 0u) << r.output;
  }

  // Everything under `dir`, relative paths, sorted.
  static std::vector<std::string> tree(const fs::path& dir) {
    std::vector<std::string> out;
    for (const auto& e : fs::recursive_directory_iterator(dir)) out.push_back(fs::relative(e.path(), dir).string());
    std::sort(out.begin(), out.end());
    return out;
  }
  // No atomic write's temporary ("<name>.tmp-XXXXXX", common/files.hpp) left behind.
  static void expect_no_tmp_files(const fs::path& dir) {
    for (const auto& e : fs::recursive_directory_iterator(dir))
      EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << "left behind: " << e.path();
  }
  static void expect_png(const fs::path& p) {
    ASSERT_TRUE(fs::exists(p)) << p;
    const std::string bytes = read_text(p);
    ASSERT_GT(bytes.size(), 8u) << p;
    EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << p;
  }

 private:
  std::string prefix_;
  std::vector<std::pair<std::string, std::string>> inputs_;
};

}  // namespace ff::test
