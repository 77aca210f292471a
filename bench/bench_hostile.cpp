// Worst-case inputs of issue 32 (docs/safety.md, "Findings") at growing sizes: wall time and
// peak memory of the scanmesh binary per input, and the time ratio per doubling of the input.
// A ratio near 2 is linear work, near 4 quadratic: before the fixes these rows showed 4 (or ran
// into minutes); a regression shows as a growing ratio here, never as a timed test.
//
//   ./build/bench/bench_hostile [--scale K]   (K doubles the largest size K times; default 3)
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "scanmesh_test_paths.h"

namespace fs = std::filesystem;

namespace {

const fs::path kBinary = fs::path(SCANMESH_BINARY_DIR) / "apps" / "scanmesh";
const fs::path kConfigs = fs::path(SCANMESH_SOURCE_DIR) / "configs";

struct Run {
  double seconds = 0;
  long peak_kb = 0;
  int exit_code = -1;
};

Run run_scanmesh(const std::vector<std::string>& args) {
  std::vector<std::string> storage{kBinary.string()};
  storage.insert(storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& s : storage) argv.push_back(s.data());
  argv.push_back(nullptr);
  std::fflush(stdout);  // or the child's freopen writes the parent's buffered lines again
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    if (!freopen("/dev/null", "w", stdout) || !freopen("/dev/null", "w", stderr)) _exit(126);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  Run r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.peak_kb = usage.ru_maxrss;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

void write_text(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

// About n points (a square number) on a wavy sheet, as .xyz text: the clouds the fans rows
// hide their outliers in.
std::string sheet_xyz(std::size_t n) {
  std::string s;
  const int side = static_cast<int>(std::sqrt(static_cast<double>(n)));
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j)
      s += std::to_string(i + 0.3 * std::sin(j)) + " " + std::to_string(j) + " 0\n";
  return s;
}

std::string ply_header(std::size_t vertices, std::size_t faces) {
  return "ply\nformat ascii 1.0\nelement vertex " + std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(faces) + "\nproperty list uchar int vertex_indices\nend_header\n";
}

// One worst case: writes its input of size n into `dir` and returns the command line.
struct Case {
  const char* name;
  std::size_t base;  // smallest n
  std::function<std::vector<std::string>(std::size_t n, const fs::path& dir)> make;
};

std::vector<Case> cases() {
  return {
      {"ply header: n properties", 100000,
       [](std::size_t n, const fs::path& d) {
         std::string s = "ply\nformat ascii 1.0\nelement vertex 0\n";
         for (std::size_t i = 0; i < n; ++i) s += "property float p" + std::to_string(i) + "\n";
         write_text(d / "props.ply", s + "end_header\n");
         return std::vector<std::string>{"info", (d / "props.ply").string()};
       }},
      {"ply header: n empty elements", 100000,
       [](std::size_t n, const fs::path& d) {
         std::string s = "ply\nformat ascii 1.0\n";
         for (std::size_t i = 0; i < n; ++i) s += "element e" + std::to_string(i) + " 0\n";
         write_text(d / "elems.ply", s + "end_header\n");
         return std::vector<std::string>{"info", (d / "elems.ply").string()};
       }},
      {"check: fan of n triangles", 50000,
       [](std::size_t n, const fs::path& d) {
         std::string s = ply_header(n + 1, n) + "0 0 0\n";
         for (std::size_t i = 0; i < n; ++i)
           s += std::to_string(std::cos(6.283185307 * i / n)) + " " +
                std::to_string(std::sin(6.283185307 * i / n)) + " 0\n";
         for (std::size_t i = 0; i < n; ++i)
           s += "3 0 " + std::to_string(1 + i) + " " + std::to_string(1 + (i + 1) % n) + "\n";
         write_text(d / "fan.ply", s);
         return std::vector<std::string>{"check", (d / "fan.ply").string()};
       }},
      {"check: n copies of a face", 100000,
       [](std::size_t n, const fs::path& d) {
         std::string s = ply_header(3, n) + "0 0 0\n1 0 0\n0 1 0\n";
         for (std::size_t i = 0; i < n; ++i) s += "3 0 1 2\n";
         write_text(d / "copies.ply", s);
         return std::vector<std::string>{"check", (d / "copies.ply").string()};
       }},
      {"render: n copies of a face", 100000,
       [](std::size_t n, const fs::path& d) {
         std::string s = ply_header(3, n) + "0 0 0\n1 0 0\n0 1 0\n";
         for (std::size_t i = 0; i < n; ++i) s += "3 0 1 2\n";
         write_text(d / "copies.ply", s);
         return std::vector<std::string>{"render", (d / "copies.ply").string(), "--out",
                                         (d / "copies.png").string()};
       }},
      {"fans: n copies of a point + sheet", 50000,
       [](std::size_t n, const fs::path& d) {
         std::string s = sheet_xyz(1600);  // a 40 x 40 sheet
         for (std::size_t i = 0; i < n; ++i) s += "5 5 0\n";
         write_text(d / "dup.xyz", s);
         return std::vector<std::string>{"fans", (d / "dup.xyz").string(), "--out",
                                         (d / "dup.ply").string()};
       }},
      {"fans: sheet + 3 % outliers to 1e308", 40000,
       [](std::size_t n, const fs::path& d) {
         std::string s = sheet_xyz(n);
         std::uint64_t state = 7;
         auto uniform = [&state] {
           state = state * 6364136223846793005ull + 1442695040888963407ull;
           return static_cast<double>(state >> 11) / 9007199254740992.0;
         };
         char line[96];
         for (std::size_t k = 0; k < n / 32; ++k) {
           double c[3];
           for (double& v : c) v = (uniform() < 0.5 ? -1 : 1) * std::pow(10.0, 308.0 * uniform());
           std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", c[0], c[1], c[2]);
           s += line;
         }
         write_text(d / "scatter.xyz", s);
         return std::vector<std::string>{"fans", (d / "scatter.xyz").string(), "--out",
                                         (d / "scatter.ply").string()};
       }},
      {"render: fan of n slivers", 125000,
       [](std::size_t n, const fs::path& d) {
         std::string s = ply_header(n + 1, n) + "0 0 0\n";
         for (std::size_t i = 0; i < n; ++i)
           s += std::to_string(100 * std::cos(6.283185307 * i / n)) + " " +
                std::to_string(100 * std::sin(6.283185307 * i / n)) + " 0\n";
         for (std::size_t i = 0; i < n; ++i)
           s += "3 0 " + std::to_string(1 + i) + " " + std::to_string(1 + (i + 1) % n) + "\n";
         write_text(d / "slivers.ply", s);
         return std::vector<std::string>{"render",      (d / "slivers.ply").string(),
                                         "--out",       (d / "slivers.png").string(),
                                         "--elevation", "90"};
       }},
      {"fans: sheet + outlier at 1e20", 40000,
       [](std::size_t n, const fs::path& d) {
         std::string s = sheet_xyz(n);
         s += "1e20 0 0\n";
         write_text(d / "far.xyz", s);
         return std::vector<std::string>{"fans", (d / "far.xyz").string(), "--out",
                                         (d / "far.ply").string()};
       }},
      // Animation lines on a fully scanned cylinder (made once in main): one closed polyline of
      // n points, and n/2 short open subpaths of one SVG path.
      {"regions: one polyline of n points", 10000,
       [](std::size_t n, const fs::path& d) {
         std::string pts;
         for (std::size_t i = 0; i < n; ++i) {
           const double a = 6.283185307 * static_cast<double>(i) / static_cast<double>(n);
           pts += std::to_string(1024 + 300 * std::cos(a)) + "," +
                  std::to_string(512 + 300 * std::sin(a)) + " ";
         }
         write_text(d / "long.svg", "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"2048\" "
                                    "height=\"1024\"><polygon points=\"" + pts + "\"/></svg>");
         return std::vector<std::string>{"regions", (d / "cylinder.smg").string(), "--lines",
                                         (d / "long.svg").string()};
       }},
      {"regions: n/2 subpaths of one path", 5000,
       [](std::size_t n, const fs::path& d) {
         std::string path_data;
         const std::size_t count = n / 2, per_row = 200;
         for (std::size_t i = 0; i < count; ++i) {
           const double x = 20.0 + 10.0 * static_cast<double>(i % per_row);
           const double y = 150.0 + 700.0 * static_cast<double>(i / per_row) /
                                        static_cast<double>(count / per_row + 1);
           path_data += "M " + std::to_string(x) + " " + std::to_string(y) + " L " +
                        std::to_string(x + 3) + " " + std::to_string(y) + " ";
         }
         write_text(d / "many.svg", "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"2048\" "
                                    "height=\"1024\"><path d=\"" + path_data + "\"/></svg>");
         return std::vector<std::string>{"regions", (d / "cylinder.smg").string(), "--lines",
                                         (d / "many.svg").string()};
       }},
  };
}

}  // namespace

int main(int argc, char** argv) {
  int scale = 3;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--scale") scale = std::max(1, std::atoi(argv[i + 1]));
  const fs::path dir = fs::temp_directory_path() / ("scanmesh_bench_hostile_" +
                                                    std::to_string(getpid()));
  fs::create_directories(dir);
  write_text(dir / "cylinder_scanner.yaml",
             "n_phi: 2048\nn_h: 1024\nradius_mm: 300.0\nh0_mm: 10.0\ndh_mm: 0.15\n"
             "noise_sigma_mm: 0.0\nspike_probability: 0.0\nseed: 3\n");
  if (run_scanmesh({"sim", "--scene", (kConfigs / "sim" / "cylinder.yaml").string(), "--scanner",
                    (dir / "cylinder_scanner.yaml").string(), "--out",
                    (dir / "cylinder.smg").string()})
          .exit_code != 0) {
    std::fprintf(stderr, "bench_hostile: could not simulate the cylinder grid\n");
    return 1;
  }
  // The binary's start-up (shared libraries: ~0.2 s) is measured once and taken off every time,
  // so that the ratios show the work on the input.
  const double startup = run_scanmesh({"--version"}).seconds;
  std::printf("start-up of the binary: %.3f s (subtracted below)\n", startup);
  std::printf("%-36s %9s %6s %9s %9s %10s\n", "worst case", "n", "exit", "work [s]", "peak MB",
              "time ratio");
  for (const Case& c : cases()) {
    double previous = 0;
    for (int k = 0; k <= scale; ++k) {
      const std::size_t n = c.base << k;
      const Run r = run_scanmesh(c.make(n, dir));
      const double work = std::max(0.0, r.seconds - startup);
      char ratio[32] = "-";
      if (k > 0 && previous > 0.02) std::snprintf(ratio, sizeof ratio, "%.2f", work / previous);
      std::printf("%-36s %9zu %6d %9.3f %9.1f %10s\n", c.name, n, r.exit_code, work,
                  r.peak_kb / 1024.0, ratio);
      previous = work;
    }
  }
  fs::remove_all(dir);
  std::printf(
      "time ratio: this size / half the size (2 = linear, 4 = quadratic; none below 0.02 s)\n");
  return 0;
}
