// The regions that `regions` and `animesh` mesh, set up from their files the same way for the
// CLI and for Python: lines, data border, region graph, region settings.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "scanmesh/core/range_grid.h"
#include "scanmesh/meshing/aft/animation_lines.h"
#include "scanmesh/meshing/aft/data_border.h"
#include "scanmesh/meshing/aft/regions.h"
#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::aft {

struct RegionSetup {
  std::unique_ptr<ScanSurface> surface;  //!< of the grid given to set_up_regions (a copy)
  LineSet lines;  //!< the user's lines clipped to the data border, then the border
  RegionGraph graph;
  RegionSettings settings;
  DataBorderMode border_mode = DataBorderMode::Auto;
  DataBorderResult border;  //!< its counts (border.lines is moved into `lines`)
};

//! Reads the settings (defaults without a path) and the lines (none without a path; rows
//! counted as `line_rows` says, parse_file_rows), clips them to the data border and adds it,
//! validates them, analyses their regions and applies the settings. The border mode is
//! `data_border` when given (a parse_data_border_mode name, read after the settings, so that a
//! bad settings file is reported first), else the settings' data_border, else auto.
RegionSetup set_up_regions(const RangeGrid& grid,
                           const std::optional<std::filesystem::path>& lines_path,
                           const std::optional<std::filesystem::path>& settings_path,
                           const std::optional<std::string>& data_border,
                           const std::string& line_rows);

}  // namespace scanmesh::aft
