"""What a header key, a serial device's word or a log's comment states of the sample rate, the gyro's unit or
sensitivity, or the accelerometer's unit or sensitivity, by its words
(:func:`name_words`), and whether its value states the same as the header
(:func:`judge`): the one rule behind :func:`~gyrofilter.recording.header.contradiction` and ``convert``'s comments
(:mod:`~gyrofilter.recording.foreign.comments`). Pure: words and text in, a kind or a verdict out.

A value is read as people write it (attack passes 55, 56): its first number, after quotes, ``~``, ``approx.``,
``about`` or ``±``, and the word right after it (``200 Hz (nominal)``, ``100 Hz, 16 bit``, ``"200"``,
``200/s``); a rate in Hz, kHz, ``sps``, ``/s`` or samples, or a period (``Update rate: 10 ms``); a period in s, ms,
us (``µs``, ``usec``) or ns, one that would mean a rate below 1 Hz or above
:data:`~gyrofilter.units.MAX_SAMPLE_RATE_HZ` being a time stamp (``TS: 1700000000``, ``TS: 512.3``); a rate in deg/s or bps
is a rate of turn or a baud rate, not a sample rate (``Target rate: 100 dps``); a sensitivity in LSB per deg/s or
its inverse (``8.75 mdps/LSB``: 114.29), a number in deg/s or after ``±`` a full scale
(``gyro_scale: ±2000 dps``); a unit among other words (``units: s, deg/s, g``), none named being no statement
(``unit: IMU-07``). A number with a decimal comma (``200,0``) does not read. :func:`pairs` splits a text into its
``key: value`` pairs (``fs=200 Hz; unit=rad/s``, ``Rate: 100 Hz, FS: 2000 dps``, ``settings: fs=200``).
"""
from __future__ import annotations

import decimal
import math
import re
import unicodedata

from ..inputs import is_plain_number
from ..units import MAX_SAMPLE_RATE_HZ
from .unit_words import known_unit

#: what a key states, by its words: a key of only a kind's words and at least one of its own states the sample rate
#: (``sample_rate``, ``rate_hz``, ``odr``, ``imu_rate``, ``samplerate``, ``logging_rate``, ``sensor_odr``), the
#: sample period (``dt``, ``sample_period_ms``, ``Ts``), the gyro's unit (``unit``, ``gyro_scale``, ``rate_unit``;
#: also ``gyro: rad/s``, a value that is a unit), its sensitivity (``lsb_per_deg``, ``gyro_sensitivity``,
#: ``scale_factor``: a number), the accelerometer's unit (``acc_unit``; ``accel: m/s^2``) or sensitivity
#: (``acc_lsb_per_g``). ``gyro_output_rate_hz`` (the chip's own), ``cutoff_hz``, ``baud_rate``, ``rate_dps`` and
#: ``gyro_rate`` (a rate of turn) are none of them; a sample rate may name the gyro (``Gyro sample rate``)
STATES = {  # kind: (the other words its key may hold, its own words)
    "rate": ({"sample", "samples", "data", "output", "update", "imu", "khz", "logging", "log", "acquisition", "polling",
              "nominal", "sensor", "in", "target", "actual", "recording", "publish", "of"},
             {"rate", "samplerate", "odr", "fs", "sps", "sampling", "frequency", "freq", "hz"}),
    "period": ({"sample", "sampling", "time", "s", "sec", "ms", "us", "ns", "in", "nominal", "logging", "log", "of"},
               {"period", "interval", "dt", "ts", "timestep"}),
    "unit": ({"gyro", "gyr", "gyroscope", "rate", "angular", "velocity", "omega", "measurement", "rotation", "turn"},
             {"unit", "units", "scale"}),
    "sensitivity": ({"gyro", "gyr", "per", "dps", "mdps", "deg", "degree", "degrees", "s", "sec", "second", "factor",
                     "typ", "typical", "nominal", "nom"},
                    {"lsb", "sensitivity", "scale"}),
    "accel_unit": ({"acc", "accel", "accelerometer", "acceleration"}, {"unit", "units", "scale"}),
    "accel_sensitivity": ({"acc", "accel", "accelerometer", "acceleration", "per", "g", "mg", "factor", "typ", "typical",
                           "nominal", "nom"},
                          {"lsb", "sensitivity", "scale"}),
}
#: the other words of a key stating the temperature's unit, besides a word of a temperature (:func:`_temperature`)
_TEMP_UNIT_WORDS = ({"die", "imu", "sensor", "chip"}, {"unit", "units", "scale"})
_ACCEL_WORDS = STATES["accel_unit"][0]
_GYRO_WORDS = {"gyro", "gyr", "gyroscope"}
_SAMPLING = {"sample", "samples", "sampling", "odr"}
#: the slowest rate a period states: a longer one is a time stamp (``TS: 512.3``, s since boot), as no gyro samples
#: once a second or slower (convert infers no rate below 5 Hz)
_MIN_PERIOD_RATE_HZ = 1.0
_SECONDS = {"s": 1.0, "sec": 1.0, "secs": 1.0, "second": 1.0, "seconds": 1.0, "ms": 1e-3, "msec": 1e-3, "msecs": 1e-3,
            "millis": 1e-3, "millisecond": 1e-3, "milliseconds": 1e-3, "us": 1e-6, "μs": 1e-6, "usec": 1e-6, "usecs": 1e-6,
            "micros": 1e-6, "microseconds": 1e-6, "ns": 1e-9, "nsec": 1e-9, "nanoseconds": 1e-9}
