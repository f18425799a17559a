"""Another tool's gyro log as a recording of format v1 (``gyrofilter convert``).

A phone logger's CSV (``timestamp,gyro_x,gyro_y,gyro_z`` in rad/s, time in ns), a ROS bag
export (``%time,field.header.seq,...,field.angular_velocity.x,...``), an Arduino sketch's
whitespace text of raw LSB: :func:`read_foreign` reads plain text of that kind (comma, semicolon,
tab or blank separated, gzip too) and returns a :class:`Foreign` whose rows a
:class:`~gyrofilter.recording.RecordingWriter` writes a chunk at a time.

- **Memory.** The log is read in chunks of :data:`~gyrofilter.recording.reader.CHUNK_ROWS` rows,
  never whole: a first pass checks every row and keeps 16 bytes a row (its line number and its
  time), a pass over the time column follows when its unit is inferred (the times in s need
  it), and :meth:`Foreign.chunks` reads it once more for the writer. A log that cannot be read
  twice (a pipe) is first copied, as it is, to an anonymous temporary file, within a bound
  (:mod:`gyrofilter.recording.logtext`: a longer pipe is refused, saying to give the log as a file).
- **Columns.** The time and the three gyro columns are found by their usual names
  (:data:`TIME_NAME`, :data:`GYRO_NAME`: ``t``/``time``/``timestamp``/``%time``/
  ``seconds_elapsed``, ``gx``/``gyro_x``/``wx``/``omega_x``/``angular_velocity.x``, ``x``; case,
  ``field.`` prefixes, ``.``/``-``/blanks and a unit in brackets do not matter), or given by
  ``columns`` (names or 1-based numbers: three gyro columns x, y, z, or the time column and
  then those three). Several candidates for one axis are refused: no guess picks a column.
- **Unit.** The gyro unit is the one the caller gives or the one the column names state
  (``Gyroscope x (rad/s)``, ``gyro_x_dps``); never guessed (a wrong one is a factor 57). The
  values are written as they are, with their unit in the header (``gyro_unit``), so that
  nothing is rounded.
- **Time.** The time column's unit (s, ms, us, ns) is the caller's, the name's (``time_ms``,
  ``millis``, ``%time`` of a ROS export in ns, ``seconds_elapsed``) or, failing both, the one in
  which the median step means ``--sample-rate-hz``, else the first of s, ms, us, ns in which it means
  :data:`~gyrofilter.recording.foreign.stamps.MIN_INFERRED_RATE_HZ` or more (a gyro logs at 5 Hz or faster), said in
  the summary; refused where another unit means a rate a gyro logs at too, 1 Hz to 32 kHz (steps of 1: 1 Hz in s or
  1 kHz in ms; of 125: 8 Hz in ms or 8 kHz in us: :func:`~gyrofilter.recording.foreign.stamps.infer_time_unit`). ``t`` counts from the first time stamp
  (stamps are subtracted exactly, as decimals: ns or s since 1970 keep every nanosecond); the first
  stamp is kept in the header (``time_origin``). The rate is the caller's or 1 / the mean
  step, gaps aside (refused where the gaps are ambiguous: :func:`_time_axis`); either way ``t`` is held to it as the reader holds a recording's
  (:class:`~gyrofilter.recording.checks.TimeCheck`: every window of 1000 steps within 5 %), so
  a file whose steps are not one rate is refused, naming the line. Without a time column the
  caller gives the rate.
- **Refusals** name the file, the line and the column: a recording of format v1 (its header
  would be skipped as comments, its unit with it), a cell that is not a plain decimal
  number (:func:`~gyrofilter.inputs.is_plain_number`), a row of the wrong length, a time that does not increase,
  a rate beyond +-100000 deg/s, a comment before the first row that states the rate or a unit
  otherwise (:mod:`~gyrofilter.recording.foreign.comments`). Comment lines (``#``, ``//``) and blank lines are skipped and
  counted; nothing else is dropped but a last line without its line end (a log cut short
  mid-line: its last number may be cut too), left out with a warning as a recording's is.
"""
from __future__ import annotations

import contextlib
import math
import re
from dataclasses import dataclass

import numpy as np

