"""Robust Haar wavelet variance: an M-estimate of scale of the wavelet coefficients per scale, so
that a composite fit (:mod:`gyrofilter.analysis.noise.gmwm`) is not pulled by spikes or heavy tails.

The Haar MODWT coefficient at scale m (τ = m / f_s) is ``W_t = (X_{t+2m} - 2 X_{t+m} + X_t) / (2m)``
with X the cumulative sum of the rate: half the difference of two adjacent m-sample means, so
that ``E W² = ν²(τ) = σ²_A(τ) / 2`` (Percival & Walden 2000, sec. 8.6). The classical estimate is the
mean of W²; one spike of size s enters every coefficient whose 2m-sample window holds it, so a few
spikes move it at every scale.

**M-estimate of scale** (Guerrier, Molinari & Victoria-Feser 2014, "Robust inference for time
series models: a wavelet-based framework", and the robust GMWM of Guerrier et al. 2020): per
scale, ``s`` solves ``mean ρ(W_t / s) = b`` with Tukey's biweight ρ(t) = 1 - (1 - (t/c)²)³ for
|t| <= c, else 1 (bounded, so one coefficient moves the mean of ρ by at most 1/M), and
``b = E ρ(Z)`` for Z standard normal (Fisher-consistent at a Gaussian: s² = ν² there). It is solved
by the fixed point ``s²_{k+1} = s²_k mean ρ(W / s_k) / b`` from the MAD (Maronna, Martin & Yohai
2006, sec. 2.7.2). The constant c sets the estimator's Gaussian efficiency,
``eff = (1/2) / (Var ρ(Z) / E[Z ρ'(Z)]²)`` (the classical estimate's asymptotic variance of log s
over the M-estimate's; Maronna, Martin & Yohai 2006, ch. 2): :data:`ROBUST_EFFICIENCY` = 0.9
gives c = 3.21 and a breakdown point b = 0.22 (0.6, the default of the authors' R packages gmwm
and wv, gives c = 1.73 and b = 0.46). **Efficiency correction**: the estimate is less precise
than the classical one by 1/eff at a Gaussian, so its equivalent degrees of freedom are
``eff η_j`` (the composite fit's weights).

**Heavy tails** (``tails = (fraction, scale_ratio)``, the ``heavy_tails`` effect): a heavy-tailed
white noise is not a contamination but the model, whose ν² is its variance over 2m. The
coefficient at scale m sums 2m samples, K ~ Binomial(2m, p) of them wide, so given K it is
Gaussian with relative variance ``r_K = (2m - K + K c²) k₀² / (2m)`` (E r_K = 1); the M-estimate of
such a scale mixture is below its variance (by 30 % at m = 16, p = 0.05, c = 20; under 2 % from
m = 256). The estimate is divided by the M-scale the mixture itself gives, s²_m solving
``Σ_K P(K) g(sqrt(r_K) / s_m) = b`` with ``g(t) = E ρ(tZ)`` (a polynomial times the normal
density, by quadrature), so it is Fisher-consistent at the heavy-tailed white noise. Where other (Gaussian)
terms dominate a scale the correction is slightly too large; it tends to 1 at long scales.

**Limit.** Spikes at a rate p touch a fraction of about 2 m p of the coefficients at scale m;
beyond the breakdown point (2 m p > b) no estimate of scale can tell them from the noise: there
they act as white noise of variance p s² (``docs/gap.md``, robust composite fit, measures it).
"""
from __future__ import annotations

import functools
import math

import numpy as np

#: Gaussian efficiency of the robust wavelet variance: 0.9 (c = 3.21, breakdown point 0.22), not
#: the 0.6 of Guerrier et al.'s R packages: in the gap the outlier detector has removed the spikes
#: it finds, and the composite fit on the robust estimate kept the true model as often as on the
#: classical one at 0.9 but lost its random walk at 0.6 (tools/robust_gmwm.py, docs/gap.md)
ROBUST_EFFICIENCY = 0.9
#: at most this many coefficients per scale enter the M-estimate (evenly strided; neighbouring
#: coefficients overlap in all but a few of their 2m samples)
MAX_COEFFICIENTS = 200_000

