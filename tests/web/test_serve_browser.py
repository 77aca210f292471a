"""The web UI in a real browser (Debian's chromium, headless, through chromedriver): the page
loads with the live view, a calibration and a simulated scan started from the page complete
(the session verifies with `scanmesh replay`), the 3D views show the points and meshes (not
blank), and animation lines drawn through the page's API reach `regions` and `animesh`.

SCANMESH_UI_SCREENSHOTS=DIR keeps a screenshot of every screen there (docs/ui/ holds them)."""
import os
import re
import tempfile
import unittest

from serve_fixture import Server, run_cli
from webdriver import Browser, browser_available

# Share of a 3D view's pixels that differ from its background (#1e1e1e).
NON_BLANK = """
const c = document.querySelector(arguments[0] + ' canvas');
const t = document.createElement('canvas'); t.width = c.width; t.height = c.height;
const g = t.getContext('2d'); g.drawImage(c, 0, 0);
const d = g.getImageData(0, 0, t.width, t.height).data;
let n = 0;
for (let i = 0; i < d.length; i += 4)
  if (Math.abs(d[i] - 30) + Math.abs(d[i + 1] - 30) + Math.abs(d[i + 2] - 30) > 24) n++;
return n / (d.length / 4);
"""

JOB_DONE = """
const s = window.scanmeshUI.state.status;
return s && s.job.kind === arguments[0] && s.job.state !== 'running' && s.job.state !== 'stopping'
  && window.scanmeshUI.state.shownJob === s.job.id + s.job.state ? s.job.state : null;
"""


