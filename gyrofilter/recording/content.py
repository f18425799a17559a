"""What a recording holds once read: :class:`Recording` (every column in memory, and the
header), :class:`RecordingHead` (a recording being read chunk by chunk by
:func:`~gyrofilter.recording.reader.iter_recording`) and :class:`Note` (an annotation line and
its place among the samples); :func:`convert_gyro` and :func:`warn_about_gaps` work on them.
"""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import RecordingError
from ..inputs import number_array
from ..units import ACCEL_UNITS, check_lsb_per_g, from_dps, to_dps, to_mps2
from .header import (ACCEL_COLUMNS, FORMAT_VERSION, GYRO_COLUMNS, INPUT_RATE_KEY, VERSION_KEY, accel_header, accel_units_header, check_facts,
                     dps_header, format_number)


class _HeaderFacts:
    """Sample rate and units as the ``header`` of a recording states them, read through
    :meth:`_facts` (a :class:`Recording` checks them there: its header is a mutable dict, changed
    perhaps since it was built)."""

    def _facts(self) -> dict:
        """The header the properties read (a :class:`Recording`'s checked again, see there)."""
        return self.header

    @property
    def sample_rate_hz(self) -> float:
        """The header's ``sample_rate_hz`` as a float (Hz)."""
        return float(self._facts()["sample_rate_hz"])

    @property
    def input_sample_rate_hz(self) -> float:
        """The rate (Hz) of the samples the rows come from: the header's ``input_sample_rate_hz``
        (a filtered output's: a row per block of input samples) as a float, else ``sample_rate_hz``."""
        header = self._facts()
        return float(header.get(INPUT_RATE_KEY, header["sample_rate_hz"]))

    @property
    def gyro_unit(self) -> str:
        """The header's ``gyro_unit``: ``dps``, ``rad/s`` or ``lsb`` (the gyro columns' unit)."""
        return self._facts()["gyro_unit"]

    @property
    def lsb_per_dps(self):
        """The header's ``lsb_per_dps`` as a float (LSB per deg/s), or None when absent."""
        value = self._facts().get("lsb_per_dps")
        return None if value is None else float(value)

    @property
    def accel_unit(self):
        """The header's ``accel_unit`` (``m/s^2``, ``g`` or ``lsb``: the columns ``ax, ay, az``'s
        unit), or None when absent."""
        return self.header.get("accel_unit")

    @property
    def lsb_per_g(self):
        """The header's ``lsb_per_g`` as a float (LSB per g), or None when absent."""
        value = self.header.get("lsb_per_g")
        return None if value is None else float(value)

    def require_accelerometer(self, names):
        """Refuse an analysis of the accelerometer of a recording with columns ``names`` that has
        no ``ax, ay, az`` or no ``accel_unit`` (a v1 file written before the key: its columns are
        read and carried along, but their unit is not known), with RecordingError naming the file
        and what is missing. The reader has checked the rest (:func:`~gyrofilter.recording.header.check_accelerometer`)."""
        path = getattr(self, "path", None) or "recording"
        if not all(c in names for c in ACCEL_COLUMNS):
            raise RecordingError(f"{path}: no accelerometer columns {', '.join(ACCEL_COLUMNS)}")
        if self.accel_unit is None:
            raise RecordingError(f"{path}: header key 'accel_unit' is missing, so the unit of {', '.join(ACCEL_COLUMNS)} "
                                 "is not known; add '# accel_unit: m/s^2|g|lsb' (and '# lsb_per_g: N' with lsb) to its header")


class Note(tuple):
    """An annotation line of a recording (docs/formats.md, section 1).

    It unpacks and compares as the pair ``(line, text)`` (file line number, text after the
    ``#``), and ``row`` is the index of the sample that follows it (the number of samples
    before it), so that a reader can put it back at its place among the samples.
    """

    def __new__(cls, line, text, row):
        note = super().__new__(cls, (line, text))
        note.row = row
        return note

    def __getnewargs__(self):
        return (*self, self.row)

    @property
    def line(self):
        """File line number (1-based) of the annotation."""
        return self[0]

    @property
    def text(self):
        """The annotation's text, after the ``#`` and its blank."""
        return self[1]


