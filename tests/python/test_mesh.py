"""Mesh and PointCloud <-> NumPy, mesh files, the checker (python/src/mesh.cpp, io.cpp)."""

import os
import tempfile
import unittest

import numpy as np

import scanmesh


def octahedron():
    positions = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]],
                         dtype=np.float64) * 10.0
    triangles = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                          [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]], dtype=np.int32)
    return positions, triangles


class MeshRoundTrip(unittest.TestCase):
    def test_numpy_round_trip_is_exact(self):
        rng = np.random.default_rng(5)
        positions = rng.normal(size=(500, 3)) * 123.456  # full float64 mantissas
        triangles = rng.integers(0, 500, size=(900, 3)).astype(np.int32)
        normals = rng.normal(size=(500, 3)).astype(np.float32)
        colors = rng.integers(0, 256, size=(500, 3)).astype(np.uint8)
        labels = rng.integers(-5, 5, size=900).astype(np.int32)
        mesh = scanmesh.Mesh(positions, triangles, normals=normals, colors=colors,
                             face_labels=labels)
        self.assertEqual((mesh.vertex_count, mesh.face_count), (500, 900))
        for got, want, dtype in ((mesh.positions, positions, np.float64),
                                 (mesh.triangles, triangles, np.int32),
                                 (mesh.normals, normals, np.float32),
                                 (mesh.colors, colors, np.uint8),
                                 (mesh.face_labels, labels, np.int32)):
            self.assertEqual(got.dtype, dtype)
            np.testing.assert_array_equal(got, want)
        # The input arrays were copied: changing them leaves the mesh alone.
        positions[0] = 0
        self.assertNotEqual(mesh.positions[0, 0], 0)

    def test_views_are_read_only_zero_copy(self):
        positions, triangles = octahedron()
        mesh = scanmesh.Mesh(positions, triangles)
        p = mesh.positions
        self.assertFalse(p.flags.writeable)
        self.assertIs(p.base, mesh)
        self.assertEqual(p.__array_interface__["data"][0],
                         mesh.positions.__array_interface__["data"][0])
        with self.assertRaises(ValueError):
            p[0, 0] = 1.0
        self.assertEqual(mesh.normals.shape, (0, 3))
        self.assertFalse(mesh.has_normals)
        with_normals = mesh.with_vertex_normals()
        np.testing.assert_allclose(with_normals.normals, positions / 10.0, atol=1e-6)
        moved = mesh.replace(positions=positions + 1.0)
        np.testing.assert_array_equal(moved.positions, positions + 1.0)
        np.testing.assert_array_equal(moved.triangles, triangles)

    def test_int64_and_list_input_and_errors(self):
        positions, triangles = octahedron()
        mesh = scanmesh.Mesh(positions.tolist(), triangles.astype(np.int64))
        np.testing.assert_array_equal(mesh.triangles, triangles)
        with self.assertRaisesRegex(ValueError, "refers to vertex 6 of 6"):
            scanmesh.Mesh(positions, triangles + 6)
        with self.assertRaisesRegex(ValueError, "shape"):
            scanmesh.Mesh(positions[:, :2], triangles)
        with self.assertRaisesRegex(ValueError, "integers"):
            scanmesh.Mesh(positions, triangles.astype(float))
        with self.assertRaisesRegex(ValueError, "0..255"):
            scanmesh.Mesh(positions, triangles, colors=np.full((6, 3), 256))
        with self.assertRaises(ValueError):
            scanmesh.Mesh(positions, triangles, normals=np.zeros((5, 3)))

    def test_file_round_trips(self):
        positions, triangles = octahedron()
        colors = np.arange(18, dtype=np.uint8).reshape(6, 3) * 10
        mesh = scanmesh.Mesh(positions, triangles, colors=colors,
                             face_labels=np.arange(8, dtype=np.int32))
        with tempfile.TemporaryDirectory() as tmp:
            for name in ("m.ply", "m_ascii.ply", "m.obj", "m.stl"):
                path = os.path.join(tmp, name)
                if "ascii" in name:
                    scanmesh.write_ply(path, mesh, ascii=True)
                else:
                    scanmesh.write_mesh(path, mesh)
                back = scanmesh.read_mesh(path)
                self.assertEqual(back.face_count, 8, name)
                # The octahedron's coordinates are exact in float32, so every format keeps them.
                corners = back.positions[back.triangles].reshape(-1, 3)
                want = positions[triangles].reshape(-1, 3)
                np.testing.assert_array_equal(np.sort(corners, axis=0), np.sort(want, axis=0))
                if name.endswith(".ply"):
                    np.testing.assert_array_equal(back.positions, positions)
                    np.testing.assert_array_equal(back.triangles, triangles)
                    np.testing.assert_array_equal(back.colors, colors)
                    np.testing.assert_array_equal(back.face_labels, np.arange(8))
            with self.assertRaises(ValueError):
                scanmesh.write_mesh(os.path.join(tmp, "m.xyz"), mesh)


class Checker(unittest.TestCase):
    def test_closed_octahedron(self):
        report = scanmesh.check(scanmesh.Mesh(*octahedron()))
        self.assertEqual(report["euler_characteristic"], 2)
        self.assertEqual(report["genus"], 0)
        self.assertEqual(report["boundary_loops"], 0)
        self.assertTrue(report["defect_free"])
        self.assertEqual(set(report["verdicts"]), set(scanmesh.mesh_properties()))
        self.assertTrue(all(report["verdicts"].values()))
        self.assertIn("closed", report["verdicts"])

    def test_open_and_unchecked(self):
        positions, triangles = octahedron()
        report = scanmesh.check(scanmesh.Mesh(positions, triangles[:-1]),
                                self_intersections=False)
        self.assertFalse(report["verdicts"]["closed"])
        self.assertIsNone(report["verdicts"]["intersection-free"])
        self.assertEqual(report["boundary_loops"], 1)
        self.assertEqual(report["boundary_loop_lengths"], [3])
        self.assertIn("boundary", report["evidence"]["closed"])


class PointClouds(unittest.TestCase):
    def test_xyz_file_and_arrays(self):
        rng = np.random.default_rng(1)
        points = rng.normal(size=(50, 3))
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "c.xyz")
            np.savetxt(path, points, fmt="%.17g")
            cloud = scanmesh.read_point_cloud(path)
        self.assertEqual(len(cloud), 50)
        self.assertFalse(cloud.organised)
        np.testing.assert_array_equal(cloud.positions, points)
        self.assertFalse(cloud.positions.flags.writeable)
        made = scanmesh.PointCloud(points, colors=np.zeros((50, 3), np.uint8))
        self.assertEqual(made.colors.shape, (50, 3))


if __name__ == "__main__":
    unittest.main()
