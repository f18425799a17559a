"""Paper 003's ARMA analysis on the real static MPU6050 recordings, and ARMA vs Allan model.

    python tools/arma_report.py [--recordings recordings] [--json docs/arma_results.json] [--seeds 3]

For every static recording (recordings/mpu6050_static_*.csv.gz) and axis: the ADF statistic,
normality verdicts (KS raw and with one LSB of dither, JB), the Pandit-Wu order, the chosen
model and the ARMA(1, 1) next to paper 003's x_t - 1.0000 x_{t-1} = a_t - 0.9994 a_{t-1}.

Then which model reproduces the measured overlapping Allan deviation better: the chosen ARMA
and the ARMA(1, 1), simulated (same length and rate, several seeds, RMS of the deviations), and
the Allan-based noise model (gyrofilter.noise_model fit: Q/N/B/K/R), simulated through
gyrofilter.simulate (white noise N, bias instability B, rate random walk K, rate ramp R,
quantisation 1/131 deg/s) over the same seeds. Discrepancy = RMS over tau of
log10(model ADEV / measured ADEV) (0.01 ~ 2.3 % off).
"""
from __future__ import annotations

import argparse
import glob
import json
import math
import os
import sys

import numpy as np

from gyrofilter import arma
from gyrofilter.allan import overlapping_adev
from gyrofilter.noise_model import characterise_axis
from gyrofilter.recording import read_recording
from gyrofilter.simulate import simulate_dps


def allan_model_adev(x, fs, lsb_per_dps, seeds, tau):
    """Mean ADEV of the Allan-fitted five-term model, simulated like the recording."""
    res = characterise_axis(x, fs)
    f = res.fitted
    val = lambda t: f[t].value or 0.0  # noqa: E731
    effects = []
    if val("bias_instability") > 0:
        effects.append({"effect": "bias_instability", "b_dps": val("bias_instability")})
    if val("rrw") > 0:
        effects.append({"effect": "rate_random_walk", "k_dps_per_sqrt_s": val("rrw")})
    if val("rate_ramp") > 0:
        effects.append({"effect": "rate_ramp", "r_dps_per_s": val("rate_ramp")})
    model = {"sample_rate_hz": fs, "gyro_unit": "dps",
             "axes": {a: {"bias_dps": 0.0, "arw_dps_per_sqrt_hz": val("arw"), "effects": effects if a == "x" else []} for a in "xyz"}}
    if lsb_per_dps:
        model["gyro_unit"] = "lsb"
        model["lsb_per_dps"] = lsb_per_dps
    curves = []
    for s in seeds:
        sim, _ = simulate_dps(model, len(x) / fs, seed=s)
        sim = sim[: len(x), 0]
        curves.append(overlapping_adev(sim - sim.mean(), fs, tau)[1])
    terms = {t: f[t].value for t in ("quantization", "arw", "bias_instability", "rrw", "rate_ramp")}
    return np.sqrt(np.mean(np.square(curves), axis=0)), terms, model


