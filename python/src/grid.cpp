// RangeGrid <-> NumPy, the surface fields, and the grid stages clean and curvature
// (the library calls of `scanmesh clean` and `scanmesh curvature`, apps/src/cmd_grid.cpp and
// cmd_curvature.cpp).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "common.h"
#include "scanmesh/acquisition/grid_cleaning.h"
#include "scanmesh/acquisition/scan_cleaning.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_export.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/reconstruction/surface_fields.h"

namespace scanmesh::python {

namespace {

py::ssize_t rows(const RangeGrid& g) { return g.n_h(); }
py::ssize_t cols(const RangeGrid& g) { return g.n_phi(); }

// The grid from NumPy planes (n_h x n_phi, rows of constant h): validity from `valid`, else
// from the radius (finite and > 0); every valid cell goes through set_sample, so the library
// checks it.
RangeGrid grid_from_arrays(py::handle radius, py::handle valid, py::handle confidence,
                           py::handle color, double phi0, double h0, double dh,
                           const py::dict& metadata) {
  py::array r_raw = py::array::ensure(radius);
  if (!r_raw || r_raw.ndim() != 2)
    value_error("RangeGrid.from_arrays: radius must be a 2-D array (n_h, n_phi)");
  const py::ssize_t n_h = r_raw.shape(0), n_phi = r_raw.shape(1);
  if (n_h > INT32_MAX || n_phi > INT32_MAX ||
      static_cast<std::uint64_t>(n_h) * static_cast<std::uint64_t>(n_phi) > kMaxGridCells)
    value_error("RangeGrid.from_arrays: at most 2^26 cells");
  RangeGrid g(static_cast<int>(n_phi), static_cast<int>(n_h), phi0, h0, dh);
  const auto r = to_double_array(radius, "radius", {n_h, n_phi});
  // (A default py::array_t is an empty array, not a null handle: presence is tracked apart.)
  const bool has_c = !confidence.is_none(), has_v = !valid.is_none();
  py::array_t<double, py::array::c_style> c;
  if (has_c) c = to_double_array(confidence, "confidence", {n_h, n_phi});
  py::array_t<bool, py::array::c_style> v;
  if (has_v) {
    py::array raw = py::array::ensure(valid);
    if (!raw || raw.dtype().kind() != 'b')
      value_error("RangeGrid.from_arrays: valid must be a boolean array");
    v = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(raw);
    if (v.ndim() != 2 || v.shape(0) != n_h || v.shape(1) != n_phi)
      value_error("RangeGrid.from_arrays: valid must have the radius's shape");
  }
  for (int j = 0; j < g.n_h(); ++j)
    for (int i = 0; i < g.n_phi(); ++i) {
      const std::size_t k = g.index(i, j);
      const double rk = r.data()[k];
      const bool is_valid = has_v ? v.data()[k] : (std::isfinite(rk) && rk > 0);
      if (!is_valid) continue;
      const double ck = has_c ? c.data()[k] : 1.0;
      try {
        g.set_sample(i, j, static_cast<float>(rk), static_cast<float>(ck));
      } catch (const InvalidInputError& e) {
        throw InvalidInputError("RangeGrid.from_arrays: cell (i = " + std::to_string(i) +
                                ", j = " + std::to_string(j) + "): " + e.what());
      }
    }
  if (!color.is_none()) {
    py::array raw = py::array::ensure(color);
    if (!raw || raw.ndim() != 3 || raw.shape(0) != n_h || raw.shape(1) != n_phi ||
        raw.shape(2) != 3)
      value_error("RangeGrid.from_arrays: color must have shape (n_h, n_phi, 3)");
    const auto rgb = to_rgb(raw.attr("reshape")(-1, 3), "color");
    g.colors() = rgb;
  }
  for (const auto& [key, value] : metadata)
    g.metadata[py::str(key).cast<std::string>()] = py::str(value).cast<std::string>();
  return g;
}

py::dict cleaning_report(const CleaningReport& r) {
  py::dict d;
  SCANMESH_PUT_FIELDS(d, r, valid_before, valid_after, spikes_removed, fragments_removed,
                      fragment_cells_removed, components_kept);
  return d;
}

// Read-only views of per-cell arrays in the grid's layout, kept alive by `owner`: numbers as
// (n_h, n_phi), flags as bool (n_h, n_phi), vectors as (n_h, n_phi, 3).
py::array cells_view(py::handle owner, const std::vector<float>& numbers, py::ssize_t n_h,
                     py::ssize_t n_phi) {
  return view(owner, numbers.data(), {n_h, n_phi});
}
py::array cells_view(py::handle owner, const std::vector<std::uint8_t>& flags, py::ssize_t n_h,
                     py::ssize_t n_phi) {
  return view(owner, flags.data(), {n_h, n_phi}, false, py::dtype("bool"));
}
py::array cells_view(py::handle owner, const std::vector<Eigen::Vector3f>& vectors, py::ssize_t n_h,
                     py::ssize_t n_phi) {
  return view(owner, vectors.empty() ? nullptr : vectors.data()->data(), {n_h, n_phi, 3});
}

// A new array of `shape` (C order) whose cell k holds value_at(k), for the first `cells` k
// (Index: what value_at takes, the grid's int or the fields' std::size_t).
template <typename Index, typename ValueAt>
py::array tabulated(Index cells, std::vector<py::ssize_t> shape, ValueAt value_at) {
  std::vector<decltype(value_at(cells))> v(static_cast<std::size_t>(cells));
  for (Index k = 0; k < cells; ++k) v[static_cast<std::size_t>(k)] = value_at(k);
  return owned(std::move(v), std::move(shape));
}

// The getter of a read-only view of one of the grid's planes (all but the writable colours).
template <typename T>
auto plane_property(const std::vector<T>& (RangeGrid::*plane)() const) {
  return [plane](py::object self) {
    const auto& g = self.cast<const RangeGrid&>();
    return cells_view(self, (g.*plane)(), rows(g), cols(g));
  };
}

// The getter of a read-only view of one of the per-cell arrays of SurfaceFields.
template <typename T>
auto fields_property(std::vector<T> SurfaceFields::*cells) {
  return [cells](py::object self) {
    const auto& f = self.cast<const SurfaceFields&>();
    return cells_view(self, f.*cells, f.n_h, f.n_phi);
  };
}

// The constructors and the geometry: sizes, spacings, every column's angle and row's height.
void add_grid_geometry(py::class_<RangeGrid>& grid) {
  const RangeGrid defaults(2, 2);
  grid.def(py::init<int, int, double, double, double>(), py::arg("n_phi") = 512,
           py::arg("n_h") = 512, py::arg("phi0") = defaults.phi0(), py::arg("h0") = defaults.h0(),
           py::arg("dh") = defaults.dh(),
           "An empty grid (every cell invalid). ValueError for sizes below 2 or dh <= 0.")
      .def_static("from_arrays", &grid_from_arrays, py::arg("radius"), py::kw_only(),
                  py::arg("valid") = py::none(), py::arg("confidence") = py::none(),
                  py::arg("color") = py::none(), py::arg("phi0") = 0.0, py::arg("h0") = 0.0,
                  py::arg("dh") = 1.0, py::arg("metadata") = py::dict(), R"doc(
A grid from NumPy planes of shape (n_h, n_phi) (copied). A cell is valid where `valid` is True,
or, without `valid`, where the radius is finite and > 0 (NaN or 0 marks a hole). A valid cell
needs a finite radius > 0 (else ValueError naming the cell); its confidence (default 1) is
clamped to [0, 1] as RangeGrid::set_sample does (non-finite: 0). `color` is (n_h, n_phi, 3) of
0..255.)doc")
      .def_property_readonly("n_phi", &RangeGrid::n_phi, "Columns (angles).")
      .def_property_readonly("n_h", &RangeGrid::n_h, "Rows (heights).")
      .def_property_readonly(
          "shape", [](const RangeGrid& g) { return py::make_tuple(g.n_h(), g.n_phi()); },
          "(n_h, n_phi): the shape of the planes.")
      .def_property_readonly("phi0", &RangeGrid::phi0, "Angle of column 0 (rad).")
      .def_property_readonly("h0", &RangeGrid::h0, "Height of row 0 (mm).")
      .def_property_readonly("dh", &RangeGrid::dh, "Row spacing (mm).")
      .def_property_readonly("dphi", &RangeGrid::dphi, "Column spacing 2 pi / n_phi (rad).")
      .def_property_readonly(
          "geometry",
          [](const RangeGrid& g) {
            py::dict d;
            d["n_phi"] = g.n_phi();
            d["n_h"] = g.n_h();
            d["phi0"] = g.phi0();
            d["h0"] = g.h0();
            d["dh"] = g.dh();
            d["dphi"] = g.dphi();
            return d;
          },
          "The grid's geometry as a dict: n_phi, n_h, phi0 (rad), h0 (mm), dh (mm), dphi (rad).")
      .def_property_readonly("cell_count", &RangeGrid::cell_count)
      .def("valid_count", &RangeGrid::valid_count, "Number of valid cells.")
      .def(
          "phis",
          [](const RangeGrid& g) {
            return tabulated(g.n_phi(), {g.n_phi()}, [&g](int i) { return g.phi(i); });
          },
          "Angle of every column, float64 (n_phi,) (a new array).")
      .def(
          "heights",
          [](const RangeGrid& g) {
            return tabulated(g.n_h(), {g.n_h()}, [&g](int j) { return g.h(j); });
          },
          "Height of every row, float64 (n_h,) (a new array).");
}

// The planes as NumPy views, and the cells' Cartesian positions.
void add_grid_planes(py::class_<RangeGrid>& grid) {
  grid.def_property_readonly(
          "radius", plane_property(&RangeGrid::radii),
          "Radius plane, float32 (n_h, n_phi), zero-copy read-only view (0 in invalid cells).")
      .def_property_readonly("valid", plane_property(&RangeGrid::validity),
                             "Validity plane, bool (n_h, n_phi), zero-copy read-only view.")
      .def_property_readonly(
          "confidence", plane_property(&RangeGrid::confidences),
          "Confidence plane, float32 (n_h, n_phi) in [0, 1], zero-copy read-only view.")
      .def_property_readonly(
          "color",
          [](py::object self) {
            auto& g = self.cast<RangeGrid&>();
            return view(self, &g.colors().data()->r, {rows(g), cols(g), 3}, true);
          },
          "Colour plane, uint8 (n_h, n_phi, 3) sRGB, zero-copy WRITABLE view: writing to it "
          "changes the grid. Invalid cells keep their colour.")
      .def(
          "xyz",
          [](const RangeGrid& g) {
            std::vector<double> v(g.cell_count() * 3, std::nan(""));
            for (int j = 0; j < g.n_h(); ++j)
              for (int i = 0; i < g.n_phi(); ++i)
                if (g.valid(i, j)) {
                  const Eigen::Vector3d p = g.cartesian(i, j);
                  for (int c = 0; c < 3; ++c) v[g.index(i, j) * 3 + c] = p[c];
                }
            return owned(std::move(v), {g.n_h(), g.n_phi(), 3});
          },
          "Cartesian position of every cell, float64 (n_h, n_phi, 3) (a new array); NaN in "
          "invalid cells.")
      .def(
          "points",
          [](const RangeGrid& g) {
            std::vector<double> v;
            v.reserve(g.valid_count() * 3);
            for (int j = 0; j < g.n_h(); ++j)
              for (int i = 0; i < g.n_phi(); ++i)
                if (g.valid(i, j)) {
                  const Eigen::Vector3d p = g.cartesian(i, j);
                  v.insert(v.end(), {p.x(), p.y(), p.z()});
                }
            const py::ssize_t n = static_cast<py::ssize_t>(v.size() / 3);
            return owned(std::move(v), {n, 3});
          },
          "Cartesian positions of the valid cells in index order, float64 (N, 3) (a new array).");
}

void add_grid_editing(py::class_<RangeGrid>& grid) {
  grid.def(
          "set_sample",
          [](RangeGrid& g, int i, int j, float r, float confidence) {
            if (i < 0 || i >= g.n_phi() || j < 0 || j >= g.n_h())
              throw py::index_error("cell index out of range");
            g.set_sample(i, j, r, confidence);
          },
          py::arg("i"), py::arg("j"), py::arg("r"), py::arg("confidence") = 1.0f,
          "Marks cell (i = phi index, j = h index) valid with radius r (> 0, finite; "
          "ValueError otherwise) and the confidence, clamped to [0, 1].")
      .def(
          "invalidate",
          [](RangeGrid& g, int i, int j) {
            if (i < 0 || i >= g.n_phi() || j < 0 || j >= g.n_h())
              throw py::index_error("cell index out of range");
            g.invalidate(i, j);
          },
          py::arg("i"), py::arg("j"),
          "Marks cell (i, j) invalid (radius and confidence 0, colour kept).")
      .def(
          "set_radius",
          [](RangeGrid& g, py::handle radius, py::handle confidence) {
            const auto r = to_double_array(radius, "radius", {rows(g), cols(g)});
            const bool has_c = !confidence.is_none();
            py::array_t<double, py::array::c_style> c;
            if (has_c) c = to_double_array(confidence, "confidence", {rows(g), cols(g)});
            RangeGrid next = g;  // all or nothing: a bad cell leaves the grid as it was
            for (int j = 0; j < g.n_h(); ++j)
              for (int i = 0; i < g.n_phi(); ++i) {
                const std::size_t k = g.index(i, j);
                const double rk = r.data()[k];
                if (std::isfinite(rk) && rk > 0)
                  next.set_sample(i, j, static_cast<float>(rk),
                                  static_cast<float>(has_c ? c.data()[k] : 1.0));
                else
                  next.invalidate(i, j);
              }
            // Copy into the existing planes (same sizes: views stay valid and see the change).
            std::copy(next.radii().begin(), next.radii().end(), g.radii().begin());
            std::copy(next.validity().begin(), next.validity().end(), g.validity().begin());
            std::copy(next.confidences().begin(), next.confidences().end(),
                      g.confidences().begin());
          },
          py::arg("radius"), py::arg("confidence") = py::none(),
          "Replaces every cell's radius from a (n_h, n_phi) array: finite values > 0 make valid "
          "cells (confidence from `confidence`, default 1), NaN / 0 / negative make holes. "
          "Existing views see the new values.");
}

void add_grid_metadata_and_copies(py::class_<RangeGrid>& grid) {
  grid.def_property(
          "metadata", [](const RangeGrid& g) { return g.metadata; },
          [](RangeGrid& g, const std::map<std::string, std::string>& entries) {
            g.metadata = entries;
          },
          "Provenance key/value strings (a dict copy; assign a dict to replace them).")
      .def(
          "copy", [](const RangeGrid& g) { return RangeGrid(g); }, "A deep copy.")
      .def("__copy__", [](const RangeGrid& g) { return RangeGrid(g); })
      .def("__deepcopy__", [](const RangeGrid& g, py::dict) { return RangeGrid(g); })
      .def(py::self == py::self);  // NOLINT
}

// .smg bytes and pickling.
void add_grid_serialization(py::class_<RangeGrid>& grid) {
  grid.def(
          "to_bytes",
          [](const RangeGrid& g) {
            const auto bytes = encode_grid(g);
            return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
          },
          "The grid as .smg file bytes (docs/formats.md).")
      .def_static(
          "from_bytes",
          [](const py::bytes& b, const std::string& source) {
            const std::string s = b;
            return decode_grid(std::span(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()),
                               source);
          },
          py::arg("data"), py::arg("source") = "<bytes>",
          "A grid from .smg bytes; FileFormatError (a ValueError) naming `source` if malformed.")
      .def(py::pickle(
          [](const RangeGrid& g) {
            const auto bytes = encode_grid(g);
            return py::make_tuple(
                py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
          },
          [](const py::tuple& t) {
            const std::string s = t[0].cast<py::bytes>();
            return decode_grid(std::span(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()),
                               "<pickle>");
          }));
}

void bind_range_grid(py::module_& m) {
  py::class_<RangeGrid> grid(m, "RangeGrid", R"doc(
The cylindrical range grid (docs/formats.md, "RangeGrid"): cell (i, j) holds the radius r at
angle phi_i = phi0 + i * 2 pi / n_phi and height h_j = h0 + j * dh (mm, radians; z is the
turntable axis). The NumPy planes are indexed [j, i] = [h index, phi index]: rows of constant h,
the lowest h first, as in the .smg file (RangeGrid::index(i, j) = j * n_phi + i). Pictures of
the grid (texture_image, the PNG exports) are upright instead: their rows are these reversed.

Planes (all zero-copy views into the grid, kept alive by the array):
  radius      float32 (n_h, n_phi)     read-only (0 in invalid cells)
  valid       bool    (n_h, n_phi)     read-only
  confidence  float32 (n_h, n_phi)     read-only, in [0, 1] (0 in invalid cells)
  color       uint8   (n_h, n_phi, 3)  WRITABLE: assigning to it changes the grid's colours
The radius, validity and confidence planes are read-only because the library relies on their
invariants (a valid cell has a finite radius > 0, an invalid one radius 0); change them with
set_sample / invalidate / set_radius, or build a new grid with RangeGrid.from_arrays.
)doc");
  add_grid_geometry(grid);
  add_grid_planes(grid);
  add_grid_editing(grid);
  add_grid_metadata_and_copies(grid);
  add_grid_serialization(grid);
  grid.def("__repr__", [](const RangeGrid& g) {
    return "<scanmesh.RangeGrid " + std::to_string(g.n_phi()) + " x " + std::to_string(g.n_h()) +
           ", " + std::to_string(g.valid_count()) + " valid>";
  });
}

void bind_surface_fields(py::module_& m) {
  py::class_<SurfaceFields>(m, "SurfaceFields", R"doc(
Per-cell normals and principal curvatures of a grid (`curvature`, `read_fields`), in the grid's
(n_h, n_phi) layout. Arrays are zero-copy read-only views (kept alive by the array):
  defined        bool    (n_h, n_phi)    False where the method had no estimate
  normal         float32 (n_h, n_phi, 3) unit, away from the axis
  k1, k2         float32 (n_h, n_phi)    1/mm, k1 >= k2 (seed000: k1 only, k2 = 0)
  dir1, dir2     float32 (n_h, n_phi, 3) principal directions
mean() and gauss() return new arrays.)doc")
      .def_readonly("n_phi", &SurfaceFields::n_phi)
      .def_readonly("n_h", &SurfaceFields::n_h)
      .def_property_readonly("method", [](const SurfaceFields& f) { return to_string(f.method); })
      .def_readonly("radius_mm", &SurfaceFields::radius_mm,
                    "Neighbourhood radius of the quadric methods, 0 otherwise.")
      .def("defined_count", &SurfaceFields::defined_count)
      .def_property_readonly("defined", fields_property(&SurfaceFields::defined))
      .def_property_readonly("normal", fields_property(&SurfaceFields::normal))
      .def_property_readonly("k1", fields_property(&SurfaceFields::k1))
      .def_property_readonly("k2", fields_property(&SurfaceFields::k2))
      .def_property_readonly("dir1", fields_property(&SurfaceFields::dir1))
      .def_property_readonly("dir2", fields_property(&SurfaceFields::dir2))
      .def(
          "mean",
          [](const SurfaceFields& f) {
            return tabulated(f.size(), {f.n_h, f.n_phi}, [&f](std::size_t k) { return f.mean(k); });
          },
          "Mean curvature H = (k1 + k2) / 2, float32 (n_h, n_phi) (a new array).")
      .def(
          "gauss",
          [](const SurfaceFields& f) {
            return tabulated(f.size(), {f.n_h, f.n_phi},
                             [&f](std::size_t k) { return f.gauss(k); });
          },
          "Gaussian curvature K = k1 k2, float32 (n_h, n_phi) (a new array).")
      .def("__repr__", [](const SurfaceFields& f) {
        return "<scanmesh.SurfaceFields " + to_string(f.method) + " " + std::to_string(f.n_phi) +
               " x " + std::to_string(f.n_h) + ", " + std::to_string(f.defined_count()) +
               " defined>";
      });
}

void bind_cleaning(py::module_& m) {
  const CleaningOptions clean_defaults;
  m.def(
      "clean",
      [](const RangeGrid& grid, double spike_threshold_mm, double spike_spread_factor,
         int spike_min_neighbours, int min_component_cells, int fill_holes) {
        CleaningOptions o;
        SCANMESH_SET_FIELDS(o, spike_threshold_mm, spike_spread_factor, spike_min_neighbours,
                            min_component_cells);
        if (fill_holes < 0)
          throw InvalidInputError("clean: fill_holes must be >= 0 (0: off), got " +
                                  std::to_string(fill_holes));
        RangeGrid out = grid;
        CleaningReport report;
        HoleFillReport filled;
        {
          py::gil_scoped_release release;
          report = clean_grid(out, o);
          // As `scanmesh clean`: the cleaning recorded in the metadata, then the filling.
          out.metadata["cleaned"] = "spikes " + std::to_string(report.spikes_removed) +
                                    ", fragment cells " +
                                    std::to_string(report.fragment_cells_removed);
          if (fill_holes > 0) {
            filled = fill_small_holes(out, fill_holes);
            out.metadata["filled_cells"] = std::to_string(filled.cells);
          }
        }
        py::dict d = cleaning_report(report);
        d["holes_filled"] = filled.holes;
        d["cells_filled"] = filled.cells;
        d["valid_after"] = out.valid_count();
        return py::make_tuple(std::move(out), d);
      },
      py::arg("grid"), py::kw_only(),
      py::arg("spike_threshold_mm") = clean_defaults.spike_threshold_mm,
      py::arg("spike_spread_factor") = clean_defaults.spike_spread_factor,
      py::arg("spike_min_neighbours") = clean_defaults.spike_min_neighbours,
      py::arg("min_component_cells") = clean_defaults.min_component_cells,
      py::arg("fill_holes") = 0, R"doc(
Cleans a copy of the grid as `scanmesh clean` does (clean_grid, grid_cleaning.h): spikes
(|r - prediction| > spike_threshold_mm + spike_spread_factor * spread) and connected pieces of
fewer than min_component_cells cells become holes; then, when fill_holes > 0, interior holes of
at most that many cells are filled (fill_small_holes; confidence 0). The input is not changed.
Returns (cleaned grid, report dict: valid_before, valid_after, spikes_removed,
fragments_removed, fragment_cells_removed, components_kept, holes_filled, cells_filled).
ValueError for negative thresholds.)doc");
}

void bind_curvature(py::module_& m) {
  m.def(
      "curvature",
      [](const RangeGrid& grid, const std::string& method, double radius_mm) {
        require_range("curvature", "radius_mm", radius_mm, 0, 1e4);
        const CurvatureMethod cm = parse_curvature_method(method);
        py::gil_scoped_release release;
        return compute_fields(grid, cm, radius_mm);
      },
      py::arg("grid"), py::kw_only(), py::arg("method") = "grid-quadric",
      py::arg("radius_mm") = 0.0, R"doc(
Per-cell normals and principal curvatures (compute_fields, as `scanmesh curvature`).
method: "grid-quadric" (the CLI's default), "analytic", "quadric" or "seed" / "seed000" (seed
000's maximum-curvature operator, k1 only). radius_mm: neighbourhood radius of the quadric
methods (0: the library default, 6 mm). Returns SurfaceFields. ValueError for an unknown
method or a radius outside [0, 1e4].)doc");
}

}  // namespace

void init_grid(py::module_& m) {
  bind_range_grid(m);
  bind_surface_fields(m);
  bind_cleaning(m);
  bind_curvature(m);
}

}  // namespace scanmesh::python
