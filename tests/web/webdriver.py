"""A minimal W3C WebDriver client for Debian's chromium + chromedriver (headless), enough for the
web UI tests: open a page, find and click elements, run scripts, take screenshots."""
import base64
import json
import os
import shutil
import socket
import subprocess
import tempfile
import time
import urllib.error
import urllib.request

ELEMENT = "element-6066-11e4-a52e-4f735466cecf"


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def browser_available():
    return shutil.which("chromedriver") is not None and (
        shutil.which("chromium") is not None or os.path.exists("/usr/bin/chromium"))


class Browser:
    def __init__(self, width=1400, height=1000):
        self.port = free_port()
        self.profile = tempfile.mkdtemp(prefix="scanmesh_chromium_")
        self.driver = subprocess.Popen(["chromedriver", "--port=%d" % self.port],
                                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.base = "http://127.0.0.1:%d" % self.port
        deadline = time.time() + 30
        while True:
            try:
                self._call("GET", "/status")
                break
            except (urllib.error.URLError, ConnectionError):
                if time.time() > deadline:
                    raise
                time.sleep(0.1)
        args = ["--headless", "--no-sandbox", "--disable-dev-shm-usage",
                # WebGL without a GPU: SwiftShader, Chromium's software renderer.
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                "--window-size=%d,%d" % (width, height), "--user-data-dir=" + self.profile]
        caps = {"capabilities": {"alwaysMatch": {"browserName": "chrome", "goog:chromeOptions": {
            "binary": "/usr/bin/chromium", "args": args}, "goog:loggingPrefs": {"browser": "ALL"}}}}
        self.session = self._call("POST", "/session", caps)["sessionId"]

    def _call(self, method, path, body=None):
        data = None if body is None else json.dumps(body).encode()
        req = urllib.request.Request(self.base + path, data=data, method=method,
                                     headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(req, timeout=120) as r:
                return json.loads(r.read())["value"]
        except urllib.error.HTTPError as e:
            raise RuntimeError("webdriver %s %s: %s" % (method, path, e.read()[:500]))

    def _s(self, method, path, body=None):
        return self._call(method, "/session/%s%s" % (self.session, path), body)

    def get(self, url):
        self._s("POST", "/url", {"url": url})

    def find(self, css):
        return self._s("POST", "/element", {"using": "css selector", "value": css})[ELEMENT]

    def click(self, css):
        self._s("POST", "/element/%s/click" % self.find(css), {})

    def type(self, css, text):
        element = self.find(css)
        self._s("POST", "/element/%s/clear" % element, {})
        self._s("POST", "/element/%s/value" % element, {"text": text})

    def drag_on(self, css, start, end):
        """Presses the mouse at `start`, moves to `end`, releases: W3C actions, i.e. real pointer
        events in the page. Points are (dx, dy) from the element's centre, in CSS pixels."""
        element = self.find(css)
        def at(p):
            return {"type": "pointerMove", "duration": 0, "origin": {ELEMENT: element},
                    "x": int(p[0]), "y": int(p[1])}
        self._s("POST", "/actions", {"actions": [{"type": "pointer", "id": "mouse",
            "parameters": {"pointerType": "mouse"}, "actions": [
                at(start), {"type": "pointerDown", "button": 0},
                at(end), {"type": "pointerUp", "button": 0}]}]})

    def text(self, css):
        return self._s("GET", "/element/%s/text" % self.find(css))

    def run(self, script, *args):
        """Runs `script` as a function body; a returned Promise is awaited."""
        return self._s("POST", "/execute/sync", {"script": script, "args": list(args)})

    def wait_for(self, script, timeout=120, *args):
        deadline = time.time() + timeout
        value = None
        while time.time() < deadline:
            value = self.run(script, *args)
            if value:
                return value
            time.sleep(0.25)
        raise AssertionError("timed out waiting for: %s (last %r)" % (script, value))

    def screenshot(self, path=None):
        png = base64.b64decode(self._s("GET", "/screenshot"))
        if path:
            with open(path, "wb") as f:
                f.write(png)
        return png

    def console_errors(self):
        try:
            entries = self._s("GET", "/se/log?type=browser") or []
        except RuntimeError:
            entries = self._call("POST", "/session/%s/se/log" % self.session, {"type": "browser"}) or []
        return [e["message"] for e in entries if e.get("level") == "SEVERE"]

    def close(self):
        try:
            self._call("DELETE", "/session/" + self.session)
        finally:
            self.driver.terminate()
            self.driver.wait(timeout=30)
            shutil.rmtree(self.profile, ignore_errors=True)
