"""The intervals of the fitted noise coefficients (:mod:`~gyrofilter.analysis.noise.fit`).

Uncertainty of a fitted coefficient (two-sided, at ``confidence``, default 95 %): the fit is
linear in the Allan variances on its active set, ``theta = G y`` with ``G = (A' W A)^-1 A' W``,
so ``cov(theta) = G C G'``. ``C`` (:func:`avar_covariance`) has the standard deviations of the
NIST SP 1065 Table 5 EDF for each noise type, summed over the fitted mixture (conservative, see
:func:`gyrofilter.analysis.noise.allan.edf_mixture`), and the correlations between cluster times from the
Allan transfer function (:func:`avar_correlation`). The interval inverts the test of the estimate with
that variance at each value of the term (:func:`_interval`: the others' share normal, the term's own
a chi-square with ``edf = 2 theta_j^2 / var_own`` (Satterthwaite)), spanning as well the fits with a bias instability B,
a random walk K or a ramp R that the record does not resolve forced in (:func:`fitted_intervals`). A term not resolved
gets an upper bound by test inversion (:func:`upper_bound`). The round-trip tests check that the
interval covers the true coefficient in at least 90 % of simulated records (measured: 94-100 %);
``tools/allan_coverage.py`` measures intervals and bounds where K and a temperature drift are not
resolved.
"""
from __future__ import annotations

import functools
import math
from statistics import NormalDist

import numpy as np

from .allan import chi2_ppf, confidence_text, edf_oavar
from .model import TERM_ALPHA, TERM_SLOPE, TERM_SYMBOL, TERM_UNIT, TERMS, Coefficient, basis, term_shares


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


@functools.lru_cache(maxsize=16)
def _term_moments(n_samples, m):
    """Per term (rows in TERMS order) at the cluster sizes ``m`` (a tuple) of ``n_samples``: the
    relative standard deviation ``sqrt(2 / edf)`` of the Allan variance (SP 1065 EDF) and the
    correlation matrix (:func:`avar_correlation`); kept, since the bounds' searches ask for the
    covariance of many mixtures on the same taus."""
    m = np.asarray(m, dtype=np.float64)
    rel_sd = np.array([np.sqrt(2.0 / edf_oavar(n_samples, m, TERM_ALPHA[t])) for t in TERMS])
    corr = np.array([avar_correlation(m[:, None], m[None, :], TERM_ALPHA[t]) for t in TERMS])
    return rel_sd, corr


def avar_covariance(tau_s, m, n_samples, theta_sq):
    """Approximate covariance matrix of the Allan variance estimates at ``m`` (cluster sizes; ``tau_s`` the cluster times, s; ``n_samples`` samples) for the noise
    mixture ``theta_sq`` (Q^2 ... R^2): standard deviations from the SP 1065 EDF of each term,
    summed (conservative), and correlations from :func:`avar_correlation`, averaged over the
    terms with weights sqrt(sd_ki sd_kj)."""
    m = np.asarray(m, dtype=np.float64)
    rel_sd, corr = _term_moments(int(n_samples), tuple(m.tolist()))
    sd_k = term_shares(theta_sq, tau_s) * rel_sd
    sd = sd_k.sum(axis=0)
    num = np.zeros((m.size, m.size))
    den = np.zeros((m.size, m.size))
    for k in range(len(TERMS)):
        if not np.any(sd_k[k] > 0):
            continue
        a = np.sqrt(np.outer(sd_k[k], sd_k[k]))
        num += a * corr[k]
        den += a
    rho = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.eye(m.size))
    return sd, rho * np.outer(sd, sd)


def _gain(a, w, active):
    """The weighted least-squares gain ``(A' W A)^-1 A' W`` of the ``active`` columns of ``a``; where
    ``A' W A`` is singular (more active terms than cluster times, on a record of a few dozen
    samples: "Singular matrix" was all a user read), its pseudo-inverse, the least-norm solution."""
    aa = a[:, active]
    normal, right = aa.T @ (aa * w[:, None]), (aa * w[:, None]).T
    try:
        return np.linalg.solve(normal, right)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(normal) @ right


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


