#!/usr/bin/env python3
"""The one writer of every table and number in README.md and docs/*.md that a command or tool produces.

    python tools/docs.py                  # every block (the slow ones: benchmarks, batteries, long analyses)
    python tools/docs.py --fast           # only the fast blocks (seconds)
    python tools/docs.py --only NAME...   # these blocks or artefacts
    python tools/docs.py --check [--fast] # exit 1, listing the blocks whose committed text differs
    python tools/docs.py --list           # every block: name, page, fast or slow, where its numbers come from

A block sits in its one page between two markers, and its first line says how to regenerate it:

    <!-- docs.py: NAME -->
    <!-- written by `python tools/docs.py --only NAME` from SOURCE: edit the generator, not this text -->
    ...
    <!-- /docs.py: NAME -->

Each NAME has one generator below, which calls the package or the tool that computes the numbers
(the tools' logic stays in the tools). Some blocks render an *artefact* that a slow command writes
and the repository keeps (``docs/figures/evaluate.json``, ``docs/gap/*.json``): the artefact is
made by its own slow step, the block from it in a moment.

* **fast** blocks are regenerated and compared in full by ``--check`` and tests/test_docs.py;
* **slow** blocks (benchmarks, batteries, long analyses) are written by a full run only;
  ``--check`` checks that each is there and names its tool, and, where a block has a
  ``check``, recomputes a cheap deterministic part of it (timings are never checked);
* **artefacts** are remade by a full run (or ``--only NAME``); ``--check`` recomputes a cheap
  part of each (one recording) and compares it with the committed file.

Tools read the real data sets beside the repository (``--data DIR``, default ../shared/data);
a block that needs data that are not there is skipped and keeps its committed text.
"""
from __future__ import annotations

import argparse
import contextlib
import dataclasses
import datetime
import importlib.util
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from gyrofilter.analysis.gap.pipeline import analyse_gap
from gyrofilter.analysis.gap.detectors.common import RESONANCE_MAX_Q
from gyrofilter.analysis.gap.report import d_text
from gyrofilter.evaluation import evaluate as E
from gyrofilter.filter.settings import SETTING_RANGES, FilterSettings
from gyrofilter.filter.presets import DEFAULT_PRESET, PRESETS
from gyrofilter.recording import read_recording
from gyrofilter.recording.unit_words import CONVERTED, UNIT_WORDS
from gyrofilter.sim.resonance import band_pass

ROOT = Path(__file__).resolve().parents[1]
TOOLS = ROOT / "tools"
sys.path.insert(0, str(TOOLS))  # the other tools, imported by name

import allan_figures  # noqa: E402
import bench_gap  # noqa: E402
import dynamic_test  # noqa: E402
import gap_real  # noqa: E402
PAGES = [ROOT / "README.md", ROOT / "CONTRIBUTING.md", *sorted((ROOT / "docs").glob("*.md"))]
DATA = ROOT.parent / "shared" / "data"  # the real data sets beside the repository (--data)
MARK = re.compile(r"^<!-- docs\.py: ([\w-]+) -->\n(.*?)^<!-- /docs\.py: \1 -->$", re.M | re.S)
ANY_MARK = re.compile(r"^<!-- /?docs\.py: ([\w-]+) -->$", re.M)
HEADER = "<!-- written by `python tools/docs.py --only {name}` from {source}: edit the generator, not this text -->"


class Skip(Exception):
    """A generator cannot run here (data or an extra missing): the committed block stays."""


@dataclass
class Block:
    name: str
    page: str  # the one page that holds it, relative to the repository
    source: str  # the command or tool its numbers come from (said in the block's first line)
    generate: Callable[[], str]
    slow: bool = False
    check: Optional[Callable[[str], list]] = None  # slow blocks: body -> problems, fast and deterministic


@dataclass
class Artefact:
    name: str
    source: str
    make: Callable[[], None]
    check: Callable[[], list]  # -> problems: a cheap part recomputed and compared with the committed files


BLOCKS: dict[str, Block] = {}
ARTEFACTS: dict[str, Artefact] = {}


def block(name, page, source, slow=False, check=None):
    def register(fn):
        BLOCKS[name] = Block(name, page, source, fn, slow, check)
        return fn
    return register


def artefact(name, source, check):
    def register(fn):
        ARTEFACTS[name] = Artefact(name, source, fn, check)
        return fn
    return register


# ---------------------------------------------------------------------------------------------
# running commands and tools


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def _run(argv, cwd=ROOT):
    res = subprocess.run(argv, cwd=cwd, env=_env(), stdout=subprocess.PIPE, text=True, check=False)
    if res.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, argv))} exited {res.returncode}")
    return res.stdout


def command(*args, shown=None):
    """``gyrofilter ARGS`` run from the repository: the prompt line and its stdout."""
    out = _run([sys.executable, "-m", "gyrofilter", *args])
    return f"$ gyrofilter {shown or ' '.join(args)}\n{out}"


def tool(script, *args, prompt=True, keep=None):
    """``python tools/SCRIPT ARGS`` run from the repository: its stdout (lines ``keep`` accepts),
    after a prompt line."""
    out = _run([sys.executable, str(TOOLS / script), *args])
    if keep is not None:
        out = "".join(line for line in out.splitlines(keepends=True) if keep(line))
    return (f"$ python tools/{script} {' '.join(args)}".rstrip() + "\n" if prompt else "") + out


def fence(text, lang="text"):
    return f"```{lang}\n{text.strip()}\n```"


def no_headings(markdown):
    """A tool's Markdown without its headings (they would become sections of the page): bold lines."""
    return re.sub(r"^#+ (.*)$", r"**\1**", markdown.strip(), flags=re.M)


def data_dir(name):
    path = DATA / name
    if not path.is_dir():
        raise Skip(f"{path} is not there")
    return path


# ---------------------------------------------------------------------------------------------
# README.md and docs/live.md: the commands on shipped recordings


