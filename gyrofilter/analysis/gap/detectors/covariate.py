"""Detector 4, with a recorded temperature: the covariate first (see :mod:`gyrofilter.analysis.gap.detectors`).

Where the temperature itself follows a warm-up, a bias warm-up in time and a temperature
coefficient fit the block means about equally, and so can a slow stochastic wander (a bias
instability or a random walk takes up a settling as well). The measured covariate is the
cause to name: it predicts the bias at the next power-up, an exponential in time does not. So
:func:`detect_slow` reads the slow effects twice:

* the **covariate reading** (:func:`temperature_first`): the temperature coefficient is fitted
  first, and the time shapes and stochastic spectra are looked for in what it leaves
  (:func:`gyrofilter.analysis.gap.detectors.slow.slow_reading` on the residual); the coefficient is
  then re-estimated by generalised least squares under the stochastic model of that residual
  (:func:`gls`), and it must be significant there, jointly with any time shape found in the
  residual (``z^2 > JOINT_THRESHOLD``), or, where that model is a bias instability, pass the time
  shapes' test against flicker (:func:`~gyrofilter.analysis.gap.detectors.flicker.flicker_p_value`: a
  settling the temperature explains is then named as the temperature, not as a shape in time);
  otherwise the temperature is not named;
* the **time reading**: the slow effects without the temperature (the shapes ramp, step and
  warm-up, and the stochastic spectra), as on a record without a ``temp`` column.

Which reading is returned is a rule of the confounded causes, stated with its thresholds in
:mod:`gyrofilter.analysis.gap.confound` (:func:`~gyrofilter.analysis.gap.confound.covariate_or_time`):
the covariate reading, with the time reading riding on the temperature candidate
(``other_reading``), unless a ramp or a step in time beats the temperature; where the covariate
reading is the more complex one, the time reading with the covariate reading riding on it. The two
are then weighed on the discrepancy D.
"""
from __future__ import annotations

import math

import numpy as np

from ....effects import BIAS_INSTABILITY, BIAS_STEP, GAUSS_MARKOV, RATE_RAMP, RATE_RANDOM_WALK, SHAPES, TEMPERATURE, WANDERS, WARMUP
from ..confound import covariate_or_time
from .common import DETERMINISTIC_THRESHOLD, FLICKER_ALPHA, JOINT_THRESHOLD, Candidate
from ...stats import block_means, dot
from .flicker import flicker_p_value
from .slow import periodogram_detrended, slow_spectrum, slow_reading


def detect_slow(x, sample_rate_hz, temp_c=None):
    """Slow bias effects of one axis (the decision rules of :mod:`gyrofilter.analysis.gap.detectors`),
    the covariate reading first where a temperature is recorded (module docstring).

    Returns ``(candidates, stats)``: a list of :class:`Candidate` (a temperature candidate
    carries the time reading, a list of candidates, as its ``other_reading`` when that reading
    names anything, or the time reading's first candidate the covariate reading) and the raw
    statistics ``{name: value}``.
    """
    stats = {}
    time_reading, _ = slow_reading(x, sample_rate_hz, SHAPES, stats=stats)
    if temp_c is None:
        return time_reading, stats
    covariate = temperature_first(x, sample_rate_hz, temp_c, stats)
    y, _ = block_means(x)
    shape = time_reading[0].effect if time_reading and time_reading[0].effect in (RATE_RAMP, BIAS_STEP, WARMUP) else None
    if shape and stats.get(TEMPERATURE, 0.0) > DETERMINISTIC_THRESHOLD:
        stats["beside_temperature_p"] = p_value = beside_covariate_p(y, temp_c, shape)
        stats["explained_by_temperature"] = p_value > FLICKER_ALPHA  # confound.covariate_or_time
        if covariate is None and p_value > FLICKER_ALPHA and not any(c.effect in WANDERS for c in time_reading):
            # a settling real against flicker, alone in its reading, that the temperature explains: the
            # covariate's reading (beside a strong wander, nothing holds beside the temperature)
            covariate = temperature_first(x, sample_rate_hz, temp_c, stats, explains=(shape, p_value))
    return covariate_or_time(time_reading, covariate, stats, y.size), stats


