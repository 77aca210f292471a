// One turntable step of a laser scan as the rest of acquisition sees it, whichever way it was
// obtained: captured from devices, replayed from a recorded session, or rendered by the simulated
// camera. The capture loop and session recorder produce steps; laser-line extraction,
// triangulation and grid assembly consume them through ScanStepSource.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "scanmesh/core/image.h"

namespace scanmesh {

struct ScanStep {
  std::size_t index = 0;       //!< 0 .. step_count-1
  double angle_rad = 0;        //!< turntable angle the board reported for this step
  Image8 laser_off;            //!< all lasers off: background and texture colour
  std::vector<Image8> laser_on;  //!< laser_on[k]: only laser k switched on
  double timestamp_s = 0;      //!< capture time of the laser-off frame (monotonic clock)
};

//! A finite, random-access sequence of scan steps (a session on disk, a simulation, memory).
class ScanStepSource {
 public:
  virtual ~ScanStepSource() = default;
  virtual std::size_t step_count() const = 0;
  virtual int laser_count() const = 0;
  //! Throws scanmesh::Error (FileFormatError for a damaged session) if step i cannot be read.
  virtual ScanStep step(std::size_t i) const = 0;
};

}  // namespace scanmesh
