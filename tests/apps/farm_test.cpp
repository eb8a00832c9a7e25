// End-to-end tests of the farm: `flexfarm run` and `flexfarm merge` on a small Monte Carlo study
// (tests/data/studies/mc_small.yaml). The result table must be byte-identical whatever the thread
// count, lane width, MPI rank count or Slurm sharding, and after a `kill -9` and `--resume`; a
// diverging variant is recorded and reported by the exit code; bad input writes nothing.
//
// Every comparison hashes the files (64-bit FNV-1a, printed with the size in failure messages):
// results.csv always, and the dump of results.sqlite when the sqlite3 shell is on PATH.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/apps/cli_fixture.hpp"  // on_path, mpirun

namespace {

using ff::test::mpirun;
using ff::test::on_path;

namespace fs = std::filesystem;

const std::string kSource = FLEXFARM_SOURCE_DIR;
const std::string kBinary = FLEXFARM_BINARY;
const std::string kStudy = kSource + "/tests/data/studies/mc_small.yaml";
const std::string kModel = kSource + "/configs/fbtb.yaml";

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

// One CSV line into cells ("..." may hold commas).
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"') quoted = !quoted;
    else if (c == ',' && !quoted) cells.emplace_back();
    else cells.back() += c;
  }
  return cells;
}

// Single-quoted for /bin/sh.
std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : s) h = (h ^ c) * 0x100000001b3ull;
  return h;
}

// "1234 bytes, fnv1a 0123456789abcdef" (or "missing").
std::string fingerprint(const std::string& bytes) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%zu bytes, fnv1a %016llx", bytes.size(), static_cast<unsigned long long>(fnv1a(bytes)));
  return buf;
}
std::string fingerprint(const fs::path& p) { return fs::exists(p) ? fingerprint(read_text(p)) : std::string("missing"); }

// The first line where two texts differ, for failure messages.
std::string first_difference(const std::string& a, const std::string& b) {
  const auto la = split_lines(a), lb = split_lines(b);
  for (std::size_t i = 0; i < std::max(la.size(), lb.size()); ++i) {
    const std::string x = i < la.size() ? la[i] : "<none>", y = i < lb.size() ? lb[i] : "<none>";
    if (x != y) return "first difference at line " + std::to_string(i + 1) + ":\n  expected: " + x + "\n  actual:   " + y;
  }
  return "same lines, different bytes";
}

// Number of variants of mc_small.yaml (its `samples:`), so the tests follow the study file.
int study_size() {
  std::smatch m;
  const std::string text = read_text(kStudy);
  const std::regex re("samples:\\s*([0-9]+)");
  return std::regex_search(text, m, re) ? std::stoi(m[1]) : -1;
}

// The complete rows of a journal (DIR/journal-TAG.csv: two header lines, then one row per variant);
// a last line without its newline is a torn write and does not count.
struct Journal {
  std::string complete;  // the text up to its last newline
  std::vector<int> ids;  // eval_id of each complete row, in file order
};
Journal read_journal(const fs::path& p) {
  Journal j;
  const std::string text = read_text(p);
  const auto end = text.rfind('\n');
  if (end == std::string::npos) return j;
  j.complete = text.substr(0, end + 1);
  const auto lines = split_lines(j.complete);
  for (std::size_t i = 2; i < lines.size(); ++i) j.ids.push_back(std::stoi(lines[i].substr(0, lines[i].find(','))));
  return j;
}

// The pid of a process whose environment holds `entry` (e.g. OMPI_COMM_WORLD_RANK=1) and whose
// working directory is `cwd`; -1 if none.
pid_t find_process(const std::string& entry, const fs::path& cwd) {
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::error_code ec;
    if (fs::read_symlink(e.path() / "cwd", ec) != cwd) continue;
    std::string env = read_text(e.path() / "environ");
    std::replace(env.begin(), env.end(), '\0', '\n');
    if (("\n" + env).find("\n" + entry + "\n") != std::string::npos) return std::stoi(name);
  }
  return -1;
}

// Sum of the `variants` column of a timings file's rows (first_eval_id,variants,seconds).
int timed_variants(const std::string& rows) {
  int n = 0;
  for (const auto& l : split_lines(rows)) {
    const auto cells = split_csv(l);
    if (cells.size() == 3 && cells[0] != "first_eval_id") n += std::stoi(cells[1]);
  }
  return n;
}

// `flexfarm run STUDY --out OUT ARGS` (by default mc_small.yaml, --threads 1) in the background,
// started directly (no shell in between) so that the pid is flexfarm's own; its output goes to `log`.
// -1 when fork fails.
pid_t start_run(const fs::path& out, const std::string& log, const std::string& study = kStudy,
                const std::vector<std::string>& args = {"--threads", "1"}) {
  std::vector<std::string> argv = {kBinary, "run", study, "--out", out.string()};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> cargv;
  for (const auto& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
  cargv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::close(fd);
    }
    ::execv(cargv[0], cargv.data());
    ::_exit(127);
  }
  return pid;
}

// Waits (at most two minutes) until `journal` holds `wanted` rows; true when the process ended first
// (its wait status in *status). *seen: the rows last counted.
bool wait_for_rows(pid_t pid, const fs::path& journal, int wanted, int* status, std::size_t* seen) {
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(120)) {
    if (::waitpid(pid, status, WNOHANG) == pid) return true;
    *seen = read_journal(journal).ids.size();
    if (static_cast<int>(*seen) >= wanted) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

struct Result {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
  double seconds = 0;
  std::vector<std::string> lines() const { return split_lines(output); }
};

// Runs a shell command in `dir`, its output captured in `log`.
Result shell(const fs::path& dir, const std::string& command, const fs::path& log) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string cmd = "cd " + quote(dir.string()) + " && " + command + " > " + quote(log.string()) + " 2>&1";
  const int status = std::system(cmd.c_str());
  Result r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.output = read_text(log);
  return r;
}

// A finished run's tables: results.csv and the dump of results.sqlite ("" without the sqlite3 shell).
struct Tables {
  std::string csv, sqlite;
};
Tables read_tables(const fs::path& out) {
  Tables t;
  t.csv = read_text(out / "results.csv");
  if (on_path("sqlite3") && fs::exists(out / "results.sqlite")) {
    const fs::path dump = out.parent_path() / (out.filename().string() + ".sqlite-dump.txt");
    shell(out, "sqlite3 -readonly results.sqlite .dump", dump);
    t.sqlite = read_text(dump);
    fs::remove(dump);
  }
  return t;
}

// The uninterrupted single-process run every other run must match: `run --threads 1` (default
// lanes), computed once per test program; its tables are kept in memory.
struct Reference {
  Result run;
  Tables tables;
};
fs::path reference_dir() { return fs::temp_directory_path() / ("ff_farm_" + std::to_string(::getpid()) + "_reference"); }
const Reference& reference() {
  static const Reference ref = [] {
    Reference r;
    const fs::path dir = reference_dir();
    fs::remove_all(dir);
    fs::create_directories(dir);
    r.run = shell(dir, quote(kBinary) + " run " + quote(kStudy) + " --out out --threads 1", dir / "output.txt");
    r.tables = read_tables(dir / "out");
    std::error_code ec;
    fs::remove_all(dir, ec);  // kept in memory
    return r;
  }();
  return ref;
}

