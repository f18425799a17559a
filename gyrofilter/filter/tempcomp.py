"""Temperature compensation of the gyro bias: b(T) = b(T0) + c (T - T0).

A MEMS gyro's zero-rate output moves with die temperature (MPU6050 datasheet, table 6.1: ZRO
variation over -40..85 C of +-20 deg/s, i.e. up to ~0.16 deg/s/C; individual parts are far
smaller and nearly linear over a few degrees). The start-up calibration measures the bias at the
start-up temperature T0; afterwards the bias that is left is, to first order::

    b(T) - b(T0) = c (T - T0)

with c the ``temperature`` effect's ``coefficient_dps_per_c`` of the gap report
(docs/formats.md, section 3) or of a simulator model. Compensation subtracts it per sample::

    y = x - c (T - T0)

T0 should be the mean temperature of the calibration window, so that the two corrections do
not overlap. Pure functions on arrays; the streaming form is built into the pipeline
(``GyroFilter(..., temp_coefficient_dps_per_c=c)``, ``update(sample, temp_c)``), whose T is the running
median of the latest temperatures (:func:`gyrofilter.tempscreen.running_medians`: a read glitch is no T).
"""
from __future__ import annotations

import numpy as np

from ..effects import TEMPERATURE
from ..errors import SettingsError
from ..inputs import axis_values, check_number
from ..units import AXES, TEMP_RANGE_C, check_rates_dps, shown
from .samples import as_numbers, check_temperature
from .settings import MAX_TEMP_COEFFICIENT_DPS_PER_C
from ..tempscreen import temp_glitches


def _coefficients(coefficient_dps_per_c):
    """c as 3 floats (x, y, z) from one number or 3 (an array of 3: :func:`~gyrofilter.inputs.axis_values`),
    each a number as :func:`~gyrofilter.inputs.check_number` takes it (True was taken as 1, a
    string ended in numpy's ValueError) within the filter's +-MAX_TEMP_COEFFICIENT_DPS_PER_C (1e308
    made inf rates, 1e300 rates of 3e302 deg/s); SettingsError naming it otherwise."""
    c = axis_values(coefficient_dps_per_c)
    several = isinstance(c, (tuple, list))
    if several and len(c) != 3:
        raise SettingsError(f"coefficient_dps_per_c must be one number or 3 (x, y, z), got {shown(c)}")
    return np.array([check_number(v, "coefficient_dps_per_c", low=-MAX_TEMP_COEFFICIENT_DPS_PER_C,
                                  high=MAX_TEMP_COEFFICIENT_DPS_PER_C) for v in (c if several else (c,) * 3)], dtype=float)


def _rates_and_temperatures(gyro_dps, temp_c):
    """``gyro_dps`` and ``temp_c`` as float arrays, checked as GyroFilter checks what it is fed
    (:mod:`gyrofilter.filter.samples`): numbers (a masked value, complex numbers, booleans or
    strings refused: :func:`~gyrofilter.filter.samples.as_numbers`), each finite, rates within
    +-MAX_RATE_DPS (a gyro_dps whose last axis is not 3 is left to the caller's shape check) and
    temperatures within TEMP_RANGE_C; SettingsError (a SampleError) naming the first refused."""
    x = as_numbers(gyro_dps, "gyro_dps", "deg/s")
    t = as_numbers(temp_c, "temp_c", "deg C")
    if not np.all(np.isfinite(t)):
        raise SettingsError("temp_c holds NaN or infinite values")
    if not np.all(np.isfinite(x)):
        raise SettingsError("gyro_dps holds NaN or infinite values")
    if x.shape[-1:] == (3,):
        check_rates_dps(x.reshape(-1, 3), "gyro_dps")
    ok = (t >= TEMP_RANGE_C[0]) & (t <= TEMP_RANGE_C[1])
    if not ok.all():
        row = int(np.flatnonzero(~ok.ravel())[0])
        check_temperature(float(t.ravel()[row]), True, f"temp_c row {row}", row)
    return x, t


