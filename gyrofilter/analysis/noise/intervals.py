"""The intervals of the fitted noise coefficients (:mod:`~gyrofilter.analysis.noise.fit`).

Uncertainty of a fitted coefficient (two-sided, at ``confidence``, default 95 %): the fit is
linear in the Allan variances on its active set, ``theta = G y`` with ``G = (A' W A)^-1 A' W``,
so ``cov(theta) = G C G'``. ``C`` (:func:`avar_covariance`) has the standard deviations of the
NIST SP 1065 Table 5 EDF for each noise type, summed over the fitted mixture (conservative, see
:func:`gyrofilter.analysis.noise.allan.edf_mixture`), and the correlations between cluster times from the
Allan transfer function (:func:`avar_correlation`). The interval is the chi-square interval with
``edf = 2 theta_j^2 / var_j`` (Satterthwaite). The round-trip tests check that it covers the true
coefficient in at least 90 % of simulated records (measured: 92-100 %).
"""
from __future__ import annotations

import functools
import math
from statistics import NormalDist

import numpy as np

from .allan import chi2_interval, edf_oavar
from .model import TERM_ALPHA, TERM_SYMBOL, TERM_UNIT, TERMS, Coefficient, basis, term_shares


@functools.lru_cache(maxsize=None)
def _rho_table(alpha):
    """Correlation of overlapping Allan variance estimates at cluster sizes m and r m for
    power-law rate noise S(f) ~ f^alpha, large-record approximation (tabulated over log r).

    For a Gaussian series the covariance of two quadratic estimators is
    ``2 tr(A1 S A2 S)``; for averages of squared filter outputs over many overlapping starts it
    becomes ``(2/K) int |H1|^2 |H2|^2 S(f)^2 df`` with the Allan transfer function
    ``|H_m(f)|^2 = 4 sin^4(pi f m) / (m sin(pi f))^2`` (NIST SP 1065 sec. 7). With
    ``g(u) = 4 sin^4 u / u^2`` (the continuous form; its mean 3/2u^2 beyond u = 40 pi)::

        rho(r) = int g(u) g(r u) u^(2 alpha) du / sqrt(int g(u)^2 u^(2a) du  int g(ru)^2 u^(2a) du)

    Checked by Monte Carlo in the tests (white noise: rho(2) = 0.53, rho(4) = 0.19).
    """
    cut = 40.0 * math.pi

    def g(v):
        out = np.empty_like(v)
        small = v < cut
        vs = v[small]
        out[small] = np.where(vs > 1e-8, 4.0 * np.sin(vs) ** 4 / np.maximum(vs, 1e-300) ** 2, 4.0 * vs ** 2)
        out[~small] = 1.5 / v[~small] ** 2
        return out

    log_r = np.linspace(0.0, math.log(1e8), 120)
    rho = np.empty_like(log_r)
    for i, lr in enumerate(log_r):
        r = math.exp(lr)
        u = np.unique(np.concatenate([np.logspace(-6, 7, 4000), np.linspace(0.0, cut / r, 3000)[1:],
                                      np.linspace(0.0, cut, 3000)[1:]]))
        w = u ** (2.0 * alpha)
        g1, g2 = g(u), g(r * u)
        rho[i] = _trapezoid(g1 * g2 * w, u) / math.sqrt(_trapezoid(g1 ** 2 * w, u) * _trapezoid(g2 ** 2 * w, u))
    return log_r, np.clip(rho, 0.0, 1.0)


def _trapezoid(y, x):
    """Trapezoid rule, sum (x[i+1] - x[i]) (y[i+1] + y[i]) / 2 (numpy's trapz, removed in numpy 2.4,
    is trapezoid from numpy 2.0 on; written out so that numpy 1.24 and 2.x give the same numbers)."""
    return float(np.sum(np.diff(x) * (y[1:] + y[:-1])) / 2.0)


#: below this cluster size the discrete transfer function is integrated directly
_DISCRETE_M = 64


