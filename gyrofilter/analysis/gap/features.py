"""The features of the gap analysis (:mod:`gyrofilter.analysis.gap.pipeline`, step 2) and how far a
measurement departs from its simulations.

The features of one axis (:func:`features`): the overlapping Allan deviation at log-spaced tau
(:func:`feature_adev`), band powers of the periodogram in log-spaced bands, the largest
periodogram line over the local noise level, the lag-1 autocorrelation of the high-passed noise,
the spike count and the tail statistic (the winsorized kurtosis of the prewhitened noise,
:func:`gyrofilter.analysis.gap.detectors.tails_statistic`). Each feature's departure is ``z = (f_meas - mean_sims) / max(sd_sims,
floor)`` (:func:`departures`); the discrepancy ``D = mean_k z_k^2`` (:func:`discrepancy`) is the
gap's measure of fit. The sentences of the report that say where a measurement departs most
(:func:`strongest`, :func:`still_departs`) are here too.
"""
from __future__ import annotations

import math

import numpy as np

from .. import stats
from . import detectors as det

METRIC = ("mean squared z-score of the Allan deviation, band powers, spectral line, lag-1, spike count and tail statistic "
          "vs model simulations")
#: floors of the feature spreads (log units for log features)
_LOG_FLOOR = 0.02


# ---------------------------------------------------------------------------------------------
# features


