// Runs the scanmesh binary of this build tree as a user would (a shell command line, stdout and
// stderr together) — shared by the command-line tests.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

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

//! `scanmesh ARGS 2>&1`; ARGS is passed to the shell as written.
inline RunResult run(const std::string& args) {
  RunResult result;
  FILE* pipe = popen((scanmesh_binary().string() + " " + args + " 2>&1").c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) result.output += buffer.data();
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

}  // namespace scanmesh::test