@dataclass
class Recording(_HeaderFacts):
    """A recording in memory: every column as in the file, plus the header.

    ``columns`` maps each column name to a float array in file order and in the file's units;
    use :attr:`gyro_dps` for the rates in deg/s whatever the file's ``gyro_unit``. ``notes`` are
    the annotation lines, each a :class:`Note` (``(line, text)`` with the sample ``row`` it precedes);
    ``t_gaps`` the steps of a file's ``t`` that span lost samples (:class:`~gyrofilter.recording.checks.TimeCheck`,
    :func:`warn_about_gaps`).
    """

    columns: dict
    header: dict
    path: str | None = None
    warnings: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    t_gaps: int = 0

    def __post_init__(self):
        """Hold what a file holds (:func:`checked_columns`); the reader's columns (int or float
        arrays) are kept as they are, float32 of ``compact`` too. The header states the sample
        rate and units the properties read, checked as a file's are
        (:func:`~gyrofilter.recording.header.check_facts`: the version aside)."""
        check_facts(self.header, self.path or "recording")
        self.columns = checked_columns(self.columns)

    def _facts(self) -> dict:
        """The header, held to :func:`~gyrofilter.recording.header.check_facts` (RecordingError
        naming the recording) where the properties read it: a rate set to 0, nan or -100 after the
        recording was built gave a ZeroDivisionError, nan or a negative duration. A few
        microseconds a call; the properties are read per recording, never per sample. (A
        :class:`RecordingHead`'s header is the reader's, checked as the file is read, or a
        partial one of a time check's.)"""
        check_facts(self.header, self.path or "recording")
        return self.header

    def __len__(self):
        return len(next(iter(self.columns.values()), ()))  # the columns are of one length

    @property
    def gyro(self) -> np.ndarray:
        """Angular rate, shape (N, 3), in the file's ``gyro_unit``; RecordingError naming the
        recording without the columns ``gx, gy, gz`` (read with ``columns=`` that left one out)."""
        columns = checked_columns(self.columns)  # a column may have been replaced since (a mutable dict)
        missing = [c for c in GYRO_COLUMNS if c not in columns]
        if missing:
            raise RecordingError(f"{self.path or 'recording'}: no gyro column(s) {', '.join(missing)}")
        return np.column_stack([columns[c] for c in GYRO_COLUMNS])

    @property
    def gyro_dps(self) -> np.ndarray:
        """Angular rate, shape (N, 3), in deg/s."""
        return to_dps(self.gyro, self.gyro_unit, self.lsb_per_dps)

    @property
    def accel_mps2(self) -> np.ndarray:
        """Acceleration, shape (N, 3), in m/s^2 (:func:`~gyrofilter.units.to_mps2`); RecordingError
        naming the file when the recording has no ``ax, ay, az`` or no ``accel_unit``
        (:meth:`require_accelerometer`)."""
        columns = checked_columns(self.columns)
        self.require_accelerometer(columns)
        return to_mps2(np.column_stack([columns[c] for c in ACCEL_COLUMNS]), self.accel_unit, self.lsb_per_g)

    @property
    def t_s(self):
        """Sample times in seconds: the ``t`` column, or uniform times from the sample rate."""
        columns = checked_columns(self.columns)
        if "t" in columns:
            return columns["t"]
        return np.arange(len(self)) / self.sample_rate_hz

    @property
    def temp_c(self):
        """Sensor temperature in deg C, or None without a ``temp`` column."""
        return checked_columns(self.columns).get("temp")

    @property
    def duration_s(self) -> float:
        """Number of samples / ``sample_rate_hz`` (s)."""
        return len(self) / self.sample_rate_hz

    @classmethod
    def from_dps(cls, gyro_dps, sample_rate_hz, *, t_s=None, temp_c=None, accel=None, accel_unit=None, lsb_per_g=None,
                 extra=None, header=None):
        """Build an in-memory recording with ``gyro_unit: dps`` from ``gyro_dps``, an (N, 3) array
        in deg/s, at ``sample_rate_hz`` (Hz); optional ``t_s`` (N,) times (s), ``temp_c`` (N,)
        temperatures (deg C), ``accel`` (N, 3) accelerometer columns ``ax, ay, az`` in ``accel_unit``
        (``m/s^2``, ``g``, or ``lsb`` with ``lsb_per_g``: header keys), ``extra`` further columns
        (name -> (N,) array, none named as a column made from the other arguments) and ``header`` keys; the accelerometer's unit keys come from ``accel_unit``
        and ``lsb_per_g`` only (a source's header gave ``accel_unit`` to a copy without ``ax, ay, az``,
        which the writer refused)."""
        gyro_dps = _numbers(gyro_dps, "gyro_dps")
        if gyro_dps.ndim != 2 or gyro_dps.shape[1] != 3:
            raise RecordingError(f"gyro_dps must have shape (N, 3), got {gyro_dps.shape}")
        head = {VERSION_KEY: FORMAT_VERSION}
        head.update(dps_header({k: v for k, v in (header or {}).items() if k not in accel_header(header or {})},
                               sample_rate_hz))
        _check_accel_arguments(accel, accel_unit, lsb_per_g)
        head.update(accel_units_header(accel_unit, lsb_per_g))
        columns = {}
        if t_s is not None:
            columns["t"] = _numbers(t_s, "t_s")
        for i, name in enumerate(GYRO_COLUMNS):
            columns[name] = gyro_dps[:, i].copy()
        if temp_c is not None:
            columns["temp"] = _numbers(temp_c, "temp_c")
        if accel is not None:
            accel = _numbers(accel, "accel")
            if accel.ndim != 2 or accel.shape[1] != 3:
                raise RecordingError(f"accel must have shape (N, 3), got {accel.shape}")
            for i, name in enumerate(ACCEL_COLUMNS):
                columns[name] = accel[:, i].copy()
        for name, values in (extra or {}).items():
            if name in columns:  # it would replace the rates, times or temperatures given
                raise RecordingError(f"extra column {name!r} is a column from_dps makes ({', '.join(columns)}); "
                                     "give its values through its own argument")
            columns[name] = _numbers(values, f"extra column {name!r}")
        return cls(columns=columns, header=head)