class Farm : public ::testing::Test {
 protected:
  fs::path dir;  // fresh per test; commands run here
  int commands = 0;

  void SetUp() override {
    dir = fs::temp_directory_path() / ("ff_farm_" + std::to_string(::getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override {
    if (HasFailure()) {
      std::printf("kept for inspection: %s\n", dir.c_str());
      return;
    }
    std::error_code ec;
    fs::remove_all(dir, ec);
  }

  // `flexfarm ARGS` (ARGS quoted as needed) in `dir`.
  Result flexfarm(const std::string& args) {
    return shell(dir, quote(kBinary) + " " + args, dir / ("log-" + std::to_string(++commands) + ".txt"));
  }
  // `flexfarm run mc_small.yaml --out OUT ARGS`.
  Result run_study(const std::string& out, const std::string& args = "") {
    return flexfarm("run " + quote(kStudy) + " --out " + out + " " + args);
  }

  // The reference run, which must have succeeded.
  static const Reference& ref() {
    const Reference& r = reference();
    EXPECT_EQ(r.run.exit_code, 0) << "reference run failed:\n" << r.run.output;
    EXPECT_FALSE(r.tables.csv.empty()) << "reference run wrote no results.csv:\n" << r.run.output;
    if (on_path("sqlite3")) {
      EXPECT_FALSE(r.tables.sqlite.empty()) << "no dump of the reference results.sqlite";
    }
    return r;
  }

  // OUT's results.csv (and sqlite dump) byte-identical to the reference run's.
  void expect_reference_tables(const std::string& out, const std::string& what) {
    const Reference& r = ref();
    const Tables t = read_tables(dir / out);
    EXPECT_EQ(fingerprint(t.csv), fingerprint(r.tables.csv))
        << what << ": results.csv differs from the uninterrupted --threads 1 run; " << first_difference(r.tables.csv, t.csv);
    EXPECT_EQ(fingerprint(t.sqlite), fingerprint(r.tables.sqlite))
        << what << ": results.sqlite dump differs; " << first_difference(r.tables.sqlite, t.sqlite);
  }

  // A study of many cheap variants in `dir` (two segments, a 0.3 s move), so that its time is the
  // farm's rather than the kernel's.
  void write_cheap_study(const std::string& name, int samples) const {
    write_text(dir / name, "name: many\n"
                           "model: " + kModel + "\n"
                           "set:\n"
                           "  segments: 2\n"
                           "  trajectory.moves: [{target: 0.5, hold: 0.3}]\n"
                           "variables:\n"
                           "  - path: payload.mass\n"
                           "    distribution: {type: normal, mean: 328.7, std: 40}\n"
                           "  - path: joints.stiffness\n"
                           "    distribution: {type: normal, mean: 39.5e3, std: 2.0e3}\n"
                           "design: {type: monte_carlo, samples: " + std::to_string(samples) + "}\n");
  }

  // A small study in `dir` (absolute model path): `samples` Monte Carlo variants of the payload mass.
  void write_small_study(const std::string& name, int seed = 3, int samples = 24,
                         const std::string& model = kModel) const {
    write_text(dir / name, "name: small\n"
                           "seed: " + std::to_string(seed) + "\n"
                           "model: " + model + "\n"
                           "set:\n"
                           "  trajectory.moves: [{target: 0.5, hold: 8.0}]\n"
                           "  simulation.integrator: sdirk2\n"
                           "variables:\n"
                           "  - path: payload.mass\n"
                           "    distribution: {type: normal, mean: 328.7, std: 40}\n"
                           "design: {type: monte_carlo, samples: " + std::to_string(samples) + "}\n");
  }
};

// ---- determinism -------------------------------------------------------------------------

TEST_F(Farm, ThreadCountAndLaneWidthDoNotChangeResults) {
  const int n = study_size();
  ASSERT_GT(n, 100) << kStudy << ": no `samples:` found";
  const Reference& r = ref();
  ASSERT_EQ(static_cast<int>(split_lines(r.tables.csv).size()), n + 1) << r.run.output;
  // Both outcomes occur, so every comparison covers rows with and without settling times.
  EXPECT_NE(r.tables.csv.find(",ok,"), std::string::npos);
  EXPECT_NE(r.tables.csv.find(",not_settled,"), std::string::npos);
  std::printf("reference (--threads 1, %d variants): %.1f s\n", n, r.run.seconds);
  for (const std::string args : {"--threads 1 --lanes 1", "--threads 2 --lanes 8", "--threads 2 --lanes 3"}) {
    const std::string out = "out" + std::to_string(commands);
    const auto res = run_study(out, args);
    ASSERT_EQ(res.exit_code, 0) << args << ":\n" << res.output;
    expect_reference_tables(out, args);
    std::printf("%s: %.1f s\n", args.c_str(), res.seconds);
  }
}

// ---- journal and resume ------------------------------------------------------------------

TEST_F(Farm, ResumeAfterKill9IsByteIdentical) {
  const int n = study_size();
  ref();
  const fs::path out = dir / "out";
  const fs::path journal = out / "journal-main.csv";

  // Run B in the background; once a third of the variants are journalled, kill -9 it mid-run.
  const std::string log = (dir / "killed.txt").string();
  const pid_t pid = start_run(out, log);
  ASSERT_GE(pid, 0) << "fork failed";
  const int wanted = n / 3;
  const auto t0 = std::chrono::steady_clock::now();
  int status = 0;
  std::size_t seen = 0;
  const bool exited = wait_for_rows(pid, journal, wanted, &status, &seen);
  if (!exited) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
  }
  ASSERT_FALSE(exited) << "the run ended (status " << status << ") before it could be killed; journal rows seen: " << seen
                       << "; make mc_small.yaml bigger\n"
                       << read_text(log);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "status " << status;
  const double killed_after = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  EXPECT_FALSE(fs::exists(out / "results.csv")) << "a killed run must not leave a result table";
  const Journal before = read_journal(journal);
  const int done = static_cast<int>(before.ids.size());
  ASSERT_GE(done, wanted);
  ASSERT_LT(done, n) << "the run had finished every variant before the kill";
  const std::string timings_before = read_text(out / "timings-main.csv");

  // Resume with other threads and lanes: only the missing variants are computed.
  const auto r = run_study("out", "--resume --threads 2 --lanes 5");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_reference_tables("out", "killed and resumed");
  for (const auto& e : fs::recursive_directory_iterator(out)) {
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << "left behind: " << e.path();
  }

  const Journal after = read_journal(journal);
  EXPECT_EQ(after.complete.rfind(before.complete, 0), 0u) << "the rows journalled before the kill must be kept as they were";
  EXPECT_EQ(static_cast<int>(after.ids.size()), n) << "journal rows after resume (before: " << done << ")";
  const std::set<int> unique(after.ids.begin(), after.ids.end());
  EXPECT_EQ(unique.size(), after.ids.size()) << "a variant was computed twice";
  EXPECT_EQ(unique.size(), static_cast<std::size_t>(n));
  if (!unique.empty()) {
    EXPECT_EQ(*unique.begin(), 0);
    EXPECT_EQ(*unique.rbegin(), n - 1);
  }
  // The resumed run's own timing rows account for exactly the missing variants (when the killed
  // run's timings file ended on a whole line, the usual case: its rows are flushed one by one).
  const std::string timings_after = read_text(out / "timings-main.csv");
  ASSERT_EQ(timings_after.rfind(timings_before, 0), 0u);
  if (timings_before.empty() || timings_before.back() == '\n') {
    EXPECT_EQ(timed_variants(timings_after.substr(timings_before.size())), n - done)
        << "the resumed run computed other than the " << n - done << " missing variants";
  }
  std::printf("killed after %.2f s with %d of %d variants journalled; resume: %.1f s\n", killed_after, done, n, r.seconds);
}


// kill -9 at random moments of one study, resumed after each: in the end no variant is lost or
// computed twice and results.csv is byte-identical to an uninterrupted run. In ctest: 3 kills of a
// 300-variant study; the figure in docs/validation.md: FLEXFARM_KILLS=20 FLEXFARM_KILL_VARIANTS=10000.
TEST_F(Farm, KilledAtRandomMomentsAndResumedLosesAndRepeatsNothing) {
  const auto env = [](const char* name, int fallback) { return std::getenv(name) ? std::atoi(std::getenv(name)) : fallback; };
  const int kills = env("FLEXFARM_KILLS", 3), n = env("FLEXFARM_KILL_VARIANTS", 300);
  write_cheap_study("many.yaml", n);
  const std::string study = (dir / "many.yaml").string();
  const auto ref = flexfarm("run many.yaml --out ref --threads 2");
  ASSERT_EQ(ref.exit_code, 0) << ref.output;
  const std::string uninterrupted = read_text(dir / "ref" / "results.csv");

  // Each attempt is killed after a random share of the time the work it has left would take (the
  // time of a run with nothing left to compute, plus the uninterrupted run's time per variant), so
  // that kills land while the study loads, while batches run, and while rows and results are
  // written, until the last.
  const double idle = flexfarm("run many.yaml --out ref --threads 2 --resume").seconds;
  std::mt19937_64 rng(20261202);
  std::uniform_real_distribution<double> share(0.1, 0.9);
  const fs::path out = dir / "out";
  int mid_run = 0;
  std::string rows_at_kill;  // journal rows after each attempt
  for (int k = 0; k < kills; ++k) {
    const std::string log = (dir / ("attempt-" + std::to_string(k) + ".txt")).string();
    std::vector<std::string> args = {"--threads", "2"};
    if (k > 0) args.push_back("--resume");
    const pid_t pid = start_run(out, log, study, args);
    ASSERT_GE(pid, 0) << "fork failed";
    const int left = n - static_cast<int>(read_journal(out / "journal-main.csv").ids.size());
    std::this_thread::sleep_for(std::chrono::duration<double>(share(rng) * (idle + ref.seconds * left / n)));
    int status = 0;
    const bool ended = ::waitpid(pid, &status, WNOHANG) == pid;
    if (!ended) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      ++mid_run;
    } else {
      ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "attempt " << k << ": status " << status << "\n" << read_text(log);
    }
    rows_at_kill += (k ? " " : "") + std::to_string(read_journal(out / "journal-main.csv").ids.size());
  }
  const auto last = flexfarm("run many.yaml --out out --resume --threads 2");
  ASSERT_EQ(last.exit_code, 0) << last.output;
  const std::string resumed = read_text(out / "results.csv");
  EXPECT_EQ(fingerprint(resumed), fingerprint(uninterrupted)) << first_difference(uninterrupted, resumed);
  const Journal journal = read_journal(out / "journal-main.csv");
  const std::set<int> unique(journal.ids.begin(), journal.ids.end());
  EXPECT_EQ(unique.size(), journal.ids.size()) << "a variant was journalled twice";
  EXPECT_EQ(static_cast<int>(unique.size()), n) << "a variant was lost";
  EXPECT_GE(mid_run, (kills + 1) / 2) << "most kills must land mid-run for the test to mean anything";
  std::printf("%d variants, uninterrupted %.1f s; %d kills (%d mid-run; rows journalled after each: %s), the final resume %.1f s: "
              "%zu lost, %zu duplicated, results.csv %s\n",
              n, ref.seconds, kills, mid_run, rows_at_kill.c_str(), last.seconds, n - unique.size(), journal.ids.size() - unique.size(),
              resumed == uninterrupted ? "byte-identical" : "DIFFERENT");
}

// The disk fills mid-run (a 48 KiB tmpfs as --out): one clear error naming the journal and the
// system's reason, the journal whole up to its last row, nothing half-written; once space is freed
// (the tmpfs grown), --resume completes and results.csv is byte-identical to an uninterrupted run.
TEST_F(Farm, DiskFullMidRunKeepsTheJournalWholeAndResumeCompletes) {
  const int n = 300;
  write_small_study("small.yaml", 3, n);
  const auto ref = flexfarm("run small.yaml --out ref --threads 2");
  ASSERT_EQ(ref.exit_code, 0) << ref.output;
  const fs::path disk = dir / "disk";
  fs::create_directories(disk);
  if (std::system(("mount -t tmpfs -o size=48k tmpfs " + quote(disk.string()) + " 2>/dev/null").c_str()) != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here (needs root): the full-disk test did not run";
  struct Unmount {
    std::string path;
    ~Unmount() { std::system(("umount " + path).c_str()); }
  } unmount{quote(disk.string())};

  const auto full = flexfarm("run small.yaml --out disk/out --threads 2");
  EXPECT_NE(full.exit_code, 0) << full.output;
  EXPECT_NE(full.output.find("journal-main.csv: cannot write the journal: No space left on device"), std::string::npos)
      << full.output;
  const fs::path journal = disk / "out" / "journal-main.csv";
  const std::string text = read_text(journal);
  const Journal whole = read_journal(journal);
  EXPECT_EQ(whole.complete, text) << "the journal must end on a whole row";
  EXPECT_GT(whole.ids.size(), 0u);
  EXPECT_LT(static_cast<int>(whole.ids.size()), n) << "the disk must fill before the study ends for the test to mean anything";
  EXPECT_FALSE(fs::exists(disk / "out" / "results.csv"));
  for (const auto& e : fs::directory_iterator(disk / "out")) EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();

  ASSERT_EQ(std::system(("mount -o remount,size=32m " + quote(disk.string())).c_str()), 0);
  const auto resumed = flexfarm("run small.yaml --out disk/out --threads 2 --resume");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const std::string a = read_text(dir / "ref" / "results.csv"), b = read_text(disk / "out" / "results.csv");
  EXPECT_EQ(fingerprint(b), fingerprint(a)) << first_difference(a, b);
  std::printf("disk full after %zu of %d rows; resumed to all %d, results.csv %s\n", whole.ids.size(), n, n,
              a == b ? "byte-identical" : "DIFFERENT");
}

// One MPI rank killed mid-run: the run stops with a message naming the rank; --resume with another
// rank count completes it, and results.csv is byte-identical to a single process's.
TEST_F(Farm, MpiRankKilledMidRunStopsNamingItAndResumeWithOtherRanksCompletes) {
  if (!on_path("mpirun")) GTEST_SKIP() << "mpirun is not on PATH: install OpenMPI (Debian openmpi-bin; CI has it)";
  const int n = 600;
  write_cheap_study("many.yaml", n);
  const auto ref = flexfarm("run many.yaml --out ref --threads 2");
  ASSERT_EQ(ref.exit_code, 0) << ref.output;
  const std::string log = (dir / "mpirun.txt").string();
  const pid_t launcher = ::fork();
  if (launcher == 0) {
    const std::string cmd = "cd " + quote(dir.string()) + " && exec env " + mpirun(2) + quote(kBinary) +
                            " run many.yaml --out out --threads 1 > " + quote(log) + " 2>&1";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ASSERT_GE(launcher, 0) << "fork failed";
  int status = 0;
  std::size_t seen = 0;
  const fs::path journal1 = dir / "out" / "journal-rank-1-of-2.csv";
  ASSERT_FALSE(wait_for_rows(launcher, journal1, 20, &status, &seen)) << "mpirun ended first:\n" << read_text(log);
  const pid_t rank1 = find_process("OMPI_COMM_WORLD_RANK=1", dir);
  ASSERT_GT(rank1, 0) << "rank 1 not found among the processes";
  ::kill(rank1, SIGKILL);
  ::waitpid(launcher, &status, 0);
  const std::string said = read_text(log);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) != 0) << "status " << status << "\n" << said;
  EXPECT_NE(said.find("rank 1"), std::string::npos) << said;
  EXPECT_FALSE(fs::exists(dir / "out" / "results.csv"));
  const int before = static_cast<int>(read_journal(journal1).ids.size() +
                                      read_journal(dir / "out" / "journal-rank-0-of-2.csv").ids.size());
  ASSERT_LT(before, n) << "the kill came after the study had ended";

  const auto resumed = shell(dir, mpirun(3) + quote(kBinary) + " run many.yaml --out out --threads 1 --resume", dir / "resume.txt");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const std::string a = read_text(dir / "ref" / "results.csv"), b = read_text(dir / "out" / "results.csv");
  EXPECT_EQ(fingerprint(b), fingerprint(a)) << first_difference(a, b);
  std::printf("rank 1 of 2 killed with %d of %d rows journalled; mpirun said: %s; resumed on 3 ranks: results.csv %s\n", before, n,
              said.substr(said.find("rank 1") == std::string::npos ? 0 : said.rfind('\n', said.find("rank 1")) + 1, 160).c_str(),
              a == b ? "byte-identical" : "DIFFERENT");
}

TEST_F(Farm, TornJournalIsRepairedOnResumeAndTheUserIsTold) {
  const int n = 24;
  write_small_study("small.yaml", 3, n);
  ASSERT_EQ(flexfarm("run small.yaml --out out").exit_code, 0);
  const std::string uninterrupted = read_text(dir / "out" / "results.csv");
  const fs::path journal = dir / "out" / "journal-main.csv";
  // The last row cut mid-write and garbage after it: the half row, a line of the wrong shape, a line
  // of the right shape without an eval_id, each ended by a newline, and a torn last line.
  std::string text = read_journal(journal).complete;
  text.pop_back();
  const std::size_t last = text.rfind('\n') + 1;
  const int torn_id = std::stoi(text.substr(last, text.find(',', last) - last));
  const std::string commas(std::count(text.begin() + last, text.end(), ','), ',');
  text = text.substr(0, last + (text.size() - last) / 2) + "\ngarbage,not a row\n" + commas + "\n12,3";
  write_text(journal, text);
  fs::remove(dir / "out" / "results.csv");
  const auto r = flexfarm("run small.yaml --out out --resume");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("repaired: a torn last line (4 bytes) cut, 3 line(s) that are not result rows dropped"),
            std::string::npos)
      << r.output;
  const std::string repaired = read_text(dir / "out" / "results.csv");
  EXPECT_EQ(fingerprint(repaired), fingerprint(uninterrupted)) << first_difference(uninterrupted, repaired);
  const Journal after = read_journal(journal);
  const std::set<int> unique(after.ids.begin(), after.ids.end());
  EXPECT_EQ(unique.size(), after.ids.size()) << "a variant was journalled twice";
  EXPECT_EQ(static_cast<int>(unique.size()), n);
  EXPECT_EQ(after.ids.back(), torn_id) << "the torn row is computed again, last";
}

