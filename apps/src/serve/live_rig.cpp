#include "serve/live_rig.h"

#include <algorithm>
#include <cmath>

#include "scanmesh/core/errors.h"
#include "scanmesh/drivers/board.h"
#include "scanmesh/drivers/camera.h"
#include "scanmesh/sim/pty_board.h"
#include "scanmesh/sim/sim_camera.h"
#include "cli_support.h"
#include "sim_rig.h"

namespace scanmesh::cli::web {
namespace {

// The simulated devices of the live view run 20x faster than real time: a table turn or a
// laser switch shows within a frame or two instead of the real second.
constexpr double kSimLiveTimeScale = 0.05;

drivers::Frame grab_fresh(drivers::Camera& camera) {
  camera.flush();
  camera.grab();  // the frame in flight when the laser switched
  return camera.grab();
}

// Each accepted peak as a green mark (saturated ones yellow) over the camera frame.
void draw_peaks(Image8& image, const std::vector<LinePeak>& peaks) {
  for (const LinePeak& p : peaks) {
    const int x0 = static_cast<int>(std::lround(p.u));
    const Rgb8 colour = p.saturated ? Rgb8{255, 230, 0} : Rgb8{0, 255, 60};
    for (int x = x0 - 1; x <= x0 + 1; ++x)
      if (x >= 0 && x < image.width && p.row >= 0 && p.row < image.height)
        image.set_rgb(x, p.row, colour);
  }
}

}  // namespace

LiveRig::LiveRig(DeviceChoice devices) : devices_(std::move(devices)) {}

LiveRig::~LiveRig() { release(); }

void LiveRig::open_locked() {
  if (camera_) return;
  const drivers::PixelFormat format = drivers::parse_pixel_format(
      devices_.format.empty() ? (devices_.sim ? "rgb24" : "yuyv") : devices_.format);
  drivers::BoardOptions board_options;
  std::string board_path = devices_.board;
  if (devices_.sim) {
    sim::SimBoardOptions bo;
    bo.time_scale = kSimLiveTimeScale;
    pty_ = std::make_unique<sim::PtyBoard>(bo);
    auto firmware = pty_->shared_firmware();
    sim::SimCameraOptions co;
    co.width = devices_.width;
    co.height = devices_.height;
    co.time_scale = kSimLiveTimeScale;
    sim_camera_ = std::make_shared<sim::SimCamera>(
        make_sim_renderer(devices_.scene, devices_.width, devices_.height),
        [firmware] { return firmware->angle_rad(); }, [firmware] { return firmware->laser_mask(); },
        co);
    sim_camera_->start_streaming();
    camera_ = std::make_unique<SimCameraSource>(sim_camera_, format, 5.0);
    board_path = pty_->slave_path();
    board_options.banner_timeout = std::chrono::milliseconds(5000);
    board_options.command_timeout = std::chrono::milliseconds(3000);
  } else {
    drivers::CameraSettings cs;
    cs.width = devices_.width;
    cs.height = devices_.height;
    cs.format = format;
    camera_ = std::make_unique<drivers::V4l2Camera>(devices_.camera, cs);
  }
  try {
    board_ = std::make_unique<drivers::Board>(open_board_transport(board_path, devices_.baud),
                                              drivers::make_horus_dialect(), board_options);
    board_->connect();
    if (exposure_ > 0) camera_->set_exposure(exposure_);
  } catch (...) {
    board_.reset();
    camera_.reset();
    sim_camera_.reset();
    pty_.reset();
    throw;
  }
}

void LiveRig::check_not_held_locked(const std::function<bool()>& job_running) {
  if (held_ && job_running()) throw DevicesHeld("the devices are busy with a job");
  held_ = false;
}

LiveFrame LiveRig::frame(const std::function<bool()>& job_running) {
  std::lock_guard lock(mutex_);
  check_not_held_locked(job_running);
  open_locked();
  try {
    return frame_locked();
  } catch (...) {
    // A device that failed mid-frame: lasers off if the board still answers, and both closed
    // (the next request opens them again, or reports what is wrong).
    close_locked();
    throw;
  }
}

LiveFrame LiveRig::frame_locked() {
  LiveFrame out;
  for (int k = 0; k < 2; ++k) board_->set_laser(k, false);
  drivers::Frame off = grab_fresh(*camera_);
  double sum = 0;
  for (std::uint8_t v : off.rgb.pixels) sum += v;
  out.mean_level = off.rgb.pixels.empty() ? 0 : sum / static_cast<double>(off.rgb.pixels.size());
  Image8 shown = off.rgb;
  if (laser_ >= 0) {
    board_->set_laser(laser_, true);
    drivers::Frame on = grab_fresh(*camera_);
    board_->set_laser(laser_, false);
    LineExtractionStats stats;
    const auto peaks = extract_laser_line(on.rgb, off.rgb, line_, &stats);
    out.peaks = peaks.size();
    out.saturated = stats.saturated;
    shown = std::move(on.rgb);
    draw_peaks(shown, peaks);
  }
  out.angle_deg = board_->angle_rad() / kDeg;
  out.png = encode_png(shown, "live frame");
  return out;
}

void LiveRig::apply(const nlohmann::json& s) {
  if (!s.is_object()) throw InvalidInputError("settings must be a JSON object");
  LineExtractionOptions line = line_;
  int exposure = exposure_, laser = laser_;
  for (const auto& [key, value] : s.items()) {
    if (key == "exposure") {
      if (!value.is_number_integer() || value.get<long long>() < 1 || value.get<long long>() > 10000)
        throw InvalidInputError("exposure must be a whole number in [1, 10000] (100 us units)");
      exposure = value.get<int>();
    } else if (key == "threshold") {
      if (!value.is_number() || !(value.get<double>() >= 1 && value.get<double>() <= 255))
        throw InvalidInputError("threshold must be a number in [1, 255] (grey levels)");
      line.min_peak = value.get<double>();
    } else if (key == "method") {
      if (!value.is_string()) throw InvalidInputError("method must be com, gaussian or blais-rioux");
      line.method = parse_peak_method(value.get<std::string>());
    } else if (key == "laser") {
      if (!value.is_number_integer() || value.get<int>() < -1 || value.get<int>() > 1)
        throw InvalidInputError("laser must be -1 (off), 0 (left) or 1 (right)");
      laser = value.get<int>();
    } else {
      throw InvalidInputError("unknown setting '" + key + "'");
    }
  }
  std::lock_guard lock(mutex_);
  if (exposure != exposure_ && camera_) camera_->set_exposure(exposure);
  exposure_ = exposure;
  laser_ = laser;
  line_ = line;
}

void LiveRig::turn(double degrees, const std::function<bool()>& job_running) {
  if (!std::isfinite(degrees) || std::abs(degrees) > 360)
    throw InvalidInputError("turn: degrees must be in [-360, 360]");
  std::lock_guard lock(mutex_);
  check_not_held_locked(job_running);
  open_locked();
  try {
    board_->move_by(degrees * kDeg);
  } catch (...) {
    close_locked();
    throw;
  }
}

void LiveRig::close_locked() noexcept {
  if (board_) board_->shutdown();
  board_.reset();
  camera_.reset();
  sim_camera_.reset();
  pty_.reset();
}

void LiveRig::hold_for(const std::function<void()>& start_job) {
  std::lock_guard lock(mutex_);
  close_locked();
  held_ = true;
  try {
    start_job();
  } catch (...) {
    held_ = false;
    throw;
  }
}

void LiveRig::release() {
  std::lock_guard lock(mutex_);
  close_locked();
}

nlohmann::json LiveRig::describe() const {
  std::lock_guard lock(mutex_);
  nlohmann::json j = {{"simulated", devices_.sim},
                      {"camera", devices_.sim ? "sim:camera" : devices_.camera},
                      {"board", devices_.sim ? "sim:board" : devices_.board},
                      {"width", devices_.width},
                      {"height", devices_.height},
                      {"open", camera_ != nullptr},
                      {"exposure", exposure_ > 0 ? exposure_ : (devices_.sim ? kSimNominalExposure : 0)},
                      {"threshold", line_.min_peak},
                      {"method", peak_method_name(line_.method)},
                      {"laser", laser_}};
  if (board_) j["firmware"] = board_->firmware_banner();
  return j;
}

}  // namespace scanmesh::cli::web
