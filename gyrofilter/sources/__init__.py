"""Live sources: an MPU6050 on I2C, a serial stream, a replayed recording, a simulation.

One syntax names every source (``--source SOURCE`` of ``gyrofilter record`` and ``run``)::

    KIND[:ARG][,key=value[,key=value...]][,flag]

    mpu6050[:bus=1,addr=0x68,rate=100,range=250,dlpf=3,temp=1,accel=1,accel_range=2,allow_chip=0x70]
    serial:/dev/ttyUSB0[,baud=115200,unit=lsb,lsb_per_dps=131,rate=100,header_timeout=5]
    replay:FILE[,realtime][,speed=2]          (or just FILE, a .csv/.csv.gz recording)
    sim[:MODEL.json][,seed=1][,realtime=0][,duration=60][,rate=1000]   (or sim:model=MODEL.json,...)

A bare ``/dev/tty...`` is a serial port and a bare existing file or ``*.csv``/``*.csv.gz`` name
is a replay. A path holding commas (``replay:logs/a,b/imu.csv.gz,realtime``) is the longest
comma-joined start that is an existing file; one holding ``=`` (``data/date=2024-01-01/imu.csv.gz``)
is the path when a path separator or a dot comes before its ``=``. Numbers are plain decimals (``gyrofilter.inputs.parse_number``: ``12``, ``0.5``,
``1e3``; no ``nan``, ``inf`` or ``1_000``), whole numbers (``bus``, ``addr``, ``seed``, ...) also
``0x`` hex of at most 8 digits; flags are ``1/0``, ``yes/no``, ``true/false``, ``on/off`` or the
bare key (= true). An unknown key, a key given twice (``addr`` and ``address`` are one key; so are
``sim``'s model and ``model=``), a ``key=`` without a value and a number out of its range are
refused with one line that names the key.

Every opened source is a :class:`gyrofilter.sources.base.Source`:

- ``sample_rate_hz`` (float), ``gyro_unit`` (``dps``, ``rad/s`` or ``lsb``) and ``lsb_per_dps``
  (float with ``lsb``, else None): the units of ``read()``'s rows, as numbers; ``gyro_dps(rows)``
  converts the rows' gyro columns to deg/s;
- ``header``: dict of recording-header keys (text, for the file) (``sample_rate_hz``, ``gyro_unit``, ``lsb_per_dps``
  when the unit is lsb, ``sensor``, ``chip_id``, ``full_scale_dps``, ``dlpf_cfg``,
  ``start_time_utc``, ...);
- ``columns``: names of what ``read()`` returns, starting with ``t`` (sample index / sample
  rate, from the sensor's clock: lost samples show as a jump in ``t``), then ``gx, gy, gz`` in
  the header's ``gyro_unit``, then optional ``temp`` (deg C), then optional ``ax, ay, az`` (all
  three or none; the accelerometer, in the header's ``accel_unit``, with ``lsb_per_g`` when it is
  ``lsb``);
- ``read()``: the rows available now, shape (n, len(columns)); waits at most about 0.1 s;
  shape (0, k) when nothing arrived; raises :class:`gyrofilter.errors.SourceEnded` at the end
  of a finite source (the exception's text says why it ended);
- ``finish()``: at a stop (Ctrl-C), the rows the source held back waiting for more input (a
  serial line whose counter jumped, :meth:`~gyrofilter.sources.serial.protocol.LineParser.finish`),
  as at the end of its stream; none for the others;
- ``pop_notes()``: events since the last call (gaps, restarts), written as annotation lines;
- ``stats``: counters (``samples``, ``lost_samples``, ``garbage_bytes``, ...);
- ``close()`` (also ``with source: ...``).

Device libraries (smbus2, pyserial) are imported only when such a source is opened.
"""
from __future__ import annotations

import os
import re

from ..errors import SettingsError
from ..inputs import check_number, parse_number, quote
from ..units import GYRO_UNITS
from .mpu6050 import driver as mpu6050_driver
from .replay import ReplaySource
from .serial.port import SerialSource, written_files
from .simulated import SimulatedSource

__all__ = ["open_source", "parse_source", "source_outputs", "SOURCE_HELP", "KINDS"]

