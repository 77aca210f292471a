// The simulated scanner for `scanmesh scan --sim`: the simulated board firmware behind a pty,
// spoken to by the real termios transport and board driver, and the simulated camera seen
// through drivers::Camera (in-process: the emulated V4L2 node needs umockdev's preload, which
// only the tests run under; docs/testing.md).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "scanmesh/drivers/camera.h"
#include "scanmesh/sim/pty_board.h"
#include "scanmesh/sim/sim_camera.h"

namespace scanmesh::cli {

//! Faults for the simulated devices from `--sim-fault KIND@N` strings, e.g. "board-unplug@40",
//! "camera-eio@12". Throws InvalidInputError for an unknown kind.
void apply_sim_fault(const std::string& spec, sim::SimBoardOptions& board,
                     sim::SimCameraOptions& camera);

//! The frame renderer of the simulation. `scene` empty: the synthetic turntable renderer.
//! (The scene renderer sim::TurntableCamera plugs in here.)
sim::FrameRenderer make_sim_renderer(const std::string& scene, int width, int height);

//! drivers::Camera over a SimCamera, decoding with the same code as the V4L2 backend.
class SimCameraSource final : public drivers::Camera {
 public:
  SimCameraSource(std::shared_ptr<sim::SimCamera> camera, drivers::PixelFormat format,
                  double timeout_s);
  drivers::Frame grab() override;
  void flush() override {}
  drivers::CameraDescriptor descriptor() const override;

 private:
  std::shared_ptr<sim::SimCamera> camera_;
  drivers::PixelFormat format_;
  double timeout_s_;
  std::optional<std::uint32_t> last_sequence_;
};

}  // namespace scanmesh::cli
