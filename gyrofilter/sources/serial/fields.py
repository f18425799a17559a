"""The serial line protocol's header words, the units they (or the source options) give, those that name the
fields of a line (or, without them, the fields its width implies) and the accelerometer's units, and the ranges a
line's values must lie in (:mod:`gyrofilter.sources.serial.protocol`, whose module docstring states the protocol)."""
from __future__ import annotations

import re

import numpy as np

from ...errors import DeviceError, SettingsError
from ...inputs import check_number, is_plain_number, parse_number, quote
from ...recording import ACCEL_COLUMNS, GYRO_COLUMNS, format_number, misspelt_key, name_words, units_header
from ...units import (ACCEL_UNITS, GYRO_UNITS, MAX_ACCEL_MPS2, MAX_RATE_DPS, TEMP_RANGE_C, check_lsb_per_dps,
                      check_lsb_per_g, check_sample_rate_hz, to_dps, to_mps2)
from ..mpu6050.chip import temperature_c

HEADER_PREFIX = b"# gyrofilter-serial:"
PROTOCOL_VERSION = "1"
_HEADER_KEY = re.compile(r"[A-Za-z0-9_]+")
_PRINTABLE = bytes(range(0x20, 0x7F)) + b"\t"

class UnitsConflict(DeviceError):
    """The device's header disagrees with the units already in use (options or an earlier header).
    ``rows``: the rows of the lines before it in the bytes fed with it (the samples received in
    the units in use, for the caller to keep: :meth:`.protocol.LineParser.feed`)."""

    rows = None


def temp_unit_raw(values, where, in_use):
    """Whether the header's ``temp_unit`` word (``c``, the default, or ``mpu6050_raw``) says TEMP_OUT counts
    (T = raw / 340 + 36.53 deg C, register map rev 4.2 section 4.18); DeviceError for another word.
    ``in_use``: the reading of the samples with a temperature made so far (None: none yet); a header that
    changes it is :class:`UnitsConflict`, as one changing the gyro's units: a restarted device's banner without
    the first one's ``temp_unit`` read the temperatures after it in the other unit, 30 deg C then 36.6 in one
    column, without a word (attack pass 37g)."""
    unit = values.get("temp_unit", "c")
    if unit not in ("c", "mpu6050_raw"):
        raise DeviceError(f"{where}: temp_unit {quote(unit, 40)} is not c or mpu6050_raw")
    if in_use is not None and in_use != (unit == "mpu6050_raw"):
        raise UnitsConflict(f"{where}: the device's header changed temp_unit mid-stream "
                            f"({'mpu6050_raw' if in_use else 'c'} -> {unit}); start a new recording")
    return unit == "mpu6050_raw"


#: the fields a line may hold, in any order given by the header's ``fields=``
KNOWN_FIELDS = ("counter", *GYRO_COLUMNS, "temp", *ACCEL_COLUMNS)


def inferred_fields(width):
    """The fields of a line of ``width`` values when no header names them: ``counter,gx,gy,gz`` (4) or
    ``counter,gx,gy,gz,temp`` (5); None for any other width."""
    return ["counter", *GYRO_COLUMNS] + (["temp"] if width == 5 else []) if width in (4, 5) else None


def header_words(line, where):
    """The ``key=value`` words of a header ``line`` (bytes, from :data:`HEADER_PREFIX`) as a dict;
    DeviceError naming ``where`` for anything else."""
    if line.translate(None, _PRINTABLE):
        raise DeviceError(f"{where}: the header line holds bytes that are not printable ASCII")
    text = line[len(HEADER_PREFIX):].decode("ascii").split()
    if not text or text[0] != PROTOCOL_VERSION:
        raise DeviceError(f"{where}: unsupported serial protocol version {quote(text[0] if text else '', 20)} "
                          f"(this reader speaks {PROTOCOL_VERSION})")
    values = {}
    for word in text[1:]:
        key, eq, value = word.partition("=")
        if not eq or not _HEADER_KEY.fullmatch(key) or not value:
            raise DeviceError(f"{where}: header word {quote(word, 40)} is not key=value "
                              "(a key of letters, digits and _, a value)")
        if key in values:
            raise DeviceError(f"{where}: the header gives {key} twice")
        values[key] = value
    return values


