"""The fleet's table and the units that stand out (:mod:`gyrofilter.analysis.fleet`): one row per
recording and axis, the flag rules, fleet.csv and fleet.md. Numbers in, text out.

**The flag rules** (:func:`flag_units`; robust statistics per axis across the units of the fleet,
Iglewicz & Hoaglin, *How to Detect and Handle Outliers*, ASQC 1993, ch. 3: modified z-score,
limit 3.5):

1. *Coefficients N, B, K, R*, per axis of each sensor (the accelerometer's ``ax``, ``ay``, ``az``
   too, :data:`SENSORS`). On the natural log of each unit's level (the fitted value when the
   term is resolved, else its 95 % upper bound): the fleet's median m and spread
   s = max(1.4826 MAD, 0.1). 1.4826 MAD is the standard deviation for normal data; the floor
   0.1 (10 %) is an assumed least unit-to-unit spread, for a small fleet whose units agree closer
   than that by chance would otherwise flag ordinary units (four of the five real recordings
   agree on N of z within 1.4 %). A unit is flagged **high** when even the low end of its
   interval is far above the fleet, (ln low - m) / s > 3.5, on a resolved term; N is also
   flagged **low** when (m - ln high) / s > 3.5. B, K and R are not flagged low: a longer record
   resolves them lower, which is no defect. Unresolved terms enter the median as their upper
   bounds, which only raises it: the rule errs on the side of no flag.
2. *Findings: a departure the unit has and its fleet has not* (issue 35: a unit stands out where
   it differs from the other units, not where the gap analysis has a label for it). On the real
   board of four MPU-9250 units the gap analysis named one spectral line a narrow band on one
   unit, a sinusoid on another and both on a third, and heavy tails on some: every label was
   "rare" and all four units stood out. So the units are compared on what was measured, the
   discrepancy D of the axis against the plain baseline before any extension, and a finding
   counts as its **departure** (:func:`departures`): the labels that are alternative readings of
   one departure are one (:data:`ALTERNATIVES`: the lines, sinusoid and narrow band,
   :data:`gyrofilter.effects.LINES`, where their frequencies lie within :data:`LINE_SAME_REL`,
   5 %, of each other: the 31-Hz line on z of the real MPU6050 recordings is named at 31.0-31.57 Hz
   on four of them, 1.8 % apart, and a narrow band 0.3 Hz wide at 9.6 Hz spans 3 %; the
   wanders, :data:`~gyrofilter.effects.WANDERS`; the tails, outliers and heavy tails,
   :data:`~gyrofilter.effects.TAILS`; every other effect is its own departure). A unit is flagged
   for a departure on an axis when all three hold:

   a. *rare*: fewer than half of the units analysed by ``gap`` have it on that axis
      (:data:`RARE_SHARE`);
   b. *clear*: the unit's D before on that axis is at least :data:`RARE_MIN_D` (the gap analysis
      names a weak effect on a clean unit now and then, about 1 axis in several hundred, at D
      near 1);
   c. *the unit differs there*: the median D before of the other units on that axis is within the
      null band, at most :data:`~gyrofilter.analysis.gap.detectors.OUTSIDE_NULL_D` (the unit departs
      where its peers do not), or the unit's D before is an outlier high among the fleet's on that
      axis: the modified z-score of rule 1 on ln D, (ln D - m) / s > 3.5, m the median and
      s = max(1.4826 MAD, :data:`MIN_SPREAD_D_LN`) over the units analysed (the unit departs far
      more than its peers do, who share some other departure).

   The floor 0.5 of s is the least unit-to-unit spread of ln D assumed, as rule 1's 10 % is of a
   coefficient: D grows steeply with a departure's size (about as its amplitude to the power 2-4
   on a line), so units of one model that share a line whose amplitude differs by 15 % from unit
   to unit spread ln D by 0.10-1.10 (1.4826 MAD of the four units, median 0.38, in 20 simulated
   boards of four MPU-9250-like units, 16 min at 43 Hz: tests/test_fleet.py ``write_board``,
   seeds 1-20), and without the floor their highest D lay up to 2.6 spreads above the median (3.3
   in 8 such boards with a sinusoid for the line), with it up to 1.7. A departure most units share
   (the board's line, whatever each unit's label) is never flagged, nor one that leaves the unit's
   D among its peers'. On those 20 boards the old rule (a label fewer than half have, at D of at
   least 3) flagged a unit on 4; this one on none.

A comparison needs at least :data:`MIN_UNITS` units with a number (3 peers besides the unit);
with fewer, no unit is flagged on it and :func:`flag_units` says so in its statistics.
"""
from __future__ import annotations

