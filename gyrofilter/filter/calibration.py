"""Start-up bias calibration with a stillness check (paper 001, section 2.1).

Paper 001: keep the sensor still after power-up, record the zero-rate output for a while, take
the mean per axis and subtract it from every later sample:

    b = (1/n) * sum_{i=1..n} x_i                                                     (001, 2.1)

A wrong bias is worse than none, so the window is checked before it is accepted. Under
stillness the window is a constant plus noise. The check, per axis:

0. Gross errors (paper 001's single-sample spikes of more than 200 LSB) are found by the rule of
   the block averaging (section 2.2), over the whole window and centred on its median, which one
   spike cannot move:

       c = median(x),  s = 1.4826 median|x_i - c|,  x_i is a gross error when |x_i - c| > max(q, 6 s)

   (q: the filter's ``outlier_q_dps``, 1 deg/s; 6 s keeps the noise of a sensor noisier than q).
   Each is replaced by the mean of the axis's other samples before anything below is computed, so
   the bias is the mean of the samples that are not gross errors and a spike neither moves it nor
   raises the noise (its differences that touch a gross error are left out too);
   ``Calibration.rejected`` counts them. An axis with more than :data:`MAX_GROSS_FRACTION` (10 %)
   of its samples beyond the limit is refused: that is motion (a turn) or a faulty sensor, not a few
   spikes (a sensor with 4 % spikes holds more than 10 % in a 200-sample window with a probability
   of 1e-4). (One spike of 30 deg/s in 2 s at 100 Hz moved the bias
   by 0.15 deg/s and the noise from 0.05 to 2.1 deg/s before; the stillness statistic below scales
   with the same noise, so it let the window pass whatever the spike's size.) A window of fewer
   than 10 samples may leave out none, and the median absolute deviation of so few is a poor scale:
   a still window of 3-9 samples of 0.5 deg/s white noise is refused 6-13 % of the time (2000
   simulated windows each; 0.4 % at 10 samples, none at 40); the refusal says to raise ``calibration_s``.

1. White-noise level from first differences, insensitive to slow changes:
   sigma = std(x[i+1] - x[i]) / sqrt(2).
2. Split the window into ``n_sub`` = min(10, n // 2) equal sub-windows of m samples and take their means
   m_k. Still, each m_k differs from the overall mean by noise of standard deviation about
   sigma / sqrt(m). The statistic is z = max_k |m_k - mean| / (sigma / sqrt(m)); the window
   is refused when z > ``stillness_z`` (default 6: a still white-noise window exceeds it with a
   probability below 1e-7, while a turn of the board shifts some sub-window mean far more).
   A window of 3 samples has nothing to compare and is not checked; fewer than 3 cannot
   measure sigma and are refused (the filters need the noise level).
3. A constant rotation cannot be told from a bias by a gyro alone; a mean beyond
   ``max_bias_dps`` (default :data:`MAX_BIAS_DPS`, 20 deg/s, the MPU6050 datasheet's initial
   zero-rate-output tolerance) is refused as implausible for a bias; so is a noise level sigma
   beyond :data:`MAX_NOISE_STD_DPS` and a mean temperature outside ``units.TEMP_RANGE_C``.

The accepted calibration can be saved to and loaded from a small JSON file so that a device
can skip re-learning (the bias changes between power-ups, so reuse it only for the same run).
A loaded file is held to the limits of a start-up calibration (:meth:`Calibration.load`).
"""
from __future__ import annotations

import datetime as _dt
import json
import math
from dataclasses import dataclass

import numpy as np

from ..errors import CalibrationError, SettingsError
from ..files import write_text_whole
from ..inputs import check_number, load_json, python_value, quote
from ..units import AXES, MAD_TO_SIGMA, MAX_RATE_DPS, TEMP_RANGE_C, check_rates_dps, check_sample_rate_hz, plain, shown
from ..tempscreen import temp_glitches
from .averaging import PAPER_Q_DPS
from .samples import as_numbers


def calibration_samples(sample_rate_hz, calibration_s):
    """Samples in the calibration window: round(``calibration_s`` (s) * ``sample_rate_hz`` (Hz))
    (paper 001 section 2.1: the first seconds of the still sensor give the bias)."""
    return int(round(calibration_s * sample_rate_hz))


