"""GMWM-style composite noise fit: a sum of Gauss-Markov processes, white noise, quantisation,
rate random walk and drift fitted to the Haar wavelet variance of a rate series.

Wavelet variance. The Haar MODWT wavelet variance at scale τ is half the overlapping Allan
variance at averaging time τ: ν²(τ) = σ²_A(τ) / 2 (Percival & Guttorp 1994, "Long-memory
processes, the Allan variance and wavelets", eq. 9; Percival & Walden 2000, "Wavelet Methods
for Time Series Analysis", sec. 8.6). It is estimated at the dyadic scales τ_j = 2^j / f_s
(j = 0, 1, ...) from the overlapping Allan variance (:func:`gyrofilter.analysis.noise.allan.overlapping_adev`,
the same M_j = N - 2^{j+1} + 1 differences as the unbiased MODWT estimator), and its
uncertainty from the equivalent degrees of freedom η_j = max(M_j / 2^{j+1}, 1)
(Percival & Walden 2000, eq. 313c, "η₃"; the choice of R's gmwm/wv for its intervals):
Var(ν̂²_j) ≈ 2 ν⁴_j / η_j.

Theoretical wavelet variances of the terms (m = τ f_s samples; AVAR/2 of each):

* white rate noise N (deg/s/√Hz):             ν² = N² / (2τ)
* quantisation Q (deg):                        ν² = 3 Q² / (2τ²)         (IEEE Std 952-1997 C.2)
* rate random walk K (deg/s/√s), discrete:     ν² = K² (2m² + 1) / (12 m f_s)  (Guerrier et al.
  2013, table 1: γ² (τ_j² + 2) / (12 τ_j) with τ_j = 2m samples and γ = K/√f_s)
* drift (rate ramp) R (deg/s²):                ν² = R² τ² / 4
* flicker (bias instability) B (deg/s):        the simulator's bank of Gauss-Markov terms
  (:func:`gyrofilter.sim.flicker.flicker_bank`, T_min = 1/f_s, T_max = the record's length),
  the sum of their exact ν² (the simulator draws the slow ones at knots: within 1 %); flat at B² ln 2 / π (AVAR/2 of IEEE Std 952-1997 C.3) over the bank
* Gauss-Markov, stationary std σ, correlation time T, exact for the sampled AR(1)
  φ = exp(-1/(f_s T)): half of :func:`gyrofilter.sim.noise_terms.ar1_allan_variance`
  (equivalent to Guerrier et al. 2013, table 1, and Zhang 2008).

Fit (Guerrier, Skaloud, Stebler & Victoria-Feser 2013, "Wavelet-variance-based estimation for
composite stochastic processes", JASA 108: 1021-1030): θ̂ = argmin Σ_j (ν̂²_j - ν²_j(θ))² / Var(ν̂²_j),
a diagonal weight matrix (the GMWM with the inverse of the estimated variances, scales treated as
independent), every parameter log-transformed (positive), by ``scipy.optimize.least_squares``
from several starting points.

Model selection: every combination of the optional terms (quantisation, random walk, drift)
with k = 0..3 Gauss-Markov terms (white noise always in) is fitted (the flicker term is
not among the default optional terms, as in R's gmwm; the gap analysis's composite asks for it), and the model with the
smallest **WVIC** is chosen (Guerrier, Stebler, Skaloud & Victoria-Feser 2016, "Wavelet-based
improvements for inertial sensor error modeling", IEEE TIM 65(4); the ``rank.models`` of their R
package gmwm): C = Q(θ̂) + 2 tr(Ω Cov(ν(θ̂), ν̂)), an estimate of the expected objective of the
fitted model on an independent replicate ν̂* of the wavelet variance (Q alone falls with every
term; the second term, the optimism, is what the fit gained by fitting ν̂'s own noise; Efron
1986). Linearized, ν(θ̂) - ν ≈ A (AᵀΩA)⁻¹ AᵀΩ (ν̂ - ν) with A = ∂ν/∂θ, so in the standardized
units of the weights (Ω = diag 1/Var ν̂², A_w = Ω^½ A) the optimism is 2 tr(P V_w), P the
projection onto the columns of A_w and V_w the correlation-scale covariance Ω^½ Cov(ν̂) Ω^½ of
the estimator, estimated once by a parametric bootstrap of the largest model
(:data:`BOOTSTRAP_RUNS` runs, :func:`bootstrap_cov`), as gmwm does. Were the scales independent
with Var ν̂² exactly as weighted (V_w = I), the optimism would be 2 p and C = Q + 2 p, the AIC-like
criterion used before (``criterion="q2p"``, kept for comparison); the overlapping scales are
correlated, a robust estimate is less precise than its η says and a heavy-tailed noise makes the
short scales noisier, which the bootstrap sees and a fixed penalty does not. ``tools/gmwm_select.py``
measures both on simulated composite processes (docs/gap.md).
"""
from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from ...effects import BIAS_INSTABILITY, GAUSS_MARKOV, RATE_RAMP, RATE_RANDOM_WALK
from .allan import AllanInputError, ConstantAxisError, constant_words, overlapping_adev, rate_numbers
from .model import QUANTIZATION
from .wv_robust import ROBUST_EFFICIENCY, robust_wv
from ...sim.model import validate_model
from ...sim.flicker import BiasInstability, flicker_bank
from ...sim.noise_terms import ScaleMixtureNormal, ar1_allan_variance
from ...sim.simulate import simulate_axis_dps