def _misfit_scale(chi2_nu, widen):
    """The factor the covariance is scaled by: the misfit ``chi2_nu`` where ``widen`` and above 1."""
    return chi2_nu if widen and chi2_nu is not None and chi2_nu > 1.0 else 1.0


def _forced_fit(a, w, y, terms, cov_of, widen):
    """The unconstrained weighted least-squares fit of ``terms`` (bool, 5): ``(gain, theta, cov,
    scale)``, its gain (:func:`_gain`), the five values, the covariance of the Allan variances at
    its mixture (negative values taken as 0; ``cov_of``) and its misfit scale (:func:`_misfit_scale`)."""
    gain = _gain(a, w, terms)
    theta = np.zeros(a.shape[1])
    theta[terms] = gain @ y
    cov = cov_of(np.maximum(theta, 0.0))
    return gain, theta, cov, _misfit_scale(reduced_chi2(a, y, theta, w, cov, terms)[0], widen)


def _fixed_fit(a, w, y, terms, u, t):
    """The five values of the weighted least-squares fit of ``terms`` (bool, 5) to ``y`` with term
    ``u`` (an index in ``terms``) held at ``theta_u = t``: the others are ``G (y - t a_u)`` with the
    gain ``G`` (:func:`fitted_intervals`) of their columns of ``a`` and the weights ``w``
    (unclipped: a term the hypothesis pushes below zero shows it)."""
    others = terms.copy()
    others[u] = False
    theta = np.zeros(a.shape[1])
    theta[u] = t
    if others.any():
        theta[others] = _gain(a, w, others) @ (y - t * a[:, u])
    return theta


def upper_bound(a, w, y, active, u, confidence, cov_of, widen=True):
    """``(bound, scale)``: the upper bound of ``theta_u`` (a term not resolved; ``active``: the
    fitted terms, bool 5) by inverting the one-sided test of its estimate (Neyman's construction;
    Casella & Berger, *Statistical Inference*, 2nd ed., sec. 9.2.1), or None where no value is
    excluded; and the misfit scale of the fit with ``u`` forced in.

    ``h = max(theta_u^, 0)``, with ``theta_u^`` the estimate of the fit with ``u`` forced in (the
    gain ``g`` of ``active`` and ``u``; the value the data give the term, so the bound is never below
    it). If ``theta_u`` were ``t``, that estimate would scatter with the variance
    ``sd(t)^2 = g C(t) g'``: ``C(t) = cov_of(theta(t))`` (:func:`avar_covariance`), ``theta(t)``
    the other terms refitted with ``u`` held at ``t`` (:func:`_fixed_fit`, negative values taken as
    0). Of it, ``sd(0)^2`` is the other terms' scatter, taken as normal (the estimate is a
    difference of Allan variances: it can be negative) and multiplied by the misfit scale of the fit
    with ``u`` forced in (``max(1, chi2_nu)``, :func:`reduced_chi2`, with ``widen``; the misfit of the
    fit without ``u`` holds ``u``'s own share, which the hypothesis now explains):
    ``s0^2 = scale sd(0)^2``. The rest, ``sd(t)^2 - sd(0)^2``, is the term's own, taken as
    ``t chi2(nu) / nu`` with ``nu = 2 t^2 / (sd(t)^2 - sd(0)^2)`` (Satterthwaite, as the intervals:
    skewed, never below 0; not scaled by the misfit, structure no term fits is not the term's own
    scatter, and a ``nu`` so divided below 1 bounded K on a 655-s MPU6050 record at 190 times the
    value the data allow, where its deviation would be 100 times the one measured). The
    two lower deviations at the one-sided level ``(1 - confidence) / 2`` are added in quadrature
    (exact for two normal parts), ``d(t) = sqrt((t - t chi2_p(nu) / nu)^2 + (z s0)^2)``, and ``t`` is
    excluded when ``h < t - d(t)``; the bound is the smallest ``t`` excluded (bisection).
    The bound ``h + z sd`` with ``sd`` at the fitted mixture (which lacks the term, or holds it
    at its low estimate) held a simulated random walk K on 73 % of the axes where a 95 % bound
    should hold it on 97.5 % (``python tools/allan_coverage.py``, white + random walk, 60 min: 68 of
    93): it leaves out the scatter a real term adds to the long taus; and a normal quantile at
    ``sd(t)`` excludes no value where the estimate's relative spread exceeds 1/z (a K that 30 minutes
    do not resolve)."""
    forced = active.copy()
    forced[u] = True
    gain, _, _, scale = _forced_fit(a, w, y, forced, cov_of, widen)
    g = gain[int(np.sum(forced[:u]))]
    h = max(float(g @ y), 0.0)
    p = 0.5 - confidence / 2.0
    z = NormalDist().inv_cdf(1.0 - p)

    def var_at(t):
        theta_t = _fixed_fit(a, w, y, forced, u, t)
        return max(float(g @ cov_of(np.maximum(theta_t, 0.0)) @ g), 0.0)

    var0 = var_at(0.0)
    s0 = math.sqrt(var0 * scale)

    def excluded(t):
        own = var_at(t) - var0
        low = t if own <= 0 else t * float(chi2_ppf(p, 2.0 * t * t / own)) / (2.0 * t * t / own)
        return h < t - math.hypot(t - low, z * s0)

    lo, hi = h, max(2.0 * h + 2.0 * z * s0, _SMALLEST_BOUND)
    for _ in range(_STEPS):
        if excluded(hi):
            break
        lo, hi = hi, 4.0 * hi
    else:
        return None, scale
    while hi - lo > _BOUND_TOLERANCE * hi and hi > _SMALLEST_BOUND:  # (h = s0 = 0: every t > 0 excluded)
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if excluded(mid) else (mid, hi)
    return hi, scale


