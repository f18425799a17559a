"""Speed of the gap analysis on hours of 100 Hz data.

    python tools/bench_gap.py [--hours 1 2] [--rate 100]

Simulates an MPU6050-like recording (131 LSB per deg/s, a warm-up on x, a sinusoid on z) of the
given lengths and times ``gyrofilter.gap.analyse_gap`` with the command's defaults, side by
side with a baseline: one overlapping Allan deviation of the three axes
(``gyrofilter.allan.overlapping_adev``, default taus), the least any Allan-based analysis does.
Wall-clock times on a shared machine; the load average is printed with them.
"""
from __future__ import annotations

import argparse
import os
import time


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--hours", type=float, nargs="*", default=[1.0, 2.0])
    p.add_argument("--rate", type=float, default=100.0)
    args = p.parse_args(argv)

    from gyrofilter.allan import overlapping_adev
    from gyrofilter.gap import analyse_gap
    from gyrofilter.simulate import simulate

    model = {"sample_rate_hz": args.rate, "gyro_unit": "lsb", "lsb_per_dps": 131.0,
             "axes": {"x": {"bias_dps": -3.3, "arw_dps_per_sqrt_hz": 0.009,
                            "effects": [{"effect": "warmup", "amplitude_dps": 0.2, "tau_s": 300.0}]},
                      "y": {"bias_dps": 1.1, "arw_dps_per_sqrt_hz": 0.012, "effects": []},
                      "z": {"bias_dps": 0.4, "arw_dps_per_sqrt_hz": 0.008,
                            "effects": [{"effect": "sinusoid", "frequency_hz": 7.3, "amplitude_dps": 0.02}]}}}
    print(f"{'record':>14s} {'samples/axis':>13s} {'gap (s)':>9s} {'baseline ADEV x3 (s)':>21s} "
          f"{'findings':>30s}  load")
    for hours in args.hours:
        rec = simulate(model, hours * 3600.0, seed=1)
        g = rec.gyro_dps
        t0 = time.perf_counter()
        for i in range(3):
            overlapping_adev(g[:, i], args.rate)
        t_adev = time.perf_counter() - t0
        t0 = time.perf_counter()
        rep = analyse_gap(rec, seed=0)
        t_gap = time.perf_counter() - t0
        found = ",".join(f"{f['axis']}:{f['effect']}" for f in rep["findings"])
        load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
        print(f"{hours:10.1f} h {len(rec):13d} {t_gap:9.1f} {t_adev:21.2f} {found:>30s}  {load:.1f}")


if __name__ == "__main__":
    main()
