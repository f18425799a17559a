"""Gyro noise coefficients from the Allan deviation, with uncertainties and units.

The five-term model (IEEE Std 952; paper 000 eqs. 4-8; paper 002) of the Allan variance of a
gyro's rate::

    sigma^2(tau) = 3 Q^2 / tau^2  +  N^2 / tau  +  (2 ln 2 / pi) B^2  +  K^2 tau / 3  +  R^2 tau^2 / 2

=========  =====================  ================  ====================  ======================
symbol     name                   unit (here)       slope of sigma(tau)   read-off (papers 000/002)
=========  =====================  ================  ====================  ======================
Q          quantization (angle)   deg               -1                    sigma(sqrt(3) s) on the -1 line
N          angle random walk      deg/sqrt(s)       -1/2                  sigma(1 s) on the -1/2 line
B          bias instability       deg/s             0                     flat minimum / 0.664
K          rate random walk       deg/s/sqrt(s)     +1/2                  sigma(3 s) on the +1/2 line
R          rate ramp              deg/s^2           +1                    sigma(sqrt(2) s) on the +1 line
=========  =====================  ================  ====================  ======================

(deg/sqrt(s) is the same as deg/s/sqrt(Hz): N is the rate noise density.)

Two estimates are given:

* :func:`read_off`: the slope read-offs of papers 000/002. A region of the curve whose local
  log-log slope is within ``slope_tolerance`` of the term's slope defines the line; its point
  nearest the read-off tau is extended along the slope to the read-off tau. The interval is the
  chi-square interval of that point.
* :func:`fit`: weighted non-negative least squares of the five-term model to the overlapping
  Allan variance (the form used by nmayorov/allan-variance), iteratively reweighted with
  ``w_i = edf_i / (2 model_i^2)`` (the variance of a chi-square estimate with ``edf_i`` degrees
  of freedom), over the taus with at least ``min_clusters`` (default 9, paper 002) clusters.

Uncertainty of a fitted coefficient (two-sided, at ``confidence``, default 95 %): the fit is
linear in the Allan variances on its active set, ``theta = G y`` with ``G = (A' W A)^-1 A' W``,
so ``cov(theta) = G C G'``. ``C`` (:func:`avar_covariance`) has the standard deviations of the
NIST SP 1065 Table 5 EDF for each noise type, summed over the fitted mixture (conservative, see
:func:`gyrofilter.analysis.allan.edf_mixture`), and the correlations between cluster times from the
Allan transfer function (:func:`avar_correlation`). The interval is the chi-square interval with
``edf = 2 theta_j^2 / var_j`` (Satterthwaite). The round-trip tests check that it covers the true
coefficient in at least 90 % of simulated records (measured: 92-100 %).

A term is **not resolved** (value ``None``) when the fit sets it to zero or ``theta_j - z sd_j``
reaches zero (the data are consistent with its absence); such terms are dropped, weakest first,
and the fit repeated, so that they cannot bias the others. Its upper bound is still given
(``upper``), for example to fill Kalibr's ``gyroscope_random_walk`` honestly.

The read-off intervals are the chi-square interval of the point read (NIST SP 1065 eq. 41).

The two estimates answer different questions. A read-off is the whole curve at one tau, and
every term adds to sigma^2 there, so (up to the curve's own scatter) it is at least the term it
names (e.g. N^2 / tau <= sigma^2(tau) gives N <= sigma(tau) sqrt(tau); 0.44 B^2 <= sigma_min^2).
The fit separates the terms. So a read-off can give a number where the fit does not resolve
the term: that number is an upper estimate of the term, not a value of it.
"""
from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from .allan import (MIN_CLUSTERS, AllanInputError, chi2_interval, cluster_sizes, edf_mixture,
                    edf_oavar, n_clusters, overlapping_adev, simple_interval)
from ..errors import SettingsError
from ..units import DEG_PER_RAD, MAX_RATE_DPS, MIN_NOISE_DPS, plain, utf8_text

#: term names in model order, with unit, power of tau in sigma^2, basis and power-law alpha
TERMS = ("quantization", "arw", "bias_instability", "rrw", "rate_ramp")
TERM_SYMBOL = {"quantization": "Q", "arw": "N", "bias_instability": "B", "rrw": "K", "rate_ramp": "R"}
TERM_UNIT = {"quantization": "deg", "arw": "deg/sqrt(s)", "bias_instability": "deg/s",
             "rrw": "deg/s/sqrt(s)", "rate_ramp": "deg/s^2"}