#: where the search for a bound starts, in units of the largest fitted variance (and where the
#: bisection stops: a term the data give 0 with no scatter of the others, every value above 0
#: excluded, halved it down to the smallest float, then for ever), its most steps (each x4), and
#: its relative precision
_SMALLEST_BOUND = 1e-16
_STEPS = 40
_BOUND_TOLERANCE = 1e-3


def _freed_bound(a, w, y, active, u, freed, bound, confidence, cov_of, widen):
    """The bound of a term ``u`` not resolved, whatever K and R are (:func:`fitted_intervals`): the
    largest of ``bound`` (:func:`upper_bound` of ``u`` in the fit of ``active``) and the bounds of
    ``u`` in the fits (a) with each term of ``freed`` (K, R not resolved) that ``active`` lacks
    forced in as well, in turn, and (b) without each K or R of ``active`` that the fit with ``u``
    forced in does not resolve (``theta_v - z sd_v <= 0`` at that fit's mixture and misfit scale;
    the fit's drop rule, :func:`~gyrofilter.analysis.noise.fit.characterise_axis`, would drop it
    there), in turn; None where one of them excludes no value.

    Why (b): a slow drift that is neither term (the default MPU6050 model's temperature) is fitted
    as K, and K then takes part of B's flat level once B is forced in. The bound of the one fit
    held the gyro's B on 70 of 75 axes where B was not resolved at 30 min and on 21 of 27 at 60 min
    (seeds 101-160, ``python tools/allan_coverage.py``); this union on 72 of 75 and 26 of 27 (the
    accelerometer's: 80 of 86 -> 85 of 86, 7 of 9 -> 9 of 9), for bounds a median 1.03-1.12x the
    one fit's (1.3x for a random walk that 10 minutes do not resolve); no term's interval or
    resolution changes. A term resolved in the fit drawn but not once K or R is free is bounded so
    too (its bound was ``max(theta_j, 0) + z sd_j`` of the fits, the rule :func:`upper_bound`
    replaced for the terms left out)."""
    if bound is None:
        return None
    n = a.shape[1]
    fits = [active | (np.arange(n) == v) for v in freed if not active[v]]
    forced = active | (np.arange(n) == u)
    gain, theta, cov, scale = _forced_fit(a, w, y, forced, cov_of, widen)
    z = NormalDist().inv_cdf(0.5 + confidence / 2.0)
    fits += [active & (np.arange(n) != v) for v in np.flatnonzero(active)
             if v != u and TERM_SLOPE[TERMS[v]] > 0
             and not _resolved(theta, gain, forced, v, cov * scale, z)[0]]
    for fit_terms in fits:
        b, fit_scale = _bound_of(a, w, y, fit_terms, u, confidence, cov_of, widen)
        if b is None and fit_scale is not None:  # this fit excludes no value (a singular one is skipped)
            return None
        bound = bound if b is None else max(bound, b)
    return bound


