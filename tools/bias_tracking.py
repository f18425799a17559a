"""Bias tracking of the bias-augmented Kalman filter (paper 003) against start-up-only calibration.

    python tools/bias_tracking.py [--recordings recordings] [--figure docs/figures/bias_tracking.png] [--quick]

1. BROAD trials (recordings/broad_*.csv.gz, real IMU + optical reference; CC BY 4.0, Laidig et
   al. 2021): the true bias of each rest phase is the mean gyro over that phase (the sensor is
   still; the optical reference confirms it). For every rest phase after the first we compare
   the start-up calibration (first 2 s) and the filter's estimate at the *start* of the phase
   (before it has seen that rest: a prediction) and at its end. Also the RMSE of the rate output
   against the optical reference rate, in motion and at rest.
2. Simulated long recordings (gyrofilter.sim.simulate, MPU6050-like white noise 0.1 deg/s per
   sample at 100 Hz) whose bias drifts: warm-up 25 -> 35 C with 0.02 deg/s/C, a bias random walk
   (K = 0.002 deg/s/sqrt(s)) and a 0.15 deg/s bias step, plus hand-like motion with rest breaks.
   The true bias is the same model simulated without white noise (the simulator's per-term
   random streams make the terms identical). RMS bias error over time.

Prints a markdown table and draws the figure.
"""
from __future__ import annotations

import argparse
import glob
import math
import os
import sys
import time

import numpy as np

from gyrofilter.analysis.arma.bias_kf import BiasKalmanFilter, BiasKFSettings
from gyrofilter.recording import read_recording
from gyrofilter.sim.simulate import simulate_dps

CAL_S = 2.0
RMSE_BLOCK_S = 0.1
SIM_FS = 100.0


def arma_settings(x_rest_dps, fs, fallback: BiasKFSettings):
    """Settings whose bias model is the ARMA(1, 1) of a still stretch (paper 003 via gyrofilter.analysis.arma.identify).

    Per axis; an axis whose ARMA(1, 1) has no Gauss-Markov decomposition keeps the fallback's model;
    one whose fitted tau the stretch does not determine (longer than 0.2 x the stretch,
    ``identify.bias_model_within_record``) is the random walk the stretch does determine (tau inf).
    Returns (settings, description).
    """
    from gyrofilter.analysis.arma import identify as arma
    from gyrofilter.analysis.arma import fit as arma_fit

    taus, sigmas, walks, desc = [], [], [], []
    for i, name in enumerate("xyz"):
        x = x_rest_dps[:, i] - x_rest_dps[:, i].mean()
        fit = arma_fit.fit_arma(x, 1, 1)
        m = arma.bias_model_from_arma11(fit, fs, record_s=len(x) / fs)
        if m.valid:
            taus.append(m.tau_s)
            sigmas.append(0.0 if math.isinf(m.bias_sigma_dps) else m.bias_sigma_dps)
            walks.append(m.bias_walk_dps_per_sqrt_s)
            tau = f"tau {m.tau_s:.3g} s" if m.tau_determined else f"tau not determined in {len(x) / fs:.0f} s: random walk"
            desc.append(f"{name}: phi {fit.phi[0]:.5f}, theta {fit.theta[0]:.5f} -> {tau}, drive {m.bias_walk_dps_per_sqrt_s:.2g} deg/s/sqrt(s)")
        else:
            taus.append(fallback.bias_tau_s)
            sigmas.append(fallback.bias_sigma_dps)
            walks.append(fallback.bias_walk_dps_per_sqrt_s)
            desc.append(f"{name}: phi {fit.phi[0]:.4f}, theta {fit.theta[0]:.4f}: no bias model, default kept")
    s = BiasKFSettings(bias_tau_s=tuple(taus), bias_sigma_dps=tuple(sigmas), bias_walk_dps_per_sqrt_s=tuple(walks))
    return s, "; ".join(desc)


def rest_phases(movement):
    """(start, end) index pairs of movement == 0 runs."""
    m = np.asarray(movement) > 0.5
    edges = np.flatnonzero(np.diff(np.r_[1, m.astype(int), 1]))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2])]


