"""The fleet of docs/fleet.md: the real static MPU6050 recordings plus simulated units, one with a hidden defect.

    python tools/fleet_real.py [--units 8] [--seed 14] [--out out/fleet_real] [--jobs N]

Writes ``--units`` simulated 10-minute MPU6050-like units to OUT/sim (100 Hz, 131 LSB per deg/s,
white noise log-normal around the 449-s recording's with an 8 % unit-to-unit spread, biases
within +-5 deg/s), one of them, drawn from the seed, with a defect drawn from the seed too: a
bias instability B of 0.004-0.01 deg/s or a spectral line of 0.02-0.05 deg/s at 2-45 Hz, on a
drawn axis. Then runs, and prints with its output::

    gyrofilter gap recordings/mpu6050_static_*.csv.gz OUT/sim/*.csv.gz --fleet OUT/report

The defect is printed only after the run.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NOMINAL_ARW = {"x": 0.0075, "y": 0.011, "z": 0.0093}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--units", type=int, default=8)
    p.add_argument("--seed", type=int, default=14)
    p.add_argument("--out", default=os.path.join(REPO, "out", "fleet_real"))
    p.add_argument("--jobs", type=int, default=None)
    args = p.parse_args(argv)

    from gyrofilter.recording import write_recording
    from gyrofilter.sim.simulate import simulate

    rng = np.random.default_rng(args.seed)
    bad, axis = int(rng.integers(args.units)), "xyz"[rng.integers(3)]
    if rng.random() < 0.5:
        defect = {"effect": "bias_instability", "b_dps": float(rng.uniform(0.004, 0.01))}
    else:
        defect = {"effect": "sinusoid", "frequency_hz": float(rng.uniform(2, 45)), "amplitude_dps": float(rng.uniform(0.02, 0.05))}
    sim = os.path.join(args.out, "sim")
    os.makedirs(sim, exist_ok=True)
    for u in range(args.units):
        axes = {a: {"bias_dps": float(rng.uniform(-5, 5)),
                    "arw_dps_per_sqrt_hz": float(NOMINAL_ARW[a] * np.exp(0.08 * rng.standard_normal())), "effects": []}
                for a in "xyz"}
        if u == bad:
            axes[axis]["effects"].append(defect)
        model = {"sample_rate_hz": 100.0, "gyro_unit": "lsb", "lsb_per_dps": 131.0, "full_scale_dps": 250.0, "axes": axes}
        write_recording(os.path.join(sim, f"sim{u:02d}.csv.gz"), simulate(model, 600.0, seed=args.seed * 100 + u))
    os.chdir(REPO)
    inputs = ["recordings/mpu6050_static_*.csv.gz", os.path.relpath(os.path.join(sim, "*.csv.gz"))]
    cmd = ["gyrofilter", "gap", *inputs, "--fleet", os.path.relpath(os.path.join(args.out, "report")), "--force"]
    if args.jobs:
        cmd += ["--jobs", str(args.jobs)]
    print("$ " + " ".join(f"'{c}'" if "*" in c else c for c in cmd), flush=True)
    code = subprocess.run([sys.executable, "-m", "gyrofilter", *cmd[1:]], check=False).returncode
    params = ", ".join(f"{k} = {v:.4g}" for k, v in defect.items() if k != "effect")
    print(f"\nhidden defect: sim{bad:02d}, axis {axis}: {defect['effect']} ({params})")
    return code


if __name__ == "__main__":
    sys.exit(main())
