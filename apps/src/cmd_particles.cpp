// `scanmesh particles`: seed 003's spring-network triangulation of an implicit surface, a
// static scene, an animated skeleton (one PLY per frame + a PNG strip) or a scan's continuous
// surface (docs/particles.md, docs/cli.md).
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_support.h"
#include "commands.h"
#include "implicit_adapters.h"
#include "pipeline.h"
#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/config_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/image.h"
#include "scanmesh/core/render.h"
#include "scanmesh/meshing/mesh_topology.h"
#include "scanmesh/meshing/particles/particles.h"
#include "scanmesh/reconstruction/scan_surface.h"

namespace scanmesh::cli {

namespace {

struct ParticlesArgs {
  std::string scene;  //!< static scene or animated skeleton YAML
  std::string grid;   //!< scan mode: grid file
  double edge = 0.0;  //!< R
  bool adaptive = false;
  int frames = 10;
  int steps_per_frame = 20;
  bool no_flips = false;
  std::uint64_t seed = 1;
  std::string out;
};

using Eigen::Vector3d;

//! Union (min) of a static scene's objects.
class SceneUnionSurface final : public particles::ImplicitSurface {
 public:
  SceneUnionSurface(const sim::Scene& scene, Eigen::AlignedBox3d box)
      : objects_(scene.objects), box_(box) {}
  std::optional<particles::ImplicitValue> evaluate(const Vector3d& x) const override {
    sim::FieldSample best;
    best.value = 1e300;
    for (const auto& o : objects_) {
      const sim::FieldSample f = o->field(x);
      if (f.value < best.value) best = f;
    }
    return particles::ImplicitValue{.value = best.value, .gradient = best.gradient};
  }
  Eigen::AlignedBox3d bounds() const override { return box_; }

