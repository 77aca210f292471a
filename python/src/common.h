// Shared helpers of the Python bindings (docs/python.md): NumPy views of C++ memory, checked
// conversions of NumPy input, keyword-argument helpers and the error mapping.
//
// Memory rules, in one place:
//  - a *view* points into an object that Python owns (a RangeGrid's planes, a Mesh's vectors)
//    and keeps that object alive through the array's base; it is only handed out for memory
//    that never moves while the object lives (the grid's planes never resize; a Mesh in Python
//    is immutable), and it is read-only unless the data have no invariant to break;
//  - an *owned* array takes over a vector the library returned (moved, not copied);
//  - NumPy input is always copied into the library's types (their layout is not NumPy's).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/operators.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "scanmesh/core/color.h"
#include "scanmesh/core/point_cloud_io.h"

namespace scanmesh::python {

namespace py = pybind11;

// The vector element types are exposed as rows of NumPy arrays: their layout must be packed.
static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double));
static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
static_assert(sizeof(Eigen::Vector2f) == 2 * sizeof(float));
static_assert(sizeof(Eigen::Vector2d) == 2 * sizeof(double));
static_assert(sizeof(std::array<int, 3>) == 3 * sizeof(int));
static_assert(sizeof(Rgb8) == 3);
static_assert(sizeof(int) == 4);

//! A NumPy array over `data` (shape and strides in elements of T), kept alive by `base`.
//! Read-only unless `writable`.
template <typename T>
py::array view(py::handle base, const T* data, std::vector<py::ssize_t> shape,
               bool writable = false, py::dtype dtype = py::dtype::of<T>()) {
  std::vector<py::ssize_t> strides(shape.size());
  py::ssize_t step = static_cast<py::ssize_t>(sizeof(T));
  for (std::size_t d = shape.size(); d-- > 0;) {
    strides[d] = step;
    step *= shape[d];
  }
  py::array a(dtype, shape, strides, data, base);
  if (!writable) a.attr("setflags")(py::arg("write") = false);
  return a;
}

//! A NumPy array that owns `values` (moved into a capsule; no copy), reshaped to `shape`
//! (elements of T, C order). Writable: nothing else refers to the memory.
template <typename T>
py::array owned(std::vector<T>&& values, std::vector<py::ssize_t> shape,
                py::dtype dtype = py::dtype::of<T>()) {
  auto* heap = new std::vector<T>(std::move(values));
  py::capsule owner(heap, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return view(owner, heap->data(), std::move(shape), true, dtype);
}

//! Sets dict["name"] = object.name for every member name listed, in the listed order (the order
//! of the dict's keys): the library's result structs as the dicts Python gets, each member named
//! once, so that a key cannot drift from its member. Members under another key, or computed,
//! are set apart.
//! C++ has no reflection: turning a member's name into its key takes the preprocessor.
#define SCANMESH_PUT_FIELDS(dict, object, ...)                         \
  do {                                                                 \
    SCANMESH_FOR_EACH_(SCANMESH_PUT_FIELD_, dict, object, __VA_ARGS__) \
  } while (false)
#define SCANMESH_PUT_FIELD_(dict, object, name) dict[#name] = (object).name;

//! Sets object.name = name for every name listed: the keyword arguments of a binding into the
//! library's options struct, where each argument carries its member's name.
#define SCANMESH_SET_FIELDS(object, ...)                                 \
  do {                                                                   \
    SCANMESH_FOR_EACH_(SCANMESH_SET_FIELD_, object, unused, __VA_ARGS__) \
  } while (false)
#define SCANMESH_SET_FIELD_(object, unused, name) (object).name = name;

// SCANMESH_FOR_EACH_(m, a, b, x1, x2, ...) is m(a, b, x1) m(a, b, x2) ...: the C++20 __VA_OPT__
// recursion, one step per rescan of SCANMESH_EXPAND_ (enough for 86 names; more leave an
// unexpanded SCANMESH_FOR_EACH_AGAIN_ behind: a compile error, not a silently shorter dict).
#define SCANMESH_FOR_EACH_(m, a, b, ...) \
  __VA_OPT__(SCANMESH_EXPAND_(SCANMESH_FOR_EACH_STEP_(m, a, b, __VA_ARGS__)))
#define SCANMESH_FOR_EACH_STEP_(m, a, b, x, ...) \
  m(a, b, x) __VA_OPT__(SCANMESH_FOR_EACH_AGAIN_ SCANMESH_PARENS_(m, a, b, __VA_ARGS__))
#define SCANMESH_FOR_EACH_AGAIN_() SCANMESH_FOR_EACH_STEP_
#define SCANMESH_PARENS_ ()
#define SCANMESH_EXPAND_(...) \
  SCANMESH_EXPAND16_(SCANMESH_EXPAND16_(SCANMESH_EXPAND16_(SCANMESH_EXPAND16_(__VA_ARGS__))))
#define SCANMESH_EXPAND16_(...) \
  SCANMESH_EXPAND4_(SCANMESH_EXPAND4_(SCANMESH_EXPAND4_(SCANMESH_EXPAND4_(__VA_ARGS__))))
#define SCANMESH_EXPAND4_(...) \
  SCANMESH_EXPAND1_(SCANMESH_EXPAND1_(SCANMESH_EXPAND1_(SCANMESH_EXPAND1_(__VA_ARGS__))))
#define SCANMESH_EXPAND1_(...) __VA_ARGS__

//! Raises ValueError("<what>: <problem>").
[[noreturn]] void value_error(const std::string& message);

//! Rows of an N x C floating-point array (any real dtype, copied and converted).
std::vector<Eigen::Vector3d> to_vec3d(py::handle array, const char* name);
std::vector<Eigen::Vector3f> to_vec3f(py::handle array, const char* name);
std::vector<Eigen::Vector2f> to_vec2f(py::handle array, const char* name);
//! An N x 3 integer array (any integer dtype; values must fit a C int, and be >= 0 when
//! `non_negative`).
std::vector<std::array<int, 3>> to_int3(py::handle array, const char* name, bool non_negative);
std::vector<int> to_ints(py::handle array, const char* name);
//! An N x 3 integer array of 0..255.
std::vector<Rgb8> to_rgb(py::handle array, const char* name);
//! An unorganised cloud (width: the number of points) of an (N, 3) array of positions, with
//! normals and colours unless None. Whether they have a row per position is the caller's check:
//! each binding words that error its own way.
PointCloud to_cloud(py::handle positions, const char* name, py::handle normals = py::none(),
                    py::handle colors = py::none());
//! A float64 array of exactly the given shape (copied, converted).
py::array_t<double, py::array::c_style> to_double_array(py::handle array, const char* name,
                                                        std::vector<py::ssize_t> shape);
//! Three finite numbers (any sequence or array of 3).
Eigen::Vector3d to_point(py::handle value, const char* name);

//! Sets the attributes named by `kwargs` on `target` (a bound object with read/write properties);
//! TypeError for a name it does not have.
void set_fields(py::object target, const py::kwargs& kwargs, const char* what);

//! Raises ValueError("<what>: <name> must be in [lo, hi], got v") unless lo <= v <= hi (NaN
//! fails): the CLI's range checks for options the library does not check itself.
void require_range(const char* what, const char* name, double v, double lo, double hi);

void register_errors(py::module_& m);
void init_grid(py::module_& m);
void init_scan(py::module_& m);
void init_mesh(py::module_& m);
void init_meshing(py::module_& m);
void init_io(py::module_& m);

}  // namespace scanmesh::python
