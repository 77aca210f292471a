// Cameras as the capture loop sees them, and the V4L2 backend for UVC webcams.
//
// V4L2 (Linux media API, "Video for Linux 2"): open by path or card name, VIDIOC_QUERYCAP,
// VIDIOC_ENUM_FMT, VIDIOC_S_FMT (YUYV, MJPEG, RGB24), VIDIOC_S_PARM (frame rate), streaming I/O
// with MMAP or USERPTR buffers, manual exposure/gain/brightness, poll() with a timeout, frame
// timestamps and sequence numbers, drop detection from sequence gaps.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "scanmesh/core/image.h"

namespace scanmesh::drivers {

enum class PixelFormat { Yuyv, Mjpeg, Rgb24 };
std::string to_string(PixelFormat f);
//! "yuyv" | "mjpeg" | "rgb24"; throws InvalidInputError otherwise.
PixelFormat parse_pixel_format(const std::string& name);

//! One captured frame: decoded RGB plus, for MJPEG, the original compressed bytes (so a session
//! can keep them unchanged).
struct Frame {
  Image8 rgb;
  PixelFormat format = PixelFormat::Yuyv;
  std::vector<std::uint8_t> original;  //!< MJPEG bytes as the camera sent them; empty otherwise
  std::uint32_t sequence = 0;          //!< the driver's frame counter
  double timestamp_s = 0;              //!< capture time (CLOCK_MONOTONIC), seconds
  std::uint32_t dropped_before = 0;    //!< frames lost since the previous one (sequence gap)
};

//! What a recorded session keeps about a camera.
struct CameraDescriptor {
  std::string path, card, driver, bus_info;
  int width = 0, height = 0;
  PixelFormat format = PixelFormat::Yuyv;
  double fps = 0;
};

class Camera {
 public:
  virtual ~Camera() = default;
  //! Waits for the next frame. Throws DeviceError (timeout, unplugged, I/O error, undecodable).
  virtual Frame grab() = 0;
  //! Discards frames captured before now (after a laser switched), so the next grab() shows
  //! the new state.
  virtual void flush() = 0;
  virtual CameraDescriptor descriptor() const = 0;
  //! Manual exposure in 100 µs units, while streaming (the live view's slider). Throws
  //! DeviceError when the device refuses it.
  virtual void set_exposure(int exposure_100us) = 0;
};

enum class IoMethod { Mmap, UserPtr };

struct CameraSettings {
  int width = 640, height = 480;
  PixelFormat format = PixelFormat::Yuyv;
  double fps = 30;
  IoMethod io = IoMethod::Mmap;
  int buffer_count = 4;
  std::optional<int> exposure;    //!< V4L2_CID_EXPOSURE_ABSOLUTE (100 µs units); sets manual mode
  std::optional<int> gain;        //!< V4L2_CID_GAIN
  std::optional<int> brightness;  //!< V4L2_CID_BRIGHTNESS
  std::chrono::milliseconds timeout{2000};  //!< per frame
};

struct CameraInfo {
  std::string path, card, driver, bus_info;
  std::vector<PixelFormat> formats;      //!< the ones scanmesh can decode
  std::vector<std::string> all_formats;  //!< every fourcc the device lists
};

//! /dev/video* nodes that are capture devices. Nodes that cannot be opened are skipped.
std::vector<CameraInfo> list_cameras();

//! The V4L2 backend. Not copyable; closes the node on destruction.
class V4l2Camera final : public Camera {
 public:
  //! `device` is a path (/dev/video0) or a card name / bus_info as `scanmesh devices` prints
  //! it. Throws DeviceError: missing, busy (EBUSY), not a capture device, unsupported format.
  V4l2Camera(const std::string& device, const CameraSettings& settings);
  ~V4l2Camera() override;
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  Frame grab() override;
  void flush() override;
  CameraDescriptor descriptor() const override { return descriptor_; }
  void set_exposure(int exposure_100us) override;
  const CameraInfo& info() const { return info_; }
  //! Frames lost to sequence gaps since streaming started.
  std::uint64_t dropped_frames() const { return dropped_; }

 private:
  struct Buffer {
    void* start = nullptr;
    std::size_t length = 0;
    std::vector<std::uint8_t> owned;  //!< USERPTR memory
  };
  void configure(const CameraSettings& settings);
  void set_control(std::uint32_t id, std::int32_t value, const char* what);
  void queue(unsigned index);
  bool try_dequeue(Frame& frame);
  void stop() noexcept;
  [[noreturn]] void fail(const std::string& what, int err) const;

  int fd_ = -1;
  std::string path_;
  CameraInfo info_;
  CameraDescriptor descriptor_;
  CameraSettings settings_;
  std::vector<Buffer> buffers_;
  std::uint32_t bytes_per_line_ = 0, size_image_ = 0;
  bool streaming_ = false;
  std::optional<std::uint32_t> last_sequence_;
  std::uint64_t dropped_ = 0;
  std::uint32_t flushed_dropped_ = 0;  //!< drops seen while flushing, reported with the next frame
};

//! Decodes one frame payload into RGB. YUYV (BT.601 full range, as UVC cameras send it) and
//! RGB24 are checked against the size; MJPEG goes through libjpeg (decode_jpeg) and must decode to
//! width x height. Throws FileFormatError naming `source` for a truncated or corrupt frame.
//! Pure, so it can be fuzzed (tests/fuzz/fuzz_v4l2_frame_decode.cpp).
Image8 decode_frame(PixelFormat format, std::span<const std::uint8_t> bytes, int width, int height,
                    std::uint32_t bytes_per_line = 0, const std::string& source = "frame");

}  // namespace scanmesh::drivers
