// PNG bar chart of the min-angle histogram of a checked mesh.
#include <algorithm>
#include <string>

#include "scanmesh/core/image.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/reconstruction/curvature_maps.h"

namespace scanmesh {

void write_quality_histogram_png(const std::filesystem::path& path, const MeshCheckReport& report,
                                 const std::string& title) {
  const int width = 640, height = 400, left = 60, bottom = 40, top = 50;
  const Rgb8 background{255, 255, 255}, axis{0, 0, 0}, good{60, 150, 80}, bad{200, 90, 60};
  Image8 image(width, height, 3, 255);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) image.set_rgb(x, y, background);
  const auto& h = report.min_angle_histogram;
  const std::size_t peak = std::max<std::size_t>(1, *std::max_element(h.begin(), h.end()));
  const int plot_w = width - left - 20, plot_h = height - top - bottom;
  const int bar_w = plot_w / static_cast<int>(h.size());
  for (std::size_t i = 0; i < h.size(); ++i) {
    const int bar_h = static_cast<int>(static_cast<double>(h[i]) / peak * plot_h);
    const int x0 = left + static_cast<int>(i) * bar_w;
    for (int x = x0 + 2; x < x0 + bar_w - 2; ++x)
      for (int y = height - bottom - bar_h; y < height - bottom; ++y)
        image.set_rgb(x, y, i >= 6 ? good : bad);
    draw_text(image, x0 + 2, height - bottom + 8, std::to_string(i * 5), axis, 2);
  }
  for (int x = left; x < left + plot_w; ++x) image.set_rgb(x, height - bottom, axis);
  for (int y = top; y <= height - bottom; ++y) image.set_rgb(left - 1, y, axis);
  draw_text(image, left, 10, title, axis, 2);
  draw_text(image, left, 30,
            "faces " + std::to_string(report.faces) + "  max bin " + std::to_string(peak), axis, 1);
  write_png(path, image);
}

}  // namespace scanmesh
