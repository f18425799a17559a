"""The units another tool's column names state (``gyrofilter convert``): one table of their spellings.

:data:`UNIT_WORDS` maps each spelling, lower case with blanks removed (:func:`spelling`), per
quantity (``time``, ``rate``, ``temp``, ``accel``) to the unit it means, spelled as the option
that gives that unit takes it (``--time-unit``, ``--unit``, ``--temp-unit``, ``--accel-unit``),
or to None where the spelling is ambiguous (``deg`` of a temperature: deg C or deg F?), which
the option resolves. Every place of :mod:`gyrofilter.recording.foreign` and
:mod:`~gyrofilter.recording.foreign_extras` that reads a unit from a column name, in brackets
or at the end of the name (:func:`name_units`), reads it here.

Units a recording does not hold are converted exactly as they are read (:data:`CONVERTED`,
:func:`to_floats`): milli-g to g and millidegrees/s to deg/s by 10^-3 (SI prefix milli, NIST SP
330, 2019, section 3), deg F to deg C by T/degC = (T/degF - 32) * 5/9 and kelvin by
T/degC = T/K - 273.15 (NIST SP 811, 2008, appendix B.9); each decimal cell scaled exactly (as a fraction) and rounded once to a float, so
that ``98.6`` degF is written ``37``, not ``36.99999999999999``.
"""
from __future__ import annotations

import re
from decimal import Decimal
from fractions import Fraction

import numpy as np

from ..errors import RecordingError

_SPELLINGS = {  # quantity -> unit (None: ambiguous) -> its spellings, lower case, without blanks
    "time": {"s": ("s", "sec", "secs", "second", "seconds"),
             "ms": ("ms", "msec", "msecs", "millis", "millisecond", "milliseconds"),
             "us": ("us", "µs", "μs", "usec", "usecs", "micros", "microsecond", "microseconds"),
             "ns": ("ns", "nsec", "nsecs", "nanos", "nanosecond", "nanoseconds")},
    "rate": {"dps": ("dps", "deg/s", "deg/sec", "deg/second", "degs", "deg_s", "deg_per_s", "deg_per_sec", "degs^-1",
                     "degs-1", "deg*s^-1", "deg.s^-1", "deg.s-1", "degree/s", "degrees/s", "degrees/sec",
                     "degrees/second", "degree_per_second", "degrees_per_second", "°/s", "°/sec", "°s^-1", "°s-1"),
             "rad/s": ("rad/s", "rad/sec", "rad/second", "rads", "rad_s", "rad_per_s", "rad_per_sec", "rads^-1",
                       "rads-1", "rad*s^-1", "rad.s^-1", "rad.s-1", "radian/s", "radians/s", "radians/sec",
                       "radians/second", "radians_per_second"),
             "mdps": ("mdps", "mdeg/s", "mdeg/sec", "millidegrees/s", "m°/s"),
             "lsb": ("lsb", "raw", "counts")},
    "temp": {"c": ("c", "°c", "degc", "deg_c", "degreesc", "degreec", "celsius", "℃", "°celsius"),
             "f": ("f", "°f", "degf", "deg_f", "degreesf", "degreef", "fahrenheit", "℉"),
             "k": ("k", "kelvin", "kelvins"),
             "mpu6050": ("raw", "lsb", "counts"),
             None: ("deg", "degs", "degree", "degrees", "°")},
    "accel": {"m/s^2": ("m/s^2", "m/s2", "m/s²", "ms^-2", "ms-2", "ms2", "m_s2", "m_s_2", "mps2", "m/s/s", "m*s^-2",
                        "m.s^-2", "m.s-2"),
              "g": ("g", "gee", "g0", "gn"),
              "mg": ("mg", "milli-g", "millig"),
              "lsb": ("lsb", "raw", "counts")},
}
#: quantity -> spelling (lower case, blanks removed) -> the unit it means (None: ambiguous, for the option to say)
UNIT_WORDS = {quantity: {s: unit for unit, spellings in units.items() for s in spellings}
              for quantity, units in _SPELLINGS.items()}
