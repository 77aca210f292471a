#include <gtest/gtest.h>
#include <zlib.h>

#include <atomic>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/grid_file.h"
#include "test_util.h"

// Largest single allocation since the last reset, to show that hostile headers are rejected
// before anything is allocated for them. Replacing the global operator new is allowed by the
// standard; this replacement only adds the bookkeeping.
namespace {
std::atomic<std::size_t> g_largest_allocation{0};
}
void* operator new(std::size_t n) {
  std::size_t seen = g_largest_allocation.load(std::memory_order_relaxed);
  while (n > seen && !g_largest_allocation.compare_exchange_weak(seen, n)) {
  }
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace scanmesh {
namespace {

using test::TempDir;
using test::write_raw;

RangeGrid random_grid(int n_phi, int n_h, unsigned seed) {
  RangeGrid g(n_phi, n_h, -0.3, -123.456, 0.37);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> radius(20.0f, 400.0f), unit(0.0f, 1.0f);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int j = 0; j < n_h; ++j)
    for (int i = 0; i < n_phi; ++i) {
      if (unit(rng) < 0.7f) g.set_sample(i, j, radius(rng), unit(rng));
      g.set_color(i, j,
                  {static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng)),
                   static_cast<std::uint8_t>(byte(rng))});
    }
  g.metadata["source"] = "sim";
  g.metadata["scene"] = "bust \xc3\xa9t\xc3\xa9";  // UTF-8
  g.metadata["empty"] = "";
  g.metadata["binary"] = std::string("a\0b\xff\n", 5);
  return g;
}

std::uint32_t crc_of(const std::vector<std::uint8_t>& b, std::size_t n) {
  return static_cast<std::uint32_t>(crc32(0L, b.data(), static_cast<uInt>(n)));
}
// Re-seals a patched file with a correct CRC, so the test reaches the check behind it.
void reseal(std::vector<std::uint8_t>& b) {
  const std::uint32_t crc = crc_of(b, b.size() - 4);
  for (int k = 0; k < 4; ++k) b[b.size() - 4 + k] = static_cast<std::uint8_t>(crc >> (8 * k));
}
void put_u32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) b[at + k] = static_cast<std::uint8_t>(v >> (8 * k));
}
void put_f32(std::vector<std::uint8_t>& b, std::size_t at, float v) {
  put_u32(b, at, std::bit_cast<std::uint32_t>(v));
}
void put_f64(std::vector<std::uint8_t>& b, std::size_t at, double v) {
  const auto u = std::bit_cast<std::uint64_t>(v);
  for (int k = 0; k < 8; ++k) b[at + k] = static_cast<std::uint8_t>(u >> (8 * k));
}
std::uint32_t get_u32(const std::vector<std::uint8_t>& b, std::size_t at) {
  std::uint32_t v = 0;
  for (int k = 0; k < 4; ++k) v |= static_cast<std::uint32_t>(b[at + k]) << (8 * k);
  return v;
}

// Reads `bytes` from a file called `name` and returns the FileFormatError message ("" if none).
std::string rejection(const TempDir& dir, const std::string& name,
                      const std::vector<std::uint8_t>& bytes) {
  write_raw(dir / name, bytes);
  try {
    read_grid(dir / name);
  } catch (const FileFormatError& e) {
    EXPECT_EQ(e.file(), dir / name);
    return e.what();
  }
  return "";
}

TEST(GridFile, RoundTripIsLosslessFor512x512) {
  TempDir dir;
  const RangeGrid grid = random_grid(512, 512, 1);
  write_grid(dir / "scan.smg", grid);
  EXPECT_EQ(std::filesystem::file_size(dir / "scan.smg"), encode_grid(grid).size());
  const RangeGrid back = read_grid(dir / "scan.smg");
  EXPECT_TRUE(back == grid);
  EXPECT_EQ(back.metadata, grid.metadata);
  EXPECT_EQ(back.valid_count(), grid.valid_count());
  EXPECT_EQ(back.phi0(), -0.3);
  EXPECT_EQ(back.h0(), -123.456);
  EXPECT_EQ(back.dh(), 0.37);
  EXPECT_TRUE(looks_like_grid_file(dir / "scan.smg"));
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"scan.smg"});
}

