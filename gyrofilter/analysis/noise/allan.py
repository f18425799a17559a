"""Allan deviation of a rate series, with confidence intervals.

A gyro's rate samples ``x_k`` (any unit; the deviation comes out in the same unit) taken every
``tau0 = 1 / sample_rate_hz`` seconds are treated as *frequency* data in the sense of NIST SP
1065; the integrated angle ``X_j = tau0 * sum_{k<j} x_k`` (``X_0 = 0``, N + 1 points) is the
*phase*. With cluster size ``m`` (``tau = m tau0``) the overlapping Allan variance is
(NIST SP 1065, eq. 11, p. 16; paper 000 eq. 2 for the non-overlapping form)::

    sigma^2(tau) = 1 / (2 tau^2 (N - 2m + 1)) * sum_{j=0}^{N-2m} (X_{j+2m} - 2 X_{j+m} + X_j)^2

i.e. half the mean squared difference of adjacent cluster averages, taken at every start
sample. It is computed from cumulative sums in O(N) per tau, in cache-sized chunks so the extra
memory is one float64 copy of the input (the cumulative sum) plus a small work buffer.

Confidence intervals (see :func:`confidence_interval`):

* ``"simple"``: paper 000's relative error of the deviation, ``1 / sqrt(2 (N/m - 1))``, shown
  as ``sigma (1 -+ e)``;
* ``"chi2"``: NIST SP 1065 section 5.3: ``edf * s^2 / chi2_{p}(edf)`` with the equivalent
  degrees of freedom (edf) of the overlapping Allan variance for the dominant power-law noise
  type at that tau (SP 1065 Table 5; Howe, Allan & Barnes 1981).
"""
from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np

from ...errors import GyroFilterError, SettingsError
from ...inputs import check_number, number_array
from ...units import check_sample_rate_hz, one_value, plain

#: cluster count below which a deviation (and any fit using it) is flagged: paper 002 needs
#: N/m >= 9 for an error under 25 %.
MIN_CLUSTERS = 9
#: default tau spacing (points per decade)
POINTS_PER_DECADE = 10
#: work-buffer length for the chunked sums (fits in L2 cache)
_CHUNK = 1 << 16


class AllanInputError(GyroFilterError, ValueError):
    """The data or the requested cluster times cannot give an Allan deviation."""


class ConstantAxisError(AllanInputError):
    """An axis whose samples are all equal (a stuck or unconnected axis): nothing to characterise.
    ``axis``: its name; the others of a recording may still be analysed: ``varying``, the letters
    of the axes asked for whose samples are not all equal, where the caller has looked (None: not known)."""

    def __init__(self, message, axis):
        super().__init__(message)
        self.axis = axis
        self.varying = None


def refuse_constant(x, where, *, unit="deg/s", axis=None):
    """ConstantAxisError (of ``axis``) whose message starts with ``where`` when the finite series
    ``x`` (a float array) holds one value only (up to float64 rounding, :func:`~gyrofilter.units.one_value`): the one wording of a constant series' refusal
    (the Allan fit, the wavelet variance)."""
    if x.size and np.all(np.isfinite(x)) and one_value(x.min(), x.max()):
        raise ConstantAxisError(constant_words(where, x.size, x.flat[0], unit), axis)


def constant_words(where, n, value, unit="deg/s"):
    """The words of :func:`refuse_constant`: ``where``, the ``n`` samples and their one ``value``."""
    return (f"{where}: all {n} samples equal {value:g} {unit} (constant data): no noise to characterise "
            "(sensor not connected, or a saturated/stuck axis?)")


def rate_numbers(x, name="x"):
    """``x`` as a float64 array when it holds numbers (ints or floats), else AllanInputError naming
    ``name``: a masked value (converting would drop the mask and take the value behind it as
    data), complex numbers (converting drops the imaginary part), booleans, strings, objects or
    ragged lists (the rule and its words: :func:`gyrofilter.inputs.number_array`)."""
    array, problem = number_array(x, name)
    if problem is not None:
        raise AllanInputError(problem[0])
    return array


