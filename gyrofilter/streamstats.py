"""Summaries of a series that arrives in chunks, in memory that does not grow with its length.

* :class:`RunningMoments`: count, mean and standard deviation per column. Each chunk's own
  count ``n_b``, mean ``m_b`` and sum of squared deviations ``M2_b`` are merged into the running
  ones (Chan, Golub & LeVeque 1979, the pairwise update)::

      n = n_a + n_b,  d = m_b - m_a,  m = m_a + d n_b / n,  M2 = M2_a + M2_b + d^2 n_a n_b / n

  so no sum of squares is ever formed: a large mean does not cancel the variance. A column
  whose values are all equal (a stuck sensor) has a standard deviation of exactly 0: its
  minimum and maximum are kept, since the rounding of the means (-3.3 is no binary fraction)
  leaves an M2 of about 1e-30 that a ratio of two such standard deviations would read as a
  number (46x).
* :func:`moving_mean`: a centred moving mean, clipped to the series at its ends, in passes of
  :data:`PASS_SAMPLES` (the analyses' high-pass, and the fast noise heavy tails are hidden in).
* :class:`Envelope`: the minimum and maximum of every bucket of ``bucket`` consecutive rows,
  for drawing a long series; when more than ``max_buckets`` buckets exist, neighbouring
  buckets are merged in pairs and ``bucket`` doubles, so it keeps between ``max_buckets / 2``
  and ``max_buckets`` buckets whatever the length, and the band drawn from them contains
  every value.
"""
from __future__ import annotations

import numpy as np

from .units import one_value

#: samples per pass of the chunked series helpers (:func:`moving_mean`, ``analysis.stats.detrend_line``): their
#: temporaries are a few MB whatever the record's length
PASS_SAMPLES = 1 << 16


class RunningMoments:
    """Count, mean and sample standard deviation of the rows added so far (per column of
    ``n_columns``)."""

    def __init__(self, n_columns):
        self.count = 0
        self.mean = np.zeros(n_columns)
        self._m2 = np.zeros(n_columns)
        self._low = np.full(n_columns, np.inf)
        self._high = np.full(n_columns, -np.inf)

    def add(self, rows):
        """Add the rows of an (k, n_columns) array (pairwise update, module docstring)."""
        rows = np.asarray(rows, dtype=float)
        n_b = len(rows)
        if n_b == 0:
            return
        mean_b = rows.mean(axis=0)
        m2_b = ((rows - mean_b) ** 2).sum(axis=0)
        self._low = np.minimum(self._low, rows.min(axis=0))
        self._high = np.maximum(self._high, rows.max(axis=0))
        if self.count == 0:
            self.count, self.mean, self._m2 = n_b, mean_b, m2_b
            return
        n = self.count + n_b
        delta = mean_b - self.mean
        self.mean = self.mean + delta * (n_b / n)
        self._m2 = self._m2 + m2_b + delta ** 2 * (self.count * n_b / n)
        self.count = n

    @property
    def std(self):
        """Sample standard deviation (ddof = 1), exactly 0 where every value is one
        (:func:`~gyrofilter.units.one_value`: the same up to float64 rounding); NaN with fewer than 2 rows."""
        if self.count < 2:
            return np.full_like(self.mean, np.nan)
        return np.where(one_value(self._low, self._high), 0.0, np.sqrt(self._m2 / (self.count - 1)))