 private:
  std::vector<std::shared_ptr<const sim::SceneObject>> objects_;
  Eigen::AlignedBox3d box_;
};

// The scene's own bounds (every sim object knows its box), clipped to a 2 m cube around the
// origin so an unbounded shape (an infinite cylinder) still gives a finite meshing domain.
Eigen::AlignedBox3d find_bounds(const sim::Scene& scene) {
  const Eigen::AlignedBox3d world(Vector3d::Constant(-1000.0), Vector3d::Constant(1000.0));
  Eigen::AlignedBox3d box = scene.bounds();
  if (box.isEmpty()) throw InvalidInputError("particles: the scene has no objects");
  box = box.intersection(world);
  if (box.isEmpty())
    throw InvalidInputError("particles: the scene lies outside the 2 m cube around the origin");
  const Vector3d margin = 0.02 * box.sizes() + Vector3d::Constant(1e-3);
  box.min() -= margin;
  box.max() += margin;
  return box;
}

nlohmann::json mesh_json(const Mesh& m) {
  const TopologyStats s = topology_stats(m);
  return {{"vertices", m.vertex_count()},
          {"triangles", m.face_count()},
          {"boundary_loops", s.boundary_loops},
          {"nonmanifold_edges", s.nonmanifold_edges},
          {"euler_characteristic", s.euler_characteristic}};
}

int run_particles(const ParticlesArgs& args) {
  if (args.scene.empty() == args.grid.empty())
    throw InvalidInputError("particles: give either a SCENE.yaml or --grid GRID.smg");
  if (!(args.edge > 0.0)) throw InvalidInputError("particles: --edge must be positive");
  const std::filesystem::path out(args.out);
  OutputFolder folder(out);
  particles::ParticleOptions o{.edge_length = args.edge, .adaptive = args.adaptive};
  o.flips = !args.no_flips;
  o.seed = args.seed;
  nlohmann::json report = {{"edge_length", args.edge}, {"adaptive", args.adaptive}};
  const Stopwatch watch;
  // A full-resolution scan can take minutes: a bar on the terminal (iterations of the final
  // relaxation against its limit, then frames).
  Progress progress("particles");
  o.progress = [&progress](int done, int total) { progress.update(done, total); };

  // A scene is a configuration: its size limit holds before it is parsed (a 22 MB scene was
  // read whole and parsed here, 14 s and 1.6 GB, before the scene reader refused it).
  if (!args.grid.empty() ||
      !sim::AnimatedSkeleton::is_animated_yaml(read_config_text(args.scene))) {
    Mesh mesh;
    std::vector<std::uint64_t> ids;
    int iterations = 0;
    bool converged = false;
    if (!args.grid.empty()) {
      const ScanSurface surface(read_grid(args.grid));
      const particles::ScanImplicitSurface implicit(surface);
      auto r = particles::particle_mesh(implicit, o);
      mesh = std::move(r.mesh), ids = std::move(r.vertex_ids), iterations = r.iterations;
      converged = r.converged;
      report["mode"] = "scan";
    } else {
      const sim::Scene scene = load_scene(args.scene);
      const SceneUnionSurface surface(scene, find_bounds(scene));
      auto r = particles::particle_mesh(surface, o);
      mesh = std::move(r.mesh), ids = std::move(r.vertex_ids), iterations = r.iterations;
      converged = r.converged;
      report["mode"] = "static";
    }
    progress.finish();
    particles::write_ply_with_ids(out / "particles.ply", mesh, ids);
    write_png(out / "particles.png", render_views(mesh));
    report["iterations"] = iterations;
    report["converged"] = converged;
    report["mesh"] = mesh_json(mesh);
    report["seconds"] = watch.seconds();
    write_file_atomically(out / "particles.json", json_text(report) + "\n");
    say() << "particles: " << mesh.vertex_count() << " vertices, " << mesh.face_count()
          << " triangles after " << iterations << " iterations ("
          << (converged ? "converged" : "NOT converged: iteration limit") << ") -> " << out.string()
          << "\n";
    result() = report;
    result()["out"] = out.string();
    folder.keep();
    return 0;
  }

  // Animated skeleton: frames evenly over the keyframe range.
  const auto skeleton = std::make_shared<const sim::AnimatedSkeleton>(
      sim::AnimatedSkeleton::from_yaml_file(args.scene));
  const auto surface_at =
      [skeleton](double t) -> std::shared_ptr<const particles::ImplicitSurface> {
    return std::make_shared<AnimatedSkeletonSurface>(skeleton, t);
  };
  const auto frames = particles::animate(surface_at, skeleton->start_time(), skeleton->end_time(),
                                         args.frames, o, args.steps_per_frame);
  progress.finish();
  nlohmann::json list = nlohmann::json::array();
  std::vector<Image8> strip;
  const std::size_t shown = std::min<std::size_t>(frames.size(), 12);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04zu.ply", f);
    particles::write_ply_with_ids(out / name, frames[f].mesh, frames[f].vertex_ids);
    nlohmann::json j = mesh_json(frames[f].mesh);
    j["file"] = name;
    j["time"] = frames[f].time;
    j["cuts"] = frames[f].cuts;
    j["fallback_cuts"] = frames[f].fallback_cuts;
    list.push_back(j);
    // The strip shows at most 12 frames, evenly spread, all with the same camera.
    if (shown > 0 && (f * (shown - 1)) % std::max<std::size_t>(frames.size() - 1, 1) < shown - 1)
      strip.push_back(render_mesh(frames[f].mesh, {.width = 256,
                                                   .height = 256,
                                                   .azimuth_deg = 270.0,
                                                   .elevation_deg = 20.0,
                                                   .use_vertex_colors = false}));
  }
  write_png(out / "frames.png", hconcat(strip));
  report["mode"] = "animation";
  report["frames"] = list;
  report["seconds"] = watch.seconds();
  write_file_atomically(out / "particles.json", json_text(report) + "\n");
  say() << "particles: " << frames.size() << " frames, last " << frames.back().mesh.vertex_count()
        << " vertices -> " << out.string() << "\n";
  result() = report;
  result()["out"] = out.string();
  folder.keep();
  return 0;
}

}  // namespace

void register_particles_commands(CLI::App& app, CommandList& commands) {
  auto particles = std::make_shared<ParticlesArgs>();
  auto* c = app.add_subcommand(
      "particles",
      "Mesh an implicit scene, an animated one or a scan's surface with a particle "
      "spring network");
  c->add_option("scene", particles->scene, "Scene YAML (static or with keyframes)")
      ->check(CLI::ExistingFile);
  c->add_option("--grid", particles->grid, "Mesh a scan's continuous surface (.smg)")
      ->check(CLI::ExistingFile);
  c->add_option("--edge", particles->edge, "Target edge length R (mm)")
      ->required()
      ->check(above(0, 1e6));
  c->add_flag("--adaptive", particles->adaptive, "Curvature-adaptive rest lengths");
  c->add_option("--frames", particles->frames, "Frames of an animated scene")
      ->capture_default_str()
      ->check(in_range(1, 100000));
  c->add_option("--steps", particles->steps_per_frame, "Iterations per frame")
      ->capture_default_str()
      ->check(in_range(1, 100000));
  c->add_flag("--no-flips", particles->no_flips, "Disable edge flips to valence 6");
  c->add_option("--seed", particles->seed, "Random seed")
      ->capture_default_str()
      ->check(seed_range());
  c->add_option("-o,--out", particles->out, "Output folder")->required();
  commands.push_back({c, [particles] { return run_particles(*particles); }});
}

}  // namespace scanmesh::cli
