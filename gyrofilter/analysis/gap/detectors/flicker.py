"""A shape in time against flicker: how often white noise with a bias instability's 1/f wander,
fitted to the record, draws a step, a ramp, a warm-up or a covariate's trace as clearly as the record
shows it (:func:`flicker_p_value`; the slow detector's rules, :mod:`gyrofilter.analysis.gap.detectors`).

Bias instability is the wander of every MEMS gyro, and in ten minutes its 1/f excursions pass the
shape tests over white noise and over the exact random-walk and Gauss-Markov likelihoods as a step,
a line or a settling on about one axis in five. The test here is a likelihood ratio under white
noise plus flicker, the flicker-to-white ratio profiled under both models, calibrated by a
parametric bootstrap of the model without the shape: exact on block means, in the eigenbasis of
the flicker covariance where both models' covariances are diagonal, so that a thousand records
cost a few matrix products.
"""
from __future__ import annotations

import math

import numpy as np

from ....effects import BIAS_STEP, RATE_RAMP
from .common import FLICKER_BLOCKS, FLICKER_RATIOS, FLICKER_REPLICATES, FLICKER_STREAM


def flicker_covariance(n):
    """Autocovariance, lags 0 .. n-1, of unit flicker on ``n`` block means: the spectrum
    ``S(omega) = 1 / max(|omega|, omega_c)`` on ``[-pi, pi]`` (:func:`slow_spectrum`'s ``h / omega``
    with ``h = 1``), flat below ``omega_c = 1 / n``, the corner of the simulator's slowest
    Gauss-Markov component, whose time constant is the record's length
    (:func:`gyrofilter.sim.flicker.flicker_bank`). ``r_k = (1/pi) int_0^pi S(omega) cos(k omega)
    d omega``, in closed form with the cosine integral Ci:
    ``r_0 = (1 + ln(pi / omega_c)) / pi``, ``r_k = (sin(omega_c k) / (omega_c k) + Ci(pi k) -
    Ci(omega_c k)) / pi``."""
    from scipy.special import sici

    wc = 1.0 / n
    k = np.arange(1, n, dtype=float)
    r = np.empty(n)
    r[0] = (1.0 + math.log(math.pi / wc)) / math.pi
    r[1:] = (np.sin(wc * k) / (wc * k) + sici(math.pi * k)[1] - sici(wc * k)[1]) / math.pi
    return r


def _flicker_basis(n):
    """Eigen-decomposition ``R = V diag(lam) V^T`` of the unit flicker covariance on ``n`` block
    means (:func:`flicker_covariance`, cached per ``n``): white noise plus flicker, ``s0 I + h R``, is
    diagonal in that basis, ``s0 + h lam``, so its likelihood and its draws cost O(n)."""
    if n not in _FLICKER_BASES:
        r = flicker_covariance(n)
        lam, vec = np.linalg.eigh(r[np.abs(np.subtract.outer(np.arange(n), np.arange(n)))])
        if len(_FLICKER_BASES) > 8:
            _FLICKER_BASES.clear()
        _FLICKER_BASES[n] = (np.maximum(lam, 0.0), vec)
    return _FLICKER_BASES[n]


_FLICKER_BASES = {}


def _shape_columns(name, n):
    """The regressors a shape's scan tries on ``n`` blocks (columns): every split of a step (as the
    detector's scan, :func:`deterministic_shapes`), the line, or a warm-up's 40 time constants."""
    t = np.arange(n, dtype=float) + 0.5
    if name == BIAS_STEP:
        return (np.arange(n)[:, None] >= np.arange(2, n - 1)[None, :]).astype(float)
    if name == RATE_RAMP:
        return t[:, None]
    taus = np.geomspace(1.5, float(n), 40)
    return np.exp(-t[:, None] / taus[None, :])


