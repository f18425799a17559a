"""Detector 1b, ``heavy_tails``: a white noise heavier-tailed than a Gaussian at every sample,
told apart from ``outliers`` (a few isolated spikes on a Gaussian floor); see
:mod:`gyrofilter.analysis.gap.detectors`.

**Residual.** The tails are those of the noise's innovations: ``e = x - moving_mean(x, W)``
(the colored-noise detector's high pass, which removes every slow effect; the mean taken over
the samples clipped to 4 robust sd, so that a wide sample does not leak into its neighbours)
prewhitened by the AR(2) fitted to its lag-1 and lag-2 autocorrelations (Yule-Walker),
``e_w[n] = e[n] - a1 e[n-1] - a2 e[n-2]``, in units of its robust standard deviation ``s``
(1.4826 MAD): ``u = e_w / s``. Any
Gaussian process (colored noise, narrow bands, random walks) stays Gaussian under these linear
filters, so ``u`` is standard normal in the tails whatever the spectrum, and its samples are
nearly independent.

**Tail statistic** (:func:`tails_statistic`, a feature of the gap analysis, so it is also
computed on every baseline simulation): the winsorized kurtosis ``K_w = mean(v^2) / mean(v)^2``,
``v = min(|u|, k)^2``, k = :data:`~gyrofilter.analysis.gap.detectors.common.TAILS_WINSOR_SD`, over its
value for a standard normal, as a log: 0 for a Gaussian whatever its scale, with sampling sd
about ``1.6 / sqrt(N)`` (:func:`tails_sd`); a single spike moves it by at most about
``k^4 / (3 N)``, so it measures the tails of the whole record, not its largest samples.

**Models of the tails** (:func:`tail_fits`), fitted by maximum likelihood to the histogram of
``|u|`` (bins of 0.25, or of the quantization step where that is coarser, to 4 (8 steps), then 40
log-spaced to the largest and one beyond it; exact bin probabilities, so the cost does not grow
with N):

* Gaussian: ``|u| ~ |N(0, sigma^2)|``;
* heavy tails, the simulator's ``heavy_tails`` (a Gaussian scale mixture; Tukey 1960):
  ``(1 - p) N(0, sigma^2) + p N(0, c^2 sigma^2)``;
* isolated spikes, the simulator's ``outliers``: ``(1 - p) N(0, sigma^2) + p (spike + N(0, sigma^2))``,
  ``|spike| = m exp(0.25 z)`` (log-normal about the median m, the spread of
  :data:`~gyrofilter.analysis.gap.detectors.outliers.OUTLIER_SPREAD_LN`; 16-point Gauss-Hermite).

**Rule** (:func:`detect_heavy_tails`). Heavy tails are named when

1. the tail statistic departs from the baseline's simulations by ``z >=``
   :data:`~gyrofilter.analysis.gap.detectors.common.HEAVY_TAILS_Z` (without simulations: from its
   sampling sd under a Gaussian), and
2. the scale mixture beats the Gaussian, ``2 Delta log L >=``
   :data:`~gyrofilter.analysis.gap.detectors.common.HEAVY_TAILS_THRESHOLD`, and
3. it explains the tails better than isolated spikes: ``2 (log L_mixture - log L_spikes) >= 0``
   (both have three parameters: the likelier model), and by at least
   :data:`~gyrofilter.analysis.gap.confound.HEAVY_TAILS_OVER_SPIKES` (very strong evidence,
   Kass & Raftery 1995) when the outlier detector has found spikes beyond its gross-error
   threshold: spikes far outside the noise are direct evidence of gross errors, replaced by a
   heavy-tailed noise only on strong evidence.

Without the baseline's simulations (``tails_z`` None) a rate quantized in steps above
:data:`~gyrofilter.analysis.gap.detectors.common.TAILS_MAX_STEP_SD` noise sd is not judged (the
quantizer alone moves the statistic; the simulations carry the same quantizer).

A heavy-tailed noise puts a continuous excess at every level of the distribution, from 2-3
standard deviations outward, with wide-component samples of every size; isolated gross errors
are a separate cluster of a few samples far outside a Gaussian floor, all of about one size.
Where fewer than a few hundred samples carry the tails the two cannot be told apart (both fit to
within the margin); the finding, or the outlier finding, then says that the other explains the
tails about as well. A gross-error process whose spike sizes spread over more than a factor of
about 2 is, by this rule, a heavy-tailed noise. The parameters are the mixture's ``fraction`` p
and ``scale_ratio`` c; the residual is not cleaned (the tails are noise, and its variance is the
model's white noise, N^2 f_s).
"""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np

