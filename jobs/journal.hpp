// The journal of finished variants: DIR/journal-<tag>.csv, one per process (a rank, a shard or a
// plain run). Line 1 "# flexfarm journal study=<hash>", line 2 the results header, then one
// results row per finished variant, appended and flushed batch by batch. A process killed
// mid-write leaves at most one incomplete last line, which readers ignore.
#pragma once

#include <map>
#include <string>

namespace ff {

// Every complete row of every journal in `dir`, by eval_id. Throws std::runtime_error when a
// journal belongs to another study (other hash) or another header.
std::map<int, std::string> read_journals(const std::string& dir, const std::string& hash, const std::string& header);

class JournalWriter {
 public:
  // Opens DIR/journal-<tag>.csv for appending (creating it with its two header lines). A torn last
  // line left by a killed run, and any line that is not a result row, are dropped first.
  JournalWriter(const std::string& dir, const std::string& tag, const std::string& hash, const std::string& header);
  ~JournalWriter();
  JournalWriter(const JournalWriter&) = delete;
  JournalWriter& operator=(const JournalWriter&) = delete;
  // Appends complete rows (each ending in a newline) and syncs them to the disk. A failed write (the
  // disk full) is cut back off, so the journal still ends on its last whole row, and throws naming
  // the file and the system's reason.
  void append(const std::string& rows);
  // What opening repaired (a torn last line cut, lines that are not rows dropped), for the user; "" if nothing.
  const std::string& repaired() const { return repaired_; }

 private:
  int fd_ = -1;
  std::string path_;
  std::string repaired_;
};

}  // namespace ff
