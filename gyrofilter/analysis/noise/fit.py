"""The weighted fit of the five-term noise model to the Allan deviation, one axis or three.

Weighted non-negative least squares of the five-term model (:mod:`~gyrofilter.analysis.noise.model`)
to the overlapping Allan variance (the form used by nmayorov/allan-variance), iteratively reweighted with
``w_i = edf_i / (2 model_i^2)`` (the variance of a chi-square estimate with ``edf_i`` degrees
of freedom), over the taus with at least ``min_clusters`` (default 9, paper 002) clusters.

A term is **not resolved** (value ``None``) when the fit sets it to zero or ``theta_j - z sd_j``
reaches zero (the data are consistent with its absence); such terms are dropped, weakest first,
and the fit repeated, so that they cannot bias the others. Its upper bound is still given
(``upper``), for example to fill Kalibr's ``gyroscope_random_walk`` honestly.

**Is the noise just Q/N/B/K/R?** :func:`characterise_axis` warns when the *full fit* (every term
asked for, none dropped: the first fit above, kept as ``AxisNoise.full_fit_values``) lies outside
the chi-square interval of the deviation at more than a fifth of the fitted taus
(:data:`MIN_FULL_FIT_CONSISTENCY`; four times the 5 % a 95 % interval leaves out). The question is
whether *any* model of the family fits the curve, so it is asked of the family's best member, not
of the model drawn: a term is dropped from that one because its coefficient is within its
uncertainty of zero, which does not show it absent (a test that does not reject does not accept),
and the model without it can miss the data where that term's share is largest. Measured
(``python tools/allan_consistency.py``, docs/allan.md): on 10-minute records of white noise and
bias instability alone, B is left out on about half of the axes, and the model drawn lies below
the interval at 15-20 % of the longest taus (9-31 clusters), while the true model lies outside at
the 5 % a 95 % interval should at every cluster count (the intervals and their EDF are right):
judged on the model drawn, the warning fired on about a fifth of such records; judged on the
full fit, on at most 5 % at 10, 30 and 120 minutes, while it still fires on a tone and on a
Gauss-Markov wander whose bump lies among the fitted taus.

:func:`characterise_axis` gives both estimates of a record's axis: this fit, with the intervals of
:mod:`~gyrofilter.analysis.noise.intervals`, and the read-offs of
:mod:`~gyrofilter.analysis.noise.readoff`; the model and its units are in
:mod:`~gyrofilter.analysis.noise.model`.
"""
from __future__ import annotations

import itertools

import numpy as np

from .allan import (MIN_CLUSTERS, AllanInputError, check_confidence, chi2_interval, confidence_text, cluster_sizes, edf_mixture, rate_numbers, edf_oavar,
                    refuse_constant, n_clusters, overlapping_adev, simple_interval)
from .intervals import fitted_intervals
from .model import TERM_ALPHA, TERMS, AxisNoise, basis, sensor_terms, term_shares
from .readoff import read_off
from ...errors import SettingsError
from ...inputs import check_number
from ...units import AXES, MIN_NOISE_DPS, check_axes, plain


def nnls_weighted(a, y, w, allowed=None):
    """min sum_i w_i (y_i - (A theta)_i)^2 subject to theta >= 0 (``a``: A, ``y``, ``w``: weights;
    ``allowed``: the indices of the columns that may be nonzero, default all).

    With five unknowns the 2^5 active sets are enumerated: the NNLS optimum is the
    unconstrained least-squares solution on its own support, so the best feasible subset
    solution is the exact optimum (no iteration, no tolerance).
    """
    a = np.asarray(a, dtype=np.float64)
    sw = np.sqrt(np.asarray(w, dtype=np.float64))
    aw = a * sw[:, None]
    yw = y * sw
    scale = np.linalg.norm(aw, axis=0)
    scale[scale == 0] = 1.0
    aw = aw / scale
    k = a.shape[1]
    allowed = list(range(k)) if allowed is None else list(allowed)
    best, best_cost = np.zeros(k), float(yw @ yw)
    for r in range(1, len(allowed) + 1):
        for subset in itertools.combinations(allowed, r):
            cols = list(subset)
            sol, *_ = np.linalg.lstsq(aw[:, cols], yw, rcond=None)
            if np.any(sol < 0):
                continue
            resid = yw - aw[:, cols] @ sol
            cost = float(resid @ resid)
            if cost < best_cost * (1 - 1e-12):
                best_cost = cost
                best = np.zeros(k)
                best[cols] = sol
    return best / scale


#: the smallest variance, relative to the largest, that the fit's weights take as it is
_WEIGHT_FLOOR = 1e-100
#: the fraction of fitted taus whose interval must hold the full fit, else the warning that the
#: noise is not just Q/N/B/K/R (module docstring): 80 %, at most four times the 5 % of taus that
#: 95 % intervals leave out
MIN_FULL_FIT_CONSISTENCY = 0.8