from ....effects import HEAVY_TAILS
from .colored import colored_window
from ..confound import tails_or_spikes
from .common import Candidate, HEAVY_TAILS_THRESHOLD, HEAVY_TAILS_Z, TAILS_MAX_STEP_SD, TAILS_WINSOR_SD
from ...noise.screen import gross_and_beside
from ...stats import dot, moving_mean, robust_sigma
from .outliers import OUTLIER_SPREAD_LN, clean_spikes

_GH_Z, _GH_W = np.polynomial.hermite_e.hermegauss(16)
_GH_W = _GH_W / _GH_W.sum()


def _winsor_moments(k):
    """``E[v^j]``, j = 1..4, of ``v = min(|Z|, k)^2`` for Z standard normal, in closed form:
    ``E[Z^2n; |Z| < k] = (2n-1) E[Z^(2n-2); |Z| < k] - 2 k^(2n-1) phi(k)`` (integration by
    parts) from ``2 Phi(k) - 1``, plus ``k^2n P(|Z| > k)``."""
    nd = NormalDist()
    inner, dens, tail = 2.0 * nd.cdf(k) - 1.0, nd.pdf(k), 2.0 * nd.cdf(-k)
    out = []
    for n in range(1, 5):
        inner = (2 * n - 1) * inner - 2.0 * k ** (2 * n - 1) * dens
        out.append(inner + tail * k ** (2 * n))
    return tuple(out)


_WINSOR = _winsor_moments(TAILS_WINSOR_SD)


def tail_residual(x, sample_rate_hz, e=None):
    """``u``: the high-passed, AR(2)-prewhitened residual over its robust sd (module docstring);
    an empty array when the series is too short or constant. ``e``: ``x - moving_mean(x, W)``
    when the caller has it (it becomes ``u``'s storage). The prewhitening runs in place, a pass
    at a time from the end, so the residual costs one N-sample array. Where a sample could shift its
    W neighbours by more than :data:`LEAK_SD` noise sd through the moving mean, the screen's spikes
    and the two samples beside each (:func:`~gyrofilter.analysis.noise.screen.gross_and_beside`) are
    replaced by their neighbours in the mean and left out of ``u`` (a copy then): gross errors are
    isolated spikes, the outliers detector's, not the noise's tails (one spike of 150 deg/s was named
    ``heavy_tails``)."""
    if x.size < 64:
        return np.zeros(0)
    w = colored_window(x.size, sample_rate_hz)
    if e is None:
        e = moving_mean(x, w)
        np.subtract(x, e, out=e)
    # a spike of S sd shifts the W samples around it by S / W sd each through the moving mean (one of
    # 1900 sd at W = 64 made 100 samples of 30 sd: a "heavy tail" of 0.17 % of the record): where one
    # sample could shift its neighbours by more than LEAK_SD, the mean is taken of the series with the
    # screen's spikes (noise.screen.gross_and_beside) replaced by their neighbours (clean_spikes). Then
    # the moving mean of the samples clipped to +-4 robust sd: a wide sample would shift the W
    # samples around it by 1/W of itself and so widen the core (by 20 % at 8 % of 20 times the
    # sd); not needed where fewer than 1e-3 of the samples are beyond (a Gaussian: 6e-5)
    clip = 4.0 * robust_sigma(e, max_count=20_000)
    beyond = largest = 0
    for lo in range(0, e.size, _PASS):
        part = np.abs(e[lo:lo + _PASS])
        beyond, largest = beyond + int(np.count_nonzero(part > clip)), max(largest, float(part.max()))
    spikes = None
    if largest > LEAK_SD / 4.0 * clip * w:
        spikes = np.zeros(x.size, dtype=bool)
        spikes[gross_and_beside(x)] = True
        if spikes.any():
            np.subtract(x, moving_mean(clean_spikes(x, spikes), w), out=e)
        else:
            spikes = None
    if beyond > 1e-3 * e.size:
        level = x - e
        np.clip(e, -clip, clip, out=e)
        e += level
        level = moving_mean(e, w)
        np.subtract(x, level, out=e)
        del level
    if spikes is not None:  # the gross errors are the outliers detector's, not the noise's tails: left out
        e[spikes] = 0.0
    c0 = float(dot(e, e))
    if not c0 > 0:
        return np.zeros(0)
    r1, r2 = float(dot(e[1:], e[:-1])) / c0, float(dot(e[2:], e[:-2])) / c0
    den = 1.0 - r1 * r1
    a1, a2 = (r1 * (1.0 - r2) / den, (r2 - r1 * r1) / den) if den > 1e-9 else (0.0, 0.0)
    n = e.size
    for hi in range(n, 2, -_PASS):  # u_i = e_{i+2} - a1 e_{i+1} - a2 e_i, written over e_{i+2}
        lo = max(2, hi - _PASS)
        part = e[lo:hi] - a1 * e[lo - 1:hi - 1]
        part -= a2 * e[lo - 2:hi - 2]
        e[lo:hi] = part
    u = e[2:] if spikes is None else e[2:][~spikes[2:]]
    s = robust_sigma(u, max_count=20_000)
    if not s > 0:
        return np.zeros(0)
    u /= s
    return u


