"""Gain of the pipeline's temperature compensation (GyroFilter temp_coefficient_dps_per_c).

    python tools/tempcomp_gain.py [--recordings recordings] [--seeds 3]

1. Simulated static MPU6050-like recordings (gyrofilter.sim.simulate: white noise 0.0094
   deg/s/sqrt(Hz), 1/131 deg/s quantisation, 100 Hz) that warm up 25 -> 35 C (tau 600 s,
   MPU6050 temperature resolution 1/340 C) with a bias temperature coefficient of
   (0.02, -0.015, 0.01) deg/s/C, 20 min. GyroFilter (2 s start-up calibration; presets "paper"
   and "recommended") filters each once without and once with temp_coefficient_dps_per_c = c,
   i.e. y = x - c (T - T0), T0 = mean temperature of the calibration window. The truth is
   0 deg/s; we report the output's RMS and its mean over the last 5 min (the residual bias).
2. Real recordings with a temp column: the least-squares coefficient per axis with its
   standard error, and what it would change (c * temperature span) against the noise.
"""
from __future__ import annotations

import argparse
import glob
import os
import sys

import numpy as np

from gyrofilter import GyroFilter
from gyrofilter.recording import read_recording
from gyrofilter.sim.simulate import simulate_dps
from gyrofilter.filter.tempcomp import fit_coefficient

C_DPS_PER_C = (0.02, -0.015, 0.01)
CAL_S = 2.0


def model():
    ax = lambda b, c: {"bias_dps": b, "arw_dps_per_sqrt_hz": 0.0094,  # noqa: E731
                       "effects": [{"effect": "temperature", "coefficient_dps_per_c": c}]}
    return {"sample_rate_hz": 100.0, "gyro_unit": "lsb", "lsb_per_dps": 131.0,
            "temperature": {"start_c": 25.0, "end_c": 35.0, "tau_s": 600.0, "noise_c": 0.02, "resolution_c": 1 / 340},
            "axes": {"x": ax(-3.3, C_DPS_PER_C[0]), "y": ax(1.1, C_DPS_PER_C[1]), "z": ax(-0.5, C_DPS_PER_C[2])}}


def run_pipeline(x, temp, fs, preset, coefficient):
    f = GyroFilter(fs, calibration_s=CAL_S, preset=preset, temp_coefficient_dps_per_c=coefficient)
    y = f.filter(x, temp)
    out_rate = fs / 5.0
    last = y[-int(300 * out_rate):]
    return float(np.sqrt(np.mean(np.sum(y**2, axis=1)))), np.abs(last.mean(axis=0))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--recordings", default="recordings")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--duration-s", type=float, default=1200.0)
    args = ap.parse_args(argv)
    fs = 100.0
    print("### Temperature compensation in the pipeline: simulated warm-up 25 -> 35 C\n")
    print(f"{args.duration_s / 60:.0f} min; coefficient {C_DPS_PER_C} deg/s/C; truth 0 deg/s. Output RMS (norm of 3 axes) and |mean| over the last 5 min per axis (deg/s).\n")
    print("| preset | seed | RMS without | RMS with compensation | gain | last-5-min bias without (x, y, z) | with (x, y, z) |")
    print("|---|---|---|---|---|---|---|")
    for preset in ("paper", "recommended"):
        gains = []
        for seed in range(args.seeds):
            x, temp = simulate_dps(model(), args.duration_s, seed=seed)
            rms_raw, bias_raw = run_pipeline(x, temp, fs, preset, 0.0)
            rms_comp, bias_comp = run_pipeline(x, temp, fs, preset, C_DPS_PER_C)
            gains.append(rms_raw / rms_comp)
            print(f"| {preset} | {seed} | {rms_raw:.4f} | {rms_comp:.4f} | {rms_raw / rms_comp:.1f}x | "
                  + ", ".join(f"{v:.4f}" for v in bias_raw) + " | " + ", ".join(f"{v:.4f}" for v in bias_comp) + " |")
        print(f"| {preset} | mean gain | | | {np.mean(gains):.1f}x | | |")
    print()

    print("### Real MPU6050 recordings with a temp column\n")
    print("| recording | temp span (C) | c x, y, z (deg/s/C) +- 1 s.e. | c * span vs per-sample noise |")
    print("|---|---|---|---|")
    for p in sorted(glob.glob(os.path.join(args.recordings, "mpu6050_static_*.csv.gz"))):
        rec = read_recording(p)
        if rec.temp_c is None:
            continue
        g = rec.gyro_dps
        span = float(np.ptp(rec.temp_c))
        try:
            c, se = fit_coefficient(g, rec.temp_c)
        except ValueError as exc:
            print(f"| {os.path.basename(p)} | {span:.2f} | {exc} | - |")
            continue
        eff = ", ".join(f"{abs(ci) * span:.4f}/{g[:, i].std():.3f}" for i, ci in enumerate(c))
        print(f"| {os.path.basename(p)} | {span:.2f} | " + ", ".join(f"{ci:+.4f} +- {si:.4f}" for ci, si in zip(c, se)) + f" | {eff} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
