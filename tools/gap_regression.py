"""The hidden-effect battery, paired: the same cases analysed by this checkout and by an earlier
revision, scored alike. Does a change keep the battery's rate, case by case?

    python tools/gap_regression.py --rev REV [--cases 72] [--seed 4000] [--scale 1] [--duration S]
                                   [--sims 12] [-v]

The cases are :func:`gap_battery.battery_cases` (every kind cycled, as ``tools/gap_battery.py``
draws them), less the kinds REV's simulator does not know; each is simulated by this checkout and
written as a recording into a temporary folder, so both versions read the same samples. REV is
exported with ``git archive`` and each version runs ``analyse_gap(read_recording(FILE), seed=case
seed, n_sims=--sims)`` on every file in its own process (``PYTHONPATH`` = its tree; the two run
at once). Both reports are scored by this checkout's :func:`gyrofilter.sim.hidden_effects.check`.

Printed: per effect, the cases and how many each version names within tolerance (clean cases:
how many have any finding); the totals with their 95 % Wilson intervals; the cases gained and
lost, and the exact two-sided McNemar p of the difference (the binomial test of the discordant
pairs, McNemar 1947): a paired comparison tells a change from the luck of the draw on far fewer
cases than two unpaired rates; how many cases of each version have a finding besides the hidden
one (a false cause: scored apart from the named rate).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import zipfile
from collections import defaultdict
from pathlib import Path

import gyrofilter.sim.hidden_effects as he
from gyrofilter.recording import write_recording

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))  # the battery's own cases, by name (also when loaded from a test)
from gap_battery import battery_cases  # noqa: E402

#: run in each version's own process: analyse every recording of the folder, write its findings
WORKER = r"""
import glob, json, os, sys
import gyrofilter
try:
    from gyrofilter.analysis.gap.pipeline import analyse_gap
except ImportError:  # a revision from before the analysis families moved into folders
    from gyrofilter.analysis.gap import analyse_gap
from gyrofilter.recording import read_recording
folder, tag, tree, sims = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
assert os.path.realpath(gyrofilter.__file__).startswith(os.path.realpath(tree)), gyrofilter.__file__
for path in sorted(glob.glob(os.path.join(folder, "*.csv"))):
    seed = int(os.path.basename(path)[:-4])
    rep = analyse_gap(read_recording(path), seed=seed, n_sims=sims)
    keep = [{"axis": f["axis"], "effect": f["effect"], "params": f["params"],
             "alternatives": f.get("alternatives", [])} for f in rep["findings"]]
    with open(os.path.join(folder, f"{seed}.{tag}.json"), "w") as fh:
        json.dump({"findings": keep}, fh)
"""


def export(rev, into):
    """``git archive REV`` of this repository unpacked into ``into``; the tree's path."""
    zip_path = os.path.join(into, "rev.zip")
    subprocess.run(["git", "-C", str(ROOT), "archive", "--format=zip", "-o", zip_path, rev], check=True)
    tree = os.path.join(into, "rev")
    with zipfile.ZipFile(zip_path) as archive:
        archive.extractall(tree)
    return tree


def known_effects(tree):
    """The effect kinds of the simulator in ``tree``."""
    out = subprocess.run([sys.executable, "-c", "import gyrofilter.sim.hidden_effects as he; print(','.join(he.EFFECTS))"],
                         env=dict(os.environ, PYTHONPATH=tree), cwd=tree, check=True, stdout=subprocess.PIPE, text=True)
    return set(out.stdout.strip().split(",")) | {"none"}


