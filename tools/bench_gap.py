"""Time and peak memory of ``gyrofilter gap FILE`` against ``gyrofilter allan FILE`` (the same file), by record length.

    python tools/bench_gap.py [--records 10m@100 1h@100 24h@100 1h@1000] [--clean]
                              [--files recordings/*.csv.gz] [--cache DIR] [--json OUT.json]

For each record (LENGTH@RATE in Hz) an MPU6050-like recording (131 LSB per deg/s, columns t, gx,
gy, gz) is simulated **with effects** (x: warm-up and colored noise; y: bias instability and
spikes; z: a sinusoid; ``--clean`` adds the same record without them: bias, white noise and
quantization only) and written as a user's ``.csv.gz`` (``gyrofilter.recording.write_recording``)
into a cache directory (default ``$TMPDIR/gyrofilter-bench-gap``; the file's name holds a hash of
the model, length, rate and seed, so a rerun reuses it and a changed model makes a new one).
Then the two commands run on it as a user runs them, with their defaults, each in a fresh
process: ``gyrofilter allan FILE`` and ``gyrofilter gap FILE --json OUT.json`` (``allan`` gets
``--keep-outliers`` where it refuses the record's spikes otherwise, said in the table). Printed
per run: wall-clock seconds of each command (reading the file included), their ratio, the peak
resident memory of each process (``ru_maxrss`` of the child from ``os.wait4``), the part of the
gap's time its parameters' intervals took (``intervals.runtime_s`` of the report), the
findings, and the 1-minute load average of this shared machine at the end. ``--files`` times
recordings the same way (``--records`` with no value: only them). ``--json`` also writes the rows
(``tools/docs.py`` renders the tables of docs/gap.md and README.md from that file).

Targets (issue 36, restating issue 24's 8x): 24 h at 100 Hz, gap at most 400 MB peak and at most 12x the time of allan;
1 h at 1 kHz, gap at most 60 s.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SEED = 1

EFFECTS = {"x": [{"effect": "warmup", "amplitude_dps": 0.2, "tau_s": 300.0},
                 {"effect": "colored_noise", "lag1": 0.2}],
           "y": [{"effect": "bias_instability", "b_dps": 0.004},
                 {"effect": "outliers", "rate": 2e-5, "magnitude_dps": 1.5}],
           "z": [{"effect": "sinusoid", "frequency_hz": 7.3, "amplitude_dps": 0.02}]}
TARGETS = "targets (issue 36): 24 h @ 100 Hz gap <= 400 MB peak and <= 12x allan's time; 1 h @ 1 kHz gap <= 60 s"


def model(rate_hz, effects):
    axes = {"x": {"bias_dps": -3.3, "arw_dps_per_sqrt_hz": 0.009},
            "y": {"bias_dps": 1.1, "arw_dps_per_sqrt_hz": 0.012},
            "z": {"bias_dps": 0.4, "arw_dps_per_sqrt_hz": 0.008}}
    for a, spec in axes.items():
        spec["effects"] = list(EFFECTS[a]) if effects else []
    return {"sample_rate_hz": rate_hz, "gyro_unit": "lsb", "lsb_per_dps": 131.0, "axes": axes}


def record_file(cache, text, effects):
    """The cached ``.csv.gz`` of record ``text`` (LENGTH@RATE), written when missing (to a
    temporary name first, so an interrupted build leaves no partial file) by a process of its own:
    a child forked from a parent that had simulated a day would start at the parent's resident
    size, and ``ru_maxrss`` would report that instead of the command's own peak."""
    duration_s, rate = parse_record(text)
    m = model(rate, effects)
    key = hashlib.sha256(json.dumps([m, duration_s, SEED], sort_keys=True).encode()).hexdigest()[:12]
    path = os.path.join(cache, f"{text.replace('@', '_at_')}_{'effects' if effects else 'clean'}_{key}.csv.gz")
    if not os.path.exists(path):
        os.makedirs(cache, exist_ok=True)
        print(f"writing {path} (once; reused by later runs)", file=sys.stderr, flush=True)
        code = ("import json, sys; from gyrofilter.recording import write_recording; "
                "from gyrofilter.sim.simulate import simulate; "
                "write_recording(sys.argv[1], simulate(json.loads(sys.argv[2]), float(sys.argv[3]), seed=int(sys.argv[4])))")
        fd, tmp = tempfile.mkstemp(suffix=".csv.gz", dir=cache)
        os.close(fd)
        try:
            env = dict(os.environ, PYTHONPATH=os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep))
            subprocess.run([sys.executable, "-c", code, tmp, json.dumps(m), repr(duration_s), str(SEED)], check=True, env=env)
            os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.remove(tmp)
    return path


def timed(argv):
    """Run ``argv`` in a fresh process: (exit code, stdout, wall-clock s, peak RSS MB of that process)."""
    t0 = time.perf_counter()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep))
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(argv, stdout=out, stderr=err, env=env, text=True)
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        wall_s = time.perf_counter() - t0
        out.seek(0)
        err.seek(0)
        return proc.returncode, out.read(), err.read(), wall_s, usage.ru_maxrss / 1024  # Linux: KiB


