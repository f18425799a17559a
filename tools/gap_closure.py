"""Does the gap's loop close on real records? D before and after extension against the null band
of clean simulated records of the same length and rate, and the extended model's wavelet-variance
distance against a GMWM-style composite fit.

    python tools/gap_closure.py [--null-seeds 20] [--seed 0] [--only SUBSTRING] [--no-distance]

Records: the long ADIS16405 records (``../shared/data/adis16405_long``, skipped when absent; licence
CC BY-NC-SA, never copied into the repo), the static MPU6050 logs and the longest rest phase of
each BROAD trial (``recordings/``; movement flag 0, less 1.5 s at both ends, the guard of
``gyrofilter.evaluation.metrics``). Per record and axis:

* D before -> after: the gap's discrepancy (docs/gap.md) against the baseline and the extended model;
* the null band: the 95th percentile of D after, pooled over the three axes of ``--null-seeds``
  clean records simulated from the record's own baseline model (bias, white noise, quantisation),
  same length and rate, each analysed by ``analyse_gap`` like the record (a clean record's
  findings, if any, count in its D after as they would for a real one); "in" when D after is at
  or below it;
* where it is not: the feature that departs most from the extended model's simulations (the Allan
  deviation at one tau or one band power; z in units of the simulated spread);
* with the distance columns: the weighted distance (1/J) Σ_j (ν̂²_j - ν²_j)² / Var(ν̂²_j) of the
  extended model's Haar wavelet variance (mean of 16 simulations, ``gmwm.MODEL_CURVE_RUNS``) and of the GMWM-style fit
  (``gyrofilter.analysis.noise.gmwm.select_model``, all dyadic scales) to the measured one (docs/gap.md);
* **held out**, the check independent of D and of the fitted data: the record cut in two halves,
  the gap and the GMWM-style fit made on one half and their wavelet variances scored by the same
  distance against the *other* half's, the mean of both directions. In-sample, the GMWM-style fit
  has the advantage of having minimised that very distance; held out, neither has, and a model
  that explains the sensor (not the sample) should do better. The last line counts the axes where
  the extended model is the closer one, each way.

Every gap run here is made without the parameters' intervals (``bootstrap=0``): the table uses
none, so its findings are those before the intervals' rule (a temperature whose coefficient's
interval holds 0 is listed here, where ``gyrofilter gap`` lists it as uncertain). Prints a Markdown table; the null bands take most of the time (about 20 gap runs per record).
"""
from __future__ import annotations

import argparse
import glob
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
ADIS_DIR = os.path.join(os.path.dirname(ROOT), "shared", "data", "adis16405_long")


def records(only=None, adis_dir=ADIS_DIR):
    """(name, Recording) of the records compared, in table order: the ADIS16405 records in
    ``adis_dir``, the shipped MPU6050 logs and the BROAD rest phases."""
    import numpy as np

    from gyrofilter.evaluation.metrics import REST_GUARD_S
    from gyrofilter.recording import Recording, read_recording

    out = []
    for path in sorted(glob.glob(os.path.join(adis_dir, "*.csv.gz"))) + \
            sorted(glob.glob(os.path.join(ROOT, "recordings", "mpu6050_static_*.csv.gz"))):
        out.append((os.path.basename(path).replace(".csv.gz", ""), path))
    for path in sorted(glob.glob(os.path.join(ROOT, "recordings", "broad_*.csv.gz"))):
        out.append((os.path.basename(path).replace(".csv.gz", "") + " rest", path))
    for name, path in out:
        if only is not None and only not in name:
            continue
        rec = read_recording(path)
        if name.endswith(" rest"):
            rec = rest_phase(rec, REST_GUARD_S, Recording, np)
        yield name, rec


def rest_phase(rec, guard_s, recording_cls, np):
    """The longest run of ``movement == 0`` less ``guard_s`` at both ends, as a Recording."""
    still = np.asarray(rec.columns["movement"]) < 0.5
    edges = np.flatnonzero(np.diff(np.r_[0, still.astype(int), 0]))
    a, b = max(zip(edges[::2], edges[1::2]), key=lambda p: p[1] - p[0])
    g = int(round(guard_s * rec.sample_rate_hz))
    cols = {k: np.asarray(v)[a + g:b - g] for k, v in rec.columns.items()}
    return recording_cls(columns=cols, header=dict(rec.header), path=rec.path)


