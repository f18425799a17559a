"""The settings of :class:`~gyrofilter.filter.pipeline.GyroFilter`: :class:`FilterSettings` (every
setting, its default and meaning), the range of each number (:data:`SETTING_RANGES`) and the
bounds they share, and the one check of them all (:meth:`FilterSettings.validate`).
"""
from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from .averaging import AVERAGERS, PAPER_Q_DPS
from .calibration import MAX_BIAS_DPS, MAX_BIAS_RANGE, STILLNESS_Z_RANGE
from .hold import DEFAULTS as HOLD_DEFAULTS
from ..errors import SettingsError
from ..inputs import axis_values, check_number, python_value
from .predictor import closed_loop_radius, stable_gain_threshold
from ..units import MAX_RATE_DPS, shown


#: longest start-up still window (s), and most samples in it (an hour at 1 kHz, 115 MB with the
#: temperatures): its samples are held until it ends
MAX_CALIBRATION_S = 3600.0
MAX_CALIBRATION_SAMPLES = 3_600_000
#: largest |temperature coefficient| (deg/s per deg C): 60x the MPU6050's (its zero-rate output
#: moves at most 20 deg/s over -40..85 deg C, 0.16 deg/s per deg C)
MAX_TEMP_COEFFICIENT_DPS_PER_C = 10.0

#: The range of every numeric setting (the bounds :func:`gyrofilter.inputs.check_number` takes).
#: Every size and count has an upper bound, so that no setting asks for more memory or time
#: than a Pi has (a block is held in memory, the rings are fifo_depth, qr_window and hold_window
#: long, and median_slope compares every pair of a block's samples); rates and variances stay
#: within MAX_RATE_DPS (its square), so that every square the filters take stays finite.
SETTING_RANGES = {
    "calibration_s": dict(low=0, high=MAX_CALIBRATION_S),
    "calibration_retry_s": dict(low=0, high=86_400.0),
    "stillness_z": STILLNESS_Z_RANGE,
    "max_bias_dps": MAX_BIAS_RANGE,
    "block_len": dict(low=1, high=100, integer=True),
    "outlier_q_dps": dict(low=0, low_open=True, high=MAX_RATE_DPS),
    "outlier_range_k": dict(low=0, high=100),
    "outlier_range_blocks": dict(low=1, high=999, integer=True),
    "fifo_depth": dict(low=1, high=100, integer=True),
    "fit_order": dict(low=0, high=10, integer=True),
    "p0_dps2": dict(low=0, low_open=True, high=MAX_RATE_DPS ** 2),
    "qr_window": dict(low=0, high=10_000, integer=True),
    "hold_h": dict(low=0, low_open=True, high=1e6),
    "hold_window": dict(low=2, high=1_000, integer=True),
    "hold_max_blocks": dict(low=1, high=10 ** 9, integer=True),
    "gain_min": dict(low=0, low_open=True, high=1),
    "innovation_forgetting": dict(low=0, low_open=True, high=1),
    "prior_var_max_r": dict(low=0, high=1e6),
    "guard_blocks": dict(low=0, high=10 ** 6, integer=True),
    "guard_k_sigma": dict(low=0, low_open=True, high=1e6),
}


