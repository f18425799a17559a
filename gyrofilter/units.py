"""Unit conventions and conversions.

Angular rate is in deg/s (names end in ``_dps``) unless a name says otherwise; times in
seconds (``_s``), rates in hertz (``_hz``), temperatures in degrees Celsius (``_c``).
Arrays of three-axis samples have shape (N, 3), columns x, y, z.
"""
import math
from functools import partial

import numpy as np

from .errors import SampleError, SettingsError
from .inputs import MAX_QUOTE_CHARS, check_number, python_value, scalar

DEG_PER_RAD = 180.0 / math.pi
AXES = ("x", "y", "z")  # the axes of every three-axis array, its columns in this order
MAD_TO_SIGMA = 1.4826  # sigma = 1.4826 MAD for Gaussian data (1 / Phi^-1(3/4); Hampel 1974)
GYRO_UNITS = ("dps", "rad/s", "lsb")
#: the units of a recording's accelerometer columns ``ax, ay, az`` (its header's ``accel_unit``)
ACCEL_UNITS = ("m/s^2", "g", "lsb")
#: standard gravity g_n in m/s^2, exact by definition (3rd CGPM 1901; NIST SP 330, 2019, section 2.3.4):
#: the one value of g that converts an accelerometer's ``g`` and ``lsb`` (LSB per g) to m/s^2
STANDARD_GRAVITY_MPS2 = 9.80665
MAX_SAMPLE_RATE_HZ = 100_000.0  # far above any MEMS gyro (the MPU6050 samples at most at 8 kHz)
#: the plausible temperatures (deg C) of a gyro's die, ends included, for a sample and a calibration:
#: beyond any MEMS part (the MPU6050's TEMP_OUT register spans -60 to +133 deg C)
TEMP_RANGE_C = (-100.0, 200.0)
#: the MPU6050's temperature register (register map section 4.18): T / degC = TEMP_OUT / 340 + 36.53
#: (the device's driver and ``convert --temp-unit mpu6050`` of a log of raw counts)
MPU6050_TEMP_LSB_PER_C = 340.0
MPU6050_TEMP_OFFSET_C = 36.53
#: largest |angular rate| a sample may have (deg/s): 50x the MPU6050's widest full scale (2000 deg/s)
#: and 7x the widest MEMS gyros' (about 14 000 deg/s); it keeps every square the filters take finite
MAX_RATE_DPS = 100_000.0
#: largest |acceleration| a sample of an accelerometer may have (m/s^2; about 1e6 g): far beyond any MEMS
#: accelerometer (the MPU6050 reads +-16 g, high-g parts +-400 g, shock sensors some 1e5 g), and it
#: keeps every square an analysis takes finite (1e308 g read as m/s^2 is inf)
MAX_ACCEL_MPS2 = 1e7
#: smallest noise (deg/s) the analyses take: an axis whose Allan deviation (allan) or standard deviation
#: (arma) stays below it is refused. No gyro is that quiet (a unit error?), and the fits' fourth
#: powers of it stay normal float64 numbers (a noise of 1e-300 deg/s ended in a failed SVD)
MIN_NOISE_DPS = 1e-100
#: float64 spacings within which samples are one value (the rounding of a unit's conversion or of a sum, not noise):
#: a stuck axis reading 19.99 deg/s and the float after it, at random, is stuck (its std 1e-15 gave ratios of 10000x
#: and an N of 1e-16, attack pass 59)
ROUNDING_ULPS = 16


def rounding(value):
    """The float64 rounding of numbers near ``value`` (a number or an array): ``ROUNDING_ULPS * spacing(|value|)``."""
    return ROUNDING_ULPS * np.spacing(np.abs(value))


def one_value(low, high):
    """Whether the values from ``low`` to ``high`` (numbers or arrays: the least and greatest of a series) are one
    value up to float64 rounding: ``high - low <= rounding(max(|low|, |high|))``. The one test of a constant (stuck)
    axis."""
    return high - low <= rounding(np.maximum(np.abs(low), np.abs(high)))


