"""Convert the real MPU6050 logs in ``../shared/data`` into recording format v1 (``recordings/``).

Usage::

    python tools/convert_mpu6050.py [--shared ../shared] [--out recordings]

Two upstream data sets (see each folder's ``SOURCE.md``):

* ``mpu6050_imucalibration`` (tomisuarez2/ImuCalibration, MIT): raw int16 LSB at exactly
  100 Hz (Arduino data-ready interrupt, SMPLRT_DIV = 79). Gyro written as integer LSB
  (``gyro_unit: lsb``, ``lsb_per_dps: 131``), lossless. Accel carried along as ``ax, ay, az``
  in g = LSB / 16384, to 10 significant digits (``round(a * 16384)`` gives back the raw
  integer exactly). No ``t`` column: the samples are uniform at 100 Hz. The 5 upstream
  header lines become ``upstream_*`` header keys.
* ``mpu6050_sensorfusion`` (sunsided/sensor-fusion, EUPL-1.2): gyro in deg/s that are exact
  multiples of 1/131 deg/s, so they are stored as integer LSB ``q = round(x * 131)``; the
  conversion fails loudly unless ``|q / 131 - x| <= 1e-9 * max(1, |x|)`` for every value
  (the source CSV has 10 significant digits, hence the relative bound). The host timestamps
  are bursty (median dt 2 ms, up to 0.5 s) and are not the sampling instants, so there is no
  ``t`` column: ``sample_rate_hz = (N - 1) / (t_last - t_first)`` (the mean sample rate,
  about 99.3 Hz), and the host time goes along as an extra column ``host_t`` (s).
  ``temp`` from ``temp_C``; accel ``ax, ay, az`` in g as in the source.

Files are written with :func:`gyrofilter.recording.RecordingWriter` (gzip level 9, mtime 0,
so a rerun gives byte-identical files).
"""
from __future__ import annotations

import argparse
import csv
import os
import sys
from pathlib import Path

import numpy as np

from gyrofilter.recording import RecordingWriter

REPO = Path(__file__).resolve().parent.parent
LSB_PER_DPS = 131  # MPU6050 FS_SEL=0 (+-250 deg/s), datasheet table 6.1
LSB_PER_G = 16384  # MPU6050 AFS_SEL=0 (+-2 g)
REL_TOL = 1e-9
# EUPL-1.2 article 5 asks derivative works to state that and when the work was modified. A fixed
# date (the date this conversion was written) keeps reruns byte-identical; change it when the
# conversion itself changes.
CONVERSION_DATE = "2026-11-22"

SF_REPO = "github.com/sunsided/sensor-fusion"
SF_COMMIT = "f16045a9d1d4f9037a183f436fe3c098a38ad99d"
SF_LICENCE = ("EUPL-1.2 (European Union Public Licence v1.2), data by the sunsided/sensor-fusion authors; "
              "licence text: recordings/LICENSES/EUPL-1.2_sensor-fusion.md")
IC_REPO = "github.com/tomisuarez2/ImuCalibration"
IC_COMMIT = "c86ea2531da0da7929b884b52d8955c0ea0615ff"
IC_LICENCE = "MIT, Copyright (c) 2025 tomisuarez2; licence text: recordings/LICENSES/MIT_ImuCalibration.txt"

SET2_AXES = ("set-2 (upstream README): X forward, Y left, Z up; accel reads -1 g on Z when Z points up; "
             "gyro X sign flipped (positive = clockwise about X), gyro Y and Z positive counter-clockwise")
SET1_AXES = ("set-1 (upstream README): accel X and gyro X sign flipped, accel reads +1 g on Z when Z points up")

