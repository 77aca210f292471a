// Point-cloud readers (docs/formats.md, "Point clouds"). Every file is treated as hostile:
// declared counts are checked against the bytes present before anything is reserved.
#include "scanmesh/core/point_cloud_io.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
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


std::size_t PointCloud::finite_count() const {
  return static_cast<std::size_t>(
      std::count_if(positions.begin(), positions.end(), [](const auto& p) { return p.allFinite(); }));
}

PointCloud PointCloud::finite_points() const {
  PointCloud out;
  for (std::size_t k = 0; k < positions.size(); ++k) {
    if (!positions[k].allFinite()) continue;
    out.positions.push_back(positions[k]);
    if (has_normals()) out.normals.push_back(normals[k]);
    if (has_colors()) out.colors.push_back(colors[k]);
  }
  out.width = static_cast<int>(out.positions.size());
  return out;
}

namespace {

std::uint8_t color_channel(double v) {
  if (!std::isfinite(v)) return 0;
  return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
}

}  // namespace

PointCloud parse_xyz(const std::string& text, const std::filesystem::path& source) {
  PointCloud cloud;
  std::size_t line_no = 0, pos = 0;
  std::size_t columns = 0;
  std::vector<double> values;
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
    values.assign(fields.size(), 0.0);
    for (std::size_t k = 0; k < fields.size(); ++k) {
      if (!parse_double(fields[k], values[k]))
        throw FileFormatError(source, where + "'" + std::string(fields[k]) + "' is not a number");
      if (k < 3 && !std::isfinite(values[k]))
        throw FileFormatError(source,
                              where + "'" + std::string(fields[k]) + "' is not a finite number");
    }
    cloud.positions.emplace_back(values[0], values[1], values[2]);
    // The column count decides the layout (docs/formats.md): 6 = normals, 7+ = colours first.
    if (columns == 6) {
      cloud.normals.emplace_back(static_cast<float>(values[3]), static_cast<float>(values[4]),
                                 static_cast<float>(values[5]));
    } else if (columns >= 7) {
      cloud.colors.push_back(
          {color_channel(values[3]), color_channel(values[4]), color_channel(values[5])});
      const std::size_t n0 = columns >= 10 ? 7 : 6;  // x y z r g b [a] nx ny nz
      if (columns >= 9)
        cloud.normals.emplace_back(static_cast<float>(values[n0]),
                                   static_cast<float>(values[n0 + 1]),
                                   static_cast<float>(values[n0 + 2]));
    }
  }
  if (cloud.positions.empty()) throw FileFormatError(source, "no points");
  cloud.width = static_cast<int>(cloud.positions.size());
  return cloud;
}

std::vector<char> lzf_decompress(const char* in, std::size_t in_size, std::size_t expected_size,
                                 const std::filesystem::path& source) {
  std::vector<char> out;
  out.reserve(expected_size);
  const auto fail = [&](const std::string& what) {
    throw FileFormatError(source, "PCD binary_compressed data is corrupt: " + what);
  };
  std::size_t ip = 0;
  while (ip < in_size) {
    const unsigned ctrl = static_cast<unsigned char>(in[ip++]);
    if (ctrl < 32) {  // a run of ctrl + 1 literal bytes
      const std::size_t run = ctrl + 1;
      if (ip + run > in_size) fail("a literal run passes the end of the input");
      if (out.size() + run > expected_size) fail("more bytes than the header declares");
      out.insert(out.end(), in + ip, in + ip + run);
      ip += run;
      continue;
    }
    // A back reference: length (ctrl >> 5) + 2, extended by one byte when it is 7 + 2.
    std::size_t len = ctrl >> 5;
    if (len == 7) {
      if (ip >= in_size) fail("a back reference passes the end of the input");
      len += static_cast<unsigned char>(in[ip++]);
    }
    len += 2;
    if (ip >= in_size) fail("a back reference passes the end of the input");
    const std::size_t back = ((ctrl & 0x1fu) << 8) + static_cast<unsigned char>(in[ip++]) + 1;
    if (back > out.size()) fail("a back reference points before the start of the output");
    if (out.size() + len > expected_size) fail("more bytes than the header declares");
    // Byte by byte: the source may overlap what is being written (runs of a repeated byte).
    for (std::size_t k = 0, from = out.size() - back; k < len; ++k) out.push_back(out[from + k]);
  }
  if (out.size() != expected_size)
    fail(std::to_string(out.size()) + " bytes decoded, the header declares " +
         std::to_string(expected_size));
  return out;
}

