"""Characterise a fleet: many recordings at once, one table, and the units that stand out.

Three pure parts and two ways to run the first one:

- :func:`analyse_recording` ``(path, settings) -> result``: the per-file work of ``gyrofilter
  allan`` (Allan deviation and coefficients) or ``gyrofilter gap`` (the gap analysis, and the
  Allan coefficients of the same file). It reads the file and returns plain data (the reports
  as the single-file commands write them); a file that cannot be analysed gives a result with
  its ``error`` instead of an exception. Its numbers depend only on the file and the settings
  (the gap simulations use ``settings.seed`` for every file), never on where it runs.
- :func:`run_local` runs it in worker processes (a
  :class:`concurrent.futures.ProcessPoolExecutor`), :func:`run_dask` on a Dask distributed cluster
  (``Client.map``; the ``[cluster]`` extra, imported only there). Both yield ``(index, result)``
  as files finish.
- :func:`fleet_rows` makes one row per recording and axis (a failed file: one row with the
  reason), :func:`flag_units` marks the units that stand out, :func:`fleet_csv` and
  :func:`fleet_markdown` render the table.

**The flag rules** (:func:`flag_units`; robust statistics per axis across the units of the fleet,
Iglewicz & Hoaglin, *How to Detect and Handle Outliers*, ASQC 1993, ch. 3: modified z-score,
limit 3.5):

1. *Coefficients N, B, K, R.* On the natural log of each unit's level (the fitted value when the
   term is resolved, else its 95 % upper bound): the fleet's median m and spread
   s = max(1.4826 MAD, 0.1). 1.4826 MAD is the standard deviation for normal data; the floor
   0.1 (10 %) is an assumed least unit-to-unit spread, for a small fleet whose units agree closer
   than that by chance would otherwise flag ordinary units (four of the five real recordings
   agree on N of z within 1.4 %). A unit is flagged **high** when even the low end of its
   interval is far above the fleet, (ln low - m) / s > 3.5, on a resolved term; N is also
   flagged **low** when (m - ln high) / s > 3.5. B, K and R are not flagged low: a longer record
   resolves them lower, which is no defect. Unresolved terms enter the median as their upper
   bounds, which only raises it: the rule errs on the side of no flag.
2. *Findings.* A gap finding (effect on an axis) that fewer than half of the units analysed by
   ``gap`` have is flagged on the units that have it ("a finding most units lack"), where the
   baseline's discrepancy on that axis is at least :data:`RARE_MIN_D` (a clear departure: the
   gap analysis names a weak effect on a clean unit now and then, about 1 axis in several
   hundred, at D near 1).

A comparison needs at least :data:`MIN_UNITS` units with a number (3 peers besides the unit);
with fewer, no unit is flagged on it and :func:`flag_units` says so in its statistics.
"""
from __future__ import annotations

import asyncio
import collections
import contextlib
import csv
import dataclasses
import io
import math
import multiprocessing
import os
import signal
import threading
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool

import numpy as np

from ..effects import BIAS_INSTABILITY, RATE_RAMP, RATE_RANDOM_WALK
from .noise.allan import MIN_CLUSTERS
from .gap.pipeline import analyse_file
from .noise.export import JSON_KEY, kalibr_yaml, to_json
from .noise.model import ANGLE_RANDOM_WALK, QUANTIZATION, TERMS, TERM_SYMBOL, TERM_UNIT
from .still import LEFT_OUT, characterise_recording
from ..errors import MissingExtraError, SettingsError, one_line
from ..extras import install_hint, require
from ..inputs import quote
from ..units import AXES, MAD_TO_SIGMA, utf8_text

