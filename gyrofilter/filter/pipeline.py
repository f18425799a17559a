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
from dataclasses import asdict

import numpy as np

from . import adaptive_kalman, kalman
from .hold import SIGMA_B_FLOOR_DPS, block_noise_std, make_hold
from .averaging import AVERAGERS, average_block_line_if_cut, average_blocks_line_if_cut
from .calibration import Calibration, calibrate, calibration_samples, noise_calibration_samples, without_gross_errors
from ..errors import CalibrationError, FilterDiverged, SampleError, SettingsError
from ..inputs import check_number, did_you_mean
from ..recording.checks import first_step_back
from .presets import DEFAULT_PRESET, PRESETS
from .samples import as_numbers, check_sample, check_samples, check_temperature
from .settings import MAX_CALIBRATION_SAMPLES, SETTING_NAMES, FilterSettings
from .tempcomp import compensate
from .threshold import RangeThreshold
from ..tempscreen import TEMP_MEDIAN_SAMPLES, latest_median, running_medians, temperature_history
from ..units import MAX_RATE_DPS, RATE_TOLERANCE, TEMP_RANGE_C, check_sample_rate_hz, plain, rounding, shown


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

    One stream, one thread at a time: the filter is the running state of one stream of samples in
    time order, without a lock (it would cost every sample); two threads feeding one filter
    interleave their samples and lose counter updates, without an error. A second stream or
    thread gets a filter of its own (``GyroFilter(rate_hz, calibration=f.calibration)`` starts it
    with the first's calibration).

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
            raise SettingsError(f"unknown preset {shown(preset)}; choose one of {', '.join(PRESETS)}")
        unknown = sorted(set(settings) - set(SETTING_NAMES))
        if unknown:
            named = [f"{u}{did_you_mean(u, SETTING_NAMES)}" for u in unknown]
            raise SettingsError(f"unknown setting(s) {', '.join(named)}; known: {', '.join(SETTING_NAMES)}")
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
        self._temp_seen = temperature_history()  # the latest temperatures: T is their running median
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
        self._threshold = RangeThreshold(s.outlier_q_dps, s.outlier_range_k, s.outlier_range_blocks)
        self.rejected = np.zeros(3, dtype=np.int64)
        self.fallback_blocks = np.zeros(3, dtype=np.int64)
        self.blocks_out = 0
        self.samples_in = 0  # every sample fed to update() or filter(), calibration included
        self._t_last_s = None  # the last time given to filter_timed (s)
        self.calibration = None
        self._bias = (0.0, 0.0, 0.0)
        self._rounding = np.zeros(3)  # units.rounding of the bias: block means within it are 0
        self._cal_needed = calibration_samples(self.sample_rate_hz, s.calibration_s)
        if calibration is None and s.calibration_s > 0:
            noise_calibration_samples(self.sample_rate_hz, s.calibration_s)
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
        A row beyond the rates any gyro reads raises :class:`~gyrofilter.errors.FilterDiverged`
        (:func:`_check_rows`), the sample taken.
        """
        sample = check_sample(sample)
        if temp_c is not None or self._temp_on:
            temp_c = check_temperature(temp_c, self._temp_on, "update()")
        row = self._update(sample, temp_c)
        if row is not None and not (-_MAX_ROW_DPS <= row[0] <= _MAX_ROW_DPS and -_MAX_ROW_DPS <= row[1] <= _MAX_ROW_DPS
                                    and -_MAX_ROW_DPS <= row[2] <= _MAX_ROW_DPS):  # (NaN fails each)
            _check_rows(self, np.array([row]), self.samples_in - 1)
        return row

    def _update(self, sample, temp_c):
        """:meth:`update` of the checked ``sample`` and ``temp_c``, its row unchecked."""
        self.samples_in += 1
        if self._cal_buf is not None:
            self._cal_buf[self._cal_fill] = sample
            self._cal_temp[self._cal_fill] = math.nan if temp_c is None else temp_c
            self._cal_fill += 1
            if self._cal_fill == self._cal_needed:
                self._finish_calibration()
            return None
        if self._temp_on:
            c, dt = self._temp_coef, latest_median(self._temp_seen, temp_c, self._temp_ref) - self._temp_ref
            sample = (sample[0] - c[0] * dt, sample[1] - c[1] * dt, sample[2] - c[2] * dt)
        block = self._block
        block.append(sample)
        if len(block) < self.settings.block_len:
            return None
        self._block = []
        columns = list(zip(*block))
        q = self._threshold.one(columns)
        y1 = self._y1
        modes = self._akf.modes() if self._by_model else None
        for a, values in enumerate(columns):
            paper = mean, rejected, fallback = self._average_one(values, q[a])
            if self._by_model:  # both rules' block means: the kernel takes one by its model (a smoother logs both)
                motion_mean, motion_rejected, _ = average_block_line_if_cut(values, q[a], paper)
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
        return self._filter(check_samples(samples_dps), temp_c)

    def _filter(self, x, temp_c):
        """:meth:`filter` of the checked samples ``x`` (:func:`check_samples`)."""
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
            row = self._update(tuple(x[i].tolist()), None if temps is None else float(temps[i]))
            i += 1
            if row is not None:
                outputs.append(np.array([row]))
        if self._temp_on and i < len(x):
            x = compensate(x[i:], running_medians(self._temp_seen, temps[i:], self._temp_ref), self._temp_coef, self._temp_ref)
            i = 0
        length = self.settings.block_len
        n_blocks = (len(x) - i) // length
        if n_blocks:
            blocks = x[i : i + n_blocks * length].reshape(n_blocks, length, 3)
            q = self._threshold.many(blocks)
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
        rows = np.concatenate(outputs)
        _check_rows(self, rows)
        return rows

    def filter_timed(self, samples_dps, t_s, temp_c=None):
        """:meth:`filter` with time stamps: returns ``(t_rows_s, rows)``.

        ``t_s`` (N,) are the times of the N samples (s, any origin); ``rows`` (M, 3) are what
        ``filter(samples_dps, temp_c)`` returns and ``t_rows_s`` (M,) the time of each row's
        block's last input sample. A row comes out when that sample goes in, so it is always one
        of this call's samples, whatever the chunking. Times must be finite (SampleError names
        the first that is not, and the filter is left as it was) and not float16: its 11
        significant bits space the times 1 ms apart from 1 s on, 1 s from 1024 s and 32 s near its
        largest, 65504 s, so the stamps of a 100-Hz record collapse onto each other within seconds
        (refused, not up-cast: the stamps are already rounded; float64 keeps them, float32's 24 bits
        to 1 ms from 8192 s on, 1 s from 8.4e6 s: epoch times repeat, refused as below, saying so).
        Times increase strictly, as a recording's ``t`` does
        (:func:`~gyrofilter.recording.checks.first_step_back`), also from the last time of the
        previous call of this method: a repeated or decreasing time is refused (SampleError naming
        its row, the filter left as it was), since the rows' times would repeat or go back.
        """
        x = check_samples(samples_dps)
        t = as_numbers(t_s, "t_s", "s")
        if np.asarray(t_s).dtype == np.float16:
            raise SampleError("t_s is float16, which holds times to 11 significant bits (1 s apart from 1024 s "
                              "on); give them as float64 (or float32)")
        if t.shape != (len(x),):
            raise SampleError(f"t_s must have shape ({len(x)},), one time per sample, got {t.shape}")
        finite = np.isfinite(t)
        if not finite.all():
            row = int(np.flatnonzero(~finite)[0])
            raise SampleError(f"t_s must be finite (s), got {t[row]!r}", row, f"t_s row {row}")
        before = t[:0] if self._t_last_s is None else np.array([self._t_last_s])
        row = first_step_back(np.diff(np.concatenate((before, t))))
        if row is not None:
            row += 1 - len(before)
            earlier = f"row {row - 1}'s {float(t[row - 1])!r}" if row > 0 else \
                f"{self._t_last_s!r}, the last time of the previous call"
            why = "" if np.asarray(t_s).dtype != np.float32 else \
                (f"; t_s is float32, whose 24 significant bits space times {float(np.spacing(np.float32(t[row]))):g} s "
                 "apart here: give them as float64")
            raise SampleError(f"t_s must increase strictly (s), got {float(t[row])!r} after {earlier}{why}",
                              row, f"t_s row {row}")
        blocks_out = self.blocks_out
        try:
            rows = self._filter(x, temp_c)
        except FilterDiverged as exc:  # every sample taken: the good rows' times too
            self._t_last_s = float(t[-1])
            exc.t_rows_s = t[self.block_end_indices(self.blocks_out - blocks_out)[:len(exc.rows)] - (self.samples_in - len(x))]
            raise
        if len(t):
            self._t_last_s = float(t[-1])
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
        t = as_numbers(temp_c, "temp_c", "deg C")
        if t.shape != (n,):
            raise SampleError(f"temp_c must have shape ({n},), one temperature per sample, got {t.shape}")
        ok = (t >= TEMP_RANGE_C[0]) & (t <= TEMP_RANGE_C[1])
        if not self._temp_on:
            ok |= np.isnan(t)
        if not ok.all():
            row = int(np.flatnonzero(~ok)[0])
            check_temperature(float(t[row]), self._temp_on, f"temp_c row {row}", row)
        return t

    def _track(self, y, out, y_motion=None, used=adaptive_kalman.NO_USED):
        """Block means y (M, 3) -> output (M, 3): the tracker, then the hold stage if enabled.
        ``y_motion``, ``used``: the adaptive filter's (adaptive_kalman.run_blocks_adaptive). A block mean less than the
        bias's float64 rounding from it (``units.rounding``, 16 spacings: 6e-14 deg/s at 20 deg/s) is 0: a stuck
        axis reading the bias and the float after it is filtered to 0, not to rounding (7e-16 deg/s, which the
        analyses took for noise, attack pass 60)."""
        for means in (y, y_motion):
            if means is not None:
                np.copyto(means, 0.0, where=np.abs(means) <= self._rounding)
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
                            max_bias_dps=s.max_bias_dps, temp_c=temps, outlier_q_dps=s.outlier_q_dps)
        except CalibrationError:
            self._cal_fill = 0  # the window is dropped: the next sample starts a new one
            if self._cal_tries_left <= 0:
                raise
            self._cal_tries_left -= 1
            return
        self.calibration = cal
        window = without_gross_errors(self._cal_buf, s.outlier_q_dps, in_place=True)[0]  # as the calibration measured it
        self._threshold.seed(window, s.block_len)
        self._start_kalman(block_noise_std(window, s.block_len), still_blocks=self._cal_needed // s.block_len)
        if s.hold:
            # the window passed the stillness check: start holding, sigma_b from its block means
            self._hold = self._make_hold(calibration_window_dps=window)
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
            if self._cal_temp is not None:  # the window's latest temperatures start the running median
                self._temp_seen.extend(self._cal_temp[-TEMP_MEDIAN_SAMPLES:].tolist())
        self._bias = tuple(float(b) for b in cal.bias_dps)
        self._rounding = rounding(np.asarray(self._bias))
        if not self._adaptive:  # paper 001's initial Q and R: the variance of a block mean of the calibration's white noise
            self._pkf.start(cal.noise_std_dps)
        self._cal_buf = None
        self._cal_temp = None


#: the greatest rate a row may have: MAX_RATE_DPS, and the filter's arithmetic on samples at it (5e-8 deg/s past it,
#: the paper's filter); within 1e-5 deg/s past it, a row written (FILTERED_FORMAT, 9 digits) reads back within it
_MAX_ROW_DPS = MAX_RATE_DPS * (1 + 1e-10)


def _check_rows(filt, rows, end=None):
    """Raise :class:`~gyrofilter.errors.FilterDiverged` at the first of the rows ``rows`` (M, 3) of the filter
    ``filt`` with a value beyond +-MAX_RATE_DPS deg/s (:data:`_MAX_ROW_DPS`) or not finite (``end``: the index of
    the one row's block's last sample; else they are its latest rows): a filter that diverged (the paper's on fast
    motion, attack pass 68) gave rates no gyro reads, which every output refuses (a recording's check,
    :mod:`gyrofilter.recording.checks`) but a stream would have passed on. One vectorised pass over the rows."""
    bad = ~(np.abs(rows) <= _MAX_ROW_DPS)
    if not bad.any():
        return
    row, axis = (int(v) for v in np.argwhere(bad)[0])
    advice = (f"; preset {filt.preset!r} is the paper's filter, which does not follow fast motion: the default preset "
              f"({DEFAULT_PRESET!r}) does" if filt.preset == "paper" else "")
    raise FilterDiverged(f"the filter's output left the rates any gyro reads: its row {filt.blocks_out - len(rows) + row} "
                         f"has g{'xyz'[axis]} {float(rows[row, axis]):.9g} deg/s, beyond +-{MAX_RATE_DPS:g} deg/s{advice}",
                         rows[:row], int(filt.block_end_indices(len(rows))[row] if end is None else end), rows)


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
        named = "the calibration" if isinstance(calibration, Calibration) else f"calibration {calibration}"
        raise SettingsError(f"{named} replaces the start-up calibration, so a calibration window "
                            f"(calibration_s={shown(calibration_s)}) has nothing to do; give one of them")


def _check_calibration_rate(cal, sample_rate_hz, name):
    """Refuse a calibration made at another sample rate: its per-sample noise (which starts Q, R
    and the guard) scales with sqrt(f_s) for white noise, and the sensor's low-pass filter
    differs with the rate. Within 5 % (a logger's rate drifts around its nominal one) it stands."""
    if abs(cal.sample_rate_hz - sample_rate_hz) > RATE_TOLERANCE * sample_rate_hz:
        raise SettingsError(f"{name} was made at {cal.sample_rate_hz:g} Hz and this filter runs at "
                            f"{sample_rate_hz:g} Hz, more than {RATE_TOLERANCE:.0%} apart: its noise level "
                            "does not hold at another rate; calibrate at this rate")
