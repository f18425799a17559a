#!/usr/bin/env python3
"""Allan analysis of every MPU6050 recording in recordings/: the tables of docs/allan.md and its figures.

    python tools/allan_figures.py [--out docs/figures] [--recordings recordings]

For every ``recordings/mpu6050_*.csv.gz``:

* static recordings (header ``description`` starts with "static"): the five-term fit and the
  paper 000/002 read-offs per axis, printed as Markdown tables (ARW, bias instability, RRW with
  95 % intervals and units; :func:`tables`), and the figure ``docs/figures/allan_<name>.png``;
* motion recordings: listed, not characterised (their Allan deviation measures the motion).

Then the before/after-filtering figure of paper 001 Fig. 4 on the longest static recording:
the Allan deviation of the raw rate and of ``gyrofilter.GyroFilter`` output (20 Hz) on one
plot, ``docs/figures/allan_before_after.png`` (preset "paper"), and the same for every other
preset (``allan_before_after_<preset>.png``); its table is :func:`before_after_table`.
``tools/docs.py`` writes both tables into docs/allan.md.
"""
import argparse
import glob
import os
import sys

import numpy as np

from gyrofilter.effects import RATE_RANDOM_WALK
from gyrofilter.analysis.noise.allan import overlapping_adev
from gyrofilter.analysis.noise.fit import characterise
from gyrofilter.analysis.noise.model import ANGLE_RANDOM_WALK, convert
from gyrofilter.analysis.noise.plots import AXIS_COLOURS, plot_allan, plot_before_after
from gyrofilter.filter.calibration import calibration_samples
from gyrofilter.filter.presets import PRESETS
from gyrofilter.recording import read_recording

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def _interval(c, unit, digits=3):
    if c.value is None:
        up = convert(c.upper, c.term, unit)
        return "not resolved" + (f" (< {up:.2g})" if up is not None else "")
    v, lo, hi = (convert(x, c.term, unit) for x in (c.value, c.low, c.high))
    return f"{v:.{digits}g} [{lo:.{digits}g}, {hi:.{digits}g}]"


def recordings(folder):
    """(static, motion): lists of (name, Recording) of the ``mpu6050_*.csv.gz`` in ``folder``."""
    static, motion = [], []
    for path in sorted(glob.glob(os.path.join(folder, "mpu6050_*.csv.gz"))):
        rec = read_recording(path)
        name = os.path.basename(path).replace(".csv.gz", "")
        (static if rec.header.get("description", "").startswith("static") else motion).append((name, rec))
    return static, motion


def characterised(static):
    """{name: (Recording, characterise() result)} of the static recordings."""
    return {name: (rec, characterise(rec.gyro_dps, rec.sample_rate_hz)) for name, rec in static}


def tables(results, motion_names):
    """The Markdown tables of ``results`` (from :func:`characterised`): ARW and Q; B, K, R; read-offs."""
    rows_arw, rows_slow, rows_ro = [], [], []
    for name, (rec, res) in results.items():
        tmax = res["x"].tau_s[res["x"].fit_used][-1]
        for a, r in res.items():
            f = r.fitted
            rows_arw.append(f"| {name} | {a} | {rec.duration_s:.0f} s / {tmax:.0f} s | {_interval(f[ANGLE_RANDOM_WALK], 'deg/sqrt(s)')} | "
                            f"{_interval(f[ANGLE_RANDOM_WALK], 'deg/sqrt(h)')} | {_interval(f['quantization'], 'deg')} | "
                            f"{r.fit_consistency():.0%} |")
            rows_slow.append(f"| {name} | {a} | {_interval(f['bias_instability'], 'deg/s')} | "
                             f"{_interval(f[RATE_RANDOM_WALK], 'deg/s/sqrt(s)')} | {_interval(f['rate_ramp'], 'deg/s^2')} |")
            b_ro = r.readoff["bias_instability"]
            at_tau = "" if b_ro.value is None else f" at {b_ro.tau_s:.0f} s"
            rows_ro.append(f"| {name} | {a} | {_interval(r.readoff[ANGLE_RANDOM_WALK], 'deg/sqrt(s)')} | "
                           f"{_interval(b_ro, 'deg/s')}{at_tau} |")
    return "\n".join([
        "#### Angle random walk N (fit, 95 % interval)", "",
        "| recording | axis | length / longest fitted tau | N (deg/sqrt(s) = deg/s/sqrt(Hz)) | N (deg/sqrt(h)) | Q (deg) "
        "| model inside the tau-wise 95 % intervals |",
        "|---|---|---|---|---|---|---|", *rows_arw, "",
        "#### Bias instability B, rate random walk K, rate ramp R (fit, 95 % interval; upper bound when not resolved)", "",
        "| recording | axis | B (deg/s) | K (deg/s/sqrt(s)) | R (deg/s^2) |", "|---|---|---|---|---|", *rows_slow, "",
        "#### Paper 000/002 slope read-offs on the same curves (N at tau = 1 s on the -1/2 line; B = flat minimum / 0.664)", "",
        "| recording | axis | N read-off (deg/sqrt(s)) | B read-off (deg/s) |", "|---|---|---|---|", *rows_ro, "",
        "Motion recordings, not characterised (the Allan deviation would measure the motion): " + ", ".join(motion_names),
    ])