def _bound_of(a, w, y, active, u, confidence, cov_of, widen):
    """:func:`upper_bound`'s ``(bound, scale)``, or ``(None, None)`` where the fit's matrix is singular."""
    try:
        return upper_bound(a, w, y, active, u, confidence, cov_of, widen)
    except np.linalg.LinAlgError:
        return None, None


def _resolved(theta, gain, terms, j, cov, z):
    """``(resolved, sd_j)`` of term ``j`` estimated as ``theta[j]`` by the rows ``gain`` of the fitted
    ``terms`` under the covariance ``cov`` of the Allan variances: ``sd_j = sqrt(g_j C g_j')`` and
    resolved when ``theta_j - z sd_j > 0``."""
    row = gain[int(np.sum(terms[:j]))]
    sd = math.sqrt(max(float(row @ cov @ row), 1e-300))
    return float(theta[j]) - z * sd > 0, sd


def _interval(a, w, y, terms, j, confidence, cov_of, scale):
    """``(low, high)`` of a resolved term ``j`` of the weighted least-squares fit of ``terms``
    (bool, 5) to ``y``: the test of its estimate ``h = g y`` (``g`` its row of the gain,
    :func:`_gain`) inverted at each ``theta_j = t`` (Neyman's construction, as :func:`upper_bound`;
    Casella & Berger sec. 9.2.1). At ``t`` the others are refitted (:func:`_fixed_fit`, negative
    values taken as 0): ``theta(t)``. The estimate's variance ``g C(theta(t)) g'``
    (:func:`avar_covariance`, times ``scale``, the misfit scale) splits into the others' part
    ``s0(t)^2`` (the same with ``theta_j = 0``), taken as normal, and the term's own, the rest,
    taken as ``t chi2(nu) / nu`` with ``nu = 2 t^2 / own`` (Satterthwaite). With ``p = (1 - confidence) / 2``
    and the two deviations added in quadrature, ``t`` is too high where
    ``h < t - sqrt((t - t chi2_p(nu) / nu)^2 + (z s0)^2)``, too low where
    ``h > t + sqrt((t chi2_(1-p)(nu) / nu - t)^2 + (z s0)^2)``; the interval lies between (bisection).
    None where the estimate ``h`` is not above 0 (a singular fit's least-norm one, :func:`_gain`) or where
    ``t ~ 0`` is not too low (the low end would be 0): the others' spread with
    ``theta_j = 0`` refitted holds ``h`` though the spread at the estimate does not; the term is
    then not resolved (Q on 1 of 88 resolved 10-min ``white-quant`` axes, ``tools/allan_coverage.py``).

    The rule before, the chi-square interval with ``edf = 2 theta_j^2 / var_j`` at the estimate,
    is right where the estimate is a scaled chi-square (variance ~ theta_j^2). B's is mostly the
    others': on 10-min records of N = 0.01, B = 0.005, K = 0.003 (``tools/allan_coverage.py``,
    ``white-flicker-rw``, seeds 41-80) three quarters of the variance of B^2 in the fit of N, B and
    K are N's and K's. A scatter that does not grow with B, read at a high estimate, gives a large
    edf and a lower end ``h^2 / (h + z sd)`` above ``h - z sd``: in that fit it left the true B
    out on 15 of 120 axes, every one below the interval (a normal interval: 6), and on 14 of the 61
    axes where the fit drawn resolves B (the high estimates); with the variance at the hypothesis,
    on 5 of 61, for intervals a median 1.16x as wide (log high/low; K's 1.06x, N's 1.03x).
    """
    g = _gain(a, w, terms)[int(np.sum(terms[:j]))]
    h = float(g @ y)
    if not h > 0:  # (a singular fit's least-norm estimate, fewer taus than terms: the bisections never ended)
        return None
    p = 0.5 - confidence / 2.0
    z = NormalDist().inv_cdf(1.0 - p)

    def ends(t):  # t - low and high - t of the estimate's spread at t
        mix = np.maximum(_fixed_fit(a, w, y, terms, j, t), 0.0)
        var = max(float(g @ cov_of(mix) @ g), 0.0) * scale
        mix[j] = 0.0
        s0 = z * math.sqrt(max(float(g @ cov_of(mix) @ g), 0.0) * scale) if mix.any() else 0.0
        own = var - (s0 / z) ** 2
        if not own > 0:  # no share of its own at t (or t = 0): the others' spread alone
            return s0, s0
        nu = 2.0 * t * t / own
        return (math.hypot(t - t * float(chi2_ppf(p, nu)) / nu, s0),
                math.hypot(t * float(chi2_ppf(1.0 - p, nu)) / nu - t, s0))

    lo, hi = h, 2.0 * h + 2.0 * ends(h)[1]
    for _ in range(_STEPS):  # (the own part grows as t^2: some t is too high)
        if h < hi - ends(hi)[0]:
            break
        lo, hi = hi, 4.0 * hi
    while hi - lo > _BOUND_TOLERANCE * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if h < mid - ends(mid)[0] else (mid, hi)
    high, lo, hi = hi, 0.0, h
    if not h > _BOUND_TOLERANCE * h + ends(_BOUND_TOLERANCE * h)[1]:  # the others' spread at t ~ 0 holds h
        return None
    while hi - lo > _BOUND_TOLERANCE * hi:  # t ~ 0 is too low (h > z s0)
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if h > mid + ends(mid)[1] else (lo, mid)
    return lo, high