@block("readme-replay", "README.md", "`gyrofilter replay recordings/mpu6050_static_449s.csv.gz`")
def readme_replay():
    return fence(command("replay", "recordings/mpu6050_static_449s.csv.gz"))


@block("replay-bundled", "docs/live.md", "`gyrofilter replay` on the bundled recording")
def replay_bundled():
    rec = "recordings/mpu6050_static_100s.csv.gz"  # the recording the package bundles, at a path that reads the same anywhere
    return fence(command("replay", rec) + "\n" + command("replay", rec, "--preset", "paper"))


# ---------------------------------------------------------------------------------------------
# docs/settings.md and docs/formats.md: the filter's settings, presets and ranges


def settings_meanings():
    """{setting: (default as the docstring writes it, meaning)} from the table in the docstring of
    FilterSettings, the one statement of what each setting means."""
    lines = FilterSettings.__doc__.splitlines()
    rules = [i for i, ln in enumerate(lines) if ln.strip().startswith("====")]
    starts = [m.start() for m in re.finditer(r"=+", lines[rules[0]])]
    out, name = {}, None
    for ln in lines[rules[1] + 1: rules[2]]:
        setting, default, meaning = (ln[a:b].strip() for a, b in zip(starts, starts[1:] + [None]))
        if setting:
            name = setting
            out[name] = (default, meaning)
        else:
            out[name] = (out[name][0], f"{out[name][1]} {meaning}")
    return out


def _value(v):
    return f"`{v}`" if isinstance(v, str) else repr(v)


@block("settings", "docs/settings.md", "the fields and the docstring of `gyrofilter.filter.pipeline.FilterSettings`")
def settings_table():
    meanings = settings_meanings()
    fields = dataclasses.fields(FilterSettings)
    if set(meanings) != {f.name for f in fields}:
        raise ValueError(f"FilterSettings' docstring table and fields differ: {set(meanings) ^ {f.name for f in fields}}")
    rows = ["| setting | default | meaning |", "|---|---|---|"]
    for f in fields:
        written, meaning = meanings[f.name]
        if written not in (str(f.default), f"{f.default:g}" if isinstance(f.default, float) else None):
            raise ValueError(f"FilterSettings' docstring gives {f.name} the default {written}, the field {f.default!r}")
        rows.append(f"| `{f.name}` | {_value(f.default)} | {meaning} |")
    return "\n".join(rows)


@block("unit-spellings", "docs/formats.md", "`gyrofilter.recording.unit_words.UNIT_WORDS`")
def unit_spellings_table():
    options = {"time": "--time-unit", "rate": "--unit", "temp": "--temp-unit", "accel": "--accel-unit"}
    rows = ["| column | option value | spellings a name states it by (any case, blanks aside) |", "|---|---|---|"]
    for quantity, words in UNIT_WORDS.items():
        for unit in dict.fromkeys(words.values()):
            said = ", ".join(f"`{w}`" for w, u in words.items() if u == unit)
            value = ("none: ambiguous, the option says which" if unit is None else f"`{options[quantity]} {unit}`"
                     + (f" (converted to {CONVERTED[unit][0].replace('c', '°C')}: {CONVERTED[unit][1]})"
                        if unit in CONVERTED else ""))
            rows.append(f"| {quantity} | {value} | {said} |")
    return "\n".join(rows)


@block("presets", "docs/settings.md", "`gyrofilter.filter.presets.PRESETS`")
def presets_table():
    rows = ["| preset | its settings (the others keep the defaults above) |", "|---|---|"]
    for name, settings in PRESETS.items():
        same = next((other for other, s in PRESETS.items() if s is settings and other != name), None)
        if same is not None and list(PRESETS).index(same) < list(PRESETS).index(name):
            text = f"the same as `{same}`"
        else:
            text = ", ".join(f"`{k}={v!r}`" for k, v in settings.items()) or "none: paper 001's values"
        rows.append(f"| `{name}`{' (the default)' if name == DEFAULT_PRESET else ''} | {text} |")
    return "\n".join(rows)


def _range_number(x):
    return f"{x:g}" if abs(x) < 1e6 else f"{x:.0e}".replace("e+0", "e").replace("e+", "e")


@block("setting-ranges", "docs/formats.md", "`gyrofilter.filter.settings.SETTING_RANGES`")
def setting_ranges_table():
    lines = ["| setting | range |", "|---|---|"]
    for name, r in SETTING_RANGES.items():
        low = f"{'(' if r.get('low_open') else '['}{_range_number(r['low'])}"
        high = f"{_range_number(r['high'])}{')' if r.get('high_open') else ']'}"
        lines.append(f"| `{name}` | {low}, {high}{' whole' if r.get('integer') else ''} |")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# docs/results.md and docs/evaluate.md: the filters on measured data (gyrofilter evaluate)

EVALUATE_DIR = ROOT / "docs" / "figures"
HOLDOUT_DIR = EVALUATE_DIR / "holdout"


def _evaluate_check(folder):
    """Static std reductions of two filters on one recording, recomputed, against the committed JSON."""
    doc = json.loads((folder / "evaluate.json").read_text(encoding="utf-8"))
    rec = read_recording(ROOT / "recordings" / "mpu6050_static_100s.csv.gz")
    specs = {s.name: s for s in E.default_filters()}
    problems = []
    for name in ("paper001", "recommended preset"):
        now = E.static_reduction(specs[name], rec.gyro_dps, rec.sample_rate_hz)
        committed = doc["static_std_reduction"][name]["mpu6050_static_100s"]
        if not np.allclose(now, committed, rtol=1e-9):
            problems.append(f"{folder.relative_to(ROOT)}/evaluate.json: {name} on mpu6050_static_100s: "
                            f"committed {committed}, the code gives {now.tolist()}")
    return problems


