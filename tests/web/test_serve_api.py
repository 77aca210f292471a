"""`scanmesh serve`'s API on the simulated devices: scans that finish into valid sessions,
pause/resume, one job at a time, live controls that act on the drivers, bad input refused with
a clear 4xx and nothing lost, and the security rules (loopback, Host, token, data folder only)."""
import json
import os
import socket
import subprocess
import time
import unittest

from serve_fixture import SCANMESH, Server, run_cli


class ServeApi(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        # The fast synthetic line pattern on the table: this test also runs under the sanitizers,
        # where rendering the head takes minutes (the browser test scans the head).
        cls.server = Server("--scene", "synthetic")

    @classmethod
    def tearDownClass(cls):
        code = cls.server.stop()
        cls.server.cleanup()
        assert code == 0, "serve exited %d on SIGTERM" % code

    def post(self, path, body, **kw):
        return self.server.request(path, body, **kw)

    def session_dir(self, name):
        return os.path.join(self.server.data_dir, "sessions", name)

    def test_a_page_and_assets_are_served(self):
        status, page, headers = self.server.request("/")
        self.assertEqual(status, 200)
        self.assertIn(b"<title>scanmesh</title>", page)
        for path in ("/app.js", "/style.css", "/three/three.min.js", "/three/OrbitControls.js",
                     "/three/PLYLoader.js", "/three/OBJLoader.js"):
            status, body, _ = self.server.request(path)
            self.assertEqual(status, 200, path)
            self.assertGreater(len(body), 1000, path)
        # Nothing else of the three.js folder or the disk.
        self.assertEqual(self.server.request("/three/examples/js/loaders/GLTFLoader.js")[0], 404)
        self.assertEqual(self.server.request("/three/GLTFLoader.js")[0], 404)

    def test_live_controls_act_on_the_simulated_camera_and_board(self):
        self.assertEqual(self.post("/api/live/settings", {"exposure": 150, "threshold": 25, "laser": 0})[0], 200)
        status, png, h = self.server.request("/api/live/frame")
        self.assertEqual(status, 200)
        self.assertEqual(png[:8], b"\x89PNG\r\n\x1a\n")
        normal_peaks, normal_level = int(h["X-Peaks"]), float(h["X-Mean-Level"])
        self.assertGreater(normal_peaks, 50)
        self.assertGreater(normal_level, 1)
        # Twice the exposure: the sensor collects twice the light (less where it clips at 255).
        self.post("/api/live/settings", {"exposure": 300})
        _, _, h = self.server.request("/api/live/frame")
        self.assertGreater(float(h["X-Mean-Level"]), 1.5 * normal_level)
        self.assertLessEqual(float(h["X-Mean-Level"]), 2 * normal_level + 0.5)
        # A threshold above every peak's height: no peaks; laser off: no peaks either.
        self.post("/api/live/settings", {"exposure": 150, "threshold": 255})
        self.assertEqual(int(self.server.request("/api/live/frame")[2]["X-Peaks"]), 0)
        self.post("/api/live/settings", {"threshold": 25, "laser": -1})
        self.assertEqual(int(self.server.request("/api/live/frame")[2]["X-Peaks"]), 0)
        self.post("/api/live/settings", {"laser": 0})
        # The table turns through the board driver.
        before = float(self.server.request("/api/live/frame")[2]["X-Angle"])
        self.assertEqual(self.post("/api/live/turn", {"degrees": 30})[0], 200)
        after = float(self.server.request("/api/live/frame")[2]["X-Angle"])
        self.assertAlmostEqual(after - before, 30, delta=0.2)

    def test_bad_settings_are_refused_and_change_nothing(self):
        before = self.server.status()["live"]
        for bad in ({"exposure": -3}, {"exposure": "lots"}, {"threshold": 1e9}, {"method": "magic"},
                    {"laser": 7}, {"colour": 1}, {"exposure": 200, "laser": 9}):
            status, body, _ = self.post("/api/live/settings", bad)
            self.assertEqual(status, 400, bad)
            self.assertTrue(body["error"], bad)
        self.assertEqual(self.server.status()["live"]["exposure"], before["exposure"])
        self.assertEqual(self.post("/api/live/turn", {"degrees": "x"})[0], 400)
        self.assertEqual(self.post("/api/live/turn", {"degrees": 1e6})[0], 400)

    def test_bad_requests_get_clear_4xx(self):
        cases = [
            ("/api/scan/start", {"name": "../escape"}, 400),
            ("/api/scan/start", {"name": ".hidden"}, 400),
            ("/api/scan/start", {"name": "a/b"}, 400),
            ("/api/scan/start", {}, 400),
            ("/api/scan/start", {"name": "x", "steps": 2}, 400),
            ("/api/scan/start", {"name": "x", "steps": "many"}, 400),
            ("/api/scan/resume", {"session": "missing"}, 404),
            ("/api/sessions/replay", {"session": "missing"}, 404),
            ("/api/calibration/start", {"poses": 9}, 400),
            ("/api/calibration/start", {"check": "yes"}, 400),
            ("/api/lines", {"grid": "../../etc/passwd", "lines": []}, 403),
            ("/api/lines", {"grid": "nothing.smg", "lines": []}, 404),
            ("/api/lines", {"grid": "g.smg", "lines": [{"id": "a", "kind": "line", "closed": "yes",
                                                      "points": [[0, 0], [1, 1]]}]}, 400),
            ("/api/lines", {"grid": "g.smg", "lines": [{"id": "a", "kind": 3, "points": [[0, 0], [1, 1]]}]}, 400),
            ("/api/lines", {"grid": "g.smg", "lines": [{"id": "a b", "kind": "line", "points": [[0, 0], [1, 1]]}]}, 400),
            ("/api/lines", {"grid": "g.smg", "lines": [{"id": "a", "kind": "line", "points": [[0, "x"], [1, 1]]}]}, 400),
            ("/api/animesh", {"grid": "/etc/passwd"}, 403),
            ("/api/job/stop", {}, 409),
        ]
        for path, body, expected in cases:
            status, answer, _ = self.post(path, body)
            self.assertEqual(status, expected, (path, body, answer))
            self.assertIsInstance(answer, dict)
            self.assertTrue(answer.get("error"), (path, body))
        # Not JSON at all, or JSON that is not an object.
        self.assertEqual(self.post("/api/scan/start", None, raw_body=b"{name", content_type="application/json")[0], 400)
        self.assertEqual(self.post("/api/scan/start", None, raw_body=b"[1]", content_type="application/json")[0], 400)
        # A form post (what another site could make a browser send) is refused.
        self.assertEqual(self.post("/api/scan/start", None, raw_body=b"name=x",
                                   content_type="application/x-www-form-urlencoded")[0], 415)
        self.assertFalse(os.path.exists(self.session_dir("x")))

    def test_files_come_only_from_the_data_folder(self):
        outside = os.path.join(self.server.data, "secret.txt")
        with open(outside, "w") as f:
            f.write("TOP-SECRET-CONTENT")
        os.makedirs(os.path.join(self.server.data_dir, "results"), exist_ok=True)
        link = os.path.join(self.server.data_dir, "results", "link.txt")
        if not os.path.lexists(link):
            os.symlink(outside, link)
        for path in ("/files/%2e%2e/secret.txt", "/files/..%2fsecret.txt", "/files/results/link.txt",
                     "/files/%2fetc%2fpasswd", "/api/lines?grid=..%2Fsecret.txt"):
            status, body, _ = self.server.request(path)
            self.assertIn(status, (403, 404), path)
            self.assertNotIn(b"TOP-SECRET-CONTENT", body if isinstance(body, bytes) else json.dumps(body).encode())
        self.assertEqual(self.server.request("/files/no/such.png")[0], 404)

    def test_binds_loopback_by_default(self):
        self.assertTrue(self.server.address.startswith("127.0.0.1:"), self.server.first_line)
        self.assertNotIn("token=", self.server.first_line)
        # Not reachable on the machine's other addresses (where it has any).
        port = int(self.server.address.split(":")[1])
        other = subprocess.run(["hostname", "-I"], capture_output=True, text=True).stdout.split()
        for address in [a for a in other if ":" not in a and not a.startswith("127.")][:2]:
            with self.assertRaises(OSError, msg=address):
                socket.create_connection((address, port), timeout=2).close()

    def test_host_header_must_name_this_machine(self):
        status, body, _ = self.server.request("/api/status", headers={"Host": "attacker.example:80"})
        self.assertEqual(status, 403)
        self.assertIn("not this machine", body["error"])
        # A domain that merely starts like a loopback address (DNS rebinding) is not this machine.
        for host in ("127.evil.example", "127.0.0.1.evil.example:80", "localhost.evil.example"):
            self.assertEqual(self.server.request("/api/status", headers={"Host": host})[0], 403, host)
        for host in ("localhost", "127.0.0.1:1234", "127.1.2.3", "[::1]:8080"):
            self.assertEqual(self.server.request("/api/status", headers={"Host": host})[0], 200, host)

    def test_scan_pause_resume_and_one_job_at_a_time(self):
        status, job, _ = self.post("/api/scan/start", {"name": "paused", "steps": 40})
        self.assertEqual(status, 202, job)
        # A second scan (or any job) while one records: refused, the first one unharmed.
        status, answer, _ = self.post("/api/scan/start", {"name": "second", "steps": 40})
        self.assertEqual(status, 409)
        self.assertIn("one job at a time", answer["error"])
        self.assertEqual(self.post("/api/calibration/start", {"name": "c2"})[0], 409)
        self.assertFalse(os.path.exists(self.session_dir("second")))
        self.assertFalse(os.path.exists(os.path.join(self.server.data_dir, "results", "second")))
        # The live view is refused while the devices record.
        self.assertEqual(self.server.request("/api/live/frame")[0], 409)
        self.server.wait_job(until=lambda s: s.get("job_session", {}).get("steps_done", 0) >= 3)
        self.assertEqual(self.post("/api/job/stop", {})[0], 200)
        s = self.server.wait_job()
        self.assertEqual(s["job"]["state"], "stopped", s["job"])
        done = s["job_session"]["steps_done"]
        self.assertGreaterEqual(done, 3)
        self.assertLess(done, 40)
        self.assertEqual(s["job"]["commands"][0]["exit_code"], 11)
        # Resume: the session completes, every frame verifies.
        self.assertEqual(self.post("/api/scan/resume", {"session": "paused"})[0], 202)
        s = self.server.wait_job()
        self.assertEqual(s["job"]["state"], "succeeded", s["job"])
        code, replay = run_cli("replay", self.session_dir("paused"), "--out",
                               os.path.join(self.server.data, "replay-paused"))
        self.assertEqual(code, 0, replay)
        self.assertTrue(replay["complete"])
        self.assertEqual(replay["steps_recorded"], 40)
        self.assertEqual(replay["frames_verified"], 40 * 3)
        # The session list shows it complete.
        sessions = {x["name"]: x for x in self.server.request("/api/sessions")[1]}
        self.assertTrue(sessions["paused"]["complete"])
        # A name that exists is refused (nothing overwritten).
        self.assertEqual(self.post("/api/scan/start", {"name": "paused"})[0], 409)

    def test_z_calibration_stopped_and_resumed_still_calibrates(self):
        self.assertEqual(self.post("/api/calibration/start", {"name": "cal", "poses": 1, "check": False})[0], 202)
        self.server.wait_job(until=lambda s: s.get("job_session", {}).get("steps_done", 0) >= 3)
        self.post("/api/job/stop", {})
        s = self.server.wait_job()
        self.assertEqual(s["job"]["state"], "stopped", s["job"])
        self.assertFalse(os.path.exists(os.path.join(self.server.data_dir, "calibration.yaml")))
        self.assertEqual(self.post("/api/scan/resume", {"session": "cal", "check": False})[0], 202)
        s = self.server.wait_job()
        self.assertEqual(s["job"]["kind"], "calibration")
        self.assertEqual(s["job"]["state"], "succeeded", s["job"])
        argv = [c["argv"][0] for c in s["job"]["commands"]]
        self.assertEqual(argv, ["scan", "calibrate"])
        self.assertTrue(os.path.exists(os.path.join(self.server.data_dir, "calibration.yaml")))
        self.assertTrue(self.server.status()["calibration"]["exists"])


class ServeRemote(unittest.TestCase):
    def test_other_addresses_need_allow_remote(self):
        r = subprocess.run([SCANMESH, "serve", "--sim", "--host", "0.0.0.0", "--port", "0",
                            "--data", "/tmp/scanmesh-serve-refused"], capture_output=True, text=True, timeout=60)
        self.assertEqual(r.returncode, 3)
        self.assertIn("--allow-remote", r.stderr)

    def test_remote_mode_needs_the_token(self):
        server = Server("--host", "0.0.0.0", "--allow-remote")
        try:
            token = server.first_line.split("token=")[1].strip()
            self.assertGreaterEqual(len(token), 32)
            status, body, _ = server.request("/api/status")
            self.assertEqual(status, 401)
            self.assertEqual(server.request("/api/status?token=wrong")[0], 401)
            self.assertEqual(server.request("/", headers={"X-Scanmesh-Token": token[:-1] + "x"})[0], 401)
            status, _, headers = server.request("/?token=" + token)
            self.assertEqual(status, 200)
            self.assertIn("scanmesh_token=" + token, headers.get("Set-Cookie", ""))
            self.assertEqual(server.request("/api/status", headers={"Cookie": "scanmesh_token=" + token})[0], 200)
            self.assertEqual(server.request("/api/status", headers={"X-Scanmesh-Token": token})[0], 200)
        finally:
            self.assertEqual(server.stop(), 0)
            server.cleanup()

    def test_missing_hardware_is_a_clear_503_not_a_crash(self):
        server = Server(devices=("--device", "/dev/video-scanmesh-none", "--board", "/dev/ttyACM-scanmesh-none"))
        try:
            status, body, _ = server.request("/api/live/frame")
            self.assertEqual(status, 503)
            self.assertIn("/dev/video-scanmesh-none", body["error"])
            self.assertEqual(server.request("/api/status")[0], 200)  # still serving
            self.assertEqual(server.request("/api/live/turn", {"degrees": 10})[0], 503)
        finally:
            self.assertEqual(server.stop(), 0)
            server.cleanup()

    def test_stopping_the_server_mid_scan_keeps_the_session(self):
        server = Server("--scene", "synthetic")
        try:
            self.assertEqual(server.request("/api/scan/start", {"name": "cut", "steps": 60})[0], 202)
            server.wait_job(until=lambda s: s.get("job_session", {}).get("steps_done", 0) >= 2)
            self.assertEqual(server.stop(), 0)
            session = os.path.join(server.data_dir, "sessions", "cut")
            code, replay = run_cli("replay", session, "--out", os.path.join(server.data, "r"))
            self.assertEqual(code, 0, replay)
            self.assertGreaterEqual(replay["steps_recorded"], 2)
            self.assertFalse(replay["complete"])
        finally:
            server.cleanup()


if __name__ == "__main__":
    unittest.main()
