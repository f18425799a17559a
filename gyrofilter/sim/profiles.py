"""Synthetic angular-rate profiles for dynamic tests (truth to add to real static noise).

Every profile starts with at least 10 s at rest (the start-up calibration needs the sensor
still) and is a function of time only, so the truth can be evaluated at any instant, also shifted
(the lag estimate of :mod:`gyrofilter.evaluation.metrics` uses that). Rates in deg/s on one axis; the
dynamic test adds the same profile to each axis of a real static recording.

``paper001`` is the dynamic test of paper 001 (its section 5) exactly as
issue 2 item 6 states it, 90 s:

    w(t) = 0                                 0  <= t < 10
           20 (t - 10) / 10                  10 <= t < 20     (ramp 0 -> 20 deg/s)
           20                                20 <= t < 30
           20 + 10 sin(2 pi 0.2 (t - 30))    30 <= t < 60
           20                                60 <= t < 70
           20 - 20 (t - 70) / 10             70 <= t < 80     (ramp 20 -> 0)
           0                                 80 <= t <= 90

``sine_1hz`` (faster sine), ``steps`` (rate steps: infinite angular acceleration) and
``chirp`` (0.1 -> 2 Hz sweep) are the additional profiles; their equations are in their
docstrings. Each profile lists its *segments*, the time windows where the rate changes, over
which lags are measured.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..errors import SettingsError
from ..units import check_sample_rate_hz


@dataclass(frozen=True)
class Profile:
    """A synthetic rate profile: ``rate_dps(t_s)`` for an array of times (s)."""

    name: str
    duration_s: float
    rate_fn: Callable
    # ((t0_s, t1_s, label, max_lag_s), ...): where the rate changes, and the largest lag that is
    # unambiguous there (under half the period of a periodic segment)
    segments: tuple = field(default_factory=tuple)
    description: str = ""

    def rate_dps(self, t_s):
        """Truth in deg/s at times ``t_s`` (array); 0 outside [0, duration_s]."""
        t = np.asarray(t_s, dtype=float)
        out = np.asarray(self.rate_fn(t), dtype=float)
        return np.where((t >= 0) & (t <= self.duration_s), out, 0.0)


def _paper001(t):
    t = np.asarray(t, dtype=float)
    return np.select(
        [t < 10, t < 20, t < 30, t < 60, t < 70, t < 80],
        [0.0 * t, 2.0 * (t - 10.0), 20.0 + 0.0 * t, 20.0 + 10.0 * np.sin(2 * math.pi * 0.2 * (t - 30.0)), 20.0 + 0.0 * t, 20.0 - 2.0 * (t - 70.0)],
        default=0.0 * t,
    )


def _sine_1hz(t):
    """0 for t < 10 s; 30 sin(2 pi 1.0 (t - 10)) for 10 <= t < 80; 0 after (90 s)."""
    t = np.asarray(t, dtype=float)
    return np.where((t >= 10) & (t < 80), 30.0 * np.sin(2 * math.pi * 1.0 * (t - 10.0)), 0.0)


_STEP_TIMES_S = (10.0, 20.0, 30.0, 45.0, 60.0, 70.0, 80.0)
_STEP_LEVELS_DPS = (20.0, 0.0, -30.0, 10.0, 0.0, 50.0, 0.0)


def _steps(t):
    """Piecewise constant: 0, then at t = 10, 20, 30, 45, 60, 70, 80 s the rate jumps to
    20, 0, -30, 10, 0, 50, 0 deg/s (90 s)."""
    t = np.asarray(t, dtype=float)
    out = np.zeros_like(t)
    for t0, level in zip(_STEP_TIMES_S, _STEP_LEVELS_DPS):
        out = np.where(t >= t0, level, out)
    return out


def _chirp(t):
    """Linear chirp 20 sin(2 pi (f0 tau + (f1 - f0) tau^2 / (2 T))), tau = t - 10, f0 = 0.1 Hz,
    f1 = 2 Hz, T = 70 s, for 10 <= t < 80 s; 0 otherwise (90 s)."""
    t = np.asarray(t, dtype=float)
    tau = t - 10.0
    phase = 2 * math.pi * (0.1 * tau + (2.0 - 0.1) * tau**2 / (2 * 70.0))
    return np.where((t >= 10) & (t < 80), 20.0 * np.sin(phase), 0.0)


PROFILES = {
    "paper001": Profile(
        "paper001", 90.0, _paper001,
        ((10.0, 20.0, "ramp up", 3.0), (30.0, 60.0, "sine 0.2 Hz", 2.0), (70.0, 80.0, "ramp down", 3.0)),
        "paper 001 / issue 2 item 6: ramps 0->20->0 deg/s, 0.2 Hz +-10 deg/s sine on 20 deg/s",
    ),
    "sine_1hz": Profile(
        "sine_1hz", 90.0, _sine_1hz, ((10.0, 80.0, "sine 1 Hz", 0.45),),
        "30 deg/s peak sine at 1 Hz from 10 to 80 s",
    ),
    "steps": Profile(
        "steps", 90.0, _steps,
        tuple((t0 - 1.0, t0 + 2.0, f"step to {lv:g}", 3.0) for t0, lv in zip(_STEP_TIMES_S, _STEP_LEVELS_DPS)),
        "rate steps 0, 20, 0, -30, 10, 0, 50, 0 deg/s at 10, 20, 30, 45, 60, 70, 80 s",
    ),
    "chirp": Profile(
        "chirp", 90.0, _chirp, ((10.0, 45.0, "chirp 0.1-1 Hz", 0.45), (45.0, 80.0, "chirp 1-2 Hz", 0.22)),
        "20 deg/s peak linear chirp 0.1 -> 2 Hz from 10 to 80 s",
    ),
}


def get_profile(name) -> Profile:
    """The profile called ``name`` (one of :data:`PROFILES`)."""
    try:
        return PROFILES[name]
    except KeyError:
        raise SettingsError(f"unknown profile {name!r}; expected one of {', '.join(PROFILES)}") from None


def profile_samples_dps(profile, sample_rate_hz, duration_s=None):
    """The truth sampled at t_i = i / fs, i = 0 .. N-1, N = round(duration * fs): (t_s, rate_dps).

    ``profile``: a :class:`Profile` or the name of one (:data:`PROFILES`); ``sample_rate_hz``: fs
    (Hz); ``duration_s``: the duration (s), default the profile's.
    """
    if isinstance(profile, str):
        profile = get_profile(profile)
    sample_rate_hz = check_sample_rate_hz(sample_rate_hz)
    duration_s = profile.duration_s if duration_s is None else float(duration_s)
    n = int(round(duration_s * sample_rate_hz))
    t_s = np.arange(n) / sample_rate_hz
    return t_s, profile.rate_dps(t_s)