#: slope of log sigma vs log tau for each term
TERM_SLOPE = {"quantization": -1.0, "arw": -0.5, "bias_instability": 0.0, "rrw": 0.5, "rate_ramp": 1.0}
#: tau (s) at which the read-off line gives the coefficient (sigma(tau_read) = coefficient)
READ_TAU_S = {"quantization": math.sqrt(3.0), "arw": 1.0, "rrw": 3.0, "rate_ramp": math.sqrt(2.0)}
#: power-law exponent of the rate PSD (NIST SP 1065); the ramp is treated as random-walk FM
TERM_ALPHA = {"quantization": 2, "arw": 0, "bias_instability": -1, "rrw": -2, "rate_ramp": -2}
#: sqrt(2 ln 2 / pi) = 0.664: flat Allan deviation per unit bias instability (paper 000)
FLICKER_FLOOR = math.sqrt(2.0 * math.log(2.0) / math.pi)


def basis(tau_s):
    """Columns of the model matrix at the cluster times ``tau_s`` (n,) in s:
    ``[3/tau^2, 1/tau, 2 ln2/pi, tau/3, tau^2/2]`` (shape (n, 5))."""
    tau = np.asarray(tau_s, dtype=np.float64)
    return np.column_stack([3.0 / tau ** 2, 1.0 / tau, np.full_like(tau, 2.0 * math.log(2.0) / math.pi),
                            tau / 3.0, tau ** 2 / 2.0])


def model_adev(coefficients, tau_s):
    """sqrt of the five-term model (deg/s) at ``tau_s`` (s) for ``coefficients`` = (Q, N, B, K, R)
    in their base units (TERM_UNIT; None counts as 0)."""
    c = np.array([0.0 if v is None else float(v) for v in coefficients])
    return np.sqrt(basis(tau_s) @ c ** 2)


# --------------------------------------------------------------------------------------------
# Unit conversions (all coefficients are stored in the deg/s-based units of TERM_UNIT)
# --------------------------------------------------------------------------------------------

#: (term, unit) -> factor: value_in_unit = factor * value_in_base_unit
UNIT_FACTORS = {
    ("quantization", "deg"): 1.0,
    ("quantization", "arcsec"): 3600.0,
    ("quantization", "rad"): 1.0 / DEG_PER_RAD,
    ("arw", "deg/sqrt(s)"): 1.0,
    ("arw", "deg/s/sqrt(Hz)"): 1.0,
    ("arw", "deg/sqrt(h)"): 60.0,                    # sqrt(3600 s / h)
    ("arw", "rad/s/sqrt(Hz)"): 1.0 / DEG_PER_RAD,    # Kalibr gyroscope_noise_density
    ("bias_instability", "deg/s"): 1.0,
    ("bias_instability", "deg/h"): 3600.0,
    ("bias_instability", "rad/s"): 1.0 / DEG_PER_RAD,
    ("rrw", "deg/s/sqrt(s)"): 1.0,
    ("rrw", "deg/s^2/sqrt(Hz)"): 1.0,
    ("rrw", "deg/h/sqrt(h)"): 3600.0 * 60.0,
    ("rrw", "rad/s^2/sqrt(Hz)"): 1.0 / DEG_PER_RAD,  # Kalibr gyroscope_random_walk
    ("rate_ramp", "deg/s^2"): 1.0,
    ("rate_ramp", "deg/h^2"): 3600.0 ** 2,
}
#: the customary units shown beside the base unit
CUSTOMARY_UNIT = {"quantization": "arcsec", "arw": "deg/sqrt(h)", "bias_instability": "deg/h",
                  "rrw": "deg/h/sqrt(h)", "rate_ramp": "deg/h^2"}


def convert(value, term, unit, to_base=False):
    """Convert ``value``, a coefficient of ``term``, from its base unit (TERM_UNIT) to ``unit``, or back
    with ``to_base=True``. Raises SettingsError for an unknown (term, unit) pair."""
    try:
        factor = UNIT_FACTORS[(term, unit)]
    except KeyError:
        known = ", ".join(u for t, u in UNIT_FACTORS if t == term)
        raise SettingsError(f"no unit {unit!r} for {term!r}; known: {known}") from None
    if value is None:
        return None
    return value / factor if to_base else value * factor