#: the Allan coefficients in the fleet table: N, B, K, R (Q, the quantization, is left out)
COEFFICIENTS = (ANGLE_RANDOM_WALK, BIAS_INSTABILITY, RATE_RANDOM_WALK, RATE_RAMP)
#: modified z-score beyond which a unit stands out (Iglewicz & Hoaglin 1993)
FLAG_Z = 3.5
#: least spread s of the log levels (10 %): the unit-to-unit spread assumed at least
MIN_SPREAD_LN = 0.1
#: fewest units with a number for a comparison (the unit and 3 peers)
MIN_UNITS = 4
#: a finding is rare when fewer than this share of the units have it
RARE_SHARE = 0.5
#: a rare finding flags a unit only where the baseline's discrepancy D on that axis (before the
#: extension) is at least this: a departure well outside clean units' (D is about 1 when the baseline
#: explains the data; clean simulated 300-s units: 0.6-1.7, and a rare false sinusoid at D 1.2,
#: tests/test_fleet.py seed 13; units with a hidden line: 7.8-26)
RARE_MIN_D = 3.0
#: environment of local worker processes: one thread per numeric library, as many workers as cores
#: (two workers with a BLAS thread pool each on 2 cores: 1.8x slower); a value set already is kept
WORKER_ENVIRONMENT = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
#: longest wait (s) for a Dask scheduler to answer (``--scheduler``): the connection and Dask's
#: handshake, which Dask itself would wait for without end
SCHEDULER_TIMEOUT_S = 10.0
#: how often (s) a local worker process checks that the process that started it is still there
PARENT_POLL_S = 0.5
#: exceptions that make a file's row "failed": the same as the command line's one-line errors,
#: and running out of memory (a worker with too large a file)
FILE_ERRORS = (OSError, ValueError, MemoryError)


@dataclasses.dataclass(frozen=True)
class FleetSettings:
    """What :func:`analyse_recording` does with each file (picklable, the same for all files).

    ``command``: ``"allan"`` (the Allan part only) or ``"gap"`` (the gap analysis and the Allan
    part). The Allan part uses ``axes``, ``confidence``, ``min_clusters``, ``keep_outliers`` as
    ``gyrofilter allan`` does; the gap part ``seed`` and ``sims`` as ``gyrofilter gap``.
    """

    command: str
    axes: tuple | str = AXES  # axis letters, in order: all three, or e.g. "xz" from the command line
    confidence: float = 0.95
    min_clusters: int = MIN_CLUSTERS
    keep_outliers: bool = False
    seed: int = 0
    sims: int | None = None


def analyse_recording(path, settings):
    """The per-file work of a fleet run: a dict of plain data.

    Keys: ``recording`` (``path``), ``error`` (None, or the one-line reason the file could not be
    analysed), ``warnings`` (sentences), ``sample_rate_hz``, ``duration_s``, ``allan`` (the Allan
    document of docs/formats.md section 4, or None), ``kalibr`` (Kalibr's imu.yaml text, or
    None), ``gap`` (the gap report of section 3, or None) and ``runtime_s`` (wall time).

    With ``settings.command == "gap"`` a failure of the Allan part (gross errors, a record too
    short for two cluster times) leaves ``allan`` None with the reason in ``warnings``, and the
    gap report stands.
    """
    t0 = time.perf_counter()
    result = {"recording": path, "error": None, "warnings": [], "sample_rate_hz": None, "duration_s": None,
              "allan": None, "kalibr": None, "gap": None}
    try:
        if settings.command == "gap":
            result["gap"] = _gap_report(path, settings, result["warnings"])
            result["sample_rate_hz"] = result["gap"]["sample_rate_hz"]
            result["duration_s"] = result["gap"]["duration_s"]
        try:
            _allan_part(path, settings, result)
        except FILE_ERRORS as exc:
            if settings.command == "allan":
                raise
            result["warnings"].append(f"Allan coefficients not fitted: {one_line(exc)}")
    except FILE_ERRORS as exc:
        reason = "out of memory" if isinstance(exc, MemoryError) else one_line(exc)
        result["error"] = reason if reason.startswith(path) else f"{path}: {reason}"
    result["runtime_s"] = time.perf_counter() - t0
    return result


def _gap_report(path, settings, warnings):
    return analyse_file(path, seed=settings.seed, n_sims=settings.sims, warn=warnings.append)[1]


def _allan_part(path, settings, result):
    def warn(text):
        if text not in result["warnings"]:  # the gap part read the same file and said it already
            result["warnings"].append(text)

    head, results = characterise_recording(path, axes=settings.axes, confidence=settings.confidence,
                                           min_clusters=settings.min_clusters,
                                           keep_outliers=settings.keep_outliers, warn=warn, skip_constant=True)
    sample_rate_hz = head.sample_rate_hz
    for axis, r in results.items():
        result["warnings"].extend(text if text.startswith("axis ") else f"axis {axis}: {text}" for text in r.warnings)
    result["allan"] = to_json(results, sample_rate_hz, recording=path, duration_s=head.rows / sample_rate_hz)
    result["kalibr"] = kalibr_yaml(results, sample_rate_hz, recording=path)
    result["sample_rate_hz"], result["duration_s"] = sample_rate_hz, head.rows / sample_rate_hz


