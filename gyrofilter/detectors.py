"""Detectors for the model-gap analysis: one statistic per effect of the effect table.

Every detector works on one axis, a 1-D rate series ``x_dps`` (deg/s) sampled at
``sample_rate_hz``, and returns a :class:`Candidate` (or None): the effect name, its parameter
estimates in the units of the effect table (docs/formats.md, section 2), the detector's statistic, the
threshold it had to pass and an evidence sentence. :mod:`gyrofilter.gap` runs the same
statistic on the baseline simulations to show the simulated spread, and keeps a candidate only
when the extended model lowers the discrepancy.

The detectors run in a fixed **decision order**, each on the series cleaned of what the earlier
ones found, because the effects are confusable:

1. ``outliers`` -- isolated spikes. Statistic: the second-difference residual
   ``r_i = x_i - (x_{i-1} + x_{i+1}) / 2`` (white noise: ``sd(r) = sigma sqrt(3/2)``) against a
   robust (MAD) scale; a spike is ``|r_i| > k sd(r)`` with ``k`` set so that white Gaussian noise
   gives 0.05 expected false spikes per axis (``k = Phi^-1(1 - 0.025 / N)``, about 5.0 for
   N = 360 000), and a finding needs at least 3 spikes (white noise: probability 2e-5).
   Paper 001 (gross errors: isolated, much larger than the noise). Found spikes are replaced
   by their neighbours' median before the next detectors run.
2. ``sinusoid`` -- a line in the periodogram. The periodogram ordinate divided by the local
   noise level (median over a +-5 % frequency band / ln 2) is Exp(1) under any smooth noise
   spectrum, so the largest of ``M`` ordinates exceeds ``t`` with probability about
   ``M exp(-t)`` (Fisher's test, the max-periodogram form; Priestley 1981, sec. 6.1.4). The line
   is fitted by least squares (amplitude, phase) at the refined frequency and subtracted.
2b. ``narrowband`` -- a band of noise with a resolved width (a resonance): the Welch PSD over a
   running-median background (±min(f_s / 10, 10 Hz)), the peak excess in units of its sampling error
   ``(R - 1) sqrt(K)`` (K Welch segments; Welch 1967), centre, half-power width and rms refined
   by a least-squares fit of the effect's own AR(2) resonator PSD (:func:`band_estimate`). Runs
   on the series with the sinusoid removed; a band cannot be subtracted (it is noise), so the
   later detectors see it, and the colored noise's lag-1 is corrected for it.
3. ``colored_noise`` -- the lag-1 autocorrelation ``r1 = sum e_i e_{i+1} / sum e_i^2`` of the
   high-passed noise ``e = x - moving_mean(x, W)``; white noise: ``r1 ~ N(-1/W, 1/N)``
   (Box & Jenkins). Slow effects barely move ``r1`` because ``W`` is short.
4. Slow bias effects, on block means ``y_k`` of the cleaned series (at most 2048 blocks of
   ``Delta`` seconds): deterministic shapes (``rate_ramp``: LS line; ``bias_step``: two-mean
   scan; ``warmup``: ``a exp(-t/tau)`` scanned over tau; ``temperature``: regression on the
   block-mean temperature) are scored by the drop of the residual sum of squares in units of
   the block white-noise variance (``Delta chi^2``); stochastic spectra
   (``rate_random_walk`` ``S = K^2 / (4 pi^2 f^2 Delta)``, ``bias_instability``
   ``S = B^2 / (2 pi f Delta)``, ``gauss_markov`` AR(1); IEEE Std 952-1997 annex C for the
   PSD forms) by the Whittle likelihood ratio over white noise (Whittle 1953) on the
   LS-detrended block means, the random walk's expected periodogram taking the detrend into
   account (:func:`_detrended_shapes`). Decision rules, in order:

   * the best deterministic shape is the largest ``Delta chi^2 - k ln n`` (k free
     parameters: BIC), so a warm-up with a very long tau loses to a ramp;
   * the best stochastic spectrum is the largest ``2 Delta log L - 6 k``: an extra parameter
     (Gauss-Markov's tau) must buy 6 (likelihood-ratio test at about 1.4 %), and a
     Gauss-Markov process whose tau exceeds a fifth of the record is a random walk as far as
     the data can tell;
   * a shape above its threshold is tested against the stochastic spectra of its residual:
     if one is still significant, the shape is kept only if its amplitude is significant
     against that fitted noise (the variance of the amplitude estimate under it, e.g.
     ``q sum_k (sum_{i>=k} w_i)^2`` for a random walk), giving both findings; otherwise the
     shape must also beat the *exact* Kalman-filter likelihood of a random-walk and of a
     Gauss-Markov wander on the same (undetrended) block means, so a wander that happens to
     look like a ramp or a step is called a wander;
   * with no shape, the best stochastic spectrum is reported if above its threshold.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

#: expected number of false spikes per axis on white Gaussian noise (with at least
#: OUTLIER_MIN_COUNT spikes required: P(Poisson(0.05) >= 3) = 2e-5 per axis)
OUTLIER_FALSE_PER_AXIS = 0.05
#: minimum number of spikes for an outlier finding
OUTLIER_MIN_COUNT = 3
#: false-alarm probability per axis for the periodogram line test
SINUSOID_ALPHA = 1e-4
#: z-score (in units of 1/sqrt(N)) the lag-1 autocorrelation must exceed, and the smallest
#: |lag1| reported (smaller correlations are real but immaterial)
COLORED_Z = 6.0
COLORED_MIN_LAG1 = 0.03
#: Delta chi^2 / 2 Delta log L thresholds of the slow-effect tests, set from clean recordings
#: only (white noise + quantization + a temperature column, 10 and 40 min, 60 runs): the
#: largest null values were 10.6 (step scan), 6.9 (warm-up scan, ramp, temperature) and 4.4
#: (Gauss-Markov), so the thresholds sit 2-4 times above the null maxima
DETERMINISTIC_THRESHOLD = 25.0
STOCHASTIC_THRESHOLD = 16.0
#: 2 Delta log L an extra spectral parameter must buy (chi^2_1: about 1.4 %)
STOCHASTIC_PENALTY = 6.0
#: z^2 a deterministic shape must reach against the fitted stochastic noise to be kept with it
JOINT_THRESHOLD = 25.0
#: number of blocks the slow-effect detectors work on (at most)
MAX_BLOCKS = 2048


@dataclass
class Candidate:
    """A departure from the baseline, mapped to an effect of the table."""

    effect: str
    params: dict
    statistic: float
    threshold: float
    evidence: str
    statistic_name: str = ""
    #: model component to subtract from the series (deterministic effects), per sample, or None
    component: object = None
    extra: dict = field(default_factory=dict)


# ---------------------------------------------------------------------------------------------
# helpers


def robust_sigma(x):
    """1.4826 MAD (a Gaussian's sigma), falling back to the std when the MAD is 0 (coarse
    quantization)."""
    x = np.asarray(x, dtype=float)
    if x.size > 200_000:  # a strided subsample is plenty for a scale estimate
        x = x[:: int(math.ceil(x.size / 100_000))]
    med = np.median(x)
    mad = 1.4826 * np.median(np.abs(x - med))
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


def detrend_line(x):
    """``x`` minus its least-squares line ``a + s t``, ``t = i - (N - 1) / 2`` (closed form,
    O(N)): ``s = sum t x / sum t^2`` with ``sum t^2 = N (N^2 - 1) / 12``."""
    n = x.size
    t = np.arange(n, dtype=float)
    t -= 0.5 * (n - 1)
    tt = n * (n * n - 1.0) / 12.0
    slope = float(dot(t, x)) / tt if tt > 0 else 0.0
    t *= slope
    t += float(x.mean())
    return x - t


def moving_mean(x, window):
    """Centred moving mean with window ``window`` samples: sample ``i`` averages
    ``x[i - W//2 : i - W//2 + W]``, clipped to the series at the edges (shorter windows), from
    one cumulative sum."""
    window = max(1, int(window))
    n = x.size
    c = np.empty(n + 1)
    c[0] = 0.0
    np.cumsum(x, out=c[1:])
    half = window // 2
    if window >= n:
        lo = np.clip(np.arange(n) - half, 0, n)
        hi = np.clip(np.arange(n) - half + window, 0, n)
        return (c[hi] - c[lo]) / (hi - lo)
    out = np.empty(n)
    # interior: i in [half, n - window + half], windows of full length
    i0, i1 = half, n - window + half + 1
    np.subtract(c[window:n + 1], c[:n + 1 - window], out=out[i0:i1])
    out[i0:i1] /= window
    head = np.arange(i0)
    out[:i0] = c[head - half + window] / (head - half + window)
    tail = np.arange(i1, n)
    lo = tail - half
    out[i1:] = (c[n] - c[lo]) / (n - lo)
    return out


def block_means(x, max_blocks=MAX_BLOCKS):
    """Means of ``n`` consecutive blocks of ``L = ceil(N / max_blocks)`` samples (a trailing
    partial block is dropped). Returns ``(y, L)``."""
    n_samples = x.size
    length = max(1, int(math.ceil(n_samples / max_blocks)))
    n = n_samples // length
    y = x[: n * length].reshape(n, length).mean(axis=1)
    return y, length


# ---------------------------------------------------------------------------------------------
# 1. outliers


def outlier_statistic(x):
    """Spike mask and count: ``|x_i - (x_{i-1}+x_{i+1})/2| > k sd`` and a local maximum.

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
    sd_r = robust_sigma(a[1:-1])
    if sd_r <= 0:
        return mask, np.inf, 0.0
    from statistics import NormalDist

    k = NormalDist().inv_cdf(1.0 - 0.5 * OUTLIER_FALSE_PER_AXIS / n)
    np.abs(a, out=a)
    big = np.flatnonzero(a > k * sd_r)
    # a spike at i also moves r at i-1 and i+1 by half its size: keep local maxima only
    left = np.where(big > 0, a[np.maximum(big - 1, 0)], 0.0)
    right = np.where(big < n - 1, a[np.minimum(big + 1, n - 1)], 0.0)
    mask[big[(a[big] >= left) & (a[big] >= right)]] = True
    return mask, k, sd_r


def clean_spikes(x, mask):
    """Replace masked samples by the mean of their neighbours (the median of the next 2 on
    each side that are not masked)."""
    if not mask.any():
        return x
    y = x.copy()
    idx = np.flatnonzero(mask)
    n = x.size
    for i in idx:
        nb = [j for j in (i - 2, i - 1, i + 1, i + 2) if 0 <= j < n and not mask[j]]
        y[i] = np.median(x[nb]) if nb else np.median(x)
    return y


#: log-spread of the spike magnitudes assumed when correcting for spikes below the threshold
#: (the simulator's default ``spread_ln``)
OUTLIER_SPREAD_LN = 0.25


def _spike_model(m_dps, sd_r, thr):
    """Detection probability and mean log|r| of detected spikes for spikes
    ``|s| = m exp(0.25 z)`` seen through the second-difference noise ``N(0, sd_r^2)``
    (64 x 64 quantile grid)."""
    from statistics import NormalDist

    q = np.array([NormalDist().inv_cdf((i + 0.5) / 64) for i in range(64)])
    s = m_dps * np.exp(OUTLIER_SPREAD_LN * q)[:, None]
    r = np.abs(s + sd_r * q[None, :])
    det = r > thr
    p = float(det.mean())
    mean_log = float(np.log(r[det]).mean()) if det.any() else -np.inf
    return p, mean_log


def detect_outliers(x):
    """Outlier (spike) candidate.

    Spikes below the threshold are missed, so the parameters are fitted to the detected ones:
    the median magnitude ``m`` is the one whose detected spikes (``|s| = m exp(0.25 z)`` plus
    the second-difference noise, thresholded like the data) have the observed mean log|r|,
    and ``rate = count / (N P_detect(m))`` (P_detect floored at 0.2).
    """
    mask, k, sd_r = outlier_statistic(x)
    count = int(mask.sum())
    if count < OUTLIER_MIN_COUNT:
        return None, mask
    cleaned = clean_spikes(x, mask)
    mags = np.abs(x[mask] - cleaned[mask])
    thr = k * sd_r
    r_abs = np.abs(x[1:-1] - 0.5 * (x[:-2] + x[2:]))
    observed = float(np.mean(np.log(r_abs[mask[1:-1]]))) if mask[1:-1].any() else float(np.log(np.median(mags)))
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
    expected = OUTLIER_FALSE_PER_AXIS
    cand = Candidate(
        effect="outliers",
        params={"rate": rate, "magnitude_dps": magnitude},
        statistic=float(count),
        threshold=float(OUTLIER_MIN_COUNT),
        statistic_name="spikes beyond %.1f robust sd of the second difference" % k,
        evidence=(f"{count} isolated spikes beyond {k:.1f} robust standard deviations of the "
                  f"second difference (white noise expects {expected:g}); median spike "
                  f"{magnitude:.3g} deg/s = {magnitude / (sd_r / math.sqrt(1.5)):.1f} noise sd "
                  f"(corrected for the {100 * (1 - p_det):.0f} % of spikes below the threshold)"),
    )
    return cand, mask


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


def _least_squares(columns, x):
    """Coefficients of the least-squares fit of ``x`` by the given columns (and a constant,
    the last coefficient), from the normal equations ``G beta = A^T x`` with the Gram matrix
    ``G = A^T A`` summed by :func:`dot` (no N-row BLAS / LAPACK call; well conditioned for the
    few smooth columns used here)."""
    cols = list(columns)
    k = len(cols) + 1
    gram = np.empty((k, k))
    rhs = np.empty(k)
    n = x.size
    for i, ci in enumerate(cols):
        for j in range(i, len(cols)):
            gram[i, j] = gram[j, i] = dot(ci, cols[j])
        gram[i, -1] = gram[-1, i] = ci.sum()
        rhs[i] = dot(ci, x)
    gram[-1, -1] = n
    rhs[-1] = x.sum()
    return np.linalg.solve(gram, rhs)


def sinusoid_fit(x, fs, f_hz):
    """Least-squares ``a cos(2 pi f t) + b sin(2 pi f t) + c``; returns (amplitude, phase, fit)."""
    w = np.arange(x.size) * (2 * math.pi * f_hz / fs)
    c, s = np.cos(w), np.sin(w)
    coef = _least_squares([c, s], x)
    amp = math.hypot(coef[0], coef[1])
    phase = math.atan2(coef[0], coef[1])  # amp sin(w + phase)
    return amp, phase, coef[0] * c + coef[1] * s


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


def sinusoid_statistic(x, fs, return_spectrum=False):
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
    out = (float(ratio[j]), j * fs / n, threshold)
    return out + (spec,) if return_spectrum else out


def detect_sinusoid(x, fs):
    """Sinusoid candidate: frequency refined around the peak, amplitude by least squares."""
    stat, f0, thr = sinusoid_statistic(x, fs)
    if not stat > thr:
        return None
    df = fs / periodogram_length(x.size)
    # refine: golden-section search of the LS amplitude within +-1 bin of the periodogram
    lo, hi = max(f0 - df, df), min(f0 + df, fs / 2)
    f_hz = golden_max(_dft_amplitude(x - x.mean(), fs, f0), lo, hi, 30)
    amplitude, phase, fit = sinusoid_fit(x, fs, f_hz)
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


def _dft_amplitude(xc, fs, f0):
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
        w = np.arange(a, a + seg.size) * (-2 * math.pi * f0 / fs)
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
        theta = 2 * math.pi * (f - f0) / fs
        inner = moments[0] - 1j * theta * moments[1] - 0.5 * theta * theta * moments[2]
        return abs(np.sum(np.exp(-1j * theta * starts) * inner))

    return amp


# ---------------------------------------------------------------------------------------------
# 2b. narrow-band noise (a spectral line with a resolved width)

#: the band statistic (peak excess over the background in units of its sampling error,
#: ``(R - 1) sqrt(K)``) a band must exceed; on white and AR(1) noise (lag1 -0.7 to 0.7,
#: 12 000 to 10^6 samples at 100 Hz, 80 runs) its largest value was 1.5
NARROWBAND_THRESHOLD = 4.0
#: half-width (Hz) of the running-median background of :func:`band_estimate` (at most f_s / 10)
BAND_BACKGROUND_HZ = 10.0


def band_estimate(x_dps, sample_rate_hz, *, nperseg=8192, smooth_bins=15, fit=True):
    """Centre, half-power full width and rms of the strongest band of a rate series.

    One-sided Welch PSD S(f) (Hann, 50 % overlap, segments of ``nperseg`` samples, fewer when
    the record holds less than 16 of them: the largest power of 2 up to N / 16; Welch 1967);
    background b(f) = running median of S over ±W, W = min(f_s / 10, 10 Hz); excess e = S - b, and ē its moving
    average over ``smooth_bins`` bins (the Welch bins are noisy). The peak is the bin of largest
    R = 1 + ē / b among the bins whose whole background window lies inside (0, f_s / 2) (at the
    edges the median of a sloped spectrum is biased); the band is the contiguous run of bins
    around it with ē > ē_peak / 2 (its width is the half-power full width, at least about
    ``smooth_bins`` bins: a pure line shows that width), the centre the e-weighted mean
    frequency of that run, and rms² = Σ e Δf over the contiguous run with ē > 0 (a one-sided
    PSD integrates to the variance). Returns a dict with ``center_hz``, ``bandwidth_hz``,
    ``rms_dps``, ``peak_ratio`` (R at the peak), ``resolution_hz`` (the width a pure line
    shows, ``smooth_bins`` Δf) and ``segments`` (K, the number of Welch segments). With ``fit``
    the centre, width and rms are then refined by :func:`_resonator_fit`.
    """
    from scipy.ndimage import median_filter, uniform_filter1d
    from scipy.signal import welch

    x = np.asarray(x_dps, dtype=float)
    seg = int(min(nperseg, 2 ** int(math.log2(max(x.size // 16, 16)))))
    f, s = welch(x - x.mean(), fs=sample_rate_hz, nperseg=seg)
    df = f[1] - f[0]
    background_hz = min(sample_rate_hz / 10.0, BAND_BACKGROUND_HZ)
    width = max(3, int(round(2 * background_hz / df)) | 1)
    back = median_filter(s, size=width, mode="nearest")
    excess = s - back
    smooth = uniform_filter1d(excess, smooth_bins, mode="nearest")
    ratio = 1.0 + smooth / np.maximum(back, 1e-300)
    ratio[(f < background_hz) | (f > sample_rate_hz / 2 - background_hz)] = 0.0
    k = int(np.argmax(ratio))

    def run(mask):
        lo = hi = k
        while lo > 0 and mask[lo - 1]:
            lo -= 1
        while hi < mask.size - 1 and mask[hi + 1]:
            hi += 1
        return lo, hi

    lo, hi = run(smooth > smooth[k] / 2.0)
    w = excess[lo:hi + 1]
    total = float(w.sum())
    centre = float(dot(w, f[lo:hi + 1]) / total) if total > 0 else float(f[k])
    plo, phi = run(smooth > 0.0)
    rms = math.sqrt(max(float(excess[plo:phi + 1].sum()), 0.0) * df)
    out = {"center_hz": centre, "bandwidth_hz": float((hi - lo + 1) * df), "rms_dps": rms,
           "peak_ratio": float(ratio[k]), "resolution_hz": float(smooth_bins * df),
           "segments": int(max(1, (x.size - seg) // (seg // 2) + 1))}
    if fit and rms > 0:
        out.update(_resonator_fit(f, s, out, sample_rate_hz))
    return out


def _resonator_fit(f, s, band, fs):
    """Refine centre, width and rms by fitting the ``narrowband`` effect's own PSD (the AR(2)
    resonator of :func:`gyrofilter.noise_terms.narrowband_filter`, one-sided 2 |B|² / |A|² / f_s)
    on a local linear background, ``S(f) = b0 + b1 (f - f_c) + S_L(f; f_c, B, rms)``, to the Welch
    PSD within ±max(5 B, 1 Hz) of the centre, by least squares on log S (the Welch log-ordinates
    have a constant variance, about 1/K). The nonparametric estimate is the start; the result is
    kept only if it fits better. The resonator's Lorentzian tails hold power outside the
    half-power run that the nonparametric rms misses."""
    from scipy.optimize import least_squares

    from .noise_terms import filter_psd, narrowband_filter

    c0, b0w, rms0 = band["center_hz"], band["bandwidth_hz"], band["rms_dps"]
    half = max(5.0 * b0w, 1.0)
    sel = (f >= max(c0 - half, f[1])) & (f <= min(c0 + half, fs / 2 - f[1]))
    if sel.sum() < 8:
        return {}
    fw, logs = f[sel], np.log(np.maximum(s[sel], 1e-300))
    edge = np.r_[s[sel][:3], s[sel][-3:]]
    start = np.array([c0, math.log(b0w), math.log(rms0), math.log(max(float(np.median(edge)), 1e-300)), 0.0])

    def model(p):
        centre, bw, rms, level, slope = p[0], math.exp(p[1]), math.exp(p[2]), math.exp(p[3]), p[4]
        b, a = narrowband_filter(rms, centre, bw, fs)
        line = 2.0 * filter_psd(b, a, fw, fs)
        return np.log(np.maximum(level * (1.0 + slope * (fw - centre)) + line, 1e-300))

    def resid(p):
        return model(p) - logs

    lower = [c0 - half / 2, math.log(b0w / 20), start[2] - 3, start[3] - 5, -1.0 / half]
    upper = [c0 + half / 2, math.log(min(4 * b0w, fs / 4)), start[2] + 3, start[3] + 5, 1.0 / half]
    try:
        res = least_squares(resid, np.clip(start, np.add(lower, 1e-9), np.subtract(upper, 1e-9)),
                            bounds=(lower, upper), max_nfev=200)
    except (ValueError, FloatingPointError, np.linalg.LinAlgError):
        return {}
    if not (res.success and res.cost < 0.5 * float(np.sum(resid(start) ** 2))):
        return {}
    return {"center_hz": float(res.x[0]), "bandwidth_hz": float(math.exp(res.x[1])), "rms_dps": float(math.exp(res.x[2]))}


def detect_narrowband(x, fs):
    """Narrow-band noise candidate (the ``narrowband`` effect: centre, half-power width, rms)
    from :func:`band_estimate`.

    Statistic ``(R - 1) sqrt(K)``: the Welch estimate averages K segments, so the excess over
    the background at one bin has a relative sampling error of about 1 / sqrt(K) (chi-square
    with about 2K degrees of freedom; Welch 1967), and smoothing only lowers it; the threshold
    :data:`NARROWBAND_THRESHOLD` sits well above its largest value on white and AR(1) noise.
    Runs after the sinusoid detector, so a pure line is already subtracted; the evidence says
    whether the fitted width exceeds the estimator's resolution (``resolution_hz``) by half
    again, i.e. whether the width is resolved."""
    if x.size < 4096 or fs <= 0:
        return None
    band = band_estimate(x, fs)
    stat = (band["peak_ratio"] - 1.0) * math.sqrt(band["segments"])
    if not stat > NARROWBAND_THRESHOLD or band["rms_dps"] <= 0:
        return None
    resolved = band["bandwidth_hz"] > 1.5 * band["resolution_hz"]
    return Candidate(
        effect="narrowband",
        params={"center_hz": band["center_hz"], "bandwidth_hz": band["bandwidth_hz"], "rms_dps": band["rms_dps"]},
        statistic=stat,
        threshold=NARROWBAND_THRESHOLD,
        statistic_name="Welch band excess over the running-median background, in sampling errors",
        evidence=(f"a band of noise at {band['center_hz']:.4g} Hz, half-power width {band['bandwidth_hz']:.3g} Hz "
                  + ("(resolved: the Welch resolution is " if resolved else "(not resolved: the Welch resolution is ")
                  + f"{band['resolution_hz']:.2g} Hz), rms {band['rms_dps']:.3g} deg/s; its peak is "
                  f"{band['peak_ratio']:.2g} times the background PSD ({stat:.0f} sampling errors, threshold "
                  f"{NARROWBAND_THRESHOLD:g})"),
    )


def narrowband_lag1(center_hz, bandwidth_hz, fs):
    """Lag-1 autocorrelation of the ``narrowband`` effect's AR(2) resonator,
    r₁ = φ₁ / (1 - φ₂) (Box & Jenkins, eq. 3.2.26), φ₁ = 2 r cos θ, φ₂ = -r²
    (:func:`gyrofilter.noise_terms.narrowband_filter`)."""
    theta = 2.0 * math.pi * center_hz / fs
    r = math.exp(-math.pi * bandwidth_hz / fs)
    return 2.0 * r * math.cos(theta) / (1.0 + r * r)


def lag1_without_band(lag1, var_total, band_params, fs):
    """The colored noise's lag-1 once a band is taken out: the measured ``lag1`` is that of the
    sum (variance ``var_total``), r₁ (v_c + v_L) = ρ v_c + r_L v_L with v_L = rms², v_c =
    var_total - v_L and r_L = :func:`narrowband_lag1`, so ρ = (r₁ var_total - r_L v_L) / v_c,
    clipped to ±0.99 (None when the band holds nearly all the variance)."""
    v_line = band_params["rms_dps"] ** 2
    v_c = var_total - v_line
    if not v_c > 0.05 * var_total:
        return None
    r_line = narrowband_lag1(band_params["center_hz"], band_params["bandwidth_hz"], fs)
    return float(np.clip((lag1 * var_total - r_line * v_line) / v_c, -0.99, 0.99))


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


# ---------------------------------------------------------------------------------------------
# 4. slow bias effects on block means


PERIODOGRAM = "detrended"

_SHAPES = {}


def _detrended_shapes(n):
    """Exact expected periodogram shapes of the LS-detrended block means (cached per n):
    white noise ``w_j = |P f_j|^2 / n`` and a unit random walk (``cov = min(k, l) + 1``)
    ``g_j = sum_m |sum_{l >= m} (P f_j)_l|^2 / n``, with ``P`` the projection off
    ``[1, t]`` and ``f_j`` the Fourier vector of frequency ``omega_j`` (``M = L L^T``, ``L``
    lower-triangular ones, so ``v^H M v = |L^T v|^2``). The detrend takes power away from the
    lowest frequencies of a random walk; modelling that keeps a random walk from looking
    like a Gauss-Markov process."""
    if n in _SHAPES:
        return _SHAPES[n]
    t = np.arange(n, dtype=float)
    q_mat, _ = np.linalg.qr(np.column_stack([np.ones(n), t - t.mean()]))
    j = np.arange(1, (n + 1) // 2)
    j = j[j < n / 2]
    omega = 2 * math.pi * j / n
    out_w = np.empty(j.size)
    out_g = np.empty(j.size)
    for start in range(0, j.size, 256):
        om = omega[start:start + 256]
        f = np.exp(-1j * np.outer(t, om))
        v = f - q_mat @ (q_mat.T @ f)
        out_w[start:start + 256] = np.sum(np.abs(v) ** 2, axis=0) / n
        u = np.cumsum(v[::-1], axis=0)[::-1]
        out_g[start:start + 256] = np.sum(np.abs(u) ** 2, axis=0) / n
    if len(_SHAPES) > 8:
        _SHAPES.clear()
    _SHAPES[n] = (out_w, out_g)
    return out_w, out_g


def _periodogram_detrended(y):
    """Periodogram of the least-squares detrended block means."""
    r = detrend_line(y)
    n = r.size
    spec = np.abs(np.fft.rfft(r)) ** 2 / n
    j = np.arange(spec.size)
    keep = (j >= 1) & (j < n / 2)
    return spec[keep], j[keep] * 2 * math.pi / n


def _periodogram(y):
    """Periodogram of the block means through their increments ("bridge" periodogram):
    ``I_j = |DFT(d - mean d)|^2 / m / (4 sin^2(omega_j / 2))`` with ``d = diff(y)``,
    ``m = n - 1``. For a random walk plus white noise its expectation is exactly
    ``q / (4 sin^2(omega/2)) + s0`` at every Fourier frequency (the increments are
    stationary, so no end-effect leakage; a least-squares detrend instead flattens the lowest
    frequencies and makes a random walk look like a Gauss-Markov process); for stationary
    noise it is the ordinary spectrum; a linear trend is removed with the mean increment."""
    d = np.diff(y)
    d = d - d.mean()
    m = d.size
    spec = np.abs(np.fft.rfft(d)) ** 2 / m
    j = np.arange(spec.size)
    keep = (j >= 1) & (j < m / 2)
    omega = j[keep] * 2 * math.pi / m
    return spec[keep] / (4 * np.sin(omega / 2) ** 2), omega


def _spectrum(model, theta, omega, delta_s):
    """Component spectrum of a stochastic bias model for block means (sampling delta_s)."""
    if model == "rate_random_walk":
        q = theta[0]
        return q / (4 * np.sin(omega / 2) ** 2)
    if model == "bias_instability":
        h = theta[0]
        return h / omega
    if model == "gauss_markov":
        var, phi = theta
        return var * (1 - phi ** 2) / (1 - 2 * phi * np.cos(omega) + phi ** 2)
    raise ValueError(model)


def _whittle(spec, omega, model, delta_s, s0_start, white_shape=None, rw_shape=None):
    """Minimise the Whittle negative log-likelihood ``l = sum_j log S_j + I_j / S_j``
    (Whittle 1953) over the model's parameters and the white level ``s0`` (log / logit
    parametrisation, L-BFGS-B with the analytic gradient
    ``dl/dp = sum_j (1 / S_j - I_j / S_j^2) dS_j/dp``); returns (nll, theta, s0)."""
    from scipy.optimize import minimize

    low = max(float(spec[: max(4, spec.size // 16)].mean()), 1e-300)
    cos_w = np.cos(omega)
    if model == "rate_random_walk":
        shape = 1.0 / (4 * np.sin(omega / 2) ** 2) if rw_shape is None else rw_shape
    elif model == "bias_instability":
        shape = 1.0 / omega
    wsh = np.ones_like(omega) if white_shape is None else white_shape

    def fun(p):
        s0 = math.exp(p[0])
        if model == "gauss_markov":
            var = math.exp(p[1])
            phi = 1.0 / (1.0 + math.exp(-p[2]))
            den = 1 - 2 * phi * cos_w + phi * phi
            comp = var * (1 - phi * phi) / den
            dphi = var * ((-2 * phi) * den - (1 - phi * phi) * (-2 * cos_w + 2 * phi)) / den ** 2
            derivs = (s0 * wsh, comp, dphi * phi * (1 - phi))
        else:
            comp = math.exp(p[1]) * shape
            derivs = (s0 * wsh, comp)
        s = s0 * wsh + comp
        w = 1.0 / s - spec / (s * s)
        grad = np.array([float(np.dot(w, d)) for d in derivs])
        return float(np.sum(np.log(s) + spec / s)), grad

    if model == "rate_random_walk":
        starts = [[math.log(s0_start), math.log(low * 4 * math.sin(omega[1] / 2) ** 2 + 1e-300)]]
    elif model == "bias_instability":
        starts = [[math.log(s0_start), math.log(low * omega[2] + 1e-300)]]
    else:
        starts = [[math.log(s0_start), math.log(max(low, s0_start) * 0.2), math.log(phi / (1 - phi))]
                  for phi in (0.5, 0.9, 0.99)]
    best = None
    for p0 in starts:
        try:
            res = minimize(fun, np.asarray(p0, dtype=float), jac=True, method="BFGS",
                           options={"maxiter": 200})
        except (ValueError, FloatingPointError, OverflowError):
            continue
        if np.isfinite(res.fun) and (best is None or res.fun < best[0]):
            best = (float(res.fun), res.x)
    if best is None:
        s0 = float(spec.mean())
        return float(np.sum(np.log(s0) + spec / s0)), ((0.0,) if model != "gauss_markov" else (0.0, 0.5)), s0
    p = best[1]
    s0 = math.exp(p[0])
    if model == "gauss_markov":
        theta = (math.exp(p[1]), 1.0 / (1.0 + math.exp(-p[2])))
    else:
        theta = (math.exp(p[1]),)
    return best[0], theta, s0


STOCHASTIC_MODELS = ("rate_random_walk", "bias_instability", "gauss_markov")
_N_PARAMS = {"rate_random_walk": 1, "bias_instability": 1, "gauss_markov": 2,
             "rate_ramp": 1, "temperature": 1, "bias_step": 2, "warmup": 2}


def stochastic_fits(y, delta_s):
    """Whittle fits of each stochastic model to the block means ``y`` (bridge periodogram,
    :func:`_periodogram`).

    Returns ``{model: (two_delta_loglik, theta, s0)}`` and the white-only level.
    """
    n = y.size
    if PERIODOGRAM == "bridge":
        spec, omega = _periodogram(y)
        wsh, gsh = np.ones_like(spec), None
    else:
        spec, omega = _periodogram_detrended(y)
        wsh, gsh = _detrended_shapes(n)
    s0_white = float(np.mean(spec / wsh))
    nll0 = float(np.sum(np.log(s0_white * wsh) + spec / (s0_white * wsh)))
    s0_hf = float(spec[spec.size // 2:].mean())
    out = {}
    for model in STOCHASTIC_MODELS:
        nll, theta, s0 = _whittle(spec, omega, model, delta_s, s0_hf, wsh, gsh)
        out[model] = (max(0.0, 2 * (nll0 - nll)), theta, s0)
    return out, s0_hf


def _stochastic_params(model, theta, delta_s):
    """Table parameters from the block-mean model parameters."""
    if model == "rate_random_walk":
        # q = K^2 delta  (random walk of the rate, increment variance per block)
        return {"k_dps_per_sqrt_s": math.sqrt(theta[0] / delta_s)}
    if model == "bias_instability":
        # S_d(omega) = h / omega = B^2 / (2 pi f delta) with omega = 2 pi f delta -> h = B^2
        return {"b_dps": math.sqrt(theta[0])}
    var, phi = theta
    return {"sigma_dps": math.sqrt(var), "tau_s": -delta_s / math.log(phi)}


def _amplitude_variance(w, model, theta, s0):
    """Variance of ``w^T y`` (``sum w = 0``) under white ``s0`` plus the stochastic model."""
    var = s0 * float(np.dot(w, w))
    if model is None:
        return var
    if model == "rate_random_walk":
        # cov(y_i, y_j) = q min(i, j): w^T C w = q sum_k (sum_{i>=k} w_i)^2
        tail = np.cumsum(w[::-1])[::-1]
        return var + theta[0] * float(np.dot(tail, tail))
    # stationary: (1 / M) sum_j S(omega_j) |W(omega_j)|^2 over a padded grid
    m = 1 << int(math.ceil(math.log2(4 * w.size)))
    wf = np.abs(np.fft.fft(w, m)) ** 2
    omega = 2 * math.pi * np.arange(m) / m
    omega = np.minimum(omega, 2 * math.pi - omega)
    omega[0] = omega[1] / 2
    s = _spectrum(model, theta, omega, 1.0)
    return var + float(np.sum(s * wf) / m)


def _deterministic_shapes(y, delta_s, temp_blocks=None):
    """Best fit of each deterministic shape: ``{effect: (delta_chi2_raw, params, shape_blocks,
    w)}`` with ``delta_chi2_raw = (w^T y)^2 / (w^T w)`` (divide by the white level) and
    ``shape_blocks`` the fitted component (mean-free) on the blocks."""
    n = y.size
    t = (np.arange(n) + 0.5) * delta_s
    yc = y - y.mean()
    out = {}

    def single(g):
        gc = g - g.mean()
        gg = float(np.dot(gc, gc))
        if gg <= 0:
            return 0.0, 0.0, gc
        a = float(np.dot(gc, yc)) / gg
        return a * a * gg, a, gc

    # ramp
    d, a, gc = single(t)
    out["rate_ramp"] = (d, {"r_dps_per_s": a}, a * gc, gc / np.dot(gc, gc))
    # step: two-mean scan over split k (first k blocks vs the rest)
    if n >= 8:
        c = np.cumsum(yc)
        k = np.arange(2, n - 1)
        s_left = c[k - 1]
        stat = s_left ** 2 * n / (k * (n - k))
        i = int(np.argmax(stat))
        kk = int(k[i])
        g = (np.arange(n) >= kk).astype(float)
        d, a, gc = single(g)
        out["bias_step"] = (d, {"time_s": kk * delta_s, "size_dps": a}, a * gc,
                            gc / np.dot(gc, gc))
    # warm-up: a exp(-t / tau) scanned over tau
    if n >= 8:
        taus = np.geomspace(max(1.5 * delta_s, 1e-9), max(n * delta_s, 2 * delta_s), 40)
        best = None
        for tau in taus:
            d, a, gc = single(np.exp(-t / tau))
            if best is None or d > best[0]:
                best = (d, a, tau, gc)
        # refine tau (golden search in log tau around the best grid point)
        log_tau = golden_max(lambda lt: single(np.exp(-t / math.exp(lt)))[0],
                             math.log(best[2] / 1.3), math.log(best[2] * 1.3), 20)
        tau = math.exp(log_tau)
        d, a, gc = single(np.exp(-t / tau))
        if d < best[0]:
            d, a, tau, gc = best
        out["warmup"] = (d, {"amplitude_dps": a, "tau_s": tau}, a * gc, gc / np.dot(gc, gc))
    if temp_blocks is not None and np.ptp(temp_blocks) > 0:
        d, a, gc = single(temp_blocks)
        out["temperature"] = (d, {"coefficient_dps_per_c": a}, a * gc, gc / np.dot(gc, gc))
    return out


def _kf_nll(y, phi, q, s0, mean):
    """Exact Gaussian negative log-likelihood (x2, constants dropped) of
    ``y_k = b_k + v_k``, ``b_k = mean + phi (b_{k-1} - mean) + w_k``, ``var v = s0``,
    ``var w = q`` (scalar Kalman filter; Harvey 1989, sec. 3.4). ``phi = 1`` is the random
    walk (local level) with a diffuse start (the first observation initialises the level);
    ``phi < 1`` the Gauss-Markov process started in its stationary law."""
    if phi >= 1.0:
        b, p_var, start = y[0], s0, 1
    else:
        b, p_var, start = mean, q / (1 - phi * phi), 0
    total = 0.0
    log = math.log
    for k in range(start, y.size):
        b = mean + phi * (b - mean)
        p_var = phi * phi * p_var + q
        f = p_var + s0
        e = y[k] - b
        total += log(f) + e * e / f
        gain = p_var / f
        b += gain * e
        p_var -= gain * p_var
    return total


def exact_stochastic_gain(y, sto, delta_s):
    """2 Delta log L of the exact (time-domain) random-walk and Gauss-Markov models over
    white noise with a constant mean, on the block means *with* their trend, started from the
    Whittle estimates. Used to compare a deterministic shape with a stochastic wander on the
    same data (the Whittle fits see the detrended series only)."""
    from scipy.optimize import minimize

    y = np.asarray(y, dtype=float)
    n = y.size
    mean = float(y.mean())
    var0 = float(np.var(y))
    base = n * math.log(var0) + n  # white noise, MLE variance
    out = {}
    q0 = max(sto["rate_random_walk"][1][0], 1e-12 * var0)
    s00 = max(sto["rate_random_walk"][2], 1e-12 * var0)
    res = minimize(lambda p: _kf_nll(y, 1.0, math.exp(p[0]), math.exp(p[1]), mean),
                   [math.log(q0), math.log(s00)], method="Nelder-Mead",
                   options={"xatol": 1e-2, "fatol": 0.05, "maxiter": 200})
    # the diffuse start drops one observation: add the white model's term for it back
    out["rate_random_walk"] = (max(0.0, base - (res.fun + math.log(var0) + 1)),
                               (math.exp(res.x[0]),), math.exp(res.x[1]))
    var_g, phi_g = sto["gauss_markov"][1]
    s0g = max(sto["gauss_markov"][2], 1e-12 * var0)
    phi_g = min(max(phi_g, 0.5), 0.9999)
    res = minimize(lambda p: _kf_nll(y, 1 / (1 + math.exp(-p[1])), math.exp(p[0]), math.exp(p[2]), mean),
                   [math.log(max(var_g * (1 - phi_g ** 2), 1e-12 * var0)), math.log(phi_g / (1 - phi_g)), math.log(s0g)],
                   method="Nelder-Mead", options={"xatol": 1e-2, "fatol": 0.05, "maxiter": 300})
    phi = 1 / (1 + math.exp(-res.x[1]))
    qg = math.exp(res.x[0])
    out["gauss_markov"] = (max(0.0, base - res.fun), (qg / max(1 - phi * phi, 1e-12), phi), math.exp(res.x[2]))
    return out


def detect_slow(x, fs, temp_c=None):
    """Slow bias effects of one axis (see the module docstring for the decision rules).

    Returns ``(candidates, stats)``: a list of :class:`Candidate` and the raw statistics
    (for the simulated-spread comparison): ``{name: value}``.
    """
    y, length = block_means(x)
    n = y.size
    stats = {}
    if n < 16:
        return [], stats
    delta_s = length / fs
    temp_blocks = None
    if temp_c is not None:
        tb, _ = block_means(np.asarray(temp_c, dtype=float))
        if tb.size == n and np.ptp(tb) > 0:
            temp_blocks = tb
    penalty = math.log(n)
    sto, s0 = stochastic_fits(y, delta_s)
    det = _deterministic_shapes(y, delta_s, temp_blocks)
    for name, (d, *_rest) in det.items():
        stats[name] = d / s0
    for name, (d2, *_rest) in sto.items():
        stats[name] = d2

    def best_of_sto(table):
        # nested spectra: an extra parameter must buy STOCHASTIC_PENALTY in 2 Delta log L
        # (likelihood-ratio test, chi^2_1 at about 1.4 %); and a Gauss-Markov whose tau is
        # longer than a fifth of the record is a random walk as far as the data can tell
        items = []
        for k, v in table.items():
            if k == "gauss_markov" and -delta_s / math.log(min(max(v[1][1], 1e-12), 1 - 1e-12)) > n * delta_s / 5:
                continue
            items.append((v[0] - _N_PARAMS[k] * STOCHASTIC_PENALTY, k))
        return max(items) if items else (-np.inf, None)

    def best_of(table, value):
        items = [(value(v) - _N_PARAMS[k] * penalty, k) for k, v in table.items()]
        return max(items) if items else (-np.inf, None)

    _, det_name = best_of(det, lambda v: v[0] / s0)
    _, sto_name = best_of_sto(sto)
    det_sig = det_name is not None and det[det_name][0] / s0 > DETERMINISTIC_THRESHOLD
    sto_sig = sto_name is not None and sto[sto_name][0] > STOCHASTIC_THRESHOLD

    findings = []
    t_blocks = (np.arange(n) + 0.5) * delta_s
    if det_sig:
        d, params, shape, w = det[det_name]
        resid = y - shape
        sto_r, s0_r = stochastic_fits(resid, delta_s)
        _, sto_r_name = best_of_sto(sto_r)
        sto_r_sig = sto_r[sto_r_name][0] > STOCHASTIC_THRESHOLD
        keep_det = True
        if sto_r_sig:
            two_dl, theta, s0_model = sto_r[sto_r_name]
            var = _amplitude_variance(w, sto_r_name, theta, s0_model)
            amp = float(np.dot(w, y))
            z2 = amp * amp / var
            keep_det = z2 > JOINT_THRESHOLD
            stats["joint_z2"] = z2
            # the stochastic model is re-fitted without the shape when the shape is dropped
            if keep_det:
                findings.append(_rw_or_gm(sto_r_name, sto_r, resid, delta_s))
            else:
                findings.append(_rw_or_gm(sto_name, sto, y, delta_s))
        if keep_det and not findings:
            # a wander that happens to look like the shape: compare exact likelihoods on the
            # same (undetrended) block means; the shape must beat the best stochastic model
            # by STOCHASTIC_PENALTY per extra parameter
            # (on at most 512 coarser blocks: the Kalman filter is a Python loop)
            group = max(1, int(math.ceil(n / 512)))
            m = n // group
            yg = y[: m * group].reshape(m, group).mean(axis=1)
            gg = shape[: m * group].reshape(m, group).mean(axis=1)
            gg = gg - gg.mean()
            ygc = yg - yg.mean()
            rss0 = float(np.dot(ygc, ygc))
            fit = float(np.dot(gg, ygc)) ** 2 / max(float(np.dot(gg, gg)), 1e-300)
            rss1 = max(rss0 - fit, 1e-300)
            two_dl_det = m * math.log(rss0 / rss1)
            sto_g, _ = stochastic_fits(yg, delta_s * group)
            exact = exact_stochastic_gain(yg, sto_g, delta_s * group)
            group_delta = delta_s * group
            score_det = two_dl_det - _N_PARAMS[det_name] * STOCHASTIC_PENALTY
            best_exact = max((v[0] - _N_PARAMS[k] * STOCHASTIC_PENALTY, k) for k, v in exact.items())
            stats["exact_det"] = two_dl_det
            stats.update({"exact_" + k: v[0] for k, v in exact.items()})
            if best_exact[0] > score_det:
                keep_det = False
                name = best_exact[1]
                if sto_sig and sto_name in ("rate_random_walk", "gauss_markov", "bias_instability"):
                    findings.append(_rw_or_gm(sto_name, sto, y, delta_s))
                else:
                    findings.append(_stochastic_candidate(name, exact[name], group_delta, m))
        if keep_det:
            findings.insert(0, _deterministic_candidate(det_name, d / s0, params, x, fs,
                                                       length, t_blocks, temp_c))
    elif sto_sig:
        findings.append(_rw_or_gm(sto_name, sto, y, delta_s))
    return findings, stats


#: 2 Delta log L (exact likelihood) a Gauss-Markov process must gain over a random walk
EXACT_GM_MARGIN = 8.0


def _rw_or_gm(name, table, y, delta_s):
    """Random walk or Gauss-Markov: decided on the exact (Kalman) likelihoods of the block
    means (at most 512), which keep the low-frequency information the detrended Whittle fit
    loses. Gauss-Markov needs ``EXACT_GM_MARGIN`` more than the random walk and a tau below a
    fifth of the record; on 30-minute and 10-minute test cases this told the two apart in 53
    of 56 cases against 49 of 56 for the Whittle comparison. Other models pass through."""
    n = y.size
    if name not in ("rate_random_walk", "gauss_markov"):
        return _stochastic_candidate(name, table[name], delta_s, n)
    group = max(1, int(math.ceil(n / 512)))
    m = n // group
    yg = y[: m * group].reshape(m, group).mean(axis=1)
    sto_g, _ = stochastic_fits(yg, delta_s * group)
    exact = exact_stochastic_gain(yg, sto_g, delta_s * group)
    gm = exact["gauss_markov"]
    tau = _stochastic_params("gauss_markov", gm[1], delta_s * group)["tau_s"]
    if gm[0] - exact["rate_random_walk"][0] > EXACT_GM_MARGIN and tau < n * delta_s / 5:
        return _stochastic_candidate("gauss_markov", gm, delta_s * group, m)
    return _stochastic_candidate("rate_random_walk", table["rate_random_walk"], delta_s, n)


def _stochastic_candidate(name, fit, delta_s, n):
    two_dl, theta, s0 = fit
    params = _stochastic_params(name, theta, delta_s)
    words = {"rate_random_walk": "a 1/f^2 (random-walk) bias spectrum",
             "bias_instability": "a 1/f (flicker) bias spectrum",
             "gauss_markov": "an exponentially correlated (Lorentzian) bias spectrum"}[name]
    return Candidate(
        effect=name, params=params, statistic=two_dl, threshold=STOCHASTIC_THRESHOLD,
        statistic_name="2 Delta log-likelihood (Whittle) over white noise",
        evidence=(f"the spectrum of {n} block means ({delta_s:.3g} s each) rises at low "
                  f"frequency like {words}: likelihood ratio 2 Delta log L = {two_dl:.0f} over "
                  f"white noise (threshold {STOCHASTIC_THRESHOLD:.0f})"),
    )


def _refine_step(x, fs, length, time_s):
    """Sample-level step time: two-mean scan of the raw series within +-2 blocks."""
    k = int(round(time_s * fs))
    lo, hi = max(1, k - 2 * length), min(x.size - 1, k + 2 * length)
    w = max(4 * length, 50)
    best, best_i = -1.0, k
    c = np.concatenate(([0.0], np.cumsum(x)))
    for i in range(lo, hi + 1):
        a0, b1 = max(0, i - w), min(x.size, i + w)
        left = (c[i] - c[a0]) / (i - a0)
        right = (c[b1] - c[i]) / (b1 - i)
        s = (right - left) ** 2 * (i - a0) * (b1 - i) / (b1 - a0)
        if s > best:
            best, best_i = s, i
    a0, b1 = max(0, best_i - w), min(x.size, best_i + w)
    return best_i / fs


def _deterministic_candidate(name, d, params, x, fs, length, t_blocks, temp_c):
    params = dict(params)
    n = x.size
    t = np.arange(n) / fs
    if name == "bias_step":
        ts = _refine_step(x, fs, length, params["time_s"])
        after = t >= ts
        params["time_s"] = ts
        params["size_dps"] = float(x[after].mean() - x[~after].mean()) if after.any() and (~after).any() else params["size_dps"]
        comp = params["size_dps"] * after
        what = f"the mean steps by {params['size_dps']:+.3g} deg/s at t = {ts:.1f} s"
    elif name == "rate_ramp":
        # LS slope on the full-rate series
        slope = float(_least_squares([t - t.mean()], x)[0])
        params["r_dps_per_s"] = slope
        comp = slope * t
        what = f"the bias drifts linearly by {params['r_dps_per_s']:+.3g} deg/s per s"
    elif name == "warmup":
        tau = params["tau_s"]
        g = np.exp(-t / tau)
        coef = _least_squares([g], x)
        params["amplitude_dps"] = float(coef[0])
        comp = coef[0] * g
        what = (f"the bias settles exponentially: {params['amplitude_dps']:+.3g} deg/s at t = 0, "
                f"time constant {tau:.3g} s")
    else:  # temperature
        tc = np.asarray(temp_c, dtype=float)
        coef = _least_squares([tc - tc.mean()], x)
        params["coefficient_dps_per_c"] = float(coef[0])
        comp = coef[0] * (tc - tc.mean())
        what = (f"the bias follows the temperature with {params['coefficient_dps_per_c']:+.3g} "
                f"deg/s per deg C over {np.ptp(tc):.2f} deg C")
    params = {k: float(v) for k, v in params.items()}
    return Candidate(
        effect=name, params=params, statistic=d, threshold=DETERMINISTIC_THRESHOLD,
        statistic_name="Delta chi^2 of the block means over a constant bias",
        component=comp - comp.mean(),
        evidence=(f"{what}; the fit lowers chi^2 of the block means by {d:.0f} (threshold "
                  f"{DETERMINISTIC_THRESHOLD:.0f}, white noise: chi^2_1 to chi^2_2 scan)"),
    )
