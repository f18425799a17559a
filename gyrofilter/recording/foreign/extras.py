"""The temperature and accelerometer columns of another tool's log (``gyrofilter convert``), and
the range check of its values, the gyro's too (:func:`gyro_out_of_range`).

:func:`find_extras` picks them among the columns the gyro and the time leave
(:mod:`gyrofilter.recording.foreign` reads the log and passes the names):

- **Temperature.** A column named like a temperature
  (:data:`~gyrofilter.recording.header.TEMPERATURE_LIKE_NAMES`: ``TempC``, ``temp_c``,
  ``Temperature``, ``TEMP``, ...; or :data:`TEMP_UNIT_NAME`: ``TempF``, ``temp_k``) becomes the recording's ``temp`` in deg C. Its unit is
  ``temp_unit`` (``c``, or ``mpu6050``: raw counts of the MPU6050's TEMP_OUT, T / degC =
  counts / 340 + 36.53, register map section 4.18) or the one its name states (``TempC``,
  ``temp_c``, ``Temperature (°C)``: deg C; ``(raw)``: counts). A column whose unit neither says
  is left out with a warning naming ``--temp-unit`` (raw counts written as deg C would be
  silently wrong); ``none`` leaves it out. A value beyond :data:`~gyrofilter.units.TEMP_RANGE_C`
  is refused naming its line and column (raw counts in a column named in deg C), after the pass
  over the rows, as a rate beyond :data:`~gyrofilter.units.MAX_RATE_DPS` is.
- **Accelerometer.** Columns named like an accelerometer's axis (:data:`ACCEL_NAME`: ``ax``,
  ``AccX``, ``acc_x``, ``accel_x``, ``accelerometer_x``, ``linear_acceleration.x`` of a ROS
  export, which includes gravity) become ``ax, ay, az`` with the header's ``accel_unit``: the
  ``accel_unit`` given (``m/s^2``, ``g``, ``lsb`` with ``lsb_per_g``) or the one the names state
  (``(m/s^2)``, ``[g]``, ``_g``, ``_mps2``, ``_lsb``); the values as they are. Without a unit, or
  without one of the three axes, they are left out with a warning saying why; ``none`` leaves
  them out. A value beyond :data:`~gyrofilter.units.MAX_ACCEL_MPS2` is refused naming its line.
- **Units** a name states are read from the one table of
  :mod:`~gyrofilter.recording.unit_words` (deg F and K converted to deg C, mg to g, exactly).
- **Refused** in one line naming the columns: two candidates for the temperature or for one
  axis of the accelerometer, a unit given that contradicts the names', columns that state
  different units, an option given for a column the log does not have.
"""
from __future__ import annotations

import itertools
import re
from dataclasses import dataclass, field

import numpy as np

from ...errors import RecordingError
from ...inputs import quote
from ...units import (AXES, MAX_ACCEL_MPS2, MAX_RATE_DPS, MPU6050_TEMP_LSB_PER_C, MPU6050_TEMP_OFFSET_C,
                     TEMP_RANGE_C, check_lsb_per_g, to_dps, to_mps2)
from ..header import ACCEL_COLUMNS, TEMPERATURE_LIKE_NAMES, accel_units_header, format_number
from ..unit_words import (CONVERTED, columns_stated, converted_text, given_unit, name_units, recorded, stated_unit, to_floats,
                         units_of, unread_unit)
from ..writer import EXACT_FORMAT, exact_format

#: the units of a log's temperature column (``convert --temp-unit``): deg C, deg F (converted),
#: raw MPU6050 counts, or ``none`` (left out)
TEMP_UNITS = units_of("temp") + ("none",)
#: the units of a log's accelerometer columns (``convert --accel-unit``): the recording's, mg
#: (converted to g), or ``none``
ACCEL_UNIT_CHOICES = units_of("accel") + ("none",)
#: an accelerometer column's name once normalised (``foreign``'s rule), its axis in ``axis``, an
#: optional unit at the end
ACCEL_NAME = re.compile(r"(?:.*_)?(?:a|ac|acc|accl|accel|acceleration|accelerometer|linear_acceleration|"
                        r"linearacceleration)_?(?P<axis>[xyz])" rf"(?:_(?P<unit>{name_units('accel')}))?")