OPTIONAL_TERMS = (QUANTIZATION, RATE_RANDOM_WALK, RATE_RAMP)
#: every term a fit can hold beside white noise and Gauss-Markov terms, in parameter order (the
#: names of the Allan terms, :mod:`gyrofilter.analysis.noise.model`)
TERMS = OPTIONAL_TERMS + (BIAS_INSTABILITY,)
_FIELD = {QUANTIZATION: "quantization_deg", RATE_RANDOM_WALK: "rrw_dps_per_sqrt_s", RATE_RAMP: "rate_ramp_dps_per_s",
          BIAS_INSTABILITY: "bias_instability_dps"}
MAX_GM = 3


#: parametric-bootstrap runs of the largest model for the WVIC's estimator covariance
BOOTSTRAP_RUNS = 30
#: criteria closer than this to the lowest count as a tie, won by the model with fewer parameters
#: (the one-standard-error rule of Breiman et al. 1984): the optimism is a bootstrap estimate
#: (BOOTSTRAP_RUNS runs give the covariance's elements to about +-26 %, so an extra term's 2 V_kk,
#: about 1-2, to about +-0.4)
TIE = 0.5


@dataclass
class WaveletVariance:
    """Haar wavelet variance at dyadic scales: ``tau_s``, ``wv_dps2`` (ν², (deg/s)²), ``edf`` (η;
    of a robust estimate, η times its Gaussian efficiency), ``robust`` (the Gaussian efficiency
    of the M-estimate, :mod:`gyrofilter.analysis.noise.wv_robust`; 0 for the classical estimate),
    ``constant_dps`` (the one value of a constant series, whose ν² is 0 at every scale; else None:
    :func:`fit_model` refuses it in the Allan fit's words)."""

    sample_rate_hz: float
    n_samples: int
    tau_s: np.ndarray
    wv_dps2: np.ndarray
    edf: np.ndarray
    robust: float = 0.0
    tails: tuple = None  # (fraction, scale_ratio) of a heavy-tailed white noise (the robust estimate is consistent at it)
    constant_dps: float = None

    @property
    def m(self):
        return np.round(self.tau_s * self.sample_rate_hz).astype(np.int64)

    @property
    def sd_dps2(self):
        """Standard error of ν̂²: ν̂² sqrt(2 / η) (chi-square with η degrees of freedom)."""
        return self.wv_dps2 * np.sqrt(2.0 / self.edf)


