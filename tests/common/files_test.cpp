// Tests of common/files.hpp: whole-or-nothing writes, file names made from input names, the lock.
#include "common/files.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <csignal>

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

// A file size limit (RLIMIT_FSIZE, SIGXFSZ ignored): every write past it fails with EFBIG, as a full
// disk fails with ENOSPC. The error names the file and the reason, and no temporary is left beside it.
TEST(AtomicWrite, AFailedWriteNamesTheReasonAndLeavesNothing) {
  const fs::path d = fresh_dir("full");
  const std::string p = (d / "out.txt").string();
  ff::write_file_atomic(p, "old\n");
  rlimit before{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &before), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit small = before;
  small.rlim_cur = 4096;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string what;
  try {
    ff::write_file_atomic(p, std::string(1 << 16, 'x'));
  } catch (const std::runtime_error& e) {
    what = e.what();
  }
  ::setrlimit(RLIMIT_FSIZE, &before);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_EQ(what, p + ": write failed: File too large");
  EXPECT_EQ(ff::read_file(p), "old\n");  // the old file stays
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator{}), 1);  // and nothing beside it
  fs::remove_all(d);
}

// (#32.5) An output directory shared with others (/shared/runs): a link planted at the old fixed
// temporary name ("<path>.tmp") or at the target itself is never followed. The victim keeps its
// bytes, the target becomes a file of its own, and the planted link is left as it was.
TEST(AtomicWrite, ALinkPlantedAtTheTemporaryOrTheTargetIsNeverFollowed) {
  const fs::path d = fresh_dir("planted");
  const fs::path elsewhere = fresh_dir("planted_elsewhere");
  const std::string victim = (elsewhere / "victim.txt").string();
  ff::write_file_atomic(victim, "the victim's own bytes\n");
  const std::string p = (d / "report.html").string();
  fs::create_symlink(victim, p + ".tmp");
  ff::write_file_atomic(p, "the report\n");
  EXPECT_EQ(ff::read_file(victim), "the victim's own bytes\n");
  EXPECT_FALSE(fs::is_symlink(p));
  EXPECT_EQ(ff::read_file(p), "the report\n");
  EXPECT_EQ(fs::read_symlink(p + ".tmp").string(), victim);

  const std::string q = (d / "table.md").string();
  fs::create_symlink(victim, q);  // the target itself: replaced by the new file, not written through
  ff::write_file_atomic(q, "the table\n");
  EXPECT_EQ(ff::read_file(victim), "the victim's own bytes\n");
  EXPECT_FALSE(fs::is_symlink(q));
  EXPECT_EQ(ff::read_file(q), "the table\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator{}), 3);  // report.html, its planted link, table.md
  fs::remove_all(d);
  fs::remove_all(elsewhere);
}

// A writer that wants a name (SQLite, a video encoder) gets one in a private directory (mode 0700) beside
// the target, with the target's name or the extension it asks for; uncommitted, nothing is left.
TEST(AtomicFile, AWriterByNameGetsAPrivateTemporaryAndAnUncommittedOneLeavesNothing) {
  const fs::path d = fresh_dir("by_name");
  const std::string target = (d / "arm.mp4").string();
  {
    ff::AtomicFile tmp(target, ".avi");
    const fs::path t = tmp.path();
    EXPECT_EQ(t.filename(), "arm.avi");
    EXPECT_EQ(t.parent_path().parent_path(), d);
    EXPECT_EQ(t.parent_path().filename().string().rfind("arm.mp4.tmp-", 0), 0u) << t;
    EXPECT_EQ(fs::status(t.parent_path()).permissions() & fs::perms::all, fs::perms::owner_all);
    EXPECT_TRUE(fs::is_regular_file(t));
    EXPECT_GE(tmp.fd(), 0);
    tmp.write("frames");
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator{}), 0);
  {
    ff::AtomicFile tmp(target, ".avi");
    tmp.write("frames");
    tmp.close();
    tmp.commit();
  }
  EXPECT_EQ(ff::read_file(target), "frames");
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator{}), 1);
  fs::remove_all(d);
}

// Appends (a run's timings), locks and a run's own subdirectories (DIR/traces) refuse a planted link:
// nothing is appended to, created or written in the place it points at.
TEST(PlantedLinks, AppendsLocksAndOwnDirectoriesRefuseThem) {
  const fs::path d = fresh_dir("links");
  const fs::path elsewhere = fresh_dir("links_elsewhere");
  ff::write_file_atomic((elsewhere / "victim.csv").string(), "victim\n");
  fs::create_symlink(elsewhere / "victim.csv", d / "timings-main.csv");
  EXPECT_THROW(ff::open_append_nofollow((d / "timings-main.csv").string()), std::runtime_error);
  EXPECT_EQ(ff::read_file((elsewhere / "victim.csv").string()), "victim\n");
  fs::create_symlink(elsewhere / "created.lock", d / "journal-main.lock");
  EXPECT_THROW(ff::FileLock((d / "journal-main.lock").string(), "busy"), std::runtime_error);
  EXPECT_FALSE(fs::exists(elsewhere / "created.lock"));
  fs::create_symlink(elsewhere, d / "traces");
  try {
    ff::make_own_directory((d / "traces").string());
    ADD_FAILURE() << "a link was taken for the run's own directory";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((d / "traces").string() + ": not a directory of its own"), std::string::npos) << e.what();
  }
  ff::make_own_directory((d / "plots").string());  // made when missing, and again when there
  ff::make_own_directory((d / "plots").string());
  EXPECT_TRUE(fs::is_directory(d / "plots"));
  const int fd = ff::open_append_nofollow((d / "new.csv").string());  // a missing file is created
  EXPECT_GE(fd, 0);
  ::close(fd);
  EXPECT_TRUE(fs::is_regular_file(d / "new.csv"));
  fs::remove_all(d);
  fs::remove_all(elsewhere);
}

// (#32.4) An empty or blank path (an unset $OUT) is caught before it becomes "/journal-main.csv".
TEST(BlankPath, EmptyAndWhiteSpaceOnlyAreBlankAndAnythingElseIsNot) {
  for (const std::string& blank : {std::string(), std::string(" "), std::string("\t \n")}) EXPECT_TRUE(ff::is_blank_path(blank)) << blank;
  for (const std::string& path : {std::string("."), std::string("/"), std::string(" out "), std::string("a b")})
    EXPECT_FALSE(ff::is_blank_path(path)) << path;
  EXPECT_THROW(ff::AtomicFile(""), std::runtime_error);
}

}  // namespace
