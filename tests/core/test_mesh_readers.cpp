// OFF, OBJ (+ MTL) and STL readers: round trips through scanmesh's own writers, hand-written
// files of each dialect, the scanned meshes of the real-data corpus, and malformed files that
// must be rejected naming the file.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "scanmesh/core/errors.h"
#include "scanmesh/core/mesh_io.h"
#include "test_util.h"
#include "scanmesh_test_paths.h"

namespace scanmesh {
namespace {

using test::TempDir;

Mesh tetrahedron() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  return m;
}

void expect_format_error_naming(const std::function<void()>& f, const std::string& name,
                                const std::string& words) {
  try {
    f();
    ADD_FAILURE() << "no FileFormatError for " << name;
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(OffReader, ReadsPolygonsColoursAndComments) {
  const Mesh m = parse_off(
      "COFF # coloured\n4 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n"
      "0 1 0 10 20 30 255\n\n4 0 1 2 3\n3 0 2 3\n",
      "quad.off");
  ASSERT_EQ(m.vertex_count(), 4u);
  ASSERT_EQ(m.face_count(), 3u);  // the quad as two triangles, plus one
  EXPECT_EQ(m.triangles[1], (std::array<int, 3>{0, 2, 3}));
  ASSERT_TRUE(m.has_colors());
  EXPECT_EQ(m.colors[3], (Rgb8{10, 20, 30}));
  // Counts on the keyword's line, floats for colours (0..1).
  const Mesh f = parse_off("OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "inline.off");
  EXPECT_EQ(f.face_count(), 1u);
}

TEST(OffReader, RejectsMalformedFiles) {
  expect_format_error_naming([] { parse_off("", "e.off"); }, "e.off", "empty");
  expect_format_error_naming([] { parse_off("PLY\n", "w.off"); }, "w.off", "not an OFF");
  expect_format_error_naming([] { parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n", "t.off"); }, "t.off",
                             "truncated");
  expect_format_error_naming([] { parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "i.off"); },
                             "i.off", "line 6");
  expect_format_error_naming([] { parse_off("OFF\n1 0 0\nnan 0 0\n", "n.off"); }, "n.off",
                             "non-finite");
  expect_format_error_naming([] { parse_off("OFF\n900000000 0 0\n0 0 0\n", "b.off"); }, "b.off",
                             "more than the file can hold");
  expect_format_error_naming([] { parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "p.off"); },
                             "p.off", "n >= 3");
}

TEST(ObjReader, RoundTripsScanmeshObjWithTexture) {
  TempDir dir;
  Mesh m = tetrahedron();
  m.texcoords = {{0.1f, 0.2f}, {0.9f, 0.2f}, {0.5f, 0.8f}};
  m.face_texcoords = {{0, 1, 2}, {0, 1, 2}, {0, 1, 2}, {0, 1, 2}};
  m.compute_vertex_normals();
  write_obj(dir.path() / "t.obj", m, "t.png");
  const ObjMesh back = read_obj(dir.path() / "t.obj");
  ASSERT_EQ(back.mesh.vertex_count(), 4u);
  ASSERT_EQ(back.mesh.triangles, m.triangles);
  for (std::size_t k = 0; k < 4; ++k)
    EXPECT_LT((back.mesh.positions[k] - m.positions[k]).norm(), 1e-9);
  ASSERT_TRUE(back.mesh.has_texcoords());
  EXPECT_NEAR(back.mesh.texcoords[back.mesh.face_texcoords[2][2]].y(), 0.8f, 1e-6);
  EXPECT_EQ(back.texture, dir.path() / "t.png");  // map_Kd of the MTL, beside the OBJ
  EXPECT_TRUE(back.mesh.has_normals());
}

TEST(ObjReader, ReadsNegativeIndicesVertexColoursAndRejectsBadIndices) {
  const ObjMesh o = parse_obj("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf -3 -2 -1\n", "c.obj");
  ASSERT_EQ(o.mesh.face_count(), 1u);
  EXPECT_EQ(o.mesh.triangles[0], (std::array<int, 3>{0, 1, 2}));
  ASSERT_TRUE(o.mesh.has_colors());
  EXPECT_EQ(o.mesh.colors[1], (Rgb8{0, 255, 0}));
  expect_format_error_naming([] { parse_obj("v 0 0 0\nf 1 2 3\n", "bad.obj"); }, "bad.obj",
                             "line 2");
  expect_format_error_naming([] { parse_obj("v 0 0\n", "short.obj"); }, "short.obj", "line 1");
  expect_format_error_naming([] { parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n", "vt.obj"); },
                             "vt.obj", "names no 'vt'");
}

TEST(StlReader, RoundTripsBinaryAndReadsAscii) {
  TempDir dir;
  write_stl(dir.path() / "t.stl", tetrahedron());
  const Mesh b = read_mesh(dir.path() / "t.stl");
  EXPECT_EQ(b.vertex_count(), 4u);  // corners welded
  EXPECT_EQ(b.face_count(), 4u);
  const std::string ascii =
      "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
      "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\n"
      "vertex 0 1 0\nendloop\nendfacet\nendsolid s\n";
  const Mesh a = parse_stl({reinterpret_cast<const std::uint8_t*>(ascii.data()), ascii.size()},
                           "a.stl");
  EXPECT_EQ(a.vertex_count(), 4u);
  EXPECT_EQ(a.face_count(), 2u);
  const std::string cut = ascii.substr(0, ascii.find("vertex 0 1 0"));
  const std::string bad = cut + "endloop\n";
  expect_format_error_naming(
      [&] { parse_stl({reinterpret_cast<const std::uint8_t*>(bad.data()), bad.size()}, "b.stl"); },
      "b.stl", "exactly 3");
}

TEST(MeshReaders, ReadEveryScannedMeshOfTheCorpus) {
  // Vertex and face counts as the files' headers declare them (docs/testing.md).
  const struct {
    const char* file;
    std::size_t vertices, faces;
  } corpus[] = {{"nefertiti.off", 299, 562},     {"head.off", 1487, 2918},
                {"elephant.off", 2775, 5558},    {"lion-head.off", 8356, 16674},
                {"mannequin-devil.off", 12977, 25888}};
  for (const auto& c : corpus) {
    const Mesh m = read_mesh(std::filesystem::path(SCANMESH_CORPUS_DIR) / "meshes" / c.file);
    EXPECT_EQ(m.vertex_count(), c.vertices) << c.file;
    EXPECT_EQ(m.face_count(), c.faces) << c.file;  // all triangles
    EXPECT_NO_THROW(m.validate()) << c.file;
  }
}

}  // namespace
}  // namespace scanmesh
