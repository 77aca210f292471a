#include "scanmesh/sim/sim_camera.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace scanmesh::sim {
namespace {

std::uint8_t clamp8(double v) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
}

std::uint32_t hash32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

}  // namespace

FrameRenderer synthetic_turntable_renderer(int width, int height) {
  if (width < 8 || height < 8 || width % 2 != 0)
    throw std::invalid_argument("synthetic renderer needs an even width >= 8 and height >= 8");
  return [width, height](double angle, unsigned mask) {
    Image8 img(width, height, 3);
    // Background: cells of 8x8 pixels whose colours scroll with the table angle.
    const int shift = static_cast<int>(std::floor(angle / (2 * std::numbers::pi) * width * 4));
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const auto cell = static_cast<std::uint32_t>(((x + shift) >> 3) * 7919 + (y >> 3));
        const std::uint32_t h = hash32(cell);
        std::uint8_t* p = img.at(x, y);
        p[0] = static_cast<std::uint8_t>(40 + (h & 63));
        p[1] = static_cast<std::uint8_t>(40 + ((h >> 8) & 63));
        p[2] = static_cast<std::uint8_t>(40 + ((h >> 16) & 63));
      }
    // Laser k: a red line, 2 px wide, left (k = 0) or right (k = 1) of the centre, its offset
    // varying with the angle as a profile would.
    for (int k = 0; k < 8; ++k) {
      if (!(mask & (1u << k))) continue;
      const double side = (k % 2 == 0) ? -1.0 : 1.0;
      const double offset = width * (0.12 + 0.08 * (1 + std::sin(angle * (k + 1))) / 2);
      for (int y = 0; y < height; ++y) {
        const double wobble = 3.0 * std::sin(y * 0.1 + angle);
        const int x0 = static_cast<int>(std::lround(width / 2.0 + side * offset + wobble));
        for (int x = x0; x < x0 + 2; ++x) {
          if (x < 0 || x >= width) continue;
          std::uint8_t* p = img.at(x, y);
          p[0] = 255;
          p[1] = clamp8(p[1] * 0.3);
          p[2] = clamp8(p[2] * 0.3);
        }
      }
    }
    return img;
  };
}

std::vector<std::uint8_t> encode_yuyv(const Image8& rgb) {
  if (rgb.channels != 3 || rgb.width % 2 != 0)
    throw std::invalid_argument("YUYV needs an RGB image of even width");
  std::vector<std::uint8_t> out(static_cast<std::size_t>(rgb.width) * rgb.height * 2);
  std::size_t o = 0;
  for (int y = 0; y < rgb.height; ++y)
    for (int x = 0; x < rgb.width; x += 2) {
      const std::uint8_t* a = rgb.at(x, y);
      const std::uint8_t* b = rgb.at(x + 1, y);
      const auto luma = [](const std::uint8_t* p) {
        return 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
      };
      const double ya = luma(a), yb = luma(b);
      const double r = (a[0] + b[0]) / 2.0, g = (a[1] + b[1]) / 2.0, bl = (a[2] + b[2]) / 2.0;
      const double ym = 0.299 * r + 0.587 * g + 0.114 * bl;
      out[o++] = clamp8(ya);
      out[o++] = clamp8(128 + 0.564 * (bl - ym));
      out[o++] = clamp8(yb);
      out[o++] = clamp8(128 + 0.713 * (r - ym));
    }
  return out;
}

SimCamera::SimCamera(FrameRenderer renderer, std::function<double()> angle_rad,
                     std::function<unsigned()> laser_mask, SimCameraOptions options)
    : renderer_(std::move(renderer)),
      angle_(std::move(angle_rad)),
      lasers_(std::move(laser_mask)),
      options_(std::move(options)) {
  if (!(options_.fps > 0)) throw std::invalid_argument("camera fps must be positive");
}

void SimCamera::start_streaming() {
  std::lock_guard lock(mutex_);
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(options_.time_scale / options_.fps));
  next_frame_ = Clock::now() + period;
}

namespace {
// The renderer draws the scene at the nominal exposure; a longer exposure collects
// proportionally more light, clipped at the sensor's full well (255), as a real sensor does.
void apply_exposure(Image8& img, double gain) {
  if (gain == 1.0) return;
  for (auto& v : img.pixels) v = static_cast<std::uint8_t>(std::min(255.0, v * gain + 0.5));
}
}  // namespace

void SimCamera::set_exposure_gain(double gain) {
  if (!(gain > 0) || gain > 100) throw std::invalid_argument("exposure gain must be in (0, 100]");
  std::lock_guard lock(mutex_);
  exposure_gain_ = gain;
}

void SimCamera::set_faults(const CameraFaults& faults) {
  std::lock_guard lock(mutex_);
  options_.faults = faults;
}

bool SimCamera::unplugged() const {
  std::lock_guard lock(mutex_);
  return unplugged_;
}

std::uint32_t SimCamera::frames_delivered() const {
  std::lock_guard lock(mutex_);
  return delivered_;
}

SimCamera::Capture SimCamera::capture(SimPixelFormat format) {
  std::unique_lock lock(mutex_);
  Capture c;
  const CameraFaults& f = options_.faults;
  if (unplugged_ || (f.unplug_at_sequence >= 0 && sequence_ >= f.unplug_at_sequence)) {
    unplugged_ = true;
    c.status = Capture::Status::Unplugged;
    return c;
  }
  const auto now = Clock::now();
  if (now < next_frame_) return c;  // still exposing
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(options_.time_scale / options_.fps));
  next_frame_ = now + period;
  // A dropped frame still used up its sequence number: the host sees the gap.
  while (f.drop_sequences.count(sequence_)) ++sequence_;
  c.sequence = sequence_++;
  if (static_cast<std::int64_t>(c.sequence) == f.eio_at_sequence) {
    c.status = Capture::Status::Eio;
    return c;
  }
  const bool corrupt = f.corrupt_sequences.count(c.sequence) > 0;
  const int quality = options_.jpeg_quality;
  lock.unlock();
  c.angle_rad = angle_();
  c.laser_mask = lasers_();
  Image8 img = renderer_(c.angle_rad, c.laser_mask);
  apply_exposure(img, exposure_gain_);
  if (img.width != options_.width || img.height != options_.height || img.channels != 3)
    throw std::logic_error("renderer returned a frame of the wrong size");
  switch (format) {
    case SimPixelFormat::Yuyv:
      c.bytes = encode_yuyv(img);
      break;
    case SimPixelFormat::Mjpeg:
      c.bytes = encode_jpeg(img, quality);
      break;
    case SimPixelFormat::Rgb24:
      c.bytes = img.pixels;
      break;
  }
  if (corrupt) {
    // Damage as seen on a flaky USB link: the payload is cut short and its header scrambled.
    for (std::size_t i = 2; i < std::min<std::size_t>(c.bytes.size(), 64); ++i) c.bytes[i] ^= 0x5a;
    c.bytes.resize(c.bytes.size() / 2);
  }
  c.timestamp_s = std::chrono::duration<double>(now.time_since_epoch()).count();
  c.status = Capture::Status::Ok;
  lock.lock();
  ++delivered_;
  return c;
}

}  // namespace scanmesh::sim
