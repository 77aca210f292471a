// The simulated scanner for `scanmesh scan --sim`: the simulated board firmware behind a pty,
// spoken to by the real termios transport and board driver, and the simulated camera seen
// through drivers::Camera (in-process: the emulated V4L2 node needs umockdev's preload, which
// only the tests run under; docs/testing.md).
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "scanmesh/drivers/camera.h"
#include "scanmesh/drivers/transport.h"
#include "scanmesh/sim/pty_board.h"
#include "scanmesh/sim/sim_camera.h"
#include "scanmesh/sim/turntable_camera.h"

namespace scanmesh::cli {

//! Faults for the simulated devices from `--sim-fault KIND@N` strings, e.g. "board-unplug@40",
//! "camera-eio@12". Throws InvalidInputError for an unknown kind.
void apply_sim_fault(const std::string& spec, sim::SimBoardOptions& board,
                     sim::SimCameraOptions& camera);

//! "WIDTHxHEIGHT" (even width, 8..8192 each) -> (width, height); throws InvalidInputError.
std::pair<int, int> parse_frame_size(const std::string& size);

//! The built-in Ciclop rig at another frame size: the intrinsics scale with the sensor (the same
//! lens on a smaller sensor readout). `scan --sim --scene`, `calibrate --sim --size` and the
//! device demo all use this, so a session and its calibration describe the same camera.
sim::RigConfig scaled_ciclop_rig(int width, int height);

//! The frame renderer of the simulation. `scene` empty: the synthetic turntable renderer.
//! (The scene renderer sim::TurntableCamera plugs in here.)
sim::FrameRenderer make_sim_renderer(const std::string& scene, int width, int height);

//! The board's transport for `--board`: a tty path (/dev/ttyACM0), or VID:PID / usb:BUS:ADDR
//! through libusb. Throws DeviceError.
std::unique_ptr<drivers::Transport> open_board_transport(const std::string& board, int baud);

//! The exposure (100 µs units) at which the simulated camera's frames look as rendered.
constexpr int kSimNominalExposure = 150;

//! drivers::Camera over a SimCamera, decoding with the same code as the V4L2 backend.
class SimCameraSource final : public drivers::Camera {
 public:
  SimCameraSource(std::shared_ptr<sim::SimCamera> camera, drivers::PixelFormat format,
                  double timeout_s);
  drivers::Frame grab() override;
  void flush() override {}
  drivers::CameraDescriptor descriptor() const override;
  //! Exposure relative to kSimNominalExposure (the renderer's brightness).
  void set_exposure(int exposure_100us) override;

 private:
  std::shared_ptr<sim::SimCamera> camera_;
  drivers::PixelFormat format_;
  double timeout_s_;
  std::optional<std::uint32_t> last_sequence_;
};

}  // namespace scanmesh::cli
