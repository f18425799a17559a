"""Paper 003's ARMA analysis on the real static MPU6050 recordings, and ARMA vs Allan model.

    python tools/arma_report.py [--recordings recordings] [--json OUT.json] [--seeds 12] [--figure docs/figures/arma_adev.png]
    python tools/arma_report.py --from-json OUT.json      # tables and figure again, no refit
    python tools/arma_report.py --from-json OUT.json --recompute-adev --seeds 12   # model ADEVs over 12 seeds

For every static recording (recordings/mpu6050_static_*.csv.gz) and axis: the ADF statistic,
normality verdicts (KS raw and with one LSB of dither, JB), the Pandit-Wu order, the chosen
model and the ARMA(1, 1) next to paper 003's x_t - 1.0000 x_{t-1} = a_t - 0.9994 a_{t-1}.

Then which model reproduces the measured overlapping Allan deviation better: the chosen ARMA
and the ARMA(1, 1), simulated (same length and rate, several seeds, RMS of the deviations), and
the Allan-based noise model (gyrofilter.analysis.noise.fit: Q/N/B/K/R), simulated through
gyrofilter.sim.simulate (white noise N, bias instability B, rate random walk K, rate ramp R,
quantisation 1/131 deg/s) over the same seeds. Discrepancy = RMS over tau of
log10(model ADEV / measured ADEV) (0.01 ~ 2.3 % off).
"""
from __future__ import annotations

import argparse
import glob
import json
import os
import sys

import numpy as np

from gyrofilter.analysis.noise.model import QUANTIZATION, ANGLE_RANDOM_WALK
from gyrofilter.effects import RATE_RANDOM_WALK
from gyrofilter.analysis.arma import identify as arma
from gyrofilter.analysis.arma import checks as arma_checks
from gyrofilter.analysis.arma import fit as arma_fit
from gyrofilter.analysis.noise.allan import overlapping_adev
from gyrofilter.analysis.noise.fit import characterise_axis
from gyrofilter.recording import read_recording
from gyrofilter.sim.simulate import simulate_dps


def allan_model_adev(x, fs, lsb_per_dps, seeds, tau):
    """Mean ADEV of the Allan-fitted five-term model, simulated like the recording."""
    res = characterise_axis(x, fs)
    terms = {t: res.fitted[t].value for t in (QUANTIZATION, ANGLE_RANDOM_WALK, "bias_instability", RATE_RANDOM_WALK, "rate_ramp")}
    model = allan_model(terms, fs, lsb_per_dps)
    curves = []
    for s in seeds:
        sim, _ = simulate_dps(model, len(x) / fs, seed=s)
        sim = sim[: len(x), 0]
        curves.append(overlapping_adev(sim - sim.mean(), fs, tau)[1])
    return np.sqrt(np.mean(np.square(curves), axis=0)), terms, model


def allan_model(terms, fs, lsb_per_dps):
    """Simulator model (axis x) of the fitted Allan terms: N white, B flicker, K random walk, R ramp, LSB quantisation."""
    val = lambda t: terms.get(t) or 0.0  # noqa: E731
    effects = []
    if val("bias_instability") > 0:
        effects.append({"effect": "bias_instability", "b_dps": val("bias_instability")})
    if val(RATE_RANDOM_WALK) > 0:
        effects.append({"effect": "rate_random_walk", "k_dps_per_sqrt_s": val(RATE_RANDOM_WALK)})
    if val("rate_ramp") > 0:
        effects.append({"effect": "rate_ramp", "r_dps_per_s": val("rate_ramp")})
    model = {"sample_rate_hz": fs, "gyro_unit": "dps",
             "axes": {a: {"bias_dps": 0.0, "arw_dps_per_sqrt_hz": val(ANGLE_RANDOM_WALK), "effects": effects if a == "x" else []} for a in "xyz"}}
    if lsb_per_dps:
        model["gyro_unit"] = "lsb"
        model["lsb_per_dps"] = lsb_per_dps
    return model