@artefact("evaluate", "`gyrofilter evaluate --out docs/figures --force`", lambda: _evaluate_check(EVALUATE_DIR))
def make_evaluate():
    _run([sys.executable, "-m", "gyrofilter", "evaluate", "--out", "docs/figures", "--force"])


@artefact("evaluate-holdout", "`gyrofilter evaluate --split holdout --out docs/figures/holdout --force`",
          lambda: _evaluate_check(HOLDOUT_DIR))
def make_evaluate_holdout():
    _run([sys.executable, "-m", "gyrofilter", "evaluate", "--split", "holdout", "--out", "docs/figures/holdout", "--force"])


def _evaluation(folder):
    return json.loads((folder / "evaluate.json").read_text(encoding="utf-8"))


def _reductions(doc, name):
    return np.concatenate([np.asarray(v, dtype=float) for v in doc["static_std_reduction"][name].values()])


def _geomean(v):
    return float(np.exp(np.mean(np.log(v))))


def _lag_ms(d):
    lag = d.get("worst_lag_s", d.get("lag_s"))
    return "" if lag is None or not math.isfinite(lag) else f" / {lag * 1e3:.0f} ms"


@block("results-paper001", "docs/results.md", "`docs/figures/evaluate.json` (`gyrofilter evaluate --out docs/figures`)")
def results_paper001():
    doc = _evaluation(EVALUATE_DIR)
    paper, default = _reductions(doc, "paper001"), _reductions(doc, "recommended preset")
    n_rec = len(doc["static_std_reduction"]["paper001"])
    dyn = {name: doc["dynamic"][name]["paper001"] for name in ("paper001", "recommended preset")}

    def lag(name):
        return f"{dyn[name]['worst_lag_s'] * 1e3:.0f} ms".replace("-", "−")

    return "\n".join([
        "| | paper 001 claims | faithful filter (`preset=\"paper\"`), measured | the default (`recommended`), measured |",
        "|---|---|---|---|",
        f"| static std reduction, {paper.size} axes of {n_rec} static recordings: range (geometric mean) | 11.5x and 12.6x "
        f"| **{paper.min():.1f}–{paper.max():.1f}x** ({_geomean(paper):.1f}x) | {default.min():.1f}–{default.max():.1f}x "
        f"({_geomean(default):.0f}x) |",
        "| dynamic test (paper-001 profile + real static noise): RMSE pooled over the recordings of 90 s or more, "
        f"3 axes each | \"good dynamic behaviour\" | {dyn['paper001']['rmse_dps']:.3g} deg/s | "
        f"{dyn['recommended preset']['rmse_dps']:.2g} deg/s |",
        f"| worst lag on that profile (negative = early) | | {lag('paper001')} | {lag('recommended preset')} |",
    ])


PRESET_ROWS = {  # evaluate's filter name -> the row label of the result tables
    "raw": "raw",
    "block mean 5": "block mean of 5, no gross-error rule",
    "CV Kalman q=1e4": "filterpy constant-velocity KF (q = 1e4)",
    "paper001": "faithful paper 001 (`paper`)",
    "hold preset": "constant-rate hold (`hold`)",
    "recommended preset": "**default** (`recommended` = `adaptive_kalman`)",
    "recommended, paper's rule": "default with paper 001's rule everywhere (`outlier_rule=\"paper\"`)",
    "recommended, smoothed (offline)": "smoothed offline (`replay --smooth`)",
}


def preset_table(doc, names):
    """Static reduction, RMSE and worst lag per profile, RMSE over all valid blocks and lag per
    BROAD trial, for the filters ``names`` of an evaluation document."""
    profiles = list(doc["dynamic"][names[0]])
    trials = list(doc["broad"][names[0]])
    head = (["filter", "static std reduction, min / geometric mean"]
            + [f"{p}: RMSE (deg/s) / worst lag" for p in profiles]
            + [f"{t}: RMSE (deg/s) / lag" for t in trials])
    rows = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name in names:
        red = _reductions(doc, name)
        cells = [PRESET_ROWS[name], f"{red.min():.1f} / {_geomean(red):.1f}x"]
        cells += [f"{doc['dynamic'][name][p]['rmse_dps']:.3g}{_lag_ms(doc['dynamic'][name][p])}" for p in profiles]
        cells += [f"{doc['broad'][name][t]['rmse_all_dps']:.3g}{_lag_ms(doc['broad'][name][t])}" for t in trials]
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


@block("results-holdout", "docs/results.md",
       "`docs/figures/holdout/evaluate.json` (`gyrofilter evaluate --split holdout --out docs/figures/holdout`)")
def results_holdout():
    return preset_table(_evaluation(HOLDOUT_DIR), list(PRESET_ROWS))


@block("results-all", "docs/results.md", "`docs/figures/evaluate.json` (`gyrofilter evaluate --out docs/figures`)")
def results_all():
    return preset_table(_evaluation(EVALUATE_DIR), list(PRESET_ROWS))


@block("evaluate-table", "docs/evaluate.md", "`docs/figures/evaluate_table.md` (`gyrofilter evaluate --out docs/figures`)")
def evaluate_table():
    return (EVALUATE_DIR / "evaluate_table.md").read_text(encoding="utf-8").strip()


@block("evaluate-broad", "docs/evaluate.md", "`docs/figures/evaluate.json` (`gyrofilter evaluate --out docs/figures`)")
def evaluate_broad():
    doc = _evaluation(EVALUATE_DIR)
    names = ["raw", "block mean 5", "CV Kalman q=1e4", "paper001", "paper KF + hold", "hold preset",
             "recommended preset", "recommended, smoothed (offline)"]
    trials = list(doc["broad"]["raw"])
    rows = ["| filter | " + " | ".join(trials) + " |", "|---|" + "---|" * len(trials)]
    for name in names:
        cells = [f"{d['rmse_motion_dps']:.2f} / {d['rmse_rest_dps']:.2f} / {d['rms_rest_vs_zero_dps']:.3f} / "
                 f"{d['rmse_all_dps']:.2f}" for d in (doc["broad"][name][t] for t in trials)]
        rows.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def _static_recordings():
    return E.find_static_recordings(str(ROOT / "recordings"))