def failed(path, reason):
    """The result of a file whose work never ran or never returned (a glob that matched nothing,
    a worker that died): its ``error`` names the file ``path`` and ``reason``."""
    return {"recording": path, "error": f"{path}: {reason}", "warnings": [], "sample_rate_hz": None, "duration_s": None,
            "allan": None, "kalibr": None, "gap": None, "runtime_s": None}


# -------------------------------------------------------------------------------- names of outputs


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


# ------------------------------------------------------------------------------------- backends


def default_jobs():
    """The CPU cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def run_local(paths, settings, jobs):
    """Yield ``(index, result)`` of :func:`analyse_recording` (with ``settings``) for each of ``paths`` as it
    finishes, in ``jobs`` worker processes (:class:`~concurrent.futures.ProcessPoolExecutor`).

    ``jobs=1`` runs in one worker process too: every backend computes with one thread per
    numeric library (:data:`WORKER_ENVIRONMENT`, Dask's default for its workers), because a
    multi-threaded BLAS sums in another order and the last bits of some results would depend on
    where they ran. A worker that dies (killed, out of memory) fails the files it had, with that
    reason. When the caller stops (Ctrl-C, an error) the workers are ended at once, not after
    their current file; when the calling process dies (SIGKILL), each worker ends by itself within
    :data:`PARENT_POLL_S` seconds (:func:`_worker_init`)."""
    # fresh processes (not forks of this one and its thread pools) that start with WORKER_ENVIRONMENT
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_worker_init, initargs=(os.getpid(),))
    try:
        with _worker_environment():  # the workers start during the first submits
            futures = {pool.submit(analyse_recording, path, settings): i for i, path in enumerate(paths)}
        for future in as_completed(futures):
            i = futures[future]
            try:
                result = future.result()
            except BrokenProcessPool:
                result = failed(paths[i], "a worker process ended abruptly (killed, or out of memory: "
                                          "try a smaller --jobs)")
            yield i, result
    except BaseException:  # Ctrl-C, an error, or the caller closed this generator: end the workers now
        processes = list((pool._processes or {}).values())  # no public way before Python 3.14
        pool.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            process.terminate()
        raise
    pool.shutdown()


@contextlib.contextmanager
def _worker_environment():
    """Set the variables of :data:`WORKER_ENVIRONMENT` that are not set, for processes started
    inside the block; restore the environment after it."""
    added = {k: v for k, v in WORKER_ENVIRONMENT.items() if k not in os.environ}
    os.environ.update(added)
    try:
        yield
    finally:
        for key in added:
            os.environ.pop(key, None)


def _worker_init(parent_pid):
    """Set up a local worker process: Ctrl-C is left to the parent, which ends the workers
    (:func:`run_local`), and a daemon thread ends the worker at once (``os._exit``) when the
    parent ``parent_pid`` is gone: a killed parent cannot end its workers, which would otherwise
    finish their file and then wait for work for ever. The check, every :data:`PARENT_POLL_S`
    seconds, compares ``os.getppid()`` with ``parent_pid`` (an orphan is adopted by another
    process), which works wherever Python runs."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_exit_with_parent, args=(parent_pid,), name="gyrofilter-parent-watch",
                     daemon=True).start()


def _exit_with_parent(parent_pid):
    while os.getppid() == parent_pid:
        time.sleep(PARENT_POLL_S)
    os._exit(1)


def run_dask(paths, settings, address, timeout_s=None):
    """Connect to the Dask distributed cluster whose scheduler is at ``address``, then return an
    iterator that yields ``(index, result)`` of :func:`analyse_recording` (with ``settings``) for
    each of ``paths`` as it finishes there (``dask.distributed.Client.map``). The workers read the
    files at the same paths, so the paths must name the same files on every worker (a shared file
    system). A file whose task killed its workers (Dask's ``KilledWorker``) fails with that reason.

    SettingsError, before any work, when no Dask scheduler answers at ``address`` within
    ``timeout_s`` seconds (default :data:`SCHEDULER_TIMEOUT_S`): nothing listening, a server of
    another protocol (an HTTP server), one that never answers, a malformed address."""
    distributed = _distributed()
    client = _connect(distributed, address, SCHEDULER_TIMEOUT_S if timeout_s is None else timeout_s)
    return _dask_results(distributed, client, paths, settings)


