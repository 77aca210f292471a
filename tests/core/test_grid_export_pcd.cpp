// The one test file that includes PCL: reads the exported PCD back with PCL itself.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>

#include "scanmesh/core/grid_export.h"
#include "test_util.h"

namespace scanmesh {
namespace {

TEST(GridExportPcd, PcdIsOrganisedWithNanHolesAndExactPoints) {
  test::TempDir dir;
  RangeGrid grid(96, 64, 0.2, -30.0, 0.75);
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i) {
      if ((i + 2 * j) % 7 != 0) grid.set_sample(i, j, 80.0f + 0.3f * i - 0.1f * j);
      grid.set_color(i, j, {static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(j), 200});
    }
  export_pcd(dir / "scan.pcd", grid);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"scan.pcd"});

  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(dir.path() / "scan.pcd", cloud), 0);
  ASSERT_EQ(cloud.width, 96u);
  ASSERT_EQ(cloud.height, 64u);
  EXPECT_TRUE(cloud.isOrganized());
  EXPECT_FALSE(cloud.is_dense);
  std::size_t nan_cells = 0, exact_cells = 0;
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i) {
      const pcl::PointXYZRGB& p = cloud.at(i, j);  // (column, row)
      if (!grid.valid(i, j)) {
        nan_cells += std::isnan(p.x) && std::isnan(p.y) && std::isnan(p.z);
      } else {
        const Eigen::Vector3f q = grid.cartesian(i, j).cast<float>();
        exact_cells += p.x == q.x() && p.y == q.y() && p.z == q.z();
      }
      EXPECT_EQ(p.r, i);
      EXPECT_EQ(p.g, j);
      EXPECT_EQ(p.b, 200);
    }
  EXPECT_EQ(nan_cells, grid.cell_count() - grid.valid_count());
  EXPECT_EQ(exact_cells, grid.valid_count());
  EXPECT_EQ(grid.valid_count(), 5266u);  // 96 * 64 minus the 878 cells with (i + 2j) % 7 == 0
}

TEST(GridExportPcd, ExistingFileIsReplacedAtomically) {
  test::TempDir dir;
  test::write_raw(dir / "scan.pcd", std::string("old"));
  export_pcd(dir / "scan.pcd", RangeGrid(8, 4));
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(dir.path() / "scan.pcd", cloud), 0);
  EXPECT_EQ(cloud.size(), 32u);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"scan.pcd"});
}

}  // namespace
}  // namespace scanmesh
