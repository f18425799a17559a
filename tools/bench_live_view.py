"""Memory and CPU of `gyrofilter run --serve` at 1 kHz with 3 stream clients, beside `run` alone.

Run: python tools/bench_live_view.py [--duration 30] [--clients 3] [--rate 1000]

Both runs are `gyrofilter run --source sim:seed=1,rate=RATE --duration D --out TMP --quiet`, the
simulated gyro paced in real time (as a sensor delivers it), in a subprocess; the second adds
`--serve 127.0.0.1:0` and CLIENTS stream clients (threads of this process that load the page,
then read /stream to the end, as a browser tab does). For each run: the child's CPU time
(user + system, from wait4) and its share of one core over the wall time, its peak resident
memory (ru_maxrss), the rows it wrote; then the extra cost of the view. The issue's target: under
10 % of one core extra CPU and under 50 MB extra memory. A Raspberry Pi 4 core is roughly 4 to 8
times slower than this machine's: scale the CPU figures, not the memory.
"""
import argparse
import os
import platform
import re
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


class StreamClient(threading.Thread):
    """Loads / (and its script and style sheet), then reads /stream until the server closes it."""

    def __init__(self, port):
        super().__init__(daemon=True)
        self.port = port
        self.bytes = 0

    def _get(self, path, read_all=True):
        sock = socket.create_connection(("127.0.0.1", self.port), timeout=60)
        sock.sendall(f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{self.port}\r\n\r\n".encode())
        while chunk := sock.recv(65536):
            self.bytes += len(chunk)
        sock.close()

    def run(self):
        try:
            for path in ("/", "/view.js", "/view.css", "/stream"):
                self._get(path)
        except OSError:
            pass


def run_once(rate_hz, duration_s, clients, serve):
    """One `gyrofilter run`; its figures as a dict."""
    with tempfile.TemporaryDirectory() as folder:
        cmd = [sys.executable, "-m", "gyrofilter", "run", "--source", f"sim:seed=1,rate={rate_hz:g}",
               "--duration", f"{duration_s:g}", "--out", os.path.join(folder, "out.csv"), "--quiet"]
        if serve:
            cmd += ["--serve", "127.0.0.1:0"]
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
        start = time.monotonic()
        proc = subprocess.Popen(cmd, cwd=REPO, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True)
        readers = []
        if serve:
            port = int(re.search(r"127\.0\.0\.1:(\d+)/", proc.stderr.readline()).group(1))
            readers = [StreamClient(port) for _ in range(clients)]
            for reader in readers:
                reader.start()
        err = proc.stderr.read()
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        wall = time.monotonic() - start
        for reader in readers:
            reader.join(10)
        if proc.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)} failed:\n{err}")
        rows = int(re.search(r"(\d+) filtered rows out", err).group(1))
    cpu = usage.ru_utime + usage.ru_stime
    return {"cpu_s": cpu, "cpu_pct": 100.0 * cpu / wall, "rss_mb": usage.ru_maxrss / 1024.0, "rows": rows,
            "wall_s": wall, "stream_kb": [r.bytes / 1024.0 for r in readers]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=30.0, help="seconds of samples per run (default 30)")
    parser.add_argument("--clients", type=int, default=3, help="stream clients of the second run (default 3)")
    parser.add_argument("--rate", type=float, default=1000.0, help="sample rate, Hz (default 1000)")
    args = parser.parse_args()
    alone = run_once(args.rate, args.duration, 0, serve=False)
    served = run_once(args.rate, args.duration, args.clients, serve=True)
    print(f"gyrofilter run, sim source paced at {args.rate:g} Hz for {args.duration:g} s; python "
          f"{platform.python_version()} on {platform.machine()}, {os.cpu_count()} cores")
    head = f"--serve, {args.clients} clients"
    print(f"{'':28s}{'run alone':>14s}{head:>22s}{'extra':>14s}")
    for label, key, fmt in (("CPU, s", "cpu_s", "{:.2f}"), ("CPU, % of one core", "cpu_pct", "{:.1f}"),
                            ("peak memory (RSS), MB", "rss_mb", "{:.1f}"), ("wall time, s", "wall_s", "{:.1f}")):
        a, b = alone[key], served[key]
        print(f"{label:28s}{fmt.format(a):>14s}{fmt.format(b):>22s}{'+' + fmt.format(b - a):>14s}")
    print(f"{'filtered rows out':28s}{alone['rows']:>14d}{served['rows']:>22d}")
    print(f"{'received per client, kB':28s}{'':>14s}{', '.join(f'{k:.0f}' for k in served['stream_kb']):>22s}")
    extra_cpu, extra_mb = served["cpu_pct"] - alone["cpu_pct"], served["rss_mb"] - alone["rss_mb"]
    verdict = "within" if extra_cpu < 10 and extra_mb < 50 else "OVER"
    print(f"extra for the live view: {extra_cpu:+.1f} % of one core, {extra_mb:+.1f} MB "
          f"({verdict} the target of 10 % and 50 MB)")


if __name__ == "__main__":
    main()
