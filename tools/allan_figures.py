#!/usr/bin/env python3
"""Allan analysis of every MPU6050 recording in recordings/: the README table and figures.

    python tools/allan_figures.py [--out docs/figures] [--recordings recordings]

For every ``recordings/mpu6050_*.csv.gz``:

* static recordings (header ``description`` starts with "static"): the five-term fit and the
  paper 000/002 read-offs per axis, printed as Markdown tables (ARW, bias instability, RRW with
  95 % intervals and units, beside papers 000/002 and the datasheet), and the figure
  ``docs/figures/allan_<name>.png``;
* motion recordings: listed, not characterised (their Allan deviation measures the motion).

Then the before/after-filtering figure of paper 001 Fig. 4 on the longest static recording:
the Allan deviation of the raw rate and of ``gyrofilter.GyroFilter`` output (20 Hz) on one
plot, ``docs/figures/allan_before_after.png`` (preset "paper"), and the same for every other
preset (``allan_before_after_<preset>.png``).
"""
import argparse
import glob
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

from gyrofilter.analysis.allan import overlapping_adev  # noqa: E402
from gyrofilter.filter.calibration import calibration_samples  # noqa: E402
from gyrofilter.analysis.noise_fit import characterise  # noqa: E402
from gyrofilter.analysis.noise_model import convert  # noqa: E402
from gyrofilter.analysis.plots_allan import AXIS_COLOURS, plot_allan, plot_before_after  # noqa: E402
from gyrofilter.recording import read_recording  # noqa: E402

DATASHEET_ARW_DPS_PER_SQRT_HZ = 0.005  # MPU-6000/6050 Product Specification rev 3.4, table 6.1
PAPER002 = {"arw": (7.972e-2, 10.29e-2, 9.143e-2), "b": (1.35e-2, 2.1e-2, 9.409e-3)}


