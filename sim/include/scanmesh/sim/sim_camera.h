// Simulated UVC camera: renders a frame for the turntable angle and laser mask the simulated
// board reports at the moment of capture, encodes it as the camera would send it (YUYV, MJPEG
// or RGB24) and numbers it. Frame timing follows the frame rate (scaled by time_scale). Faults:
// dropped frames (sequence gaps), corrupt MJPEG, EIO, unplug. Thread-safe.
//
// The renderer is a callback, so the real scene renderer (sim::TurntableCamera) and the small
// synthetic one below are interchangeable.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "scanmesh/core/image.h"

namespace scanmesh::sim {

//! RGB image of the turntable at `turntable_angle_rad` with the lasers in `laser_mask` on
//! (bit k: laser k). Must be deterministic: the same arguments give the same pixels.
using FrameRenderer = std::function<Image8(double turntable_angle_rad, unsigned laser_mask)>;

//! A small deterministic stand-in for the scene renderer: a textured background that turns
//! with the table and one bright red vertical line per switched-on laser, whose column depends
//! on the angle. Good enough to check that frames, angles and lasers stay together.
FrameRenderer synthetic_turntable_renderer(int width, int height);

enum class SimPixelFormat { Yuyv, Mjpeg, Rgb24 };

struct CameraFaults {
  std::set<std::uint32_t> drop_sequences;     //!< these sequence numbers are never delivered
  std::set<std::uint32_t> corrupt_sequences;  //!< delivered with a damaged payload
  std::int64_t eio_at_sequence = -1;          //!< DQBUF fails with EIO instead of this frame
  std::int64_t unplug_at_sequence = -1;       //!< from this frame on: ENODEV
  bool busy = false;  //!< another program streams: VIDIOC_S_FMT fails with EBUSY
};

struct SimCameraOptions {
  int width = 160, height = 120;
  double fps = 30;
  double time_scale = 1.0;  //!< 0.01: frames come 100x faster than real time
  std::vector<SimPixelFormat> formats = {SimPixelFormat::Yuyv, SimPixelFormat::Mjpeg,
                                         SimPixelFormat::Rgb24};
  int jpeg_quality = 90;
  std::string card = "Simulated UVC Camera";
  std::string bus_info = "usb-scanmesh-sim-1";
  CameraFaults faults;
};

//! RGB -> YUYV (BT.601 full range; each pixel pair shares the mean chroma).
std::vector<std::uint8_t> encode_yuyv(const Image8& rgb);

class SimCamera {
 public:
  using Clock = std::chrono::steady_clock;
  SimCamera(FrameRenderer renderer, std::function<double()> angle_rad,
            std::function<unsigned()> laser_mask, SimCameraOptions options = {});

  struct Capture {
    enum class Status { Ok, NotReady, Eio, Unplugged };
    Status status = Status::NotReady;
    std::vector<std::uint8_t> bytes;
    std::uint32_t sequence = 0;
    double timestamp_s = 0;  //!< CLOCK_MONOTONIC seconds
    double angle_rad = 0;
    unsigned laser_mask = 0;
  };

  void start_streaming();
  //! The next frame if its exposure is over, rendered at the board's state now.
  Capture capture(SimPixelFormat format);
  //! Renders without encoding (tests compare recorded frames against this).
  Image8 render(double angle_rad, unsigned laser_mask) const {
    return renderer_(angle_rad, laser_mask);
  }

  const SimCameraOptions& options() const { return options_; }
  void set_faults(const CameraFaults& faults);
  //! Exposure relative to the nominal one the renderer draws (1: as rendered); pixel values
  //! scale with it and clip at 255. Throws std::invalid_argument outside (0, 100].
  void set_exposure_gain(double gain);
  bool unplugged() const;
  std::uint32_t frames_delivered() const;

 private:
  mutable std::mutex mutex_;
  FrameRenderer renderer_;
  std::function<double()> angle_;
  std::function<unsigned()> lasers_;
  SimCameraOptions options_;
  Clock::time_point next_frame_;
  std::uint32_t sequence_ = 0;
  std::uint32_t delivered_ = 0;
  bool unplugged_ = false;
  double exposure_gain_ = 1.0;
};

}  // namespace scanmesh::sim
