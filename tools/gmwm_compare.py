"""The gap's extended model against a GMWM-style composite fit, on the wavelet variance of real records.

    python tools/gmwm_compare.py [--seed 0] [--sims 4] [--only SUBSTRING]

For the long ADIS16405 records (``../shared/data/adis16405_long``, skipped when absent; licence
CC BY-NC-SA, never copied into the repo) and the static MPU6050 logs (``recordings/``), per axis:
the measured Haar wavelet variance ν̂² (= overlapping AVAR / 2, :mod:`gyrofilter.analysis.noise.gmwm`) and the
weighted distance (1/J) Σ_j (ν̂²_j - ν²_j)² / Var(ν̂²_j) to the curves of

* the gap's baseline (bias + white noise + quantisation) and extended model (``analyse_gap``;
  their curves are the mean over ``--sims`` simulations),
* the five-term Allan NNLS fit (``gyrofilter.analysis.noise.fit``: Q, N, B, K, R),
* the GMWM-style composite fit (``gyrofilter.analysis.noise.gmwm.select_model``).

About 1 means the model is within the sampling error at every dyadic scale. Prints a Markdown table.
"""
from __future__ import annotations

import argparse
import glob
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
ADIS_DIR = os.path.join(os.path.dirname(ROOT), "shared", "data", "adis16405_long")


def recordings(only=None):
    """Paths of the records compared: the ADIS16405 long records (when present), the static MPU6050 logs."""
    paths = sorted(glob.glob(os.path.join(ADIS_DIR, "*.csv.gz")))
    paths += sorted(glob.glob(os.path.join(ROOT, "recordings", "mpu6050_static_*.csv.gz")))
    return [p for p in paths if only is None or only in os.path.basename(p)]


def compare_record(rec, *, seed=0, sims=4, name=None):
    """Rows (one dict per axis) of distances for one recording; numbers only."""
    import numpy as np

    from gyrofilter.analysis.noise import gmwm
    from gyrofilter.analysis.gap.pipeline import analyse_gap
    from gyrofilter.analysis.noise.fit import characterise_axis

    t0 = time.perf_counter()
    rep = analyse_gap(rec, seed=seed, recording_name=name)
    t_gap = time.perf_counter() - t0
    fs = rec.sample_rate_hz
    gyro = rec.gyro_dps
    seeds = tuple(range(1000 + seed, 1000 + seed + sims))
    rows = []
    for i, axis in enumerate("xyz"):
        x = np.asarray(gyro[:, i], dtype=float)
        wv = gmwm.haar_wv(x, fs)
        base = gmwm.simulated_wv(rep["baseline"]["model"], i, x.size, seeds=seeds)
        ext = gmwm.simulated_wv(rep["extended_model"], i, x.size, seeds=seeds)
        t1 = time.perf_counter()
        best, _ = gmwm.select_model(wv, starts=3, seed=seed)
        t_fit = time.perf_counter() - t1
        nnls = characterise_axis(x, fs, axis=axis)
        rows.append({
            "axis": axis, "n": x.size, "fs": fs,
            "d_before": rep["discrepancy"]["before"][axis], "d_after": rep["discrepancy"]["after"][axis],
            "findings": [f["effect"] for f in rep["findings"] if f["axis"] == axis],
            "dist_baseline": gmwm.wv_distance(wv, base.wv_dps2),
            "dist_extended": gmwm.wv_distance(wv, ext.wv_dps2),
            "dist_nnls": gmwm.wv_distance(wv, nnls.model_adev(wv.tau_s) ** 2 / 2.0),
            "dist_gmwm": gmwm.wv_distance(wv, best.wv(wv.tau_s)),
            "gmwm": best, "t_gap_s": t_gap, "t_fit_s": t_fit,
        })
    return rows


def _gm_text(fit):
    gm = ", ".join(f"σ {s:.2g} deg/s, T {t:.3g} s" for s, t in fit.gauss_markov)
    return f"{fit.name}" + (f" ({gm})" if gm else "")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--sims", type=int, default=4, help="simulations per model curve (default 4)")
    p.add_argument("--only", default=None, help="only recordings whose file name contains this")
    args = p.parse_args(argv)

    from gyrofilter.recording import read_recording

    paths = recordings(args.only)
    if not any(ADIS_DIR in path for path in paths) and args.only is None:
        print(f"note: {ADIS_DIR} absent, ADIS16405 records skipped", file=sys.stderr)
    print("| record | axis | gap D before -> after | gap findings | baseline | gap extended | Allan NNLS (QNBKR) "
          "| GMWM-style | GMWM model |")
    print("|---|---|---|---|---|---|---|---|---|")
    for path in paths:
        name = os.path.basename(path).replace(".csv.gz", "")
        rec = read_recording(path)
        for r in compare_record(rec, seed=args.seed, sims=args.sims, name=name):
            print(f"| `{name}` | {r['axis']} | {r['d_before']:.2f} -> {r['d_after']:.2f} | "
                  f"{', '.join(r['findings']) or '-'} | {r['dist_baseline']:.3g} | {r['dist_extended']:.3g} | "
                  f"{r['dist_nnls']:.3g} | {r['dist_gmwm']:.3g} | {_gm_text(r['gmwm'])} |", flush=True)
        print(f"  ({name}: gap {r['t_gap_s']:.0f} s, last GMWM selection {r['t_fit_s']:.1f} s)", file=sys.stderr, flush=True)


if __name__ == "__main__":
    main()
