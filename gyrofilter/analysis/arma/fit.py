"""ARMA(p, q) estimation in paper 003's signs (:mod:`gyrofilter.analysis.arma.identify`): the conditional
least-squares fit, its stationary and invertible parametrisation, and simulation.

Estimation is Pandit-Wu's nonlinear least squares on the conditional residuals (conditional
sum of squares, CSS), a_t = x_t - sum phi_i x_{t-i} + sum theta_j a_{t-j} computed with
``scipy.signal.lfilter``, minimised by ``scipy.optimize.least_squares`` from a Hannan-Rissanen
start; stationarity and invertibility are kept by optimising the partial autocorrelations
(Monahan 1984 / Jones 1980 transform). The tests compare it with statsmodels' exact maximum
likelihood.

statsmodels is the optional ``stats`` extra (``pip install "gyrofilter[stats]"``), the gate of
the whole ARMA analysis (:func:`require_stats`); it and scipy are imported inside the functions
that use them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...errors import SettingsError
from ...extras import require


def require_stats():
    """Import statsmodels, or raise MissingExtraError naming the extra that installs it."""
    require("statsmodels", "ARMA analysis")


LSQ_METHOD = "lm"  # MINPACK Levenberg-Marquardt: ~5x faster than "trf" here, same or lower RSS


# ---------------------------------------------------------------------------------------------
# the fit


@dataclass
class ArmaFit:
    """One fitted ARMA(p, q) in the paper's signs: x_t - sum phi x_{t-i} = a_t - sum theta a_{t-j}."""

    p: int
    q: int
    phi: list
    theta: list
    sigma_a: float  # residual (innovation) std, in the series' unit
    rss: float
    n_residuals: int
    aic: float  # paper-003 per-sample form: ln(sigma_a^2) + 2 (p + q) / N
    residuals: np.ndarray = field(repr=False, default=None, compare=False)

    @property
    def n_params(self) -> int:
        """p + q, the number of ARMA coefficients."""
        return self.p + self.q

    @property
    def order(self):
        """(p, q)."""
        return (self.p, self.q)

    def equation(self, digits=4) -> str:
        """The model as paper 003 writes it with ``digits`` decimals, e.g. ``x_t - 1.0000 x_{t-1} = a_t - 0.9994 a_{t-1}``."""
        left = "x_t" + "".join(_term(-c, f"x_{{t-{i + 1}}}", digits) for i, c in enumerate(self.phi))
        right = "a_t" + "".join(_term(-c, f"a_{{t-{j + 1}}}", digits) for j, c in enumerate(self.theta))
        return f"{left} = {right}"

    def to_dict(self):
        """The fit as plain data (the ``arma --json`` document's fit entries)."""
        return {"p": self.p, "q": self.q, "phi": list(self.phi), "theta": list(self.theta),
                "sigma_a": self.sigma_a, "rss": self.rss, "n_residuals": self.n_residuals, "aic": self.aic,
                "equation": self.equation()}


def _term(c, name, digits):
    sign = "-" if c < 0 else "+"
    return f" {sign} {abs(c):.{digits}f} {name}"


# ---------------------------------------------------------------------------------------------
# ARMA estimation (conditional least squares)


def pacf_to_coefficients(r):
    """Coefficients c_1..c_k of a stationary polynomial 1 - sum c_i B^i from partial autocorrelations ``r`` (r_i in (-1, 1)).

    Durbin-Levinson step (Monahan 1984): c^(k)_k = r_k, c^(k)_j = c^(k-1)_j - r_k c^(k-1)_{k-j}.
    """
    c = np.zeros(0)
    for rk in np.asarray(r, float):
        c = np.concatenate([c - rk * c[::-1], [rk]])
    return c


def coefficients_to_pacf(c):
    """Inverse of :func:`pacf_to_coefficients`: the partial autocorrelations of the coefficients ``c``
    (raises ValueError if the polynomial has a root on or inside the unit circle)."""
    c = np.asarray(c, float).copy()
    r = np.zeros(len(c))
    for k in range(len(c), 0, -1):
        rk = c[k - 1]
        if not abs(rk) < 1:
            raise ValueError("not stationary/invertible")
        r[k - 1] = rk
        prev = c[: k - 1]
        c = (prev + rk * prev[::-1]) / (1 - rk * rk)
    return r