TEST_F(Farm, SecondRunOnTheSameOutRefusesAtOnceAndTheFirstFinishes) {
  const int n = study_size();
  const fs::path out = dir / "out";
  const std::string log = (dir / "first.txt").string();
  const pid_t pid = start_run(out, log);
  ASSERT_GE(pid, 0) << "fork failed";
  int status = 0;
  std::size_t seen = 0;
  ASSERT_FALSE(wait_for_rows(pid, out / "journal-main.csv", 1, &status, &seen))
      << "the first run ended before the second could start; make mc_small.yaml bigger\n" << read_text(log);
  // The second run, with and without --resume: refused at once, naming the directory; nothing written.
  const std::string before = read_journal(out / "journal-main.csv").complete;
  for (const std::string args : {"--resume", ""}) {
    const auto second = run_study("out", args);
    EXPECT_NE(second.exit_code, 0) << second.output;
    EXPECT_NE(second.output.find("another flexfarm run is writing it"), std::string::npos) << second.output;
    EXPECT_LT(second.seconds, 5.0) << "the second run must refuse at once, not wait";
  }
  EXPECT_EQ(read_journal(out / "journal-main.csv").complete.rfind(before, 0), 0u) << "the second run touched the journal";
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status << "\n" << read_text(log);
  const Journal journal = read_journal(out / "journal-main.csv");
  EXPECT_EQ(std::set<int>(journal.ids.begin(), journal.ids.end()).size(), static_cast<std::size_t>(n));
  EXPECT_EQ(journal.ids.size(), static_cast<std::size_t>(n)) << "a variant journalled twice";
  const std::string first = read_text(out / "results.csv");
  EXPECT_EQ(static_cast<int>(split_lines(first).size()), n + 1);
  // Once the first has ended, a --resume on the same directory runs, finds nothing to compute, and
  // writes the same table.
  const auto after = run_study("out", "--resume");
  EXPECT_EQ(after.exit_code, 0) << after.output;
  EXPECT_EQ(fingerprint(read_text(out / "results.csv")), fingerprint(first));
}
TEST_F(Farm, RunWithoutResumeRefusesAnExistingJournal) {
  write_small_study("study.yaml");
  auto r = flexfarm("run study.yaml --out out");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string journal = read_text(dir / "out" / "journal-main.csv");
  const std::string results = read_text(dir / "out" / "results.csv");
  ASSERT_FALSE(journal.empty());

  r = flexfarm("run study.yaml --out out");
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("--resume"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("flexfarm: error: "), std::string::npos) << r.output;
  EXPECT_EQ(fingerprint(dir / "out" / "journal-main.csv"), fingerprint(journal)) << "the journal was touched";
  EXPECT_EQ(fingerprint(dir / "out" / "results.csv"), fingerprint(results)) << "the results were touched";
}