def _connect(distributed, address, timeout_s):
    """A ``distributed.Client`` of the scheduler at ``address``, or SettingsError in one line.

    Dask's own connect waits for the peer's handshake without a time limit and sizes its buffer
    from the peer's first 8 bytes (an HTTP server's make 3 EiB: MemoryError), so the handshake is
    first tried alone, under ``timeout_s`` seconds; only a peer that completes it gets a Client."""
    from distributed.comm import connect

    async def handshake():
        comm = await asyncio.wait_for(connect(address, timeout=timeout_s), timeout_s)
        await comm.close()

    try:
        asyncio.run(handshake())
        return distributed.Client(address, timeout=timeout_s)
    except Exception as exc:  # noqa: BLE001 - whatever the comm layer raises, no scheduler is there
        if isinstance(exc, (TimeoutError, asyncio.TimeoutError)):
            reason = f"no answer within {timeout_s:g} s"
        elif isinstance(exc, MemoryError):
            reason = "it answered in another protocol"
        else:
            reason = one_line(exc)[:120]
        raise SettingsError(f"--scheduler {quote(address)}: no Dask scheduler answered there ({reason})") from None


def _dask_results(distributed, client, paths, settings):
    """The results of ``paths`` on ``client``'s cluster as they finish (:func:`run_dask`); closes the client."""
    with client:
        futures = client.map(analyse_recording, paths, settings=settings, pure=False)
        index = {future.key: i for i, future in enumerate(futures)}
        for future in distributed.as_completed(futures):
            i = index[future.key]
            try:
                result = future.result()
            except distributed.KilledWorker as exc:
                result = failed(paths[i], f"the Dask workers running it died ({exc})")
            yield i, result


def _distributed():
    """``dask.distributed``, or MissingExtraError naming the ``[cluster]`` extra."""
    require("dask", "--scheduler (a Dask cluster)")
    try:
        import dask.distributed
    except ImportError:  # dask without its distributed scheduler
        raise MissingExtraError(f"--scheduler needs dask.distributed: {install_hint('cluster')}") from None
    return dask.distributed


# ------------------------------------------------------------------------------------ the table

#: the columns of fleet.csv, in order (docs/formats.md, section 9)
COLUMNS = (["unit", "recording", "axis", "status", "sample_rate_hz", "duration_s"]
           + [f"{JSON_KEY[term]}{end}" for term in TERMS for end in ("", "_low", "_high", "_upper")]
           + ["findings", "d_before", "d_after", "runtime_s", "flag", "warnings"])


def fleet_rows(names, results):
    """One row (a dict over :data:`COLUMNS`) per recording and axis of ``results`` (those of
    :func:`analyse_recording`, named by ``names``, e.g. :func:`unit_names`), in the order given; a
    failed recording has one row whose ``status`` is the one-line reason, and no axis. Numbers
    are floats or None (not resolved, not analysed)."""
    rows = []
    for name, res in zip(names, results):
        base = dict.fromkeys(COLUMNS)
        base.update(unit=name, recording=res["recording"], status="ok" if res["error"] is None else res["error"],
                    sample_rate_hz=res["sample_rate_hz"], duration_s=res["duration_s"],
                    runtime_s=res["runtime_s"], warnings=list(res["warnings"]), flag=[])
        if res["error"] is not None:
            rows.append(base)
            continue
        allan_axes = (res["allan"] or {}).get("axes", {})
        gap = res["gap"]
        stuck = {w[len("axis ")]: w for w in base["warnings"] if w.startswith("axis ") and w.endswith(LEFT_OUT)}
        axes = [a for a in AXES if a in allan_axes or a in stuck or gap is not None]
        for axis in axes:
            # the recording's warnings, and of the per-axis ones ("axis x: ...") only this axis's
            row = dict(base, axis=axis, flag=[],
                       warnings=[w for w in base["warnings"] if not w.startswith("axis ") or w.startswith(f"axis {axis}:")])
            if axis in stuck and gap is None:  # an Allan fleet's stuck axis: a row that says so, not none
                row["status"] = f"{res['recording']}: {stuck[axis]}"
            if axis in allan_axes:
                details = allan_axes[axis]["details"]
                for term in (QUANTIZATION,) + COEFFICIENTS:
                    key = JSON_KEY[term]
                    d = details[key]
                    row[key], row[f"{key}_low"], row[f"{key}_high"] = d["value"], d["low"], d["high"]
                    row[f"{key}_upper"] = None if d["resolved"] else d["upper_bound"]
            if gap is not None:
                row["findings"] = [f for f in gap["findings"] if f["axis"] == axis]
                d = gap.get("discrepancy", {})
                row["d_before"] = d.get("before", {}).get(axis)
                row["d_after"] = d.get("after", {}).get(axis)
            rows.append(row)
    return rows


