#include "common/files.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace ff {

bool is_blank_path(const std::string& path) {
  return path.find_first_not_of(" \t\n\r\f\v") == std::string::npos;
}

AtomicFile::AtomicFile(const std::string& target, const std::string& ext) : target_(target) {
  if (is_blank_path(target)) throw std::runtime_error("an empty or blank output path");
  std::string tmpl = target + ".tmp-XXXXXX";
  if (::mkdtemp(tmpl.data()) == nullptr) fail(std::string("cannot create a temporary beside it: ") + std::strerror(errno));
  dir_ = tmpl;
  std::filesystem::path name = std::filesystem::path(target).filename();
  if (!ext.empty()) name.replace_extension(ext);
  path_ = dir_ + "/" + name.string();
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);  // as fopen: the umask decides
  if (fd_ < 0) fail(std::string("cannot create a temporary beside it: ") + std::strerror(errno));
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (committed_) return;
  if (!path_.empty()) ::unlink(path_.c_str());
  if (!dir_.empty()) {
    std::error_code ignored;  // a writer's own leftovers too (SQLite's journal)
    std::filesystem::remove_all(dir_, ignored);
  }
}

void AtomicFile::fail(const std::string& why) const { throw std::runtime_error(target_ + ": " + why); }

void AtomicFile::write(const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(std::string("write failed: ") + (n < 0 ? std::strerror(errno) : "nothing written"));
    done += static_cast<std::size_t>(n);
  }
}

void AtomicFile::close() {
  const int fd = release();
  if (fd >= 0 && ::close(fd) != 0) fail(std::string("write failed: ") + std::strerror(errno));  // NFS reports here
}

void AtomicFile::commit() {
  if (::rename(path_.c_str(), target_.c_str()) != 0) fail(std::string("cannot rename into place: ") + std::strerror(errno));
  committed_ = true;
  std::error_code ignored;
  std::filesystem::remove_all(dir_, ignored);
}

int AtomicFile::release() {
  const int fd = fd_;
  fd_ = -1;
  return fd;
}

void write_file_atomic(const std::string& path, const std::string& text) {
  AtomicFile tmp(path);
  tmp.write(text);
  tmp.close();
  tmp.commit();
}

int open_append_nofollow(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0666);
  if (fd < 0) throw std::runtime_error(path + ": cannot open for writing: " + std::strerror(errno));
  return fd;
}

std::string make_file_stem(const std::string& name) {
  std::string out;
  for (char c : name) out += std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ? c : '_';
  return out;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void make_directories(const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec) throw std::runtime_error(path + ": cannot create directory: " + ec.message());
}

void make_own_directory(const std::string& path) {
  if (::mkdir(path.c_str(), 0755) != 0 && errno != EEXIST)
    throw std::runtime_error(path + ": cannot create directory: " + std::strerror(errno));
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw std::runtime_error(path + ": not a directory of its own (a link, or a file, is in its place): remove it, or use another output directory");
}

FileLock::FileLock(const std::string& path, const std::string& what) {
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);  // never a planted link
  if (fd_ < 0) throw std::runtime_error(path + ": cannot open the lock file: " + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK) throw std::runtime_error(what);
    throw std::runtime_error(path + ": cannot lock: " + std::strerror(err));
  }
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // closing releases the lock
}

}  // namespace ff
