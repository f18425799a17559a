"""The paper-001 real-time pipeline, three axes, streaming and batch.

    raw (deg/s) [-> temperature compensation] -> start-up bias calibration
                -> block averaging with gross-error rejection
                -> Kalman filter with least-squares-prediction prior -> filtered (deg/s)

Stages: :mod:`gyrofilter.filter.calibration` (001 section 2.1), :mod:`gyrofilter.filter.averaging` (2.2),
:mod:`gyrofilter.filter.predictor` and :mod:`gyrofilter.filter.kalman` (2.3). Output: one row per block of
``block_len`` samples, at ``sample_rate_hz / block_len``.

``update()`` (one sample at a time) and ``filter()`` (an array) share the state and the
arithmetic, so any mix of calls gives the same numbers as feeding every sample to ``update()``.
The state has a fixed size: nothing grows per sample, so a filter can run for days.
"""
from __future__ import annotations

import copy
import math
import os
from dataclasses import asdict, dataclass, fields, replace
from functools import partial

import numpy as np

from . import adaptive_kalman, kalman
from .hold import SIGMA_B_FLOOR_DPS, block_noise_std, make_hold
from .averaging import AVERAGERS, average_block_line_if_cut, average_blocks_line_if_cut
from .calibration import MAX_BIAS_DPS, Calibration, calibrate, calibration_samples
from ..errors import CalibrationError, SampleError, SettingsError
from ..inputs import check_number
from .predictor import closed_loop_radius, stable_gain_threshold
from .presets import DEFAULT_PRESET, PRESETS
from .tempcomp import compensate
from ..units import AXES, MAX_RATE_DPS, RATE_TOLERANCE, TEMP_RANGE_C, check_rates_dps, check_sample_rate_hz, plain


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
    "stillness_z": dict(low=0, low_open=True, high=1e6),
    "max_bias_dps": dict(low=0, low_open=True, high=MAX_RATE_DPS),
    "block_len": dict(low=1, high=100, integer=True),
    "outlier_q_dps": dict(low=0, low_open=True, high=MAX_RATE_DPS),
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
    outlier_q_dps: float = 1.0
    fifo_depth: int = 10
    fit_order: int = 2
    p0_dps2: float = 1.0
    qr_window: int = 10
    qr_stat: str = "variance"
    r_source: str = "window"
    backend: str = "auto"
    tracker: str = "kalman"
    hold: bool = False
    hold_h: float = 10.0
    hold_window: int = 20
    hold_max_blocks: int = 400
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
        return (float(c),) * 3 if isinstance(c, (int, float)) else tuple(float(v) for v in c)

    def validate(self) -> "FilterSettings":
        """Check every setting and return them with the numbers as plain Python ints and floats
        (an integer setting may be given as 5.0); SettingsError names the first bad one, its value
        and what is expected. Numbers must lie in :data:`SETTING_RANGES` (never a bool, NaN or
        infinity: :func:`gyrofilter.inputs.check_number`)."""

        def need(cond, name, what):
            if not cond:
                raise SettingsError(f"setting {name}={_shown(getattr(self, name))}: {what}")

        numbers = {name: check_number(getattr(self, name), f"setting {name}", **bounds)
                   for name, bounds in SETTING_RANGES.items()}
        checked = replace(self, **numbers)
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