def compensate(gyro_dps, temp_c, coefficient_dps_per_c, reference_temp_c):
    """y = x - c (T - T0) per axis, in deg/s.

    ``gyro_dps``: x, (N, 3) or (3,) in deg/s; ``temp_c``: T, (N,) or a scalar, deg C;
    ``coefficient_dps_per_c``: c, one value or 3 (deg/s per deg C, each within the filter's
    +-MAX_TEMP_COEFFICIENT_DPS_PER_C); ``reference_temp_c``: T0 (deg C,
    within :data:`~gyrofilter.units.TEMP_RANGE_C`: a NaN made every rate NaN). SettingsError otherwise,
    and for what :func:`_rates_and_temperatures` refuses.
    """
    x, t = _rates_and_temperatures(gyro_dps, temp_c)
    if x.shape[-1:] != (3,):
        raise SettingsError(f"gyro_dps must have shape (N, 3) or (3,), got {x.shape}")
    if t.shape not in ((), x.shape[:-1]):
        raise SettingsError(f"temp_c must be one temperature or one per sample, shape {x.shape[:-1]}, got {t.shape}")
    c = _coefficients(coefficient_dps_per_c)
    t0 = check_number(reference_temp_c, "reference_temp_c (deg C)", low=TEMP_RANGE_C[0], high=TEMP_RANGE_C[1])
    return x - c * (t[..., None] - t0)


def coefficients_from_model(model: dict):
    """(cx, cy, cz) in deg/s/C from a simulator model / gap ``extended_model`` (0 where no temperature effect):
    the sum of each axis's ``temperature`` effects. Reads ``model`` as it is: check it first (the command
    line's ``--temp-model`` goes through :func:`gyrofilter.sim.model.validate_model`)."""
    out = []
    axes = model.get("axes", {})
    for name in AXES:
        c = 0.0
        for eff in axes.get(name, {}).get("effects", []):
            if eff.get("effect") == TEMPERATURE:
                c += float(eff["coefficient_dps_per_c"])
        out.append(c)
    return tuple(out)


def fit_coefficient(gyro_dps, temp_c):
    """Least-squares slope c per axis of a static record: x = b + c (T - mean T) + noise.

    ``gyro_dps``: x, (N, 3) in deg/s; ``temp_c``: T, (N,) in deg C. Returns (c (3,), standard error (3,)). Meaningless unless the temperature actually varied
    (raises when its spread is below one 0.1 C step, or a value is not finite: a NaN gave NaN coefficients,
    and for what :func:`_rates_and_temperatures` refuses). Rows whose temperature is a read glitch
    (:func:`gyrofilter.tempscreen.temp_glitches`, without its allowance at the ends: a good row left out
    costs the fit nothing) are left out: one TEMP_OUT of 0x8000 (-59.85 deg C) among 30 000 took a
    fitted 0.0300 to 0.0248 (attack pass 37l).
    """
    x, t = _rates_and_temperatures(gyro_dps, temp_c)
    if x.ndim != 2 or x.shape[1] != 3 or t.shape != (len(x),):
        raise SettingsError(f"need gyro_dps (N, 3) and temp_c (N,), got {x.shape} and {t.shape}")
    glitches = temp_glitches(t, None)
    if glitches.size:
        x, t = np.delete(x, glitches, axis=0), np.delete(t, glitches)
    if len(x) < 3:  # the standard error has N - 2 degrees of freedom (2 samples: NaN)
        raise SettingsError(f"fit_coefficient needs at least 3 samples, got {len(x)}")
    dt = t - t.mean()
    sxx = float(dt @ dt)
    if np.ptp(t) < 0.1:
        raise SettingsError(f"temperature spans only {np.ptp(t):.3f} C; no coefficient can be fitted")
    c = (dt @ (x - x.mean(axis=0))) / sxx
    resid = x - x.mean(axis=0) - np.outer(dt, c)
    se = np.sqrt(resid.var(axis=0, ddof=2) / sxx)
    return c, se
