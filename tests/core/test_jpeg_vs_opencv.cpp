// core's libjpeg codec against OpenCV's imgcodecs, which the MJPEG path used before: the same
// JPEG bytes from the encoder and the same pixels from the decoder, so recorded sessions,
// simulated frames and their tests are unchanged. Its own executable: only it loads imgcodecs
// (and the ~120 libraries behind it).
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "scanmesh/core/image.h"

namespace scanmesh {
namespace {

// Noise over a gradient: every 8 x 8 block and both chroma planes carry detail.
Image8 test_picture(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> noise(-40, 40);
  Image8 im(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      auto c = [&](int base) {
        return static_cast<std::uint8_t>(std::clamp(base + noise(rng), 0, 255));
      };
      im.set_rgb(x, y, {c(255 * x / w), c(255 * y / h), c(128)});
    }
  return im;
}

cv::Mat as_bgr(const Image8& rgb) {
  const cv::Mat view(rgb.height, rgb.width, CV_8UC3, const_cast<std::uint8_t*>(rgb.pixels.data()));
  cv::Mat bgr;
  cv::cvtColor(view, bgr, cv::COLOR_RGB2BGR);
  return bgr;
}

Image8 opencv_decode(const std::vector<std::uint8_t>& bytes, int flags = cv::IMREAD_COLOR) {
  const cv::Mat bgr = cv::imdecode(bytes, flags);
  Image8 out(bgr.cols, bgr.rows, 3);
  cv::Mat rgb(bgr.rows, bgr.cols, CV_8UC3, out.pixels.data());
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return out;
}

TEST(JpegVsOpenCv, EncoderWritesOpenCvsBytes) {
  for (const int quality : {10, 50, 85, 90, 95, 100})
    for (const auto& [w, h] : {std::pair{640, 480}, std::pair{33, 17}}) {
      const Image8 im = test_picture(w, h, static_cast<unsigned>(quality));
      std::vector<std::uint8_t> theirs;
      ASSERT_TRUE(cv::imencode(".jpg", as_bgr(im), theirs, {cv::IMWRITE_JPEG_QUALITY, quality}));
      EXPECT_EQ(encode_jpeg(im, quality), theirs) << "quality " << quality << ", " << w << "x" << h;
    }
}

TEST(JpegVsOpenCv, DecoderGivesOpenCvsPixels) {
  std::vector<std::vector<std::uint8_t>> streams;
  for (const int quality : {30, 90}) {
    const Image8 im = test_picture(161, 99, 7);
    streams.push_back(encode_jpeg(im, quality));
    std::vector<std::uint8_t> progressive, grey, optimized;
    cv::imencode(".jpg", as_bgr(im), progressive,
                 {cv::IMWRITE_JPEG_QUALITY, quality, cv::IMWRITE_JPEG_PROGRESSIVE, 1});
    cv::Mat g;
    cv::cvtColor(as_bgr(im), g, cv::COLOR_BGR2GRAY);
    cv::imencode(".jpg", g, grey, {cv::IMWRITE_JPEG_QUALITY, quality});
    cv::imencode(".jpg", as_bgr(im), optimized,
                 {cv::IMWRITE_JPEG_QUALITY, quality, cv::IMWRITE_JPEG_OPTIMIZE, 1});
    streams.insert(streams.end(), {progressive, grey, optimized});
  }
  for (std::size_t i = 0; i < streams.size(); ++i) {
    const Image8 ours = decode_jpeg(streams[i], "stream");
    const Image8 theirs = opencv_decode(streams[i]);
    ASSERT_EQ(ours.width, theirs.width) << "stream " << i;
    ASSERT_EQ(ours.height, theirs.height) << "stream " << i;
    EXPECT_EQ(ours.pixels, theirs.pixels) << "stream " << i;
  }
}

}  // namespace
}  // namespace scanmesh
