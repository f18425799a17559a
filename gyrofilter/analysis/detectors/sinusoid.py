"""Detector 2, ``sinusoid``: a line in the periodogram (see :mod:`gyrofilter.analysis.detectors`)."""

from __future__ import annotations

import functools
import math

import numpy as np

from .common import Candidate, SINUSOID_ALPHA, detrend_line, dot, golden_max, robust_sigma


# ---------------------------------------------------------------------------------------------
# 2. sinusoid


def _local_level(power, first_bin, ratio=1.1, min_bins=16):
    """Local noise level of a periodogram: median over log-spaced bands (width ratio 1.1,
    at least 16 bins) / ln 2, interpolated in log-log. Bins below ``first_bin`` get the first
    band's level. The band medians come from one sort (no Python loop over bands)."""
    n = power.size
    edges = [first_bin]
    while edges[-1] < n:
        nxt = max(edges[-1] + min_bins, int(edges[-1] * ratio))
        edges.append(min(nxt, n))
    if len(edges) > 2 and edges[-1] - edges[-2] < min_bins:
        edges.pop(-2)
    edges = np.asarray(edges)
    # one sort of "band index + power / scale" orders the bins by band, then by power
    # (log power scaled into [0, 1), so that a strong line does not eat the precision);
    # computed in place in one array
    key = np.maximum(power[first_bin:edges[-1]], 1e-300)
    np.log(key, out=key)
    lo, span = float(key.min()), float(np.ptp(key)) * 1.000001 + 1e-12
    key -= lo
    key /= span
    key += np.repeat(np.arange(edges.size - 1, dtype=float), np.diff(edges))
    key.sort()
    counts = np.diff(edges)
    starts = edges[:-1] - first_bin
    lo_i, hi_i = starts + (counts - 1) // 2, starts + counts // 2
    band_ids = np.arange(edges.size - 1)
    med = 0.5 * (np.exp(lo + (key[lo_i] - band_ids) * span) + np.exp(lo + (key[hi_i] - band_ids) * span))
    centres = 0.5 * (edges[:-1] + edges[1:] - 1)
    levels = np.log(np.maximum(med / math.log(2.0), 1e-300))
    log_bin = np.arange(n, dtype=float)
    log_bin[0] = 1.0
    np.log(log_bin, out=log_bin)
    out = np.interp(log_bin, np.log(np.maximum(centres, 1.0)), levels)
    return np.exp(out, out=out)


#: samples per pass of :func:`_least_squares` and :func:`fitted`: the columns of a fit are made a
#: piece at a time, so a fit of a day at 100 Hz needs a few MB besides the record
CHUNK_SAMPLES = 1 << 16


