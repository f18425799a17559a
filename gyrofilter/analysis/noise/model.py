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

The coefficients are estimated in the modules beside this one: :mod:`~gyrofilter.analysis.noise.fit`
(the weighted fit, :func:`~gyrofilter.analysis.noise.fit.characterise`), with the intervals of
:mod:`~gyrofilter.analysis.noise.intervals`, and :mod:`~gyrofilter.analysis.noise.readoff` (the
slope read-offs of papers 000/002); :mod:`~gyrofilter.analysis.noise.screen` finds the gross
errors a record must not hold, :mod:`~gyrofilter.analysis.noise.export` writes the allan JSON and
Kalibr's imu.yaml (its values: :mod:`~gyrofilter.analysis.noise.kalibr`). This module holds the model itself: the terms, their units and conversions,
and the result types.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...effects import BIAS_INSTABILITY, RATE_RAMP, RATE_RANDOM_WALK
from ...errors import SettingsError
from ...units import DEG_PER_RAD, STANDARD_GRAVITY_MPS2

#: the Allan terms' names in code (IEEE Std 952's Q and N; B, K and R are named as the effects they
#: are, gyrofilter.effects): one name per term in every module (docs/formats.md, "Glossary")
QUANTIZATION = "quantization"
ANGLE_RANDOM_WALK = "angle_random_walk"
#: term names in model order, with unit, power of tau in sigma^2, basis and power-law alpha
TERMS = (QUANTIZATION, ANGLE_RANDOM_WALK, BIAS_INSTABILITY, RATE_RANDOM_WALK, RATE_RAMP)
TERM_SYMBOL = {QUANTIZATION: "Q", ANGLE_RANDOM_WALK: "N", BIAS_INSTABILITY: "B", RATE_RANDOM_WALK: "K", RATE_RAMP: "R"}
TERM_UNIT = {QUANTIZATION: "deg", ANGLE_RANDOM_WALK: "deg/sqrt(s)", BIAS_INSTABILITY: "deg/s",
             RATE_RANDOM_WALK: "deg/s/sqrt(s)", RATE_RAMP: "deg/s^2"}
#: slope of log sigma vs log tau for each term
TERM_SLOPE = {QUANTIZATION: -1.0, ANGLE_RANDOM_WALK: -0.5, BIAS_INSTABILITY: 0.0, RATE_RANDOM_WALK: 0.5, RATE_RAMP: 1.0}
#: tau (s) at which the read-off line gives the coefficient (sigma(tau_read) = coefficient)
READ_TAU_S = {QUANTIZATION: math.sqrt(3.0), ANGLE_RANDOM_WALK: 1.0, RATE_RANDOM_WALK: 3.0, RATE_RAMP: math.sqrt(2.0)}
#: power-law exponent of the rate PSD (NIST SP 1065); the ramp is treated as random-walk FM
TERM_ALPHA = {QUANTIZATION: 2, ANGLE_RANDOM_WALK: 0, BIAS_INSTABILITY: -1, RATE_RANDOM_WALK: -2, RATE_RAMP: -2}
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


def term_shares(theta_sq, tau):
    return (basis(tau) * theta_sq).T  # (5, n)


# --------------------------------------------------------------------------------------------
# Unit conversions (all coefficients are stored in the deg/s-based units of TERM_UNIT)
# --------------------------------------------------------------------------------------------

