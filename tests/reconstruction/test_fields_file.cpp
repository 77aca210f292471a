// The surface fields file (.smf): lossless round trip and rejection of damaged files.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/binary_io.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/reconstruction/fields_file.h"

namespace scanmesh {
namespace {

namespace fs = std::filesystem;

class FieldsFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("scanmesh_test_fields_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  fs::path path(const std::string& name) const { return dir_ / name; }

  static void write_raw(const fs::path& p, const std::vector<std::uint8_t>& bytes) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
  }
  // Re-seals a modified file with a correct CRC, to reach the checks behind the checksum.
  static void fix_crc(std::vector<std::uint8_t>& bytes) {
    const std::uint32_t crc = crc32_of(bytes.data(), bytes.size() - 4);
    for (int k = 0; k < 4; ++k)
      bytes[bytes.size() - 4 + k] = static_cast<std::uint8_t>(crc >> (8 * k));
  }
  // read_fields must throw FileFormatError naming the file; returns the message.
  static std::string rejection(const fs::path& p) {
    try {
      read_fields(p);
    } catch (const FileFormatError& e) {
      EXPECT_NE(std::string(e.what()).find(p.filename().string()), std::string::npos) << e.what();
      EXPECT_EQ(e.file(), p);
      return e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << "wrong exception type: " << e.what();
      return {};
    }
    ADD_FAILURE() << p << " was accepted";
    return {};
  }

  fs::path dir_;
};

SurfaceFields random_fields(int n_phi, int n_h, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  SurfaceFields f;
  f.resize(n_phi, n_h);
  f.method = CurvatureMethod::Quadric;
  f.radius_mm = 4.5;
  for (std::size_t k = 0; k < f.size(); ++k) {
    if (u(rng) < -0.4f) continue;  // ~30 % undefined, all zero as the header requires
    f.defined[k] = 1;
    f.normal[k] = Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized();
    f.k1[k] = 0.1f * u(rng);
    f.k2[k] = f.k1[k] - 0.05f * std::abs(u(rng));
    f.dir1[k] = Eigen::Vector3f(u(rng), u(rng), u(rng));
    f.dir2[k] = Eigen::Vector3f(u(rng), u(rng), 1e-30f * u(rng));  // denormals survive too
  }
  return f;
}

void expect_equal(const SurfaceFields& a, const SurfaceFields& b) {
  EXPECT_EQ(a.n_phi, b.n_phi);
  EXPECT_EQ(a.n_h, b.n_h);
  EXPECT_EQ(a.method, b.method);
  EXPECT_EQ(a.radius_mm, b.radius_mm);
  EXPECT_EQ(a.defined, b.defined);
  EXPECT_EQ(a.normal, b.normal);
  EXPECT_EQ(a.k1, b.k1);
  EXPECT_EQ(a.k2, b.k2);
  EXPECT_EQ(a.dir1, b.dir1);
  EXPECT_EQ(a.dir2, b.dir2);
}

TEST_F(FieldsFile, RoundTripIsLosslessAndTheSizeIsAsDocumented) {
  const SurfaceFields f = random_fields(37, 23, 7);
  write_fields(path("f.smf"), f);
  EXPECT_EQ(fs::file_size(path("f.smf")), 40u + 45u * 37 * 23 + 4);
  expect_equal(read_fields(path("f.smf")), f);
  for (const auto method :
       {CurvatureMethod::Analytic, CurvatureMethod::Quadric, CurvatureMethod::Seed000}) {
    SurfaceFields g = random_fields(5, 4, 11);
    g.method = method;
    g.radius_mm = 0;
    write_fields(path("g.smf"), g);
    expect_equal(read_fields(path("g.smf")), g);
  }
}

TEST_F(FieldsFile, UndefinedCellsAreWrittenAsZero) {
  SurfaceFields f = random_fields(4, 3, 1);
  f.defined[2] = 0;
  f.k1[2] = 3.0f;
  f.normal[2] = Eigen::Vector3f(1, 0, 0);
  write_fields(path("f.smf"), f);
  const SurfaceFields g = read_fields(path("f.smf"));
  EXPECT_EQ(g.k1[2], 0.0f);
  EXPECT_EQ(g.normal[2], Eigen::Vector3f::Zero());
  EXPECT_EQ(g.defined_count(), f.defined_count());
}

TEST_F(FieldsFile, WriterRejectsInconsistentFields) {
  SurfaceFields f = random_fields(4, 3, 1);
  f.k2.pop_back();
  EXPECT_THROW(write_fields(path("f.smf"), f), InvalidInputError);
  SurfaceFields g = random_fields(4, 3, 1);
  g.defined[0] = 1;
  g.k1[0] = std::nanf("");
  EXPECT_THROW(write_fields(path("g.smf"), g), InvalidInputError);
  EXPECT_FALSE(fs::exists(path("f.smf")));
  EXPECT_FALSE(fs::exists(path("g.smf")));
}

TEST_F(FieldsFile, TruncationAtTwentyPositionsIsRejected) {
  write_fields(path("f.smf"), random_fields(16, 9, 3));
  const std::vector<std::uint8_t> bytes = read_file_bytes(path("f.smf"));
  for (int t = 0; t < 20; ++t) {
    const std::size_t keep = bytes.size() * t / 20 + (t % 3);  // 0, 1 and 2 bytes in too
    const fs::path p = path("cut_" + std::to_string(keep) + ".smf");
    write_raw(p, std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + keep));
    const std::string message = rejection(p);
    EXPECT_NE(message.find("truncated"), std::string::npos) << message;
  }
}