class BrowserUi(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        # Not a skip: scripts/install-deps installs both, and a UI test that quietly skips in CI
        # would prove nothing.
        if not browser_available():
            raise RuntimeError("chromium and chromedriver are required (scripts/install-deps)")
        size = os.environ.get("SCANMESH_UI_SIZE", "320x240")
        cls.server = Server("--steps", "48", size=size)
        cls.shots = os.environ.get("SCANMESH_UI_SCREENSHOTS") or tempfile.mkdtemp(prefix="scanmesh_ui_")
        os.makedirs(cls.shots, exist_ok=True)
        cls.browser = Browser()
        cls.browser.get(cls.server.url + "/")

    @classmethod
    def tearDownClass(cls):
        cls.browser.close()
        code = cls.server.stop()
        cls.server.cleanup()
        assert code == 0, "serve exited %d" % code

    def shot(self, name):
        png = self.browser.screenshot(os.path.join(self.shots, name + ".png"))
        self.assertEqual(png[:8], b"\x89PNG\r\n\x1a\n")

    def tab(self, name):
        self.browser.click('#tabs button[data-tab="%s"]' % name)

    def test_1_page_loads_with_the_live_view(self):
        b = self.browser
        self.assertEqual(b.run("return document.title"), "scanmesh")
        b.wait_for("return document.getElementById('live-img').naturalWidth > 0")
        info = b.wait_for("const t = document.getElementById('live-info').textContent; return t.includes('peaks') ? t : null")
        self.assertGreater(int(re.search(r"(\d+) laser peaks", info).group(1)), 0)
        self.assertIn("sim:camera", b.text("#devices"))
        self.shot("live")

    def test_2_calibration_from_the_page(self):
        b = self.browser
        self.tab("calibration")
        b.click("#calib-start")
        verdict = b.wait_for("const v = document.getElementById('calib-verdict'); return v ? v.textContent : null", 240)
        self.assertIn(verdict, ("PASS", "FAIL"))
        job = self.server.status()["job"]
        self.assertEqual(job["kind"], "calibration")
        self.assertEqual(verdict == "PASS", job["commands"][2]["exit_code"] == 0)
        result = b.text("#calib-result")
        self.assertIn("fx (px)", result)
        self.assertIn("reprojection RMS", result)
        self.assertTrue(os.path.exists(os.path.join(self.server.data_dir, "calibration.yaml")))
        self.shot("calibration")

    def test_3_scan_from_the_page_completes_into_a_valid_session_and_mesh(self):
        b = self.browser
        self.tab("scan")
        b.type("#scan-name", "browser-scan")
        b.click("#scan-start")
        self.assertEqual(b.wait_for(JOB_DONE, 300, "scan"), "succeeded")
        b.wait_for("return document.getElementById('scan-info').textContent.includes('scan complete')", 60)
        session = os.path.join(self.server.data_dir, "sessions", "browser-scan")
        code, replay = run_cli("replay", session, "--out", os.path.join(self.server.data, "replay"))
        self.assertEqual(code, 0, replay)
        self.assertTrue(replay["complete"])
        self.assertEqual(replay["steps_recorded"], 48)
        # The points arrived as the scan recorded (the page asked for them step by step).
        self.assertGreater(b.run("return window.scanmeshUI.state.scanXyz.length / 3"), 1000)
        self.assertEqual(b.run("return window.scanmeshUI.state.pointsFrom"), 48)
        code, check = run_cli("check", os.path.join(self.server.data_dir, "results", "browser-scan", "mesh.ply"))
        self.assertEqual(code, 0, check)
        self.assertGreater(b.run(NON_BLANK, "#scan-view"), 0.03)
        self.shot("scan")

    def test_4_mesh_view_with_quality_colours(self):
        b = self.browser
        self.tab("meshes")
        b.wait_for("return document.querySelectorAll('#mesh-list li').length > 0")
        b.run("return window.scanmeshUI.openMesh('results/browser-scan/mesh.ply')")
        b.run("const s = document.getElementById('mesh-colour'); s.value = 'minangle'; s.dispatchEvent(new Event('change'));")
        stats = b.wait_for("const t = document.getElementById('mesh-stats').textContent; return t.includes('triangles') ? t : null")
        triangles = int(re.search(r"(\d+) triangles", stats).group(1))
        self.assertGreater(triangles, 1000)
        self.assertGreater(b.run(NON_BLANK, "#mesh-view"), 0.03)
        self.shot("meshes")
        # The OBJ beside it, with the texture its .mtl names.
        b.run("return window.scanmeshUI.openMesh('results/browser-scan/mesh.obj')")
        b.run("const s = document.getElementById('mesh-colour'); s.value = 'texture'; s.dispatchEvent(new Event('change'));")
        b.wait_for("return window.scanmeshUI.state.meshPath.endsWith('.obj') && !!window.scanmeshUI.state.meshTexture")
        self.assertGreater(b.run(NON_BLANK, "#mesh-view"), 0.03)
        self.shot("meshes-texture")

    def test_5_lines_drawn_in_the_page_reach_regions_and_animesh(self):
        b = self.browser
        self.tab("lines")
        b.click("#lines-sim")
        self.assertEqual(b.wait_for(JOB_DONE, 120, "sim-grid"), "succeeded")
        b.wait_for("return window.scanmeshUI.state.texture && window.scanmeshUI.state.texture.width === 512")
        # A closed line round the face, drawn through the page's API (as a click sequence would).
        line_id = b.run("return window.scanmeshUI.addLine([[170,150],[340,150],[340,400],[170,400]], 'line', true)")
        self.assertEqual(line_id, "line1")
        # Editing by mouse: drag the corner (340, 400) to (330, 390) through real pointer events
        # (the 512 x 512 texture shown 1:1, centred on the canvas's centre (256, 256)).
        b.drag_on("#lines-canvas", (340 - 256, 400 - 256), (330 - 256, 390 - 256))
        moved = b.run("return window.scanmeshUI.state.lines[0].points[2]")
        self.assertAlmostEqual(moved[0], 330, delta=1.0)
        self.assertAlmostEqual(moved[1], 390, delta=1.0)
        b.click("#lines-save")
        count = int(b.wait_for("const e = document.getElementById('lines-region-count'); return e ? e.textContent : null", 120))
        self.assertGreaterEqual(count, 1)
        grid = b.run("return window.scanmeshUI.state.grid")
        grid_dir = os.path.join(self.server.data_dir, os.path.dirname(grid))
        svg = os.path.join(grid_dir, "lines.svg")
        with open(svg) as f:
            self.assertIn('<polygon id="line1" class="line"', f.read())
        # The saved SVG is the CLI's input: the same regions from the command line.
        code, regions = run_cli("regions", os.path.join(self.server.data_dir, grid), "--lines", svg)
        self.assertEqual(code, 0, regions)
        self.assertEqual(len(regions["regions"]), count)
        b.wait_for("return document.getElementById('lines-regions').naturalWidth > 0")
        self.shot("lines")
        b.click("#lines-mesh")
        self.assertEqual(b.wait_for(JOB_DONE, 300, "animesh"), "succeeded")
        stats = b.wait_for("const t = document.getElementById('mesh-stats').textContent; return t.includes('animesh') ? t : null", 60)
        self.assertGreater(int(re.search(r"(\d+) triangles", stats).group(1)), 100)
        self.assertTrue(os.path.exists(os.path.join(grid_dir, "animesh", "mesh.ply")))
        self.assertGreater(b.run(NON_BLANK, "#mesh-view"), 0.03)
        self.shot("animesh")

    def test_6_sessions_list_and_no_page_errors(self):
        b = self.browser
        self.tab("sessions")
        rows = b.wait_for("const n = document.querySelectorAll('#sessions-table tbody tr').length; return n >= 2 ? n : 0")
        self.assertGreaterEqual(rows, 2)
        b.click("#sessions-table tbody tr:first-child button")  # Replay of browser-scan
        self.assertEqual(b.wait_for(JOB_DONE, 120, "replay"), "succeeded")
        b.wait_for("return document.getElementById('sessions-sheet').naturalWidth > 0")
        self.shot("sessions")
        errors = [e for e in b.console_errors() if "favicon" not in e]
        self.assertEqual(errors, [])


if __name__ == "__main__":
    unittest.main()
