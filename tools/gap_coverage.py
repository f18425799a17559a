"""Coverage of the gap's 95 % parameter intervals over hidden-effect batteries.

    python tools/gap_coverage.py [--cases 40] [--seed 9000] [--duration S] [--scale 1] [--sims 8]
                                 [--bootstrap N] [--effects a,b] [--compare] [--oracle] [-v]

For every effect kind of :mod:`gyrofilter.sim.hidden_effects` draws ``--cases`` cases (seeds
``seed + k``; random axis and parameters over the kind's ranges, 30-60 min unless
``--duration``), runs :func:`gyrofilter.analysis.gap.pipeline.analyse_gap` on each with ``--bootstrap``
replicates, and counts, for the cases where the hidden effect is named on its axis, how often
every true parameter lies inside the finding's ``params_ci95`` (a ``phase_rad`` modulo 2 pi;
``colored_noise``'s ``lag2`` where the finding reports it, against lag1² where the hidden
noise is a low pass). A parameter the record does not determine (``null``) is no trial: it is
counted apart (column ``null``), as are the cases where the hidden effect is listed as
``uncertain`` on its axis instead of named (column ``uncert``). The baseline's ``bias_dps`` and
``arw_dps_per_sqrt_hz`` are checked on the
two untouched axes of every case. Each row gives the trials (cases x parameters), the coverage
and its 95 % Wilson interval (the binomial uncertainty of a coverage measured on that many
trials; the parameters of one case are not independent, so it is a lower bound on the
uncertainty), and the coverage per parameter.

``--compare`` also scores, on the same bootstrap runs, the intervals the gap does not use: the
percentile interval ``[q_0.025, q_0.975]`` of the replicates, the basic interval
``[2 u - q_0.975, 2 u - q_0.025]`` on the parameter's scale, and the normal-t interval without the
bias correction (run it with ``--bootstrap 60`` or more: the percentiles of 20 runs are their
extremes). ``--oracle`` runs no gap: on the same ``bias_step`` records it scores the exact
interval of the step size (true step time, true noise level), the coverage the records' own noise
allows.
"""
from __future__ import annotations

import argparse
import math
import time
from collections import defaultdict

import numpy as np
from scipy.stats import t as student_t

import gyrofilter.analysis.gap.intervals as gi
import gyrofilter.sim.hidden_effects as he
from gyrofilter.analysis.gap.pipeline import analyse_gap
from gyrofilter.units import AXES


def inside(true, interval, name):
    """Whether ``true`` lies in ``interval`` ([low, high]; a phase modulo 2 pi)."""
    if interval is None:
        return False
    low, high = interval
    if name == "phase_rad":
        k = math.ceil((low - true) / (2 * math.pi))
        return low <= true + 2 * math.pi * k <= high
    return low <= true <= high


class Recorder:
    """Keeps every ``gap_intervals._interval`` call's estimate, replicates and scale, so that
    ``--compare`` can score other intervals on the same bootstrap runs."""

    def __init__(self):
        self.calls = []
        self._original = gi._interval

    def __enter__(self):
        def recording(estimate, replicates, scale, *bounds):  # bounds: the parameter's domain, as the gap's
            self.calls.append((estimate, list(replicates), scale))
            return self._original(estimate, replicates, scale, *bounds)

        gi._interval = recording
        return self

    def __exit__(self, *exc):
        gi._interval = self._original


def alternatives(estimate, replicates, scale):
    """The intervals ``--compare`` scores besides the gap's: ``{method: [low, high] or None}``."""
    if scale == "log" and not estimate > 0:
        scale = "linear"
    u_hat = float(gi._forward([estimate], scale)[0])
    u = gi._forward([np.nan if r is None else r for r in replicates], scale)
    u = u[np.isfinite(u)]
    if isinstance(gi._spread(estimate, replicates, scale), str):  # the gap's own rule: not determined
        return dict.fromkeys(METHODS[1:])
    dev = u - u_hat
    if scale == "phase":
        dev = (dev + math.pi) % (2 * math.pi) - math.pi
    lo, hi = np.quantile(dev, [0.025, 0.975])
    half = float(student_t.ppf(0.975, u.size - 1)) * math.sqrt(1 + 1 / u.size) * float(np.std(dev, ddof=1))
    pairs = {"percentile": (u_hat + lo, u_hat + hi), "basic": (u_hat - hi, u_hat - lo),
             "t, not bias-corrected": (u_hat - half, u_hat + half)}
    return {m: [gi._back(a, scale), gi._back(b, scale)] for m, (a, b) in pairs.items()}


