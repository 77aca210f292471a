// `scanmesh regions` and `scanmesh animesh`: seed 000's animation meshes (docs/animation-meshes.md,
// docs/cli.md).
#include <CLI/CLI.hpp>
#include <cctype>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_support.h"
#include "commands.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_export.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/image.h"
#include "scanmesh/core/image_text.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/core/render.h"
#include "scanmesh/core/texture_layout.h"
#include "scanmesh/meshing/aft/animesh.h"
#include "scanmesh/meshing/aft/data_border.h"
#include "scanmesh/meshing/aft/region_setup.h"
#include "scanmesh/meshing/mesh_check.h"
#include "scanmesh/reconstruction/curvature_maps.h"
#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::cli {

namespace {

using Eigen::Vector2d;

// data_border: "" = not given (the settings file's data_border, else auto).
// line_rows: how the files' y coordinates count ("top": the convention, "bottom": older files).
struct RegionsArgs {
  std::string grid, lines, settings, png, data_border, line_rows = "top";
};

struct AnimeshArgs {
  std::string grid, lines, settings, out, data_border, line_rows = "top";
  std::optional<std::uint64_t> seed;
  std::string strategy;
};

Rgb8 region_color(int r) {
  static const Rgb8 palette[] = {{230, 25, 75},  {60, 180, 75},   {255, 225, 25}, {0, 130, 200},
                                 {245, 130, 48}, {145, 30, 180},  {70, 240, 240}, {240, 50, 230},
                                 {210, 245, 60}, {250, 190, 212}, {0, 128, 128},  {220, 190, 255},
                                 {170, 110, 40}, {255, 250, 200}, {128, 0, 0},    {170, 255, 195},
                                 {128, 128, 0},  {255, 215, 180}, {0, 0, 128},    {128, 128, 128}};
  return palette[r % 20];
}

void plot(Image8& im, double x, double y, Rgb8 c) {
  const int xi = static_cast<int>(std::floor(x)), yi = static_cast<int>(std::floor(y));
  const int xw = ((xi % im.width) + im.width) % im.width;
  if (yi < 0 || yi >= im.height) return;
  im.set_rgb(xw, yi, c);
}

void draw_segment(Image8& im, Vector2d a, Vector2d b, Rgb8 c) {
  const int steps = std::max(1, static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff() * 2)));
  for (int s = 0; s <= steps; ++s) {
    const Vector2d p = a + (b - a) * (static_cast<double>(s) / steps);
    plot(im, p.x(), p.y(), c);
  }
}

// The texture in the grid pixel frame (row j = h index j), in which the region graph's
// geometry is drawn; the finished picture is turned upright (core/texture_layout.h).
Image8 texture_in_grid_rows(const RangeGrid& grid) {
  Image8 im = texture_image(grid);
  flip_rows(im);
  return im;
}