_PASS = 1 << 16
#: the shift (in noise sd) a sample's leak through the high pass's moving mean may put on each of
#: its W neighbours before the mean is taken of the clipped samples (:func:`tail_residual`)
LEAK_SD = 0.25


def _lattice_step(x, count=100_000):
    """The quantization step of ``x``: the smallest difference between distinct values of (a
    stretch of) the series; 0 when every value differs by less than 1e-12 of the range."""
    values = np.unique(x[:count])
    if values.size < 2:
        return 0.0
    steps = np.diff(values)
    steps = steps[steps > 1e-12 * max(float(values[-1] - values[0]), 1e-300)]
    return float(steps.min()) if steps.size else 0.0


def tail_step(x, sample_rate_hz):
    """The quantization step of ``x`` in units of its high-passed noise's robust sd (0 when the
    series is on no lattice): the narrowest histogram bin of :func:`tail_fits`."""
    resid = moving_mean(x, colored_window(x.size, sample_rate_hz))
    np.subtract(x, resid, out=resid)  # in place: one N-sample array, not two
    return _lattice_step(x) / robust_sigma(resid, max_count=20_000)


def tails_statistic(x, sample_rate_hz, u=None):
    """``log(K_w / K_Z)``: the winsorized kurtosis ``K_w = mean(v^2) / mean(v)^2`` of the residual,
    ``v = min(|u|, k)^2``, over its Gaussian value (module docstring); 0 when it cannot be
    computed. Self-normalized, so the robust scale only sets the winsorizing level. The sums
    run a pass at a time (no N-sample temporary)."""
    u = tail_residual(x, sample_rate_hz) if u is None else u
    if u.size == 0:
        return 0.0
    m1, m2, _, _ = _WINSOR
    sum_v = sum_v2 = 0.0
    for lo in range(0, u.size, _PASS):
        v = np.minimum(np.abs(u[lo:lo + _PASS]), TAILS_WINSOR_SD)
        v *= v
        sum_v += float(v.sum())
        sum_v2 += float(dot(v, v))
    mean_v = sum_v / u.size
    return math.log(max(sum_v2 / u.size / mean_v**2, 1e-12) / (m2 / m1**2))


def tails_sd(n):
    """Sampling sd of :func:`tails_statistic` for a Gaussian white noise of ``n`` samples, by the
    delta method on (mean v^2, mean v): ``Var = [Var v^2 / m2^2 + 4 Var v / m1^2 - 4 Cov(v^2, v) /
    (m1 m2)] / n`` with ``m_j = E v^j`` (:func:`_winsor_moments`)."""
    m1, m2, m3, m4 = _WINSOR
    var = (m4 - m2 * m2) / m2**2 + 4.0 * (m2 - m1 * m1) / m1**2 - 4.0 * (m3 - m2 * m1) / (m1 * m2)
    return math.sqrt(var / max(n, 1))