def _rows_in(body, table):
    """Problems: the data rows of ``table`` that ``body`` lacks."""
    return [f"row not as the code gives it: {row}" for row in table.splitlines()[2:] if row not in body]


@block("dynamic-static", "docs/results.md", "tools/dynamic_test.py (first table)", slow=True,
       check=lambda body: _rows_in(body, dynamic_test.static_table(_static_recordings()[:1])))
def dynamic_static():
    return dynamic_test.static_table(_static_recordings())


@block("dynamic-spikes", "docs/results.md", "tools/dynamic_test.py (second table)", slow=True,
       check=lambda body: _rows_in(body, dynamic_test.static_table(_static_recordings()[:1], spikes=True)))
def dynamic_spikes():
    return dynamic_test.static_table(_static_recordings(), spikes=True)


@block("dynamic-profile", "docs/results.md", "tools/dynamic_test.py (third table and docs/figures/dynamic_paper001.png)",
       slow=True)
def dynamic_profile():
    recs = _static_recordings()
    dynamic_test.figure(recs, str(ROOT / "docs" / "figures" / "dynamic_paper001.png"))
    return dynamic_test.dynamic_table(recs)


@block("tune-recommended", "docs/evaluate.md", "tools/tune_recommended.py", slow=True)
def tune_recommended():
    return fence(tool("tune_recommended.py"))


@block("tune-adaptive-kalman", "docs/evaluate.md", "tools/tune_adaptive_kalman.py", slow=True)
def tune_adaptive_kalman():
    return fence(tool("tune_adaptive_kalman.py"))


@block("vibration", "docs/evaluate.md", "tools/vibration.py")
def vibration():
    return no_headings(tool("vibration.py", prompt=False))


# ---------------------------------------------------------------------------------------------
# docs/allan.md


@artefact("allan-figures", "tools/allan_figures.py (docs/figures/allan_*.png)", lambda: [])
def make_allan_figures():
    _run([sys.executable, str(TOOLS / "allan_figures.py")])


def _allan():
    return allan_figures.recordings(str(ROOT / "recordings"))


@block("allan-real", "docs/allan.md", "tools/allan_figures.py (the tables; the figures: `python tools/allan_figures.py`)")
def allan_real():
    static, motion = _allan()
    return allan_figures.tables(allan_figures.characterised(static), [name for name, _ in motion])


@block("allan-before-after", "docs/allan.md", "tools/allan_figures.py (before/after table)")
def allan_before_after():
    static, _ = _allan()
    name, rec = allan_figures.longest(static)
    return (f"{name} ({rec.duration_s:.0f} s at {rec.sample_rate_hz:g} Hz; output every 5 samples, "
            f"{rec.sample_rate_hz / 5:.2f} Hz); std after the calibration window:\n\n"
            + allan_figures.before_after_table(rec, ("paper", "hold", "recommended")))


@block("kalibr-mpu6050", "docs/allan.md", "`gyrofilter simulate` (the default MPU6050 model, 30 min) and `gyrofilter allan --kalibr`",
       slow=True)  # a simulation: numpy 1.24 moves a few samples by 1 LSB (the 0.9-4x claim: tests/test_kalibr.py)
def kalibr_mpu6050():
    model = "gyrofilter/data/mpu6050_model.json"
    sim = ["simulate", "--model", model, "--duration", "1800", "--seed", "1", "--out", "mpu6050_30min.csv.gz"]
    allan = ["allan", "mpu6050_30min.csv.gz", "--kalibr", "imu.yaml"]
    with tempfile.TemporaryDirectory() as tmp:  # relative names: the yaml's comment reads the same anywhere
        _run([sys.executable, "-m", "gyrofilter", *sim[:2], str(ROOT / model), *sim[3:]], cwd=tmp)
        out = _run([sys.executable, "-m", "gyrofilter", *allan], cwd=tmp)
        yaml = (Path(tmp) / "imu.yaml").read_text(encoding="utf-8")
    said = out[out.index("  kalibr, "):]
    return fence(f"$ gyrofilter {' '.join(sim)}\n$ gyrofilter {' '.join(allan)}\n...\n{said}$ cat imu.yaml\n{yaml}")


@block("allan-consistency", "docs/allan.md", "tools/allan_consistency.py --jobs 2", slow=True)
def allan_consistency():
    return fence(tool("allan_consistency.py", "--jobs", "2"))


@block("allan-coverage", "docs/allan.md", "tools/allan_coverage.py --seeds 41-80 --jobs 2", slow=True)
def allan_coverage():
    return fence(tool("allan_coverage.py", "--seeds", "41-80", "--jobs", "2"))


@block("bench-allan", "docs/allan.md", "tools/bench_allan.py --day-file", slow=True)
def bench_allan():
    return fence(tool("bench_allan.py", "--day-file"))


# ---------------------------------------------------------------------------------------------
# docs/gap.md and docs/gap_closure.md


def _gap_check():
    """The gap analysis of the shortest recording, recomputed, against its committed report."""
    name = "mpu6050_static_100s"
    committed, _ = gap_real.reports()[name]
    now = analyse_gap(read_recording(ROOT / "recordings" / f"{name}.csv.gz"), seed=0,
                      recording_name=f"recordings/{name}.csv.gz")
    return [f"docs/gap/{name}.json: '{key}' is not what the gap analysis gives now"
            for key in ("findings", "discrepancy", "notes", "extended_model")
            if not _same(json.loads(json.dumps(now[key])), committed[key])]