#: the protocol's own keys, beside the recording header's that a device may send (:func:`meant_key`)
PROTOCOL_KEYS = ("fields", "counter_bits", "temp_unit", "accel_unit", "lsb_per_g")
# the words (recording.name_words) of a device's key that name what a protocol key states (meant_key)
_FIELD_WORDS = frozenset({"field", "fields", "order", "column", "columns", "cols", "axes", "axis", "layout", "names",
                          "fmt", "format", "remap", "map", "mapping", "orientation"})
_AXIS_WORDS = frozenset({"swap", "invert", "inverted", "flip", "sign", "signs", "mirror"})  # swap_xy=1, invert_z=1
_COUNTER_WORDS = frozenset({"counter", "count", "cnt", "cntr", "ctr", "seq", "sequence", "idx", "index", "wrap",
                            "rollover"})
_WIDTH_WORDS = frozenset({"bits", "bit", "bytes", "byte", "width", "size", "len", "length", "max", "modulo", "modulus",
                          "mod", "wrap", "wraps", "rollover", "type", "range", "limit", "period"})
_TEMP_UNIT_WORDS = frozenset({"unit", "units", "scale", "fmt", "format", "raw", "mode", "type"})
_TEMP_UNIT_VALUES = frozenset({"c", "f", "k", "raw", "celsius", "degc", "fahrenheit", "kelvin", "counts", "lsb"})


def meant_key(key, value):
    """The key gyrofilter reads that a device's header word ``key=value`` means but spells otherwise, or None.

    Kept as a descriptive key it would change nothing, without a word (attack passes 51, 52): ``field=`` or
    ``field_names=counter,gz,gy,gx`` left the default field order (x and z swapped), ``temprature_unit=mpu6050_raw``
    read raw counts as deg C, ``count_bits=8`` or ``seq_bits=8`` left a byte counter's wrap read as a restart. So a
    word means

    - a key gyrofilter reads (or of :data:`PROTOCOL_KEYS`) spelt otherwise (:func:`~gyrofilter.recording.misspelt_key`);
    - ``fields`` when its value lists ``gx``, ``gy`` and ``gz``, or ``x``, ``y`` and ``z`` (``columns=counter;gz;gy;gx``,
      ``names=counter,gyro_z,gyro_y,gyro_x``, ``remap=zyx``), or its key has a word of a line's layout
      (:data:`_FIELD_WORDS`: ``axis_order=zyx``) and its value is not a number (``mag_field_ut=50`` is the device's
      own), or a word of an axis's swap or sign (``swap_xy=1``, ``invert_z=1``: the fields are the device's as sent);
    - ``temp_unit`` when its value is ``mpu6050_raw``, or its key has a word of a temperature (``t``, ``temp...``,
      ``tmp``) and a word of a unit (:data:`_TEMP_UNIT_WORDS`: ``t_unit``, ``temp_raw``, ``temprature_unit``) or
      a unit's value (``temp=raw``);
    - ``counter_bits`` when its key has a word of a counter and one of its width (``seq_bits``, ``counter_max``,
      ``counter_type``).

    A digit in the key makes it another sensor's (``temp2_unit``), and other descriptive keys stay the device's own
    (``temp_offset``, ``sample_count``, ``temp_sensor``, ``adc_bits``).
    """
    meant = misspelt_key(key, also=PROTOCOL_KEYS)
    if meant is not None or key in PROTOCOL_KEYS:
        return meant
    listed = set(name_words(value.lower()))  # gyro_z,gyro_y,gyro_x; seq,z,y,x; zyx
    if {"gx", "gy", "gz"} <= listed or {"x", "y", "z"} <= listed or sorted(value.lower()) == ["x", "y", "z"]:
        return "fields"
    if value.lower() == "mpu6050_raw":
        return "temp_unit"
    words = set(name_words(key))
    if any(c.isdigit() for c in key):
        return None
    if any(w == "t" or w.startswith(("tem", "tmp")) for w in words) and (
            words & _TEMP_UNIT_WORDS or value.lower() in _TEMP_UNIT_VALUES):
        return "temp_unit"
    if words & _FIELD_WORDS and not is_plain_number(value) or words & _AXIS_WORDS:
        return "fields"
    return "counter_bits" if words & _COUNTER_WORDS and words & _WIDTH_WORDS else None