SOURCE_HELP = (
    "SOURCE is KIND[:ARG][,key=value...]: "
    "mpu6050[:bus=1,addr=0x68,rate=100,range=250,dlpf=3,temp=1,accel=1,accel_range=2,allow_chip=0x70] | "
    "serial:/dev/ttyUSB0[,baud=115200,unit=lsb,lsb_per_dps=131,rate=100,header_timeout=5] | "
    "replay:FILE[,realtime][,speed=1] (or just FILE) | "
    "sim[:MODEL.json][,seed=1,realtime=1,duration=S,rate=HZ] (default: an MPU6050-like model)"
)


MAX_HEX_DIGITS = 8


def _int(low=None, high=None):
    """A parser of a whole number (plain decimal, or ``0x`` hex of at most 8 digits) in [low, high]."""
    def parse(text, what):
        if re.fullmatch(r"0[xX][0-9a-fA-F]{1,%d}" % MAX_HEX_DIGITS, text):
            return check_number(int(text, 16), what, low=low, high=high, integer=True)
        return parse_number(text, what, low=low, high=high, integer=True)
    return parse


def _float(text, what):
    return parse_number(text, what)


def _bool(text, what):
    low = text.lower()
    if low in ("1", "yes", "true", "on"):
        return True
    if low in ("0", "no", "false", "off"):
        return False
    raise SettingsError(f"{what} must be 1/0, yes/no, true/false or on/off, got {quote(text, 40)}")


def _unit(text, what):
    if text not in GYRO_UNITS:
        raise SettingsError(f"{what} must be one of {', '.join(GYRO_UNITS)}, got {quote(text, 40)}")
    return text


def _text(text, what):
    return text


# kind -> (what the positional argument is or None, {key: (parser, keyword name, description)}).
# A parser takes (value text, what to call it in a message) and raises SettingsError. Numbers are
# plain decimals (gyrofilter.inputs.parse_number; whole numbers also 0x hex); the openers check
# the ranges of what they take (rates, baud, timeouts, seeds, durations), the bounds here are the
# ones no opener checks.
KINDS = {
    "mpu6050": (None, {
        "bus": (_int(0, 65535), "bus", "I2C bus number N of /dev/i2c-N"),
        "addr": (_int(0, 0x7F), "address", "I2C address, 0x68 or 0x69"),
        "address": (_int(0, 0x7F), "address", "same as addr"),
        "rate": (_float, "sample_rate_hz", "sample rate in Hz"),
        "range": (_int(), "range_dps", "full scale in deg/s: 250, 500, 1000 or 2000"),
        "dlpf": (_int(0, 7), "dlpf", "DLPF_CFG 0..6 (CONFIG register bits 2:0)"),
        "temp": (_bool, "temperature", "read the temperature too (1/0)"),
        "accel": (_bool, "accel", "read the accelerometer too (1/0; default 1)"),
        "accel_range": (_int(), "accel_range_g", "accelerometer full scale in g: 2, 4, 8 or 16"),
        "allow_chip": (_int(0, 0xFF), "allow_chip", "accept this WHO_AM_I value (a relative or clone)"),
    }),
    "serial": ("port", {
        "baud": (_int(), "baudrate", "baud rate"),
        "unit": (_unit, "gyro_unit", "gyro unit if the device sends no header: dps, rad/s or lsb"),
        "lsb_per_dps": (_float, "lsb_per_dps", "LSB per deg/s if unit=lsb"),
        "rate": (_float, "sample_rate_hz", "sample rate in Hz if the device sends no header"),
        "header_timeout": (_float, "header_timeout_s", "seconds to wait for the device's header line"),
    }),
    "replay": ("path", {
        "realtime": (_bool, "realtime", "deliver samples at the recording's pace"),
        "speed": (_float, "speed", "pace factor with realtime (2 = twice as fast)"),
    }),
    "sim": ("model", {
        "model": (_text, "model", "the simulator model (JSON file; a gap report's extended_model is used)"),
        "seed": (_int(), "seed", "random seed"),
        "realtime": (_bool, "realtime", "deliver samples at the model's pace (default 1)"),
        "duration": (_float, "duration_s", "end after this many seconds of samples"),
        "rate": (_float, "sample_rate_hz", "sample rate in Hz (overrides the model's)"),
    }),
}
_SYNTAX = "SOURCE is KIND[:ARG][,key=value...], KIND one of mpu6050, serial, replay, sim"
_ALIASES = {"mpu": "mpu6050", "simulate": "sim", "simulation": "sim", "file": "replay"}


