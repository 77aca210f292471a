// `scanmesh demo`: the whole walking skeleton on the built-in head, in one output folder.
//   simulated scan -> cleaned grid -> grid mesh -> mesh files, pictures, report.json
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>

#include "cli_support.h"
#include "commands.h"
#include "pipeline.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/grid_export.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/reconstruction/curvature_maps.h"
#include "scanmesh/reconstruction/fields_file.h"
#include "scanmesh/reconstruction/surface_fields.h"

namespace scanmesh::cli {

namespace {

struct ErrorStats {
  double sum = 0, sum_sq = 0, max_abs = 0;
  std::size_t n = 0;
  void add(double e) {
    sum += e;
    sum_sq += e * e;
    max_abs = std::max(max_abs, std::abs(e));
    ++n;
  }
  nlohmann::json to_json() const {
    return {{"cells", n},
            {"mean_error_mm", n ? sum / n : 0.0},
            {"rms_error_mm", n ? std::sqrt(sum_sq / n) : 0.0},
            {"max_abs_error_mm", max_abs}};
  }
};

// How far the cleaned grid is from the simulator's exact surface, and what cleaning caught.
// Skin and hair are reported apart: the hair zone is simulated much noisier on purpose.
nlohmann::json accuracy_against_truth(const RangeGrid& raw, const RangeGrid& cleaned,
                                      const sim::SimulatedScan& scan, const sim::Scene& scene) {
  ErrorStats skin, hair;
  std::size_t spikes_in = 0, spikes_left = 0, good_removed = 0, skin_removed = 0;
  for (std::size_t k = 0; k < cleaned.cell_count(); ++k) {
    const auto& truth = scan.truth[k];
    if (raw.validity()[k] && truth.spike) ++spikes_in;
    if (!cleaned.validity()[k]) {
      if (raw.validity()[k] && !truth.spike) {
        ++good_removed;
        skin_removed += !scene.in_hair_zone(truth.point);
      }
      continue;
    }
    if (truth.spike) {
      ++spikes_left;
      continue;
    }
    const double e = cleaned.radii()[k] - truth.radius;
    (scene.in_hair_zone(truth.point) ? hair : skin).add(e);
  }
  return {{"outside_hair", skin.to_json()},
          {"hair", hair.to_json()},
          {"spikes_simulated", spikes_in},
          {"spikes_left_after_cleaning", spikes_left},
          {"non_spike_cells_removed_by_cleaning", good_removed},
          {"non_spike_cells_removed_outside_hair", skin_removed}};
}

// Quadric-fit curvature against the exact implicit surface, outside the (noisier) hair.
nlohmann::json curvature_against_truth(const SurfaceFields& f, const sim::SimulatedScan& scan,
                                       const sim::Scene& scene) {
  std::vector<double> h_err, normal_deg;
  for (std::size_t k = 0; k < f.size(); ++k) {
    if (!f.defined[k] || scene.in_hair_zone(scan.truth[k].point)) continue;
    const auto& t = scan.truth[k].geometry;
    normal_deg.push_back(
        std::acos(std::clamp(f.normal[k].cast<double>().dot(t.normal), -1.0, 1.0)) * 180.0 /
        std::numbers::pi);
    if (std::abs(t.mean()) > 0.005)
      h_err.push_back(std::abs(f.mean(k) - t.mean()) / std::abs(t.mean()));
  }
  auto median = [](std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  return {{"method", to_string(f.method)},
          {"radius_mm", f.radius_mm},
          {"defined_cells", f.defined_count()},
          {"median_rel_error_H_outside_hair_where_abs_H_above_0.005", median(h_err)},
          {"median_normal_error_deg_outside_hair", median(normal_deg)}};
}

nlohmann::json drop_counts(const sim::SimulatedScan& scan) {
  std::size_t counts[6] = {};
  for (const auto& t : scan.truth) ++counts[static_cast<int>(t.drop)];
  return {{"no_hit", counts[static_cast<int>(sim::DropReason::NoHit)]},
          {"outside_band", counts[static_cast<int>(sim::DropReason::OutsideBand)]},
          {"grazing", counts[static_cast<int>(sim::DropReason::Grazing)]},
          {"occluded", counts[static_cast<int>(sim::DropReason::Occluded)]},
          {"hair_speckle", counts[static_cast<int>(sim::DropReason::HairSpeckle)]}};
}

}  // namespace

GridProducts write_grid_products(const std::filesystem::path& out, const RangeGrid& grid,
                                 const GridMeshOptions& meshing, nlohmann::json& timings) {
  GridProducts p;
  Stopwatch t;
  p.meshed = grid_mesh(grid, meshing);
  timings["grid_mesh_s"] = t.seconds();
  p.mesh_json = {{"options", to_json(meshing)},
                 {"quads_meshed", p.meshed.quads_meshed},
                 {"quads_skipped_for_holes", p.meshed.quads_skipped_for_holes},
                 {"quads_skipped_for_depth_jumps", p.meshed.quads_skipped_for_depth_jumps},
                 {"mesh", mesh_summary(p.meshed.mesh)}};

  t = {};
  export_texture_png(out / "texture.png", grid);
  export_depth_png(out / "depth.png", grid);
  export_pcd(out / "scan.pcd", grid);
  write_mesh_files(out / "mesh.ply", out / "mesh.obj", p.meshed.mesh, "texture.png");
  timings["write_files_s"] = t.seconds();

  t = {};
  p.fields = compute_fields_grid_quadric(grid);
  timings["curvature_s"] = t.seconds();
  write_fields(out / "fields.smf", p.fields);
  std::vector<float> mean(p.fields.size());
  for (std::size_t k = 0; k < p.fields.size(); ++k) mean[k] = p.fields.mean(k);
  write_png(out / "curvature.png",
            diverging_map(mean, p.fields.defined, grid.n_phi(), grid.n_h(), "H [1/mm]"));

  t = {};
  write_png(out / "render.png", render_views(p.meshed.mesh));
  timings["render_s"] = t.seconds();
  return p;
}

namespace {

int run_demo(const DemoArgs& args) {
  if (args.device.enabled) return run_device_demo(args);
  const std::filesystem::path out(args.out);
  OutputFolder folder(out);
  nlohmann::json timings;
  Stopwatch total;

  const sim::Scene scene = load_scene(args.scene);
  sim::ScannerConfig config = load_scanner(args.scanner);
  if (args.seed) config.seed = *args.seed;
  config.validate();

  Stopwatch t;
  const sim::SimulatedScan scan = simulate_with_progress(scene, config);
  timings["simulate_s"] = t.seconds();
  write_grid(out / "scan_raw.smg", scan.grid);

  t = {};
  RangeGrid grid = scan.grid;
  const CleaningReport cleaning = clean_grid(grid, args.cleaning);
  timings["clean_s"] = t.seconds();
  grid.metadata["cleaned"] = "spikes and fragments removed";
  write_grid(out / "scan.smg", grid);

  const GridProducts products = write_grid_products(out, grid, args.meshing, timings);
  const GridMesh& meshed = products.meshed;
  const SurfaceFields& fields = products.fields;
  timings["total_s"] = total.seconds();

  const nlohmann::json report = {
      {"scene", scene.name},
      {"scanner", to_json(config)},
      {"raw_grid", grid_summary(scan.grid)},
      {"dropouts", drop_counts(scan)},
      {"cleaning", {{"options", to_json(args.cleaning)}, {"result", to_json(cleaning)}}},
      {"accuracy_vs_ground_truth", accuracy_against_truth(scan.grid, grid, scan, scene)},
      {"grid_mesh", products.mesh_json},
      {"curvature", curvature_against_truth(fields, scan, scene)},
      {"timings", timings},
      {"versions", versions()},
      {"files",
       {"scan_raw.smg", "scan.smg", "scan.pcd", "mesh.ply", "mesh.obj", "mesh.mtl", "texture.png",
        "depth.png", "render.png", "fields.smf", "curvature.png", "report.json"}}};
  write_file_atomically(out / "report.json", json_text(report) + "\n");

  say() << "scanmesh demo: " << scene.name << ", " << grid.n_phi() << " x " << grid.n_h()
        << " grid, " << grid.valid_count() << " valid cells after cleaning\n"
        << "  mesh: " << meshed.mesh.vertex_count() << " vertices, " << meshed.mesh.face_count()
        << " triangles\n"
        << "  rms error vs ground truth (outside hair): "
        << report["accuracy_vs_ground_truth"]["outside_hair"]["rms_error_mm"].get<double>()
        << " mm\n"
        << "  outputs in " << out.string() << "/: mesh.ply mesh.obj mesh.mtl texture.png depth.png"
        << " render.png curvature.png fields.smf scan.smg scan_raw.smg scan.pcd report.json\n";
  result() = report;
  result()["out"] = out.string();
  folder.keep();
  return 0;
}

}  // namespace

void register_demo_commands(CLI::App& app, CommandList& commands) {
  auto demo = std::make_shared<DemoArgs>();
  auto* c =
      app.add_subcommand("demo", "Simulated head scan -> clean grid -> mesh, pictures and report");
  c->add_option("-o,--out", demo->out, "Output folder")->capture_default_str();
  c->add_option("--scene", demo->scene, "Scene YAML (default: built-in head)")
      ->check(CLI::ExistingFile);
  c->add_option("--scanner", demo->scanner, "Scanner YAML (default: built-in head scanner)")
      ->check(CLI::ExistingFile);
  c->add_option("--seed", demo->seed, "Random seed of all defects")->check(seed_range());
  add_cleaning_options(*c, demo->cleaning);
  add_mesh_options(*c, demo->meshing);
  add_device_demo_options(*c, demo->device);
  commands.push_back({c, [demo] { return run_demo(*demo); }});
}

}  // namespace scanmesh::cli
