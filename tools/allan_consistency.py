"""How often `gyrofilter allan` says "the noise is not just Q/N/B/K/R": on records that hold only
those noises (false alarms) and on records that hold more (hits).

    python tools/allan_consistency.py [--records 200,100,60] [--hit-records 20] [--jobs 2]

The warning (:func:`gyrofilter.analysis.noise.fit.characterise_axis`, its rule in the module
docstring of :mod:`gyrofilter.analysis.noise.fit`) fires on an axis where fewer than 80 % of the
fitted taus hold the full fit (every term fitted, none dropped) inside their chi-square interval.
Each count is given twice: for that rule ("full fit"), and for the same rule judged on the model
drawn ("model drawn": the terms not resolved dropped), the rule before.

* **False alarms**: the default MPU6050 model (``gyrofilter/data/mpu6050_model.json``) without its
  temperature effect and profile, so white noise, bias instability and the LSB's quantization,
  simulated at 100 Hz for 10, 30 and 120 minutes (``--records`` each, seeds 0, 1, ...); a record
  alarms when any of its three axes warns. The upper bound is the one-sided 95 % Clopper-Pearson
  bound of the rate.
* **Where the 10-minute alarms come from**: at every fitted tau, by its number of clusters, how
  often the true model, the model drawn and the full fit lie below or above the interval (a 95 %
  interval leaves out 2.5 % on either side).
* **Hits**: records where the five terms are really wrong (the examples of ``examples/models/``):
  a 7.3-Hz tone (``sinusoid.json``, axis z), a Gauss-Markov wander of 3 s (``gauss_markov.json``
  with ``tau_s`` 3 s) and of 30 s (as shipped; axis x), a bias warm-up (``warmup.json``, axis x)
  and the default model with its temperature (all axes); ``--hit-records`` each, seeds 1000, 1001,
  ..., rate per axis that holds the effect.
"""
from __future__ import annotations

import argparse
import copy
import math
import os
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from gyrofilter.analysis.noise.fit import MIN_FULL_FIT_CONSISTENCY, characterise
from gyrofilter.analysis.noise.model import model_adev
from gyrofilter.effects import BIAS_INSTABILITY, GAUSS_MARKOV, TEMPERATURE
from gyrofilter.sim.model import load_model
from gyrofilter.sim.simulate import simulate_dps
from gyrofilter.sources.simulated import DEFAULT_MODEL_PATH
from gyrofilter.units import AXES

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SAMPLE_RATE_HZ = 100.0
NULL_DURATIONS_S = (600.0, 1800.0, 7200.0)
HIT_SEED = 1000
#: the cluster counts of the cause table: [low, high)
CLUSTER_BANDS = ((9, 16), (16, 32), (32, 64), (64, 256), (256, None))


def null_model():
    """The default MPU6050 model without its temperature profile and effect."""
    model = load_model(str(DEFAULT_MODEL_PATH))
    model.pop("temperature")
    model.pop("accelerometer", None)  # its temperature coefficients need the profile; the gyro is analysed
    for axis in model["axes"].values():
        axis["effects"] = [e for e in axis["effects"] if e["effect"] != TEMPERATURE]
    return model


def example(name, **changes):
    """``examples/models/NAME.json`` with ``changes`` set in its effects of that name."""
    model = load_model(os.path.join(ROOT, "examples", "models", f"{name}.json"))
    for axis in model["axes"].values():
        for effect in axis["effects"]:
            if effect["effect"] == name:
                effect.update(changes)
    return model


#: (name, model, axes that hold the effect, duration in s)
HITS = (("7.3-Hz tone, 0.03 deg/s", lambda: example("sinusoid"), "z", 600.0),
        ("Gauss-Markov 0.01 deg/s, 3 s", lambda: example(GAUSS_MARKOV, tau_s=3.0), "x", 600.0),
        ("Gauss-Markov 0.01 deg/s, 30 s", lambda: example(GAUSS_MARKOV), "x", 1800.0),
        ("Gauss-Markov 0.01 deg/s, 30 s", lambda: example(GAUSS_MARKOV), "x", 7200.0),
        ("warm-up 0.2 deg/s, 120 s", lambda: example("warmup"), "x", 600.0),
        ("temperature (default model)", lambda: load_model(str(DEFAULT_MODEL_PATH)), AXES, 600.0),
        ("temperature (default model)", lambda: load_model(str(DEFAULT_MODEL_PATH)), AXES, 7200.0))


def outside(values, r):
    """(below, above): bool masks over the fitted taus of the axis result ``r`` where the model of
    ``values`` (Q, N, B, K, R) lies below / above the interval."""
    mod = model_adev(values, r.tau_s)[r.fit_used]
    return mod < r.ci_low[r.fit_used], mod > r.ci_high[r.fit_used]


def true_values(model, axis):
    """(Q, N, B, K, R) of the null model's ``axis``: its ARW and bias instability."""
    ax = model["axes"][axis]
    b = next((e["b_dps"] for e in ax["effects"] if e["effect"] == BIAS_INSTABILITY), 0.0)
    return (0.0, ax["arw_dps_per_sqrt_hz"], b, 0.0, 0.0)


