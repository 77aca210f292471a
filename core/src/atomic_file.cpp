// Atomic output: temp file beside the target, write, fsync, close, rename (docs/formats.md,
// "Atomic writes"). POSIX calls rather than iostreams so that every failing write reports errno.
#include "scanmesh/core/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <sstream>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {

std::string os_error(const std::string& what, const std::filesystem::path& path, int err) {
  return "cannot " + what + " '" + path.string() + "': " + std::strerror(err);
}

// Closes the descriptor and removes the temporary file unless released; keeps every error path
// of write_file_atomically short.
class TempFileGuard {
 public:
  TempFileGuard(std::filesystem::path p, int fd) : path_(std::move(p)), fd_(fd) {}
  TempFileGuard(const TempFileGuard&) = delete;
  TempFileGuard& operator=(const TempFileGuard&) = delete;
  ~TempFileGuard() {
    if (fd_ >= 0) ::close(fd_);
    if (!released_) ::unlink(path_.c_str());
  }
  int fd() const { return fd_; }
  //! Closes now and reports errno on failure (close can report deferred write errors).
  int close_fd() {
    const int rc = ::close(fd_);
    fd_ = -1;
    return rc;
  }
  void release() { released_ = true; }

 private:
  std::filesystem::path path_;
  int fd_;
  bool released_ = false;
};

void fsync_directory(const std::filesystem::path& dir) {
  // Makes the rename itself durable. Best effort: some file systems refuse fsync on directories.
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  (void)::fsync(fd);
  ::close(fd);
}

}  // namespace

std::filesystem::path temporary_path_beside(const std::filesystem::path& path) {
  static std::atomic<unsigned long> counter{0};
  const std::string name = "." + path.filename().string() + ".tmp." + std::to_string(::getpid()) +
                           "." + std::to_string(counter.fetch_add(1));
  return path.parent_path() / name;
}

void write_file_atomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes) {
  if (path.filename().empty())
    throw IoError("cannot write '" + path.string() + "': not a file name");
  const std::filesystem::path tmp = temporary_path_beside(path);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) throw IoError(os_error("create a file beside", path, errno));
  TempFileGuard guard(tmp, fd);

  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw IoError(os_error("write", path, errno));
    }
    if (n == 0) throw IoError(os_error("write", path, EIO));
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) throw IoError(os_error("flush", path, errno));
  if (guard.close_fd() != 0) throw IoError(os_error("close", path, errno));
  if (::rename(tmp.c_str(), path.c_str()) != 0) throw IoError(os_error("rename onto", path, errno));
  guard.release();
  fsync_directory(path.parent_path());
}

void write_file_atomically(const std::filesystem::path& path, std::string_view text) {
  write_file_atomically(path,
                        std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& fill) {
  std::ostringstream buffer(std::ios::binary);
  fill(buffer);  // may throw: nothing has touched the disk yet
  if (!buffer) throw IoError("cannot write '" + path.string() + "': formatting the content failed");
  write_file_atomically(path, std::string_view(buffer.view()));
}

void commit_temporary_file(const std::filesystem::path& temporary,
                           const std::filesystem::path& path) {
  const int fd = ::open(temporary.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    ::unlink(temporary.c_str());
    throw IoError(os_error("reopen the temporary file for", path, err));
  }
  TempFileGuard guard(temporary, fd);
  if (::fsync(fd) != 0) throw IoError(os_error("flush", path, errno));
  if (guard.close_fd() != 0) throw IoError(os_error("close", path, errno));
  if (::rename(temporary.c_str(), path.c_str()) != 0)
    throw IoError(os_error("rename onto", path, errno));
  guard.release();
  fsync_directory(path.parent_path());
}

StagedFiles::~StagedFiles() {
  if (committed_) return;
  for (const auto& [temporary, final_path] : staged_) ::unlink(temporary.c_str());
}

std::filesystem::path StagedFiles::stage(const std::filesystem::path& final_path) {
  staged_.emplace_back(temporary_path_beside(final_path), final_path);
  return staged_.back().first;
}

void StagedFiles::commit() {
  // The staged files are complete and flushed (their writers were atomic); only the renames
  // are left, which do not need disk space.
  for (const auto& [temporary, final_path] : staged_)
    if (::rename(temporary.c_str(), final_path.c_str()) != 0)
      throw IoError(os_error("rename onto", final_path, errno));
  committed_ = true;
  if (!staged_.empty()) fsync_directory(staged_.front().second.parent_path());
}

std::vector<std::uint8_t> read_file_bytes(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw IoError(os_error("open", path, errno));
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) throw IoError(os_error("stat", path, errno));
  if (S_ISDIR(st.st_mode)) throw IoError(os_error("read", path, EISDIR));
  std::vector<std::uint8_t> bytes;
  // st_size is only a hint (the file may change, or be a pipe); read until EOF.
  if (S_ISREG(st.st_mode) && st.st_size > 0) bytes.reserve(static_cast<std::size_t>(st.st_size));
  std::uint8_t chunk[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw IoError(os_error("read", path, errno));
    }
    if (n == 0) break;
    bytes.insert(bytes.end(), chunk, chunk + n);
  }
  return bytes;
}

}  // namespace scanmesh