import collections
import csv
import math
import os

import numpy as np

from ...effects import BIAS_INSTABILITY, LINE_FREQUENCY, LINES, RATE_RAMP, RATE_RANDOM_WALK, REGISTRY, TAILS, WANDERS
from ...errors import SettingsError
from ...recording.header import markdown_text
from ...units import AXES, MAD_TO_SIGMA, utf8_text
from ..gap.detectors import OUTSIDE_NULL_D
from ..gap.report import not_analysed_why
from ..noise.export import ACCEL_JSON_KEY, JSON_KEY
from ..noise.model import (ACCELEROMETER_TERMS, ANGLE_RANDOM_WALK, GYROSCOPE_TERMS, QUANTIZATION, TERM_SYMBOL,
                           TERMS)
from ..still import LEFT_OUT, NOT_STATIC


#: the Allan coefficients in the fleet table: N, B, K, R (Q, the quantization, is left out)
COEFFICIENTS = (ANGLE_RANDOM_WALK, BIAS_INSTABILITY, RATE_RANDOM_WALK, RATE_RAMP)


#: a sensor of the fleet table: ``prefix`` of its axes' names (``x``; the accelerometer's ``ax``, as
#: ``allan`` names them), ``block`` of the allan JSON that holds its axes (None: the document itself),
#: ``keys`` of its coefficients (its fleet.csv columns, the JSON's keys) and ``terms``
#: (:class:`~gyrofilter.analysis.noise.model.SensorTerms`: the units ``allan`` prints)
FleetSensor = collections.namedtuple("FleetSensor", "prefix block keys terms")
GYRO = FleetSensor("", None, JSON_KEY, GYROSCOPE_TERMS)
ACCEL = FleetSensor("a", "accelerometer", ACCEL_JSON_KEY, ACCELEROMETER_TERMS)
#: the sensors in the order of their rows and columns
SENSORS = (GYRO, ACCEL)


def sensor_of(axis):
    """The :class:`FleetSensor` of a row's ``axis`` (``x``, ``ax``, ...)."""
    return ACCEL if axis.startswith(ACCEL.prefix) else GYRO


#: modified z-score beyond which a unit stands out (Iglewicz & Hoaglin 1993)
FLAG_Z = 3.5


#: least spread s of the log levels (10 %): the unit-to-unit spread assumed at least
MIN_SPREAD_LN = 0.1


#: fewest units with a number for a comparison (the unit and 3 peers)
MIN_UNITS = 4


#: a finding is rare when fewer than this share of the units have it
RARE_SHARE = 0.5


#: a rare departure flags a unit only where the baseline's discrepancy D on that axis (before the
#: extension) is at least this: a departure well outside clean units' (D is about 1 when the baseline
#: explains the data; clean simulated 300-s units: 0.6-1.7, and a rare false sinusoid at D 1.2,
#: tests/test_fleet.py seed 13; units with a hidden line: 7.8-26)
RARE_MIN_D = 3.0


#: least spread s of ln D before across the fleet (module docstring, rule 2c)
MIN_SPREAD_D_LN = 0.5


#: the gap's labels that are alternative readings of one departure from the baseline (rule 2)
ALTERNATIVES = (LINES, WANDERS, TAILS)


#: two lines (sinusoid or narrow band) of an axis are one departure when their frequencies are within
#: this share of the higher one (module docstring, rule 2)
LINE_SAME_REL = 0.05