std::string upper_case(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

// Pixels of region r on the row through grid pixel p, left and right of it (at most the width).
int region_run_width(const aft::RegionLocator& locate, const ScanSurface& surface, Vector2d p,
                     std::size_t r, int width) {
  int run = 1;
  for (const int step : {-1, 1})
    for (int k = 1; k < width && run < width; ++k) {
      const auto at = locate.region_at(aft::pixel_to_param(surface, p + Vector2d(step * k, 0)));
      if (!at || *at != static_cast<int>(r)) break;
      ++run;
    }
  return run;
}

Image8 draw_regions(const RangeGrid& grid, const ScanSurface& surface, const aft::RegionGraph& g,
                    const aft::LineSet& lines) {
  Image8 im = texture_in_grid_rows(grid);
  // Region fill: each pixel centre classified by the graph (openings hatched dark).
  const aft::RegionLocator locate(g);
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const auto r = locate.region_at(aft::pixel_to_param(surface, {x + 0.5, y + 0.5}));
      if (!r) continue;
      const Rgb8 c = g.regions[*r].opening ? Rgb8{20, 20, 20} : region_color(*r);
      const Rgb8 t = im.rgb(x, y);
      im.set_rgb(
          x, y,
          {static_cast<std::uint8_t>((t.r + c.r) / 2), static_cast<std::uint8_t>((t.g + c.g) / 2),
           static_cast<std::uint8_t>((t.b + c.b) / 2)});
    }
  for (const auto& seg : g.segments) {
    const auto kind = lines.lines[seg.line].kind;
    const Rgb8 c = kind == aft::LineKind::Opening      ? Rgb8{255, 255, 0}
                   : kind == aft::LineKind::Seam       ? Rgb8{0, 255, 255}
                   : kind == aft::LineKind::DataBorder ? Rgb8{255, 140, 0}
                                                       : Rgb8{255, 255, 255};
    for (std::size_t k = 0; k + 1 < seg.pts.size(); ++k)
      draw_segment(im, aft::param_to_pixel(surface, seg.pts[k]),
                   aft::param_to_pixel(surface, seg.pts[k + 1]), c);
  }
  flip_rows(im);
  // Labels on the upright picture (text drawn before the flip would read upside down): the
  // region's number and, where the settings name it and the name fits inside the region on its
  // label's row, the name, on a light box. Openings stay unlabelled (they are holes).
  for (std::size_t r = 0; r < g.regions.size(); ++r) {
    if (g.regions[r].opening) continue;
    const Vector2d grid_px = aft::param_to_pixel(surface, g.regions[r].label_point);
    const std::string number = std::to_string(r);
    const std::string& name = g.regions[r].name;
    const bool named = !name.empty() && name != "region-" + number;
    std::string text = named ? number + " " + upper_case(name) : number;
    if (named && text_width(text) + 2 > region_run_width(locate, surface, grid_px, r, im.width))
      text = number;
    const Vector2d p = texture_to_grid_pixel(grid_px, im.height);
    const int w = text_width(text) + 2, h = text_height() + 2;
    const int x = (static_cast<int>(p.x()) % im.width + im.width) % im.width;
    draw_label(im, std::clamp(x - w / 2, 0, std::max(0, im.width - w)),
               std::clamp(static_cast<int>(p.y()) - h / 2, 0, std::max(0, im.height - h)), text,
               {0, 0, 0}, {245, 245, 245});
  }
  return im;
}

Image8 draw_mesh_2d(const RangeGrid& grid, const ScanSurface& surface,
                    const aft::AnimationMesh& am) {
  Image8 im = texture_in_grid_rows(grid);
  auto px = [&](int v) { return aft::param_to_pixel(surface, am.params[v]); };
  for (const auto& t : am.mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      Vector2d a = px(t[k]), b = px(t[(k + 1) % 3]);
      b.x() = a.x() + std::remainder(b.x() - a.x(), static_cast<double>(im.width));
      draw_segment(im, a, b, {20, 20, 60});
    }
  for (const auto& e : am.line_edges) {
    Vector2d a = px(e[0]), b = px(e[1]);
    b.x() = a.x() + std::remainder(b.x() - a.x(), static_cast<double>(im.width));
    draw_segment(im, a, b, {255, 40, 40});
  }
  flip_rows(im);
  return im;
}

// The grid and what set_up_regions made of it (the surface holds its own copy of the grid's
// planes).
struct Loaded : aft::RegionSetup {
  RangeGrid grid;
};

Loaded load(const std::string& grid_path, const std::string& lines_path,
            const std::string& settings_path, const std::string& data_border,
            const std::string& line_rows) {
  Loaded l;
  l.grid = read_grid(grid_path);
  // No --lines: no user lines (the data border alone can make a region of a partial scan).
  // The option wins over the settings file's data_border, which wins over auto.
  static_cast<aft::RegionSetup&>(l) = aft::set_up_regions(
      l.grid, lines_path.empty() ? std::nullopt : std::optional<std::filesystem::path>(lines_path),
      settings_path.empty() ? std::nullopt : std::optional<std::filesystem::path>(settings_path),
      data_border.empty() ? std::nullopt : std::optional<std::string>(data_border), line_rows);
  return l;
}

// One line, only when a border was added (a full scan's output stays as it was).
std::string border_text(const Loaded& l) {
  if (!l.border.border_on) return "";
  return "data border (" + std::string(aft::to_string(l.border_mode)) +
         "): " + std::to_string(l.border.border_lines) + " border lines, " +
         std::to_string(l.border.clipped_lines) + " lines clipped, " +
         std::to_string(l.border.dropped_lines) + " lines outside the data dropped\n";
}

nlohmann::json border_json(const Loaded& l) {
  return {{"mode", aft::to_string(l.border_mode)},
          {"on", l.border.border_on},
          {"border_lines", l.border.border_lines},
          {"clipped_lines", l.border.clipped_lines},
          {"dropped_lines", l.border.dropped_lines}};
}