TEST_F(Farm, StudyOfAnotherModelRefusesTheJournal) {
  fs::copy_file(kModel, dir / "model.yaml");
  const std::string model = read_text(dir / "model.yaml");
  write_small_study("study.yaml", 3, 24, "model.yaml");
  const std::string study = read_text(dir / "study.yaml");
  auto r = flexfarm("run study.yaml --out out");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string journal = read_text(dir / "out" / "journal-main.csv");
  const std::string timings = read_text(dir / "out" / "timings-main.csv");
  const std::string results = read_text(dir / "out" / "results.csv");

  const auto refused = [&](const std::string& what) {
    const auto res = flexfarm("run study.yaml --out out --resume");
    EXPECT_NE(res.exit_code, 0) << what << ":\n" << res.output;
    EXPECT_NE(res.output.find("flexfarm: error: "), std::string::npos) << what << ":\n" << res.output;
    EXPECT_NE(res.output.find("another study"), std::string::npos) << what << ":\n" << res.output;
    EXPECT_EQ(fingerprint(dir / "out" / "journal-main.csv"), fingerprint(journal)) << what << ": the journal was touched";
    EXPECT_EQ(fingerprint(dir / "out" / "results.csv"), fingerprint(results)) << what << ": the results were touched";
  };
  write_small_study("study.yaml", 4, 24, "model.yaml");  // another seed
  refused("study with another seed");
  write_text(dir / "study.yaml", study);
  write_text(dir / "model.yaml", std::regex_replace(model, std::regex("inertia: 118.6"), "inertia: 120.0"));
  refused("study whose model changed");

  // Both files as they were: the journal is accepted again, and there is nothing left to compute.
  write_text(dir / "model.yaml", model);
  r = flexfarm("run study.yaml --out out --resume");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(fingerprint(dir / "out" / "results.csv"), fingerprint(results));
  EXPECT_EQ(fingerprint(dir / "out" / "journal-main.csv"), fingerprint(journal));
  EXPECT_EQ(timed_variants(read_text(dir / "out" / "timings-main.csv")), timed_variants(timings))
      << "a resume of a finished run computed variants again";
}

