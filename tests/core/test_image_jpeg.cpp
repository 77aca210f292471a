// JPEG through libjpeg: round trips stay close to the original, grey and odd sizes decode,
// damaged and hostile streams are refused with the source named, and decode_image tells JPEG
// from PNG by the bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/image.h"

namespace scanmesh {
namespace {

// A smooth colour field: JPEG keeps it within a few grey levels at quality 95.
Image8 smooth_picture(int w, int h) {
  Image8 im(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      im.set_rgb(x, y,
                 {static_cast<std::uint8_t>(40 + 150 * x / std::max(1, w - 1)),
                  static_cast<std::uint8_t>(200 - 120 * y / std::max(1, h - 1)),
                  static_cast<std::uint8_t>(128 + 60 * std::sin(0.1 * (x + y)))});
  return im;
}

double mean_abs_difference(const Image8& a, const Image8& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) sum += std::abs(a.pixels[i] - b.pixels[i]);
  return sum / static_cast<double>(a.pixels.size());
}

TEST(ImageJpeg, RoundTripKeepsSizeAndStaysCloseToTheOriginal) {
  for (const auto& [w, h] : {std::pair{64, 48}, std::pair{33, 17}, std::pair{1, 1}}) {
    const Image8 original = smooth_picture(w, h);
    const auto bytes = encode_jpeg(original, 95);
    ASSERT_GE(bytes.size(), 4u);
    EXPECT_EQ(bytes[0], 0xff);
    EXPECT_EQ(bytes[1], 0xd8);
    EXPECT_EQ(bytes[bytes.size() - 2], 0xff);
    EXPECT_EQ(bytes[bytes.size() - 1], 0xd9);
    const Image8 back = decode_jpeg(bytes, "round trip");
    ASSERT_EQ(back.width, w);
    ASSERT_EQ(back.height, h);
    ASSERT_EQ(back.channels, 3);
    EXPECT_LT(mean_abs_difference(original, back), 3.0) << w << " x " << h;
  }
}

TEST(ImageJpeg, LowerQualityGivesFewerBytesAndLargerErrors) {
  const Image8 original = smooth_picture(96, 96);
  const auto fine = encode_jpeg(original, 95), coarse = encode_jpeg(original, 20);
  EXPECT_LT(coarse.size(), fine.size());
  EXPECT_GT(mean_abs_difference(original, decode_jpeg(coarse, "coarse")),
            mean_abs_difference(original, decode_jpeg(fine, "fine")));
}

TEST(ImageJpeg, DamagedAndHostileStreamsAreRefusedNamingTheSource) {
  const auto good = encode_jpeg(smooth_picture(32, 32), 90);
  auto expect_refused = [](const std::vector<std::uint8_t>& bytes, const std::string& what) {
    try {
      decode_jpeg(bytes, "frame-7.jpg");
      ADD_FAILURE() << what << " decoded";
    } catch (const FileFormatError& e) {
      EXPECT_NE(std::string(e.what()).find("frame-7.jpg"), std::string::npos) << e.what();
    }
  };
  expect_refused({}, "an empty stream");
  expect_refused({0x89, 'P', 'N', 'G'}, "a PNG signature");
  expect_refused(std::vector<std::uint8_t>(good.begin(), good.begin() + 20), "a cut header");
  // SOI followed by garbage: no frame header at all.
  std::vector<std::uint8_t> garbage{0xff, 0xd8};
  for (int i = 0; i < 200; ++i) garbage.push_back(static_cast<std::uint8_t>(i * 37));
  expect_refused(garbage, "garbage after SOI");
  // A frame header declaring 65000 x 65000 (12 GB of pixels) is refused before any allocation.
  auto huge = good;
  for (std::size_t i = 2; i + 8 < huge.size(); ++i)
    if (huge[i] == 0xff && huge[i + 1] == 0xc0) {  // SOF0: FF C0, length, precision, h, w
      huge[i + 5] = huge[i + 7] = 0xfd;
      huge[i + 6] = huge[i + 8] = 0xe8;
      break;
    }
  expect_refused(huge, "a 65000 x 65000 header");
}

TEST(ImageJpeg, ATruncatedScanStillDecodesToTheDeclaredSize) {
  // libjpeg fills what is missing and warns; the MJPEG frame check (EOI) is the caller's.
  const auto good = encode_jpeg(smooth_picture(64, 64), 90);
  const std::vector<std::uint8_t> cut(good.begin(), good.begin() + good.size() * 2 / 3);
  const Image8 back = decode_jpeg(cut, "cut");
  EXPECT_EQ(back.width, 64);
  EXPECT_EQ(back.height, 64);
}

TEST(ImageJpeg, DecodeImageTellsJpegFromPngByItsBytes) {
  const Image8 original = smooth_picture(20, 10);
  const Image8 from_png = decode_image(encode_png(original, "p.png"), "p.png");
  EXPECT_EQ(from_png.pixels, original.pixels);  // PNG is lossless
  const Image8 from_jpeg = decode_image(encode_jpeg(original, 95), "j.jpg");
  EXPECT_EQ(from_jpeg.width, 20);
  EXPECT_LT(mean_abs_difference(original, from_jpeg), 3.0);
  EXPECT_THROW(decode_image(std::vector<std::uint8_t>{'G', 'I', 'F', '8'}, "x.gif"),
               FileFormatError);
}

TEST(ImageJpeg, EncodeRefusesImpossibleInputs) {
  EXPECT_THROW(encode_jpeg(Image8(8, 8, 1), 90), InvalidInputError);  // grey
  EXPECT_THROW(encode_jpeg(Image8(), 90), InvalidInputError);         // empty
  EXPECT_THROW(encode_jpeg(smooth_picture(8, 8), 0), InvalidInputError);
  EXPECT_THROW(encode_jpeg(smooth_picture(8, 8), 101), InvalidInputError);
}

}  // namespace
}  // namespace scanmesh
