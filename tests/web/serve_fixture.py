"""Starts `scanmesh serve` for the web UI tests (tests/web/) and talks to it.

The binary comes from SCANMESH_BIN; every server gets its own data folder and a free port
(--port 0; the port is read from the line the server prints when it listens).
"""
import json
import os
import re
import shutil
import signal
import subprocess
import tempfile
import time
import urllib.error
import urllib.request

SCANMESH = os.environ.get("SCANMESH_BIN", "scanmesh")


class Server:
    def __init__(self, *args, size="320x240", devices=("--sim",)):
        self.data = tempfile.mkdtemp(prefix="scanmesh_serve_test_")
        cmd = [SCANMESH, "serve"] + list(devices) + ["--size", size, "--port", "0",
               "--data", os.path.join(self.data, "d")] + list(args)
        self.process = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = self.process.stdout.readline()
        match = re.search(r"http://([^/]+)/(\S*)", line)
        if not match:
            self.process.kill()
            raise RuntimeError("serve did not start: %r %s" % (line, self.process.stderr.read()))
        self.address = match.group(1)
        self.url = "http://" + self.address
        self.first_line = line
        self.data_dir = os.path.join(self.data, "d")

    def request(self, path, body=None, headers=None, raw_body=None, content_type="application/json"):
        """(status, parsed JSON or bytes, response headers) for GET (body None) or POST."""
        data = raw_body if raw_body is not None else (None if body is None else json.dumps(body).encode())
        req = urllib.request.Request(self.url + path, data=data, headers=dict(headers or {}))
        if data is not None and content_type:
            req.add_header("Content-Type", content_type)
        try:
            with urllib.request.urlopen(req, timeout=60) as r:
                status, payload, h = r.status, r.read(), r.headers
        except urllib.error.HTTPError as e:
            status, payload, h = e.code, e.read(), e.headers
        if h.get("Content-Type", "").startswith("application/json"):
            payload = json.loads(payload)
        return status, payload, h

    def status(self):
        return self.request("/api/status")[1]

    def wait_job(self, timeout=300, until=None):
        """Waits until the job ends (or `until(status)` holds); returns the last status."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            s = self.status()
            if until is not None:
                if until(s):
                    return s
            elif s["job"]["state"] not in ("running", "stopping"):
                return s
            time.sleep(0.2)
        raise AssertionError("job did not end in %d s: %s" % (timeout, s))

    def stop(self):
        """SIGTERM, as Ctrl-C would; returns the exit code."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
        try:
            code = self.process.wait(timeout=60)
        finally:
            self.process.stdout.close()
            self.process.stderr.close()
        return code

    def cleanup(self):
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        shutil.rmtree(self.data, ignore_errors=True)


def run_cli(*args):
    """Runs scanmesh ARGS --json: (exit code, result object)."""
    r = subprocess.run([SCANMESH] + list(args) + ["--json"], capture_output=True, text=True, timeout=300)
    try:
        return r.returncode, json.loads(r.stdout)
    except ValueError:
        return r.returncode, {"stdout": r.stdout, "stderr": r.stderr}
