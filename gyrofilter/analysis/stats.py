"""Statistics the analysis families share (the gap's detectors, the stillness check, the
gross-error screen): a robust scale, block means, chunked detrending, moving means and running
medians, an exact dot product and a golden-section search. Numbers in, numbers out."""

from __future__ import annotations

import bisect
import math

import numpy as np

from ..streamstats import PASS_SAMPLES, moving_mean  # noqa: F401 (moving_mean: the analyses' name for it)
from ..units import MAD_TO_SIGMA

#: number of blocks the slow-effect detectors and the stillness check work on (at most)
MAX_BLOCKS = 2048


def robust_sigma(x, max_count=100_000):
    """1.4826 MAD (a Gaussian's sigma), falling back to the std when the MAD is 0 (coarse
    quantization); of an evenly strided subsample of about ``max_count`` values when the series is
    more than twice as long."""
    x = np.asarray(x, dtype=float)
    if x.size > 2 * max_count:  # a strided subsample is plenty for a scale estimate
        x = x[:: int(math.ceil(x.size / max_count))]
    med = np.median(x)
    mad = MAD_TO_SIGMA * np.median(np.abs(x - med))
    if mad > 0:
        return float(mad)
    return float(np.std(x))


def golden_max(func, a, b, iterations):
    """Golden-section search for the maximum of a unimodal ``func`` on ``[a, b]``; returns
    the midpoint of the final bracket (Kiefer 1953)."""
    g = (math.sqrt(5) - 1) / 2
    c1, c2 = b - g * (b - a), a + g * (b - a)
    f1, f2 = func(c1), func(c2)
    for _ in range(iterations):
        if f1 > f2:
            b, c2, f2 = c2, c1, f1
            c1 = b - g * (b - a)
            f1 = func(c1)
        else:
            a, c1, f1 = c1, c2, f2
            c2 = a + g * (b - a)
            f2 = func(c2)
    return 0.5 * (a + b)


def dot(a, b):
    """``sum_i a_i b_i`` by numpy's own loop (``einsum``), not BLAS: ``np.dot`` on long vectors
    starts OpenBLAS threads, which spin against other processes on a shared machine (the Allan
    code measured 137 s instead of 6 s for 1 h at 1 kHz with the other core busy)."""
    return np.einsum("i,i->", a, b)




def detrend_line(x, out=None):
    """``x`` minus its least-squares line ``a + s t``, ``t = i - (N - 1) / 2`` (closed form,
    O(N)): ``s = sum t x / sum t^2`` with ``sum t^2 = N (N^2 - 1) / 12``. Into ``out`` (which
    may be ``x`` itself) or a new array. A pass's ``t`` is one table ``0 .. P - 1`` (P =
    :data:`PASS_SAMPLES`) plus the pass's offset, ``sum t x = sum s x_s + (lo - centre) sum x``
    over the pass, so the only N-sample array is the result."""
    n = x.size
    tt = n * (n * n - 1.0) / 12.0
    centre = 0.5 * (n - 1)
    table = np.arange(min(n, PASS_SAMPLES), dtype=float)
    txs = 0.0
    for lo in range(0, n, PASS_SAMPLES):
        part = x[lo:lo + PASS_SAMPLES]
        txs += float(dot(table[:part.size], part)) + (lo - centre) * float(part.sum())
    slope = txs / tt if tt > 0 else 0.0
    mean = float(x.mean())
    out = np.empty(n) if out is None else out
    line = np.empty(table.size)
    for lo in range(0, n, PASS_SAMPLES):
        part = x[lo:lo + PASS_SAMPLES]
        t = line[:part.size]
        np.multiply(table[:part.size], slope, out=t)
        t += mean + slope * (lo - centre)
        np.subtract(part, t, out=out[lo:lo + part.size])
    return out


def window_medians(values, spans):
    """The medians of ``values[lo:hi]`` for each ``(lo, hi)`` of ``spans``, each of odd length
    and neither end moving back from one span to the next (a running median): the middle value
    of a sorted copy of the window, which each span updates by what leaves and enters it
    (bisection, O(log W) comparisons and one move of at most W values per value, where a
    median of each window anew costs O(W) each). The middle of an odd count is one of the
    values, so the result equals ``np.median(values[lo:hi])`` exactly. ``values`` must be
    finite (NaN has no place in the order)."""
    vals = np.asarray(values, dtype=float).tolist()
    window, cur_lo, cur_hi = [], 0, 0
    out = np.empty(len(spans))
    for k, (lo, hi) in enumerate(spans):
        if (hi - lo) % 2 == 0 or lo < cur_lo or hi < cur_hi:
            raise ValueError(f"window_medians: span {k} ({lo}, {hi}) is of even length or moves back")
        if lo >= cur_hi:  # no value in common with the last window
            window = sorted(vals[lo:hi])
        else:
            for v in vals[cur_lo:lo]:
                del window[bisect.bisect_left(window, v)]
            for v in vals[cur_hi:hi]:
                bisect.insort(window, v)
        cur_lo, cur_hi = lo, hi
        out[k] = window[len(window) // 2]
    return out


def block_means(x, max_blocks=MAX_BLOCKS):
    """Means of ``n`` consecutive blocks of ``L = ceil(N / max_blocks)`` samples (a trailing
    partial block is dropped). Returns ``(y, L)``."""
    n_samples = x.size
    length = max(1, int(math.ceil(n_samples / max_blocks)))
    n = n_samples // length
    y = x[: n * length].reshape(n, length).mean(axis=1)
    return y, length


#: samples of the first look of :func:`grid_step` (evenly spread): continuous values are told
#: there without sorting the whole series
GRID_PROBE = 1 << 17
#: how far from a whole number of steps a value may be (in steps: the text's float rounding)
GRID_TOLERANCE = 1e-6
#: fewest distinct values that show a grid
GRID_MIN_VALUES = 3


def grid_step(x, step=None):
    """The step ``q`` of the grid the values of ``x`` sit on, or None: the smallest positive
    difference of its sorted distinct values where every value is a whole multiple k of it (within
    :data:`GRID_TOLERANCE` of a step) and there are at least :data:`GRID_MIN_VALUES` of them
    (returned as the least-squares q of values = k q, 0.05 where one difference reads 0.0499...98);
    with ``step`` given, ``step`` where the values (two or more) are whole multiples of it.
    A quantized sensor stored in deg/s (int16 codes / 131) or rad/s sits on such a grid; a
    continuous series (a float simulation, a fit's output) does not. An offset grid (x0 + k q) is
    not taken: a simulation quantizes to whole multiples of the step."""
    x = np.asarray(x, dtype=float)
    probe = np.unique(x[::max(1, x.size // GRID_PROBE)])
    if probe.size >= GRID_MIN_VALUES and _on_grid(probe, step) is None:
        return None  # off the grid already there: no sort of the whole series
    return _on_grid(np.unique(x), step)


def _on_grid(values, step):
    """:func:`grid_step` of the sorted distinct ``values``."""
    if values.size < (2 if step else GRID_MIN_VALUES):
        return None
    given = step
    step = step or float(np.min(np.diff(values)))
    codes = values / step
    if not np.all(np.abs(codes - np.rint(codes)) <= GRID_TOLERANCE):
        return None
    codes = np.rint(codes)  # the least-squares step of values = codes q: the text's rounding of one difference averaged out
    return given or float(np.dot(values, codes) / np.dot(codes, codes))
