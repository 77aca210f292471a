// Atomic file output: every file scanmesh writes goes through here, so a crash, a kill or a
// full disk never leaves a half-written file under the final name.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <ostream>
#include <span>
#include <string_view>
#include <vector>

namespace scanmesh {

//! Writes `bytes` to a temporary file beside `path`, fsyncs it and renames it over `path`.
//! Throws IoError (naming the file and the OS reason, e.g. "No space left on device") if any
//! step fails; the temporary file is removed and an existing `path` is left untouched.
void write_file_atomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);
void write_file_atomically(const std::filesystem::path& path, std::string_view text);

//! Same, for writers that stream: `fill` writes into a binary std::ostream backed by a
//! buffer; nothing touches the disk until `fill` returns.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& fill);

//! For writers that can only write to a path themselves (e.g. PCL): a unique temporary path
//! beside `path`, named `.<filename>.tmp.<pid>.<counter>`. Nothing is created.
std::filesystem::path temporary_path_beside(const std::filesystem::path& path);
//! Second half of an atomic write done by someone else: fsyncs the complete file `temporary`
//! and renames it over `path`. On failure removes `temporary` and throws IoError.
void commit_temporary_file(const std::filesystem::path& temporary,
                           const std::filesystem::path& path);

//! A set of output files that appear together or not at all (a command's outputs in one
//! directory): each is written completely, by any writer, under a temporary name beside its
//! final one (stage), and commit() renames them all into place. Destroyed without commit(), it
//! removes what it staged, so a write that fails half way through the set (a full disk) leaves
//! every final name as it was, not new files next to old ones.
class StagedFiles {
 public:
  StagedFiles() = default;
  StagedFiles(const StagedFiles&) = delete;
  StagedFiles& operator=(const StagedFiles&) = delete;
  ~StagedFiles();
  //! The temporary path to write `final_path`'s content to (nothing is created).
  std::filesystem::path stage(const std::filesystem::path& final_path);
  //! Renames every staged file onto its final name, in staging order. Throws IoError naming
  //! the file if a staged file is missing or a rename fails.
  void commit();

 private:
  std::vector<std::pair<std::filesystem::path, std::filesystem::path>> staged_;  // temp, final
  bool committed_ = false;
};

//! A command's output folder. The constructor creates it at once (before any work, so an
//! existing file of that name or an uncreatable path fails in a second, not after a long run)
//! and throws IoError naming it. Destroyed without keep() (the command failed), it removes the
//! folders this run created, as far as they are still empty: a failed command leaves no new
//! folder behind.
class OutputFolder {
 public:
  explicit OutputFolder(std::filesystem::path dir);
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  ~OutputFolder();
  const std::filesystem::path& path() const { return dir_; }
  //! The command succeeded: the folder stays.
  void keep() { kept_ = true; }

 private:
  std::filesystem::path dir_;
  std::vector<std::filesystem::path> created_;  // innermost last
  bool kept_ = false;
};

//! For outputs that cannot be staged (an OBJ names its .mtl after its own file name): remembers
//! which of `paths` do not exist yet and removes those again when destroyed without keep(), so a
//! command that fails half way leaves no new file (each file is still written atomically).
class NewFilesGuard {
 public:
  explicit NewFilesGuard(const std::vector<std::filesystem::path>& paths);
  NewFilesGuard(const NewFilesGuard&) = delete;
  NewFilesGuard& operator=(const NewFilesGuard&) = delete;
  ~NewFilesGuard();
  void keep() { kept_ = true; }

 private:
  std::vector<std::filesystem::path> new_;
  bool kept_ = false;
};

//! Reads a whole file. Throws IoError if it cannot be opened or read.
//! Only regular files (a symbolic link to one is fine): a device, FIFO or socket is refused
//! with FileFormatError before a byte is read (a frame linked to /dev/zero would never end), and
//! so is a file larger than `max_bytes`.
inline constexpr std::size_t kMaxInputFileBytes = std::size_t{4} << 30;
//! Line and feature files (SVG, JSON, text): 64 MiB.
inline constexpr std::size_t kMaxTextInputBytes = std::size_t{64} << 20;
//! YAML/JSON configurations (scene, scanner, rig, regions): 2 MiB; their parser holds ~140
//! bytes per byte of text (a 5 MB scene took 700 MB).
inline constexpr std::size_t kMaxConfigFileBytes = std::size_t{2} << 20;
std::vector<std::uint8_t> read_file_bytes(const std::filesystem::path& path,
                                          std::size_t max_bytes = kMaxInputFileBytes);

}  // namespace scanmesh