// ---- Slurm shards and MPI ranks ----------------------------------------------------------

TEST_F(Farm, ShardsMergeToTheSameTable) {
  const int n = study_size();
  ref();
  const fs::path out = dir / "out";
  std::string merge_fail;
  for (int i = 0; i < 3; ++i) {
    if (i == 2) {
      // Two shards of three done: merge names what is missing and writes nothing.
      const auto m = flexfarm("merge " + quote(kStudy) + " --out out");
      EXPECT_NE(m.exit_code, 0) << m.output;
      const int missing = (n - 2 + 2) / 3;  // eval_id % 3 == 2
      EXPECT_NE(m.output.find(std::to_string(missing) + " of " + std::to_string(n) + " variants"), std::string::npos)
          << "expected '" << missing << " of " << n << " variants' in:\n" << m.output;
      EXPECT_FALSE(fs::exists(out / "results.csv"));
      EXPECT_FALSE(fs::exists(out / "results.sqlite"));
    }
    const std::string shard = std::to_string(i) + "/3";
    const auto r = run_study("out", "--shard " + shard);
    ASSERT_EQ(r.exit_code, 0) << shard << ":\n" << r.output;
    EXPECT_FALSE(fs::exists(out / "results.csv")) << "shard " << shard << " wrote the result table";
    const Journal j = read_journal(out / ("journal-shard-" + std::to_string(i) + "-of-3.csv"));
    EXPECT_EQ(static_cast<int>(j.ids.size()), (n - i + 2) / 3) << shard;
    for (int id : j.ids) {
      EXPECT_EQ(id % 3, i) << "shard " << shard << " computed eval_id " << id;
    }
    std::printf("shard %s: %.1f s\n", shard.c_str(), r.seconds);
  }
  EXPECT_FALSE(fs::exists(out / "journal-main.csv"));
  const auto m = flexfarm("merge " + quote(kStudy) + " --out out");
  ASSERT_EQ(m.exit_code, 0) << m.output;
  expect_reference_tables("out", "three shards merged");
}

TEST_F(Farm, BadShardsAreRejected) {
  write_small_study("study.yaml");
  for (const std::string shard : {"3/3", "x", "1/0", "-1/3", "1/3/3", "/3", "1/"}) {
    const auto r = flexfarm("run study.yaml --out out --shard " + quote(shard));
    EXPECT_NE(r.exit_code, 0) << "--shard '" << shard << "':\n" << r.output;
    EXPECT_NE(r.output.find("--shard"), std::string::npos) << "--shard '" << shard << "':\n" << r.output;
    EXPECT_FALSE(fs::exists(dir / "out")) << "--shard '" << shard << "' created --out";
    fs::remove_all(dir / "out");
  }
}

