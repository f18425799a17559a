"""Do gap's answers hold on other simulations? The same records analysed with the simulations
drawn from seeds 0, 1 and 2: the causes per axis, the intervals, and D.

    python tools/gap_stability.py [--seeds 0,1,2] [--bootstrap N] [--sim-seeds 1,2,3,4,5,6]
                                  [--only SUBSTRING] [--adis DIR] [--jobs 2] [--json OUT]

Records: those of ``tools/gap_closure.py`` (the ADIS16405 logs where ``../shared/data`` has them,
the shipped static MPU6050 logs, the BROAD rest phases), none of which the detectors were tuned
on, and the default model's 10-minute records (``gyrofilter record --source
sim:seed=K,realtime=0 --duration 600``, one per ``--sim-seeds``). Each is analysed by
``analyse_gap`` with the command's defaults (intervals included) once per ``--seeds``, the seed
drawing every simulation (the decisions' and the intervals'). The commands use seed 0 whatever
their ``--seed`` (``COMMAND_SEED``), so their answer is the first column; the others show how it
holds on other simulations, the measure of how sure the decisions are.

Per axis it counts:

* **same causes**: the set of named effects is the same for every seed (an effect reported as
  uncertain is not named);
* **interval outside**: a ``params_ci95`` interval that does not contain its own estimate;
* **interval over 100x**: a positive (log-scale) parameter's interval whose ends differ by more
  than a factor 100, the rule of :mod:`gyrofilter.analysis.gap.intervals` (printed intervals only:
  ``null``, "not determined", counts as neither; a signed parameter such as an autocorrelation
  near 0, [8e-6, 0.005], is bounded by its distance from 0, not by its ratio);
* for the default model's records, a named cause outside the model's own terms (its model has
  white noise, bias instability, temperature and quantization), and whether the temperature is
  named or listed as an alternative.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

#: the default model's terms a finding may name (gyrofilter.sim.model's default: white noise,
#: bias instability, temperature sensitivity, quantization)
DEFAULT_MODEL_EFFECTS = {"bias_instability", "temperature"}


def _sim_record(seed, folder):
    path = os.path.join(folder, f"default_model_seed{seed}.csv.gz")
    subprocess.run([sys.executable, "-m", "gyrofilter", "record", "--source", f"sim:seed={seed},realtime=0",
                    "--duration", "600", "--out", path, "--quiet"], check=True)
    return path


def _job(args):
    name, seed, only_path, bootstrap, adis = args
    from gap_closure import records

    from gyrofilter.analysis.gap.pipeline import analyse_gap
    from gyrofilter.recording import read_recording

    if only_path:
        rec = read_recording(only_path)
    else:
        rec = next(r for n, r in records(only=name, adis_dir=adis) if n == name)
    rep = analyse_gap(rec, seed=seed, bootstrap=bootstrap)
    return name, seed, rep


def axis_rows(rep):
    """{axis: {"named": sorted effects, "alternatives": effects listed, "outside": [...],
    "wide": [...], "D": D after}} of one report."""
    from gyrofilter.analysis.gap.intervals import MAX_SPAN_RATIO, SCALES

    out = {a: {"named": [], "alternatives": [], "outside": [], "wide": [], "uncertain": [],
               "D": rep.get("discrepancy", {}).get("after", {}).get(a)} for a in "xyz"}
    for f in rep["findings"]:
        row = out[f["axis"]]
        row["named"].append(f["effect"])
        row["alternatives"] += [alt["effect"] for alt in f.get("alternatives", [])]
        for k, v in f["params"].items():
            ci = (f.get("params_ci95") or {}).get(k)
            if not ci or k == "phase_rad":
                continue
            lo, hi = ci
            if not lo <= v <= hi:
                row["outside"].append(f"{f['effect']}.{k}={v:.4g} [{lo:.4g}, {hi:.4g}]")
            elif SCALES.get(f["effect"], {}).get(k) == "log" and lo > 0 and hi / lo > MAX_SPAN_RATIO:
                row["wide"].append(f"{f['effect']}.{k}=[{lo:.3g}, {hi:.3g}]")
    for u in rep.get("uncertain", []):
        out[u["axis"]]["uncertain"].append(u["effect"])
    for row in out.values():
        row["named"].sort()
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--sim-seeds", default="1,2,3,4,5,6")
    ap.add_argument("--only", default=None)
    ap.add_argument("--adis", default=None, help="folder of the ADIS16405 records (default: ../shared/data/adis16405_long)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--json", default=None, help="write every axis's rows here")
    ap.add_argument("--bootstrap", type=int, default=None, help="bootstrap runs (default: the command's)")
    args = ap.parse_args(argv)
    seeds = [int(s) for s in args.seeds.split(",")]
    from gap_closure import ADIS_DIR, records

    adis = args.adis or ADIS_DIR
    jobs = [(name, s, None, args.bootstrap, adis) for name, _ in records(only=args.only, adis_dir=adis)
            for s in seeds]
    with tempfile.TemporaryDirectory() as folder:
        sims = [] if not args.sim_seeds else [int(k) for k in args.sim_seeds.split(",")]
        for k in sims:
            name = f"default model seed {k}"
            if args.only is None or args.only in name:
                path = _sim_record(k, folder)
                jobs += [(name, s, path, args.bootstrap, adis) for s in seeds]
        results = {}
        with ProcessPoolExecutor(args.jobs) as pool:
            for name, seed, rep in pool.map(_job, jobs):
                results.setdefault(name, {})[seed] = axis_rows(rep)
                print(f"  {name} seed {seed}: done", file=sys.stderr, flush=True)
    summary = report(results, seeds)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"rows": results, "summary": summary}, f, indent=1)


def report(results, seeds):
    """Print the table and the counts; return the counts."""
    counts = {"real_axes": 0, "real_same": 0, "sim_axes": 0, "sim_same": 0, "outside": 0, "wide": 0,
              "sim_foreign": 0, "sim_temperature_named": 0, "sim_temperature_listed": 0, "sim_temperature_suggested": 0,
              "sim_axis_seeds": 0}
    print("| record | axis | " + " | ".join(f"seed {s}" for s in seeds) + " | same | D |")
    print("|---|---|" + "---|" * len(seeds) + "---|---|")
    for name, by_seed in results.items():
        sim = name.startswith("default model")
        for a in "xyz":
            rows = [by_seed[s][a] for s in seeds]
            same = all(r["named"] == rows[0]["named"] for r in rows)
            kind = "sim" if sim else "real"
            counts[f"{kind}_axes"] += 1
            counts[f"{kind}_same"] += same
            for r in rows:
                counts["outside"] += len(r["outside"])
                counts["wide"] += len(r["wide"])
                if sim:
                    counts["sim_axis_seeds"] += 1
                    counts["sim_foreign"] += any(e not in DEFAULT_MODEL_EFFECTS for e in r["named"])
                    named, listed = "temperature" in r["named"], "temperature" in r["alternatives"]
                    counts["sim_temperature_named"] += named
                    counts["sim_temperature_listed"] += listed and not named
                    counts["sim_temperature_suggested"] += "temperature" in r["uncertain"] and not (named or listed)
            cells = [", ".join(r["named"]) + (f" (uncertain: {', '.join(r['uncertain'])})" if r["uncertain"] else "")
                     or "-" for r in rows]
            d = " / ".join(f"{r['D']:.3g}" if r["D"] is not None else "-" for r in rows)
            print(f"| {name} | {a} | " + " | ".join(cells) + f" | {'yes' if same else 'NO'} | {d} |")
            for r in rows:
                for text in r["outside"]:
                    print(f"    interval outside its estimate: {text}")
                for text in r["wide"]:
                    print(f"    interval over 100x: {text}")
    print()
    print(f"real records: same causes on {counts['real_same']} of {counts['real_axes']} axes; "
          f"default model: {counts['sim_same']} of {counts['sim_axes']}")
    print(f"intervals outside their estimate: {counts['outside']}; over a factor 100: {counts['wide']}")
    if counts["sim_axis_seeds"]:
        print(f"default model (axis x seed): a cause outside its terms on {counts['sim_foreign']} of "
              f"{counts['sim_axis_seeds']}; the temperature named on {counts['sim_temperature_named']}, listed as an "
              f"alternative on {counts['sim_temperature_listed']} more, suggested (uncertain) on "
              f"{counts['sim_temperature_suggested']} more")
    return counts


if __name__ == "__main__":
    main()
