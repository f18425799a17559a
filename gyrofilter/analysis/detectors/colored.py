"""Detector 3, ``colored_noise``: the lag-1 autocorrelation of the high-passed noise (see :mod:`gyrofilter.analysis.detectors`)."""

from __future__ import annotations

import math

import numpy as np

from .common import COLORED_MIN_LAG1, COLORED_Z, Candidate, dot, moving_mean


# ---------------------------------------------------------------------------------------------
# 3. colored noise


def colored_window(n, fs):
    """High-pass window (samples) for the lag-1 statistic: 64 samples or 0.5 s."""
    return int(min(max(64, round(0.5 * fs)), max(8, n // 8)))


def lag1_statistic(x, fs):
    """Lag-1 autocorrelation of ``x - moving_mean(x, W)``; white noise: about -1/W."""
    n = x.size
    if n < 32:
        return 0.0, 0
    w = colored_window(n, fs)
    e = moving_mean(x, w)
    np.subtract(x, e, out=e)
    den = float(dot(e, e))
    if den <= 0:
        return 0.0, w
    return float(dot(e[1:], e[:-1]) / den), w


def lag1_from_highpassed(r1, window):
    """Undo the high-pass: for an AR(1) noise of lag-1 ``rho``, removing the moving mean of
    ``W`` samples removes the variance fraction ``c = (1 + rho) / ((1 - rho) W)`` (the
    long-run variance over W) from both the variance and the lag-1 covariance, so
    ``r1 = (rho - c) / (1 - c)``; solved for ``rho`` by fixed-point iteration."""
    rho = r1
    for _ in range(50):
        c = (1 + rho) / (max(1 - rho, 1e-3) * window)
        c = min(c, 0.9)
        new = r1 * (1 - c) + c
        new = float(np.clip(new, -0.99, 0.99))
        if abs(new - rho) < 1e-7:
            break
        rho = new
    return rho


def detect_colored(x, fs):
    """Colored-noise candidate: ``lag1`` from the high-passed r1 (:func:`lag1_from_highpassed`)."""
    r1, w = lag1_statistic(x, fs)
    if w == 0:
        return None
    lag1 = lag1_from_highpassed(r1, w)
    z = lag1 * math.sqrt(x.size)
    if abs(z) < COLORED_Z or abs(lag1) < COLORED_MIN_LAG1:
        return None
    lag1 = float(np.clip(lag1, -0.99, 0.99))
    return Candidate(
        effect="colored_noise",
        params={"lag1": lag1},
        statistic=abs(z),
        threshold=COLORED_Z,
        statistic_name="|lag-1 autocorrelation| in units of 1/sqrt(N)",
        evidence=(f"lag-1 autocorrelation of the noise {lag1:+.3f} (white noise: 0 +- "
                  f"{1 / math.sqrt(x.size):.4f}, so {abs(z):.0f} standard errors away)"),
    )
