// Point-cloud readers for the fan mesher (docs/formats.md, "XYZ point clouds").
#include "scanmesh/meshing/fans/point_cloud_io.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <optional>
#include <sstream>
#include <string_view>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_file.h"
#include "scanmesh/core/mesh_io.h"

namespace scanmesh {

namespace {

bool parse_double(std::string_view s, double& out) {
  if (s.empty()) return false;
  if (s.front() == '+') s.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && ptr == s.data() + s.size();
}

// A whole header word as a non-negative integer no larger than `max`; nullopt otherwise (no
// std::atoi: out-of-range text is undefined behaviour there).
std::optional<long long> parse_header_count(const std::string& s, long long max) {
  long long v = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size() || v < 0 || v > max) return std::nullopt;
  return v;
}

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (std::isspace(static_cast<unsigned char>(line[i])) || line[i] == ','))
      ++i;
    const std::size_t b = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i])) && line[i] != ',')
      ++i;
    if (i > b) out.push_back(line.substr(b, i - b));
  }
  return out;
}

std::string lower_extension(const std::filesystem::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

}  // namespace

std::vector<Eigen::Vector3d> parse_xyz(const std::string& text,
                                       const std::filesystem::path& source) {
  std::vector<Eigen::Vector3d> pts;
  std::size_t line_no = 0, pos = 0;
  std::size_t columns = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (const auto hash = line.find('#'); hash != std::string_view::npos)
      line = line.substr(0, hash);
    const auto fields = split_fields(line);
    if (fields.empty()) continue;
    const std::string where = "line " + std::to_string(line_no) + ": ";
    if (fields.size() < 3)
      throw FileFormatError(source, where + "expected at least 3 numbers (x y z)");
    if (columns == 0) columns = fields.size();
    if (fields.size() != columns)
      throw FileFormatError(source, where + "has " + std::to_string(fields.size()) +
                                        " columns, earlier lines have " + std::to_string(columns));
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k)
      if (!parse_double(fields[k], p[k]) || !std::isfinite(p[k]))
        throw FileFormatError(source,
                              where + "'" + std::string(fields[k]) + "' is not a finite number");
    for (std::size_t k = 3; k < fields.size(); ++k) {
      double ignored = 0;
      if (!parse_double(fields[k], ignored))
        throw FileFormatError(source, where + "'" + std::string(fields[k]) + "' is not a number");
    }
    pts.push_back(p);
  }
  if (pts.empty()) throw FileFormatError(source, "no points");
  return pts;
}