_RATE_SUFFIXES = {"", "hz", "khz", "sps", "samples/s", "s/s", "/s", "1/s", "samples/sec", "samples", "hertz", "/sec",
                  "/second", "readings/s", "readings/sec", "readings", "samples/second", "readings/second",
                  "samples/second", "sa/s", "s^-1", "s-1", "per"}  # 200 per second, 200 s^-1
#: after a rate's number and word, a time other than the second (``200 per minute``, ``200 samples per ms``)
_PER_OTHER = re.compile(r"\s*(?:per\s+|/\s*)(?:min|minutes?|h|hr|hours?|d|days?|ms|msec|milliseconds?|[uµμ]s|usec)\b",
                        re.IGNORECASE)
#: a second, after ``per`` (``200 per second``)
_SECOND = re.compile(r"\s*(?:s|sec|secs|seconds?)\b", re.IGNORECASE)
#: words in a key's brackets that remark on its value, not its unit
_REMARKS = {"nominal", "approx", "approximately", "typ", "typical", "actual", "measured", "set", "target", "configured",
            "default", "expected", "requested", "nom", "per channel", "per axis"}
#: units any column may be in (a gyro's, an accelerometer's, a temperature's, a counter's): not read in a list of units
_ANY_COLUMNS = {"counts", "raw", "lsb"}
#: deg/s (g) per unit of a sensitivity written inverse, per LSB (``8.75 mdps/LSB``, ``0.000266 rad/s/LSB``, ``0.061 mg/LSB``)
_PER_LSB_SCALES = {"rate": {"dps": 1.0, "mdps": 1e-3, "rad/s": 180.0 / math.pi, "mrad/s": 0.18 / math.pi},
                   "accel": {"g": 1.0, "mg": 1e-3}}