def haar_wv(x_dps, sample_rate_hz, *, min_edf=2.0, min_m=1, robust=False, tails=None):
    """Haar wavelet variance ν̂²(τ_j) = σ̂²_A(τ_j) / 2 at τ_j = 2^j / f_s, with η_j (module docstring).

    Scales start at the first 2^j >= ``min_m`` samples and stop where η_j = (N - 2m + 1) / (2m)
    falls below ``min_edf``. ``robust``: the biweight M-estimate of each scale's coefficients
    instead (:func:`gyrofilter.analysis.noise.wv_robust.robust_wv`; η_j times its Gaussian efficiency,
    :data:`~gyrofilter.analysis.noise.wv_robust.ROBUST_EFFICIENCY` for True, else the number given),
    Fisher-consistent at the heavy-tailed white noise ``tails`` = (fraction, scale_ratio) when given;
    ``tails`` also makes the WVIC's bootstrap (:func:`bootstrap_cov`) simulate that noise.
    A constant series (no model fits a wavelet variance of 0) is marked (``constant_dps``).
    """
    x_dps = rate_numbers(x_dps, "x_dps")
    n = int(x_dps.size)
    m = []
    j = max(0, int(math.ceil(math.log2(max(min_m, 1)))))
    while (n - 2 * 2**j + 1) / (2.0 * 2**j) >= min_edf:
        m.append(2**j)
        j += 1
    if len(m) < 2:
        second = 2 ** (max(0, int(math.ceil(math.log2(max(min_m, 1))))) + 1)  # the second scale, samples
        raise AllanInputError(f"x_dps has {n} samples; a wavelet-variance fit needs at least "
                              f"{math.ceil(min_edf * 2 * second + 2 * second - 1)} (two scales of {min_edf:g} "
                              "equivalent degrees of freedom)")
    constant = float(x_dps.flat[0]) if np.all(np.isfinite(x_dps)) and np.ptp(x_dps) == 0 else None
    m = np.array(m, dtype=np.int64)
    efficiency = ROBUST_EFFICIENCY if robust is True else float(robust)
    edf = np.maximum((n - 2 * m + 1) / (2.0 * m), 1.0) * (efficiency or 1.0)
    values = _wv_values(x_dps, sample_rate_hz, m, efficiency, tails)
    return WaveletVariance(float(sample_rate_hz), n, m / float(sample_rate_hz), values, edf, robust=efficiency,
                           constant_dps=constant, tails=tails)


def _wv_values(x_dps, sample_rate_hz, m, efficiency=0.0, tails=None):
    """ν̂² at the scales ``m`` (samples): AVAR / 2, or the robust estimate of that Gaussian
    efficiency (when not 0)."""
    if efficiency:
        return robust_wv(x_dps, m, efficiency=efficiency, tails=tails)
    return overlapping_adev(x_dps, sample_rate_hz, np.asarray(m) / sample_rate_hz)[1] ** 2 / 2.0


def wv_white(tau_s, arw_dps_per_sqrt_hz):
    """ν² of white rate noise: N² / (2τ)."""
    return arw_dps_per_sqrt_hz**2 / (2.0 * np.asarray(tau_s))


def wv_quantization(tau_s, q_deg):
    """ν² of quantisation noise: 3 Q² / (2τ²)."""
    return 3.0 * q_deg**2 / (2.0 * np.asarray(tau_s) ** 2)


def wv_rrw(tau_s, k_dps_per_sqrt_s, sample_rate_hz):
    """ν² of a sampled rate random walk: K² (2m² + 1) / (12 m f_s), m = τ f_s."""
    m = np.asarray(tau_s) * sample_rate_hz
    return k_dps_per_sqrt_s**2 * (2.0 * m**2 + 1.0) / (12.0 * m * sample_rate_hz)


def wv_ramp(tau_s, r_dps_per_s2):
    """ν² of a drift R t: R² τ² / 4."""
    return r_dps_per_s2**2 * np.asarray(tau_s) ** 2 / 4.0


def wv_flicker(tau_s, b_dps, sample_rate_hz, duration_s):
    """ν² of the simulator's bias instability B over a record of ``duration_s``: the sum of the
    exact ν² of its full-rate flicker bank (:func:`gyrofilter.sim.flicker.flicker_bank`, T_min = 1/f_s,
    T_max = ``duration_s``, 2 per decade), flat at B² ln 2 / π between ~3/f_s and T_max / 9."""
    tau_s = np.asarray(tau_s, dtype=float)
    return b_dps**2 * _flicker_unit(tuple(tau_s.ravel()), float(sample_rate_hz), float(duration_s)).reshape(tau_s.shape)


@functools.lru_cache(maxsize=64)
def _flicker_unit(tau_s, sample_rate_hz, duration_s):
    """:func:`wv_flicker` for B = 1 at the scales ``tau_s`` (a tuple): the fit evaluates it at
    every step, and it is B² times this."""
    taus_s, q_dps = flicker_bank(1.0, sample_rate_hz, 1.0 / sample_rate_hz, max(duration_s, 1.0 / sample_rate_hz))
    return sum(wv_gauss_markov(np.array(tau_s), q_dps, t, sample_rate_hz) for t in taus_s)