from ...errors import RecordingError
from ...inputs import BLANKS, is_plain_number, quote, refuse_unordered
from ...units import AXES, RATE_TOLERANCE, check_lsb_per_dps, check_sample_rate_hz
from ..checks import TimeCheck
from ...closable import Closable
from ..content import RecordingHead
from .comments import Comments, refuse_recording
from .extras import find_extras, gyro_out_of_range, left_out_line, no_gyro_column, whole_rates
from .stamps import TIME_UNITS, Stamps, infer_time_unit, seconds_from
from ..header import FORMAT_VERSION, GYRO_COLUMNS, VERSION_KEY, format_number, refuse_rowless
from ..logtext import log_lines, open_log
from ..reader import CHUNK_ROWS
from ..unit_words import (columns_stated, converted_text, ending_unit, given_unit, known_unit, name_units, recorded,
                         stated_unit, to_floats, units_of, unread_unit)
from ..writer import EXACT_FORMAT, exact_format

#: a time column's name once normalised (:func:`_normal`), with its unit when the name states it
TIME_NAME = re.compile(r"(?:header_)?(?P<word>t|time|times|timestamp|time_stamp|stamp|%time|seconds_elapsed|elapsed|"
                       r"elapsed_time|seconds|secs|sec|millis|micros|nanos)" rf"(?:_(?P<unit>{name_units('time')}))?")
#: a gyro column's name once normalised, its axis in ``axis``, an optional unit at the end
GYRO_NAME = re.compile(r"(?:.*_)?(?:g|gy|gyr|gyro|gyroscope|w|omega|angular_velocity|angularvelocity|rotation_rate|"
                       r"rotationrate|rot|rate)_?(?P<axis>[xyz])" rf"(?:_(?P<unit>{name_units('rate')}))?")
#: a bare axis name (``x``: the phone loggers' gyroscope files), taken where no gyro-named column exists
BARE_AXIS = re.compile(r"(?P<axis>[xyz])")
#: time columns whose name, not a unit word (:mod:`~gyrofilter.recording.unit_words`), states their unit
_NAME_TIME_UNITS = {"%time": "ns", "seconds_elapsed": "s"}
#: the blanks between the cells of a log split at blanks (:data:`~gyrofilter.inputs.BLANKS`)
_BLANK_RUN = re.compile(f"[{re.escape(BLANKS)}]+")
_BRACKET = re.compile(r"\s*[(\[]\s*([^()\[\]]*?)\s*[)\]]\s*$")
_COMMENT = ("#", "//")
class Foreign(Closable):
    """What :func:`read_foreign` found, checked in a first pass over the log: the recording's
    ``header`` (ready to write), its ``columns``, the exact ``formats`` of their values (the
    writer's rule, :func:`~gyrofilter.recording.writer.exact_format`, applied to each whole
    column, so that the file is the one writing it in one go makes), ``rows``, and the
    ``summary``, sentences saying what was read and how (columns, units, rate, jitter), and the
    ``warnings`` (a last line cut short, left out). :meth:`chunks` reads the log again and yields its rows. Holds the log open (or its copy,
    when it is a pipe) until closed."""

    def __init__(self, source, path, header, columns, formats, rows, summary, plan, warnings):
        self._source, self.path, self._plan = source, path, plan
        self.header, self.columns, self.formats, self.rows, self.summary = header, columns, formats, rows, summary
        self.warnings = warnings

    @property
    def sample_rate_hz(self):
        """The header's rate (Hz)."""
        return float(self.header["sample_rate_hz"])

    def chunks(self):
        """The rows of the recording, arrays (at most :data:`CHUNK_ROWS`, len(columns)) in the
        columns' order: the log read again, its gyro cells as floats and ``t`` as checked."""
        t_s, done = self._plan.t_s, 0
        for numbers, cells in _row_chunks(self._source, self.path, self._plan, again=True):
            if done + len(numbers) > self.rows:
                raise RecordingError(f"{self.path}: changed while it was read (more than {self.rows} rows now)")
            with _unchanged(self.path):
                gyro = [to_floats(col, self._plan.gyro_read) for col in cells[:3]]
            yield np.column_stack(([t_s[done:done + len(numbers)]] if t_s is not None else []) + gyro
                                  + self._plan.extras.values(cells[3 + (t_s is not None):]))
            done += len(numbers)
        if done != self.rows:
            raise RecordingError(f"{self.path}: changed while it was read ({done} rows now, {self.rows} before)")

    def _close(self):
        self._source.close()


