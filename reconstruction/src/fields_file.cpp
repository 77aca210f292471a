// Surface fields file (.smf), version 1. Byte layout and the list of what the reader rejects:
// docs/formats.md, "Surface fields file (.smf)". Numbers little-endian (core/binary_io.h).
#include "scanmesh/reconstruction/fields_file.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <span>
#include <string>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/binary_io.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_file.h"

namespace scanmesh {

namespace {

// "SCANMESHFLDS" then CR LF SUB LF, the same text-mode tripwire as the grid file's magic.
constexpr std::array<std::uint8_t, 16> kMagic = {'S', 'C', 'A', 'N', 'M',  'E',  'S',  'H',
                                                 'F', 'L', 'D', 'S', '\r', '\n', 0x1a, '\n'};
constexpr std::uint32_t kVersion = 1;
// magic(16) version(4) n_phi(4) n_h(4) method(4) radius_mm(8)
constexpr std::size_t kHeaderBytes = 40;
constexpr std::size_t kCrcBytes = 4;
// defined u8 + normal 3 f32 + k1 f32 + k2 f32 + dir1 3 f32 + dir2 3 f32
constexpr std::uint64_t kBytesPerCell = 1 + 12 + 4 + 4 + 12 + 12;

std::uint32_t method_code(CurvatureMethod m) {
  switch (m) {
    case CurvatureMethod::Analytic:
      return 0;
    case CurvatureMethod::Quadric:
      return 1;
    case CurvatureMethod::Seed000:
      return 2;
    case CurvatureMethod::GridQuadric:
      return 3;
  }
  throw InvalidInputError("unknown curvature method");
}

std::string cell_name(std::size_t k, std::uint32_t n_phi) {
  return "cell (" + std::to_string(k % n_phi) + ", " + std::to_string(k / n_phi) + ")";
}

bool finite3(const Eigen::Vector3f& v) { return v.allFinite(); }

std::vector<std::uint8_t> encode_fields(const SurfaceFields& f) {
  const std::size_t n = f.size();
  if (f.n_phi < 1 || f.n_h < 1 || static_cast<std::uint64_t>(f.n_phi) * f.n_h != n ||
      f.normal.size() != n || f.k1.size() != n || f.k2.size() != n || f.dir1.size() != n ||
      f.dir2.size() != n)
    throw InvalidInputError("surface fields " + std::to_string(f.n_phi) + " x " +
                            std::to_string(f.n_h) + " have inconsistent plane sizes");
  if (!std::isfinite(f.radius_mm) || f.radius_mm < 0)
    throw InvalidInputError("surface fields: radius_mm " + std::to_string(f.radius_mm) +
                            " is not finite and >= 0");
  for (std::size_t k = 0; k < n; ++k)
    if (f.defined[k] && (!finite3(f.normal[k]) || !std::isfinite(f.k1[k]) ||
                         !std::isfinite(f.k2[k]) || !finite3(f.dir1[k]) || !finite3(f.dir2[k])))
      throw InvalidInputError(
          "surface fields: " + cell_name(k, static_cast<std::uint32_t>(f.n_phi)) +
          " holds a non-finite value");

  std::vector<std::uint8_t> out;
  out.reserve(kHeaderBytes + kBytesPerCell * n + kCrcBytes);
  ByteWriter w(out);
  // Byte by byte: GCC 12 misreads vector::insert right after reserve as an overflow.
  for (const std::uint8_t b : kMagic) w.u8(b);
  w.u32(kVersion);
  w.u32(static_cast<std::uint32_t>(f.n_phi));
  w.u32(static_cast<std::uint32_t>(f.n_h));
  w.u32(method_code(f.method));
  w.f64(f.radius_mm);
  // Undefined cells are written as 0 whatever the planes hold (the header's rule), so the
  // reader can insist on it.
  const auto vec3 = [&](const std::vector<Eigen::Vector3f>& plane) {
    for (std::size_t k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c) w.f32(f.defined[k] ? plane[k][c] : 0.0f);
  };
  const auto scalar = [&](const std::vector<float>& plane) {
    for (std::size_t k = 0; k < n; ++k) w.f32(f.defined[k] ? plane[k] : 0.0f);
  };
  for (std::size_t k = 0; k < n; ++k) w.u8(f.defined[k] ? 1 : 0);
  vec3(f.normal);
  scalar(f.k1);
  scalar(f.k2);
  vec3(f.dir1);
  vec3(f.dir2);
  w.u32(crc32_of(out.data(), out.size()));
  return out;
}

}  // namespace

SurfaceFields decode_fields(std::span<const std::uint8_t> bytes,
                            const std::filesystem::path& source) {
  const auto fail = [&](const std::string& problem) { throw FileFormatError(source, problem); };
  const std::uint8_t* p = bytes.data();
  const std::size_t size = bytes.size();

  // 1. Magic: a short file that starts like a fields file is "truncated", anything else "not".
  if (size == 0) fail("truncated: the file is empty");
  if (std::memcmp(p, kMagic.data(), std::min(size, kMagic.size())) != 0)
    fail("not a scanmesh surface fields file (bad magic; expected \"SCANMESHFLDS\\r\\n\\x1a\\n\")");
  if (size < kHeaderBytes + kCrcBytes)
    fail("truncated: file has " + std::to_string(size) + " bytes, a fields file has at least " +
         std::to_string(kHeaderBytes + kCrcBytes));

  // 2. Version before anything else: a later version may lay out the rest differently.
  const std::uint32_t version = read_le_u32(p + 16);
  if (version != kVersion)
    fail("version " + std::to_string(version) + " not supported; this build reads version " +
         std::to_string(kVersion));

  // 3. Sizes against the limit and the byte count, before anything is allocated.
  const std::uint32_t n_phi = read_le_u32(p + 20), n_h = read_le_u32(p + 24);
  if (n_phi < 1 || n_h < 1)
    fail("grid size " + std::to_string(n_phi) + " x " + std::to_string(n_h) + " is impossible");
  const std::uint64_t cells = static_cast<std::uint64_t>(n_phi) * n_h;
  require_cell_limit(n_phi, n_h, kMaxGridCells, source);
  const std::uint64_t expected = kHeaderBytes + kBytesPerCell * cells + kCrcBytes;
  require_file_size(expected, size, source);

  // 4. Checksum over everything before it.
  require_trailing_crc32(bytes, source);

  // 5. Header values.
  const std::uint32_t method = read_le_u32(p + 28);
  if (method > 3) fail("curvature method " + std::to_string(method) + " is unknown (0 to 3)");
  const double radius_mm = read_le_f64(p + 32);
  if (!std::isfinite(radius_mm) || radius_mm < 0)
    fail("radius_mm " + std::to_string(radius_mm) + " is not finite and >= 0");

  // 6. Planes: every cell checked before the result is built.
  const std::size_t n = static_cast<std::size_t>(cells);
  const std::uint8_t* defined_plane = p + kHeaderBytes;
  const std::uint8_t* normal_plane = defined_plane + n;
  const std::uint8_t* k1_plane = normal_plane + 12 * n;
  const std::uint8_t* k2_plane = k1_plane + 4 * n;
  const std::uint8_t* dir1_plane = k2_plane + 4 * n;
  const std::uint8_t* dir2_plane = dir1_plane + 12 * n;
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint8_t d = defined_plane[k];
    if (d > 1) fail(cell_name(k, n_phi) + ": defined byte " + std::to_string(d) + " is not 0 or 1");
    const auto check = [&](const char* what, const std::uint8_t* plane, int components) {
      for (int c = 0; c < components; ++c) {
        const float v = read_le_f32(plane + 4 * (components * k + c));
        if (!std::isfinite(v)) fail(cell_name(k, n_phi) + ": " + what + " is not finite");
        if (d == 0 && v != 0.0f)
          fail(cell_name(k, n_phi) + ": undefined cell has " + what + " " + std::to_string(v) +
               " (must be 0)");
      }
    };
    check("normal", normal_plane, 3);
    check("k1", k1_plane, 1);
    check("k2", k2_plane, 1);
    check("dir1", dir1_plane, 3);
    check("dir2", dir2_plane, 3);
  }