# ---------------------------------------------------------------------------------------------
# the three models of the tails, on the histogram of |u|


def _fold(edges, s):
    """P(edge_j <= |N(0, s^2)| < edge_j+1) per bin."""
    from scipy.special import ndtr

    c = ndtr(edges / s)
    return 2.0 * (c[1:] - c[:-1])


def _spikes(edges, m, s):
    """P(edge_j <= |spike + N(0, s^2)| < edge_j+1), |spike| = m exp(0.25 z) (Gauss-Hermite)."""
    from scipy.special import ndtr

    out = np.zeros(edges.size - 1)
    for z, w in zip(_GH_Z, _GH_W):
        size = m * math.exp(OUTLIER_SPREAD_LN * z)
        up, down = ndtr((edges - size) / s), ndtr((-edges - size) / s)
        out += w * ((up[1:] - up[:-1]) + (down[:-1] - down[1:]))
    return out


def _log_l(counts, probs):
    return float(np.sum(counts * np.log(np.maximum(probs, 1e-300))))


def _best(objective, starts):
    """The Nelder-Mead minimum of ``objective`` over the starting points ``starts``."""
    from scipy.optimize import minimize

    best = None
    for x0 in starts:
        res = minimize(objective, np.asarray(x0, dtype=float), method="Nelder-Mead",
                       options={"xatol": 1e-5, "fatol": 1e-4, "maxiter": 3000})
        if best is None or res.fun < best.fun:
            best = res
    return best


def tail_fits(u, step=0.0, models=("gauss", "mixture", "spikes")):
    """Maximum-likelihood fits of the three models (module docstring) to the histogram of
    ``|u|``, in bins no narrower than the quantization ``step`` (units of ``u``). Returns a dict:
    ``log_l`` per model (``gauss``, ``mixture``, ``spikes``), the mixture's ``fraction``,
    ``scale_ratio`` and core ``sigma`` (units of the robust sd), the spikes' ``rate`` and
    ``magnitude`` (same units); only of the ``models`` asked for (the intervals' bootstrap
    re-fits the mixture alone)."""
    from scipy.optimize import minimize_scalar

    width = max(0.25, float(step))
    linear = max(4.0, 8.0 * width)
    top = max(1.125 * linear, max(float(u.max()), -float(u.min())) * 1.001)  # max |u|
    edges = np.r_[np.arange(0.0, linear - 1e-9, width), np.geomspace(linear, top, 40), np.inf]  # the last bin is
    # empty, so the models' probabilities sum to 1 over the bins (no mass beyond the largest sample is lost)
    counts = sum(np.histogram(np.abs(u[lo:lo + _PASS]), edges)[0] for lo in range(0, u.size, _PASS))  # |u| a pass at a time

    def params(t):  # (sigma, share in (0, 1/2), ratio or magnitude), each bounded: the search may wander;
        # the ratio's cap is applied after exp (exp(log 999) is 999.0000000000003: a scale ratio above the model's 1000)
        t = np.clip(t, -50.0, 50.0)
        return math.exp(min(max(t[0], -5.0), 5.0)), 0.5 / (1.0 + math.exp(-t[1])), min(math.exp(t[2]), 999.0)

    def mixture(t):
        s, p, c = params(t)
        return -_log_l(counts, (1 - p) * _fold(edges, s) + p * _fold(edges, (1.0 + c) * s))

    def spikes(t):
        s, p, m = params(t)
        return -_log_l(counts, (1 - p) * _fold(edges, s) + p * _spikes(edges, m, s))

    logit = lambda p: math.log(p / (0.5 - p))  # noqa: E731
    out = {"log_l": {}}
    if "gauss" in models:
        gauss = minimize_scalar(lambda t: -_log_l(counts, _fold(edges, math.exp(t))), bounds=(-2.0, 2.0), method="bounded")
        out["log_l"]["gauss"] = -float(gauss.fun)
    if "mixture" in models:
        mix = _best(mixture, [(0.0, logit(p), math.log(c - 1)) for p in (0.005, 0.1) for c in (2.0, 20.0)])
        sigma, fraction, ratio = params(mix.x)
        out["log_l"]["mixture"] = -float(mix.fun)
        out.update(sigma=sigma, fraction=fraction, scale_ratio=1.0 + ratio)
    if "spikes" in models:
        spk = _best(spikes, [(0.0, logit(p), math.log(m)) for p in (0.001, 0.03) for m in (3.0, 10.0, 30.0)])
        _, rate, magnitude = params(spk.x)
        out["log_l"]["spikes"] = -float(spk.fun)
        out.update(rate=rate, magnitude=magnitude)
    return out