METHODS = ("gap (bias-corrected t)", "percentile", "basic", "t, not bias-corrected")


def score(case, report, calls=None):
    """``(named, uncertain, {param: {method: inside}}, [params not determined], {param: [inside]} of
    the untouched axes' baseline)``; only the gap's own method unless ``calls`` (a
    :class:`Recorder`'s) are given."""
    hit = [f for f in report["findings"] if f["effect"] == case["effect"] and f["axis"] == case["axis"]]
    uncertain = any(e["effect"] == case["effect"] and e["axis"] == case["axis"] for e in report.get("uncertain", []))
    found, null = {}, []
    if hit:
        f = hit[0]
        for name, value in f["params"].items():
            if name not in case["params"] and not (name == "lag2" and case["effect"] == "colored_noise"):
                continue
            interval = (f.get("params_ci95") or {}).get(name)
            if interval is None:
                null.append(name)
                continue
            true = case["params"].get(name, case["params"].get("lag1", 0.0) ** 2)
            found[name] = {METHODS[0]: inside(true, interval, name)}
            call = next((c for c in calls or [] if c[0] == value), None)
            if call is not None:
                found[name].update({m: inside(true, iv, name) for m, iv in alternatives(*call).items()})
    base = defaultdict(list)
    for a in AXES:
        if a == case["axis"]:
            continue
        got = report["baseline"]["axes"][a].get("params_ci95") or {}
        true = case["model"]["axes"][a]
        for name in ("bias_dps", "arw_dps_per_sqrt_hz"):
            base[name].append(inside(true[name], got.get(name), name))
    return bool(hit), uncertain, found, null, base


def oracle(args):
    """``--oracle``: on the same ``bias_step`` records, the coverage of the exact interval of the
    step size, mean after - mean before at the true step time +- 1.96 sigma sqrt(1/n1 + 1/n2)
    with the true per-sample sigma (quantization included): what the records' own noise allows,
    no estimator involved."""
    kinds = args.effects.split(",") if args.effects else list(he.EFFECTS)
    ok = n = 0
    for k in range(args.cases * len(kinds)):
        if kinds[k % len(kinds)] != "bias_step":
            continue
        case = he.draw_case(args.seed + k, effect="bias_step", duration_s=args.duration, scale=args.scale)
        rec = he.simulate_case(case)
        i = AXES.index(case["axis"])
        x = rec.gyro_dps[:, i]
        rate = rec.sample_rate_hz
        first = int(math.ceil(case["params"]["time_s"] * rate - 1e-9))
        axis = case["model"]["axes"][case["axis"]]
        sigma = math.sqrt(axis["arw_dps_per_sqrt_hz"] ** 2 * rate + (1 / case["model"]["lsb_per_dps"]) ** 2 / 12)
        size = float(x[first:].mean() - x[:first].mean())
        half = 1.96 * sigma * math.sqrt(1 / first + 1 / (x.size - first))
        ok += abs(size - case["params"]["size_dps"]) <= half
        n += 1
    lo, hi = he.wilson(ok, n)
    print(f"bias_step size_dps, exact interval at the true step time with the true noise level: {ok}/{n} = "
          f"{100 * ok / max(n, 1):.1f} % [{100 * lo:.1f}, {100 * hi:.1f}] (the records' own luck)")


def run(args):
    if args.oracle:
        oracle(args)
        return
    kinds = args.effects.split(",") if args.effects else list(he.EFFECTS)
    rows = defaultdict(lambda: {"cases": 0, "named": 0, "uncertain": 0, "null": defaultdict(int),
                                "params": defaultdict(lambda: defaultdict(lambda: [0, 0]))})
    base = defaultdict(lambda: [0, 0])
    times = []
    t_all = time.perf_counter()
    for k in range(args.cases * len(kinds)):
        effect = kinds[k % len(kinds)]
        case = he.draw_case(args.seed + k, effect=effect, duration_s=args.duration, scale=args.scale)
        rec = he.simulate_case(case)
        t0 = time.perf_counter()
        with Recorder() as recorder:
            report = analyse_gap(rec, seed=args.seed + k, n_sims=args.sims, bootstrap=args.bootstrap)
        times.append((time.perf_counter() - t0, report.get("intervals", {}).get("runtime_s", 0.0)))
        named, uncertain, found, null, base_in = score(case, report, recorder.calls if args.compare else None)
        row = rows[effect]
        row["cases"] += 1
        row["named"] += named
        row["uncertain"] += uncertain
        for name in null:
            row["null"][name] += 1
        for name, by_method in found.items():
            for method, ok in by_method.items():
                row["params"][name][method][0] += ok
                row["params"][name][method][1] += 1
        for name, oks in base_in.items():
            base[name][0] += sum(oks)
            base[name][1] += len(oks)
        if args.verbose:
            hit = next((f for f in report["findings"] if f["effect"] == effect and f["axis"] == case["axis"]), None)
            got = ("; ".join(f"{p}={hit['params'][p]:.4g} [{', '.join(f'{v:.4g}' for v in (hit.get('params_ci95') or {}).get(p) or [])}]"
                             f"{'' if ok[METHODS[0]] else ' MISS'}" for p, ok in found.items())
                   + "".join(f"; {p} not determined" for p in null) if hit else
                   "uncertain" if uncertain else "not named")
            true = ", ".join(f"{p}={v:.4g}" for p, v in case["params"].items())
            print(f"case {args.seed + k:5d} {effect:17s} {case['axis']} {true} -> {got}", flush=True)
    summarise(rows, base, times, time.perf_counter() - t_all, args.compare)