@functools.lru_cache(maxsize=None)
def _discrete_correlation(alpha):
    """Exact large-record correlation for cluster sizes 1 .. _DISCRETE_M - 1 (matrix indexed by
    m - 1): the discrete ``|H_m(f)|^2 = 4 sin^4(pi f m) / (m sin(pi f))^2`` with
    ``S(f) = (2 sin(pi f))^alpha`` integrated over 0 < f < 1/2 (the continuous table gives
    0.53 where the exact value for m = 1, 2 is 0.46)."""
    f = np.linspace(0.5 / 20000, 0.5, 20000)
    s = (2.0 * np.sin(np.pi * f)) ** alpha / np.sin(np.pi * f) ** 2
    m = np.arange(1, _DISCRETE_M)[:, None]
    h = 4.0 * np.sin(np.pi * f * m) ** 4 / m ** 2 * s
    gram = h @ h.T
    d = np.sqrt(np.diag(gram))
    return gram / np.outer(d, d)


def avar_correlation(m1, m2, alpha):
    """Correlation of the overlapping Allan variance estimates at cluster sizes m1 and m2 for
    power-law noise ``alpha`` (0, -1 or -2; +2 uses the white-FM table). See :func:`_rho_table`;
    pairs of cluster sizes below 64 use :func:`_discrete_correlation`."""
    alpha = max(min(int(alpha), 0), -2)
    log_r, rho = _rho_table(alpha)
    m1 = np.asarray(m1, dtype=np.float64)
    m2 = np.asarray(m2, dtype=np.float64)
    r = np.abs(np.log(m2 / m1))
    out = np.interp(r, log_r, rho)
    m1b, m2b = np.broadcast_arrays(m1, m2)
    small = (m1b < _DISCRETE_M) & (m2b < _DISCRETE_M)
    if np.any(small):
        table = _discrete_correlation(alpha)
        i1 = m1b[small].astype(int) - 1
        i2 = m2b[small].astype(int) - 1
        out = np.array(out, dtype=np.float64, copy=True)
        out[small] = table[i1, i2]
    return out


def avar_covariance(tau_s, m, n_samples, theta_sq):
    """Approximate covariance matrix of the Allan variance estimates at ``m`` (cluster sizes; ``tau_s`` the cluster times, s; ``n_samples`` samples) for the noise
    mixture ``theta_sq`` (Q^2 ... R^2): standard deviations from the SP 1065 EDF of each term,
    summed (conservative), and correlations from :func:`avar_correlation`, averaged over the
    terms with weights sqrt(sd_ki sd_kj)."""
    m = np.asarray(m, dtype=np.float64)
    shares = term_shares(theta_sq, tau_s)
    sd_k = np.array([shares[k] * np.sqrt(2.0 / edf_oavar(n_samples, m, TERM_ALPHA[t]))
                     for k, t in enumerate(TERMS)])
    sd = sd_k.sum(axis=0)
    num = np.zeros((m.size, m.size))
    den = np.zeros((m.size, m.size))
    for k, t in enumerate(TERMS):
        if not np.any(sd_k[k] > 0):
            continue
        a = np.sqrt(np.outer(sd_k[k], sd_k[k]))
        num += a * avar_correlation(m[:, None], m[None, :], TERM_ALPHA[t])
        den += a
    rho = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.eye(m.size))
    return sd, rho * np.outer(sd, sd)


def _gain(a, w, active):
    aa = a[:, active]
    return np.linalg.solve(aa.T @ (aa * w[:, None]), (aa * w[:, None]).T)