// The radius ratio 2 r_in / R_circ in bins of 0.1; from 0.5 on drawn as good (0.5 is about a
// 30-30-120 or a 20-80-80 deg triangle).
void write_radius_ratio_histogram_png(const std::filesystem::path& path,
                                      const aft::AnimationMeshQuality& q) {
  std::vector<std::size_t> counts(q.radius_ratio_histogram.begin(), q.radius_ratio_histogram.end());
  std::vector<std::string> labels;
  for (std::size_t i = 0; i < counts.size(); ++i)
    labels.push_back(i == 0 ? "0" : "." + std::to_string(i));
  write_histogram_png(path, counts, labels, "RADIUS RATIO 2 R_IN / R_CIRC",
                      {.begin = 5, .end = counts.size()});
}

int run_regions(const RegionsArgs& a) {
  const Loaded l = load(a.grid, a.lines, a.settings, a.data_border, a.line_rows);
  say() << border_text(l) << l.graph.to_text();
  if (!a.png.empty()) {
    write_png(a.png, draw_regions(l.grid, *l.surface, l.graph, l.lines));
    say() << "region layout: " << a.png << "\n";
  }
  nlohmann::json regions = nlohmann::json::array();
  for (std::size_t r = 0; r < l.graph.regions.size(); ++r) {
    const aft::Region& reg = l.graph.regions[r];
    regions.push_back({{"region", r},
                       {"name", reg.name},
                       {"opening", reg.opening},
                       {"area_rad_mm", reg.area},
                       {"unit_mm", reg.unit_mm},
                       {"mesher", reg.mesher}});
  }
  result() = {
      {"regions", regions}, {"segments", l.graph.segments.size()}, {"data_border", border_json(l)}};
  if (!a.png.empty()) result()["png"] = a.png;
  return 0;
}

