#!/usr/bin/env python3
"""Benchmark of the bias-augmented Kalman filter (gyrofilter.analysis.arma.bias_kf): samples per second.

    python tools/bench_bias_kf.py

Scalar per-axis kernel (the default) against the same model run through filterpy's
KalmanFilter (``engine="filterpy"``, the baseline and the tests' oracle), on 20 s of simulated
100 Hz data with rest and motion. Best of 3 repeats. The live budget at 100 Hz is 10 ms per
sample; a Raspberry Pi is roughly 5-10x slower than this machine.
"""

import numpy as np

from gyrofilter.analysis.arma.bias_kf import BiasKalmanFilter

from bench import best_of  # tools/bench.py, beside this file

FS = 100.0


def data(n=2000, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    x = np.array([1.0, -0.5, 0.3]) + rng.normal(0, 0.1, (n, 3))
    x[n // 2 :] += 40 * np.sin(2 * np.pi * 0.5 * t[n // 2 :])[:, None]
    return x


def main(argv=None):  # no options; argv for tools/bench.py
    x = data()
    rows = []
    for engine in ("numpy", "filterpy"):
        batch = best_of(lambda: BiasKalmanFilter(FS, engine=engine).run(x))

        def stream():
            f = BiasKalmanFilter(FS, engine=engine)
            for s in x:
                f.update(s)

        streaming = best_of(stream)
        rows.append((engine, len(x) / batch, len(x) / streaming))
    print("bias_kf: 3-axis samples per second (best of 3, 2000 samples)")
    print(f"  {'kernel':<38}{'run() batch':>14}{'update() stream':>18}")
    for name, b, s in rows:
        label = "scalar kernel (default)" if name == "numpy" else "filterpy KalmanFilter x3 (baseline)"
        print(f"  {label:<38}{b:14.0f}{s:18.0f}")
    print(f"  speed-up over filterpy: {rows[0][1] / rows[1][1]:.1f}x batch, {rows[0][2] / rows[1][2]:.1f}x streaming")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
