"""Time and peak memory of ``gyrofilter report`` beside ``allan`` + ``gap`` run apart, on shipped recordings.

    python tools/bench_report.py [--recordings recordings/mpu6050_static_100s.csv.gz ...] [--repeats 3]

Each command runs as a user runs it, in a fresh Python process (``python -m gyrofilter``: the
start-up and the imports counted), writing its output to a temporary folder: ``allan REC --json``,
``gap REC --json`` and ``report REC --out``, each ``--repeats`` times in turn; printed per recording
are the median wall-clock seconds of each, allan + gap (the baseline: what the report replaces),
the report's ratio to it (target: at most 1.5) and the peak resident memory (MB, ``wait4``'s
rusage) of each process, with the 1-minute load average of this shared machine at the end.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT = ["recordings/mpu6050_static_100s.csv.gz", "recordings/mpu6050_static_655s.csv.gz"]
TARGET_RATIO = 1.5


def timed(args):
    """(wall seconds, peak RSS MB) of ``python -m gyrofilter ARGS`` in a fresh process."""
    env = {**os.environ, "PYTHONPATH": ROOT + os.pathsep + os.environ.get("PYTHONPATH", "")}
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "gyrofilter", *args], cwd=ROOT, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    err = proc.stderr.read().decode(errors="replace")
    proc.stderr.close()
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode:
        raise SystemExit(f"gyrofilter {' '.join(args)} failed ({proc.returncode}): {err.strip()}")
    return wall, usage.ru_maxrss / 1024


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recordings", nargs="+", default=DEFAULT, help="recordings (relative to the repository)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print(f"{'recording':<34} {'allan s':>8} {'gap s':>8} {'allan+gap':>10} {'report s':>9} {'ratio':>6} "
          f"{'allan MB':>9} {'gap MB':>7} {'report MB':>10}")
    with tempfile.TemporaryDirectory() as tmp:
        for rec in args.recordings:
            runs = {"allan": [], "gap": [], "report": []}
            for _ in range(args.repeats):  # in turn, so that a busy moment of the machine hits all three
                runs["allan"].append(timed(["allan", rec, "--json", f"{tmp}/a.json", "--force"]))
                runs["gap"].append(timed(["gap", rec, "--json", f"{tmp}/g.json", "--force"]))
                runs["report"].append(timed(["report", rec, "--out", f"{tmp}/r.html", "--force"]))
            wall = {k: statistics.median(w for w, _ in v) for k, v in runs.items()}
            peak = {k: max(m for _, m in v) for k, v in runs.items()}
            base = wall["allan"] + wall["gap"]
            print(f"{os.path.basename(rec):<34} {wall['allan']:8.2f} {wall['gap']:8.2f} {base:10.2f} "
                  f"{wall['report']:9.2f} {wall['report'] / base:6.2f} {peak['allan']:9.0f} {peak['gap']:7.0f} "
                  f"{peak['report']:10.0f}")
    print(f"(median of {args.repeats} runs each, fresh processes; ratio = report / (allan + gap), target <= "
          f"{TARGET_RATIO:g}; peak resident memory per process; load average {os.getloadavg()[0]:.2f})")


if __name__ == "__main__":
    main()
