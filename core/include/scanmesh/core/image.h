// 8/16-bit raster images, PNG I/O (libpng) and JPEG (libjpeg). Pictures for people: textures,
// depth maps, renders, curvature maps; JPEG for camera frames (MJPEG) and textures.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "scanmesh/core/color.h"

namespace scanmesh {

//! Row-major 8-bit image, row 0 at the top, `channels` = 1 (grey), 3 (RGB) or 4 (RGBA).
struct Image8 {
  int width = 0, height = 0, channels = 3;
  std::vector<std::uint8_t> pixels;

  Image8() = default;
  Image8(int w, int h, int c, std::uint8_t fill = 0);
  std::uint8_t* at(int x, int y) {
    return &pixels[(static_cast<std::size_t>(y) * width + x) * channels];
  }
  const std::uint8_t* at(int x, int y) const {
    return &pixels[(static_cast<std::size_t>(y) * width + x) * channels];
  }
  void set_rgb(int x, int y, Rgb8 c);
  Rgb8 rgb(int x, int y) const;
};

//! Turns the image upside down (row 0 becomes the last row).
void flip_rows(Image8& image);

//! The PNG file bytes of an 8-bit image (grey, RGB or RGBA); `name` names it in errors.
//! Throws InvalidInputError for an invalid image, IoError when libpng fails.
std::vector<std::uint8_t> encode_png(const Image8& image, const std::filesystem::path& name);
//! Writes an 8-bit PNG atomically. Throws IoError on failure.
void write_png(const std::filesystem::path& path, const Image8& image);
//! Reads an 8-bit grey/RGB/RGBA PNG (16-bit and palette images are converted to 8-bit).
//! Throws FileFormatError for anything that is not a readable PNG.
Image8 read_png(const std::filesystem::path& path);
//! The same decoder on bytes already in memory; `source` names them in errors.
Image8 decode_png(std::span<const std::uint8_t> bytes, const std::filesystem::path& source);

//! Decodes a JPEG (baseline or progressive, grey, YCbCr or RGB) to 8-bit RGB, grey replicated.
//! Throws FileFormatError naming `source` when libjpeg cannot decode it (CMYK and YCCK are
//! refused), the header declares more than 1 GiB of RGB bytes, or the stream needs more than
//! 1 GiB of working memory or 500 scans. Data libjpeg recovers from (a truncated scan) decodes
//! silently. The EXIF orientation is not applied: pixels stay in stored order.
//! `expected_size` (width, height): a header declaring another size is refused before any
//! pixel is allocated (a camera frame must have the negotiated size).
Image8 decode_jpeg(std::span<const std::uint8_t> bytes, const std::filesystem::path& source,
                   const std::optional<std::pair<int, int>>& expected_size = std::nullopt);
//! The JPEG bytes of an RGB image at `quality` (1..100): baseline, 4:2:0, standard Huffman
//! tables, JFIF header (libjpeg's defaults, as OpenCV's encoder).
std::vector<std::uint8_t> encode_jpeg(const Image8& rgb, int quality);
//! A JPEG (by its SOI marker and the next marker's FF) or else a PNG, decoded as decode_jpeg /
//! decode_png do.
Image8 decode_image(std::span<const std::uint8_t> bytes, const std::filesystem::path& source);

}  // namespace scanmesh