def noise_calibration_samples(sample_rate_hz, calibration_s):
    """:func:`calibration_samples` of a calibration that measures the noise as well as the bias:
    SettingsError naming the setting when the window holds fewer than :data:`MIN_SAMPLES` (a
    variance of one sample is NaN, of two hardly a measurement)."""
    c = calibration_samples(sample_rate_hz, calibration_s)
    if c < MIN_SAMPLES:
        raise SettingsError(f"setting calibration_s={plain(calibration_s)} gives {c} sample(s) at "
                            f"{float(sample_rate_hz):g} Hz; the calibration needs at least {MIN_SAMPLES} to measure the noise")
    return c


N_SUB_WINDOWS = 10
NOISE_FLOOR_DPS = 1e-9  # noise scale used for perfectly constant input, where sigma is 0
MAX_BIAS_DPS = 20.0  # the largest plausible bias (deg/s): the MPU6050's initial zero-rate-output tolerance
#: the largest plausible white-noise level (deg/s) of a still sensor, as large as the largest bias: the
#: MPU6050's rate noise is 0.005 deg/s/sqrt(Hz), 0.45 deg/s at its top rate of 8 kHz
MAX_NOISE_STD_DPS = 20.0
MIN_SAMPLES = 3  # fewer samples cannot measure the noise
#: the most samples a calibration window holds: 1e9, beyond an hour (settings.MAX_CALIBRATION_S) at
#: the highest sample rate (units.MAX_SAMPLE_RATE_HZ), 3.6e8
MAX_SAMPLES = 10**9
#: a still window's sample is a gross error beyond max(q, GROSS_ERROR_Z robust sigmas) of its median
GROSS_ERROR_Z = 6.0
#: the most gross errors a still window may hold per axis, as a fraction of its samples (module docstring)
MAX_GROSS_FRACTION = 0.1


