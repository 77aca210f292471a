// Every output file goes through core/atomic_file.h (write_file_atomically, or
// temporary_path_beside + commit_temporary_file for writers that need a path). This test reads the
// library and CLI sources and fails on any other way of creating or writing a file, so a new
// writer cannot silently bypass the atomic path. A line that must write directly (an append-only
// journal, say) carries the marker comment `non-atomic:` with its reason.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>
#include "scanmesh_test_paths.h"

namespace {

namespace fs = std::filesystem;

TEST(AtomicWriters, NoSourceWritesFilesAroundAtomicFile) {
  const fs::path root(SCANMESH_SOURCE_DIR);
  // Calls that create or write files by themselves.
  const std::regex direct_write(
      R"((std::)?ofstream|std::fstream|\bfopen\s*\(|\bcreat\s*\(|O_WRONLY|O_RDWR|O_CREAT|)"
      R"(cv::imwrite|imwrite\s*\(|pcl::io::save\w*\s*\(|\bsavePCDFile\w*\s*\(|png_image_write_to_file)");
  std::vector<std::string> offenders;
  std::size_t files = 0;
  for (const char* module :
       {"core", "sim", "drivers", "acquisition", "reconstruction", "meshing", "apps"}) {
    if (!fs::is_directory(root / module)) continue;
    for (const auto& e : fs::recursive_directory_iterator(root / module)) {
      const fs::path& p = e.path();
      if (!e.is_regular_file() || (p.extension() != ".cpp" && p.extension() != ".h")) continue;
      if (p.filename() == "atomic_file.cpp") continue;  // the one place allowed
      ++files;
      std::ifstream in(p);
      std::string line;
      for (int n = 1; std::getline(in, line); ++n) {
        const std::string code = line.substr(0, line.find("//"));
        if (!std::regex_search(code, direct_write)) continue;
        if (line.find("non-atomic:") != std::string::npos) continue;
        // PCL's writer, given a temporary path beside the target and committed afterwards.
        if (line.find("savePCDFileBinary(tmp") != std::string::npos) continue;
        offenders.push_back(fs::relative(p, root).string() + ":" + std::to_string(n) + ": " + line);
      }
    }
  }
  EXPECT_GT(files, 20u) << "no sources found under " << root;
  std::string list;
  for (const auto& o : offenders) list += "\n  " + o;
  EXPECT_TRUE(offenders.empty())
      << "writes that bypass core/atomic_file.h (use write_file_atomically, or mark the line "
         "'non-atomic: <reason>'):"
      << list;
}

}  // namespace
