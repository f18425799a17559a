"""What a header key, a serial device's word or a log's comment states of the sample rate, the gyro's unit or
sensitivity, or the accelerometer's unit, by its words (:func:`~gyrofilter.recording.header.name_words`), and
whether its value states the same as the header (:func:`judge`): the one rule behind
:func:`~gyrofilter.recording.header.contradiction` and ``convert``'s comments
(:mod:`~gyrofilter.recording.foreign.comments`). Pure: words and text in, a kind or a verdict out.

A value is read as people write it (attack pass 55): quotes, a ``~``, a closing ``.`` or ``;``, a remark in
brackets or after ``#`` aside (``"200"``, ``~200 Hz``, ``200 Hz (nominal)``, ``200 # set in firmware``); a rate
in Hz, kHz, ``sps``, ``/s`` or samples per second; a period in s, ms, us (``µs``) or ns, one that would mean a
rate outside :data:`~gyrofilter.units.MIN_SAMPLE_RATE_HZ` .. :data:`~gyrofilter.units.MAX_SAMPLE_RATE_HZ` being
a time stamp (``ts: 1700000000``), not a period; a unit among other words (``units: s, deg/s, g``), none named
being no statement (``unit: IMU-07``, ``units: SI``); a number with a unit of deg/s, or after ``±``, a full
scale (``gyro_scale: ±2000 dps``), not a unit or a sensitivity.
"""
from __future__ import annotations

import re

from ..inputs import is_plain_number
from ..units import MAX_SAMPLE_RATE_HZ, MIN_SAMPLE_RATE_HZ
from .unit_words import known_unit

#: what a key states, by its words: a key of only a kind's words and at least one of its own states the sample rate
#: (``sample_rate``, ``rate_hz``, ``odr``, ``imu_rate``, ``samplerate``, ``logging_rate``, ``sensor_odr``), the
#: sample period (``dt``, ``sample_period_ms``, ``Ts``), the gyro's unit (``unit``, ``gyro_scale``, ``rate_unit``;
#: also ``gyro: rad/s``, a value that is a unit), its sensitivity (``lsb_per_deg``, ``gyro_sensitivity``,
#: ``scale_factor``: a number) or the accelerometer's unit (``acc_unit``). ``gyro_output_rate_hz`` (the chip's own),
#: ``cutoff_hz``, ``baud_rate``, ``rate_dps`` and ``gyro_rate`` (a rate of turn) are none of them; a sample rate
#: may name the gyro (``Gyro sample rate``)
STATES = {  # kind: (the other words its key may hold, its own words)
    "rate": ({"sample", "samples", "data", "output", "update", "imu", "khz", "logging", "log", "acquisition", "polling",
              "nominal", "sensor", "in", "target", "actual"},
             {"rate", "samplerate", "odr", "fs", "sps", "sampling", "frequency", "freq", "hz"}),
    "period": ({"sample", "sampling", "time", "s", "sec", "ms", "us", "ns", "in", "nominal", "logging", "log"},
               {"period", "interval", "dt", "ts"}),
    "unit": ({"gyro", "gyr", "gyroscope", "rate", "angular", "velocity", "omega", "measurement", "rotation", "turn"},
             {"unit", "units", "scale"}),
    "sensitivity": ({"gyro", "gyr", "per", "dps", "deg", "degree", "degrees", "s", "factor"}, {"lsb", "sensitivity", "scale"}),
    "accel_unit": ({"acc", "accel", "accelerometer", "acceleration"}, {"unit", "units", "scale"}),
}
_SAMPLING = {"sample", "samples", "sampling", "odr"}
_SECONDS = {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "μs": 1e-6, "ns": 1e-9}
_RATE_SUFFIXES = {"", "hz", "khz", "sps", "samples/s", "s/s", "/s", "1/s", "samples/sec", "samplespersecond", "persecond",
                  "hertz"}
#: a number as it opens a value: a sign of range or of about (``±``, ``+-``, ``~``) before it
_NUMBER = re.compile(r"\s*(?P<range>±|\+-|\+/-)?\s*[~≈]?\s*(?P<number>[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)(?P<rest>.*)")
#: a key's unit in brackets at its end (``Sample rate (samples/s)``, ``Sample period [µs]``)
_BRACKETED = re.compile(r"(?P<key>.*?)\s*[(\[](?P<unit>[^()\[\]]*)[)\]]\s*")