def parse_source(spec: str):
    """Split a SOURCE text into ``(kind, keyword arguments)`` for the source's opener.

    ``spec``: the SOURCE text (``KIND[:ARG][,key=value...]``, a bare ``/dev/tty...`` port or a
    bare recording file name; see the module docstring). Returns ``(kind, kwargs)``: ``kind`` is
    one of :data:`KINDS` (aliases such as ``mpu`` or ``file`` resolved) and ``kwargs`` maps the
    opener's keyword names (``address``, ``sample_rate_hz``, ``path``, ...) to parsed values, in the
    units of the :data:`KINDS` table (rates in Hz, ranges in deg/s, times in s). Nothing is
    opened. Raises :class:`gyrofilter.errors.SettingsError` naming the bad kind, key or value.

    >>> parse_source("mpu6050:bus=1,addr=0x69,rate=200")
    ('mpu6050', {'bus': 1, 'address': 105, 'sample_rate_hz': 200.0})
    >>> parse_source("replay:rec.csv.gz,realtime")
    ('replay', {'path': 'rec.csv.gz', 'realtime': True})
    >>> parse_source("sim,seed=3")
    ('sim', {'seed': 3})
    """
    if not isinstance(spec, str):
        raise SettingsError(f"a source is text ({_SYNTAX}), got {type(spec).__name__}")
    if not spec.strip():
        raise SettingsError(f"empty source ({_SYNTAX})")
    spec = spec.strip()
    where = f"source {quote(spec)}"
    cut = min((i for i in (spec.find(":"), spec.find(",")) if i >= 0), default=len(spec))
    head, sep, rest = spec[:cut], spec[cut : cut + 1], spec[cut + 1 :]  # KIND ends at the first ':' or ','
    kind = _ALIASES.get(head.lower(), head.lower())
    if kind not in KINDS:
        # no known KIND prefix: a bare device or file name
        first = ",".join(spec.split(",")[:_path_items(spec.split(","))])
        if first.startswith("/dev/tty") or first.startswith("/dev/serial"):
            kind, rest = "serial", spec
        elif os.path.exists(first) or first.endswith((".csv", ".csv.gz", ".gz")):
            kind, rest = "replay", spec
        elif sep:
            raise SettingsError(f"{where}: unknown kind {quote(head, 40)} ({_SYNTAX})")
        else:
            raise SettingsError(f"{where}: no such file, and not a kind ({_SYNTAX})")
    positional_name, keys = KINDS[kind]
    kwargs = {}
    given = {}  # keyword name -> the key (or the positional) that gave it
    items = rest.split(",") if rest else []
    if positional_name is not None and _path_items(items) > 1:  # a file whose path holds commas: taken whole
        kwargs[positional_name] = ",".join(items[:_path_items(items)]).strip()
        given[positional_name] = f"the {positional_name}"
        items = [""] + items[_path_items(items):]
    for index, item in enumerate(items):
        item = item.strip()
        if not item:
            continue
        key, eq, value = item.partition("=")
        key, value = key.strip().lower(), value.strip()
        if index == 0 and positional_name is not None and (os.path.isfile(item) or key not in keys and (not eq or _names_a_file(item, key))):
            kwargs[positional_name] = item
            given[positional_name] = f"the {positional_name}"
            continue
        if key not in keys:
            known = ", ".join(keys)
            if not eq and positional_name is not None:
                raise SettingsError(f"{where}: {quote(item, 40)} is not a key of {kind} (known: {known}); "
                                    f"the {positional_name} comes first, right after '{kind}:'")
            raise SettingsError(f"{where}: unknown key {quote(key, 40)} for {kind} (known: {known})")
        parser, name, description = keys[key]
        if name in given:
            raise SettingsError(f"{where}: key {key!r} repeats {given[name]}: give it once")
        if not eq and parser is not _bool:
            raise SettingsError(f"{where}: key {key!r} needs a value ({key}=..., {description})")
        if eq and not value:
            raise SettingsError(f"{where}: key {key!r} has an empty value ({key}=..., {description})")
        try:
            kwargs[name] = parser(value, f"key {key!r}") if eq else True
        except SettingsError as exc:
            raise SettingsError(f"{where}: {exc}") from None
        given[name] = f"key {key!r}"
    if kind in ("serial", "replay") and positional_name not in kwargs:
        raise SettingsError(f"{where}: {kind} needs a {positional_name} ({_SYNTAX})")
    return kind, kwargs


