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

//! Reads a whole file. Throws IoError if it cannot be opened or read.
std::vector<std::uint8_t> read_file_bytes(const std::filesystem::path& path);

}  // namespace scanmesh