#: the end of a temperature-like name (:data:`TEMPERATURE_LIKE_NAMES`) that states its unit (``TempC``, ``temp_degc``, ``celsius``)
_TEMP_NAME = re.compile(rf"(?:.*_|temp|temperature)?(?P<unit>{name_units('temp')})")
#: a temperature's name once normalised that ends in deg C, deg F or K of the table (``TempF``,
#: ``temp_k``, ``Temperature_Fahrenheit``): a temperature as those of :data:`TEMPERATURE_LIKE_NAMES`
#: are (not ``temp_raw``: raw counts of another die than the MPU6050's are not its counts)
TEMP_UNIT_NAME = re.compile(rf"(?:die_)?temp(?:erature)?_?(?:{name_units('temp', ('c', 'f', 'k'))})")
#: how a summary or refusal says a temperature unit
_TEMP_WORDS = {"c": "deg C", "f": "deg F", "k": "K", "mpu6050": "raw counts"}


@dataclass
class Extras:
    """The temperature and accelerometer columns kept: their ``indices`` in the log, the
    recording's ``columns`` (``temp``, ``ax, ay, az``), the ``header`` keys they need, the
    ``summary`` and ``warnings`` to say, ``why`` each column found is left out (index -> reason), the units read (``temp_unit``, stated by its name where ``temp_named``; ``accel_read``; ``accel_unit``,
    the recording's, and ``lsb_per_g``) and, per column, whether every value so far is integral (the writer's format)."""

    indices: list = field(default_factory=list)
    columns: list = field(default_factory=list)
    header: dict = field(default_factory=dict)
    summary: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    why: dict = field(default_factory=dict)
    temp_unit: str = None
    temp_named: bool = False
    accel_unit: str = None
    accel_read: str = None
    lsb_per_g: float = None
    integral: list = field(default_factory=list)

    def values(self, cells):
        """The columns' values (floats; the temperature in deg C, the accelerometer in the recording's
        unit: :func:`~gyrofilter.recording.unit_words.to_floats`) of the cells of one chunk, one
        list of texts per column in :attr:`columns`' order."""
        out = [to_floats(col, self.temp_unit if name == "temp" else self.accel_read) for name, col in zip(self.columns, cells)]
        if self.temp_unit == "mpu6050":
            out[0] = out[0] / MPU6050_TEMP_LSB_PER_C + MPU6050_TEMP_OFFSET_C
        return out

    def check(self, cells, lines, names, path):
        """The refusal of the first temperature beyond :data:`TEMP_RANGE_C` or acceleration beyond
        :data:`MAX_ACCEL_MPS2` of a chunk's ``cells``, naming its line (``lines``) and column, or
        None; keeps each column's integrality."""
        values = self.values(cells)
        self.integral = [whole and exact_format(v) == "%d" for whole, v in zip(self.integral or [True] * len(values), values)]
        for k, v in enumerate(values):
            temp = self.columns[k] == "temp"
            with np.errstate(over="ignore"):
                ok = ((v >= TEMP_RANGE_C[0]) & (v <= TEMP_RANGE_C[1]) if temp else
                      np.abs(to_mps2(v, self.accel_unit, self.lsb_per_g)) <= MAX_ACCEL_MPS2)
            bad = np.flatnonzero(~ok)
            if not bad.size:
                continue
            i, value = self.indices[k], format_number(v[bad[0]])
            what = (f"{value} deg C is beyond {TEMP_RANGE_C[0]:g} .. {TEMP_RANGE_C[1]:g} deg C, no gyro's die"
                    + ("; raw MPU6050 counts? give --temp-unit mpu6050" if not self.temp_named and self.temp_unit != "mpu6050"
                       else "; --temp-unit none leaves the column out") if temp else
                    f"{value} {self.accel_unit} is beyond the +-{MAX_ACCEL_MPS2:g} m/s^2 any accelerometer reads")
            return f"{path}: line {lines[bad[0]]}, column {i + 1} ({quote(names[i])}): {what}"
        return None

    def formats(self):
        """The writer's formats of the columns: ``%d`` where every value is integral, else
        :data:`~gyrofilter.recording.writer.EXACT_FORMAT` (the writer's rule, :func:`exact_format`)."""
        return ["%d" if whole else EXACT_FORMAT for whole in (self.integral or [True] * len(self.columns))]


