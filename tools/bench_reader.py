#!/usr/bin/env python3
"""Benchmark of the recording reader and of the commands' memory on long logs, in one run.

    python tools/bench_reader.py [--file REC.csv.gz] [--repeats 3]

1. Peak resident memory (``ru_maxrss`` of the child process, from ``os.wait4``) and wall time of
   ``gyrofilter replay FILE`` (also with ``--smooth``), ``gyrofilter run --source replay:FILE`` and ``gyrofilter allan FILE``
   on the same recording (below), each in a
   fresh process started by a small interpreter, beside the
   same commands on the bundled 100 s recording (the fixed cost: interpreter, numpy, the Kalman
   kernel or scipy). Target: at most 200 MB for 1 h at 1 kHz.
2. Reading a recording (default: 1 h at 1 kHz simulated from gyrofilter/data/mpu6050_model.json,
   3.6 million rows of t, gx, gy, gz, temp; written to a temporary folder, about 20 s), as .csv.gz
   and as plain .csv: ``gyrofilter.recording.read_recording`` (whole arrays, every check) and
   ``iter_recording`` (chunks only) beside ``numpy.loadtxt(path, delimiter=",", skiprows=...)``
   and, when importable, ``pandas.read_csv(path, comment="#")``. Time = best of ``--repeats``.
   Target (issue "The main job as users run it"): the reader at least as fast as numpy.loadtxt.
3. ``gyrofilter allan FILE --json`` end to end (a fresh process: read, check, deviations, fit,
   intervals, JSON) beside the same file through ``numpy.loadtxt`` + ``allantools.oadev`` on the
   three axes at the same cluster times (a fresh process too; deviations only), when allantools
   is installed. The issue's measurement: 1.33x the baseline's time before the chunked reader.
"""
import argparse
import gzip
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
MODEL = os.path.join(HERE, "..", "gyrofilter", "data", "mpu6050_model.json")


def _best(fn, repeats):
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _skiprows(path):
    """Header lines plus the column-name row (what numpy.loadtxt must skip)."""
    from gyrofilter.recording import iter_recording

    chunks = iter_recording(path, chunk_rows=1)
    head = next(chunks)
    next(chunks)
    return head.line_of_row(0) - 1