def departures(findings):
    """The departures (rule 2) that the gap ``findings`` of the units on one axis read: a key per
    finding, in order. A line's key is ``"line f_lo-f_hi Hz"``: the lines of all ``findings``
    sorted by frequency, each joined to the one below it when within :data:`LINE_SAME_REL` of its
    frequency (single linkage), and f_lo, f_hi the group's lowest and highest frequency (``"line f
    Hz"`` for one frequency); another
    finding's key is its group of :data:`ALTERNATIVES` joined by "/", or its effect alone."""
    lines = sorted({f["params"][LINE_FREQUENCY[f["effect"]]] for f in findings if f["effect"] in LINES})
    group_of, members = {}, []
    for hz in lines:
        if not members or hz - members[-1][-1] > LINE_SAME_REL * hz:
            members.append([])
        members[-1].append(hz)
        group_of[hz] = members[-1]
    keys = []
    for f in findings:
        if f["effect"] in LINES:
            group = group_of[f["params"][LINE_FREQUENCY[f["effect"]]]]
            keys.append(f"line {group[0]:.4g} Hz" if len(group) == 1 else f"line {group[0]:.4g}-{group[-1]:.4g} Hz")
        else:
            keys.append("/".join(next((g for g in ALTERNATIVES if f["effect"] in g), (f["effect"],))))
    return keys


def unit_names(paths):
    """A distinct name per recording of ``paths`` for its reports and its rows: the file name without
    ``.gz`` and ``.csv``; recordings whose names clash take as many parent folders as tell them
    apart, joined by ``-`` (``robot1/imu.csv``, ``robot2/imu.csv`` -> ``robot1-imu``,
    ``robot2-imu``). Raises SettingsError when no number of folders does."""
    parts = [os.path.abspath(p).split(os.sep) for p in paths]
    stems = [_stem(p[-1]) for p in parts]
    depth = [1] * len(paths)
    while True:
        names = ["-".join(p[-d:-1] + [s]) for p, s, d in zip(parts, stems, depth)]
        clash = {n for n, count in collections.Counter(names).items() if count > 1}
        if not clash:
            return names
        for i, n in enumerate(names):
            if n in clash:
                if depth[i] >= len(parts[i]):
                    others = [paths[j] for j, m in enumerate(names) if m == n and j != i]
                    raise SettingsError(f"{paths[i]} and {others[0]}: no folder names tell their reports apart; "
                                        "rename one of them")
                depth[i] += 1


def _stem(filename):
    for suffix in (".gz", ".csv"):
        if filename.endswith(suffix) and len(filename) > len(suffix):
            filename = filename[: -len(suffix)]
    return filename


#: the columns of fleet.csv, in order (docs/formats.md, section 9)
COLUMNS = (["unit", "recording", "axis", "status", "sample_rate_hz", "duration_s"]
           + [f"{s.keys[term]}{end}" for s in SENSORS for term in TERMS for end in ("", "_low", "_high", "_upper")]
           + ["findings", "d_before", "d_after", "runtime_s", "flag", "warnings"])