def wv_gauss_markov(tau_s, sigma_dps, corr_time_s, sample_rate_hz):
    """ν² of a sampled Gauss-Markov process (AR(1), φ = exp(-1/(f_s T))): exact, AVAR/2."""
    phi = math.exp(-1.0 / (sample_rate_hz * corr_time_s))
    return 0.5 * ar1_allan_variance(phi, sigma_dps**2, np.asarray(tau_s) * sample_rate_hz)


@dataclass
class GmwmFit:
    """One fitted composite model. Parameters in physical units; absent terms are None / []."""

    sample_rate_hz: float
    arw_dps_per_sqrt_hz: float
    quantization_deg: float = None
    rrw_dps_per_sqrt_s: float = None
    rate_ramp_dps_per_s: float = None
    bias_instability_dps: float = None
    duration_s: float = None  # the record's length: the flicker bank's longest correlation time
    gauss_markov: list = field(default_factory=list)  # [(sigma_dps, tau_s)], by increasing tau_s
    objective: float = float("nan")  # Q(θ̂) = Σ (ν̂² - ν²(θ̂))² / Var(ν̂²)
    n_params: int = 0
    optimism: float = float("nan")  # WVIC's 2 tr(P V_w) (2 p with criterion "q2p")
    criterion: float = float("nan")  # Q + optimism
    jacobian_w: np.ndarray = None  # ∂ν/∂θ at θ̂ in units of the weights (A_w = Ω^½ A), J x p

    @property
    def name(self):
        parts = ["WN"]
        parts += [label for label, v in (("QN", self.quantization_deg), ("RW", self.rrw_dps_per_sqrt_s),
                                         ("DR", self.rate_ramp_dps_per_s), ("FL", self.bias_instability_dps)) if v is not None]
        parts += [f"{len(self.gauss_markov)}GM"] if self.gauss_markov else []
        return "+".join(parts)

    def wv(self, tau_s, gm_memo=None):
        """The model's wavelet variance ν²(τ) ((deg/s)²): the sum of its terms' closed forms.
        ``gm_memo``: a dict of the Gauss-Markov terms' ν² at these same scales ``tau_s``, by
        ``(sigma_dps, tau_s)``, filled as it goes (a fit evaluates the model at the same scales
        thousands of times, and its numerical Jacobian moves one parameter at a time: the other
        terms' values are the ones computed before, bit for bit)."""
        sample_rate_hz = self.sample_rate_hz
        out = wv_white(tau_s, self.arw_dps_per_sqrt_hz)
        if self.quantization_deg is not None:
            out = out + wv_quantization(tau_s, self.quantization_deg)
        if self.rrw_dps_per_sqrt_s is not None:
            out = out + wv_rrw(tau_s, self.rrw_dps_per_sqrt_s, sample_rate_hz)
        if self.rate_ramp_dps_per_s is not None:
            out = out + wv_ramp(tau_s, self.rate_ramp_dps_per_s)
        if self.bias_instability_dps is not None:
            out = out + wv_flicker(tau_s, self.bias_instability_dps, sample_rate_hz, self.duration_s)
        for sigma_dps, tau_gm_s in self.gauss_markov:
            if gm_memo is None:
                term = wv_gauss_markov(tau_s, sigma_dps, tau_gm_s, sample_rate_hz)
            else:
                term = gm_memo.get((sigma_dps, tau_gm_s))
                if term is None:
                    term = gm_memo[(sigma_dps, tau_gm_s)] = wv_gauss_markov(tau_s, sigma_dps, tau_gm_s, sample_rate_hz)
            out = out + term
        return out

    def to_dict(self):
        return {"model": self.name, "arw_dps_per_sqrt_hz": self.arw_dps_per_sqrt_hz,
                "quantization_deg": self.quantization_deg, "rrw_dps_per_sqrt_s": self.rrw_dps_per_sqrt_s,
                "rate_ramp_dps_per_s": self.rate_ramp_dps_per_s, "bias_instability_dps": self.bias_instability_dps,
                GAUSS_MARKOV: [{"sigma_dps": s, "tau_s": t} for s, t in self.gauss_markov],
                "objective": self.objective, "n_params": self.n_params, "optimism": self.optimism,
                "criterion": self.criterion}


def wv_distance(wv: WaveletVariance, model_wv_dps2):
    """Weighted distance per scale between a measured and a model wavelet variance:
    (1/J) Σ_j (ν̂²_j - ν²_j)² / Var(ν̂²_j), Var(ν̂²_j) = 2 ν̂⁴_j / η_j. About 1 when the model is
    within the sampling error at every scale; the same number for AVAR (the factor 2 cancels)."""
    r = (wv.wv_dps2 - np.asarray(model_wv_dps2)) / wv.sd_dps2
    return float(np.mean(r**2))


