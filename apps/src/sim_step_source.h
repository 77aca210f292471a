// A ScanStepSource that renders each step on the fly with the simulated turntable camera (the
// device path without devices or a session folder). Header-only: used by the CLI and the bench.
#pragma once

#include <numbers>

#include "scanmesh/acquisition/scan_step.h"
#include "scanmesh/sim/turntable_camera.h"

namespace scanmesh::cli {

class SimulatedStepSource : public ScanStepSource {
 public:
  //! Step i at turntable angle 2 pi i / steps; every laser of the rig, one per frame.
  SimulatedStepSource(const sim::TurntableCamera& camera, std::size_t steps)
      : camera_(camera), steps_(steps) {}
  std::size_t step_count() const override { return steps_; }
  int laser_count() const override { return camera_.laser_count(); }
  ScanStep step(std::size_t i) const override {
    ScanStep s;
    s.index = i;
    s.angle_rad = 2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(steps_);
    s.laser_off = camera_.render(s.angle_rad, 0u);
    for (int k = 0; k < camera_.laser_count(); ++k)
      s.laser_on.push_back(camera_.render(s.angle_rad, 1u << k));
    s.timestamp_s = static_cast<double>(i);
    return s;
  }

 private:
  const sim::TurntableCamera& camera_;
  std::size_t steps_;
};

}  // namespace scanmesh::cli