namespace {

// The header of a PCD file and where its data starts.
struct PcdHeader {
  std::vector<std::string> fields;
  std::vector<int> sizes, counts;
  std::vector<char> types;
  long long width = -1, height = 1, points = -1;
  std::string data;
  std::size_t data_offset = 0;
  // Per field: byte offset within a point record and first column of an ASCII line.
  std::vector<std::size_t> offset, column;
  std::size_t stride = 0, ncols = 0;

  std::optional<std::size_t> find(std::string_view name) const {
    for (std::size_t f = 0; f < fields.size(); ++f)
      if (fields[f] == name) return f;
    return std::nullopt;
  }
};

PcdHeader parse_pcd_header(const std::string& bytes, const std::filesystem::path& source) {
  PcdHeader h;
  std::size_t pos = 0;
  while (pos < bytes.size() && h.data.empty()) {
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
    if (key == "VERSION" || key == "VIEWPOINT") {
    } else if (key == "FIELDS") {
      while (in >> tok) h.fields.push_back(tok);
    } else if (key == "SIZE") {
      while (in >> tok) h.sizes.push_back(count_word(tok));
    } else if (key == "TYPE") {
      while (in >> tok) h.types.push_back(tok.empty() ? '?' : tok[0]);
    } else if (key == "COUNT") {
      while (in >> tok) h.counts.push_back(count_word(tok));
    } else if (key == "WIDTH") {
      in >> h.width;
    } else if (key == "HEIGHT") {
      in >> h.height;
    } else if (key == "POINTS") {
      in >> h.points;
    } else if (key == "DATA") {
      in >> h.data;
      if (h.data.empty()) throw FileFormatError(source, "PCD DATA line names no encoding");
    } else {
      throw FileFormatError(source, "unknown PCD header line '" + line.substr(0, 40) + "'");
    }
    const bool list_key = key == "VERSION" || key == "VIEWPOINT" || key == "FIELDS" ||
                          key == "SIZE" || key == "TYPE" || key == "COUNT";
    if (in.fail() && !list_key)
      throw FileFormatError(source, "malformed PCD header line '" + line.substr(0, 40) + "'");
  }
  if (h.data.empty()) throw FileFormatError(source, "PCD header has no DATA line");
  if (h.fields.empty()) throw FileFormatError(source, "PCD header has no FIELDS");
  if (h.counts.empty()) h.counts.assign(h.fields.size(), 1);
  if (h.sizes.size() != h.fields.size() || h.types.size() != h.fields.size() ||
      h.counts.size() != h.fields.size())
    throw FileFormatError(source, "PCD FIELDS, SIZE, TYPE and COUNT differ in length");
  // Overflow-safe WIDTH x HEIGHT (hostile headers declare 9e18 x 9e18).
  long long area = 0;
  if (h.width < 0 || h.height < 0 || __builtin_mul_overflow(h.width, h.height, &area))
    throw FileFormatError(source, "PCD WIDTH x HEIGHT is negative or too large");
  if (h.points < 0) h.points = area;
  if (h.points != area) throw FileFormatError(source, "PCD POINTS does not equal WIDTH x HEIGHT");
  if (h.width > std::numeric_limits<int>::max() || h.height > std::numeric_limits<int>::max())
    throw FileFormatError(source, "PCD WIDTH or HEIGHT is too large");
  h.offset.assign(h.fields.size(), 0);
  h.column.assign(h.fields.size(), 0);
  for (std::size_t f = 0; f < h.fields.size(); ++f) {
    if (h.sizes[f] <= 0 || h.counts[f] <= 0)
      throw FileFormatError(source, "PCD SIZE/COUNT not positive");
    h.offset[f] = h.stride;
    h.column[f] = h.ncols;
    h.stride += static_cast<std::size_t>(h.sizes[f]) * h.counts[f];
    h.ncols += h.counts[f];
  }
  for (const char* axis : {"x", "y", "z"}) {
    const auto f = h.find(axis);
    if (!f) throw FileFormatError(source, "PCD has no x, y and z fields");
    if (h.types[*f] != 'F' || (h.sizes[*f] != 4 && h.sizes[*f] != 8))
      throw FileFormatError(source, "PCD x/y/z must be TYPE F with SIZE 4 or 8");
  }
  if (h.data != "ascii" && h.data != "binary" && h.data != "binary_compressed")
    throw FileFormatError(source, "PCD DATA '" + h.data +
                                      "' is not supported (ascii, binary or binary_compressed)");
  h.data_offset = pos;
  return h;
}

// The attribute fields a PCD may carry besides x y z.
struct PcdLayout {
  std::array<std::size_t, 3> xyz{};
  std::optional<std::array<std::size_t, 3>> normal;
  std::optional<std::size_t> rgb;  // packed 0x00RRGGBB in a 4-byte F or U field
};

PcdLayout pcd_layout(const PcdHeader& h) {
  PcdLayout l;
  for (int a = 0; a < 3; ++a) l.xyz[a] = *h.find(std::string(1, "xyz"[a]));
  const auto nx = h.find("normal_x"), ny = h.find("normal_y"), nz = h.find("normal_z");
  if (nx && ny && nz) {
    bool numeric = true;
    for (std::size_t f : {*nx, *ny, *nz}) numeric &= h.types[f] == 'F' && h.sizes[f] == 4;
    if (numeric) l.normal = std::array<std::size_t, 3>{*nx, *ny, *nz};
  }
  auto rgb = h.find("rgb");
  if (!rgb) rgb = h.find("rgba");
  if (rgb && h.sizes[*rgb] == 4 && h.counts[*rgb] == 1) l.rgb = rgb;
  return l;
}

Rgb8 unpack_rgb(std::uint32_t v) {
  return {static_cast<std::uint8_t>((v >> 16) & 0xff), static_cast<std::uint8_t>((v >> 8) & 0xff),
          static_cast<std::uint8_t>(v & 0xff)};
}

double read_float_field(const char* p, int size) {
  if (size == 4) {
    float x;
    std::memcpy(&x, p, 4);
    return x;
  }
  double x;
  std::memcpy(&x, p, 8);
  return x;
}

// Appends one point; the field bytes come from `at(field)` (row or column layout).
template <typename FieldBytes>
void append_binary_point(PointCloud& cloud, const PcdHeader& h, const PcdLayout& l,
                         FieldBytes at) {
  Eigen::Vector3d v;
  for (int a = 0; a < 3; ++a) v[a] = read_float_field(at(l.xyz[a]), h.sizes[l.xyz[a]]);
  cloud.positions.push_back(v);
  if (l.normal) {
    Eigen::Vector3f n;
    for (int a = 0; a < 3; ++a) n[a] = static_cast<float>(read_float_field(at((*l.normal)[a]), 4));
    cloud.normals.push_back(n);
  }
  if (l.rgb) {
    std::uint32_t packed;
    std::memcpy(&packed, at(*l.rgb), 4);
    cloud.colors.push_back(unpack_rgb(packed));
  }
}

void read_pcd_ascii(PointCloud& cloud, const std::string& bytes, const PcdHeader& h,
                    const PcdLayout& l, const std::filesystem::path& source) {
  std::string_view rest(bytes.data() + h.data_offset, bytes.size() - h.data_offset);
  long long read = 0;
  std::size_t p = 0;
  const auto number = [&](std::string_view s, double& out) {
    if (s == "nan" || s == "NaN" || s == "-nan") {
      out = std::nan("");
      return;
    }
    if (!parse_double(s, out))
      throw FileFormatError(source, "PCD point " + std::to_string(read) + ": '" + std::string(s) +
                                        "' is not a number");
  };
  while (p < rest.size() && read < h.points) {
    std::size_t e = rest.find('\n', p);
    if (e == std::string_view::npos) e = rest.size();
    const auto cols = split_fields(rest.substr(p, e - p));
    p = e + 1;
    if (cols.empty()) continue;
    if (cols.size() != h.ncols)
      throw FileFormatError(source, "PCD point " + std::to_string(read) + " has " +
                                        std::to_string(cols.size()) + " values, expected " +
                                        std::to_string(h.ncols));
    Eigen::Vector3d v;
    for (int a = 0; a < 3; ++a) number(cols[h.column[l.xyz[a]]], v[a]);
    cloud.positions.push_back(v);
    if (l.normal) {
      Eigen::Vector3f n;
      for (int a = 0; a < 3; ++a) {
        double c = 0;
        number(cols[h.column[(*l.normal)[a]]], c);
        n[a] = static_cast<float>(c);
      }
      cloud.normals.push_back(n);
    }
    if (l.rgb) {
      double c = 0;
      number(cols[h.column[*l.rgb]], c);
      // A packed F field is printed as the float whose bits are the colour; U as the integer.
      std::uint32_t packed = 0;
      if (h.types[*l.rgb] == 'F')
        packed = std::bit_cast<std::uint32_t>(static_cast<float>(c));
      else if (c >= 0 && c <= 4294967295.0)
        packed = static_cast<std::uint32_t>(c);
      cloud.colors.push_back(unpack_rgb(packed));
    }
    ++read;
  }
  if (read < h.points)
    throw FileFormatError(source, "PCD is truncated: " + std::to_string(read) + " of " +
                                      std::to_string(h.points) + " points");
}

void read_pcd_binary(PointCloud& cloud, const std::string& bytes, const PcdHeader& h,
                     const PcdLayout& l, const std::filesystem::path& source) {
  const std::size_t remaining = bytes.size() - h.data_offset;
  if (static_cast<unsigned long long>(h.points) > remaining / h.stride)
    throw FileFormatError(source, "PCD binary data is truncated: " + std::to_string(h.points) +
                                      " points of " + std::to_string(h.stride) +
                                      " bytes declared, " + std::to_string(remaining) +
                                      " bytes present");
  for (long long i = 0; i < h.points; ++i) {
    const char* rec = bytes.data() + h.data_offset + static_cast<std::size_t>(i) * h.stride;
    append_binary_point(cloud, h, l, [&](std::size_t f) { return rec + h.offset[f]; });
  }
}

// binary_compressed: two uint32 (compressed and uncompressed size), then LZF data that holds
// each field for all points in turn (column by column).
void read_pcd_compressed(PointCloud& cloud, const std::string& bytes, const PcdHeader& h,
                         const PcdLayout& l, const std::filesystem::path& source) {
  const std::size_t remaining = bytes.size() - h.data_offset;
  if (remaining < 8) throw FileFormatError(source, "PCD binary_compressed data has no sizes");
  std::uint32_t compressed = 0, uncompressed = 0;
  std::memcpy(&compressed, bytes.data() + h.data_offset, 4);
  std::memcpy(&uncompressed, bytes.data() + h.data_offset + 4, 4);
  if (compressed > remaining - 8)
    throw FileFormatError(source, "PCD binary_compressed data is truncated: " +
                                      std::to_string(compressed) + " bytes declared, " +
                                      std::to_string(remaining - 8) + " present");
  unsigned long long expected = 0;
  if (__builtin_mul_overflow(static_cast<unsigned long long>(h.points),
                             static_cast<unsigned long long>(h.stride), &expected) ||
      expected != uncompressed)
    throw FileFormatError(source, "PCD binary_compressed size " + std::to_string(uncompressed) +
                                      " does not equal POINTS x point size");
  // LZF expands at most ~ 264x (a 3-byte back reference emits up to 264 bytes): a bound that
  // refuses allocation bombs before the output is reserved.
  if (uncompressed > 264ull * compressed + 32)
    throw FileFormatError(source, "PCD binary_compressed declares more data than " +
                                      std::to_string(compressed) + " bytes can hold");
  const std::vector<char> raw =
      lzf_decompress(bytes.data() + h.data_offset + 8, compressed, uncompressed, source);
  std::vector<std::size_t> column_start(h.fields.size(), 0);
  for (std::size_t f = 0, at = 0; f < h.fields.size(); ++f) {
    column_start[f] = at;
    at += static_cast<std::size_t>(h.points) * h.sizes[f] * h.counts[f];
  }
  for (long long i = 0; i < h.points; ++i)
    append_binary_point(cloud, h, l, [&](std::size_t f) {
      return raw.data() + column_start[f] +
             static_cast<std::size_t>(i) * h.sizes[f] * h.counts[f];
    });
}

}  // namespace