TEST_F(FieldsFile, FlippedBytesAtTwentyPositionsAreRejected) {
  write_fields(path("f.smf"), random_fields(16, 9, 4));
  const std::vector<std::uint8_t> bytes = read_file_bytes(path("f.smf"));
  for (int t = 0; t < 20; ++t) {
    // Spread over the file, including the magic (0), the header and the CRC (last byte).
    const std::size_t at = t == 19 ? bytes.size() - 1 : (bytes.size() - 1) * t / 19 + t % 4;
    std::vector<std::uint8_t> damaged = bytes;
    damaged[at] ^= 0x5a;
    const fs::path p = path("flip_" + std::to_string(at) + ".smf");
    write_raw(p, damaged);
    rejection(p);
  }
}

TEST_F(FieldsFile, HugeDeclaredSizesAreRejectedBeforeAllocating) {
  write_fields(path("f.smf"), random_fields(4, 4, 5));
  std::vector<std::uint8_t> bytes = read_file_bytes(path("f.smf"));
  const auto set_u32 = [&](std::size_t at, std::uint32_t v) {
    for (int k = 0; k < 4; ++k) bytes[at + k] = static_cast<std::uint8_t>(v >> (8 * k));
  };
  set_u32(20, 0xffffffffu);
  set_u32(24, 0xffffffffu);
  write_raw(path("huge.smf"), bytes);
  EXPECT_NE(rejection(path("huge.smf")).find("exceeds the limit"), std::string::npos);
  // At the limit (8192 x 8192 = 2^26 cells) the size is allowed, but the file is far too short.
  set_u32(20, 8192);
  set_u32(24, 8192);
  write_raw(path("big.smf"), bytes);
  EXPECT_NE(rejection(path("big.smf")).find("truncated: expected 3019898924 bytes"),
            std::string::npos);
  set_u32(20, 0);
  write_raw(path("zero.smf"), bytes);
  EXPECT_NE(rejection(path("zero.smf")).find("impossible"), std::string::npos);
}

TEST_F(FieldsFile, ContentBehindAValidChecksumIsStillChecked) {
  write_fields(path("f.smf"), random_fields(4, 4, 6));
  const std::vector<std::uint8_t> good = read_file_bytes(path("f.smf"));
  const auto damaged = [&](const std::string& name, auto&& edit) {
    std::vector<std::uint8_t> b = good;
    edit(b);
    fix_crc(b);
    write_raw(path(name), b);
    return rejection(path(name));
  };
  EXPECT_NE(damaged("version.smf", [](auto& b) { b[16] = 2; }).find("version 2 not supported"),
            std::string::npos);
  EXPECT_NE(damaged("method.smf", [](auto& b) { b[28] = 7; }).find("method 7"), std::string::npos);
  EXPECT_NE(damaged("radius.smf", [](auto& b) { b[39] = 0xff; }).find("radius_mm"),
            std::string::npos);  // top byte 0xff: a huge negative radius
  EXPECT_NE(damaged("defined.smf", [](auto& b) { b[40] = 3; }).find("cell (0, 0)"),
            std::string::npos);
  // k1 of cell 5 (after 16 defined bytes and 16 normals) made infinite.
  EXPECT_NE(damaged("inf.smf",
                    [](auto& b) {
                      const std::size_t at = 40 + 16 + 12 * 16 + 4 * 5;
                      b[at] = 0;
                      b[at + 1] = 0;
                      b[at + 2] = 0x80;
                      b[at + 3] = 0x7f;
                    })
                .find("not finite"),
            std::string::npos);
  std::vector<std::uint8_t> longer = good;
  longer.push_back(0);
  write_raw(path("trailing.smf"), longer);
  EXPECT_NE(rejection(path("trailing.smf")).find("trailing garbage"), std::string::npos);
  write_raw(path("grid.smf"), std::vector<std::uint8_t>{'S', 'C', 'A', 'N', 'M', 'E', 'S', 'H', 'G',
                                                        'R', 'I', 'D', '\r', '\n', 0x1a, '\n'});
  EXPECT_NE(rejection(path("grid.smf")).find("bad magic"), std::string::npos);
  EXPECT_THROW(read_fields(path("missing.smf")), IoError);
}

TEST(CurvatureMethodNames, ParseAndPrint) {
  EXPECT_EQ(parse_curvature_method("analytic"), CurvatureMethod::Analytic);
  EXPECT_EQ(parse_curvature_method("quadric"), CurvatureMethod::Quadric);
  EXPECT_EQ(parse_curvature_method("seed"), CurvatureMethod::Seed000);
  EXPECT_EQ(parse_curvature_method("seed000"), CurvatureMethod::Seed000);
  EXPECT_THROW(parse_curvature_method("bogus"), InvalidInputError);
  for (const auto m :
       {CurvatureMethod::Analytic, CurvatureMethod::Quadric, CurvatureMethod::Seed000})
    EXPECT_EQ(parse_curvature_method(to_string(m)), m);
  SurfaceFields f;
  f.resize(3, 2);
  EXPECT_EQ(f.size(), 6u);
  EXPECT_EQ(f.k2.size(), 6u);
  EXPECT_EQ(f.defined_count(), 0u);
  f.defined[1] = f.defined[4] = 1;
  EXPECT_EQ(f.defined_count(), 2u);
}

}  // namespace
}  // namespace scanmesh