def _line(label, cases, named, uncertain, ok, n, null, per_param):
    lo, hi = he.wilson(ok, n)
    cover = f"{100 * ok / n:6.1f} %  [{100 * lo:4.1f}, {100 * hi:5.1f}]" if n else f"{'-':>8s}  {'':14s}"
    print(f"{label:22s} {cases:>5} {named:>5} {n:6d} {ok:6d} {cover} {uncertain:>6} {null:>4}  {per_param}")


def summarise(rows, base, times, total_s, compare=False):
    print()
    print(f"{'effect':22s} {'cases':>5s} {'named':>5s} {'trials':>6s} {'inside':>6s} {'coverage':>8s}  "
          f"{'95 % (Wilson)':14s} {'uncert':>6s} {'null':>4s}  per parameter (inside/trials)")
    total = defaultdict(lambda: [0, 0])
    for effect, row in rows.items():
        for method in METHODS:
            for v in row["params"].values():
                if method in v:
                    total[(effect, method)][0] += v[method][0]
                    total[(effect, method)][1] += v[method][1]
                    total[("all", method)][0] += v[method][0]
                    total[("all", method)][1] += v[method][1]
        per = ", ".join([f"{p} {v[METHODS[0]][0]}/{v[METHODS[0]][1]}" for p, v in row["params"].items()]
                        + [f"{p} null {k}" for p, k in row["null"].items()])
        _line(effect, row["cases"], row["named"], row["uncertain"], *total[(effect, METHODS[0])],
              sum(row["null"].values()), per)
    _line("all effects", sum(r["cases"] for r in rows.values()), sum(r["named"] for r in rows.values()),
          sum(r["uncertain"] for r in rows.values()), *total[("all", METHODS[0])],
          sum(sum(r["null"].values()) for r in rows.values()), "")
    for name, (ok, n) in base.items():
        _line(f"baseline {name}"[:22], "", "", "", ok, n, "", "(the untouched axes)")
    gap_s = sorted(t for t, _ in times)
    iv_s = sorted(t for _, t in times)
    print(f"gap runtime per case: median {gap_s[len(gap_s) // 2]:.1f} s, of which intervals "
          f"{iv_s[len(iv_s) // 2]:.1f} s; battery {total_s:.0f} s")
    if compare:
        print()
        print("coverage of other intervals on the same bootstrap runs (%):")
        print(f"{'effect':22s} " + " ".join(f"{m:>24s}" for m in METHODS))
        for effect in list(rows) + ["all"]:
            cells = [total[(effect, m)] for m in METHODS]
            print(f"{effect:22s} " + " ".join(f"{100 * ok / n if n else float('nan'):24.1f}" for ok, n in cells))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--cases", type=int, default=40, help="cases per effect kind")
    p.add_argument("--seed", type=int, default=9000)
    p.add_argument("--scale", type=float, default=1.0)
    p.add_argument("--duration", type=float, default=None, help="record length in s (default: 30-60 min drawn)")
    p.add_argument("--sims", type=int, default=8, help="baseline simulations (the intervals do not depend on them)")
    p.add_argument("--bootstrap", type=int, default=gi.DEFAULT_BOOTSTRAP)
    p.add_argument("--effects", default=None, help="comma-separated effect kinds (default: all)")
    p.add_argument("--oracle", action="store_true",
                   help="only the exact step-size interval on the same bias_step records (no gap run)")
    p.add_argument("--compare", action="store_true", help="also score the percentile, basic and not bias-corrected intervals")
    p.add_argument("-v", "--verbose", action="store_true")
    args = p.parse_args(argv)
    run(args)


if __name__ == "__main__":
    main()
