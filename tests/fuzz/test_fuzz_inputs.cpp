// Every seed input (tests/fuzz/corpus/<name>/) and every saved crash input
// (tests/fuzz/regressions/<name>/) goes through its fuzz entry point in the ordinary test build,
// so a crash found by the fuzzer once stays fixed and the normal (and sanitizer) suite exercises
// every parser on hostile bytes. One test per file; a test fails if the entry point crashes,
// throws anything but scanmesh::Error (the entry points catch those) or returns non-zero.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <ostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "fuzz_registry.h"
#include "scanmesh_test_paths.h"

namespace scanmesh::fuzz {
namespace {

namespace fs = std::filesystem;

const fs::path kFuzzDir = fs::path(SCANMESH_SOURCE_DIR) / "tests" / "fuzz";

struct Input {
  std::size_t entry = 0;
  std::string kind;  // "corpus" or "regressions"
  fs::path file;
};

// Shown by GoogleTest when a test fails.
void PrintTo(const Input& in, std::ostream* os) { *os << in.file.string(); }

std::vector<Input> collect_inputs() {
  std::vector<Input> inputs;
  const auto& all = entries();
  for (std::size_t e = 0; e < all.size(); ++e)
    for (const char* kind : {"corpus", "regressions"}) {
      const fs::path dir = kFuzzDir / kind / all[e].name;
      if (!fs::is_directory(dir)) continue;
      std::vector<fs::path> files;
      for (const auto& f : fs::directory_iterator(dir))
        if (f.is_regular_file()) files.push_back(f.path());
      std::sort(files.begin(), files.end());
      for (const fs::path& f : files) inputs.push_back({e, kind, f});
    }
  return inputs;
}

std::string test_name(const Input& in) {
  std::string n = entries()[in.entry].name + "_" + in.kind + "_" + in.file.filename().string();
  for (char& c : n)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return n;
}

std::vector<std::uint8_t> read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class FuzzInput : public ::testing::TestWithParam<Input> {};

TEST_P(FuzzInput, ParsesOrRejectsCleanly) {
  const Input& in = GetParam();
  const Entry& entry = entries()[in.entry];
  static std::set<std::string> initialised;
  if (entry.initialize && initialised.insert(entry.name).second) {
    int argc = 1;
    char arg0[] = "test_fuzz_inputs";
    char* argv_storage[] = {arg0, nullptr};
    char** argv = argv_storage;
    entry.initialize(&argc, &argv);
  }
  const std::vector<std::uint8_t> bytes = read_all(in.file);
  // An exactly sized heap copy, so AddressSanitizer sees any read past the end.
  const std::unique_ptr<std::uint8_t[]> data(
      new std::uint8_t[std::max<std::size_t>(bytes.size(), 1)]);
  std::copy(bytes.begin(), bytes.end(), data.get());
  EXPECT_EQ(entry.test_one_input(data.get(), bytes.size()), 0) << in.file;
}

INSTANTIATE_TEST_SUITE_P(Inputs, FuzzInput, ::testing::ValuesIn(collect_inputs()),
                         [](const ::testing::TestParamInfo<Input>& param_info) {
                           return test_name(param_info.param);
                         });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(FuzzInput);

TEST(FuzzCorpus, EveryEntryPointHasSeeds) {
  for (const Entry& e : entries()) {
    const fs::path dir = kFuzzDir / "corpus" / e.name;
    std::size_t n = 0;
    if (fs::is_directory(dir))
      for (const auto& f : fs::directory_iterator(dir)) n += f.is_regular_file() ? 1 : 0;
    EXPECT_GE(n, 1u) << "fuzz_" << e.name << ".cpp has no seed files in " << dir;
  }
}

TEST(FuzzCorpus, EveryInputFolderHasAnEntryPoint) {
  std::set<std::string> names;
  for (const Entry& e : entries()) names.insert(e.name);
  for (const char* kind : {"corpus", "regressions"}) {
    if (!fs::is_directory(kFuzzDir / kind)) continue;
    for (const auto& d : fs::directory_iterator(kFuzzDir / kind))
      if (d.is_directory()) {
        EXPECT_TRUE(names.count(d.path().filename().string()))
            << d.path() << " has no tests/fuzz/fuzz_" << d.path().filename().string() << ".cpp";
      }
  }
}

// CI fuzzes in replay mode with a fixed number of inputs per target from ci-runs.txt
// (scripts/fuzz); a target without a line would silently fall back to a default budget.
TEST(FuzzCorpus, EveryEntryPointHasAReplayBudget) {
  std::ifstream table(kFuzzDir / "ci-runs.txt");
  ASSERT_TRUE(table) << "missing " << kFuzzDir / "ci-runs.txt";
  std::map<std::string, long> runs;
  for (std::string line; std::getline(table, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string name;
    long n = 0;
    ASSERT_TRUE(fields >> name >> n) << "bad line in ci-runs.txt: " << line;
    runs[name] = n;
  }
  for (const Entry& e : entries()) {
    ASSERT_TRUE(runs.count(e.name)) << "fuzz_" << e.name << ".cpp has no line in ci-runs.txt";
    EXPECT_GE(runs[e.name], 10000) << e.name;
  }
}

}  // namespace
}  // namespace scanmesh::fuzz
