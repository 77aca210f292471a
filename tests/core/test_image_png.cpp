#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <string>
#include <vector>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/image.h"
#include "test_util.h"

namespace scanmesh {
namespace {

using test::TempDir;

Image8 pattern(int w, int h, int channels) {
  Image8 image(w, h, channels);
  for (std::size_t k = 0; k < image.pixels.size(); ++k)
    image.pixels[k] = static_cast<std::uint8_t>((k * 37 + k / 7) & 0xff);
  return image;
}

// A 16-bit grey PNG without gAMA or sRGB chunk, every sample `value`, built chunk by chunk
// (the library writes 8-bit PNGs only).
std::vector<std::uint8_t> grey16_png(int w, int h, std::uint16_t value) {
  std::vector<std::uint8_t> out{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  auto be32 = [](std::vector<std::uint8_t>& v, std::uint32_t x) {
    for (int s = 24; s >= 0; s -= 8) v.push_back(static_cast<std::uint8_t>(x >> s));
  };
  auto chunk = [&](const char* type, const std::vector<std::uint8_t>& data) {
    be32(out, static_cast<std::uint32_t>(data.size()));
    std::vector<std::uint8_t> body(type, type + 4);
    body.insert(body.end(), data.begin(), data.end());
    out.insert(out.end(), body.begin(), body.end());
    be32(out, static_cast<std::uint32_t>(crc32(0, body.data(), static_cast<uInt>(body.size()))));
  };
  std::vector<std::uint8_t> header;
  be32(header, static_cast<std::uint32_t>(w));
  be32(header, static_cast<std::uint32_t>(h));
  header.insert(header.end(), {16, 0, 0, 0, 0});  // 16 bits, grey, deflate, no filter, no interlace
  chunk("IHDR", header);
  std::vector<std::uint8_t> raw;
  for (int y = 0; y < h; ++y) {
    raw.push_back(0);  // filter: none
    for (int x = 0; x < w; ++x)
      raw.insert(raw.end(), {std::uint8_t(value >> 8), std::uint8_t(value)});
  }
  std::vector<std::uint8_t> packed(compressBound(static_cast<uLong>(raw.size())));
  uLongf size = static_cast<uLongf>(packed.size());
  compress(packed.data(), &size, raw.data(), static_cast<uLong>(raw.size()));
  packed.resize(size);
  chunk("IDAT", packed);
  chunk("IEND", {});
  return out;
}

TEST(ImagePng, SixteenBitSamplesAreScaledNotTakenForLinearLight) {
  for (const auto& [value, expected] : {std::pair{0x8000, 128}, std::pair{0xffff, 255},
                                        std::pair{0x0000, 0}, std::pair{0x4000, 64}}) {
    const Image8 image = decode_png(grey16_png(5, 3, static_cast<std::uint16_t>(value)), "g16.png");
    ASSERT_EQ(image.channels, 1);
    ASSERT_EQ(image.width, 5);
    for (std::uint8_t p : image.pixels) EXPECT_NEAR(p, expected, 1) << "sample " << value;
  }
}

TEST(ImagePng, RoundTripIsExactForGreyRgbAndRgba) {
  TempDir dir;
  for (int channels : {1, 3, 4}) {
    const Image8 image = pattern(37, 23, channels);
    const auto path = dir / ("c" + std::to_string(channels) + ".png");
    write_png(path, image);
    const Image8 back = read_png(path);
    EXPECT_EQ(back.width, 37);
    EXPECT_EQ(back.height, 23);
    EXPECT_EQ(back.channels, channels);
    EXPECT_EQ(back.pixels, image.pixels) << channels << " channels";
  }
}

TEST(ImagePng, RowZeroIsTheTopRow) {
  TempDir dir;
  Image8 image(2, 2, 3, 0);
  image.set_rgb(1, 0, {255, 0, 0});  // top right
  write_png(dir / "corner.png", image);
  const Image8 back = read_png(dir / "corner.png");
  EXPECT_EQ(back.rgb(1, 0), (Rgb8{255, 0, 0}));
  EXPECT_EQ(back.rgb(1, 1), (Rgb8{0, 0, 0}));
  EXPECT_EQ(back.pixels[3], 255);  // byte 3 = pixel (1, 0) red: row-major from the top
}

TEST(ImagePng, GarbageIsAFileFormatErrorNamingTheFile) {
  TempDir dir;
  test::write_raw(dir / "fake.png", std::string("\x89PNG\r\n\x1a\n but not really a png"));
  try {
    read_png(dir / "fake.png");
    FAIL() << "no exception";
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("fake.png"), std::string::npos) << e.what();
  }
  // A valid PNG cut in half.
  write_png(dir / "whole.png", pattern(64, 64, 3));
  std::vector<std::uint8_t> bytes = read_file_bytes(dir / "whole.png");
  bytes.resize(bytes.size() / 2);
  test::write_raw(dir / "half.png", bytes);
  EXPECT_THROW(read_png(dir / "half.png"), FileFormatError);
}

TEST(ImagePng, InvalidImagesAreRejectedBeforeWriting) {
  TempDir dir;
  Image8 image(4, 4, 3);
  image.pixels.pop_back();
  EXPECT_THROW(write_png(dir / "bad.png", image), InvalidInputError);
  EXPECT_THROW(Image8(4, 4, 2), InvalidInputError);
  EXPECT_TRUE(dir.entries().empty());
}

}  // namespace
}  // namespace scanmesh