def gyro_out_of_range(values, unit, lsb_per_dps, line_of, gyro, names, path):
    """The refusal of the first gyro value (``values``: the x, y, z columns of a chunk in ``unit``)
    beyond +-MAX_RATE_DPS, naming its line and column (``gyro``: their indices), or None."""
    with np.errstate(over="ignore"):
        dps = to_dps(np.column_stack(values), unit, lsb_per_dps)
    bad = np.argwhere(~(np.abs(dps) <= MAX_RATE_DPS))
    if not bad.size:
        return None
    row, axis = (int(i) for i in bad[0])
    return (f"{path}: line {line_of[row]}, column {gyro[axis] + 1} ({quote(names[gyro[axis]])}): "
            f"{format_number(values[axis][row])} {unit} is beyond the +-{MAX_RATE_DPS:g} deg/s any gyro reads")


def find_extras(names, normal, taken, path, *, temp_unit=None, accel_unit=None, lsb_per_g=None):
    """The :class:`Extras` of a log whose column ``names`` are ``normal`` once normalised (key,
    unit in brackets or None), the columns ``taken`` (gyro, time) aside; see the module's rules."""
    if temp_unit is not None and temp_unit not in TEMP_UNITS:
        raise RecordingError(f"--temp-unit must be one of {', '.join(TEMP_UNITS)}, got {quote(temp_unit)}")
    if accel_unit is not None and accel_unit not in ACCEL_UNIT_CHOICES:
        raise RecordingError(f"--accel-unit must be one of {', '.join(ACCEL_UNIT_CHOICES)}, got {quote(accel_unit)}")
    free = [i for i in range(len(names)) if i not in taken]
    extras = Extras()
    _temperature(extras, [i for i in free if normal[i][0] in TEMPERATURE_LIKE_NAMES or TEMP_UNIT_NAME.fullmatch(normal[i][0])],
                 names, normal, temp_unit, path)
    _accelerometer(extras, [i for i in free if i not in extras.indices], names, normal, accel_unit, lsb_per_g, path)
    return extras


