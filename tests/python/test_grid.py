"""RangeGrid <-> NumPy, the simulator, clean and curvature (python/src/grid.cpp, scan.cpp)."""

import copy
import os
import pickle
import unittest

import numpy as np

import scanmesh

SOURCE = os.environ.get("SCANMESH_SOURCE_DIR",
                        os.path.join(os.path.dirname(__file__), "..", ".."))
SPHERE = os.path.join(SOURCE, "configs", "sim", "sphere.yaml")
# configs/sim/sphere.yaml: a ball of radius 80 mm centred on the axis at z = 100.
SPHERE_RADIUS, SPHERE_Z = 80.0, 100.0


def sphere_grid(**fields):
    """A small, noise-free scan of the sphere scene (128 x 128 cells, rows 1 mm apart)."""
    options = dict(n_phi=128, n_h=128, h0_mm=36.0, dh_mm=1.0, noise_sigma_mm=0.0,
                   spike_probability=0.0, hair=False, seed=7)
    options.update(fields)
    return scanmesh.sim(SPHERE, scanmesh.ScannerConfig(**options))


class SimulatedSphere(unittest.TestCase):
    def test_radius_plane_matches_the_sphere(self):
        grid = sphere_grid()
        self.assertEqual(grid.shape, (128, 128))
        self.assertEqual(grid.radius.shape, (128, 128))
        self.assertEqual(grid.radius.dtype, np.float32)
        heights = grid.heights()
        np.testing.assert_allclose(heights, 36.0 + np.arange(128))
        expected = np.sqrt(np.maximum(SPHERE_RADIUS**2 - (heights - SPHERE_Z) ** 2, 0.0))
        valid = grid.valid
        self.assertGreater(valid.sum(), 0.6 * valid.size)
        rows, cols = np.nonzero(valid)
        # Noise off: the measured radius is the exact ray hit, stored as float32.
        error = np.abs(grid.radius[rows, cols] - expected[rows])
        self.assertLess(error.max(), 1e-3, "max |r - sqrt(R^2 - (h - z0)^2)| in mm")
        # Every row crossing the sphere away from its poles is measured all the way round.
        middle = np.abs(heights - SPHERE_Z) < 50
        self.assertTrue(valid[middle].all())
        # Rows above and below the ball hit nothing.
        self.assertFalse(valid[np.abs(heights - SPHERE_Z) > SPHERE_RADIUS].any())
        # Invalid cells hold radius 0 and confidence 0 (docs/formats.md).
        self.assertTrue((grid.radius[~valid] == 0).all())
        self.assertTrue((grid.confidence[~valid] == 0).all())

    def test_truth_agrees_with_the_grid_and_the_sphere(self):
        grid, truth = scanmesh.sim_with_truth(SPHERE, n_phi=64, n_h=64, h0_mm=40.0, dh_mm=2.0,
                                              noise_sigma_mm=0.0, spike_probability=0.0,
                                              hair=False)
        hit = truth["hit"]
        self.assertEqual(hit.shape, (64, 64))
        np.testing.assert_array_equal(grid.valid, hit & (truth["drop"] == 0))
        v = grid.valid
        np.testing.assert_allclose(grid.radius[v], truth["radius"][v], atol=1e-4)
        np.testing.assert_allclose(truth["k1"][v], 1 / SPHERE_RADIUS, rtol=1e-6)
        np.testing.assert_allclose(truth["k2"][v], 1 / SPHERE_RADIUS, rtol=1e-6)
        distance = np.linalg.norm(truth["point"][v] - [0, 0, SPHERE_Z], axis=1)
        np.testing.assert_allclose(distance, SPHERE_RADIUS, atol=1e-6)
        np.testing.assert_allclose(grid.xyz()[v], truth["point"][v], atol=1e-3)

    def test_sim_is_deterministic_and_the_seed_matters(self):
        a = sphere_grid(noise_sigma_mm=0.2, seed=3)
        b = sphere_grid(noise_sigma_mm=0.2, seed=3)
        c = sphere_grid(noise_sigma_mm=0.2, seed=4)
        self.assertEqual(a, b)
        self.assertNotEqual(a, c)

    def test_invalid_scanner_values_raise_value_error(self):
        with self.assertRaises(ValueError) as caught:
            scanmesh.sim(SPHERE, n_phi=1)
        self.assertIsInstance(caught.exception, scanmesh.InvalidInputError)
        with self.assertRaises(ValueError):
            scanmesh.sim(SPHERE, noise_sigma_mm=-1.0)
        with self.assertRaises(TypeError):
            scanmesh.sim(SPHERE, no_such_field=1)


class ZeroCopyPlanes(unittest.TestCase):
    def test_colour_view_writes_through_to_the_grid(self):
        grid = sphere_grid()
        color = grid.color
        self.assertEqual(color.shape, (128, 128, 3))
        self.assertTrue(color.flags.writeable)
        color[5, 7] = (1, 2, 3)
        # A new view, the texture picture and the serialised grid all see the change.
        np.testing.assert_array_equal(grid.color[5, 7], [1, 2, 3])
        # The picture is upright (core/texture_layout.h): its rows are the planes' rows reversed.
        np.testing.assert_array_equal(scanmesh.texture_image(grid)[::-1], grid.color)
        again = scanmesh.RangeGrid.from_bytes(grid.to_bytes())
        np.testing.assert_array_equal(again.color[5, 7], [1, 2, 3])

    def test_radius_validity_confidence_views_are_read_only_and_share_memory(self):
        grid = sphere_grid()
        for plane in (grid.radius, grid.valid, grid.confidence):
            self.assertFalse(plane.flags.writeable)
            self.assertFalse(plane.flags.owndata)
            with self.assertRaises(ValueError):
                plane[0, 0] = 1
        # Two views share the grid's memory: no copy was made.
        self.assertEqual(grid.radius.__array_interface__["data"][0],
                         grid.radius.__array_interface__["data"][0])
        # Changes made through the grid's methods are seen by an existing view.
        view = grid.radius
        grid.set_sample(3, 64, 42.5, 0.5)
        self.assertEqual(view[64, 3], np.float32(42.5))
        grid.invalidate(3, 64)
        self.assertEqual(view[64, 3], 0)

    def test_view_keeps_the_grid_alive(self):
        radius = sphere_grid().radius  # the grid itself is not referenced any more
        import gc
        gc.collect()
        self.assertGreater(float(radius.max()), 70.0)
        self.assertIsInstance(radius.base, scanmesh.RangeGrid)