def reduced_chi2(a, y, theta, w, cov_y, active):
    """The fit's misfit: ``(chi2_nu, dof)``, or ``(None, None)`` where the fit has no residual
    degree of freedom (as many fitted taus as active terms) or no active term.

    ``a``: the model matrix at the fitted taus; ``y``: the measured Allan variances there;
    ``theta``: the fitted Q^2 .. R^2 (same units as ``y``); ``w``: the fit's weights
    ``1 / sd_i^2`` (the weights ``edf_i / (2 model_i^2)`` of :func:`~gyrofilter.analysis.noise.fit.fit`,
    from the fitted mixture); ``cov_y``: the covariance :func:`avar_covariance` of ``y``;
    ``active``: the fitted terms (bool, 5). With the residuals ``r = y - A theta``::

        X^2 = sum_i w_i r_i^2,   dof = E[X^2] = tr(W (I - H) C (I - H)'),   chi2_nu = X^2 / dof

    ``H = A (A' W A)^-1 A' W`` (the active columns; ``r = (I - H) y`` for the weights ``W``), and
    ``dof`` the expectation of the quadratic form ``r' W r`` if ``y`` had the covariance ``C``
    (E[x'Mx] = tr(MC) for a zero-mean x of covariance C; e.g. Searle, *Linear Models*, 1971,
    ch. 2). For independent estimates (``C = W^-1``) it is the textbook ``n - p`` (taus fitted
    minus terms fitted; Bevington & Robinson, *Data Reduction and Error Analysis for the Physical
    Sciences*, 3rd ed., ch. 6 and 11); the Allan variances at neighbouring taus are correlated
    (:func:`avar_correlation`: 0.53 between m and 2m for white noise, more between the grid's
    neighbours 10 per decade apart), so their residuals scatter less than ``n - p`` independent
    ones would: ``dof`` is an effective count, smaller, and ``X^2 / (n - p)`` would understate the
    misfit (it is optimistic). ``chi2_nu`` is then the factor by
    which the stated covariance understates the scatter the fit leaves: about 1 where the
    five-term model and ``C`` describe the curve, above 1 where the curve has structure no term fits.
    """
    if not active.any() or a.shape[0] <= int(np.sum(active)):
        return None, None
    r = y - a @ theta
    x2 = float(np.sum(w * r ** 2))
    resid = np.eye(a.shape[0]) - a[:, active] @ _gain(a, w, active)
    dof = float(np.sum(w * np.einsum("ij,jk,ik->i", resid, cov_y, resid)))
    if not dof > 0:
        return None, None
    return x2 / dof, dof