std::vector<Eigen::Vector3d> parse_pcd(const std::string& bytes,
                                       const std::filesystem::path& source) {
  std::vector<std::string> fields;
  std::vector<int> sizes, counts;
  std::vector<char> types;
  long long width = -1, height = 1, points = -1;
  std::string data;
  std::size_t pos = 0;
  while (pos < bytes.size() && data.empty()) {
    std::size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) throw FileFormatError(source, "PCD header ends without DATA");
    std::string line = bytes.substr(pos, end - pos);
    pos = end + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    std::string key;
    in >> key;
    std::string tok;
    const auto count_word = [&](const std::string& word) {
      // SIZE is 1..8 bytes and COUNT a few thousand at most in any real PCD.
      const auto v = parse_header_count(word, 1 << 20);
      if (!v)
        throw FileFormatError(source, "PCD " + key + " value '" + word.substr(0, 24) +
                                          "' is not an integer in 0..1048576");
      return static_cast<int>(*v);
    };
    if (key == "VERSION") {
    } else if (key == "FIELDS") {
      while (in >> tok) fields.push_back(tok);
    } else if (key == "SIZE") {
      while (in >> tok) sizes.push_back(count_word(tok));
    } else if (key == "TYPE") {
      while (in >> tok) types.push_back(tok.empty() ? '?' : tok[0]);
    } else if (key == "COUNT") {
      while (in >> tok) counts.push_back(count_word(tok));
    } else if (key == "WIDTH") {
      in >> width;
    } else if (key == "HEIGHT") {
      in >> height;
    } else if (key == "VIEWPOINT") {
    } else if (key == "POINTS") {
      in >> points;
    } else if (key == "DATA") {
      in >> data;
      if (data.empty()) throw FileFormatError(source, "PCD DATA line names no encoding");
    } else {
      throw FileFormatError(source, "unknown PCD header line '" + line.substr(0, 40) + "'");
    }
    if (in.fail() && key != "VERSION" && key != "VIEWPOINT" && key != "FIELDS" && key != "SIZE" &&
        key != "TYPE" && key != "COUNT")
      throw FileFormatError(source, "malformed PCD header line '" + line.substr(0, 40) + "'");
  }
  if (data.empty()) throw FileFormatError(source, "PCD header has no DATA line");
  if (fields.empty()) throw FileFormatError(source, "PCD header has no FIELDS");
  if (counts.empty()) counts.assign(fields.size(), 1);
  if (sizes.size() != fields.size() || types.size() != fields.size() ||
      counts.size() != fields.size())
    throw FileFormatError(source, "PCD FIELDS, SIZE, TYPE and COUNT differ in length");
  // Overflow-safe WIDTH x HEIGHT (hostile headers declare 9e18 x 9e18).
  long long area = 0;
  if (width < 0 || height < 0 || __builtin_mul_overflow(width, height, &area))
    throw FileFormatError(source, "PCD WIDTH x HEIGHT is negative or too large");
  if (points < 0) points = area;
  if (points != area) throw FileFormatError(source, "PCD POINTS does not equal WIDTH x HEIGHT");
  std::array<int, 3> xyz{-1, -1, -1};
  std::vector<std::size_t> offset(fields.size(), 0), column(fields.size(), 0);
  std::size_t stride = 0, ncols = 0;
  for (std::size_t f = 0; f < fields.size(); ++f) {
    if (sizes[f] <= 0 || counts[f] <= 0)
      throw FileFormatError(source, "PCD SIZE/COUNT not positive");
    offset[f] = stride;
    column[f] = ncols;
    stride += static_cast<std::size_t>(sizes[f]) * counts[f];
    ncols += counts[f];
    for (int a = 0; a < 3; ++a)
      if (fields[f] == std::string(1, "xyz"[a])) xyz[a] = static_cast<int>(f);
  }
  for (int a = 0; a < 3; ++a) {
    if (xyz[a] < 0) throw FileFormatError(source, "PCD has no x, y and z fields");
    const int f = xyz[a];
    if (types[f] != 'F' || (sizes[f] != 4 && sizes[f] != 8))
      throw FileFormatError(source, "PCD x/y/z must be TYPE F with SIZE 4 or 8");
  }
  if (data != "ascii" && data != "binary")
    throw FileFormatError(source, "PCD DATA '" + data + "' is not supported (ascii or binary)");
  // The declared point count is checked against the bytes that follow the header before anything
  // is reserved: an ASCII point takes at least one character per value (plus separators), a
  // binary point exactly `stride` bytes.
  const std::size_t remaining = bytes.size() - pos;
  const std::size_t min_point_bytes = data == "binary" ? stride : 2 * ncols - 1;
  if (static_cast<unsigned long long>(points) > remaining / min_point_bytes + 1)
    throw FileFormatError(source, "PCD declares " + std::to_string(points) + " points but only " +
                                      std::to_string(remaining) + " bytes of data follow");
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(static_cast<std::size_t>(points));
  if (data == "ascii") {
    std::string_view rest(bytes.data() + pos, bytes.size() - pos);
    long long read = 0;
    std::size_t p = 0;
    while (p < rest.size() && read < points) {
      std::size_t e = rest.find('\n', p);
      if (e == std::string_view::npos) e = rest.size();
      const auto cols = split_fields(rest.substr(p, e - p));
      p = e + 1;
      if (cols.empty()) continue;
      if (cols.size() != ncols)
        throw FileFormatError(source, "PCD point " + std::to_string(read) + " has " +
                                          std::to_string(cols.size()) + " values, expected " +
                                          std::to_string(ncols));
      Eigen::Vector3d v;
      for (int a = 0; a < 3; ++a) {
        const std::string_view s = cols[column[xyz[a]]];
        if (s == "nan" || s == "NaN" || s == "-nan") {
          v[a] = std::nan("");
        } else if (!parse_double(s, v[a])) {
          throw FileFormatError(source, "PCD point " + std::to_string(read) + ": '" +
                                            std::string(s) + "' is not a number");
        }
      }
      ++read;
      if (v.allFinite()) pts.push_back(v);
    }
    if (read < points)
      throw FileFormatError(source, "PCD is truncated: " + std::to_string(read) + " of " +
                                        std::to_string(points) + " points");
  } else if (data == "binary") {
    if (static_cast<unsigned long long>(points) > remaining / stride)
      throw FileFormatError(source, "PCD binary data is truncated: " + std::to_string(points) +
                                        " points of " + std::to_string(stride) +
                                        " bytes declared, " + std::to_string(remaining) +
                                        " bytes present");
    for (long long i = 0; i < points; ++i) {
      const char* rec = bytes.data() + pos + static_cast<std::size_t>(i) * stride;
      Eigen::Vector3d v;
      for (int a = 0; a < 3; ++a) {
        const int f = xyz[a];
        if (sizes[f] == 4) {
          float x;
          std::memcpy(&x, rec + offset[f], 4);
          v[a] = x;
        } else {
          std::memcpy(&v[a], rec + offset[f], 8);
        }
      }
      if (v.allFinite()) pts.push_back(v);
    }
  } else {
    throw FileFormatError(source, "PCD DATA '" + data + "' is not supported (ascii or binary)");
  }
  if (pts.empty()) throw FileFormatError(source, "PCD has no finite point");
  return pts;
}

std::vector<Eigen::Vector3d> read_point_cloud(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".ply") {
    Mesh m = read_ply(path);
    if (m.positions.empty()) throw FileFormatError(path, "PLY has no vertices");
    return m.positions;
  }
  if (ext == ".smg") {
    const RangeGrid g = read_grid(path);
    std::vector<Eigen::Vector3d> pts;
    for (int j = 0; j < g.n_h(); ++j)
      for (int i = 0; i < g.n_phi(); ++i)
        if (g.valid(i, j)) pts.push_back(g.cartesian(i, j));
    if (pts.empty()) throw FileFormatError(path, "grid has no valid cell");
    return pts;
  }
  if (ext == ".pcd" || ext == ".xyz" || ext == ".txt" || ext == ".pts") {
    const auto raw = read_file_bytes(path);
    const std::string bytes(raw.begin(), raw.end());
    return ext == ".pcd" ? parse_pcd(bytes, path) : parse_xyz(bytes, path);
  }
  throw InvalidInputError("unknown point-cloud extension '" + ext + "' of " + path.string() +
                          " (use .ply, .pcd, .xyz, .txt, .pts or .smg)");
}

}  // namespace scanmesh