def make_units(values, where):
    """Checked recording-header units from header words (text: DeviceError for a bad value) or source options
    (numbers: SettingsError), messages naming ``where``."""
    unit = values.get("gyro_unit")
    if unit is None:
        raise SettingsError(f"{where}: gyro unit missing (a header's gyro_unit=dps|rad/s|lsb, or the source option "
                            "unit=dps|rad/s|lsb)")
    if unit not in GYRO_UNITS:
        raise SettingsError(f"{where}: gyro_unit {quote(unit)} is not one of {', '.join(GYRO_UNITS)}")
    sample_rate_hz = _positive(values, "sample_rate_hz", where, "rate=HZ")
    lsb_per_dps = None
    if unit == "lsb" or values.get("lsb_per_dps") is not None:  # checked whenever given: a header keeps it
        lsb_per_dps = _positive(values, "lsb_per_dps", where, "gyro_unit lsb needs lsb_per_dps")
    if unit != "lsb":
        lsb_per_dps = None
    return units_header(sample_rate_hz, unit, lsb_per_dps)


def _positive(values, key, where, hint):
    """``values[key]`` (header text or an option's number) as a positive number (a float): a sample rate within
    :func:`gyrofilter.units.check_sample_rate_hz`'s range, an ``lsb_per_dps`` within
    :func:`gyrofilter.units.check_lsb_per_dps`'s."""
    value = values.get(key)
    if value is None:
        raise SettingsError(f"{where}: {key} missing ({hint})")
    what = f"{where}: {key}"
    error = DeviceError if isinstance(value, str) else SettingsError
    number = (parse_number(value, what, error=error) if isinstance(value, str)
              else check_number(value, what, error=error))
    if key == "sample_rate_hz":
        number = check_sample_rate_hz(number, what, error)
    else:
        number = check_lsb_per_dps(number, what, error)
    return float(number)


def in_range(values, fields, header, temp_raw):
    """Mask of the lines of ``values`` (per line, in ``fields`` order; units of the recording
    ``header``) within the ranges: each gyro value within +-MAX_RATE_DPS once in deg/s, a temperature
    in TEMP_RANGE_C once in deg C (``temp_raw``: TEMP_OUT, converted), an accelerometer value within
    +-MAX_ACCEL_MPS2 once in m/s^2. No sensor reads beyond, and the recording would refuse it."""
    gyro = values[:, [fields.index(name) for name in GYRO_COLUMNS]]
    lsb_per_dps, lsb_per_g = header.get("lsb_per_dps"), header.get("lsb_per_g")
    with np.errstate(over="ignore"):  # 1e308 rad/s: inf deg/s, refused
        ok = (np.abs(to_dps(gyro, header["gyro_unit"], lsb_per_dps and float(lsb_per_dps))) <= MAX_RATE_DPS).all(axis=1)
        if "temp" in fields:
            temp = values[:, fields.index("temp")]
            temp_c = temperature_c(temp) if temp_raw else temp
            ok &= (temp_c >= TEMP_RANGE_C[0]) & (temp_c <= TEMP_RANGE_C[1])
        if ACCEL_COLUMNS[0] in fields:  # 1e300 g: written, the recording would end at it
            accel = values[:, [fields.index(name) for name in ACCEL_COLUMNS]]
            ok &= (np.abs(to_mps2(accel, header["accel_unit"], lsb_per_g and float(lsb_per_g)))
                   <= MAX_ACCEL_MPS2).all(axis=1)
    return ok


