"""Gap analysis of the real MPU6050 recordings: the JSON reports and figures behind docs/gap.md.

    python tools/gap_real.py [--seed 0]

For every static MPU6050 recording in ``recordings/`` runs ``gyrofilter.analysis.gap.pipeline.analyse_gap``
(seed 0, the command's defaults), writes the JSON reports to ``docs/gap/<name>.json`` and
``docs/figures/gap_<name>_{adev,spectrum}_<axis>.png`` for the axes with findings, and prints
the table. ``tools/docs.py`` writes the table, the evidence and the figure links into docs/gap.md
from the committed reports (:func:`table`, :func:`evidence`, :func:`figure_links`).
"""
from __future__ import annotations

import argparse
import glob
import json
import os
import time

from gyrofilter.analysis.gap.pipeline import analyse_gap
from gyrofilter.cli.outputs import write_json
from gyrofilter.recording import read_recording

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
JSON_DIR = os.path.join(ROOT, "docs", "gap")
FIGURE_DIR = os.path.join(ROOT, "docs", "figures")


def recording_paths():
    return sorted(glob.glob(os.path.join(ROOT, "recordings", "mpu6050_static_*.csv.gz")))


def _name(path):
    return os.path.basename(path).replace(".csv.gz", "")


def _fmt_params(params):
    return ", ".join(f"{k} = {v:.3g}" for k, v in params.items() if k != "phase_rad")


def analyse(seed=0):
    """Run the gap analysis on every static recording; write the reports and figures."""
    from gyrofilter.analysis.gap.report import plot_adev, plot_spectrum

    os.makedirs(JSON_DIR, exist_ok=True)
    for path in recording_paths():
        rec = read_recording(path)
        name = _name(path)
        t0 = time.perf_counter()
        rep = analyse_gap(rec, seed=seed, recording_name=os.path.relpath(path, ROOT))
        write_json(os.path.join(JSON_DIR, f"{name}.json"), rep)
        for a in sorted({f["axis"] for f in rep["findings"]}):
            for kind, plot in (("adev", plot_adev), ("spectrum", plot_spectrum)):
                plot(rep["departures"][a], a, os.path.join(FIGURE_DIR, f"gap_{name}_{kind}_{a}.png"))
        print(f"{name}: {len(rep['findings'])} findings, {time.perf_counter() - t0:.1f} s", flush=True)


def reports():
    """{name: (report, has a temperature column)} from the committed docs/gap/<name>.json."""
    out = {}
    for path in recording_paths():
        with open(os.path.join(JSON_DIR, f"{_name(path)}.json"), encoding="utf-8") as fh:
            rep = json.load(fh)
        out[_name(path)] = (rep, "temp" in read_recording(path).columns)
    return out


def table_row(name, rep, has_temp):
    """One row of the table: the recording, its findings and D; the runtime as the report says."""
    d = rep["discrepancy"]
    found = "; ".join(f"{f['axis']}: {f['effect']} ({_fmt_params(f['params'])})" for f in rep["findings"]) or "none"
    return (f"| `{name}` | {rep['duration_s']:.0f} s at {rep['sample_rate_hz']:g} Hz | {'yes' if has_temp else 'no'} | "
            f"{found} | {d['overall_before']:.2f} -> {d['overall_after']:.2f} | {rep['runtime_s']:.1f} s |")


def table(reps):
    return "\n".join(["| recording | length | temp | findings (cause, parameters) | discrepancy D (mean of axes) "
                      "before -> after | runtime |", "|---|---|---|---|---|---|",
                      *(table_row(name, rep, temp) for name, (rep, temp) in reps.items())])


def evidence(reps):
    """Evidence, gain per finding, the suggested (``uncertain``) and the notes of every report, one
    bullet each."""
    from gyrofilter.analysis.gap.report import uncertain_text

    lines = []
    for name, (rep, _) in reps.items():
        for f in rep["findings"]:
            lines.append(f"- `{name}`, {f['axis']}: **{f['effect']}** ({_fmt_params(f['params'])}); "
                         f"D {f['gain']['before']:.2f} -> {f['gain']['after']:.2f}. {f['evidence']}.")
        lines += [f"- `{name}`: suggested, not named: {uncertain_text(u, ' = ')}."
                  for u in rep.get("uncertain", [])]
        lines += [f"- `{name}`: {note}." for note in rep.get("notes", [])]
    return "\n".join(lines)


def figure_links(reps):
    """The Allan-deviation and spectrum figures of every axis with findings, two per line."""
    lines = []
    for name, (rep, _) in reps.items():
        for a in sorted({f["axis"] for f in rep["findings"]}):
            lines.append(f"![{name} {a} Allan deviation](figures/gap_{name}_adev_{a}.png) "
                         f"![{name} {a} spectrum](figures/gap_{name}_spectrum_{a}.png)")
    return "\n\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    analyse(args.seed)
    print(table(reports()))


if __name__ == "__main__":
    main()