@dataclass(frozen=True)
class FilterSettings:
    """Settings of :class:`GyroFilter`; the defaults are paper 001's values (preset "paper";
    GyroFilter's default preset is "recommended", see gyrofilter.filter.presets).

    ============================ ========= ===================================================
    setting                      default   meaning
    ============================ ========= ===================================================
    calibration_s                2.0       start-up still window for the bias (s), <= 3600 and
                                           <= 3.6 million samples; 0 = none (refused
                                           where the filter needs it, unless loaded)
    calibration_retry_s          0.0       keep trying new windows for this long (s) when the
                                           sensor moved; 0 = raise at once
    stillness_z                  6.0       stillness limit (noise units, see calibration)
    max_bias_dps                 20.0      largest plausible bias (deg/s; MPU6050 datasheet)
    block_len                    5         L, samples per non-sliding block (001: 5)
    outlier_q_dps                1.0       q, gross-error threshold |x_i - mean| (deg/s)
    outlier_range_k              0         k_r: a block's q is max(q, k_r x the lower quartile
                                           of the ranges of the last outlier_range_blocks
                                           blocks), per axis, so a vibration is not cut as
                                           gross errors (gyrofilter.filter.threshold);
                                           0 = q (001)
    outlier_range_blocks         15        N, blocks of that quartile (<= 999)
    outlier_rule                 paper     "paper" (|x_i - mean| > q), "median_slope" (robust
                                           line per block; see averaging) or "by_model"
                                           (paper in the adaptive filter's constant-rate
                                           model, median_slope in its LS model)
    fifo_depth                   10        posteriors in the LS-prediction FIFO (001: 10)
    fit_order                    2         order of the LS fit (001: 2, quadratic)
    p0_dps2                      1.0       P0, variance of the initial state ((deg/s)^2)
    qr_window                    10        blocks over which Q and R are computed; 0 = all
    qr_stat                      variance  "variance" or "std": reading of sigma in eqs 11-12
    r_source                     window    "window" (eq. 12) or "calibration" (fixed R)
    backend                      auto      "auto", "python" or "numba" for the Kalman loop
    tracker                      kalman    "kalman" (paper 001) or "block_mean" (no filter)
    hold                         False     constant-rate hold after the tracker (adaptive)
    hold_h                       10.0      CUSUM threshold of the hold (block-noise units)
    hold_window                  20        blocks the hold's constancy test looks at
    hold_max_blocks              400       memory of the held mean (blocks)
    kalman_noise                 paper     how the Kalman stage gets Q and R: "paper" (eqs.
                                           11-12 over qr_window) or "adaptive" (R from the
                                           calibration, Q by covariance matching, constant-rate
                                           / LS model switch; adaptive_kalman.run_blocks_adaptive); the
                                           switch uses hold_h, hold_window, hold_max_blocks
    gain_min                     0.6       "adaptive": least Kalman gain K of the LS model; the
                                           loop must be stable at it (predictor.
                                           closed_loop_radius < 1: K > 0.335 for 10 points,
                                           order 2)
    innovation_forgetting        0.1       "adaptive": a in C_k = (1-a) C_(k-1) + a nu_k^2,
                                           the innovation variance estimate, in (0, 1]
    prior_var_max_r              4.0       "adaptive": above this prior variance, in units of
                                           R, the LS prior is dropped (gain 1); 0 = never
    guard_blocks                 0         divergence guard: re-seed the Kalman filter from the
                                           block mean after this many blocks in a row more than
                                           guard_k_sigma sigma_b from the block means; 0 = off
                                           (the faithful filter)
    guard_k_sigma                10.0      the guard's limit in sigma_b, the std of a block mean
                                           at rest (from the calibration window)
    temp_coefficient_dps_per_c   0         c per axis (one number or 3): subtract
                                           c (T - T0), T0 the calibration's mean temperature;
                                           needs temperatures (see gyrofilter.filter.tempcomp)
    ============================ ========= ===================================================

    Every number must lie in its range in :data:`SETTING_RANGES` (a bool is not a number), the
    temperature coefficients within +-:data:`MAX_TEMP_COEFFICIENT_DPS_PER_C`.

    On qr_window: paper 001 computes Q and R over the last 10 blocks. A long window (0, all; or
    hundreds of blocks) keeps Q at its value at rest, so the LS prediction is trusted far past a
    turn's onset: with ``preset="paper"`` (the guard off) a 30 deg/s step overshot by 310 deg/s
    before it settled (10 blocks: at most the step itself, a lag of a few blocks). The guard
    (``guard_blocks``) re-seeds such a filter; the default preset does not need it.

    ``preset="hold"`` is ``tracker="block_mean", hold=True``; ``preset="adaptive_kalman"`` (= the
    default ``"recommended"``) is ``kalman_noise="adaptive"`` with the guard on (gyrofilter.filter.presets).

    On q: paper 001 saw gross errors of more than 200 LSB; one such spike in a block of 5 sits
    4/5 * 200 = 160 LSB from the block mean, while its own example block
    (67, 49, 55, -233, 21) puts normal samples up to 75 LSB from the mean. q = 1 deg/s
    (131 LSB at +-250 deg/s) separates the two.
    """

    calibration_s: float = 2.0
    calibration_retry_s: float = 0.0
    stillness_z: float = 6.0
    max_bias_dps: float = MAX_BIAS_DPS
    block_len: int = 5
    outlier_q_dps: float = PAPER_Q_DPS
    outlier_range_k: float = 0.0
    outlier_range_blocks: int = 15
    fifo_depth: int = 10
    fit_order: int = 2
    p0_dps2: float = 1.0
    qr_window: int = 10
    qr_stat: str = "variance"
    r_source: str = "window"
    backend: str = "auto"
    tracker: str = "kalman"
    hold: bool = False
    hold_h: float = HOLD_DEFAULTS["cusum_h"]
    hold_window: int = HOLD_DEFAULTS["window_blocks"]
    hold_max_blocks: int = HOLD_DEFAULTS["max_blocks"]
    outlier_rule: str = "paper"
    temp_coefficient_dps_per_c: object = 0.0
    kalman_noise: str = "paper"
    gain_min: float = 0.6
    innovation_forgetting: float = 0.1
    prior_var_max_r: float = 4.0
    guard_blocks: int = 0
    guard_k_sigma: float = 10.0

    def temp_coefficients(self):
        """The temperature coefficients as a tuple of 3 floats (deg/s per deg C)."""
        c = self.temp_coefficient_dps_per_c
        return tuple(float(v) for v in c) if isinstance(c, (tuple, list)) else (float(c),) * 3

    def validate(self) -> "FilterSettings":
        """Check every setting and return them with the numbers as plain Python ints and floats
        (an integer setting may be given as 5.0); SettingsError names the first bad one, its value
        and what is expected. Numbers must lie in :data:`SETTING_RANGES` (never a bool, NaN or
        infinity: :func:`gyrofilter.inputs.check_number`)."""

        def need(cond, name, what):
            if not cond:
                raise SettingsError(f"setting {name}={shown(getattr(self, name))}: {what}")

        numbers = {name: check_number(getattr(self, name), f"setting {name}", **bounds)
                   for name, bounds in SETTING_RANGES.items()}
        # every other setting as the Python value it holds (units.python_value): numpy's True is True
        # ("hold=True: must be True or False"), np.float32(0.01) or np.array(0.01) one coefficient
        # (one was iterated over as if it were 3, the other refused as an array)
        plain_values = {f.name: python_value(getattr(self, f.name)) for f in fields(self) if f.name not in numbers}
        plain_values["temp_coefficient_dps_per_c"] = axis_values(self.temp_coefficient_dps_per_c)
        checked = replace(self, **numbers, **plain_values)
        checked._validate_choices(need)
        return checked

    def _validate_choices(self, need):
        """The checks beyond the ranges: the named choices and the settings that depend on each other."""
        need(self.qr_window != 1, "qr_window", "must be 0 (all) or >= 2: a variance needs two values")
        need(self.qr_stat in ("variance", "std"), "qr_stat", "must be 'variance' or 'std'")
        need(self.r_source in ("window", "calibration"), "r_source", "must be 'window' or 'calibration'")
        need(self.backend in ("auto", "python", "numba"), "backend", "must be 'auto', 'python' or 'numba'")
        need(isinstance(self.hold, bool), "hold", "must be True or False")
        need(self.tracker in ("kalman", "block_mean"), "tracker", "must be 'kalman' or 'block_mean'")
        rules = (*AVERAGERS, "by_model")
        need(self.outlier_rule in rules, "outlier_rule", f"must be one of {', '.join(map(repr, rules))}")
        need(self.kalman_noise in ("paper", "adaptive"), "kalman_noise", "must be 'paper' or 'adaptive'")
        need(self.outlier_rule != "by_model" or (self.kalman_noise == "adaptive" and self.tracker == "kalman"), "outlier_rule",
             "'by_model' follows the adaptive Kalman filter's model: it needs kalman_noise='adaptive' and "
             "tracker='kalman'; with another filter choose the rule too, e.g. outlier_rule='paper' "
             "(--set outlier_rule=paper)")
        c = self.temp_coefficient_dps_per_c
        several = isinstance(c, (tuple, list))
        items = c if several else (c,)
        need(len(items) == (3 if several else 1)
             and all(_is_number(v) and abs(v) <= MAX_TEMP_COEFFICIENT_DPS_PER_C for v in items),
             "temp_coefficient_dps_per_c",
             f"must be one number or 3 (deg/s per deg C, axes x, y, z), each within +-{MAX_TEMP_COEFFICIENT_DPS_PER_C:g}")
        if self.kalman_noise == "adaptive":
            radius = closed_loop_radius(self.fifo_depth, self.fit_order, self.gain_min)
            need(radius < 1, "gain_min", f"leaves the LS loop unstable (largest root modulus {radius:.3f} with "
                 f"fifo_depth={self.fifo_depth}, fit_order={self.fit_order}; stable above "
                 f"{stable_gain_threshold(self.fifo_depth, self.fit_order):.3f})")


SETTING_NAMES = tuple(f.name for f in fields(FilterSettings))
_REAL = (int, float, np.integer, np.floating)
_BOOL = (bool, np.bool_)


def _is_number(value):
    """Whether ``value`` is an int or float (numpy's too), not a bool."""
    return isinstance(value, _REAL) and not isinstance(value, _BOOL)