def fleet_rows(names, results):
    """One row (a dict over :data:`COLUMNS`) per recording and axis of ``results`` (those of
    :func:`~gyrofilter.analysis.fleet.work.analyse_recording`, named by ``names``, e.g. :func:`unit_names`), in the order given; a
    failed recording has one row whose ``status`` is the one-line reason, and no axis. Numbers
    are floats or None (not resolved, not analysed). The gyro's rows (axes ``x``, ``y``, ``z``)
    come first, then the accelerometer's (``ax``, ``ay``, ``az``, where the record has one), each
    holding its own sensor's columns; an axis left out of the Allan analysis (a stuck axis; the
    whole accelerometer when it does not read gravity or has gross errors,
    :func:`~gyrofilter.analysis.still.characterise_recording`) is a row whose ``status`` says why.
    A row's warnings are the recording's and its own axis's (``axis ax: ...``); the
    accelerometer's as a whole (a warning ending in :data:`~gyrofilter.analysis.still.LEFT_OUT`
    that names no axis) are on its rows only.

    Two keys beyond the columns: ``skipped`` (the recording was not analysed because its gyro
    moved: its one row, a record the still-sensor analysis refuses, not a failed file) and
    ``moved`` (analysed with ``--allow-motion`` although its gyro moved: a warning of the record
    or of a gyro axis says :data:`~gyrofilter.analysis.still.NOT_STATIC`; kept out of the
    comparison, :func:`flag_units`)."""
    rows = []
    for name, res in zip(names, results):
        base = dict.fromkeys(COLUMNS)
        base.update(unit=name, recording=res["recording"], status="ok" if res["error"] is None else res["error"],
                    sample_rate_hz=res["sample_rate_hz"], duration_s=res["duration_s"],
                    runtime_s=res["runtime_s"], warnings=list(res["warnings"]), flag=[],
                    skipped=bool(res.get("skipped")),
                    moved=any(NOT_STATIC in w and not w.startswith(f"axis {ACCEL.prefix}") for w in res["warnings"]))
        if res["error"] is not None:
            rows.append(base)
            continue
        allan = res["allan"] or {}
        gap = res["gap"]
        idle = ((gap or {}).get("discrepancy") or {}).get("not_analysed", {})
        if gap is not None and not gap.get("discrepancy"):  # too short for the gap: no axis analysed, as gap says
            idle = dict.fromkeys(AXES, not_analysed_why(gap))
        per_axis = [w for w in base["warnings"] if w.startswith("axis ")]
        stuck = {w[len("axis "):].split(":", 1)[0]: w for w in per_axis if w.endswith(LEFT_OUT)}
        accel_out = [w for w in base["warnings"] if not w.startswith("axis ") and w.endswith(LEFT_OUT)]
        shared = [w for w in base["warnings"] if not w.startswith("axis ") and w not in accel_out]
        gyro_axes = allan.get("axes", {})
        accel_axes = (allan.get(ACCEL.block) or {}).get("axes", {})
        axes = [a for a in AXES if a in gyro_axes or a in stuck or gap is not None]
        # the accelerometer's axes: those analysed or left out, the gyro's when it was left out as a whole
        axes += [ACCEL.prefix + a for a in AXES if a in accel_axes or ACCEL.prefix + a in stuck
                 or (accel_out and a in axes)]
        for axis in axes:
            sensor = sensor_of(axis)
            row = dict(base, axis=axis, flag=[],
                       warnings=shared + (accel_out if sensor is ACCEL else [])
                       + [w for w in per_axis if w.startswith(f"axis {axis}:")])
            if axis in stuck and gap is None or sensor is ACCEL and axis in stuck:
                row["status"] = f"{res['recording']}: {stuck[axis]}"  # a stuck axis: a row that says so, not none
            elif sensor is ACCEL and accel_out and axis[len(ACCEL.prefix):] not in accel_axes:
                why = accel_out[0].removeprefix(f"{res['recording']}: ")  # the reason names the file
                row["status"] = f"{res['recording']}: axis {axis}: {why}"
            if axis in idle:  # the gap had nothing to analyse there: its D (about 0) is no measurement
                row["status"] = f"{res['recording']}: axis {axis}: {idle[axis]}, not analysed"
            analysed = (accel_axes if sensor is ACCEL else gyro_axes).get(axis[len(sensor.prefix):])
            if analysed is not None:
                for term in (QUANTIZATION,) + COEFFICIENTS:
                    key = sensor.keys[term]
                    d = analysed["details"][key]
                    row[key], row[f"{key}_low"], row[f"{key}_high"] = d["value"], d["low"], d["high"]
                    row[f"{key}_upper"] = None if d["resolved"] else d["upper_bound"]
            if gap is not None and axis not in idle and sensor is GYRO:
                row["findings"] = [f for f in gap["findings"] if f["axis"] == axis]
                d = gap.get("discrepancy", {})
                row["d_before"] = d.get("before", {}).get(axis)
                row["d_after"] = d.get("after", {}).get(axis)
            rows.append(row)
    return rows


def failed_rows(rows):
    """The rows of ``rows`` (:func:`fleet_rows`) of recordings that failed: their one row, no axis
    (the skipped ones aside, :func:`skipped_rows`)."""
    return [r for r in rows if r["status"] != "ok" and r["axis"] is None and not r.get("skipped")]


def skipped_rows(rows):
    """The rows of ``rows`` (:func:`fleet_rows`) of recordings not analysed because their gyro moved."""
    return [r for r in rows if r.get("skipped")]


def moved_units(rows):
    """The units of ``rows`` (:func:`fleet_rows`) analysed although their gyro moved, in order."""
    return list(dict.fromkeys(r["unit"] for r in rows if r.get("moved") and r["status"] == "ok"))


