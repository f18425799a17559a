"""Peak memory and time of the narrow-band detector's Welch PSD on a 24-h 100-Hz axis (8.64 M
samples), side by side with ``scipy.signal.welch`` on the whole series (the baseline it replaced):

    python tools/bench_narrowband_memory.py [--hours 24] [--rate-hz 100]

Prints, per method, the peak traced memory above the input (tracemalloc; MB and in input-array
sizes), the wall-clock seconds, and the largest relative difference of the two PSDs.
"""
from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np


def measure(func):
    """(result, peak MB above what was traced before, seconds) of ``func()``."""
    tracemalloc.start()
    t0 = time.perf_counter()
    out = func()
    seconds = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return out, peak / 1e6, seconds


def main():
    from scipy.signal import welch

    from gyrofilter.analysis.gap.detectors.narrowband import welch_psd

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--hours", type=float, default=24.0)
    p.add_argument("--rate-hz", type=float, default=100.0)
    args = p.parse_args()
    n = int(args.hours * 3600 * args.rate_hz)
    x = np.random.default_rng(1).normal(size=n)
    seg = 8192
    welch_psd(x[:10 * seg], args.rate_hz, seg)  # imports and first calls outside the measurement
    welch(x[:10 * seg], fs=args.rate_hz, nperseg=seg)
    (_, s_new, _), mb_new, t_new = measure(lambda: welch_psd(x, args.rate_hz, seg))
    (_, s_old), mb_old, t_old = measure(lambda: welch(x - x.mean(), fs=args.rate_hz, nperseg=seg))
    input_mb = x.nbytes / 1e6
    print(f"{n} samples ({input_mb:.0f} MB input), segments of {seg}")
    print(f"{'method':<22} {'peak MB':>9} {'input sizes':>12} {'seconds':>8}")
    for name, mb, sec in (("scipy.signal.welch", mb_old, t_old), ("welch_psd (batched)", mb_new, t_new)):
        print(f"{name:<22} {mb:9.1f} {mb / input_mb:12.2f} {sec:8.2f}")
    print(f"largest relative PSD difference: {float(np.max(np.abs(s_new - s_old) / s_old)):.1e}")


if __name__ == "__main__":
    main()