#: (term, unit) -> factor: value_in_unit = factor * value_in_base_unit
UNIT_FACTORS = {
    (QUANTIZATION, "deg"): 1.0,
    (QUANTIZATION, "arcsec"): 3600.0,
    (QUANTIZATION, "rad"): 1.0 / DEG_PER_RAD,
    (ANGLE_RANDOM_WALK, "deg/sqrt(s)"): 1.0,
    (ANGLE_RANDOM_WALK, "deg/s/sqrt(Hz)"): 1.0,
    (ANGLE_RANDOM_WALK, "deg/sqrt(h)"): 60.0,                    # sqrt(3600 s / h)
    (ANGLE_RANDOM_WALK, "rad/s/sqrt(Hz)"): 1.0 / DEG_PER_RAD,    # Kalibr gyroscope_noise_density
    (BIAS_INSTABILITY, "deg/s"): 1.0,
    (BIAS_INSTABILITY, "deg/h"): 3600.0,
    (BIAS_INSTABILITY, "rad/s"): 1.0 / DEG_PER_RAD,
    (RATE_RANDOM_WALK, "deg/s/sqrt(s)"): 1.0,
    (RATE_RANDOM_WALK, "deg/s^2/sqrt(Hz)"): 1.0,
    (RATE_RANDOM_WALK, "deg/h/sqrt(h)"): 3600.0 * 60.0,
    (RATE_RANDOM_WALK, "rad/s^2/sqrt(Hz)"): 1.0 / DEG_PER_RAD,  # Kalibr gyroscope_random_walk
    (RATE_RAMP, "deg/s^2"): 1.0,
    (RATE_RAMP, "deg/h^2"): 3600.0 ** 2,
}
#: the customary units shown beside the base unit
CUSTOMARY_UNIT = {QUANTIZATION: "arcsec", ANGLE_RANDOM_WALK: "deg/sqrt(h)", BIAS_INSTABILITY: "deg/h",
                  RATE_RANDOM_WALK: "deg/h/sqrt(h)", RATE_RAMP: "deg/h^2"}

#: an accelerometer's terms in the m/s-based units of its Allan deviation (m/s^2): the same five-term model
#: with velocity in the place of the angle (IEEE Std 1293-2018, Annex C: Q in m/s, the velocity random walk N
#: in m/s/sqrt(s) = m/s^2/sqrt(Hz), B in m/s^2, the acceleration random walk K in m/s^2/sqrt(s), the ramp R
#: in m/s^3)
ACCEL_TERM_UNIT = {QUANTIZATION: "m/s", ANGLE_RANDOM_WALK: "m/s/sqrt(s)", BIAS_INSTABILITY: "m/s^2",
                   RATE_RANDOM_WALK: "m/s^2/sqrt(s)", RATE_RAMP: "m/s^3"}
#: its customary units: a datasheet's noise density in ug/sqrt(Hz) (micro-g, g = 9.80665 m/s^2), B in ug
ACCEL_CUSTOMARY_UNIT = {QUANTIZATION: "m/s", ANGLE_RANDOM_WALK: "ug/sqrt(Hz)", BIAS_INSTABILITY: "ug",
                        RATE_RANDOM_WALK: "m/s^2/sqrt(h)", RATE_RAMP: "ug/s"}
_UG_PER_MPS2 = 1e6 / STANDARD_GRAVITY_MPS2
UNIT_FACTORS.update({
    (QUANTIZATION, "m/s"): 1.0,
    (ANGLE_RANDOM_WALK, "m/s/sqrt(s)"): 1.0,
    (ANGLE_RANDOM_WALK, "m/s^2/sqrt(Hz)"): 1.0,                  # Kalibr accelerometer_noise_density
    (ANGLE_RANDOM_WALK, "m/s/sqrt(h)"): 60.0,                    # sqrt(3600 s / h)
    (ANGLE_RANDOM_WALK, "ug/sqrt(Hz)"): _UG_PER_MPS2,
    (BIAS_INSTABILITY, "m/s^2"): 1.0,
    (BIAS_INSTABILITY, "ug"): _UG_PER_MPS2,
    (RATE_RANDOM_WALK, "m/s^2/sqrt(s)"): 1.0,
    (RATE_RANDOM_WALK, "m/s^3/sqrt(Hz)"): 1.0,                   # Kalibr accelerometer_random_walk
    (RATE_RANDOM_WALK, "m/s^2/sqrt(h)"): 60.0,
    (RATE_RAMP, "m/s^3"): 1.0,
    (RATE_RAMP, "ug/s"): _UG_PER_MPS2,
})