def _unpack(theta, terms, k_gm, sample_rate_hz, duration_s):
    """Log-parameters -> GmwmFit fields (variances and correlation times are exp of theta)."""
    values = iter(np.exp(theta))
    out = {"arw_dps_per_sqrt_hz": math.sqrt(next(values))}
    for term in TERMS:
        if term in terms:
            out[_FIELD[term]] = math.sqrt(next(values))
    gm = [(math.sqrt(next(values)), float(next(values))) for _ in range(k_gm)]
    out[GAUSS_MARKOV] = sorted(gm, key=lambda p: p[1])
    return GmwmFit(sample_rate_hz=sample_rate_hz, duration_s=duration_s, **out)


def _starts(wv: WaveletVariance, terms, k_gm, rng, count):
    """Starting log-parameters: white from the first scale, random walk and drift from the last,
    quantisation small, flicker at half the lowest level, Gauss-Markov times spread over the scales; then ``count - 1`` jittered copies."""
    tau, nu = wv.tau_s, wv.wv_dps2
    base = [math.log(2.0 * nu[0] * tau[0])]
    scale = {QUANTIZATION: 0.1 * 2.0 * nu[0] * tau[0] ** 2 / 3.0, RATE_RANDOM_WALK: 0.3 * 12.0 * nu[-1] / (2.0 * tau[-1]),
             RATE_RAMP: 0.1 * 4.0 * nu[-1] / tau[-1] ** 2, BIAS_INSTABILITY: 0.5 * float(np.min(nu)) * math.pi / math.log(2.0)}
    base += [math.log(scale[t]) for t in TERMS if t in terms]
    gm_taus = np.geomspace(tau[0] * 4.0, tau[-1] / 4.0, k_gm + 2)[1:-1] if k_gm else []
    for t in gm_taus:
        j = int(np.argmin(np.abs(np.log(tau / t))))
        base += [math.log(max(nu[j], 1e-300)), math.log(t)]
    base = np.array(base)
    return [base] + [base + rng.normal(0.0, 1.0, base.size) for _ in range(count - 1)]


def unfittable(wv: WaveletVariance):
    """Why no model can be fitted to ``wv``, or None: a scale whose wavelet variance is 0 (the
    series' averages over it all equal: a square wave at the Nyquist frequency, x[n] = +-a
    alternately, at every scale of an even number of samples). Every term's variance is positive
    at every scale, so none reaches 0, and the fit's starts (the white level from the first
    scale, the flicker's from the lowest, on log-parameters) would take the log of 0."""
    zero = np.flatnonzero(~(np.asarray(wv.wv_dps2) > 0.0))
    if zero.size == 0:
        return None
    return (f"the wavelet variance is 0 at tau = {wv.tau_s[zero[0]]:.3g} s: the series' averages over that scale are "
            "all equal (a square wave at the Nyquist frequency has them so), which no noise model gives")


def fit_model(wv: WaveletVariance, terms=(), k_gm=0, *, starts=4, seed=0):
    """GMWM fit of white noise + ``terms`` (subset of :data:`TERMS`) + ``k_gm``
    Gauss-Markov terms to ``wv``: weighted least squares on log-parameters (module docstring).
    A wavelet variance no model fits (:func:`unfittable`) raises ValueError saying why, a constant
    series's ConstantAxisError in the Allan fit's words (:func:`~gyrofilter.analysis.noise.allan.refuse_constant`)."""
    from scipy.optimize import least_squares

    if wv.constant_dps is not None:
        raise ConstantAxisError(constant_words("x_dps", wv.n_samples, wv.constant_dps), None)
    why = unfittable(wv)
    if why is not None:
        raise ValueError(why)

    sample_rate_hz, duration_s = wv.sample_rate_hz, wv.n_samples / wv.sample_rate_hz
    rng = np.random.default_rng(seed)
    lo_t, hi_t = math.log(0.5 / sample_rate_hz), math.log(wv.tau_s[-1] * 100.0)

    gm_memo = {}  # the Gauss-Markov terms' ν² at wv's scales (GmwmFit.wv)

    def residuals(theta):
        return (wv.wv_dps2 - _unpack(theta, terms, k_gm, sample_rate_hz, duration_s).wv(wv.tau_s, gm_memo)) / wv.sd_dps2

    n_par = 1 + len(terms) + 2 * k_gm
    lower = np.full(n_par, -200.0)
    upper = np.full(n_par, 50.0)
    lower[1 + len(terms) + 1::2] = lo_t  # correlation times within reach of the scales
    upper[1 + len(terms) + 1::2] = hi_t
    best = None
    for x0 in _starts(wv, terms, k_gm, rng, starts):
        gm_memo.clear()  # a start's own terms: the memo stays the size of one descent
        res = least_squares(residuals, np.clip(x0, lower + 1e-9, upper - 1e-9), bounds=(lower, upper), method="trf",
                            x_scale=1.0, max_nfev=400 * n_par)
        if best is None or res.cost < best.cost:
            best = res
    out = _unpack(best.x, terms, k_gm, sample_rate_hz, duration_s)
    out.objective = float(2.0 * best.cost)
    out.n_params = n_par
    out.optimism = 2.0 * n_par
    out.criterion = out.objective + out.optimism
    out.jacobian_w = -np.asarray(best.jac)  # the residuals are (ν̂² - ν²(θ)) / sd
    return out