def _same(a, b, rtol=1e-6):
    """Equal JSON values, numbers to ``rtol`` (BLAS sums in another order with another thread count)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k], rtol) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y, rtol) for x, y in zip(a, b))
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        return math.isclose(a, b, rel_tol=rtol, abs_tol=1e-12)
    return a == b


@artefact("gap-reports", "tools/gap_real.py (docs/gap/*.json and the gap figures)", _gap_check)
def make_gap_real():
    gap_real.analyse(seed=0)


@block("gap-real", "docs/gap.md", "`docs/gap/*.json` (`python tools/gap_real.py`)")
def gap_real_block():
    reps = gap_real.reports()
    return "\n\n".join([gap_real.table(reps), "Evidence, gain per finding, and notes:", gap_real.evidence(reps),
                        gap_real.figure_links(reps)])


def _gap_example_check(body):
    rep, _ = gap_real.reports()["mpu6050_static_655s"]
    d = rep["discrepancy"]
    shown = {a: f"{a}: D {d_text(d['before'][a], d['before_se'][a])}" for a in "xyz"}
    return [f"axis {a}: '{shown[a]}' of docs/gap/mpu6050_static_655s.json is not in the block"
            for a in "xyz" if shown[a] not in body]


@block("gap-example", "docs/gap.md", "`gyrofilter gap recordings/mpu6050_static_655s.csv.gz --json gap.json`",
       slow=True, check=_gap_example_check)
def gap_example():
    with tempfile.TemporaryDirectory() as tmp:
        return fence(command("gap", "recordings/mpu6050_static_655s.csv.gz", "--json", os.path.join(tmp, "gap.json"),
                             shown="gap recordings/mpu6050_static_655s.csv.gz --json gap.json"))


def _battery(*args):
    return fence(tool("gap_battery.py", *args, keep=lambda line: not line.startswith(("case ", "  "))))


@block("gap-hidden-real", "docs/gap.md", "tools/gap_battery.py --real", slow=True)
def gap_hidden_real():
    return _battery("--real", "recordings/mpu6050_static_449s.csv.gz", "recordings/mpu6050_static_655s.csv.gz",
                    "--cases", "10")


@block("gap-battery-standard", "docs/gap.md", "tools/gap_battery.py (standard battery)", slow=True)
def gap_battery_standard():
    return _battery("--cases", "48", "--sims", "12", "--seed", "3000")


@block("gap-battery-harder", "docs/gap.md", "tools/gap_battery.py (harder battery)", slow=True)
def gap_battery_harder():
    return _battery("--cases", "72", "--duration", "600", "--scale", "0.3333", "--sims", "12", "--seed", "4000")


@block("gap-regression-harder", "docs/gap.md",
       "tools/gap_regression.py (the harder battery, paired against the last commit before issue 24)", slow=True)
def gap_regression_harder():
    return fence(tool("gap_regression.py", "--rev", "c82287b", "--cases", "216", "--duration", "600", "--scale", "0.3333",
                      "--seed", "14000", "-v"))


@block("gap-battery-clean-10min", "docs/gap.md", "tools/gap_battery.py (clean 10-minute records)", slow=True)
def gap_battery_clean_10min():
    return _battery("--cases", "40", "--duration", "600", "--effects", "none", "--sims", "12", "--seed", "6000")


@block("gap-battery-clean-30min", "docs/gap.md", "tools/gap_battery.py (clean 30-minute records)", slow=True)
def gap_battery_clean_30min():
    return _battery("--cases", "20", "--duration", "1800", "--effects", "none", "--sims", "12", "--seed", "7000")


@block("gap-battery-band", "docs/gap.md", "tools/gap_battery.py (humps, rings and wandering tones hidden)", slow=True)
def gap_battery_band():
    return (_battery("--cases", "36", "--duration", "600", "--effects", "resonance,ringing,none", "--sims", "12", "--seed",
                     "15000", "--d-after") + "\n\n"
            + _battery("--cases", "24", "--effects", "wandering_tone,none", "--sims", "12", "--seed", "15100", "--d-after"))


@block("gap-battery-tails", "docs/gap.md", "tools/gap_battery.py (heavy tails and outliers hidden)", slow=True)
def gap_battery_tails():
    harder = ("--scale", "0.3333", "--duration", "600")
    runs = [("heavy_tails", (), "8000"), ("heavy_tails", harder, "8100"), ("outliers", (), "8200"), ("outliers", harder, "8300")]
    return "\n\n".join(_battery("--cases", "40", "--effects", effect, *size, "--sims", "12", "--seed", seed)
                         for effect, size, seed in runs)


@block("gap-coverage", "docs/gap.md", "tools/gap_coverage.py", slow=True)
def gap_coverage():
    return fence(tool("gap_coverage.py", "--cases", "60", "--duration", "600", "--seed", "9000",
                      keep=lambda line: not line.startswith(("case ", "  "))))


@block("gap-heavy-tails", "docs/gap.md", "tools/gap_heavy_tails.py --stand-ins 10 --real --adis DIR (DIR: the ADIS16405 records)",
       slow=True)
def gap_heavy_tails():
    adis = data_dir("adis16405_long")
    out = tool("gap_heavy_tails.py", "--stand-ins", "10", "--real", "--adis", str(adis))
    return fence(out.replace(str(adis), "DIR"))


@block("gap-tone-modulation", "docs/gap.md", "tools/tone_modulation.py --adis DIR (DIR: the ADIS16405 records)", slow=True)
def gap_tone_modulation():
    adis = data_dir("adis16405_long")
    return tool("tone_modulation.py", "--adis", str(adis), prompt=False).strip()


@block("gap-tails-cause", "docs/gap.md", "tools/tails_cause.py --adis DIR (DIR: the ADIS16405 records)", slow=True)
def gap_tails_cause():
    adis = data_dir("adis16405_long")
    return tool("tails_cause.py", "--adis", str(adis), prompt=False).strip()


@block("robust-gmwm", "docs/gap.md", "tools/robust_gmwm.py", slow=True)
def robust_gmwm():
    return fence(tool("robust_gmwm.py"))


@block("gmwm-select", "docs/gap.md", "tools/gmwm_select.py", slow=True)
def gmwm_select():
    return fence(tool("gmwm_select.py"))


@block("gap-confound", "docs/gap.md", "tools/gap_confound.py --seeds 1,2,3,4,5,6,7,8,9,10 --long-seeds 1", slow=True)
def gap_confound():
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "confound.md")
        tool("gap_confound.py", "--seeds", "1,2,3,4,5,6,7,8,9,10", "--long-seeds", "1", "--out", out)
        with open(out, encoding="utf-8") as fh:
            return fh.read().rstrip("\n")


@block("gap-stability", "docs/gap.md", "tools/gap_stability.py --adis DIR (DIR: the ADIS16405 records)", slow=True)
def gap_stability():
    return tool("gap_stability.py", "--adis", str(data_dir("adis16405_long")), prompt=False).strip()


BENCH_GAP_JSON = ROOT / "docs" / "figures" / "bench_gap.json"


def _bench_gap_check():
    """The committed rows name the 24-h and the 1-h 1-kHz records (timings are never checked)."""
    if not BENCH_GAP_JSON.exists():
        return [f"{BENCH_GAP_JSON.relative_to(ROOT)} is missing: python tools/docs.py --only bench-gap-run"]
    records = {r["record"] for r in json.loads(BENCH_GAP_JSON.read_text(encoding="utf-8"))["rows"]}
    return [f"{BENCH_GAP_JSON.relative_to(ROOT)}: no row for {r}" for r in ("24h @ 100 Hz", "1h @ 1000 Hz")
            if r not in records]


@artefact("bench-gap-run", "tools/bench_gap.py --json docs/figures/bench_gap.json", _bench_gap_check)
def make_bench_gap():
    _run([sys.executable, str(TOOLS / "bench_gap.py"), "--json", str(BENCH_GAP_JSON)])


def _bench_gap_rows():
    return json.loads(BENCH_GAP_JSON.read_text(encoding="utf-8"))["rows"]


@block("bench-gap", "docs/gap.md", "`docs/figures/bench_gap.json` (`python tools/bench_gap.py --json docs/figures/bench_gap.json`)")
def bench_gap_table():
    return fence(f"$ python tools/bench_gap.py\n{bench_gap.report(json.loads(BENCH_GAP_JSON.read_text(encoding='utf-8')))}")


@block("readme-long-gap", "README.md", "`docs/figures/bench_gap.json` (`python tools/bench_gap.py --json docs/figures/bench_gap.json`)")
def readme_long_gap():
    rows = {r["record"]: r for r in _bench_gap_rows()}
    day, fast = rows["24h @ 100 Hz"], rows["1h @ 1000 Hz"]
    return (f"A day at 100 Hz ({day['samples']:,} samples per axis, a {day['file_mb']:.0f}-MB `.csv.gz`): "
            f"`gyrofilter gap` takes {day['gap_s']:.0f} s and {day['gap_peak_mb']:.0f} MB at its peak, "
            f"{day['ratio']:.1f} times the {day['allan_s']:.0f} s of `gyrofilter allan` on the same file "
            f"(its peak {day['allan_peak_mb']:.0f} MB); an hour at 1 kHz takes {fast['gap_s']:.0f} s "
            f"({fast['gap_peak_mb']:.0f} MB). Measured by `tools/bench_gap.py` on a shared 2-core machine "
            f"(load {max(day['load'], fast['load']):.1f}): [docs/gap.md](docs/gap.md#speed-and-memory).")


@block("bench-report", "docs/report.md", "tools/bench_report.py", slow=True)
def bench_report():
    return fence(tool("bench_report.py"))


@block("gap-closure", "docs/gap_closure.md", "tools/gap_closure.py --adis DIR (DIR: the ADIS16405 records)", slow=True)
def gap_closure():
    adis = data_dir("adis16405_long")
    return tool("gap_closure.py", "--adis", str(adis), prompt=False).strip()


# ---------------------------------------------------------------------------------------------
# CONTRIBUTING.md


@block("test-time", "CONTRIBUTING.md", "tools/docs.py timing `python -m pytest -q` (the default suite)", slow=True)
def test_time():
    """The one statement of how long the default suite takes: run it, as the README's test
    command does, and say when, on how many cores, under what load and with or without numba."""
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"], cwd=ROOT, env=_env(),
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, check=False)
    wall_s = time.perf_counter() - t0
    summary = next((ln for ln in reversed(res.stdout.splitlines()) if " passed" in ln), "no summary line")
    numba = "with numba" if importlib.util.find_spec("numba") else "without numba"
    return (f"Measured {datetime.date.today().isoformat()} by `python tools/docs.py --only test-time`: the default suite "
            f"took {wall_s:.0f} s on {os.cpu_count()} cores {numba} (load {load:.1f} at the start; "
            f"{summary.strip('= ')}).")


# ---------------------------------------------------------------------------------------------
# docs/fleet.md


def _fleet_check(body):
    """The rows of the real recordings must carry the D of their committed gap reports."""
    problems = []
    for name, (rep, _) in gap_real.reports().items():
        d = rep["discrepancy"]
        for a in "xyz":
            cell = f"| {d['before'][a]:.3g} -> {d['after'][a]:.3g} |"
            row = next((ln for ln in body.splitlines() if ln.startswith(f"| {name} | {a} |")), "")
            if cell not in row:
                problems.append(f"{name} {a}: D {cell} of docs/gap/{name}.json is not in its row")
    return problems


@block("fleet-real", "docs/fleet.md", "tools/fleet_real.py --jobs 2", slow=True, check=_fleet_check)
def fleet_real():
    out = ROOT / "out" / "fleet_real"
    printed = tool("fleet_real.py", "--jobs", "2", "--out", "out/fleet_real", prompt=False)
    summary = (out / "report" / "fleet.md").read_text(encoding="utf-8")
    table = re.search(r"^\| unit \| axis \| N .*?(?=\n\n|\Z)", summary, re.M | re.S).group(0)
    return fence("$ python tools/fleet_real.py --jobs 2\n" + printed) + "\n\nThe table of `fleet.md`:\n\n" + table


@block("bench-fleet", "docs/fleet.md", "tools/bench_fleet.py --files 32 --hours 1", slow=True)
def bench_fleet():
    printed = tool("bench_fleet.py", "--files", "32", "--hours", "1")
    per_hour = float(re.search(r"\(([\d.]+) s per hour of data\)", printed).group(1))
    core_hours = 10_000 * 24 * per_hour / 3600
    return "\n".join([
        fence(printed), "",
        f"By that cost, on paper (assumptions below): **{24 * per_hour:.0f} s** of one core per unit of 24 h at "
        f"100 Hz; **{core_hours:.0f} core-hours** for 10 000 such units; on one 16-core machine at 90 % parallel "
        f"efficiency **{core_hours / (16 * 0.9):.0f} hours**, with 9 workers (8 GB) {core_hours / (9 * 0.9):.0f} hours; "
        f"at 1 kHz ten times as much ({10 * core_hours:.0f} core-hours).",
    ])


# ---------------------------------------------------------------------------------------------
# timings of the other pages


@block("bench-pipeline", "docs/speed.md", "tools/bench.py pipeline", slow=True)
def bench_pipeline():
    return fence(tool("bench.py", "pipeline"))


@block("bench-reader", "docs/speed.md", "tools/bench_reader.py", slow=True)
def bench_reader():
    return fence(tool("bench_reader.py"))


@block("bench-serial", "docs/live.md", "tools/bench_serial.py", slow=True)
def bench_serial():
    return fence(tool("bench_serial.py"))


#: the resonator's centres (fractions of f_s) and quality factors the width table shows
WIDTH_FRACTIONS = (0.05, 0.1, 0.12, 0.15, 0.2, 0.25, 0.3, 0.4)
WIDTH_QS = (1.0, 2.0, 4.0, 10.0)


def _half_power_width(fraction, q):
    """The half-power full width (f₂ − f₁)/f_s of the resonator ``band_pass(fraction, q, 1)``, read
    off its own frequency response |H(e^{2πjf})|² = 1/2 on either side of the peak (brentq)."""
    from scipy.optimize import brentq

    b, a = band_pass(fraction, q, 1.0)

    def excess(f):
        z = np.exp(-2j * np.pi * f * np.arange(3))
        return abs(np.dot(b, z) / np.dot(a, z)) ** 2 - 0.5

    return brentq(excess, fraction, 0.5 - 1e-12) - brentq(excess, 1e-12, fraction)


@block("resonance-width", "docs/simulate.md", "`gyrofilter.sim.resonance.band_pass` (its half-power points) and "
       "`gyrofilter.analysis.gap.detectors.common.RESONANCE_MAX_Q`")
def resonance_width():
    head = "| Q | " + " | ".join(f"f₀ = {r:g} f_s" for r in WIDTH_FRACTIONS) + " |"
    rows = [head, "|---" * (len(WIDTH_FRACTIONS) + 1) + "|"]
    for q in WIDTH_QS:
        narrower = [1.0 - _half_power_width(r, q) / (r / q) for r in WIDTH_FRACTIONS]
        rows.append(f"| {q:g} | " + " | ".join(f"{100 * n:.0f} %" for n in narrower) + " |")
    return ("How much narrower than f₀/Q the `resonance`'s (and `ringing`'s) half-power band is, read off the "
            "filter's own response:\n\n" + "\n".join(rows) + "\n\n"
            f"`gap` names a peak whose fitted `q` is at most {RESONANCE_MAX_Q:g} a `resonance` and a narrower one a "
            "`narrowband` line (its line rule, [gap.md](gap.md#a-hump-a-line-or-shocks-that-ring)): a `resonance` "
            f"simulated with `q` above {RESONANCE_MAX_Q:g} is reported, where the record shows it, as a `narrowband`.")


@block("default-model", "docs/simulate.md", "`gyrofilter/data/mpu6050_model.json` (the default model's gyro axes)")
def default_model():
    from gyrofilter.sources.simulated import DEFAULT_MODEL_PATH

    model = json.loads(Path(DEFAULT_MODEL_PATH).read_text(encoding="utf-8"))
    rows = ["| axis | bias deg/s | N deg/s/sqrt(Hz) | effects |", "|---|---|---|---|"]
    for axis, spec in model["axes"].items():
        effects = "; ".join(e["effect"] + " " + ", ".join(f"{k} = {v:g}" for k, v in e.items() if k != "effect")
                            for e in spec.get("effects", []))
        rows.append(f"| {axis} | {spec['bias_dps']:g} | {spec['arw_dps_per_sqrt_hz']:g} | {effects} |")
    return (f"The default model's gyro at {model['sample_rate_hz']:g} Hz, {model['lsb_per_dps']:g} LSB per deg/s "
            f"(±{model['full_scale_dps']:g} deg/s), the values a record of it is checked against:\n\n" + "\n".join(rows))


@block("bench-simulate", "docs/simulate.md", "tools/bench_simulate.py", slow=True)
def bench_simulate():
    return fence(tool("bench_simulate.py"))


@block("bench-mpu6050", "docs/mpu6050.md", "tools/bench_mpu6050.py", slow=True)
def bench_mpu6050():
    return fence(tool("bench_mpu6050.py"))


@block("bench-bias-kf", "docs/arma.md", "tools/bench_bias_kf.py", slow=True)
def bench_bias_kf():
    return fence(tool("bench_bias_kf.py"))


# ---------------------------------------------------------------------------------------------
# docs/arma.md: paper 003


@block("arma-report", "docs/arma.md", "tools/arma_report.py --json out/arma_results.json", slow=True)
def arma_report():
    (ROOT / "out").mkdir(exist_ok=True)
    return no_headings(tool("arma_report.py", "--json", "out/arma_results.json", prompt=False))


@block("bias-tracking", "docs/arma.md", "tools/bias_tracking.py", slow=True)
def bias_tracking():
    return no_headings(tool("bias_tracking.py", prompt=False))


@block("tempcomp-gain", "docs/arma.md", "tools/tempcomp_gain.py", slow=True)
def tempcomp_gain():
    return no_headings(tool("tempcomp_gain.py", prompt=False))


# ---------------------------------------------------------------------------------------------
# the markers: finding, writing, checking


def _page(block_):
    return ROOT / block_.page


def committed():
    """{name: (page, body without the header line, header line)} of every block in the pages."""
    out = {}
    for page in PAGES:
        for m in MARK.finditer(page.read_text(encoding="utf-8")):
            header, _, body = m.group(2).partition("\n")
            out.setdefault(m.group(1), []).append((page, body, header))
    return out


def structure_problems():
    """Markers that do not pair, unknown names, blocks missing, twice, or on another page."""
    problems = []
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        paired = {m.group(1) for m in MARK.finditer(text)}
        for m in ANY_MARK.finditer(text):
            if m.group(1) not in paired:
                problems.append(f"{page.relative_to(ROOT)}: marker of '{m.group(1)}' without its pair")
    found = committed()
    for name in found:
        if name not in BLOCKS:
            problems.append(f"'{name}' in {found[name][0][0].relative_to(ROOT)} has no generator in tools/docs.py")
    for name, b in BLOCKS.items():
        where = [p for p, _, _ in found.get(name, [])]
        if where != [_page(b)]:
            problems.append(f"'{name}' must be once in {b.page}, is in {[str(p.relative_to(ROOT)) for p in where] or 'no page'}")
        elif found[name][0][2] != HEADER.format(name=name, source=b.source):
            problems.append(f"'{name}': its first line is not the header naming `tools/docs.py --only {name}` and {b.source}")
    return problems


def write(name, body):
    """Replace the text between the markers of block ``name`` in its page by header and ``body``."""
    b = BLOCKS[name]
    page = _page(b)
    text = page.read_text(encoding="utf-8")
    if not any(m.group(1) == name for m in MARK.finditer(text)):
        raise KeyError(f"{b.page} has no markers for '{name}'")
    new = f"<!-- docs.py: {name} -->\n{HEADER.format(name=name, source=b.source)}\n{body.strip()}\n<!-- /docs.py: {name} -->"
    page.write_text(MARK.sub(lambda m: new if m.group(1) == name else m.group(0), text), encoding="utf-8")


def check(names):
    """Problems, one line each: the structure, the fast blocks in full, the slow blocks' checks,
    the artefacts' checks (for ``names``)."""
    problems = structure_problems()
    found = committed()
    for name in names:
        if name in ARTEFACTS:
            problems += [f"{name} (artefact): {p}" for p in ARTEFACTS[name].check()]
            continue
        b = BLOCKS[name]
        if name not in found:
            continue  # said by the structure check
        body = found[name][0][1]
        if not b.slow:
            if generate(name).strip() != body.strip():
                problems.append(f"{name} ({b.page}): differs from what `python tools/docs.py --only {name}` writes")
        elif b.check is not None:
            problems += [f"{name} ({b.page}): {p}" for p in b.check(body)]
    return problems


