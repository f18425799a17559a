#!/usr/bin/env python3
"""Benchmarks, printed side by side with a baseline in one run.

    python tools/bench.py            # every section
    python tools/bench.py pipeline   # one section (pipeline, reader, allan, mpu6050, serial, simulate, gap, bias_kf)

Pipeline section: streaming ``update()`` and batch ``filter()`` throughput in three-axis samples
per second for the presets "paper" and "recommended" (also in motion) and each Kalman kernel
(numba, Python), the offline smoother ``gyrofilter.smooth`` (batch only), peak memory of ``filter()`` on a 1-hour 100 Hz recording, and the same pipeline
written the plain way (filterpy ``KalmanFilter`` per block plus ``np.polyfit`` per prediction,
``tests/support/plain_filter.py``) as the baseline. Targets on this machine (issue 2): streaming >=
500 000 samples/s, batch >= 5 000 000 samples/s, >= 30x the plain way (numba kernel); the
Python kernel >= 50 000 samples/s. Other sections live in
``tools/bench_<name>.py`` beside this file. Timings are the best of a few repeats.
"""
import importlib
import itertools
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

from gyrofilter import GyroFilter, smooth
from gyrofilter.filter.jit import numba_available


RATE_HZ = 100.0
# the faithful filter and the default (adaptive_kalman), at rest and in motion; the default with
# paper 001's gross-error rule in motion too (the cost of outlier_rule="by_model") and with q fixed
# at rest (the cost of the threshold that follows the blocks' range, outlier_range_k)
PRESETS_BENCHED = (("paper", {}, "rest"), ("recommended", {}, "rest"), ("recommended", {"outlier_range_k": 0}, "rest"),
                   ("recommended", {}, "moving"), ("recommended", {"outlier_rule": "paper"}, "moving"))


def best_of(fn, repeats=3):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def pipeline():
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the test oracle
    from support.plain_filter import plain_filter

    rng = np.random.default_rng(0)
    hour = rng.normal([1.5, -0.7, 3.0], 0.1, (int(3600 * RATE_HZ), 3))
    t = np.arange(len(hour)) / RATE_HZ
    # the same noise plus a 30-deg/s, 1-Hz sine on every axis after the calibration: the adaptive
    # filter then runs its LS model and constancy test on every block (its slowest path)
    moving = hour + np.where(t >= 2.0, 30.0 * np.sin(2 * np.pi * (t - 2.0)), 0.0)[:, None]
    backends = ["numba", "python"] if numba_available() else ["python"]
    n_plain = int(60 * RATE_HZ)
    t_plain = best_of(lambda: plain_filter(hour[:n_plain], RATE_HZ), repeats=1)
    plain_rate = n_plain / t_plain
    print("pipeline (three-axis samples per second; 1 h at 100 Hz = 360 000 samples, input 8.6 MB)")
    print(f"  {'implementation':<52}{'streaming':>12}{'batch':>14}{'batch peak MB':>15}{'vs plain':>10}")

    def row(label, stream_rate, batch_rate, peak):
        stream = f"{stream_rate:>12,.0f}" if stream_rate == stream_rate else f"{'(offline)':>12}"
        print(f"  {label:<52}{stream}{batch_rate:>14,.0f}{peak / 1e6:>15.1f}{batch_rate / plain_rate:>9.0f}x", flush=True)

    def traced_peak(fn):
        tracemalloc.start()
        fn()
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        return peak

    peaks = {}  # the same arrays whatever the kernel: traced once, with the first (fastest) backend
    for (preset, settings, data), backend in itertools.product(PRESETS_BENCHED, backends):
        data = moving if data == "moving" else hour
        stream_in = list(map(tuple, data[:300_000].tolist()))
        make = lambda: GyroFilter(RATE_HZ, preset=preset, backend=backend, **settings)  # noqa: E731
        make().filter(hour[:1000])  # load the compiled kernel once

        def run_stream():
            update = make().update
            for s in stream_in:
                update(s)

        t_stream = best_of(run_stream)
        t_batch = best_of(lambda: make().filter(data))
        rule = "".join({"outlier_rule": ", paper's rule", "outlier_range_k": ", q fixed"}[name] for name in settings)
        label = f"{preset}{rule}{', in motion' if data is moving else ''}"
        if label not in peaks:
            peaks[label] = traced_peak(lambda: make().filter(data))
        peak = peaks[label]
        row(f"{label}, kernel {backend}", len(stream_in) / t_stream, len(data) / t_batch, peak)
        if preset == "recommended" and data is moving and not settings:  # the offline smoother: forward, backward, combination
            t_smooth = best_of(lambda: smooth(data, RATE_HZ, backend=backend))
            if "smooth" not in peaks:
                peaks["smooth"] = traced_peak(lambda: smooth(data, RATE_HZ, backend=backend))
            peak = peaks["smooth"]
            row(f"smooth(), in motion, kernel {backend}", float("nan"), len(data) / t_smooth, peak)
    print(f"  {'plain way (filterpy + np.polyfit)':<52}{'':>12}{plain_rate:>14,.0f}{'':>15}{1:>9.0f}x")
    print("  targets: streaming >= 500,000; batch >= 5,000,000; >= 30x the plain way (numba); Python kernel >= 50,000")


SECTIONS = ["pipeline", "reader", "allan", "mpu6050", "serial", "simulate", "gap", "bias_kf"]


def main(argv):
    chosen = argv or SECTIONS
    for name in chosen:
        if name == "pipeline":
            pipeline()
        else:
            try:
                module = importlib.import_module(f"bench_{name}")
            except ModuleNotFoundError:
                print(f"{name}: tools/bench_{name}.py is not there")
                continue
            module.main([])  # each section with its own defaults
        print()


if __name__ == "__main__":
    main(sys.argv[1:])
