// Native range grid file (.smg), version 1. Byte layout, version policy and the list of what the
// reader rejects: docs/formats.md, "Native range grid file (.smg)".
//
// All numbers are little-endian (core/binary_io.h).
#include "scanmesh/core/grid_file.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/binary_io.h"
#include "scanmesh/core/errors.h"

namespace scanmesh {

namespace {

// A length for a message: "%g", never std::to_string's 309 digits of 1e308.
// "SCANMESHGRID" then CR LF SUB LF (the PNG trick): a text-mode transfer that rewrites line ends
// or stops at ^Z mangles these four bytes and the magic check fails straight away.
constexpr std::array<std::uint8_t, 16> kMagic = {'S', 'C', 'A', 'N', 'M',  'E',  'S',  'H',
                                                 'G', 'R', 'I', 'D', '\r', '\n', 0x1a, '\n'};
// magic(16) version(4) header_length(4) n_phi(4) n_h(4) phi0(8) h0(8) dh(8) metadata_count(4)
constexpr std::size_t kFixedHeaderBytes = 60;
constexpr std::size_t kCrcBytes = 4;
// radius f32 + valid u8 + confidence f32 + rgb 3 x u8
constexpr std::uint64_t kBytesPerCell = 12;

std::string cell_name(std::size_t k, std::uint32_t n_phi) {
  return "cell (" + std::to_string(k % n_phi) + ", " + std::to_string(k / n_phi) + ")";
}

}  // namespace

std::vector<std::uint8_t> encode_grid(const RangeGrid& grid) {
  std::uint64_t metadata_bytes = 0;
  for (const auto& [key, value] : grid.metadata) metadata_bytes += 8 + key.size() + value.size();
  const std::uint64_t header_length = kFixedHeaderBytes + metadata_bytes;
  if (header_length > 0xffffffffu || grid.metadata.size() > 0xffffffffu)
    throw InvalidInputError("range grid metadata is too large for a grid file (" +
                            std::to_string(metadata_bytes) + " bytes)");
  const std::size_t n = grid.cell_count();

  std::vector<std::uint8_t> out;
  out.reserve(header_length + kBytesPerCell * n + kCrcBytes);
  ByteWriter w(out);
  w.bytes(kMagic.data(), kMagic.size());
  w.u32(kGridFileVersion);
  w.u32(static_cast<std::uint32_t>(header_length));
  w.u32(static_cast<std::uint32_t>(grid.n_phi()));
  w.u32(static_cast<std::uint32_t>(grid.n_h()));
  w.f64(grid.phi0());
  w.f64(grid.h0());
  w.f64(grid.dh());
  w.u32(static_cast<std::uint32_t>(grid.metadata.size()));
  for (const auto& [key, value] : grid.metadata) {
    w.u32(static_cast<std::uint32_t>(key.size()));
    w.bytes(key.data(), key.size());
    w.u32(static_cast<std::uint32_t>(value.size()));
    w.bytes(value.data(), value.size());
  }
  for (float r : grid.radii()) w.f32(r);
  w.bytes(grid.validity().data(), n);
  for (float c : grid.confidences()) w.f32(c);
  for (const Rgb8& c : grid.colors()) {
    w.u8(c.r);
    w.u8(c.g);
    w.u8(c.b);
  }
  w.u32(crc32_of(out.data(), out.size()));
  return out;
}

RangeGrid decode_grid(std::span<const std::uint8_t> bytes, const std::filesystem::path& source) {
  const auto fail = [&](const std::string& problem) { throw FileFormatError(source, problem); };
  const std::uint8_t* p = bytes.data();
  const std::size_t size = bytes.size();

  // 1. Magic (a short file that starts like a grid file is "truncated", anything else is "not").
  if (size == 0) fail("truncated: the file is empty");
  const std::size_t magic_seen = std::min(size, kMagic.size());
  if (std::memcmp(p, kMagic.data(), magic_seen) != 0)
    fail("not a scanmesh grid file (bad magic; expected \"SCANMESHGRID\\r\\n\\x1a\\n\")");
  if (size < kFixedHeaderBytes + kCrcBytes)
    fail("truncated: file has " + std::to_string(size) + " bytes, a grid file has at least " +
         std::to_string(kFixedHeaderBytes + kCrcBytes));

  // 2. Version before anything else: a later version may lay out the rest differently.
  const std::uint32_t version = read_le_u32(p + 16);
  if (version != kGridFileVersion)
    fail("version " + std::to_string(version) + " not supported; this build reads version " +
         std::to_string(kGridFileVersion));

  // 3. Sizes, checked against the limit and the actual byte count before anything is allocated.
  const std::uint32_t header_length = read_le_u32(p + 20);
  const std::uint32_t n_phi = read_le_u32(p + 24);
  const std::uint32_t n_h = read_le_u32(p + 28);
  if (n_phi < 2 || n_h < 2)
    fail("grid size " + std::to_string(n_phi) + " x " + std::to_string(n_h) +
         " is impossible (at least 2 x 2)");
  const std::uint64_t cells = static_cast<std::uint64_t>(n_phi) * n_h;
  require_cell_limit(n_phi, n_h, kMaxGridCells, source);
  if (header_length < kFixedHeaderBytes)
    fail("header length " + std::to_string(header_length) + " is shorter than the fixed header (" +
         std::to_string(kFixedHeaderBytes) + " bytes)");
  const std::uint64_t expected = header_length + kBytesPerCell * cells + kCrcBytes;
  require_file_size(expected, size, source);

  // 4. Checksum over everything before it.
  require_trailing_crc32(bytes, source);

  // 5. Geometry.
  const double phi0 = read_le_f64(p + 32), h0 = read_le_f64(p + 40), dh = read_le_f64(p + 48);
  if (!std::isfinite(phi0) || !std::isfinite(h0)) fail("phi0/h0 are not finite");
  if (!std::isfinite(dh) || !(dh > 0.0))
    fail("height step dh = " + format_number(dh) + " is not positive");
  if (dh < kMinGridLengthMm)
    fail("height step dh = " + format_number(dh) + " mm is below 1e-9 mm: not a scan");
  if (std::abs(h0) > kMaxGridLengthMm || std::abs(h0 + dh * n_h) > kMaxGridLengthMm)
    fail("rows span heights beyond 1e6 mm (h0 " + format_number(h0) + " mm, dh " +
         format_number(dh) + " mm): not a scan");

  // 6. Metadata, every length checked against the end of the header.
  std::map<std::string, std::string> metadata;
  const std::uint32_t metadata_count = read_le_u32(p + 56);
  std::size_t pos = kFixedHeaderBytes;
  const auto read_string = [&](std::uint32_t entry, const char* what) {
    if (header_length - pos < 4)
      fail("metadata entry " + std::to_string(entry) + ": " + what +
           " length runs past the header");
    const std::uint32_t len = read_le_u32(p + pos);
    pos += 4;
    if (len > header_length - pos)
      fail("metadata entry " + std::to_string(entry) + ": " + what + " of " + std::to_string(len) +
           " bytes runs past the header (" + std::to_string(header_length) + " bytes)");
    std::string s(reinterpret_cast<const char*>(p + pos), len);
    pos += len;
    return s;
  };
  for (std::uint32_t e = 0; e < metadata_count; ++e) {
    std::string key = read_string(e, "key");
    std::string value = read_string(e, "value");
    if (!metadata.emplace(std::move(key), std::move(value)).second)
      fail("metadata entry " + std::to_string(e) + ": duplicate key");
  }
  if (pos != header_length)
    fail("header length field says " + std::to_string(header_length) +
         " bytes but the header ends at " + std::to_string(pos));

  // 7. Planes: check every cell before building the grid.
  const std::size_t n = static_cast<std::size_t>(cells);
  const std::uint8_t* radius_plane = p + header_length;
  const std::uint8_t* valid_plane = radius_plane + 4 * n;
  const std::uint8_t* confidence_plane = valid_plane + n;
  const std::uint8_t* rgb_plane = confidence_plane + 4 * n;
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint8_t v = valid_plane[k];
    const float r = read_le_f32(radius_plane + 4 * k);
    const float c = read_le_f32(confidence_plane + 4 * k);
    if (v > 1)
      fail(cell_name(k, n_phi) + ": validity byte " + std::to_string(v) + " is not 0 or 1");
    if (v == 1 && (!std::isfinite(r) || !(r >= kMinGridLengthMm) || r > kMaxGridLengthMm))
      fail(cell_name(k, n_phi) + ": valid cell has radius " + format_number(r) +
           " (must be finite, at least 1e-9 and at most 1e6 mm)");
    if (v == 0 && r != 0.0f)
      fail(cell_name(k, n_phi) + ": invalid cell has radius " + std::to_string(r) + " (must be 0)");
    if (!std::isfinite(c) || c < 0.0f || c > 1.0f)
      fail(cell_name(k, n_phi) + ": confidence " + std::to_string(c) + " is outside [0, 1]");
  }