def add_bic(r, recordings, max_n, seeds):
    """The same Pandit-Wu walk decided by BIC (gyrofilter's default), its whiteness and ADEV."""
    rec = read_recording(os.path.join(recordings, r["recording"]))
    x = rec.gyro_dps[:, "xyz".index(r["axis"])]
    series, _, rate, _ = arma.prepare_series(x, rec.sample_rate_hz)
    chosen, adequate, _, _ = arma.select_order(series, max_n=max_n, criterion="bic")
    w = arma_checks.whiteness(chosen.residuals, chosen.n_params)
    tau = np.asarray(r["adev"]["tau_s"])
    _, dev = arma.arma_adev(chosen, len(series), rate, seeds=seeds, taus_s=tau)
    r["bic"] = {"chosen": chosen.to_dict(), "adequate_order": list(adequate), "ljung_box_p_value": w.ljung_box_p_value,
                "white": w.white, "peak": spectral_peak(chosen.to_dict(), rate)}
    r["adev"]["arma_bic"] = dev.tolist()
    r["discrepancy"]["arma_bic"] = arma.adev_discrepancy(np.asarray(r["adev"]["measured"]), dev)


def _fit_from_dict(d):
    return arma_fit.ArmaFit(d["p"], d["q"], d["phi"], d["theta"], d["sigma_a"], d["rss"], d["n_residuals"], d["aic"])


def recompute_adev(r, seeds):
    """Every model's mean ADEV again over ``seeds`` (no refit), and the discrepancies."""
    tau = np.asarray(r["adev"]["tau_s"])
    measured = np.asarray(r["adev"]["measured"])
    models = {"arma_chosen": r["report"]["chosen"], "arma11": r["report"]["arma11"]}
    if "bic" in r:
        models["arma_bic"] = r["bic"]["chosen"]
    for key, d in models.items():
        _, dev = arma.arma_adev(_fit_from_dict(d), r["n"], r["fs"], seeds=seeds, taus_s=tau)
        r["adev"][key] = dev.tolist()
        r["discrepancy"][key] = arma.adev_discrepancy(measured, dev)
    model = allan_model(r["allan_terms"], r["fs"], r.get("lsb_per_dps"))
    curves = []
    for s in seeds:
        sim, _ = simulate_dps(model, r["n"] / r["fs"], seed=s)
        sim = sim[: r["n"], 0]
        curves.append(overlapping_adev(sim - sim.mean(), r["fs"], tau)[1])
    dev = np.sqrt(np.mean(np.square(curves), axis=0))
    r["adev"]["allan_model"] = dev.tolist()
    r["discrepancy"]["allan_model"] = arma.adev_discrepancy(measured, dev)
    r.pop("noise_floor", None)
    r["n_seeds"] = len(seeds)


def noise_floor(r, seeds=(100, 101, 102)):
    """Typical discrepancy of ONE simulated record of the Allan model from that model's mean curve:
    what a perfect model would score against a single measured record of this length."""
    tau = np.asarray(r["adev"]["tau_s"])
    mean_curve = np.asarray(r["adev"]["allan_model"])
    model = allan_model(r["allan_terms"], r["fs"], r.get("lsb_per_dps", 131.0))
    d = []
    for s in seeds:
        sim, _ = simulate_dps(model, r["n"] / r["fs"], seed=s)
        sim = sim[: r["n"], 0]
        d.append(arma.adev_discrepancy(mean_curve, overlapping_adev(sim - sim.mean(), r["fs"], tau)[1]))
    return float(np.mean(d))


