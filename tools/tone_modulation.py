"""What a named wandering tone still misses: is the power beside the tone's band modulated in time?

    python tools/tone_modulation.py --adis DIR [--sims 4] [--null 40]
                                    [--records adis16405_static_2,adis16405_static_3]

For every axis on which ``analyse_gap`` (the command's defaults, no intervals) names a
``wandering_tone``, the statistics of :mod:`gyrofilter.analysis.gap.detectors.excursion` (their
one home): the flanks of the tone's band (centre +- 3.5 spreads, twice its width on each side)
cut out of the series, their excess kurtosis (0 for Gaussian noise, above 0 where the band's
power comes and goes) and their envelope line (the flank power over 0.1-s blocks, its
periodogram over 0.01-2 Hz, the largest ordinate over the median one, and its period); on the
record, the tone's band folded on that period (its least power over the median, the share of the
cycle below 0.9 of it) and the excursion the analysis finds (its period, height and length,
or none); and the tail statistic of the whole axis
(:func:`gyrofilter.analysis.gap.detectors.tails_statistic`, the feature that departed).

The same for ``--sims`` runs of the extended model the analysis wrote (seeds 0, 1, ...), less the
compression ``gap`` may have fitted (:func:`without_compression`), with the tone's excursion where one was found and without it (the tone's Gauss-Markov wander alone).
The false alarms of the excursion's threshold: the envelope line of ``--null`` hidden-effect
wandering tones without excursion (:func:`gyrofilter.sim.hidden_effects.draw_case`, half of
10 min and half of 30-60 min) and of the runs without it (docs/gap.md, "A tone whose
frequency wanders").
"""
from __future__ import annotations

import argparse
import copy
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from gyrofilter.effects import COMPRESSION, WANDERING_TONE  # noqa: E402

#: the first seed of the hidden-effect tones of the false-alarm count (``--null``)
NULL_SEED = 36100

def tails(x, sample_rate_hz):
    """The gap analysis' tail statistic of ``x``."""
    from gyrofilter.analysis.gap.detectors import tail_residual, tails_statistic

    return tails_statistic(x, sample_rate_hz, u=tail_residual(x, sample_rate_hz))


def tone_axes(adis, records):
    """Each axis of the records ``records`` (comma-separated names of .csv.gz files in the folder
    ``adis``) on which ``analyse_gap`` (the command's defaults, no intervals) names a
    ``wandering_tone``: ``(name, recording, gap report, axis index, the tone's centre_hz, its
    spread_hz, the axis in deg/s)``."""
    from gyrofilter.analysis.gap.baseline import axis_dps
    from gyrofilter.analysis.gap.pipeline import analyse_gap
    from gyrofilter.recording import read_recording

    for name in records.split(","):
        rec = read_recording(os.path.join(adis, f"{name}.csv.gz"))
        rep = analyse_gap(rec, bootstrap=0)
        for finding in rep["findings"]:
            if finding["effect"] == WANDERING_TONE:
                i = "xyz".index(finding["axis"])
                yield (name, rec, rep, i, finding["params"]["center_hz"], finding["params"]["spread_hz"],
                       np.asarray(axis_dps(rec, i), dtype=float))


def without_compression(spec):
    """The model ``spec`` without the compression ``gap`` may have fitted: the tools measure what the
    tone and the rest of the model leave, on the runs of the model without it."""
    out = copy.deepcopy(spec)
    for entry in out["axes"].values():
        entry["effects"] = [e for e in entry.get("effects", []) if e["effect"] != COMPRESSION]
    return out


def with_excursion(spec, i, exc=None):
    """The validated model ``spec`` with the excursion of axis ``i``'s wandering tone set to the
    estimate ``exc`` (:func:`gyrofilter.analysis.gap.detectors.tone_excursion`), or taken out
    (``exc`` None, or no excursion present)."""
    keys = ("excursion_hz", "excursion_period_s", "excursion_s")
    given = {k: exc[k] for k in keys} if exc and exc["present"] else {"excursion_hz": 0.0, "excursion_period_s": None,
                                                                      "excursion_s": None}
    axis = spec["axes"]["xyz"[i]]
    effects = [dict(e, **given) if e["effect"] == WANDERING_TONE else e for e in axis["effects"]]
    return dict(spec, axes=dict(spec["axes"], **{"xyz"[i]: dict(axis, effects=effects)}))