def _freed_points(a, w, y, active, freed, j, cov_of, z, confidence):
    """The interval (:func:`_interval`) of term ``j`` in the fit with each term of ``freed``
    ({index: misfit scale}) forced in, in turn (:func:`fitted_intervals`), None where ``j`` is not
    resolved there (:func:`_resolved`): a list."""
    out = []
    for u, scale in freed.items():
        forced = active | (np.arange(a.shape[1]) == u)
        gain = _gain(a, w, forced)
        theta = np.zeros(a.shape[1])
        theta[forced] = gain @ y
        resolved = _resolved(theta, gain, forced, j, cov_of(np.maximum(theta, 0.0)) * scale, z)[0]
        out.append(_interval(a, w, y, forced, j, confidence, cov_of, scale) if resolved else None)
    return out


def _freed_terms(bounds, scales):
    """The terms not resolved whose value the others' intervals are taken whatever
    (:func:`fitted_intervals`): ``{index: misfit scale}`` of those of ``bounds`` (the terms not
    resolved) that do not fall with tau (``TERM_SLOPE >= 0``: B, K, R) and whose fit with the term
    forced in is not singular (``scales``: :func:`_bound_of`'s).

    Not Q: N's interval conditional on Q = 0 held N on 96-98 % of the axes without a Q
    (``python tools/allan_coverage.py``, seeds 41-80, 10 min), and freeing Q widened it a median
    1.6-fold there. The price: a Q the fit drops is held at 0 and N takes its share of the shortest
    taus (``white-quant``, Q = 1e-4 deg on x, dropped on 24 of 40 10-min axes: N held on 13 of
    them; on 105 of the case's 120 axes). Freed, N held on 115 of 120; freed on one side only (the
    low end of N's interval with Q free: a Q above 0 lowers N), 115 of 120 too, for N's intervals a
    median 1.25-1.30x as wide on the cases without Q.

    B is freed as K and R are (issue 37): held at 0, an unresolved B leaves its flat share of the
    long taus to a resolved K, whose interval then sits above the truth. On 10-min, 100 Hz records
    with N = 0.01, B = 0.005 deg/s and K = 0.003 together (attack pass 34a), K's interval, or its
    bound where not resolved, held K on 109 of 130 seeds (84 %), on 34 of 40 with K = 0.002; with B
    freed too, on 124 of 130 and 39 of 40 (white noise and K alone: 39 -> 40 of 40), for K's
    interval a median 1.00-1.17x as wide where resolved, N's unchanged (1.09x with white noise and
    K alone; these with the chi-square interval at the estimate that :func:`_interval` replaced:
    with it, ``tools/allan_coverage.py`` ``white-flicker-rw``, seeds 41-80, 10 min, holds B on 56
    of the 61 axes that resolve it, 47 before). The bounds of the terms the fit drawn does not
    resolve stay the union over K and R alone (:func:`_freed_bound`; B's own bound among them); a
    term resolved there but not once B is free is bounded by the union with B forced in as well."""
    return {u: scales[u] for u in bounds if scales[u] is not None and TERM_SLOPE[TERMS[u]] >= 0}