def _to_unconstrained(c, limit=1.0 - 1e-12):
    try:
        r = coefficients_to_pacf(c)
    except ValueError:
        r = np.full(len(c), 0.5 if len(c) else 0.0) * np.sign(np.sum(c) or 1.0)
    return np.arctanh(np.clip(r, -limit, limit))


def _resized_u(c, k):
    """Unconstrained start for order k from coefficients c of another order: their partial
    autocorrelations truncated or zero-padded (a nested model of the same lower-order shape)."""
    try:
        r = coefficients_to_pacf(np.asarray(c, float)) if len(c) else np.zeros(0)
    except ValueError:
        return None
    r = np.r_[r[:k], np.zeros(max(0, k - len(r)))]
    return np.arctanh(np.clip(r, -1.0 + 1e-12, 1.0 - 1e-12))


def _from_unconstrained(u):
    return pacf_to_coefficients(np.tanh(u))


def arma_residuals(x, phi, theta):
    """Conditional residuals a_t = x_t - sum phi_i x_{t-i} + sum theta_j a_{t-j}, zero before t = 0,
    of the series ``x`` for the coefficients ``phi`` and ``theta``."""
    from scipy.signal import lfilter

    return lfilter(np.r_[1.0, -np.asarray(phi, float)], np.r_[1.0, -np.asarray(theta, float)], x)


