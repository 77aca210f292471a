// Point-cloud readers: XYZ and PCD (ASCII, binary, binary_compressed, organised) parse valid
// input with its attributes and reject malformed files, naming them.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <limits>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/range_grid.h"
#include "scanmesh/core/point_cloud_io.h"
#include "scanmesh_test_paths.h"

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
      parse_xyz("# header\n1 2 3 0 0 1\n\n4,5,6,0,1,0\n-1e-3 +2 3.5 1 1 1 # c\n", "cloud.xyz")
          .positions;
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
  const auto pts = parse_pcd(kAsciiPcd, "a.pcd").positions;
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
  const auto pts = parse_pcd(s, "b.pcd").positions;
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
  std::string compressed = s;  // ASCII text is no LZF stream with sizes
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
  const auto pts = read_point_cloud(path).positions;
  ASSERT_EQ(pts.size(), static_cast<std::size_t>(valid));
  EXPECT_TRUE(pts[0].isApprox(grid.cartesian(1, 0)));
}

}  // namespace
}  // namespace scanmesh

namespace scanmesh {
namespace {

// PCL itself writes the files (the anchor of the format): binary_compressed with colours and
// normals, and an organised cloud with NaN holes.
pcl::PointCloud<pcl::PointXYZRGBNormal> pcl_cloud(int width, int height) {
  pcl::PointCloud<pcl::PointXYZRGBNormal> c;
  c.width = width;
  c.height = height;
  c.is_dense = false;
  c.resize(static_cast<std::size_t>(width) * height);
  for (int k = 0; k < width * height; ++k) {
    auto& p = c[k];
    p.x = 0.5f * k;
    p.y = 1.0f - 0.25f * k;
    p.z = 3.0f + k;
    p.r = static_cast<std::uint8_t>(10 * k);
    p.g = 200;
    p.b = static_cast<std::uint8_t>(255 - k);
    p.normal_x = 0;
    p.normal_y = 0;
    p.normal_z = 1;
  }
  return c;
}

TEST(PcdReader, ReadsPclBinaryCompressedWithColoursAndNormals) {
  const auto path = std::filesystem::path(SCANMESH_BINARY_DIR) / "t_compressed.pcd";
  const auto src = pcl_cloud(37, 1);
  ASSERT_EQ(pcl::io::savePCDFileBinaryCompressed(path.string(), src), 0);
  const PointCloud cloud = read_point_cloud(path);
  ASSERT_EQ(cloud.size(), 37u);
  ASSERT_TRUE(cloud.has_colors());
  ASSERT_TRUE(cloud.has_normals());
  for (int k = 0; k < 37; ++k) {
    EXPECT_EQ(cloud.positions[k], Eigen::Vector3d(src[k].x, src[k].y, src[k].z));
    EXPECT_EQ(cloud.colors[k], (Rgb8{src[k].r, src[k].g, src[k].b}));
    EXPECT_EQ(cloud.normals[k], Eigen::Vector3f(0, 0, 1));
  }
  // A corrupt LZF stream is an error naming the file, never a crash or a short cloud.
  auto bytes = read_file_bytes(path);
  std::string text(bytes.begin(), bytes.end());
  text[text.size() - 3] = static_cast<char>(0xff);
  text[text.size() - 2] = static_cast<char>(0xff);
  expect_format_error([&] { parse_pcd(text.substr(0, text.size() - 40), "lzf.pcd"); }, "lzf.pcd");
}

TEST(PcdReader, OrganisedCloudKeepsItsLatticeWithNaNHoles) {
  const auto path = std::filesystem::path(SCANMESH_BINARY_DIR) / "t_organised.pcd";
  auto src = pcl_cloud(6, 4);
  src[7].x = src[7].y = src[7].z = std::numeric_limits<float>::quiet_NaN();
  ASSERT_EQ(pcl::io::savePCDFileBinary(path.string(), src), 0);
  const PointCloud cloud = read_point_cloud(path);
  EXPECT_TRUE(cloud.organised());
  EXPECT_EQ(cloud.width, 6);
  EXPECT_EQ(cloud.height, 4);
  ASSERT_EQ(cloud.size(), 24u);
  EXPECT_FALSE(cloud.positions[7].allFinite());
  EXPECT_EQ(cloud.finite_count(), 23u);
  EXPECT_EQ(cloud.positions[8], Eigen::Vector3d(src[8].x, src[8].y, src[8].z));
  EXPECT_EQ(cloud.finite_points().size(), 23u);
}

TEST(XyzReader, ReadsColourAndNormalColumns) {
  const PointCloud c = parse_xyz("1 2 3 255 128 0 0 0 1\n4 5 6 1 2 3 1 0 0\n", "rgbn.xyz");
  ASSERT_TRUE(c.has_colors());
  ASSERT_TRUE(c.has_normals());
  EXPECT_EQ(c.colors[0], (Rgb8{255, 128, 0}));
  EXPECT_EQ(c.normals[1], Eigen::Vector3f(1, 0, 0));
  const PointCloud n = parse_xyz("1 2 3 0 0 1\n", "n.xyz");
  EXPECT_TRUE(n.has_normals());
  EXPECT_FALSE(n.has_colors());
}

}  // namespace
}  // namespace scanmesh