def broad_trial(path, settings):
    rec = read_recording(path)
    fs = rec.sample_rate_hz
    gyro = rec.gyro_dps
    from gyrofilter.evaluation.reference import reference_from_recording

    ref = reference_from_recording(rec)
    n_cal = int(round(CAL_S * fs))
    t0 = time.perf_counter()
    tr = BiasKalmanFilter(fs, settings, calibration_s=CAL_S).run(gyro)
    cost_us = (time.perf_counter() - t0) / len(gyro) * 1e6
    b_cal = np.asarray(tr.calibration.bias_dps)
    phases = [p for p in rest_phases(rec.columns["movement"]) if p[1] - p[0] > fs]  # >= 1 s
    # the same filter with the bias model identified (ARMA(1, 1)) on the trial's first rest phase
    a0, e0 = phases[0]
    arma_s, arma_desc = arma_settings(gyro[a0:e0], fs, settings)
    tr_arma = BiasKalmanFilter(fs, arma_s, calibration_s=CAL_S).run(gyro)
    rows = []
    for k, (a, b) in enumerate(phases[1:], start=2):
        truth = gyro[a:b].mean(axis=0)
        i_start = max(a - n_cal, 0)
        i_end = b - 1 - n_cal
        rows.append({
            "phase": k, "t_s": a / fs, "duration_s": (b - a) / fs,
            "startup": float(np.linalg.norm(b_cal - truth)),
            "kf_start": float(np.linalg.norm(tr.bias_dps[i_start] - truth)),
            "kf_end": float(np.linalg.norm(tr.bias_dps[i_end] - truth)),
            "arma_start": float(np.linalg.norm(tr_arma.bias_dps[i_start] - truth)),
            "arma_end": float(np.linalg.norm(tr_arma.bias_dps[i_end] - truth)),
        })
    # rate RMSE against the optical reference, on 0.1 s block means (the differentiated optical
    # reference is too noisy sample by sample); blocks with an occluded row are skipped
    from gyrofilter.evaluation.reference import block_mean_masked

    L = max(1, int(round(RMSE_BLOCK_S * fs)))
    r = block_mean_masked(ref[n_cal:], L)
    moving = block_mean_masked(np.asarray(rec.columns["movement"][n_cal:], float), L) > 0.5
    valid = np.all(np.isfinite(r), axis=1)
    out = {}
    for name, y in (("startup", gyro[n_cal:] - b_cal), ("kf", tr.rate_dps)):
        yb = block_mean_masked(y, L)
        for label, mask in (("motion", valid & moving), ("rest", valid & ~moving)):
            out[f"{name}_{label}"] = float(np.sqrt(np.mean(np.sum((yb[mask] - r[mask]) ** 2, axis=1))))
    return {"name": os.path.basename(path).replace(".csv.gz", ""), "fs": fs, "rows": rows, "rmse": out,
            "trace": tr, "phases": phases, "gyro": gyro, "n_cal": n_cal, "cost_us": cost_us, "arma_desc": arma_desc}


def motion_profile(n, fs, rng, motion_s, rest_s, start_rest_s=10.0):
    """Hand-like motion (sum of 3 random sines per axis, 20-60 deg/s) in bursts separated by rests."""
    t = np.arange(n) / fs
    rate = np.zeros((n, 3))
    period = motion_s + rest_s
    phase_t = (t - start_rest_s) % period
    moving = (t >= start_rest_s) & (phase_t < motion_s)
    for axis in range(3):
        for _ in range(3):
            f = rng.uniform(0.1, 1.5)
            rate[:, axis] += rng.uniform(20, 60) / 3 * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
    # smooth on/off so that every burst starts and ends at rest
    env = np.zeros(n)
    env[moving] = np.sin(np.pi * phase_t[moving] / motion_s) ** 0.5
    return rate * env[:, None], moving


def sim_model(arw):
    axis = lambda b: {"bias_dps": b, "arw_dps_per_sqrt_hz": arw, "effects": [  # noqa: E731
        {"effect": "temperature", "coefficient_dps_per_c": 0.02},
        {"effect": "rate_random_walk", "k_dps_per_sqrt_s": 0.002},
        {"effect": "bias_step", "time_s": 700.0, "size_dps": 0.15}]}
    return {"sample_rate_hz": SIM_FS, "gyro_unit": "dps",
            "temperature": {"start_c": 25.0, "end_c": 35.0, "tau_s": 400.0, "noise_c": 0.02, "resolution_c": 1 / 340},
            "axes": {"x": axis(-3.3), "y": axis(1.1), "z": axis(-0.5)}}


