#include "pipeline.h"

#include <pcl/pcl_config.h>
#include <png.h>
#include <Eigen/Core>

#include <cstdio>
#include <system_error>

#include "cli_support.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/image_text.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/meshing/mesh_topology.h"

namespace scanmesh::cli {

sim::Scene load_scene(const std::string& path) {
  return path.empty() ? sim::builtin_head_scene() : sim::Scene::from_yaml_file(path);
}

sim::ScannerConfig load_scanner(const std::string& path) {
  return path.empty() ? sim::builtin_head_scanner() : sim::ScannerConfig::from_yaml_file(path);
}

sim::SimulatedScan simulate_with_progress(const sim::Scene& scene,
                                          const sim::ScannerConfig& config) {
  Progress progress("simulating");
  auto scan =
      sim::simulate_scan(scene, config, [&](int done, int total) { progress.update(done, total); });
  progress.finish();
  return scan;
}

Image8 render_views(const Mesh& mesh, int view_size) {
  // The built-in head looks towards azimuth 180 deg, so these are its front, three-quarter and
  // side views; each view names its camera so that other objects' views can be told apart.
  struct View {
    double azimuth;
    const char* name;
  };
  std::vector<Image8> views;
  for (const View& v : {View{180.0, "FRONT"}, View{225.0, "THREE-QUARTER"}, View{270.0, "SIDE"}}) {
    Image8 image =
        render_mesh(mesh, {.width = view_size, .height = view_size, .azimuth_deg = v.azimuth});
    const int scale = view_size >= 400 ? 2 : 1;
    char caption[64];
    std::snprintf(caption, sizeof caption, "%s (AZIMUTH %.0f)", v.name, v.azimuth);
    draw_text(image, 8 * scale, 8 * scale, caption, {220, 220, 220}, scale);
    views.push_back(std::move(image));
  }
  return hconcat(views);
}

void write_mesh_files(const std::filesystem::path& ply, const std::filesystem::path& obj,
                      const Mesh& mesh, const std::string& texture_png) {
  if (!ply.empty()) write_ply(ply, mesh);
  if (!obj.empty()) write_obj(obj, mesh, texture_png);
}

nlohmann::json to_json(const sim::ScannerConfig& c) {
  return {{"n_phi", c.n_phi},
          {"n_h", c.n_h},
          {"radius_mm", c.radius_mm},
          {"h0_mm", c.h0_mm},
          {"dh_mm", c.dh_mm},
          {"noise_sigma_mm", c.noise_sigma_mm},
          {"grazing_dropout", c.grazing_dropout},
          {"grazing_limit_deg", c.grazing_limit_deg},
          {"occlusion", c.occlusion},
          {"camera_baseline_deg", c.camera_baseline_deg},
          {"hair", c.hair},
          {"hair_noise_sigma_mm", c.hair_noise_sigma_mm},
          {"hair_dropout_probability", c.hair_dropout_probability},
          {"spike_probability", c.spike_probability},
          {"height_band", c.height_band},
          {"band_min_mm", c.band_min_mm},
          {"band_max_mm", c.band_max_mm},
          {"seed", c.seed}};
}

nlohmann::json to_json(const CleaningOptions& o) {
  return {{"spike_threshold_mm", o.spike_threshold_mm},
          {"spike_spread_factor", o.spike_spread_factor},
          {"spike_min_neighbours", o.spike_min_neighbours},
          {"min_component_cells", o.min_component_cells}};
}

nlohmann::json to_json(const CleaningReport& r) {
  return {{"valid_before", r.valid_before},
          {"valid_after", r.valid_after},
          {"spikes_removed", r.spikes_removed},
          {"fragments_removed", r.fragments_removed},
          {"fragment_cells_removed", r.fragment_cells_removed},
          {"components_kept", r.components_kept}};
}

nlohmann::json to_json(const GridMeshOptions& o) {
  return {{"max_depth_jump_mm", o.max_depth_jump_mm}, {"close_seam", o.close_seam}};
}

nlohmann::json grid_summary(const RangeGrid& grid) {
  return {{"n_phi", grid.n_phi()},
          {"n_h", grid.n_h()},
          {"h0_mm", grid.h0()},
          {"dh_mm", grid.dh()},
          {"phi0_rad", grid.phi0()},
          {"cells", grid.cell_count()},
          {"valid_cells", grid.valid_count()},
          {"metadata", grid.metadata}};
}

nlohmann::json mesh_summary(const Mesh& mesh) {
  const TopologyStats t = topology_stats(mesh);
  return {{"vertices", mesh.vertex_count()},
          {"faces", mesh.face_count()},
          {"edges", t.edges},
          {"boundary_edges", t.boundary_edges},
          {"nonmanifold_edges", t.nonmanifold_edges},
          {"inconsistently_oriented_edges", t.inconsistent_edges},
          {"boundary_loops", t.boundary_loops},
          {"euler_characteristic", t.euler_characteristic}};
}

nlohmann::json versions() {
  return {
      {"scanmesh", SCANMESH_VERSION},
      {"compiler", __VERSION__},
      {"eigen", std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) +
                    "." + std::to_string(EIGEN_MINOR_VERSION)},
      {"pcl", PCL_VERSION_PRETTY},
      {"libpng", PNG_LIBPNG_VER_STRING},
      {"nlohmann_json", std::to_string(NLOHMANN_JSON_VERSION_MAJOR) + "." +
                            std::to_string(NLOHMANN_JSON_VERSION_MINOR) + "." +
                            std::to_string(NLOHMANN_JSON_VERSION_PATCH)}};
}

}  // namespace scanmesh::cli
