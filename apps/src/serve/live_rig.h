// The live view of `scanmesh serve`: the camera and the turntable board held open between jobs,
// a frame on request with the extracted laser peaks drawn over it, and the controls that act on
// the drivers (exposure, laser, table). Real devices (V4L2 + libusb/tty) or the simulated ones
// behind the same driver code (the pty board, the simulated UVC camera). A scan or calibration
// job needs the devices itself: release() closes them, the next frame() opens them again.
#pragma once

#include <functional>
#include <memory>
#include <stdexcept>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "scanmesh/acquisition/line_extraction.h"

namespace scanmesh::drivers {
class Board;
class Camera;
}  // namespace scanmesh::drivers
namespace scanmesh::sim {
class PtyBoard;
class SimCamera;
}  // namespace scanmesh::sim

namespace scanmesh::cli::web {

struct DeviceChoice {
  bool sim = false;
  std::string camera, board;  //!< hardware: as `scan --device/--board`
  int baud = 115200;
  int width = 640, height = 480;
  std::string format;  //!< empty: rgb24 in simulation, yuyv on hardware
  //! Simulation: what stands on the turntable: "head", a scene YAML, or "" for the fast
  //! synthetic line pattern (the tests under the sanitizers).
  std::string scene = "head";
};

struct LiveFrame {
  std::vector<std::uint8_t> png;  //!< the laser-on frame (laser-off with laser -1), peaks drawn
  std::size_t peaks = 0;
  std::size_t saturated = 0;
  double mean_level = 0;  //!< mean grey level of the laser-off frame (0..255): the exposure
  double angle_deg = 0;
};

class LiveRig {
 public:
  explicit LiveRig(DeviceChoice devices);
  ~LiveRig();
  LiveRig(const LiveRig&) = delete;
  LiveRig& operator=(const LiveRig&) = delete;

  //! Thrown by frame() and turn() while a job holds the devices.
  struct DevicesHeld : std::runtime_error {
    using std::runtime_error::runtime_error;
  };

  //! Opens the devices if needed and takes a frame pair. Throws DeviceError, or DevicesHeld
  //! while held and `job_running()` says the holder still runs.
  LiveFrame frame(const std::function<bool()>& job_running);
  //! Applies the page's settings: {"exposure": int, "threshold": DN, "method": name,
  //! "laser": -1|0|1}. Throws InvalidInputError naming a bad field (nothing is changed then).
  void apply(const nlohmann::json& settings);
  //! Turns the table by `degrees` (live positioning before a scan). Throws DeviceError,
  //! DevicesHeld as frame().
  void turn(double degrees, const std::function<bool()>& job_running);
  //! Closes the devices and keeps them closed for a job: `start_job` runs under the rig's lock,
  //! so no frame request can open them between the close and the job's start. The hold ends at
  //! the first request after the job.
  void hold_for(const std::function<void()>& start_job);
  //! Closes the devices (the server's end).
  void release();
  nlohmann::json describe() const;

 private:
  void open_locked();
  void close_locked() noexcept;
  LiveFrame frame_locked();
  void check_not_held_locked(const std::function<bool()>& job_running);
  bool held_ = false;
  DeviceChoice devices_;
  mutable std::mutex mutex_;
  std::unique_ptr<sim::PtyBoard> pty_;
  std::shared_ptr<sim::SimCamera> sim_camera_;
  std::unique_ptr<drivers::Camera> camera_;
  std::unique_ptr<drivers::Board> board_;
  int exposure_ = 0;  //!< 0: the camera's own until the page sets one
  int laser_ = 0;     //!< -1: none
  LineExtractionOptions line_;
};

}  // namespace scanmesh::cli::web