def generate(name):
    return BLOCKS[name].generate()


def selection(args):
    if args.only:
        unknown = [n for n in args.only if n not in BLOCKS and n not in ARTEFACTS]
        if unknown:
            raise SystemExit(f"tools/docs.py: unknown block(s) {', '.join(unknown)} (see --list)")
        return list(args.only)
    if args.fast:
        return [n for n, b in BLOCKS.items() if not b.slow]
    return [*ARTEFACTS, *BLOCKS]  # the artefacts first: blocks render them


def main(argv=None):
    global DATA
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fast", action="store_true", help="only the fast blocks")
    p.add_argument("--only", nargs="+", metavar="NAME", help="only these blocks or artefacts")
    p.add_argument("--check", action="store_true", help="write nothing; exit 1 listing what differs")
    p.add_argument("--list", action="store_true", help="list the blocks and artefacts")
    p.add_argument("--data", type=Path, default=DATA, help=f"the real data sets beside the repository (default {DATA})")
    args = p.parse_args(argv)
    DATA = args.data
    if args.list:
        for name, a in ARTEFACTS.items():
            print(f"{name:26s} artefact  slow  {a.source}")
        for name, b in BLOCKS.items():
            print(f"{name:26s} {b.page:20s} {'slow' if b.slow else 'fast'}  {b.source}")
        return 0
    names = selection(args)
    if args.check:
        problems = check(names)
        print("\n".join(problems) if problems else f"{len(names)} block(s) and artefact(s) as committed")
        return 1 if problems else 0
    t_all, failed = time.perf_counter(), []
    for name in names:
        t0 = time.perf_counter()
        try:
            if name in ARTEFACTS:
                ARTEFACTS[name].make()
            else:
                write(name, generate(name))
        except Skip as why:
            print(f"{name}: skipped ({why}); the committed text stays", file=sys.stderr)
            continue
        except Exception as exc:  # one failing generator must not cost the others' work
            print(f"{name}: FAILED: {type(exc).__name__}: {exc}; the committed text stays", file=sys.stderr)
            failed.append(name)
            continue
        print(f"{name}: {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
    print(f"tools/docs.py: {len(names)} in {time.perf_counter() - t_all:.0f} s"
          + (f"; failed: {', '.join(failed)}" if failed else ""), file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    with contextlib.suppress(BrokenPipeError):
        sys.exit(main())