def beside_covariate_p(y, temp_c, shape):
    """Whether the time shape ``shape`` holds beside the temperature: its p-value against flicker on
    the block means ``y`` with the block-mean temperature fitted in both models
    (:func:`~gyrofilter.analysis.gap.detectors.flicker.flicker_p_value`)."""
    tb, _ = block_means(np.asarray(temp_c, dtype=float))
    return flicker_p_value(y, shape, beside=tb)


def temperature_first(x, sample_rate_hz, temp_c, stats, explains=None):
    """The covariate reading of one axis: ``[temperature candidate, *what the residual shows]``,
    or None when the temperature coefficient is not significant (module docstring).
    ``explains``: ``(shape, p)`` where the time reading's shape passed its test against flicker and
    the temperature explains it (what the temperature leaves of it flicker draws in a share ``p``
    of records, :func:`beside_covariate_p`): the shape's evidence is the covariate's, and step 3's
    test is waived.

    1. The least-squares coefficient ``a`` of the block means on the block-mean temperature must
       lower chi^2 of the block means by more than ``DETERMINISTIC_THRESHOLD`` (in units of
       their white level, as every shape).
    2. The time shapes and stochastic spectra of ``x - a (T - mean T)``
       (:func:`~gyrofilter.analysis.gap.detectors.slow.slow_reading`).
    3. ``a`` re-estimated by GLS (:func:`gls`) of the block means on ``[1, T, shape]`` under the
       residual's stochastic model (``shape``: the residual's time shape, if any), its
       ``z^2 = a^2 / Var(a)`` above ``JOINT_THRESHOLD``; the residual's effects re-read on
       ``x - a_GLS (T - mean T)``.
    """
    y, length = block_means(x)
    n = y.size
    temp = np.asarray(temp_c, dtype=float)
    tb, _ = block_means(temp)
    if n < 16 or tb.size != n or not np.ptp(tb) > 0:
        return None
    spec, _ = periodogram_detrended(y)
    s0 = float(spec[spec.size // 2:].mean())  # the white level of the block means
    tc = tb - tb.mean()
    a = float(np.dot(tc, y - y.mean()) / np.dot(tc, tc))
    d = a * a * float(np.dot(tc, tc)) / s0
    stats[TEMPERATURE] = d
    if not d > DETERMINISTIC_THRESHOLD:
        return None
    t_mean = float(temp.mean())
    rest, noise = slow_reading(_less(x, a, temp, t_mean), sample_rate_hz, SHAPES)
    columns = [tb]
    if rest and rest[0].component is not None:  # the residual's time shape, fitted jointly
        columns.append(block_means(rest[0].component)[0][:n])
    coef, cov = gls(y, columns, noise)
    a_gls, z2 = float(coef[1]), float(coef[1] ** 2 / cov[1, 1])
    stats["temperature_gls_z2"] = z2
    p_value = None
    if not z2 > JOINT_THRESHOLD and noise[0] == BIAS_INSTABILITY and explains is None:
        # under a bias instability, the test of the time shapes: the covariate against flicker
        stats["temperature_flicker_p"] = p_value = flicker_p_value(y, tb)
    if not (z2 > JOINT_THRESHOLD or (p_value is not None and p_value <= FLICKER_ALPHA) or explains):
        stats["temperature_gls"] = (a_gls, float(cov[1, 1]), noise[0], JOINT_THRESHOLD)  # confound.suggested_temperature
        return None
    stats.pop("temperature_gls", None)  # named: not also suggested (an earlier reading may have set it)
    rest, _ = slow_reading(_less(x, a_gls, temp, t_mean), sample_rate_hz, SHAPES)
    comp = a_gls * (temp - t_mean)
    comp -= comp.mean()
    words = {None: "white noise", BIAS_INSTABILITY: "a bias instability", RATE_RANDOM_WALK: "a random walk",
             GAUSS_MARKOV: "a Gauss-Markov wander"}[noise[0]]
    cand = Candidate(
        effect=TEMPERATURE, params={"coefficient_dps_per_c": a_gls}, statistic=d,
        threshold=DETERMINISTIC_THRESHOLD, statistic_name="Delta chi^2 of the block means over a constant bias",
        component=comp,
        evidence=(f"the bias follows the temperature with {a_gls:+.3g} deg/s per deg C over {np.ptp(temp):.2f} deg C "
                  f"(generalised least squares under {words} left by it: z = {math.sqrt(z2):.1f}, threshold "
                  f"{math.sqrt(JOINT_THRESHOLD):.0f}"
                  + ("" if p_value is None else
                     f"; or, as here, white noise with flicker draws it as clearly in {100 * p_value:.1f} % of records, "
                     f"at most {100 * FLICKER_ALPHA:g} % as a shape in time")
                  + ("" if not explains or z2 > JOINT_THRESHOLD else
                     f"; or, as here, the bias settles as a {explains[0].replace('_', ' ')} would, beyond what flicker "
                     f"draws, and the temperature explains that settling: flicker draws what it leaves of the "
                     f"{explains[0].replace('_', ' ')} in {100 * explains[1]:.0f} % of records")
                  + f"); the fit lowers chi^2 of the block means by {d:.0f} (threshold {DETERMINISTIC_THRESHOLD:.0f})"))
    return [cand] + rest


def _less(x, a, temp, t_mean):
    """``x - a (temp - t_mean)``, a new series."""
    out = temp - t_mean
    out *= -a
    out += x
    return out


def gls(y, columns, noise):
    """Generalised least squares of the block means ``y`` on ``[1, *columns]`` under the noise
    ``noise = (model, theta, s0, delta_s)`` of :func:`~gyrofilter.analysis.gap.detectors.slow.slow_reading`
    (white level ``s0`` plus the stochastic model ``model``, or white alone when it is None):
    ``beta = (X' C^-1 X)^-1 X' C^-1 y``, ``Cov(beta) = (X' C^-1 X)^-1`` (Aitken 1935).

    ``C`` is Toeplitz for the stationary models: the autocovariance
    ``c_k = (1/M) sum_j S(omega_j) e^(i omega_j k) + s0 [k = 0]`` of the spectrum of
    :func:`~gyrofilter.analysis.gap.detectors.slow.slow_spectrum` on a grid of ``M >= 8 n`` frequencies
    (the flicker's ``h / omega`` is cut at half the lowest grid frequency), solved by Levinson
    recursion (:func:`scipy.linalg.solve_toeplitz`, no BLAS). A random walk is not stationary:
    the regression is made on first differences, whose noise ``w_k + v_k - v_{k-1}`` is an MA(1)
    with ``c_0 = q + 2 s0``, ``c_1 = -s0`` (the constant drops out). Returns ``(beta, cov)`` with
    ``beta[0]`` the constant (0 for the random walk)."""
    from scipy.linalg import solve_toeplitz

    model, theta, s0, _ = noise
    y = np.asarray(y, dtype=float)
    n = y.size
    x_mat = np.column_stack([np.ones(n)] + [np.asarray(c, dtype=float) for c in columns])
    if model == RATE_RANDOM_WALK:
        yy, xx = np.diff(y), np.diff(x_mat[:, 1:], axis=0)
        acov = np.zeros(n - 1)
        acov[0], acov[1] = theta[0] + 2 * s0, -s0
    else:
        yy, xx = y, x_mat
        if model is None:
            acov = np.zeros(n)
        else:
            m = 1 << int(math.ceil(math.log2(8 * n)))
            omega = 2 * math.pi * np.arange(m) / m
            omega = np.minimum(omega, 2 * math.pi - omega)
            omega[0] = omega[1] / 2
            acov = np.fft.ifft(slow_spectrum(model, theta, omega, 1.0)).real[:n]
        acov[0] += s0
    rhs = np.column_stack([xx, yy])
    solved = solve_toeplitz(acov, rhs) if model is not None else rhs / s0
    k = xx.shape[1]
    a_mat = np.array([[float(dot(xx[:, i], solved[:, j])) for j in range(k)] for i in range(k)])
    b_vec = np.array([float(dot(xx[:, i], solved[:, k])) for i in range(k)])
    cov = np.linalg.inv(a_mat)
    beta = cov @ b_vec
    if model == RATE_RANDOM_WALK:
        beta, cov_full = np.concatenate(([0.0], beta)), np.zeros((k + 1, k + 1))
        cov_full[1:, 1:] = cov
        cov = cov_full
    return beta, cov