  SurfaceFields f;
  f.resize(static_cast<int>(n_phi), static_cast<int>(n_h));
  f.method = method == 0   ? CurvatureMethod::Analytic
             : method == 1 ? CurvatureMethod::Quadric
             : method == 2 ? CurvatureMethod::Seed000
                           : CurvatureMethod::GridQuadric;
  f.radius_mm = radius_mm;
  const auto vec3 = [](const std::uint8_t* plane, std::size_t k) {
    return Eigen::Vector3f(read_le_f32(plane + 12 * k), read_le_f32(plane + 12 * k + 4),
                           read_le_f32(plane + 12 * k + 8));
  };
  for (std::size_t k = 0; k < n; ++k) {
    f.defined[k] = defined_plane[k];
    f.normal[k] = vec3(normal_plane, k);
    f.k1[k] = read_le_f32(k1_plane + 4 * k);
    f.k2[k] = read_le_f32(k2_plane + 4 * k);
    f.dir1[k] = vec3(dir1_plane, k);
    f.dir2[k] = vec3(dir2_plane, k);
  }
  return f;
}

void write_fields(const std::filesystem::path& path, const SurfaceFields& fields) {
  const std::vector<std::uint8_t> bytes = encode_fields(fields);
  write_file_atomically(path, std::span<const std::uint8_t>(bytes));
}

SurfaceFields read_fields(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(path);
  return decode_fields(bytes, path);
}

}  // namespace scanmesh
