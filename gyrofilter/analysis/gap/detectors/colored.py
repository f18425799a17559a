"""Detector 3, ``colored_noise``: the lag-1 and lag-2 autocorrelations of the high-passed noise (see :mod:`gyrofilter.analysis.gap.detectors`)."""

from __future__ import annotations

import math

import numpy as np

from ....effects import COLORED_NOISE, NARROWBAND, RESONATORS, WANDERING_TONE
from .common import COLORED_MIN_LAG1, COLORED_MIN_LAG2_GAP, COLORED_Z, REPEATS_LAG2_MIN_WEIGHT, Candidate
from ...stats import dot, moving_mean
from .resonance import band_correlation
from ....sim.noise_terms import arma11_from_lags, arma11_long_run_ratio


# ---------------------------------------------------------------------------------------------
# 3. colored noise


def colored_window(n, sample_rate_hz):
    """High-pass window (samples) for the lag-1 statistic: 64 samples or 0.5 s."""
    return int(min(max(64, round(0.5 * sample_rate_hz)), max(8, n // 8)))


def highpassed(x, sample_rate_hz):
    """``(x - moving_mean(x, W), W)``, W of :func:`colored_window`."""
    w = colored_window(x.size, sample_rate_hz)
    e = moving_mean(x, w)
    np.subtract(x, e, out=e)
    return e, w


def lag1_statistic(x, sample_rate_hz, e=None):
    """Lag-1 autocorrelation of ``x - moving_mean(x, W)`` (``e``, when the caller has it);
    white noise: about -1/W."""
    if x.size < 32:
        return 0.0, 0
    e, w = highpassed(x, sample_rate_hz) if e is None else (e, colored_window(x.size, sample_rate_hz))
    den = float(dot(e, e))
    if den <= 0:
        return 0.0, w
    return float(dot(e[1:], e[:-1]) / den), w


def long_run_ratio(lag1, lag2=None):
    """Spectrum at zero over the variance, 1 + 2 Σ_k ρ_k, of the colored noise with these
    autocorrelations (``lag2`` None: the AR(1), (1 + ρ₁) / (1 - ρ₁));
    :func:`gyrofilter.sim.noise_terms.arma11_long_run_ratio`."""
    pair = None if lag2 is None else arma11_from_lags(lag1, lag2)
    phi, mu = pair if pair is not None else (lag1, 0.0)
    return arma11_long_run_ratio(phi, mu)


def lags_from_highpassed(r1, r2, window, band_lags=None, band_share=0.0):
    """Undo the high-pass, and take out a band's share: the colored noise's (rho_1, rho_2) from
    the lag-1 and lag-2 autocorrelations r1, r2 of the high-passed series (``r2`` None: rho_1
    alone, of an AR(1)).

    Removing the moving mean of ``W`` samples removes the colored noise's long-run variance over
    W, ``c v_c`` with ``c = L / W`` (L = :func:`long_run_ratio`), from its variance and from its
    lag-k covariances alike (k << W); a band (``band_lags`` = its (r_L1, r_L2),
    :func:`narrowband_lags`; ``band_share`` = v_L / V, its variance over that of the high-passed
    series) has no power at zero and loses nothing. So, in units of the high-passed variance V,
    r_k = rho_k v_c + r_Lk v_L - c v_c with v_c = (1 - v_L) / (1 - c), and
    rho_k = (r_k - r_Lk v_L) / v_c + c; solved by fixed-point iteration. Without a band,
    ``r_k = (rho_k - c) / (1 - c)``. Returns None when the band holds nearly all the variance."""
    r_l = band_lags if band_lags is not None else (0.0, 0.0)
    if not band_share < 0.95:
        return None
    rho1, rho2 = r1, r2
    for _ in range(50):
        c = min(long_run_ratio(float(np.clip(rho1, -0.99, 0.99)), rho2) / window, 0.9)
        v_c = (1.0 - band_share) / (1.0 - c)
        new1 = float(np.clip((r1 - r_l[0] * band_share) / v_c + c, -0.99, 0.99))
        new2 = None if r2 is None else float(np.clip((r2 - r_l[1] * band_share) / v_c + c, -0.99, 0.99))
        done = abs(new1 - rho1) < 1e-7 and (r2 is None or abs(new2 - rho2) < 1e-7)
        rho1, rho2 = new1, new2
        if done:
            break
    return rho1, rho2


def other_correlation(var_per_sample, band_lags=None, band_var=0.0, wander=None):
    """``(lags, share)`` of the correlated parts of the high-passed series that are not the
    colored noise, for :func:`lags_from_highpassed`: a narrow band (its ``(r_L1, r_L2)`` and
    variance ``band_var``) and a wander's high-frequency part (``wander`` = its ``(v, r1, r2)``,
    :func:`gyrofilter.analysis.gap.baseline.wander_highpassed`), variance-weighted:
    ``r_k = sum_j r_jk v_j / sum_j v_j``, ``share = sum_j v_j / V`` (V = ``var_per_sample``,
    the series' variance). ``(None, 0.0)`` without either."""
    parts = []
    if band_lags is not None:
        parts.append((band_lags[0], band_lags[1], band_var))
    if wander is not None:
        parts.append((wander[1], wander[2], wander[0]))
    total = sum(v for _, _, v in parts)
    if not total > 0 or not var_per_sample > 0:
        return None, 0.0
    return (sum(r1 * v for r1, _, v in parts) / total, sum(r2 * v for _, r2, v in parts) / total), total / var_per_sample


def lags_without_repeats(r1, r2, f, iterations=4):
    """The noise's lag-1 and lag-2 autocorrelations ρ1, ρ2 under rows repeated at the fraction
    ``f`` (each row independently a copy of the row before it), from those measured, ``r1``,
    ``r2``. A repeated row's neighbours are the rows around the one it copies, so to first order
    in f for the lag-2 (the lag-1's exact for isolated repeats):

        r1 = f + (1 - f)² ρ1 + f (1 - f) ρ2
        r2 = f ρ1 + (1 - 2f) ρ2 + f ρ3,        ρ3 ≈ ρ2² / ρ1 (a first-order low pass's)

    solved by fixed-point iteration from ρ2 = r2 (white noise under repeats: r1 = f, r2 = 0
    give 0 and 0; a low pass of lag-1 0.5 under 5 % repeats reads r1 = 0.513). Where ρ2's weight
    1 - 2f in r2 is below :data:`~gyrofilter.analysis.gap.detectors.common.REPEATS_LAG2_MIN_WEIGHT`
    (f above 0.45; none at f = 0.5) r2 does not determine ρ2: it is taken as a first-order low
    pass's, ρ2 = ρ1²."""
    rho1, rho2 = r1, r2
    for _ in range(iterations):
        rho1 = (r1 - f - f * (1 - f) * rho2) / (1 - f) ** 2
        if 1 - 2 * f < REPEATS_LAG2_MIN_WEIGHT:
            rho2 = rho1 * rho1
            continue
        rho3 = rho2 * rho2 / rho1 if abs(rho1) > 1e-3 else 0.0
        rho2 = (r2 - f * rho1 - f * rho3) / (1 - 2 * f)
    return rho1, rho2


def detect_colored(x, sample_rate_hz, bands=(), wander=None, repeated_fraction=0.0, z_min=COLORED_Z):
    """Colored-noise candidate: ``lag1`` (and ``lag2`` where the noise is not a first-order low
    pass) from the high-passed r1, r2, less the correlation of the band candidates ``bands``
    (``narrowband``, ``wandering_tone``, ``resonance``: noise still in ``x``;
    :func:`~gyrofilter.analysis.gap.detectors.resonance.band_correlation`) and of a wander's high-frequency part (``wander``: its ``(v, r1, r2)``
    in the high-passed series, :func:`gyrofilter.analysis.gap.baseline.wander_highpassed`)
    (:func:`lags_from_highpassed`, :func:`other_correlation`). With a wander the significance is
    that of the correlation it leaves.

    ``lag2`` is reported when it falls below ``lag1²``, the AR(1)'s, by :data:`COLORED_Z`
    standard errors, sqrt((1 + 2ρ² - 3ρ⁴) / N) (Bartlett's variance of r₂ for an AR(1) of
    lag-1 ρ; Box, Jenkins & Reinsel, eq. 2.1.13), and by at least :data:`COLORED_MIN_LAG2_GAP`,
    and a first-order ARMA has the pair (:func:`gyrofilter.sim.noise_terms.arma11_from_lags`):
    a correlation that dies faster than a low pass's (a two-tap average, a decimation filter).
    One that dies slower is a slow process the slow detectors name (a flicker floor gives
    lag2 close to lag1), and the high-pass correction, which holds for correlation times well
    below W, would inflate it.

    ``repeated_fraction``: the record's rows repeated beyond chance (f, the ``repeated_samples``
    finding), whose correlation is taken out of r1 and r2 first (:func:`lags_without_repeats`).

    ``z_min``: the z the lag-1 must reach (:data:`COLORED_Z`; the late step's
    :data:`~gyrofilter.analysis.gap.detectors.common.COLORED_LATE_Z` where the axis does not close
    and its lag-1 departs most, :mod:`gyrofilter.analysis.gap.late_colored`)."""
    n = x.size
    if n < 32:
        return None
    e, w = highpassed(x, sample_rate_hz)
    den = float(dot(e, e))
    if den <= 0:
        return None
    r1, r2 = float(dot(e[1:], e[:-1]) / den), float(dot(e[2:], e[:-2]) / den)
    del e
    if repeated_fraction > 0:
        r1, r2 = lags_without_repeats(r1, r2, repeated_fraction)
    left = lags_from_highpassed(r1, None, w, *other_correlation(den / n, wander=wander))
    if left is None:  # the wander holds nearly all the high-passed variance
        return None
    z = left[0] * math.sqrt(n)
    if abs(z) < z_min:  # the correlation of the noise as measured (less a wander's)
        return None
    band_lags, band_var = band_correlation(bands, sample_rate_hz)  # the bands' own correlation: the colored noise's is what is left
    band_lags, band_share = other_correlation(den / n, band_lags, band_var, wander)
    lags = lags_from_highpassed(r1, r2, w, band_lags, band_share)
    if lags is None:
        return None
    lag1, lag2 = lags
    gap2 = lag2 - lag1 * lag1
    se2 = math.sqrt((1 + 2 * lag1**2 - 3 * lag1**4) / n)
    arma = -gap2 >= max(COLORED_Z * se2, COLORED_MIN_LAG2_GAP) and arma11_from_lags(lag1, lag2) is not None
    if not arma:  # the AR(1): lag1 with the AR(1)'s own high-pass correction
        lag1, _ = lags_from_highpassed(r1, None, w, band_lags, band_share)
    if abs(lag1) < COLORED_MIN_LAG1:
        return None
    evidence = f"lag-1 autocorrelation of the noise {lag1:+.3f}"
    if bands or wander is not None:
        evidence += " once the " + " and the ".join(
            name for name, there in (("narrow band's", any(c.effect == NARROWBAND for c in bands)),
                                     ("tone's", any(c.effect == WANDERING_TONE for c in bands)),
                                     ("resonance's", any(c.effect in RESONATORS for c in bands)),
                                     ("wander's", wander is not None)) if there
        ) + " own correlation is taken out"
    evidence += f" (white noise: 0 +- {1 / math.sqrt(n):.4f}; as measured {abs(z):.0f} standard errors away)"
    if arma:
        evidence += (f"; lag-2 {lag2:+.3f}, below the {lag1 * lag1:.3f} of a first-order low pass "
                     f"by {-gap2 / se2:.0f} standard errors: a first-order ARMA noise")
    return Candidate(
        effect=COLORED_NOISE,
        params={"lag1": lag1, "lag2": lag2} if arma else {"lag1": lag1},
        statistic=abs(z),
        threshold=z_min,
        statistic_name="|lag-1 autocorrelation| in units of 1/sqrt(N)",
        evidence=evidence,
    )
