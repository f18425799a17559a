"""Detector 1, ``outliers``: isolated spikes (see :mod:`gyrofilter.analysis.gap.detectors`)."""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np

from ....effects import OUTLIERS
from .common import Candidate, OUTLIER_FALSE_PER_AXIS, OUTLIER_MIN_COUNT
from ...noise.screen import GROSS_Z
from ...stats import robust_sigma


# ---------------------------------------------------------------------------------------------
# 1. outliers


def outlier_statistic(x, q_dps=0.0):
    """Spike mask and count: ``|x_i - (x_{i-1}+x_{i+1})/2| > k sd`` and a local maximum.

    ``sd`` is the robust sd of the second difference, at least what a quantizer of step ``q_dps``
    puts into it alone, ``sqrt(1.5 / 12) q``: a quiet sensor whose samples sit on one code has a
    robust sd of about 0, and its one-step excursions, the quantizer's, are no spikes (issue 37).
    Returns ``(mask, k, sd_r)``.
    """
    n = x.size
    mask = np.zeros(n, dtype=bool)
    if n < 16:
        return mask, np.inf, 0.0
    a = np.empty(n)
    np.add(x[:-2], x[2:], out=a[1:-1])
    a[1:-1] *= -0.5
    a[1:-1] += x[1:-1]
    a[0] = x[0] - x[1]
    a[-1] = x[-1] - x[-2]
    sd_r = max(robust_sigma(a[1:-1]), math.sqrt(1.5 / 12.0) * q_dps)
    if sd_r <= 0:
        return mask, np.inf, 0.0
    k = NormalDist().inv_cdf(1.0 - 0.5 * OUTLIER_FALSE_PER_AXIS / n)
    np.abs(a, out=a)
    big = np.flatnonzero(a > k * sd_r)
    # a spike at i also moves r at i-1 and i+1 by half its size: keep local maxima only
    left = np.where(big > 0, a[np.maximum(big - 1, 0)], 0.0)
    right = np.where(big < n - 1, a[np.minimum(big + 1, n - 1)], 0.0)
    mask[big[(a[big] >= left) & (a[big] >= right)]] = True
    return mask, k, sd_r


def gross_spikes(x, mask, sd_r):
    """The spikes of ``mask`` (a boolean mask over ``x``) that are gross errors as the screen defines
    them: their second-difference residual beyond :data:`~gyrofilter.analysis.noise.screen.GROSS_Z`
    robust sd ``sd_r`` (:func:`outlier_statistic`'s), which white Gaussian noise never reaches
    (P below 1e-500 a sample), a mask. One such sample is a spike however few there are: ``allan``
    refuses it, ``gap`` names it (a single 40-sigma spike, 33 sd of the residual, stays below: three
    are needed then). The others of fewer than three are the noise's own exceedances. The first and
    last samples' residuals are their difference from their one neighbour (:func:`outlier_statistic`'s,
    the screen's): a start-up read's garbage is a spike too, not a warm-up nor a step at the end."""
    out = np.zeros(mask.size, dtype=bool)
    idx = np.flatnonzero(mask)
    if idx.size and sd_r > 0 and mask.size > 1:
        out[idx[residuals(x, idx) > GROSS_Z * sd_r]] = True
    return out


def residuals(x, idx):
    """``|r_i|`` of the samples ``idx`` of ``x`` (at least two samples): ``x_i - (x_{i-1} + x_{i+1}) / 2``,
    at the first and last sample their difference from their one neighbour (:func:`outlier_statistic`'s)."""
    n = x.size
    before, after = np.where(idx > 0, idx - 1, idx + 1), np.where(idx < n - 1, idx + 1, idx - 1)
    return np.abs(x[idx] - 0.5 * (x[before] + x[after]))


def clean_spikes(x, mask, in_place=False):
    """Replace masked samples by the mean of their neighbours (the median of the next 2 on
    each side that are not masked), in a copy or (``in_place``) in ``x`` itself: the
    replacements read only samples that are not masked."""
    if not mask.any():
        return x
    y = x if in_place else x.copy()
    idx = np.flatnonzero(mask)
    y[idx] = _replacements(x, mask, idx)
    return y


