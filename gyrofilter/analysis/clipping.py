"""Whether a gyro record was clipped at its sensor's full scale (:func:`clipped`): pure, numbers in, words out."""
from __future__ import annotations

import numpy as np

from ..units import AXES


def clipped(gyro_dps, full_scale_dps, lsb_per_dps=None):
    """Why a record ``gyro_dps`` ((N, 3), deg/s) looks clipped, or None: the samples at the sensor's
    full scale ``full_scale_dps`` (deg/s, the header's ``full_scale_dps``), counted per axis. A
    sample is at the full scale when |rate| >= full scale - one LSB (1 / ``lsb_per_dps`` deg/s, 0
    when the unit is not LSB): an int16 register saturates at 32767 or -32768 LSB, which at
    131 LSB per deg/s is 250.1 deg/s beyond a 250 deg/s range. A clipped sample is not the rate:
    the motion was faster than the sensor reads. None also when ``full_scale_dps`` is None."""
    if full_scale_dps is None:
        return None
    limit_dps = full_scale_dps - (1.0 / lsb_per_dps if lsb_per_dps else 0.0)
    counts = np.count_nonzero(np.abs(np.asarray(gyro_dps, dtype=float)) >= limit_dps, axis=0)
    if not counts.any():
        return None
    where = ", ".join(f"{a}: {int(n)}" for a, n in zip(AXES, counts) if n)
    return (f"{int(counts.sum())} sample(s) at the full scale of +-{full_scale_dps:g} deg/s ({where}): the rate was "
            "clipped there (the motion was faster than the sensor's range)")