# (source file, output name, upstream path, axes note, description)
SENSORFUSION = [
    ("static_10min_set2.csv", "mpu6050_static_655s",
     "data/set-2/unmoved-with-x-pointing-forward-10min/mpu6050_{accelerometer,gyroscope,temperature}.mat",
     SET2_AXES,
     "static: unmoved on a table for 655 s, X forward, Z up; sensor already warm (~25.5 C), temperature "
     "falls slowly to ~25.1 C; bias about [4.535, 0.047, 1.122] deg/s"),
    ("static_2min_set2.csv", "mpu6050_static_123s",
     "data/set-2/unmoved-with-x-pointing-forward/mpu6050_{accelerometer,gyroscope,temperature}.mat",
     SET2_AXES,
     "static: unmoved for 123 s, same orientation as mpu6050_static_655s, another run"),
    ("static_1min_set1.csv", "mpu6050_static_64s_set1",
     "data/set-1/unmoved-x-pointing-forward/mpu6050_{accelerometer,gyroscope,temperature}.mat",
     SET1_AXES,
     "static: unmoved for 64 s, X forward (set-1 sign conventions, accel Z about +1 g)"),
    ("dynamic_rotate_ccw_z_set2.csv", "mpu6050_rotate_z_24s",
     "data/set-2/rotate-ccw-around-z-pointing-up/mpu6050_{accelerometer,gyroscope,temperature}.mat",
     SET2_AXES,
     "motion: two 360 deg counter-clockwise turns about Z (Z up), by hand, 24 s; no reference rate; gyro Z "
     "peaks at 88.9 deg/s; gyro Z minus the static bias 1.122 deg/s integrates to about 703 deg (nominal 720)"),
]

# (source file, output name, upstream path, description)
IMUCALIBRATION = [
    ("example_data_tinit_calc.csv", "mpu6050_static_449s", "calibration data/example_data_tinit_calc.csv",
     "static: still for 449 s (upstream log for the Allan-variance choice of the initialisation time); "
     "bias about [-3.345, 1.089, -0.498] deg/s"),
    ("imu_static_test.csv", "mpu6050_static_100s", "results test data/imu_static_test.csv",
     "static: still for 100 s, another power-on than mpu6050_static_449s (X bias -3.268 vs -3.345 deg/s)"),
    ("example_data_calibration.csv", "mpu6050_multipose_102s", "calibration data/example_data_calibration.csv",
     "motion: multi-position calibration sequence by hand (still for the initialisation time, then moves to "
     "new poses each held still for the waiting time); SATURATES: gyro x reaches +-full scale "
     "(32767/-32768 LSB) in 12 samples and gyro z in 6"),
    ("imu_90_x_rot.csv", "mpu6050_rotate_x90_100s", "results test data/imu_90_x_rot.csv",
     "motion: a 90 deg rotation about X by hand within 100 s, still before and after; no reference rate; "
     "gyro minus the first-3-s mean integrates to about [90.7, 16.2, 9.1] deg"),
]


class ConversionError(RuntimeError):
    pass


def _g(x):
    return format(float(x), ".10g")


def _provenance(repo, commit, path, shared_rel):
    return f"{repo} commit {commit} path {path} (converted from ../shared/data/{shared_rel})"


def quantize_lossless(values, step_per_unit, what, path):
    """Integers ``q = round(values * step_per_unit)``; raise unless ``q / step`` equals ``values``.

    Equality within ``1e-9 * max(1, |x|)``: the source CSV holds 10 significant digits.
    """
    q = np.round(values * step_per_unit)
    err = np.abs(q / step_per_unit - values)
    bound = REL_TOL * np.maximum(1.0, np.abs(values))
    bad = np.argwhere(err > bound)
    if bad.size:
        row, col = (int(v) for v in bad[0])
        raise ConversionError(
            f"{path}: data row {row + 1}, {what} column {col}: {values[row, col]!r} is not a multiple of "
            f"1/{step_per_unit} (nearest {q[row, col] / step_per_unit!r}); {len(bad)} such values; refusing to convert")
    return q.astype(np.int64)