class GyroFilter:
    """Paper-001 pipeline for a three-axis gyro; see the module docstring and FilterSettings.

    Parameters
    ----------
    sample_rate_hz : float
        Input sample rate (Hz), finite and > 0 (:func:`gyrofilter.units.check_sample_rate_hz`).
    calibration_s : float, optional
        Length of the start-up bias calibration (s); None keeps the preset's (2 s).
    preset : str
        Named settings (:mod:`gyrofilter.filter.presets`); the default "recommended" is the best
        measured filter, "paper" the faithful reproduction.
    calibration : Calibration or str, optional
        A :class:`~gyrofilter.filter.calibration.Calibration` or the path of a saved one: skips the
        start-up calibration.
    **settings
        Any :class:`FilterSettings` field (units in its table); explicit keyword settings
        override the ``preset``.

    >>> f = GyroFilter(sample_rate_hz=100.0, calibration_s=2.0)
    >>> f.update((0.01, -0.02, 0.0)) is None      # calibrating
    True
    """

    def __copy__(self):
        """A whole copy (as ``copy.deepcopy``): the state is arrays a shallow copy would share, so
        feeding the copy would change the original's later rows."""
        return copy.deepcopy(self)

    def __init__(self, sample_rate_hz, calibration_s=None, *, preset=DEFAULT_PRESET, calibration=None, **settings):
        if not isinstance(preset, str) or preset not in PRESETS:
            raise SettingsError(f"unknown preset {_shown(preset)}; choose one of {', '.join(PRESETS)}")
        unknown = sorted(set(settings) - set(SETTING_NAMES))
        if unknown:
            raise SettingsError(f"unknown setting(s) {', '.join(unknown)}; known: {', '.join(SETTING_NAMES)}")
        _check_calibration_argument(calibration, calibration_s)
        chosen = dict(PRESETS[preset])
        chosen.update(settings)
        if calibration_s is not None:
            chosen["calibration_s"] = calibration_s
        self.settings = FilterSettings(**chosen).validate()
        self.sample_rate_hz = check_sample_rate_hz(sample_rate_hz)
        self.preset = preset
        s = self.settings
        self._adaptive = s.kalman_noise == "adaptive"
        # by_model: paper 001's rule in the constant-rate model, median_slope in the LS model
        self._by_model = s.outlier_rule == "by_model"
        self._average_one, self._average_many = AVERAGERS["paper" if self._by_model else s.outlier_rule]
        self._temp_coef = s.temp_coefficients()
        self._temp_on = any(self._temp_coef)
        self._temp_ref = None  # T0 of the temperature compensation: the calibration's mean temperature
        self._y1 = np.zeros((1, 3))
        self._y1_motion = np.zeros((1, 3))  # outlier_rule="by_model": the motion rule's block mean
        self._out1 = np.zeros((1, 3))
        self._hold = None  # constant-rate hold stage (gyrofilter.filter.hold), built after calibration
        # divergence guard: sigma_b, the std of a block mean at rest (the adaptive filter's R too)
        self._sigma_b = np.ones(3)
        self.block_log = None  # a gyrofilter.filter.smoother.BlockLog while a Smoother records this filter
        # Kalman state (fixed size); the kernel's arguments are bound once, updated in place
        if self._adaptive:
            self._akf = adaptive_kalman.AdaptiveKalman(s)
            self._guard_run = self._akf.guard_run
        else:
            self._pkf = kalman.PaperKalman(s, self._sigma_b)
            self._guard_run = self._pkf.guard_run
        # block and calibration state
        self._block = []
        self.rejected = np.zeros(3, dtype=np.int64)
        self.fallback_blocks = np.zeros(3, dtype=np.int64)
        self.blocks_out = 0
        self.samples_in = 0  # every sample fed to update() or filter(), calibration included
        self.calibration = None
        self._bias = (0.0, 0.0, 0.0)
        self._cal_needed = calibration_samples(self.sample_rate_hz, s.calibration_s)
        if calibration is None and s.calibration_s > 0 and self._cal_needed < 3:
            raise SettingsError(f"setting calibration_s={plain(s.calibration_s)} gives {self._cal_needed} sample(s) at "
                                f"{self.sample_rate_hz:g} Hz; the calibration needs at least 3 to measure the noise")
        if calibration is None and self._cal_needed > MAX_CALIBRATION_SAMPLES:
            raise SettingsError(f"setting calibration_s={plain(s.calibration_s)} gives {self._cal_needed} samples at "
                                f"{self.sample_rate_hz:g} Hz; the still window is held in memory: at most "
                                f"{MAX_CALIBRATION_SAMPLES} samples ({MAX_CALIBRATION_SAMPLES / self.sample_rate_hz:g} s)")
        self._cal_buf = None
        self._cal_fill = 0
        self._cal_tries_left = 0
        self._cal_temp = None
        if calibration is None and self._cal_needed == 0:
            # settings that need the bias, noise or temperature of a still start-up window
            for needed, setting, why in (
                    (self._temp_on, "temp_coefficient_dps_per_c",
                     "or a loaded calibration with temp_c: its mean temperature is the reference T0"),
                    (s.hold, "hold=True", "or a loaded calibration"),
                    (s.tracker == "kalman" and s.kalman_noise == "adaptive", "kalman_noise='adaptive'",
                     "or a loaded calibration: the still window's noise and bias start its model (without them it "
                     "carries the uncorrected bias for about a minute); preset 'paper' runs without one")):
                if needed:
                    raise SettingsError(f"setting {setting} needs a start-up calibration (calibration_s > 0) {why}")
        if calibration is not None:
            if isinstance(calibration, Calibration):
                self.calibration = calibration.checked("the calibration", max_bias_dps=s.max_bias_dps)
            else:
                self.calibration = Calibration.load(calibration, max_bias_dps=s.max_bias_dps)
            _check_calibration_rate(self.calibration, self.sample_rate_hz,
                                    "the calibration" if isinstance(calibration, Calibration) else f"calibration {calibration}")
            self._apply_calibration(self.calibration)
            self._start_kalman(np.asarray(self.calibration.noise_std_dps, dtype=float) / math.sqrt(s.block_len), still_blocks=0)
            if s.hold:
                # a loaded calibration says nothing about stillness now: start tracking
                self._hold = self._make_hold(noise_std_dps=self.calibration.noise_std_dps)
        elif self._cal_needed > 0:
            self._cal_buf = np.zeros((self._cal_needed, 3))
            self._cal_temp = np.full(self._cal_needed, np.nan)  # NaN: a sample without a temperature
            self._cal_tries_left = int(s.calibration_retry_s // max(s.calibration_s, 1e-9))

    # ------------------------------------------------------------------ public API

    @property
    def bias_dps(self):
        """Start-up bias estimate per axis (deg/s), or None while calibrating."""
        return None if self._cal_buf is not None else self._bias

    @property
    def calibrating(self) -> bool:
        """True while the start-up calibration still collects samples (no output yet)."""
        return self._cal_buf is not None

    @property
    def compensates_temperature(self) -> bool:
        """True when update() and filter() need temperatures (temp_coefficient_dps_per_c set)."""
        return self._temp_on

    @property
    def output_rate_hz(self) -> float:
        """Rate of the output rows (Hz): ``sample_rate_hz / block_len``."""
        return self.sample_rate_hz / self.settings.block_len

    @property
    def pending_samples(self) -> int:
        """Samples held for a block that is not full yet (they produce output once it is)."""
        return len(self._block)

    @property
    def first_block_index(self):
        """Index of the first input sample of output row 0, or None while calibrating.

        Output row k (counted from the first row the filter gave) is the block of input samples
        ``first_block_index + k L .. first_block_index + (k + 1) L - 1`` (L = ``settings.block_len``),
        indices counting every sample fed since the start (``samples_in``), calibration included:
        the samples before it are the calibration window (and the windows a retry refused).
        """
        if self.calibrating:
            return None
        return self.samples_in - self.pending_samples - self.blocks_out * self.settings.block_len

    def block_end_indices(self, n_rows) -> np.ndarray:
        """For the latest ``n_rows`` output rows: the index of each row's last input sample.

        Indices count every sample fed since the start (``samples_in``), calibration included,
        so ``t_s[block_end_indices(len(rows))]`` time-stamps the rows a call just returned (see
        :meth:`filter_timed`, which does this for one call). ``n_rows`` is a whole number from 0 to
        the rows output so far (``blocks_out``), else SettingsError.
        """
        n_rows = check_number(n_rows, f"n_rows of block_end_indices (the filter has output {self.blocks_out} rows)",
                              low=0, high=self.blocks_out, integer=True)
        last = self.samples_in - self.pending_samples - 1
        return last - self.settings.block_len * np.arange(n_rows - 1, -1, -1, dtype=np.int64)

    def update(self, sample, temp_c=None):
        """Feed one sample and return the filtered block it completed, if any.

        ``sample``: (gx, gy, gz), a tuple, list or array of 3 numbers in deg/s, each finite and
        within +-:data:`~gyrofilter.units.MAX_RATE_DPS`. ``temp_c``: the sample's temperature
        (deg C, within TEMP_RANGE_C of gyrofilter.units; None or NaN for none),
        required when compensating (``compensates_temperature``); otherwise used only while
        calibrating, so that the calibration keeps the window's mean temperature
        (``Calibration.temp_c``, for a later run that compensates) when every sample had one.
        Returns None while calibrating and between blocks, else the filtered (x, y, z) in deg/s
        for the block this sample completed.

        A refused sample or temperature raises :class:`~gyrofilter.errors.SampleError` (a
        SettingsError) before it touches the filter: the filter is as if it had not been sent.
        A start-up window that fails its check raises CalibrationError once no retry is left
        (``calibration_retry_s``); that window is dropped, and the next sample starts a new one.
        """
        sample = _sample3(sample)
        if temp_c is not None or self._temp_on:
            temp_c = _temperature(temp_c, self._temp_on, "update()")
        self.samples_in += 1
        if self._cal_buf is not None:
            self._cal_buf[self._cal_fill] = sample
            self._cal_temp[self._cal_fill] = math.nan if temp_c is None else temp_c
            self._cal_fill += 1
            if self._cal_fill == self._cal_needed:
                self._finish_calibration()
            return None
        if self._temp_on:
            c, dt = self._temp_coef, temp_c - self._temp_ref
            sample = (sample[0] - c[0] * dt, sample[1] - c[1] * dt, sample[2] - c[2] * dt)
        block = self._block
        block.append(sample)
        if len(block) < self.settings.block_len:
            return None
        self._block = []
        q = self.settings.outlier_q_dps
        y1 = self._y1
        modes = self._akf.modes() if self._by_model else None
        for a, values in enumerate(zip(*block)):
            paper = mean, rejected, fallback = self._average_one(values, q)
            if self._by_model:  # both rules' block means: the kernel takes one by its model (a smoother logs both)
                motion_mean, motion_rejected, _ = average_block_line_if_cut(values, q, paper)
                self._y1_motion[0, a] = motion_mean - self._bias[a]
                if modes[a] != adaptive_kalman.REST:
                    rejected, fallback = motion_rejected, False
            if rejected or fallback:
                self.rejected[a] += rejected
                self.fallback_blocks[a] += fallback
            y1[0, a] = mean - self._bias[a]
        self._track(y1, self._out1, self._y1_motion if self._by_model else None)
        self.blocks_out += 1
        x, y, z = self._out1[0].tolist()
        return (x, y, z)

    def filter(self, samples_dps, temp_c=None) -> np.ndarray:
        """Feed ``samples_dps``, an (N, 3) array in deg/s, and ``temp_c``, N temperatures in deg C
        (required when compensating; otherwise used only while calibrating, as in :meth:`update`).

        Returns the filtered blocks it completed, (M, 3). From a new filter,
        M = (N - calibration samples) // block_len and row k is block k after the calibration.
        Leftover samples wait in the filter for the next call.

        The samples are checked as :meth:`update` checks one, all before any is used: the first
        refused sample or temperature raises :class:`~gyrofilter.errors.SampleError` naming its
        row (``.row``) and leaves the filter as it was. A CalibrationError (the start-up window
        refused, no retry left) drops that window; the samples of this call after it are not
        used, and the next sample given starts a new window.
        """
        return self._filter(_samples(samples_dps), temp_c)

    def _filter(self, x, temp_c):
        """:meth:`filter` of the checked samples ``x`` (:func:`_samples`)."""
        temps = self._check_temps(temp_c, len(x))
        samples_in = self.samples_in + len(x)
        outputs = []
        i = 0
        while self._cal_buf is not None and i < len(x):
            take = min(self._cal_needed - self._cal_fill, len(x) - i)
            self._cal_buf[self._cal_fill : self._cal_fill + take] = x[i : i + take]
            self._cal_temp[self._cal_fill : self._cal_fill + take] = math.nan if temps is None else temps[i : i + take]
            self._cal_fill += take
            i += take
            if self._cal_fill == self._cal_needed:
                self.samples_in = samples_in - len(x) + i  # counted before a refused window raises
                self._finish_calibration()
        while self._block and i < len(x):
            row = self.update(x[i], None if temps is None else float(temps[i]))
            i += 1
            if row is not None:
                outputs.append(np.array([row]))
        if self._temp_on and i < len(x):
            x = compensate(x[i:], temps[i:], self._temp_coef, self._temp_ref)
            i = 0
        length = self.settings.block_len
        n_blocks = (len(x) - i) // length
        if n_blocks:
            blocks = x[i : i + n_blocks * length].reshape(n_blocks, length, 3)
            q = self.settings.outlier_q_dps
            y, rejected, fallback = paper = self._average_many(blocks, q)
            bias = np.asarray(self._bias)
            out = np.empty_like(y)
            if self._by_model:  # both rules' block means; the kernel takes one by its model, and says which
                y_motion, rejected_motion, _ = average_blocks_line_if_cut(blocks, q, paper)
                y -= bias
                y_motion -= bias
                used = np.empty((n_blocks, 3), dtype=np.int64)
                self._track(y, out, y_motion, used)
                motion = used == adaptive_kalman.MOTION
                rejected = np.where(motion, rejected_motion, rejected)
                fallback = fallback & ~motion
            else:
                y -= bias
                self._track(y, out)
            self.rejected += rejected.sum(axis=0)
            self.fallback_blocks += fallback.sum(axis=0)
            self.blocks_out += n_blocks
            outputs.append(out)
            i += n_blocks * length
        # samples that do not complete a block wait for the next call (the block may already
        # hold samples from update() or an earlier call: those stay, in order)
        self._block.extend(tuple(row) for row in x[i:].tolist())
        self.samples_in = samples_in
        if not outputs:
            return np.empty((0, 3))
        return np.concatenate(outputs)

    def filter_timed(self, samples_dps, t_s, temp_c=None):
        """:meth:`filter` with time stamps: returns ``(t_rows_s, rows)``.

        ``t_s`` (N,) are the times of the N samples (s, any origin); ``rows`` (M, 3) are what
        ``filter(samples_dps, temp_c)`` returns and ``t_rows_s`` (M,) the time of each row's
        block's last input sample. A row comes out when that sample goes in, so it is always one
        of this call's samples, whatever the chunking. Times must be finite (SampleError names
        the first that is not, and the filter is left as it was).
        """
        x = _samples(samples_dps)
        t = _numbers(t_s, "t_s", "s")
        if t.shape != (len(x),):
            raise SampleError(f"t_s must have shape ({len(x)},), one time per sample, got {t.shape}")
        finite = np.isfinite(t)
        if not finite.all():
            row = int(np.flatnonzero(~finite)[0])
            raise SampleError(f"t_s must be finite (s), got {t[row]!r}", row, f"t_s row {row}")
        rows = self._filter(x, temp_c)
        return t[self.block_end_indices(len(rows)) - (self.samples_in - len(x))], rows

    def state_dict(self) -> dict:
        """The settings and counters worth reporting (plain Python values)."""
        return {
            "preset": self.preset,
            "settings": asdict(self.settings),
            "bias_dps": self.bias_dps,
            "blocks_out": self.blocks_out,
            "rejected": self.rejected.tolist(),
            "fallback_blocks": self.fallback_blocks.tolist(),
            "guard_reseeds": self.guard_reseeds,
        }

    # ------------------------------------------------------------------ internals

    def _check_temps(self, temp_c, n):
        """The temperatures for filter(): n values (deg C), or None when none are given. Each is
        within TEMP_RANGE_C or NaN (none), which only keeps the calibration from
        keeping a temperature and is refused when compensating (as :meth:`update` does)."""
        if temp_c is None:
            if self._temp_on:
                raise SampleError("temperature compensation is on: filter() needs temp_c, one temperature (deg C) per sample")
            return None
        t = _numbers(temp_c, "temp_c", "deg C")
        if t.shape != (n,):
            raise SampleError(f"temp_c must have shape ({n},), one temperature per sample, got {t.shape}")
        ok = (t >= TEMP_RANGE_C[0]) & (t <= TEMP_RANGE_C[1])
        if not self._temp_on:
            ok |= np.isnan(t)
        if not ok.all():
            row = int(np.flatnonzero(~ok)[0])
            _temperature(float(t[row]), self._temp_on, f"temp_c row {row}", row)
        return t

    def _track(self, y, out, y_motion=None, used=adaptive_kalman.NO_USED):
        """Block means y (M, 3) -> output (M, 3): the tracker, then the hold stage if enabled.
        ``y_motion``, ``used``: the adaptive filter's (adaptive_kalman.run_blocks_adaptive)."""
        if self.settings.tracker != "kalman":
            out[:] = y
        elif not self._adaptive:
            self._pkf.run(y, out)
        elif self.block_log is None:
            self._akf.run(y, out, adaptive_kalman.NO_TRACE, y_motion, used)
        else:
            trace = np.empty((len(y), 3, 3))
            self._akf.run(y, out, trace, y_motion, used)
            self.block_log.append(y, y if y_motion is None else y_motion, out, trace)
        if self._hold is not None:
            self._hold.step(y, out, out)

    def _finish_calibration(self):
        s = self.settings
        try:
            temps = self._cal_temp if np.isfinite(self._cal_temp).all() else None
            cal = calibrate(self._cal_buf, self.sample_rate_hz, stillness_threshold=s.stillness_z,
                            max_bias_dps=s.max_bias_dps, temp_c=temps)
        except CalibrationError:
            self._cal_fill = 0  # the window is dropped: the next sample starts a new one
            if self._cal_tries_left <= 0:
                raise
            self._cal_tries_left -= 1
            return
        self.calibration = cal
        self._start_kalman(block_noise_std(self._cal_buf, s.block_len), still_blocks=self._cal_needed // s.block_len)
        if s.hold:
            # the window passed the stillness check: start holding, sigma_b from its block means
            self._hold = self._make_hold(calibration_window_dps=self._cal_buf)
        self._apply_calibration(cal)

    def _start_kalman(self, sigma_b_dps, still_blocks):
        """sigma_b (3,) for the guard and the adaptive filter's R = sigma_b^2 (see
        adaptive_kalman.AdaptiveKalman.start: after n still calibration blocks it starts at rest)."""
        self._sigma_b[:] = np.maximum(sigma_b_dps, SIGMA_B_FLOOR_DPS)
        if self._adaptive:
            self._akf.start(self._sigma_b, still_blocks)

    @property
    def guard_reseeds(self):
        """Per axis: how often the divergence guard re-seeded the Kalman filter."""
        return self._guard_run[kalman.GUARD_RESEEDS : kalman.GUARD_RESEEDS + 3].tolist()

    def _make_hold(self, **source):
        s = self.settings
        return make_hold(s.block_len, cusum_h=s.hold_h, window_blocks=s.hold_window,
                         max_blocks=s.hold_max_blocks, backend=s.backend, **source)

    def _apply_calibration(self, cal):
        if self._temp_on:
            if cal.temp_c is None:
                raise SettingsError("setting temp_coefficient_dps_per_c needs the calibration's temperature (temp_c), "
                                    "and this calibration has none (its samples came without temperatures): "
                                    "calibrate again from a source with temperatures")
            self._temp_ref = cal.temp_c
        self._bias = tuple(float(b) for b in cal.bias_dps)
        if not self._adaptive:  # paper 001's initial Q and R: the variance of a block mean of the calibration's white noise
            self._pkf.start(cal.noise_std_dps)
        self._cal_buf = None
        self._cal_temp = None


def _check_calibration_argument(calibration, calibration_s):
    """``calibration=`` is None, a Calibration or the path of a saved one (str or os.PathLike: an
    int would be read as a file descriptor, and closed), and comes without an explicit
    ``calibration_s`` (it replaces the start-up calibration); else SettingsError."""
    if calibration is None:
        return
    if not isinstance(calibration, (Calibration, str, os.PathLike)):
        raise SettingsError(f"calibration must be a Calibration or the path of a saved one (str or os.PathLike), "
                            f"got {type(calibration).__name__}")
    if calibration_s is not None:
        shown = "the calibration" if isinstance(calibration, Calibration) else f"calibration {calibration}"
        raise SettingsError(f"{shown} replaces the start-up calibration, so a calibration window "
                            f"(calibration_s={_shown(calibration_s)}) has nothing to do; give one of them")


def _check_calibration_rate(cal, sample_rate_hz, name):
    """Refuse a calibration made at another sample rate: its per-sample noise (which starts Q, R
    and the guard) scales with sqrt(f_s) for white noise, and the sensor's low-pass filter
    differs with the rate. Within 5 % (a logger's rate drifts around its nominal one) it stands."""
    if abs(cal.sample_rate_hz - sample_rate_hz) > RATE_TOLERANCE * sample_rate_hz:
        raise SettingsError(f"{name} was made at {cal.sample_rate_hz:g} Hz and this filter runs at "
                            f"{sample_rate_hz:g} Hz, more than {RATE_TOLERANCE:.0%} apart: its noise level "
                            "does not hold at another rate; calibrate at this rate")


def _sample3(sample):
    """One sample for update() as a tuple of 3 floats (deg/s); SampleError names what is wrong.

    A sample is a tuple, list or array of shape (3,) of numbers (no bools, no set or dict: they
    have no order), each finite and within +-MAX_RATE_DPS (:func:`gyrofilter.inputs.check_number`).
    Checked before the sample touches any state, so a refused sample leaves the filter as it was.
    """
    if type(sample) is tuple and len(sample) == 3:  # the common case, kept cheap (NaN fails every comparison)
        x, y, z = sample
        m = MAX_RATE_DPS
        if type(x) is float and type(y) is float and type(z) is float and -m <= x <= m and -m <= y <= m and -m <= z <= m:
            return sample
    if isinstance(sample, np.ndarray) and sample.shape == (3,) or isinstance(sample, (tuple, list)) and len(sample) == 3:
        x, y, z = sample.tolist() if isinstance(sample, np.ndarray) else sample
        m = MAX_RATE_DPS
        if (type(x) in _PLAIN and type(y) in _PLAIN and type(z) in _PLAIN  # ints, numpy numbers, a list or an array row
                and -m <= x <= m and -m <= y <= m and -m <= z <= m):
            return float(x), float(y), float(z)
        error = partial(SampleError, where=_UPDATE_TAKES)  # any other or refused: check_number says why
        return tuple(check_number(v, f"g{axis} (deg/s)", low=-MAX_RATE_DPS, high=MAX_RATE_DPS, error=error)
                     for axis, v in zip(AXES, sample))
    raise SampleError(f"got {_shown(sample)}", where=_UPDATE_TAKES)


_UPDATE_TAKES = f"update() takes one sample (gx, gy, gz): 3 finite numbers in deg/s within +-{MAX_RATE_DPS:g}"


_REAL = (int, float, np.integer, np.floating)
_BOOL = (bool, np.bool_)
_PLAIN = frozenset((int, float, np.float64, np.float32, np.int64, np.int32))  # update()'s quick check


def _samples(samples_dps):
    """The samples for filter(): an (N, 3) float array, each finite and within +-MAX_RATE_DPS
    (deg/s), checked in one pass; SampleError names the first refused row (``.row``)."""
    x = _numbers(samples_dps, "samples_dps", "deg/s")
    if x.ndim != 2 or x.shape[1] != 3:
        raise SampleError(f"samples_dps must have shape (N, 3), got {x.shape}")
    return check_rates_dps(x, "samples_dps")


def _numbers(values, name, unit):
    """``values`` as a float array when they are numbers (ints or floats: no strings, bools,
    objects or ragged lists), else SampleError naming ``name``."""
    try:
        x = np.asarray(values)
    except (ValueError, TypeError):  # a ragged list
        raise SampleError(f"{name} must be an array of numbers in {unit}, got {_shown(values)}") from None
    if x.dtype.kind not in "iuf":
        raise SampleError(f"{name} must be numbers in {unit}, got an array of {x.dtype}")
    return x.astype(float, copy=False)


def _temperature(value, required, where, row=0):
    """A sample's temperature as a float in TEMP_RANGE_C (deg C), or NaN when it has
    none (None or NaN), which ``required`` (compensating) refuses; SampleError says why."""
    if value is None or isinstance(value, (float, np.floating)) and math.isnan(value):
        if required:
            raise SampleError("temperature compensation is on: it needs temp_c, a temperature (deg C), with every sample",
                              row, where)
        return math.nan
    return check_number(value, "temp_c (deg C)", low=TEMP_RANGE_C[0], high=TEMP_RANGE_C[1],
                        error=partial(SampleError, row=row, where=where))


def _is_number(value):
    """Whether ``value`` is an int or float (numpy's too), not a bool."""
    return isinstance(value, _REAL) and not isinstance(value, _BOOL)


def _shown(value):
    """A short, plain text of a user's value for an error message."""
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape}"
    text = plain(value)
    return text if len(text) <= 80 else text[:77] + "..."