def simulated_run(seed, duration_s, motion_s, rest_s, settings, arma_s=None):
    noisy, _ = simulate_dps(sim_model(0.01), duration_s, seed=seed)
    bias, _ = simulate_dps(sim_model(0.0), duration_s, seed=seed)
    n = len(noisy)
    rate, moving = motion_profile(n, SIM_FS, np.random.default_rng(1000 + seed), motion_s, rest_s)
    x = noisy + rate
    n_cal = int(CAL_S * SIM_FS)
    tr = BiasKalmanFilter(SIM_FS, settings, calibration_s=CAL_S).run(x)
    truth = bias[n_cal:]
    err_kf = np.linalg.norm(tr.bias_dps - truth, axis=1)
    err_su = np.linalg.norm(np.asarray(tr.calibration.bias_dps) - truth, axis=1)
    rate_err_kf = np.sqrt(np.mean(np.sum((tr.rate_dps - rate[n_cal:]) ** 2, axis=1)))
    rate_err_su = np.sqrt(np.mean(np.sum((x[n_cal:] - np.asarray(tr.calibration.bias_dps) - rate[n_cal:]) ** 2, axis=1)))
    err_arma = None
    if arma_s is not None:
        tr_a = BiasKalmanFilter(SIM_FS, arma_s, calibration_s=CAL_S).run(x)
        err_arma = np.linalg.norm(tr_a.bias_dps - truth, axis=1)
    return {"seed": seed, "err_arma": err_arma, "t_s": np.arange(n_cal, n) / SIM_FS, "err_kf": err_kf, "err_su": err_su,
            "still": tr.still, "moving": moving[n_cal:], "rate_kf": rate_err_kf, "rate_su": rate_err_su}


def rms(a):
    return float(np.sqrt(np.mean(np.square(a))))