TEST(GridFile, LayoutMatchesTheDocumentedOffsets) {
  RangeGrid grid(4, 3, 0.0, 0.0, 1.0);
  grid.set_sample(1, 2, 7.5f, 0.5f);
  const std::vector<std::uint8_t> b = encode_grid(grid);
  // 60-byte fixed header, no metadata, 12 bytes per cell, CRC-32.
  ASSERT_EQ(b.size(), 60u + 12u * 12u + 4u);
  EXPECT_EQ(std::string(b.begin(), b.begin() + 12), "SCANMESHGRID");
  EXPECT_EQ(get_u32(b, 16), 1u);
  EXPECT_EQ(get_u32(b, 20), 60u);
  EXPECT_EQ(get_u32(b, 24), 4u);
  EXPECT_EQ(get_u32(b, 28), 3u);
  EXPECT_EQ(get_u32(b, 56), 0u);
  const std::size_t k = grid.index(1, 2);
  EXPECT_EQ(std::bit_cast<float>(get_u32(b, 60 + 4 * k)), 7.5f);
  EXPECT_EQ(b[60 + 48 + k], 1);
  EXPECT_EQ(std::bit_cast<float>(get_u32(b, 60 + 48 + 12 + 4 * k)), 0.5f);
  EXPECT_EQ(get_u32(b, b.size() - 4), crc_of(b, b.size() - 4));
}

TEST(GridFile, TruncatedFileIsRejectedAtTwentyCuts) {
  TempDir dir;
  const std::vector<std::uint8_t> good = encode_grid(random_grid(40, 30, 2));
  const std::size_t header = get_u32(good, 20);
  std::vector<std::size_t> cuts = {0,  1,  12, 16,         19,     24,
                                   40, 59, 60, header - 1, header, header + 1};
  for (int k = 1; k <= 7; ++k) cuts.push_back(header + (good.size() - header) * k / 8);
  cuts.push_back(good.size() - 1);
  ASSERT_EQ(cuts.size(), 20u);
  for (std::size_t cut : cuts) {
    const std::vector<std::uint8_t> bytes(good.begin(), good.begin() + static_cast<long>(cut));
    const std::string m = rejection(dir, "cut.smg", bytes);
    EXPECT_NE(m.find("cut.smg"), std::string::npos) << "cut at " << cut << ": '" << m << "'";
    EXPECT_NE(m.find("truncated"), std::string::npos) << "cut at " << cut << ": '" << m << "'";
  }
}

TEST(GridFile, FlippedByteIsRejectedAtTwentyPositions) {
  TempDir dir;
  const std::vector<std::uint8_t> good = encode_grid(random_grid(40, 30, 3));
  for (int k = 0; k < 20; ++k) {
    const std::size_t at = (good.size() - 1) * k / 19;
    std::vector<std::uint8_t> bad = good;
    bad[at] ^= 0x10;
    const std::string m = rejection(dir, "flip.smg", bad);
    EXPECT_NE(m.find("flip.smg"), std::string::npos) << "byte " << at << ": '" << m << "'";
    // Past the sizes (offset 32), only the checksum can tell.
    if (at >= 32) {
      EXPECT_NE(m.find("checksum mismatch"), std::string::npos)
          << "byte " << at << ": '" << m << "'";
    }
  }
}

TEST(GridFile, HugeDeclaredSizesAreRejectedWithoutAllocating) {
  TempDir dir;
  std::vector<std::uint8_t> b = encode_grid(RangeGrid(2, 2));
  b.resize(64);  // header and CRC only: what a hostile file would send
  struct Case {
    std::uint32_t n_phi, n_h, header_length, metadata_count;
    const char* expected;
  };
  const Case cases[] = {
      {0xffffffffu, 0xffffffffu, 60, 0, "exceeds the limit"},
      {1u << 14, 1u << 13, 60, 0, "exceeds the limit"},
      {1u << 13, 1u << 13, 60, 0, "truncated: expected 805306432 bytes, file has 64"},
      {2, 2, 0xfffffff0u, 0, "truncated"},
  };
  for (const Case& c : cases) {
    put_u32(b, 24, c.n_phi);
    put_u32(b, 28, c.n_h);
    put_u32(b, 20, c.header_length);
    put_u32(b, 56, c.metadata_count);
    write_raw(dir / "huge.smg", b);
    const std::vector<std::uint8_t> bytes = read_file_bytes(dir / "huge.smg");
    g_largest_allocation = 0;
    try {
      decode_grid(bytes, dir / "huge.smg");
      ADD_FAILURE() << "accepted " << c.n_phi << " x " << c.n_h;
    } catch (const FileFormatError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << e.what();
    }
    EXPECT_LT(g_largest_allocation.load(), 4096u) << c.n_phi << " x " << c.n_h;
  }

  // A metadata count of 4 billion in a well-formed, correctly sealed 2 x 2 file.
  std::vector<std::uint8_t> m = encode_grid(RangeGrid(2, 2));
  put_u32(m, 56, 0xffffffffu);
  reseal(m);
  g_largest_allocation = 0;
  try {
    decode_grid(m, "meta.smg");
    ADD_FAILURE() << "accepted a metadata count of 2^32-1";
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("runs past the header"), std::string::npos) << e.what();
  }
  EXPECT_LT(g_largest_allocation.load(), 4096u);
}

