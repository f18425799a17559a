"""The slope read-offs of papers 000 and 002: each noise coefficient read from the Allan deviation
at one cluster time.

A region of the curve whose local log-log slope is within ``slope_tolerance`` of the term's
slope defines the line; its point nearest the read-off tau is extended along the slope to the
read-off tau (:func:`read_off`). The interval is the chi-square interval of the point read
(NIST SP 1065 eq. 41).

The two estimates answer different questions. A read-off is the whole curve at one tau, and
every term adds to sigma^2 there, so (up to the curve's own scatter) it is at least the term it
names (e.g. N^2 / tau <= sigma^2(tau) gives N <= sigma(tau) sqrt(tau); 0.44 B^2 <= sigma_min^2).
The fit (:mod:`~gyrofilter.analysis.noise.fit`) separates the terms. So a read-off can give a
number where the fit does not resolve the term: that number is an upper estimate of the term,
not a value of it.
"""
from __future__ import annotations

import numpy as np

from ...effects import BIAS_INSTABILITY
from .model import FLICKER_FLOOR, READ_TAU_S, TERM_SLOPE, TERMS, Coefficient


#: the start of the note of a read-off the curve cannot give (its minimum is 0), which the console
#: shows in its place
NOT_DETERMINED = "not determined"


def local_slopes(tau_s, adev_values, half_window=1):
    """d log sigma / d log tau at each tau of ``tau_s`` (s) for the deviations ``adev_values``, by a least-squares line over +-half_window points
    (read-offs use +-2: five points, half a decade)."""
    lt, ls = np.log(tau_s), np.log(np.maximum(adev_values, 1e-300))
    n = lt.size
    out = np.full(n, np.nan)
    for i in range(n):
        lo, hi = max(0, i - half_window), min(n, i + half_window + 1)
        if hi - lo >= 2:
            out[i] = np.polyfit(lt[lo:hi], ls[lo:hi], 1)[0]
    return out


def _runs(indices, min_run):
    """The indices that belong to runs of at least ``min_run`` consecutive integers."""
    if indices.size == 0:
        return indices
    breaks = np.flatnonzero(np.diff(indices) != 1) + 1
    keep = [run for run in np.split(indices, breaks) if run.size >= min_run]
    return np.concatenate(keep) if keep else indices[:0]


def read_off(tau_s, adev_values, ci_low, ci_high, used, *, slope_tolerance=0.15, min_run=3, unit="deg/s"):
    """Coefficients read from the slopes of the Allan deviation (papers 000 and 002).

    ``tau_s`` (s), ``adev_values`` and its interval ``ci_low``, ``ci_high`` (deg/s): the curve;
    ``used``: the taus with enough clusters; ``unit``: the deviation's (the notes name it: an
    accelerometer's m/s^2).

    Q, N, K, R: among the taus (with enough clusters) whose local slope is within
    ``slope_tolerance`` of the term's slope (-1, -1/2, +1/2, +1), the one nearest the read-off
    tau (sqrt(3), 1, 3, sqrt(2) s) is moved along that slope to the read-off tau (a region is
    ``min_run`` or more consecutive taus, so that one noisy point at a long tau is not a region):
    ``c = sigma(tau_i) (tau_read / tau_i)^slope`` (e.g. N = sigma(tau_i) sqrt(tau_i), paper 002).
    B: the minimum of the curve, if the curve is flat there (slope within the tolerance of 0
    over ``min_run`` consecutive taus),
    divided by 0.664 (paper 000; = sqrt(pi / (2 ln 2)) sigma_min, paper 002); where that minimum
    is 0 (every cluster average equal at that tau: a gyro alternating between two values, at every
    even cluster size) B is :data:`NOT_DETERMINED`, neither a value nor a bound (a bound of 0
    would say there is no bias instability, which an interval of 0 does not show).
    The interval is the chi-square interval of the point used, moved the same way. Each value
    holds the other terms' share of the curve at its tau: an upper estimate of its term
    (module docstring), another estimator than :func:`fit`.
    """
    tau = np.asarray(tau_s, dtype=np.float64)
    dev = np.asarray(adev_values, dtype=np.float64)
    idx_all = np.flatnonzero(used)
    slopes = np.full(tau.size, np.nan)
    slopes[idx_all] = local_slopes(tau[idx_all], dev[idx_all], half_window=2)
    out = {}
    for term in TERMS:
        s = TERM_SLOPE[term]
        if term == BIAS_INSTABILITY:
            if idx_all.size == 0:
                out[term] = Coefficient(term, None, note="no cluster time with enough clusters")
                continue
            i = int(idx_all[np.argmin(dev[idx_all])])
            if not dev[i] > 0.0:
                out[term] = Coefficient(term, None, tau_s=float(tau[i]),
                                        note=f"{NOT_DETERMINED}: the Allan deviation is 0 at tau = {tau[i]:g} s "
                                             "(every cluster average equal there)")
                continue
            flat = _runs(idx_all[np.abs(slopes[idx_all]) <= slope_tolerance], min_run)
            if i not in flat:
                upper = ci_high[i] / FLICKER_FLOOR
                out[term] = Coefficient(term, None, upper=upper, tau_s=float(tau[i]),
                                        note=f"not resolved: no flat minimum (the curve still falls at "
                                             f"tau = {tau[i]:g} s, slope {slopes[i]:+.2f}); B <= {upper:.3g} {unit}")
                continue
            out[term] = Coefficient(term, dev[i] / FLICKER_FLOOR, ci_low[i] / FLICKER_FLOOR,
                                    ci_high[i] / FLICKER_FLOOR, tau_s=float(tau[i]),
                                    note=f"flat minimum at tau = {tau[i]:g} s (local slope {slopes[i]:+.2f}) / 0.664")
            continue
        region = idx_all[np.abs(slopes[idx_all] - s) <= slope_tolerance]
        region = _runs(region, min_run)
        if region.size == 0:
            out[term] = Coefficient(term, None, note=f"not resolved: no region of slope {s:+g} "
                                                     f"({min_run} or more consecutive taus)")
            continue
        t_read = READ_TAU_S[term]
        i = int(region[np.argmin(np.abs(np.log(tau[region] / t_read)))])
        f = (t_read / tau[i]) ** s
        out[term] = Coefficient(term, dev[i] * f, ci_low[i] * f, ci_high[i] * f, tau_s=float(tau[i]),
                                note=f"read at tau = {tau[i]:g} s (local slope {slopes[i]:+.2f})")
    return out
