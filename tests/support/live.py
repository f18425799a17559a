"""What the tests of the live view share: `gyrofilter run --serve` in a subprocess, and clients
of its HTTP server on real sockets (a Server-Sent Events reader, a client that never reads, a raw
request)."""
from __future__ import annotations

import json
import os
import re
import socket
import subprocess
import sys
import threading
import time

from . import REPO

URL = re.compile(r"http://127\.0\.0\.1:(\d+)/")


def start_run(*args, timeout_s=60):
    """``gyrofilter run ARGS --serve 127.0.0.1:0 --quiet`` in a subprocess; ``(proc, port)`` once
    it says where the view is (its first stderr line)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    proc = subprocess.Popen([sys.executable, "-m", "gyrofilter", "run", *args, "--serve", "127.0.0.1:0", "--quiet"],
                            cwd=REPO, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    line = proc.stderr.readline()
    found = URL.search(line)
    if not found:
        proc.kill()
        out, err = proc.communicate(timeout=timeout_s)
        raise AssertionError(f"no live view address in {line!r}{err!r}")
    return proc, int(found.group(1))


def request(port, raw, timeout_s=10.0):
    """Send ``raw`` (bytes, a whole request) to the server; the status code of its answer (or
    None when it closed without one) and the answer's bytes."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout_s) as sock:
        try:
            sock.sendall(raw)
            sock.shutdown(socket.SHUT_WR)  # nothing more comes: the server answers what it has
        except OSError:  # it answered and closed before reading it all
            pass
        data = b""
        try:
            while chunk := sock.recv(65536):
                data += chunk
        except ConnectionResetError:
            pass
    found = re.match(rb"HTTP/1\.[01] (\d{3}) ", data)
    return (int(found.group(1)) if found else None), data


def get(port, path, host="127.0.0.1"):
    """GET ``path``: (status, headers text, body bytes)."""
    status, data = request(port, f"GET {path} HTTP/1.1\r\nHost: {host}:{port}\r\nConnection: close\r\n\r\n".encode())
    head, _, body = data.partition(b"\r\n\r\n")
    return status, head.decode("latin-1"), body


def status(port):
    code, _, body = get(port, "/status")
    assert code == 200
    return json.loads(body)


class EventReader(threading.Thread):
    """A stream client that reads /stream until the server closes it or :meth:`stop`: ``events``
    holds (name, parsed JSON) in order; ``status_code`` the answer's status."""

    def __init__(self, port):
        super().__init__(daemon=True)
        self.port = port
        self.events = []
        self.status_code = None
        self.connected = threading.Event()
        self._halt = threading.Event()
        self.error = None

    def run(self):
        try:
            with socket.create_connection(("127.0.0.1", self.port), timeout=30) as sock:
                sock.sendall(f"GET /stream HTTP/1.1\r\nHost: 127.0.0.1:{self.port}\r\n\r\n".encode())
                buf = b""
                while not self._halt.is_set():
                    chunk = sock.recv(65536)
                    if not chunk:
                        break
                    buf += chunk
                    if self.status_code is None and b"\r\n\r\n" in buf:
                        head, _, buf = buf.partition(b"\r\n\r\n")
                        self.status_code = int(head.split()[1])
                        self.connected.set()
                    while self.status_code is not None and b"\n\n" in buf:
                        block, _, buf = buf.partition(b"\n\n")
                        self._parse(block.decode())
        except Exception as exc:  # noqa: BLE001 - reported by the test
            self.error = exc
        finally:
            self.connected.set()

    def _parse(self, block):
        fields = dict(line.split(": ", 1) for line in block.splitlines() if ": " in line)
        if "event" in fields:
            self.events.append((fields["event"], json.loads(fields["data"])))

    def stop(self):
        self._halt.set()

    def named(self, name):
        return [data for event, data in self.events if event == name]


class StalledClient:
    """A stream client that asks for /stream and then never reads (a small receive buffer, so
    the server's writes to it block soon)."""

    def __init__(self, port):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        self.sock.connect(("127.0.0.1", port))
        self.sock.sendall(f"GET /stream HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())

    def close(self):
        self.sock.close()


def wait_for(predicate, timeout_s=30.0, what="the condition"):
    """Poll ``predicate`` until it is true (a failure naming ``what`` after ``timeout_s``)."""
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.05)
