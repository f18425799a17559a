"""gyrofilter allan: overlapping Allan deviation and noise coefficients of a recording.

Prints, per axis, the fitted coefficients Q, N, B, K, R with their intervals in deg/s-based and
customary units, the slope read-offs of papers 000/002 beside them, and what the record is too
short to resolve. ``--json`` writes the Allan document of docs/formats.md, ``--plot`` the
log-log figure, ``--kalibr`` Kalibr's imu.yaml gyroscope entries.
"""
import json
import sys

from ..allan import MIN_CLUSTERS
from ..errors import SettingsError
from ..noise_model import (CUSTOMARY_UNIT, TERM_SYMBOL, TERM_UNIT, TERMS, characterise_axis,
                           convert, kalibr_yaml, to_json)
from ..recording import read_recording

NAMES = {"quantization": "quantization", "arw": "angle random walk", "bias_instability": "bias instability",
         "rrw": "rate random walk", "rate_ramp": "rate ramp"}


def add_arguments(parser):
    parser.add_argument("recording", help="recording file (format v1, .csv or .csv.gz), sensor still")
    parser.add_argument("--json", metavar="OUT", help="write the deviation curves and coefficients as JSON")
    parser.add_argument("--plot", metavar="OUT.png", help="draw the Allan deviation per axis (needs matplotlib)")
    parser.add_argument("--kalibr", metavar="OUT.yaml", help="write Kalibr imu.yaml gyroscope noise entries")
    parser.add_argument("--axes", default="xyz", help="axes to analyse, a subset of xyz (default xyz)")
    parser.add_argument("--confidence", type=float, default=0.95, help="two-sided confidence of the intervals (default 0.95)")
    parser.add_argument("--min-clusters", type=int, default=MIN_CLUSTERS,
                        help=f"fit only taus with at least this many clusters (default {MIN_CLUSTERS}, paper 002; lower values are flagged)")
    parser.add_argument("--progress", action="store_true", help="report progress on stderr")


def _say(text):
    print(text, file=sys.stderr)


def _fmt(c, unit):
    if c.value is None:
        up = convert(c.upper, c.term, unit)
        return "not resolved" + (f" (< {up:.3g})" if up is not None else "")
    v, lo, hi = (convert(x, c.term, unit) for x in (c.value, c.low, c.high))
    return f"{v:.4g} [{lo:.3g}, {hi:.3g}]"


def run(args):
    axes = args.axes
    if not axes or any(a not in "xyz" for a in axes) or len(set(axes)) != len(axes):
        raise SettingsError(f"--axes must be a subset of xyz such as xz, got {args.axes!r}")
    if args.min_clusters < 2:
        raise SettingsError(f"--min-clusters must be at least 2, got {args.min_clusters}")
    rec = read_recording(args.recording)
    for w in rec.warnings:
        _say(f"gyrofilter: warning: {w}")
    if "t" in rec.columns and len(rec) > 1:
        import numpy as np

        gaps = int((np.diff(rec.columns["t"]) > 1.5 / rec.sample_rate_hz).sum())
        if gaps:
            _say(f"gyrofilter: warning: {args.recording}: t shows {gaps} gap(s); the Allan deviation assumes uniform samples")
    gyro = rec.gyro_dps
    fs = rec.sample_rate_hz
    progress = args.progress or sys.stderr.isatty()
    results = {}
    for a in axes:
        if progress:
            _say(f"allan: axis {a} ({len(gyro)} samples)...")
        results[a] = characterise_axis(gyro[:, "xyz".index(a)], fs, axis=a, confidence=args.confidence,
                                       min_clusters=args.min_clusters)
    print(f"recording: {args.recording}")
    print(f"  {len(rec)} samples at {fs:g} Hz ({rec.duration_s:.1f} s); unit {rec.gyro_unit}; "
          f"taus {results[axes[0]].tau_s[0]:g} .. {results[axes[0]].tau_s[-1]:g} s")
    print(f"  coefficients: weighted NNLS fit of the five-term Allan model, value [{args.confidence:.0%} interval]; "
          "read-off = slope method of papers 000/002")
    for a, r in results.items():
        print(f"  axis {a}:")
        for t in TERMS:
            c, ro = r.fitted[t], r.readoff[t]
            base, cust = TERM_UNIT[t], CUSTOMARY_UNIT[t]
            print(f"    {TERM_SYMBOL[t]} {NAMES[t]:<17} {_fmt(c, base):<34} {base:<14} = {_fmt(c, cust):<32} {cust:<14}"
                  f" read-off: {_fmt(ro, base)}")
        missing = [TERM_SYMBOL[t] for t in ("bias_instability", "rrw", "rate_ramp") if r.fitted[t].value is None]
        if missing:
            longest = r.tau_s[r.fit_used][-1]
            print(f"    ({', '.join(missing)} not resolved: the longest cluster time with {args.min_clusters} clusters is "
                  f"{longest:.3g} s; slower effects need a longer still recording; the bounds above hold)")
        for w in r.warnings:
            _say(f"gyrofilter: warning: {w}")
    if args.json:
        doc = to_json(results, fs, recording=args.recording, duration_s=rec.duration_s)
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(doc, fh, indent=1)
        _say(f"wrote {args.json}")
    if args.kalibr:
        with open(args.kalibr, "w", encoding="utf-8") as fh:
            fh.write(kalibr_yaml(results, fs, recording=args.recording))
        _say(f"wrote {args.kalibr}")
    if args.plot:
        from ..plots_allan import plot_allan

        plot_allan(args.plot, results, title=f"{args.recording} ({rec.duration_s:.0f} s at {fs:g} Hz)")
        _say(f"drew {args.plot}")
    return 0
