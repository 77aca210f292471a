// Laser-line extraction (docs/acquisition.md, "Line extraction"): per image row, the laser-off
// frame is subtracted, the strongest peak of the red difference is found, checked (height above
// the local background, width, secondary peaks, saturation) and located to a fraction of a pixel
// by one of three estimators, with a confidence in [0, 1].
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "scanmesh/core/image.h"

namespace scanmesh {

enum class PeakMethod {
  CenterOfMass,  //!< centroid of the background-subtracted profile in a +- 1.5 FWHM window
  Gaussian,      //!< weighted least-squares parabola through the log profile (exact for a Gaussian)
  BlaisRioux,    //!< zero crossing of Blais and Rioux's 4th/8th-order derivative filter
};

const char* peak_method_name(PeakMethod m);
//! "com", "gaussian", "blais-rioux" (also the names above). Throws InvalidInputError.
PeakMethod parse_peak_method(const std::string& name);

struct LineExtractionOptions {
  PeakMethod method = PeakMethod::Gaussian;
  int channel = 0;               //!< colour channel carrying the laser (0 = red)
  double min_peak = 25.0;        //!< peak height above the local background (DN) to accept
  int com_half_window = 3;       //!< centre-of-mass window: peak +- this many pixels
  int background_offset = 10;    //!< local background sampled this far either side of the peak
  double max_width_px = 16.0;    //!< wider bumps (ambient changes, reflections) are rejected
  double secondary_ratio = 0.5;  //!< a second peak above this share of the first rejects the row
  int secondary_guard_px = 4;    //!< the second peak must lie this far beyond the first's flanks
  //! A peak whose other channels rose by more than this share of the laser channel's rise is
  //! room light, not the (red) laser; 0 disables the test. Saturated peaks are not tested.
  double max_other_channel_ratio = 0.5;
  int saturation_level = 254;              //!< a laser-on value at or above this is saturated
  int first_column = 0, last_column = -1;  //!< search range (-1: to the last column)

  //! Throws InvalidInputError for impossible values.
  void validate() const;
};

struct LinePeak {
  int row = 0;
  double u = 0.0;           //!< subpixel column of the line centre (pixel centres at integers)
  float amplitude = 0.0f;   //!< peak height above the local background (DN)
  float width = 0.0f;       //!< full width at half maximum (px)
  float confidence = 0.0f;  //!< 0..1: signal to threshold, saturation, secondary peaks
  bool saturated = false;
};

struct LineExtractionStats {
  std::size_t rows = 0, peaks = 0;
  std::size_t rejected_weak = 0, rejected_wide = 0, rejected_secondary = 0, rejected_ambient = 0,
              saturated = 0;
};

//! At most one peak per row, in row order. `laser_on` and `laser_off` must have the same size
//! and channel count (InvalidInputError otherwise).
std::vector<LinePeak> extract_laser_line(const Image8& laser_on, const Image8& laser_off,
                                         const LineExtractionOptions& options = {},
                                         LineExtractionStats* stats = nullptr);

}  // namespace scanmesh
