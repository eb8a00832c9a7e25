// Tests of common/files.hpp: whole-or-nothing writes, file names made from input names, the lock.
#include "common/files.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("ff_files_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// A name from a hostile input cannot climb out of its directory or name an absolute path.
TEST(FileStem, NamesFromInputsStayInTheirDirectory) {
  EXPECT_EQ(ff::make_file_stem("../../etc/passwd"), "______etc_passwd");
  EXPECT_EQ(ff::make_file_stem("/tmp/x"), "_tmp_x");
  EXPECT_EQ(ff::make_file_stem("trajectory.moves[0].target"), "trajectory_moves_0__target");
  EXPECT_EQ(ff::make_file_stem("hub_torque-2"), "hub_torque-2");
  for (const std::string& hostile : std::vector<std::string>{"..", "a/../../b", "C:\\x", std::string("nul\0byte", 8), "\xe2\x80\xa6"})
    EXPECT_EQ(ff::make_file_stem(hostile).find_first_of("/.\\:"), std::string::npos) << hostile;
}

TEST(AtomicWrite, ReplacesTheFileWholeAndLeavesNoTemporary) {
  const fs::path d = fresh_dir("atomic");
  const std::string p = (d / "a.txt").string();
  ff::write_file_atomic(p, "first\n");
  ff::write_file_atomic(p, "second\n");
  std::stringstream s;
  s << std::ifstream(p).rdbuf();
  EXPECT_EQ(s.str(), "second\n");
  EXPECT_FALSE(fs::exists(p + ".tmp"));
  fs::remove_all(d);
}

// /dev/full: every write fails with ENOSPC, as on a full disk. The error names the file and the
// reason, and no temporary is left beside it.
TEST(AtomicWrite, AFailedWriteNamesTheReasonAndLeavesNothing) {
  const fs::path d = fresh_dir("full");
  const std::string p = (d / "out.txt").string();
  fs::create_symlink("/dev/full", p + ".tmp");  // the temporary the write goes to
  try {
    ff::write_file_atomic(p, std::string(1 << 16, 'x'));
    ADD_FAILURE() << "a write to /dev/full succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(p + ": write failed: No space left on device"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(p));
  EXPECT_FALSE(fs::is_symlink(p + ".tmp"));
  fs::remove_all(d);
}

}  // namespace