def feature_taus(n, sample_rate_hz):
    """Log-spaced cluster times (s), 6 per decade, one sample to a ninth of the record."""
    m_max = max(1, n // 9)
    m = np.unique(np.round(np.logspace(0, math.log10(m_max), max(2, int(6 * math.log10(max(m_max, 2))) + 1))).astype(int))
    return m / sample_rate_hz


def feature_bands(n, sample_rate_hz, count=24):
    """Log-spaced frequency band edges (Hz) from 8 / T to f_s / 2."""
    f_lo = 8.0 * sample_rate_hz / n
    f_hi = sample_rate_hz / 2
    if f_lo >= f_hi:
        return np.array([0.0, f_hi])
    return np.geomspace(f_lo, f_hi, count + 1)


#: the Allan feature starts a second difference every max(1, m // ADEV_STARTS) samples
ADEV_STARTS = 8
#: at most this many second differences per tau (:data:`_ADEV_CHUNK`-long runs of consecutive
#: start points, evenly spread over the record) once a record has more
ADEV_MAX_TERMS = 1 << 20


def feature_adev(x, sample_rate_hz, taus_s):
    """Overlapping Allan deviation with the second differences started every
    ``s = max(1, m // 8)`` samples instead of every sample, and at most
    :data:`ADEV_MAX_TERMS` of them per tau:

    ``sigma^2(m tau0) = sum_{j in J} (X_{j+2m} - 2 X_{j+m} + X_j)^2 / (2 (m tau0)^2 |J|)``,
    ``X`` the integral of the mean-removed rate (NIST SP 1065 eq. 11 on a subset ``J`` of its
    start points). ``J`` = ``0, s, 2s, ... <= N - 2m``; where that is more than
    :data:`ADEV_MAX_TERMS` start points, ``J`` keeps :data:`ADEV_MAX_TERMS` of them in runs of
    :data:`_ADEV_CHUNK` consecutive ones, evenly spread from the first to the last (runs, not a
    coarser stride: a stride could alias a periodic rate onto one phase).

    The expectation is that of the fully overlapping estimator. Neighbouring second
    differences overlap in all but ``s`` of ``2m`` samples, so keeping 8 per cluster length loses
    almost nothing: on white noise and on a random walk (300 runs of 60 000 samples, m = 1 to
    6666) the spread of log sigma was within 2 % of the fully overlapping one. The cap binds only
    at short taus of long records (m < 8 |J|max / N: up to m = 66 for a day at 100 Hz), where
    2^20 terms still leave a spread of log sigma near 1 / sqrt(2^21) = 0.07 %, far below the
    features' floor of 2 % (:data:`_LOG_FLOOR`). The cost falls from one pass over the record
    per tau to about 9 passes for all taus together, and to about 2 for a day at 100 Hz. The
    measurement and its simulations use the same estimator."""
    n = x.size
    phase = np.empty(n + 1)
    phase[0] = 0.0
    np.subtract(x, float(np.mean(x)), out=phase[1:])
    np.cumsum(phase[1:], out=phase[1:])  # X in units of 1 / f_s: sigma = sqrt(...) / m below
    m_all = np.round(np.asarray(taus_s, dtype=float) * sample_rate_hz).astype(np.int64)
    out = np.empty(m_all.size)
    buf = np.empty(_ADEV_CHUNK)
    for i, m in enumerate(m_all):
        m = int(m)
        step = max(1, m // ADEV_STARTS)
        k = (n - 2 * m) // step + 1
        total = 0.0
        for a, b in _adev_runs(k):  # into one buffer: no N-long temporaries
            d = buf[:b - a]
            np.multiply(phase[m + a * step:m + (b - 1) * step + 1:step], -2.0, out=d)
            d += phase[2 * m + a * step:2 * m + (b - 1) * step + 1:step]
            d += phase[a * step:(b - 1) * step + 1:step]
            total += float(stats.dot(d, d))
        out[i] = math.sqrt(total / (2.0 * min(k, ADEV_MAX_TERMS))) / m
    return out


_ADEV_CHUNK = 1 << 15


def _adev_runs(k):
    """The runs ``(a, b)`` of start-point indices ``a .. b - 1`` (of ``0 .. k - 1``) that
    :func:`feature_adev` sums: all of them in :data:`_ADEV_CHUNK` pieces up to
    :data:`ADEV_MAX_TERMS`, else ``ADEV_MAX_TERMS / _ADEV_CHUNK`` runs of :data:`_ADEV_CHUNK`
    evenly spread, the first at 0 and the last ending at ``k``."""
    if k <= ADEV_MAX_TERMS:
        return [(a, min(k, a + _ADEV_CHUNK)) for a in range(0, k, _ADEV_CHUNK)]
    runs = ADEV_MAX_TERMS // _ADEV_CHUNK
    starts = np.round(np.linspace(0, k - _ADEV_CHUNK, runs)).astype(np.int64)
    return [(int(a), int(a) + _ADEV_CHUNK) for a in starts]


def features(x, sample_rate_hz, taus_s, bands_hz, overwrite=False):
    """Feature vector of one axis: (log ADEV per tau (:func:`feature_adev`), log band powers,
    log line ratio, lag1, log(1 + spikes), log winsorized kurtosis). Returns a dict of arrays.

    ``overwrite``: ``x`` is the caller's to lose (a simulated run, a fresh copy of an axis): the
    periodogram, computed last, uses it as its work space. Memory besides ``x``: one N-sample
    array (the high-passed series, shared by the lag-1 and the tail statistics; then the
    detrended copy for the periodogram, unless ``overwrite``) and the half-length periodogram."""
    adev = feature_adev(x, sample_rate_hz, taus_s)
    mask, _, _ = det.outlier_statistic(x)
    spikes = math.log1p(float(mask.sum()))
    del mask
    e = det.highpassed(x, sample_rate_hz)[0] if x.size >= 64 else None
    r1, _ = det.lag1_statistic(x, sample_rate_hz, e=e)
    tails = det.tails_statistic(x, sample_rate_hz, u=det.tail_residual(x, sample_rate_hz, e=e))
    del e
    line, _, _, spec = det.sinusoid_statistic(x, sample_rate_hz, return_spectrum=True, overwrite=overwrite)
    n_p = det.periodogram_length(x.size)  # the samples the periodogram uses
    if spec is None:
        spec = det.periodogram(x, overwrite=overwrite)
    idx = _first_bins(bands_hz, spec.size, n_p, sample_rate_hz)
    bp = np.array([spec[a:b].mean() if b > a else np.nan for a, b in zip(idx[:-1], idx[1:])])
    return {"adev": np.log(np.maximum(adev, 1e-300)), "band": np.log(np.maximum(bp, 1e-300)),
            "line": np.array([math.log(max(line, 1.0))]), "lag1": np.array([r1]),
            "spikes": np.array([spikes]), "tails": np.array([tails])}


def _first_bins(freqs_hz, size, n, sample_rate_hz):
    """For each frequency, the first periodogram bin ``j`` (of ``size``) with
    ``j f_s / N >= f``: ``searchsorted(arange(size) f_s / N, f)`` without the array."""
    idx = np.clip(np.ceil(np.asarray(freqs_hz, dtype=float) * n / sample_rate_hz).astype(np.int64), 0, size)
    for i, f in enumerate(np.asarray(freqs_hz, dtype=float)):  # settle float rounding at the edge
        while idx[i] > 0 and (idx[i] - 1) * sample_rate_hz / n >= f:
            idx[i] -= 1
        while idx[i] < size and idx[i] * sample_rate_hz / n < f:
            idx[i] += 1
    return idx


_FLOORS = {"adev": _LOG_FLOOR, "band": _LOG_FLOOR, "line": 0.3, "lag1": None, "spikes": 0.5, "tails": None}


#: a feature's spread is pooled with the baseline's where the two models' means differ by at
#: most this many standard errors (:func:`departures`)
POOL_SE = 2.0


def departures(meas, sims, n, pool=None):
    """z-scores of the measured features against the simulated runs (dict of ``(z, mean, sd)``).

    ``pool``: ``(deps, runs)``, the baseline's departures and its number of runs, for an
    extended model's few runs (6 against the baseline's 12 or more). Where the two models agree
    at a feature (means within :data:`POOL_SE` standard errors, ``|m - m_0| <= 2 sqrt(s^2/k +
    s_0^2/k_0)``) the extension does not touch it, and its spread is the pooled one,
    ``s^2 = ((k - 1) s^2 + (k_0 - 1) s_0^2) / (k + k_0 - 2)``: from 5 degrees of freedom an sd is
    known within a factor of about 2 either way, and one that falls low by chance multiplies z
    (a sinusoid's extended model put the Allan deviation at 270 s of an hour at z = +10 with an
    sd of 0.044 where the baseline's 12 runs give 0.115, so D 3.9, and the composite step added
    a bias instability the record does not have; pooled: sd 0.10, z = +4.5, D 1.8). Where they differ, the model's own spread."""
    out = {}
    for key, value in meas.items():
        stack = np.array([s[key] for s in sims])
        k = len(sims)
        mean = np.nanmean(stack, axis=0)
        sd = np.nanstd(stack, axis=0, ddof=1) if k > 1 else np.zeros_like(mean)
        if pool is not None and k > 1:
            (_, mean_0, sd_0), k_0 = pool[0][key], pool[1]
            same = np.abs(mean - mean_0) <= POOL_SE * np.sqrt(sd ** 2 / k + sd_0 ** 2 / k_0)
            sd = np.where(same, np.sqrt(((k - 1) * sd ** 2 + (k_0 - 1) * sd_0 ** 2) / (k + k_0 - 2)), sd)
        floor = _FLOORS[key] if _FLOORS[key] is not None else 1.0 / math.sqrt(n)
        z = (value - mean) / np.maximum(sd, floor)
        out[key] = (np.where(np.isfinite(z), z, 0.0), mean, sd)
    return out


def discrepancy(deps):
    """``D = mean z^2`` over all features of one axis (lower is better)."""
    z = np.concatenate([v[0] for v in deps.values()])
    return float(np.mean(z ** 2)) if z.size else 0.0


#: a D beyond it is written "far outside (D > 1e+06)", not as a number (:func:`d_shown`)
D_FAR = 1e6


def d_shown(value):
    """A discrepancy D as the notes and reports write it: 3 significant digits, or "far outside
    (D > 1e+06)" beyond :data:`D_FAR`. So large a D comes from a spread of the simulations near 0
    (an axis constant but for one sample: "0.643 -> 4.96e+08"); it says that the model is far
    off, and its digits say nothing more. The JSON keeps the number."""
    return f"far outside (D > {D_FAR:g})" if value > D_FAR else f"{value:.3g}"


# ---------------------------------------------------------------------------------------------
# what the report says about the departures


def departure_summary(deps, meas, taus, bands):
    """Per-axis departures: z per feature, and the measured and simulated values (natural
    logs for the Allan deviation in deg/s and the band powers in (deg/s)^2 per bin)."""
    fl = lambda v: [float(u) for u in v]  # noqa: E731
    return {"adev_tau_s": fl(taus), "adev_z": fl(deps["adev"][0]),
            "adev_meas_log": fl(meas["adev"]),
            "adev_sim_mean_log": fl(deps["adev"][1]), "adev_sim_sd_log": fl(deps["adev"][2]),
            "band_edges_hz": fl(bands), "band_z": fl(deps["band"][0]),
            "band_meas_log": fl(meas["band"]),
            "band_sim_mean_log": fl(deps["band"][1]), "band_sim_sd_log": fl(deps["band"][2]),
            "line_z": float(deps["line"][0][0]), "lag1_z": float(deps["lag1"][0][0]),
            "spikes_z": float(deps["spikes"][0][0]), "tails_z": float(deps["tails"][0][0]),
            "discrepancy": discrepancy(deps)}


def _furthest(deps, taus, bands):
    """(feature key, z, index, description) of the feature furthest outside the simulations' spread."""
    best = None
    for key, (z, mean, sd) in deps.items():
        j = int(np.argmax(np.abs(z)))
        if best is None or abs(z[j]) > abs(best[1]):
            best = (key, float(z[j]), j)
    key, z, j = best
    where = {"adev": lambda: f"Allan deviation at tau = {taus[j]:.3g} s",
             "band": lambda: f"spectrum band {bands[j]:.3g}-{bands[j + 1]:.3g} Hz",
             "line": lambda: "largest spectral line",
             "lag1": lambda: "lag-1 autocorrelation",
             "spikes": lambda: "spike count",
             "tails": lambda: "tail statistic (winsorized kurtosis of the noise)"}[key]()
    return key, z, j, where


def strongest(deps, taus, bands, axis):
    """A sentence on where the measurement of ``axis`` is furthest outside the simulations' spread
    ("" below :data:`~gyrofilter.analysis.gap.detectors.REPORTED_DEPARTURE_Z` sd). It ends the
    evidence of each finding of the axis, so it names the axis as a whole: "largest departure in
    the Allan deviation at tau = 7.17 s" under a band at 20 Hz read as the band's."""
    _, z, _, where = _furthest(deps, taus, bands)
    if abs(z) < det.REPORTED_DEPARTURE_Z:
        return ""
    return (f"axis {axis} as a whole departs most from the baseline simulations in the {where}, "
            f"z = {z:+.1f} sd of the simulated spread")


def departs_most(deps, taus, bands):
    """The feature furthest outside the simulations' spread, for the report: ``{"feature": key
    of :func:`features`, "where": its description, "z": its departure}``."""
    key, z, _, where = _furthest(deps, taus, bands)
    return {"feature": key, "where": where, "z": z}


def still_departs(axis, d_after, deps, taus, bands):
    """The note on an axis whose D after extension is above :data:`~gyrofilter.analysis.gap.detectors.OUTSIDE_NULL_D`: the feature
    furthest outside the extended model's simulations, and what its sign says. For the Allan
    deviation and the band powers, fast (tau < 1 s or above 1 Hz: the white, colored and band
    noise) or slow scales (the bias terms); above the simulations, more power than the model
    holds there (an effect the table lacks or too weak to name), below, a fitted term too strong
    at that scale."""
    key, z, j, where = _furthest(deps, taus, bands)
    text = (f"axis {axis}: after extension D = {d_shown(d_after)}, above {det.OUTSIDE_NULL_D:g} (clean records of 27 s "
            f"to 2.8 h stay below it in 95 % of runs): the model does not close here. The {where} departs most "
            f"(z = {z:+.1f} sd of the extended model's simulations)")
    if key in ("adev", "band"):
        fast = taus[j] < 1.0 if key == "adev" else bands[j] >= 1.0
        scale = "fast scales: the white, colored or band noise" if fast else "slow scales: the bias terms"
        if z > 0:
            return text + f"; the measurement holds more power there than the model ({scale} miss a part)"
        return text + f"; the model puts too much power there ({scale} are too strong at that scale)"
    if key == "tails":
        return text + ("; the noise's tails are heavier than the model's" if z > 0 else
                       "; the model's noise is heavier-tailed than the measurement's")
    return text + {"line": "; a spectral line the model lacks", "lag1": "; the noise's short correlation differs",
                   "spikes": "; spikes the model lacks or overstates"}[key]


def discrepancy_error(meas, sims, n, pool=None):
    """The sampling error of D of the measurement ``meas`` against the runs ``sims`` (a model's
    spread pooled by ``pool`` as in :func:`departures`): the jackknife over the runs (Efron &
    Tibshirani 1993, ch. 11), D with run ``j`` left out for each ``j`` and
    ``se = sqrt((m - 1) / m sum_j (D_j - mean D)^2)``. 0 with fewer than 3 runs. D is ratio-like:
    one feature far outside a spread estimated from a few runs makes its error of the order of D
    itself (a hidden sinusoid's axis: 17.6 +- 10.4 from 10 runs)."""
    m = len(sims)
    if m < 3:
        return 0.0
    d = np.array([discrepancy(departures(meas, sims[:j] + sims[j + 1:], n, pool)) for j in range(m)])
    return float(np.sqrt((m - 1) / m * np.sum((d - d.mean()) ** 2)))


def null_spread(sims, n, pool=None):
    """The null spread of D of a model from its simulated runs' features ``sims`` (a list, one
    dict of features per run): ``sd_j(D_j)`` with ``D_j`` the discrepancy of run ``j`` against
    the other runs (:func:`gyrofilter.analysis.gap.features.departures`, with the measurement's
    ``pool``), ``n`` the samples per run. 0 with fewer than 3 runs."""
    if len(sims) < 3:
        return 0.0
    d = [discrepancy(departures(sims[j], sims[:j] + sims[j + 1:], n, pool)) for j in range(len(sims))]
    return float(np.std(d, ddof=1))