def run_null(job):
    """One null record: per axis (drawn warns, full warns, cause rows or None)."""
    duration_s, seed, cause = job
    model = null_model()
    gyro_dps, _ = simulate_dps(copy.deepcopy(model), duration_s, seed=seed)
    out = []
    for axis, r in characterise(gyro_dps, SAMPLE_RATE_HZ).items():
        rows = None
        if cause:
            k = r.n_clusters[r.fit_used]
            rows = (k, *outside(true_values(model, axis), r), *outside(r.fit_values, r), *outside(r.full_fit_values, r))
        out.append((r.fit_consistency() < MIN_FULL_FIT_CONSISTENCY, r.full_fit_consistency() < MIN_FULL_FIT_CONSISTENCY,
                    rows))
    return out


def run_hit(job):
    """One record of hit case ``index``: (drawn warns, full warns) of each axis that holds the effect."""
    index, seed = job
    _, make, axes, duration_s = HITS[index]
    gyro_dps, _ = simulate_dps(make(), duration_s, seed=seed)
    res = characterise(gyro_dps, SAMPLE_RATE_HZ)
    return [(res[a].fit_consistency() < MIN_FULL_FIT_CONSISTENCY,
             res[a].full_fit_consistency() < MIN_FULL_FIT_CONSISTENCY) for a in axes]


def upper_bound(k, n, level=0.95):
    """One-sided Clopper-Pearson upper bound of a rate with ``k`` events in ``n`` trials: the p
    with P(X <= k | n, p) = 1 - level (bisection on the binomial distribution function)."""
    if k >= n:
        return 1.0
    lo, hi = k / n, 1.0
    for _ in range(60):
        mid = (lo + hi) / 2
        cdf = sum(math.comb(n, i) * mid ** i * (1 - mid) ** (n - i) for i in range(k + 1))
        lo, hi = (mid, hi) if cdf > 1 - level else (lo, mid)
    return hi


def rate(k, n):
    return f"{k:3d}/{n:<3d} = {100 * k / n:4.1f} %"


def cause_table(results):
    """The rows of the where-from table: per cluster band the fractions below / above."""
    lines = [f"{'clusters':>9s} {'taus':>5s}   {'true model':>13s}   {'model drawn':>13s}   {'full fit':>13s}",
             f"{'':>9s} {'':>5s}   {'below  above':>13s}   {'below  above':>13s}   {'below  above':>13s}"]
    rows = [axis[2] for record in results for axis in record]
    k = np.concatenate([r[0] for r in rows])
    masks = [np.concatenate([r[i] for r in rows]) for i in range(1, 7)]
    for low, high in CLUSTER_BANDS:
        sel = (k >= low) & (k < (high or np.inf))
        if not sel.any():
            continue
        band = f"{low}-{high - 1}" if high else f">= {low}"
        cells = "   ".join(f"{100 * masks[i][sel].mean():5.1f}% {100 * masks[i + 1][sel].mean():5.1f}%" for i in (0, 2, 4))
        lines.append(f"{band:>9s} {int(sel.sum()):5d}   {cells}")
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", default="200,100,60",
                        help="null records at 10, 30 and 120 minutes (default 200,100,60)")
    parser.add_argument("--hit-records", type=int, default=20, help="records of each hit case (default 20)")
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    args = parser.parse_args(argv)
    counts = [int(v) for v in args.records.split(",")]
    if len(counts) != len(NULL_DURATIONS_S) or min(counts) < 1 or args.hit_records < 1:
        parser.error("--records takes three counts >= 1 (10, 30, 120 minutes); --hit-records >= 1")
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        null = [list(pool.map(run_null, [(d, s, d == NULL_DURATIONS_S[0]) for s in range(n)]))
                for d, n in zip(NULL_DURATIONS_S, counts)]
        hits = [list(pool.map(run_hit, [(i, HIT_SEED + s) for s in range(args.hit_records)])) for i in range(len(HITS))]
    print("False alarms: the default MPU6050 model without its temperature (white noise, bias instability, "
          "quantization), 100 Hz; records with a warning on any axis (one-sided 95 % upper bound)")
    print(f"{'record':>8s}   {'model drawn (before)':>26s}   {'full fit (the rule)':>36s}")
    for d, results in zip(NULL_DURATIONS_S, null):
        n = len(results)
        drawn = sum(any(a[0] for a in rec) for rec in results)
        full = sum(any(a[1] for a in rec) for rec in results)
        print(f"{d / 60:5.0f} min   {rate(drawn, n):>26s}   {rate(full, n):>20s} (<= {100 * upper_bound(full, n):4.1f} %)")
    print()
    print(f"Where the 10-minute alarms come from: fitted taus outside their 95 % interval, "
          f"{len(null[0])} records x 3 axes")
    print("\n".join(cause_table(null[0])))
    print()
    print(f"Hits: the axes that hold the effect, {args.hit_records} records each (seeds {HIT_SEED}-"
          f"{HIT_SEED + args.hit_records - 1}); axes with a warning")
    print(f"{'case':>30s} {'record':>8s}   {'model drawn (before)':>20s}   {'full fit (the rule)':>20s}")
    for (name, _, _, d), results in zip(HITS, hits):
        axes = [a for rec in results for a in rec]
        print(f"{name:>30s} {d / 60:5.0f} min   {rate(sum(a[0] for a in axes), len(axes)):>20s}   "
              f"{rate(sum(a[1] for a in axes), len(axes)):>20s}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