// An empty --shard (e.g. `--shard "$TASK"` with TASK unset in a Slurm script) is a bad shard too: taken
// as "no --shard", every array task would run the whole study into the same journal.
TEST_F(Farm, EmptyShardIsRejected) {
  write_small_study("study.yaml");
  const auto r = flexfarm("run study.yaml --out out --shard ''");
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("--shard"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out")) << "--shard '' created --out";
}

TEST_F(Farm, MpiTwoRanksMatchOneProcess) {
  if (!on_path("mpirun"))
    GTEST_SKIP() << "mpirun is not on PATH: install OpenMPI (Debian openmpi-bin, as scripts/bootstrap does; CI has it)";
  ref();
  const auto r = shell(dir, mpirun(2) + quote(kBinary) + " run " + quote(kStudy) + " --out out --threads 1", dir / "mpirun.txt");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const int n = study_size();
  for (int rank = 0; rank < 2; ++rank) {
    const fs::path p = dir / "out" / ("journal-rank-" + std::to_string(rank) + "-of-2.csv");
    ASSERT_TRUE(fs::exists(p)) << p << " missing (is flexfarm built with MPI: FLEXFARM_MPI=ON, libopenmpi-dev found?)\n"
                               << r.output;
    const Journal j = read_journal(p);
    EXPECT_EQ(static_cast<int>(j.ids.size()), (n - rank + 1) / 2) << p;
    for (int id : j.ids) {
      EXPECT_EQ(id % 2, rank) << "rank " << rank << " computed eval_id " << id;
    }
  }
  EXPECT_FALSE(fs::exists(dir / "out" / "journal-main.csv")) << "a rank ran the whole study as a single process";
  expect_reference_tables("out", "mpirun -np 2");
  std::printf("mpirun -np 2: %.1f s\n", r.seconds);
}

// ---- failing variants --------------------------------------------------------------------

// Runs a three-run study whose middle run diverges (PD gain 1e12 with one explicit RK4 step per
// control period) and returns results.csv as rows of cells (header first).
class FarmDiverging : public Farm {
 protected:
  Result result;
  std::vector<std::vector<std::string>> rows;
  std::map<std::string, std::size_t> column;

  void SetUp() override {
    Farm::SetUp();
    write_text(dir / "study.yaml", "name: diverging\n"
                                   "model: " + kModel + "\n"
                                   "set:\n"
                                   "  trajectory.moves: [{target: 0.5, hold: 8.0}]\n"
                                   "runs:\n"
                                   "  - label: stable\n"
                                   "  - label: diverging\n"
                                   "    set:\n"
                                   "      controller.kp: 1.0e12\n"
                                   "      simulation.integrator: rk4\n"
                                   "      simulation.substeps: 1\n"
                                   "  - label: stable after\n"
                                   "    set:\n"
                                   "      controller.kd: 3.5e4\n"
                                   "  - label: CVODE fails\n"
                                   "    set:\n"
                                   "      controller.kp: 1.0e12\n"
                                   "      simulation.integrator: cvode_dense\n");
    result = flexfarm("run study.yaml --out out");
    for (const auto& l : split_lines(read_text(dir / "out" / "results.csv"))) rows.push_back(split_csv(l));
    if (!rows.empty())
      for (std::size_t c = 0; c < rows[0].size(); ++c) column[rows[0][c]] = c;
  }
  std::string cell(std::size_t row, const std::string& name) const {
    const auto it = column.find(name);
    if (it == column.end() || row >= rows.size() || it->second >= rows[row].size()) return "<no such cell>";
    return rows[row][it->second];
  }
};

TEST_F(FarmDiverging, DivergingVariantIsRecordedAndExitCodeSaysSo) {
  EXPECT_EQ(result.exit_code, 3) << result.output;
  EXPECT_NE(result.output.find("flexfarm: error: 2 variant(s) failed"), std::string::npos) << result.output;
  ASSERT_EQ(rows.size(), 5u) << "every run has its row, the one after the diverging one too:\n" << result.output;
  EXPECT_EQ(cell(2, "label"), "diverging");
  EXPECT_EQ(cell(2, "status"), "nonfinite");
  EXPECT_EQ(cell(4, "label"), "CVODE fails");
  EXPECT_EQ(cell(4, "status"), "solver_fail");
  for (std::size_t row : {1u, 3u}) {
    const std::string st = cell(row, "status");
    EXPECT_TRUE(st == "ok" || st == "not_settled") << "row " << row << " (" << cell(row, "label") << "): " << st;
  }
  EXPECT_EQ(static_cast<int>(read_journal(dir / "out" / "journal-main.csv").ids.size()), 4);
  EXPECT_TRUE(fs::exists(dir / "out" / "results.sqlite"));
  EXPECT_TRUE(fs::exists(dir / "out" / "table.md"));
}

// A run whose state became NaN never settled: its settling cells must be empty ("not settled"),
// not 0 s, which reads as the best possible result and enters every statistic of the column.
TEST_F(FarmDiverging, DivergedVariantHasNoSettlingTime) {
  ASSERT_EQ(rows.size(), 5u) << result.output;
  ASSERT_EQ(cell(2, "status"), "nonfinite");
  for (const std::string name : {"m1_tip_settling_s", "m1_hub_settling_s"})
    EXPECT_EQ(cell(2, name), "") << name << " of the diverged run; its row: " << split_lines(read_text(dir / "out" / "results.csv"))[2];
}

// Monte Carlo draws from a distribution's tail that the model rejects (a negative stiffness or
// mass): each such variant has its row with the status `invalid` and no metrics, every other
// variant runs, and the exit code and message say so, naming the first and why.
TEST_F(Farm, DrawsTheModelRejectsAreInvalidRowsAndTheStudyFinishes) {
  write_text(dir / "tails.yaml", "name: tails\n"
                                 "model: " + kModel + "\n"
                                 "set:\n"
                                 "  trajectory.moves: [{target: 0.5, hold: 3.0}]\n"
                                 "variables:\n"
                                 "  - path: joints.stiffness\n"
                                 "    distribution: {type: normal, mean: 39.5e3, std: 4.0e4}\n"
                                 "  - path: payload.mass\n"
                                 "    distribution: {type: normal, mean: 328.7, std: 400}\n"
                                 "design: {type: monte_carlo, samples: 16}\n");
  const Result r = flexfarm("run tails.yaml --out out");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  const auto lines = split_lines(read_text(dir / "out" / "results.csv"));
  ASSERT_EQ(lines.size(), 17u) << r.output;
  const auto head = split_csv(lines[0]);
  const auto col = [&](const std::string& name) { return std::find(head.begin(), head.end(), name) - head.begin(); };
  int invalid = 0, first = -1;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto row = split_csv(lines[i]);
    // The model's own rules, applied here to the drawn values: stiffness > 0, mass >= 0.
    const bool rejected = std::stod(row[col("joints.stiffness")]) <= 0 || std::stod(row[col("payload.mass")]) < 0;
    EXPECT_EQ(row[col("status")] == "invalid", rejected) << lines[i];
    if (rejected) {
      EXPECT_EQ(row[col("m1_peak_torque_Nm")], "") << "an invalid variant has no metrics: " << lines[i];
      if (first < 0) first = static_cast<int>(i - 1);
      ++invalid;
    } else {
      EXPECT_NE(row[col("m1_peak_torque_Nm")], "") << lines[i];
    }
  }
  ASSERT_GT(invalid, 0) << "seed 1 draws six rejected variants of 16; without one this test means nothing";
  EXPECT_NE(r.output.find(std::to_string(invalid) + " variant(s) invalid"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the first, eval_id " + std::to_string(first) + ": "), std::string::npos) << r.output;
  EXPECT_NE(read_text(dir / "out" / "table.md").find(std::to_string(invalid) + " invalid"), std::string::npos);
}

// Names a study file chooses (parameter paths, case labels, labels) become file names only through
// make_file_stem: a run writes nothing outside --out, whatever they say.
TEST_F(Farm, HostileNamesInAStudyWriteNothingOutsideOut) {
  const std::string absolute = "/tmp/ff_hostile_" + std::to_string(::getpid());
  write_text(dir / "hostile.yaml", "name: ../../hostile\n"
                                   "model: " + kModel + "\n"
                                   "set:\n"
                                   "  trajectory.moves: [{target: 0.5, hold: 3.0}]\n"
                                   "cases:\n"
                                   "  - label: ../../outside\n"
                                   "  - label: " + absolute + "\n"
                                   "variables:\n"
                                   "  - path: trajectory.moves[0].target\n"
                                   "    levels: [0.3, 0.5]\n"
                                   "design: {type: grid}\n");
  const auto r = flexfarm("run hostile.yaml --out out");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const fs::path rel = fs::relative(e.path(), dir);
    const bool ours = *rel.begin() == "out" || rel == "hostile.yaml" || rel.string().rfind("log-", 0) == 0;
    EXPECT_TRUE(ours) << "written outside --out: " << e.path();
  }
  EXPECT_TRUE(fs::exists(dir / "out" / "cases_m1_tip_settling_s.png"));
  for (const auto& e : fs::directory_iterator(dir.parent_path()))
    EXPECT_EQ(e.path().filename().string().find("outside"), std::string::npos) << e.path();
  for (const auto& e : fs::directory_iterator("/tmp"))
    EXPECT_NE(e.path().string().rfind(absolute, 0), 0u) << e.path();
}

// ---- rejected studies: exit 2, one line naming the file, line and key, nothing written -----

TEST_F(Farm, BadStudyWritesNothing) {
  const std::string head = "model: " + kModel + "\n";
  const struct {
    const char* file;
    std::string text;
    const char* prefix;  // of the one output line, after "flexfarm: error: "
    const char* words;   // also in it
  } cases[] = {
      {"unknown_key.yaml",
       head + "colour: red\nvariables:\n  - path: payload.mass\n    distribution: {type: normal, mean: 300, std: 4}\n"
              "design: {type: monte_carlo, samples: 4}\n",
       "unknown_key.yaml:2: colour: ", "unknown key"},
      {"negative_std.yaml",
       head + "variables:\n  - path: payload.mass\n    distribution: {type: normal, mean: 328.7, std: -1}\n"
              "design: {type: monte_carlo, samples: 4}\n",
       "negative_std.yaml:4: variables[0].distribution", "std"},
      {"grid_without_levels.yaml",
       head + "variables:\n  - path: payload.mass\n    nominal: 300\ndesign: {type: grid}\n",
       "grid_without_levels.yaml:3: variables[0].levels: ", "levels"},
      {"no_samples.yaml",
       head + "variables:\n  - path: payload.mass\n    distribution: {type: normal, mean: 328.7, std: 40}\n"
              "design: {type: monte_carlo, samples: 0}\n",
       "no_samples.yaml:5: design: ", "samples"},
      {"negative_mass_drawn.yaml",
       head + "variables:\n  - path: payload.mass\n    distribution: {type: uniform, lower: -10, upper: -1}\n"
              "design: {type: monte_carlo, samples: 4}\n",
       "negative_mass_drawn.yaml:3: variables[0] (payload.mass): ", ">= 0"},
  };
  for (const auto& c : cases) {
    write_text(dir / c.file, c.text);
    const auto r = flexfarm(std::string("run ") + c.file + " --out out");
    EXPECT_EQ(r.exit_code, 2) << c.file << ":\n" << r.output;
    const auto lines = r.lines();
    ASSERT_EQ(lines.size(), 1u) << c.file << ":\n" << r.output;
    EXPECT_EQ(lines[0].rfind(std::string("flexfarm: error: ") + c.prefix, 0), 0u) << c.file << ":\n" << r.output;
    EXPECT_NE(lines[0].find(c.words), std::string::npos) << c.file << ":\n" << r.output;
    EXPECT_FALSE(fs::exists(dir / "out")) << c.file << " created --out";
  }
}

// A distribution error names the offending key (here `std`), as every other study error does.
TEST_F(Farm, BadDistributionNamesTheOffendingKey) {
  write_text(dir / "study.yaml", "model: " + kModel +
                                     "\nvariables:\n  - path: payload.mass\n    distribution: {type: normal, mean: 328.7, std: -1}\n"
                                     "design: {type: monte_carlo, samples: 4}\n");
  const auto r = flexfarm("run study.yaml --out out");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output.rfind("flexfarm: error: study.yaml:4: variables[0].distribution.std: ", 0), 0u) << r.output;
}