@dataclass
class _Plan:
    """How the data rows of a log are read: its column ``names``, how a line is ``split``, the
    line with the names (None without), the columns ``wanted`` (x, y, z, then the time's), the
    line the data start after; the gyro unit read (``gyro_read``: mdps is written in dps); the ``extras`` kept (temperature, accelerometer:
    :mod:`~gyrofilter.recording.foreign.extras`), after those; ``t_s``, once known."""

    names: list
    split: object
    header_line: object
    wanted: list
    after_line: int
    gyro_read: str
    extras: object
    t_s: object = None


def _normal(name):
    """A column name as the patterns match it, and the text in its brackets (or None), the unit
    it states: ``"Gyroscope x (rad/s)"`` -> ``("gyroscope_x", "rad/s")``, ``"field.angular_velocity.x"`` ->
    ``("angular_velocity_x", None)``."""
    name = name.strip(BLANKS).strip('"').strip(BLANKS)
    unit = None
    bracket = _BRACKET.search(name)
    if bracket:
        unit = bracket.group(1)
        name = name[:bracket.start()]
    key = re.sub(r"[^a-z0-9%]+", "_", name.lower()).strip("_")
    return key.removeprefix("field_"), unit


def _splitter(line):
    """How the cells of ``line`` are split: at commas, else semicolons, else at runs of blanks and tabs."""
    for sep in (",", ";"):
        if sep in line:
            return lambda text, sep=sep: [c.strip(BLANKS).strip('"') for c in text.split(sep)]
    return lambda text: _BLANK_RUN.split(text.strip(BLANKS))


def _pick(names, path, columns, time_unit, unit):
    """(index of the time column or None, its unit or None, [indices of x, y, z], unit the names
    state or None), from the column ``names`` by :data:`TIME_NAME`/:data:`GYRO_NAME` or from ``columns``."""
    normal = [_normal(n) for n in names]
    if columns is not None:
        chosen = [_column_index(c, names, path) for c in columns]
        if len(chosen) not in (3, 4) or len(set(chosen)) != len(chosen):
            raise RecordingError(f"--columns takes 3 different columns (gyro x, y, z) or 4 (time, x, y, z), got {len(chosen)}")
        gyro = chosen[-3:]
        time = chosen[0] if len(chosen) == 4 else _time_column(normal, gyro)
    else:
        gyro = [_gyro_column(normal, names, axis, path) for axis in AXES]
        time = _time_column(normal, gyro)
    stated = columns_stated(path, "rate", [u for i in gyro for u in _name_units(normal[i], GYRO_NAME, "rate")], unit,
                            "the gyro columns state")
    whose = f"the time column {quote(names[time]) if time is not None else ''} states"
    units = [None] if time is None else _name_units(normal[time], TIME_NAME, "time")
    unit = given_unit(path, "--time-unit", time_unit, columns_stated(path, "time", units, time_unit, whose), whose, "time")
    if unit is not None and unit not in TIME_UNITS:  # stated, not guessed over: "time (min)" read as s is 60 x the rate
        raise unread_unit(path, f"the time column {quote(names[time])} states", unit, "--time-unit", ", ".join(TIME_UNITS))
    return time, unit, gyro, stated


def _name_units(normal, pattern, quantity):
    """The units of ``quantity`` a column's name (:func:`_normal`) states, for :func:`columns_stated`: the
    text in its brackets and the unit ending its ``pattern`` (``gyro_x_dps``, ``time_ms``) or a name it
    does not match, or its word (``millis``); None for each not stated. Both count: a bracket hid the
    unit ending the name (``gyro_x_mdps (filtered)`` with ``--unit dps`` wrote millidegrees as degrees)."""
    key, bracket = normal
    match = pattern.fullmatch(key)
    if match is None:  # a name no pattern reads (given in --columns): the unit it ends in
        return [stated_unit(quantity, bracket), ending_unit(quantity, key)]
    word = match.groupdict().get("word") or ""
    return [stated_unit(quantity, bracket), stated_unit(quantity, match["unit"]) or known_unit(quantity, word)
            or _NAME_TIME_UNITS.get(word)]