def _shape_or_flicker(columns, nuisance, lam, series):
    """Likelihood ratio ``2 log L(shape + flicker + white) - 2 log L(flicker + white)`` of every series
    (columns of ``series``), the shape's best regressor among ``columns``, each model with the
    ``nuisance`` regressors (the constant, and a covariate where the shape is tested beside it) and
    its own ratio of flicker to white; and, per series, the flicker-to-white ratio and white level of
    the model without the shape. All in the flicker basis (:func:`_flicker_basis`: ``series``,
    ``columns`` and ``nuisance`` rotated by ``V^T``, ``lam`` the eigenvalues).

    With ``h = rho s0``, the covariance is ``s0 (1 + rho lam)`` in that basis; for a fixed ``rho``
    the white level and the regression are generalised least squares, ``-2 log L = m log(Q / m) +
    sum log(1 + rho lam) + m``, ``Q`` the weighted residual sum of squares after the nuisance
    regressors (and the shape's best regressor ``g``: ``Q - (g' W y)^2 / (g' W g)``, both
    projected off the nuisance regressors in the metric ``W``; Kariya & Kurata 2004, ch. 2), and
    ``rho`` is profiled over :data:`FLICKER_RATIOS` (and 0). The nuisance regressors' normal
    matrix is inverted as a pseudo-inverse: a covariate whose block means are constant over
    these blocks (a heater cycling every two blocks) is the constant again, and adds nothing
    (``inv`` raised "Singular matrix", and the axis's every detector was lost)."""
    m = series.shape[0]
    r0 = float(np.mean(lam))
    best0 = np.full(series.shape[1], np.inf)
    best1 = np.full(series.shape[1], np.inf)
    rho0 = np.zeros(series.shape[1])
    s0 = np.zeros(series.shape[1])
    for rho in np.concatenate(([0.0], FLICKER_RATIOS / r0)):
        v = 1.0 + rho * lam
        w = 1.0 / v
        wz = w[:, None] * nuisance
        inv = np.linalg.pinv(nuisance.T @ wz, hermitian=True)  # a covariate constant on these blocks adds nothing
        zy = wz.T @ series
        zg = wz.T @ columns
        wy = w[:, None] * series
        q0 = np.einsum("ij,ij->j", series, wy) - np.einsum("ij,ij->j", zy, inv @ zy)
        num = columns.T @ wy - zg.T @ (inv @ zy)
        den = np.einsum("ij,ij,i->j", columns, columns, w) - np.einsum("ij,ij->j", zg, inv @ zg)
        q1 = q0 - np.max(num * num / np.maximum(den, 1e-300)[:, None], axis=0)
        logdet = float(np.sum(np.log(v)))
        nll0 = m * np.log(np.maximum(q0, 1e-300) / m) + logdet
        nll1 = m * np.log(np.maximum(q1, 1e-300) / m) + logdet
        better = nll0 < best0
        best0 = np.where(better, nll0, best0)
        rho0 = np.where(better, rho, rho0)
        s0 = np.where(better, q0 / m, s0)
        best1 = np.minimum(best1, nll1)
    return best0 - best1, rho0, s0


def flicker_p_value(y, shape, beside=None):
    """How often flicker alone draws the shape ``shape`` (a step, ramp or warm-up by its name, or a
    covariate by its block means, one per block mean) as clearly as the block means ``y`` show it:
    the parametric bootstrap p-value (Davison & Hinkley 1997, sec. 4.2) of the likelihood ratio of
    the shape (with white noise and flicker) over white noise and flicker (:func:`_shape_or_flicker`),
    the records drawn from the model without the shape fitted to ``y`` (at most
    :data:`FLICKER_BLOCKS` block means; :data:`FLICKER_REPLICATES` records from a fixed stream: the
    same record gives the same answer). ``beside``: a covariate's block means fitted in both models
    (the shape tested beside it). Bias instability is the wander of every MEMS gyro, and in ten
    minutes its 1/f excursions pass the shape tests above as a step, a line or a settling on about
    one axis in five (the default model's z axis, 200 records: 37); against it a shape's better fit
    over white noise is no evidence."""
    group = max(1, int(math.ceil(y.size / FLICKER_BLOCKS)))
    m = y.size // group

    def grouped(v):
        return np.asarray(v, dtype=float)[: m * group].reshape(m, group).mean(axis=1)

    yg = grouped(y)
    lam, vec = _flicker_basis(m)
    columns = _shape_columns(shape, m) if isinstance(shape, str) else grouped(shape)[:, None]
    nuisance = np.ones((m, 1)) if beside is None else np.column_stack([np.ones(m), grouped(beside)])
    columns, nuisance = vec.T @ columns, vec.T @ nuisance
    observed, rho, s0 = _shape_or_flicker(columns, nuisance, lam, (vec.T @ yg)[:, None])
    scale = np.sqrt(s0[0] * (1.0 + rho[0] * lam))
    draws = scale[:, None] * np.random.default_rng(FLICKER_STREAM).standard_normal((m, FLICKER_REPLICATES))
    null, _, _ = _shape_or_flicker(columns, nuisance, lam, draws)
    observed = observed[0]
    return (1 + int(np.sum(~(null < observed)))) / (FLICKER_REPLICATES + 1)  # no ratio (NaN): as flicker draws it
