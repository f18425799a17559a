#!/usr/bin/env python
"""Convert the 4 BROAD trials (../shared/data/broad_omc_reference) to recording format v1.

Output: recordings/broad_<trial>.csv.gz with columns

    t, gx, gy, gz, ref_x, ref_y, ref_z, ref_valid, movement

- gx, gy, gz: the IMU gyro, unchanged (rad/s, 285.714 Hz = 2000/7 Hz; t = index / fs as upstream).
- ref_x, ref_y, ref_z: body-frame reference rate in rad/s derived from the optical quaternions by
  the central difference omega_k = rotvec(q_{k-h}^-1 q_{k+h}) fs / (2h), h = 2
  (:func:`gyrofilter.evaluation.reference.body_rate_from_quaternions`), delayed by REF_SHIFT_SAMPLES = 1
  sample so that it lines up with the gyro (see below).
- ref_valid: 1 where the reference is derivable; 0 where an occlusion (NaN quaternion) lies
  within the difference span or at the ends. Format v1 forbids NaN cells, so the ref_* cells of
  those rows hold 0 and must be ignored (``gyrofilter.evaluation.reference.reference_from_recording`` turns
  them back into NaN). No sample is interpolated.
- movement: upstream flag, 1 during the movement phase, 0 at rest.

Time alignment: normalised cross-correlation of the bias-corrected gyro with the reference over
the movement phase (``estimate_time_offset_s``, +-0.1 s, parabolic peak) finds the reference
leading the gyro by 4.13-4.16 ms (1.19 samples) in all four trials, consistently (the IMU's
internal filter delay). Filters cannot remove that sensor delay, so the reference is delayed by one
whole sample (no interpolation); the residual offset is measured again and written to the
header (ref_offset_after_shift_s), about -0.6 ms.

Licence of the data: CC BY 4.0, D. Laidig, M. Caruso, A. Cereatti, T. Seel, "BROAD - A Benchmark
for Robust Inertial Orientation Estimation", Data 6(7), 2021, doi:10.3390/data6070072
(github.com/dlaidig/broad, commit 7e2f8189bb4a3ac91eae32c69b6bc87f08a6e2ad). Changes: format
conversion, derived reference-rate columns.

Usage: python tools/convert_broad.py [--src DIR] [--out DIR]
"""
import argparse
import gzip
import os
import sys

import numpy as np


from gyrofilter.recording import RecordingWriter
from gyrofilter.evaluation.reference import body_rate_from_quaternions, estimate_time_offset_s

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_SRC = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "data", "broad_omc_reference"))
DEFAULT_OUT = os.path.normpath(os.path.join(HERE, "..", "recordings"))

SAMPLE_RATE_HZ = 2000.0 / 7.0  # 285.714... Hz, upstream sampling_rate_hz
HALF_SPAN = 2
REF_SHIFT_SAMPLES = 1
TRIALS = {
    "02_undisturbed_slow_rotation_B": ("broad_02_slow.csv.gz", "slow rotation"),
    "05_undisturbed_slow_rotation_with_breaks_B": ("broad_05_slow_breaks.csv.gz", "slow rotation with rest breaks"),
    "07_undisturbed_fast_rotation_B": ("broad_07_fast.csv.gz", "fast rotation"),
    "09_undisturbed_fast_rotation_with_breaks_B": ("broad_09_fast_breaks.csv.gz", "fast rotation with rest breaks"),
}
ATTRIBUTION = (
    "CC BY 4.0; D. Laidig, M. Caruso, A. Cereatti, T. Seel, BROAD - A Benchmark for Robust Inertial "
    "Orientation Estimation, Data 6(7) 2021, doi:10.3390/data6070072; github.com/dlaidig/broad "
    "commit 7e2f8189bb4a3ac91eae32c69b6bc87f08a6e2ad; changed: converted to gyrofilter format v1, "
    "reference-rate columns derived from the optical quaternions"
)


