"""The confounded causes of the example model (docs/gap.md, "Confounded causes"): per record and
axis, D of the covariate reading (the temperature first) and of the time reading (a warm-up or a
slow wander instead), the allowance within which they count as equal, what the gap names, and the
temperature coefficient with its 95 % interval against the model's true one.

    python tools/gap_confound.py [--seeds 1,2,3,4] [--long-seeds 1,2,3] [--out FILE]

Records: gyrofilter/data/mpu6050_model.json simulated for 1 h at 100 Hz (``--seeds``) and for
24 h at 10 Hz (``--long-seeds``), each analysed by ``analyse_gap`` with the defaults (seed 0).
The numbers are read from the report's notes ("readings weighed on D"). The last line counts the
axes whose model has a bias instability: on how many it is named, and how the slow detector's
two wanders were weighed (notes "readings of the slow wander weighed on D";
``gyrofilter.analysis.gap.confound.weigh_wanders``).
"""
import argparse
import json
import re
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gyrofilter.analysis.gap.pipeline import analyse_gap  # noqa: E402
from gyrofilter.sim.simulate import simulate  # noqa: E402
from gyrofilter.units import AXES  # noqa: E402

WEIGHED = re.compile(r"axis (\w): readings weighed on D: with the temperature ([\d.e+-]+), in time \((.*)\) "
                     r"([\d.e+-]+); allowance ([\d.e+-]+) .*?: (.*)$")

#: the verdicts of gap.confound.weigh_wanders' notes
VERDICTS = ("the record cannot tell them apart", "the bias instability is clearly better",
            "the Gauss-Markov is clearly better")
WANDER = re.compile(r"axis (\w): readings of the slow wander weighed on D: .*: (" + "|".join(VERDICTS) + ")")


def rows(duration_s, sample_rate_hz, seed, model, tally):
    model = dict(model, sample_rate_hz=sample_rate_hz)
    t0 = time.perf_counter()
    report = analyse_gap(simulate(model, duration_s, seed=seed), seed=0)
    runtime = time.perf_counter() - t0
    weighed = {}
    for note in report["notes"]:
        m = WEIGHED.match(note)
        if m:
            weighed[m.group(1)] = m.groups()[1:]
        m = WANDER.match(note)
        if m:
            tally[m.group(2)] = tally.get(m.group(2), 0) + 1
    for a in AXES:
        if any(e["effect"] == "bias_instability" for e in model["axes"][a]["effects"]):
            tally["axes"] = tally.get("axes", 0) + 1
            tally["named"] = tally.get("named", 0) + any(f["axis"] == a and f["effect"] == "bias_instability"
                                                         for f in report["findings"])
        named = ", ".join(f["effect"] + ("*" if f.get("alternatives") else "") for f in report["findings"] if f["axis"] == a)
        coef = next((_coefficient(f, model, a) for f in report["findings"]
                     if f["axis"] == a and f["effect"] == "temperature"), "-")
        if a in weighed:
            d_cov, time_reading, d_time, allowance, verdict = weighed[a]
            time_names = ", ".join(re.findall(r"(\w+) \(", time_reading))
            cells = [d_cov, time_names, d_time, allowance, verdict.split(";")[0].split(",")[0]]
        else:
            cells = ["-", "-", "-", "-", "not confounded"]
        yield [f"{duration_s / 3600:g} h at {sample_rate_hz:g} Hz, seed {seed}", a] + cells + [named or "-", coef, f"{runtime:.0f} s"]


def _coefficient(finding, model, axis):
    """The coefficient, its 95 % interval and whether the model's true one lies in it."""
    value = finding["params"]["coefficient_dps_per_c"]
    true = next(e["coefficient_dps_per_c"] for e in model["axes"][axis]["effects"] if e["effect"] == "temperature")
    low, high = (finding.get("params_ci95") or {}).get("coefficient_dps_per_c") or (None, None)
    if low is None:
        return f"{value:.4g} (true {true:.4g}; no interval)"
    return f"{value:.4g} [{low:.4g}, {high:.4g}], true {true:.4g} {'inside' if low <= true <= high else 'OUTSIDE'}"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", default="1,2,3,4")
    p.add_argument("--long-seeds", default="1,2,3")
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    model = json.loads((ROOT / "gyrofilter" / "data" / "mpu6050_model.json").read_text(encoding="utf-8"))
    head = ["record", "axis", "D with the temperature", "time reading", "D in time", "allowance (2 null spreads)",
            "verdict", "named (* with alternatives)", "coefficient (deg/s/C) [95 % interval]", "gap runtime"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    runs = [(3600.0, 100.0, int(s)) for s in args.seeds.split(",") if s] + \
        [(86400.0, 10.0, int(s)) for s in args.long_seeds.split(",") if s]
    tally = {}
    for duration_s, sample_rate_hz, seed in runs:
        for row in rows(duration_s, sample_rate_hz, seed, model, tally):
            lines.append("| " + " | ".join(row) + " |")
            print(lines[-1], flush=True)
    lines += ["", f"bias_instability named on {tally.get('named', 0)} of {tally.get('axes', 0)} axes that have it; the two "
              f"wanders weighed on D on {sum(tally.get(v, 0) for v in VERDICTS)}: "
              + ", ".join(f"{v} on {tally.get(v, 0)}" for v in VERDICTS) + "."]
    print(lines[-1], flush=True)
    if args.out:
        Path(args.out).write_text("\n".join(lines) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