def _column_index(text, names, path):
    """The index of the column ``text`` of ``--columns``: a name of the column row, or a 1-based number
    in ASCII digits (as every number a user gives: :mod:`gyrofilter.inputs`; ``１`` or ``¹`` is no number),
    or, from code, that number as an int. A name that several columns have is refused (not guessed)."""
    text = str(int(text)) if isinstance(text, (int, np.integer)) and not isinstance(text, (bool, np.bool_)) else text
    if not isinstance(text, str):
        raise RecordingError(f"{path}: --columns: {text!r} is neither a column name nor a 1-based number")
    if names.count(text) > 1:
        where = [str(i + 1) for i, n in enumerate(names) if n == text]
        raise RecordingError(f"{path}: --columns: {quote(text)} names columns {', '.join(where[:-1])} and {where[-1]}; "
                             "give its number")
    if text in names:
        return names.index(text)
    if re.fullmatch(r"[0-9]+", text) and 1 <= int(text) <= len(names):
        return int(text) - 1
    raise RecordingError(f"{path}: --columns: no column {quote(text)} (have {quote(', '.join(names))}; "
                         f"or give 1-based numbers, 1 to {len(names)})")


def _gyro_column(normal, names, axis, path):
    """The one column that holds the gyro's ``axis``: named like a gyro's (:data:`GYRO_NAME`), else bare (``x``)."""
    for pattern in (GYRO_NAME, BARE_AXIS):
        found = [i for i, (key, _) in enumerate(normal) if (m := pattern.fullmatch(key)) and m["axis"] == axis]
        if len(found) == 1:
            return found[0]
        if len(found) > 1:
            raise RecordingError(f"{path}: line with the column names: columns {', '.join(quote(names[i]) for i in found)} "
                                 f"could each be the gyro's {axis}; name the three in --columns")
    raise RecordingError(no_gyro_column(path, names, normal, _time_column(normal, []), axis))


def _time_column(normal, gyro):
    """The time column: the first whose name states its unit, else the first named like a time; None without one."""
    candidates = [i for i, (key, _) in enumerate(normal) if i not in gyro and TIME_NAME.fullmatch(key)]
    stated = [i for i in candidates if (units := {*_name_units(normal[i], TIME_NAME, "time")} - {None}) and units <= set(TIME_UNITS)]
    return (stated or candidates or [None])[0]


def _cell(cells, index, line, names, path):
    text = cells[index].strip(BLANKS)
    if not is_plain_number(text):
        raise RecordingError(f"{path}: line {line}, column {index + 1} ({quote(names[index])}): "
                             f"not a plain decimal number: {quote(text)}")
    return text


def _row_chunks(raw, path, plan, counts=None, *, again=False):
    """The data rows of the log, :data:`CHUNK_ROWS` at a time: (their line numbers, the cells of the
    columns ``plan.wanted`` as text, one list per column). Each row is checked (its length, its
    cells plain decimal numbers; ``again``: a pass after the first, which checked them, checks the
    length only, and :func:`_unchanged` the numbers); blank and comment lines are skipped,
    counted in ``counts["skipped"]``; a last line cut short is said in ``counts["warnings"]``."""
    names, wanted = plan.names, plan.wanted
    numbers, cells_of = [], [[] for _ in wanted]
    rows_seen = again
    for number, text, lines in log_lines(raw, path, None if counts is None else counts["warnings"]):
        if number <= plan.after_line:
            continue
        if not text.strip(BLANKS) or text.lstrip(BLANKS).startswith(_COMMENT):
            if counts is not None:
                counts["skipped"] += lines
            if not rows_seen:
                _before_rows(counts, text, lines, path)
                counts["comments"].add(number, text)
            continue
        rows_seen = True
        cells = plan.split(text)
        if len(cells) != len(names):
            raise RecordingError(f"{path}: line {number}: {len(cells)} values, but {len(names)} columns "
                                 f"({'line ' + str(plan.header_line) if plan.header_line else 'the first row'})")
        for store, index in zip(cells_of, wanted):
            store.append(cells[index].strip(BLANKS) if again else _cell(cells, index, number, names, path))
        numbers.append(number)
        if len(numbers) == CHUNK_ROWS:
            yield numbers, cells_of
            numbers, cells_of = [], [[] for _ in wanted]
    if numbers:
        yield numbers, cells_of