def load_trial(path):
    """Upstream CSV -> (t_s, gyro_rads (N,3), quat_wxyz (N,4) with NaN, movement (N,))."""
    with gzip.open(path, "rt") as fh:
        data = np.loadtxt(fh, delimiter=",", skiprows=2)  # "# BROAD ..." line, column names
    return data[:, 0], data[:, 1:4], data[:, 4:8], data[:, 8]


def derive_reference(gyro_rads, quat, movement):
    """Reference (N,3) rad/s with NaN, aligned to the gyro; and the offsets before/after (s)."""
    ref = body_rate_from_quaternions(quat, SAMPLE_RATE_HZ, half_span=HALF_SPAN)
    first_move = int(np.flatnonzero(movement == 1)[0])
    bias = gyro_rads[:first_move].mean(axis=0)
    moving = movement == 1
    before, _ = estimate_time_offset_s(gyro_rads - bias, ref, SAMPLE_RATE_HZ, 0.1, mask=moving)
    shifted = np.full_like(ref, np.nan)
    shifted[REF_SHIFT_SAMPLES:] = ref[: len(ref) - REF_SHIFT_SAMPLES]
    after, peak = estimate_time_offset_s(gyro_rads - bias, shifted, SAMPLE_RATE_HZ, 0.1, mask=moving)
    return shifted, before, after, peak


def convert(src_dir, out_dir):
    rows = []
    for trial, (name, what) in TRIALS.items():
        src = os.path.join(src_dir, trial + ".csv.gz")
        t_s, gyro, quat, movement = load_trial(src)
        ref, before, after, peak = derive_reference(gyro, quat, movement)
        valid = np.isfinite(ref).all(axis=1)
        ref_cells = np.where(valid[:, None], ref, 0.0)
        header = {
            "sample_rate_hz": repr(SAMPLE_RATE_HZ),
            "gyro_unit": "rad/s",
            "sensor": "myon aktos-t IMU (MEMS) + Optitrack optical motion capture reference",
            "source": f"BROAD trial {trial} ({what})",
            "licence": ATTRIBUTION,
            "ref_method": (
                f"body-frame rate rotvec(q[k-{HALF_SPAN}]^-1 q[k+{HALF_SPAN}]) * fs / {2 * HALF_SPAN} from the optical "
                f"quaternions (IMU wrt ENU), delayed by {REF_SHIFT_SAMPLES} sample; ref_valid=0 rows (occlusion) hold 0 and "
                "must be ignored; tools/convert_broad.py"
            ),
            "ref_offset_before_shift_s": f"{before:.6f}",
            "ref_offset_after_shift_s": f"{after:.6f}",
            "ref_xcorr_peak": f"{peak:.5f}",
            "movement": "1 during the movement phase, 0 at rest (upstream flag)",
        }
        columns = ["t", "gx", "gy", "gz", "ref_x", "ref_y", "ref_z", "ref_valid", "movement"]
        formats = ["%.6f", "%.9g", "%.9g", "%.9g", "%.6g", "%.6g", "%.6g", "%d", "%d"]
        data = np.column_stack([t_s, gyro, ref_cells, valid.astype(int), movement.astype(int)])
        out = os.path.join(out_dir, name)
        with RecordingWriter(out, header, columns, formats=formats, flush_interval_s=None, fsync=False,
                             compresslevel=9) as w:
            w.write(data)
        rows.append((name, trial, len(t_s), len(t_s) / SAMPLE_RATE_HZ, int((~valid).sum()), before, after))
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--src", default=DEFAULT_SRC)
    parser.add_argument("--out", default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    print("| file | trial | samples | duration (s) | ref invalid rows | offset before / after shift (ms) |")
    print("|---|---|---|---|---|---|")
    for name, trial, n, dur, bad, before, after in convert(args.src, args.out):
        print(f"| {name} | {trial} | {n} | {dur:.1f} | {bad} | {before * 1e3:.2f} / {after * 1e3:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
