// The native range grid file (.smg): versioned, little-endian, CRC-32 checked, lossless.
// Layout in docs/formats.md, "Native range grid file".
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "scanmesh/core/range_grid.h"

namespace scanmesh {

inline constexpr std::uint32_t kGridFileVersion = 1;
//! Largest grid a reader accepts (cells); protects against allocation bombs in hostile files.
inline constexpr std::uint64_t kMaxGridCells = 1ull << 26;
//! Largest length a grid may hold (mm: |h0|, the top row's height, dh, a radius): 1 km. Beyond it
//! a file is not a scan, and coordinates that large break every spacing-based grid downstream.
inline constexpr double kMaxGridLengthMm = 1e6;
//! Smallest dh and valid radius a grid may hold (mm): 1 picometre. Below it the cells of every
//! column crowd one point of the axis (radii of 1e-30 made the fans and curvature run for
//! seconds to produce nothing).
inline constexpr double kMinGridLengthMm = 1e-9;

//! Serialises every field of the grid (sizes, phi0, h0, dh, radius, validity, confidence,
//! colour, metadata) and appends a CRC-32 of all preceding bytes.
std::vector<std::uint8_t> encode_grid(const RangeGrid& grid);
//! Parses bytes from encode_grid. Throws FileFormatError (naming `source`) for a wrong magic,
//! unknown version, truncation, checksum mismatch, impossible sizes or inconsistent planes.
RangeGrid decode_grid(std::span<const std::uint8_t> bytes, const std::filesystem::path& source);

void write_grid(const std::filesystem::path& path, const RangeGrid& grid);  // atomic
RangeGrid read_grid(const std::filesystem::path& path);

//! True if the file starts with the native grid magic (used by `scanmesh info`).
bool looks_like_grid_file(const std::filesystem::path& path);

}  // namespace scanmesh
