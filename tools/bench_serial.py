"""Host cost per line of the serial reader, beside a naive readline() + split baseline.

Run: python tools/bench_serial.py [--lines N]

Lines are the protocol's ``counter,gx,gy,gz,temp`` (about 26 bytes, as the Arduino sketch
sends them). What is timed:

* parse only (bytes already in memory): ``LineParser.feed`` on chunks of 100 lines (a 0.1 s read
  at 1 kHz) and of 10 lines, through the vectorised path and through the line-by-line path
  (forced by a ``#`` device message in every chunk); baseline: ``BytesIO.readline()``, split,
  ``float()`` per line, appending rows to a list;
* end to end through pyserial on a real pseudo-terminal (a writer thread fills the master side
  as fast as it can): CPU time of the reading thread per line (``time.thread_time``), for
  ``SerialSource.read()`` and for pyserial's ``readline()`` + split + ``float()``.

At 1 kHz the reader's budget is 1000 us per line in total; the point is how little of it the
host spends, on a Raspberry Pi about 10x slower than this machine.
"""
import argparse
import io
import os
import sys
import threading
import time
import tty

import numpy as np


from gyrofilter.errors import SourceEnded
from gyrofilter.sources.serial.protocol import LineParser
from gyrofilter.sources.serial.port import SerialSource

from bench import best_of  # tools/bench.py, beside this file

HEADER = (b"# gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps=131 sample_rate_hz=1000 "
          b"fields=counter,gx,gy,gz,temp temp_unit=mpu6050_raw\n")


def make_lines(n, start=0, temp_c=False):
    """n protocol lines; the temperature as the MPU6050's raw register (what HEADER says), or in
    deg C (``temp_c``: what a reader without a header takes; it refuses a raw -1520 as absurd)."""
    rng = np.random.default_rng(0)
    g = rng.integers(-2000, 2000, size=(n, 3))
    temp = [f"{25 + (i % 7) / 100:.2f}" if temp_c else f"{-1520 + i % 7}" for i in range(n)]
    return [f"{start + i},{g[i, 0]},{g[i, 1]},{g[i, 2]},{temp[i]}\n".encode() for i in range(n)]


def parse_costs(n):
    lines = make_lines(n)
    rows = {}
    for per_chunk in (100, 10):
        chunks = [b"".join(lines[i:i + per_chunk]) for i in range(0, n, per_chunk)]
        slow_chunks = [b"# m\n" + c for c in chunks]  # a '#' line forces the line-by-line path

        def feed_all(pieces):
            p = LineParser()
            p.feed(HEADER)
            for c in pieces:
                p.feed(c)
            assert p.stats["samples"] == n

        rows[f"LineParser, {per_chunk} lines/chunk, numpy path"] = best_of(lambda: feed_all(chunks)) / n * 1e6
        rows[f"LineParser, {per_chunk} lines/chunk, line-by-line path"] = best_of(lambda: feed_all(slow_chunks)) / n * 1e6
    data = b"".join(lines)

    def naive():
        f = io.BytesIO(data)
        out = []
        while True:
            line = f.readline()
            if not line:
                break
            out.append([float(x) for x in line.decode().strip().split(",")])
        assert len(out) == n

    rows["baseline: BytesIO.readline() + split + float"] = best_of(naive) / n * 1e6
    return rows


def _writer(master, lines, header):
    try:
        if header:
            os.write(master, HEADER)
        data = b"".join(lines)
        view = memoryview(data)
        while view:
            k = os.write(master, view[:4096])
            view = view[k:]
        time.sleep(0.2)
    finally:
        os.close(master)


def _on_pty(lines, read_all):
    """Run ``read_all(port_name) -> lines read`` in a thread while a writer fills the pty.

    Returns (reading thread CPU seconds, lines read)."""
    master, slave = os.openpty()
    tty.setraw(slave)
    name = os.ttyname(slave)
    result = {}

    def reader():
        t0 = time.thread_time()
        result["got"] = read_all(name)
        result["cpu"] = time.thread_time() - t0

    thread = threading.Thread(target=reader)
    thread.start()
    time.sleep(0.3)  # the port is open (and its input flushed) before the data come
    writer = threading.Thread(target=_writer, args=(master, lines, False))
    writer.start()
    writer.join()
    thread.join()
    os.close(slave)
    return result["cpu"], result["got"]


def pty_costs(n):
    import serial

    lines = make_lines(n, temp_c=True)  # the pty sends no header

    def chunked(name):
        src = SerialSource(name, gyro_unit="lsb", lsb_per_dps=131, sample_rate_hz=1000)
        got = 0
        try:
            while True:
                got += len(src.read())
        except SourceEnded:
            pass
        src.close()
        return got

    def naive(name):
        port = serial.Serial(name, 115200, timeout=0.1)
        got = 0
        try:
            while True:
                line = port.readline()
                if line:
                    try:
                        [float(x) for x in line.decode().strip().split(",")]
                        got += 1
                    except ValueError:
                        pass
        except (serial.SerialException, OSError):
            pass
        port.close()
        return got

    rows = {}
    for label, fn in (("SerialSource.read() on a pty (reader thread CPU)", chunked),
                      ("baseline: pyserial readline() + split + float on a pty", naive)):
        cpu, got = _on_pty(lines, fn)
        rows[label] = (cpu / max(got, 1) * 1e6, got)
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lines", type=int, default=20_000, help="lines per measurement")
    args = parser.parse_args([] if argv is None else argv)
    print(f"serial reader: host cost per line ({args.lines} lines of counter,gx,gy,gz,temp; best of 3 for parse-only)")
    print(f"{'approach':<58} {'us/line':>9} {'lines read':>11}")
    for name, us in parse_costs(args.lines).items():
        print(f"{name:<58} {us:9.2f} {args.lines:>11}")
    try:
        for name, (us, got) in pty_costs(args.lines).items():
            print(f"{name:<58} {us:9.2f} {got:>11}")
    except ImportError:
        print("pyserial not installed: end-to-end rows skipped")
    print("  budget at 1 kHz: 1000 us per line")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
