"""The time column of another tool's gyro log (``gyrofilter convert``): its stamps as exact offsets from the first
(:class:`Stamps`), its unit when neither the caller nor its name states it (:func:`infer_time_unit`), its cells as
seconds (:func:`seconds_from`)."""
from __future__ import annotations

import decimal
import math
import sys

import numpy as np

from ...errors import RecordingError
from ...inputs import quote
from ...units import RATE_TOLERANCE

#: time units of a time column and their length in s
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
#: the slowest rate a time unit is inferred for: a gyro logs at 5 Hz or faster (the MPU6050's slowest is 3.9 Hz)
MIN_INFERRED_RATE_HZ = 5.0
#: the fastest rate a gyro outputs (the ICM-42688-P's 32 kHz; the MPU6050's 8 kHz): a time unit in which the steps
#: mean a rate from 1 Hz to this one is a unit the log may be in
FASTEST_GYRO_HZ = 32_000.0


class Stamps:
    """The time column's cells, a chunk at a time (:meth:`add`), as offsets from the first stamp.
    The cells are subtracted as decimals, exactly, before they become floats: a phone's stamps
    in s since 1970 with 9 decimals (or ns since 1970) keep every ns, which floats of the stamps
    themselves (2.4e-7 s apart near 1.7e9) would not. Kept: the offsets as floats (8 bytes a row;
    the time unit is inferred from their median step) when ``keep``, and the first stamp beyond a
    float's range and the first offset beyond it, refused by :meth:`check` as the first in the
    file (a first stamp of 1e400 is blamed, not the next row, whose offset from it is what overflows)."""

    def __init__(self, keep):
        self.first, self.origin, self.offsets = None, None, [] if keep else None
        self.huge = self.far = None  # (row, text) of the first stamp beyond a float / offset beyond one
        self.rows = 0
        self.last = None  # (offset, text) of the last stamp taken
        self.exponent = None  # the place of the finest last digit of a stamp (-3: 0.001 of the unit)

    def add(self, texts, where):
        """Take the next chunk's cells; False once a stamp or offset is beyond a float. A stamp
        that does not increase is refused at once (``where(i)`` names the chunk's row i): a gzip
        bomb of equal rows, "0,0,0,0" 150 million times in 1.8 MB, was read whole first (16 bytes a row: 2.4 GB)."""
        if self.first is None:
            self.origin = texts[0]
            self.first = decimal.Decimal(texts[0])
            if not math.isfinite(float(self.first)):
                self.huge = (0, texts[0])  # blamed when an offset from it is beyond a float
        with decimal.localcontext() as ctx:
            ctx.traps[decimal.Overflow] = False  # 1e99999 - 0 is Infinity, refused by check()
            stamps = [decimal.Decimal(t) for t in texts]
            offsets = np.array([float(d - self.first) for d in stamps])
        places = [d.as_tuple().exponent for d in stamps if d.is_finite()]
        if places:
            self.exponent = min(places + ([self.exponent] if self.exponent is not None else []))
        bad = np.flatnonzero(~np.isfinite(offsets))
        if bad.size and self.far is None:
            self.far = (self.rows + int(bad[0]), texts[int(bad[0])])
            for row in range(int(bad[0]) + 1):  # a stamp itself beyond a float comes at or before its offset
                if self.huge is None and not math.isfinite(float(decimal.Decimal(texts[row]))):
                    self.huge = (self.rows + row, texts[row])
        with np.errstate(invalid="ignore"):  # inf - inf: an offset beyond a float
            steps = np.diff(offsets) if self.last is None else np.diff(np.r_[self.last[0], offsets])
            back = np.flatnonzero((steps <= 0) & np.isfinite(steps))  # an offset beyond a float: refused by check()
        if back.size:
            i = int(back[0]) + (1 if self.last is None else 0)
            before = texts[i - 1] if i > 0 else self.last[1]
            raise RecordingError(f"{where(i)}: t does not increase ({quote(texts[i])} after {quote(before)})")
        if self.offsets is not None:
            self.offsets.append(offsets)
        self.rows += len(texts)
        self.last = (float(offsets[-1]), texts[-1])
        return self.far is None

    def check(self, where, path):
        """Refuse the first stamp beyond a float's range, or too far from the first for a float;
        ``where(row)`` names a row."""
        if self.far is None:
            return
        row, text = self.huge or self.far
        why = (f"is beyond the range of a float ({sys.float_info.max:.3g})" if self.huge else
               f"is too far from the first ({quote(self.origin)}) to be a time of this log")
        raise RecordingError(f"{path}: {where(row)}: time stamp {quote(text)} {why}")


def seconds_from(texts, origin, unit_s):
    """The time column's cells as seconds from the first stamp ``origin`` (text): the exact decimal
    offsets (:class:`Stamps`) scaled exactly, then rounded once to a float, so that a stamp
    39966971 ns after the first is written 0.039966971, not 0.039966971000000004."""
    scale = decimal.Decimal(repr(unit_s))
    first = decimal.Decimal(origin)
    return np.array([float((decimal.Decimal(t) - first) * scale) for t in texts])


def infer_time_unit(steps, path, name, sample_rate_hz=None):
    """(The time unit of stamps whose steps are ``steps``, how it was found, in words): the one in which their median means ``sample_rate_hz`` (the
    caller's, None: not given) within RATE_TOLERANCE, else the first in which it means MIN_INFERRED_RATE_HZ or more;
    refused where another unit means a rate a gyro may log at too, 1 Hz to :data:`FASTEST_GYRO_HZ` (within
    RATE_TOLERANCE: 32 kHz stamped in whole us steps by 31) (steps of 1: 1 Hz in s or 1 kHz in ms, a 1 Hz log written
    at 1000 Hz, attack pass 59; steps of 125: 8 Hz in ms or the MPU6050's 8 kHz in us, pass 60)."""
    median = float(np.median(steps))
    rates = {unit: 1.0 / (median * seconds) for unit, seconds in TIME_UNITS.items()} if median > 0 else {}
    given = [unit for unit, rate in rates.items() if sample_rate_hz and abs(rate - sample_rate_hz) <= RATE_TOLERANCE * sample_rate_hz]
    if len(given) == 1:
        return given[0], "inferred: the unit giving --sample-rate-hz; --time-unit to say otherwise"
    unit = next((unit for unit, rate in rates.items() if rate >= MIN_INFERRED_RATE_HZ), None)
    if unit is None:
        raise RecordingError(f"{path}: the time column {quote(name)} does not step forward; give --time-unit or --sample-rate-hz")
    both = [other for other, rate in rates.items() if other == unit or 1.0 <= rate <= FASTEST_GYRO_HZ * (1 + RATE_TOLERANCE)]
    if len(both) > 1:
        settle = (" (or --sample-rate-hz)" if not sample_rate_hz else
                  f" (--sample-rate-hz {sample_rate_hz:g} is neither: is it right?)")  # attack pass 62
        raise RecordingError(f"{path}: the time column {quote(name)} steps by {median:g}: "
                             + " or ".join(f"{rates[u]:g} Hz in {u}" for u in both) + f"; give --time-unit {' or '.join(both)}"
                             + settle)
    return unit, f"inferred: the first unit giving {MIN_INFERRED_RATE_HZ:g} Hz or more; --time-unit to say otherwise"