def _check_accel_arguments(accel, accel_unit, lsb_per_g):
    """Refuse :meth:`Recording.from_dps`'s accelerometer arguments that do not go together
    (RecordingError): a unit or scale without ``accel``, a unit not in ACCEL_UNITS, ``lsb``
    without a ``lsb_per_g`` in its range (with another unit it is not written, as a file's
    ``lsb_per_g`` beside ``accel_unit: g`` is not copied)."""
    if accel is None and (accel_unit is not None or lsb_per_g is not None):
        raise RecordingError("from_dps: accel_unit and lsb_per_g go with accel (the columns ax, ay, az); give accel too")
    if accel_unit is not None and accel_unit not in ACCEL_UNITS:
        raise RecordingError(f"from_dps: accel_unit {accel_unit!r} is not one of {', '.join(ACCEL_UNITS)}")
    if accel_unit == "lsb":
        check_lsb_per_g(lsb_per_g, "from_dps: lsb_per_g", RecordingError)


def checked_columns(columns):
    """The columns of a :class:`Recording` (name -> values) as a file holds them: every column
    one number per row (shape (N,)), all of one length, or RecordingError naming the column. A
    masked value is refused (``gyro_dps``'s column_stack drops the mask: the number behind it
    would be a sample, and :func:`~gyrofilter.recording.write_recording` would write it), so are
    complex numbers, booleans, strings and objects (:func:`gyrofilter.inputs.number_array`).
    Int and float arrays are kept as they are. Run when a Recording is built and again where its
    columns are used (``gyro``, ``accel_mps2``, ``t_s``, ``temp_c``, the writer): ``columns`` is a mutable dict."""
    columns = {name: values if type(values) is np.ndarray and values.dtype.kind in "iuf"
               else _numbers(values, f"column {name!r}") for name, values in columns.items()}
    first = next(iter(columns), None)
    for name, values in columns.items():
        if values.ndim != 1:
            raise RecordingError(f"column {name!r} must hold one number per row, shape (N,), got shape {values.shape}")
        if len(values) != len(columns[first]):
            raise RecordingError(f"column {name!r} has {len(values)} values, column {first!r} has {len(columns[first])}")
    return columns


def _numbers(values, name):
    """``values`` (an argument ``name`` of :meth:`Recording.from_dps`) as a float array, or
    RecordingError: a masked value (converting would drop the mask and take the number behind it
    as data), complex numbers, booleans, strings, objects or a ragged list (the rule:
    :func:`gyrofilter.inputs.number_array`)."""
    array, problem = number_array(values, name)
    if problem is not None:
        raise RecordingError(problem[0])
    return array