#: a remark in brackets at a value's end that names a filter (``Frequency: 42 Hz (DLPF)``: its cut-off, not a sample rate)
_FILTER_REMARK = re.compile(r"\([^()]*\b(?:dlpf|lpf|low[- ]?pass|cut-?off|bandwidth|bw|filter)\b[^()]*\)\s*$", re.IGNORECASE)
#: a value in Hz (``gyro rate: 200 Hz`` is a sample rate; ``gyro rate: 200`` may be a rate of turn)
_IN_HZ = re.compile(r"\d\s*k?hz\b", re.IGNORECASE)
#: ``per`` between the words of a unit (``radians per second``, ``rad per s``)
_PER_WORD = re.compile(r"\s+per\s+", re.IGNORECASE)
#: a value's first number (a sign of range or about before it) and the word right after it
_NUMBER = re.compile(r"\s*(?:approx\.?|about|ca\.|circa)?\s*(?P<range>±|\+-|\+/-)?\s*[~≈]?\s*"
                     r"(?P<number>(?>[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?))(?![,.]\d)\s*(?P<suffix>[a-zA-Zμ°/^()\d-]*)(?P<rest>.*)")
#: a key's unit in brackets at its end (``Sample rate (samples/s)``, ``Sample period [µs]``, ``Sensitivity (mdps)``)
_BRACKETED = re.compile(r"(?P<key>.*?)\s*[(\[](?P<unit>[^()\[\]]*)[)\]]\s*")
#: the longest key whose words are read for a unit (a key of 20 000 underscores took 29 s, attack pass 65)
_MAX_KEY_CHARS = 256
#: a rate's or an acceleration's unit among a key's words (:func:`name_words`), as a value's: ``deg`` and ``rad`` in a
#: sensitivity are per second (``lsb_per_deg``), so are they with ``s``, ``sec`` or ``per second`` after them
_KEY_UNITS = {"dps": "dps", "mdps": "mdps", "deg": "deg/s", "degree": "deg/s", "degrees": "deg/s", "mdeg": "mdeg/s",
              "rad": "rad/s", "mrad": "mrad/s", "g": "g", "mg": "mg"}
#: an LSB's word (in a key, or a value's unit: ``131 LSB/(deg/s)``, ``7.63 mdps/digit``)
_LSB_IN_KEY = r"(?:lsbs?|counts?|digits?)"
#: a sensitivity's words: a unit alone after one is per LSB (``sensitivity_mdps``: mdps/LSB, a datasheet's
#: ``70 mdps/digit``); after ``scale`` it is the value's own (``gyro_scale_dps: 2000``, a full scale)
_PER_LSB_WORDS = {"sensitivity", "factor"}
#: where a text holds another ``key: value`` pair: at ``;``, at ``,`` before a key and its ``:`` (``Rate: 100 Hz, FS:
#: 2000 dps``); within a value, at ``,`` before ``key=`` too (``Accel: range=2g, sensitivity=16384``: the accelerometer's)
_PIECES = re.compile(r"\s*;\s*|\s*,\s*(?=[\"']?[A-Za-z_][\w.()\[\]/ -]{0,40}?[\"']?\s*(?::=|:))")
_INNER_PIECES = re.compile(r"\s*;\s*|\s*,\s*(?=[\"']?[A-Za-z_][\w.()\[\]/ -]{0,40}?[\"']?\s*(?::=|=>|[:=]))")
#: where a piece may hold another pair: at blanks before ``key=`` (``unit=dps rate=200``); a part that is no pair
#: belongs to the next (``accel sensitivity = 16384``, ``LSB per dps = 65.5``: one key of several words)
_BLANK_PIECES = re.compile(r"\s+(?=[A-Za-z_][\w.]*\s*=)")
#: a piece's ``key: value`` (or ``key = value``, ``:=``, ``=>``), quotes and braces aside
_KEY_VALUE = re.compile(r"\s*[\"'{]*(?P<key>[^:=\"'{}]{1,64}?)[\"'}]*\s*(?::=|=>|[:=])\s*(?P<value>.*?)\s*")