def parse_fields(text, where):
    """The header's ``fields=`` word ``text`` as a list of field names (checked: known names, the three gyro
    fields, none twice, the accelerometer's all or none); DeviceError naming ``where`` otherwise."""
    fields = [f.strip() for f in text.split(",")]
    for f in fields:
        if f not in KNOWN_FIELDS:
            raise DeviceError(f"{where}: unknown field {f!r} in fields={text} (known: {', '.join(KNOWN_FIELDS)})")
    for f in GYRO_COLUMNS:
        if f not in fields:
            raise DeviceError(f"{where}: fields={text} lacks {f}")
    if len(set(fields)) != len(fields):
        raise DeviceError(f"{where}: fields={text} names a field twice")
    accel = [f for f in ACCEL_COLUMNS if f in fields]
    if accel and len(accel) < len(ACCEL_COLUMNS):
        raise DeviceError(f"{where}: fields={text} names {', '.join(accel)} but not "
                          f"{', '.join(f for f in ACCEL_COLUMNS if f not in accel)}: the accelerometer is all of "
                          f"{', '.join(ACCEL_COLUMNS)} or none")
    return fields


#: the note of a header's accelerometer units where its fields name no accelerometer (:func:`accel_units`)
ACCEL_IGNORED_NOTE = "serial: the device's header gives accel_unit but its fields name no accelerometer (ax, ay, az): ignored"


def accel_units(values, fields, where):
    """The header's ``accel_unit`` and ``lsb_per_g`` words (checked; {} when not given) for a
    stream whose ``fields`` (None: not known yet, the width's, never the accelerometer) name the accelerometer or
    not: the unit is required with the accelerometer fields, ``lsb_per_g`` (> 0) with ``lsb``. DeviceError
    otherwise. {} too for a stream without those fields (a six-axis firmware with its accelerometer off): units
    of no column, which a recording refuses (attack pass 37g: `record` exited 2 on such a device, naming the
    recording's line); the caller notes them ignored (:data:`ACCEL_IGNORED_NOTE`)."""
    if "accel_unit" not in values:
        if fields is not None and ACCEL_COLUMNS[0] in fields:
            raise DeviceError(f"{where}: fields name {', '.join(ACCEL_COLUMNS)} but the header gives no accel_unit "
                              f"({', '.join(ACCEL_UNITS)})")
        if "lsb_per_g" in values:
            raise DeviceError(f"{where}: the header gives lsb_per_g without accel_unit=lsb")
        return {}
    unit = values["accel_unit"]
    if unit not in ACCEL_UNITS:
        raise DeviceError(f"{where}: accel_unit {quote(unit, 40)} is not one of {', '.join(ACCEL_UNITS)}")
    units = {"accel_unit": unit}
    if unit != "lsb":
        if "lsb_per_g" in values:
            raise DeviceError(f"{where}: the header gives lsb_per_g with accel_unit={unit}: it belongs to lsb only")
    elif "lsb_per_g" not in values:
        raise DeviceError(f"{where}: accel_unit=lsb needs lsb_per_g (LSB per g, e.g. 16384 for an MPU6050 at +-2 g)")
    else:
        what = f"{where}: header line: lsb_per_g"
        units["lsb_per_g"] = format_number(check_lsb_per_g(parse_number(values["lsb_per_g"], what, low=0, low_open=True,
                                                                        error=DeviceError), what, DeviceError))
    return units if fields is not None and ACCEL_COLUMNS[0] in fields else {}


def other_keys_note(previous, header, first, unit_keys, samples, noted):
    """The note of a repeated header (a dict of the recording header's keys) whose keys other than
    the ``unit_keys`` (``sensor``, ``dlpf_cfg``, ...) differ from the ``previous`` one's, or None:
    the samples keep their units, so the stream goes on, and the recording's header keeps the
    ``first`` header's; the note says what the device said, after how many ``samples``, and what
    the recording's header holds (a units change is refused instead: the parser's ``_apply``).
    ``noted``: (changes noted so far, the most noted); beyond it, that changes go unnoted from
    here (later ones were dropped without a word: the last note's ``sensor=`` read as the
    device's to the end)."""
    other = [k for k in dict.fromkeys([*previous, *header]) if k not in unit_keys]
    changed = [k for k in other if previous.get(k) != header.get(k)]
    if not changed:
        return None
    if noted[0] >= noted[1]:
        return (f"serial: the device's header changed again after sample {samples}; after {noted[1]} such notes, its "
                "changes from here on are not noted")

    def said(values):
        return ", ".join(f"{k}={values[k]}" if k in values else f"no {k}" for k in changed)
    return f"serial: the device's header says {said(header)} after sample {samples} (the recording's header keeps {said(first)})"
