"""Gross errors of a gyro record: samples that are no noise or drift (spikes far beyond the noise,
rates beyond any MEMS full scale), which an Allan analysis refuses before it fits
(:func:`gross_errors`).
"""
from __future__ import annotations

import numpy as np

from ..stats import robust_sigma
from ...units import MAX_RATE_DPS

#: a rate beyond this (deg/s) is no gyro reading (units.MAX_RATE_DPS)
GROSS_LIMIT_DPS = MAX_RATE_DPS
#: gross-error threshold on the second-difference residual, in its robust sigmas; the still
#: MPU6050 recordings in recordings/ and simulated hours at 100 Hz and 1 kHz reach 6 at most
GROSS_Z = 50.0
_GROSS_BLOCK = 1 << 16


#: fewest samples whose spikes are judged against the robust sigma of their residuals (with 3, the
#: one residual's sigma is 0 and every sample read as a gross error)
MIN_SCREENED = 16


def gross_errors(x_dps, *, z=GROSS_Z, limit_dps=GROSS_LIMIT_DPS):
    """Indices of the samples of ``x_dps`` (deg/s) that are gross errors rather than noise or drift.

    A sample is one when ``|x_i| > limit_dps`` (beyond any MEMS full scale), or when its
    second-difference residual ``r_i = x_i - (x_{i-1} + x_{i+1}) / 2`` (``x_0 - x_1`` and
    ``x_{N-1} - x_{N-2}`` at the ends) exceeds ``z`` robust sigmas of ``r``
    (:func:`gyrofilter.analysis.gap.detectors.robust_sigma`, 1.4826 MAD) and ``|r_i|`` is not smaller than its
    neighbours' (a spike moves their residuals by half its size, so of two spikes side by side only
    the larger may be found), and neither neighbour is beyond ``limit_dps``. A bias drift, smooth over three samples, leaves ``r`` alone, so only
    isolated jumps count; sensor motion does show up. The
    residuals are formed in blocks, so the extra memory does not grow with the series.
    """
    x = np.asarray(x_dps, dtype=np.float64)
    n = x.size
    with np.errstate(over="ignore", invalid="ignore"):
        if n < MIN_SCREENED:  # too few residuals for a robust sigma: only the absolute limit applies
            return np.flatnonzero(~(np.abs(x) <= limit_dps))
        threshold = z * residual_sigma(x)
        found = []
        for start in range(0, n, _GROSS_BLOCK):
            stop = min(n, start + _GROSS_BLOCK)
            lo, hi = max(0, start - 2), min(n, stop + 2)  # residuals of start-1 .. stop need x[start-2 .. stop+1]
            seg = x[lo:hi]
            r = np.empty(seg.size)
            r[1:-1] = seg[1:-1] - 0.5 * (seg[:-2] + seg[2:])
            r[0] = seg[0] - seg[1] if lo == 0 else np.nan
            r[-1] = seg[-1] - seg[-2] if hi == n else np.nan
            a = np.abs(r)
            i = np.arange(start, stop) - lo  # positions of this block's samples in seg
            left = np.where(i > 0, a[np.maximum(i - 1, 0)], 0.0)
            right = np.where(i < seg.size - 1, a[np.minimum(i + 1, seg.size - 1)], 0.0)
            spike = (a[i] > threshold) & ~(a[i] < left) & ~(a[i] < right)
            absurd = ~(np.abs(seg) <= limit_dps)
            # a neighbour of an absurd sample has a huge residual of its own: not a spike for that
            beside = absurd[np.maximum(i - 1, 0)] | absurd[np.minimum(i + 1, seg.size - 1)]
            found.append(np.flatnonzero(absurd[i] | (spike & ~beside)) + start)
    return np.concatenate(found)


def residual_sigma(x_dps):
    """The robust sigma (1.4826 MAD, :func:`~gyrofilter.analysis.stats.robust_sigma`) of the
    second-difference residual ``r_i = x_i - (x_{i-1} + x_{i+1}) / 2`` of ``x_dps`` (at least 3
    samples), over an evenly strided subsample of about 100 000 residuals: the scale
    :func:`gross_errors` judges spikes against (white noise of sigma gives sqrt(1.5) sigma)."""
    x = np.asarray(x_dps, dtype=np.float64)
    mid = np.arange(1, x.size - 1, max(1, x.size // 100_000))
    with np.errstate(over="ignore", invalid="ignore"):
        return robust_sigma(x[mid] - 0.5 * (x[mid - 1] + x[mid + 1]))


def gross_and_beside(x_dps):
    """The indices (sorted) of the spikes of ``x_dps`` and the two samples on either side of each: the
    samples of :func:`gross_errors` beyond ``GROSS_Z`` robust sigmas of the second-difference residual,
    whatever their size, in any unit (no absolute limit: a whole record beyond a full scale is a
    unit's mistake, not a spike). Of two spikes side by side the screen finds one sample of four
    whose residuals are alike (the pair's and their neighbours', half a spike each); whichever it is,
    the pair lies within two samples of it. What the stillness check
    (:func:`gyrofilter.analysis.still.not_static`) and the gap analysis' high pass
    (:func:`gyrofilter.analysis.gap.detectors.tails.tail_residual`) leave out, so that one spike
    moves neither a block's mean nor a moving mean's W samples."""
    x = np.asarray(x_dps, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        gross = gross_errors(x, limit_dps=np.inf)
    return np.unique(np.clip(np.r_[gross - 2, gross - 1, gross, gross + 1, gross + 2], 0, max(x.size - 1, 0)))