#: one sample per 1000 s: far below any gyro's output (the MPU6050's slowest is 1 kHz / 256 = 3.9 Hz)
#: and below any filter's output rate from it, while 1 / rate and the Allan cluster times stay ordinary
#: floats (a rate of 1e-300 Hz ended in a failed SVD deep in the fit)
MIN_SAMPLE_RATE_HZ = 0.001
#: largest relative difference between two statements of one sample rate: a recording's header and
#: the steps of its t, a saved calibration's and the filter's (a clock drifts around its nominal
#: rate by well under 1 %, not further)
RATE_TOLERANCE = 0.05
#: the LSB per deg/s a gyro's output may have (lsb_per_dps), ends included. MEMS gyros span about 2
#: to 10^4: a 12-bit output at +-2000 deg/s reads 1, the MPU6050 16.4 to 131, a 16-bit part at
#: +-125 deg/s 262, a 32-bit output of a navigation-grade MEMS part (ADIS16495, 0.00625 deg/s over 2^16)
#: 1.05e7. The range keeps a factor of about 10 beyond each end; a number outside it is a unit or typing
#: error (1e308 or 1e-308 LSB per deg/s would read every sample as 0 or as inf deg/s)
LSB_PER_DPS_RANGE = (0.1, 1e8)
#: the LSB per g an accelerometer's output may have (lsb_per_g), ends included. MEMS accelerometers span
#: about 5 to 3e8: a 12-bit output at +-400 g (H3LIS331) reads about 5, the MPU6050 2048 (+-16 g) to
#: 16384 (+-2 g), a 32-bit output of a navigation-grade part (ADIS16495, 0.25 mg over 2^16) 2.6e8. The
#: range keeps a factor of about 10 beyond each end, as :data:`LSB_PER_DPS_RANGE`: 1e-308 LSB per g
#: would read every sample as inf m/s^2
LSB_PER_G_RANGE = (0.5, 3e9)
MAX_DURATION_S = 1e9  # about 32 years: longer than any recording or simulation, short enough for whole sample counts


def check_axes(axes, name="axes"):
    """``axes`` as a tuple of axis letters when it is a non-empty subset of :data:`AXES` without
    repeats, in any order (a string such as ``"xz"`` or a sequence of letters), else SettingsError
    naming ``name``."""
    letters = tuple(axes) if isinstance(axes, (str, tuple, list)) else ()
    if not letters or any(a not in AXES for a in letters) or len(set(letters)) != len(letters):
        raise SettingsError(f"{name} must be a subset of {''.join(AXES)} such as xz, got {plain(axes)}")
    return letters


def check_lsb_per_dps(value, name="lsb_per_dps", error=SettingsError):
    """``value`` as a float when it is LSB per deg/s within :data:`LSB_PER_DPS_RANGE`, else ``error``
    naming ``name`` (the keyword, option or header key, with its file if any): the one check of a
    gyro's scale, for options, headers and models."""
    return _check_scale(value, LSB_PER_DPS_RANGE, "LSB per deg/s", "MEMS gyros span about 2 to 1e4", name, error)


def check_lsb_per_g(value, name="lsb_per_g", error=SettingsError):
    """``value`` as a float when it is LSB per g within :data:`LSB_PER_G_RANGE`, else ``error``
    naming ``name`` (the keyword, option or header key, with its file and line if any): the one
    check of an accelerometer's scale, for headers, options and models."""
    return _check_scale(value, LSB_PER_G_RANGE, "LSB per g", "MEMS accelerometers span about 5 to 3e8", name, error)


def _check_scale(value, bounds, unit, span, name, error):
    """``value`` as a float when it is a number (not a bool) within ``bounds``, else ``error``
    naming ``name``, the ``unit`` and the ``span`` of real parts (a 0-d array: the number it holds,
    :func:`~gyrofilter.inputs.scalar`)."""
    low, high = bounds
    value = scalar(value)
    ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
    try:
        ok = ok and low <= float(value) <= high  # NaN fails the comparison
    except OverflowError:  # an int beyond a float's range
        ok = False
    if not ok:
        raise error(f"{name} must be a number of {unit} in [{low:g}, {high:g}] ({span}), got {plain(value)}")
    return float(value)


