"""``gyrofilter gap RECORDING --json OUT.json [--report DIR] [--seed N] [--sims N]``.

Finds what the baseline noise model (constant bias + white noise + quantization) gets wrong
about a recording, names the cause (an effect of the effect table), extends the model and
measures the gain; writes the report of ``shared/interfaces.md`` section 2 to OUT.json and,
with ``--report``, a Markdown report with PNG figures. A one-line summary per finding goes to
stdout; progress goes to stderr (on a terminal, or with ``--progress``).
"""
import json
import math
import os
import sys
import time

import numpy as np


def add_arguments(parser):
    parser.add_argument("recording", metavar="RECORDING", help="recording file (format v1, .csv or .csv.gz)")
    parser.add_argument("--json", required=True, metavar="OUT.json", help="write the gap report (JSON) here")
    parser.add_argument("--report", metavar="DIR", default=None, help="also write a Markdown report with PNG figures to DIR")
    parser.add_argument("--seed", type=int, default=0, metavar="N", help="seed of the simulations (default 0)")
    parser.add_argument("--sims", type=int, default=None, metavar="N",
                        help="baseline simulations (default 24; 12-24 above 200 000 samples per axis)")
    parser.add_argument("--progress", action="store_true", help="show progress on stderr even when it is not a terminal")


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_jsonable(v) for v in value.tolist()]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def run(args):
    from ..errors import SettingsError
    from ..gap import analyse_gap
    from ..recording import read_recording

    if args.sims is not None and args.sims < 2:
        raise SettingsError(f"--sims must be >= 2, got {args.sims}")
    if args.seed < 0:
        raise SettingsError(f"--seed must be >= 0, got {args.seed}")
    show = args.progress or sys.stderr.isatty()
    t0 = time.perf_counter()

    def progress(text):
        if show:
            print(f"gap [{time.perf_counter() - t0:5.1f} s] {text}", file=sys.stderr, flush=True)

    rec = read_recording(args.recording)
    for text in rec.warnings:
        print(f"gyrofilter: warning: {text}", file=sys.stderr)
    progress(f"read {len(rec)} samples at {rec.sample_rate_hz:g} Hz")
    report = analyse_gap(rec, seed=args.seed, n_sims=args.sims, progress=progress,
                         recording_name=args.recording)
    out_dir = os.path.dirname(os.path.abspath(args.json))
    os.makedirs(out_dir, exist_ok=True)
    with open(args.json, "w", encoding="utf-8") as fh:
        json.dump(_jsonable(report), fh, indent=1)
        fh.write("\n")
    if args.report:
        from ..gap_report import write_report

        progress("report")
        path = write_report(report, rec, args.report, seed=args.seed)
        progress(f"wrote {path}")
    d = report.get("discrepancy", {})
    print(f"{args.recording}: {len(report['findings'])} finding(s); discrepancy "
          f"{d.get('overall_before', float('nan')):.3g} -> {d.get('overall_after', float('nan')):.3g} "
          f"({report.get('runtime_s', time.perf_counter() - t0):.1f} s)")
    for f in report["findings"]:
        params = ", ".join(f"{k}={v:.4g}" for k, v in f["params"].items())
        print(f"  {f['axis']}: {f['effect']} ({params}); D {f['gain']['before']:.3g} -> {f['gain']['after']:.3g}")
    for note in report.get("notes", []):
        print(f"  note: {note}")
    return 0
