#include <gtest/gtest.h>

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