PointCloud parse_pcd(const std::string& bytes, const std::filesystem::path& source) {
  const PcdHeader h = parse_pcd_header(bytes, source);
  const PcdLayout layout = pcd_layout(h);
  // The declared point count is checked against the bytes that follow the header before anything
  // is reserved: an ASCII point takes at least one character per value (plus separators), a
  // binary point exactly `stride` bytes (compressed data is checked by its own sizes).
  const std::size_t remaining = bytes.size() - h.data_offset;
  if (h.data != "binary_compressed") {
    const std::size_t min_point_bytes = h.data == "binary" ? h.stride : 2 * h.ncols - 1;
    if (static_cast<unsigned long long>(h.points) > remaining / min_point_bytes + 1)
      throw FileFormatError(source, "PCD declares " + std::to_string(h.points) +
                                        " points but only " + std::to_string(remaining) +
                                        " bytes of data follow");
  }
  PointCloud cloud;
  if (h.data == "ascii")
    read_pcd_ascii(cloud, bytes, h, layout, source);
  else if (h.data == "binary")
    read_pcd_binary(cloud, bytes, h, layout, source);
  else
    read_pcd_compressed(cloud, bytes, h, layout, source);
  if (h.height > 1) {
    cloud.width = static_cast<int>(h.width);
    cloud.height = static_cast<int>(h.height);
    if (cloud.finite_count() == 0) throw FileFormatError(source, "PCD has no finite point");
    return cloud;
  }
  cloud = cloud.finite_points();
  if (cloud.positions.empty()) throw FileFormatError(source, "PCD has no finite point");
  return cloud;
}

PointCloud read_point_cloud(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".ply") {
    Mesh m = read_ply(path);
    if (m.positions.empty()) throw FileFormatError(path, "PLY has no vertices");
    PointCloud cloud;
    cloud.positions = std::move(m.positions);
    cloud.normals = std::move(m.normals);
    cloud.colors = std::move(m.colors);
    cloud.width = static_cast<int>(cloud.positions.size());
    return cloud;
  }
  if (ext == ".smg") {
    const RangeGrid g = read_grid(path);
    PointCloud cloud;
    for (int j = 0; j < g.n_h(); ++j)
      for (int i = 0; i < g.n_phi(); ++i)
        if (g.valid(i, j)) {
          cloud.positions.push_back(g.cartesian(i, j));
          cloud.colors.push_back(g.color(i, j));
        }
    if (cloud.positions.empty()) throw FileFormatError(path, "grid has no valid cell");
    cloud.width = static_cast<int>(cloud.positions.size());
    return cloud;
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
