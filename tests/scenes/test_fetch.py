#!/usr/bin/env python3
"""scenes/fetch end to end, offline: its checksum checks on the shared meshes, copies from a
folder, downloads from a server on 127.0.0.1 (good, corrupt, silent and absent), and its
exit statuses. Usage: test_fetch.py [SHARED_SCENES_DIR]"""
import hashlib
import http.server
import io
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time
import unittest
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FETCH = os.path.join(ROOT, "scenes", "fetch")
SHARED = sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(ROOT, "..", "shared", "scenes")
SMALL = ["CornellBox-Original.obj", "CornellBox-Original.mtl", "teapot.obj"]


def fetch(*args, timeout=60):
    start = time.monotonic()
    r = subprocess.run([sys.executable, FETCH, *args], capture_output=True, text=True, timeout=timeout)
    r.seconds = time.monotonic() - start
    r.text = r.stdout + r.stderr
    return r


def have_shared():
    return os.path.isfile(os.path.join(SHARED, "teapot.obj"))


class Server:
    """An HTTP server on 127.0.0.1 answering GET /NAME from `files` (name -> bytes)."""

    def __init__(self, files):
        class Handler(http.server.BaseHTTPRequestHandler):
            def do_GET(self):
                body = files.get(self.path.lstrip("/"))
                if body is None:
                    self.send_error(404)
                    return
                self.send_response(200)
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def log_message(self, *args):
                pass

        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}"
        threading.Thread(target=self.httpd.serve_forever, daemon=True).start()

    def close(self):
        self.httpd.shutdown()
        self.httpd.server_close()


def read(name):
    with open(os.path.join(SHARED, name), "rb") as f:
        return f.read()


class Manifest(unittest.TestCase):
    def test_every_entry_has_a_source_line(self):
        with open(os.path.join(ROOT, "scenes", "SOURCES.md"), encoding="utf-8") as f:
            sources = f.read()
        with open(os.path.join(ROOT, "scenes", "manifest.tsv"), encoding="utf-8") as f:
            names = [line.split("\t")[0] for line in f if line.strip() and not line.startswith("#")]
        self.assertEqual(len(names), 11)
        for name in names:
            self.assertIn(name.replace(".mtl", ""), sources, name)


@unittest.skipUnless(have_shared(), f"no benchmark meshes in {SHARED}")
class WithTheSharedMeshes(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="volley_fetch_")

    def tearDown(self):
        shutil.rmtree(self.tmp)

    def test_check_verifies_the_shared_folder(self):
        r = fetch("--check", SHARED, timeout=120)
        self.assertEqual(r.returncode, 0, r.text)
        self.assertIn("11 of 11 files verified", r.text)

    def test_check_names_a_corrupt_and_a_missing_file(self):
        for name in SMALL[:2]:
            shutil.copy(os.path.join(SHARED, name), self.tmp)
        body = bytearray(read("teapot.obj"))
        body[1000] ^= 1
        with open(os.path.join(self.tmp, "teapot.obj"), "wb") as f:
            f.write(body)
        r = fetch("--check", self.tmp, "--only", *SMALL, "stanford-bunny.obj")
        self.assertEqual(r.returncode, 1, r.text)
        self.assertIn("teapot.obj", r.text)
        self.assertIn("sha256 " + hashlib.sha256(body).hexdigest(), r.text)
        self.assertRegex(r.text, r"stanford-bunny.obj\s+missing")
        self.assertIn("2 of 4 files verified", r.text)

    def test_from_copies_verified_then_finds_them_present(self):
        dest = os.path.join(self.tmp, "dest")
        r = fetch("--from", SHARED, "--dest", dest, "--only", *SMALL, "conference.obj")
        self.assertEqual(r.returncode, 0, r.text)
        self.assertIn("4 of 4 files verified", r.text)
        self.assertIn("4 copied", r.text)
        again = fetch("--from", SHARED, "--dest", dest, "--only", *SMALL)
        self.assertIn("3 already there", again.text)

    def test_from_refuses_a_corrupt_source(self):
        source = os.path.join(self.tmp, "source")
        os.makedirs(source)
        with open(os.path.join(source, "teapot.obj"), "wb") as f:
            f.write(read("teapot.obj")[:-1])
        dest = os.path.join(self.tmp, "dest")
        r = fetch("--from", source, "--dest", dest, "--only", "teapot.obj")
        self.assertEqual(r.returncode, 1, r.text)
        self.assertIn("210613 bytes, expected 210614", r.text)
        self.assertFalse(os.path.exists(os.path.join(dest, "teapot.obj")))

    def test_download_from_a_server_verifies_and_unzips(self):
        archive = io.BytesIO()
        with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("sponza.obj", read("sponza_dabrovic.obj"))
        files = {name: read(name) for name in SMALL}
        files["sponza.zip"] = archive.getvalue()
        server = Server(files)
        try:
            dest = os.path.join(self.tmp, "dest")
            r = fetch("--base-url", server.url, "--dest", dest, "--only", *SMALL, "sponza_dabrovic.obj")
        finally:
            server.close()
        self.assertEqual(r.returncode, 0, r.text)
        self.assertIn("4 of 4 files verified", r.text)
        self.assertIn("4 downloaded", r.text)
        self.assertEqual(fetch("--check", dest, "--only", *SMALL, "sponza_dabrovic.obj").returncode, 0)

    def test_a_corrupt_download_is_refused_and_not_kept(self):
        server = Server({"teapot.obj": read("teapot.obj").replace(b"v ", b"v  ", 1)})
        try:
            dest = os.path.join(self.tmp, "dest")
            r = fetch("--base-url", server.url, "--dest", dest, "--only", "teapot.obj")
        finally:
            server.close()
        self.assertEqual(r.returncode, 1, r.text)
        self.assertIn("teapot.obj: the copy obtained is 210615 bytes, expected 210614", r.text)
        self.assertEqual(os.listdir(dest), [])