def pairs(text, outer=None):
    """The ``(key, value)`` pairs of ``text`` (a comment's body): split where another pair starts (:data:`_PIECES`),
    a value that holds pairs of its own read too, one level deep (``settings: fs=200 Hz``), its keys named for the
    accelerometer where the ``outer`` key is (``Accel: sensitivity=16384``: ``accel sensitivity``)."""
    found, pieces = [], []
    for piece in (_PIECES if outer is None else _INNER_PIECES).split(text):
        carried, first = "", re.search(r":=|=>|[:=]", piece)
        for part in _BLANK_PIECES.split(piece) if first and first[0] == "=" else [piece]:  # Accel: range=2g, ...
            joined = f"{carried} {part}" if carried else part
            if _KEY_VALUE.fullmatch(joined):
                pieces.append(joined)
            elif _KEY_VALUE.fullmatch(part):  # the words before it are too long for a key: a piece of no pair
                pieces += [carried, part]
            else:
                carried = joined
                continue
            carried = ""
        pieces.append(carried)  # no pair: read as none
    accel = "accel " if outer is not None and _ACCEL_WORDS & set(re.findall(r"[a-z]+", outer.lower())) else ""
    for piece in dict.fromkeys(pieces):
        match = _KEY_VALUE.fullmatch(piece)
        if match and match["value"]:
            found.append((accel + match["key"], match["value"]))
            if outer is None and re.search(r"[:=]", match["value"]):
                found += [p for p in pairs(match["value"], match["key"]) if p != (match["key"], match["value"])]
    return found


def normal_text(text):
    """``text`` as statements are read: NFKC (``ＳａｍｐｌｅＲａｔｅ``: ``SampleRate``), the ordinal ``º`` as ``°`` (NFKC
    makes it an ``o``: ``º/s``), runs of blanks as one (a regular expression over 300 kB of blanks took minutes)."""
    return " ".join(unicodedata.normalize("NFKC", text.replace("º", "°")).split())


def name_words(name):
    """The words of a column name or header key, lower case: its runs of ASCII letters, split where a lower-case
    letter meets an upper-case one (``TimeStamp_ns``: time, stamp, ns; ``Temperature(C)``: temperature, c;
    ``temp2_unit``: temp, unit)."""
    return re.findall(r"[a-z]+", re.sub(r"([a-z])([A-Z])", r"\1 \2", name).lower())


def key_unit(key, value):
    """``(key, value)`` with the unit a key states moved to a value that is a number alone: in brackets at its end
    (``Sample rate (Hz): ~200``: ``Sample rate``, ``~200 Hz``), or a sensitivity's among its words
    (:func:`_sensitivity_words`: ``mdps_per_lsb: 70``, ``sensitivity_mdps: 70``, ``Sensitivity (mdps): 70``:
    ``sensitivity``, ``70 mdps/lsb``). A remark in brackets is dropped (``Sample rate (nominal): 200``)."""
    if len(key) > _MAX_KEY_CHARS:
        return key, value
    bracketed = _BRACKETED.fullmatch(key)
    unit = None
    if bracketed and bracketed["key"]:
        key, unit = bracketed["key"], re.sub(r"\s*/\s*", "/", bracketed["unit"].strip())
        if unit.strip(" .").lower() in _REMARKS:
            unit = None  # Sample rate (nominal): 200, mdps_per_lsb (typ): 70
        elif unit.lower() in _KEY_UNITS:
            key, unit = f"{key} {unit}", None  # Sensitivity (mdps): 70, a unit among its words
    if unit is None:
        key, unit = _sensitivity_words(key)
    number = _NUMBER.fullmatch(clean(value))
    alone = unit and number and not number["suffix"] and not number["rest"].strip()
    return key, f"{clean(value)} {unit}" if alone else value


