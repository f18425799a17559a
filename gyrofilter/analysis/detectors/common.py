"""Shared by the detectors: every threshold of the gap analysis (the detectors' significance
levels and the gap's decision rules), :class:`Candidate` and the series helpers."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...units import MAD_TO_SIGMA

#: expected number of false spikes per axis on white Gaussian noise (with at least
#: OUTLIER_MIN_COUNT spikes required: P(Poisson(0.05) >= 3) = 2e-5 per axis)
OUTLIER_FALSE_PER_AXIS = 0.05
#: minimum number of spikes for an outlier finding
OUTLIER_MIN_COUNT = 3
#: heavy tails (detectors.tails): the winsorizing level (robust sd) of the tail statistic, the
#: z its value must reach against the baseline's simulations (or its Gaussian sampling sd), the
#: 2 Delta log L a Gaussian scale mixture must gain over a Gaussian, and the 2 Delta log L by
#: which it must beat isolated spikes where the outlier detector found spikes (10: "very strong"
#: evidence, Kass & Raftery 1995, sec. 3.2). The mixture's threshold is set from clean records
#: only: on 100 simulated ones (white, AR(1) lag1 0.3-0.85, a two-tap average, a narrow band, a
#: large sinusoid, 1 kHz; 10-60 min, MPU6050 quantization) its largest value was 7.4, on the
#: real MPU6050 and ADIS16405 static records (15 axes) 11.3, so 30 sits 2.7-4 times above
TAILS_WINSOR_SD = 6.0
#: a rate quantized in steps above this many noise sd has the quantizer's distribution, not the
#: noise's: its tails are not judged without the baseline's simulations, which carry the same
#: quantizer (the MPU6050 at 131 LSB per deg/s: 0.06-0.11)
TAILS_MAX_STEP_SD = 0.5
HEAVY_TAILS_Z = 4.0
HEAVY_TAILS_THRESHOLD = 30.0
HEAVY_TAILS_OVER_SPIKES = 10.0
#: false-alarm probability per axis for the periodogram line test
SINUSOID_ALPHA = 1e-4
#: z-score (in units of 1/sqrt(N)) the lag-1 autocorrelation must exceed, and the smallest
#: |lag1| reported (smaller correlations are real but immaterial)
COLORED_Z = 6.0
COLORED_MIN_LAG1 = 0.03
#: the colored noise's lag-2 is reported (a first-order ARMA instead of the low pass) when it
#: falls below lag1^2 (the AR(1) value) by COLORED_Z standard errors and by at least this much
COLORED_MIN_LAG2_GAP = 0.01
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
#: 2 Delta log L (exact likelihood) a Gauss-Markov process must gain over a random walk
EXACT_GM_MARGIN = 8.0
#: a Gauss-Markov process whose tau exceeds the record length over this is a random walk as far
#: as the data can tell
GM_MAX_TAU_DIVISOR = 5
#: the band statistic (peak excess over the background in units of its sampling error,
#: ``(R - 1) sqrt(K)``) a band must exceed; on white and AR(1) noise (white + 0.3 white, lag1
#: -0.7 to 0.7, 4096 to 10^6 samples at 99.37, 100 and 285.7 Hz, 240 runs, issue 12) its
#: largest value was 2.16 (at 4096 samples and 285.7 Hz; 1.5-1.7 from 7 500 samples up), its
#: 99th percentile 1.73; on 400 more of 4096-12 000 samples 2.31 (2.29 within W of f_s / 2);
#: at the Nyquist edge of AR(1) lag1 -0.7 (a PSD peaking at f_s / 2) 2.2 on 10^6 and 2.4 on
#: 8.64 * 10^6 samples at 100 Hz
NARROWBAND_THRESHOLD = 4.0
#: D above which an axis is clearly outside the null band (its 95th percentile is 1.06-1.96 on
#: clean records of 27 s to 2.8 h, docs/gap_closure.md): an extended axis is then tried with a
#: composite stochastic part, and the report says which feature still departs
OUTSIDE_NULL_D = 2.0
#: two readings of a slow departure (the temperature's and one in time) explain a record about
#: equally when their D differ by at most this many null spreads (the sd of D over a model's own
#: simulated runs, leave one out; gap_readings): the band D keeps in 95 % of records a model
#: explains exactly. Measured on the example model (docs/gap.md, "Confounded causes")
CONFOUNDED_SPREADS = 2.0
#: the factor a composite stochastic part must lower D by
COMPOSITE_MIN_GAIN = 0.8
#: a finding's evidence names the feature furthest outside the baseline simulations' spread when
#: it is at least this many standard deviations of that spread away
REPORTED_DEPARTURE_Z = 3
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


#: samples per pass of the chunked series helpers (:func:`detrend_line`, :func:`moving_mean`): their
#: temporaries are a few MB whatever the record's length
PASS_SAMPLES = 1 << 16


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


def block_means(x, max_blocks=MAX_BLOCKS):
    """Means of ``n`` consecutive blocks of ``L = ceil(N / max_blocks)`` samples (a trailing
    partial block is dropped). Returns ``(y, L)``."""
    n_samples = x.size
    length = max(1, int(math.ceil(n_samples / max_blocks)))
    n = n_samples // length
    y = x[: n * length].reshape(n, length).mean(axis=1)
    return y, length
