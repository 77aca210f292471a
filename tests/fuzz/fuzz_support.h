// Helpers shared by the fuzz entry points (tests/fuzz/fuzz_*.cpp). Header-only (inline), so every
// entry file still links on its own and all of them link together into test_fuzz_inputs.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "scanmesh/core/binary_io.h"

namespace scanmesh::fuzz {

//! The bytes with their last four replaced by the CRC-32 of the rest, as the binary formats
//! store it. Random bytes almost never carry a valid checksum, so without this copy the fuzzer
//! would hardly get past the checksum to the checks behind it.
inline std::vector<std::uint8_t> with_valid_crc(std::span<const std::uint8_t> bytes) {
  std::vector<std::uint8_t> out(bytes.begin(), bytes.end());
  if (out.size() < 4) return out;
  const std::uint32_t crc = crc32_of(out.data(), out.size() - 4);
  for (int k = 0; k < 4; ++k) out[out.size() - 4 + k] = static_cast<std::uint8_t>(crc >> (8 * k));
  return out;
}

inline std::string as_text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

//! A property the parser promised does not hold: abort, so the fuzzer records the input.
[[noreturn]] inline void broken_promise() { std::abort(); }

//! For readers that only take a path: writes the bytes to a per-process scratch file with the
//! given extension and returns its path (the same path on every call of the process).
inline std::filesystem::path scratch_file(const std::uint8_t* data, std::size_t size,
                                          const std::string& extension) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                     ("scanmesh_fuzz_" + std::to_string(::getpid()) + extension);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  if (std::fclose(f) != 0) std::abort();
  return path;
}

}  // namespace scanmesh::fuzz
