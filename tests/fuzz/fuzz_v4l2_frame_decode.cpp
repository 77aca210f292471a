// libFuzzer entry point: the frame decoder of the V4L2 backend (YUYV, RGB24, MJPEG via libjpeg).
// Byte 0 picks the format, bytes 1-2 the size (width = 2 * (1 + b1 % 64), height = 1 + b2 % 64),
// the rest is the payload as a camera would deliver it.
#include <cstddef>
#include <cstdint>
#include <span>

#include "scanmesh/core/errors.h"
#include "scanmesh/drivers/camera.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return 0;
  using scanmesh::drivers::PixelFormat;
  const PixelFormat formats[] = {PixelFormat::Yuyv, PixelFormat::Rgb24, PixelFormat::Mjpeg};
  const PixelFormat format = formats[data[0] % 3];
  const int width = 2 * (1 + data[1] % 64), height = 1 + data[2] % 64;
  try {
    (void)scanmesh::drivers::decode_frame(format, std::span(data + 3, size - 3), width, height);
  } catch (const scanmesh::Error&) {
  }
  return 0;
}
