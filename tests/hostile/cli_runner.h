// Runs the scanmesh binary in a child process for the hostile-input and disk-full tests:
// captures stdout + stderr, optionally limits the size of every file it writes (RLIMIT_FSIZE with
// SIGXFSZ ignored, so a write past the limit fails with EFBIG as on a full disk), and kills it
// after a generous deadline so a hang fails the test instead of blocking the suite.
#pragma once

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <vector>
#include "scanmesh_test_paths.h"

namespace scanmesh::hostile {

namespace fs = std::filesystem;

inline const fs::path kBinary = fs::path(SCANMESH_BINARY_DIR) / "apps" / "scanmesh";
inline const fs::path kConfigs = fs::path(SCANMESH_SOURCE_DIR) / "configs";

struct RunResult {
  int exit_code = -1;  // 128 + signal when killed by a signal
  std::string output;  // stdout and stderr together
};

//! Runs `scanmesh args...`. `max_file_bytes` >= 0 limits every file the child writes; with
//! `ignore_sigxfsz` false the child keeps SIGXFSZ's default action, as a shell's `ulimit -f`
//! leaves it (the binary must then ignore it itself).
inline RunResult run_cli(const std::vector<std::string>& args, long long max_file_bytes = -1,
                         bool ignore_sigxfsz = true) {
  // Everything that allocates happens before fork (the test process may have threads).
  std::vector<std::string> storage{kBinary.string()};
  storage.insert(storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : storage) argv.push_back(s.data());
  argv.push_back(nullptr);

  int fds[2];
  RunResult result;
  if (pipe(fds) != 0) return result;
  const pid_t pid = fork();
  if (pid < 0) return result;
  if (pid == 0) {
    dup2(fds[1], STDOUT_FILENO);
    dup2(fds[1], STDERR_FILENO);
    close(fds[0]);
    close(fds[1]);
    if (max_file_bytes >= 0) {
      const rlimit limit{static_cast<rlim_t>(max_file_bytes), static_cast<rlim_t>(max_file_bytes)};
      setrlimit(RLIMIT_FSIZE, &limit);
      // Inherited across exec: writes fail with EFBIG instead of killing the process.
      signal(SIGXFSZ, ignore_sigxfsz ? SIG_IGN : SIG_DFL);
    }
    alarm(240);  // a hang is a failure (SIGALRM), not a stuck suite; far above any normal run
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(fds[1]);
  char buffer[4096];
  for (;;) {
    const ssize_t n = read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    result.output.append(buffer, static_cast<std::size_t>(n));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

inline std::string describe(const std::vector<std::string>& args, const RunResult& r) {
  std::string s = "scanmesh";
  for (const auto& a : args) s += " " + a;
  return s + "\n  exit " + std::to_string(r.exit_code) + ", output:\n" + r.output;
}

//! The per-process root of every scratch folder; removed when the test program ends.
inline fs::path scratch_root() {
  struct Root {
    fs::path path = fs::temp_directory_path() / ("scanmesh_hostile_" + std::to_string(getpid()));
    ~Root() {
      std::error_code ignored;
      fs::remove_all(path, ignored);
    }
  };
  static const Root root;
  return root.path;
}

//! A fresh, empty scratch folder for one test.
inline fs::path scratch_dir(const std::string& name) {
  const fs::path dir = scratch_root() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

//! Every file below `dir` (relative paths), including hidden temporary files.
inline std::set<std::string> files_in(const fs::path& dir) {
  std::set<std::string> names;
  if (!fs::exists(dir)) return names;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) names.insert(fs::relative(e.path(), dir).string());
  return names;
}

inline bool has_temporary_file(const fs::path& dir) {
  for (const std::string& name : files_in(dir))
    if (name.find(".tmp.") != std::string::npos) return true;
  return false;
}

inline std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

//! A small scanner (24 x 16 cells) so every CLI run in these tests takes a moment.
inline const char* kSmallScannerYaml =
    "n_phi: 24\nn_h: 16\nradius_mm: 300.0\nh0_mm: 40.0\ndh_mm: 8.0\nnoise_sigma_mm: 0.05\n"
    "spike_probability: 0.0\nband_min_mm: 0.0\nband_max_mm: 212.0\nseed: 3\n";

}  // namespace scanmesh::hostile
