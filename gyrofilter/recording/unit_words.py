"""The units another tool's column names state (``gyrofilter convert``): one table of their spellings.

:data:`UNIT_WORDS` maps each spelling, lower case with blanks removed (:func:`spelling`), per
quantity (``time``, ``rate``, ``temp``, ``accel``) to the unit it means, spelled as the option
that gives that unit takes it (``--time-unit``, ``--unit``, ``--temp-unit``, ``--accel-unit``),
or to None where the spelling is ambiguous (``deg`` of a temperature: deg C or deg F?), which
the option resolves. Every place of :mod:`gyrofilter.recording.foreign` and
:mod:`~gyrofilter.recording.foreign.extras` that reads a unit from a column name, in brackets
or at the end of the name (:func:`name_units`), reads it here.

Units a recording does not hold are converted exactly as they are read (:data:`CONVERTED`,
:func:`to_floats`): milli-g to g, millidegrees/s to deg/s and milliradians/s to rad/s by 10^-3 (SI prefix milli, NIST SP
330, 2019, section 3), deg F to deg C by T/degC = (T/degF - 32) * 5/9 and kelvin by
T/degC = T/K - 273.15 (NIST SP 811, 2008, appendix B.9); each decimal cell scaled exactly (as a fraction) and rounded once to a float, so
that ``98.6`` degF is written ``37``, not ``36.99999999999999``.
"""
from __future__ import annotations

import math
import re
from decimal import Decimal

import numpy as np

from ..errors import RecordingError
from ..inputs import quote

_SPELLINGS = {  # quantity -> unit (None: ambiguous) -> its spellings, lower case, without blanks
    "time": {"s": ("s", "sec", "secs", "second", "seconds"),
             "ms": ("ms", "msec", "msecs", "millis", "millisecond", "milliseconds"),
             "us": ("us", "µs", "μs", "usec", "usecs", "micros", "microsecond", "microseconds"),
             "ns": ("ns", "nsec", "nsecs", "nanos", "nanosecond", "nanoseconds")},
    "rate": {"dps": ("dps", "deg/s", "deg/sec", "deg/second", "degs", "deg_s", "deg_per_s", "deg_per_sec", "degs^-1",
                     "degs-1", "deg*s^-1", "deg.s^-1", "deg.s-1", "degree/s", "degrees/s", "degrees/sec",
                     "degrees/second", "degree/second", "degree/sec", "degree_per_second", "degrees_per_second", "°/s",
                     "°/sec", "°s^-1", "°s-1"),
             "rad/s": ("rad/s", "rad/sec", "rad/second", "rads", "rad_s", "rad_per_s", "rad_per_sec", "rads^-1",
                       "rads-1", "rad*s^-1", "rad.s^-1", "rad.s-1", "radian/s", "radians/s", "radians/sec",
                       "radians/second", "radian/second", "radian/sec", "radians_per_second"),
             "mdps": ("mdps", "mdeg/s", "mdeg/sec", "mdeg/second", "millidegrees/s", "millidegrees/sec",
                      "millidegrees/second", "millidegree/s", "millidegree/second", "m°/s"),
             "mrad/s": ("mrad/s", "mrad/sec", "mrad/second", "mrads", "mrad_s", "mrads^-1", "mrads-1", "millirad/s",
                        "milliradians/s", "milliradians/sec", "milliradians/second", "milliradian/s", "milliradian/second"),
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
CONVERTED = {"mdps": ("dps", "/ 1000"), "mrad/s": ("rad/s", "/ 1000"), "mg": ("g", "/ 1000"), "f": ("c", "(F - 32) * 5/9"),
             "k": ("c", "K - 273.15")}
#: each converted unit's conversion of a fraction n / d, as (numerator, denominator): 273.15 = 5463 / 20
_EXACT = {"mdps": lambda n, d: (n, 1000 * d), "mrad/s": lambda n, d: (n, 1000 * d), "mg": lambda n, d: (n, 1000 * d),
          "f": lambda n, d: ((n - 32 * d) * 5, 9 * d),
          "k": lambda n, d: (20 * n - 5463 * d, 20 * d)}
_MAX_EXPONENT = 400  # a float's range is 4.9e-324 .. 1.8e308: a decimal exponent beyond +-400 is outside it either way


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


def name_units(quantity, units=None):
    """A regular expression of the spellings of ``quantity``'s units (or of those of ``units``) as
    they end a column name once normalised (runs of other characters than ``a-z0-9%`` made ``_``:
    ``gyro_x_rad_s``), ASCII only."""
    forms = {f for f, unit in _FORMS[quantity].items() if f and (units is None or unit in units)}
    return "|".join(re.escape(f) for f in sorted(forms, key=lambda f: (-len(f), f)))


def ending_unit(quantity, key):
    """The unit of ``quantity`` a normalised column name ``key`` ends in after a ``_``, the longest
    spelling of :func:`name_units` (``gyro1_x_mdps``: mdps; ``host_time_ms``: ms), or None: the unit of
    a column ``--columns`` names that convert's patterns do not read, which the option must agree with."""
    match = re.search(rf"_({name_units(quantity)})$", key)
    return _FORMS[quantity][match.group(1)] if match else None


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
    return np.array([_exact_float(Decimal(t), exact) for t in texts])


def _exact_float(number, exact):
    """``exact`` of the decimal ``number`` as a fraction (integers), rounded once to a float; +-inf beyond a
    float's range (``1e400``: the range checks refuse it, as an unconverted one), and a number of
    more than :data:`_MAX_EXPONENT` decimal places taken as 0 (its fraction would hold 10^exponent:
    ``1e-999999999`` took minutes; the offset of F and K is then exact, mg's product 0)."""
    if number and number.adjusted() < -_MAX_EXPONENT:
        number = Decimal(0)
    if number and number.adjusted() > _MAX_EXPONENT:
        return math.copysign(math.inf, number)
    numerator, denominator = exact(*number.as_integer_ratio())
    try:
        return numerator / denominator  # Python's int / int: correctly rounded, once (a Fraction's float is, 10 x slower)
    except OverflowError:  # beyond a float (1.8e308)
        return math.copysign(math.inf, number)


def columns_stated(path, quantity, stated, given, whose, then=""):
    """The unit several columns' names state together (``stated``: each one's :func:`stated_unit`,
    None aside), as :func:`given_unit` takes it: two units of the table are refused (``whose``
    names state them, ``then``: what to do); a text that is no unit of the table (``gz (dsp)``, a typo, ``d\u200bps``)
    states none, so that without the option it is the one stated (its refusal asks for the
    option), and with it the table's unit beside it is the one the option must agree with."""
    stated = set(stated) - {None}
    known = sorted(s for s in stated if s in units_of(quantity))
    if len(known) > 1:
        raise RecordingError(f"{path}: {whose} different units ({', '.join(known)}){then}")
    other = sorted(stated - set(known))
    return other[0] if other and (given is None or not known) else (known or [None])[0]


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


def unread_unit(path, whose, stated, option, choices, then=""):
    """The refusal (RecordingError) of a unit ``stated`` by a log's names that convert does not read
    (``whose``: the names that state it, ``option``: the option that gives the unit, ``choices``:
    its units as said): the one wording of the gyro, time and accelerometer columns, asking for the
    option only where the unit means one of the choices (``time (min)`` read as s is 60 x the rate);
    ``then``: another way out, said after."""
    return RecordingError(f"{path}: {whose} {quote(stated)}, a unit convert does not read; give {option} {choices} "
                          f"only if it means one of them{then}")
