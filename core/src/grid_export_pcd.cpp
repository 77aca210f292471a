// PCD export: the only translation unit of scanmesh that includes PCL headers (they are heavy;
// keeping them here keeps the rest of core fast to compile). docs/formats.md, "Exports".
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cerrno>
#include <exception>
#include <limits>
#include <string>
#include <system_error>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_export.h"

namespace scanmesh {

void export_pcd(const std::filesystem::path& path, const RangeGrid& grid) {
  pcl::PointCloud<pcl::PointXYZRGB> cloud;
  cloud.width = static_cast<std::uint32_t>(grid.n_phi());
  cloud.height = static_cast<std::uint32_t>(grid.n_h());
  cloud.is_dense = false;
  cloud.points.resize(grid.cell_count());
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  for (int j = 0; j < grid.n_h(); ++j)
    for (int i = 0; i < grid.n_phi(); ++i) {
      // Organised cloud: point (column i, row j) is points[j * width + i] = RangeGrid::index.
      pcl::PointXYZRGB& q = cloud.points[grid.index(i, j)];
      if (grid.valid(i, j)) {
        const Eigen::Vector3d p = grid.cartesian(i, j);
        q.x = static_cast<float>(p.x());
        q.y = static_cast<float>(p.y());
        q.z = static_cast<float>(p.z());
      } else {
        q.x = q.y = q.z = kNaN;
      }
      const Rgb8 c = grid.color(i, j);
      q.r = c.r;
      q.g = c.g;
      q.b = c.b;
      q.a = 255;
    }

  // PCL writes to a path itself, so the atomic write is done in two halves: PCL fills a
  // temporary file beside the target, then it is fsynced and renamed over the target.
  const std::filesystem::path tmp = temporary_path_beside(path);
  std::string reason;
  try {
    // PCL prints its own failure line to stderr; scanmesh's one message below says it all.
    const auto verbosity = pcl::console::getVerbosityLevel();
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
    const int rc = pcl::io::savePCDFileBinary(tmp.string(), cloud);
    pcl::console::setVerbosityLevel(verbosity);
    if (rc != 0) reason = "PCL could not write it";
  } catch (const std::exception& e) {
    reason = e.what();
  }
  if (!reason.empty()) {
    const bool dir_missing = !std::filesystem::is_directory(
        path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path());
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    // PCL reports no errno; say what it said and what usually causes it.
    throw IoError("cannot write '" + path.string() + "': " +
                  (dir_missing ? std::string("No such file or directory")
                               : "the PCD writer failed (" + reason +
                                     "); check free disk space, quotas and file size limits"));
  }
  commit_temporary_file(tmp, path);
}

}  // namespace scanmesh
