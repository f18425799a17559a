#!/usr/bin/env python3
"""Benchmark of the Allan analysis, printed beside allantools in one run.

    python tools/bench_allan.py [--samples 10000000] [--skip-day]

1. Overlapping Allan deviation of the same 10 million samples at the same taus (the default
   grid: ~10 per decade, 1 sample .. N/9, 59 taus): ``gyrofilter.analysis.noise.allan.overlapping_adev``
   against ``allantools.oadev(x, rate, data_type="freq", taus=...)``. Time = best of 2 runs;
   peak memory = ``tracemalloc`` peak of one call (numpy reports its buffers to tracemalloc),
   also as a multiple of the input array (80 MB). The largest relative difference of the two
   results is printed as a check. Targets (issue 4): >= 2x faster, peak < 3x the input.
2. A 24-hour 100 Hz three-axis recording (8.64 million samples per axis, white noise + rate
   random walk + bias): ``gyrofilter.analysis.noise.fit.characterise`` (deviation, EDF intervals, NNLS
   fit with covariance, read-offs) wall time. Target: well under a minute.
3. With ``--day-file``: the same day written as an MPU6050-style .csv.gz recording (lsb) and the
   command ``gyrofilter allan FILE --json OUT`` timed end to end in a fresh process (reading the
   file included). Writing the file takes a few minutes, so this is off by default.
"""
import argparse
import time
import tracemalloc

import numpy as np


def _best(fn, repeats=2):
    best, out = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def _peak(fn):
    tracemalloc.start()
    tracemalloc.reset_peak()
    fn()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def oadev_vs_allantools(n_samples):
    import allantools

    from gyrofilter.analysis.noise.allan import overlapping_adev

    fs = 100.0
    rng = np.random.default_rng(0)
    x = -3.3 + rng.normal(0.0, 0.1, n_samples) + np.cumsum(rng.normal(0.0, 1e-5, n_samples))
    t_ours, (tau, ours) = _best(lambda: overlapping_adev(x, fs))
    t_ref, ref = _best(lambda: allantools.oadev(x, rate=fs, data_type="freq", taus=tau))
    assert np.array_equal(ref[0], tau)
    diff = float(np.max(np.abs(ours / ref[1] - 1.0)))
    m_ours = _peak(lambda: overlapping_adev(x, fs))
    m_ref = _peak(lambda: allantools.oadev(x, rate=fs, data_type="freq", taus=tau))
    mb = x.nbytes / 1e6
    print(f"overlapping Allan deviation: {n_samples:,} samples (input {mb:.0f} MB), {tau.size} taus "
          f"{tau[0]:g} .. {tau[-1]:g} s")
    print(f"  {'implementation':<44}{'time s':>9}{'peak MB':>10}{'peak/input':>12}  (tracemalloc: memory allocated during the call)")
    print(f"  {'gyrofilter.analysis.noise.allan.overlapping_adev':<44}{t_ours:>9.2f}{m_ours / 1e6:>10.0f}{m_ours / x.nbytes:>11.2f}x")
    print(f"  {'allantools ' + allantools.__version__ + ' oadev(data_type=freq)':<44}{t_ref:>9.2f}{m_ref / 1e6:>10.0f}"
          f"{m_ref / x.nbytes:>11.2f}x")
    print(f"  ratio: {t_ref / t_ours:.1f}x faster, {m_ref / max(m_ours, 1):.1f}x less peak memory; "
          f"max relative difference {diff:.1e}")
    print("  targets: >= 2x faster than allantools; peak < 3x the input array")


def day_characterisation():
    from gyrofilter.analysis.noise.fit import characterise
    from gyrofilter.analysis.noise.model import ANGLE_RANDOM_WALK
    from gyrofilter.effects import RATE_RANDOM_WALK

    fs, n = 100.0, 24 * 3600 * 100
    rng = np.random.default_rng(1)
    g = np.empty((n, 3))
    for a, (bias, arw, k) in enumerate([(-3.3, 0.008, 1e-4), (1.1, 0.010, 2e-4), (-0.5, 0.009, 5e-5)]):
        g[:, a] = bias + rng.normal(0.0, arw * np.sqrt(fs), n) + np.cumsum(rng.normal(0.0, k / np.sqrt(fs), n))
    t0 = time.perf_counter()
    res = characterise(g, fs)
    dt = time.perf_counter() - t0
    print(f"24 h at 100 Hz, three axes ({n:,} samples per axis): characterise() in {dt:.1f} s "
          f"(target: well under 60 s)")
    for name, r in res.items():
        n_c, k_c = r.fitted[ANGLE_RANDOM_WALK], r.fitted[RATE_RANDOM_WALK]
        k_text = "not resolved" if k_c.value is None else f"{k_c.value:.3g} [{k_c.low:.3g}, {k_c.high:.3g}]"
        print(f"  {name}: {r.tau_s.size} taus, N = {n_c.value:.4g} [{n_c.low:.4g}, {n_c.high:.4g}] deg/sqrt(s), "
              f"K = {k_text} deg/s/sqrt(s)")
    print("  (simulated: N = 0.008, 0.010, 0.009 deg/sqrt(s); K = 1e-4, 2e-4, 5e-5 deg/s/sqrt(s))")


def day_file_command():
    import os
    import subprocess
    import sys
    import tempfile

    from gyrofilter.recording import Recording, write_recording

    fs, n = 100.0, 24 * 3600 * 100
    rng = np.random.default_rng(2)
    g = np.array([-3.3, 1.1, -0.5]) + rng.normal(0.0, 0.09, (n, 3))
    g += np.cumsum(rng.normal(0.0, 1e-4 / np.sqrt(fs), (n, 3)), axis=0)
    raw = np.round(g * 131.0)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "day.csv.gz")
        rec = Recording(columns={"gx": raw[:, 0], "gy": raw[:, 1], "gz": raw[:, 2]},
                        header={"gyrofilter-recording": "1", "sample_rate_hz": "100", "gyro_unit": "lsb",
                                "lsb_per_dps": "131", "sensor": "simulated"})
        write_recording(path, rec)
        size = os.path.getsize(path)
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "gyrofilter", "allan", path, "--json", os.path.join(tmp, "out.json")],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        dt = time.perf_counter() - t0
    print(f"`gyrofilter allan` on a 24 h 100 Hz lsb recording ({size / 1e6:.0f} MB .csv.gz), end to end "
          f"in a new process: {dt:.1f} s (target: well under 60 s)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=10_000_000)
    parser.add_argument("--skip-day", action="store_true", help="skip the 24-hour characterisation")
    parser.add_argument("--day-file", action="store_true", help="also time the command on a 24-hour .csv.gz file")
    args = parser.parse_args(argv if argv is not None else [])
    oadev_vs_allantools(args.samples)
    if not args.skip_day:
        day_characterisation()
    if args.day_file:
        day_file_command()


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