  RangeGrid grid(static_cast<int>(n_phi), static_cast<int>(n_h), phi0, h0, dh);
  grid.metadata = std::move(metadata);
  auto& radii = grid.radii();
  auto& validity = grid.validity();
  auto& confidences = grid.confidences();
  auto& colors = grid.colors();
  for (std::size_t k = 0; k < n; ++k) {
    radii[k] = read_le_f32(radius_plane + 4 * k);
    confidences[k] = read_le_f32(confidence_plane + 4 * k);
    colors[k] = Rgb8{rgb_plane[3 * k], rgb_plane[3 * k + 1], rgb_plane[3 * k + 2]};
  }
  std::memcpy(validity.data(), valid_plane, n);
  return grid;
}

void write_grid(const std::filesystem::path& path, const RangeGrid& grid) {
  const std::vector<std::uint8_t> bytes = encode_grid(grid);
  write_file_atomically(path, std::span<const std::uint8_t>(bytes));
}

RangeGrid read_grid(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(path);
  return decode_grid(bytes, path);
}

bool looks_like_grid_file(const std::filesystem::path& path) {
  // Only a regular file is opened: a FIFO would block the open until a writer came (`info` on a
  // FIFO hung); the readers then refuse anything else with a message.
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  std::ifstream in(path, std::ios::binary);
  std::array<char, kMagic.size()> head{};
  if (!in.read(head.data(), head.size())) return false;
  return std::memcmp(head.data(), kMagic.data(), kMagic.size()) == 0;
}

}  // namespace scanmesh
