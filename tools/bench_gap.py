"""Time and peak memory of the gap analysis against the record length, with effects and clean.

    python tools/bench_gap.py [--records 10m@100 1h@100 3h@100 24h@100 1h@1000] [--sims N] [--bootstrap N]
                              [--files recordings/*.csv.gz]

For each record (length@rate in Hz) simulates an MPU6050-like recording (131 LSB per deg/s)
twice: **with effects** (x: warm-up and colored noise; y: bias instability and spikes; z: a
sinusoid) and **clean** (bias, white noise and quantization only), and runs
``gyrofilter.analysis.gap.analyse_gap`` with the command's defaults on each, every run in a fresh Python
process, side by side with a baseline in the same process: one overlapping Allan deviation of the
three axes (``gyrofilter.analysis.allan.overlapping_adev``, default taus), the least any Allan-based
analysis does. Printed per run: wall-clock seconds (and the part the parameters' intervals
took, ``intervals.runtime_s`` of the report), the process's peak resident memory (MB;
``resource.getrusage``, the simulated record in memory included, as when ``gyrofilter gap``
has read a file) and the memory of the record alone, the findings, and the 1-minute load
average of this shared machine at the end of the run. ``--files`` times recordings the same way
first (``--records`` with no value: only them).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

EFFECTS = {"x": [{"effect": "warmup", "amplitude_dps": 0.2, "tau_s": 300.0},
                 {"effect": "colored_noise", "lag1": 0.2}],
           "y": [{"effect": "bias_instability", "b_dps": 0.004},
                 {"effect": "outliers", "rate": 2e-5, "magnitude_dps": 1.5}],
           "z": [{"effect": "sinusoid", "frequency_hz": 7.3, "amplitude_dps": 0.02}]}


def model(rate_hz, effects):
    axes = {"x": {"bias_dps": -3.3, "arw_dps_per_sqrt_hz": 0.009},
            "y": {"bias_dps": 1.1, "arw_dps_per_sqrt_hz": 0.012},
            "z": {"bias_dps": 0.4, "arw_dps_per_sqrt_hz": 0.008}}
    for a, spec in axes.items():
        spec["effects"] = list(EFFECTS[a]) if effects else []
    return {"sample_rate_hz": rate_hz, "gyro_unit": "lsb", "lsb_per_dps": 131.0, "axes": axes}


def child(spec):
    """One run in this (fresh) process; prints one JSON line."""
    import resource
    import time

    from gyrofilter.analysis.allan import overlapping_adev
    from gyrofilter.analysis.gap import analyse_gap
    from gyrofilter.sim.simulate import simulate

    if spec.get("file"):
        from gyrofilter.recording import read_recording

        rec = read_recording(spec["file"])
    else:
        rec = simulate(spec["model"], spec["duration_s"], seed=1)
    record_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    g = rec.gyro_dps
    t0 = time.perf_counter()
    for i in range(3):
        overlapping_adev(g[:, i], rec.sample_rate_hz)
    t_adev = time.perf_counter() - t0
    del g
    t0 = time.perf_counter()
    rep = analyse_gap(rec, seed=0, n_sims=spec["sims"],
                      **({} if spec["bootstrap"] is None else {"bootstrap": spec["bootstrap"]}))
    t_gap = time.perf_counter() - t0
    print(json.dumps({"gap_s": t_gap, "adev_s": t_adev, "intervals_s": rep.get("intervals", {}).get("runtime_s", 0.0),
                      "record_mb": record_mb,
                      "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                      "findings": ",".join(f"{f['axis']}:{f['effect']}" for f in rep["findings"]) or "-",
                      "load": os.getloadavg()[0], "samples": len(rec)}))


def _run_child(spec):
    proc = subprocess.run([sys.executable, os.path.abspath(__file__), "--child", json.dumps(spec)],
                          capture_output=True, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def files_table(args):
    """The gap's time on recordings (``--files``), the intervals' part of it, and the findings."""
    print(f"{'recording':>32s} {'samples/axis':>12s} | {'gap s':>6s} {'of it intervals s':>17s} {'peak MB':>8s} "
          f"{'findings':<60s} | {'load':>5s}", flush=True)
    for path in args.files:
        r = _run_child({"file": path, "sims": args.sims, "bootstrap": args.bootstrap})
        print(f"{os.path.basename(path):>32s} {r['samples']:12d} | {r['gap_s']:6.1f} {r['intervals_s']:17.1f} "
              f"{r['peak_mb']:8.0f} {r['findings']:<60s} | {r['load']:5.1f}", flush=True)


def parse_record(text):
    length, _, rate = text.partition("@")
    unit = {"m": 60.0, "h": 3600.0, "s": 1.0}[length[-1]]
    return float(length[:-1]) * unit, float(rate or 100.0)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--records", nargs="*", default=["10m@100", "1h@100", "3h@100", "24h@100", "1h@1000"],
                   help="LENGTH@RATE, LENGTH with unit s, m or h, RATE in Hz")
    p.add_argument("--sims", type=int, default=None, help="baseline simulations (default: the command's)")
    p.add_argument("--bootstrap", type=int, default=None, help="bootstrap runs for the intervals (default: the command's)")
    p.add_argument("--files", nargs="*", default=[], help="also time these recordings (e.g. the shipped recordings/*.csv.gz)")
    p.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.child:
        child(json.loads(args.child))
        return
    if args.files:
        files_table(args)
        if not args.records:
            return

    print(f"{'record':>14s} {'samples/axis':>12s} | {'with effects: gap s':>19s} {'of it intervals s':>17s} {'peak MB':>8s} {'record MB':>9s} "
          f"{'findings':<60s} | {'clean: gap s':>12s} {'peak MB':>8s} {'findings':<10s} | {'ADEV x3 s':>9s} {'load':>5s}",
          flush=True)
    for text in args.records:
        duration_s, rate = parse_record(text)
        out = {}
        for kind in ("effects", "clean"):
            spec = {"model": model(rate, kind == "effects"), "duration_s": duration_s, "sims": args.sims,
                    "bootstrap": args.bootstrap}
            out[kind] = _run_child(spec)
        e, c = out["effects"], out["clean"]
        label = f"{text.split('@')[0]} @ {rate:g} Hz"
        print(f"{label:>14s} {e['samples']:12d} | {e['gap_s']:19.1f} {e['intervals_s']:17.1f} {e['peak_mb']:8.0f} {e['record_mb']:9.0f} "
              f"{e['findings']:<60s} | {c['gap_s']:12.1f} {c['peak_mb']:8.0f} {c['findings']:<10s} | "
              f"{e['adev_s']:9.2f} {max(e['load'], c['load']):5.1f}", flush=True)


if __name__ == "__main__":
    main()