def fit(tau_s, adev_values, m, n_samples, *, terms=TERMS, min_clusters=MIN_CLUSTERS,
        confidence=0.95, iterations=6):
    """Weighted NNLS fit of the five-term model; returns (theta_squared, used_mask, edf, warnings).

    ``tau_s`` (s), ``adev_values`` (deg/s) and ``m`` (cluster sizes) describe the measured curve
    of ``n_samples`` samples; ``terms``: the terms to fit (of Q, N, B, K, R); ``confidence``: of
    the intervals; ``iterations``: reweighting passes (the weights come from the fitted model).

    ``theta_squared`` are Q^2, N^2, B^2, K^2, R^2. Taus with fewer than ``min_clusters``
    clusters are left out; if ``min_clusters`` < 9 the warnings say so.
    """
    tau = np.asarray(tau_s, dtype=np.float64)
    avar = np.asarray(adev_values, dtype=np.float64) ** 2
    warnings = []
    k = n_clusters(n_samples, m)
    used = k >= min_clusters
    if min_clusters < MIN_CLUSTERS and np.any(used & (k < MIN_CLUSTERS)):
        warnings.append(
            f"the fit uses taus with as few as {int(k[used].min())} clusters (fewer than "
            f"{MIN_CLUSTERS}: errors above 25 %, paper 002)")
    if used.sum() < 2:
        raise AllanInputError(
            f"only {int(used.sum())} cluster time(s) have at least {min_clusters} clusters; "
            "the record is too short for a noise fit")
    allowed = [TERMS.index(t) for t in terms]
    a = basis(tau[used])
    # in units of the largest variance, floored at _WEIGHT_FLOOR of it: the weights edf / (2 y^2)
    # neither overflow for tiny deviations nor become infinite where a deviation is exactly 0
    # (data alternating +-1 have zero deviation at every even cluster size)
    unit = float(np.max(avar[used]))
    y = avar[used] / unit
    edf = edf_oavar(n_samples, m[used], 0)
    weight_ref = np.maximum(y, _WEIGHT_FLOOR)
    theta = np.zeros(5)
    for _ in range(iterations):
        w = edf / (2.0 * weight_ref ** 2)
        theta = nnls_weighted(a, y, w / np.max(w), allowed)
        mod = a @ theta
        if not np.all(mod > 0):
            break
        shares = term_shares(theta, tau[used])
        edf = edf_mixture(n_samples, m[used], shares, [TERM_ALPHA[t] for t in TERMS])
        weight_ref = np.maximum(mod, _WEIGHT_FLOOR)
    return theta * unit, used, edf, warnings


# --------------------------------------------------------------------------------------------
# One axis, three axes
# --------------------------------------------------------------------------------------------

