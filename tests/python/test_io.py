"""Files from Python: grids, fields, corrupt input, the error classes (python/src/io.cpp)."""

import os
import tempfile
import unittest

import numpy as np

import scanmesh

SOURCE = os.environ.get("SCANMESH_SOURCE_DIR",
                        os.path.join(os.path.dirname(__file__), "..", ".."))
SPHERE = os.path.join(SOURCE, "configs", "sim", "sphere.yaml")


def small_grid():
    return scanmesh.sim(SPHERE, n_phi=48, n_h=40, h0_mm=30.0, dh_mm=4.0, seed=9)


class GridFiles(unittest.TestCase):
    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory()
        self.tmp = self._tmp.name

    def tearDown(self):
        self._tmp.cleanup()

    def test_grid_round_trip_is_lossless(self):
        grid = small_grid()
        grid.color[0, 0] = (9, 8, 7)
        path = os.path.join(self.tmp, "g.smg")
        scanmesh.write_grid(path, grid)
        self.assertEqual(os.path.getsize(path), len(grid.to_bytes()))
        back = scanmesh.read_grid(path)
        self.assertEqual(back, grid)
        np.testing.assert_array_equal(back.radius, grid.radius)
        self.assertEqual(back.metadata, grid.metadata)
        # pathlib paths work too.
        import pathlib
        self.assertEqual(scanmesh.read_grid(pathlib.Path(path)), grid)

    def test_corrupt_grid_names_the_file(self):
        data = bytearray(small_grid().to_bytes())
        data[100] ^= 0xFF  # a flipped byte inside the radius plane: checksum mismatch
        path = os.path.join(self.tmp, "corrupt.smg")
        with open(path, "wb") as f:
            f.write(data)
        with self.assertRaises(ValueError) as caught:
            scanmesh.read_grid(path)
        error = caught.exception
        self.assertIsInstance(error, scanmesh.FileFormatError)
        self.assertIsInstance(error, scanmesh.Error)
        self.assertIn(path, str(error))
        self.assertIn("checksum", str(error))
        self.assertEqual(error.filename, path)

    def test_truncated_and_foreign_files(self):
        data = small_grid().to_bytes()
        path = os.path.join(self.tmp, "short.smg")
        with open(path, "wb") as f:
            f.write(data[:-10])
        with self.assertRaisesRegex(scanmesh.FileFormatError, "short.smg.*truncated"):
            scanmesh.read_grid(path)
        with self.assertRaisesRegex(ValueError, "<bytes>"):
            scanmesh.RangeGrid.from_bytes(b"not a grid at all")
        ply = os.path.join(self.tmp, "bad.ply")
        with open(ply, "w") as f:
            f.write("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n")
        with self.assertRaises(scanmesh.FileFormatError) as caught:
            scanmesh.read_mesh(ply)
        self.assertIn("bad.ply", str(caught.exception))
        xyz = os.path.join(self.tmp, "bad.xyz")
        with open(xyz, "w") as f:
            f.write("1 2 3\n4 nan 6\n")
        with self.assertRaisesRegex(ValueError, "bad.xyz"):
            scanmesh.read_point_cloud(xyz)

    def test_missing_file_is_an_os_error(self):
        missing = os.path.join(self.tmp, "missing.smg")
        with self.assertRaises(OSError) as caught:
            scanmesh.read_grid(missing)
        self.assertIsInstance(caught.exception, scanmesh.IoError)
        self.assertIn("missing.smg", str(caught.exception))

    def test_fields_round_trip_and_exports(self):
        grid = small_grid()
        fields = scanmesh.curvature(grid, method="quadric", radius_mm=12)
        path = os.path.join(self.tmp, "f.smf")
        scanmesh.write_fields(path, fields)
        back = scanmesh.read_fields(path)
        self.assertEqual(back.method, "quadric")
        self.assertEqual(back.defined_count(), fields.defined_count())
        d = fields.defined
        np.testing.assert_array_equal(back.k1[d], fields.k1[d])
        np.testing.assert_array_equal(back.normal[d], fields.normal[d])
        for name, export in (("t.png", scanmesh.export_texture_png),
                             ("d.png", scanmesh.export_depth_png),
                             ("c.pcd", scanmesh.export_pcd),
                             ("p.ply", scanmesh.export_ply_points)):
            export(os.path.join(self.tmp, name), grid)
            self.assertGreater(os.path.getsize(os.path.join(self.tmp, name)), 0)
        cloud = scanmesh.read_point_cloud(os.path.join(self.tmp, "p.ply"))
        self.assertEqual(len(cloud), grid.valid_count())
        organised = scanmesh.read_point_cloud(os.path.join(self.tmp, "c.pcd"))
        self.assertTrue(organised.organised)
        self.assertEqual((organised.width, organised.height), (grid.n_phi, grid.n_h))
        self.assertEqual(scanmesh.texture_image(grid).shape, (grid.n_h, grid.n_phi, 3))


class GilRelease(unittest.TestCase):
    def test_python_threads_run_during_a_long_call(self):
        # A Python thread stamps the clock every millisecond. Were the GIL held through the
        # simulation, it could not run until the call returned; released, it stamps throughout.
        import threading
        import time
        stamps, stop = [], threading.Event()

        def watch():
            while not stop.is_set():
                stamps.append(time.perf_counter())
                time.sleep(0.001)

        watcher = threading.Thread(target=watch)
        watcher.start()
        time.sleep(0.05)
        start = time.perf_counter()
        grid = scanmesh.sim()  # the built-in head, 512 x 512: most of a second
        end = time.perf_counter()
        stop.set()
        watcher.join()
        self.assertEqual(grid.n_phi, 512)
        middle = [t for t in stamps if start + 0.2 * (end - start) < t < end - 0.2 * (end - start)]
        self.assertGreater(len(middle), 0, "no Python thread ran during sim()")


if __name__ == "__main__":
    unittest.main()
