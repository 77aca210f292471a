// OFF, OBJ (+ MTL texture) and STL readers and read_mesh by extension (docs/formats.md, "Mesh
// files"). Like the PLY reader they treat every file as hostile: counts are checked against the
// text that remains before anything is reserved, indices against the vertices present, and every
// error names the file and the line.
#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/mesh_io.h"

namespace scanmesh {

namespace {

// Splits text into lines with their 1-based numbers, dropping '#' comments and '\r'.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text) : text_(text) {}

  //! The next line that is not blank after removing its comment; false at the end.
  bool next(std::string_view& line) {
    while (pos_ < text_.size()) {
      std::size_t end = text_.find('\n', pos_);
      if (end == std::string_view::npos) end = text_.size();
      line = text_.substr(pos_, end - pos_);
      pos_ = end + 1;
      ++line_no_;
      if (const auto hash = line.find('#'); hash != std::string_view::npos)
        line = line.substr(0, hash);
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back())))
        line.remove_suffix(1);
      while (!line.empty() && std::isspace(static_cast<unsigned char>(line.front())))
        line.remove_prefix(1);
      if (!line.empty()) return true;
    }
    return false;
  }
  std::size_t line_no() const { return line_no_; }
  std::size_t remaining_bytes() const { return pos_ < text_.size() ? text_.size() - pos_ : 0; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0, line_no_ = 0;
};

std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t b = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > b) out.push_back(line.substr(b, i - b));
  }
  return out;
}

bool to_double(std::string_view s, double& out) {
  if (s.empty()) return false;
  if (s.front() == '+') s.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && ptr == s.data() + s.size();
}

bool to_long(std::string_view s, long long& out) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && ptr == s.data() + s.size() && !s.empty();
}

[[noreturn]] void fail_at(const std::filesystem::path& source, std::size_t line,
                          const std::string& what) {
  throw FileFormatError(source, "line " + std::to_string(line) + ": " + what);
}

std::uint8_t channel(double v, bool unit_range) {
  const double scaled = unit_range ? v * 255.0 : v;
  if (!std::isfinite(scaled)) return 0;
  return static_cast<std::uint8_t>(std::lround(std::clamp(scaled, 0.0, 255.0)));
}

void fan_triangulate(const std::vector<int>& polygon, Mesh& mesh) {
  for (std::size_t c = 1; c + 1 < polygon.size(); ++c)
    mesh.triangles.push_back({polygon[0], polygon[c], polygon[c + 1]});
}

// ---------------------------------------------------------------------------------------------
// OFF

struct OffCounts {
  long long vertices = 0, faces = 0;
  bool colors = false;
};

OffCounts parse_off_header(LineCursor& in, const std::filesystem::path& source) {
  std::string_view line;
  if (!in.next(line)) throw FileFormatError(source, "empty file (no OFF header)");
  auto w = words(line);
  const std::string_view keyword = w.front();
  // [ST][C][N][4][n]OFF: texture coordinates, colours, normals; 4D and nD are not meshes here.
  if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF")
    fail_at(source, in.line_no(), "not an OFF file (first word '" +
                                      std::string(keyword.substr(0, 16)) + "')");
  const std::string_view prefix = keyword.substr(0, keyword.size() - 3);
  if (prefix.find('4') != std::string_view::npos || prefix.find('n') != std::string_view::npos)
    fail_at(source, in.line_no(), "'" + std::string(keyword) + "' (not 3D) is not supported");
  if (prefix.find('S') != std::string_view::npos || prefix.find('T') != std::string_view::npos)
    fail_at(source, in.line_no(), "OFF with texture coordinates is not supported");
  OffCounts c;
  c.colors = prefix.find('C') != std::string_view::npos;
  const bool normals = prefix.find('N') != std::string_view::npos;
  if (normals) fail_at(source, in.line_no(), "OFF with vertex normals (NOFF) is not supported");
  w.erase(w.begin());
  if (w.empty()) {
    if (!in.next(line)) throw FileFormatError(source, "OFF header has no vertex/face counts");
    w = words(line);
  }
  if (w.size() < 2 || !to_long(w[0], c.vertices) || !to_long(w[1], c.faces) || c.vertices < 0 ||
      c.faces < 0)
    fail_at(source, in.line_no(), "expected the vertex and face counts");
  // A vertex line takes at least 6 bytes ("0 0 0\n"), a face line 8 ("3 0 1 2\n").
  const auto budget = static_cast<long long>(in.remaining_bytes() / 6 + 1);
  if (c.vertices > budget || c.faces > budget ||
      c.vertices > std::numeric_limits<int>::max() - 1)
    fail_at(source, in.line_no(),
            "declares " + std::to_string(c.vertices) + " vertices and " +
                std::to_string(c.faces) + " faces, more than the file can hold");
  return c;
}

}  // namespace

