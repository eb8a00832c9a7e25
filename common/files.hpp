// Output files are written whole or not at all: to a temporary made exclusively beside them, then
// renamed over them. Output directories may be shared (/shared/runs on a cluster): a link planted
// at any name is never followed by a write.
#pragma once

#include <string>

namespace ff {

// True when `path` is empty or only white space (an unset $OUT in a script): every path a user gives
// is checked with it at the boundary (the verbs' options, $FLEXFARM_HISTORY), so that "" never
// becomes "/journal-main.csv" at the root.
bool is_blank_path(const std::string& path);

// The temporary of one atomic write of `target`: a private directory made by mkdtemp beside it
// ("<target>.tmp-XXXXXX", mode 0700, so no other user can plant a link in it) holding one file,
// created with O_CREAT|O_EXCL|O_NOFOLLOW, named as the target (or with `ext` for its extension: a
// video container), so a writer that wants a name (SQLite, a video encoder) gets one with the target's
// extension. commit() renames it over the target (a link planted at the target is replaced, never
// followed); destroyed uncommitted, it leaves nothing behind. Errors throw std::runtime_error naming
// the target and the system's reason.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& target, const std::string& ext = "");
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  const std::string& path() const { return path_; }  // the temporary's name
  int fd() const { return fd_; }                      // open for writing; -1 once closed or released
  void write(const std::string& bytes);               // all of it, to fd()
  void close();                                       // before another writer opens path()
  // Renames the temporary over the target and removes the private directory. The descriptor stays
  // open on the file, now the target's (release() hands it over).
  void commit();
  int release();

 private:
  [[noreturn]] void fail(const std::string& why) const;
  std::string target_, dir_, path_;
  int fd_ = -1;
  bool committed_ = false;
};

// Writes `text` to `path` atomically (an AtomicFile). Throws std::runtime_error naming the path on failure.
void write_file_atomic(const std::string& path, const std::string& text);

// Opens `path` for appending (O_APPEND, created when missing, 0666 less the umask), never through a link planted at
// its name (O_NOFOLLOW). Returns the descriptor; throws std::runtime_error naming the path.
int open_append_nofollow(const std::string& path);

// A file name made from a name read from an input (a parameter path, a case label, a channel):
// letters, digits, '_' and '-' kept, anything else '_', so it cannot leave its directory.
std::string make_file_stem(const std::string& name);

// The whole text of a file. Throws std::runtime_error "<path>: cannot open" when it cannot be read.
std::string read_file(const std::string& path);

// Creates a directory and its parents. Throws std::runtime_error naming the path on failure.
void make_directories(const std::string& path);

// A directory a program makes inside its output directory (DIR/traces): created when missing, and
// refused when something else is at its name (a planted link to a directory elsewhere).
void make_own_directory(const std::string& path);

// An exclusive lock on `path` (flock; the file is created if missing, never through a link), held until destruction, so that
// two processes never write the same output. Throws std::runtime_error, naming `what`, when another
// process holds it: it refuses at once rather than wait.
class FileLock {
 public:
  FileLock(const std::string& path, const std::string& what);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace ff
