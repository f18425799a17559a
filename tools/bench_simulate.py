"""Benchmark of the simulator: seconds and peak memory for a long run, next to a plain baseline.

    python tools/bench_simulate.py [--duration 3600] [--rate 1000] [--skip-file]

Cases (each in its own Python process, so peak memory is that process's max RSS):

* ``numpy one-shot``: the plain baseline, white noise + bias + quantization for all samples in
  one ``rng.standard_normal((N, 3))`` call (what a one-line simulator does).
* ``simulate_chunks, baseline model``: the same model through the streaming simulator.
* ``simulate_chunks, all effects``: every effect of the table on all three axes (flicker bank,
  RRW, ramp, Gauss-Markov, sinusoid, temperature, step, warm-up, outliers, coloured noise),
  generated in blocks and discarded (generation cost only).
* ``gyrofilter simulate -> .csv.gz``: the command, all effects, streamed to a gzip recording.

Peak memory: ``VmHWM`` of the process (includes the interpreter, numpy and scipy).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile

ALL_EFFECTS = [
    {"effect": "bias_instability", "b_dps": 0.005},
    {"effect": "rate_random_walk", "k_dps_per_sqrt_s": 0.0005},
    {"effect": "rate_ramp", "r_dps_per_s": 1e-5},
    {"effect": "gauss_markov", "sigma_dps": 0.01, "tau_s": 30.0},
    {"effect": "sinusoid", "frequency_hz": 7.3, "amplitude_dps": 0.03},
    {"effect": "temperature", "coefficient_dps_per_c": 0.02},
    {"effect": "bias_step", "time_s": 600.0, "size_dps": 0.05},
    {"effect": "warmup", "amplitude_dps": 0.2, "tau_s": 120.0},
    {"effect": "outliers", "rate": 0.0005, "magnitude_dps": 2.0},
    {"effect": "colored_noise", "lag1": 0.3},
]


def bench_model(rate_hz, effects=True):
    axis = {"bias_dps": -3.3, "arw_dps_per_sqrt_hz": 0.009, "effects": ALL_EFFECTS if effects else []}
    model = {"sample_rate_hz": rate_hz, "gyro_unit": "lsb", "lsb_per_dps": 131.0, "full_scale_dps": 250.0,
             "axes": {a: axis for a in "xyz"}}
    if effects:
        model["temperature"] = {"start_c": 25.0, "end_c": 30.0, "tau_s": 900.0, "noise_c": 0.02, "resolution_c": 1 / 340}
    return model


_PRELUDE = """
import json, resource, sys, time
import numpy as np
args = json.loads(sys.argv[1])
"""
# VmHWM is this process image's own peak; ru_maxrss would carry the parent's peak across fork + exec
_REPORT = """
try:
    peak_kb = next(int(ln.split()[1]) for ln in open("/proc/self/status") if ln.startswith("VmHWM:"))
except OSError:
    peak_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"seconds": seconds, "peak_mb": peak_kb / 1024.0, "samples": n}))
"""
CASES = {
    "numpy one-shot, baseline (bias + white noise + LSB)": """
t0 = time.perf_counter()
fs = args["rate"]; n = int(round(args["duration"] * fs))
rng = np.random.default_rng(1)
g = np.round((np.array([-3.3, -3.3, -3.3]) + 0.009 * np.sqrt(fs) * rng.standard_normal((n, 3))) * 131.0)
seconds = time.perf_counter() - t0
""",
    "simulate_chunks, baseline model": """
from gyrofilter.sim.simulate import simulate_chunks
t0 = time.perf_counter(); n = 0
for block in simulate_chunks(args["model_base"], args["duration"], seed=1):
    n += len(block.t_s)
seconds = time.perf_counter() - t0
""",
    "simulate_chunks, all effects": """
from gyrofilter.sim.simulate import simulate_chunks
t0 = time.perf_counter(); n = 0
for block in simulate_chunks(args["model_all"], args["duration"], seed=1):
    n += len(block.t_s)
seconds = time.perf_counter() - t0
""",
    "gyrofilter simulate -> .csv.gz, all effects": """
import contextlib, io
from gyrofilter.cli import main
t0 = time.perf_counter()
with contextlib.redirect_stdout(io.StringIO()):
    rc = main(["simulate", "--model", args["model_path"], "--duration", str(args["duration"]), "--seed", "1", "--out", args["out"]])
assert rc == 0
seconds = time.perf_counter() - t0
import os
n = int(round(args["duration"] * args["rate"]))
print(json.dumps({"file_mb": os.path.getsize(args["out"]) / 1e6}), file=sys.stderr)
""",
}


def run_case(code, payload):
    res = subprocess.run([sys.executable, "-c", _PRELUDE + code + _REPORT, json.dumps(payload)],
                         capture_output=True, text=True)
    if res.returncode != 0:
        raise RuntimeError(res.stderr.strip().splitlines()[-1] if res.stderr.strip() else "case failed")
    out = json.loads(res.stdout.strip().splitlines()[-1])
    if res.stderr.strip().startswith("{"):
        out.update(json.loads(res.stderr.strip().splitlines()[-1]))
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=3600.0, help="seconds simulated (default 3600)")
    parser.add_argument("--rate", type=float, default=1000.0, help="sample rate in Hz (default 1000)")
    parser.add_argument("--skip-file", action="store_true", help="skip the case that writes the .csv.gz")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        model_path = os.path.join(tmp, "all.json")
        with open(model_path, "w") as fh:
            json.dump(bench_model(args.rate), fh)
        payload = {"duration": args.duration, "rate": args.rate, "model_base": bench_model(args.rate, effects=False),
                   "model_all": bench_model(args.rate), "model_path": model_path, "out": os.path.join(tmp, "sim.csv.gz")}
        n = int(round(args.duration * args.rate))
        print(f"simulate {args.duration:g} s at {args.rate:g} Hz, 3 axes ({n} samples per axis)")
        print(f"{'case':<52} {'seconds':>9} {'peak MB':>9} {'Msamples/s':>11}")
        for name, code in CASES.items():
            if args.skip_file and "csv.gz" in name:
                continue
            r = run_case(code, payload)
            extra = f"   file {r['file_mb']:.0f} MB" if "file_mb" in r else ""
            print(f"{name:<52} {r['seconds']:9.2f} {r['peak_mb']:9.0f} {n / r['seconds'] / 1e6:11.2f}{extra}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