def null_band(base_model, n, fs, seeds, *, q=0.95):
    """The ``q`` quantile of D after over the three axes of clean records simulated from
    ``base_model`` (``len(seeds)`` runs of ``n`` samples at ``fs``), each analysed by ``analyse_gap``."""
    import numpy as np

    from gyrofilter.analysis.gap.pipeline import analyse_gap
    from gyrofilter.sim.simulate import simulate

    values = []
    for s in seeds:
        rec = simulate(base_model, n / fs, seed=int(s))
        rep = analyse_gap(rec, seed=int(s), bootstrap=0)
        values += list(rep["discrepancy"]["after"].values())
    return float(np.quantile(values, q)), values


def worst_feature(summary):
    """Sentence on the feature furthest outside the extended model's simulations: the gap's own
    ``departs_most`` where its report says the axis does not close (every feature, the tail
    statistic included), else the Allan-deviation tau or band power furthest out (from the
    report's departure summary of the axis)."""
    import numpy as np

    if "departs_most" in summary:
        return f"{summary['departs_most']['where'].split(' (')[0]} (z {summary['departs_most']['z']:+.1f})"

    from gyrofilter.analysis.gap.features import _LOG_FLOOR

    best = None
    for key, where in (("adev", "adev_tau_s"), ("band", "band_edges_hz")):
        mean = summary.get(f"extended_{key}_sim_mean_log")
        if mean is None:
            mean, sd = summary[f"{key}_sim_mean_log"], summary[f"{key}_sim_sd_log"]
        else:
            sd = summary[f"extended_{key}_sim_sd_log"]
        z = (np.asarray(summary[f"{key}_meas_log"]) - np.asarray(mean)) / np.maximum(sd, _LOG_FLOOR)
        z = np.where(np.isfinite(z), z, 0.0)
        j = int(np.argmax(np.abs(z)))
        if best is None or abs(z[j]) > abs(best[2]):
            pos = summary[where]
            label = (f"ADEV at {pos[j]:.3g} s" if key == "adev" else f"band {pos[j]:.3g}-{pos[j + 1]:.3g} Hz")
            best = (key, label, float(z[j]))
    return f"{best[1]} (z {best[2]:+.1f})"


#: issue 36's bound on the extended model's distance, in times the GMWM-style fit's
RATIO_BOUND = 1.5


def distances(rec, rep, seed):
    """Per axis (distance of the extended model, distance of the GMWM-style fit, its name)."""
    import numpy as np

    from gyrofilter.analysis.noise import gmwm

    out = []
    gyro = rec.gyro_dps
    for i in range(3):
        x = np.asarray(gyro[:, i], dtype=float)
        wv = gmwm.haar_wv(x, rec.sample_rate_hz)
        ext = gmwm.simulated_wv(rep["extended_model"], i, x.size, seeds=range(1000 + seed, 1000 + seed + gmwm.MODEL_CURVE_RUNS))
        best, _ = gmwm.select_model(wv, starts=3, seed=seed)
        out.append((gmwm.wv_distance(wv, ext.wv_dps2), gmwm.wv_distance(wv, best.wv(wv.tau_s)), best.name))
    return out


def held_out(rec, seed):
    """Per axis (extended model, GMWM-style fit): :func:`cross_scores` of the two halves of ``rec``."""
    import numpy as np

    from gyrofilter.recording import Recording

    half = len(rec) // 2
    a, b = (Recording(columns={k: np.asarray(v)[part] for k, v in rec.columns.items()}, header=dict(rec.header),
                      path=rec.path) for part in (slice(0, half), slice(half, 2 * half)))
    return cross_scores(a, b, seed)


