// Mesh and PointCloud <-> NumPy, and the mesh checker (`scanmesh check`, apps/src/cmd_fans.cpp).
#include <string>

#include "common.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/mesh.h"
#include "scanmesh/core/point_cloud_io.h"
#include "scanmesh/meshing/mesh_check.h"

namespace scanmesh::python {

namespace {

py::ssize_t ssize(std::size_t n) { return static_cast<py::ssize_t>(n); }

// The first of a row's scalars, for every row type of Mesh and PointCloud (Eigen vectors and
// std::array have data(); Rgb8 does not). The rows are packed: common.h checks it.
template <typename Row>
auto first_scalar(const Row& row) -> decltype(row.data()) {
  return row.data();
}
const std::uint8_t* first_scalar(const Rgb8& color) { return &color.r; }

// The getter of a read-only N x cols view of `rows`, kept alive by the Mesh or PointCloud: one
// helper for every per-vertex and per-face array, whatever its row type.
template <typename Owner, typename Row>
auto rows_property(std::vector<Row> Owner::*rows, py::ssize_t cols) {
  return [rows, cols](py::object self) {
    const std::vector<Row>& v = self.cast<const Owner&>().*rows;
    return view(self, v.empty() ? nullptr : first_scalar(v.front()), {ssize(v.size()), cols});
  };
}

Mesh make_mesh(py::handle positions, py::handle triangles, py::handle normals, py::handle colors,
               py::handle face_labels, py::handle texcoords, py::handle face_texcoords) {
  Mesh mesh;
  mesh.positions = to_vec3d(positions, "positions");
  if (!triangles.is_none()) mesh.triangles = to_int3(triangles, "triangles", true);
  if (!normals.is_none()) mesh.normals = to_vec3f(normals, "normals");
  if (!colors.is_none()) mesh.colors = to_rgb(colors, "colors");
  if (!face_labels.is_none()) mesh.face_labels = to_ints(face_labels, "face_labels");
  if (!texcoords.is_none()) mesh.texcoords = to_vec2f(texcoords, "texcoords");
  if (!face_texcoords.is_none())
    mesh.face_texcoords = to_int3(face_texcoords, "face_texcoords", true);
  mesh.validate();
  return mesh;
}

PointCloud make_cloud(py::handle positions, py::handle normals, py::handle colors) {
  PointCloud c = to_cloud(positions, "positions", normals, colors);
  if (c.has_normals() && c.normals.size() != c.positions.size())
    value_error("PointCloud: normals must have one row per position");
  if (c.has_colors() && c.colors.size() != c.positions.size())
    value_error("PointCloud: colors must have one row per position");
  return c;
}

py::dict check_report(const MeshCheckReport& r) {
  const TopologyStats& t = r.topology;
  py::dict d;
  SCANMESH_PUT_FIELDS(d, r, vertices, faces);
  SCANMESH_PUT_FIELDS(d, t, edges, boundary_edges, manifold_edges, nonmanifold_edges);
  d["inconsistently_oriented_edges"] = t.inconsistent_edges;
  SCANMESH_PUT_FIELDS(d, t, boundary_loops, boundary_loop_lengths, unreferenced_vertices,
                      euler_characteristic, components);
  d["genus"] = t.genus();
  SCANMESH_PUT_FIELDS(d, r, duplicate_faces, degenerate_faces, nonmanifold_vertices,
                      self_intersections, self_intersections_checked,
                      self_intersections_not_checked_reason, min_angle_deg, mean_min_angle_deg,
                      min_radius_ratio, mean_radius_ratio, fraction_min_angle_ge_30);
  d["min_angle_histogram_5deg"] =
      std::vector<std::size_t>(r.min_angle_histogram.begin(), r.min_angle_histogram.end());
  d["edge_manifold"] = r.edge_manifold();
  d["defect_free"] = r.defect_free();
  py::dict verdicts, evidence;
  for (const PropertyVerdict& v : mesh_verdicts(r)) {
    verdicts[property_name(v.property)] = v.known ? py::object(py::bool_(v.holds)) : py::none();
    evidence[property_name(v.property)] = v.evidence;
  }
  d["verdicts"] = verdicts;
  d["evidence"] = evidence;
  d["text"] = r.to_text();
  return d;
}

}  // namespace

void init_mesh(py::module_& m) {
  py::class_<Mesh>(m, "Mesh", R"doc(
An indexed triangle mesh (core/mesh.h). Immutable from Python: its arrays are zero-copy
READ-ONLY views into the mesh (kept alive by the array); build a changed mesh with
Mesh(...) or mesh.replace(name=array, ...), which copy their input.
  positions       float64 (N, 3)
  triangles       int32   (M, 3)   counter-clockwise seen from outside
  normals         float32 (N, 3)   or (0, 3) when absent
  colors          uint8   (N, 3)   or (0, 3)
  face_labels     int32   (M,)     or (0,)   region / material per face
  texcoords       float32 (K, 2)   or (0, 2) (u, v), v = 0 at the image bottom
  face_texcoords  int32   (M, 3)   or (0, 3) indices into texcoords)doc")
      .def(py::init(&make_mesh), py::arg("positions"), py::arg("triangles") = py::none(),
           py::kw_only(), py::arg("normals") = py::none(), py::arg("colors") = py::none(),
           py::arg("face_labels") = py::none(), py::arg("texcoords") = py::none(),
           py::arg("face_texcoords") = py::none(),
           "A mesh from NumPy arrays (copied). ValueError for wrong shapes, an index out of "
           "range, an attribute of the wrong length or a non-finite coordinate.")
      .def_property_readonly("positions", rows_property(&Mesh::positions, 3))
      .def_property_readonly("triangles", rows_property(&Mesh::triangles, 3))
      .def_property_readonly("normals", rows_property(&Mesh::normals, 3))
      .def_property_readonly("colors", rows_property(&Mesh::colors, 3))
      .def_property_readonly("face_labels",
                             [](py::object self) {
                               const auto& v = self.cast<const Mesh&>().face_labels;
                               return view(self, v.data(), {ssize(v.size())});
                             })
      .def_property_readonly("texcoords", rows_property(&Mesh::texcoords, 2))
      .def_property_readonly("face_texcoords", rows_property(&Mesh::face_texcoords, 3))
      .def_property_readonly("vertex_count", &Mesh::vertex_count)
      .def_property_readonly("face_count", &Mesh::face_count)
      .def_property_readonly("has_normals", &Mesh::has_normals)
      .def_property_readonly("has_colors", &Mesh::has_colors)
      .def_property_readonly("has_face_labels", &Mesh::has_face_labels)
      .def_property_readonly("has_texcoords", &Mesh::has_texcoords)
      .def("validate", &Mesh::validate, "ValueError if an index or attribute length is wrong.")
      .def(
          "with_vertex_normals",
          [](const Mesh& mesh) {
            Mesh out = mesh;
            out.compute_vertex_normals();
            return out;
          },
          "A copy with area-weighted vertex normals from the faces.")
      .def("copy", [](const Mesh& mesh) { return Mesh(mesh); })
      .def("__copy__", [](const Mesh& mesh) { return Mesh(mesh); })
      .def("__deepcopy__", [](const Mesh& mesh, py::dict) { return Mesh(mesh); })
      .def("__repr__", [](const Mesh& mesh) {
        return "<scanmesh.Mesh " + std::to_string(mesh.vertex_count()) + " vertices, " +
               std::to_string(mesh.face_count()) + " triangles>";
      });

  py::class_<PointCloud>(m, "PointCloud", R"doc(
A point cloud as read_point_cloud returns it (core/point_cloud_io.h), or built from arrays
(unorganised). Arrays are zero-copy READ-ONLY views (kept alive by the array):
  positions  float64 (N, 3)  organised clouds (height > 1) keep NaN rows for missing pixels,
                             positions[row * width + column]
  normals    float32 (N, 3) or (0, 3)
  colors     uint8   (N, 3) or (0, 3))doc")
      .def(py::init(&make_cloud), py::arg("positions"), py::kw_only(),
           py::arg("normals") = py::none(), py::arg("colors") = py::none(),
           "An unorganised cloud from arrays (copied).")
      .def_property_readonly("positions", rows_property(&PointCloud::positions, 3))
      .def_property_readonly("normals", rows_property(&PointCloud::normals, 3))
      .def_property_readonly("colors", rows_property(&PointCloud::colors, 3))
      .def_readonly("width", &PointCloud::width)
      .def_readonly("height", &PointCloud::height)
      .def_property_readonly("organised", &PointCloud::organised)
      .def("__len__", &PointCloud::size)
      .def("finite_count", &PointCloud::finite_count)
      .def("finite_points", &PointCloud::finite_points,
           "The finite points with their attributes, as an unorganised cloud.")
      .def("__repr__", [](const PointCloud& c) {
        return "<scanmesh.PointCloud " + std::to_string(c.size()) + " points" +
               (c.organised()
                    ? ", organised " + std::to_string(c.width) + " x " + std::to_string(c.height)
                    : std::string()) +
               ">";
      });

  m.def(
      "check",
      [](const Mesh& mesh, bool self_intersections) {
        MeshCheckReport r;
        {
          py::gil_scoped_release release;
          r = check_mesh(mesh, {.self_intersections = self_intersections});
        }
        return check_report(r);
      },
      py::arg("mesh"), py::kw_only(), py::arg("self_intersections") = true, R"doc(
The mesh checker (check_mesh, as `scanmesh check`; docs/fans.md, "Checker"). Returns a dict:
counts (vertices, faces, edges, boundary_edges, nonmanifold_edges, boundary_loops,
boundary_loop_lengths, euler_characteristic, components, genus, duplicate_faces,
degenerate_faces, nonmanifold_vertices, self_intersections, ...), quality (min_angle_deg,
mean_radius_ratio, fraction_min_angle_ge_30, min_angle_histogram_5deg), edge_manifold, defect_free,
"verdicts": {property name: True / False / None (not tested)} for every name of
mesh_properties(), "evidence": {name: what decided it}, and "text" (the CLI's report).
self_intersections=False skips the most expensive test (its verdict is then None).)doc");
  m.def(
      "mesh_properties",
      [] {
        std::vector<std::string> names;
        for (MeshProperty p : all_mesh_properties()) names.emplace_back(property_name(p));
        return names;
      },
      "The property names check() gives verdicts on, as `scanmesh check --require` takes them.");
}

}  // namespace scanmesh::python