def key_unit(key, value):
    """``(key, value)`` with a unit in brackets at the key's end moved to a value that is a number alone
    (``Sample rate (Hz): 200``: ``Sample rate``, ``200 Hz``)."""
    bracketed = _BRACKETED.fullmatch(key)
    if not bracketed or not bracketed["key"]:
        return key, value
    return bracketed["key"], f"{value} {bracketed['unit']}" if is_plain_number(clean(value)) else value


def stated_kind(words, value):
    """The kind of :data:`STATES` a key of ``words`` (a set) with ``value`` states, the most telling, or None."""
    gyro = {"gyro", "gyroscope"} if words & _SAMPLING else set()  # Gyro sample rate
    kinds = [kind for kind, (others, own) in STATES.items()
             if words & own and words <= others | own | (gyro if kind == "rate" else set())]
    if words <= set().union(*STATES["unit"]) and known_unit("rate", value):
        kinds.insert(0, "unit")  # gyro: rad/s
    if not words & STATES["accel_unit"][0]:
        kinds = [kind for kind in kinds if kind != "accel_unit"]
    if _NUMBER.match(clean(value)):  # gyro_scale: 131, a sensitivity (pass 54); ±2000 dps, a full scale
        kinds = [kind for kind in kinds if kind not in ("unit", "accel_unit")]
    return kinds[0] if kinds else None


def clean(value):
    """``value`` without quotes, a ``~`` or a closing ``.``, ``;`` or ``,``, a remark in brackets at its end or after
    ``#`` or ``//``: ``"200"``, ``200 Hz (nominal)``, ``200 # set in firmware`` read ``200``, ``200 Hz``."""
    value = re.split(r"\s(?:#|//)", value)[0].strip().strip("\"'{}[] ")
    value = re.sub(r"\s+\([^()]*\)$", "", value)
    return value.rstrip(".;, ").strip("\"' ")


def judge(kind, words, value, facts, rates, tolerance):
    """``(the key of ``facts`` (a header's text values) that a key of kind ``kind`` and ``words`` stating ``value``
    contradicts, what the value does not read as or None)``, or None where it states the same or nothing: a rate in
    Hz (``khz`` in the key or the value in thousands) within ``tolerance`` (relative) of one of ``rates``, a period of
    one over it, the unit (:func:`~gyrofilter.recording.unit_words.known_unit`), ``lsb_per_dps`` (where ``gyro_unit``
    is lsb; the value may end in a unit of deg/s), ``accel_unit`` (where the header has one)."""
    value = clean(value)
    number = _NUMBER.fullmatch(value)
    amount = float(number["number"]) if number and is_plain_number(number["number"]) else None
    suffix = re.sub(r"\s+", "", number["rest"]).lower() if number else ""
    if kind == "rate":
        if amount is None or suffix not in _RATE_SUFFIXES:
            return "sample_rate_hz", "a rate (Hz)"
        stated = amount * (1000 if "khz" in words or suffix == "khz" else 1)
        return None if any(abs(stated - r) <= tolerance * r for r in rates) else ("sample_rate_hz", None)
    if kind == "period":
        if not amount or suffix not in ("", *_SECONDS):
            return None
        stated = 1.0 / (amount * (_SECONDS.get(suffix) or next((_SECONDS[w] for w in ("ms", "us", "ns") if w in words), 1.0)))
        if not MIN_SAMPLE_RATE_HZ <= stated <= MAX_SAMPLE_RATE_HZ:
            return None  # a time stamp (ts: 1700000000), not a period
        return None if any(abs(stated - r) <= tolerance * r for r in rates) else ("sample_rate_hz", None)
    if kind == "sensitivity":
        if facts["gyro_unit"] != "lsb" or number and (number["range"] or known_unit("rate", suffix)):
            return None  # gyro_scale: ±2000 dps, a full scale
        per_dps = suffix == "" or "dps" in suffix or "deg" in suffix.replace("°", "deg")  # 131 LSB/(deg/s)
        if amount is None or not per_dps:
            return "lsb_per_dps", "a sensitivity (LSB per deg/s)"
        return None if amount == float(facts["lsb_per_dps"]) else ("lsb_per_dps", None)
    key, quantity = ("gyro_unit", "rate") if kind == "unit" else ("accel_unit", "accel")
    if key not in facts:
        return None
    named = {known_unit(quantity, value)} | {known_unit(quantity, word) for word in re.split(r"[\s,;()]+", value)}
    named.discard(None)
    return None if not named or facts[key] in named else (key, None)