def _make_file(folder, six_axes=False):
    """1 h at 1 kHz of the default model in ``folder``: its gyro and temperature (the readers' and
    allantools' comparisons: 5 columns), or with ``six_axes`` its accelerometer too."""
    import json

    model = MODEL
    if not six_axes:  # the default model holds an accelerometer: the gyro alone is what the baselines read
        with open(MODEL, encoding="utf-8") as f:
            spec = json.load(f)
        spec.pop("accelerometer", None)
        model = os.path.join(folder, "gyro_only.json")
        with open(model, "w", encoding="utf-8") as f:
            json.dump(spec, f)
    path = os.path.join(folder, "h1k_six.csv.gz" if six_axes else "h1k.csv.gz")
    subprocess.run([sys.executable, "-m", "gyrofilter", "simulate", "--model", model, "--duration", "3600",
                    "--sample-rate-hz", "1000", "--out", path], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return path


def readers(paths, repeats):
    from gyrofilter.recording import iter_recording, read_recording

    def chunks_only(path):
        it = iter_recording(path)
        next(it)
        for _ in it:
            pass

    candidates = [("gyrofilter read_recording", read_recording), ("gyrofilter iter_recording (chunks)", chunks_only)]
    skip = _skiprows(paths[0])
    candidates.append(("numpy.loadtxt", lambda p: np.loadtxt(p, delimiter=",", skiprows=skip)))
    try:
        import pandas as pd
    except ImportError:
        pd = None
    if pd is not None:
        candidates.append((f"pandas {pd.__version__} read_csv", lambda p: pd.read_csv(p, comment="#").to_numpy()))
    first = read_recording(paths[0])
    rows, columns = len(first), len(first.columns)
    del first
    print(f"reading a recording: {rows:,} rows x {columns} columns; time in s, best of {repeats}")
    print(f"  {'reader':<36}" + "".join(f"{os.path.basename(p):>14}" for p in paths))
    times = {}
    for name, fn in candidates:
        times[name] = [_best(lambda p=p: fn(p), repeats) for p in paths]
        print(f"  {name:<36}" + "".join(f"{t:>14.2f}" for t in times[name]))
    ratio = [lt / rr for lt, rr in zip(times["numpy.loadtxt"], times["gyrofilter read_recording"])]
    print("  read_recording vs numpy.loadtxt: " + ", ".join(f"{r:.2f}x as fast ({os.path.basename(p)})" for r, p in zip(ratio, paths)))
    print("  target: read_recording at least as fast as numpy.loadtxt (which checks no line and names none)")


#: run by a small fresh interpreter, so that the measured child is forked from a process whose
#: own memory is tiny (ru_maxrss of a forked child starts at its parent's resident size)
_MEASURE = ("import os, subprocess, sys; p = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL, "
            "stderr=subprocess.DEVNULL); _, s, u = os.wait4(p.pid, 0); print(u.ru_maxrss, os.waitstatus_to_exitcode(s))")


def _peak_of(argv):
    """(peak RSS in MB, wall s, exit code) of a command in a fresh process."""
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", _MEASURE, *argv], capture_output=True, text=True, check=True).stdout
    wall = time.perf_counter() - t0
    kb, code = map(int, out.split())
    return kb / 1024, wall, code


def commands(path, six_axes=None):
    """The memory table: each command on the bundled recording and on ``path`` (1 h at 1 kHz), and
    ``allan`` on ``six_axes`` (the same hour with the accelerometer), when given."""
    from importlib import resources

    bundled = str(resources.files("gyrofilter") / "data" / "mpu6050_static_100s.csv.gz")
    print("peak resident memory of the commands (ru_maxrss of a fresh process)")
    print(f"  {'command':<28}{'recording':<30}{'peak MB':>9}{'wall s':>9}")
    for command, extra in (("replay", []), ("replay", ["--smooth"]), ("run", []), ("allan", [])):
        for label, rec in (("bundled 100 s at 100 Hz", bundled), ("1 h at 1 kHz", path)):
            args = ["--source", f"replay:{rec}", "--quiet"] if command == "run" else [rec, *extra]
            peak, wall, code = _peak_of([sys.executable, "-m", "gyrofilter", command, *args])
            name = " ".join(["gyrofilter", command, *extra])
            print(f"  {name:<28}{label:<30}{peak:>9.0f}{wall:>9.1f}" + ("" if code == 0 else f"  (exit {code})"))
    if six_axes is not None:
        peak, wall, code = _peak_of([sys.executable, "-m", "gyrofilter", "allan", six_axes])
        print(f"  {'gyrofilter allan':<28}{'1 h at 1 kHz, six axes':<30}{peak:>9.0f}{wall:>9.1f}"
              + ("" if code == 0 else f"  (exit {code})"))
    print("  target: at most 200 MB for 1 h at 1 kHz (before the chunked reader: replay 1214 MB, allan 1214 MB);")
    print("  replay --smooth keeps every block of the recording (15 floats per block: 86 MB per hour at 1 kHz)")


#: the baseline of allan_end_to_end: numpy.loadtxt + allantools.oadev per axis, at given cluster times
_ALLANTOOLS = """import sys, json, numpy as np, allantools
path, skip, fs, taus = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), json.loads(sys.argv[4])
x = np.loadtxt(path, delimiter=",", skiprows=skip, usecols=(1, 2, 3))
for a in range(3):
    allantools.oadev(x[:, a], rate=fs, data_type="freq", taus=taus)
"""


def allan_end_to_end(paths, repeats):
    import json

    try:
        import allantools  # noqa: F401
    except ImportError:
        print("allan end to end: allantools is not installed (pip install allantools); skipped")
        return
    from gyrofilter.analysis.noise.allan import cluster_sizes
    from gyrofilter.recording import iter_recording

    print(f"allan end to end, fresh processes, wall s (best of {repeats})")
    print(f"  {'command':<52}" + "".join(f"{os.path.basename(p):>14}" for p in paths))
    ours, base = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for i, path in enumerate(paths):
            chunks = iter_recording(path)
            head = next(chunks)
            rows = sum(len(c) for c in chunks)
            fs = head.sample_rate_hz
            taus = (np.asarray(cluster_sizes(rows, fs)) / fs).tolist()
            out = os.path.join(tmp, f"a{i}.json")
            ours.append(_best(lambda: subprocess.run([sys.executable, "-m", "gyrofilter", "allan", path, "--json", out, "--force"],
                                                     check=True, stdout=subprocess.DEVNULL), repeats))
            base.append(_best(lambda: subprocess.run([sys.executable, "-c", _ALLANTOOLS, path, str(_skiprows(path)), str(fs),
                                                      json.dumps(taus)], check=True), repeats))
    print(f"  {'gyrofilter allan --json (every check, fit, intervals)':<52}" + "".join(f"{t:>14.2f}" for t in ours))
    print(f"  {'numpy.loadtxt + allantools.oadev x 3 (deviations only)':<52}" + "".join(f"{t:>14.2f}" for t in base))
    print("  gyrofilter allan vs the baseline: " + ", ".join(f"{b / o:.2f}x as fast" for o, b in zip(ours, base)))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--file", help="a recording to use (default: simulate 1 h at 1 kHz into a temporary folder)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv if argv is not None else [])
    with tempfile.TemporaryDirectory() as tmp:
        path = args.file or _make_file(tmp)
        plain = os.path.join(tmp, "plain.csv")
        with open(path, "rb") as src, open(plain, "wb") as dst:
            data = src.read()
            dst.write(gzip.decompress(data) if data[:2] == b"\x1f\x8b" else data)
        del data
        commands(path, None if args.file else _make_file(tmp, six_axes=True))
        print()
        readers([path, plain], args.repeats)
        print()
        allan_end_to_end([path, plain], args.repeats)


if __name__ == "__main__":
    main(sys.argv[1:])