def plot(path, sims, broad):
    from gyrofilter.plots import pyplot

    plt = pyplot()

    fig, axes = plt.subplots(2, 1, figsize=(10, 7.5))
    ax = axes[0]
    s = sims[0]
    step = 20
    ax.plot(s["t_s"][::step], s["err_su"][::step], color="tab:red", lw=1, label="start-up calibration only")
    ax.plot(s["t_s"][::step], s["err_kf"][::step], color="tab:blue", lw=1, label="bias-augmented KF, default bias model (random walk 0.002 deg/s/sqrt(s))")
    if s["err_arma"] is not None:
        ax.plot(s["t_s"][::step], s["err_arma"][::step], color="tab:orange", lw=1, label="same KF, bias model from the ARMA(1,1) of a real static MPU6050 log")
    ax.set_ylabel("|bias error| (deg/s)")
    ax.set_xlabel("time (s)")
    ax.set_title(f"simulated {s['t_s'][-1] / 60:.0f}-min recording: warm-up 25->35 C (0.02 deg/s/C), bias random walk, 0.15 deg/s step at 700 s; rests between motion bursts", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    ax = axes[1]
    b = next((r for r in broad if "09" in r["name"]), broad[0] if broad else None)
    if b is not None:
        fs = b["fs"]
        tt = (np.arange(len(b["trace"].bias_dps)) + b["n_cal"]) / fs
        colors = ("tab:red", "tab:green", "tab:blue")
        for i, name in enumerate("xyz"):
            ax.plot(tt[::10], b["trace"].bias_dps[::10, i] * 1000 / 57.29577951308232, color=colors[i], lw=1, label=f"KF bias {name}")
            ax.axhline(b["trace"].calibration.bias_dps[i] * 1000 / 57.29577951308232, color=colors[i], ls=":", lw=1)
            for a, e in b["phases"]:
                ax.plot([a / fs, e / fs], [b["gyro"][a:e, i].mean() * 1000 / 57.29577951308232] * 2, color=colors[i], lw=4, alpha=0.4)
        ax.set_ylabel("bias (mrad/s)")
        ax.set_xlabel("time (s)")
        ax.set_title(f"BROAD {b['name']}: KF bias (lines), start-up calibration (dotted), rest-phase means (thick)", fontsize=9)
        ax.legend(fontsize=8, ncol=3)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--recordings", default="recordings")
    ap.add_argument("--figure", default="docs/figures/bias_tracking.png")
    ap.add_argument("--quick", action="store_true", help="one short simulation, for a smoke run")
    args = ap.parse_args(argv)
    settings = BiasKFSettings()

    print("## Bias tracking: bias-augmented Kalman filter vs start-up calibration only\n")
    print(f"Filter settings: {settings}\n")
    broad = []
    paths = sorted(glob.glob(os.path.join(args.recordings, "broad_*.csv.gz")))
    if paths:
        print("### BROAD trials (real IMU, optical reference)\n")
        print("Bias error |b_est - b_rest| (norm over 3 axes, mrad/s) at each rest phase after the first; "
              "b_rest = mean gyro over that rest phase. KF at start = before it has seen that rest.\n")
        print("| trial | rest phase | starts at (s) | length (s) | start-up only | KF at start of rest | KF at end of rest | KF-ARMA at start | KF-ARMA at end |")
        print("|---|---|---|---|---|---|---|---|---|")
        to_mrad = 1000 / 57.29577951308232
        for p in paths:
            r = broad_trial(p, settings)
            broad.append(r)
            for row in r["rows"]:
                print(f"| {r['name']} | {row['phase']} | {row['t_s']:.1f} | {row['duration_s']:.1f} | {row['startup'] * to_mrad:.3f} | "
                      f"{row['kf_start'] * to_mrad:.3f} | {row['kf_end'] * to_mrad:.3f} | {row['arma_start'] * to_mrad:.3f} | {row['arma_end'] * to_mrad:.3f} |")
        tot = lambda key: math.sqrt(np.mean([row[key] ** 2 for r in broad for row in r["rows"]])) * to_mrad  # noqa: E731
        print(f"| **RMS over all rest phases** | | | | {tot('startup'):.3f} | {tot('kf_start'):.3f} | {tot('kf_end'):.3f} | {tot('arma_start'):.3f} | {tot('arma_end'):.3f} |")
        print("\nKF-ARMA: bias model from the ARMA(1, 1) of each trial's first rest phase (gyrofilter.analysis.arma.identify):\n")
        for r in broad:
            print(f"- {r['name']}: {r['arma_desc']}")
        print("\nRate RMSE against the optical reference (deg/s, norm over 3 axes, on 0.1 s block means; blocks with occlusion skipped):\n")
        print("| trial | raw - start-up bias, motion | KF rate, motion | raw - start-up bias, rest | KF rate, rest | KF cost (us/sample, this machine) |")
        print("|---|---|---|---|---|---|")
        for r in broad:
            m = r["rmse"]
            print(f"| {r['name']} | {m['startup_motion']:.3f} | {m['kf_motion']:.3f} | {m['startup_rest']:.3f} | {m['kf_rest']:.3f} | {r['cost_us']:.0f} |")
    else:
        print(f"(no BROAD recordings in {args.recordings})")

    print("\n### Simulated long recordings with bias drift\n")
    scenarios = [("rest 20 s every 60 s", 40.0, 20.0), ("rest 10 s every 5 min", 290.0, 10.0)]
    duration = 300.0 if args.quick else 1200.0
    seeds = [0] if args.quick else [0, 1]
    sims = []
    static_path = os.path.join(args.recordings, "mpu6050_static_449s.csv.gz")
    arma_s, arma_desc = None, ""
    if os.path.exists(static_path):
        st = read_recording(static_path)
        arma_s, arma_desc = arma_settings(st.gyro_dps, st.sample_rate_hz, settings)
    print(f"{duration / 60:.0f} min at {SIM_FS:g} Hz; |bias error| norm over 3 axes (deg/s), after the 2 s calibration. "
          "KF-ARMA: bias model from the ARMA(1, 1) of the real recording mpu6050_static_449s "
          f"({arma_desc or 'not available'}).\n")
    print("| scenario | seed | start-up only: RMS | KF: RMS | KF-ARMA: RMS | start-up only: last 5 min | KF: last 5 min | KF max | rate RMSE raw-startup / KF (deg/s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for label, motion_s, rest_s in scenarios:
        for seed in seeds:
            s = simulated_run(seed, duration, motion_s, rest_s, settings, arma_s)
            sims.append(s)
            last = s["t_s"] >= s["t_s"][-1] - 300
            ea = "-" if s["err_arma"] is None else f"{rms(s['err_arma']):.4f}"
            print(f"| {label} | {seed} | {rms(s['err_su']):.4f} | {rms(s['err_kf']):.4f} | {ea} | {rms(s['err_su'][last]):.4f} | "
                  f"{rms(s['err_kf'][last]):.4f} | {s['err_kf'].max():.4f} | {s['rate_su']:.3f} / {s['rate_kf']:.3f} |")
            if args.quick:
                break
    plot(args.figure, sims, broad)
    print(f"\nfigure: {args.figure}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