def _temperature(extras, found, names, normal, temp_unit, path):
    if temp_unit == "none":  # the summary's "left out" names them
        extras.why.update((i, "--temp-unit none") for i in found)
        return
    if len(found) > 1:
        raise RecordingError(f"{path}: line with the column names: columns {', '.join(quote(names[i]) for i in found)} "
                             "could each be the temperature; keep one in the log, or give --temp-unit none")
    if not found:
        if temp_unit is not None:
            raise RecordingError(f"{path}: --temp-unit {temp_unit}: no temperature column among "
                                 f"{quote(', '.join(names))} (a name such as TempC, temp_c, Temperature)")
        return
    i = found[0]
    key, bracket = normal[i]
    ending = _TEMP_NAME.fullmatch(key)
    stated = columns_stated(path, "temp", [stated_unit("temp", bracket), stated_unit("temp", ending and ending["unit"])],
                            temp_unit, f"column {quote(names[i])} states", "; --temp-unit none leaves it out")
    unit = given_unit(path, "--temp-unit", temp_unit, stated, f"column {quote(names[i])} states", "temp", _TEMP_WORDS)
    if unit not in units_of("temp"):
        extras.warnings.append(f"column {quote(names[i])} left out: its unit is not stated"
                               + (f" ({quote(stated)})" if stated is not None else "")
                               + " (deg C, deg F, K or raw MPU6050 counts?); give --temp-unit c, f or k (converted to deg C) or "
                                 "--temp-unit mpu6050 to keep it as the recording's temp, --temp-unit none to leave it out without a word")
        extras.why[i] = "unit not stated: --temp-unit"
        return
    extras.indices.append(i)
    extras.columns.append("temp")
    extras.temp_unit, extras.temp_named = unit, temp_unit is None
    extras.summary.append(f"temp {quote(names[i])} in " + (
        f"raw MPU6050 counts (deg C = counts / {MPU6050_TEMP_LSB_PER_C:g} + {MPU6050_TEMP_OFFSET_C:g})"
        if unit == "mpu6050" else _TEMP_WORDS[unit] + (f", converted to deg C: {CONVERTED[unit][1]}" if unit in CONVERTED else ""))
                          + (" (as its name states)" if stated and temp_unit is None else ""))


def _accelerometer(extras, free, names, normal, accel_unit, lsb_per_g, path):
    per_axis = {a: [i for i in free if (m := ACCEL_NAME.fullmatch(normal[i][0])) and m["axis"] == a] for a in AXES}
    found = [i for a in AXES for i in per_axis[a]]
    if accel_unit == "none":  # the summary's "left out" names them
        extras.why.update((i, "--accel-unit none") for i in found)
        return
    for a in AXES:
        if len(per_axis[a]) > 1:
            raise RecordingError(f"{path}: line with the column names: columns "
                                 f"{', '.join(quote(names[i]) for i in per_axis[a])} could each be the accelerometer's "
                                 f"{a}; keep one in the log, or give --accel-unit none")
    if not found and (accel_unit is not None or lsb_per_g is not None):
        raise RecordingError(f"{path}: --{'accel-unit' if accel_unit else 'lsb-per-g'}: no accelerometer columns among "
                             f"{quote(', '.join(names))} (names such as ax, AccX, acc_x, accel_x)")
    if not found:
        return
    stated = columns_stated(path, "accel", [stated_unit("accel", text) for i in found  # in brackets, ending the name
                                            for text in (normal[i][1], ACCEL_NAME.fullmatch(normal[i][0])["unit"])],
                            accel_unit, "the accelerometer columns state", "; --accel-unit none leaves them out")
    unit = given_unit(path, "--accel-unit", accel_unit, stated, "the accelerometer columns state", "accel")
    if unit is not None and unit not in units_of("accel"):
        raise unread_unit(path, "the accelerometer columns state", unit, "--accel-unit",
                          f"{', '.join(units_of('accel')[:-1])} or lsb (with --lsb-per-g)", "; --accel-unit none leaves them out")
    if lsb_per_g is not None and unit != "lsb":
        raise RecordingError(f"--lsb-per-g goes with an accelerometer in lsb, not {unit or 'one of no stated unit'}")
    listed = ", ".join(quote(names[i]) for i in found)
    if len(found) < len(AXES):
        missing = ", ".join(a for a in AXES if not per_axis[a])
        extras.warnings.append(f"accelerometer column(s) {listed} left out: no column for its {missing} (a recording "
                               "holds ax, ay, az together)")
        extras.why.update((i, f"accelerometer without its {missing}") for i in found)
        return
    if unit is None:
        extras.warnings.append(f"accelerometer columns {listed} left out: their unit is not stated; give --accel-unit "
                               f"{', '.join(units_of('accel')[:-1])} or lsb (with --lsb-per-g) to keep them, --accel-unit none to leave them out "
                               "without a word")
        extras.why.update((i, "unit not stated: --accel-unit") for i in found)
        return
    if unit == "lsb":
        if lsb_per_g is None:
            raise RecordingError(f"{path}: the accelerometer columns are in lsb: give --lsb-per-g (LSB per g; the "
                                 "MPU6050 at +-2 g: 16384)")
        check_lsb_per_g(lsb_per_g, "--lsb-per-g", RecordingError)
    extras.indices += found
    extras.columns += list(ACCEL_COLUMNS)
    extras.accel_read, extras.accel_unit, extras.lsb_per_g = unit, recorded(unit), lsb_per_g
    extras.header.update(accel_units_header(extras.accel_unit, lsb_per_g))
    extras.summary.append(", ".join(f"{c} {quote(names[i])}" for c, i in zip(ACCEL_COLUMNS, found))
                          + f" in {extras.accel_unit}{converted_text(unit)}"
                          + (" (as the names state)" if stated and accel_unit is None else ""))