int run_animesh(const AnimeshArgs& a) {
  Stopwatch total;
  const std::filesystem::path out(a.out);
  OutputFolder folder(out);  // before the work: a bad --out fails at once (removed on failure)
  Loaded l = load(a.grid, a.lines, a.settings, a.data_border, a.line_rows);
  if (a.seed) l.settings.seed = *a.seed;
  if (a.strategy == "random") l.settings.strategy = aft::EdgeStrategy::Random;
  if (a.strategy == "shortest") l.settings.strategy = aft::EdgeStrategy::Shortest;
  if (a.strategy == "longest") l.settings.strategy = aft::EdgeStrategy::Longest;
  const double t_load = total.seconds();
  Stopwatch mesh_time;
  const aft::AnimationMesh am = aft::build_animation_mesh(l.graph, l.lines, *l.surface, l.settings);
  const double t_mesh = mesh_time.seconds();
  const aft::AnimationMeshQuality q = aft::evaluate_quality(am, *l.surface, 6, &l.graph);
  const MeshCheckReport check = check_mesh(am.mesh);
  // The outputs appear together or not at all: a write that fails half way (a full disk) must
  // not leave this run's mesh next to an earlier run's report.
  StagedFiles outputs;
  write_ply(outputs.stage(out / "mesh.ply"), am.mesh);
  write_obj(outputs.stage(out / "mesh.obj"), am.mesh);
  write_png(outputs.stage(out / "regions.png"), draw_regions(l.grid, *l.surface, l.graph, l.lines));
  write_png(outputs.stage(out / "mesh2d.png"), draw_mesh_2d(l.grid, *l.surface, am));
  Mesh colored = am.mesh;
  colored.colors.assign(colored.positions.size(), Rgb8{200, 200, 200});
  for (std::size_t t = 0; t < colored.triangles.size(); ++t)
    for (int v : colored.triangles[t]) {
      // Half way to light grey: the regions stay apart and the shading still shows the shape.
      const Rgb8 c = region_color(colored.face_labels[t]);
      colored.colors[v] = {static_cast<std::uint8_t>((c.r + 210) / 2),
                           static_cast<std::uint8_t>((c.g + 210) / 2),
                           static_cast<std::uint8_t>((c.b + 210) / 2)};
    }
  RenderOptions ro;
  ro.draw_wireframe = true;
  ro.use_vertex_colors = true;  // region colours: the layout on the shaded surface
  write_png(outputs.stage(out / "render.png"), render_mesh(colored, ro));
  write_min_angle_histogram_png(outputs.stage(out / "min_angle_histogram.png"), check);
  write_radius_ratio_histogram_png(outputs.stage(out / "radius_ratio_histogram.png"), q);
  int unmeshed = 0;
  for (const auto& s : am.region_stats) unmeshed += s.unmeshed_front_edges;
  nlohmann::json j;
  j["vertices"] = am.mesh.positions.size();
  j["triangles"] = am.mesh.triangles.size();
  int steiner = 0;
  for (auto s : am.steiner) steiner += s;
  j["steiner_points"] = steiner;
  j["flips"] = am.flips;
  j["valence_flip_retries"] = am.valence_flip_retries;
  j["regions_remeshed"] = am.regions_remeshed;
  j["small_angle_repair"] = {{"optimise", am.repair_operations[0]},
                             {"flip", am.repair_operations[1]},
                             {"collapse", am.repair_operations[2] + am.repair_operations[3]},
                             {"split", am.repair_operations[4]},
                             {"left_below_20_deg", am.repair_left_below_20},
                             {"left_above_deviation_goal", am.repair_left_above_deviation_goal},
                             {"forced_below_20_deg", am.repair_forced_below_20}};
  j["time_s"] = {{"load_and_regions", t_load},
                 {"mesh", t_mesh},
                 {"mesh_stages",
                  {{"segments", am.seconds.segments},
                   {"regions", am.seconds.regions},
                   {"crossing_check", am.seconds.check},
                   {"serial_flips", am.seconds.flips},
                   {"serial_smoothing", am.seconds.smoothing},
                   {"serial_repair", am.seconds.repair}}},
                 {"region_thread_seconds",
                  {{"mesher", am.thread_seconds.regions},
                   {"flips", am.thread_seconds.flips},
                   {"smoothing", am.thread_seconds.smoothing},
                   {"repair", am.thread_seconds.repair}}}};
  j["serial_postprocessing_fallback"] = am.serial_postprocessing;
  j["quality"] = {{"min_angle_deg", q.min_angle_deg},
                  {"min_angle_away_from_sharp_junctions_deg", q.min_angle_non_exempt_deg},
                  {"exempt_triangles", q.small_angle_exempt},
                  {"max_angle_deg", q.max_angle_deg},
                  {"fraction_min_angle_ge_30", q.fraction_min_angle_ge_30},
                  {"fraction_min_angle_ge_20", q.fraction_min_angle_ge_20},
                  {"mean_radius_ratio", q.mean_radius_ratio},
                  {"min_radius_ratio", q.min_radius_ratio},
                  {"min_angle_histogram_5deg", q.min_angle_histogram},
                  {"radius_ratio_histogram_0.1", q.radius_ratio_histogram},
                  {"hausdorff_mesh_to_surface_mm", q.hausdorff_mesh_to_surface_mm},
                  {"hausdorff_surface_to_mesh_mm", q.hausdorff_surface_to_mesh_mm},
                  {"max_vertex_offset_mm", q.max_vertex_offset_mm},
                  {"vertices_off_surface", q.vertices_off_surface}};
  nlohmann::json val;
  for (const auto& [v, n] : q.valence_histogram) val[std::to_string(v)] = n;
  j["quality"]["valence_histogram"] = val;
  nlohmann::json regions = nlohmann::json::array();
  for (const auto& s : am.region_stats)
    regions.push_back({{"region", s.region},
                       {"name", l.graph.regions[s.region].name},
                       {"unit_mm", l.graph.regions[s.region].unit_mm},
                       {"mesher", s.mesher},
                       {"triangles", s.triangles},
                       {"steiner_points", s.steiner_points},
                       {"chose_new", s.chose_new},
                       {"chose_existing", s.chose_existing},
                       {"chose_circumcentre", s.chose_circumcentre},
                       {"rejected_circumcentres", s.rejected_circumcentres},
                       {"unmeshed_front_edges", s.unmeshed_front_edges}});
  j["regions"] = regions;
  j["data_border"] = border_json(l);
  j["line_edges"] = am.line_edges;
  j["seams"] = am.seams;
  j["check"] = {{"edge_manifold", check.edge_manifold()},
                {"duplicate_faces", check.duplicate_faces},
                {"self_intersections", check.self_intersections},
                {"boundary_loops", check.topology.boundary_loops}};
  write_file_atomically(outputs.stage(out / "animesh.json"), json_text(j) + "\n");
  outputs.commit();
  folder.keep();
  say() << border_text(l) << l.graph.to_text() << am.mesh.positions.size() << " vertices ("
        << steiner << " Steiner points), " << am.mesh.triangles.size() << " triangles, meshed in "
        << t_mesh << " s\n"
        << q.to_text() << "outputs in " << out.string()
        << "/: mesh.ply mesh.obj animesh.json regions.png mesh2d.png render.png "
           "min_angle_histogram.png radius_ratio_histogram.png\n";
  result() = j;
  result()["out"] = out.string();
  // The mesher's guarantees, checked on what was written: open fronts or a failed check are
  // reported in one line and by their own exit code (the outputs stay, animesh.json says where).
  std::vector<std::string> defects;
  if (unmeshed > 0) defects.push_back(std::to_string(unmeshed) + " front edges not closed (gaps)");
  if (!check.edge_manifold()) defects.push_back("not edge-manifold");
  if (check.self_intersections > 0)
    defects.push_back(std::to_string(check.self_intersections) + " intersecting face pairs");
  if (check.duplicate_faces > 0)
    defects.push_back(std::to_string(check.duplicate_faces) + " duplicate faces");
  if (defects.empty()) return kSuccess;
  std::string what;
  for (const std::string& d : defects) what += (what.empty() ? "" : ", ") + d;
  std::cerr << "scanmesh: incomplete mesh: " << what << "; see " << (out / "animesh.json").string()
            << "\n";
  return kMeshIncomplete;
}