def check_sample_rate_hz(value, name="sample_rate_hz", error=SettingsError):
    """``value`` as a float when it is a rate in [MIN_SAMPLE_RATE_HZ, MAX_SAMPLE_RATE_HZ] Hz, else ``error``.

    The one check of a sample rate, used by every module that takes one: a bool, a string, NaN,
    infinity, zero, a negative number, an int beyond a float's range, an implausibly low rate
    (0.001 Hz: 1 / rate overflows the analyses long before zero) or an implausibly high one (which
    would size buffers beyond memory) raises ``error`` (a :class:`~gyrofilter.errors.GyroFilterError` class;
    :class:`~gyrofilter.errors.RecordingError` for a file's header) with a message that names
    ``name`` (the keyword, option or header key, with its file if any) and the value. A 0-d array
    is the number it holds (:func:`~gyrofilter.inputs.scalar`).
    """
    value = scalar(value)
    ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
    if ok:
        try:
            value = float(value)
        except OverflowError:  # an int beyond a float's range
            ok = False
        else:
            ok = math.isfinite(value) and MIN_SAMPLE_RATE_HZ <= value <= MAX_SAMPLE_RATE_HZ
    if not ok:
        raise error(f"{name} must be a number of Hz in [{MIN_SAMPLE_RATE_HZ:g}, {MAX_SAMPLE_RATE_HZ:g}], got {plain(value)}")
    return value


def check_rates_dps(x, what):
    """``x``, an (N, 3) float array of rates in deg/s, when every value is finite and within
    +-MAX_RATE_DPS (one vectorised pass); else :class:`~gyrofilter.errors.SampleError` naming the
    first refused value by row (``.row``) and axis, e.g. "samples_dps row 7: gz (deg/s) must be in
    [-100000, 100000], got 1e+300" (``what`` = "samples_dps")."""
    ok = np.abs(x) <= MAX_RATE_DPS  # False for NaN
    if not ok.all():
        row, axis = (int(i[0]) for i in np.nonzero(~ok))
        check_number(float(x[row, axis]), f"g{AXES[axis]} (deg/s)", low=-MAX_RATE_DPS, high=MAX_RATE_DPS,
                     error=partial(SampleError, row=row, where=f"{what} row {row}"))
    return x


def check_duration_s(value, name="duration_s", error=SettingsError):
    """``value`` as a float when it is a duration in (0, MAX_DURATION_S] s, else ``error`` naming
    ``name``: the one check of a run's length (``--duration``, ``simulate``'s duration), so that
    a sample count stays a finite whole number."""
    return check_number(value, name, low=0.0, low_open=True, high=MAX_DURATION_S, error=error)


def plain(value):
    """``repr(value)`` for error messages, numpy scalars as the plain number they hold.

    numpy 2 writes ``repr(np.float64(14.99))`` as ``np.float64(14.99)``; this gives ``14.99``
    on numpy 1.24 and 2.x alike; lists and tuples element by element. Anything else (a string, an
    array) as ``repr`` writes it, cut to MAX_QUOTE_CHARS characters (with the full length) when
    longer. The one place error messages turn a user's value into text.
    """
    text = repr(python_value(value))
    return text if len(text) <= MAX_QUOTE_CHARS else f"{text[:MAX_QUOTE_CHARS]}... ({len(text)} characters)"


def shown(value):
    """:func:`plain`, but an array by its shape (``an array of shape (4,)``): a user's value that
    may be an array of samples, as an error message shows it."""
    value = scalar(value)  # a 0-d array of numbers is the number it holds
    return f"an array of shape {value.shape}" if isinstance(value, np.ndarray) else plain(value)