@dataclass(frozen=True)
class SensorTerms:
    """How one sensor's five terms are named and in which units: ``name`` (``gyroscope`` or
    ``accelerometer``), ``unit`` (its Allan deviation's unit: ``deg/s`` or ``m/s^2``), ``term_unit``
    (each term's base unit, the unit of its fitted value), ``customary_unit`` (shown beside it) and
    ``term_name`` (each term's name in words); ``gap``: whether ``gyrofilter gap`` analyses it
    (the gyro only), so that a message may point there. The fit is unit-free: the coefficients of a
    series in ``unit`` come out in ``term_unit``."""

    name: str
    unit: str
    term_unit: dict
    customary_unit: dict
    term_name: dict
    gap: bool = False


GYROSCOPE_TERMS = SensorTerms("gyroscope", "deg/s", TERM_UNIT, CUSTOMARY_UNIT, {
    QUANTIZATION: "quantization", ANGLE_RANDOM_WALK: "angle random walk", BIAS_INSTABILITY: "bias instability",
    RATE_RANDOM_WALK: "rate random walk", RATE_RAMP: "rate ramp"}, gap=True)
ACCELEROMETER_TERMS = SensorTerms("accelerometer", "m/s^2", ACCEL_TERM_UNIT, ACCEL_CUSTOMARY_UNIT, {
    QUANTIZATION: "quantization", ANGLE_RANDOM_WALK: "velocity random walk", BIAS_INSTABILITY: "bias instability",
    RATE_RANDOM_WALK: "acceleration random walk", RATE_RAMP: "acceleration ramp"})


def sensor_terms(unit):
    """The :class:`SensorTerms` of the sensor whose Allan deviation is in ``unit`` (``deg/s``: the gyro,
    ``m/s^2``: the accelerometer); SettingsError for another unit."""
    for terms in (GYROSCOPE_TERMS, ACCELEROMETER_TERMS):
        if terms.unit == unit:
            return terms
    raise SettingsError(f"unit must be {GYROSCOPE_TERMS.unit} or {ACCELEROMETER_TERMS.unit}, got {unit!r}")


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
    freed_by: tuple = ()           # fit only: the terms not resolved (B, K, R) whose freeing leaves it unresolved

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
    full_fit_values: np.ndarray  # the fit with every term asked for, none dropped (the adequacy warning's model)
    confidence: float = 0.95
    fit_reduced_chi2: float | None = None   # the fit's misfit chi2_nu (intervals.reduced_chi2); None: no dof left
    fit_dof: float | None = None            # its effective degrees of freedom
    warnings: list = field(default_factory=list)

    @property
    def interval_widening(self):
        """The factor sqrt(max(1, chi2_nu)) by which the fit's misfit widened its intervals
        (:func:`~gyrofilter.analysis.noise.intervals.fitted_intervals`; 1 without a misfit)."""
        return math.sqrt(max(1.0, self.fit_reduced_chi2 or 0.0))

    def model_adev(self, tau_s=None):
        """The fitted model's Allan deviation (deg/s) at ``tau_s`` (s; default: the measured taus)."""
        return model_adev(self.fit_values, self.tau_s if tau_s is None else tau_s)

    def fit_consistency(self):
        """Fraction of fitted taus whose chi-square interval contains the fitted model (the curve
        drawn, ``fit_values``)."""
        return self.consistency(self.fit_values)

    def full_fit_consistency(self):
        """Fraction of fitted taus whose chi-square interval contains the full fit
        (``full_fit_values``: every term asked for, none dropped), the model the warning that the
        noise is not just Q/N/B/K/R judges (:func:`~gyrofilter.analysis.noise.fit.characterise_axis`)."""
        return self.consistency(self.full_fit_values)

    def consistency(self, coefficients):
        """Fraction of fitted taus whose chi-square interval (``ci_low``, ``ci_high``) contains the
        model of ``coefficients`` = (Q, N, B, K, R) in their base units; NaN without fitted taus."""
        mod = model_adev(coefficients, self.tau_s)[self.fit_used]
        lo, hi = self.ci_low[self.fit_used], self.ci_high[self.fit_used]
        return float(np.mean((mod >= lo) & (mod <= hi))) if mod.size else float("nan")
