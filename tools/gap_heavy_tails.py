"""Heavy tails in the gap analysis: an Xsens-like record read with and without the heavy-tail stage, and the real records.

    python tools/gap_heavy_tails.py [--duration 1800] [--seed 0] [--stand-ins N] [--real [--adis DIR]]

The Xsens MTi-G record of issue 24 (not in the repository) is heavy-tailed throughout: 5.5 % of
its samples beyond 6 robust sd, kurtosis 85-160; the previous gap release called that
``outliers`` and got the short-term variance wrong. Its stand-in here is simulated: white noise
N = 0.01 deg/s/sqrt(Hz) at 100 Hz through a first-order low pass (lag1 0.5), with 6 % of the
innovations at 30 times the others' sd (``heavy_tails``; 5 % beyond 6 core sd). ``gap`` runs on it
as it is and with the heavy-tail stage switched off (the previous reading); printed: the findings,
D of the axis before and after, and an Allan distance independent of D: the weighted distance
(:func:`gyrofilter.analysis.noise.gmwm.wv_distance`, all dyadic scales) between the record's Haar
wavelet variance and the mean of 16 simulations (``gmwm.MODEL_CURVE_RUNS``) of each extended model, and of a direct two-term
composite fit (white noise + one Gauss-Markov term, the AR(1)) to the record.

``--stand-ins N``: the two distances on N draws of the stand-in (seeds ``--seed`` onwards),
in-sample and held out. In-sample the two-term fit has minimised the distance on the very scales
it is scored on (about 1 - p/J of an exact model's, p parameters, J scales) and the extended
model's curve is a mean of simulations (about 1 + 1/16); held out, both models are fitted on the
draw and scored against an independent twin (the same process, seed + ``TWIN_SEED``) and the
other way round, the mean of both directions (``gap_closure.cross_scores``, the held-out score of
``tools/gap_closure.py``).

``--real``: the tail statistic's departure from the baseline simulations and the decision on every
axis of the static MPU6050 recordings (``recordings/``) and, where present, the ADIS16405 long
records (``../shared/data/adis16405_long``; never copied into the repository).
"""
from __future__ import annotations

import argparse
import glob
import os
import time

import numpy as np

from gyrofilter.analysis.gap import detectors as det
from gyrofilter.analysis.gap import pipeline as gap
from gyrofilter.analysis.noise import gmwm
from gyrofilter.recording import read_recording
from gyrofilter.sim.simulate import simulate

from gap_closure import RATIO_BOUND, cross_scores  # tools/, the script's folder

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ADIS = os.path.join(os.path.dirname(ROOT), "shared", "data", "adis16405_long")
XSENS_LIKE = {"sample_rate_hz": 100.0, "axes": {a: {"bias_dps": 0.1, "arw_dps_per_sqrt_hz": 0.01, "effects": []} for a in "xyz"}}
#: the held-out twin of the stand-in of seed s is the stand-in of seed s + TWIN_SEED
TWIN_SEED = 10_000
XSENS_LIKE["axes"]["z"]["effects"] = [{"effect": "heavy_tails", "fraction": 0.06, "scale_ratio": 30.0},
                                      {"effect": "colored_noise", "lag1": 0.5}]


def without_tails(*args, **kwargs):
    """The heavy-tail stage switched off: the previous release's reading."""
    return None, None


def model_distance(report, rec, i):
    """The Allan distance of axis ``i`` of ``report``'s extended model to the record ``rec``'s."""
    x = rec.gyro_dps[:, i]
    ext = gmwm.simulated_wv(report["extended_model"], i, x.size, seeds=range(1000, 1000 + gmwm.MODEL_CURVE_RUNS))
    return gmwm.wv_distance(gmwm.haar_wv(x, rec.sample_rate_hz), ext.wv_dps2)


def two_term_fit(wv, seed):
    """The direct two-term composite fit (white + AR(1), GMWM-style) to the wavelet variance ``wv``."""
    return gmwm.fit_model(wv, (), 1, starts=4, seed=seed)


def two_term(x, seed):
    """The direct two-term fit (white + AR(1)) to ``x`` and its Allan distance."""
    wv = gmwm.haar_wv(x, 100.0)
    fit = two_term_fit(wv, seed)
    return fit, gmwm.wv_distance(wv, fit.wv(wv.tau_s))


def show(label, report, rec, axis):
    found = "; ".join(f"{f['effect']} (" + ", ".join(f"{k} = {v:.3g}" for k, v in f["params"].items()) + ")"
                      for f in report["findings"] if f["axis"] == axis)
    d = report["discrepancy"]
    dist = model_distance(report, rec, "xyz".index(axis))
    print(f"{label}: {found or 'no finding'}\n    D {d['before'][axis]:.3g} -> {d['after'][axis]:.3g}; "
          f"Allan distance of the extended model {dist:.3g}")
    return dist


def xsens_like(args):
    """The stand-in of seed ``--seed`` read both ways; returns (the heavy-tail reading's distance,
    the two-term fit's)."""
    rec = simulate(XSENS_LIKE, args.duration, seed=args.seed)
    print(f"Xsens-like axis z ({args.duration:.0f} s at 100 Hz): heavy_tails fraction 0.06, scale_ratio 30, "
          "colored_noise lag1 0.5")
    x = rec.gyro_dps[:, 2]
    u = det.tail_residual(x, 100.0)
    print(f"    {100 * np.mean(np.abs(u) > 6):.2g} % of the samples beyond 6 robust sd, kurtosis "
          f"{np.mean(u ** 4) / np.mean(u ** 2) ** 2:.3g}")
    new = show("with the heavy-tail stage", gap.analyse_gap(rec, seed=args.seed), rec, "z")
    real_stage = gap.det.detect_heavy_tails
    gap.det.detect_heavy_tails = without_tails
    try:
        old = show("without it (previous reading)", gap.analyse_gap(rec, seed=args.seed), rec, "z")
    finally:
        gap.det.detect_heavy_tails = real_stage
    two, direct = two_term(x, args.seed)
    print(f"direct two-term fit white + AR(1) ({two.name}): Allan distance {direct:.3g}")
    print(f"the previous reading is {old / direct:.3g} times as far as the two-term fit, the heavy-tail reading "
          f"{new / direct:.3g} times")
    return new, direct