def characterise_axis(x_dps, sample_rate_hz, *, taus_s=None, min_clusters=MIN_CLUSTERS,
                      confidence=0.95, terms=TERMS, axis="x", unit="deg/s"):
    """Overlapping Allan deviation, intervals and both coefficient estimates for one axis.

    ``x_dps``: 1-D rate series in deg/s, sampled at ``sample_rate_hz`` (Hz); ``taus_s``: the
    cluster times (s; default grid); ``min_clusters``: fewest clusters a fitted tau needs (a whole number >= 2);
    ``confidence``: of the intervals; ``terms``: the terms fitted; ``axis``: its name. Raises :class:`AllanInputError` for constant data
    (nothing to characterise), NaN, a masked value or what is not numbers
    (:func:`~gyrofilter.analysis.noise.allan.rate_numbers`), or a record too short for a fit.

    The computation has no unit: a series in another ``unit`` (an accelerometer's in m/s^2,
    :data:`~gyrofilter.analysis.noise.model.ACCELEROMETER_TERMS`) gives its deviation in that unit and
    the coefficients in the matching base units; ``unit`` (``deg/s`` or ``m/s^2``,
    :func:`~gyrofilter.analysis.noise.model.sensor_terms`) only names it and its terms' units in the
    messages and notes.
    """
    sensor = sensor_terms(unit)
    try:  # a masked value is not taken as data (the rule: inputs.number_array)
        x = rate_numbers(x_dps, "x_dps")
    except AllanInputError as exc:
        raise AllanInputError(f"axis {axis}: {exc}") from None
    if x.ndim != 1:
        raise AllanInputError(f"axis {axis}: expected a 1-D rate series, got shape {x.shape}")
    refuse_constant(x, f"axis {axis}", unit=unit, axis=axis)
    # numpy's numbers too (a float32 0.9 was "not between 0 and 1"); a text or None in min_clusters was numpy's TypeError
    confidence = check_confidence(confidence)
    min_clusters = check_number(min_clusters, "min_clusters", low=2, integer=True)
    for t in terms:
        if t not in TERMS:
            raise SettingsError(f"unknown noise term {t!r}; expected some of {', '.join(TERMS)}")
    try:
        tau, dev = overlapping_adev(x, sample_rate_hz, taus_s)
    except AllanInputError as exc:
        raise AllanInputError(f"axis {axis}: {exc}") from None
    if not np.max(dev) >= MIN_NOISE_DPS:
        raise AllanInputError(
            f"axis {axis}: the Allan deviation is below {MIN_NOISE_DPS:g} {unit} at every cluster time (largest "
            f"{np.max(dev):.3g}): too small a noise for the fit in float64; are the values in {unit}?")
    n = x.size
    m = cluster_sizes(n, sample_rate_hz, tau)
    # fit, then drop the least significant unresolved term and refit until every fitted term is
    # resolved: an unresolved term left in would bias the others (NNLS keeps it >= 0, so it can
    # only soak up variance). Which terms the model needs is judged on the Allan variances' stated
    # scatter; the misfit widens what is then said of them (fitted_intervals, widen=True): a misfit
    # elsewhere on the curve is no evidence that a term is absent (a B dropped on that ground raised
    # the misfit of the 2.8-h ADIS16405 records 3- to 19-fold)
    allowed = list(terms)
    full_theta = None
    while True:
        theta, used, _, warnings = fit(tau, dev, m, n, terms=allowed, min_clusters=min_clusters,
                                       confidence=confidence)
        if full_theta is None:  # every term asked for: the model the adequacy warning judges
            full_theta = theta
        fitted, _, _ = fitted_intervals(theta, tau, m, n, used, confidence, dev ** 2, widen=False, free=False)
        weak = [t for t in allowed if fitted[t].value is None and theta[TERMS.index(t)] > 0]
        if not weak:
            break
        if len(allowed) == 1:
            break
        allowed.remove(min(weak, key=lambda t: fitted[t].z_score))
    fitted, chi2_nu, dof = fitted_intervals(theta, tau, m, n, used, confidence, dev ** 2, term_unit=sensor.term_unit)
    # chi-square interval of every tau, EDF from the fitted noise mixture
    shares = term_shares(theta, tau)
    edf = edf_mixture(n, m, shares, [TERM_ALPHA[t] for t in TERMS])
    lo, hi = chi2_interval(1.0, edf, confidence)  # relative, so that no square of a deviation underflows
    ci_low, ci_high = dev * np.sqrt(lo), dev * np.sqrt(hi)
    _, _, rel = simple_interval(dev, n, m)
    readoff = read_off(tau, dev, ci_low, ci_high, used, unit=unit)
    k = n_clusters(n, m)
    if np.any(k < MIN_CLUSTERS):
        warnings.append(f"axis {axis}: {int(np.sum(k < MIN_CLUSTERS))} cluster time(s) have fewer than "
                        f"{MIN_CLUSTERS} clusters" + ("" if min_clusters >= MIN_CLUSTERS else " and are used by the fit")
                        + ("; they are shown but not fitted" if min_clusters >= MIN_CLUSTERS else ""))
    res = AxisNoise(sample_rate_hz=float(sample_rate_hz), n_samples=n, tau_s=tau, adev=dev, m=m,
                    n_clusters=k, edf=edf, ci_low=ci_low, ci_high=ci_high, simple_rel=rel,
                    fitted=fitted, readoff=readoff, fit_values=np.sqrt(theta), fit_used=used,
                    full_fit_values=np.sqrt(full_theta), confidence=confidence, fit_reduced_chi2=chi2_nu,
                    fit_dof=dof, warnings=warnings)
    if res.full_fit_consistency() < MIN_FULL_FIT_CONSISTENCY:
        res.warnings.append(
            f"axis {axis}: the five-term model (every term fitted) lies outside the {confidence_text(confidence)} "
            f"interval at {1 - res.full_fit_consistency():.0%} of the fitted taus: the noise is not just "
            "Q/N/B/K/R" + (" (see `gyrofilter gap`)" if sensor.gap else ""))
    return res


def characterise(gyro_dps, sample_rate_hz, *, axes=AXES, **kwargs):
    """:func:`characterise_axis` for each column of ``gyro_dps`` (shape (N, 3), deg/s) at
    ``sample_rate_hz`` (Hz) named in ``axes`` (a subset of :data:`~gyrofilter.units.AXES`); ``kwargs`` go to
    :func:`characterise_axis`; returns {axis name: AxisNoise}. ``axes`` in order, checked by
    :func:`~gyrofilter.units.check_axes` (a repeated name kept one column of two; a set named the
    columns in its hash order), else AllanInputError."""
    try:
        axes = check_axes(axes)
    except SettingsError as exc:
        raise AllanInputError(str(exc)) from None
    g = rate_numbers(gyro_dps, "gyro_dps")
    if g.ndim != 2 or g.shape[1] != len(axes):
        got = g.shape if g.ndim else "a scalar"
        raise AllanInputError(
            f"expected gyro rates of shape (N, {len(axes)}) for axes {', '.join(axes)}, got {got}"
            + ("; an axis is missing" if g.ndim == 2 and g.shape[1] < len(axes) else ""))
    return {a: characterise_axis(g[:, i], sample_rate_hz, axis=a, **kwargs) for i, a in enumerate(axes)}