def select_model(wv: WaveletVariance, *, max_gm=MAX_GM, starts=4, seed=0, terms_allowed=OPTIONAL_TERMS,
                 criterion="wvic", runs=BOOTSTRAP_RUNS):
    """Fit every model (white noise + any subset of ``terms_allowed`` (of :data:`TERMS`)
    + 0..``max_gm`` Gauss-Markov terms) and return ``(best, all_fits)``, best by the
    smallest WVIC (``criterion="wvic"``: Q + 2 tr(P V_w), V_w from ``runs`` bootstrap runs of the
    largest model, seeded by ``seed``) or Q + 2p (``"q2p"``); module docstring. Ties (within
    :data:`TIE`) go to the model with fewer parameters."""
    if criterion not in ("wvic", "q2p"):
        raise ValueError(f"criterion must be 'wvic' or 'q2p', got {criterion!r}")
    fits = []
    for k_gm in range(max_gm + 1):
        for r in range(len(terms_allowed) + 1):
            for terms in itertools.combinations(terms_allowed, r):
                fits.append(fit_model(wv, terms, k_gm, starts=starts, seed=seed))
    if criterion == "wvic":
        cov_w = bootstrap_cov(max(fits, key=lambda f: f.n_params), wv, runs=runs, seed=seed)
        for f in fits:
            f.optimism = wvic_optimism(f, cov_w)
            f.criterion = f.objective + f.optimism
    low = min(f.criterion for f in fits)
    # a term fitted to nothing (its variance at the lower bound) adds no rank, so such a model ties
    # with the smaller one it reduces to; and the optimism is an estimate: within TIE of the lowest,
    # the fewest parameters win
    return min((f for f in fits if f.criterion <= low + TIE), key=lambda f: (f.n_params, f.criterion)), fits


def wvic_optimism(fit: GmwmFit, cov_w):
    """The WVIC's optimism 2 tr(P V_w): P the projection onto the columns of the fit's
    standardized Jacobian A_w (its rank: directions with singular values below 1e-8 of the
    largest, parameters pinned at a bound, do not count), ``cov_w`` the estimator's covariance
    in units of the weights (module docstring)."""
    u, sv, _ = np.linalg.svd(fit.jacobian_w, full_matrices=False)
    u = u[:, sv > 1e-8 * sv[0]] if sv.size and sv[0] > 0 else u[:, :0]
    return 2.0 * float(np.sum((u.T @ cov_w) * u.T))


def bootstrap_cov(fit: GmwmFit, wv: WaveletVariance, *, runs=BOOTSTRAP_RUNS, seed=0):
    """Covariance of the wavelet-variance estimator (the one ``wv`` was made with: classical or
    robust, at its scales) in units of ``wv``'s weights, ``Cov(ν̂*_j / sd_j, ν̂*_k / sd_k)`` over
    ``runs`` simulations of ``fit`` of the same duration (:func:`simulate_fit`). Scales of at
    least 32 samples are simulated at a rate lowered by a power of 2 so that the first keeps 16
    samples or more: the wavelet variance at a given τ depends on the duration, not on the rate,
    for these terms (a heavy-tailed noise is then a little noisier at the first scales than the
    record's, whose coefficients average more samples)."""
    m0 = int(wv.m[0])
    d = 2 ** max(0, int(math.floor(math.log2(max(m0, 1) / 16.0)))) if m0 >= 32 else 1
    sample_rate_hz = wv.sample_rate_hz / d
    n, m = wv.n_samples // d, wv.m // d
    rng = np.random.default_rng(seed)
    draws = np.array([_wv_values(simulate_fit(fit, n, sample_rate_hz, rng, tails=wv.tails), sample_rate_hz, m, wv.robust,
                                 wv.tails) / wv.sd_dps2 for _ in range(runs)])
    return np.atleast_2d(np.cov(draws, rowvar=False))


