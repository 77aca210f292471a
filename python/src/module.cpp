// The compiled part of the `scanmesh` Python package (python/scanmesh/__init__.py re-exports it;
// docs/python.md).
#include "common.h"

PYBIND11_MODULE(_scanmesh, m) {
  using namespace scanmesh::python;
  m.doc() =
      "scanmesh: rotary laser-scanner grids and meshers (docs/python.md). Range grids and meshes "
      "as NumPy arrays; simulate, import, clean, mesh, check.";
  m.attr("__version__") = SCANMESH_VERSION;
  register_errors(m);
  init_grid(m);
  init_mesh(m);
  init_scan(m);
  init_meshing(m);
  init_io(m);
}