class Offline(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="volley_fetch_")

    def tearDown(self):
        shutil.rmtree(self.tmp)

    def test_a_converted_mesh_has_no_download(self):
        r = fetch("--dest", self.tmp, "--only", "conference.obj")
        self.assertEqual(r.returncode, 1, r.text)
        self.assertIn("no download", r.text)
        self.assertIn("--from DIR", r.text)

    def test_a_refused_connection_fails_fast_with_advice(self):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]  # closed again below: nobody listens there
        r = fetch("--base-url", f"http://127.0.0.1:{port}", "--dest", self.tmp, "--timeout", "5")
        self.assertEqual(r.returncode, 1, r.text)
        self.assertLess(r.seconds, 5)
        self.assertIn("is this machine offline?", r.text)
        self.assertIn("scenes/fetch --from DIR", r.text)

    def test_a_silent_server_times_out_instead_of_hanging(self):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            s.listen(8)  # accepts connections (the kernel does), never answers
            r = fetch("--base-url", f"http://127.0.0.1:{s.getsockname()[1]}", "--dest", self.tmp,
                      "--timeout", "1", timeout=30)
        self.assertEqual(r.returncode, 1, r.text)
        self.assertLess(r.seconds, 10)
        self.assertIn("timed out", r.text)
        self.assertIn("is this machine offline?", r.text)

    def test_usage_errors_exit_with_2(self):
        for args in (["--only", "nope.obj"], ["--timeout", "0"], ["--from", "/nonexistent"], ["--frobnicate"]):
            r = fetch("--dest", self.tmp, *args)
            self.assertEqual(r.returncode, 2, (args, r.text))
            self.assertIn("error", r.text)

    def test_help_explains(self):
        r = fetch("--help")
        self.assertEqual(r.returncode, 0)
        for part in ("--from", "--check", "--only", "--timeout", "Exit status"):
            self.assertIn(part, r.stdout)


if __name__ == "__main__":
    result = unittest.main(exit=False, verbosity=2).result
    print(f"{result.testsRun - len(result.failures) - len(result.errors) - len(result.skipped)} passed, "
          f"{len(result.failures) + len(result.errors)} failed, {len(result.skipped)} skipped")
    sys.exit(0 if result.wasSuccessful() else 1)