// ---- issue 32 ------------------------------------------------------------------------------

// (#32.19) A journal row corrupted with its cell count intact ("0.x5" for a number) is no result: a
// merge counts its variant as missing (not a line of the assembled text), and --resume drops it as it
// drops a torn row, says so, and computes the variant again: results.csv as uninterrupted.
TEST_F(Farm, ACorruptedRowOfTheRightShapeIsDroppedOnResumeAndComputedAgain) {
  const int n = 24;
  write_small_study("small.yaml", 3, n);
  ASSERT_EQ(flexfarm("run small.yaml --out out --no-history").exit_code, 0);
  const std::string uninterrupted = read_text(dir / "out" / "results.csv");
  const fs::path journal = dir / "out" / "journal-main.csv";
  const std::size_t k = 2 + n / 2;  // a row in the middle
  int corrupted_id = -1;
  // Cell `cell` of that row replaced by `bad`, the cell count kept: a metric "0.x5", a seed "x" or "-1".
  for (const auto& [cell, bad] : {std::pair<int, std::string>{-1, "0.x5"}, {1, "x"}, {1, "-1"}}) {
    auto lines = split_lines(read_text(journal));
    auto cells = split_csv(lines[k]);
    corrupted_id = std::stoi(cells[0]);
    cells[cell < 0 ? cells.size() - 1 : static_cast<std::size_t>(cell)] = bad;
    lines[k].clear();
    for (const auto& c : cells) lines[k] += (lines[k].empty() ? "" : ",") + c;
    std::string text;
    for (const auto& l : lines) text += l + "\n";
    write_text(journal, text);
    fs::remove(dir / "out" / "results.csv");

    const auto merged = flexfarm("merge small.yaml --out out --no-history");
    EXPECT_NE(merged.exit_code, 0) << bad << ": " << merged.output;
    EXPECT_NE(merged.output.find("out: 1 of 24 variants have no result yet (first: eval_id " + std::to_string(corrupted_id) + ")"),
              std::string::npos)
        << bad << ": " << merged.output;
    const auto r = flexfarm("run small.yaml --out out --resume --no-history");
    ASSERT_EQ(r.exit_code, 0) << bad << ": " << r.output;
    EXPECT_NE(r.output.find("journal-main.csv: repaired: 1 line(s) that are not result rows dropped; their variants are computed again"),
              std::string::npos)
        << bad << ": " << r.output;
    const std::string repaired = read_text(dir / "out" / "results.csv");
    EXPECT_EQ(fingerprint(repaired), fingerprint(uninterrupted)) << bad << ": " << first_difference(uninterrupted, repaired);
    const Journal after = read_journal(journal);
    EXPECT_EQ(after.ids.size(), static_cast<std::size_t>(n)) << bad;
    EXPECT_EQ(after.ids.back(), corrupted_id) << bad << ": the corrupted row is computed again, last";
    EXPECT_EQ(read_text(journal).find("," + bad + (cell < 0 ? "\n" : ",")), std::string::npos) << bad;
  }
}