def _least_squares(columns, x):
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
    columns made :data:`CHUNK_SAMPLES` at a time by ``columns(lo, hi)`` as in :func:`_least_squares`."""
    out = np.empty(n)
    for lo in range(0, n, CHUNK_SAMPLES):
        hi = min(n, lo + CHUNK_SAMPLES)
        part = out[lo:hi]
        part[:] = 0.0
        for c, col in zip(coef, columns(lo, hi)):
            part += c * col
    return out


def _sine_columns(sample_rate_hz, f_hz):
    """Columns ``cos(2 pi f n / f_s)`` and ``sin(2 pi f n / f_s)`` at samples ``lo .. hi - 1``."""
    k = 2 * math.pi * f_hz / sample_rate_hz

    def columns(lo, hi):
        w = np.arange(lo, hi) * k
        return np.cos(w), np.sin(w)
    return columns


def sinusoid_fit(x, sample_rate_hz, f_hz):
    """Least-squares ``a cos(2 pi f t) + b sin(2 pi f t) + c``; returns (amplitude, phase, fit)."""
    columns = _sine_columns(sample_rate_hz, f_hz)
    coef = _least_squares(columns, x)
    amp = math.hypot(coef[0], coef[1])
    phase = math.atan2(coef[0], coef[1])  # amp sin(w + phase)
    return amp, phase, fitted(columns, coef[:2], x.size)


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


def sinusoid_statistic(x, sample_rate_hz, return_spectrum=False):
    """Largest normalised periodogram ordinate (>= bin 8) and its frequency (Hz).

    Returns ``(stat, f_hz, threshold)`` (plus the periodogram ``|rfft|^2 / N`` of the
    detrended series with ``return_spectrum``); the periodogram is that of the first
    :func:`periodogram_length` samples, detrended (LS line) first.
    """
    nothing = (0.0, float("nan"), float("inf"))
    if x.size < 64:
        return nothing + (None,) if return_spectrum else nothing
    n = periodogram_length(x.size)
    f = np.fft.rfft(detrend_line(x[:n]))
    spec = np.square(f.real)
    spec += np.square(f.imag)
    del f
    spec /= n
    first = 8
    if spec.size <= first + 32:
        return nothing + (spec,) if return_spectrum else nothing
    ratio = _local_level(spec, first)
    np.divide(spec, ratio, out=ratio)
    ratio[:first] = 0.0
    ratio[-1] = 0.0
    j = int(np.argmax(ratio))
    m = spec.size - first
    threshold = math.log(m / SINUSOID_ALPHA)
    out = (float(ratio[j]), j * sample_rate_hz / n, threshold)
    return out + (spec,) if return_spectrum else out


def detect_sinusoid(x, sample_rate_hz):
    """Sinusoid candidate: frequency refined around the peak, amplitude by least squares."""
    stat, f0, thr = sinusoid_statistic(x, sample_rate_hz)
    if not stat > thr:
        return None
    df = sample_rate_hz / periodogram_length(x.size)
    # refine: golden-section search of the LS amplitude within +-1 bin of the periodogram
    lo, hi = max(f0 - df, df), min(f0 + df, sample_rate_hz / 2)
    f_hz = golden_max(_dft_amplitude(x - x.mean(), sample_rate_hz, f0), lo, hi, 30)
    amplitude, phase, fit = sinusoid_fit(x, sample_rate_hz, f_hz)
    sigma = robust_sigma(np.diff(x)) / math.sqrt(2)
    return Candidate(
        effect="sinusoid",
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


#: blocks of the demodulated series in :func:`_dft_amplitude`
DFT_BLOCKS = 4096


def _dft_amplitude(xc, sample_rate_hz, f0):
    """``|X(f)| = |sum_n x_n exp(-2 pi i f n / f_s)|`` for ``f`` near ``f0``, in O(blocks) per
    call after one O(N) pass.

    With ``z_n = x_n exp(-2 pi i f0 n / f_s)`` (demodulated once) and ``theta = 2 pi (f - f0) /
    f_s``, ``X(f) = sum_b exp(-i theta n_b) sum_s z_{n_b + s} exp(-i theta s)`` over blocks
    starting at ``n_b``; within a block ``exp(-i theta s) = 1 - i theta s - (theta s)^2 / 2 + R``
    with ``|R| <= |theta s|^3 / 6``, so three block moments ``sum z s^k`` (k = 0, 1, 2) give
    ``X(f)`` to a relative ``(2 pi B |f - f0| / f_s)^3 / 6``: below 1e-9 for ``|f - f0|`` of
    one bin (``f_s / N``) and ``B = N / 4096`` samples per block."""
    n = xc.size
    b = max(1, -(-n // DFT_BLOCKS))
    m = -(-n // b)
    s = np.arange(b, dtype=float)
    moments = np.zeros((3, m), dtype=complex)
    step = max(1, (1 << 16) // b) * b  # whole blocks per pass, about 65536 samples: bounded memory
    for a in range(0, n, step):
        seg = xc[a:a + step]
        w = np.arange(a, a + seg.size) * (-2 * math.pi * f0 / sample_rate_hz)
        z = np.zeros(-(-seg.size // b) * b, dtype=complex)
        z.real[:seg.size] = np.cos(w) * seg
        z.imag[:seg.size] = np.sin(w) * seg
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
