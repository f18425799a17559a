"""Speed of a fleet run: the same recordings with --jobs 1, --jobs = all cores and a Dask LocalCluster.

    python tools/bench_fleet.py [--files 32] [--hours 1] [--command gap] [--data DIR]

Simulates ``--files`` MPU6050-like units of ``--hours`` at 100 Hz (131 LSB per deg/s, white noise
log-normal around the 449-s recording's, 8 % unit-to-unit; seeded, so ``--data DIR`` can keep and
reuse them), then times ``gyrofilter COMMAND FILES --fleet OUT`` end to end in a fresh process
(reading, analysis, reports, fleet table): with ``--jobs 1``, with ``--jobs`` = the cores, and with
``--scheduler`` on a ``dask.distributed.LocalCluster`` of one single-threaded worker per core
(started before the clock, its start-up printed apart; needs the ``[cluster]`` extra). Prints
files per minute and the speed-up over ``--jobs 1`` side by side, the CPU time and the peak
resident memory of the largest process of the local runs, and the load average; checks that the
fleet tables agree apart from the wall times. Wall-clock times on a shared machine: read them with
the load (``--repeat N`` keeps the fastest of N runs per backend; the CPU time, unlike the wall
time, hardly depends on other work).
"""
from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

NOMINAL_ARW = {"x": 0.0075, "y": 0.011, "z": 0.0093}


def unit_model(rng):
    axes = {a: {"bias_dps": float(rng.uniform(-5, 5)),
                "arw_dps_per_sqrt_hz": float(NOMINAL_ARW[a] * np.exp(0.08 * rng.standard_normal())), "effects": []}
            for a in "xyz"}
    return {"sample_rate_hz": 100.0, "gyro_unit": "lsb", "lsb_per_dps": 131.0, "axes": axes}


def make_fleet(folder, files, hours):
    """The recordings (written unless there already)."""
    from gyrofilter.recording import write_recording
    from gyrofilter.sim.simulate import simulate

    rng = np.random.default_rng(14)
    paths = []
    for i in range(files):
        model = unit_model(rng)
        path = os.path.join(folder, f"unit{i:03d}_{hours:g}h.csv.gz")
        if not os.path.exists(path):
            write_recording(path, simulate(model, hours * 3600.0, seed=1400 + i))
        paths.append(path)
    return paths


def timed(cmd, log_path):
    """Run ``cmd`` (output to ``log_path``); (wall s, CPU s, peak resident MB of its largest
    process): from wait4, which covers the worker processes the command waited for (Linux kB)."""
    with open(log_path, "w") as log:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        with open(log_path) as log:
            sys.exit(f"{' '.join(cmd[:5])} ... failed (exit {proc.returncode}):\n{log.read()}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0


def table(path):
    with open(path, encoding="utf-8", newline="") as fh:
        return [{k: v for k, v in row.items() if k != "runtime_s"} for row in csv.DictReader(fh)]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--files", type=int, default=32)
    p.add_argument("--hours", type=float, default=1.0)
    p.add_argument("--command", choices=("gap", "allan"), default="gap")
    p.add_argument("--data", metavar="DIR", help="keep the simulated recordings here (reused when present)")
    p.add_argument("--repeat", type=int, default=1, help="runs per backend; the fastest counts (default 1)")
    p.add_argument("--no-dask", action="store_true", help="skip the LocalCluster run")
    args = p.parse_args(argv)
    if not args.no_dask:  # before the minute of simulated recordings, not after it
        try:
            from dask.distributed import LocalCluster
        except ImportError:
            sys.exit('the LocalCluster run needs Dask: pip install -e ".[cluster]", or give --no-dask')

    from gyrofilter.analysis.fleet.runner import default_jobs

    cores = default_jobs()
    with tempfile.TemporaryDirectory() as tmp:
        data = args.data or os.path.join(tmp, "data")
        os.makedirs(data, exist_ok=True)
        t0 = time.perf_counter()
        paths = make_fleet(data, args.files, args.hours)
        print(f"{args.files} simulated recordings of {args.hours:g} h at 100 Hz ({int(args.hours * 360000)} samples "
              f"per axis) in {data}: ready in {time.perf_counter() - t0:.0f} s; {cores} cores; "
              f"gyrofilter {args.command} with the defaults")
        base = [sys.executable, "-m", "gyrofilter", args.command, *paths]
        runs = [("--jobs 1", ["--jobs", "1"]), (f"--jobs {cores}", ["--jobs", str(cores)])]
        cluster = None
        if not args.no_dask:
            t0 = time.perf_counter()
            cluster = LocalCluster(n_workers=cores, threads_per_worker=1, processes=True, dashboard_address=None)
            print(f"LocalCluster of {cores} single-threaded workers started in {time.perf_counter() - t0:.1f} s (not timed below)")
            runs.append((f"LocalCluster, {cores} workers", ["--scheduler", cluster.scheduler_address]))
        print(f"\n{'backend':<26} {'wall s':>8} {'files/min':>10} {'speed-up':>9} {'CPU s':>7} {'peak MB':>8} "
              f"{'load (1 min)':>13}")
        tables, first = [], None
        try:
            for name, extra in runs:
                best = None
                for repeat in range(args.repeat):  # the best of the repeats: the least disturbed by other work
                    out = os.path.join(tmp, f"out{len(tables)}_{repeat}")
                    wall, cpu_s, peak_mb = timed(base + extra + ["--fleet", out], out + ".log")
                    best = min(best or (wall, cpu_s, peak_mb, out), (wall, cpu_s, peak_mb, out))
                wall, cpu_s, peak_mb, out = best
                first = first or wall
                local = "--scheduler" not in extra  # the Dask workers are not children of the command
                cpu = f"{cpu_s:7.0f}" if local else f"{'n/a':>7}"
                peak = f"{peak_mb:8.0f}" if local else f"{'n/a':>8}"
                print(f"{name:<26} {wall:8.1f} {60.0 * len(paths) / wall:10.2f} {first / wall:8.2f}x {cpu} {peak} "
                      f"{os.getloadavg()[0]:13.1f}", flush=True)
                tables.append(table(os.path.join(out, "fleet.csv")))
        finally:
            if cluster is not None:
                cluster.close()
        same = all(t == tables[0] for t in tables[1:])
        print(f"\nfleet tables of all backends equal (apart from runtime_s): {same}")
        per_file = first / len(paths)
        print(f"--jobs 1: {per_file:.2f} s per recording of {args.hours:g} h ({per_file / args.hours:.2f} s per hour of data)")


if __name__ == "__main__":
    main()