// The value of `key: value` in a run.yaml ("" when absent).
std::string run_yaml_value(const fs::path& run_yaml, const std::string& key) {
  for (const auto& l : split_lines(read_text(run_yaml)))
    if (l.rfind(key + ": ", 0) == 0) return l.substr(key.size() + 2);
  return "";
}

// (#32.20) A run is recorded in the history once it has finished: one whose report.html cannot be
// written (here a directory in its place; a full disk alike) fails and is not recorded; its --resume
// records it once, started at the first attempt's start, with the wall time of both attempts.
TEST_F(Farm, ARunIsRecordedOnceFinishedWithTheWallTimeOfEveryAttempt) {
  write_small_study("small.yaml", 3, 24);
  fs::create_directories(dir / "out" / "report.html" / "in the way");
  const auto failed = flexfarm("run small.yaml --out out --history history");
  EXPECT_EQ(failed.exit_code, 1) << failed.output;
  EXPECT_NE(failed.output.find("report.html: cannot rename into place: Is a directory"), std::string::npos) << failed.output;
  EXPECT_EQ(failed.output.find("recorded as run"), std::string::npos) << failed.output;
  const auto none = flexfarm("history --history history");
  EXPECT_NE(none.output.find("no runs in"), std::string::npos) << none.output;
  const auto attempts1 = split_lines(read_text(dir / "out" / "attempts-main.csv"));
  ASSERT_GE(attempts1.size(), 2u);
  EXPECT_EQ(attempts1[0], "attempt,started,seconds");
  const auto first = split_csv(attempts1.back());
  ASSERT_EQ(first.size(), 3u) << attempts1.back();
  EXPECT_EQ(first[0], "1");
  const double first_seconds = std::stod(first[2]);
  EXPECT_GT(first_seconds, 0.0);

  fs::remove_all(dir / "out" / "report.html");
  const auto resumed = flexfarm("run small.yaml --out out --resume --history history");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("recorded as run 1 in history/history.sqlite"), std::string::npos) << resumed.output;
  const auto listed = flexfarm("history --history history");
  ASSERT_EQ(listed.lines().size(), 3u) << listed.output;  // header, separator, one run
  const auto second = split_csv(split_lines(read_text(dir / "out" / "attempts-main.csv")).back());
  ASSERT_EQ(second.size(), 3u);
  EXPECT_EQ(second[0], "2");
  // The record (run.yaml, as the history holds it): the first attempt's start, both attempts' time.
  const double seconds = std::stod(run_yaml_value(dir / "out" / "run.yaml", "seconds"));
  EXPECT_GE(seconds, first_seconds) << "the first attempt's " << first_seconds << " s are counted";
  EXPECT_LE(seconds, first_seconds + std::stod(second[2]) + 1e-3);
  EXPECT_EQ(run_yaml_value(dir / "out" / "run.yaml", "started"), first[1]);
  const auto record = flexfarm("history 1 --history history");
  EXPECT_NE(record.output.find("| started | " + first[1] + " |"), std::string::npos) << record.output;
  EXPECT_NE(read_text(dir / "out" / "report.html").find(", run 1 of the history"), std::string::npos);
  // Resumed once more, finished already (a requeued job): the same run, not recorded again.
  const auto again = flexfarm("run small.yaml --out out --resume --history history");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("already recorded as run 1 in history/history.sqlite"), std::string::npos) << again.output;
  EXPECT_EQ(flexfarm("history --history history").lines().size(), 3u);
  EXPECT_NE(read_text(dir / "out" / "report.html").find(", run 1 of the history"), std::string::npos);
}

// (#32.5) An output directory shared with others: links planted at the temporaries' old names
// ("<file>.tmp") are never followed (the victim keeps its bytes, every output is a file of its own);
// a link planted at the timings, the lock or traces/ is refused before anything is written through it.
TEST_F(Farm, LinksPlantedInASharedOutAreNeverFollowed) {
  write_small_study("small.yaml", 3, 24);
  ASSERT_EQ(flexfarm("run small.yaml --out ref --no-history").exit_code, 0);
  fs::create_directories(dir / "elsewhere");
  const fs::path victim = dir / "elsewhere" / "victim.txt";
  write_text(victim, "the victim's own bytes\n");
  fs::create_directories(dir / "out");
  int planted = 0;
  for (const auto& e : fs::directory_iterator(dir / "ref"))
    if (e.is_regular_file()) fs::create_symlink(victim, dir / "out" / (e.path().filename().string() + ".tmp")), ++planted;
  EXPECT_GE(planted, 8);  // results.csv, .sqlite, table.md, run.yaml, report.html, the plots, the journal, ...
  const auto r = flexfarm("run small.yaml --out out --no-history");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_text(victim), "the victim's own bytes\n");
  for (const auto& e : fs::directory_iterator(dir / "ref")) {
    const fs::path p = dir / "out" / e.path().filename();
    EXPECT_FALSE(fs::is_symlink(p)) << p;
    if (e.is_regular_file()) EXPECT_TRUE(fs::is_regular_file(p)) << p;
  }
  EXPECT_EQ(read_text(dir / "out" / "results.csv"), read_text(dir / "ref" / "results.csv"));

  const struct {
    const char* name;
    fs::path target;
    const char* error;
  } refused[] = {{"timings-main.csv", victim, "timings-main.csv: cannot open for writing: Too many levels of symbolic links"},
                 {"journal-main.lock", dir / "elsewhere" / "made.lock", "journal-main.lock: cannot open the lock file: Too many levels"},
                 {"traces", dir / "elsewhere", "traces: not a directory of its own"}};
  for (const auto& p : refused) {
    const fs::path out = dir / (std::string("out_") + p.name);
    fs::create_directories(out);
    fs::create_symlink(p.target, out / p.name);
    const auto res = flexfarm("run small.yaml --out " + out.string() + " --no-history");
    EXPECT_NE(res.exit_code, 0) << p.name << ": " << res.output;
    EXPECT_NE(res.output.find(p.error), std::string::npos) << p.name << ": " << res.output;
    EXPECT_FALSE(fs::exists(out / "results.csv")) << p.name;
  }
  EXPECT_EQ(read_text(victim), "the victim's own bytes\n");
  EXPECT_FALSE(fs::exists(dir / "elsewhere" / "made.lock"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "elsewhere"), fs::directory_iterator{}), 1);  // the victim alone
}

}  // namespace
