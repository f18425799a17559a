"""The checks of what :class:`~gyrofilter.filter.pipeline.GyroFilter` is fed: one sample for
``update()`` (:func:`check_sample`, cheap in the common case), an (N, 3) array for ``filter()``
(:func:`check_samples`), times and temperatures. Each refusal is a
:class:`~gyrofilter.errors.SampleError` that names the value or row, raised before the filter's
state is touched.
"""
from __future__ import annotations

import math
from functools import partial

import numpy as np

from ..errors import SampleError
from ..inputs import check_number, number_array, scalar
from ..units import AXES, MAX_RATE_DPS, TEMP_RANGE_C, check_rates_dps, shown

_UPDATE_TAKES = f"update() takes one sample (gx, gy, gz): 3 finite numbers in deg/s within +-{MAX_RATE_DPS:g}"
_PLAIN = frozenset((int, float, np.float64, np.float32, np.int64, np.int32))  # update()'s quick check


def check_sample(sample):
    """One sample for update() as a tuple of 3 floats (deg/s); SampleError names what is wrong.

    A sample is a tuple, list or array of shape (3,) of numbers (no bools, no set or dict: they
    have no order), each finite and within +-MAX_RATE_DPS (:func:`gyrofilter.inputs.check_number`).
    Checked before the sample touches any state, so a refused sample leaves the filter as it was.
    """
    if type(sample) is tuple and len(sample) == 3:  # the common case, kept cheap (NaN fails every comparison)
        x, y, z = sample
        m = MAX_RATE_DPS
        if type(x) is float and type(y) is float and type(z) is float and -m <= x <= m and -m <= y <= m and -m <= z <= m:
            return sample
    if isinstance(sample, np.ndarray) and sample.shape == (3,) or isinstance(sample, (tuple, list)) and len(sample) == 3:
        x, y, z = sample.tolist() if isinstance(sample, np.ndarray) else sample
        m = MAX_RATE_DPS
        if (type(x) in _PLAIN and type(y) in _PLAIN and type(z) in _PLAIN  # ints, numpy numbers, a list or an array row
                and -m <= x <= m and -m <= y <= m and -m <= z <= m):
            return float(x), float(y), float(z)
        error = partial(SampleError, where=_UPDATE_TAKES)  # any other or refused: check_number says why
        return tuple(check_number(v, f"g{axis} (deg/s)", low=-MAX_RATE_DPS, high=MAX_RATE_DPS, error=error)
                     for axis, v in zip(AXES, sample))
    raise SampleError(f"got {shown(sample)}", where=_UPDATE_TAKES)


def check_samples(samples_dps):
    """The samples for filter(): an (N, 3) float array, each finite and within +-MAX_RATE_DPS
    (deg/s), checked in one pass; SampleError names the first refused row (``.row``)."""
    x = as_numbers(samples_dps, "samples_dps", "deg/s")
    if x.ndim != 2 or x.shape[1] != 3:
        raise SampleError(f"samples_dps must have shape (N, 3), got {x.shape}")
    return check_rates_dps(x, "samples_dps")


def as_numbers(values, name, unit):
    """``values`` as a float array when they are numbers (ints or floats: no strings, bools,
    objects or ragged lists), else SampleError naming ``name``. A masked array with a masked
    value is refused, naming its row: converting it would drop the mask and filter the value
    behind it as data (the rule and its words: :func:`gyrofilter.inputs.number_array`)."""
    x, problem = number_array(values, name, unit)
    if problem is not None:
        words, row = problem
        raise SampleError(words, row or 0)
    return x


def check_temperature(value, required, where, row=0):
    """A sample's temperature as a float in TEMP_RANGE_C (deg C), or NaN when it has
    none (None or NaN), which ``required`` (compensating) refuses; SampleError says why."""
    value = scalar(value)
    if value is None or isinstance(value, (float, np.floating)) and math.isnan(value):
        if required:
            raise SampleError("temperature compensation is on: it needs temp_c, a temperature (deg C), with every sample",
                              row, where)
        return math.nan
    return check_number(value, "temp_c (deg C)", low=TEMP_RANGE_C[0], high=TEMP_RANGE_C[1],
                        error=partial(SampleError, row=row, where=where))