def left_out_rows(rows):
    """The axes of analysed recordings left out (a stuck axis of an ``allan`` fleet, an axis the gap
    had nothing to analyse): their rows say why. Not a failure of the unit: its other axes hold
    their results."""
    return [r for r in rows if r["status"] != "ok" and r["axis"] is not None]


def flag_units(rows):
    """Mark the rows of units that stand out (module docstring: the rules). Adds to each row's
    ``flag`` a dict per flag (``kind``: "coefficient" or "finding", ``what``, ``direction``,
    ``z`` or ``share``, ``text``) and returns the fleet statistics: a list of dicts per axis and
    quantity (``units``: how many had a number; ``median``/``spread`` of the log levels (of the
    coefficients and of "D before"), or ``having`` for a departure, ``what`` its labels joined by
    "/"; ``compared``: False when too few units). A unit whose gyro moved (``moved``, analysed
    with ``--allow-motion``) is kept out: its numbers describe the motion, and would widen the
    fleet's spread and hide the still units' flags; it is not flagged either."""
    stats = []
    ok = [r for r in rows if r["status"] == "ok" and not r.get("moved")]
    for sensor in _sensors(rows):
        for axis in (sensor.prefix + a for a in AXES):
            on_axis = [r for r in ok if r["axis"] == axis]
            for term in COEFFICIENTS:
                stats.append(_flag_coefficient(axis, term, on_axis))
            if sensor is GYRO:  # the gap analyses the gyro
                stats.extend(_flag_departures(axis, [r for r in on_axis if r["findings"] is not None]))
    return stats


def _sensors(rows):
    """The sensors of :data:`SENSORS` that ``rows`` hold: the gyro always, the accelerometer where a row is its."""
    return [s for s in SENSORS if s is GYRO or any(r["axis"] and sensor_of(r["axis"]) is s for r in rows)]


def _log_centre(values, floor):
    """Median m and spread s = max(1.4826 MAD, ``floor``) of the natural log of ``values``."""
    levels = np.log(values)
    median = float(np.median(levels))
    return median, max(MAD_TO_SIGMA * float(np.median(np.abs(levels - median))), floor)


def _flag_coefficient(axis, term, on_axis):
    """Rule 1 on one coefficient ``term`` of the rows ``on_axis`` (of ``axis``); their statistics entry."""
    sensor = sensor_of(axis)
    key, unit = sensor.keys[term], sensor.terms.term_unit[term]
    have = [r for r in on_axis if (r[key] if r[key] is not None else r[f"{key}_upper"]) is not None]
    entry = {"axis": axis, "what": TERM_SYMBOL[term], "units": len(have), "compared": len(have) >= MIN_UNITS}
    if not entry["compared"]:
        return entry
    median, spread = _log_centre([r[key] if r[key] is not None else r[f"{key}_upper"] for r in have], MIN_SPREAD_LN)
    entry.update(median=math.exp(median), spread=spread)
    for r in have:
        if r[key] is None:
            continue
        high = (math.log(r[f"{key}_low"]) - median) / spread
        low = (median - math.log(r[f"{key}_high"])) / spread
        for direction, z in (("high", high), ("low", low)):
            if z > FLAG_Z and (direction == "high" or term == ANGLE_RANDOM_WALK):
                r["flag"].append({
                    "kind": "coefficient", "what": TERM_SYMBOL[term], "direction": direction, "z": z,
                    "text": f"{TERM_SYMBOL[term]} {direction}: {r[key]:.3g} [{r[f'{key}_low']:.3g}, "
                            f"{r[f'{key}_high']:.3g}] {unit} against the fleet's median "
                            f"{math.exp(median):.3g}: {z:.1f} spreads beyond (limit {FLAG_Z:g})"})
    return entry