_LEG_X, _LEG_W = np.polynomial.legendre.leggauss(200)


def biweight_rho(t, c):
    """Tukey's biweight ρ(t) = 1 - (1 - (t/c)²)³ for |t| <= c, else 1."""
    a = np.minimum((np.asarray(t, dtype=float) / c) ** 2, 1.0)
    return 1.0 - (1.0 - a) ** 3


def _gauss_expect(func, c):
    """∫ func(z) φ(z) dz over |z| <= c (even ``func``), Gauss-Legendre with 200 nodes on [0, c]."""
    z = 0.5 * c * (_LEG_X + 1.0)
    return float(np.sum(c * _LEG_W * func(z) * np.exp(-0.5 * z * z))) / math.sqrt(2.0 * math.pi)


def _efficiency(c):
    """(b, Gaussian efficiency) of the biweight M-scale with constant c (module docstring)."""
    tail = math.erfc(c / math.sqrt(2.0))
    b = _gauss_expect(lambda z: biweight_rho(z, c), c) + tail
    var = _gauss_expect(lambda z: biweight_rho(z, c) ** 2, c) + tail - b * b
    slope = _gauss_expect(lambda z: 6.0 * z * z / c**2 * (1.0 - (z / c) ** 2) ** 2, c)  # E[Z ρ'(Z)]
    return b, 0.5 * slope**2 / var


def contamination_bias(fraction, efficiency=ROBUST_EFFICIENCY):
    """Relative bias of the M-estimate s² when a small ``fraction`` ε of the coefficients are far
    outliers (ρ = 1): ``2 ε (1 - b) / E[Z ρ'(Z)]`` (linearized; the M-scale's gross-error
    sensitivity, Hampel 1974). About 2.7 ε at efficiency 0.6, 4.8 ε at 0.9; the classical
    estimate's is unbounded (p s² / ν² of spikes of size s)."""
    c, b = biweight_constants(efficiency)
    slope = _gauss_expect(lambda z: 6.0 * z * z / c**2 * (1.0 - (z / c) ** 2) ** 2, c)
    return 2.0 * float(fraction) * (1.0 - b) / slope


@functools.lru_cache(maxsize=8)
def biweight_constants(efficiency=ROBUST_EFFICIENCY):
    """(c, b): the biweight constant of the given Gaussian efficiency (in (0.3, 0.999)) and its
    consistency constant b = E ρ_c(Z); bisection on c (the efficiency rises with c)."""
    lo, hi = 0.5, 30.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _efficiency(mid)[1] < efficiency else (lo, mid)
    c = 0.5 * (lo + hi)
    return c, _efficiency(c)[0]


def m_scale2(w, c, b, iterations=200, tol=1e-10):
    """The biweight M-estimate of scale, squared, of the zero-mean values ``w`` (module
    docstring): the fixed point s² ← s² mean ρ(w / s) / b from (1.4826 MAD)². Where the MAD is 0
    (most values exactly 0: a quiet sensor whose samples sit on one code) the iteration has no
    fixed point but 0 (every nonzero value looks like an outlier: 1e-232 after 200 steps, which
    broke the fits that divide by it); the mean square is returned there."""
    w = np.asarray(w, dtype=float)
    s2 = (1.4826 * float(np.median(np.abs(w)))) ** 2
    if not s2 > 0:
        return float(np.mean(w * w))
    sq = w * w
    for _ in range(iterations):
        new = s2 * float(np.mean(biweight_rho(np.sqrt(sq / s2), c))) / b
        done = abs(new / s2 - 1.0) < tol
        s2 = new
        if done:
            break
    return s2