def stand_in_seeds(args, first):
    """The heavy-tail reading against the two-term fit on the stand-in drawn with ``--stand-ins``
    seeds (the ratio of two distances near or below 1 moves with the record's draw), in-sample and
    held out (:func:`gap_closure.cross_scores` of the draw of seed s and its twin of seed
    s + ``TWIN_SEED``, a seed no draw uses); ``first``: :func:`xsens_like`'s pair for the first seed."""
    seeds = range(args.seed, args.seed + args.stand_ins)
    print(f"stand-ins of seeds {seeds[0]}-{seeds[-1]}, axis z: the Allan distance of the heavy-tail reading / the "
          f"two-term fit's = ratio; in-sample (both fitted on the draw and scored on it) and held out (fitted on the "
          f"draw, scored on its twin of seed + {TWIN_SEED}, and the other way round, mean of both)")
    rows = {"in-sample": [], "held out": []}
    curves = []
    for seed in seeds:
        rec = simulate(XSENS_LIKE, args.duration, seed=seed)
        if seed == args.seed:
            rows["in-sample"].append(first)
        else:
            rows["in-sample"].append((model_distance(gap.analyse_gap(rec, seed=seed), rec, 2),
                                      two_term(rec.gyro_dps[:, 2], seed)[1]))
        twin = simulate(XSENS_LIKE, args.duration, seed=seed + TWIN_SEED)
        curves += [gmwm.haar_wv(r.gyro_dps[:, 2], 100.0) for r in (rec, twin)]
        rows["held out"].append(cross_scores(rec, twin, seed, axes=(2,), composite=lambda wv: two_term_fit(wv, seed))[0])
        print(f"    seed {seed}: " + "; ".join(f"{key} {r[-1][0]:.3g} / {r[-1][1]:.3g} = {r[-1][0] / r[-1][1]:.2f}"
                                              for key, r in rows.items()), flush=True)
    for key, pairs in rows.items():
        ratios = [e / t for e, t in pairs]
        print(f"{key}: ratio {min(ratios):.2f}-{max(ratios):.2f}, at most {RATIO_BOUND:g} on "
              f"{sum(r <= RATIO_BOUND for r in ratios)} of {len(ratios)}; largest distance "
              f"{max(max(p) for p in pairs):.2g}")
    r = spread(curves)
    print(f"the {len(curves)} draws' and twins' wavelet variance spreads " + ", ".join(f"{v:.2g}" for v in r[:4])
          + f" times the Gaussian standard error the distance divides by at {curves[0].tau_s[0]:.2g}-"
          f"{curves[0].tau_s[3]:.2g} s, {r[5:].min():.2g}-{r[5:].max():.2g} from {curves[0].tau_s[5]:.2g} s on: "
          f"a model that follows one draw's curve scores about 2 mean(spread^2) = {2 * np.mean(r ** 2):.2g} held out")


def spread(curves):
    """Per scale, the sample sd of ν̂² over ``curves`` (wavelet variances of independent draws of one
    process) over the mean of the Gaussian standard error ν̂² sqrt(2/η) that
    :func:`gyrofilter.analysis.noise.gmwm.wv_distance` divides by. Held out, a model fitted on one
    draw and scored on another has E d ≈ (1/J) Σ_j (s²_j + s²_fit,j) / SE²_j, about 2 mean(spread²)
    where the fit follows its draw's curve."""
    w = np.array([c.wv_dps2 for c in curves])
    return w.std(axis=0, ddof=1) / np.mean([c.sd_dps2 for c in curves], axis=0)


def real(args):
    paths = sorted(glob.glob(os.path.join(ROOT, "recordings", "mpu6050_static_*.csv.gz")))
    paths += sorted(glob.glob(os.path.join(args.adis, "*.csv.gz")))
    print(f"{'recording':32s} axis  tail z  findings on the axis (outliers / heavy_tails)")
    for path in paths:
        rec = read_recording(path)
        report = gap.analyse_gap(rec, seed=args.seed)
        for a in "xyz":
            tails = [f["effect"] for f in report["findings"] if f["axis"] == a and f["effect"] in ("outliers", "heavy_tails")]
            notes = [n for n in report["notes"] if n.startswith(f"axis {a}: the noise's")]
            print(f"{os.path.basename(path)[:32]:32s} {a:4s} {report['departures'][a]['tails_z']:+7.1f}  "
                  f"{', '.join(tails) or '-'}{' (note: ' + notes[0][8:90] + '...)' if notes else ''}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1800.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--stand-ins", type=int, default=1,
                        help="compare the two distances, in-sample and held out, on this many stand-ins (seeds --seed onwards; 0: none)")
    parser.add_argument("--real", action="store_true")
    parser.add_argument("--adis", default=ADIS, help="folder of the ADIS16405 long records (default: ../shared/data/adis16405_long)")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    first = xsens_like(args)
    if args.stand_ins >= 1:
        stand_in_seeds(args, first)
    if args.real:
        real(args)
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