def _sensitivity_words(key):
    """``(key, unit)``: a sensitivity's unit among ``key``'s words (:func:`name_words`, any separator or case) and the
    key without it, or ``(key, None)``. With an LSB's word it is the way round they are written (``mdps_per_lsb``,
    ``mdps_lsb``, ``mDPS per LSB``: mdps/lsb; ``counts_per_mdps``, ``lsb_dps``: lsb/mdps, lsb/dps; ``per`` before a
    word puts that word under the other: ``per_lsb_mdps`` is mdps/lsb); without, per LSB after a sensitivity's word
    (``sensitivity_mdps``, ``mdps_sensitivity``), the value's own after ``scale`` (``gyro_scale_dps``), else none
    (``rate_dps``: a rate of turn). Attack passes 63 to 65: each spelling not read was read as LSB per deg/s."""
    words, kept, unit, at, lsb = name_words(key), [], None, None, None  # at, lsb: the unit's and LSB's word
    i = 0
    while i < len(words):
        word, after = words[i], words[i + 1:i + 3]
        if word == "m" and after[:1] and "m" + after[0] in _KEY_UNITS:  # mDPS: m, dps
            word, after, skip = "m" + after[0], words[i + 2:i + 4], 1
        else:
            skip = 0
        if unit is None and word in _KEY_UNITS and after[:1] not in (["c"], ["f"], ["celsius"]):  # (deg_c: a temperature's)
            unit, at = _KEY_UNITS[word], i
            skip += 1 if after[:1] in (["s"], ["sec"], ["second"]) else 2 if after[:2] in (
                ["per", "s"], ["per", "sec"], ["per", "second"]) else 0
        elif lsb is None and re.fullmatch(_LSB_IN_KEY, word):
            lsb = i
        elif word not in ("per", "in"):
            kept.append(word)
        i += 1 + skip
    if unit is None:
        return key, None
    if lsb is not None:  # per before a word puts it under the other (per_lsb_mdps: mdps/lsb), else their order does
        under = False if words[lsb - 1:lsb] == ["per"] else True if words[at - 1:at] == ["per"] else lsb < at
        unit = f"lsb/{unit}" if under else f"{unit}/lsb"
    elif set(kept) & _PER_LSB_WORDS:
        unit = f"{unit}/lsb"
    elif "scale" not in kept:
        return key, None
    stem = " ".join(kept) if set(kept) & (_PER_LSB_WORDS | {"scale"}) else " ".join(kept + ["sensitivity"])
    if unit in ("g/lsb", "mg/lsb", "lsb/g", "lsb/mg") and not set(kept) & (_ACCEL_WORDS | _GYRO_WORDS):
        stem = f"accel {stem}"  # lsb_per_g, sensitivity_mg: the accelerometer's
    return stem, unit


def stated_kind(words, value):
    """The kind of :data:`STATES` a key of ``words`` (a set) with ``value`` states, the most telling, or None."""
    gyro = {"gyro", "gyroscope"} if words & _SAMPLING or _IN_HZ.search(value) else set()  # Gyro sample rate, gyro rate: 200 Hz
    kinds = [kind for kind, (others, own) in STATES.items()
             if words & own and words <= others | own | (gyro if kind == "rate" else set())]
    if ({"sample", "time"} <= words or {"sampling", "time"} <= words) and words <= STATES["period"][0] or words == {"time", "step"}:
        kinds.append("period")  # sample_time: 5 ms (Simulink's name of the period), Sampling time, time step
    if words == {"f", "s"}:
        kinds.append("rate")  # f_s = 200 Hz
    if {"counts", "per"} <= words <= STATES["sensitivity"][0] | {"counts"}:
        kinds.append("sensitivity")  # counts per deg/s: 65.5
    if words <= set().union(*STATES["unit"]) and known_unit("rate", _PER_WORD.sub("/", value)):
        kinds.insert(0, "unit")  # gyro: rad/s, gyro: radians per second
    if words <= _ACCEL_WORDS | STATES["accel_unit"][1] and known_unit("accel", _PER_WORD.sub("/", value)):
        kinds.insert(0, "accel_unit")  # accel: m/s^2
    temperature = {word for word in words if _temperature(word)}
    if temperature and words - temperature <= set().union(*_TEMP_UNIT_WORDS) and (
            words & _TEMP_UNIT_WORDS[1] or known_unit("temp", value)):
        kinds.insert(0, "temp_unit")  # temp_unit: F, Temperature units: K, temp: F
    if not words & _ACCEL_WORDS:
        kinds = [kind for kind in kinds if not kind.startswith("accel")]
    if _NUMBER.match(clean(value)):  # gyro_scale: 131, a sensitivity (pass 54); ±2000 dps, a full scale
        kinds = [kind for kind in kinds if kind not in ("unit", "accel_unit", "temp_unit")]
    return kinds[0] if kinds else None