class Envelope:
    """Per-bucket minimum and maximum of a long (t, (k, n_columns)) series (module docstring), in
    at most ``max_buckets`` buckets (an even number >= 2)."""

    def __init__(self, n_columns, max_buckets=4000):
        if max_buckets < 2 or max_buckets % 2:
            raise ValueError(f"max_buckets must be an even number >= 2, got {max_buckets!r}")
        self.max_buckets = max_buckets
        self.bucket = 1
        self._t = np.empty(0)      # time of each bucket's first row
        self._lo = np.empty((0, n_columns))
        self._hi = np.empty((0, n_columns))
        self._open = 0             # rows in the last bucket, 0 when it is full

    def add(self, t_s, rows):
        """Add rows (k, n_columns) with times t_s (k,)."""
        rows = np.asarray(rows, dtype=float)
        t_s = np.asarray(t_s, dtype=float)
        while len(rows):
            if self._open:  # fill the open last bucket first
                take = min(self.bucket - self._open, len(rows))
                self._lo[-1] = np.minimum(self._lo[-1], rows[:take].min(axis=0))
                self._hi[-1] = np.maximum(self._hi[-1], rows[:take].max(axis=0))
                self._open = (self._open + take) % self.bucket
                rows, t_s = rows[take:], t_s[take:]
                continue
            whole = len(rows) // self.bucket * self.bucket
            take = whole if whole else len(rows)
            starts = np.arange(0, take, self.bucket)
            self._t = np.concatenate([self._t, t_s[starts]])
            self._lo = np.concatenate([self._lo, np.minimum.reduceat(rows[:take], starts, axis=0)])
            self._hi = np.concatenate([self._hi, np.maximum.reduceat(rows[:take], starts, axis=0)])
            self._open = take % self.bucket
            rows, t_s = rows[take:], t_s[take:]
            while len(self._t) > self.max_buckets:
                self._halve()

    def _halve(self):
        """Merge buckets in pairs (an odd last bucket stays, open unless it was full)."""
        n = len(self._t)
        pairs = n // 2 * 2
        last_full = self._open == 0
        lo, hi = self._lo, self._hi
        self._t = np.concatenate([self._t[:pairs:2], self._t[pairs:]])
        self._lo = np.concatenate([np.minimum(lo[:pairs:2], lo[1:pairs:2]), lo[pairs:]])
        self._hi = np.concatenate([np.maximum(hi[:pairs:2], hi[1:pairs:2]), hi[pairs:]])
        if n % 2:  # the odd bucket holds bucket rows (or fewer): half of a doubled one
            self._open = self.bucket if last_full else self._open
        else:
            self._open = 0 if last_full else self._open + self.bucket
        self.bucket *= 2
        self._open %= self.bucket

    @property
    def t_s(self):
        """Time of each bucket's first row (s)."""
        return self._t

    @property
    def low(self):
        """Per-bucket minimum, (buckets, n_columns)."""
        return self._lo

    @property
    def high(self):
        """Per-bucket maximum, (buckets, n_columns)."""
        return self._hi


def moving_mean(x, window):
    """Centred moving mean with window ``window`` samples: sample ``i`` averages
    ``x[i - W//2 : i - W//2 + W]``, clipped to the series at the edges (shorter windows), from
    differences of cumulative sums made :data:`PASS_SAMPLES` at a time, each pass's sums started
    at 0 (a difference ``c_{j+W} - c_j`` does not need the total before the pass, and its
    rounding is that of the pass's sums, not of the record's), so the only N-sample array is the
    result."""
    window = max(1, int(window))
    n = x.size
    half = window // 2
    if window >= n:
        c = np.concatenate(([0.0], np.cumsum(x)))
        lo = np.clip(np.arange(n) - half, 0, n)
        hi = np.clip(np.arange(n) - half + window, 0, n)
        return (c[hi] - c[lo]) / (hi - lo)
    out = np.empty(n)
    # interior: out[j + half] = (c[j + W] - c[j]) / W for j in [0, n - W], a pass of j at a time,
    # c the sums from the pass's first sample
    last = n - window + 1
    c = np.empty(min(last, PASS_SAMPLES) + window)
    c[0] = 0.0
    for j0 in range(0, last, PASS_SAMPLES):
        j1 = min(last, j0 + PASS_SAMPLES)
        np.cumsum(x[j0:j1 + window - 1], out=c[1:j1 - j0 + window])
        part = out[j0 + half:j1 + half]
        np.subtract(c[window:j1 - j0 + window], c[:j1 - j0], out=part)
        part /= window
    head = np.arange(half)  # i < half: c[i - half + W] / (i - half + W)
    c_head = np.cumsum(x[:window])
    out[:half] = c_head[head - half + window - 1] / (head - half + window)
    i1 = n - window + half + 1  # i >= i1: (c[n] - c[i - half]) / (n - i + half), from the sums of the last samples
    tail = np.arange(i1, n)
    suffix = np.cumsum(x[::-1][:n - i1 + half])[::-1]  # suffix[k] = sum x[i1 - half + k:]
    out[i1:] = suffix[tail - i1] / (n - tail + half)
    return out