def utf8_text(text):
    """``text`` as a file holds it (UTF-8): each lone surrogate, which ``os.fsdecode`` makes of a
    file name's byte that is not UTF-8 (b"\\xff" -> "\\udcff"), written as its escape, the six
    characters ``\\udcff``, which read back as written; any other text unchanged."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return text.encode("utf-8", "backslashreplace").decode("utf-8")
    return text


def json_ready(value):
    """``value`` as ``json.dump(..., allow_nan=False)`` takes it: numpy arrays and scalars as lists
    and numbers, tuples as lists, dict keys as text, text as :func:`utf8_text` makes it, and a
    non-finite number (NaN, +-inf) as None (``null``: the files never hold the non-standard
    NaN/Infinity tokens; docs/formats.md)."""
    if isinstance(value, dict):
        return {utf8_text(str(k)): json_ready(v) for k, v in value.items()}
    if isinstance(value, str):
        return utf8_text(value)
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, (np.generic, np.ndarray)):  # a longdouble's tolist() is itself (it recursed without end)
        return json_ready(python_value(value) if isinstance(value, np.generic) else value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _scaled(converted, values, factor=1.0, divisor=None):
    """``converted`` (``values`` as float64) times ``factor`` or divided by ``divisor``: in place when
    ``converted`` is a copy of its own (``values`` was not float64), else a new array (the caller's
    ``values`` stay as they are). The same numbers either way (one IEEE operation per element)."""
    out = converted if isinstance(values, np.ndarray) and not np.may_share_memory(converted, values) else None
    if divisor is not None:
        return np.divide(converted, divisor, out=out)
    return np.multiply(converted, factor, out=out)


def to_dps(values, unit, lsb_per_dps=None):
    """Convert angular rate ``values`` from ``unit`` ('dps', 'rad/s' or 'lsb') to deg/s;
    ``lsb_per_dps`` (LSB per deg/s, > 0) is needed for 'lsb'. The float64 copy of ``values`` that
    is not float64 (a float32 column) is converted in place (:func:`_scaled`: one array, not two)."""
    converted = np.asarray(values, dtype=float)
    if unit == "dps":
        return converted
    if unit == "rad/s":
        return _scaled(converted, values, DEG_PER_RAD)
    if unit == "lsb":
        return _scaled(converted, values, divisor=_lsb_per_dps(lsb_per_dps))
    raise SettingsError(f"unknown gyro unit {unit!r}; expected one of {', '.join(GYRO_UNITS)}")


def _lsb_per_dps(lsb_per_dps):
    """The scale of :func:`to_dps` and :func:`from_dps` for 'lsb' (:func:`check_lsb_per_dps`: NaN
    made every rate NaN, inf every rate 0 deg/s), or SettingsError; None: the unit needs one."""
    if lsb_per_dps is None:
        raise SettingsError("gyro_unit 'lsb' needs a positive lsb_per_dps, got None")
    return check_lsb_per_dps(lsb_per_dps)


def from_dps(values_dps, unit, lsb_per_dps=None):
    """Inverse of :func:`to_dps`: ``values_dps`` (deg/s) in ``unit``, with ``lsb_per_dps`` for
    'lsb' (no rounding: 'lsb' values come back as floats)."""
    values_dps = np.asarray(values_dps, dtype=float)
    if unit == "dps":
        return values_dps
    if unit == "rad/s":
        return values_dps / DEG_PER_RAD
    if unit == "lsb":
        return values_dps * _lsb_per_dps(lsb_per_dps)
    raise SettingsError(f"unknown gyro unit {unit!r}; expected one of {', '.join(GYRO_UNITS)}")


def to_mps2(values, accel_unit, lsb_per_g=None):
    """Convert acceleration ``values`` from ``accel_unit`` (one of :data:`ACCEL_UNITS`) to m/s^2:
    a = v (``m/s^2``), a = v g_n (``g``), a = v g_n / lsb_per_g (``lsb``), with g_n =
    :data:`STANDARD_GRAVITY_MPS2`; ``lsb_per_g`` (LSB per g, > 0) is needed for 'lsb'. A float64
    copy is converted in place, as :func:`to_dps` does."""
    converted = np.asarray(values, dtype=float)
    if accel_unit == "m/s^2":
        return converted
    if accel_unit == "g":
        return _scaled(converted, values, STANDARD_GRAVITY_MPS2)
    if accel_unit == "lsb":
        if lsb_per_g is None:
            raise SettingsError("accel_unit 'lsb' needs a positive lsb_per_g, got None")
        return _scaled(converted, values, STANDARD_GRAVITY_MPS2 / check_lsb_per_g(lsb_per_g))
    raise SettingsError(f"unknown accelerometer unit {plain(accel_unit)}; expected one of {', '.join(ACCEL_UNITS)}")
