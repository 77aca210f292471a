"""The report dictionaries' keys are the ones docs/python.md lists ("Report keys").

The bindings fill them from C++ struct members by name, so renaming a member would silently
rename a key; this test makes that an API change that docs/python.md has to show."""

import os
import re
import unittest

import numpy as np

import scanmesh

SOURCE = os.environ.get("SCANMESH_SOURCE_DIR",
                        os.path.join(os.path.dirname(__file__), "..", ".."))


def documented_keys():
    """{report name: set of keys} from the "Report keys" list of docs/python.md."""
    with open(os.path.join(SOURCE, "docs", "python.md"), encoding="utf-8") as f:
        text = f.read()
    section = text.split("### Report keys", 1)[1]
    keys = {}
    for name, listed in re.findall(r"^- `([^`]+)`: (.*)$", section, flags=re.M):
        keys[name] = set(re.findall(r"`([^`]+)`", listed))
    return keys


class ReportKeys(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rng = np.random.default_rng(3)
        d = rng.normal(size=(2000, 3))
        points = 60.0 * d / np.linalg.norm(d, axis=1, keepdims=True)
        mesh, cls.fans = scanmesh.build_fans(points)
        cls.check = scanmesh.check(mesh)
        _, cls.remesh = scanmesh.remesh(mesh, 600)
        cls.documented = documented_keys()

    def expect(self, name, report):
        self.assertIn(name, self.documented, f"docs/python.md lists no keys for {name}")
        self.assertEqual(set(report.keys()), self.documented[name], name)

    def test_every_documented_report_is_checked(self):
        self.assertEqual(set(self.documented), {
            "build_fans", "check", 'check["verdicts"]', "remesh", 'remesh["stats"]',
            'remesh["prepare"]'})

    def test_fans(self):
        self.expect("build_fans", self.fans)

    def test_check(self):
        self.expect("check", self.check)
        self.expect('check["verdicts"]', self.check["verdicts"])

    def test_remesh(self):
        self.expect("remesh", self.remesh)
        self.expect('remesh["stats"]', self.remesh["stats"])
        self.expect('remesh["prepare"]', self.remesh["prepare"])


if __name__ == "__main__":
    unittest.main()