def arw_from_white_std(std_dps, sample_rate_hz):
    """Rate noise density of white noise with per-sample std ``std_dps`` at ``sample_rate_hz``:
    ``N = std / sqrt(fs)`` (deg/sqrt(s)); the discrete-to-continuous conversion Kalibr expects."""
    return std_dps / math.sqrt(sample_rate_hz)


def white_std_from_arw(arw_dps_per_sqrt_hz, sample_rate_hz):
    """Per-sample standard deviation (deg/s) of white rate noise of density N =
    ``arw_dps_per_sqrt_hz`` (deg/s/sqrt(Hz)) sampled at fs = ``sample_rate_hz`` (Hz): ``N sqrt(fs)``."""
    return arw_dps_per_sqrt_hz * math.sqrt(sample_rate_hz)


# --------------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------------

@dataclass
class Coefficient:
    """One noise coefficient in its base unit (TERM_UNIT[term]).

    ``value`` is None when the term is not resolved; ``low``/``high`` bound it at
    ``confidence``; ``upper`` is the upper bound when not resolved. ``tau_s`` is the cluster
    time that determines it (read-off point or narrowest interval).
    """

    term: str
    value: float | None
    low: float | None = None
    high: float | None = None
    upper: float | None = None
    tau_s: float | None = None
    note: str = ""
    z_score: float | None = None   # fitted c^2 / its standard deviation (fit only)

    @property
    def unit(self):
        """The coefficient's base unit (TERM_UNIT)."""
        return TERM_UNIT[self.term]

    @property
    def resolved(self):
        """True when a value was estimated (else only ``upper`` bounds it)."""
        return self.value is not None

    def to_dict(self, unit=None):
        """value, low, high in ``unit`` (default: the base unit) and the unit's name, as a dict."""
        unit = unit or self.unit
        return {"value": convert(self.value, self.term, unit), "low": convert(self.low, self.term, unit),
                "high": convert(self.high, self.term, unit), "unit": unit}


@dataclass
class AxisNoise:
    """Allan deviation of one axis and the coefficients from both methods."""

    sample_rate_hz: float
    n_samples: int
    tau_s: np.ndarray
    adev: np.ndarray
    m: np.ndarray
    n_clusters: np.ndarray
    edf: np.ndarray
    ci_low: np.ndarray          # chi-square interval of the deviation (at confidence)
    ci_high: np.ndarray
    simple_rel: np.ndarray      # paper 000 relative error 1/sqrt(2(N/m - 1))
    fitted: dict                # term -> Coefficient (weighted NNLS)
    readoff: dict               # term -> Coefficient (slope read-offs)
    fit_values: np.ndarray      # the NNLS coefficients (Q, N, B, K, R), zeros included
    fit_used: np.ndarray        # bool mask of taus used by the fit
    confidence: float = 0.95
    warnings: list = field(default_factory=list)

    def model_adev(self, tau_s=None):
        """The fitted model's Allan deviation (deg/s) at ``tau_s`` (s; default: the measured taus)."""
        return model_adev(self.fit_values, self.tau_s if tau_s is None else tau_s)

    def fit_consistency(self):
        """Fraction of fitted taus whose chi-square interval contains the model."""
        mod = self.model_adev()[self.fit_used]
        lo, hi = self.ci_low[self.fit_used], self.ci_high[self.fit_used]
        return float(np.mean((mod >= lo) & (mod <= hi))) if mod.size else float("nan")


# --------------------------------------------------------------------------------------------
# Weighted non-negative least squares (exact, five unknowns: every active set is tried)
# --------------------------------------------------------------------------------------------

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


def _term_shares(theta_sq, tau):
    return (basis(tau) * theta_sq).T  # (5, n)


#: the smallest variance, relative to the largest, that the fit's weights take as it is
_WEIGHT_FLOOR = 1e-100


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
        shares = _term_shares(theta, tau[used])
        edf = edf_mixture(n_samples, m[used], shares, [TERM_ALPHA[t] for t in TERMS])
        weight_ref = np.maximum(mod, _WEIGHT_FLOOR)
    return theta * unit, used, edf, warnings


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
    shares = _term_shares(theta_sq, tau_s)
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