_FORMS = {quantity: {re.sub(r"[^a-z0-9%]+", "_", s).strip("_"): unit for s, unit in words.items() if s.isascii()}
          for quantity, words in UNIT_WORDS.items()}  # the spellings as a normalised column name ends in them
#: the units convert reads but a recording does not hold -> (the recording's unit, how it is converted)
CONVERTED = {"mdps": ("dps", "/ 1000"), "mg": ("g", "/ 1000"), "f": ("c", "(F - 32) * 5/9"), "k": ("c", "K - 273.15")}
_EXACT = {"mdps": lambda x: x / 1000, "mg": lambda x: x / 1000, "f": lambda x: (x - 32) * 5 / 9,
          "k": lambda x: x - Fraction("273.15")}


def spelling(text):
    """``text`` as :data:`UNIT_WORDS` spells it: lower case, blanks removed."""
    return re.sub(r"\s+", "", text.lower())


def units_of(quantity):
    """The units of ``quantity`` (the option's values), in the table's order."""
    return tuple(u for u in _SPELLINGS[quantity] if u is not None)


def known_unit(quantity, text):
    """The unit of ``quantity`` that ``text`` (a spelling, or its form at the end of a normalised
    name: ``rad_s``) means, one of :func:`units_of`; None for an ambiguous or unknown text."""
    key = spelling(text)
    return None if not key else UNIT_WORDS[quantity].get(key) or _FORMS[quantity].get(key)


def stated_unit(quantity, text):
    """The unit ``text`` states of ``quantity``: one of :func:`units_of`, or ``text`` as it is where
    it is ambiguous or no spelling of the table (for the option to say); None for None."""
    return None if text is None else known_unit(quantity, text) or text


def name_units(quantity):
    """A regular expression of the spellings of ``quantity``'s units as they end a column name once
    normalised (runs of other characters than ``a-z0-9%`` made ``_``: ``gyro_x_rad_s``), ASCII only."""
    return "|".join(re.escape(f) for f in sorted(set(_FORMS[quantity]) - {""}, key=lambda f: (-len(f), f)))


def recorded(unit):
    """The unit a recording holds of ``unit``: itself, or the one :data:`CONVERTED` converts it to."""
    return CONVERTED.get(unit, (unit,))[0]


def converted_text(unit):
    """`` (mg, converted to g: / 1000)`` for a unit of :data:`CONVERTED`, else ``""``: for a summary."""
    return f" ({unit}, converted to {CONVERTED[unit][0]}: {CONVERTED[unit][1]})" if unit in CONVERTED else ""


def to_floats(texts, unit):
    """The plain decimal ``texts`` as floats in the recording's unit (:func:`recorded`): as they are,
    or converted exactly (each as a fraction) and rounded once."""
    if unit not in _EXACT:
        return np.array([float(t) for t in texts])
    exact = _EXACT[unit]
    return np.array([float(exact(Fraction(Decimal(t)))) for t in texts])


def given_unit(path, option, given, stated, whose, quantity, words=None):
    """The unit of a log's column(s) of ``quantity``: the one ``given`` in ``option``, which must
    agree with the unit ``stated`` by their names (:func:`stated_unit`: ``time_ms`` with
    ``--time-unit s`` is refused, naming ``whose`` names state it and the value that agrees),
    else the stated one (or None). A stated text that is no unit of the table, or an ambiguous
    one (``temp (deg)``, ``time (min)``), takes the unit given: the refusal of such a name asks
    for the option. The one rule of the gyro, time, temperature and accelerometer units of
    ``convert``; ``words``: how a stated unit is said."""
    if given is not None and stated is not None and given != stated and stated in units_of(quantity):
        raise RecordingError(f"{path}: {option} {given}, but {whose} {(words or {}).get(stated, stated)}; "
                             f"give {option} {stated}, or leave {option} out")
    return given if given is not None else stated