def flag_units(rows):
    """Mark the rows of units that stand out (module docstring: the rules). Adds to each row's
    ``flag`` a dict per flag (``kind``: "coefficient" or "finding", ``what``, ``direction``,
    ``z`` or ``share``, ``text``) and returns the fleet statistics: a list of dicts per axis and
    quantity (``units``: how many had a number; ``median``/``spread`` of the log levels, or
    ``having`` for findings; ``compared``: False when too few units)."""
    stats = []
    ok = [r for r in rows if r["status"] == "ok"]
    for axis in AXES:
        on_axis = [r for r in ok if r["axis"] == axis]
        for term in COEFFICIENTS:
            key = JSON_KEY[term]
            have = [r for r in on_axis if (r[key] if r[key] is not None else r[f"{key}_upper"]) is not None]
            levels = np.log([r[key] if r[key] is not None else r[f"{key}_upper"] for r in have])
            entry = {"axis": axis, "what": TERM_SYMBOL[term], "units": len(have), "compared": len(have) >= MIN_UNITS}
            stats.append(entry)
            if not entry["compared"]:
                continue
            median = float(np.median(levels))
            spread = max(MAD_TO_SIGMA * float(np.median(np.abs(levels - median))), MIN_SPREAD_LN)
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
                                    f"{r[f'{key}_high']:.3g}] {TERM_UNIT[term]} against the fleet's median "
                                    f"{math.exp(median):.3g}: {z:.1f} spreads beyond (limit {FLAG_Z:g})"})
        analysed = [r for r in on_axis if r["findings"] is not None]
        effects = sorted({f["effect"] for r in analysed for f in r["findings"]})
        for effect in effects:
            having = [r for r in analysed if any(f["effect"] == effect for f in r["findings"])]
            share = len(having) / len(analysed)
            entry = {"axis": axis, "what": effect, "units": len(analysed), "having": len(having),
                     "compared": len(analysed) >= MIN_UNITS}
            stats.append(entry)
            if entry["compared"] and share < RARE_SHARE:
                for r in having:
                    if r["d_before"] is None or r["d_before"] < RARE_MIN_D:
                        continue
                    r["flag"].append({"kind": "finding", "what": effect, "direction": "rare", "share": share,
                                       "text": f"{effect} on {axis}, a finding {len(having)} of {len(analysed)} "
                                               f"units have (limit: fewer than {RARE_SHARE:.0%})"})
    return stats


def finding_text(finding):
    """``effect(param=value, ...)`` of a gap report's ``finding`` (a dict), with 4 significant digits (fleet.md)."""
    params = ", ".join(f"{k}={v:.4g}" for k, v in finding["params"].items())
    return f"{finding['effect']}({params})"


def findings_cell(findings):
    """fleet.csv's ``findings``: ``effect:param=value`` per parameter, joined by ``;``, numbers in
    full precision (empty for none)."""
    return ";".join(f"{f['effect']}:{k}={_cell(v)}" for f in findings for k, v in f["params"].items())


def _cell(value):
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, list):
        return "; ".join(v["text"] if isinstance(v, dict) else str(v) for v in value)
    return str(value)