void add_data_border_option(CLI::App* command, std::string& value) {
  command
      ->add_option("--data-border", value,
                   "Edge of the scan's data as a region border: auto (when the data miss part "
                   "of the turn) | on | off (default: the settings' data_border, else auto)")
      ->check(CLI::IsMember({"auto", "on", "off"}));
}

void add_line_rows_option(CLI::App* command, std::string& value) {
  command
      ->add_option("--line-rows", value,
                   "How the y of --lines and the settings' points count: top (rows down from "
                   "the top of the upright texture.png) | bottom (h rows up: files written "
                   "before pictures were upright)")
      ->capture_default_str()
      ->check(CLI::IsMember({"top", "bottom"}));
}

}  // namespace

void register_aft_commands(CLI::App& app, CommandList& commands) {
  auto ra = std::make_shared<RegionsArgs>();
  CLI::App* r = app.add_subcommand("regions", "Region analysis of animation lines over a scan");
  r->add_option("grid", ra->grid, "Range grid (.smg)")->required()->check(CLI::ExistingFile);
  r->add_option("--lines", ra->lines, "Animation lines (.svg or .json); none: the data border only")
      ->check(CLI::ExistingFile);
  r->add_option("--settings", ra->settings, "Region settings (.yaml/.json)")
      ->check(CLI::ExistingFile);
  r->add_option("--png", ra->png, "Draw the regions over the texture into this PNG");
  add_data_border_option(r, ra->data_border);
  add_line_rows_option(r, ra->line_rows);
  commands.push_back({r, [ra] { return run_regions(*ra); }});

  auto aa = std::make_shared<AnimeshArgs>();
  CLI::App* m = app.add_subcommand("animesh", "Animation mesh: regions meshed by advancing fronts");
  m->add_option("grid", aa->grid, "Range grid (.smg)")->required()->check(CLI::ExistingFile);
  m->add_option("--lines", aa->lines, "Animation lines (.svg or .json); none: the data border only")
      ->check(CLI::ExistingFile);
  m->add_option("--settings", aa->settings, "Region settings (.yaml/.json)")
      ->check(CLI::ExistingFile);
  m->add_option("--out", aa->out, "Output directory")->required();
  m->add_option("--seed", aa->seed, "Seed of the random edge order")->check(seed_range());
  m->add_option("--strategy", aa->strategy, "Front edge order: random | shortest | longest")
      ->check(CLI::IsMember({"random", "shortest", "longest"}));
  add_data_border_option(m, aa->data_border);
  add_line_rows_option(m, aa->line_rows);
  commands.push_back({m, [aa] { return run_animesh(*aa); }});
}

}  // namespace scanmesh::cli