#: why a kind of source takes no unit or rate from a command-line option (see :func:`open_source`)
_OWN_UNITS = {
    "mpu6050": "an MPU6050 reads in LSB, range= sets the LSB per deg/s",
    "replay": "a replayed recording's header gives its sample rate and units",
    "sim": "the simulator model gives the units",
}


def source_outputs(spec: str):
    """The files opening SOURCE ``spec`` writes (a serial ``spy://`` URL's ``file=``:
    :func:`~gyrofilter.sources.serial.port.written_files`): outputs of the command that reads it."""
    kind, kwargs = parse_source(spec)
    return written_files(kwargs["port"]) if kind == "serial" else []


def open_source(spec: str, *, options=None, **defaults):
    """Open the source named by ``spec`` (see the module docstring).

    ``spec``: the SOURCE text, parsed by :func:`parse_source`. ``defaults`` fill keyword
    arguments the spec does not give, where that kind of source accepts them (for example
    ``gyro_unit`` and ``sample_rate_hz`` (Hz) from command-line options for a serial device that
    sends no header); others, and ``None`` values, are ignored. ``options`` names the
    command-line option that gave a default (keyword name -> option, e.g. ``{"sample_rate_hz":
    "--sample-rate-hz"}``): such a default is refused instead of ignored, with one line naming
    the option, when this kind of source cannot take it (an MPU6050's unit, a replayed file's
    rate: its header rules) or when the spec gives it too; an opener's refusal of its value names
    the option.

    Returns the opened :class:`gyrofilter.sources.base.Source` (an MPU6050Source, SerialSource,
    ReplaySource or SimulatedSource); close it, or use it in a ``with`` block. Raises
    :class:`gyrofilter.errors.SettingsError` for a bad spec.
    """
    kind, kwargs = parse_source(spec)
    spec = spec.strip()
    keys = {name: key for key, (_, name, _) in reversed(KINDS[kind][1].items())}  # keyword -> its (first) key
    named = {name: key for name, key in keys.items() if re.search(rf"(^|[,:])\s*{key}\s*=", spec, re.IGNORECASE)}
    for name, value in defaults.items():
        if value is None:
            continue
        option = (options or {}).get(name)
        if option is not None and name not in keys:
            raise SettingsError(f"{option} does not apply to source {quote(spec)}: {_OWN_UNITS[kind]}; drop the option")
        if option is not None and name in kwargs:
            raise SettingsError(f"{option} and the key {keys[name]!r} of source {quote(spec)} give the same "
                                "setting: give it once")
        if name in keys and name not in kwargs:
            kwargs[name] = value
            if option is not None:
                named[name] = option
    try:
        return _open(kind, kwargs)
    except SettingsError as exc:
        raise SettingsError(_in_source_terms(str(exc), spec, named)) from None


def _in_source_terms(message, spec, named):
    """An opener's SettingsError in the terms of the SOURCE text and the options: prefixed with
    the text, and each keyword name in ``named`` replaced by the key or option that gave it
    (``sample_rate_hz`` -> ``rate`` or ``--sample-rate-hz``)."""
    for name, key in named.items():
        if name != key:
            message = re.sub(rf"\b{name}\b", key, message)
    return message if message.startswith("source ") else f"source {quote(spec)}: {message}"


def _open(kind, kwargs):
    if kind == "mpu6050":
        return mpu6050_driver.open_mpu6050(**kwargs)
    if kind == "serial":
        return SerialSource(**kwargs)
    if kind == "replay":
        return ReplaySource(**kwargs)
    return SimulatedSource(**kwargs)


def _path_items(items):
    """How many of the comma-separated ``items`` of a SOURCE make up the path it starts with: the
    most whose comma-joined text is an existing file (``replay:logs/a,b/imu.csv.gz,realtime``: the
    file ``logs/a,b/imu.csv.gz``), else 1."""
    return max((k for k in range(2, len(items) + 1) if os.path.isfile(",".join(items[:k]).strip())), default=1)


def _names_a_file(item, key):
    """Whether the first item of a SOURCE, holding ``=`` before which is no key (``key``), is the
    positional file itself: a path with ``=`` in a folder's name (``data/date=2024-01-01/imu.csv.gz``,
    as partitioned folders are named) or a file that exists. A key never holds a path separator
    or a dot, so a mistyped key (``sed=1``) is still refused as one."""
    return any(c in key for c in (os.sep, os.altsep or os.sep, ".")) or os.path.exists(item)