Mesh parse_off(std::string_view text, const std::filesystem::path& source) {
  LineCursor in(text);
  const OffCounts counts = parse_off_header(in, source);
  Mesh mesh;
  mesh.positions.reserve(static_cast<std::size_t>(counts.vertices));
  std::string_view line;
  for (long long v = 0; v < counts.vertices; ++v) {
    if (!in.next(line))
      throw FileFormatError(source, "truncated: " + std::to_string(v) + " of " +
                                        std::to_string(counts.vertices) + " vertices");
    const auto w = words(line);
    Eigen::Vector3d p;
    if (w.size() < 3 || !to_double(w[0], p.x()) || !to_double(w[1], p.y()) ||
        !to_double(w[2], p.z()))
      fail_at(source, in.line_no(), "expected a vertex 'x y z'");
    if (!p.allFinite()) fail_at(source, in.line_no(), "non-finite coordinate");
    mesh.positions.push_back(p);
    if (counts.colors) {
      std::array<double, 3> rgb{};
      if (w.size() < 6 || !to_double(w[3], rgb[0]) || !to_double(w[4], rgb[1]) ||
          !to_double(w[5], rgb[2]))
        fail_at(source, in.line_no(), "COFF vertex without 'r g b'");
      // Integer text is 0..255; text with a decimal point is 0..1 (both occur in COFF files).
      const bool unit = w[3].find('.') != std::string_view::npos;
      mesh.colors.push_back({channel(rgb[0], unit), channel(rgb[1], unit), channel(rgb[2], unit)});
    }
  }
  std::vector<int> polygon;
  for (long long f = 0; f < counts.faces; ++f) {
    if (!in.next(line))
      throw FileFormatError(source, "truncated: " + std::to_string(f) + " of " +
                                        std::to_string(counts.faces) + " faces");
    const auto w = words(line);
    long long n = 0;
    if (w.empty() || !to_long(w[0], n) || n < 3 || static_cast<std::size_t>(n) + 1 > w.size())
      fail_at(source, in.line_no(), "expected a face 'n i1 ... in' with n >= 3 indices");
    polygon.clear();
    for (long long k = 1; k <= n; ++k) {
      long long idx = -1;
      if (!to_long(w[static_cast<std::size_t>(k)], idx) || idx < 0 || idx >= counts.vertices)
        fail_at(source, in.line_no(),
                "vertex index '" + std::string(w[static_cast<std::size_t>(k)].substr(0, 20)) +
                    "' is not in 0.." + std::to_string(counts.vertices - 1));
      polygon.push_back(static_cast<int>(idx));
    }
    fan_triangulate(polygon, mesh);
  }
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// OBJ

namespace {

// Resolves an OBJ index (1-based, negative = relative to the end) into 0..count-1.
std::optional<int> obj_index(std::string_view s, std::size_t count) {
  long long v = 0;
  if (!to_long(s, v) || v == 0) return std::nullopt;
  const long long idx = v > 0 ? v - 1 : static_cast<long long>(count) + v;
  if (idx < 0 || idx >= static_cast<long long>(count)) return std::nullopt;
  return static_cast<int>(idx);
}

// map_Kd of every material in an MTL file's text.
std::map<std::string, std::string, std::less<>> mtl_textures(std::string_view mtl_text) {
  std::map<std::string, std::string, std::less<>> out;
  LineCursor in(mtl_text);
  std::string_view line;
  std::string current;
  while (in.next(line)) {
    const auto w = words(line);
    if (w[0] == "newmtl" && w.size() >= 2) current = std::string(w[1]);
    // map_Kd [options] file: the file name is the last word.
    if (w[0] == "map_Kd" && w.size() >= 2 && !current.empty())
      out[current] = std::string(w.back());
  }
  return out;
}

std::optional<std::string> mtllib_name(std::string_view text) {
  LineCursor in(text);
  std::string_view line;
  while (in.next(line)) {
    const auto w = words(line);
    if (w[0] == "mtllib" && w.size() >= 2) return std::string(w[1]);
  }
  return std::nullopt;
}

}  // namespace

ObjMesh parse_obj(std::string_view text, const std::filesystem::path& source,
                  std::string_view mtl_text) {
  const auto textures = mtl_textures(mtl_text);
  ObjMesh out;
  Mesh& mesh = out.mesh;
  std::vector<Eigen::Vector3f> normals;  // by vn index; carried to vertices when faces name them
  std::vector<Rgb8> colors;
  std::vector<int> vertex_normal;
  bool any_color = false, textured_faces = false;
  LineCursor in(text);
  std::string_view line;
  std::vector<int> poly_v, poly_t, poly_n;
  while (in.next(line)) {
    const auto w = words(line);
    const std::string_view key = w[0];
    if (key == "v") {
      Eigen::Vector3d p;
      if (w.size() < 4 || !to_double(w[1], p.x()) || !to_double(w[2], p.y()) ||
          !to_double(w[3], p.z()))
        fail_at(source, in.line_no(), "expected 'v x y z'");
      if (!p.allFinite()) fail_at(source, in.line_no(), "non-finite coordinate");
      mesh.positions.push_back(p);
      std::array<double, 3> rgb{0, 0, 0};
      // "v x y z r g b" (MeshLab, many scanners): colours as 0..1 floats.
      if (w.size() >= 7 && to_double(w[4], rgb[0]) && to_double(w[5], rgb[1]) &&
          to_double(w[6], rgb[2]))
        any_color = true;
      colors.push_back({channel(rgb[0], true), channel(rgb[1], true), channel(rgb[2], true)});
    } else if (key == "vt") {
      double u = 0, v = 0;
      if (w.size() < 3 || !to_double(w[1], u) || !to_double(w[2], v) || !std::isfinite(u) ||
          !std::isfinite(v))
        fail_at(source, in.line_no(), "expected 'vt u v'");
      mesh.texcoords.emplace_back(static_cast<float>(u), static_cast<float>(v));
    } else if (key == "vn") {
      double x = 0, y = 0, z = 0;
      if (w.size() < 4 || !to_double(w[1], x) || !to_double(w[2], y) || !to_double(w[3], z))
        fail_at(source, in.line_no(), "expected 'vn x y z'");
      normals.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
    } else if (key == "usemtl") {
      if (w.size() >= 2 && out.texture.empty())
        if (const auto it = textures.find(w[1]); it != textures.end())
          out.texture = source.parent_path() / it->second;
    } else if (key == "f") {
      if (w.size() < 4) fail_at(source, in.line_no(), "a face needs at least 3 corners");
      poly_v.clear();
      poly_t.clear();
      poly_n.clear();
      for (std::size_t k = 1; k < w.size(); ++k) {
        const std::string_view corner = w[k];
        const std::size_t s1 = corner.find('/');
        const std::string_view vs = corner.substr(0, s1);
        const auto vi = obj_index(vs, mesh.positions.size());
        if (!vi)
          fail_at(source, in.line_no(),
                  "vertex index '" + std::string(vs.substr(0, 20)) + "' names no vertex");
        poly_v.push_back(*vi);
        if (s1 == std::string_view::npos) continue;
        const std::string_view rest = corner.substr(s1 + 1);
        const std::size_t s2 = rest.find('/');
        const std::string_view ts = rest.substr(0, s2);
        if (!ts.empty()) {
          const auto ti = obj_index(ts, mesh.texcoords.size());
          if (!ti) fail_at(source, in.line_no(), "texture index '" +
                                                     std::string(ts.substr(0, 20)) +
                                                     "' names no 'vt'");
          poly_t.push_back(*ti);
        }
        if (s2 != std::string_view::npos) {
          const auto ni = obj_index(rest.substr(s2 + 1), normals.size());
          if (!ni) fail_at(source, in.line_no(), "normal index names no 'vn'");
          poly_n.push_back(*ni);
        }
      }
      const bool has_t = poly_t.size() == poly_v.size();
      if (!poly_t.empty() && !has_t)
        fail_at(source, in.line_no(), "some corners of the face have texture indices, some not");
      if (has_t) textured_faces = true;
      vertex_normal.resize(mesh.positions.size(), -1);
      if (poly_n.size() == poly_v.size())
        for (std::size_t k = 0; k < poly_v.size(); ++k) vertex_normal[poly_v[k]] = poly_n[k];
      for (std::size_t c = 1; c + 1 < poly_v.size(); ++c) {
        mesh.triangles.push_back({poly_v[0], poly_v[c], poly_v[c + 1]});
        mesh.face_texcoords.push_back(has_t ? std::array<int, 3>{poly_t[0], poly_t[c], poly_t[c + 1]}
                                            : std::array<int, 3>{-1, -1, -1});
      }
    }
    // mtllib, o, g, s, l, p and anything else: not geometry we keep.
  }
  if (any_color) mesh.colors = std::move(colors);
  vertex_normal.resize(mesh.positions.size(), -1);
  if (!normals.empty() && std::all_of(vertex_normal.begin(), vertex_normal.end(),
                                      [](int n) { return n >= 0; }))
    for (int n : vertex_normal) mesh.normals.push_back(normals[n].normalized());
  // Texture coordinates only when every face has them (Mesh keeps all faces or none).
  const bool all_textured =
      textured_faces && std::all_of(mesh.face_texcoords.begin(), mesh.face_texcoords.end(),
                                    [](const auto& t) { return t[0] >= 0; });
  if (!all_textured) {
    mesh.face_texcoords.clear();
    mesh.texcoords.clear();
    out.texture.clear();
  }
  return out;
}

ObjMesh read_obj(const std::filesystem::path& path) {
  const auto raw = read_file_bytes(path);
  const std::string_view text(reinterpret_cast<const char*>(raw.data()), raw.size());
  std::string mtl;
  if (const auto lib = mtllib_name(text)) {
    const std::filesystem::path mtl_path = path.parent_path() / *lib;
    std::error_code ec;
    if (std::filesystem::is_regular_file(mtl_path, ec)) {
      const auto m = read_file_bytes(mtl_path);
      mtl.assign(m.begin(), m.end());
    }
  }
  return parse_obj(text, path, mtl);
}

// ---------------------------------------------------------------------------------------------
// STL

namespace {

// Welds corners with bit-identical coordinates (STL stores every triangle's corners anew).
class VertexWelder {
 public:
  explicit VertexWelder(Mesh& mesh) : mesh_(mesh) {}
  int add(const Eigen::Vector3d& p) {
    const auto [it, inserted] = index_.try_emplace({p.x(), p.y(), p.z()},
                                                   static_cast<int>(mesh_.positions.size()));
    if (inserted) mesh_.positions.push_back(p);
    return it->second;
  }

 private:
  Mesh& mesh_;
  std::map<std::array<double, 3>, int> index_;
};

void add_stl_triangle(Mesh& mesh, VertexWelder& weld, const std::array<Eigen::Vector3d, 3>& c) {
  const std::array<int, 3> t{weld.add(c[0]), weld.add(c[1]), weld.add(c[2])};
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return;  // a degenerate facet adds no face
  mesh.triangles.push_back(t);
}

Mesh parse_stl_binary(std::span<const std::uint8_t> bytes, const std::filesystem::path& source) {
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  if ((bytes.size() - 84) / 50 < n)
    throw FileFormatError(source, "binary STL declares " + std::to_string(n) +
                                      " triangles but holds " +
                                      std::to_string((bytes.size() - 84) / 50));
  Mesh mesh;
  VertexWelder weld(mesh);
  for (std::uint32_t t = 0; t < n; ++t) {
    const std::uint8_t* rec = bytes.data() + 84 + 50ull * t + 12;  // skip the facet normal
    std::array<Eigen::Vector3d, 3> corners;
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) {
        float v;
        std::memcpy(&v, rec + 12 * c + 4 * a, 4);
        if (!std::isfinite(v))
          throw FileFormatError(source, "triangle " + std::to_string(t) + ": non-finite corner");
        corners[c][a] = v;
      }
    add_stl_triangle(mesh, weld, corners);
  }
  return mesh;
}

Mesh parse_stl_ascii(std::string_view text, const std::filesystem::path& source) {
  Mesh mesh;
  VertexWelder weld(mesh);
  LineCursor in(text);
  std::string_view line;
  std::array<Eigen::Vector3d, 3> corners;
  int corner = 0;
  while (in.next(line)) {
    const auto w = words(line);
    if (w[0] == "vertex") {
      if (corner == 3) fail_at(source, in.line_no(), "a facet with more than 3 vertices");
      Eigen::Vector3d p;
      if (w.size() < 4 || !to_double(w[1], p.x()) || !to_double(w[2], p.y()) ||
          !to_double(w[3], p.z()) || !p.allFinite())
        fail_at(source, in.line_no(), "expected 'vertex x y z' with finite numbers");
      corners[corner++] = p;
    } else if (w[0] == "endloop") {
      if (corner != 3) fail_at(source, in.line_no(), "a facet needs exactly 3 vertices");
      add_stl_triangle(mesh, weld, corners);
      corner = 0;
    }
  }
  return mesh;
}

}  // namespace

Mesh parse_stl(std::span<const std::uint8_t> bytes, const std::filesystem::path& source) {
  const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  // Binary files may also start with "solid" in their 80-byte header: the size decides first.
  if (bytes.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    if (84 + 50ull * n == bytes.size()) return parse_stl_binary(bytes, source);
  }
  if (text.substr(0, 5) == "solid") {
    Mesh m = parse_stl_ascii(text, source);
    if (!m.triangles.empty()) return m;
  }
  if (bytes.size() < 84) throw FileFormatError(source, "too short for an STL file");
  return parse_stl_binary(bytes, source);
}

Mesh read_mesh(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".ply") return read_ply(path);
  if (ext == ".obj") return read_obj(path).mesh;
  const auto raw = read_file_bytes(path);
  if (ext == ".stl") return parse_stl(raw, path);
  if (ext == ".off")
    return parse_off(std::string_view(reinterpret_cast<const char*>(raw.data()), raw.size()),
                     path);
  throw InvalidInputError("unknown mesh extension '" + ext + "' of " + path.string() +
                          " (use .ply, .off, .obj or .stl)");
}

}  // namespace scanmesh