def null_ratios(count, first_seed=NULL_SEED):
    """The envelope line R of ``count`` hidden-effect wandering tones without excursion
    (:func:`gyrofilter.sim.hidden_effects.draw_case`, seeds from ``first_seed``; their duration,
    half 10-min and half 30-60-min), at their true centre and spread."""
    import gyrofilter.sim.hidden_effects as he
    from gyrofilter.analysis.gap.baseline import axis_dps
    from gyrofilter.analysis.gap.detectors import flank_envelope
    from gyrofilter.sim.simulate import simulate

    out = []
    for k in range(count):
        case = he.draw_case(first_seed + k, effect=WANDERING_TONE, duration_s=600.0 if k % 2 else None)
        rec = simulate(case["model"], case["duration_s"], seed=case["sim_seed"])
        x = np.asarray(axis_dps(rec, "xyz".index(case["axis"])), dtype=float)
        p = case["params"]
        out.append(flank_envelope(x, float(rec.sample_rate_hz), p["center_hz"], p["spread_hz"])["ratio"])
    return out


def span(values, fmt):
    """``lo to hi`` of ``values`` in the format ``fmt``."""
    return f"{format(min(values), fmt)} to {format(max(values), fmt)}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--adis", required=True, help="folder of the ADIS16405 records")
    ap.add_argument("--records", default="adis16405_static_2,adis16405_static_3")
    ap.add_argument("--sims", type=int, default=4)
    ap.add_argument("--null", type=int, default=40, help="hidden-effect tones without excursion for the false alarms")
    args = ap.parse_args(argv)

    from gyrofilter.analysis.gap.baseline import simulate_axis
    from gyrofilter.analysis.gap.detectors import EXCURSION_LINE_RATIO, flank_envelope, folded_band, tone_excursion
    from gyrofilter.sim.model import validate_model

    print("| record | axis | tone (centre, spread) | flanks | kurtosis: record / runs with / without the excursion "
          "| envelope line: record (period) / runs with / without | tone's band on that period: least power, cycle below 0.9 "
          "| excursion found: period, height, length | tail statistic: record / runs with / without |")
    print("|---|---|---|---|---|---|---|---|---|")
    null_model = []
    for name, rec, rep, i, c, s, x in tone_axes(args.adis, args.records):
        fs, axis = float(rec.sample_rate_hz), "xyz"[i]
        spec, _ = validate_model(without_compression(rep["extended_model"]))
        env = flank_envelope(x, fs, c, s)
        exc = tone_excursion(x, fs, c, s)
        least, below = folded_band(x, fs, c, s, exc["excursion_period_s"] or env["period_s"])
        t_rec = tails(x, fs)
        runs, bare = [], []
        for seed in range(args.sims):
            y = simulate_axis(with_excursion(spec, i, exc), len(rec), fs, seed, i)
            e = flank_envelope(y, fs, c, s)
            runs.append((e["kurtosis"], e["ratio"], tails(y, fs)))
            y = simulate_axis(with_excursion(spec, i), len(rec), fs, seed, i)
            e = flank_envelope(y, fs, c, s)
            bare.append((e["kurtosis"], e["ratio"], tails(y, fs)))
        null_model += [r[1] for r in bare]
        ks, rs, ts = ([r[k] for r in runs + bare] for k in range(3))
        n = len(runs)
        lo_w, lo, hi, hi_w = env["flanks_hz"]
        found = (f"{exc['excursion_period_s']:.2f} s, {exc['excursion_hz']:.2f} Hz, {exc['excursion_s']:.2f} s"
                 if exc["present"] else "none")
        print(f"| {name} | {axis} | {c:.2f} Hz, {s:.2f} Hz | {lo_w:.1f}-{lo:.1f} and {hi:.1f}-{hi_w:.1f} Hz "
              f"| {env['kurtosis']:+.2f} / {span(ks[:n], '+.3f')} / {span(ks[n:], '+.3f')} "
              f"| {env['ratio']:.0f} ({env['period_s']:.2f} s) / {span(rs[:n], '.0f')} / {span(rs[n:], '.0f')} "
              f"| {least:.2f}, {below:.0%} | {found} | {t_rec:+.4f} / {span(ts[:n], '+.4f')} / {span(ts[n:], '+.4f')} |")
    null = null_ratios(args.null)
    print(f"\nruns: {args.sims} simulations of the extended model the analysis wrote (seeds 0, 1, ...), with the tone's "
          f"excursion found (its cycle's phase random per run) and without it; a stationary Gaussian band's envelope line is about ln(K)/ln 2 = "
          f"{math.log(env['ordinates']) / math.log(2):.0f} on average over the K = {env['ordinates']} ordinates of the last "
          f"record. False alarms at the threshold R >= {EXCURSION_LINE_RATIO:g}: {sum(r >= EXCURSION_LINE_RATIO for r in null)} "
          f"of {len(null)} hidden-effect wandering tones without excursion (10-60 min; largest R {max(null):.0f}) and "
          f"{sum(r >= EXCURSION_LINE_RATIO for r in null_model)} of the {len(null_model)} runs above without it "
          f"(largest {max(null_model):.0f})")


if __name__ == "__main__":
    main()