class GridFromArrays(unittest.TestCase):
    def test_round_trip_through_numpy(self):
        grid = sphere_grid()
        again = scanmesh.RangeGrid.from_arrays(
            grid.radius, valid=grid.valid, confidence=grid.confidence, color=grid.color,
            phi0=grid.phi0, h0=grid.h0, dh=grid.dh, metadata=grid.metadata)
        self.assertEqual(again, grid)

    def test_nan_marks_holes_and_bad_cells_raise(self):
        r = np.full((4, 6), 10.0)
        r[1, 2] = np.nan
        grid = scanmesh.RangeGrid.from_arrays(r, dh=0.5)
        self.assertEqual((grid.n_h, grid.n_phi), (4, 6))
        self.assertEqual(grid.valid_count(), 23)
        self.assertFalse(grid.valid[1, 2])
        with self.assertRaisesRegex(ValueError, r"cell \(i = 2, j = 1\): .*positive"):
            scanmesh.RangeGrid.from_arrays(r, valid=np.ones((4, 6), bool))  # NaN made valid
        # Confidences are clamped to [0, 1], as RangeGrid::set_sample does.
        clamped = scanmesh.RangeGrid.from_arrays(r, confidence=np.full((4, 6), 2.0))
        self.assertEqual(clamped.confidence.max(), 1.0)
        with self.assertRaises(ValueError):
            scanmesh.RangeGrid.from_arrays(np.ones(5))

    def test_set_radius_replaces_every_cell(self):
        grid = scanmesh.RangeGrid(8, 5, h0=1.0, dh=2.0)
        view = grid.radius
        r = np.arange(40, dtype=float).reshape(5, 8)  # cell 0 is 0: a hole
        grid.set_radius(r)
        self.assertEqual(grid.valid_count(), 39)
        np.testing.assert_array_equal(view, r.astype(np.float32))
        with self.assertRaises(ValueError):
            grid.set_radius(np.ones((3, 3)))

    def test_pickle_copy_geometry(self):
        grid = sphere_grid()
        grid.metadata = {"who": "test"}
        self.assertEqual(pickle.loads(pickle.dumps(grid)), grid)
        self.assertEqual(copy.deepcopy(grid), grid)
        self.assertEqual(grid.metadata["who"], "test")
        g = grid.geometry
        self.assertEqual((g["n_phi"], g["n_h"], g["h0"], g["dh"]), (128, 128, 36.0, 1.0))
        self.assertAlmostEqual(g["dphi"], 2 * np.pi / 128)
        np.testing.assert_allclose(grid.phis(), np.arange(128) * 2 * np.pi / 128)


class CleanAndCurvature(unittest.TestCase):
    def test_clean_removes_the_simulated_spikes(self):
        raw, truth = scanmesh.sim_with_truth(SPHERE, n_phi=128, n_h=128, h0_mm=36.0,
                                             dh_mm=1.0, noise_sigma_mm=0.0,
                                             spike_probability=0.01, hair=False, seed=11)
        spikes = truth["spike"] & raw.valid
        self.assertGreater(spikes.sum(), 20)
        cleaned, report = scanmesh.clean(raw)
        self.assertEqual(report["valid_before"], raw.valid_count())
        self.assertEqual(report["valid_after"], cleaned.valid_count())
        # Every spike is gone; cleaning only invalidates, and the input is unchanged.
        self.assertFalse((cleaned.valid & spikes).any())
        self.assertFalse((cleaned.valid & ~raw.valid).any())
        self.assertEqual(raw.valid_count(), scanmesh.RangeGrid.from_bytes(raw.to_bytes())
                         .valid_count())
        self.assertIn("cleaned", cleaned.metadata)
        with self.assertRaisesRegex(ValueError, "spike"):
            scanmesh.clean(raw, spike_threshold_mm=-1)

    def test_curvature_of_the_sphere(self):
        grid = sphere_grid()
        fields = scanmesh.curvature(grid, method="grid-quadric", radius_mm=6)
        self.assertEqual(fields.method, "grid-quadric")
        d = fields.defined
        self.assertGreater(d.sum(), 0.5 * grid.valid_count())
        self.assertFalse(fields.k1.flags.writeable)
        np.testing.assert_allclose(np.median(fields.k1[d]), 1 / SPHERE_RADIUS, rtol=0.02)
        np.testing.assert_allclose(np.median(fields.mean()[d]), 1 / SPHERE_RADIUS, rtol=0.02)
        # Normals point away from the centre.
        n = fields.normal[d]
        p = grid.xyz()[d] - [0, 0, SPHERE_Z]
        cosine = np.sum(n * p, axis=1) / np.linalg.norm(p, axis=1)
        self.assertGreater(np.median(cosine), 0.999)
        with self.assertRaisesRegex(ValueError, "unknown curvature method"):
            scanmesh.curvature(grid, method="magic")


if __name__ == "__main__":
    unittest.main()