def _before_rows(counts, text, lines, path):
    """Count a blank or comment item of :func:`log_lines` (``text``, ``lines`` lines) read before
    the first data row in ``counts["before_rows"]`` (its bytes: the text and a line end per line,
    CR not counted); :func:`~gyrofilter.recording.header.refuse_rowless` refuses past its bound."""
    counts["before_rows"] += len(text) + lines
    refuse_rowless(path, counts["before_rows"])


class _FirstRow:
    """``on_line`` of :func:`~gyrofilter.recording.logtext.open_log`: the blank and comment lines of
    a piped log before its first data row counted as it is copied, and refused past the bound as
    :func:`_read` refuses them (:func:`_before_rows`), not after the whole pipe is copied; True at
    the first data row (the row after the column names, or a first row of numbers only)."""

    def __init__(self, path):
        self.path, self.counts, self.named = path, {"before_rows": 0}, False

    def __call__(self, text, lines):
        if not text.strip(BLANKS) or text.lstrip(BLANKS).startswith(_COMMENT):
            _before_rows(self.counts, text, lines, self.path)
            return False
        if self.named:
            return True
        self.named = True
        return all(is_plain_number(c) for c in _splitter(text)(text))


@contextlib.contextmanager
def _unchanged(path):
    """A pass after the first: a cell that is no number now (float's ValueError, Decimal's
    InvalidOperation) means the log changed since the first pass checked it."""
    try:
        yield
    except (ValueError, ArithmeticError):
        raise RecordingError(f"{path}: changed while it was read (a cell checked before is no number now)") from None


def read_foreign(path, *, unit=None, lsb_per_dps=None, columns=None, sample_rate_hz=None, time_unit=None, **extras):
    """Read another tool's gyro log ``path`` (see the module's rules) as a :class:`Foreign`.

    ``unit``: ``dps``, ``rad/s`` or ``lsb`` (None: the one the column names state);
    ``lsb_per_dps``: LSB per deg/s, with ``lsb``; ``columns``: 3 or 4 column names or 1-based
    numbers (None: found by name); ``sample_rate_hz``: the rate (Hz; None: from the time
    column); ``time_unit``: ``s``, ``ms``, ``us`` or ``ns`` (None: stated by the name or inferred);
    ``extras``: ``temp_unit``, ``accel_unit``, ``lsb_per_g`` of :func:`~gyrofilter.recording.foreign.extras.find_extras`.
    RecordingError naming the file, line and column for what cannot be read, SettingsError for a bad argument."""
    path = str(path)
    if unit is not None and unit not in units_of("rate"):
        raise RecordingError(f"--unit must be one of {', '.join(units_of('rate'))}, got {quote(unit)}")
    if time_unit is not None and time_unit not in TIME_UNITS:
        raise RecordingError(f"--time-unit must be one of {', '.join(TIME_UNITS)}, got {quote(time_unit)}")
    if isinstance(columns, str):  # its letters would be taken for column names one by one
        raise RecordingError(f"--columns takes a list of 3 or 4 column names or 1-based numbers, got the text {quote(columns)}")
    refuse_unordered(columns, "--columns takes a list of 3 or 4 column names or 1-based numbers in order (time, x, y, z)",
                     RecordingError)
    if sample_rate_hz is not None:
        sample_rate_hz = check_sample_rate_hz(sample_rate_hz, "--sample-rate-hz")
    raw = open_log(path, on_line=_FirstRow(path))
    try:
        return _read(raw, path, unit, lsb_per_dps, columns, sample_rate_hz, time_unit, extras)
    except BaseException:
        raw.close()
        raise


