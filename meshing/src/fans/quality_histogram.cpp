// PNG bar charts of mesh quality histograms: the min angle of a checked mesh, and any binned
// count (the animation mesh's radius ratio q).
#include <algorithm>
#include <string>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/image.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/reconstruction/curvature_maps.h"

namespace scanmesh {

void write_histogram_png(const std::filesystem::path& path, std::span<const std::size_t> counts,
                         const std::vector<std::string>& bin_labels, const std::string& title,
                         std::size_t first_good_bin) {
  if (counts.empty() || bin_labels.size() != counts.size())
    throw InvalidInputError("histogram '" + title + "': " + std::to_string(counts.size()) +
                            " bins and " + std::to_string(bin_labels.size()) + " labels");
  const int width = 640, height = 400, left = 60, bottom = 40, top = 50;
  const Rgb8 background{255, 255, 255}, axis{0, 0, 0}, good{60, 150, 80}, bad{200, 90, 60};
  Image8 image(width, height, 3, 255);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) image.set_rgb(x, y, background);
  const std::size_t peak =
      std::max<std::size_t>(1, *std::max_element(counts.begin(), counts.end()));
  std::size_t total = 0;
  for (std::size_t c : counts) total += c;
  const int plot_w = width - left - 20, plot_h = height - top - bottom;
  const int bar_w = plot_w / static_cast<int>(counts.size());
  for (std::size_t i = 0; i < counts.size(); ++i) {
    const int bar_h = static_cast<int>(static_cast<double>(counts[i]) / peak * plot_h);
    const int x0 = left + static_cast<int>(i) * bar_w;
    for (int x = x0 + 2; x < x0 + bar_w - 2; ++x)
      for (int y = height - bottom - bar_h; y < height - bottom; ++y)
        image.set_rgb(x, y, i >= first_good_bin ? good : bad);
    draw_text(image, x0 + 2, height - bottom + 8, bin_labels[i], axis, 2);
    // The count above its bar: the small bins, the ones that matter, are a few pixels high.
    if (counts[i] > 0)
      draw_text(image, x0 + 2, height - bottom - bar_h - 10, std::to_string(counts[i]), axis, 1);
  }
  for (int x = left; x < left + plot_w; ++x) image.set_rgb(x, height - bottom, axis);
  for (int y = top; y <= height - bottom; ++y) image.set_rgb(left - 1, y, axis);
  draw_text(image, left, 10, title, axis, 2);
  draw_text(image, left, 30,
            "TRIANGLES " + std::to_string(total) + "  LARGEST BIN " + std::to_string(peak), axis,
            1);
  write_png(path, image);
}

void write_quality_histogram_png(const std::filesystem::path& path, const MeshCheckReport& report,
                                 const std::string& title) {
  const auto& h = report.min_angle_histogram;
  std::vector<std::string> labels;
  for (std::size_t i = 0; i < h.size(); ++i) labels.push_back(std::to_string(i * 5));
  // Bins from 30 deg on are drawn as good: the animation meshes' goal (seed 000, issue 4).
  write_histogram_png(path, std::span<const std::size_t>(h.data(), h.size()), labels, title, 6);
}

}  // namespace scanmesh
