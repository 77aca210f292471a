#include "scanmesh/meshing/aft/region_setup.h"

#include <utility>

namespace scanmesh::aft {

RegionSetup set_up_regions(const RangeGrid& grid,
                           const std::optional<std::filesystem::path>& lines_path,
                           const std::optional<std::filesystem::path>& settings_path,
                           const std::optional<std::string>& data_border,
                           const std::string& line_rows) {
  RegionSetup s;
  const FileRows rows = parse_file_rows(line_rows);
  s.surface = std::make_unique<ScanSurface>(grid);
  if (settings_path) s.settings = read_region_settings(*settings_path, grid.n_h(), rows);
  s.border_mode = data_border ? parse_data_border_mode(*data_border)
                              : s.settings.data_border.value_or(DataBorderMode::Auto);
  s.border = with_data_border(lines_path ? read_lines(*lines_path, grid.n_h(), rows) : LineSet{},
                              *s.surface, s.border_mode);
  s.lines = std::move(s.border.lines);
  validate_lines(s.lines, *s.surface);
  s.graph = analyze_regions(s.lines, *s.surface);
  apply_region_settings(s.graph, s.settings, *s.surface);
  return s;
}

}  // namespace scanmesh::aft