def longest(static):
    """(name, Recording) of the longest static recording."""
    return max(static, key=lambda item: item[1].duration_s)


def before_after(rec, preset):
    """Raw and GyroFilter(preset) output of ``rec``: (table rows, curves for the figure)."""
    from gyrofilter import GyroFilter

    filt = GyroFilter(sample_rate_hz=rec.sample_rate_hz, preset=preset)
    out = filt.filter(rec.gyro_dps)
    out_rate = rec.sample_rate_hz / filt.settings.block_len
    cal = calibration_samples(rec.sample_rate_hz, filt.settings.calibration_s)
    rows, curves = [], []
    for i, a in enumerate("xyz"):
        raw = rec.gyro_dps[:, i]
        t_r, d_r = overlapping_adev(raw, rec.sample_rate_hz)
        t_f, d_f = overlapping_adev(out[:, i], out_rate)
        curves.append((f"{a} raw ({rec.sample_rate_hz:g} Hz)", t_r, d_r, AXIS_COLOURS[a], "o-"))
        curves.append((f"{a} filtered ({out_rate:g} Hz)", t_f, d_f, AXIS_COLOURS[a], "--"))
        s_raw, s_f = np.std(raw[cal:], ddof=1), np.std(out[:, i], ddof=1)
        rows.append(f"| {preset} | {a} | {s_raw:.4f} | {s_f:.4f} | {s_raw / s_f:.1f}x | {_at(t_r, d_r, 1.0):.2e} | "
                    f"{_at(t_f, d_f, 1.0):.2e} | {_at(t_r, d_r, 10.0):.2e} | {_at(t_f, d_f, 10.0):.2e} |")
    return rows, curves


def before_after_table(rec, presets=tuple(PRESETS)):
    """The before/after table of ``rec`` for every preset (a Markdown table)."""
    rows = [row for preset in presets for row in before_after(rec, preset)[0]]
    return "\n".join(["| preset | axis | raw std (deg/s) | filtered std (deg/s) | ratio | raw ADEV at 1 s | "
                      "filtered ADEV at 1 s | raw ADEV at 10 s | filtered ADEV at 10 s |",
                      "|---|---|---|---|---|---|---|---|---|", *rows])


def _at(tau, dev, t):
    """Log-log interpolation of a deviation curve at t."""
    return float(np.exp(np.interp(np.log(t), np.log(tau), np.log(dev))))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recordings", default=os.path.join(ROOT, "recordings"))
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "figures"))
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    static, motion = recordings(args.recordings)
    if not static:
        print(f"no static recordings/mpu6050_*.csv.gz under {args.recordings}", file=sys.stderr)
        return 1
    results = characterised(static)
    for name, (rec, res) in results.items():
        fig = os.path.join(args.out, f"allan_{name}.png")
        plot_allan(fig, res, title=f"{name}: {rec.duration_s:.0f} s at {rec.sample_rate_hz:g} Hz, MPU6050 +-250 deg/s")
        print(f"wrote {fig}", file=sys.stderr)
    print(tables(results, [name for name, _ in motion]))
    # paper 001 Fig. 4: raw vs filtered on the longest static recording, for every preset
    name, rec = longest(static)
    print(f"\n#### Before/after filtering: {name}; std after the calibration window\n")
    print(before_after_table(rec))
    for preset in PRESETS:
        fig = os.path.join(args.out, "allan_before_after.png" if preset == "paper" else f"allan_before_after_{preset}.png")
        plot_before_after(fig, before_after(rec, preset)[1],
                          title=f"{name}: Allan deviation before and after GyroFilter(preset='{preset}')"
                          + (" (paper 001 Fig. 4)" if preset == "paper" else ""))
        print(f"wrote {fig}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