def fitted_intervals(theta, tau, m, n_samples, used, confidence, avar, widen=True, free=True, term_unit=TERM_UNIT):
    """Per-term value and interval of the fit (module docstring), and the fit's misfit:
    returns ``(coefficients, chi2_nu, dof)`` (:func:`reduced_chi2`; None, None without residual
    degrees of freedom).

    ``theta``: the fitted Q^2 .. R^2; ``tau``, ``m``: the cluster times (s) and sizes; ``used``:
    the taus fitted; ``avar``: the measured Allan variances at every tau ((deg/s)^2); ``widen``:
    scale by the misfit (below; False: the intervals of the stated scatter alone); ``free``:
    each resolved term's interval spans the fits with a B, K or R not resolved forced in (below;
    False: the intervals with those terms at their fitted values, the fit's drop decision);
    ``term_unit``: each term's unit, named in the notes (the sensor's
    :class:`~gyrofilter.analysis.noise.model.SensorTerms` ``term_unit``; the fit itself has no unit).
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
    A term is resolved when ``theta_j - z sd_j > 0`` (z: the normal quantile of ``confidence``)
    and its interval's low end is above 0; the interval inverts the test of ``theta_j`` with the
    variance at each hypothesis (:func:`_interval`: the others' share normal, the term's own
    chi-square), skewed like the Allan variance where the term's own share dominates, widening
    by about sqrt(chi2_nu) with the misfit (either scale, theta_j or its root). A term not
    resolved (fitted to zero, dropped, or within its uncertainty of zero) gets the upper bound of
    :func:`upper_bound` (the test inverted, with the term forced in); a fit that is zero for every
    term has no covariance, hence no bounds.

    **The terms not resolved that rise with tau (K, R), or are flat (B).** The interval of a resolved term is
    conditional on the fit's values of the others: a term dropped is held at 0, and a random walk K
    or a ramp R that the record does not resolve, held at 0, puts its share of the long taus into B
    (on 30-min records of the default MPU6050 model B's interval held the accelerometer's B on 83 of
    99 axes where resolved, read up to 1.35x; white noise and a random walk gave a B resolved where
    there is none, on 13 of 240 axes at 30 and 60 min). So each resolved term's interval is the
    union of its interval in the fit drawn and its interval in the fit with each such ``u`` forced
    in, in turn: the unconstrained weighted least squares with ``u`` free (``G`` of the active terms
    and ``u``; the covariance at that fit's mixture, negative values taken as 0, times the misfit
    scale of that fit), whose ``cov(theta)`` holds the trade-off of the term with ``u``: its
    marginal interval whatever ``u`` is (a nuisance parameter estimated, not fixed; Casella &
    Berger sec. 9.2.2 on eliminating nuisance parameters). Where the term is within its
    uncertainty of zero in one of those fits (``theta_j - z sd_j <= 0``), it is not resolved
    (``Coefficient.freed_by``: those terms). Every bound is that union too (:func:`_freed_bound`).

    A bias instability B not resolved is freed too; the terms that fall with tau (Q, and N where
    dropped) are not (:func:`_freed_terms`: why, and the bounds).
    Holding the term at ``u``'s upper bound instead (a profile over ``[0, U_u]``) left B unresolved
    on nearly every axis, even without a random walk (white noise and flicker: B's interval
    widened 2-fold, resolved on 0 of 30 axes of 10-min records, where it was on 19): a 95 %
    interval at a 97.5 % bound is far more than 95 %.
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
    scale = _misfit_scale(chi2_nu, widen)

    def cov_of(mixture):
        return avar_covariance(tau_u, m_u, n_samples, mixture)[1]

    gain = _gain(a, w, active)
    points = {j: _resolved(theta, gain, active, j, cov_y * scale, z) for j in np.flatnonzero(active)}
    own = {j: _interval(a, w, y, active, j, confidence, cov_of, scale) for j in points if points[j][0]}
    bounds, scales = {}, {}
    for u in (j for j in range(5) if own.get(j) is None):
        bounds[u], scales[u] = _bound_of(a, w, y, active, u, confidence, cov_of, widen)
    freed = _freed_terms(bounds, scales) if free else {}
    rising = {u: s for u, s in freed.items() if TERM_SLOPE[TERMS[u]] > 0}  # the bounds: whatever K and R are
    for u in [u for u in bounds if u not in rising and bounds[u] is not None]:
        bounds[u] = _freed_bound(a, w, y, active, u, rising, bounds[u], confidence, cov_of, widen)
    out = {}
    for j, term in enumerate(TERMS):
        sym, unit = TERM_SYMBOL[term], term_unit[term]
        c2 = float(theta[j])
        if j in bounds:
            upper = None if bounds[j] is None else math.sqrt(bounds[j]) * root
            note = (f"not resolved: {sym} = {math.sqrt(c2) * root:.3g} {unit} is within the {confidence_text(confidence)} uncertainty "
                    "of zero" if active[j] else
                    f"not resolved: {sym} is not needed to fit the data (fitted to 0 or not significant)")
            if upper is not None:
                note += f"; {confidence_text(confidence)} upper bound {upper:.3g} {unit}"
            out[term] = Coefficient(term, None, upper=upper, note=note,
                                    z_score=c2 / points[j][1] if active[j] else None)
            continue
        ends = [own[j]] + _freed_points(a, w, y, active, freed, j, cov_of, z, confidence)
        freed_by = tuple(TERMS[u] for u, end in zip(freed, ends[1:]) if end is None)
        if freed_by:
            bound = _bound_of(a, w, y, active, j, confidence, cov_of, widen)[0]
            bound = _freed_bound(a, w, y, active, j, freed, bound, confidence, cov_of, widen)
            upper = None if bound is None else math.sqrt(bound) * root
            names = " and ".join(TERM_SYMBOL[t] for t in freed_by)
            out[term] = Coefficient(term, None, upper=upper, z_score=c2 / points[j][1], freed_by=freed_by,
                                    note=f"not resolved: {sym} = {math.sqrt(c2) * root:.3g} {unit} is within the "
                                         f"{confidence_text(confidence)} uncertainty of zero once {names} (not resolved) "
                                         f"{'are' if len(freed_by) > 1 else 'is'} free"
                                         + ("" if upper is None else f"; {confidence_text(confidence)} upper bound {upper:.3g} {unit}"))
            continue
        # the tau where this term's share of the model is largest: where it is read
        share = a[:, j] * c2 / (a @ theta)
        out[term] = Coefficient(term, math.sqrt(c2) * root, math.sqrt(min(e[0] for e in ends)) * root,
                                math.sqrt(max(e[1] for e in ends)) * root,
                                tau_s=float(tau_u[int(np.argmax(share))]), z_score=c2 / points[j][1])
    return out, chi2_nu, dof