TEST(GridFile, WrongVersionIsRejectedNamingBothVersions) {
  TempDir dir;
  std::vector<std::uint8_t> b = encode_grid(RangeGrid(4, 4));
  put_u32(b, 16, 2);
  reseal(b);
  const std::string m = rejection(dir, "v2.smg", b);
  EXPECT_NE(m.find("v2.smg"), std::string::npos) << m;
  EXPECT_NE(m.find("version 2 not supported; this build reads version 1"), std::string::npos) << m;
}

TEST(GridFile, InconsistentContentIsRejectedEvenWithAValidChecksum) {
  TempDir dir;
  RangeGrid grid(4, 3);
  grid.set_sample(0, 0, 10.0f, 0.5f);  // cell 0 valid, cell 1 invalid
  const std::vector<std::uint8_t> good = encode_grid(grid);
  const std::size_t radius = 60, valid = 60 + 48, confidence = 60 + 48 + 12;
  struct Case {
    std::function<void(std::vector<std::uint8_t>&)> patch;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {[&](auto& b) { b[valid + 1] = 2; }, "cell (1, 0): validity byte 2 is not 0 or 1"},
      {[&](auto& b) { put_f32(b, radius, -1.0f); }, "cell (0, 0): valid cell has radius"},
      {[&](auto& b) { put_f32(b, radius, NAN); }, "cell (0, 0): valid cell has radius"},
      {[&](auto& b) { put_f32(b, radius + 4, 3.0f); }, "cell (1, 0): invalid cell has radius"},
      {[&](auto& b) { put_f32(b, confidence, 1.5f); }, "cell (0, 0): confidence"},
      {[&](auto& b) { put_f32(b, confidence + 4, -0.1f); }, "cell (1, 0): confidence"},
      {[&](auto& b) { put_f64(b, 48, 0.0); }, "dh"},
      {[&](auto& b) { put_f64(b, 48, INFINITY); }, "dh"},
      {[&](auto& b) { put_f64(b, 32, NAN); }, "phi0/h0 are not finite"},
      {[&](auto& b) {
         put_u32(b, 24, 1);
         put_u32(b, 28, 12);
       },
       "grid size 1 x 12 is impossible"},
      {[&](auto& b) { b[0] = 's'; }, "bad magic"},
      {[&](auto& b) { b.erase(b.begin() + 12); }, "bad magic"},  // text mode: CR LF -> LF
      {[&](auto& b) { b.push_back(0); }, "trailing garbage"},
  };
  for (const Case& c : cases) {
    std::vector<std::uint8_t> b = good;
    c.patch(b);
    reseal(b);
    const std::string m = rejection(dir, "bad.smg", b);
    EXPECT_NE(m.find("bad.smg"), std::string::npos) << m;
    EXPECT_NE(m.find(c.expected), std::string::npos)
        << "expected '" << c.expected << "' in '" << m << "'";
  }
}

TEST(GridFile, DuplicateOrOverlongMetadataIsRejected) {
  TempDir dir;
  RangeGrid grid(2, 2);
  grid.metadata["ab"] = "x";
  grid.metadata["ac"] = "y";
  std::vector<std::uint8_t> b = encode_grid(grid);
  // Entries start at 60: u32 len, "ab", u32 len, "x", u32 len, "ac", ...
  std::vector<std::uint8_t> dup = b;
  dup[60 + 4 + 2 + 4 + 1 + 4 + 1] = 'b';
  reseal(dup);
  EXPECT_NE(rejection(dir, "dup.smg", dup).find("duplicate key"), std::string::npos);
  std::vector<std::uint8_t> longer = b;
  put_u32(longer, 60, 1000);
  reseal(longer);
  EXPECT_NE(rejection(dir, "long.smg", longer).find("runs past the header"), std::string::npos);
}

TEST(GridFile, NonGridFilesAreRecognised) {
  TempDir dir;
  write_raw(dir / "mesh.ply", std::string("ply\nformat ascii 1.0\n"));
  EXPECT_FALSE(looks_like_grid_file(dir / "mesh.ply"));
  EXPECT_FALSE(looks_like_grid_file(dir / "missing.smg"));
  EXPECT_NE(rejection(dir, "mesh.ply", read_file_bytes(dir / "mesh.ply"))
                .find("not a scanmesh grid file"),
            std::string::npos);
}

}  // namespace
}  // namespace scanmesh
