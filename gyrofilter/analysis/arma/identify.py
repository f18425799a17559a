"""ARMA model of a static gyro's bias noise (paper 003, Wang, Lyu and Wu 2016).

Paper 003 takes a static gyro axis minus its constant, a zero-mean series x_t in deg/s, and
models it as an ARMA(N, M) process (its eq. 1)::

    x_t - phi_1 x_{t-1} - ... - phi_N x_{t-N} = a_t - theta_1 a_{t-1} - ... - theta_M a_{t-M}

with a_t white. Signs are the paper's (and Pandit-Wu's): ``phi`` and ``theta`` here are exactly
its phi_i and theta_j; statsmodels writes the MA part with ``+``, so its ``maparams`` are
``-theta``. The procedure implemented here is the paper's section 1:

1. stationarity: augmented Dickey-Fuller (ADF) unit-root test (Hamilton 1994, ch. 17), through
   ``statsmodels.tsa.stattools.adfuller``; the paper reports -110.18 for its z gyro;
2. normality: Kolmogorov-Smirnov (on the standardised series) and Jarque-Bera (scipy);
3. order: the Pandit-Wu ARMA(2n, 2n-1) procedure (Pandit and Wu, *Time Series and System
   Analysis with Applications*, 1983, ch. 4): fit ARMA(2, 1), ARMA(4, 3), ... and go up while
   the residual sum of squares still falls significantly, judged by the F statistic::

       F = ((A_1 - A_0) / s) / (A_0 / (N - r))      ~ F(s, N - r)

   (A_0, A_1: RSS of the larger and the smaller model, s: number of extra parameters, r:
   parameters of the larger model) and by the AIC in the paper's per-sample form
   ``ln(sigma_a^2) + 2 r / N`` (paper 003 table 3 lists about -10.19). Then the adequate
   ARMA(2n, 2n-1) is reduced one parameter at a time (drop the last AR or the last MA term)
   while the reduced model is not significantly worse than ARMA(2n, 2n-1) (same F test);
   that is how the paper arrives at ARMA(1, 1) from ARMA(2, 1). The same walk can be judged
   by AIC or BIC instead of F; BIC is the default here because F and AIC over-select on
   simulated ARMA(1, 1) data (measured in :func:`select_order`), ``criterion="f"`` is the paper's;
4. adequacy: residual ACF/PACF against the +-1.96/sqrt(N) band and the Ljung-Box Q test.

Estimation is Pandit-Wu's conditional least squares (:mod:`gyrofilter.analysis.arma.fit`); the
tests of steps 1, 2 and 4 are in :mod:`gyrofilter.analysis.arma.checks`; this module holds the
order search, the bias model and the whole procedure for one axis (:func:`analyze_axis`).

Long series: CSS costs O(N) per evaluation, so a 10-minute 100 Hz log (65 000 samples) is fitted
at full rate in about a second. Series longer than ``max_samples`` are block-averaged by the
smallest integer factor k that brings them under the limit, and every result says so
(``decimation``, ``analysis_rate_hz``). The per-sample ARMA coefficients belong to the
analysis rate; the bias model's physical parameters (correlation time, bias sigma, white-noise
density) are those of the sensor's samples: the decomposition below takes the block length L
into account (block means of a Gauss-Markov bias are smoother than the bias sampled at the block
rate, an ARMA(1, 1) with theta < 0 that the plain decomposition would call white noise).

The ARMA(1, 1) also maps onto the bias model a Kalman filter needs: ARMA(1, 1) with
0 < theta <= phi < 1 has the autocovariances of a first-order Gauss-Markov bias b_t =
phi b_{t-1} + eta_t plus white noise w_t, with (matching lag-0 and lag-1 autocovariances of
(1 - phi B) x_t)::

    sigma_w^2 = theta sigma_a^2 / phi,   sigma_eta^2 = sigma_a^2 (1 + theta^2) - sigma_w^2 (1 + phi^2)

so tau = -dt / ln(phi), bias sigma = sigma_eta / sqrt(1 - phi^2); for phi -> 1 the bias is a
random walk with K = sigma_eta sqrt(fs). A tau longer than a fraction of the record
(:data:`TAU_RECORD_FRACTION`) is not determined by it: the record holds the random walk K =
sigma sqrt(2 / tau), not sigma and tau apart (:func:`bias_model_within_record`). Block means of L samples (phi_L the ARMA's phi, phi =
phi_L^(1/L) per sample, S = sum_{m<L} phi^m) have the autocovariances of the ARMA(1, 1),
gamma_0 = sigma_a^2 (1 - 2 phi_L theta + theta^2) / (1 - phi_L^2) and gamma_1 = sigma_a^2 (1 - phi_L theta)
(phi_L - theta) / (1 - phi_L^2), where the bias gives gamma_1 = sigma_b^2 phi S^2 / L^2 and gamma_0 =
sigma_b^2 (L + 2 sum_{m=1}^{L-1} (L - m) phi^m) / L^2 plus sigma_w^2 / L (Box-Jenkins' autocovariances of
an ARMA(1, 1); the block sums of an AR(1)): solved for sigma_b^2 and sigma_w^2 (L = 1: the equations above). Paper 003's x_t - 1.0000 x_{t-1} = a_t - 0.9994 a_{t-1}
is that limit: sigma_eta = (1 - theta) sigma_a = 0.0006 sigma_a per sample.

statsmodels is the optional ``stats`` extra (``pip install "gyrofilter[stats]"``,
:func:`~gyrofilter.analysis.arma.fit.require_stats`); it and scipy are imported inside the
functions that use them.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from ..noise.allan import overlapping_adev, rate_numbers
from .checks import (DEFAULT_ADF_MAXLAG, DEFAULT_ALPHA, WHITENESS_LAGS, Normality, Stationarity, Whiteness,
                          adf_test, normality_tests, whiteness)
from .fit import ArmaFit, fit_arma, require_stats, simulate_arma
from ...errors import SettingsError
from ...inputs import check_number
from ...units import MAX_RATE_DPS, MIN_NOISE_DPS, check_sample_rate_hz, json_ready, one_value, plain

DEFAULT_MAX_SAMPLES = 200_000
#: fewest samples of an axis the analysis takes: fewer leave the tests and the order search without
#: power (and below about 30 statsmodels' ADF test fails on its own lags)
MIN_SAMPLES = 200
#: the range of ``max_samples``: at least twice :data:`MIN_SAMPLES`, so that the block means of a
#: longer series (``N / k``, ``k = ceil(N / max_samples)``: more than ``max_samples / 2``) are never
#: fewer than the analysis takes; at most 1e8 (ARMA fits of more take hours and gain nothing)
MAX_SAMPLES_RANGE = (2 * MIN_SAMPLES, 10**8)
DEFAULT_MAX_N = 4  # up to ARMA(8, 7)
CRITERIA = ("f", "aic", "bic")
DEFAULT_CRITERION = "bic"  # see select_order for why not the paper's F rule
#: a fitted Gauss-Markov tau longer than this fraction of the record is not determined by it
#: (:func:`bias_model_within_record`). Measured (Gauss-Markov + white noise of 0, 0.3 and 1 bias
#: sigma, N = 200 and 4000, 5 seeds, ARMA(1, 1) of the mean-removed record): for T / tau >= 10
#: the fitted tau is at most 0.16 T (median tau_hat / tau 0.85-1.0); for T / tau <= 5 it stops
#: tracking (median 0.7 at 5, 0.35 at 2, 0.02 at 0.1) and saturates at 0.04-0.5 T (up to 1.25 T
#: and phi = 1 at N = 200) whatever the true tau: a tau_hat above T / 5 came only from records
#: with T / tau <= 5.
TAU_RECORD_FRACTION = 0.2


# ---------------------------------------------------------------------------------------------
# results


@dataclass
class OrderStep:
    """One comparison of the order search: ``smaller`` against ``larger`` by the F test."""

    smaller: tuple
    larger: tuple
    f_statistic: float
    f_critical: float
    significant: bool  # True: the larger model reduces the RSS significantly


@dataclass
class BiasModel:
    """Gauss-Markov bias plus white noise equivalent to an ARMA(1, 1) (see the module docstring).

    Rate-independent: the same numbers describe the series at any sample rate.
    ``tau_s`` is ``inf`` when phi >= 1 (random walk, then ``bias_walk_dps_per_sqrt_s`` holds K).
    ``valid`` is False when the ARMA(1, 1) has no such decomposition (theta <= 0 or theta > phi).
    ``tau_determined`` is False when the fitted tau is longer than :data:`TAU_RECORD_FRACTION` of
    the record (``record_s``, s; None: not compared, :func:`bias_model_within_record`): then
    ``tau_s`` and ``bias_sigma_dps`` are ``inf`` (``null`` in JSON) and the bias is, within the
    record, the random walk ``bias_walk_dps_per_sqrt_s``.
    """

    tau_s: float
    bias_sigma_dps: float
    bias_walk_dps_per_sqrt_s: float  # sigma_eta * sqrt(fs): the bias drive as a random-walk density
    white_noise_dps_per_sqrt_hz: float  # angle random walk N of the white part
    valid: bool
    note: str = ""
    tau_determined: bool = True
    record_s: float | None = None  # the record's length the fitted tau was compared with (s)

    def discrete(self, sample_rate_hz):
        """(phi, sigma_eta_dps, sigma_w_dps) of the bias model at ``sample_rate_hz``.

        b_k = phi b_{k-1} + eta_k, eta ~ N(0, sigma_eta^2); measurement white noise sigma_w.
        """
        dt = 1.0 / sample_rate_hz
        sigma_w = self.white_noise_dps_per_sqrt_hz * math.sqrt(sample_rate_hz)
        if math.isinf(self.tau_s):
            return 1.0, self.bias_walk_dps_per_sqrt_s * math.sqrt(dt), sigma_w
        phi = math.exp(-dt / self.tau_s)
        return phi, self.bias_sigma_dps * math.sqrt(1.0 - phi * phi), sigma_w


@dataclass
class AxisReport:
    """Everything ``analyze_axis`` found for one axis."""

    axis: str
    n_samples: int
    sample_rate_hz: float
    decimation: int
    analysis_rate_hz: float
    mean_dps: float
    std_dps: float
    stationarity: Stationarity
    normality: Normality
    fits: list  # every ArmaFit tried, in order
    steps: list  # OrderStep, in order
    adequate_order: tuple  # the ARMA(2n, 2n-1) the upward search stopped at
    chosen: ArmaFit
    arma11: ArmaFit
    bias_model: BiasModel
    whiteness: Whiteness
    notes: list = field(default_factory=list)
    criterion: str = DEFAULT_CRITERION
    warnings: list = field(default_factory=list)  # what scipy/statsmodels warned, summarised (see analyze_axis)

    def to_dict(self):
        """The report as plain data (the ``arma --json`` document's axis entry)."""
        return {
            "axis": self.axis,
            "n_samples": self.n_samples,
            "sample_rate_hz": self.sample_rate_hz,
            "decimation": self.decimation,
            "analysis_rate_hz": self.analysis_rate_hz,
            "mean_dps": self.mean_dps,
            "std_dps": self.std_dps,
            "stationarity": json_ready(asdict(self.stationarity)),
            "normality": json_ready(asdict(self.normality)),
            "order_search": [json_ready(asdict(s)) for s in self.steps],
            "fits": [f.to_dict() for f in self.fits],
            "criterion": self.criterion,
            "adequate_order": list(self.adequate_order),
            "chosen": self.chosen.to_dict(),
            "arma11": self.arma11.to_dict(),
            "bias_model": json_ready(asdict(self.bias_model)),
            "whiteness": json_ready(asdict(self.whiteness)),
            "notes": list(self.notes),
            "warnings": list(self.warnings),
        }


# ---------------------------------------------------------------------------------------------
# preparation


def check_max_samples(max_samples, name="max_samples"):
    """``max_samples`` as an int, or SettingsError naming ``name`` (the option or argument given)
    for one that is no whole number (:func:`~gyrofilter.inputs.check_number`) or is outside
    :data:`MAX_SAMPLES_RANGE`: the one check of it, the command's and the function's."""
    low, high = MAX_SAMPLES_RANGE
    max_samples = check_number(max_samples, name, integer=True)
    if not low <= max_samples <= high:
        bound = f"at least {low} (block means of a longer series are more than half of it, and the analysis needs {MIN_SAMPLES})" \
            if max_samples < low else f"at most {high}"
        raise SettingsError(f"{name} must be {bound}, got {plain(max_samples)}")
    return max_samples


def prepare_series(x, sample_rate_hz, max_samples=DEFAULT_MAX_SAMPLES):
    """Zero-mean series for the analysis: ``(series, decimation, analysis_rate_hz, mean)``, from
    ``x`` (1-D, deg/s) sampled at ``sample_rate_hz`` (Hz).

    Paper 003: "static output minus its constant". Longer than ``max_samples``: non-overlapping
    block means over the smallest factor k with N / k <= max_samples (the tail that does not
    fill a block is dropped). SettingsError (AllanInputError for what is not rates:
    :func:`~gyrofilter.analysis.noise.allan.rate_numbers`), a value that
    is not finite or one beyond :data:`~gyrofilter.units.MAX_RATE_DPS` (whose squares overflowed
    the tests near 1e154 deg/s).
    """
    x = rate_numbers(x, "series")
    if x.ndim != 1:
        raise SettingsError(f"series must be 1-D, got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise SettingsError("series holds NaN or infinite values")
    beyond = np.flatnonzero(np.abs(x) > MAX_RATE_DPS)
    if beyond.size:
        raise SettingsError(f"series sample {int(beyond[0])}: {float(x[beyond[0]]):.6g} deg/s is beyond the "
                            f"+-{MAX_RATE_DPS:g} deg/s any gyro reads; are the rates in deg/s?")
    check_sample_rate_hz(sample_rate_hz)
    max_samples = check_max_samples(max_samples)
    k = max(1, math.ceil(len(x) / max_samples))
    if k > 1:
        n = (len(x) // k) * k
        x = x[:n].reshape(-1, k).mean(axis=1)
    mean = float(x.mean())
    return x - mean, k, sample_rate_hz / k, mean


# ---------------------------------------------------------------------------------------------
# order search and bias model


def f_test(small: ArmaFit, large: ArmaFit, alpha=DEFAULT_ALPHA) -> OrderStep:
    """Pandit-Wu F test: does ``large`` reduce the RSS significantly against ``small``?

    F = ((A_1 - A_0) / s) / (A_0 / (N - r)), s = extra parameters, r = parameters of ``large``;
    significance ``alpha``: the critical value is F(s, N - r)'s upper alpha quantile, (d2 / d1)
    b / (1 - b) of the beta law's b = B^-1(1 - alpha; s / 2, (N - r) / 2) (d1 X / (d1 X + d2) of
    an F variate X is beta: Abramowitz and Stegun 26.6.4), taken from the upper tail (exact at any alpha).
    """
    from scipy import stats

    s = large.n_params - small.n_params
    n = min(small.n_residuals, large.n_residuals)
    dof = n - large.n_params
    f = ((small.rss - large.rss) / s) / (large.rss / dof)
    b = float(stats.beta.isf(alpha, s / 2, dof / 2))  # 1 - alpha is 1.0 below 1.1e-16: f.ppf gave inf
    crit = dof / s * b / (1 - b)
    return OrderStep(small.order, large.order, float(f), crit, bool(f > crit))


def information_criterion(fit: ArmaFit, criterion="aic") -> float:
    """Per-sample information criterion of ``fit``: ln(sigma_a^2) + c r / N, c = 2 (``criterion``
    "aic", paper 003's form) or ln N ("bic")."""
    n = fit.n_residuals
    c = 2.0 if criterion == "aic" else math.log(n)
    return math.log(fit.rss / n) + c * fit.n_params / n


def select_order(x, *, max_n=DEFAULT_MAX_N, alpha=DEFAULT_ALPHA, reduce=True, criterion=DEFAULT_CRITERION):
    """Pandit-Wu ARMA(2n, 2n-1) order selection for the zero-mean series ``x``; returns
    ``(chosen, adequate_order, fits, steps)``.

    ``criterion="f"`` (paper 003 / Pandit-Wu): go up n = 1, 2, ... while ARMA(2n+2, 2n+1)
    lowers the RSS significantly (F test at ``alpha``) and n < max_n. Then (``reduce``) drop the
    last AR or MA term while the smaller model is not significantly worse than the adequate
    ARMA(2n, 2n-1); among the candidates that pass, the one with the smaller RSS is kept.

    ``criterion="aic"`` or ``"bic"``: the same walk, judged by the information criterion (go up
    while it falls; drop a term while it does not rise). Paper 003 allows "F test or AIC".
    Measured on simulated ARMA(1, 1), phi 0.9, theta 0.5, N = 10 000, 12 seeds: F picks
    ARMA(1, 1) 5 times, AIC 6, BIC 12 (AR(2): 5, 5, 6 of 6). The F test's nominal 5 % is not the
    real rate, because an over-fitted ARMA's extra parameters are not identified under the
    smaller model (extra AR/MA root pairs nearly cancel and can fit a periodogram bump); the
    exact Gaussian likelihood shows the same (seed 203: likelihood-ratio / 4 = 3.74 at our
    ARMA(4, 3), above F(4, inf) 5 % = 2.37; statsmodels' own optimiser stops at a worse optimum
    there). Hence the default is BIC (``DEFAULT_CRITERION``); ``criterion="f"`` is paper 003's
    rule. The F tests are reported in ``steps`` whatever decides.
    """
    if max_n < 1:
        raise SettingsError(f"max_n must be at least 1, got {plain(max_n)}")
    if criterion not in CRITERIA:
        raise SettingsError(f"criterion must be one of {', '.join(CRITERIA)}, got {criterion!r}")
    fits = {}
    steps = []

    def get(p, q, start=None):
        if (p, q) not in fits:
            fits[(p, q)] = fit_arma(x, p, q, start=start)
        return fits[(p, q)]

    def ic(f):
        return information_criterion(f, criterion)

    n = 1
    adequate = get(2, 1)
    while n < max_n:
        bigger = get(2 * n + 2, 2 * n + 1, start=(adequate.phi, adequate.theta))
        step = f_test(adequate, bigger, alpha)
        steps.append(step)
        up = step.significant if criterion == "f" else ic(bigger) < ic(adequate)
        if not up:
            break
        n += 1
        adequate = bigger
    chosen = adequate
    if reduce:
        while True:
            candidates = []
            for p, q in ((chosen.p - 1, chosen.q), (chosen.p, chosen.q - 1)):
                if p < 0 or q < 0:
                    continue
                cand = get(p, q, start=(chosen.phi[:p], chosen.theta[:q]))
                step = f_test(cand, adequate, alpha)
                steps.append(step)
                ok = not step.significant if criterion == "f" else ic(cand) <= ic(chosen)
                if ok:
                    candidates.append(cand)
            if not candidates:
                break
            chosen = min(candidates, key=(lambda f: f.rss) if criterion == "f" else ic)
    return chosen, adequate.order, list(fits.values()), steps


def bias_model_from_arma11(fit: ArmaFit, sample_rate_hz, block=1, record_s=None) -> BiasModel:
    """Gauss-Markov bias + white noise equivalent to the ARMA(1, 1) ``fit`` (module docstring) of a
    series at ``sample_rate_hz`` (Hz) whose every value is the mean of ``block`` samples of the
    sensor (the analysis's block averaging; 1: the samples themselves). ``record_s``: the record's
    length (s), for :func:`bias_model_within_record`; None: tau is not compared with it."""
    return bias_model_within_record(_decomposed(fit, sample_rate_hz, block), record_s)


def bias_model_within_record(model: BiasModel, record_s) -> BiasModel:
    """``model`` with its tau and bias sigma "not determined" (``inf``, ``tau_determined`` False)
    when its tau exceeds :data:`TAU_RECORD_FRACTION` of the record's ``record_s`` (s; None: ``model``
    as it is). Such a bias is, within the record, a random walk: for b_{k+1} = phi b_k + eta_k,
    var(eta) = sigma^2 (1 - phi^2), and as phi -> 1 (tau >> T) sigma^2 (1 - phi^2) -> 2 sigma^2 dt
    / tau while neither sigma nor tau alone shows in T; the record determines the increment, K =
    sqrt(var(eta) / dt) = sigma sqrt(2 / tau) (``bias_walk_dps_per_sqrt_s``, kept)."""
    if record_s is None or not model.valid:
        return model
    record_s = float(record_s)
    if model.tau_s <= TAU_RECORD_FRACTION * record_s:
        return replace(model, record_s=record_s)
    note = (f"Gauss-Markov tau and bias sigma not determined (the fitted tau is longer than {TAU_RECORD_FRACTION:g} x the "
            f"record, {record_s:.4g} s): within it a random walk of K = {model.bias_walk_dps_per_sqrt_s:.4g} deg/s/sqrt(s)")
    return replace(model, tau_s=math.inf, bias_sigma_dps=math.inf, tau_determined=False, record_s=record_s, note=note)


def _decomposed(fit: ArmaFit, sample_rate_hz, block) -> BiasModel:
    """:func:`bias_model_from_arma11` before the record's length is considered."""
    if fit.order != (1, 1):
        raise SettingsError(f"bias model needs an ARMA(1, 1) fit, got ARMA{fit.order}")
    phi, theta = fit.phi[0], fit.theta[0]
    s2a = fit.sigma_a**2
    sample_rate_hz = float(sample_rate_hz)
    if block > 1 and 0 < phi < 1.0 - 1e-12:
        return _block_bias_model(phi, theta, s2a, sample_rate_hz, int(block))
    if not (phi > 0 and 0 < theta <= phi):
        return BiasModel(math.inf, 0.0, 0.0, fit.sigma_a / math.sqrt(sample_rate_hz), False,
                         f"phi={phi:.6f}, theta={theta:.6f}: no Gauss-Markov + white decomposition (needs 0 < theta <= phi); treated as white noise")
    s2w = theta * s2a / phi
    s2eta = max(0.0, s2a * (1 + theta * theta) - s2w * (1 + phi * phi))
    walk = math.sqrt(s2eta * sample_rate_hz)
    arw = math.sqrt(s2w / sample_rate_hz)
    if phi >= 1.0 - 1e-12:
        return BiasModel(math.inf, math.inf, walk, arw, True, "phi = 1: random-walk bias")
    tau = -1.0 / (sample_rate_hz * math.log(phi))
    return BiasModel(tau, math.sqrt(s2eta / (1 - phi * phi)), walk, arw, True, "")


def _block_bias_model(phi_block, theta, s2a, sample_rate_hz, block):
    """:func:`bias_model_from_arma11` of means of ``block`` samples (0 < ``phi_block`` < 1; module docstring)."""
    gamma0 = s2a * (1 - 2 * phi_block * theta + theta * theta) / (1 - phi_block**2)
    gamma1 = s2a * (1 - phi_block * theta) * (phi_block - theta) / (1 - phi_block**2)
    phi = phi_block ** (1.0 / block)
    powers = phi ** np.arange(block)
    lag1 = phi * powers.sum() ** 2 / block**2  # gamma_1 of the block means per unit bias variance
    lag0 = (block + 2 * np.sum((block - np.arange(1, block)) * powers[1:])) / block**2
    s2b = gamma1 / lag1
    s2w = block * (gamma0 - s2b * lag0)  # per sample of the sensor
    fs = sample_rate_hz * block
    arw = math.sqrt(max(s2w, 0.0) / fs)
    if not (gamma1 >= 0 and s2w > 0):
        return BiasModel(math.inf, 0.0, 0.0, math.sqrt(s2a / sample_rate_hz), False,
                         f"phi={phi_block:.6f}, theta={theta:.6f} of means of {block} samples: no Gauss-Markov + white "
                         "decomposition (the white part's variance would be <= 0 or the bias's < 0); treated as white noise")
    tau = -1.0 / (fs * math.log(phi))
    return BiasModel(tau, math.sqrt(s2b), math.sqrt(s2b * (1 - phi * phi) * fs), arw, True, "")


# ---------------------------------------------------------------------------------------------
# the whole procedure for one axis


def analyze_axis(x_dps, sample_rate_hz, *, axis="z", max_samples=DEFAULT_MAX_SAMPLES, max_n=DEFAULT_MAX_N,
                 alpha=DEFAULT_ALPHA, adf_maxlag=DEFAULT_ADF_MAXLAG, lags=WHITENESS_LAGS, quantum_dps=None,
                 criterion=DEFAULT_CRITERION) -> AxisReport:
    """Paper 003's section 1 for one static axis (deg/s): tests, Pandit-Wu order, whiteness, bias model.

    ``x_dps``: the axis's series (deg/s) at ``sample_rate_hz`` (Hz); ``max_samples``: see
    :func:`prepare_series`; ``max_n``, ``alpha``: see :func:`select_order`; ``adf_maxlag``: see
    :func:`adf_test`; ``lags``: see :func:`whiteness`.

    ``quantum_dps``: the recording's quantisation step (1 / lsb_per_dps), for the dithered KS test;
    ignored when the series is block-averaged. ``criterion``: see :func:`select_order`. Warnings
    of scipy and statsmodels are caught, not printed: ``report.warnings`` summarises them
    (:func:`summarise_warnings`).
    """
    require_stats()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        report = _analyze_axis(x_dps, sample_rate_hz, axis, max_samples, max_n, alpha, adf_maxlag, lags,
                               quantum_dps, criterion)
    report.warnings = summarise_warnings(caught)
    return report


def summarise_warnings(caught):
    """The ``caught`` warnings (``warnings.WarningMessage``) as one text per distinct kind and message, with a count.

    scipy and statsmodels warn on hard fits (ConvergenceWarning, RuntimeWarning on a near-singular
    step, ...); :func:`analyze_axis` collects them instead of letting them print, and a caller
    decides how to show them: ``["ConvergenceWarning (3x): Maximum Likelihood optimization failed
    to converge"]``.
    """
    counts = {}
    for w in caught:
        key = f"{w.category.__name__}: {' '.join(str(w.message).split())}"
        counts[key] = counts.get(key, 0) + 1
    return [key if n == 1 else key.replace(":", f" ({n}x):", 1) for key, n in counts.items()]


def _analyze_axis(x_dps, sample_rate_hz, axis, max_samples, max_n, alpha, adf_maxlag, lags, quantum_dps, criterion):
    series, k, rate, mean = prepare_series(x_dps, sample_rate_hz, max_samples)
    x_raw = rate_numbers(x_dps, "series")
    if len(x_raw) < MIN_SAMPLES:  # statsmodels' ADF test failed on 20 (ValueError: maxlag)
        raise SettingsError(f"axis {axis}: {len(x_raw)} samples; the analysis needs at least {MIN_SAMPLES}")
    if one_value(x_raw.min(), x_raw.max()):
        raise SettingsError(f"axis {axis}: constant ({mean:g} deg/s) over all {len(x_raw)} samples: "
                            "no noise to model (is the axis stuck or saturated?)")
    spread = float(np.std(series))
    if not spread >= MIN_NOISE_DPS:
        raise SettingsError(f"axis {axis}: the standard deviation is below {MIN_NOISE_DPS:g} deg/s ({spread:.3g}): too "
                            "small a noise for the fits in float64; are the rates in deg/s?")
    notes = []
    if k > 1:
        notes.append(f"{len(x_raw)} samples block-averaged by {k} to {len(series)} at {rate:.6g} Hz before the analysis "
                     f"(max_samples={max_samples}); ARMA coefficients are per analysis sample")
    stat = adf_test(series, maxlag=adf_maxlag, alpha=alpha)
    norm = normality_tests(series, alpha=alpha, quantum=quantum_dps if k == 1 else None)
    try:
        chosen, adequate, fits, steps = select_order(series, max_n=max_n, alpha=alpha, criterion=criterion)
        arma11 = next((f for f in fits if f.order == (1, 1)), None) or fit_arma(series, 1, 1)
    except SettingsError as exc:  # the data fit exactly: name the axis
        raise SettingsError(f"axis {axis}: {exc}") from None
    if not any(f is arma11 for f in fits):
        fits.append(arma11)
    white = whiteness(chosen.residuals, chosen.n_params, lags=lags, alpha=alpha)
    bias = bias_model_from_arma11(arma11, rate, block=k, record_s=len(x_raw) / float(sample_rate_hz))
    if not bias.valid:
        notes.append(bias.note)
    elif bias.tau_s < 10.0 / rate:
        notes.append(f"the ARMA(1,1) correlation time ({bias.tau_s:.3g} s) is under 10 samples: it describes coloured "
                     "(low-passed) sensor noise rather than a bias process; do not use it as a bias model")
    return AxisReport(axis, len(x_raw), float(sample_rate_hz), k, rate, mean, float(x_raw.std(ddof=1)), stat, norm,
                      fits, steps, adequate, chosen, arma11, bias, white, notes, criterion)


def arma_adev(fit: ArmaFit, n, analysis_rate_hz, *, seeds=(0, 1, 2), taus_s=None):
    """Mean overlapping Allan deviation of series simulated from ``fit`` (n samples at
    ``analysis_rate_hz``, Hz, one per seed of ``seeds``), at ``taus_s`` (s; default grid).

    Returns (tau_s, adev): the ADEV this ARMA model implies for a record like the measured one.
    """
    curves = []
    tau = None
    for s in seeds:
        sim = simulate_arma(fit.phi, fit.theta, fit.sigma_a, n, seed=s)
        tau, dev = overlapping_adev(sim, analysis_rate_hz, taus_s)
        curves.append(dev)
    return tau, np.sqrt(np.mean(np.square(curves), axis=0))


def adev_discrepancy(adev_measured, adev_model):
    """RMS of log10(model / measured) over the taus both define (``adev_model``, ``adev_measured``:
    deviations at the same taus): 0 = identical curves, 0.1 ~ 26 % off."""
    m = np.asarray(adev_measured, float)
    s = np.asarray(adev_model, float)
    ok = np.isfinite(m) & np.isfinite(s) & (m > 0) & (s > 0)
    return float(np.sqrt(np.mean(np.log10(s[ok] / m[ok]) ** 2)))