def _hannan_rissanen(x, p, q):
    """Starting values: long AR by least squares, then regress x_t on x_{t-i} and -a_{t-j} (Hannan and Rissanen 1982)."""
    n = len(x)
    if q == 0 and p == 0:
        return np.zeros(0), np.zeros(0)
    m = min(max(20, 2 * (p + q)), n // 10)
    if q > 0:
        X = np.column_stack([x[m - i - 1 : n - i - 1] for i in range(m)])
        ar_long, *_ = np.linalg.lstsq(X, x[m:], rcond=None)
        a = np.zeros(n)
        a[m:] = x[m:] - X @ ar_long
    start = m + max(p, q) if q > 0 else p
    cols = [x[start - i - 1 : n - i - 1] for i in range(p)] + [-a[start - j - 1 : n - j - 1] for j in range(q)]
    coef, *_ = np.linalg.lstsq(np.column_stack(cols), x[start:], rcond=None)
    return coef[:p], coef[p:]


def _transform_jacobian(u, eps=1e-7):
    """d coefficients / d u of the PACF transform (central differences; k x k, k <= ~8)."""
    k = len(u)
    jac = np.zeros((k, k))
    for i in range(k):
        d = np.zeros(k)
        d[i] = eps
        jac[:, i] = (_from_unconstrained(u + d) - _from_unconstrained(u - d)) / (2 * eps)
    return jac


#: a fit whose residual variance is below this fraction of the series' own (sigma_a below 1e-6 of
#: its spread) predicts the series exactly: a deterministic signal (an alternating or sinusoidal
#: one), not noise; a sensor's innovations are within a few decades of its spread
EXACT_FIT_RATIO = 1e-12


def fit_arma(x, p, q, *, start=None, keep_residuals=True) -> ArmaFit:
    """Least-squares (CSS) fit of ARMA(p, q) to a zero-mean series ``x``; paper-003 signs. With
    ``keep_residuals`` the fit keeps its residual series.

    Minimises sum_{t >= p} a_t^2 over stationary phi and invertible theta (PACF parametrisation)
    with the analytic Jacobian of the residuals::

        da_t/dphi_i = -x_{t-i} / theta(B),   da_t/dtheta_j = a_{t-j} / theta(B)

    from the best of several starts: ``start`` (phi, theta) if given (e.g. the neighbouring
    order's fit; its partial autocorrelations zero-padded or truncated, so a larger model starts
    exactly at the smaller fit), Hannan-Rissanen, and for ARMA(1, 1)-sized models a near-unit-root start
    (phi_1 = 0.999, theta_1 = 0.99, as paper 003's data need) and a small-coefficient start.
    A fit that predicts the series exactly (:data:`EXACT_FIT_RATIO`) raises SettingsError.
    """
    require_stats()
    from scipy.optimize import least_squares
    from scipy.signal import lfilter

    x = np.asarray(x, float)
    if p < 0 or q < 0:
        raise SettingsError(f"ARMA order must be non-negative, got ({p}, {q})")
    n = len(x)
    if n < 10 * (p + q + 1):
        raise SettingsError(f"series of {n} samples is too short for ARMA({p}, {q})")

    def resid(u):
        return arma_residuals(x, _from_unconstrained(u[:p]), _from_unconstrained(u[p:]))[p:]

    def jac(u):
        phi, theta = _from_unconstrained(u[:p]), _from_unconstrained(u[p:])
        a = arma_residuals(x, phi, theta)
        den = np.r_[1.0, -theta]
        xf = lfilter([1.0], den, x)
        af = lfilter([1.0], den, a)
        cols = np.empty((n - p, p + q))
        for i in range(1, p + 1):
            cols[:, i - 1] = -xf[p - i : n - i]
        for j in range(1, q + 1):
            shifted = np.zeros(n)
            shifted[j:] = af[:-j]
            cols[:, p + j - 1] = shifted[p:]
        jt = np.zeros((p + q, p + q))
        if p:
            jt[:p, :p] = _transform_jacobian(u[:p])
        if q:
            jt[p:, p:] = _transform_jacobian(u[p:])
        return cols @ jt

    if p + q == 0:
        best_u = np.zeros(0)
    else:
        starts = []
        if start is not None:
            u_phi = _resized_u(start[0], p)
            u_theta = _resized_u(start[1], q)
            if u_phi is not None and u_theta is not None:
                starts.append(np.r_[u_phi, u_theta])
        try:
            phi0, theta0 = _hannan_rissanen(x, p, q)
            starts.append(np.r_[_to_unconstrained(phi0), _to_unconstrained(theta0)])
        except np.linalg.LinAlgError:
            pass
        if p + q <= 3:
            near_unit = np.zeros(p + q)
            if p:
                near_unit[0] = np.arctanh(0.999)
            if q:
                near_unit[p] = np.arctanh(0.99)
            starts.append(near_unit)
            starts.append(np.full(p + q, 0.1))
        best_u, best_cost = None, np.inf
        for u0 in starts:
            sol = least_squares(resid, u0, jac=jac, method=LSQ_METHOD, x_scale="jac", ftol=1e-7, xtol=1e-7, gtol=1e-7,
                                max_nfev=50 * (p + q + 1))
            if sol.cost < best_cost:
                best_u, best_cost = sol.x, sol.cost
    phi = _from_unconstrained(best_u[:p])
    theta = _from_unconstrained(best_u[p:])
    a = arma_residuals(x, phi, theta)[p:]
    rss = float(a @ a)
    m = len(a)
    sigma2 = rss / m
    spread2 = float(x @ x) / n
    if not sigma2 > EXACT_FIT_RATIO * spread2:
        raise SettingsError(f"ARMA({p}, {q}) predicts the series exactly (residual variance {sigma2:.2g}, "
                            f"{sigma2 / spread2:.1g} of the series'): the data are deterministic, with no noise "
                            "for an ARMA model")
    aic = math.log(sigma2) + 2.0 * (p + q) / m
    return ArmaFit(p, q, [float(v) for v in phi], [float(v) for v in theta], math.sqrt(sigma2), rss, m, aic,
                   a if keep_residuals else None)


def simulate_arma(phi, theta, sigma_a, n, *, rng=None, seed=None, burn_in=None):
    """n samples of x_t - sum phi x_{t-i} = a_t - sum theta a_{t-j}, a ~ N(0, sigma_a^2).

    ``burn_in`` samples (default 10 / (1 - max |root|), at most 200 000) are dropped so the
    series starts stationary. Randomness from ``rng`` (a numpy Generator) or ``seed``.
    """
    from scipy.signal import lfilter

    if rng is None:
        rng = np.random.default_rng(seed)
    phi = np.asarray(phi, float)
    theta = np.asarray(theta, float)
    if burn_in is None:
        if phi.size:
            roots = np.abs(np.roots(np.r_[1.0, -phi]))
            slowest = float(roots.max()) if roots.size else 0.0
            burn_in = int(min(200_000, 10 / max(1e-6, 1 - slowest))) if slowest < 1 else 0
        else:
            burn_in = 0
    a = rng.normal(0.0, sigma_a, n + burn_in)
    return lfilter(np.r_[1.0, -theta], np.r_[1.0, -phi], a)[burn_in:]