def _temperature(word):
    """Whether a key's ``word`` names a temperature: ``temp...`` (``temp``, ``temps``, its long form) or ``tmp``."""
    return word.startswith("temp") or word == "tmp"


def clean(value):
    """``value`` without quotes, a closing ``.``, ``;`` or ``,``, a remark in brackets at its end or after ``#`` or
    ``//``: ``"200"``, ``200 Hz (nominal)``, ``200 # set in firmware`` read ``200``, ``200 Hz``."""
    value = re.split(r"\s(?:#|//)", value)[0].strip().strip("\"'{}[] ")
    return re.sub(r"\s+\([^()]*\)$", "", value).rstrip(".;, -=*#~_").strip("\"' ")  # sample_rate: 200 ----


def judge(kind, words, value, facts, rates, tolerance):
    """``(the key of ``facts`` (a header's text values) that a key of kind ``kind`` and ``words`` stating ``value``
    contradicts, what the value does not read as or None)``, or None where it states the same or nothing: a rate in
    Hz (``khz`` in the key or the value in thousands) within ``tolerance`` (relative) of one of ``rates``, a period of
    one over it, the unit (:func:`~gyrofilter.recording.unit_words.known_unit`), ``lsb_per_dps`` (where ``gyro_unit``
    is lsb), ``accel_unit`` (where the header has one), ``lsb_per_g`` (where ``accel_unit`` is lsb)."""
    if kind == "rate" and words <= {"frequency", "freq"} and _FILTER_REMARK.search(value):
        return None  # Frequency: 42 Hz (DLPF): a filter's, not the sample rate
    value = clean(value)
    if kind in ("sensitivity", "accel_sensitivity"):
        value = _PER_WORD.sub("/", value)  # 0.0153 deg/s per LSB
    number = _NUMBER.fullmatch(value)
    amount = float(number["number"]) if number and is_plain_number(number["number"]) else None
    suffix = number["suffix"].lower() if number else ""
    if kind == "rate" and suffix in _SECONDS and not ({"khz", "hz"} & words):
        kind = "period"  # Update rate: 10 ms
    if kind == "rate":
        if amount is not None and (known_unit("rate", suffix) or suffix in ("bps", "baud", "rpm")):
            return None  # a rate of turn (Target rate: 100 dps), a baud rate
        if (amount is None or suffix not in _RATE_SUFFIXES or _PER_OTHER.match(number["rest"])
                or (suffix == "per" and not _SECOND.match(number["rest"]))):
            return "sample_rate_hz", "a rate (Hz)"  # 200 per minute, 200 samples per minute: not read
        stated = amount * (1000 if "khz" in words or suffix == "khz" else 1)
        return None if any(abs(stated - r) <= tolerance * r for r in rates) else ("sample_rate_hz", None)
    if kind == "period":
        if not amount or suffix not in ("", *_SECONDS):
            return None
        stated = 1.0 / (amount * (_SECONDS.get(suffix) or next((_SECONDS[w] for w in ("ms", "us", "ns") if w in words), 1.0)))
        if not _MIN_PERIOD_RATE_HZ <= stated <= MAX_SAMPLE_RATE_HZ:
            return None  # a time stamp (ts: 1700000000, TS: 512.3 s since boot), not a period
        return None if any(abs(stated - r) <= tolerance * r for r in rates) else ("sample_rate_hz", None)
    if kind in ("sensitivity", "accel_sensitivity"):
        return _sensitivity(kind, amount, number, suffix, facts)
    units = {"unit": (("gyro_unit", "rate"), ("accel_unit", "accel"), ("temp_unit", "temp")), "accel_unit": (("accel_unit", "accel"),),
             "temp_unit": (("temp_unit", "temp"),)}[kind]
    value = _PER_WORD.sub("/", value)  # radians per second
    words = [word for word in re.split(r"[\s,;()\[\]]+", value) if word]
    if len(words) > 1:  # units: s, deg/s, counts: counts, raw, lsb among units may be any column's (attack pass 62)
        words = [word for word in words if word.lower() not in _ANY_COLUMNS]
    for key, quantity in units:
        named = {known_unit(quantity, value)} | {known_unit(quantity, word) for word in words}
        named.discard(None)
        if key in facts and named and facts[key] not in named:
            return key, None  # units: s, deg/s, m/s^2 states both
    return None