def _flag_departures(axis, analysed):
    """Rule 2 on the rows ``analysed`` by the gap on ``axis``; their statistics entries (D before,
    then one per departure found)."""
    measured = [r for r in analysed if r["d_before"] is not None and r["d_before"] > 0]
    entry = {"axis": axis, "what": "D before", "units": len(measured), "compared": len(measured) >= MIN_UNITS}
    stats = [entry]
    if entry["compared"]:
        median, spread = _log_centre([r["d_before"] for r in measured], MIN_SPREAD_D_LN)
        entry.update(median=math.exp(median), spread=spread)
    found = [f for r in analysed for f in r["findings"]]
    key_of = dict(zip(map(id, found), departures(found)))
    labels = {}  # departure -> its labels found on this axis, in the order of the registry
    for effect in (e.name for e in REGISTRY):
        for f in found:
            if f["effect"] == effect and effect not in labels.setdefault(key_of[id(f)], []):
                labels[key_of[id(f)]].append(effect)
    for key, effects in labels.items():
        having = [r for r in analysed if any(key_of[id(f)] == key for f in r["findings"])]
        share = len(having) / len(analysed)
        name = "/".join(effects) + (key[len("line"):] if key.startswith("line ") else "")
        stats.append({"axis": axis, "what": name, "units": len(analysed), "having": len(having),
                      "compared": len(analysed) >= MIN_UNITS and entry["compared"]})
        if not stats[-1]["compared"] or share >= RARE_SHARE:
            continue
        for r in having:
            d = r["d_before"]
            if d is None or d < RARE_MIN_D:
                continue
            peers = float(np.median([p["d_before"] for p in measured if p is not r]))
            z = (math.log(d) - median) / spread
            if peers > OUTSIDE_NULL_D and z <= FLAG_Z:
                continue
            why = (f"the other units' median {peers:.3g} is within the null band (at most {OUTSIDE_NULL_D:g})"
                   if peers <= OUTSIDE_NULL_D else
                   f"{z:.1f} spreads above the fleet's median {math.exp(median):.3g} (limit {FLAG_Z:g})")
            what = "/".join(f["effect"] for f in r["findings"] if key_of[id(f)] == key)
            r["flag"].append({"kind": "finding", "what": what, "direction": "rare", "share": share, "z": z,
                              "text": f"{what} on {axis}, a departure {len(having)} of {len(analysed)} units have "
                                      f"(limit: fewer than {RARE_SHARE:.0%}), at D before {d:.3g}: {why}"})
    return stats


def finding_text(finding):
    """``effect(param=value, ...)`` of a gap report's ``finding`` (a dict), with 4 significant digits (fleet.md)."""
    params = ", ".join(f"{k}={v:.4g}" for k, v in finding["params"].items())
    return f"{finding['effect']}({params})"


def findings_cell(findings):
    """fleet.csv's ``findings``: ``effect:param=value`` per parameter, joined by ``;``, numbers in
    full precision (empty for none)."""
    return ";".join(f"{f['effect']}:{k}={_cell(v)}" for f in findings for k, v in f["params"].items())


#: what a spreadsheet runs as a formula when a text cell starts with it (OWASP, "CSV Injection")
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def _cell(value):
    """A cell of fleet.csv: a number in full precision, or text; text that starts with one of
    :data:`FORMULA_STARTS` (a unit named ``=1+2``) gets a ``'`` in front, OWASP's rule against CSV
    injection, so that a spreadsheet shows it instead of running it (the exact name is in the
    fleet's JSON reports); numbers (a negative one too) are written as they are."""
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, list):
        value = "; ".join(v["text"] if isinstance(v, dict) else str(v) for v in value)
    elif not isinstance(value, str):
        return str(value)
    return "'" + value if value.startswith(FORMULA_STARTS) else value


def fleet_csv(rows):
    """fleet.csv: a header of :data:`COLUMNS` and one line per row of ``rows`` (:func:`fleet_rows`);
    numbers in full precision (Python's shortest round-trip form), empty cells for None, findings
    as :func:`findings_cell`, other lists (flags, warnings) joined by "; "; text as
    :func:`~gyrofilter.units.utf8_text` writes it, a text cell a spreadsheet would run as a formula
    after a ``'`` (:func:`_cell`). Lines end in ``\\n``; a cell holding ``,``, ``"``, a line feed or
    a carriage return is quoted, ``"`` doubled (RFC 4180; Python's ``csv.writer`` leaves a carriage
    return unquoted when the lines end in ``\\n``, and a name holding one split its row)."""
    lines = [COLUMNS] + [[findings_cell(row[c]) if c == "findings" and row[c] is not None else _cell(row[c])
                          for c in COLUMNS] for row in rows]
    text = "".join(",".join(_quoted(cell) for cell in line) + "\n" for line in lines)
    return utf8_text(text)  # names and reasons hold file names, which may not be UTF-8


