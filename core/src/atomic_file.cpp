// Atomic output: temp file beside the target, write, fsync, close, rename (docs/formats.md,
// "Atomic writes"). POSIX calls rather than iostreams so that every failing write reports errno.
#include "scanmesh/core/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <set>
#include <sstream>
#include <string>

#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {

const char* file_kind(mode_t mode) {
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// The file a user asked for: a staged output (StagedFiles) is written under its temporary
// name ".NAME.tmp.PID.N", which means nothing to the user; messages name NAME.
std::filesystem::path name_for_messages(const std::filesystem::path& path) {
  const std::string f = path.filename().string();
  const auto tmp = f.rfind(".tmp.");
  if (f.size() < 2 || f[0] != '.' || tmp == std::string::npos || tmp <= 1) return path;
  const std::string tail = f.substr(tmp + 5);  // "PID.N"
  const auto dot = tail.find('.');
  const bool digits = dot != std::string::npos && dot > 0 && dot + 1 < tail.size() &&
                      tail.find_first_not_of("0123456789.") == std::string::npos &&
                      tail.find('.', dot + 1) == std::string::npos;
  return digits ? path.parent_path() / f.substr(1, tmp - 1) : path;
}

std::string os_error(const std::string& what, const std::filesystem::path& path, int err) {
  return "cannot " + what + " '" + name_for_messages(path).string() + "': " + std::strerror(err);
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

// An existing target must be a regular file: renaming over a device node, FIFO or symbolic
// link would replace it (`--out /dev/full` replaced the system's /dev/full).
void require_replaceable(const std::filesystem::path& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return;  // not there yet: fine
  if (S_ISREG(st.st_mode)) return;
  const char* kind = S_ISLNK(st.st_mode)   ? "a symbolic link"
                     : S_ISDIR(st.st_mode) ? "a folder"
                                           : file_kind(st.st_mode);
  throw IoError("cannot write '" + path.string() + "': it exists and is " + kind +
                "; scanmesh replaces only regular files");
}

// Temporaries `.NAME.tmp.PID.N` left by a run that was killed between writing and renaming:
// removed once per folder and process when their process is gone.
void remove_orphaned_temporaries(const std::filesystem::path& dir) {
  static std::mutex mutex;
  static std::set<std::string> swept;
  const std::string key = dir.empty() ? "." : dir.string();
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (!swept.insert(key).second) return;
  }
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(key, ec)) {
    const std::string name = entry.path().filename().string();
    const std::size_t at = name.rfind(".tmp.");
    if (name.empty() || name[0] != '.' || at == std::string::npos) continue;
    long pid = 0;
    unsigned long counter = 0;
    if (std::sscanf(name.c_str() + at, ".tmp.%ld.%lu", &pid, &counter) != 2 || pid <= 0) continue;
    if (pid == ::getpid() || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    std::error_code ignored;
    std::filesystem::remove(entry.path(), ignored);
  }
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
  require_replaceable(path);
  remove_orphaned_temporaries(path.parent_path());
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
  require_replaceable(path);
  if (::fsync(fd) != 0) throw IoError(os_error("flush", path, errno));
  if (guard.close_fd() != 0) throw IoError(os_error("close", path, errno));
  if (::rename(temporary.c_str(), path.c_str()) != 0)
    throw IoError(os_error("rename onto", path, errno));
  guard.release();
  fsync_directory(path.parent_path());
}

OutputFolder::OutputFolder(std::filesystem::path dir) : dir_(std::move(dir)) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec))
    throw IoError("cannot use '" + dir_.string() + "' as the output folder: a file of that name "
                  "exists");
  for (fs::path p = dir_; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    created_.insert(created_.begin(), p);
    if (p == p.parent_path()) break;
  }
  fs::create_directories(dir_, ec);
  if (ec || !fs::is_directory(dir_)) {
    std::error_code ignored;
    for (auto it = created_.rbegin(); it != created_.rend(); ++it) fs::remove(*it, ignored);
    throw IoError("cannot create output folder '" + dir_.string() + "': " +
                  (ec ? ec.message() : "a file of that name exists"));
  }
}

OutputFolder::~OutputFolder() {
  if (kept_) return;
  std::error_code ec;  // remove() refuses a folder that is not empty: that one stays
  for (auto it = created_.rbegin(); it != created_.rend(); ++it)
    if (!std::filesystem::remove(*it, ec)) break;
}

NewFilesGuard::NewFilesGuard(const std::vector<std::filesystem::path>& paths) {
  std::error_code ec;
  for (const auto& p : paths)
    if (!p.empty() && !std::filesystem::exists(std::filesystem::symlink_status(p, ec)))
      new_.push_back(p);
}

NewFilesGuard::~NewFilesGuard() {
  if (kept_) return;
  std::error_code ignored;
  for (const auto& p : new_) std::filesystem::remove(p, ignored);
}

StagedFiles::~StagedFiles() {
  if (committed_) return;
  for (const auto& [temporary, final_path] : staged_) ::unlink(temporary.c_str());
}

std::filesystem::path StagedFiles::stage(const std::filesystem::path& final_path) {
  require_replaceable(final_path);  // at once, before the content is produced
  staged_.emplace_back(temporary_path_beside(final_path), final_path);
  return staged_.back().first;
}

void StagedFiles::commit() {
  // The staged files are complete and flushed (their writers were atomic); only the renames
  // are left, which do not need disk space.
  for (const auto& [temporary, final_path] : staged_) require_replaceable(final_path);
  for (const auto& [temporary, final_path] : staged_)
    if (::rename(temporary.c_str(), final_path.c_str()) != 0)
      throw IoError(os_error("rename onto", final_path, errno));
  committed_ = true;
  if (!staged_.empty()) fsync_directory(staged_.front().second.parent_path());
}

std::vector<std::uint8_t> read_file_bytes(const std::filesystem::path& path,
                                          std::size_t max_bytes) {
  // O_NONBLOCK: opening a FIFO must not wait for a writer; it is refused below.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) throw IoError(os_error("open", path, errno));
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) throw IoError(os_error("stat", path, errno));
  if (S_ISDIR(st.st_mode)) throw IoError(os_error("read", path, EISDIR));
  if (!S_ISREG(st.st_mode))
    throw FileFormatError(path, std::string("not a regular file (") + file_kind(st.st_mode) +
                                    "); scanmesh reads only files");
  if (static_cast<std::uint64_t>(st.st_size) > max_bytes)
    throw FileFormatError(path, "is " + std::to_string(st.st_size) + " bytes, more than the " +
                                    std::to_string(max_bytes) + " bytes this kind of file may have");
  std::vector<std::uint8_t> bytes;
  bytes.reserve(static_cast<std::size_t>(st.st_size));
  std::uint8_t chunk[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw IoError(os_error("read", path, errno));
    }
    if (n == 0) break;
    if (bytes.size() + static_cast<std::size_t>(n) > max_bytes)  // grew while being read
      throw FileFormatError(path, "grew beyond " + std::to_string(max_bytes) + " bytes while read");
    bytes.insert(bytes.end(), chunk, chunk + n);
  }
  return bytes;
}

}  // namespace scanmesh
