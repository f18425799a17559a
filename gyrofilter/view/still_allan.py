"""The Allan deviation of a run's still stretches so far, in bounded memory: what the live view
shows while the sensor runs.

Input: the raw block means of the run (deg/s; blocks of L samples, ``tau0_s = L / sample_rate_hz``)
and the start-up bias. A block is *still* when every axis is within
:data:`~gyrofilter.analysis.still.STATIC_LIMIT_DPS` of the bias (the block-mean excursion that
``allan`` calls motion). Each run of consecutive still blocks (no lost samples inside, i.e. block
times ``tau0_s`` apart) is a stretch.

Estimate: the *non-overlapping* Allan variance (NIST SP 1065, eq. 7; paper 000 eq. 2) at the
octave cluster times ``tau_k = 2^k tau0_s``, pooled over the stretches::

    sigma^2(tau_k) = sum over stretches and adjacent cluster pairs (ybar_{j+1} - ybar_j)^2 / (2 K_k)

where ``ybar_j`` are the means of consecutive clusters of ``2^k`` blocks counted from each
stretch's start and ``K_k`` is the number of adjacent pairs of all stretches. Within one stretch
this equals :func:`gyrofilter.analysis.noise.allan.adev` of its block means. Cluster means are built
level by level (two of level k make one of level k+1), so the state is a few numbers per level
however long the run. A cluster time is reported once ``K_k`` reaches
:data:`~gyrofilter.analysis.noise.allan.MIN_CLUSTERS`, with paper 000's relative error
``1 / sqrt(2 K_k)`` (:func:`gyrofilter.analysis.noise.allan.simple_interval`).
"""
from __future__ import annotations

import math

import numpy as np

from ..analysis.noise.allan import MIN_CLUSTERS
from ..analysis.still import STATIC_LIMIT_DPS

#: octave levels kept: tau up to 2^29 tau0 (years at 200 blocks per second)
LEVELS = 30
#: block times further apart than this many tau0 are a gap (lost samples): the stretch ends
GAP_FACTOR = 1.5


class StillAllan:
    """Pooled non-overlapping Allan deviation of still stretches; see the module docstring.

    ``tau0_s``: the block time (s). Feed with :meth:`add`; :meth:`result` gives the figures.
    """

    def __init__(self, tau0_s, limit_dps=STATIC_LIMIT_DPS):
        if not tau0_s > 0:
            raise ValueError(f"tau0_s must be > 0, got {tau0_s!r}")
        self.tau0_s = float(tau0_s)
        self.limit_dps = float(limit_dps)
        self._sums = np.zeros((LEVELS, 3))  # sum of squared differences of adjacent cluster means
        self._pairs = np.zeros(LEVELS, dtype=np.int64)
        self._prev = [None] * LEVELS  # the last cluster mean of the current stretch, per level
        self._pending = [None] * LEVELS  # a cluster mean waiting for its partner, per level
        self._open = False  # the last block added was still: the next still one continues its stretch
        self._last_t = None
        self.still_blocks = 0

    @property
    def still_s(self):
        """Seconds of still blocks so far."""
        return self.still_blocks * self.tau0_s

    def cut(self):
        """End the current stretch (blocks were lost before the next one)."""
        self._open = False

    def add(self, t_s, means_dps, bias_dps):
        """Add block means ``means_dps`` (n, 3) (deg/s, bias not removed) ending at ``t_s`` (n,)
        (s, increasing); ``bias_dps``: the start-up bias (x, y, z)."""
        means = np.asarray(means_dps, dtype=float).reshape(-1, 3)
        t = np.asarray(t_s, dtype=float).reshape(-1)
        n = len(means)
        if n == 0:
            return
        still = np.all(np.abs(means - np.asarray(bias_dps, dtype=float)) <= self.limit_dps, axis=1)
        gap = np.empty(n, dtype=bool)
        gap[0] = self._last_t is None or t[0] - self._last_t > GAP_FACTOR * self.tau0_s
        gap[1:] = np.diff(t) > GAP_FACTOR * self.tau0_s
        self._last_t = float(t[-1])
        edges = [0, *(np.flatnonzero(gap[1:] | (still[1:] != still[:-1])) + 1).tolist(), n]
        for a, b in zip(edges[:-1], edges[1:]):
            if not still[a]:
                self._open = False
                continue
            if gap[a] or not self._open:
                self._prev = [None] * LEVELS
                self._pending = [None] * LEVELS
            self._push(means[a:b])
            self._open = True
            self.still_blocks += b - a

    def _push(self, values):
        """Cluster means of level 0 (the blocks) through every level they complete."""
        for k in range(LEVELS):
            if not len(values):
                return
            prev = self._prev[k]
            chain = values if prev is None else np.vstack([prev[None], values])
            d = np.diff(chain, axis=0)
            self._sums[k] += (d * d).sum(axis=0)
            self._pairs[k] += len(d)
            self._prev[k] = values[-1].copy()
            if self._pending[k] is not None:
                values = np.vstack([self._pending[k][None], values])
            whole = len(values) // 2 * 2
            self._pending[k] = values[-1].copy() if len(values) % 2 else None
            values = 0.5 * (values[0:whole:2] + values[1:whole:2])

    def result(self, min_pairs=MIN_CLUSTERS):
        """The figures so far: ``{"tau_s": [...], "adev_dps": [[x, y, z], ...], "pairs": [...],
        "relative_error": [...], "still_s": S}``, one entry per cluster time with at least
        ``min_pairs`` adjacent pairs."""
        keep = np.flatnonzero(self._pairs >= max(min_pairs, 1))
        adev = np.sqrt(self._sums[keep] / (2.0 * self._pairs[keep, None]))
        return {
            "tau_s": [self.tau0_s * 2 ** int(k) for k in keep],
            "adev_dps": adev.tolist(),
            "pairs": self._pairs[keep].tolist(),
            "relative_error": [1.0 / math.sqrt(2.0 * p) for p in self._pairs[keep].tolist()],
            "still_s": self.still_s,
        }