def _fitted_intervals(theta, tau, m, n_samples, used, confidence):
    """Per-term value and interval of the fit (module docstring).

    The fit is linear in the Allan variances on its active set: ``theta = G y`` with
    ``G = (A' W A)^-1 A' W``, so ``cov(theta) = G C G'`` with ``C`` from
    :func:`avar_covariance`. A term is resolved when ``theta_j - z sd_j > 0`` (z: the normal
    quantile of ``confidence``); its interval is the chi-square interval with
    ``edf_j = 2 theta_j^2 / var_j`` (Satterthwaite), which stays positive and is skewed like the
    Allan variance itself. Terms fitted to zero get the upper bound ``z sd_j`` of a fit with the
    term forced in; a fit that is zero for every term has no covariance, hence no bounds.
    Variances are computed in units of the largest fitted one, so any deviation a float holds works.
    """
    from statistics import NormalDist
    if not np.any(theta > 0):  # e.g. data whose deviation is exactly 0 at some cluster times
        return {term: Coefficient(term, None, note="not resolved: the fit is 0 for every term, so it gives no bound")
                for term in TERMS}
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
                upper = math.sqrt(z * math.sqrt(max(var, 0.0))) * root
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
    return out


# --------------------------------------------------------------------------------------------
# Slope read-offs (papers 000 and 002)
# --------------------------------------------------------------------------------------------

def local_slopes(tau_s, adev_values, half_window=1):
    """d log sigma / d log tau at each tau of ``tau_s`` (s) for the deviations ``adev_values``, by a least-squares line over +-half_window points
    (read-offs use +-2: five points, half a decade)."""
    lt, ls = np.log(tau_s), np.log(np.maximum(adev_values, 1e-300))
    n = lt.size
    out = np.full(n, np.nan)
    for i in range(n):
        lo, hi = max(0, i - half_window), min(n, i + half_window + 1)
        if hi - lo >= 2:
            out[i] = np.polyfit(lt[lo:hi], ls[lo:hi], 1)[0]
    return out


def _runs(indices, min_run):
    """The indices that belong to runs of at least ``min_run`` consecutive integers."""
    if indices.size == 0:
        return indices
    breaks = np.flatnonzero(np.diff(indices) != 1) + 1
    keep = [run for run in np.split(indices, breaks) if run.size >= min_run]
    return np.concatenate(keep) if keep else indices[:0]


def read_off(tau_s, adev_values, ci_low, ci_high, used, *, slope_tolerance=0.15, min_run=3):
    """Coefficients read from the slopes of the Allan deviation (papers 000 and 002).

    ``tau_s`` (s), ``adev_values`` and its interval ``ci_low``, ``ci_high`` (deg/s): the curve;
    ``used``: the taus with enough clusters.

    Q, N, K, R: among the taus (with enough clusters) whose local slope is within
    ``slope_tolerance`` of the term's slope (-1, -1/2, +1/2, +1), the one nearest the read-off
    tau (sqrt(3), 1, 3, sqrt(2) s) is moved along that slope to the read-off tau (a region is
    ``min_run`` or more consecutive taus, so that one noisy point at a long tau is not a region):
    ``c = sigma(tau_i) (tau_read / tau_i)^slope`` (e.g. N = sigma(tau_i) sqrt(tau_i), paper 002).
    B: the minimum of the curve, if the curve is flat there (slope within the tolerance of 0
    over ``min_run`` consecutive taus),
    divided by 0.664 (paper 000; = sqrt(pi / (2 ln 2)) sigma_min, paper 002).
    The interval is the chi-square interval of the point used, moved the same way. Each value
    holds the other terms' share of the curve at its tau: an upper estimate of its term
    (module docstring), another estimator than :func:`fit`.
    """
    tau = np.asarray(tau_s, dtype=np.float64)
    dev = np.asarray(adev_values, dtype=np.float64)
    idx_all = np.flatnonzero(used)
    slopes = np.full(tau.size, np.nan)
    slopes[idx_all] = local_slopes(tau[idx_all], dev[idx_all], half_window=2)
    out = {}
    for term in TERMS:
        s = TERM_SLOPE[term]
        if term == "bias_instability":
            if idx_all.size == 0:
                out[term] = Coefficient(term, None, note="no cluster time with enough clusters")
                continue
            i = int(idx_all[np.argmin(dev[idx_all])])
            flat = _runs(idx_all[np.abs(slopes[idx_all]) <= slope_tolerance], min_run)
            if i not in flat:
                upper = ci_high[i] / FLICKER_FLOOR
                out[term] = Coefficient(term, None, upper=upper, tau_s=float(tau[i]),
                                        note=f"not resolved: no flat minimum (the curve still falls at "
                                             f"tau = {tau[i]:g} s, slope {slopes[i]:+.2f}); B <= {upper:.3g} deg/s")
                continue
            out[term] = Coefficient(term, dev[i] / FLICKER_FLOOR, ci_low[i] / FLICKER_FLOOR,
                                    ci_high[i] / FLICKER_FLOOR, tau_s=float(tau[i]),
                                    note=f"flat minimum at tau = {tau[i]:g} s (local slope {slopes[i]:+.2f}) / 0.664")
            continue
        region = idx_all[np.abs(slopes[idx_all] - s) <= slope_tolerance]
        region = _runs(region, min_run)
        if region.size == 0:
            out[term] = Coefficient(term, None, note=f"not resolved: no region of slope {s:+g} "
                                                     f"({min_run} or more consecutive taus)")
            continue
        t_read = READ_TAU_S[term]
        i = int(region[np.argmin(np.abs(np.log(tau[region] / t_read)))])
        f = (t_read / tau[i]) ** s
        out[term] = Coefficient(term, dev[i] * f, ci_low[i] * f, ci_high[i] * f, tau_s=float(tau[i]),
                                note=f"read at tau = {tau[i]:g} s (local slope {slopes[i]:+.2f})")
    return out


