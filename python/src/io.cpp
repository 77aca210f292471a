// Reading and writing the project's formats (docs/formats.md): range grids (.smg), surface
// fields (.smf), meshes (PLY / OBJ / OFF / STL), point clouds, and the grid exports of
// `scanmesh export`. All writers are atomic (temp file + fsync + rename).
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

#include "common.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_export.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/image.h"
#include "scanmesh/core/mesh_io.h"
#include "scanmesh/core/point_cloud_io.h"
#include "scanmesh/reconstruction/fields_file.h"

namespace scanmesh::python {

namespace {

using std::filesystem::path;

py::array image_array(Image8&& image) {
  const py::ssize_t h = image.height, w = image.width, c = image.channels;
  return owned(std::move(image.pixels), {h, w, c});
}

std::string lower_extension(const path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return ext;
}

}  // namespace

void init_io(py::module_& m) {
  // The library's readers and writers, bound as they are: each runs with the GIL released.
  const auto without_gil = py::call_guard<py::gil_scoped_release>();
  m.def("read_grid", &read_grid, py::arg("path"), without_gil,
        "Reads a native range grid file (.smg). FileFormatError (ValueError) naming the file "
        "for a malformed, truncated or corrupt file; IoError (OSError) if it cannot be read.");
  m.def("write_grid", &write_grid, py::arg("path"), py::arg("grid"), without_gil,
        "Writes a native range grid file (.smg), atomically.");

  m.def("read_mesh", &read_mesh, py::arg("path"), without_gil,
        "Reads a mesh by extension: .ply, .off, .obj, .stl (read_mesh). FileFormatError naming "
        "the file for malformed content, ValueError for another extension.");
  m.def(
      "read_obj",
      [](const path& p) {
        ObjMesh r;
        {
          py::gil_scoped_release release;
          r = read_obj(p);
        }
        py::object texture = r.texture.empty() ? py::object(py::none()) : py::cast(r.texture);
        return py::make_tuple(std::move(r.mesh), texture);
      },
      py::arg("path"), "Reads an OBJ and its MTL: (Mesh, texture image path or None).");
  m.def(
      "write_ply",
      [](const path& p, const Mesh& mesh, bool ascii) {
        py::gil_scoped_release release;
        write_ply(p, mesh, ascii ? PlyEncoding::Ascii : PlyEncoding::Binary);
      },
      py::arg("path"), py::arg("mesh"), py::kw_only(), py::arg("ascii") = false,
      "Writes PLY (binary little-endian, or ASCII): positions, and normals, colours and face "
      "labels when present.");
  m.def("write_obj", &write_obj, py::arg("path"), py::arg("mesh"), py::kw_only(),
        py::arg("texture_png") = "", without_gil,
        "Writes OBJ (v / vn / vt / f); with texture_png, also <stem>.mtl naming that image.");
  m.def("write_stl", &write_stl, py::arg("path"), py::arg("mesh"), without_gil,
        "Writes binary STL.");
  m.def(
      "write_mesh",
      [](const path& p, const Mesh& mesh) {
        const std::string ext = lower_extension(p);
        if (ext != ".ply" && ext != ".obj" && ext != ".stl")
          throw InvalidInputError("write_mesh: cannot write '" + ext + "' files (" + p.string() +
                                  "); use .ply, .obj or .stl");
        py::gil_scoped_release release;
        if (ext == ".ply")
          write_ply(p, mesh);
        else if (ext == ".obj")
          write_obj(p, mesh);
        else
          write_stl(p, mesh);
      },
      py::arg("path"), py::arg("mesh"), "Writes a mesh by extension: .ply (binary), .obj, .stl.");

  m.def("read_point_cloud", &read_point_cloud, py::arg("path"), without_gil,
        "Reads a point cloud by extension, as `scanmesh fans` does: .ply (vertices), .pcd "
        "(ascii / binary / binary_compressed, organised or not), .xyz / .txt / .pts, .smg (the "
        "grid's cells). FileFormatError naming the file for malformed content.");

  m.def("read_fields", &read_fields, py::arg("path"), without_gil,
        "Reads a surface fields file (.smf) written by curvature / write_fields.");
  m.def("write_fields", &write_fields, py::arg("path"), py::arg("fields"), without_gil,
        "Writes a surface fields file (.smf), atomically.");

  m.def("export_pcd", &export_pcd, py::arg("path"), py::arg("grid"), without_gil,
        "The grid as an organised binary PCD (PointXYZRGB, invalid cells NaN).");
  m.def("export_ply_points", &export_ply_points, py::arg("path"), py::arg("grid"), without_gil,
        "The valid cells as a binary PLY point cloud (x y z, colour, confidence, indices).");
  m.def("export_texture_png", &export_texture_png, py::arg("path"), py::arg("grid"), without_gil,
        "The colour plane as a PNG (pixel x, y = cell i, j).");
  m.def("export_depth_png", &export_depth_png, py::arg("path"), py::arg("grid"), without_gil,
        "A picture of the radius as a PNG.");
  m.def(
      "texture_image", [](const RangeGrid& g) { return image_array(texture_image(g)); },
      py::arg("grid"),
      "The texture picture, uint8 (n_h, n_phi, 3) (a new array). Upright like the PNG "
      "(core/texture_layout.h): row 0 shows the highest h, so texture_image(g)[::-1] is "
      "g.color.");
  m.def(
      "depth_image", [](const RangeGrid& g) { return image_array(depth_image(g)); },
      py::arg("grid"),
      "The depth picture (grey, invalid cells black), uint8 (n_h, n_phi, channels) (a new "
      "array), upright like texture_image.");
}

}  // namespace scanmesh::python
