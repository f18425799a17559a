"""Battery of hidden-effect cases for the gap analysis: detection and false-finding rates.

    python tools/gap_battery.py [--cases 110] [--seed 0] [--scale 1] [--duration S] [--sims N]
                                [--real recordings/mpu6050_static_655s.csv.gz ...]

Draws ``--cases`` cases with :func:`tests.hidden_effects.draw_case` (seeds ``seed .. seed +
cases - 1``; every effect of the table equally often, plus clean cases), runs
:func:`gyrofilter.analysis.gap.pipeline.analyse_gap` on each and prints per effect: cases, named on the right
axis, named with parameters within tolerance, and extra findings; for clean cases the fraction
with any finding; and how often hidden heavy tails were named outliers and hidden outliers heavy
tails (on the hidden axis). ``--scale 0.333 --duration 600`` is the harder set (effects a third of the
size, 10-minute recordings). ``--real FILE`` hides the effects in real static recordings
instead (real noise as the baseline; findings already present in the untouched recording are
not counted as extra).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from collections import defaultdict

import numpy as np

import gyrofilter.sim.hidden_effects as he



def battery_cases(cases, seed, *, effects=None, duration_s=None, scale=1.0):
    """The battery's cases, ``(seed + k, case)`` for k < ``cases``: the effect kinds (``effects``,
    comma-separated; default every effect of the table and ``none``) cycled, so each is drawn
    equally often."""
    kinds = effects.split(",") if effects else list(he.EFFECTS) + ["none"]
    for k in range(cases):
        yield seed + k, he.draw_case(seed + k, effect=kinds[k % len(kinds)], duration_s=duration_s, scale=scale)


def hidden_axis_d_after(case, rep):
    """D after extension on the axes the case's effect was hidden on (every axis of a clean case
    or of a whole-row effect)."""
    axes = case["axis"] if case["axis"] in tuple("xyz") else "xyz"
    return [rep["discrepancy"]["after"][a] for a in axes]


def run_synthetic(args):
    from gyrofilter.analysis.gap.pipeline import analyse_gap

    rows = []
    t_all = time.perf_counter()
    for seed, case in battery_cases(args.cases, args.seed, effects=args.effects, duration_s=args.duration,
                                    scale=args.scale):
        effect = case["effect"]
        rec = he.simulate_case(case)
        t0 = time.perf_counter()
        rep = analyse_gap(rec, seed=seed, n_sims=args.sims)
        dt = time.perf_counter() - t0
        named, ok, others = he.check(case, rep)
        rows.append((case, named, ok, others, dt, hidden_axis_d_after(case, rep)))
        if args.verbose:
            got = "; ".join(f"{f['axis']}:{f['effect']} " + ", ".join(f"{a}={v:.3g}" for a, v in f["params"].items())
                            for f in rep["findings"])
            true = ", ".join(f"{a}={v:.3g}" if isinstance(v, (int, float)) else f"{a}={v}" for a, v in case["params"].items())
            print(f"case {seed:4d} {effect:17s} {case['axis'] or '-'} {true:55s} -> "
                  f"{'OK ' if ok else ('nam' if named else '---')} [{got}] {dt:.1f}s", flush=True)
    summarise(rows, time.perf_counter() - t_all, args.d_after)


def run_real(args):
    from gyrofilter.analysis.gap.pipeline import analyse_gap
    from gyrofilter.recording import read_recording

    rows = []
    t_all = time.perf_counter()
    k = 0
    for path in args.real:
        rec = read_recording(path)
        base_rep = analyse_gap(rec, seed=args.seed, n_sims=args.sims)
        present = {(f["effect"], f["axis"]) for f in base_rep["findings"]}
        print(f"{os.path.basename(path)}: untouched recording -> {sorted(present)}", flush=True)
        for j in range(args.cases):
            effect = he.EFFECTS[(k + j) % len(he.EFFECTS)]
            if effect == "temperature" and (rec.temp_c is None or np.ptp(rec.temp_c) < 0.3):
                effect = "warmup"
            case = he.draw_case(args.seed + 1000 * k + j, effect=effect, duration_s=rec.duration_s, scale=args.scale)
            if effect == "temperature":
                # the real temperature varies little: scale the coefficient to a visible size
                case["params"]["coefficient_dps_per_c"] *= 3.0 / max(np.ptp(rec.temp_c), 0.1)
            case["params"].pop("phase_rad", None)
            hidden = he.hide_in_recording(rec, case["effect"], case["axis"], case["params"], seed=case["sim_seed"])
            t0 = time.perf_counter()
            rep = analyse_gap(hidden, seed=args.seed + j, n_sims=args.sims)
            dt = time.perf_counter() - t0
            named, ok, others = he.check(case, rep)
            others = [f for f in others if (f["effect"], f["axis"]) not in present]
            rows.append((case, named, ok, others, dt, hidden_axis_d_after(case, rep)))
            if args.verbose:
                got = "; ".join(f"{f['axis']}:{f['effect']}" for f in rep["findings"])
                print(f"  {effect:17s} {case['axis']} -> {'OK ' if ok else ('nam' if named else '---')} [{got}]", flush=True)
        k += 1
    summarise(rows, time.perf_counter() - t_all, args.d_after)


def summarise(rows, total_s, d_after=False):
    by = defaultdict(list)
    for row in rows:
        by[row[0]["effect"]].append(row)
    print()
    print(f"{'effect':18s} {'cases':>5s} {'named':>6s} {'in tol':>7s} {'extra findings':>15s}")
    n_eff = n_named = n_ok = 0
    for effect in list(he.EFFECTS) + ["none"]:
        rs = by.get(effect, [])
        if not rs:
            continue
        extra = sum(1 for r in rs if r[3])
        if effect == "none":
            print(f"{'none (clean)':18s} {len(rs):5d} {'':>6s} {'':>7s} {extra:9d} ({100 * extra / len(rs):.0f} %)")
            continue
        named = sum(r[1] for r in rs)
        ok = sum(r[2] for r in rs)
        n_eff += len(rs)
        n_named += named
        n_ok += ok
        print(f"{effect:18s} {len(rs):5d} {named:6d} {ok:7d} {extra:9d}")
    if n_eff:
        lo, hi = he.wilson(n_ok, n_eff)
        print(f"{'all effects':18s} {n_eff:5d} {n_named:6d} {n_ok:7d}   detection (named, in tolerance): "
              f"{100 * n_named / n_eff:.1f} %, {100 * n_ok / n_eff:.1f} % (95 % Wilson interval of the latter: "
              f"{100 * lo:.1f}-{100 * hi:.1f} %)")
    for hidden, named_as in (("heavy_tails", "outliers"), ("outliers", "heavy_tails")):  # the two readings of tails
        rs = by.get(hidden, [])
        if rs:
            wrong = sum(any(f["effect"] == named_as and f["axis"] == r[0]["axis"] for f in r[3]) for r in rs)
            print(f"{hidden} cases named {named_as} on their axis: {wrong} of {len(rs)}")
    if d_after:  # D after against the clean records' null band (2: their 95th percentile, docs/gap.md)
        for effect in list(he.EFFECTS) + ["none"]:
            ds = [d for r in by.get(effect, []) for d in r[5]]
            if ds:
                what = "axes of clean cases" if effect == "none" else f"{effect} cases, on the hidden axis"
                print(f"D after <= 2 on {sum(d <= 2.0 for d in ds)} of {len(ds)} {what} (median {np.median(ds):.2f}, "
                      f"max {np.max(ds):.2f})")
    times = [r[4] for r in rows]
    print(f"gap runtime per case: median {np.median(times):.1f} s, max {np.max(times):.1f} s; battery {total_s:.0f} s")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--cases", type=int, default=110)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--scale", type=float, default=1.0)
    p.add_argument("--duration", type=float, default=None, help="record length in s (default: 30-60 min drawn)")
    p.add_argument("--sims", type=int, default=None)
    p.add_argument("--real", nargs="*", default=None, help="hide effects in these real recordings instead")
    p.add_argument("--effects", default=None, help="comma-separated effects to cycle through (e.g. none for a clean battery)")
    p.add_argument("--d-after", action="store_true", help="also count the hidden axis's D after extension at or below 2")
    p.add_argument("-v", "--verbose", action="store_true")
    p.add_argument("--out", default=None, help="also write the summary table to this file")
    args = p.parse_args(argv)
    import contextlib
    import io

    buf = io.StringIO()
    out = sys.stdout  # whatever stdout is now (a caller may have redirected it)

    class Tee(io.TextIOBase):
        def write(self, text):
            out.write(text)
            buf.write(text)
            return len(text)

        def flush(self):
            out.flush()

    with contextlib.redirect_stdout(Tee()):
        if args.real:
            run_real(args)
        else:
            run_synthetic(args)
    if args.out:
        cmd = "python tools/gap_battery.py " + " ".join(argv if argv is not None else sys.argv[1:])
        lines = [ln for ln in buf.getvalue().splitlines() if not ln.startswith(("case ", "  "))]
        with open(args.out, "w", encoding="utf-8") as fh:
            fh.write(cmd + "\n" + "\n".join(lines).strip() + "\n")


if __name__ == "__main__":
    main()