def _interval(c, unit, digits=3):
    if c.value is None:
        up = convert(c.upper, c.term, unit)
        return "not resolved" + (f" (< {up:.2g})" if up is not None else "")
    v, lo, hi = (convert(x, c.term, unit) for x in (c.value, c.low, c.high))
    return f"{v:.{digits}g} [{lo:.{digits}g}, {hi:.{digits}g}]"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recordings", default=os.path.join(ROOT, "recordings"))
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "figures"))
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    files = sorted(glob.glob(os.path.join(args.recordings, "mpu6050_*.csv.gz")))
    if not files:
        print(f"no recordings/mpu6050_*.csv.gz under {args.recordings}", file=sys.stderr)
        return 1
    static, motion = [], []
    for path in files:
        rec = read_recording(path)
        (static if rec.header.get("description", "").startswith("static") else motion).append((path, rec))

    rows_arw, rows_slow, rows_ro, results_by_file = [], [], [], {}
    for path, rec in static:
        name = os.path.basename(path).replace(".csv.gz", "")
        res = characterise(rec.gyro_dps, rec.sample_rate_hz)
        results_by_file[name] = (rec, res)
        fig = os.path.join(args.out, f"allan_{name}.png")
        plot_allan(fig, res, title=f"{name}: {rec.duration_s:.0f} s at {rec.sample_rate_hz:g} Hz, MPU6050 +-250 deg/s")
        tmax = res["x"].tau_s[res["x"].fit_used][-1]
        for a, r in res.items():
            f = r.fitted
            rows_arw.append(f"| {name} | {a} | {rec.duration_s:.0f} s / {tmax:.0f} s | {_interval(f['arw'], 'deg/sqrt(s)')} | "
                            f"{_interval(f['arw'], 'deg/sqrt(h)')} | {_interval(f['quantization'], 'deg')} | "
                            f"{r.fit_consistency():.0%} |")
            rows_slow.append(f"| {name} | {a} | {_interval(f['bias_instability'], 'deg/s')} | "
                             f"{_interval(f['rrw'], 'deg/s/sqrt(s)')} | {_interval(f['rate_ramp'], 'deg/s^2')} |")
            ro = r.readoff
            b_ro = ro["bias_instability"]
            at_tau = "" if b_ro.value is None else f" at {b_ro.tau_s:.0f} s"
            rows_ro.append(f"| {name} | {a} | {_interval(ro['arw'], 'deg/sqrt(s)')} | "
                           f"{_interval(b_ro, 'deg/s')}{at_tau} |")
        print(f"wrote {fig}", file=sys.stderr)

    print("#### Angle random walk N (fit, 95 % interval)\n")
    print("| recording | axis | length / longest fitted tau | N (deg/sqrt(s) = deg/s/sqrt(Hz)) | N (deg/sqrt(h)) | Q (deg) | model inside the tau-wise 95 % intervals |")
    print("|---|---|---|---|---|---|---|")
    print("\n".join(rows_arw))
    print("\n#### Bias instability B, rate random walk K, rate ramp R (fit, 95 % interval; upper bound when not resolved)\n")
    print("| recording | axis | B (deg/s) | K (deg/s/sqrt(s)) | R (deg/s^2) |")
    print("|---|---|---|---|---|")
    print("\n".join(rows_slow))
    print("\n#### Paper 000/002 slope read-offs on the same curves (N at tau = 1 s on the -1/2 line; B = flat minimum / 0.664)\n")
    print("| recording | axis | N read-off (deg/sqrt(s)) | B read-off (deg/s) |")
    print("|---|---|---|---|")
    print("\n".join(rows_ro))
    print("\nMotion recordings, not characterised (the Allan deviation would measure the motion): "
          + ", ".join(os.path.basename(p) for p, _ in motion))

    # paper 001 Fig. 4: raw vs filtered on the longest static recording, for every preset
    from gyrofilter.filter.presets import PRESETS

    name, (rec, _) = max(results_by_file.items(), key=lambda kv: kv[1][0].duration_s)
    print(f"\n#### Before/after filtering: {name}; std after the calibration window\n")
    print("| preset | axis | raw std (deg/s) | filtered std (deg/s) | ratio | raw ADEV at 1 s | filtered ADEV at 1 s | raw ADEV at 10 s | filtered ADEV at 10 s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for preset in PRESETS:
        fig = os.path.join(args.out, "allan_before_after.png" if preset == "paper" else f"allan_before_after_{preset}.png")
        before_after(rec, name, preset, fig)
        print(f"wrote {fig}", file=sys.stderr)
    return 0


def before_after(rec, name, preset, fig):
    """Raw and GyroFilter(preset) Allan deviation on one plot; prints the table rows."""
    from gyrofilter import GyroFilter

    filt = GyroFilter(sample_rate_hz=rec.sample_rate_hz, preset=preset)
    out = filt.filter(rec.gyro_dps)
    out_rate = rec.sample_rate_hz / filt.settings.block_len
    cal = calibration_samples(rec.sample_rate_hz, filt.settings.calibration_s)
    curves = []
    for i, a in enumerate("xyz"):
        raw = rec.gyro_dps[:, i]
        t_r, d_r = overlapping_adev(raw, rec.sample_rate_hz)
        t_f, d_f = overlapping_adev(out[:, i], out_rate)
        curves.append((f"{a} raw ({rec.sample_rate_hz:g} Hz)", t_r, d_r, AXIS_COLOURS[a], "o-"))
        curves.append((f"{a} filtered ({out_rate:g} Hz)", t_f, d_f, AXIS_COLOURS[a], "--"))
        s_raw, s_f = np.std(raw[cal:], ddof=1), np.std(out[:, i], ddof=1)
        print(f"| {preset} | {a} | {s_raw:.4f} | {s_f:.4f} | {s_raw / s_f:.1f}x | {_at(t_r, d_r, 1.0):.2e} | "
              f"{_at(t_f, d_f, 1.0):.2e} | {_at(t_r, d_r, 10.0):.2e} | {_at(t_f, d_f, 10.0):.2e} |")
    plot_before_after(fig, curves, title=f"{name}: Allan deviation before and after GyroFilter(preset='{preset}')"
                      + (" (paper 001 Fig. 4)" if preset == "paper" else ""))


def _at(tau, dev, t):
    """Log-log interpolation of a deviation curve at t."""
    return float(np.exp(np.interp(np.log(t), np.log(tau), np.log(dev))))

if __name__ == "__main__":
    sys.exit(main())
