#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <csignal>
#include <stdexcept>
#include <string>
#include <vector>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_export.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/image.h"
#include "scanmesh/core/mesh_io.h"
#include "test_util.h"

namespace scanmesh {
namespace {

using test::read_text;
using test::TempDir;

TEST(AtomicFile, WriteReplacesContentAndLeavesNoTempFiles) {
  TempDir dir;
  const auto path = dir / "out.txt";
  write_file_atomically(path, std::string_view("first"));
  write_file_atomically(path, std::string_view("second version"));
  EXPECT_EQ(read_text(path), "second version");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
  const std::vector<std::uint8_t> bytes = read_file_bytes(path);
  EXPECT_EQ(bytes.size(), 14u);
}

// A set of outputs appears together or not at all: a failure before commit() (here a thrown
// error after the first file) leaves the earlier run's files as they were and no temporary
// files; commit() puts every new file in place.
TEST(StagedFiles, AllOrNothing) {
  TempDir dir;
  write_file_atomically(dir / "mesh.ply", std::string_view("old mesh"));
  write_file_atomically(dir / "report.json", std::string_view("old report"));
  try {
    StagedFiles outputs;
    write_file_atomically(outputs.stage(dir / "mesh.ply"), std::string_view("new mesh"));
    throw IoError("disk full while writing the report");
  } catch (const IoError&) {
  }
  EXPECT_EQ(read_text(dir / "mesh.ply"), "old mesh");
  EXPECT_EQ(read_text(dir / "report.json"), "old report");
  const auto sorted_entries = [&] {
    std::vector<std::string> e = dir.entries();
    std::sort(e.begin(), e.end());
    return e;
  };
  EXPECT_EQ(sorted_entries(), (std::vector<std::string>{"mesh.ply", "report.json"}));
  {
    StagedFiles outputs;
    write_file_atomically(outputs.stage(dir / "mesh.ply"), std::string_view("new mesh"));
    write_file_atomically(outputs.stage(dir / "report.json"), std::string_view("new report"));
    write_file_atomically(outputs.stage(dir / "render.png"), std::string_view("picture"));
    EXPECT_EQ(read_text(dir / "mesh.ply"), "old mesh");  // nothing in place before commit
    outputs.commit();
  }
  EXPECT_EQ(read_text(dir / "mesh.ply"), "new mesh");
  EXPECT_EQ(read_text(dir / "report.json"), "new report");
  EXPECT_EQ(sorted_entries(), (std::vector<std::string>{"mesh.ply", "render.png", "report.json"}));
}

TEST(AtomicFile, StreamingWriterIsWrittenOnlyWhenComplete) {
  TempDir dir;
  const auto path = dir / "stream.bin";
  write_file_atomically(path, [](std::ostream& out) { out << "abc" << 42; });
  EXPECT_EQ(read_text(path), "abc42");
}

TEST(AtomicFile, ThrowingWriterLeavesOldFileIntactAndNoTempFiles) {
  TempDir dir;
  const auto path = dir / "keep.txt";
  write_file_atomically(path, std::string_view("old content"));
  EXPECT_THROW(write_file_atomically(path,
                                     [](std::ostream& out) {
                                       out << "half of the new";
                                       throw std::runtime_error("writer failed midway");
                                     }),
               std::runtime_error);
  EXPECT_EQ(read_text(path), "old content");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"keep.txt"});
}

// A file-size limit makes write() fail with EFBIG part way through, like a full disk does with
// ENOSPC: the error must name the file and the OS reason, and nothing may be left behind.
TEST(AtomicFile, FailingWriteThrowsIoErrorAndKeepsOldFile) {
  TempDir dir;
  const auto path = dir / "big.bin";
  write_file_atomically(path, std::string_view("old"));

  struct LimitGuard {
    rlimit saved{};
    void (*old_handler)(int);
    LimitGuard() : old_handler(std::signal(SIGXFSZ, SIG_IGN)) {
      getrlimit(RLIMIT_FSIZE, &saved);
      rlimit small = saved;
      small.rlim_cur = 4096;
      setrlimit(RLIMIT_FSIZE, &small);
    }
    ~LimitGuard() {
      setrlimit(RLIMIT_FSIZE, &saved);
      std::signal(SIGXFSZ, old_handler);
    }
  };
  const std::vector<std::uint8_t> bytes(1 << 20, 0xab);
  std::string message;
  {
    LimitGuard limit;
    try {
      write_file_atomically(path, std::span<const std::uint8_t>(bytes));
    } catch (const IoError& e) {
      message = e.what();
    }
  }
  EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  EXPECT_NE(message.find("File too large"), std::string::npos) << message;
  EXPECT_EQ(read_text(path), "old");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"big.bin"});
}

TEST(AtomicFile, NonexistentDirectoryGivesIoErrorNamingThePath) {
  TempDir dir;
  const auto path = dir / "no_such_dir" / "out.bin";
  try {
    write_file_atomically(path, std::string_view("x"));
    FAIL() << "no exception";
  } catch (const IoError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(path.string()), std::string::npos) << m;
    EXPECT_NE(m.find("No such file or directory"), std::string::npos) << m;
  }
  // Every writer goes through the same path and reports the same way.
  const RangeGrid grid(8, 4);
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  const auto expect_io_error = [&](const std::function<void()>& f, const char* what) {
    try {
      f();
      ADD_FAILURE() << what << ": no exception";
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(path.parent_path().string()), std::string::npos)
          << what << ": " << e.what();
    }
  };
  expect_io_error([&] { write_grid(path, grid); }, "write_grid");
  expect_io_error([&] { export_pcd(path, grid); }, "export_pcd");
  expect_io_error([&] { export_ply_points(path, grid); }, "export_ply_points");
  expect_io_error([&] { export_texture_png(path, grid); }, "export_texture_png");
  expect_io_error([&] { write_ply(path, mesh); }, "write_ply");
  expect_io_error([&] { write_obj(path, mesh, "t.png"); }, "write_obj");
  expect_io_error([&] { write_stl(path, mesh); }, "write_stl");
  EXPECT_FALSE(std::filesystem::exists(path.parent_path()));
}

TEST(AtomicFile, ReadingAMissingFileGivesIoError) {
  TempDir dir;
  EXPECT_THROW(read_file_bytes(dir / "missing.bin"), IoError);
  EXPECT_THROW(read_grid(dir / "missing.smg"), IoError);
  EXPECT_THROW(read_ply(dir / "missing.ply"), IoError);
  EXPECT_THROW(read_png(dir / "missing.png"), IoError);
}

}  // namespace
}  // namespace scanmesh