def detect_heavy_tails(x, sample_rate_hz, *, spikes_found=False, tails_z=None):
    """Heavy-tail candidate by the rule of the module docstring, and a note (or None) when
    isolated spikes and a heavy-tailed noise explain the tails about as well.

    ``spikes_found``: the outlier detector found spikes beyond its gross-error threshold;
    ``tails_z``: the departure of :func:`tails_statistic` from the baseline's simulations (None:
    judged against its sampling sd under a Gaussian). Returns ``(Candidate or None, note or None)``."""
    u = tail_residual(x, sample_rate_hz)
    if u.size < 256:
        return None, None
    stat = tails_statistic(x, sample_rate_hz, u)
    z = stat / tails_sd(u.size) if tails_z is None else float(tails_z)
    if z < HEAVY_TAILS_Z:
        return None, None
    del u  # made again below: with tail_step's moving mean it would be two N-sample arrays at once
    step = tail_step(x, sample_rate_hz)
    if tails_z is None and step > TAILS_MAX_STEP_SD:  # the baseline's simulations would carry the quantizer too
        return None, (f"the noise's distribution departs from a Gaussian (winsorized kurtosis z = {z:+.1f}) "
                      f"but the rate is quantized in steps of more than {TAILS_MAX_STEP_SD:g} noise sd: "
                      "its tails cannot be told from the quantizer's without simulations of it")
    u = tail_residual(x, sample_rate_hz)
    fits = tail_fits(u, step)
    ll = fits["log_l"]
    lr = 2.0 * (ll["mixture"] - ll["gauss"])
    over = 2.0 * (ll["mixture"] - ll["spikes"])
    if lr < HEAVY_TAILS_THRESHOLD:
        return None, None
    gauss_kw = _WINSOR[1] / _WINSOR[0] ** 2
    heavier = (f"the noise's tails are heavier than a Gaussian's (winsorized kurtosis {math.exp(stat) * gauss_kw:.3g}, "
               f"a Gaussian's {gauss_kw:.3g}; z = {z:+.1f})")
    named, note, evidence_end = tails_or_spikes(over, spikes_found, fits, heavier)
    if not named:
        return None, note
    beyond6 = float(np.mean(np.abs(u) > 6.0))
    kurt = float(np.mean(u**4) / np.mean(u**2) ** 2)
    evidence = (f"the noise is heavier-tailed than a Gaussian at every level: winsorized kurtosis "
                f"{math.exp(stat) * gauss_kw:.3g} (a Gaussian's {gauss_kw:.3g}; z = {z:+.1f}), kurtosis {kurt:.3g}, "
                f"{100 * beyond6:.2g} % of the samples beyond 6 robust sd (a Gaussian: 2e-7 %); a Gaussian scale mixture (fraction {fits['fraction']:.3g} of the samples with "
                f"{fits['scale_ratio']:.3g} times the others' sd) beats a Gaussian by 2 Delta log L = {lr:.0f} "
                f"(threshold {HEAVY_TAILS_THRESHOLD:g}) and isolated spikes by {over:+.1f}")
    evidence += evidence_end
    cand = Candidate(effect=HEAVY_TAILS, params={"fraction": fits["fraction"], "scale_ratio": fits["scale_ratio"]},
                     statistic=lr, threshold=HEAVY_TAILS_THRESHOLD, evidence=evidence,
                     statistic_name="2 Delta log L, Gaussian scale mixture over a Gaussian (residual's histogram)")
    return cand, None