@dataclass(frozen=True)
class Calibration:
    """Result of a start-up calibration: bias and white-noise level per axis (deg/s).

    ``temp_c`` is the mean temperature of the window (deg C) when temperatures were given: the
    reference T0 of temperature compensation (gyrofilter.filter.tempcomp), None otherwise.
    ``rejected``: the gross errors per axis that the window's bias and noise leave out (module
    docstring, step 0).
    """

    bias_dps: tuple
    noise_std_dps: tuple
    samples: int
    sample_rate_hz: float
    temp_c: float | None = None
    rejected: tuple = (0, 0, 0)

    def to_json(self) -> str:
        """The calibration as JSON text (docs/formats.md, section 5): only what :meth:`load` reads
        back, held to :meth:`checked` with the widest ``max_bias_dps`` a filter takes (a
        calibration made in code with a NaN bias was written as ``NaN``, not JSON), else
        CalibrationError naming the key."""
        cal = self.checked("calibration to save", max_bias_dps=MAX_RATE_DPS)
        return json.dumps(
            {
                "gyrofilter-calibration": 1,
                "bias_dps": list(cal.bias_dps),
                "noise_std_dps": list(cal.noise_std_dps),
                "samples": cal.samples,
                "sample_rate_hz": cal.sample_rate_hz,
                **({} if cal.temp_c is None else {"temp_c": cal.temp_c}),
                "rejected": list(cal.rejected),
                "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            },
            indent=2, allow_nan=False,
        )

    def save(self, path):
        """Write :meth:`to_json` to the file ``path`` (nothing written when it refuses), whole or
        not at all (:func:`~gyrofilter.files.write_text_whole`: a failed write keeps the file that
        was there)."""
        write_text_whole(path, self.to_json() + "\n")

    def checked(self, where, *, max_bias_dps=MAX_BIAS_DPS) -> "Calibration":
        """This calibration with plain float/int fields, held to the limits of a start-up calibration
        (:func:`calibrate`), or CalibrationError whose message starts with ``where`` and names the key:
        ``bias_dps`` 3 numbers in [-max_bias_dps, max_bias_dps] (the pipeline passes its setting),
        ``noise_std_dps`` 3 numbers in [0, MAX_NOISE_STD_DPS], ``samples`` a whole number in
        [MIN_SAMPLES, MAX_SAMPLES], ``sample_rate_hz`` as :func:`gyrofilter.units.check_sample_rate_hz`
        takes it, ``temp_c`` None or in ``units.TEMP_RANGE_C``, ``rejected`` 3 whole numbers in
        [0, samples]. The one check of a calibration,
        loaded (:meth:`load`) or given in code (``GyroFilter(calibration=...)``)."""
        def number(key, value, **bounds):
            return check_number(value, f"{where}: {key}", error=CalibrationError, **bounds)

        def triple(key, values, **bounds):
            if (not isinstance(values, (list, tuple, np.ndarray)) or isinstance(values, np.ndarray) and values.ndim != 1
                    or len(values) != len(AXES)):
                got = quote(json.dumps(values)) if isinstance(values, (int, float, str, dict)) else shown(values)
                raise CalibrationError(f"{where}: {key} must be a list of 3 numbers (x, y, z), got {got}")
            return tuple(number(f"{key} {axis}", v, **bounds) for axis, v in zip(AXES, values))

        low_c, high_c = TEMP_RANGE_C
        samples = number("samples", self.samples, low=MIN_SAMPLES, high=MAX_SAMPLES, integer=True)
        try:
            bias = triple("bias_dps", self.bias_dps, low=-max_bias_dps, high=max_bias_dps)
        except CalibrationError as exc:  # a real bias beyond the setting: name the value that takes it, as calibrate does
            value = max_bias_needed(self.bias_dps)
            if value is None:
                raise
            raise CalibrationError(f"{exc}; if the bias is real, {raise_max_bias(value)}", value) from None
        return Calibration(
            bias,
            triple("noise_std_dps", self.noise_std_dps, low=0.0, high=MAX_NOISE_STD_DPS),
            samples,
            check_sample_rate_hz(number("sample_rate_hz", self.sample_rate_hz), f"{where}: sample_rate_hz",
                                 CalibrationError),
            None if self.temp_c is None else number("temp_c", self.temp_c, low=low_c, high=high_c),
            triple("rejected", self.rejected, low=0, high=samples, integer=True),
        )

    @classmethod
    def load(cls, path, *, max_bias_dps=MAX_BIAS_DPS) -> "Calibration":
        """Read a calibration saved by :meth:`save` from the file ``path`` (through
        :func:`gyrofilter.inputs.load_json`): its ``gyrofilter-calibration`` key, when present, is
        the integer 1 (the only version); ``rejected`` may be left out (files written before it: none);
        the fields are held to the limits of :meth:`checked`;
        CalibrationError names the file, the key and what is wrong."""
        data = load_json(path, "calibration", CalibrationError)
        if not isinstance(data, dict):
            raise CalibrationError(f"{path}: not a calibration JSON file (expected an object with bias_dps, noise_std_dps, ...)")
        version = data.get("gyrofilter-calibration", 1)
        if type(version) is not int or version != 1:  # 1.0 and true are not 1 either
            raise CalibrationError(f"{path}: gyrofilter-calibration version {quote(json.dumps(version))} is not "
                                   "supported; this gyrofilter reads version 1")
        missing = [k for k in ("bias_dps", "noise_std_dps", "samples", "sample_rate_hz") if k not in data]
        if missing:
            raise CalibrationError(f"{path}: the calibration lacks {', '.join(missing)}")
        fields = (data["bias_dps"], data["noise_std_dps"], data["samples"], data["sample_rate_hz"], data.get("temp_c"),
                  data.get("rejected", (0, 0, 0)))
        return cls(*fields).checked(path, max_bias_dps=max_bias_dps)


def white_noise_std(window_dps, gross=None) -> np.ndarray:
    """sigma = std(x[i+1] - x[i]) / sqrt(2) per axis (deg/s) of ``window_dps``, an (n, 3) window
    in deg/s; 0 below 3 samples. ``gross``: an (n, 3) mask of gross errors (:func:`without_gross_errors`)
    whose differences are left out (0 where fewer than 2 are left)."""
    x = np.asarray(window_dps, dtype=float)
    if len(x) < 3:
        return np.zeros(x.shape[1:])
    if gross is None:
        return np.std(np.diff(x, axis=0), axis=0, ddof=1) / math.sqrt(2.0)
    clean = ~(gross[1:] | gross[:-1])
    return np.array([np.std(np.diff(x[:, a])[clean[:, a]], ddof=1) if clean[:, a].sum() >= 2 else 0.0
                     for a in range(x.shape[1])]) / math.sqrt(2.0)


def gross_error_limits(window_dps, q_dps=PAPER_Q_DPS) -> tuple[np.ndarray, np.ndarray]:
    """(median c, limit) per axis of ``window_dps``, an (n, 3) still window in deg/s: a sample x_i is
    a gross error when |x_i - c| > limit = max(q, GROSS_ERROR_Z * 1.4826 median|x_i - c|), ``q_dps``
    paper 001's threshold q (deg/s; module docstring, step 0)."""
    x = np.asarray(window_dps, dtype=float)
    center, limit = np.empty(x.shape[1]), np.empty(x.shape[1])
    for a in range(x.shape[1]):  # an axis at a time: an hour's window at 1 kHz is 86 MB, a Pi 3 has 1 GB
        center[a] = np.median(x[:, a])
        spread = MAD_TO_SIGMA * np.median(np.abs(x[:, a] - center[a]), overwrite_input=True)
        limit[a] = max(q_dps, GROSS_ERROR_Z * spread)
    return center, limit


def without_gross_errors(window_dps, q_dps=PAPER_Q_DPS, *, in_place=False) -> tuple[np.ndarray, np.ndarray]:
    """(window, gross): ``window_dps`` ((n, 3), deg/s) with each gross error (:func:`gross_error_limits`,
    ``q_dps`` in deg/s) replaced by the mean of its axis's other samples, and the (n, 3) mask of those
    replaced. The window's mean is then the mean of the samples that are not gross errors (module
    docstring, step 0); a copy, the input left as it is, unless ``in_place`` (a float array the caller
    owns and drops: the pipeline's calibration buffer)."""
    x = window_dps if in_place else np.array(window_dps, dtype=float)
    center, limit = gross_error_limits(x, q_dps)
    gross = np.empty(x.shape, dtype=bool)
    for a in range(x.shape[1]):
        gross[:, a] = np.abs(x[:, a] - center[a]) > limit[a]
        if gross[:, a].any():  # never all: at least the median's samples are kept
            x[gross[:, a], a] = x[~gross[:, a], a].mean()
    return x, gross


def stillness_z(window_dps) -> np.ndarray:
    """The stillness statistic z per axis (noise units; see the module docstring) of
    ``window_dps``, an (n, 3) window in deg/s (or (n, k): k axes)."""
    x = np.asarray(window_dps, dtype=float)
    n_sub = min(N_SUB_WINDOWS, len(x) // 2)
    if n_sub < 2:
        return np.zeros(x.shape[1:])
    m = len(x) // n_sub
    sub_means = x[: m * n_sub].reshape(n_sub, m, -1).mean(axis=1)
    spread = np.abs(sub_means - x.mean(axis=0)).max(axis=0)
    scale = np.maximum(white_noise_std(x) / math.sqrt(m), NOISE_FLOOR_DPS)
    return spread / scale


def implausible_bias(axis, mean_dps, *, max_bias_dps=MAX_BIAS_DPS, unit=None):
    """The one rule for a still gyro's mean rate: it is its bias, |b| <= ``max_bias_dps`` (deg/s;
    default :data:`MAX_BIAS_DPS`, the MPU6050 datasheet's +-20 deg/s zero-rate output). Returns
    None for a plausible mean, else the sentence (no final "?") that names the ``axis``, the mean
    (deg/s) and the likely mistake: the sensor turning, or the rates in another unit. ``unit``: the
    unit the file gives (``rad/s``: deg/s numbers labelled rad/s read 180/pi = 57.3 times too large,
    said when the mean / 57.3 is a plausible bias)."""
    if abs(mean_dps) <= max_bias_dps:
        return None
    if unit == "rad/s" and abs(mean_dps) * math.pi / 180.0 <= max_bias_dps:
        likely = f"deg/s written as rad/s: {mean_dps * math.pi / 180.0:.3g} deg/s if the numbers are deg/s"
    else:
        likely = "raw counts read as deg/s, a wrong lsb_per_dps"
    return (f"axis {axis} reads {mean_dps:.3g} deg/s on average, beyond the plausible bias of {max_bias_dps:g} "
            f"deg/s: is the sensor turning, or are the rates in another unit ({likely})")


def max_bias_needed(bias_dps):
    """The value of the filter's setting ``max_bias_dps`` that takes the bias ``bias_dps`` on every axis,
    ceil(max |b|) (deg/s); None when ``bias_dps`` is not 3 finite numbers (not bools; numpy numbers as
    the numbers they hold, :func:`~gyrofilter.inputs.python_value`) that such a
    setting takes (|b| <= MAX_BIAS_RANGE's high), so no way through is offered."""
    bias_dps = python_value(bias_dps.tolist() if isinstance(bias_dps, np.ndarray) else bias_dps)  # numpy numbers too
    if (not isinstance(bias_dps, (list, tuple)) or len(bias_dps) != len(AXES)
            or not all(isinstance(b, (int, float)) and not isinstance(b, bool) for b in bias_dps)):
        return None
    try:
        largest = max(abs(float(b)) for b in bias_dps)
    except OverflowError:  # an integer of 400 digits (a JSON file may hold one)
        return None
    if not math.isfinite(largest) or math.ceil(largest) > MAX_BIAS_RANGE["high"]:
        return None
    return math.ceil(largest)


def raise_max_bias(value):
    """The way through for a real bias beyond ``max_bias_dps``: the words naming the filter's setting and
    ``value`` (:func:`max_bias_needed`), which ``replay`` and ``run`` take with ``--set``."""
    return f"raise the filter's setting max_bias_dps (to {value})"


#: the way through for a sensor that moved in its calibration window, in the words of GyroFilter, replay and run
SAVED_CALIBRATION_WAY = (", or use a saved calibration of this sensor (GyroFilter(calibration=...), --calibration FILE "
                         "from --save-calibration on a still recording)")


def without_settings(exc, instead):
    """The message of the CalibrationError ``exc`` for a command that takes no filter setting and no
    saved calibration (``report``'s filter part, ``evaluate``): its way through a setting
    (:func:`raise_max_bias`) or a saved calibration (:data:`SAVED_CALIBRATION_WAY`), which that command
    would refuse, replaced by ``instead``, words that say why the command does not take it, then the
    commands that do ("replay and run take --set max_bias_dps=26", "--calibration-s" for a window too short to
    leave out a gross error); as it is without one."""
    text = str(exc)
    if exc.max_bias_dps is not None:
        text = text.replace(raise_max_bias(exc.max_bias_dps),
                            f"{instead}; replay and run take --set max_bias_dps={exc.max_bias_dps}")
    text = text.replace(TOO_SHORT_FOR_GROSS_ERRORS, TOO_SHORT_FOR_GROSS_ERRORS.replace("raise calibration_s",
                                                                                      "replay and run take --calibration-s"))
    return text.replace(SAVED_CALIBRATION_WAY, f"; {instead}; replay and run take a saved calibration (--calibration "
                                                "FILE from --save-calibration on a still recording)")


def keep_still(samples, sample_rate_hz):
    """The advice of a window refused as moving: "keep it still for the first T s", T = ``samples`` /
    ``sample_rate_hz`` (Hz) in s, to 0.1 s from 1 s up (2.0 s) and to 2 digits below (0.03 s: a window of 3
    samples at 100 Hz read "0.0 s", attack pass 37h)."""
    seconds = samples / sample_rate_hz
    return f"keep it still for the first {seconds:.1f} s" if seconds >= 1 else f"keep it still for the first {seconds:.2g} s"


#: the way through for a still window too short to leave out one gross error (MAX_GROSS_FRACTION of fewer than
#: 10 samples is none): a longer window
TOO_SHORT_FOR_GROSS_ERRORS = (f"; a window of fewer than {round(1 / MAX_GROSS_FRACTION)} samples can leave out no "
                              "gross error: raise calibration_s")


#: the ranges of :func:`calibrate`'s ``stillness_threshold`` and ``max_bias_dps`` (the settings
#: ``stillness_z`` and ``max_bias_dps``: gyrofilter.filter.settings.SETTING_RANGES reads them here)
STILLNESS_Z_RANGE = dict(low=0, low_open=True, high=1e6)
MAX_BIAS_RANGE = dict(low=0, low_open=True, high=MAX_RATE_DPS)


def calibrate(window_dps, sample_rate_hz, *, stillness_threshold=6.0, max_bias_dps=MAX_BIAS_DPS, temp_c=None,
              outlier_q_dps=PAPER_Q_DPS) -> Calibration:
    """Bias = mean of a still window (paper 001, 2.1) without its gross errors, after the stillness check.

    ``window_dps`` is (n, 3) in deg/s, n >= MIN_SAMPLES (3), numbers (no masked value:
    :func:`~gyrofilter.filter.samples.as_numbers`), each finite and within +-MAX_RATE_DPS
    (:func:`gyrofilter.units.check_rates_dps`), sampled at ``sample_rate_hz`` (Hz);
    ``stillness_threshold``: the largest stillness statistic z accepted (noise units, see
    :func:`stillness_z`); ``max_bias_dps``: the largest plausible bias (deg/s); ``temp_c``
    optionally the window's n temperatures (deg C, shape (n,)), whose mean without its read glitches
    (:func:`gyrofilter.tempscreen.temp_glitches`) is kept, the reference T0; ``outlier_q_dps``:
    paper 001's gross-error threshold q (deg/s), the floor of :func:`gross_error_limits`. Gross errors are
    left out (:func:`without_gross_errors`) before the bias, the noise and the checks. Raises
    CalibrationError naming the axis and the statistic when the window is not still.
    """
    sample_rate_hz = check_sample_rate_hz(sample_rate_hz)  # True was taken as 1 Hz, 0 kept in the calibration
    # NaN passed every window as still, a text ended in numpy's UFuncTypeError
    stillness_threshold = check_number(stillness_threshold, "stillness_threshold", **STILLNESS_Z_RANGE)
    max_bias_dps = check_number(max_bias_dps, "max_bias_dps (deg/s)", **MAX_BIAS_RANGE)
    x = as_numbers(window_dps, "calibration window", "deg/s")  # a masked value is refused, not averaged
    if x.ndim != 2 or x.shape[1] != 3:
        raise SettingsError(f"calibration window must have shape (n, 3), got {x.shape}")
    check_rates_dps(x, "calibration window")  # a NaN would make a NaN bias that passes every test
    if len(x) < MIN_SAMPLES:
        raise SettingsError(
            f"calibration needs at least {MIN_SAMPLES} samples to measure the noise, got {len(x)} "
            f"({len(x) / sample_rate_hz:g} s at {sample_rate_hz:g} Hz); raise calibration_s"
        )
    outlier_q_dps = check_number(outlier_q_dps, "outlier_q_dps (deg/s)", low=0, low_open=True, high=MAX_RATE_DPS)
    bias, sigma, z, rejected = np.empty(3), np.empty(3), np.empty(3), np.empty(3, dtype=int)
    for a in range(3):  # an axis at a time: an hour's window at 1 kHz is 86 MB, a Pi 3 has 1 GB
        kept, gross = without_gross_errors(x[:, a:a + 1], outlier_q_dps)
        bias[a], z[a], rejected[a] = kept.mean(), stillness_z(kept)[0], gross.sum()
        sigma[a] = white_noise_std(x[:, a:a + 1], gross)[0]
    most_rejected = int(MAX_GROSS_FRACTION * len(x))
    for i, axis in enumerate(AXES):
        implausible = implausible_bias(axis, bias[i], max_bias_dps=max_bias_dps)
        if implausible:  # the value named takes every axis: the first's alone (x 20.5: 21) was refused for y (-25.3)
            value = max_bias_needed(bias)
            raise CalibrationError(f"calibration: {implausible}? Keep it still while calibrating, or, if the bias is real, "
                                   f"{raise_max_bias(value)}", value)
        if rejected[i] > most_rejected:
            raise CalibrationError(
                f"calibration: the sensor moved (axis {axis}: {rejected[i]} of {len(x)} samples lie beyond "
                f"{gross_error_limits(x, outlier_q_dps)[1][i]:.3g} deg/s of the window's median, more than the "
                f"{most_rejected} gross errors it may leave out); {keep_still(len(x), sample_rate_hz)}{SAVED_CALIBRATION_WAY}"
                f"{'' if most_rejected else TOO_SHORT_FOR_GROSS_ERRORS}")
        if z[i] > stillness_threshold:
            raise CalibrationError(
                f"calibration: the sensor moved (axis {axis}: sub-window means spread {z[i]:.1f} noise "
                f"units, limit {stillness_threshold:g}); {keep_still(len(x), sample_rate_hz)}{SAVED_CALIBRATION_WAY}")
        if sigma[i] > MAX_NOISE_STD_DPS:
            raise CalibrationError(
                f"calibration: axis {axis} has a noise of {sigma[i]:.3g} deg/s, beyond the {MAX_NOISE_STD_DPS:g} deg/s "
                "plausible for a still sensor"
            )
    low_c, high_c = TEMP_RANGE_C
    if temp_c is not None:
        temp_c = as_numbers(temp_c, "temp_c", "deg C")
        if temp_c.shape != (len(x),):
            raise SettingsError(f"temp_c must have shape ({len(x)},), one temperature per sample, got {temp_c.shape}")
        if np.isfinite(temp_c).all():  # a read glitch (a die's temperature is smooth) would move T0: left out
            temp_c = np.delete(temp_c, temp_glitches(temp_c, sample_rate_hz))
    temp = None if temp_c is None else check_number(
        float(np.mean(temp_c)), "calibration: the mean temperature (deg C)", low=low_c, high=high_c, error=CalibrationError)
    return Calibration(tuple(map(float, bias)), tuple(map(float, sigma)), len(x), float(sample_rate_hz), temp,
                       tuple(map(int, rejected)))
