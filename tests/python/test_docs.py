"""The example in docs/python.md runs as printed (in a temporary folder)."""

import contextlib
import io
import os
import re
import tempfile
import unittest

import scanmesh

SOURCE = os.environ.get("SCANMESH_SOURCE_DIR",
                        os.path.join(os.path.dirname(__file__), "..", ".."))


class DocsExample(unittest.TestCase):
    def test_example_runs_and_writes_its_mesh(self):
        with open(os.path.join(SOURCE, "docs", "python.md"), encoding="utf-8") as f:
            blocks = re.findall(r"```python\n(.*?)```", f.read(), re.S)
        self.assertEqual(len(blocks), 1)
        cwd = os.getcwd()
        with tempfile.TemporaryDirectory() as tmp:
            os.chdir(tmp)
            try:
                printed = io.StringIO()
                with contextlib.redirect_stdout(printed):
                    exec(compile(blocks[0], "docs/python.md", "exec"), {})
                mesh = scanmesh.read_mesh(os.path.join(tmp, "head.ply"))
            finally:
                os.chdir(cwd)
        self.assertGreater(mesh.face_count, 100000)
        self.assertIn("'closed': False", printed.getvalue())


if __name__ == "__main__":
    unittest.main()
