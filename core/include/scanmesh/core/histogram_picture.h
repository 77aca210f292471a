// Bar charts of binned counts (quality histograms of every mesher): one picture style, labelled
// with the bitmap font of image_text.h.
#pragma once

#include <cstddef>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "scanmesh/core/image.h"

namespace scanmesh {

//! Which bins are drawn green (the rest red): [begin, end).
struct GoodBins {
  std::size_t begin = 0, end = 0;
};

//! Bar chart of `counts` with one label per bin, the title and the total above, each bar's
//! count over it (640 x 400 pixels). The font has upper case, digits and punctuation.
//! InvalidInputError if there are no bins or the labels do not match them.
Image8 histogram_picture(std::span<const std::size_t> counts,
                         const std::vector<std::string>& bin_labels, const std::string& title,
                         GoodBins good);

//! histogram_picture written as a PNG (atomically).
void write_histogram_png(const std::filesystem::path& path, std::span<const std::size_t> counts,
                         const std::vector<std::string>& bin_labels, const std::string& title,
                         GoodBins good);

}  // namespace scanmesh