def spectral_peak(report_fit, fs, n_freq=4096):
    """Strongest narrow feature of the fitted ARMA spectrum |theta(e^-iw)|^2 / |phi(e^-iw)|^2:
    (frequency Hz, peak / median spectral level in dB). Near-cancelling AR/MA root pairs, which
    high-order fits are full of, give no peak here, unlike the raw AR roots."""
    phi = np.asarray(report_fit["phi"], float)
    theta = np.asarray(report_fit["theta"], float)
    if not phi.size:
        return None
    w = np.linspace(0, np.pi, n_freq)
    z = np.exp(-1j * w)
    num = np.abs(1 - sum(t * z ** (j + 1) for j, t in enumerate(theta))) ** 2 if theta.size else np.ones_like(w)
    den = np.abs(1 - sum(c * z ** (i + 1) for i, c in enumerate(phi))) ** 2
    psd = num / den
    k = int(np.argmax(psd))
    return float(w[k] / (2 * np.pi) * fs), float(10 * np.log10(psd[k] / np.median(psd)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--recordings", default="recordings")
    ap.add_argument("--json", default=None, help="write all numbers here")
    ap.add_argument("--seeds", type=int, default=12)
    ap.add_argument("--max-n", type=int, default=4)
    ap.add_argument("--figure", default="docs/figures/arma_adev.png")
    ap.add_argument("--from-json", default=None, help="re-print the tables and redraw the figure from a --json file")
    ap.add_argument("--recompute-adev", action="store_true",
                    help="with --from-json: simulate every model's ADEV again with --seeds seeds (no refit)")
    args = ap.parse_args(argv)
    if args.from_json:
        with open(args.from_json) as fh:
            results = json.load(fh)
        for r in results:
            if args.recompute_adev:
                recompute_adev(r, list(range(args.seeds)))
            r.setdefault("noise_floor", noise_floor(r))
            if "bic" not in r:
                add_bic(r, args.recordings, args.max_n, list(range(args.seeds)))
        if args.json:
            with open(args.from_json, "w") as fh:
                json.dump(results, fh, indent=1, default=lambda o: None)
        report(results, results[0].get("n_seeds", 3))
        plot(args.figure, results)
        return 0
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
            rep = arma.analyze_axis(x, fs, axis=ax, max_n=args.max_n, quantum_dps=q, criterion="f")
            xs = x - x.mean()
            tau, measured = overlapping_adev(xs, fs)
            _, adev_chosen = arma.arma_adev(rep.chosen, len(xs), fs, seeds=seeds, taus_s=tau)
            _, adev_11 = arma.arma_adev(rep.arma11, len(xs), fs, seeds=seeds, taus_s=tau)
            adev_allan, terms, _ = allan_model_adev(xs, fs, rec.lsb_per_dps, seeds, tau)
            results.append({
                "recording": os.path.basename(p), "axis": ax, "n": len(x), "fs": fs, "lsb_per_dps": rec.lsb_per_dps,
                "report": rep.to_dict(),
                "peak": spectral_peak(rep.chosen.to_dict(), fs),
                "adev": {"tau_s": tau.tolist(), "measured": measured.tolist(), "arma_chosen": adev_chosen.tolist(),
                         "arma11": adev_11.tolist(), "allan_model": adev_allan.tolist()},
                "discrepancy": {"arma_chosen": arma.adev_discrepancy(measured, adev_chosen),
                                "arma11": arma.adev_discrepancy(measured, adev_11),
                                "allan_model": arma.adev_discrepancy(measured, adev_allan)},
                "allan_terms": terms,
            })

    for r in results:
        r["noise_floor"] = noise_floor(r)
        add_bic(r, args.recordings, args.max_n, seeds)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1, default=lambda o: None)
        print(f"wrote {args.json}", file=sys.stderr)
    report(results, len(seeds))
    plot(args.figure, results)
    return 0


def plot(path, results):
    """Measured ADEV vs the three simulated models, for the longest recording of each source."""
    from gyrofilter.plots import pyplot

    plt = pyplot()

    names = [n for n in ("mpu6050_static_449s.csv.gz", "mpu6050_static_655s.csv.gz") if any(r["recording"] == n for r in results)]
    if not names:
        return
    fig, axes = plt.subplots(len(names), 3, figsize=(13, 4 * len(names)), squeeze=False)
    for row, name in enumerate(names):
        for col, ax_name in enumerate("xyz"):
            r = next(r for r in results if r["recording"] == name and r["axis"] == ax_name)
            a = r["adev"]
            d = r["discrepancy"]
            ch = r["report"]["chosen"]
            ax = axes[row][col]
            ax.loglog(a["tau_s"], a["measured"], "k.-", lw=1.5, label="measured")
            ax.loglog(a["tau_s"], a["arma_chosen"], "-", color="tab:blue", label=f"ARMA({ch['p']},{ch['q']}) by F ({d['arma_chosen']:.3f})")
            if "arma_bic" in a:
                cb = r["bic"]["chosen"]
                ax.loglog(a["tau_s"], a["arma_bic"], "-.", color="tab:purple", label=f"ARMA({cb['p']},{cb['q']}) by BIC ({d['arma_bic']:.3f})")
            ax.loglog(a["tau_s"], a["arma11"], "--", color="tab:orange", label=f"ARMA(1,1) ({d['arma11']:.3f})")
            ax.loglog(a["tau_s"], a["allan_model"], ":", color="tab:green", lw=2, label=f"Allan model ({d['allan_model']:.3f})")
            ax.set_title(f"{name.replace('.csv.gz', '')} {ax_name}", fontsize=9)
            ax.set_xlabel("tau (s)")
            ax.set_ylabel("ADEV (deg/s)")
            ax.grid(alpha=0.3, which="both")
            ax.legend(fontsize=7)
    fig.suptitle("Overlapping Allan deviation: measured vs simulated models (RMS log10 discrepancy in brackets)", fontsize=10)
    fig.tight_layout()
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"figure: {path}", file=sys.stderr)