def _read(raw, path, unit, lsb_per_dps, columns, sample_rate_hz, time_unit, options):
    """:func:`read_foreign` on the open log ``raw``: the column row, then a first pass over the
    rows that checks each and keeps 16 bytes a row (a row's line number and its time, or its
    offset from the first stamp while the time unit is not known; then a pass over the time
    column computes the times in s). Every refusal comes in the order of reading it whole."""
    header_line, names, split, first_data, preamble = None, None, None, None, 0
    counts = {"skipped": 0, "before_rows": 0, "warnings": [], "comments": Comments(path)}
    given = {key for key, option in (("sample_rate_hz", sample_rate_hz), ("gyro_unit", unit), ("lsb_per_dps", lsb_per_dps),
                                     *((key, options.get(key)) for key in ("accel_unit", "lsb_per_g", "temp_unit"))) if option is not None}
    for number, text, lines in log_lines(raw, path):
        if not text.strip(BLANKS) or text.lstrip(BLANKS).startswith(_COMMENT):
            refuse_recording(text, number, path)
            _before_rows(counts, text, lines, path)
            counts["comments"].add(number, text)
        else:
            preamble = number - 1  # the lines before it, blank or comments
            split = _splitter(text)
            cells = split(text)
            if all(is_plain_number(c) for c in cells):  # no column names: the columns are numbered
                names, first_data = [str(i + 1) for i in range(len(cells))], number
            else:
                header_line, names = number, cells
            break
    if names is None:
        raise RecordingError(f"{path}: no data (only blank or comment lines)")
    if header_line is None and columns is None:
        raise RecordingError(f"{path}: line {first_data}: numbers but no column names; give the columns by number, "
                             "e.g. --columns 1,2,3,4 (time, x, y, z) or --columns 2,3,4 (x, y, z)")
    time, t_unit, gyro, stated = _pick(names, path, columns, time_unit, unit)
    read_unit = _gyro_unit(unit, stated, lsb_per_dps, path)
    unit = recorded(read_unit)
    extras = find_extras(names, [_normal(n) for n in names], set(gyro) | {time}, path, **options)
    wanted = gyro + ([time] if time is not None else []) + extras.indices
    plan = _Plan(names, split, header_line, wanted, after_line=header_line or first_data - 1,
                 gyro_read=read_unit, extras=extras)
    counts["skipped"] = preamble
    rows, integral, out_of_range = 0, [True] * 3, None
    stamps = Stamps(keep=t_unit is None) if time is not None else None
    t_parts, line_parts = [], []
    for numbers, cells in _row_chunks(raw, path, plan, counts):
        gyro_values = [to_floats(col, read_unit) for col in cells[:3]]
        beyond = extras.check(cells[len(wanted) - len(extras.indices):], numbers, names, path)  # every chunk: formats
        out_of_range = out_of_range or gyro_out_of_range(gyro_values, unit, lsb_per_dps, numbers, gyro, names, path) or beyond
        integral = [whole and exact_format(v) == "%d" for whole, v in zip(integral, gyro_values)]
        if stamps is not None:
            line_parts.append(np.array(numbers))
            if stamps.far is None and stamps.add(cells[3], lambda i: f"{path}: line {numbers[i]}, column {time + 1} "
                                                                   f"({quote(names[time])})") and t_unit is not None:
                t_parts.append(seconds_from(cells[3], stamps.origin, TIME_UNITS[t_unit]))
        rows += len(numbers)
    skipped = counts["skipped"]
    if rows < 2:
        raise RecordingError(f"{path}: {rows} data row(s); a recording needs at least 2")
    if out_of_range:
        raise RecordingError(out_of_range)
    summary = [f"columns: x {quote(names[gyro[0]])}, y {quote(names[gyro[1]])}, z {quote(names[gyro[2]])} "
               f"in {unit}{converted_text(read_unit)}{' (as the names state)' if stated == read_unit else ''}; {rows} rows"
               + (f", {skipped} blank or comment line(s) skipped" if skipped else "")
               + (f" ({len(counts['comments'].stated)} stating the rate or a unit: checked)" if counts["comments"].stated else "")]
    left_out = left_out_line(names, wanted, extras.why, lambda i: TIME_NAME.fullmatch(_normal(names[i])[0]))
    summary += extras.summary + ([left_out] if left_out else [])
    header = {VERSION_KEY: FORMAT_VERSION}
    out_columns, formats = list(GYRO_COLUMNS), ["%d" if whole else EXACT_FORMAT for whole in integral]
    if time is not None:
        line_of = np.concatenate(line_parts)

        def where(row):
            return f"line {line_of[row]}, column {time + 1} ({quote(names[time])})"
        stamps.check(where, path)
        how = "as --time-unit states" if time_unit is not None else "as its name states"
        if t_unit is None:
            offsets = np.concatenate(stamps.offsets)
            stamps.offsets = None
            t_unit, how = infer_time_unit(np.diff(offsets), path, names[time], sample_rate_hz)
            del offsets
            with _unchanged(path):
                t_parts = [seconds_from(cells[3], stamps.origin, TIME_UNITS[t_unit])
                           for _, cells in _row_chunks(raw, path, plan, again=True)]
        t_s = np.concatenate(t_parts)
        del t_parts
        resolution_s = 10.0 ** stamps.exponent * TIME_UNITS[t_unit] if stamps.exponent is not None else 0.0
        rate_hz = _time_axis(t_s, t_unit, how, sample_rate_hz, names[time], path, summary, resolution_s)
        head = RecordingHead(header={"sample_rate_hz": format_number(rate_hz)}, names=["t"], path=path)
        check = TimeCheck(head, "the time column's steps are not at --sample-rate-hz (without it, the stamps' rate is "
                                "taken) or not one rate (split the file where it changes)" if sample_rate_hz is not None else
                          "the time column's steps are not one rate; give the rate in --sample-rate-hz if they are, or "
                          "split the file where it changes")
        check.add(t_s, where)
        check.finish()
        plan.t_s = t_s
        out_columns, formats = ["t"] + out_columns, [exact_format(t_s)] + formats
        header.update(sample_rate_hz=format_number(rate_hz), time_origin=f"{stamps.origin} {t_unit} ({names[time]})")
    elif sample_rate_hz is None:
        raise RecordingError(f"{path}: no time column among {quote(', '.join(names))}; give the rate in --sample-rate-hz, "
                             "or name the time column first in --columns")
    else:
        header["sample_rate_hz"] = format_number(sample_rate_hz)
        summary.append(f"no time column: samples taken as uniform at {sample_rate_hz:g} Hz")
    header["gyro_unit"] = unit
    if unit == "lsb":
        header["lsb_per_dps"] = format_number(lsb_per_dps)
    header.update(extras.header, converted_from=path)
    read = {"gyro_unit": read_unit, "accel_unit": extras.accel_read, "temp_unit": extras.temp_unit}  # the units read
    counts["comments"].check({**header, **{key: unit for key, unit in read.items() if unit}}, given)
    return Foreign(raw, path, header, out_columns + extras.columns, formats + extras.formats(), rows, summary,
                   plan, counts["warnings"] + whole_rates(integral, read_unit, gyro, names) + extras.warnings)


