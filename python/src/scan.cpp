// Where grids come from: the simulator (scenes, scanner configurations; `scanmesh sim`,
// apps/src/cmd_grid.cpp) and the import of other scanners' files (`scanmesh import`,
// apps/src/cmd_import.cpp).
#include <filesystem>
#include <memory>
#include <string>

#include "common.h"
#include "scanmesh/acquisition/scan_import.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/point_cloud_io.h"
#include "scanmesh/sim/range_scanner.h"
#include "scanmesh/sim/scene.h"

namespace scanmesh::python {

namespace {

using sim::ScannerConfig;
using sim::Scene;

bool is_path(py::handle h) {
  return py::isinstance<py::str>(h) ||
         py::isinstance(h, py::module_::import("os").attr("PathLike"));
}

// None: the built-in head; a Scene; or a YAML file.
Scene scene_of(py::handle scene) {
  if (scene.is_none()) return sim::builtin_head_scene();
  if (py::isinstance<Scene>(scene)) return scene.cast<Scene>();
  if (is_path(scene)) return Scene::from_yaml_file(scene.cast<std::filesystem::path>());
  throw py::type_error("scene must be None (the built-in head), a Scene or a YAML file path");
}

ScannerConfig scanner_of(py::handle scanner) {
  if (scanner.is_none()) return sim::builtin_head_scanner();
  if (py::isinstance<ScannerConfig>(scanner)) return scanner.cast<ScannerConfig>();
  if (is_path(scanner)) return ScannerConfig::from_yaml_file(scanner.cast<std::filesystem::path>());
  throw py::type_error(
      "scanner must be None (the built-in head scanner), a ScannerConfig or a YAML file path");
}

// The configuration `sim` scans with: as `scanmesh sim` builds it, plus field overrides.
ScannerConfig configure(py::handle scanner, const std::optional<std::uint64_t>& seed,
                        const std::optional<double>& noise_sigma_mm, const py::kwargs& fields) {
  ScannerConfig config = scanner_of(scanner);
  if (seed) config.seed = *seed;
  if (noise_sigma_mm) config.noise_sigma_mm = *noise_sigma_mm;
  if (fields.size() > 0) {
    py::object o = py::cast(config);
    set_fields(o, fields, "ScannerConfig");
    config = o.cast<ScannerConfig>();
  }
  config.validate();
  return config;
}

sim::SimulatedScan run_sim(py::handle scene, py::handle scanner,
                           const std::optional<std::uint64_t>& seed,
                           const std::optional<double>& noise_sigma_mm, const py::kwargs& fields) {
  const Scene s = scene_of(scene);
  const ScannerConfig config = configure(scanner, seed, noise_sigma_mm, fields);
  py::gil_scoped_release release;
  return sim::simulate_scan(s, config);
}

py::dict truth_arrays(const sim::SimulatedScan& scan) {
  const RangeGrid& g = scan.grid;
  const std::size_t n = g.cell_count();
  std::vector<std::uint8_t> hit(n), drop(n), spike(n);
  std::vector<double> radius(n), point(3 * n), normal(3 * n), k1(n), k2(n);
  for (std::size_t k = 0; k < n; ++k) {
    const sim::GroundTruthCell& t = scan.truth[k];
    hit[k] = t.hit;
    drop[k] = static_cast<std::uint8_t>(t.drop);
    spike[k] = t.spike;
    radius[k] = t.radius;
    k1[k] = t.geometry.k1;
    k2[k] = t.geometry.k2;
    for (int c = 0; c < 3; ++c) {
      point[3 * k + c] = t.point[c];
      normal[3 * k + c] = t.geometry.normal[c];
    }
  }
  const py::ssize_t h = g.n_h(), w = g.n_phi();
  py::dict d;
  d["hit"] = owned(std::move(hit), {h, w}, py::dtype("bool"));
  d["radius"] = owned(std::move(radius), {h, w});
  d["point"] = owned(std::move(point), {h, w, 3});
  d["normal"] = owned(std::move(normal), {h, w, 3});
  d["k1"] = owned(std::move(k1), {h, w});
  d["k2"] = owned(std::move(k2), {h, w});
  d["drop"] = owned(std::move(drop), {h, w});
  d["drop_reasons"] =
      py::make_tuple("none", "no_hit", "outside_band", "grazing", "occluded", "hair_speckle");
  d["spike"] = owned(std::move(spike), {h, w}, py::dtype("bool"));
  return d;
}

py::array vec3(const Eigen::Vector3d& v) {
  return owned(std::vector<double>{v.x(), v.y(), v.z()}, {3});
}

py::dict import_report(const ImportResult& r) {
  const ImportReport& rep = r.report;
  py::list arcs;
  for (const auto& [a, b] : rep.coverage.arcs) arcs.append(py::make_tuple(a, b));
  py::dict coverage;
  SCANMESH_PUT_FIELDS(coverage, rep.coverage, full_turn, columns, covered_columns);
  coverage["covered_fraction"] = rep.coverage.covered_fraction();
  coverage["arcs_rad"] = arcs;
  py::dict d;
  SCANMESH_PUT_FIELDS(d, rep, input_kind, method, input_points, input_triangles, samples_used,
                      colors, textured);
  d["axis_point"] = vec3(rep.axis.point);
  d["axis_direction"] = vec3(rep.axis.direction);
  SCANMESH_PUT_FIELDS(d, rep, sample_spacing_mm, cell_mm);
  d["turn_coverage"] = coverage;
  d["warnings"] = rep.warnings;
  std::vector<double> rot(9);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rot[static_cast<std::size_t>(3 * i + j)] = r.rotation(i, j);
  d["rotation"] = owned(std::move(rot), {3, 3});
  d["origin"] = vec3(r.origin);
  return d;
}

void bind_scene(py::module_& m) {
  py::class_<Scene>(m, "Scene", R"doc(
A simulated scene: analytic shapes and skeletal implicit surfaces with exact geometry
(docs/simulator.md). Scene.builtin_head(), Scene.from_yaml(path) or Scene.from_yaml_text(text).)doc")
      .def_static("builtin_head", &sim::builtin_head_scene,
                  "The built-in head (configs/sim/head.yaml, compiled in).")
      .def_static(
          "from_yaml", [](const std::filesystem::path& p) { return Scene::from_yaml_file(p); },
          py::arg("path"), "A scene YAML file; FileFormatError naming the file and key.")
      .def_static("from_yaml_text", &Scene::from_yaml_text, py::arg("text"),
                  py::arg("source_name") = "<text>", "A scene from YAML text.")
      .def_readonly("name", &Scene::name)
      .def_property_readonly("object_count", [](const Scene& s) { return s.objects.size(); })
      .def_property_readonly(
          "bounds",
          [](const Scene& s) {
            const auto b = s.bounds();
            return py::make_tuple(vec3(b.min()), vec3(b.max()));
          },
          "(min corner, max corner) of the objects' bounds (mm).")
      .def("__repr__", [](const Scene& s) {
        return "<scanmesh.Scene '" + s.name + "', " + std::to_string(s.objects.size()) +
               " objects>";
      });
  m.def("builtin_head_yaml", &sim::builtin_head_yaml, "The text of the built-in head scene.");
}

void bind_scanner_config(py::module_& m) {
  py::class_<ScannerConfig>(m, "ScannerConfig", R"doc(
The simulated scanner (range_scanner.h, docs/simulator.md). ScannerConfig(**fields) starts from
the library's defaults; ScannerConfig.builtin_head() is the demo's scanner
(configs/scanners/sim-head.yaml); ScannerConfig.from_yaml(path) reads a scanner file. Every field
is a read/write attribute; validate() raises ValueError for impossible values.)doc")
      .def(py::init([](const py::kwargs& fields) {
             py::object o = py::cast(ScannerConfig{});
             set_fields(o, fields, "ScannerConfig");
             return o.cast<ScannerConfig>();
           }),
           "A configuration with the library defaults, then `fields` set.")
      .def_static("builtin_head", &sim::builtin_head_scanner)
      .def_static(
          "from_yaml",
          [](const std::filesystem::path& p) { return ScannerConfig::from_yaml_file(p); },
          py::arg("path"))
      .def_static("from_yaml_text", &ScannerConfig::from_yaml_text, py::arg("text"),
                  py::arg("source_name") = "<text>")
      .def("validate", &ScannerConfig::validate)
      .def(
          "replace",
          [](const ScannerConfig& c, const py::kwargs& fields) {
            py::object o = py::cast(c);  // a copy
            set_fields(o, fields, "ScannerConfig");
            return o.cast<ScannerConfig>();
          },
          "A copy with `fields` changed.")
      .def_readwrite("n_phi", &ScannerConfig::n_phi)
      .def_readwrite("n_h", &ScannerConfig::n_h)
      .def_readwrite("radius_mm", &ScannerConfig::radius_mm, "Scanner circle R (rays start here).")
      .def_readwrite("h0_mm", &ScannerConfig::h0_mm, "Height of row 0.")
      .def_readwrite("dh_mm", &ScannerConfig::dh_mm, "Row spacing.")
      .def_readwrite("phi0_rad", &ScannerConfig::phi0_rad)
      .def_readwrite("noise_sigma_mm", &ScannerConfig::noise_sigma_mm, "Gaussian range noise.")
      .def_readwrite("grazing_dropout", &ScannerConfig::grazing_dropout)
      .def_readwrite("grazing_limit_deg", &ScannerConfig::grazing_limit_deg)
      .def_readwrite("occlusion", &ScannerConfig::occlusion)
      .def_readwrite("camera_baseline_deg", &ScannerConfig::camera_baseline_deg)
      .def_readwrite("camera_radius_mm", &ScannerConfig::camera_radius_mm)
      .def_readwrite("hair", &ScannerConfig::hair)
      .def_readwrite("hair_noise_sigma_mm", &ScannerConfig::hair_noise_sigma_mm)
      .def_readwrite("hair_dropout_probability", &ScannerConfig::hair_dropout_probability)
      .def_readwrite("spike_probability", &ScannerConfig::spike_probability)
      .def_readwrite("height_band", &ScannerConfig::height_band)
      .def_readwrite("band_min_mm", &ScannerConfig::band_min_mm)
      .def_readwrite("band_max_mm", &ScannerConfig::band_max_mm)
      .def_readwrite("seed", &ScannerConfig::seed)
      .def("__repr__", [](const ScannerConfig& c) {
        return "<scanmesh.ScannerConfig " + std::to_string(c.n_phi) + " x " +
               std::to_string(c.n_h) + ", seed " + std::to_string(c.seed) + ">";
      });
}

void bind_simulation(py::module_& m) {
  static const char* sim_doc = R"doc(
Simulates a scan (simulate_scan, as `scanmesh sim`). scene: None (the built-in head), a Scene or
a scene YAML path; scanner: None (the built-in head scanner), a ScannerConfig or a scanner YAML
path; seed and noise_sigma_mm override the scanner's (like --seed, --noise-sigma); any further
keyword is a ScannerConfig field (e.g. n_phi=128, n_h=128, spike_probability=0). Deterministic
for a given scene, scanner and seed. ValueError for impossible scanner values.)doc";
  m.def(
      "sim",
      [](py::handle scene, py::handle scanner, std::optional<std::uint64_t> seed,
         std::optional<double> noise_sigma_mm, const py::kwargs& fields) {
        return run_sim(scene, scanner, seed, noise_sigma_mm, fields).grid;
      },
      py::arg("scene") = py::none(), py::arg("scanner") = py::none(), py::kw_only(),
      py::arg("seed") = py::none(), py::arg("noise_sigma_mm") = py::none(),
      (std::string(sim_doc) + "\nReturns the RangeGrid.").c_str());
  m.def(
      "sim_with_truth",
      [](py::handle scene, py::handle scanner, std::optional<std::uint64_t> seed,
         std::optional<double> noise_sigma_mm, const py::kwargs& fields) {
        sim::SimulatedScan scan = run_sim(scene, scanner, seed, noise_sigma_mm, fields);
        py::dict truth = truth_arrays(scan);
        return py::make_tuple(std::move(scan.grid), truth);
      },
      py::arg("scene") = py::none(), py::arg("scanner") = py::none(), py::kw_only(),
      py::arg("seed") = py::none(), py::arg("noise_sigma_mm") = py::none(),
      (std::string(sim_doc) + R"doc(
Returns (RangeGrid, truth): truth is a dict of new (n_h, n_phi[, 3]) arrays with the exact
noise-free geometry per cell: hit (bool), radius, point, normal, k1, k2 (float64), drop (uint8
index into truth["drop_reasons"]: none, no_hit, outside_band, grazing, occluded, hair_speckle)
and spike (bool: the measurement was replaced by an outlier).)doc")
          .c_str());
}

void bind_import(py::module_& m) {
  const ImportOptions io_defaults;
  m.def(
      "import_scan",
      [](py::handle input, py::handle axis, py::handle axis_point, int n_phi, int n_h, double dh,
         double layer_gap_cells, double max_lattice_jump) {
        ImportOptions o;
        if (py::isinstance<py::str>(axis)) {
          const std::string a = axis.cast<std::string>();
          if (a == "z")
            o.direction = AxisDirection::Z;
          else if (a == "estimate")
            o.direction = AxisDirection::Estimate;
          else
            throw InvalidInputError(
                "import_scan: axis must be 'z', 'estimate' or three numbers, "
                "got '" +
                a + "'");
        } else {
          o.direction = AxisDirection::Given;
          o.axis_direction = to_point(axis, "axis");
        }
        if (!axis_point.is_none()) o.axis_point = to_point(axis_point, "axis_point");
        SCANMESH_SET_FIELDS(o, n_phi, n_h, dh, layer_gap_cells, max_lattice_jump);
        require_range("import_scan", "layer_gap_cells", layer_gap_cells, 0, 1e6);
        require_range("import_scan", "max_lattice_jump", max_lattice_jump, 0, 1e6);
        ImportResult r;
        if (py::isinstance<Mesh>(input)) {
          const Mesh& mesh = input.cast<const Mesh&>();
          py::gil_scoped_release release;
          r = grid_from_mesh(mesh, nullptr, o, "<mesh>");
        } else if (py::isinstance<PointCloud>(input)) {
          const PointCloud& cloud = input.cast<const PointCloud&>();
          py::gil_scoped_release release;
          r = cloud.organised() ? grid_from_organised_cloud(cloud, o, "<point cloud>")
                                : grid_from_cloud(cloud, o, "<point cloud>");
        } else if (is_path(input)) {
          const auto path = input.cast<std::filesystem::path>();
          py::gil_scoped_release release;
          r = import_scan(path, o);
        } else {
          const PointCloud cloud = to_cloud(input, "points");
          py::gil_scoped_release release;
          r = grid_from_cloud(cloud, o, "<points>");
        }
        py::dict report = import_report(r);
        return py::make_tuple(std::move(r.grid), report);
      },
      py::arg("input"), py::kw_only(), py::arg("axis") = "z", py::arg("axis_point") = py::none(),
      py::arg("n_phi") = io_defaults.n_phi, py::arg("n_h") = io_defaults.n_h,
      py::arg("dh") = io_defaults.dh, py::arg("layer_gap_cells") = io_defaults.layer_gap_cells,
      py::arg("max_lattice_jump") = io_defaults.max_lattice_jump, R"doc(
Another scanner's data into a RangeGrid (import_scan, as `scanmesh import`; docs/acquisition.md,
"Importing scans"). input: a file path (clouds .ply .pcd .xyz .txt .pts, meshes .ply .off .obj
.stl .vtk .vtp), a Mesh (ray-cast), a PointCloud (binned; organised ones ray-cast) or an (N, 3)
array of points (binned). axis: "z", "estimate" (PCA) or a direction (3 numbers); axis_point: a
point on the axis (default: the data's centroid; a partial turn needs the turntable's axis);
n_phi, n_h, dh: grid size and row spacing (0: from the data's sample spacing).
Returns (RangeGrid, report dict: input_kind, method, counts, axis, cell size, turn_coverage,
warnings, rotation and origin of the input -> grid frame map p_grid = rotation (p - origin)).
FileFormatError (ValueError) for a file that cannot be a scan, ValueError for impossible options
or an unknown extension, IoError (OSError) when the file cannot be read.)doc");
}

}  // namespace

void init_scan(py::module_& m) {
  bind_scene(m);
  bind_scanner_config(m);
  bind_simulation(m);
  bind_import(m);
}

}  // namespace scanmesh::python
