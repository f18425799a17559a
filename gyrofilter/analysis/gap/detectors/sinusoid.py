"""Detector 2, ``sinusoid``: a line in the periodogram (see :mod:`gyrofilter.analysis.gap.detectors`)."""

from __future__ import annotations

import cmath
import functools
import math

import numpy as np

from ....effects import SINUSOID
from .common import Candidate, SINUSOID_ALPHA
from ...stats import detrend_line, dot, golden_max, robust_sigma


# ---------------------------------------------------------------------------------------------
# 2. sinusoid


def _band_levels(power, first_bin, ratio=1.1, min_bins=16):
    """Local noise level of a periodogram, at its nodes: the median over log-spaced bands (width
    ratio 1.1, at least 16 bins) / ln 2, ``(log of the band centres, log of the levels)``;
    :func:`_level_at` interpolates them in log-log (bins below the first centre get the first
    band's level, above the last the last's). Each band's median comes from a partial sort
    (``numpy.partition``) of a copy of that band alone: linear time."""
    n = power.size
    edges = [first_bin]
    while edges[-1] < n:
        nxt = max(edges[-1] + min_bins, int(edges[-1] * ratio))
        edges.append(min(nxt, n))
    if len(edges) > 2 and edges[-1] - edges[-2] < min_bins:
        edges.pop(-2)
    edges = np.asarray(edges)
    med = np.empty(edges.size - 1)
    for band, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
        mid = [(hi - lo - 1) // 2, (hi - lo) // 2]
        part = np.partition(power[lo:hi], mid)
        med[band] = 0.5 * (max(float(part[mid[0]]), 1e-300) + max(float(part[mid[1]]), 1e-300))
    centres = 0.5 * (edges[:-1] + edges[1:] - 1)
    return np.log(np.maximum(centres, 1.0)), np.log(np.maximum(med / math.log(2.0), 1e-300))


def _level_at(bins, nodes):
    """The local level (:func:`_band_levels`' ``nodes``) at ``bins`` (an array of bin indices)."""
    return np.exp(np.interp(np.log(np.maximum(bins.astype(float), 1.0)), *nodes))


def _peak_ratio(power, first_bin, nyquist=False):
    """``(max_j power_j / level_j, j)`` over bins ``first_bin .. N - 1`` (the first of equal
    maxima; ``(0, 0)`` where every ratio is 0), the last bin's ratio halved with ``nyquist``
    (an even record: the last bin is f_s / 2, whose ordinate is chi-squared with one degree of
    freedom, not two: P(ratio / 2 > t) = erfc(sqrt t) <= exp(-t), the other bins' tail, so the
    threshold holds for it too). The last bin was not searched: a line at f_s / 2, the sequence
    a, -a, a, ..., went to the narrow-band detector, D after 30 to 66. The level of :func:`_level_at`, without the level
    at every bin: between two nodes the level is monotone (a line in log-log; constant beyond the
    end nodes), so a stretch's largest ratio is at most its largest power over the smaller level
    at its two ends. The stretches are searched in the order of that bound, the exact ratios
    computed only where the bound is not below the best found (a few stretches of the millions
    of bins of a long record)."""
    nodes = _band_levels(power, first_bin)
    last = power.size - 1  # the last bin, searched on its own below
    inner = np.ceil(np.exp(nodes[0])).astype(np.int64)
    starts = np.unique(np.clip(np.concatenate(([first_bin], inner)), first_bin, last))
    starts = starts[starts < last]
    ends = np.append(starts[1:], last)
    peaks = np.maximum.reduceat(power[first_bin:last], starts - first_bin)
    level_lo, level_hi = _level_at(starts, nodes), _level_at(ends - 1, nodes)
    bound = peaks / np.minimum(level_lo, level_hi)
    best, best_j = -math.inf, -1
    for k in np.argsort(-bound, kind="stable"):
        if bound[k] < best:
            break
        lo, hi = int(starts[k]), int(ends[k])
        r = power[lo:hi] / _level_at(np.arange(lo, hi), nodes)
        i = int(np.argmax(r))
        if r[i] > best or (r[i] == best and lo + i < best_j):
            best, best_j = float(r[i]), lo + i
    if last >= first_bin:
        r = float(power[last] / _level_at(np.array([last]), nodes)[0]) / (2.0 if nyquist else 1.0)
        if r > best:
            best, best_j = r, last
    return (best, best_j) if best > 0 else (0.0, 0)  # no power: as argmax over all-zero ratios


#: samples per pass of :func:`least_squares` and :func:`fitted`: the columns of a fit are made a
#: piece at a time, so a fit of a day at 100 Hz needs a few MB besides the record
CHUNK_SAMPLES = 1 << 16


def least_squares(columns, x):
    """Coefficients of the least-squares fit of ``x`` by the given columns (and a constant,
    the last coefficient), from the normal equations ``G beta = A^T x`` with the Gram matrix
    ``G = A^T A`` summed by :func:`dot` (no N-row BLAS / LAPACK call; well conditioned for the
    few smooth columns used here). ``columns(lo, hi)`` returns the columns' values at samples
    ``lo .. hi - 1``; they are made and summed :data:`CHUNK_SAMPLES` at a time."""
    n = x.size
    gram = rhs = None
    for lo in range(0, n, CHUNK_SAMPLES):
        hi = min(n, lo + CHUNK_SAMPLES)
        cols = list(columns(lo, hi))
        xs = x[lo:hi]
        if gram is None:
            k = len(cols) + 1
            gram, rhs = np.zeros((k, k)), np.zeros(k)
        for i, ci in enumerate(cols):
            for j in range(i, len(cols)):
                gram[i, j] += dot(ci, cols[j])
            gram[i, -1] += ci.sum()
            rhs[i] += dot(ci, xs)
        rhs[-1] += xs.sum()
    gram[-1, -1] = n
    gram = np.triu(gram) + np.triu(gram, 1).T
    return np.linalg.solve(gram, rhs)


def fitted(columns, coef, n):
    """``sum_k coef_k column_k`` at samples ``0 .. n - 1`` (the fit without its constant), the
    columns made :data:`CHUNK_SAMPLES` at a time by ``columns(lo, hi)`` as in :func:`least_squares`."""
    out = np.empty(n)
    for lo in range(0, n, CHUNK_SAMPLES):
        hi = min(n, lo + CHUNK_SAMPLES)
        part = out[lo:hi]
        part[:] = 0.0
        for c, col in zip(coef, columns(lo, hi)):
            part += c * col
    return out


def _sine_columns(sample_rate_hz, f_hz):
    """Columns ``cos(2 pi f n / f_s)`` and ``sin(2 pi f n / f_s)`` at samples ``lo .. hi - 1``
    (at most :data:`CHUNK_SAMPLES` of them), the real and imaginary parts of :func:`phasors`;
    at ``f = f_s / 2`` the cosine alone, ``(-1)^n`` (the sine is 0 at every sample)."""
    k = 2 * math.pi * f_hz / sample_rate_hz
    table = phasors(k, CHUNK_SAMPLES)

    def columns(lo, hi):
        p = table[:hi - lo] * cmath.exp(1j * k * lo)
        return (p.real,) if 2 * f_hz == sample_rate_hz else (p.real, p.imag)
    return columns


def phasors(k, count):
    """``exp(i k s)``, s = 0 .. count - 1: a table whose product with the number
    ``exp(i k lo)`` is ``exp(i k n)`` at samples ``n = lo .. lo + count - 1``, one complex product
    per sample in place of a cosine and a sine (the angle ``k n`` rounded as ``k lo`` and
    ``k s`` are: 1e-16 of it, as when it is formed whole)."""
    return np.exp(1j * k * np.arange(count))


def sinusoid_fit(x, sample_rate_hz, f_hz):
    """Least-squares ``a cos(2 pi f t) + b sin(2 pi f t) + c``; returns (amplitude, phase, fit).
    At ``f = f_s / 2``, ``b = 0`` (:func:`_sine_columns`): ``a (-1)^n = |a| sin(pi n + phase)``
    with phase ``+-pi / 2``."""
    columns = _sine_columns(sample_rate_hz, f_hz)
    coef = least_squares(columns, x)
    a, b = coef[0], (coef[1] if coef.size == 3 else 0.0)
    amp = math.hypot(a, b)
    phase = math.atan2(a, b)  # amp sin(w + phase)
    return amp, phase, fitted(columns, coef[:-1], x.size)


#: a line refined to within this fraction of a bin of f_s / 2 is at f_s / 2 (:func:`line_frequency`)
NYQUIST_SNAP_BINS = 0.01


def line_frequency(x, sample_rate_hz, f0_hz):
    """The frequency of the line whose periodogram peak is at ``f0_hz``: the largest
    :func:`dft_amplitude` within a bin of it (golden section, 30 steps), and ``f_s / 2`` itself
    when that lies within :data:`NYQUIST_SNAP_BINS` of a bin of it (a line at Nyquist is the
    sequence ``a (-1)^n``; its DFT amplitude falls on either side only, so the search ends a
    hair below, where the sine column is a hair above 0 and the fit ill-conditioned)."""
    nyquist = sample_rate_hz / 2
    df = sample_rate_hz / periodogram_length(x.size)
    lo, hi = max(f0_hz - df, df), min(f0_hz + df, nyquist)
    f_hz = golden_max(dft_amplitude(x, sample_rate_hz, f0_hz, float(x.mean())), lo, hi, 30)
    return nyquist if nyquist - f_hz < NYQUIST_SNAP_BINS * df else f_hz


@functools.lru_cache(maxsize=64)
def periodogram_length(n):
    """The number of samples the periodogram uses: the largest ``N' <= n`` whose prime factors
    are all at most 11, the radices numpy's FFT (pocketfft) runs natively. A length with a
    large prime factor goes through Bluestein's algorithm, measured 24 times slower (333 269
    samples: 350 ms, 332 750 = 2 5^3 11^3: 15 ms, machine loaded); dropping the last ``n - N'`` samples costs at most 1.6 %
    of the record from 10^4 samples on (0.8 % from 10^5, 3.8 % at 256)."""
    best = 1
    p11 = 1
    while p11 <= n:
        p7 = p11
        while p7 <= n:
            p5 = p7
            while p5 <= n:
                p3 = p5
                while p3 <= n:
                    best = max(best, p3 << ((n // p3).bit_length() - 1))
                    p3 *= 3
                p5 *= 5
            p7 *= 7
        p11 *= 11
    return best


def periodogram(x, overwrite=False):
    """The periodogram ``|rfft(r)|^2 / N`` of ``r`` = the first ``N`` = :func:`periodogram_length`
    samples of ``x``, detrended (:func:`detrend_line`), bins ``0 .. N / 2``. ``overwrite``: ``x``
    may be used as the work space (its values are lost).

    Memory: for even ``N`` the only N-sample array besides the result is ``r`` (``x`` itself
    with ``overwrite``): ``r`` is read as ``N / 2`` complex numbers ``z_j = r_2j + i r_2j+1``,
    transformed in place by the four-step FFT (Bailey 1990: ``N / 2 = R C``; ``R``-point FFTs of
    the columns, twiddles ``exp(-2 pi i k1 j2 / (N / 2))``, ``C``-point FFTs of the rows, a
    block of columns or rows at a time), and unpacked to the real transform,
    ``X_k = (Z_k + conj Z_{N/2-k}) / 2 - i exp(-2 pi i k / N) (Z_k - conj Z_{N/2-k}) / 2``
    (Press et al., Numerical Recipes, sec. 12.3). numpy's ``rfft`` of the same series needs
    three N-sample buffers more (measured: 198 MB for a day at 100 Hz); the two agree to
    rounding (1e-12 relative). Odd ``N``: ``numpy.fft.rfft``."""
    n = periodogram_length(x.size)
    r = detrend_line(x[:n], out=x[:n] if overwrite and x.flags.c_contiguous else None)
    if n % 2 or n < 1024:
        f = np.fft.rfft(r)
        spec = np.square(f.real)
        spec += np.square(f.imag)
        spec /= n
        return spec
    z = r.view(np.complex128)
    _four_step_fft(z)
    return _real_power(z, n)


def _four_step_fft(z):
    """``z`` replaced by its DFT, stored transposed: ``Z[k1 + R k2]`` at ``z[k1 C + k2]``
    (``len(z) = R C``, ``R`` = :func:`_four_step_rows`)."""
    size = z.size
    rows = _four_step_rows(size)
    cols = size // rows
    a = z.reshape(rows, cols)
    step = max(1, CHUNK_SAMPLES // rows)
    for c0 in range(0, cols, step):  # R-point FFTs of the columns, a block of columns at a time
        a[:, c0:c0 + step] = np.fft.fft(a[:, c0:c0 + step], axis=0)
    step = max(1, CHUNK_SAMPLES // cols)
    for r0 in range(0, rows, step):  # twiddles exp(-2 pi i k1 j2 / size), then C-point FFTs of the rows
        k1 = np.arange(r0, min(rows, r0 + step), dtype=np.int64)
        block = a[r0:r0 + k1.size]
        block *= _unit_outer(k1, cols, size)
        a[r0:r0 + k1.size] = np.fft.fft(block, axis=1)


def _unit_outer(k, count, size, split=64):
    """``exp(-2 pi i (k_a j mod size) / size)`` for ``j = 0 .. count - 1``, a (len k, count)
    array, from two small tables: ``j = q split + r``, the factor of ``k q split`` times that of
    ``k r`` (one complex product per element instead of an exponential; rounding 1e-16)."""
    k = k[:, None]
    coarse = np.exp((-2j * math.pi / size) * ((k * (np.arange(-(-count // split)) * split)) % size))
    fine = np.exp((-2j * math.pi / size) * ((k * np.arange(split)) % size))
    return (coarse[:, :, None] * fine[:, None, :]).reshape(k.size, -1)[:, :count]


def _real_power(z, n):
    """``|X_k|^2 / n``, k = 0 .. n / 2, of the real series whose packed complex transform
    :func:`_four_step_fft` left in ``z`` (the unpacking of :func:`periodogram`), a block of
    stored rows at a time into two preallocated buffers: row ``k1`` holds ``Z_k``,
    ``k = k1 + R k2``, and its partners ``Z_{N/2-k}`` are row ``R - k1`` reversed (row 0:
    itself, reversed and shifted by one), so a block's partners are a view of the array."""
    half = n // 2
    rows = _four_step_rows(half)
    cols = half // rows
    a = z.reshape(rows, cols)
    spec = np.empty(half + 1)
    out = spec[:half].reshape(cols, rows)  # out[k2, k1] = spec[k1 + R k2]
    col_factor = np.exp((-2j * math.pi * rows / n) * np.arange(cols))
    step = max(1, CHUNK_SAMPLES // cols)
    total = np.empty((step, cols), dtype=complex)
    diff = np.empty((step, cols), dtype=complex)
    power = np.empty((step, cols))
    for r0 in range(0, rows, step):
        r1 = min(rows, r0 + step)
        size = r1 - r0
        zk, zs, zd, pw = a[r0:r1], total[:size], diff[:size], power[:size]
        if r0 == 0:
            np.conjugate(a[(rows - np.arange(size)) % rows, ::-1], out=zs)
            zs[0] = np.roll(zs[0], 1)
        else:
            np.conjugate(a[rows - r1 + 1:rows - r0 + 1][::-1, ::-1], out=zs)
        np.subtract(zk, zs, out=zd)  # Z_k - conj Z_{N/2-k}
        zs += zk  # Z_k + conj Z_{N/2-k}
        zd *= col_factor  # times -i exp(-2 pi i k / n), k = k1 + R k2: a factor per column, then per row
        zd *= (-1j * np.exp((-2j * math.pi / n) * np.arange(r0, r1)))[:, None]
        zs += zd  # 2 X_k
        np.square(zs.real, out=pw)
        pw += np.square(zs.imag)
        out[:, r0:r1] = pw.T
    z0 = a[0, 0]
    spec[half] = (z0.real - z0.imag) ** 2
    spec *= 0.25
    spec[half] *= 4.0
    spec /= n
    return spec


def _four_step_rows(size):
    """``R`` of :func:`_four_step_fft` for a transform of ``size`` points."""
    root = math.isqrt(size)
    return min((d for d in range(1, root + 1) if size % d == 0), key=lambda d: abs(d - root))


def sinusoid_statistic(x, sample_rate_hz, return_spectrum=False, overwrite=False):
    """Largest normalised periodogram ordinate (>= bin 8) and its frequency (Hz).

    Returns ``(stat, f_hz, threshold)`` (plus the periodogram ``|rfft|^2 / N`` of the
    detrended series with ``return_spectrum``); the periodogram is that of the first
    :func:`periodogram_length` samples, detrended (LS line) first (:func:`periodogram`;
    ``overwrite``: ``x`` may be its work space).
    """
    nothing = (0.0, float("nan"), float("inf"))
    if x.size < 64:
        return nothing + (None,) if return_spectrum else nothing
    n = periodogram_length(x.size)
    spec = periodogram(x, overwrite=overwrite)
    first = 8
    if spec.size <= first + 32:
        return nothing + (spec,) if return_spectrum else nothing
    stat, j = _peak_ratio(spec, first, nyquist=n % 2 == 0)
    m = spec.size - first
    threshold = math.log(m / SINUSOID_ALPHA)
    out = (stat, j * sample_rate_hz / n, threshold)
    return out + (spec,) if return_spectrum else out


def detect_sinusoid(x, sample_rate_hz):
    """Sinusoid candidate: frequency refined around the peak, amplitude by least squares."""
    stat, f0, thr = sinusoid_statistic(x, sample_rate_hz)
    if not stat > thr:
        return None
    f_hz = line_frequency(x, sample_rate_hz, f0)
    sigma = robust_sigma(_diff_sample(x)) / math.sqrt(2)
    amplitude, phase, fit = sinusoid_fit(x, sample_rate_hz, f_hz)
    return Candidate(
        effect=SINUSOID,
        params={"frequency_hz": f_hz, "amplitude_dps": amplitude, "phase_rad": phase},
        statistic=stat,
        threshold=thr,
        statistic_name="periodogram peak / local noise level",
        component=fit,
        evidence=(f"spectral line at {f_hz:.4g} Hz, {stat:.0f} times the local noise level of the "
                  f"periodogram (white noise: exceeds {thr:.0f} with probability "
                  f"{SINUSOID_ALPHA:g}); amplitude {amplitude:.3g} deg/s "
                  f"({amplitude / sigma:.2f} noise sd)"),
    )


def _diff_sample(x, max_count=100_000):
    """``np.diff(x)`` as :func:`robust_sigma` samples it (every ``s``-th difference where it
    would subsample), without the N-sample array of all differences."""
    n = x.size - 1
    step = int(math.ceil(n / max_count)) if n > 2 * max_count else 1
    return x[1::step] - x[:-1:step]


#: blocks of the demodulated series in :func:`dft_amplitude`
DFT_BLOCKS = 4096


def dft_amplitude(x, sample_rate_hz, f0, mean=0.0):
    """``|X(f)| = |sum_n x_n exp(-2 pi i f n / f_s)|`` for ``f`` near ``f0``, in O(blocks) per
    call after one O(N) pass.

    With ``z_n = x_n exp(-2 pi i f0 n / f_s)`` (demodulated once) and ``theta = 2 pi (f - f0) /
    f_s``, ``X(f) = sum_b exp(-i theta n_b) sum_s z_{n_b + s} exp(-i theta s)`` over blocks
    starting at ``n_b``; within a block ``exp(-i theta s) = 1 - i theta s - (theta s)^2 / 2 + R``
    with ``|R| <= |theta s|^3 / 6``, so three block moments ``sum z s^k`` (k = 0, 1, 2) give
    ``X(f)`` to a relative ``(2 pi B |f - f0| / f_s)^3 / 6``: below 1e-9 for ``|f - f0|`` of
    one bin (``f_s / N``) and ``B = N / 4096`` samples per block. ``x_n`` is the series less
    ``mean``, taken a pass at a time."""
    n = x.size
    b = max(1, -(-n // DFT_BLOCKS))
    m = -(-n // b)
    s = np.arange(b, dtype=float)
    moments = np.zeros((3, m), dtype=complex)
    step = max(1, (1 << 16) // b) * b  # whole blocks per pass, about 65536 samples: bounded memory
    k = -2 * math.pi * f0 / sample_rate_hz
    table = phasors(k, step)
    for a in range(0, n, step):
        seg = x[a:a + step] - mean
        z = np.zeros(-(-seg.size // b) * b, dtype=complex)
        np.multiply(table[:seg.size], cmath.exp(1j * k * a), out=z[:seg.size])
        z[:seg.size] *= seg
        z = z.reshape(-1, b)
        rows = slice(a // b, a // b + z.shape[0])
        moments[0, rows] = z.sum(axis=1)
        moments[1, rows] = np.einsum("ij,j->i", z, s)
        moments[2, rows] = np.einsum("ij,j->i", z, s * s)
    starts = np.arange(m) * float(b)

    def amp(f):
        theta = 2 * math.pi * (f - f0) / sample_rate_hz
        inner = moments[0] - 1j * theta * moments[1] - 0.5 * theta * theta * moments[2]
        return abs(np.sum(np.exp(-1j * theta * starts) * inner))

    return amp
