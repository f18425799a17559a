"""The series tests of paper 003's procedure (:mod:`gyrofilter.analysis.arma.identify`): stationarity (the
augmented Dickey-Fuller test), normality (Kolmogorov-Smirnov and Jarque-Bera) and the residuals'
whiteness (ACF/PACF and the Ljung-Box test), each at a significance level ``alpha``.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from .fit import require_stats

DEFAULT_ADF_MAXLAG = 20
DEFAULT_ALPHA = 0.05
WHITENESS_LAGS = 20


# ---------------------------------------------------------------------------------------------
# results


@dataclass
class Stationarity:
    """Augmented Dickey-Fuller test (H0: unit root). Stationary where it is rejected at alpha (:func:`adf_test`)."""

    adf_statistic: float
    p_value: float
    lags_used: int
    n_obs: int
    critical_values: dict
    stationary: bool


@dataclass
class Normality:
    """Kolmogorov-Smirnov (standardised series vs N(0, 1)) and Jarque-Bera tests (H0: normal)."""

    ks_statistic: float
    ks_p_value: float
    ks_critical_5pct: float
    jb_statistic: float
    jb_p_value: float
    jb_critical_5pct: float
    skewness: float
    excess_kurtosis: float
    normal_ks: bool
    normal_jb: bool
    ks_dithered_statistic: float = None  # KS after adding uniform dither of one quantisation step
    ks_dithered_p_value: float = None
    normal_ks_dithered: bool = None


@dataclass
class Whiteness:
    """Residual whiteness: ACF/PACF against +-1.96/sqrt(N), Ljung-Box Q (H0: white)."""

    lags: list
    acf: list
    pacf: list
    band: float
    outside_band: int  # lags (1..lags) whose |ACF| exceeds the band; ~5 % expected for white noise
    ljung_box_q: float
    ljung_box_lag: int
    ljung_box_p_value: float
    white: bool


# ---------------------------------------------------------------------------------------------
# the tests


def adf_test(x, maxlag=DEFAULT_ADF_MAXLAG, alpha=DEFAULT_ALPHA) -> Stationarity:
    """Augmented Dickey-Fuller test of the series ``x`` with a constant, lag order by AIC up to
    ``maxlag``, at significance ``alpha``: stationary (the unit root rejected) where the statistic
    is below MacKinnon's (2010) critical value at 1, 5 or 10 %, and at any other alpha where
    MacKinnon's (1994) p-value is below it (statsmodels tables no other critical value).

    statsmodels' default maxlag (12 (N/100)^(1/4), 60 at N = 65 000) takes ~20 s there for
    the same verdict, hence the cap. The test runs on the standardised series (x - mean) / std,
    which with a constant gives the same statistic: statsmodels' regression is not scale-free
    (noise of 1e-21 deg/s read -0.00, "unit root not rejected", for -59). The lag order is
    :func:`adf_aic_lag`'s, the one statsmodels' ``autolag="AIC"`` picks, without its 21 kept
    regressions (993 MB on the 200 000 samples of ``arma``'s default, issue 37).
    """
    require_stats()
    from statsmodels.tsa.stattools import adfuller

    x = np.asarray(x, float)
    spread = float(np.std(x))
    z = (x - float(np.mean(x))) / spread if spread > 0 else x
    lag = adf_aic_lag(z, maxlag)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        stat, p, lags, nobs, crit = adfuller(z, maxlag=lag, regression="c", autolag=None)
    tabled = next((v for k, v in crit.items() if math.isclose(alpha * 100, float(k.rstrip("%")))), None)
    stationary = stat < tabled if tabled is not None else p < alpha  # the 5 % value at any other alpha made 0.001 laxer than 0.01
    return Stationarity(float(stat), float(p), int(lags), int(nobs), {k: float(v) for k, v in crit.items()},
                        bool(stationary))


def adf_aic_lag(z, maxlag):
    """The lag order p (0..``maxlag``) of the ADF regression of the series ``z`` with a constant
    that minimises AIC = n ln(SSR_p / n) + 2 (p + 2), every order fitted on the same n = N - 1 -
    ``maxlag`` rows (the regression dz_t = a + b z_{t-1} + sum_{i<=p} c_i dz_{t-i} + e_t):
    statsmodels' ``adfuller(autolag="AIC")`` rule (``_autolag``: OLS on the first p + 2 columns of
    one design, AIC = -2 llf + 2 k with its constant n ln 2 pi + n dropped, the smallest lag on a
    tie). One QR factorisation of the design with dz appended, [X y] = QR, gives every SSR_p:
    SSR_p = sum_{j >= p + 2} R[j, m]^2 (m = maxlag + 2, y's column), in O(N maxlag) memory.
    """
    z = np.asarray(z, float)
    if maxlag > z.size // 2 - 2:  # statsmodels' own bound (nobs // 2 - 1 - 1 trend term), its error
        raise ValueError("maxlag must be less than (nobs/2 - 1 - ntrend) where n trend is the number of included "
                         "deterministic regressors")
    dz = np.diff(z)
    n = dz.size - maxlag
    design = np.empty((n, maxlag + 3))
    design[:, 0] = 1.0
    design[:, 1] = z[maxlag:-1]
    for i in range(1, maxlag + 1):
        design[:, 1 + i] = dz[maxlag - i:dz.size - i]
    design[:, -1] = dz[maxlag:]
    r = np.linalg.qr(design, mode="r")
    ssr = np.cumsum(r[::-1, -1] ** 2)[::-1][2:]  # ssr[p] = sum_{j >= p + 2} R[j, m]^2
    with np.errstate(divide="ignore"):  # an exact fit: ln 0 = -inf, the smallest AIC
        aic = n * np.log(ssr / n) + 2 * (np.arange(maxlag + 1) + 2)
    return int(np.argmin(aic))  # the first of equal values: the smallest lag


def normality_tests(x, alpha=DEFAULT_ALPHA, quantum=None, seed=0) -> Normality:
    """Kolmogorov-Smirnov on (x - mean) / std against N(0, 1), and Jarque-Bera.

    JB = N/6 (S^2 + (K - 3)^2 / 4) ~ chi2(2) (Jarque and Bera 1987). The KS critical value is
    the asymptotic 1.358 / sqrt(N); with mean and std estimated from the data the KS p-value is
    conservative (Lilliefors), and on quantised data (MPU6050 LSB steps) KS also sees the steps:
    with ``quantum`` (the step, in the series' unit) KS is repeated on x + U(-quantum/2, quantum/2)
    (seeded dither, ``seed``), which removes the steps but not a non-normal shape. ``alpha``:
    the significance level of the verdicts (``normal_*``: p >= alpha); the critical values are the
    5 % ones their names state, whatever alpha. The statistics are scale-free, so they are computed on ``x`` times the
    power of two that brings its standard deviation near 1 (exact: the same bits at any scale a
    fourth power holds; noise of 1e-90 deg/s, above the floor of ``units.MIN_NOISE_DPS``, had
    fourth powers below the smallest float: JB and the kurtosis read nan and normality "rejected").
    """
    require_stats()
    from scipy import stats

    x = np.asarray(x, float)
    exponent = int(np.frexp(x.std())[1])
    x = np.ldexp(x, -exponent)
    z = (x - x.mean()) / x.std(ddof=1)
    ks = stats.kstest(z, "norm")
    jb = stats.jarque_bera(x)
    n = len(x)
    result = Normality(
        ks_statistic=float(ks.statistic),
        ks_p_value=float(ks.pvalue),
        ks_critical_5pct=float(1.358 / math.sqrt(n)),
        jb_statistic=float(jb.statistic),
        jb_p_value=float(jb.pvalue),
        jb_critical_5pct=float(stats.chi2.ppf(0.95, 2)),  # as KS's: the 5 % values, shown; the verdicts at alpha
        skewness=float(stats.skew(x)),
        excess_kurtosis=float(stats.kurtosis(x)),
        normal_ks=bool(ks.pvalue >= alpha),
        normal_jb=bool(jb.pvalue >= alpha),
    )
    if quantum:
        step = math.ldexp(quantum, -exponent)
        xd = x + np.random.default_rng(seed).uniform(-step / 2, step / 2, n)
        ksd = stats.kstest((xd - xd.mean()) / xd.std(ddof=1), "norm")
        result.ks_dithered_statistic = float(ksd.statistic)
        result.ks_dithered_p_value = float(ksd.pvalue)
        result.normal_ks_dithered = bool(ksd.pvalue >= alpha)
    return result


def whiteness(residuals, n_params=0, lags=WHITENESS_LAGS, alpha=DEFAULT_ALPHA) -> Whiteness:
    """ACF/PACF of ``residuals`` (lags 1..lags) and the Ljung-Box test at ``lags`` with ``n_params``
    df removed, at significance ``alpha``.

    Q = N (N + 2) sum_{k=1}^{h} r_k^2 / (N - k) ~ chi2(h - p - q) (Ljung and Box 1978).
    """
    require_stats()
    from statsmodels.stats.diagnostic import acorr_ljungbox
    from statsmodels.tsa.stattools import acf, pacf

    r = np.asarray(residuals, float)
    n = len(r)
    a = acf(r, nlags=lags, fft=True)[1:]
    pa = pacf(r, nlags=lags, method="ywm")[1:]
    band = 1.96 / math.sqrt(n)
    lb = acorr_ljungbox(r, lags=[lags], model_df=n_params)
    q = float(np.asarray(lb["lb_stat"])[0])
    p = float(np.asarray(lb["lb_pvalue"])[0])
    return Whiteness(list(range(1, lags + 1)), [float(v) for v in a], [float(v) for v in pa], band,
                     int(np.sum(np.abs(a) > band)), q, lags, p, bool(p >= alpha))