def fleet_csv(rows):
    """fleet.csv: a header of :data:`COLUMNS` and one line per row of ``rows`` (:func:`fleet_rows`);
    numbers in full precision (Python's shortest round-trip form), empty cells for None, findings
    as :func:`findings_cell`, other lists (flags, warnings) joined by "; "; text as
    :func:`~gyrofilter.units.utf8_text` writes it."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(COLUMNS)
    for row in rows:
        writer.writerow([findings_cell(row[c]) if c == "findings" and row[c] is not None else _cell(row[c])
                         for c in COLUMNS])
    return utf8_text(out.getvalue())  # names and reasons hold file names, which may not be UTF-8


def _coef_md(row, key):
    value, low, high, upper = (row[key + end] for end in ("", "_low", "_high", "_upper"))
    if value is not None:
        return f"{value:.3g} [{low:.3g}, {high:.3g}]"
    return f"< {upper:.2g}" if upper is not None else ""


def fleet_markdown(rows, stats, *, title):
    """fleet.md, headed ``title``: the units that stand out, the failed files, a row per
    recording and axis (``rows``, :func:`fleet_rows`; the gap's findings and D columns only
    when some row has gap results), and the fleet statistics ``stats`` (what
    :func:`flag_units` returns) with the rules."""
    units = list(dict.fromkeys(r["unit"] for r in rows))
    failed_rows = [r for r in rows if r["status"] != "ok"]  # a recording, or one stuck axis of it
    done = len({r["unit"] for r in rows if r["status"] == "ok"})
    flagged = [r for r in rows if r["flag"]]
    lines = [f"# {title}", "",
             (f"{len(units)} recordings: {done} analysed, {len(units) - done} failed; "
              f"{len({r['unit'] for r in flagged})} stand out."), "", "## Units that stand out", ""]
    if flagged:
        lines += ["| unit | axis | why |", "|---|---|---|"]
        lines += [f"| {r['unit']} | {r['axis']} | {f['text']} |" for r in flagged for f in r["flag"]]
    else:
        lines.append("None.")
    if failed_rows:
        lines += ["", "## Failed", "", "| unit | recording | reason |", "|---|---|---|"]
        lines += [f"| {r['unit']} | `{r['recording']}` | {r['status']} |" for r in failed_rows]
    keys = [JSON_KEY[t] for t in COEFFICIENTS]
    head = " | ".join(f"{TERM_SYMBOL[t]} ({TERM_UNIT[t]})" for t in COEFFICIENTS)
    # the gap's columns only when the gap ran (a gap fleet); an allan fleet has none to show
    gap = any(r["findings"] is not None for r in rows if r["status"] == "ok")
    lines += ["", "## Per recording and axis", "",
              "Fit and 95 % interval, or < the upper bound when the record does not resolve the term"
              + ("; findings of the gap analysis; D = discrepancy against the baseline before and after the findings."
                 if gap else "."), "",
              f"| unit | axis | {head} |" + (" findings | D before -> after |" if gap else "") + " runtime (s) | flags |",
              "|---|---|" + "---|" * (len(keys) + 2 * gap) + "---|---|"]
    for r in rows:
        if r["status"] != "ok":
            continue
        cells = [_coef_md(r, k) for k in keys]
        if gap:
            cells.append("" if r["findings"] is None else ("; ".join(finding_text(f) for f in r["findings"]) or "none"))
            cells.append("" if r["d_before"] is None else f"{r['d_before']:.3g} -> {r['d_after']:.3g}")
        cells += [f"{r['runtime_s']:.1f}", ", ".join(f"{f['what']} {f['direction']}" for f in r["flag"])]
        lines.append(f"| {r['unit']} | {r['axis']} | " + " | ".join(cells) + " |")
    lines += ["", "## Fleet statistics", "",
              (f"Coefficients: median m over the units of the level (fit, or upper bound when not resolved) and "
               f"spread s = max({MAD_TO_SIGMA} MAD, {MIN_SPREAD_LN:g}) of its natural log; a unit is flagged when the "
               f"near end of its interval lies more than {FLAG_Z:g} s from m (N high or low; B, K, R high). "
               f"Findings: flagged when fewer than {RARE_SHARE:.0%} of the units analysed have them and the "
               f"unit's D before the extension is at least {RARE_MIN_D:g}. "
               f"At least {MIN_UNITS} units per comparison."), "",
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