def convert_sensorfusion(src: Path, out: Path, upstream_path, axes, description, shared_rel):
    with open(src, newline="") as fh:
        names = next(csv.reader(fh))
    expected = ["t_s", "acc_x_g", "acc_y_g", "acc_z_g", "gyro_x_dps", "gyro_y_dps", "gyro_z_dps", "temp_C"]
    if names != expected:
        raise ConversionError(f"{src}: line 1: columns {names}, expected {expected}")
    data = np.loadtxt(src, delimiter=",", skiprows=1, ndmin=2)
    if data.shape[1] != len(expected) or not np.isfinite(data).all():
        raise ConversionError(f"{src}: expected {len(expected)} finite columns, got shape {data.shape}")
    host_t = data[:, 0]
    if np.any(np.diff(host_t) <= 0):
        raise ConversionError(f"{src}: t_s does not increase")
    gyro_lsb = quantize_lossless(data[:, 4:7], LSB_PER_DPS, "gyro", src)
    quantize_lossless(data[:, 1:4], LSB_PER_G, "accel", src)  # a check only: accel is written in g
    n = len(data)
    rate_hz = (n - 1) / (host_t[-1] - host_t[0])
    dt_s = np.diff(host_t)
    header = {
        "sensor": "MPU6050",
        "sample_rate_hz": f"{rate_hz:.6g}",
        "gyro_unit": "lsb",
        "lsb_per_dps": str(LSB_PER_DPS),
        "full_scale_dps": "250",
        "accel_unit": "g",
        "accel_full_scale_g": "2",
        "dlpf_cfg": "unknown",
        "description": description,
        "source": _provenance(SF_REPO, SF_COMMIT, upstream_path, shared_rel),
        "licence": SF_LICENCE,
        "axis_convention": axes,
        "timing": (f"host_t is the host-side (MATLAB) arrival time in s, bursty (median dt {1e3 * np.median(dt_s):.1f} ms, "
                   f"{100 * np.mean(dt_s > 0.02):.0f} % of dt > 20 ms, max {dt_s.max():.2f} s), not the sampling instant; "
                   "samples are treated as uniform at sample_rate_hz = (N - 1) / (host_t[-1] - host_t[0]); "
                   "the upstream nominal rate is 100 Hz"),
        "conversion": ("tools/convert_mpu6050.py: gyro = round(gyro_dps * 131) (checked lossless), "
                       "accel in g and temp in deg C as in the source (10 significant digits)"),
        "modified": (f"{CONVERSION_DATE}: the upstream MATLAB data (via the CSV named in source) rewritten as "
                     "gyrofilter recording format v1: gyro deg/s -> integer LSB, columns renamed and reordered, "
                     "header added; values otherwise unchanged"),
    }
    columns = ["gx", "gy", "gz", "temp", "ax", "ay", "az", "host_t"]
    rows = [
        (int(g[0]), int(g[1]), int(g[2]), _g(r[7]), _g(r[1]), _g(r[2]), _g(r[3]), _g(r[0]))
        for g, r in zip(gyro_lsb.tolist(), data.tolist())
    ]
    _write(out, header, columns, ["%d", "%d", "%d", "%s", "%s", "%s", "%s", "%s"], rows)
    return n, rate_hz


def read_imucalibration(src: Path):
    """The 5 upstream header lines as a dict, and the integer rows (N, 6): ax, ay, az, gx, gy, gz."""
    with open(src, newline="") as fh:
        lines = [next(fh) for _ in range(5)]
    upstream = {}
    for i, ln in enumerate(lines[:4]):
        key, sep, value = ln.strip().partition(",")
        if not sep:
            raise ConversionError(f"{src}: line {i + 1}: expected 'key,value', got {ln.strip()!r}")
        upstream[key.strip()] = value.strip()
    if [k for k in upstream] != ["Fs", "Logging Type", "Initialization time", "Waiting time"]:
        raise ConversionError(f"{src}: unexpected upstream header keys {list(upstream)}")
    if lines[4].strip() != "ax,ay,az,gx,gy,gz":
        raise ConversionError(f"{src}: line 5: expected 'ax,ay,az,gx,gy,gz', got {lines[4].strip()!r}")
    if float(upstream["Fs"]) != 100:
        raise ConversionError(f"{src}: line 1: Fs is {upstream['Fs']}, expected 100")
    data = np.loadtxt(src, delimiter=",", skiprows=5, ndmin=2, dtype=np.int64)
    if data.shape[1] != 6:
        raise ConversionError(f"{src}: expected 6 columns, got {data.shape[1]}")
    if data.min() < -32768 or data.max() > 32767:
        raise ConversionError(f"{src}: values outside int16")
    return upstream, data


