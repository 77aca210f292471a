// Point-cloud readers: XYZ and PCD parse valid input and reject malformed files, naming them.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/range_grid.h"
#include "scanmesh/meshing/fans/point_cloud_io.h"

namespace scanmesh {
namespace {

void expect_format_error(const std::function<void()>& f, const std::string& name) {
  try {
    f();
    ADD_FAILURE() << "no FileFormatError";
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
  }
}

TEST(XyzReader, ParsesCommentsExtraColumnsAndCommas) {
  const auto pts =
      parse_xyz("# header\n1 2 3 0 0 1\n\n4,5,6,0,1,0\n-1e-3 +2 3.5 1 1 1 # c\n", "cloud.xyz");
  ASSERT_EQ(pts.size(), 3u);
  EXPECT_EQ(pts[1], Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(pts[2], Eigen::Vector3d(-1e-3, 2, 3.5));
}

TEST(XyzReader, RejectsMalformedLines) {
  expect_format_error([] { parse_xyz("1 2 3\n1 2 x\n", "bad1.xyz"); }, "bad1.xyz");
  expect_format_error([] { parse_xyz("1 2\n", "bad2.xyz"); }, "bad2.xyz");
  expect_format_error([] { parse_xyz("1 2 3\n1 2 3 4\n", "bad3.xyz"); }, "bad3.xyz");
  expect_format_error([] { parse_xyz("# nothing\n\n", "bad4.xyz"); }, "bad4.xyz");
  expect_format_error([] { parse_xyz("1 2 inf\n", "bad5.xyz"); }, "bad5.xyz");
}

const char* kAsciiPcd =
    "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\n"
    "COUNT 1 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n"
    "1 2 3 9\n4 5 6 9\nnan nan nan 0\n";

TEST(PcdReader, ParsesAsciiAndSkipsNaN) {
  const auto pts = parse_pcd(kAsciiPcd, "a.pcd");
  ASSERT_EQ(pts.size(), 2u);
  EXPECT_EQ(pts[1], Eigen::Vector3d(4, 5, 6));
}

TEST(PcdReader, ParsesBinary) {
  std::string s =
      "VERSION 0.7\nFIELDS rgb x y z\nSIZE 4 4 4 8\nTYPE U F F F\nCOUNT 1 1 1 1\nWIDTH 2\n"
      "HEIGHT 1\nPOINTS 2\nDATA binary\n";
  for (int i = 0; i < 2; ++i) {
    char rec[20];
    const std::uint32_t rgb = 0;
    const float x = 1.5f + i, y = 2.5f;
    const double z = -3.25;
    std::memcpy(rec, &rgb, 4);
    std::memcpy(rec + 4, &x, 4);
    std::memcpy(rec + 8, &y, 4);
    std::memcpy(rec + 12, &z, 8);
    s.append(rec, 20);
  }
  const auto pts = parse_pcd(s, "b.pcd");
  ASSERT_EQ(pts.size(), 2u);
  EXPECT_EQ(pts[1], Eigen::Vector3d(2.5, 2.5, -3.25));
  expect_format_error([&] { parse_pcd(s.substr(0, s.size() - 5), "trunc.pcd"); }, "trunc.pcd");
}

TEST(PcdReader, RejectsMalformedHeadersAndData) {
  std::string s = kAsciiPcd;
  expect_format_error([&] { parse_pcd(s.substr(0, s.find("DATA")), "nodata.pcd"); }, "nodata.pcd");
  std::string noz = s;
  noz.replace(noz.find("x y z"), 5, "x y w");
  expect_format_error([&] { parse_pcd(noz, "noz.pcd"); }, "noz.pcd");
  std::string short_points = s;
  short_points.replace(short_points.find("POINTS 3"), 8, "POINTS 4");
  expect_format_error([&] { parse_pcd(short_points, "count.pcd"); }, "count.pcd");
  std::string cols = s;
  cols.replace(cols.find("4 5 6 9"), 7, "4 5 6");
  expect_format_error([&] { parse_pcd(cols, "cols.pcd"); }, "cols.pcd");
  std::string compressed = s;
  compressed.replace(compressed.find("DATA ascii"), 10, "DATA binary_compressed");
  expect_format_error([&] { parse_pcd(compressed, "comp.pcd"); }, "comp.pcd");
  std::string word = s;
  word.replace(word.find("4 5 6 9"), 7, "4 five 6 9");
  expect_format_error([&] { parse_pcd(word, "word.pcd"); }, "word.pcd");
}

TEST(PointCloudFile, DispatchesOnExtension) {
  const auto dir = std::filesystem::path(SCANMESH_BINARY_DIR);
  {
    std::ofstream(dir / "t_cloud.xyz") << "0 0 0\n1 0 0\n0 1 0\n";
    std::ofstream(dir / "t_cloud.pcd") << kAsciiPcd;
  }
  EXPECT_EQ(read_point_cloud(dir / "t_cloud.xyz").size(), 3u);
  EXPECT_EQ(read_point_cloud(dir / "t_cloud.pcd").size(), 2u);
  EXPECT_THROW(read_point_cloud(dir / "t_cloud.abc"), InvalidInputError);
  EXPECT_THROW(read_point_cloud(dir / "does_not_exist.xyz"), Error);
}

TEST(PointCloudFile, GridGivesItsValidCells) {
  RangeGrid grid(16, 8, 0.0, 0.0, 1.0);
  int valid = 0;
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 16; ++i)
      if ((i + j) % 3 != 0) {
        grid.set_sample(i, j, 50.0f + static_cast<float>(i));
        ++valid;
      }
  const auto path = std::filesystem::path(SCANMESH_BINARY_DIR) / "t_cloud.smg";
  write_grid(path, grid);
  const auto pts = read_point_cloud(path);
  ASSERT_EQ(pts.size(), static_cast<std::size_t>(valid));
  EXPECT_TRUE(pts[0].isApprox(grid.cartesian(1, 0)));
}

}  // namespace
}  // namespace scanmesh
