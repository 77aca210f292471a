// `scanmesh import`: another scanner's file (cloud, mesh, organised cloud) into a RangeGrid,
// with a JSON report of what was read and which part of the turn it covers
// (docs/acquisition.md, "Importing scans"; docs/cli.md).
#include <CLI/CLI.hpp>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "cli_support.h"
#include "commands.h"
#include "scanmesh/acquisition/scan_import.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_export.h"
#include "scanmesh/core/grid_file.h"

namespace scanmesh::cli {

namespace {

struct ImportArgs {
  std::string input, out, report, texture_png, depth_png;
  std::string axis = "z";        // z | estimate | X,Y,Z (a direction)
  std::string axis_point;        // empty: the data's centroid; else X,Y,Z
  int n_phi = 0, n_h = 0;
  double dh = 0;
};

Eigen::Vector3d parse_vector(const std::string& text, const std::string& option) {
  std::istringstream in(text);
  Eigen::Vector3d v;
  char c1 = 0, c2 = 0;
  std::string rest;
  if (!(in >> v.x() >> c1 >> v.y() >> c2 >> v.z()) || c1 != ',' || c2 != ',' || (in >> rest) ||
      !v.allFinite())
    throw InvalidInputError(option + " '" + text + "' is not three numbers X,Y,Z");
  return v;
}

ImportOptions import_options(const ImportArgs& a) {
  ImportOptions o;
  if (a.axis == "z") {
    o.direction = AxisDirection::Z;
  } else if (a.axis == "estimate") {
    o.direction = AxisDirection::Estimate;
  } else {
    o.direction = AxisDirection::Given;
    o.axis_direction = parse_vector(a.axis, "--axis");
    if (o.axis_direction.norm() == 0) throw InvalidInputError("--axis must not be 0,0,0");
  }
  if (!a.axis_point.empty()) o.axis_point = parse_vector(a.axis_point, "--axis-point");
  if (a.n_phi < 0 || a.n_h < 0 || !(a.dh >= 0 && a.dh <= 1e6))
    throw InvalidInputError("--n-phi, --n-h and --dh must be positive (0 or absent: automatic)");
  if (a.n_phi == 1 || a.n_h == 1) throw InvalidInputError("--n-phi and --n-h must be at least 2");
  o.n_phi = a.n_phi;
  o.n_h = a.n_h;
  o.dh = a.dh;
  return o;
}

double degrees(double rad) { return rad * 180.0 / std::numbers::pi; }

nlohmann::json report_json(const ImportResult& r, const std::string& input) {
  const ImportReport& rep = r.report;
  nlohmann::json arcs = nlohmann::json::array();
  for (const auto& [a, b] : rep.coverage.arcs)
    arcs.push_back({{"start_deg", degrees(a)}, {"end_deg", degrees(b)}, {"span_deg", degrees(b - a)}});
  const auto vec = [](const Eigen::Vector3d& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); };
  return {{"input", input},
          {"input_kind", rep.input_kind},
          {"method", rep.method},
          {"input_points", rep.input_points},
          {"input_triangles", rep.input_triangles},
          {"samples_used", rep.samples_used},
          {"colors", rep.colors},
          {"textured", rep.textured},
          {"axis", {{"point", vec(rep.axis.point)}, {"direction", vec(rep.axis.direction)}}},
          {"sample_spacing_mm", rep.sample_spacing_mm},
          {"cell_mm", rep.cell_mm},
          {"grid",
           {{"n_phi", r.grid.n_phi()},
            {"n_h", r.grid.n_h()},
            {"dh_mm", r.grid.dh()},
            {"h0_mm", r.grid.h0()},
            {"valid_cells", r.grid.valid_count()}}},
          {"turn_coverage",
           {{"full_turn", rep.coverage.full_turn},
            {"covered_columns", rep.coverage.covered_columns},
            {"columns", rep.coverage.columns},
            {"covered_fraction", rep.coverage.covered_fraction()},
            {"arcs", arcs}}},
          {"warnings", rep.warnings}};
}

void print_summary(const ImportResult& r, const ImportArgs& a) {
  const ImportReport& rep = r.report;
  std::ostringstream text;
  text << std::setprecision(4) << "import: " << a.input << ": " << rep.input_kind << ", "
       << rep.input_points << " points";
  if (rep.input_triangles) text << ", " << rep.input_triangles << " triangles";
  text << (rep.colors ? ", colours" : "") << "\n  " << rep.method << " into " << r.grid.n_phi()
       << " x " << r.grid.n_h() << " cells (dh " << r.grid.dh() << " mm), " << r.grid.valid_count()
       << " valid\n  axis through (" << rep.axis.point.transpose() << ") along ("
       << rep.axis.direction.transpose()
       << ")\n  turn covered: " << 100.0 * rep.coverage.covered_fraction() << " %";
  if (!rep.coverage.full_turn && !rep.coverage.arcs.empty()) {
    text << " (" << rep.coverage.arcs.size() << " arc(s), longest "
         << degrees(rep.coverage.arcs[0].first) << " to " << degrees(rep.coverage.arcs[0].second)
         << " deg)";
    if (a.axis_point.empty())
      text << "\n  note: a partial turn about the data's centroid; give the turntable's "
              "axis with --axis-point if the file has one (Horus: 0,0,0)";
  }
  text << "\n";
  for (const auto& w : rep.warnings) text << "  warning: " << w << "\n";
  say() << text.str();
}

int run_import(const ImportArgs& a) {
  const ImportResult r = import_scan(a.input, import_options(a));
  // The grid, its report and pictures appear together or not at all.
  StagedFiles outputs;
  write_grid(outputs.stage(a.out), r.grid);
  if (!a.report.empty())
    write_file_atomically(outputs.stage(a.report), json_text(report_json(r, a.input)) + "\n");
  if (!a.texture_png.empty()) export_texture_png(outputs.stage(a.texture_png), r.grid);
  if (!a.depth_png.empty()) export_depth_png(outputs.stage(a.depth_png), r.grid);
  outputs.commit();
  print_summary(r, a);
  say() << "wrote " << a.out << "\n";
  result() = report_json(r, a.input);
  result()["out"] = a.out;
  return kSuccess;
}

}  // namespace

void register_import_commands(CLI::App& app, CommandList& commands) {
  auto args = std::make_shared<ImportArgs>();
  auto* c = app.add_subcommand(
      "import", "Another scanner's cloud or mesh (.ply .pcd .xyz .off .obj .stl .vtk .vtp) into "
                "a range grid");
  c->add_option("input", args->input, "The scan file")->required()->check(CLI::ExistingFile);
  c->add_option("--out", args->out, "Range grid to write (.smg)")->required();
  c->add_option("--report", args->report, "JSON report (what was read, turn coverage)");
  c->add_option("--texture", args->texture_png, "Also write the grid's colours as a PNG");
  c->add_option("--depth", args->depth_png, "Also write a picture of the radius");
  c->add_option("--axis", args->axis,
                "Rotation axis direction: z (default), estimate (PCA), or X,Y,Z");
  c->add_option("--axis-point", args->axis_point,
                "A point X,Y,Z on the axis (default: the data's centroid)");
  c->add_option("--n-phi", args->n_phi, "Columns (default: from the sample spacing)");
  c->add_option("--n-h", args->n_h, "Rows (default: from --dh)");
  c->add_option("--dh", args->dh, "Row spacing in mm (default: from the sample spacing)");
  commands.push_back({c, [args] { return run_import(*args); }});
}

}  // namespace scanmesh::cli
