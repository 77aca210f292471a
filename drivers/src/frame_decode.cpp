#include <algorithm>
#include <span>
#include <utility>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/image.h"
#include "scanmesh/drivers/camera.h"

namespace scanmesh::drivers {
namespace {

std::uint8_t clamp8(int v) { return static_cast<std::uint8_t>(std::clamp(v, 0, 255)); }

}  // namespace

std::string to_string(PixelFormat f) {
  switch (f) {
    case PixelFormat::Yuyv:
      return "yuyv";
    case PixelFormat::Mjpeg:
      return "mjpeg";
    case PixelFormat::Rgb24:
      return "rgb24";
  }
  return "?";
}

PixelFormat parse_pixel_format(const std::string& name) {
  if (name == "yuyv") return PixelFormat::Yuyv;
  if (name == "mjpeg") return PixelFormat::Mjpeg;
  if (name == "rgb24") return PixelFormat::Rgb24;
  throw InvalidInputError("unknown pixel format '" + name + "' (yuyv, mjpeg or rgb24)");
}

Image8 decode_frame(PixelFormat format, std::span<const std::uint8_t> bytes, int width, int height,
                    std::uint32_t bytes_per_line, const std::string& source) {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
    throw InvalidInputError("frame size " + std::to_string(width) + "x" + std::to_string(height) +
                            " is impossible");
  const auto w = static_cast<std::size_t>(width), h = static_cast<std::size_t>(height);
  switch (format) {
    case PixelFormat::Yuyv: {
      Image8 out(width, height, 3);
      const std::size_t stride = bytes_per_line ? bytes_per_line : w * 2;
      if (stride < w * 2 || width % 2 != 0)
        throw FileFormatError(source, "YUYV line of " + std::to_string(stride) +
                                          " bytes cannot hold " + std::to_string(width) +
                                          " pixels");
      if (bytes.size() < stride * (h - 1) + w * 2)
        throw FileFormatError(source, "YUYV frame truncated: " + std::to_string(bytes.size()) +
                                          " bytes for " + std::to_string(width) + "x" +
                                          std::to_string(height));
      // BT.601 full range ("JFIF"), integer arithmetic with 16 fractional bits.
      for (std::size_t y = 0; y < h; ++y) {
        const std::uint8_t* row = bytes.data() + y * stride;
        std::uint8_t* dst = out.pixels.data() + y * w * 3;
        for (std::size_t x = 0; x < w; x += 2) {
          const int y0 = row[x * 2], u = row[x * 2 + 1] - 128, y1 = row[x * 2 + 2],
                    v = row[x * 2 + 3] - 128;
          const int dr = (91881 * v) >> 16, dg = (-22554 * u - 46802 * v) >> 16,
                    db = (116130 * u) >> 16;
          dst[x * 3 + 0] = clamp8(y0 + dr);
          dst[x * 3 + 1] = clamp8(y0 + dg);
          dst[x * 3 + 2] = clamp8(y0 + db);
          dst[x * 3 + 3] = clamp8(y1 + dr);
          dst[x * 3 + 4] = clamp8(y1 + dg);
          dst[x * 3 + 5] = clamp8(y1 + db);
        }
      }
      return out;
    }
    case PixelFormat::Rgb24: {
      Image8 out(width, height, 3);
      const std::size_t stride = bytes_per_line ? bytes_per_line : w * 3;
      if (stride < w * 3 || bytes.size() < stride * (h - 1) + w * 3)
        throw FileFormatError(source, "RGB24 frame truncated: " + std::to_string(bytes.size()) +
                                          " bytes for " + std::to_string(width) + "x" +
                                          std::to_string(height));
      for (std::size_t y = 0; y < h; ++y)
        std::copy_n(bytes.data() + y * stride, w * 3, out.pixels.data() + y * w * 3);
      return out;
    }
    case PixelFormat::Mjpeg: {
      // A JPEG starts with SOI (FF D8) and, when complete, ends with EOI (FF D9); UVC cameras
      // may pad after EOI. SOI is checked here so that the EOI test below has four bytes and
      // the message names the frame.
      if (bytes.size() < 4 || bytes[0] != 0xff || bytes[1] != 0xd8)
        throw FileFormatError(source, "MJPEG frame does not start with a JPEG SOI marker");
      // A frame cut short by a USB error lacks EOI; libjpeg would fill the rest with grey and
      // call it a success, so the check is ours. Zero padding after EOI is allowed.
      std::size_t end = bytes.size();
      while (end > 2 && bytes[end - 1] == 0) --end;
      if (bytes[end - 2] != 0xff || bytes[end - 1] != 0xd9)
        throw FileFormatError(source, "MJPEG frame is truncated (no JPEG EOI marker)");
      // The size the JPEG header declares must be the negotiated one *before* decoding: a
      // corrupt or hostile header declaring 60000 x 60000 would otherwise make the decoder
      // allocate gigabytes (found by fuzz_v4l2_frame_decode). decode_jpeg checks it right
      // after reading the header.
      return decode_jpeg(bytes, source, std::make_pair(width, height));
    }
  }
  throw InvalidInputError("unknown pixel format");
}

}  // namespace scanmesh::drivers
