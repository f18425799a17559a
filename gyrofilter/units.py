"""Unit conventions and conversions.

Angular rate is in deg/s (names end in ``_dps``) unless a name says otherwise; times in
seconds (``_s``), rates in hertz (``_hz``), temperatures in degrees Celsius (``_c``).
Arrays of three-axis samples have shape (N, 3), columns x, y, z.
"""
import math

import numpy as np

from .errors import SettingsError

DEG_PER_RAD = 180.0 / math.pi
GYRO_UNITS = ("dps", "rad/s", "lsb")


def to_dps(values, unit, lsb_per_dps=None):
    """Convert angular rate ``values`` from ``unit`` ('dps', 'rad/s' or 'lsb') to deg/s."""
    values = np.asarray(values, dtype=float)
    if unit == "dps":
        return values
    if unit == "rad/s":
        return values * DEG_PER_RAD
    if unit == "lsb":
        if not lsb_per_dps or lsb_per_dps <= 0:
            raise SettingsError(f"gyro_unit 'lsb' needs a positive lsb_per_dps, got {lsb_per_dps!r}")
        return values / lsb_per_dps
    raise SettingsError(f"unknown gyro unit {unit!r}; expected one of {', '.join(GYRO_UNITS)}")


def from_dps(values_dps, unit, lsb_per_dps=None):
    """Inverse of :func:`to_dps` (no rounding: 'lsb' values come back as floats)."""
    values_dps = np.asarray(values_dps, dtype=float)
    if unit == "dps":
        return values_dps
    if unit == "rad/s":
        return values_dps / DEG_PER_RAD
    if unit == "lsb":
        if not lsb_per_dps or lsb_per_dps <= 0:
            raise SettingsError(f"gyro_unit 'lsb' needs a positive lsb_per_dps, got {lsb_per_dps!r}")
        return values_dps * lsb_per_dps
    raise SettingsError(f"unknown gyro unit {unit!r}; expected one of {', '.join(GYRO_UNITS)}")