def dominant_root(fit, fs):
    """The AR root nearest the unit circle: (modulus, frequency Hz)."""
    if not fit.phi:
        return None
    roots = np.roots(np.r_[1.0, -np.asarray(fit.phi)])
    r = roots[np.argmax(np.abs(roots))]
    return float(abs(r)), float(abs(np.angle(r)) / (2 * math.pi) * fs)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--recordings", default="recordings")
    ap.add_argument("--json", default=None, help="write all numbers here")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--max-n", type=int, default=4)
    args = ap.parse_args(argv)
    seeds = list(range(args.seeds))
    paths = sorted(glob.glob(os.path.join(args.recordings, "mpu6050_static_*.csv.gz")))
    if not paths:
        print(f"no static recordings in {args.recordings}", file=sys.stderr)
        return 1
    results = []
    for p in paths:
        rec = read_recording(p)
        fs = rec.sample_rate_hz
        g = rec.gyro_dps
        q = 1.0 / rec.lsb_per_dps if rec.lsb_per_dps else None
        for i, ax in enumerate("xyz"):
            print(f"{os.path.basename(p)} axis {ax} ...", file=sys.stderr, flush=True)
            x = g[:, i]
            rep = arma.analyze_axis(x, fs, axis=ax, max_n=args.max_n, quantum_dps=q)
            xs = x - x.mean()
            tau, measured = overlapping_adev(xs, fs)
            _, adev_chosen = arma.arma_adev(rep.chosen, len(xs), fs, seeds=seeds, taus_s=tau)
            _, adev_11 = arma.arma_adev(rep.arma11, len(xs), fs, seeds=seeds, taus_s=tau)
            adev_allan, terms, _ = allan_model_adev(xs, fs, rec.lsb_per_dps, seeds, tau)
            results.append({
                "recording": os.path.basename(p), "axis": ax, "n": len(x), "fs": fs,
                "report": rep.to_dict(),
                "root": dominant_root(rep.chosen, fs),
                "adev": {"tau_s": tau.tolist(), "measured": measured.tolist(), "arma_chosen": adev_chosen.tolist(),
                         "arma11": adev_11.tolist(), "allan_model": adev_allan.tolist()},
                "discrepancy": {"arma_chosen": arma.adev_discrepancy(measured, adev_chosen),
                                "arma11": arma.adev_discrepancy(measured, adev_11),
                                "allan_model": arma.adev_discrepancy(measured, adev_allan)},
                "allan_terms": terms,
            })

    print("### Paper 003's tests and Pandit-Wu order on the static MPU6050 recordings\n")
    print("| recording | axis | N | ADF (5 % crit. -2.86) | KS raw / dithered | JB | Pandit-Wu: adequate -> chosen | residuals white (Ljung-Box p) | ARMA(1,1) | bias model from ARMA(1,1) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    v = lambda ok: "normal" if ok else "rejected"  # noqa: E731
    for r in results:
        d = r["report"]
        n = d["normality"]
        ch = d["chosen"]
        w = d["whiteness"]
        b = d["bias_model"]
        a11 = d["arma11"]
        if b["valid"]:
            tau = "inf" if b["tau_s"] is None else f"{b['tau_s']:.0f} s"
            bm = f"tau {tau}, drive {b['bias_walk_dps_per_sqrt_s']:.2g} deg/s/sqrt(s)"
        else:
            bm = "none (theta > phi or phi < 0: white noise)"
        root = f"; AR root {r['root'][0]:.3f} at {r['root'][1]:.1f} Hz" if r["root"] and ch["p"] >= 2 else ""
        print(f"| {r['recording']} | {r['axis']} | {r['n']} | {d['stationarity']['adf_statistic']:.1f} | "
              f"{v(n['normal_ks'])} / {v(n['normal_ks_dithered']) if n['normal_ks_dithered'] is not None else '-'} | {v(n['normal_jb'])} | "
              f"ARMA{tuple(d['adequate_order'])} -> ARMA({ch['p']},{ch['q']}){root} | {'yes' if w['white'] else 'no'} ({w['ljung_box_p_value']:.2g}) | "
              f"phi {a11['phi'][0]:.4f}, theta {a11['theta'][0]:.4f} | {bm} |")
    print("\nPaper 003 (ADIS16405, z): ADF -110.18; KS and JB reject; ARMA(1,1) phi 1.0000, theta 0.9994.\n")
    print("### Which model reproduces the measured Allan deviation?\n")
    print(f"RMS over tau of log10(model ADEV / measured ADEV), models simulated like the recording ({len(seeds)} seeds); lower is better.\n")
    print("| recording | axis | chosen ARMA | ARMA(1,1) | Allan model (Q/N/B/K/R fit) | better |")
    print("|---|---|---|---|---|---|")
    wins = {"arma_chosen": 0, "arma11": 0, "allan_model": 0}
    for r in results:
        dd = r["discrepancy"]
        best = min(dd, key=dd.get)
        wins[best] += 1
        ch = r["report"]["chosen"]
        print(f"| {r['recording']} | {r['axis']} | {dd['arma_chosen']:.4f} (ARMA({ch['p']},{ch['q']})) | {dd['arma11']:.4f} | {dd['allan_model']:.4f} | {best} |")
    print(f"\nbest per axis: {wins}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1, default=lambda o: None)
        print(f"wrote {args.json}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
