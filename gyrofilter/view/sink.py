"""What ``gyrofilter run`` hands to its outlets (the live view, the UDP stream) and the calls
every outlet has.

An outlet has three methods, called from the run loop's thread:

- ``start(info)``: once, with the run's constants (:class:`RunInfo`), before the first step;
- ``feed(step)``: after every read of the source (:class:`Step`); it returns at once and never
  waits for the network (an outlet that cannot keep up drops what it cannot send, and counts it);
- ``close()``: once, at the end; returns a summary for the user ("" for none).

The arrays of a step belong to the run loop: an outlet that keeps them past ``feed`` copies them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RunInfo:
    """The constants of a run: the SOURCE as given, its sample rate (Hz), the filter's block length
    (samples per row), output rate (Hz) and preset."""

    source: str
    sample_rate_hz: float
    block_len: int
    output_rate_hz: float
    preset: str


@dataclass(frozen=True)
class Step:
    """One read of the source and what the filter made of it.

    ``t_s`` (N,) and ``gyro_dps`` (N, 3): the samples read (sensor clock, s; deg/s, bias not
    removed); ``temp_c`` (N,) their temperatures (deg C) or None; ``rows_t_s`` (M,) and
    ``rows_dps`` (M, 3): the filtered rows this read completed (t = the block's last sample).
    The counters are the run's totals so far: ``samples_in``, ``rows_out`` (filtered rows written),
    ``lost_samples`` (the source's), ``rejected_outliers`` (per axis); ``calibration`` is
    "calibrating", "calibrated" or "loaded" (a saved calibration), ``bias_dps`` the bias removed
    (x, y, z) or None while calibrating.
    """

    t_s: np.ndarray
    gyro_dps: np.ndarray
    temp_c: np.ndarray | None
    rows_t_s: np.ndarray
    rows_dps: np.ndarray
    samples_in: int
    rows_out: int
    lost_samples: int
    rejected_outliers: tuple
    calibration: str
    bias_dps: tuple | None