def listed_units(lines):
    """The unit cells of a fleet.csv (:func:`fleet_csv`), read from ``lines`` (its text's lines as
    a file opened with ``newline=""`` yields them, a row at a time), as a set: what
    :func:`lists_unit` looks a unit up in. A table whose header is not :data:`COLUMNS` (another
    tool's fleet.csv, its first column "camera") lists none: its cells named no report of ours,
    yet a file ``cam.imu.yaml`` of one's own beside it was removed as an earlier run's."""
    rows = csv.reader(lines)
    if next(rows, None) != COLUMNS:
        return set()
    return {row[0] for row in rows if row}


def lists_unit(listed, unit):
    """Whether the unit cells ``listed`` (:func:`listed_units`) hold the unit named ``unit``, as
    :func:`fleet_csv` writes its name."""
    return utf8_text(_cell(unit)) in listed


def _quoted(cell):
    """A CSV cell as RFC 4180 writes it: in ``"`` when it holds ``,``, ``"``, CR or LF, ``"`` doubled."""
    return '"' + cell.replace('"', '""') + '"' if any(c in cell for c in ',"\r\n') else cell


def _coef_md(row, key):
    value, low, high, upper = (row[key + end] for end in ("", "_low", "_high", "_upper"))
    if value is not None:
        return f"{value:.3g} [{low:.3g}, {high:.3g}]"
    return f"< {upper:.2g}" if upper is not None else ""


def _coefficient_table(rows, sensor, gap):
    """The lines of fleet.md's table of ``sensor``'s coefficients (in the units ``allan`` prints), a
    line per row of ``rows``; with ``gap`` the gap's findings and D columns."""
    keys = [sensor.keys[t] for t in COEFFICIENTS]
    head = " | ".join(f"{TERM_SYMBOL[t]} ({sensor.terms.term_unit[t]})" for t in COEFFICIENTS)
    lines = [f"| unit | axis | {head} |" + (" findings | D before -> after |" if gap else "") + " runtime (s) | flags |",
             "|---|---|" + "---|" * (len(keys) + 2 * gap) + "---|---|"]
    for r in rows:
        cells = [_coef_md(r, k) for k in keys]
        if gap:
            cells.append("" if r["findings"] is None else ("; ".join(finding_text(f) for f in r["findings"]) or "none"))
            cells.append("" if r["d_before"] is None else f"{r['d_before']:.3g} -> {r['d_after']:.3g}")
        cells += [f"{r['runtime_s']:.1f}", ", ".join(f"{f['what']} {f['direction']}" for f in r["flag"])]
        lines.append(f"| {markdown_text(r['unit'])} | {r['axis']} | " + " | ".join(cells) + " |")
    return lines


def outcome_text(rows):
    """The fleet's outcome in one line (fleet.md's and the summary's): recordings, analysed (and of
    them moving), not still, failed, axes left out, units that stand out."""
    failed, left_out, skipped = failed_rows(rows), left_out_rows(rows), skipped_rows(rows)
    done = len({r["unit"] for r in rows if r["status"] == "ok"})
    moved = moved_units(rows)
    return (f"{len({r['unit'] for r in rows})} recording(s), {done} analysed"
            + (f" ({len(moved)} of them moving: kept out of the comparison)" if moved else "")
            + (f", {len(skipped)} not still (not analysed)" if skipped else "")
            + f", {len(failed)} failed" + (f", {len(left_out)} axis/axes left out" if left_out else "")
            + f", {len({r['unit'] for r in rows if r['flag']})} stand(s) out")


