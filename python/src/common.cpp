#include "common.h"

#include <climits>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "scanmesh/core/errors.h"

namespace scanmesh::python {

namespace {

std::string shape_text(const py::array& a) {
  std::ostringstream s;
  s << "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s << (d ? ", " : "") << a.shape(d);
  s << (a.ndim() == 1 ? ",)" : ")");
  return s.str();
}

// The array as C-contiguous T, with shape N x cols (cols 0: one dimension).
template <typename T>
py::array_t<T, py::array::c_style> rows_of(py::handle obj, const char* name, py::ssize_t cols) {
  py::array raw = py::array::ensure(obj);
  if (!raw) value_error(std::string(name) + " must be an array");
  const bool ok = cols == 0 ? raw.ndim() == 1
                            : (raw.ndim() == 2 && raw.shape(1) == cols) ||
                                  (raw.ndim() == 1 && raw.shape(0) == 0);
  if (!ok) {
    std::ostringstream s;
    s << name << " must be an array of shape " << (cols == 0 ? "(N,)" : "(N, ")
      << (cols == 0 ? "" : std::to_string(cols) + ")") << ", got shape " << shape_text(raw);
    value_error(s.str());
  }
  auto converted = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(raw);
  if (!converted) throw py::error_already_set();
  return converted;
}

void require_integer(py::handle obj, const char* name) {
  py::array raw = py::array::ensure(obj);
  if (raw && raw.size() > 0 && raw.dtype().kind() != 'i' && raw.dtype().kind() != 'u')
    value_error(std::string(name) + " must hold integers, got dtype " +
                py::str(raw.dtype()).cast<std::string>());
}

template <typename Vec, typename T>
std::vector<Vec> packed_rows(py::handle obj, const char* name, bool finite) {
  constexpr py::ssize_t cols = Vec::RowsAtCompileTime;
  const auto a = rows_of<T>(obj, name, cols);
  const py::ssize_t n = a.ndim() == 2 ? a.shape(0) : 0;
  std::vector<Vec> out(static_cast<std::size_t>(n));
  const T* src = a.data();
  for (py::ssize_t i = 0; i < n; ++i)
    for (py::ssize_t c = 0; c < cols; ++c) {
      const T v = src[i * cols + c];
      if (finite && !std::isfinite(v))
        value_error(std::string(name) + ": row " + std::to_string(i) + " is not finite");
      out[static_cast<std::size_t>(i)][c] = v;
    }
  return out;
}

}  // namespace

void value_error(const std::string& message) { throw py::value_error(message); }

std::vector<Eigen::Vector3d> to_vec3d(py::handle array, const char* name) {
  return packed_rows<Eigen::Vector3d, double>(array, name, false);
}
std::vector<Eigen::Vector3f> to_vec3f(py::handle array, const char* name) {
  return packed_rows<Eigen::Vector3f, float>(array, name, false);
}
std::vector<Eigen::Vector2f> to_vec2f(py::handle array, const char* name) {
  return packed_rows<Eigen::Vector2f, float>(array, name, false);
}

std::vector<std::array<int, 3>> to_int3(py::handle array, const char* name, bool non_negative) {
  require_integer(array, name);
  const auto a = rows_of<std::int64_t>(array, name, 3);
  const py::ssize_t n = a.ndim() == 2 ? a.shape(0) : 0;
  std::vector<std::array<int, 3>> out(static_cast<std::size_t>(n));
  const std::int64_t* src = a.data();
  for (py::ssize_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const std::int64_t v = src[i * 3 + c];
      if (v > INT_MAX || v < (non_negative ? 0 : INT_MIN))
        value_error(std::string(name) + ": row " + std::to_string(i) + " holds " +
                    std::to_string(v) + ", not an index");
      out[static_cast<std::size_t>(i)][c] = static_cast<int>(v);
    }
  return out;
}

std::vector<int> to_ints(py::handle array, const char* name) {
  require_integer(array, name);
  const auto a = rows_of<std::int64_t>(array, name, 0);
  std::vector<int> out(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    const std::int64_t v = a.data()[i];
    if (v > INT_MAX || v < INT_MIN)
      value_error(std::string(name) + ": entry " + std::to_string(i) + " does not fit an int");
    out[static_cast<std::size_t>(i)] = static_cast<int>(v);
  }
  return out;
}

std::vector<Rgb8> to_rgb(py::handle array, const char* name) {
  require_integer(array, name);
  const auto a = rows_of<std::int64_t>(array, name, 3);
  const py::ssize_t n = a.ndim() == 2 ? a.shape(0) : 0;
  std::vector<Rgb8> out(static_cast<std::size_t>(n));
  const std::int64_t* src = a.data();
  for (py::ssize_t i = 0; i < n; ++i) {
    std::uint8_t c[3];
    for (int k = 0; k < 3; ++k) {
      const std::int64_t v = src[i * 3 + k];
      if (v < 0 || v > 255)
        value_error(std::string(name) + ": row " + std::to_string(i) + " holds " +
                    std::to_string(v) + ", outside 0..255");
      c[k] = static_cast<std::uint8_t>(v);
    }
    out[static_cast<std::size_t>(i)] = {c[0], c[1], c[2]};
  }
  return out;
}

PointCloud to_cloud(py::handle positions, const char* name, py::handle normals, py::handle colors) {
  PointCloud cloud;
  cloud.positions = to_vec3d(positions, name);
  cloud.width = static_cast<int>(cloud.positions.size());
  if (!normals.is_none()) cloud.normals = to_vec3f(normals, "normals");
  if (!colors.is_none()) cloud.colors = to_rgb(colors, "colors");
  return cloud;
}

py::array_t<double, py::array::c_style> to_double_array(py::handle array, const char* name,
                                                        std::vector<py::ssize_t> shape) {
  py::array raw = py::array::ensure(array);
  if (!raw) value_error(std::string(name) + " must be an array");
  bool ok = raw.ndim() == static_cast<py::ssize_t>(shape.size());
  for (std::size_t d = 0; ok && d < shape.size(); ++d) ok = raw.shape(d) == shape[d];
  if (!ok) {
    std::ostringstream s;
    s << name << " must have shape (";
    for (std::size_t d = 0; d < shape.size(); ++d) s << (d ? ", " : "") << shape[d];
    s << "), got " << shape_text(raw);
    value_error(s.str());
  }
  auto converted = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(raw);
  if (!converted) throw py::error_already_set();
  return converted;
}

Eigen::Vector3d to_point(py::handle value, const char* name) {
  const auto a = to_double_array(value, name, {3});
  const Eigen::Vector3d v(a.at(0), a.at(1), a.at(2));
  if (!v.allFinite()) value_error(std::string(name) + " must be three finite numbers");
  return v;
}

void set_fields(py::object target, const py::kwargs& kwargs, const char* what) {
  for (const auto& [key, value] : kwargs) {
    const std::string name = py::str(key);
    if (name.empty() || name[0] == '_' || !py::hasattr(target, name.c_str()) ||
        py::isinstance<py::function>(target.attr(name.c_str())))
      throw py::type_error(std::string(what) + " has no option '" + name + "'");
    target.attr(name.c_str()) = value;
  }
}

void require_range(const char* what, const char* name, double v, double lo, double hi) {
  if (v >= lo && v <= hi) return;
  std::ostringstream s;
  s << what << ": " << name << " must be in [" << lo << ", " << hi << "], got " << v;
  value_error(s.str());
}

// Python classes for the library's typed errors (errors.h), each also a subclass of the built-in
// exception a Python caller expects: impossible parameters and malformed files are ValueErrors,
// refusals of the operating system OSErrors.
namespace {
PyObject* g_error = nullptr;
PyObject* g_invalid_input = nullptr;
PyObject* g_file_format = nullptr;
PyObject* g_io = nullptr;
PyObject* g_device = nullptr;

PyObject* new_exception(py::module_& m, const char* name, PyObject* base1, PyObject* base2,
                        const char* doc) {
  const std::string qualified = "scanmesh." + std::string(name);
  py::tuple bases = base2 ? py::make_tuple(py::handle(base1), py::handle(base2))
                          : py::make_tuple(py::handle(base1));
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (!type) throw py::error_already_set();
  m.add_object(name, py::handle(type));  // the module keeps a reference; so do we (never freed)
  return type;
}
}  // namespace

void register_errors(py::module_& m) {
  g_error = new_exception(m, "Error", PyExc_Exception, nullptr,
                          "Base of every error the scanmesh library raises.");
  g_invalid_input =
      new_exception(m, "InvalidInputError", g_error, PyExc_ValueError,
                    "An impossible parameter or option value (the library's InvalidInputError).");
  g_file_format = new_exception(
      m, "FileFormatError", g_error, PyExc_ValueError,
      "A file's content is malformed, truncated or corrupt; the message starts with the file "
      "name, which is also the exception's `filename` attribute.");
  g_io = new_exception(m, "IoError", g_error, PyExc_OSError,
                       "The operating system refused a read or write (missing file, "
                       "permission, disk full).");
  g_device = new_exception(m, "DeviceError", g_error, PyExc_RuntimeError,
                           "A device failed or answered nonsense.");

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const FileFormatError& e) {
      py::object error = py::reinterpret_borrow<py::object>(g_file_format)(e.what());
      error.attr("filename") = e.file().string();
      PyErr_SetObject(g_file_format, error.ptr());
    } catch (const InvalidInputError& e) {
      PyErr_SetString(g_invalid_input, e.what());
    } catch (const IoError& e) {
      PyErr_SetString(g_io, e.what());
    } catch (const DeviceError& e) {
      PyErr_SetString(g_device, e.what());
    } catch (const Error& e) {
      PyErr_SetString(g_error, e.what());
    } catch (const std::filesystem::filesystem_error& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    }
  });
}

}  // namespace scanmesh::python
