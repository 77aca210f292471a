// Runs the scanmesh binary of this build tree as a user would (a shell command line, stdout and
// stderr together) — shared by the command-line tests.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include "scanmesh_test_paths.h"

namespace scanmesh::test {

struct RunResult {
  int exit_code = -1;  //!< the process's exit code; -1 if it did not exit normally
  std::string output;  //!< stdout and stderr together
};

inline const std::filesystem::path& scanmesh_binary() {
  static const std::filesystem::path binary =
      std::filesystem::path(SCANMESH_BINARY_DIR) / "apps" / "scanmesh";
  return binary;
}

//! `scanmesh ARGS 2>&1`; ARGS is passed to the shell as written. `stderr_to` other than "&1"
//! sends stderr elsewhere (run_stdout: to /dev/null, for output that must be stdout alone).
inline RunResult run(const std::string& args, const std::string& stderr_to = "&1") {
  RunResult result;
  FILE* pipe = popen((scanmesh_binary().string() + " " + args + " 2>" + stderr_to).c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) result.output += buffer.data();
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

//! `scanmesh ARGS 2>/dev/null`: what a program reading stdout gets.
inline RunResult run_stdout(const std::string& args) { return run(args, "/dev/null"); }

}  // namespace scanmesh::test