def _check_series(x, name="x"):
    """``x`` as a contiguous float64 series (:func:`rate_numbers`), or AllanInputError: not 1-D,
    fewer than 3 samples, or a value that is not finite."""
    x = rate_numbers(x, name)
    if x.ndim != 1:
        raise AllanInputError(
            f"{name} must be a 1-D rate series (one axis), got an array of shape {x.shape}; "
            "pass one column at a time")
    if x.size < 3:
        raise AllanInputError(
            f"{name} has {x.size} samples; an Allan deviation needs at least 3 (two clusters of one "
            f"sample plus one), and a noise fit needs {MIN_CLUSTERS} clusters per tau")
    bad = ~np.isfinite(x)
    if bad.any():
        first = int(np.argmax(bad))
        raise AllanInputError(
            f"{name} contains {int(bad.sum())} NaN/inf value(s), the first at sample {first}; "
            "the Allan deviation needs evenly spaced finite samples (fill or cut gaps first)")
    return np.ascontiguousarray(x)


def default_cluster_sizes(n_samples, points_per_decade=POINTS_PER_DECADE, min_clusters=MIN_CLUSTERS):
    """Log-spaced cluster sizes ``m`` from 1 to ``n_samples // min_clusters`` (about
    ``points_per_decade`` per decade, duplicates removed)."""
    m_max = int(n_samples // min_clusters)
    if m_max < 1:
        raise AllanInputError(
            f"{n_samples} samples are fewer than {min_clusters} clusters of one sample; "
            "record longer")
    if m_max == 1:
        return np.array([1], dtype=np.int64)
    n_points = max(2, int(math.ceil(points_per_decade * math.log10(m_max))) + 1)
    m = np.unique(np.round(np.logspace(0.0, math.log10(m_max), n_points)).astype(np.int64))
    return m[(m >= 1) & (m <= m_max)]


def cluster_sizes(n_samples, sample_rate_hz, taus_s=None):
    """Cluster sizes ``m = round(tau * fs)`` for ``taus_s`` (s; or the default grid when None),
    for ``n_samples`` samples at ``sample_rate_hz`` (fs, Hz).

    Raises :class:`AllanInputError` when a tau is shorter than one sample or so long that the
    record does not hold two clusters plus one sample (``2 m > N - 1``).
    """
    rate = check_sample_rate_hz(sample_rate_hz)
    if taus_s is None:
        return default_cluster_sizes(n_samples)
    taus, refused = number_array(taus_s, "taus_s", "s")  # numbers only: [True] was 1 s, "0.1" 0.1 s, ["a"] a ValueError
    if refused:
        raise SettingsError(refused[0])
    taus = np.atleast_1d(taus)
    if taus.ndim != 1 or taus.size == 0 or not np.all(np.isfinite(taus)):
        raise SettingsError(f"taus_s must be a 1-D list of finite cluster times in s, got {plain(taus_s)}")
    with np.errstate(over="ignore"):  # compared as floats: a tau of 1e300 s is no int64, 1e308 s at 100 Hz inf
        m = np.round(taus * rate)
    if np.any(m < 1):
        raise AllanInputError(
            f"tau {taus[m < 1].min():g} s is shorter than one sample (1/{rate:g} Hz = {1 / rate:g} s)")
    m_limit = (n_samples - 1) // 2
    if np.any(m > m_limit):
        raise AllanInputError(
            f"the record ({n_samples} samples = {n_samples / rate:g} s) is too short for tau = "
            f"{taus[m > m_limit].max():g} s: the longest tau with two clusters is "
            f"{m_limit / rate:g} s, and {MIN_CLUSTERS} clusters (paper 002) allow up to "
            f"{(n_samples // MIN_CLUSTERS) / rate:g} s")
    return m.astype(np.int64)


def _phase(x, tau0):
    """Integrated series X (N + 1 points, X_0 = 0) of the mean-removed rate, in chunks.

    Removing the mean does not change the Allan variance (second differences of X cancel a
    linear term) but keeps X small, so float64 cancellation stays at the 1e-16 level.
    """
    n = x.size
    mean = float(np.mean(x))
    phase = np.empty(n + 1, dtype=np.float64)
    phase[0] = 0.0
    carry = 0.0
    for start in range(0, n, _CHUNK):
        stop = min(n, start + _CHUNK)
        seg = phase[start + 1:stop + 1]
        np.subtract(x[start:stop], mean, out=seg)
        np.cumsum(seg, out=seg)
        seg += carry
        carry = float(seg[-1])
    phase *= tau0
    return phase


def _sum_second_difference_squared(phase, m, stride=1):
    """sum_j (X_{j+2m} - 2 X_{j+m} + X_j)^2 over j = 0, stride, 2 stride, ... <= len - 1 - 2m,
    and the number of terms."""
    n_terms = (phase.size - 1 - 2 * m) // stride + 1
    if stride != 1:
        idx = np.arange(n_terms) * stride
        d = phase[idx + 2 * m] - 2.0 * phase[idx + m] + phase[idx]
        return _sum_squares(d), n_terms
    buf = np.empty(min(_CHUNK, n_terms), dtype=np.float64)
    total = 0.0
    for start in range(0, n_terms, _CHUNK):
        stop = min(n_terms, start + _CHUNK)
        b = buf[:stop - start]
        # X_{j+2m} - 2 X_{j+m} + X_j, written without temporaries
        np.subtract(phase[start + 2 * m:stop + 2 * m], phase[start + m:stop + m], out=b)
        b -= phase[start + m:stop + m]
        b += phase[start:stop]
        total += _sum_squares(b)
    return total, n_terms


def _sum_squares(v):
    """sum_i v_i^2, by numpy's own loop: BLAS ddot (np.dot) starts OpenBLAS threads, which spin
    against whatever else runs on the machine (measured: 1 h at 1 kHz took 137 s instead of 12 s
    with the other core busy; ``python tools/bench_reader.py``)."""
    return float(np.einsum("i,i->", v, v))


def overlapping_adev(x, sample_rate_hz, taus_s=None):
    """Overlapping Allan deviation of the 1-D rate series ``x``.

    ``sigma^2(m tau0) = sum_{j=0}^{N-2m} (X_{j+2m} - 2X_{j+m} + X_j)^2 / (2 (m tau0)^2 (N-2m+1))``
    with ``X`` the integral of ``x`` (NIST SP 1065 eq. 11). Equal to allantools
    ``oadev(x, rate, data_type="freq", taus)``.

    Parameters
    ----------
    x : array_like, shape (N,)
        Rate samples in any unit; the deviation is in the same unit.
    sample_rate_hz : float
        Sampling rate (Hz); ``tau0 = 1 / sample_rate_hz``.
    taus_s : array_like or None
        Cluster times (s), rounded to whole samples. None: log-spaced, about 10 per decade, from
        one sample up to a ninth of the record (so every tau has at least 9 clusters).

    Returns
    -------
    tau_s, adev : ndarray
        The cluster times actually used (``m / sample_rate_hz``) and the deviations.
    """
    return _deviation(x, sample_rate_hz, taus_s, overlapping=True)


def _deviation(x, sample_rate_hz, taus_s, overlapping):
    """sqrt(sum of squared second differences / (2 n_terms)) / tau at every cluster size; the
    second differences start at every sample (overlapping) or every m-th (non-overlapping)."""
    rate = check_sample_rate_hz(sample_rate_hz)
    x = _check_series(x)
    m = cluster_sizes(x.size, rate, taus_s)
    phase = _phase(x, 1.0 / rate)
    out = np.empty(m.size, dtype=np.float64)
    for i, mi in enumerate(m):
        total, n_terms = _sum_second_difference_squared(phase, int(mi), stride=1 if overlapping else int(mi))
        out[i] = math.sqrt(total / (2.0 * n_terms)) / (mi / rate)
    if not np.all(np.isfinite(out)):  # squares beyond float64: |x| near 1e150 or more
        raise AllanInputError(f"x: values up to {float(np.max(np.abs(x))):.3g} overflow the squares of the Allan "
                              "variance in float64; give the series in a unit that keeps it below about 1e100")
    return m / rate, out


def adev(x, sample_rate_hz, taus_s=None):
    """Non-overlapping Allan deviation (paper 000 eq. 2; NIST SP 1065 eq. 7).

    ``sigma^2(tau) = 1 / (2 (K - 1)) sum_k (xbar_{k+1} - xbar_k)^2`` over the ``K = N // m``
    adjacent cluster averages. Less precise than :func:`overlapping_adev`; kept for the
    reference values of paper 000 and Stable32. ``x``, ``sample_rate_hz`` (Hz) and ``taus_s`` (s)
    as for :func:`overlapping_adev`; returns what it returns.
    """
    return _deviation(x, sample_rate_hz, taus_s, overlapping=False)


# --------------------------------------------------------------------------------------------
# Confidence intervals
# --------------------------------------------------------------------------------------------

#: power-law exponent alpha of the rate PSD S(f) ~ f^alpha for each noise type (NIST SP 1065
#: names, with the gyro rate playing the part of frequency): quantization = white PM (+2),
#: angle random walk = white FM (0), bias instability = flicker FM (-1), rate random walk =
#: random-walk FM (-2).
ALPHA = {"white_pm": 2, "flicker_pm": 1, "white_fm": 0, "flicker_fm": -1, "random_walk_fm": -2}


def n_clusters(n_samples, m):
    """Number of non-overlapping clusters ``N // m`` of ``n_samples`` (N) samples at cluster size
    ``m`` (paper 000's K = N/n; paper 002 wants >= 9)."""
    return np.asarray(n_samples // np.asarray(m, dtype=np.int64), dtype=np.int64)


def edf_oavar(n_samples, m, alpha):
    """Equivalent degrees of freedom of the overlapping Allan variance at cluster size ``m``
    for pure power-law noise ``S(f) ~ f^alpha`` (NIST SP 1065 Table 5, p. 40; N = number of
    *phase* points = ``n_samples + 1``)::

        alpha = +2: (N+1)(N-2m) / (2(N-m))
        alpha = +1: exp(sqrt(ln((N-1)/2m) ln((2m+1)(N-1)/4)))
        alpha =  0: (3(N-1)/(2m) - 2(N-2)/N) 4m^2 / (4m^2 + 5)
        alpha = -1: 2(N-2)/(2.3N - 4.9) for m = 1,  5N^2 / (4m(N+3m)) for m >= 2
        alpha = -2: (N-2)/m ((N-1)^2 - 3m(N-1) + 4m^2) / (N-3)^2

    Returns an array (broadcast over ``m``), clipped below at 1.
    """
    n = float(n_samples) + 1.0
    m = np.asarray(m, dtype=np.float64)
    if alpha == 2:
        edf = (n + 1) * (n - 2 * m) / (2 * (n - m))
    elif alpha == 1:
        a = np.maximum((n - 1) / (2 * m), 1.0)
        b = (2 * m + 1) * (n - 1) / 4
        edf = np.exp(np.sqrt(np.log(a) * np.log(b)))
    elif alpha == 0:
        edf = (3 * (n - 1) / (2 * m) - 2 * (n - 2) / n) * 4 * m ** 2 / (4 * m ** 2 + 5)
    elif alpha == -1:
        edf = np.where(m < 2, 2 * (n - 2) / (2.3 * n - 4.9), 5 * n ** 2 / (4 * m * (n + 3 * m)))
    elif alpha == -2:
        edf = (n - 2) / m * ((n - 1) ** 2 - 3 * m * (n - 1) + 4 * m ** 2) / (n - 3) ** 2
    else:
        raise SettingsError(f"alpha must be one of +2, +1, 0, -1, -2 (NIST SP 1065 Table 5), got {plain(alpha)}")
    return np.maximum(edf, 1.0)


def edf_mixture(n_samples, m, shares, alphas):
    """EDF of the overlapping Allan variance of a sum of independent power-law noises.

    ``n_samples``: N; ``m``: cluster sizes; ``alphas[k]``: noise k's power-law exponent
    (S(f) ~ f^alpha, as for :func:`edf_oavar`); ``shares[k, i]`` is noise k's part of the Allan
    variance at ``m[i]`` (any scale). The
    standard deviation of a sum of estimates is at most the sum of their standard deviations
    (Cauchy-Schwarz; the cross terms of the quadratic estimator are non-negative), so with
    ``sd_k = share_k sqrt(2 / edf_k)``::

        edf = 2 (sum_k share_k)^2 / (sum_k share_k sqrt(2 / edf_k))^2

    which is never larger than the true EDF (a conservative interval).
    """
    shares = np.atleast_2d(np.asarray(shares, dtype=np.float64))
    total = shares.sum(axis=0)
    sd = np.zeros_like(total)
    for share, alpha in zip(shares, alphas):
        sd += share * np.sqrt(2.0 / edf_oavar(n_samples, m, alpha))
    with np.errstate(divide="ignore", invalid="ignore"):
        edf = np.where(sd > 0, 2.0 * (total / np.where(sd > 0, sd, 1.0)) ** 2, 1.0)  # a ratio: any scale
    return np.maximum(edf, 1.0)


def chi2_ppf(p, dof):
    """Quantile ``p`` of the chi-square distribution with ``dof`` degrees of freedom (scipy when installed, else Wilson-Hilferty:
    ``k (1 - 2/(9k) + z_p sqrt(2/(9k)))^3``, within 1 % for k >= 3). scipy's ``special.chdtri``
    (the inverse upper tail: ``chdtri(k, 1 - p)``) is ``stats.chi2.ppf``'s own kernel without
    the 50 MB that importing ``scipy.stats`` costs."""
    dof = np.asarray(dof, dtype=np.float64)
    try:
        from scipy.special import chdtri
    except ImportError:  # pragma: no cover - scipy is present in the test environment
        z = NormalDist().inv_cdf(p)
        c = 2.0 / (9.0 * dof)
        return dof * np.maximum(1.0 - c + z * np.sqrt(c), 1e-6) ** 3
    return chdtri(dof, 1.0 - p)


#: the highest confidence of the Allan intervals: nearer 1 the quantiles' probabilities
#: 0.5 +- c / 2 round to 0 or 1 (0.9999999999999999 gave the interval (0, inf) and ended in
#: statistics' StatisticsError in the fitted intervals; ``allan --confidence`` stopped here)
MAX_CONFIDENCE = 0.9999


def check_confidence(confidence, what="confidence"):
    """``confidence`` as a float in (0, :data:`MAX_CONFIDENCE`], or SettingsError naming ``what``:
    a number as :func:`~gyrofilter.inputs.check_number` takes it (numpy's and 0-d arrays the
    numbers they hold, never a bool; a longdouble ended in scipy's TypeError, a text in Python's).
    The one check of a confidence of the Allan intervals."""
    try:
        return check_number(confidence, what, low=0.0, high=MAX_CONFIDENCE, low_open=True)
    except SettingsError:
        raise SettingsError(f"{what} must be in (0, {MAX_CONFIDENCE:g}] (e.g. 0.95), got {plain(confidence)}") from None


def confidence_text(confidence):
    """A confidence as the percent it is, to its last given digit: 0.95 -> '95%', 0.9999 -> '99.99%'
    (a whole percent named 0.9999 a 100% interval); the one text of a confidence of the Allan intervals."""
    return f"{100.0 * float(confidence):.6g}%"


def chi2_interval(avar, edf, confidence=0.95):
    """Two-sided interval for the Allan *variance* (NIST SP 1065 eq. 41, p. 42)::

        edf s^2 / chi2_{(1+c)/2}(edf)  <=  sigma^2  <=  edf s^2 / chi2_{(1-c)/2}(edf)

    ``avar``: s^2, the estimates ((deg/s)^2); ``edf``: their degrees of freedom; ``confidence``:
    c, in (0, 1). Returns (low, high).
    """
    confidence = check_confidence(confidence)
    avar = np.asarray(avar, dtype=np.float64)
    edf = np.asarray(edf, dtype=np.float64)
    low = edf * avar / chi2_ppf(0.5 + confidence / 2.0, edf)
    high = edf * avar / chi2_ppf(0.5 - confidence / 2.0, edf)
    return low, high


def simple_interval(adev_values, n_samples, m):
    """Paper 000's one-sigma bound on the *deviation*: ``sigma (1 -+ 1/sqrt(2 (N/m - 1)))``
    (N = 10000, m = 100 -> 7.11 %), sigma = ``adev_values`` (deg/s), N = ``n_samples``, m the
    cluster sizes. Returns (low, high, relative_error); low is clipped at 0."""
    ratio = np.asarray(n_samples / np.asarray(m, dtype=np.float64))
    with np.errstate(divide="ignore"):
        rel = 1.0 / np.sqrt(2.0 * np.maximum(ratio - 1.0, 0.0))
    adev_values = np.asarray(adev_values, dtype=np.float64)
    return np.maximum(adev_values * (1.0 - rel), 0.0), adev_values * (1.0 + rel), rel