def _replacements(x, mask, idx):
    """The values :func:`clean_spikes` puts at the masked samples ``idx``."""
    n = x.size
    out = np.empty(idx.size)
    for k, i in enumerate(idx):
        nb = [j for j in (i - 2, i - 1, i + 1, i + 2) if 0 <= j < n and not mask[j]]
        out[k] = np.median(x[nb]) if nb else np.median(x)
    return out


#: log-spread of the spike magnitudes assumed when correcting for spikes below the threshold
#: (the simulator's default ``spread_ln``)
OUTLIER_SPREAD_LN = 0.25


def _spike_model(m_dps, sd_r, thr):
    """Detection probability and mean log|r| of detected spikes for spikes
    ``|s| = m exp(0.25 z)`` seen through the second-difference noise ``N(0, sd_r^2)``
    (64 x 64 quantile grid)."""
    q = np.array([NormalDist().inv_cdf((i + 0.5) / 64) for i in range(64)])
    s = m_dps * np.exp(OUTLIER_SPREAD_LN * q)[:, None]
    r = np.abs(s + sd_r * q[None, :])
    det = r > thr
    p = float(det.mean())
    mean_log = float(np.log(r[det]).mean()) if det.any() else -np.inf
    return p, mean_log


def detect_outliers(x, q_dps=0.0):
    """Outlier (spike) candidate (``q_dps``: the recorded unit's step, :func:`outlier_statistic`).

    Spikes of two sizes count, each against its own false alarms: those beyond ``k`` robust sd of
    the second difference where there are at least
    :data:`~gyrofilter.analysis.gap.detectors.common.OUTLIER_MIN_COUNT` of them besides the gross
    errors (white noise: 0.05 expected, so 3 happen by chance at 2e-5 per axis), else only the gross
    errors (:func:`gross_spikes`, beyond ``GROSS_Z`` robust sd: one is a spike, however few; the
    noise's own one or two exceedances beside them would drag the fitted size to theirs). Spikes
    below the threshold used (``k`` or ``GROSS_Z`` robust sd) are missed, so the parameters are
    fitted to the detected ones: the median magnitude ``m`` is the one whose detected spikes
    (``|s| = m exp(0.25 z)`` plus the second-difference noise, thresholded like the data) have the
    observed mean log|r|, and ``rate = count / (N P_detect(m))`` (P_detect floored at 0.2).
    """
    mask, k, sd_r = outlier_statistic(x, q_dps)
    gross = gross_spikes(x, mask, sd_r)
    if int(mask.sum()) - int(gross.sum()) < OUTLIER_MIN_COUNT:  # too few below: only the gross errors
        mask, k = gross, GROSS_Z
        if not mask.any():
            return None, mask
    count = int(mask.sum())
    idx = np.flatnonzero(mask)
    mags = np.abs(x[idx] - _replacements(x, mask, idx))  # the spikes' sizes, as clean_spikes removes them
    thr = k * sd_r
    observed = float(np.mean(np.log(residuals(x, idx))))  # the spikes' |second difference|, ends included
    lo, hi = math.log(0.3 * thr), math.log(max(100 * thr, 10 * float(np.max(mags))))
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if _spike_model(math.exp(mid), sd_r, thr)[1] < observed:
            lo = mid
        else:
            hi = mid
    magnitude = math.exp(0.5 * (lo + hi))
    p_det = max(_spike_model(magnitude, sd_r, thr)[0], 0.2)
    rate = count / x.size / p_det
    expected = OUTLIER_FALSE_PER_AXIS if k < GROSS_Z else 0.0
    cand = Candidate(
        effect=OUTLIERS,
        params={"rate": rate, "magnitude_dps": magnitude},
        statistic=float(count),
        threshold=float(OUTLIER_MIN_COUNT if k < GROSS_Z else 1),
        statistic_name="spikes beyond %.1f robust sd of the second difference" % k,
        evidence=(f"{count} isolated spikes beyond {k:.1f} robust standard deviations of the "
                  f"second difference (white noise expects {expected:g}); median spike "
                  f"{magnitude:.3g} deg/s = {magnitude / (sd_r / math.sqrt(1.5)):.1f} noise sd "
                  f"(corrected for the {100 * (1 - p_det):.0f} % of spikes below the threshold)"),
    )
    return cand, mask