def run_commands(path):
    """``gyrofilter allan`` and ``gyrofilter gap`` on ``path``: a row dict."""
    py = [sys.executable, "-m", "gyrofilter"]
    with tempfile.TemporaryDirectory() as tmp:
        code, _, err, allan_s, allan_mb = timed([*py, "allan", path])
        allan_args = ""
        if code == 2 and "--keep-outliers" in err:
            allan_args = "--keep-outliers"
            code, _, err, allan_s, allan_mb = timed([*py, "allan", path, allan_args])
        if code != 0:
            raise RuntimeError(f"gyrofilter allan {path} exited {code}: {err.strip()[-300:]}")
        out_json = os.path.join(tmp, "gap.json")
        code, _, err, gap_s, gap_mb = timed([*py, "gap", path, "--json", out_json])
        if code != 0:
            raise RuntimeError(f"gyrofilter gap {path} exited {code}: {err.strip()[-300:]}")
        with open(out_json, encoding="utf-8") as f:
            rep = json.load(f)
    return {"samples": int(round(rep["duration_s"] * rep["sample_rate_hz"])), "sample_rate_hz": rep["sample_rate_hz"],
            "file_mb": os.path.getsize(path) / 1e6,
            "gap_s": gap_s, "gap_peak_mb": gap_mb, "allan_s": allan_s, "allan_peak_mb": allan_mb,
            "allan_args": allan_args, "ratio": gap_s / allan_s,
            "intervals_s": rep.get("intervals", {}).get("runtime_s", 0.0),
            "findings": ",".join(f"{f['axis']}:{f['effect']}" for f in rep["findings"]) or "-",
            "load": os.getloadavg()[0]}


def parse_record(text):
    length, _, rate = text.partition("@")
    unit = {"m": 60.0, "h": 3600.0, "s": 1.0}[length[-1]]
    return float(length[:-1]) * unit, float(rate or 100.0)


def table(rows):
    """The printed table of ``rows`` (dicts of :func:`run_commands` with ``record`` and ``kind``)."""
    lines = [f"{'record':>28s} {'samples/axis':>12s} {'file MB':>7s} | {'gap s':>6s} {'allan s':>7s} {'ratio':>6s} | "
             f"{'gap peak MB':>11s} {'allan peak MB':>13s} | {'of gap: intervals s':>19s} {'findings':<40s} {'load':>5s}"]
    for r in rows:
        star = "*" if r["allan_args"] else ""
        lines.append(f"{r['record'] + ' ' + r['kind']:>28s} {r['samples']:12d} {r['file_mb']:7.0f} | {r['gap_s']:6.1f} "
                     f"{r['allan_s']:6.1f}{star:1s} {r['ratio']:5.1f}x | {r['gap_peak_mb']:11.0f} {r['allan_peak_mb']:13.0f} | "
                     f"{r['intervals_s']:19.1f} {r['findings']:<40s} {r['load']:5.1f}")
    if any(r["allan_args"] for r in rows):
        lines.append("* allan refuses the record's spikes by default: timed with --keep-outliers")
    lines.append(TARGETS)
    return "\n".join(lines)


def report(doc):
    """What the tool prints for ``doc`` (``{"cores": ..., "rows": [...]}``, as ``--json`` writes it)."""
    return (f"gyrofilter allan FILE / gyrofilter gap FILE --json OUT.json, each in a fresh process (peak MB: "
            f"ru_maxrss, MiB); {doc['cores']} cores shared with other work (load: 1-minute average)\n" + table(doc["rows"]))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--records", nargs="*", default=["10m@100", "1h@100", "24h@100", "1h@1000"],
                   help="LENGTH@RATE, LENGTH with unit s, m or h, RATE in Hz")
    p.add_argument("--clean", action="store_true", help="also the records without effects")
    p.add_argument("--files", nargs="*", default=[], help="also time these recordings (e.g. the shipped recordings/*.csv.gz)")
    p.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "gyrofilter-bench-gap"),
                   help="where the simulated records are kept between runs")
    p.add_argument("--json", default=None, metavar="OUT.json", help="also write the rows as JSON")
    args = p.parse_args(argv)
    rows = []
    jobs = [(os.path.basename(f), "", f) for f in args.files]
    for text in args.records:
        for effects in (True, False) if args.clean else (True,):
            label = text.split("@")[0] + f" @ {parse_record(text)[1]:g} Hz"
            jobs.append((label, "with effects" if effects else "clean", (text, effects)))
    for label, kind, what in jobs:
        path = what if isinstance(what, str) else record_file(args.cache, *what)
        row = dict(run_commands(path), record=label, kind=kind)
        rows.append(row)
        print(table([row]).splitlines()[1], file=sys.stderr, flush=True)
    doc = {"cores": os.cpu_count(), "rows": rows}
    print(report(doc))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(doc, f, indent=1)
            f.write("\n")


if __name__ == "__main__":
    main()