def _sensitivity(kind, amount, number, suffix, facts):
    """:func:`judge` of a sensitivity: LSB per deg/s (``131``, ``131 LSB/(deg/s)``, ``8.75 mdps/LSB``: 114.29) where
    ``gyro_unit`` is lsb, LSB per g (``16384``, ``16384 LSB/g``, ``0.061 mg/LSB``) where ``accel_unit`` is. The
    number stands for all it rounds from as printed, 0.1 % to 1 % (a datasheet's ``0.0153 dps/LSB`` is 1 / 65.5, its
    ``7.6 mdps/LSB`` 1 / 131, attack pass 60; ``0.02 dps/LSB``, one digit, is not 1 / 65.5)."""
    unit_key, key, quantity = ("gyro_unit", "lsb_per_dps", "rate") if kind == "sensitivity" else ("accel_unit", "lsb_per_g", "accel")
    if facts.get(unit_key) != "lsb" or number and (number["range"] or known_unit(quantity, suffix) not in (None, "lsb")):
        return None  # gyro_scale: ±2000 dps, a full scale (65.5 LSB, 65.5 LSB per dps: a sensitivity)
    over = re.fullmatch(r"\(?(.+?)\)?/(?:lsb|digits?|counts?)", suffix)  # 8.75 mdps/LSB, (deg/s)/LSB, mdps/count
    scale = _PER_LSB_SCALES[quantity].get(known_unit(quantity, over[1])) if over else None
    under = re.fullmatch(_LSB_IN_KEY + r"/\(?(.+?)\)?", suffix)  # 65.5 LSB/(deg/s), 131 LSB/mdps: 131 000
    lsb = not suffix or re.fullmatch(_LSB_IN_KEY, suffix)  # 65.5, 65.5 LSB, 131 counts
    per = _PER_LSB_SCALES[quantity].get(known_unit(quantity, under[1])) if under else (1.0 if lsb else None)
    if amount is None or not (per or scale):  # (LSB/kdps, LSB/(deg/min) do not read: attack pass 63 took them for deg/s)
        return key, f"a sensitivity (LSB per {'deg/s' if kind == 'sensitivity' else 'g'})"
    if not 0 < abs(amount) < math.inf:
        return key, None  # no sensitivity is 0, or beyond a float (1e400: attack pass 62, a traceback)
    amount = abs(amount)  # -70 mdps/LSB: an axis the other way round, 70 (attack pass 61: any passed)
    half = 0.5 * float(decimal.Decimal(1).scaleb(decimal.Decimal(number["number"]).as_tuple().exponent))  # as printed
    half = min(max(half, 1e-3 * amount), 1e-2 * amount)  # within 0.1 % to 1 % (0.02 dps/LSB is not 65.5)
    low, high = (amount - half) / (per or 1.0), (amount + half) / (per or 1.0)
    if scale:  # 8.75 mdps/LSB, 0.000266 rad/s/LSB: 1 / (the number in deg/s)
        if not high * scale > 0:
            return key, None  # 4.9e-324 mdps/LSB: 0
        low, high = 1.0 / (high * scale), (1.0 / (low * scale) if low * scale > 0 else math.inf)
    held = float(facts[key])
    return None if low <= held <= high else (key, None)