def gauss_rho_mean(t, c):
    """g(t) = E ρ_c(t Z) for Z standard normal: P(|Z| >= L) + ∫_{|z|<L} ρ_c(tz) φ(z) dz with
    L = c/t (the integrand a polynomial times φ; 64-node Gauss-Legendre on [0, L]). ``t``: array."""
    from scipy.special import ndtr

    t = np.maximum(np.asarray(t, dtype=float), 1e-300)
    lim = c / t
    x, w = np.polynomial.legendre.leggauss(64)
    z = 0.5 * lim[:, None] * (x[None, :] + 1.0)
    inner = np.sum(w[None, :] * biweight_rho(t[:, None] * z, c) * np.exp(-0.5 * z * z), axis=1)
    return 2.0 * ndtr(-lim) + lim * inner / math.sqrt(2.0 * math.pi)


def heavy_tail_factor(m, fraction, scale_ratio, c, b):
    """s²_m: the M-scale (squared, relative to the variance) of the Haar coefficients at scale m
    of a heavy-tailed white noise (module docstring); the robust estimate is divided by it."""
    from scipy.optimize import brentq
    from scipy.stats import binom

    n, p, ratio = 2 * int(m), float(fraction), float(scale_ratio)
    if p <= 0.0 or ratio <= 1.0:
        return 1.0
    k0sq = 1.0 / (1.0 - p + p * ratio * ratio)
    mean, sd = n * p, math.sqrt(n * p * (1.0 - p))
    k = np.arange(max(0, int(mean - 12 * sd - 5)), min(n, int(mean + 12 * sd + 5)) + 1)
    prob = binom.pmf(k, n, p)
    rel = np.sqrt((n - k + k * ratio * ratio) * k0sq / n)
    excess = lambda log_s: float(np.sum(prob * gauss_rho_mean(rel / math.exp(log_s), c))) - b  # noqa: E731
    return math.exp(2.0 * brentq(excess, -8.0, 8.0, xtol=1e-10))


def integrated(x, pass_samples=1 << 16):
    """``X_t = sum_{k<t} (x_k - mean x)``, t = 0 .. N, the integral of the mean-removed series,
    summed a pass at a time (the only N-sample array is the result)."""
    x = np.asarray(x, dtype=float)
    mean = float(np.mean(x))
    cum = np.empty(x.size + 1)
    cum[0] = 0.0
    for lo in range(0, x.size, pass_samples):
        part = cum[lo + 1:lo + 1 + pass_samples]
        np.subtract(x[lo:lo + pass_samples], mean, out=part)
        np.cumsum(part, out=part)
        part += cum[lo]
    return cum


def haar_coefficients(x, m, max_count=MAX_COEFFICIENTS, cum=None):
    """Haar MODWT coefficients W_t = (X_{t+2m} - 2X_{t+m} + X_t) / (2m) of the mean-removed
    series at scale m, every ``max(1, m // 8, ceil(M / max_count))``-th of the M = N - 2m + 1.
    ``cum``: :func:`integrated` of ``x`` when the caller has it (several scales of one series)."""
    cum = integrated(x) if cum is None else cum
    count = cum.size - 2 * m
    stride = max(1, m // 8, int(math.ceil(count / max_count)))
    t = np.arange(0, count, stride)
    return (cum[t + 2 * m] - 2.0 * cum[t + m] + cum[t]) / (2.0 * m)


def robust_wv(x, m_list, *, efficiency=ROBUST_EFFICIENCY, tails=None):
    """Robust wavelet variance ν̂² at the scales ``m_list`` (samples): the biweight M-scale of
    each scale's coefficients, divided by :func:`heavy_tail_factor` when ``tails`` =
    (fraction, scale_ratio) is given. Returns an array ((deg/s)² for ``x`` in deg/s)."""
    c, b = biweight_constants(efficiency)
    out = np.empty(len(m_list))
    cum = integrated(x)
    for j, m in enumerate(m_list):
        out[j] = m_scale2(haar_coefficients(x, int(m), cum=cum), c, b)
        if tails is not None:
            out[j] /= heavy_tail_factor(int(m), tails[0], tails[1], c, b)
    return out