def left_out_line(names, wanted, why, time_like):
    """The summary's line of the log's columns left out, each with why (``why``: index -> reason, of
    :class:`Extras`; a time-like name, ``time_like(index)``, is another time column; any other is a
    name convert does not read), or None when every column of ``names`` is ``wanted``."""
    def reason(i):
        return why.get(i) or ("another time column" if time_like(i) else "not a column convert reads")
    left = [i for i in range(len(names)) if i not in wanted]
    runs = [", ".join(quote(names[i]) for i in run) + f" ({why})" for why, run in itertools.groupby(left, reason)]
    return f"left out: {', '.join(runs)}" if left else None


def no_gyro_column(path, names, normal, time, axis):
    """The refusal of a log with no column for the gyro's ``axis`` (``names``, ``normal`` and ``time`` as
    :func:`columns_example` takes them), with an example of ``--columns`` in the log's own names, or,
    where it has fewer than three besides the time, why none (a preamble line before the column row)."""
    example = columns_example(names, normal, time)
    if example is None:
        return (f"{path}: no column for the gyro's {axis} among {quote(', '.join(names))}: the line with the column "
                f"names holds {len(names) - (time is not None)}{' besides the time' if time is not None else ''}, and a gyro "
                "has three (is the column row further down, after a preamble?)")
    return (f"{path}: no column for the gyro's {axis} among {quote(', '.join(names))}; name the three (or the time "
            f"and the three) in --columns, e.g. --columns {example}")


def columns_example(names, normal, time):
    """An example of ``--columns`` in this log's own ``names`` (``normal``: once normalised; ``time``:
    the time column's index or None): the time, then the first three columns named like no
    accelerometer or temperature (else the first three others); None when the log has fewer than three
    columns besides the time (an example of fewer is refused, and time plus two reads the time as x)."""
    def extra(i):
        key = normal[i][0]
        return ACCEL_NAME.fullmatch(key) or key in TEMPERATURE_LIKE_NAMES or TEMP_UNIT_NAME.fullmatch(key)
    others = [i for i in range(len(names)) if i != time]
    if len(others) < 3:
        return None
    plain = [i for i in others if not extra(i)]
    three = (plain if len(plain) >= 3 else others)[:3]
    return ",".join(names[i] for i in ([time] if time is not None else []) + three)


def whole_rates(integral, unit, gyro, names):
    """The warning (a list of none or one) of gyro columns (``gyro``: their indices) read in ``unit``
    whose every value is a whole number (``integral``: per column): raw counts, as a sketch prints an
    MPU6050's registers, taken as deg/s read 131 times too large (+-250 deg/s). Not refused: a log in
    whole deg/s exists."""
    if unit == "lsb" or not all(integral):
        return []
    return [f"every value of the gyro columns {', '.join(quote(names[i]) for i in gyro)} is a whole number, as "
            f"raw counts are: if they are the sensor's counts, not {unit}, give --unit lsb --lsb-per-dps X (the "
            "MPU6050 at +-250 deg/s: 131)"]
