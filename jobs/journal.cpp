#include "jobs/journal.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/files.hpp"
#include "results/table.hpp"

namespace ff {

namespace {

const std::string kMagic = "# flexfarm journal study=";

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Number of cells in a CSV line, quotes respected.
std::size_t count_cells(const std::string& line) {
  std::size_t n = 1;
  bool quoted = false;
  for (char c : line) {
    if (c == '"') quoted = !quoted;
    else if (c == ',' && !quoted) ++n;
  }
  return n;
}

// A whole results row: as many cells as the header, led by a whole-number eval_id, and read by the
// results' own reader (every number a number: a row torn, or corrupted with its cell count intact, is not).
bool is_row(const std::string& line, const std::string& header) {
  const std::size_t comma = line.find(',');
  if (line.empty() || comma == 0 || comma == std::string::npos || comma > 9 ||
      count_cells(line) != count_cells(header.substr(0, header.size() - 1)))
    return false;
  for (std::size_t i = 0; i < comma; ++i)
    if (line[i] < '0' || line[i] > '9') return false;
  try {
    return parse_results_csv(header + line + "\n", "journal row").rows.size() == 1;
  } catch (const std::runtime_error&) {
    return false;
  }
}

}  // namespace

std::map<int, std::string> read_journals(const std::string& dir, const std::string& hash, const std::string& header) {
  std::map<int, std::string> rows;
  if (!std::filesystem::is_directory(dir)) return rows;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("journal-", 0) != 0 || entry.path().extension() != ".csv") continue;
    const std::string text = read_all(entry.path().string());
    const std::string path = entry.path().string();
    std::size_t pos = text.find('\n');
    if (pos == std::string::npos) continue;  // killed before its header was complete
    if (text.rfind(kMagic, 0) != 0) throw std::runtime_error(path + ":1: not a flexfarm journal");
    if (text.substr(kMagic.size(), pos - kMagic.size()) != hash)
      throw std::runtime_error(path + ":1: journal of another study or model (the files changed since); use another --out directory");
    const std::size_t hdr_end = text.find('\n', pos + 1);
    if (hdr_end == std::string::npos) continue;
    if (text.substr(pos + 1, hdr_end - pos) != header) throw std::runtime_error(path + ":2: journal with other columns");
    // Whole rows only: a line without its newline (a torn write), or one that is no row (corrupted), is
    // skipped here, so its variant is computed again; JournalWriter drops it from its own journal, saying so.
    pos = hdr_end + 1;
    while (pos < text.size()) {
      const std::size_t end = text.find('\n', pos);
      if (end == std::string::npos) break;
      const std::string line = text.substr(pos, end - pos);
      pos = end + 1;
      if (is_row(line, header)) rows.emplace(std::stoi(line.substr(0, line.find(','))), line + "\n");
    }
  }
  return rows;
}

JournalWriter::JournalWriter(const std::string& dir, const std::string& tag, const std::string& hash,
                             const std::string& header)
    : path_(dir + "/journal-" + tag + ".csv") {
  const std::string old = std::filesystem::exists(path_) ? read_all(path_) : std::string();
  const std::string head = kMagic + hash + "\n" + header;
  std::string text = head;
  // Keep the complete rows of an existing journal of this study; cut a torn last line and drop any
  // line that is not a row (garbage appended): their variants are computed again. Another study's
  // journal (or none) starts afresh.
  if (old.rfind(head, 0) == 0) {
    std::size_t pos = head.size(), torn = 0, dropped = 0;
    while (pos < old.size()) {
      const std::size_t end = old.find('\n', pos);
      if (end == std::string::npos) {
        torn = old.size() - pos;
        break;
      }
      const std::string line = old.substr(pos, end - pos);
      if (is_row(line, header)) text += line + "\n";
      else ++dropped;
      pos = end + 1;
    }
    if (torn || dropped)
      repaired_ = path_ + ": repaired: " +
                  (torn ? "a torn last line (" + std::to_string(torn) + " bytes) cut" : std::string()) +
                  (torn && dropped ? ", " : "") +
                  (dropped ? std::to_string(dropped) + " line(s) that are not result rows dropped" : std::string()) +
                  "; their variants are computed again";
  }
  // Replace the file whole (an exclusive temporary, renamed over it), then append to that same file
  // (never reopened by name, so never through a link planted at it): a kill at any point loses no row.
  AtomicFile tmp(path_);
  fd_ = tmp.fd();
  try {
    append(text);
  } catch (...) {
    fd_ = -1;  // the temporary's, removed with it
    throw;
  }
  tmp.commit();
  fd_ = tmp.release();
  if (::fcntl(fd_, F_SETFL, O_APPEND) != 0)
    throw std::runtime_error(path_ + ": cannot open the journal for appending: " + std::strerror(errno));
}

JournalWriter::~JournalWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void JournalWriter::append(const std::string& rows) {
  const off_t before = ::lseek(fd_, 0, SEEK_END);
  std::size_t done = 0;
  while (done < rows.size()) {
    const ssize_t n = ::write(fd_, rows.data() + done, rows.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = n < 0 ? std::strerror(errno) : "nothing written";
      if (before >= 0 && ::ftruncate(fd_, before) != 0) {}  // best effort: the reader drops a torn line anyway
      throw std::runtime_error(path_ + ": cannot write the journal: " + why +
                               "; it holds every row up to the last whole one: free space and run again with --resume");
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd_) != 0 && errno != EINVAL)
    throw std::runtime_error(path_ + ": cannot sync the journal to disk: " + std::strerror(errno));
}

}  // namespace ff