def mcnemar_p(gained, lost):
    """Exact two-sided McNemar p: the binomial(gained + lost, 1/2) probability of a split at
    least as uneven as this one."""
    n, k = gained + lost, min(gained, lost)
    if n == 0:
        return 1.0
    return min(1.0, 2.0 * sum(math.comb(n, j) for j in range(k + 1)) / 2.0**n)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--rev", required=True, help="the earlier revision (a git commit, tag or branch)")
    p.add_argument("--cases", type=int, default=72)
    p.add_argument("--seed", type=int, default=4000)
    p.add_argument("--scale", type=float, default=1.0)
    p.add_argument("--duration", type=float, default=None, help="record length in s (default: 30-60 min drawn)")
    p.add_argument("--sims", type=int, default=12)
    p.add_argument("-v", "--verbose", action="store_true", help="also list the cases the two score differently")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="gap-regression-") as work:
        tree = export(args.rev, work)
        known = known_effects(tree)
        folder = os.path.join(work, "cases")
        os.makedirs(folder)
        cases = {}
        for seed, case in battery_cases(args.cases, args.seed, duration_s=args.duration, scale=args.scale):
            if case["effect"] in known:
                write_recording(os.path.join(folder, f"{seed}.csv"), he.simulate_case(case))
                cases[seed] = case
        procs = [subprocess.Popen([sys.executable, "-c", WORKER, folder, tag, t, str(args.sims)], cwd=work,
                                  env=dict(os.environ, PYTHONPATH=t))
                 for tag, t in (("rev", tree), ("here", str(ROOT)))]
        if any(proc.wait() != 0 for proc in procs):
            sys.exit("gap_regression: an analysis failed (its traceback above)")
        scores, extras = {}, {}
        for seed, case in cases.items():
            scores[seed] = []
            for tag in ("rev", "here"):
                with open(os.path.join(folder, f"{seed}.{tag}.json")) as fh:
                    named, ok, others = he.check(case, json.load(fh))
                scores[seed].append(bool(others) if case["effect"] == "none" else ok)
                extras.setdefault(seed, []).append(bool(others))
    report(args, cases, scores, extras, list(he.EFFECTS) + ["none"])


def report(args, cases, scores, extras, order):
    """The table of :func:`main`'s docstring; ``extras``: per case, whether each version has a
    finding other than the hidden one."""
    by = defaultdict(list)
    for seed, case in cases.items():
        by[case["effect"]].append(scores[seed])
    print(f"{'effect':18s} {'cases':>5s} {args.rev:>12s} {'this checkout':>14s}   (named in tolerance; clean: with a finding)")
    effect_pairs = []
    for effect in order:
        rows = by.get(effect)
        if not rows:
            continue
        print(f"{effect + (' (clean)' if effect == 'none' else ''):18s} {len(rows):5d} {sum(r[0] for r in rows):12d} "
              f"{sum(r[1] for r in rows):14d}")
        if effect != "none":
            effect_pairs += rows
    n = len(effect_pairs)
    if n:
        line = []
        for j, name in enumerate((args.rev, "this checkout")):
            k = sum(r[j] for r in effect_pairs)
            lo, hi = he.wilson(k, n)
            line.append(f"{name} {k}/{n} = {100 * k / n:.1f} % [{100 * lo:.1f}, {100 * hi:.1f}]")
        print("in tolerance (95 % Wilson): " + "; ".join(line))
        gained = sum(1 for r in effect_pairs if r[1] and not r[0])
        lost = sum(1 for r in effect_pairs if r[0] and not r[1])
        print(f"paired: {gained} case(s) gained, {lost} lost; exact McNemar p = {mcnemar_p(gained, lost):.2g}")
        hidden = [extras[seed] for seed, case in cases.items() if case["effect"] != "none"]
        print(f"cases with a finding besides the hidden one: {args.rev} {sum(e[0] for e in hidden)}, "
              f"this checkout {sum(e[1] for e in hidden)} of {len(hidden)}")
    if args.verbose:
        for seed, (old, new) in sorted(scores.items()):
            if old != new or extras[seed][0] != extras[seed][1]:
                print(f"  case {seed} {cases[seed]['effect']} on {cases[seed]['axis']}: {args.rev} {old}, this checkout {new}"
                      f"; extra findings: {args.rev} {extras[seed][0]}, this checkout {extras[seed][1]}")


if __name__ == "__main__":
    main()