def simulate_fit(fit: GmwmFit, n, sample_rate_hz, rng, tails=None):
    """``n`` samples of the composite model ``fit`` at ``sample_rate_hz`` (deg/s): white noise
    N sqrt(f_s) w (w a unit-variance Gaussian scale mixture with ``tails`` = (fraction,
    scale_ratio), :class:`gyrofilter.sim.noise_terms.ScaleMixtureNormal`), quantisation as the
    difference of a white angle noise of sd Q (ν² = 3Q²/(2τ²)), a random walk K / sqrt(f_s) per
    sample, a drift R t, the bias instability's flicker bank over the ``n`` samples and stationary
    AR(1) Gauss-Markov terms (the simulator's equations, :mod:`gyrofilter.sim.noise_terms`)."""
    from scipy.signal import lfilter

    draws = rng if tails is None else ScaleMixtureNormal(rng, np.random.default_rng(rng.integers(2**63)), *tails)
    x = fit.arw_dps_per_sqrt_hz * math.sqrt(sample_rate_hz) * draws.standard_normal(n)
    if fit.quantization_deg is not None:
        x += np.diff(fit.quantization_deg * rng.standard_normal(n + 1)) * sample_rate_hz
    if fit.rrw_dps_per_sqrt_s is not None:
        x += np.cumsum(fit.rrw_dps_per_sqrt_s / math.sqrt(sample_rate_hz) * rng.standard_normal(n))
    if fit.rate_ramp_dps_per_s is not None:
        x += fit.rate_ramp_dps_per_s * np.arange(n) / sample_rate_hz
    if fit.bias_instability_dps is not None:
        bank = BiasInstability(fit.bias_instability_dps, sample_rate_hz, rng, 1.0 / sample_rate_hz, n / sample_rate_hz)
        for start in range(0, n, 1 << 16):  # in blocks, as the simulator streams it: bounded memory
            x[start:start + (1 << 16)] += bank.next(np.zeros(min(1 << 16, n - start)), None)
    for sigma_dps, tau_s in fit.gauss_markov:
        phi = math.exp(-1.0 / (sample_rate_hz * tau_s))
        w = rng.standard_normal(n)
        x += lfilter([sigma_dps * math.sqrt(1.0 - phi * phi)], [1.0, -phi], w, zi=[phi * sigma_dps * rng.standard_normal()])[0]
    return x


#: runs of a simulated model curve (:func:`simulated_wv`): the mean of R runs carries 1/R of one
#: run's sampling variance, so a model that is exact scores about 1 + 1/R in :func:`wv_distance`
#: against a record of the same length (1.25 with 4 runs, 1.06 with 16), where a fit to the record
#: itself scores about 1 - p/J (p parameters, J scales)
MODEL_CURVE_RUNS = 16


def simulated_wv(model, axis, n_samples, *, seeds=None, min_edf=2.0):
    """Mean Haar wavelet variance of ``axis`` (0, 1, 2) of a simulator model over ``seeds`` runs
    (default the first :data:`MODEL_CURVE_RUNS`) of ``n_samples`` samples: the model's curve where
    no closed form covers every effect."""
    seeds = range(MODEL_CURVE_RUNS) if seeds is None else seeds
    spec = validate_model(model)[0]
    sample_rate_hz = spec["sample_rate_hz"]
    runs = []
    for seed in seeds:
        x = np.concatenate(list(simulate_axis_dps(spec, n_samples / sample_rate_hz, axis, seed=int(seed), validated=spec)))
        runs.append(haar_wv(x, sample_rate_hz, min_edf=min_edf))
    return WaveletVariance(sample_rate_hz, runs[0].n_samples, runs[0].tau_s, np.mean([r.wv_dps2 for r in runs], axis=0),
                           runs[0].edf)