def fleet_markdown(rows, stats, *, title, not_recordings=()):
    """fleet.md, headed ``title``: the units that stand out, the failed files, a row per
    recording and axis (``rows``, :func:`fleet_rows`; the gap's findings and D columns only
    when some row has gap results; the accelerometer's rows in a table of their own, in its
    units, when the fleet has one), and the fleet statistics ``stats`` (what
    :func:`flag_units` returns) with the rules. ``not_recordings``: (path, why) of the paths given
    that are no recordings (a folder, a README), skipped and not counted."""
    failed, left_out, skipped = failed_rows(rows), left_out_rows(rows), skipped_rows(rows)
    flagged = [r for r in rows if r["flag"]]
    lines = [f"# {title}", "", outcome_text(rows) + ".", "", "## Units that stand out", ""]
    if flagged:
        lines += ["| unit | axis | why |", "|---|---|---|"]
        lines += [f"| {markdown_text(r['unit'])} | {r['axis']} | {f['text']} |" for r in flagged for f in r["flag"]]
    else:
        lines.append("None.")
    moved = moved_units(rows)
    if moved:
        lines += ["", f"Analysed although the gyro moved (--allow-motion), kept out of the comparison: "
                      f"{', '.join(markdown_text(u) for u in moved)}."]
    for heading, which in (("Not still (not analysed; --allow-motion analyses them)", skipped), ("Failed", failed),
                           ("Axes left out", left_out)):
        if which:
            lines += ["", f"## {heading}", "", "| unit | recording | reason |", "|---|---|---|"]
            lines += [f"| {markdown_text(r['unit'])} | {markdown_text(r['recording'])} | {markdown_text(r['status'])} |"
                      for r in which]
    if not_recordings:
        lines += ["", "## Not recordings (skipped, not counted)", "", "| path | why |", "|---|---|"]
        lines += [f"| {markdown_text(path)} | {markdown_text(why)} |" for path, why in not_recordings]
    # the gap's columns only when the gap ran (a gap fleet); an allan fleet has none to show
    gap = any(r["findings"] is not None for r in rows if r["status"] == "ok")
    lines += ["", "## Per recording and axis", "",
              "Fit and 95 % interval, or < the upper bound when the record does not resolve the term"
              + ("; findings of the gap analysis; D = discrepancy against the baseline before and after the findings."
                 if gap else "."), ""]
    lines += _coefficient_table([r for r in rows if r["status"] == "ok" and sensor_of(r["axis"]) is GYRO], GYRO, gap)
    accel = [r for r in rows if r["status"] == "ok" and sensor_of(r["axis"]) is ACCEL]
    if accel:
        lines += ["", "## Accelerometer, per recording and axis", "",
                  f"The same of the acceleration (in {ACCEL.terms.unit}; the axes {', '.join(ACCEL.prefix + a for a in AXES)}"
                  ", as allan names them): N the velocity random walk, K the acceleration random walk.", ""]
        lines += _coefficient_table(accel, ACCEL, False)
    lines += ["", "## Fleet statistics", "",
              (f"Coefficients: median m over the units of the level (fit, or upper bound when not resolved) and "
               f"spread s = max({MAD_TO_SIGMA} MAD, {MIN_SPREAD_LN:g}) of its natural log; a unit is flagged when the "
               f"near end of its interval lies more than {FLAG_Z:g} s from m (N high or low; B, K, R high). "
               f"Findings, as departures (labels that read one departure count as one: "
               f"{'; '.join('/'.join(g) for g in ALTERNATIVES)}): flagged when fewer than {RARE_SHARE:.0%} of "
               f"the units analysed have the departure, the unit's D before the extension is at least "
               f"{RARE_MIN_D:g}, and the other units' median D before is at most {OUTSIDE_NULL_D:g} (the null band) "
               f"or the unit's D lies more than {FLAG_Z:g} s above the fleet's (s of ln D at least "
               f"{MIN_SPREAD_D_LN:g}). At least {MIN_UNITS} units per comparison."), "",
              "| axis | quantity | units | median | spread s (ln) / units with it |", "|---|---|---|---|---|"]
    for s in stats:
        if not s["compared"]:
            tail = f"not compared: fewer than {MIN_UNITS} units"
            lines.append(f"| {s['axis']} | {s['what']} | {s['units']} | | {tail} |")
        elif "median" in s:
            lines.append(f"| {s['axis']} | {s['what']} | {s['units']} | {s['median']:.3g} | {s['spread']:.3g} |")
        else:
            lines.append(f"| {s['axis']} | {s['what']} | {s['units']} | | {s['having']} |")
    return utf8_text("\n".join(lines) + "\n")  # names and reasons hold file names, which may not be UTF-8
