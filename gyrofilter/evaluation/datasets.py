"""The data sets of the comparison (:mod:`gyrofilter.evaluation.evaluate`): the real static MPU6050
recordings, the BROAD trials with their optical reference, and the static noise segments the
synthetic motion is added to.
"""
from __future__ import annotations

import contextlib
import glob
import os

import numpy as np

from ..errors import RecordingError
from ..inputs import quote
from ..recording import filtered_words, read_recording
from ..units import AXES, one_value

NOISE_SEGMENT_S = 90.0
#: the columns a BROAD trial has beside the gyro's: the optical reference rate and the movement flag
BROAD_COLUMNS = ("ref_x", "ref_y", "ref_z", "movement")
#: how a recording's name ends (the reader's two formats); a name that ends otherwise (``a.csv~``,
#: ``a.csv.gz.bak``: a backup copy) is no recording of the folder
RECORDING_ENDINGS = (".csv.gz", ".csv")


def stem(path):
    name = os.path.basename(path)
    for ext in RECORDING_ENDINGS:
        if name.endswith(ext):
            return name[: -len(ext)]
    return name


def find_static_recordings(recordings_dir):
    """Real static MPU6050 recordings in the folder ``recordings_dir``: sensor MPU6050 and a
    description starting with 'static' (or, without a description, 'static' in the file name).
    RecordingError naming a filtered output of the sensor (:func:`~gyrofilter.recording.filtered_from`:
    ``replay --out`` keeps the ``sensor`` key), whose rows are bias-removed block means, not samples."""
    out = []
    for path in _files(recordings_dir, "*.csv*"):
        rec = read_recording(path)
        if "mpu6050" not in rec.header.get("sensor", "").lower():
            continue
        filtered = filtered_words(rec.header)
        if filtered:
            raise RecordingError(f"{path}: is {filtered} that evaluate compares the filters on; move it out of the "
                                 "recordings folder")
        desc = rec.header.get("description", "").strip().lower()
        if desc.startswith("static") or (not desc and "static" in os.path.basename(path).lower()):
            _refuse_stuck(rec, path)
            out.append(rec)
    return out


def _refuse_stuck(rec, path):
    """RecordingError naming ``path`` and the axis of ``rec`` whose samples are all equal (a stuck or
    unconnected axis, as ``allan`` refuses it): its std reduction would be 0 / 0, or a ratio of the
    rounding residues of two means."""
    gyro = rec.gyro_dps
    for i, axis in enumerate(AXES):
        if len(gyro) and one_value(gyro[:, i].min(), gyro[:, i].max()):
            raise RecordingError(f"{path}: axis {axis}: all {len(gyro)} samples equal {gyro[0, i]:g} deg/s (a stuck "
                                 "axis): no noise for the filters to reduce; move it out of the recordings folder")


def find_broad_recordings(recordings_dir):
    """The BROAD trials (``broad_*.csv*``, with optical reference) in the folder ``recordings_dir``,
    read; RecordingError naming a file without the columns of :data:`BROAD_COLUMNS` or without a
    movement phase (a user's own recording so named), which the metrics need."""
    trials = []
    for path in _files(recordings_dir, "broad_*.csv*"):
        rec = read_recording(path)
        missing = [c for c in BROAD_COLUMNS if c not in rec.columns]
        if missing:
            raise RecordingError(f"{path}: has no column(s) {', '.join(missing)} that a BROAD trial has "
                                 "(recordings/README_broad.md); rename a recording of your own")
        if not np.any(np.asarray(rec.columns["movement"]) == 1):
            raise RecordingError(f"{path}: its movement column is never 1: a BROAD trial has a movement phase "
                                 "between rests (recordings/README_broad.md)")
        trials.append(rec)
    return trials


def _files(folder, pattern):
    """The files of ``folder`` whose names match ``pattern`` and end as a recording's
    (:data:`RECORDING_ENDINGS`), sorted: the folder's name taken as it is
    (``glob.escape``: ``rec[1]`` is no pattern that matches the folder ``rec1``). RecordingError
    naming two of one :func:`stem` (``a.csv`` and ``a.csv.gz``): the results know a recording by
    its stem, so the second's replaced the first's; and naming two paths of one file (a symbolic or
    hard link beside its recording), whose results would count twice."""
    paths = sorted(p for p in glob.glob(os.path.join(glob.escape(folder), pattern)) if p.endswith(RECORDING_ENDINGS))
    seen = {}
    for path in paths:
        other = seen.setdefault(stem(path), path)
        if other != path:
            raise RecordingError(f"{other} and {path}: both named {quote(stem(path))} in the results; "
                                 "move one of them out of the recordings folder")
    files = {}
    for path in paths:
        with contextlib.suppress(OSError):  # an unreadable one is named by its reading
            st = os.stat(path)
            other = files.setdefault((st.st_dev, st.st_ino), path)
            if other != path:
                raise RecordingError(f"{other} and {path}: one file (a link), whose results would count twice; "
                                     "move the link out of the recordings folder")
    return paths


def noise_segments(static_recs, duration_s=NOISE_SEGMENT_S, names=None):
    """(name, x_dps (n, 3), sample_rate_hz): the first ``duration_s`` (s) of each recording of ``static_recs``
    long enough (only those named in ``names``, when given)."""
    segs = []
    for rec in static_recs:
        name = stem(rec.path or "")
        if names is not None and name not in names:
            continue
        n = int(round(duration_s * rec.sample_rate_hz))
        if len(rec) >= n:
            segs.append((name, rec.gyro_dps[:n], rec.sample_rate_hz))
    return segs