def bic_text(r):
    b = r.get("bic")
    if not b:
        return "- | -"
    c = b["chosen"]
    pk = b["peak"]
    peak = f"; peak {pk[1]:.1f} dB at {pk[0]:.1f} Hz" if pk and c["p"] + c["q"] > 2 else ""
    return f"ARMA({c['p']},{c['q']}){peak} | {'yes' if b['white'] else 'no'} ({b['ljung_box_p_value']:.2g})"


def report(results, n_seeds):
    print("### Paper 003's tests and Pandit-Wu order on the static MPU6050 recordings\n")
    print("| recording | axis | N | ADF (5 % crit. -2.86) | KS raw / dithered | JB | Pandit-Wu, F rule (paper): adequate -> chosen | white? (Ljung-Box p) | Pandit-Wu, BIC: chosen | white? (p) | ARMA(1,1) | bias model from ARMA(1,1) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
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
            tau = tau if b.get("tau_determined", True) else f"not determined (> {arma.TAU_RECORD_FRACTION:g} x {b['record_s']:.0f} s)"
            bm = f"tau {tau}, drive {b['bias_walk_dps_per_sqrt_s']:.2g} deg/s/sqrt(s)"
        else:
            bm = "none (theta > phi or phi < 0: white noise)"
        pk = r.get("peak") or spectral_peak(ch, r["fs"])
        root = f"; spectrum peak {pk[1]:.1f} dB at {pk[0]:.1f} Hz" if pk and ch["p"] + ch["q"] > 2 else ""
        print(f"| {r['recording']} | {r['axis']} | {r['n']} | {d['stationarity']['adf_statistic']:.1f} | "
              f"{v(n['normal_ks'])} / {v(n['normal_ks_dithered']) if n['normal_ks_dithered'] is not None else '-'} | {v(n['normal_jb'])} | "
              f"ARMA{tuple(d['adequate_order'])} -> ARMA({ch['p']},{ch['q']}){root} | {'yes' if w['white'] else 'no'} ({w['ljung_box_p_value']:.2g}) | "
              f"{bic_text(r)} | "
              f"phi {a11['phi'][0]:.4f}, theta {a11['theta'][0]:.4f} | {bm} |")
    print("\nPaper 003 (ADIS16405, z): ADF -110.18; KS and JB reject; ARMA(1,1) phi 1.0000, theta 0.9994.\n")
    print("### Which model reproduces the measured Allan deviation?\n")
    print(f"RMS over tau of log10(model ADEV / measured ADEV), models simulated like the recording ({n_seeds} seeds); lower is better.\n")
    print("| recording | axis | ARMA chosen by F (paper) | ARMA chosen by BIC | ARMA(1,1) | Allan model (Q/N/B/K/R fit) | better | floor: one record of a perfect model |")
    print("|---|---|---|---|---|---|---|---|")
    labels = {"arma_chosen": "ARMA by F", "arma_bic": "ARMA by BIC", "arma11": "ARMA(1,1)", "allan_model": "Allan"}
    wins = dict.fromkeys(labels.values(), 0)
    for r in results:
        dd = r["discrepancy"]
        best = labels[min(dd, key=dd.get)]
        wins[best] += 1
        ch = r["report"]["chosen"]
        floor = r.get("noise_floor")
        cb = r.get("bic", {}).get("chosen", {"p": "-", "q": "-"})
        bic = f"{dd['arma_bic']:.4f} (ARMA({cb['p']},{cb['q']}))" if "arma_bic" in dd else "-"
        print(f"| {r['recording']} | {r['axis']} | {dd['arma_chosen']:.4f} (ARMA({ch['p']},{ch['q']})) | {bic} | {dd['arma11']:.4f} | {dd['allan_model']:.4f} | {best} | "
              + ("-" if floor is None else f"{floor:.4f}") + " |")
    print("\nbest per axis: " + ", ".join(f"{label} {n}" for label, n in wins.items()))


if __name__ == "__main__":
    sys.exit(main())