def fitted_intervals(theta, tau, m, n_samples, used, confidence, avar, widen=True):
    """Per-term value and interval of the fit (module docstring), and the fit's misfit:
    returns ``(coefficients, chi2_nu, dof)`` (:func:`reduced_chi2`; None, None without residual
    degrees of freedom).

    ``theta``: the fitted Q^2 .. R^2; ``tau``, ``m``: the cluster times (s) and sizes; ``used``:
    the taus fitted; ``avar``: the measured Allan variances at every tau ((deg/s)^2); ``widen``:
    scale by the misfit (below; False: the intervals of the stated scatter alone).
    The fit is linear in the Allan variances on its active set: ``theta = G y`` with
    ``G = (A' W A)^-1 A' W``, so ``cov(theta) = G C G'`` with ``C`` from
    :func:`avar_covariance`. Where the fit's reduced chi-square exceeds 1, ``C`` (so every
    ``var_j``) is multiplied by it: the stated scatter of the Allan variances does not cover the
    misfit, and least-squares practice scales the covariance of the parameters by chi2_nu
    (Bevington & Robinson, ch. 11; the Birge ratio, R. T. Birge, Phys. Rev. 40, 207, 1932; the
    Particle Data Group's scale factor S = sqrt(chi2_nu), Review of Particle Physics,
    Introduction, "Unconstrained averaging"); below 1 nothing changes (a fit better than its
    stated scatter is not taken as a reason to narrow the intervals).
    Every statement below uses the scaled ``var_j``: the resolution test, the interval, the bound.
    A term is resolved when ``theta_j - z sd_j > 0`` (z: the normal
    quantile of ``confidence``); its interval is the chi-square interval with
    ``edf_j = 2 theta_j^2 / var_j`` (Satterthwaite), which stays positive and is skewed like the
    Allan variance itself (scaling ``var_j`` by chi2_nu divides ``edf_j`` by it: the interval
    widens by about sqrt(chi2_nu) on either scale, theta_j or its square root). A term left out
    of the fit (fitted to zero, or dropped as not resolved) gets the upper bound
    ``max(theta_j, 0) + z sd_j`` of the unconstrained fit with the term forced in (a dropped
    term keeps the value the data give it: its bound is not below it); a fit that is zero for
    every term has no covariance, hence no bounds.
    Variances are computed in units of the largest fitted one, so any deviation a float holds works.
    """
    if not np.any(theta > 0):  # e.g. data whose deviation is exactly 0 at some cluster times
        return {term: Coefficient(term, None, note="not resolved: the fit is 0 for every term, so it gives no bound")
                for term in TERMS}, None, None
    z = NormalDist().inv_cdf(0.5 + confidence / 2.0)
    tau_u, m_u = tau[used], m[used]
    a = basis(tau_u)
    # variances in units of the largest fitted one (their squares below stay normal floats);
    # a coefficient is sqrt(theta), so it is sqrt(theta in units) * root
    var_unit = float(np.max(theta)) or 1.0
    root = math.sqrt(var_unit)
    theta = theta / var_unit
    sd, cov_y = avar_covariance(tau_u, m_u, n_samples, theta)
    w = 1.0 / sd ** 2
    active = theta > 0
    y = np.asarray(avar, dtype=np.float64)[used] / var_unit
    chi2_nu, dof = reduced_chi2(a, y, theta, w, cov_y, active)
    if widen and chi2_nu is not None and chi2_nu > 1.0:
        cov_y = cov_y * chi2_nu
    out = {}
    cov = np.zeros((5, 5))
    if active.any():
        g = _gain(a, w, active)
        cov[np.ix_(active, active)] = g @ cov_y @ g.T
    for j, term in enumerate(TERMS):
        sym, unit = TERM_SYMBOL[term], TERM_UNIT[term]
        if not active[j]:
            forced = active.copy()
            forced[j] = True
            try:
                g = _gain(a, w, forced)
                pos = int(np.sum(forced[:j]))  # row of term j among the forced-in terms
                var = float((g @ cov_y @ g.T)[pos, pos])
                upper = math.sqrt(max(float(g[pos] @ y), 0.0) + z * math.sqrt(max(var, 0.0))) * root
            except np.linalg.LinAlgError:
                upper = None
            note = f"not resolved: {sym} is not needed to fit the data (fitted to 0 or not significant)"
            if upper is not None:
                note += f"; {confidence:.0%} upper bound {upper:.3g} {unit}"
            out[term] = Coefficient(term, None, upper=upper, note=note)
            continue
        var = max(float(cov[j, j]), 1e-300)
        sdj = math.sqrt(var)
        c2 = float(theta[j])
        upper = math.sqrt(c2 + z * sdj) * root
        if c2 - z * sdj <= 0:
            out[term] = Coefficient(term, None, upper=upper, z_score=c2 / sdj,
                                    note=f"not resolved: {sym} = {math.sqrt(c2) * root:.3g} {unit} is within the "
                                         f"{confidence:.0%} uncertainty of zero; upper bound {upper:.3g}")
            continue
        edf = 2.0 * c2 ** 2 / var
        lo, hi = chi2_interval(c2, edf, confidence)
        # the tau where this term's share of the model is largest: where it is read
        share = a[:, j] * c2 / (a @ theta)
        out[term] = Coefficient(term, math.sqrt(c2) * root, math.sqrt(float(lo)) * root, math.sqrt(float(hi)) * root,
                                tau_s=float(tau_u[int(np.argmax(share))]), z_score=c2 / sdj)
    return out, chi2_nu, dof