# --------------------------------------------------------------------------------------------
# One axis, three axes
# --------------------------------------------------------------------------------------------

#: a rate beyond this (deg/s) is no gyro reading (units.MAX_RATE_DPS)
GROSS_LIMIT_DPS = MAX_RATE_DPS
#: gross-error threshold on the second-difference residual, in its robust sigmas; the still
#: MPU6050 recordings in recordings/ and simulated hours at 100 Hz and 1 kHz reach 6 at most
GROSS_Z = 50.0
_GROSS_BLOCK = 1 << 16


def gross_errors(x_dps, *, z=GROSS_Z, limit_dps=GROSS_LIMIT_DPS):
    """Indices of the samples of ``x_dps`` (deg/s) that are gross errors rather than noise or drift.

    A sample is one when ``|x_i| > limit_dps`` (beyond any MEMS full scale), or when its
    second-difference residual ``r_i = x_i - (x_{i-1} + x_{i+1}) / 2`` (``x_0 - x_1`` and
    ``x_{N-1} - x_{N-2}`` at the ends) exceeds ``z`` robust sigmas of ``r``
    (:func:`gyrofilter.analysis.detectors.robust_sigma`, 1.4826 MAD) and ``|r_i|`` is not smaller than its
    neighbours' (a spike moves their residuals by half its size, so of two spikes side by side only
    the larger may be found), and neither neighbour is beyond ``limit_dps``. A bias drift, smooth over three samples, leaves ``r`` alone, so only
    isolated jumps count; sensor motion does show up. The
    residuals are formed in blocks, so the extra memory does not grow with the series.
    """
    from .detectors import robust_sigma

    x = np.asarray(x_dps, dtype=np.float64)
    n = x.size
    with np.errstate(over="ignore", invalid="ignore"):
        if n < 3:
            return np.flatnonzero(~(np.abs(x) <= limit_dps))
        step = max(1, n // 100_000)
        mid = np.arange(1, n - 1, step)
        threshold = z * robust_sigma(x[mid] - 0.5 * (x[mid - 1] + x[mid + 1]))
        found = []
        for start in range(0, n, _GROSS_BLOCK):
            stop = min(n, start + _GROSS_BLOCK)
            lo, hi = max(0, start - 2), min(n, stop + 2)  # residuals of start-1 .. stop need x[start-2 .. stop+1]
            seg = x[lo:hi]
            r = np.empty(seg.size)
            r[1:-1] = seg[1:-1] - 0.5 * (seg[:-2] + seg[2:])
            r[0] = seg[0] - seg[1] if lo == 0 else np.nan
            r[-1] = seg[-1] - seg[-2] if hi == n else np.nan
            a = np.abs(r)
            i = np.arange(start, stop) - lo  # positions of this block's samples in seg
            left = np.where(i > 0, a[np.maximum(i - 1, 0)], 0.0)
            right = np.where(i < seg.size - 1, a[np.minimum(i + 1, seg.size - 1)], 0.0)
            spike = (a[i] > threshold) & ~(a[i] < left) & ~(a[i] < right)
            absurd = ~(np.abs(seg) <= limit_dps)
            # a neighbour of an absurd sample has a huge residual of its own: not a spike for that
            beside = absurd[np.maximum(i - 1, 0)] | absurd[np.minimum(i + 1, seg.size - 1)]
            found.append(np.flatnonzero(absurd[i] | (spike & ~beside)) + start)
    return np.concatenate(found)


def characterise_axis(x_dps, sample_rate_hz, *, taus_s=None, min_clusters=MIN_CLUSTERS,
                      confidence=0.95, terms=TERMS, axis="x"):
    """Overlapping Allan deviation, intervals and both coefficient estimates for one axis.

    ``x_dps``: 1-D rate series in deg/s, sampled at ``sample_rate_hz`` (Hz); ``taus_s``: the
    cluster times (s; default grid); ``min_clusters``: fewest clusters a fitted tau needs;
    ``confidence``: of the intervals; ``terms``: the terms fitted; ``axis``: its name. Raises :class:`AllanInputError` for constant data
    (nothing to characterise), NaN, or a record too short for a fit.
    """
    x = np.asarray(x_dps, dtype=np.float64)
    if x.ndim != 1:
        raise AllanInputError(f"axis {axis}: expected a 1-D rate series, got shape {x.shape}")
    if x.size and np.all(np.isfinite(x)) and np.ptp(x) == 0:
        raise AllanInputError(
            f"axis {axis}: all {x.size} samples equal {x[0]:g} deg/s (constant data): no noise to "
            "characterise (sensor not connected, or a saturated/stuck axis?)")
    if not (isinstance(confidence, (int, float)) and 0.0 < confidence < 1.0):
        raise SettingsError(f"confidence must be between 0 and 1 (e.g. 0.95), got {plain(confidence)}")
    for t in terms:
        if t not in TERMS:
            raise SettingsError(f"unknown noise term {t!r}; expected some of {', '.join(TERMS)}")
    try:
        tau, dev = overlapping_adev(x, sample_rate_hz, taus_s)
    except AllanInputError as exc:
        raise AllanInputError(f"axis {axis}: {exc}") from None
    if not np.max(dev) >= MIN_NOISE_DPS:
        raise AllanInputError(
            f"axis {axis}: the Allan deviation is below {MIN_NOISE_DPS:g} deg/s at every cluster time (largest "
            f"{np.max(dev):.3g}): too small a noise for the fit in float64; are the rates in deg/s?")
    n = x.size
    m = cluster_sizes(n, sample_rate_hz, tau)
    # fit, then drop the least significant unresolved term and refit until every fitted term is
    # resolved: an unresolved term left in would bias the others (NNLS keeps it >= 0, so it can
    # only soak up variance)
    allowed = list(terms)
    while True:
        theta, used, _, warnings = fit(tau, dev, m, n, terms=allowed, min_clusters=min_clusters,
                                       confidence=confidence)
        fitted = _fitted_intervals(theta, tau, m, n, used, confidence)
        weak = [t for t in allowed if fitted[t].value is None and theta[TERMS.index(t)] > 0]
        if not weak:
            break
        if len(allowed) == 1:
            break
        allowed.remove(min(weak, key=lambda t: fitted[t].z_score))
    # chi-square interval of every tau, EDF from the fitted noise mixture
    shares = _term_shares(theta, tau)
    edf = edf_mixture(n, m, shares, [TERM_ALPHA[t] for t in TERMS])
    lo, hi = chi2_interval(1.0, edf, confidence)  # relative, so that no square of a deviation underflows
    ci_low, ci_high = dev * np.sqrt(lo), dev * np.sqrt(hi)
    _, _, rel = simple_interval(dev, n, m)
    readoff = read_off(tau, dev, ci_low, ci_high, used)
    k = n_clusters(n, m)
    if np.any(k < MIN_CLUSTERS):
        warnings.append(f"axis {axis}: {int(np.sum(k < MIN_CLUSTERS))} cluster time(s) have fewer than "
                        f"{MIN_CLUSTERS} clusters" + ("" if min_clusters >= MIN_CLUSTERS else " and are used by the fit")
                        + ("; they are shown but not fitted" if min_clusters >= MIN_CLUSTERS else ""))
    res = AxisNoise(sample_rate_hz=float(sample_rate_hz), n_samples=n, tau_s=tau, adev=dev, m=m,
                    n_clusters=k, edf=edf, ci_low=ci_low, ci_high=ci_high, simple_rel=rel,
                    fitted=fitted, readoff=readoff, fit_values=np.sqrt(theta), fit_used=used,
                    confidence=confidence, warnings=warnings)
    if res.fit_consistency() < 0.8:
        res.warnings.append(
            f"axis {axis}: the five-term model lies outside the {confidence:.0%} interval at "
            f"{1 - res.fit_consistency():.0%} of the fitted taus: the noise is not just Q/N/B/K/R "
            "(see `gyrofilter gap`)")
    return res


def characterise(gyro_dps, sample_rate_hz, *, axes="xyz", **kwargs):
    """:func:`characterise_axis` for each column of ``gyro_dps`` (shape (N, 3), deg/s) at
    ``sample_rate_hz`` (Hz) named in ``axes`` (a subset of "xyz"); ``kwargs`` go to
    :func:`characterise_axis`; returns {axis name: AxisNoise}."""
    g = np.asarray(gyro_dps, dtype=np.float64)
    if g.ndim != 2 or g.shape[1] != len(axes):
        got = g.shape if g.ndim else "a scalar"
        raise AllanInputError(
            f"expected gyro rates of shape (N, {len(axes)}) for axes {', '.join(axes)}, got {got}"
            + ("; an axis is missing" if g.ndim == 2 and g.shape[1] < len(axes) else ""))
    return {a: characterise_axis(g[:, i], sample_rate_hz, axis=a, **kwargs) for i, a in enumerate(axes)}


# --------------------------------------------------------------------------------------------
# Export: the allan JSON (docs/formats.md, section 4) and Kalibr's imu.yaml
# --------------------------------------------------------------------------------------------

#: JSON key of each coefficient (docs/formats.md, section 4), in its base unit
JSON_KEY = {"quantization": "quantization_deg", "arw": "arw_dps_per_sqrt_hz",
            "bias_instability": "bias_instability_dps", "rrw": "rrw_dps_per_sqrt_s",
            "rate_ramp": "rate_ramp_dps_per_s"}
#: the units of JSON_KEY (rate_ramp_dps_per_s is deg/s per s = deg/s^2)
JSON_UNIT = {"quantization": "deg", "arw": "deg/s/sqrt(Hz)", "bias_instability": "deg/s",
             "rrw": "deg/s/sqrt(s)", "rate_ramp": "deg/s/s"}


def _coef_json(c: Coefficient):
    if c.value is None:
        return None
    return {"value": c.value, "low": c.low, "high": c.high}


def _details_json(c: Coefficient):
    d = {"symbol": TERM_SYMBOL[c.term], "unit": JSON_UNIT[c.term], "resolved": c.resolved,
         "value": c.value, "low": c.low, "high": c.high, "upper_bound": c.upper, "tau_s": c.tau_s}
    cu = CUSTOMARY_UNIT[c.term]
    d["customary"] = {"unit": cu, "value": convert(c.value, c.term, cu), "low": convert(c.low, c.term, cu),
                      "high": convert(c.high, c.term, cu), "upper_bound": convert(c.upper, c.term, cu)}
    if c.note:
        d["note"] = c.note
    return d


def to_json(results, sample_rate_hz, *, recording=None, duration_s=None):
    """The ``gyrofilter allan --json`` document (docs/formats.md, section 4) of ``results``
    ({axis name: AxisNoise}, from :func:`characterise`) for a record at ``sample_rate_hz`` (Hz);
    ``recording`` (its name) and ``duration_s`` (s) are written when given."""
    doc = {"sample_rate_hz": float(sample_rate_hz)}
    if recording is not None:
        doc["recording"] = utf8_text(str(recording))
    if duration_s is not None:
        doc["duration_s"] = float(duration_s)
    any_axis = next(iter(results.values()))
    doc["method"] = {
        "deviation": "overlapping Allan deviation of the rate in deg/s (NIST SP 1065 eq. 11)",
        "coefficients": "weighted non-negative least squares of sigma^2 = 3Q^2/tau^2 + N^2/tau + "
                        "(2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2 over taus with >= 9 clusters",
        "interval": f"{any_axis.confidence:.0%} two-sided: chi-square interval with edf = 2 c^2 / var(c^2), "
                    "var from cov = G C G' of the linear fit (C: Allan-variance covariance from the NIST SP "
                    "1065 Table 5 EDFs and the Allan transfer function); low/high bound the value",
        "curve_interval": f"adev_low_dps/adev_high_dps: {any_axis.confidence:.0%} chi-square interval of each "
                          "point (NIST SP 1065 eq. 41, EDF for the fitted noise mixture); paper000_relative_error: "
                          "1/sqrt(2 (N/m - 1))",
        "null": "not resolved by the data (fitted to zero, or within its uncertainty of zero; then dropped "
                "from the fit); see details.<key>.upper_bound",
        "readoff": "slope read-offs of papers 000/002 (readoff.<key>): the curve at one tau, where every term adds "
                   "to it, so each is an upper estimate of its term; another estimator than the fit, for comparison",
        "units": {JSON_KEY[t]: JSON_UNIT[t] for t in TERMS},
    }
    doc["axes"] = {}
    for name, r in results.items():
        ax = {"tau_s": r.tau_s.tolist(), "adev_dps": r.adev.tolist(),
              "adev_low_dps": r.ci_low.tolist(), "adev_high_dps": r.ci_high.tolist(),
              "paper000_relative_error": [None if not math.isfinite(v) else v for v in r.simple_rel.tolist()],
              "n_clusters": r.n_clusters.tolist(), "edf": r.edf.tolist(),
              "coefficients": {JSON_KEY[t]: _coef_json(r.fitted[t]) for t in TERMS},
              "details": {JSON_KEY[t]: _details_json(r.fitted[t]) for t in TERMS},
              "readoff": {JSON_KEY[t]: _details_json(r.readoff[t]) for t in TERMS},
              "kalibr": kalibr_values(r),
              "fit_consistency": r.fit_consistency(),
              "warnings": list(r.warnings)}
        doc["axes"][name] = ax
    return doc


def kalibr_values(r: AxisNoise):
    """Kalibr's continuous-time ``gyroscope_noise_density`` (rad/s/sqrt(Hz)) = N and
    ``gyroscope_random_walk`` (rad/s^2/sqrt(Hz)) = K for one axis. When K is not resolved its
    upper bound is used (stated in ``random_walk_is_upper_bound``); B is *not* K. ``r``: the
    axis's AxisNoise."""
    n = r.fitted["arw"]
    k = r.fitted["rrw"]
    nd = n.value if n.value is not None else n.upper
    rw = k.value if k.value is not None else k.upper
    return {"gyroscope_noise_density": convert(nd, "arw", "rad/s/sqrt(Hz)"),
            "gyroscope_random_walk": convert(rw, "rrw", "rad/s^2/sqrt(Hz)"),
            "noise_density_is_upper_bound": n.value is None,
            "random_walk_is_upper_bound": k.value is None}


def kalibr_yaml(results, sample_rate_hz, *, recording=None, rostopic="/imu0"):
    """Kalibr ``imu.yaml`` gyroscope entries: the largest value over the axes (Kalibr takes one
    number for all three), continuous time, SI units. Accelerometer lines are not written (this
    package characterises the gyro only); Kalibr needs them, so fill them in from your own
    accelerometer analysis. ``results``, ``sample_rate_hz`` (Hz) and ``recording`` as for
    :func:`to_json`; ``rostopic``: the IMU topic written."""
    per_axis = {a: kalibr_values(r) for a, r in results.items()}
    nd = max(v["gyroscope_noise_density"] for v in per_axis.values())
    rw = max(v["gyroscope_random_walk"] for v in per_axis.values())
    lines = ["# Kalibr IMU noise model (gyroscope), written by gyrofilter allan",
             f"# recording: {utf8_text(str(recording))}" if recording else "# recording: (array)",
             "# continuous-time densities; the maximum over the axes is used:"]
    for a, v in per_axis.items():
        lines.append(f"#   {a}: noise_density {v['gyroscope_noise_density']:.6e} rad/s/sqrt(Hz)"
                     f"{' (upper bound)' if v['noise_density_is_upper_bound'] else ''}, random_walk "
                     f"{v['gyroscope_random_walk']:.6e} rad/s^2/sqrt(Hz)"
                     f"{' (upper bound: K not resolved)' if v['random_walk_is_upper_bound'] else ''}")
    lines += ["# Kalibr recommends inflating these for real-world conditions (e.g. x10 for the random walk).",
              "# accelerometer_noise_density and accelerometer_random_walk: not estimated here",
              f"gyroscope_noise_density: {nd:.6e}   # rad/s/sqrt(Hz)",
              f"gyroscope_random_walk: {rw:.6e}   # rad/s^2/sqrt(Hz)",
              f"rostopic: {rostopic}",
              f"update_rate: {float(sample_rate_hz):g}   # Hz", ""]
    return "\n".join(lines)
