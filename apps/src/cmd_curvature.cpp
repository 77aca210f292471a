// `scanmesh curvature`: per-cell normals and curvatures of a grid, the fields file and pictures
// (docs/cli.md, docs/reconstruction.md).
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "cli_support.h"
#include "commands.h"
#include "pipeline.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/image.h"
#include "scanmesh/reconstruction/curvature_maps.h"
#include "scanmesh/reconstruction/fields_file.h"
#include "scanmesh/reconstruction/surface_fields.h"

namespace scanmesh::cli {

namespace {

struct CurvatureArgs {
  std::string grid;
  std::string out;                      //!< output directory
  std::string method = "grid-quadric";  //!< analytic | grid-quadric | quadric | seed
  double radius_mm = 0;                 //!< quadric neighbourhood radius; <= 0: the default
};

// Percentiles of one per-cell quantity over the defined cells.
template <typename F>
nlohmann::json percentiles(const SurfaceFields& f, F&& value) {
  std::vector<double> v;
  v.reserve(f.size());
  for (std::size_t k = 0; k < f.size(); ++k)
    if (f.defined[k]) v.push_back(value(k));
  if (v.empty()) return nullptr;
  std::sort(v.begin(), v.end());
  const auto at = [&](double q) {
    return v[static_cast<std::size_t>(std::lround(q * static_cast<double>(v.size() - 1)))];
  };
  return {{"min", v.front()}, {"p1", at(0.01)},  {"p5", at(0.05)}, {"p50", at(0.5)},
          {"p95", at(0.95)},  {"p99", at(0.99)}, {"max", v.back()}};
}

bool has_normals(const SurfaceFields& f) {
  for (std::size_t k = 0; k < f.size(); ++k)
    if (f.defined[k] && !f.normal[k].isZero()) return true;
  return false;
}

int run_curvature(const CurvatureArgs& args) {
  Stopwatch total;
  nlohmann::json timings;
  const CurvatureMethod method = parse_curvature_method(args.method);

  Stopwatch t;
  const RangeGrid grid = read_grid(args.grid);
  timings["read_s"] = t.seconds();
  const std::filesystem::path dir = args.out;
  OutputFolder folder(dir);  // before the work: a bad --out fails at once

  t = Stopwatch();
  const SurfaceFields fields = compute_fields(grid, method, args.radius_mm);
  timings["compute_s"] = t.seconds();

  t = Stopwatch();
  // The six outputs appear together or not at all (a failure half way leaves none of them).
  StagedFiles outputs;
  nlohmann::json files = nlohmann::json::array();
  const auto written = [&](const char* name) {
    files.push_back(name);
    return outputs.stage(dir / name);
  };
  write_fields(written("fields.smf"), fields);

  const int w = fields.n_phi, h = fields.n_h;
  std::vector<float> k_max(fields.size()), mean(fields.size()), gauss(fields.size());
  for (std::size_t k = 0; k < fields.size(); ++k) {
    k_max[k] = std::max(std::abs(fields.k1[k]), std::abs(fields.k2[k]));
    mean[k] = fields.mean(k);
    gauss[k] = fields.gauss(k);
  }
  write_png(written("curvature_grey.png"), grey_map(k_max, fields.defined, w, h));
  // Seed 000's operator estimates one maximum curvature only (k2 = 0): H and K would be
  // artefacts of that convention, not measurements, so they are not drawn for it.
  const bool two_curvatures = method != CurvatureMethod::Seed000;
  if (two_curvatures) {
    write_png(written("mean_curvature.png"), diverging_map(mean, fields.defined, w, h, "H [1/mm]"));
    write_png(written("gauss_curvature.png"),
              diverging_map(gauss, fields.defined, w, h, "K [1/mm^2]"));
  }
  if (has_normals(fields)) write_png(written("normals.png"), normal_map(fields));
  timings["write_s"] = t.seconds();
  timings["total_s"] = total.seconds();

  nlohmann::json stats;
  stats["k_max"] = percentiles(fields, [&](std::size_t k) { return k_max[k]; });
  stats["k1"] = percentiles(fields, [&](std::size_t k) { return fields.k1[k]; });
  if (two_curvatures) {
    stats["k2"] = percentiles(fields, [&](std::size_t k) { return fields.k2[k]; });
    stats["H"] = percentiles(fields, [&](std::size_t k) { return mean[k]; });
    stats["K"] = percentiles(fields, [&](std::size_t k) { return gauss[k]; });
  }
  const std::size_t defined = fields.defined_count();
  const nlohmann::json report = {{"grid_file", args.grid},
                                 {"method", to_string(method)},
                                 {"radius_mm", fields.radius_mm},
                                 {"grid", grid_summary(grid)},
                                 {"counts",
                                  {{"cells", grid.cell_count()},
                                   {"valid_cells", grid.valid_count()},
                                   {"defined_cells", defined}}},
                                 {"units", {{"k", "1/mm"}, {"H", "1/mm"}, {"K", "1/mm^2"}}},
                                 {"percentiles", stats},
                                 {"files", files},
                                 {"timings", timings},
                                 {"versions", versions()}};
  write_file_atomically(outputs.stage(dir / "curvature.json"), json_text(report) + "\n");

  outputs.commit();
  folder.keep();

  std::ostringstream line;
  line << "curvature (" << to_string(method) << "): " << defined << " of " << grid.valid_count()
       << " valid cells defined";
  if (defined > 0)
    line << ", median max |k| " << std::setprecision(3)
         << report["percentiles"]["k_max"]["p50"].get<double>() << " 1/mm";
  line << "; wrote " << files.size() + 1 << " files to " << dir.string();
  say() << line.str() << "\n";
  result() = report;
  result()["out"] = dir.string();
  return 0;
}

}  // namespace

void register_curvature_commands(CLI::App& app, CommandList& commands) {
  auto curv = std::make_shared<CurvatureArgs>();
  auto* c = app.add_subcommand(
      "curvature", "Normals and curvature of a grid: fields file, pictures and curvature.json");
  c->add_option("grid", curv->grid, "Grid file (.smg)")->required();
  c->add_option("-o,--out", curv->out, "Output folder")->required();
  c->add_option("--method", curv->method,
                "analytic, grid-quadric, quadric or seed (the legacy 7 x 7, 12-direction "
                "maximum-curvature operator; k1 only)")
      ->capture_default_str()
      ->check(CLI::IsMember({"analytic", "grid-quadric", "quadric", "seed", "seed000"}));
  c->add_option("--radius", curv->radius_mm,
                "Neighbourhood radius of the quadric fit (mm; 0: default)")
      ->capture_default_str()
      ->check(in_range(0, 1e4));
  commands.push_back({c, [curv] { return run_curvature(*curv); }});
}

}  // namespace scanmesh::cli