def cross_scores(a, b, seed, *, axes=(0, 1, 2), composite=None):
    """Per axis of ``axes`` (extended model, composite fit): each model fitted on one of the records
    ``a``, ``b`` and scored by :func:`gyrofilter.analysis.noise.gmwm.wv_distance` against the other's
    Haar wavelet variance, the mean of the two directions,
    d = ½ [d(ν̂²_b, ν²(θ̂_a)) + d(ν̂²_a, ν²(θ̂_b))] (cross-validation, Stone 1974). The extended model
    is ``analyse_gap``'s (no intervals), its curve the mean of ``gmwm.MODEL_CURVE_RUNS`` simulations
    of the scored record's length; the composite fit is ``composite(wv)`` of the fitting record's
    wavelet variance (default: the GMWM-style selection ``gmwm.select_model``)."""
    import numpy as np

    from gyrofilter.analysis.noise import gmwm
    from gyrofilter.analysis.gap.pipeline import analyse_gap

    if composite is None:
        def composite(wv):
            return gmwm.select_model(wv, starts=3, seed=seed)[0]
    sums = np.zeros((len(axes), 2))
    for fit, score in ((a, b), (b, a)):
        rep = analyse_gap(fit, seed=seed, bootstrap=0)
        for k, i in enumerate(axes):
            y = np.asarray(score.gyro_dps[:, i], dtype=float)
            wv = gmwm.haar_wv(y, score.sample_rate_hz)
            ext = gmwm.simulated_wv(rep["extended_model"], i, y.size, seeds=range(2000 + seed, 2000 + seed + gmwm.MODEL_CURVE_RUNS))
            best = composite(gmwm.haar_wv(np.asarray(fit.gyro_dps[:, i], dtype=float), fit.sample_rate_hz))
            sums[k] += (gmwm.wv_distance(wv, ext.wv_dps2), gmwm.wv_distance(wv, best.wv(wv.tau_s)))
    return [tuple(row / 2) for row in sums]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--null-seeds", type=int, default=20, help="clean records per null band (default 20)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--only", default=None, help="only records whose name contains this")
    p.add_argument("--no-distance", action="store_true", help="skip the wavelet-variance distances")
    p.add_argument("--adis", default=ADIS_DIR, metavar="DIR",
                   help="folder of the ADIS16405 records (*.csv.gz, recording format v1; not shipped, licence "
                        "CC BY-NC-SA); default: ../shared/data/adis16405_long beside the repository")
    args = p.parse_args(argv)

    from gyrofilter.analysis.gap.pipeline import analyse_gap

    if not glob.glob(os.path.join(args.adis, "*.csv.gz")):
        print(f"note: {args.adis} absent, ADIS16405 records skipped", file=sys.stderr)
    head = "| record | axis | D before -> after | null band (95 %) | closed | findings | still departs |"
    rule = "|---|---|---|---|---|---|---|"
    if not args.no_distance:
        head += " WV distance: extended / GMWM-style (model) | held out: extended / GMWM-style |"
        rule += "---|---|"
    print(head)
    print(rule)
    wins = {"in-sample": [0, 0], "held out": [0, 0]}
    outside = {"in-sample": [], "held out": []}  # axes beyond RATIO_BOUND times the GMWM-style fit's distance
    for name, rec in records(args.only, args.adis):
        rep = analyse_gap(rec, seed=args.seed, recording_name=name, bootstrap=0)
        n, fs = len(rec), rec.sample_rate_hz
        seeds = range(9000 + args.seed, 9000 + args.seed + args.null_seeds)
        band, _ = null_band(rep["baseline"]["model"], n, fs, seeds)
        dist = None if args.no_distance else distances(rec, rep, args.seed)
        out = None if args.no_distance else held_out(rec, args.seed)
        for i, a in enumerate("xyz"):
            before, after = rep["discrepancy"]["before"][a], rep["discrepancy"]["after"][a]
            found = ", ".join(f["effect"] for f in rep["findings"] if f["axis"] == a) or "-"
            closed = after <= band
            row = (f"| `{name}` ({n / fs:.0f} s at {fs:.4g} Hz) | {a} | {before:.2f} -> {after:.2f} | {band:.2f} | "
                   f"{'yes' if closed else 'no'} | {found} | {'' if closed else worst_feature(rep['departures'][a])} |")
            if dist is not None:
                row += f" {dist[i][0]:.3g} / {dist[i][1]:.3g} ({dist[i][2]}) | {out[i][0]:.3g} / {out[i][1]:.3g} |"
                for key, (ext, other) in (("in-sample", dist[i][:2]), ("held out", out[i])):
                    wins[key][0] += ext < other
                    wins[key][1] += 1
                    if ext > RATIO_BOUND * other:
                        outside[key].append(f"{name} {a} ({ext / other:.2g}x{', both below 1' if ext < 1 else ''})")
            print(row, flush=True)
        print(f"  ({name}: gap {rep['runtime_s']:.0f} s)", file=sys.stderr, flush=True)
    if not args.no_distance:
        print("\n" + "; ".join(f"{key}, the extended model is closer than the GMWM-style fit on {k} of {n} axes"
                               for key, (k, n) in wins.items()))
        for key, (k, n) in wins.items():
            print(f"{key}, within {RATIO_BOUND:g} times the GMWM-style fit's distance on {n - len(outside[key])} of {n} axes"
                  + (f"; beyond it: {', '.join(outside[key])}" if outside[key] else ""))


if __name__ == "__main__":
    main()