def _gyro_unit(unit, stated, lsb_per_dps, path):
    """The gyro unit: the caller's, which must agree with the names', or the names'; never guessed."""
    unit = given_unit(path, "--unit", unit, stated, "the column names say", "rate")
    choices = f"{', '.join(units_of('rate')[:-1])} or lsb (with --lsb-per-dps)"
    if unit not in units_of("rate") and stated:
        raise unread_unit(path, "the gyro columns state", stated, "--unit", choices)
    if unit not in units_of("rate"):
        raise RecordingError(f"{path}: the gyro unit is not stated by --unit or the column names (a comment is not read as one); "
                             f"give --unit {choices}")
    if unit == "lsb":
        if lsb_per_dps is None:
            raise RecordingError("--unit lsb needs --lsb-per-dps (LSB per deg/s; the MPU6050 at +-250 deg/s: 131)")
        check_lsb_per_dps(lsb_per_dps, "--lsb-per-dps", RecordingError)
    elif lsb_per_dps is not None:
        raise RecordingError(f"--lsb-per-dps goes with --unit lsb, not {unit}")
    return unit


def _time_axis(t_s, t_unit, how, sample_rate_hz, name, path, summary, resolution_s):
    """The rate in Hz (the caller's, or 1 / the mean step of ``t_s``, the times in s, its gaps, steps
    over 1.5 median steps, and the steps under half the median left out: a sample late by more than
    half a step and the next early by as much, or a few stamped at once after a gap, move the mean
    of those kept by neither); says how in ``summary``. The mean, not the median: stamps
    rounded to a coarse unit step by one of two values (an Arduino's ``millis()`` at 385 Hz: 2 or
    3 ms), whose median is one of them (3 ms: 333 Hz, the rate 13 % off and written as the
    recording's, every analysis's tau and density off with it); the mean is the rate they span
    (and the reader's check of ``t`` refuses such stamps where they are more than 5 % off it).

    Gaps tell lost samples from a slower rate only where the median step is two of the stamps'
    ``resolution_s`` (their last digit's place) or more: a step one unit longer is then within 1.5
    median steps. A median step of one unit with gaps that put the rate they span more than
    RATE_TOLERANCE below the one they leave out (``millis()`` of a 714 Hz log steps 1 or 2 ms: 40 %)
    is refused (fewer: read as lost samples, within the tolerance the reader holds ``t`` to), as are
    gaps that span half the time or more, one step in a hundred or more (bursts of samples stamped
    as they arrive, 50 us apart every 10 ms, whose median step would write 20 kHz for 100 Hz; not
    one long pause); both would be read as a faster rate with lost samples. The caller's rate is
    taken as given."""
    step_s = np.diff(t_s)
    median_s = float(np.median(step_s))
    text = f"time: column {quote(name)} in {t_unit} ({how})"
    gap = step_s > 1.5 * median_s
    kept = ~gap & (step_s >= 0.5 * median_s)
    kept = kept if kept.any() else ~gap  # none near the median (steps of 1 us and 10 ms by turns): refused below
    mean_s = float(np.mean(step_s[kept])) if median_s > 0 else math.nan
    if sample_rate_hz is None:
        if not median_s > 0:
            raise RecordingError(f"{path}: the time column {quote(name)} does not step forward (median step {median_s:g} s)")
        span_s = float(t_s[-1] - t_s[0])
        if median_s < 2 * resolution_s * (1 - 1e-9) and span_s / len(step_s) > mean_s * (1 + RATE_TOLERANCE):
            raise RecordingError(f"{path}: the time column {quote(name)} steps by its stamps' last digit "
                                 f"({median_s * 1e3:.4g} ms), so its {int(np.count_nonzero(gap))} longer steps may be lost "
                                 "samples or a slower rate: give the rate in --sample-rate-hz")
        if float(np.sum(step_s[gap])) >= 0.5 * span_s and np.count_nonzero(gap) >= 0.01 * len(step_s):
            raise RecordingError(f"{path}: the gaps of the time column {quote(name)} (steps over 1.5 median steps) span "
                                 f"{100 * float(np.sum(step_s[gap])) / span_s:.3g} % of it: bursts of samples, or most "
                                 "lost; give the rate in --sample-rate-hz")
        sample_rate_hz = check_sample_rate_hz(float(f"{1.0 / mean_s:.6g}"), f"{path}: the rate of the time column", RecordingError)
        text += f"; rate {sample_rate_hz:g} Hz from its mean step (gaps aside)"
    else:  # the stamps' rate beside it: one off by less than the reader's tolerance of t is written as given
        text += f"; rate {sample_rate_hz:g} Hz as given" + (
            f" (the stamps' mean step: {1.0 / mean_s:.6g} Hz)" if median_s > 0 else "")
    if median_s > 0:
        low, high = np.round(np.percentile(step_s, [5, 95]) / median_s - 1, 9) + 0.0  # no float noise (-1.8e-11 %)
        gaps = int(np.count_nonzero(step_s > 1.5 * median_s))
        text += (f"; jitter: 90 % of the steps within {100 * low:+.2g} % .. {100 * high:+.2g} % of the median "
                 f"({median_s * 1e3:.4g} ms), {gaps} gap(s) longer than 1.5 steps")
    summary.append(text)
    return sample_rate_hz