def convert_imucalibration(src: Path, out: Path, upstream_path, description, shared_rel):
    upstream, data = read_imucalibration(src)
    header = {
        "sensor": "MPU6050",
        "sample_rate_hz": "100",
        "gyro_unit": "lsb",
        "lsb_per_dps": str(LSB_PER_DPS),
        "full_scale_dps": "250",
        "accel_unit": "g",
        "accel_full_scale_g": "2",
        "dlpf_cfg": "0",
        "description": description,
        "source": _provenance(IC_REPO, IC_COMMIT, upstream_path, shared_rel),
        "licence": IC_LICENCE,
        "setup": ("Arduino UNO, upstream sketch 'arduino code/MPU6050_raw/MPU6050_raw.ino': I2Cdevlib MPU6050 "
                  "defaults (+-250 deg/s, +-2 g), setDLPFMode(0), SMPLRT_DIV 79 -> 100 Hz, data-ready "
                  "interrupt, UART 38400 baud; no timestamps, no temperature"),
        "upstream_fs": upstream["Fs"],
        "upstream_logging_type": upstream["Logging Type"]
        + (" (0 = multi-position calibration log)" if upstream["Logging Type"] == "0"
           else " (1 = free / Allan-variance log)"),
        "upstream_initialization_time": upstream["Initialization time"] + " (s; -1 = not used)",
        "upstream_waiting_time": upstream["Waiting time"] + " (s; -1 = not used)",
        "conversion": ("tools/convert_mpu6050.py: gyro = upstream raw int16 LSB unchanged; "
                       "accel = raw / 16384 in g (10 significant digits, round(a * 16384) gives the raw value)"),
        "modified": (f"{CONVERSION_DATE}: rewritten as gyrofilter recording format v1 (columns reordered, "
                     "accel scaled to g, header added); gyro values unchanged"),
    }
    columns = ["gx", "gy", "gz", "ax", "ay", "az"]
    rows = [
        (r[3], r[4], r[5], _g(r[0] / LSB_PER_G), _g(r[1] / LSB_PER_G), _g(r[2] / LSB_PER_G))
        for r in data.tolist()
    ]
    _write(out, header, columns, ["%d", "%d", "%d", "%s", "%s", "%s"], rows)
    return len(data), 100.0


def _write(out, header, columns, formats, rows):
    tmp = out.with_name(out.name + ".part.gz")
    with RecordingWriter(tmp, header, columns, formats=formats, flush_interval_s=None, fsync=False, compresslevel=9) as w:
        w.write(np.array(rows, dtype=object))
    os.replace(tmp, out)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--shared", default=str(REPO.parent / "shared"),
                        help="the shared folder holding data/mpu6050_* (default: ../shared beside the repo)")
    parser.add_argument("--out", default=str(REPO / "recordings"), help="output folder (default: recordings/)")
    args = parser.parse_args(argv)
    data = Path(args.shared) / "data"
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    jobs = []
    for fname, name, upath, axes, desc in SENSORFUSION:
        rel = f"mpu6050_sensorfusion/{fname}"
        jobs.append((rel, name, lambda s, o, u=upath, a=axes, d=desc, r=rel: convert_sensorfusion(s, o, u, a, d, r)))
    for fname, name, upath, desc in IMUCALIBRATION:
        rel = f"mpu6050_imucalibration/{fname}"
        jobs.append((rel, name, lambda s, o, u=upath, d=desc, r=rel: convert_imucalibration(s, o, u, d, r)))
    total = 0
    try:
        for rel, name, convert in jobs:
            src = data / rel
            out = out_dir / f"{name}.csv.gz"
            n, rate = convert(src, out)
            size = out.stat().st_size
            total += size
            print(f"{out.relative_to(out_dir.parent) if out_dir.parent in out.parents else out}: "
                  f"{n} rows, {rate:.4g} Hz, {n / rate:.1f} s, {size / 1024:.1f} KiB  <- {rel}")
    except (OSError, ConversionError, ValueError) as exc:
        print(f"convert_mpu6050: {exc}", file=sys.stderr)
        return 2
    print(f"total {total / 1024:.1f} KiB in {len(jobs)} files")
    return 0


if __name__ == "__main__":
    sys.exit(main())
