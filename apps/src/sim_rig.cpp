#include "sim_rig.h"

#include <chrono>
#include <cstdio>
#include <thread>

#include "scanmesh/core/errors.h"
#include "scanmesh/drivers/serial_transport.h"
#include "scanmesh/drivers/usb_transport.h"
#include "scanmesh/sim/scene.h"
#include "scanmesh/sim/turntable_camera.h"

namespace scanmesh::cli {

void apply_sim_fault(const std::string& spec, sim::SimBoardOptions& board,
                     sim::SimCameraOptions& camera) {
  const auto at = spec.find('@');
  if (at == std::string::npos || at + 1 >= spec.size())
    throw InvalidInputError("--sim-fault '" + spec + "' must be KIND@N");
  const std::string kind = spec.substr(0, at);
  long n = 0;
  try {
    std::size_t used = 0;
    n = std::stol(spec.substr(at + 1), &used);
    if (used != spec.size() - at - 1 || n < 0) throw std::invalid_argument("n");
  } catch (const std::exception&) {
    throw InvalidInputError("--sim-fault '" + spec + "': N must be a non-negative integer");
  }
  const int ni = static_cast<int>(n);
  if (kind == "board-unplug")
    board.faults.unplug_at_command = ni;
  else if (kind == "board-stall")
    board.faults.stall_at_command = ni;
  else if (kind == "board-drop-ok")
    board.faults.drop_ok_at_command = ni;
  else if (kind == "board-garble-ok")
    board.faults.garble_ok_at_command = ni;
  else if (kind == "board-hang-move")
    board.faults.hang_move_at_command = ni;
  else if (kind == "camera-drop")
    camera.faults.drop_sequences.insert(static_cast<std::uint32_t>(n));
  else if (kind == "camera-corrupt")
    camera.faults.corrupt_sequences.insert(static_cast<std::uint32_t>(n));
  else if (kind == "camera-eio")
    camera.faults.eio_at_sequence = n;
  else if (kind == "camera-unplug")
    camera.faults.unplug_at_sequence = n;
  else
    throw InvalidInputError("--sim-fault kind '" + kind +
                            "' is unknown (board-unplug, board-stall, board-drop-ok, "
                            "board-garble-ok, board-hang-move, camera-drop, camera-corrupt, "
                            "camera-eio, camera-unplug)");
}

std::pair<int, int> parse_frame_size(const std::string& s) {
  int w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(s.c_str(), "%dx%d%c", &w, &h, &tail) != 2 || w < 8 || h < 8 || w > 8192 ||
      h > 8192 || w % 2 != 0)
    throw InvalidInputError("--size '" + s + "' must be WIDTHxHEIGHT (even width, 8..8192)");
  return {w, h};
}

sim::RigConfig scaled_ciclop_rig(int width, int height) {
  return sim::rig_at_size(sim::builtin_ciclop_rig(), width, height);
}

sim::FrameRenderer make_sim_renderer(const std::string& scene, int width, int height) {
  // Without a scene the synthetic renderer stays the default: it is fast and its frames are what
  // the session and kill/resume tests compare bit for bit.
  if (scene.empty()) return sim::synthetic_turntable_renderer(width, height);
  auto world = std::make_shared<sim::Scene>(scene == "head" ? sim::builtin_head_scene()
                                                            : sim::Scene::from_yaml_file(scene));
  const sim::RigConfig rig = scaled_ciclop_rig(width, height);
  auto camera = std::make_shared<sim::TurntableCamera>(*world, rig);
  // The closure owns the scene and the camera (which keeps a reference to the scene).
  return [world, camera](double angle_rad, unsigned laser_mask) {
    return camera->render(angle_rad, laser_mask);
  };
}

SimCameraSource::SimCameraSource(std::shared_ptr<sim::SimCamera> camera,
                                 drivers::PixelFormat format, double timeout_s)
    : camera_(std::move(camera)), format_(format), timeout_s_(timeout_s) {}

drivers::CameraDescriptor SimCameraSource::descriptor() const {
  const auto& o = camera_->options();
  drivers::CameraDescriptor d;
  d.path = "sim:camera";
  d.card = o.card;
  d.driver = "scanmesh-sim";
  d.bus_info = o.bus_info;
  d.width = o.width;
  d.height = o.height;
  d.format = format_;
  d.fps = o.fps;
  return d;
}

void SimCameraSource::set_exposure(int exposure_100us) {
  if (exposure_100us < 1 || exposure_100us > 100 * kSimNominalExposure)
    throw DeviceError("sim:camera", "exposure " + std::to_string(exposure_100us) +
                                        " out of range 1.." +
                                        std::to_string(100 * kSimNominalExposure));
  camera_->set_exposure_gain(static_cast<double>(exposure_100us) / kSimNominalExposure);
}

std::unique_ptr<drivers::Transport> open_board_transport(const std::string& board, int baud) {
  if (board.starts_with("/")) return drivers::open_serial_transport(board, baud);
  drivers::UsbSerialOptions o = drivers::parse_usb_board_spec(board);
  o.baud = baud;
  return drivers::open_usb_transport(o);
}


drivers::Frame SimCameraSource::grab() {
  const auto sim_format = format_ == drivers::PixelFormat::Yuyv    ? sim::SimPixelFormat::Yuyv
                          : format_ == drivers::PixelFormat::Mjpeg ? sim::SimPixelFormat::Mjpeg
                                                                   : sim::SimPixelFormat::Rgb24;
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s_);
  drivers::Frame frame;
  int corrupt = 0;
  const auto& o = camera_->options();
  for (;;) {
    if (std::chrono::steady_clock::now() > deadline)
      throw DeviceError("sim:camera", "no frame within " + std::to_string(timeout_s_) + " s");
    const sim::SimCamera::Capture c = camera_->capture(sim_format);
    using Status = sim::SimCamera::Capture::Status;
    if (c.status == Status::NotReady) {
      std::this_thread::sleep_for(std::chrono::microseconds(50));
      continue;
    }
    if (c.status == Status::Unplugged) throw DeviceError("sim:camera", "unplugged (ENODEV)");
    if (c.status == Status::Eio) throw DeviceError("sim:camera", "VIDIOC_DQBUF: I/O error (EIO)");
    if (last_sequence_ && c.sequence > *last_sequence_ + 1)
      frame.dropped_before += c.sequence - *last_sequence_ - 1;
    last_sequence_ = c.sequence;
    try {
      frame.rgb = drivers::decode_frame(format_, c.bytes, o.width, o.height, 0,
                                        "sim:camera frame " + std::to_string(c.sequence));
    } catch (const FileFormatError& e) {
      ++frame.dropped_before;
      if (++corrupt >= 3)
        throw DeviceError("sim:camera", std::string("3 corrupt frames in a row: ") + e.what());
      continue;
    }
    frame.format = format_;
    frame.sequence = c.sequence;
    frame.timestamp_s = c.timestamp_s;
    if (format_ == drivers::PixelFormat::Mjpeg) frame.original = c.bytes;
    return frame;
  }
}

}  // namespace scanmesh::cli