@dataclass
class RecordingHead(_HeaderFacts):
    """A recording being read by :func:`~gyrofilter.recording.iter_recording`: header, column names and path.

    ``warnings`` and ``notes`` (:class:`Note`: ``(line, text)`` and ``row``) grow while the chunks are read, ``rows`` counts
    the samples read so far and ``t_gaps`` the steps of the ``t`` column that span lost samples
    (:class:`~gyrofilter.recording.checks.TimeCheck`); ``notes_cut``: more annotations than the reader keeps
    (:data:`~gyrofilter.recording.header.MAX_NOTES`) were met. :meth:`line_of_row` gives the file
    line of a sample read so far.
    """

    header: dict
    names: list
    path: str
    warnings: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    notes_cut: bool = False
    rows: int = 0
    t_gaps: int = 0
    _line_runs: list = field(default_factory=list, repr=False)  # (row, line, step): lines evenly spaced from row on

    def column(self, chunk, name):
        """Column ``name`` of ``chunk`` (a view), or None when the file has no such column."""
        return chunk[:, self.names.index(name)] if name in self.names else None

    def gyro_dps(self, chunk):
        """Angular rate of ``chunk``, shape (k, 3), in deg/s."""
        return to_dps(chunk[:, [self.names.index(c) for c in GYRO_COLUMNS]], self.gyro_unit, self.lsb_per_dps)

    def accel_mps2(self, chunk):
        """Acceleration of ``chunk``, shape (k, 3), in m/s^2; RecordingError as
        :meth:`Recording.accel_mps2` without ``ax, ay, az`` or ``accel_unit``."""
        self.require_accelerometer(self.names)
        return to_mps2(chunk[:, [self.names.index(c) for c in ACCEL_COLUMNS]], self.accel_unit, self.lsb_per_g)

    def t_s(self, chunk, first_row):
        """Times (s) of ``chunk`` whose first sample is sample ``first_row`` of the file: the ``t``
        column, or ``row / sample_rate_hz``."""
        t = self.column(chunk, "t")
        return t if t is not None else np.arange(first_row, first_row + len(chunk)) / self.sample_rate_hz

    def line_of_row(self, row):
        """File line number (1-based) of sample ``row`` (0-based), for the samples read so far."""
        k = bisect.bisect_right(self._line_runs, (row, math.inf)) - 1
        first_row, first_line, step = self._line_runs[k]
        return first_line + (row - first_row) * step

    def _add_rows(self, lines):
        """Count the next samples, read from the file lines ``lines`` (increasing ints). Their lines
        are kept as runs of evenly spaced lines, an entry where the spacing changes (a pair per
        place where lines and samples fell out of step was about 120 bytes a sample of a file
        whose every row is followed by a blank line or a note: a day at 100 Hz, 1 GB)."""
        if not len(lines):
            return
        lines = np.asarray(lines, dtype=np.int64)
        first = self.rows
        self.rows += len(lines)
        if not self._line_runs:  # the file's first sample: a run of one row, its step set by the next
            self._line_runs.append((first, int(lines[0]), 1))
            lines, first = lines[1:], first + 1
        steps = np.diff(lines, prepend=self.line_of_row(first - 1))  # each line's step from the one before
        for k in (0, *(np.flatnonzero(np.diff(steps)) + 1).tolist())[:len(lines)]:
            row, step = first + k, int(steps[k])
            run_row, run_line, run_step = self._line_runs[-1]  # the row before is on it
            if step == run_step:
                continue
            if run_row == row - 1:  # a run of one row takes the step
                self._line_runs[-1] = (run_row, run_line, step)
            else:
                self._line_runs.append((row, int(lines[k]), step))


def convert_gyro(rec: Recording, unit: str, lsb_per_dps=None) -> Recording:
    """A copy of ``rec`` with the gyro columns expressed in ``unit`` (other columns unchanged);
    ``lsb_per_dps`` (LSB per deg/s) is needed for 'lsb'."""
    gyro = from_dps(rec.gyro_dps, unit, lsb_per_dps)
    columns = dict(rec.columns)
    for i, name in enumerate(GYRO_COLUMNS):
        columns[name] = gyro[:, i]
    header = dict(rec.header, gyro_unit=unit)
    if unit == "lsb":
        header["lsb_per_dps"] = format_number(lsb_per_dps)
    else:
        header.pop("lsb_per_dps", None)
    return Recording(columns=columns, header=header, path=rec.path, warnings=list(rec.warnings), notes=list(rec.notes),
                     t_gaps=rec.t_gaps)


def warn_about_gaps(head, consequence, warn):
    """Warn (``warn(text)``) when the t column of a recording read
    (:class:`~gyrofilter.recording.RecordingHead`) showed missing samples; ``consequence`` says
    what that means for the command.

    ``head``: the :class:`RecordingHead` after its chunks were read, or a :class:`Recording`
    (its ``t_gaps`` counts the steps of ``t`` that span lost samples: longer than 1.5 sample intervals, or in a
    filtered output, whose header names ``input_sample_rate_hz``, rows whose block of input samples
    spans lost ones); ``consequence``: text appended to the warning; ``warn``: a callable taking one
    line of text. Returns None; warns at most once.
    """
    if head.t_gaps:
        gaps = ("longer than 1.5 sample intervals" if head.input_sample_rate_hz == head.sample_rate_hz else
                "(rows whose block of input samples spans lost samples)")
        warn(f"{head.path}: t shows {head.t_gaps} gap(s) {gaps}; {consequence}")
