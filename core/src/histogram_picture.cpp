#include "scanmesh/core/histogram_picture.h"

#include <algorithm>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/image_text.h"

namespace scanmesh {

Image8 histogram_picture(std::span<const std::size_t> counts,
                         const std::vector<std::string>& bin_labels, const std::string& title,
                         GoodBins good) {
  if (counts.empty() || bin_labels.size() != counts.size())
    throw InvalidInputError("histogram '" + title + "': " + std::to_string(counts.size()) +
                            " bins and " + std::to_string(bin_labels.size()) + " labels");
  const int width = 640, height = 400, left = 60, bottom = 40, top = 50;
  const Rgb8 axis{0, 0, 0}, good_colour{60, 150, 80}, bad_colour{200, 90, 60};
  Image8 image(width, height, 3, 255);  // white
  const std::size_t peak =
      std::max<std::size_t>(1, *std::max_element(counts.begin(), counts.end()));
  std::size_t total = 0;
  for (std::size_t c : counts) total += c;
  const int plot_w = width - left - 20, plot_h = height - top - bottom;
  const int bar_w = plot_w / static_cast<int>(counts.size());
  for (std::size_t i = 0; i < counts.size(); ++i) {
    const int bar_h = static_cast<int>(static_cast<double>(counts[i]) / peak * plot_h);
    const int x0 = left + static_cast<int>(i) * bar_w;
    const bool is_good = i >= good.begin && i < good.end;
    for (int x = x0 + 2; x < x0 + bar_w - 2; ++x)
      for (int y = height - bottom - bar_h; y < height - bottom; ++y)
        image.set_rgb(x, y, is_good ? good_colour : bad_colour);
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
  return image;
}

void write_histogram_png(const std::filesystem::path& path, std::span<const std::size_t> counts,
                         const std::vector<std::string>& bin_labels, const std::string& title,
                         GoodBins good) {
  write_png(path, histogram_picture(counts, bin_labels, title, good));
}

}  // namespace scanmesh
