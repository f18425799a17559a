"""The writers of recording format v1: :class:`RecordingWriter` (rows appended and flushed while
a live source runs) and :func:`write_recording` (a :class:`~gyrofilter.recording.content.Recording`
in one go). They write only what reads back: the header through the one header writer
(:func:`~gyrofilter.recording.header.header_text`) and its checks, finite values only, checked
as the reader checks them (:mod:`gyrofilter.recording.checks`), ``t`` and raw data exactly (the
shortest text of each float), annotations on one line.
"""
from __future__ import annotations

import contextlib
import errno
import gzip
import os
import time
import zlib

import numpy as np

from ..closable import Closable
from ..errors import RecordingError
from ..files import written_whole
from ..inputs import MAX_QUOTE_CHARS, check_number, is_plain_number, number_array, quote, refuse_unordered
from .checks import TimeCheck, check_rates
from .content import Recording, RecordingHead, checked_columns
from .header import header_text, note_line

#: %-format of a value written exactly: ``str`` of a float (a numpy scalar too) is the shortest
#: text that reads back to the same float
EXACT_FORMAT = "%s"
#: %-format of the filtered rates that ``run`` and ``replay`` write: 9 significant digits, on purpose
#: (far below the filter's noise; the raw data they come from are written exactly)
FILTERED_FORMAT = "%.9g"
_INTEGER_LIMIT = 2.0 ** 53  # integral floats below it are written as integers (exact, short)
#: what a writer's refusal of its ``t`` column says by default
_NOT_WRITTEN = "not written: it would not read back"


def write_recording(path, rec: Recording, *, compresslevel=6):
    """Write ``rec`` to ``path`` (gzip at ``compresslevel`` when the name ends in ``.gz``), whole or
    not at all (:func:`~gyrofilter.files.written_whole`: a failed write keeps the file that was
    there; it left a header alone, a recording of 0 samples), in one go: every value exactly (it
    reads back as the same float), each note before the sample it preceded (its ``row``, :class:`~gyrofilter.recording.Note`; a plain ``(line, text)`` pair
    after the data), so that the file reads back with its notes where they were.
    The header, the values and ``t`` are checked before the file is created (:class:`RecordingWriter`)."""
    columns = checked_columns(rec.columns)  # as built, or a column replaced since
    names = list(columns)
    data = np.column_stack([columns[c] for c in names]) if names else np.empty((0, 0))
    _check_finite(data, names, path)
    header_text(rec.header, names, path)
    if len(data):
        head = RecordingHead(header=rec.header, names=names, path=os.fspath(path))
        check_rates(data, head, lambda row: f"row {row + 1} of the rows to write")
        if "t" in names:
            times = TimeCheck(head, _NOT_WRITTEN)
            times.add(head.column(data, "t"), lambda row: f"row {row + 1} of the output")
            times.finish()
    notes = sorted((_note_place(path, k, note, len(data)) for k, note in enumerate(rec.notes)),
                   key=lambda note: note[0])  # stable: notes of one row keep their order
    with written_whole(path) as name, RecordingWriter(name, rec.header, names, flush_interval_s=None,
                                                      compresslevel=compresslevel, name=path) as writer:
        done = 0
        for row, text in notes:
            writer.write(data[done:row])
            writer.note(text)
            done = row
        writer.write(data[done:])


def _note_place(path, k, note, rows):
    """``(row, text)`` of the ``k``-th note of a recording (to write to ``path``) of ``rows`` samples: the sample it goes
    before, its ``row`` within [0, rows] (a plain ``(line, text)`` pair: ``rows``, after the data),
    so that every sample is written once whatever a note built in code says. A note that is no
    ``(line, text)`` pair with a text (a string note was written as its second letter, a
    triple's third item taken for nothing) is refused, nothing written."""
    if not (isinstance(note, (tuple, list)) and len(note) == 2 and isinstance(note[1], str)):
        raise RecordingError(f"{os.fspath(path)}: note {k + 1} of the recording, {repr(note)[:MAX_QUOTE_CHARS]}, is not a "
                             "(line, text) pair "
                             "(a Note, or a tuple of a line number and the text); nothing written")
    row = check_number(getattr(note, "row", rows), f"the row of the note {quote(note[1])}", integer=True,
                       error=RecordingError)
    return max(0, min(row, rows)), note[1]


def _check_finite(rows, columns, where):
    """Refuse rows (n, len(columns)) holding NaN or +-inf, naming the first: a recording holds finite numbers."""
    bad = np.argwhere(~np.isfinite(rows))
    if bad.size:
        row, col = (int(i) for i in bad[0])
        raise RecordingError(f"{where}: column {quote(columns[col])} of row {row + 1} of the rows to write is "
                             f"{float(rows[row, col])!r}; a recording holds finite numbers only (those rows not written)")


def _rows_of_numbers(rows, where, columns, formats):
    """``rows`` for :meth:`RecordingWriter.write` as an array: an object array (text cells) as
    it is, once each cell is a number as the file will hold it (:func:`_written_as_read`),
    anything else as numbers (:func:`gyrofilter.inputs.number_array`), or RecordingError naming
    the first cell that is not (its row, its column of ``columns``): a masked value (converting
    would drop the mask and write the number behind it as a sample), complex numbers (their
    imaginary part dropped), booleans or strings, or a text cell whose column's format (of
    ``formats``, None for exact) takes no text (``%d``: a TypeError of Python's)."""
    if isinstance(rows, np.ndarray) and rows.dtype == object:
        for (row, col), cell in np.ndenumerate(rows if rows.ndim == 2 else rows.reshape(-1, 1)):
            name = quote(columns[col]) if rows.ndim == 2 and col < len(columns) else str(col + 1)
            if not _written_as_read(cell):
                shown = quote(cell if isinstance(cell, str) else repr(cell))
                raise RecordingError(f"{where}: the rows to write: row {row + 1}, column {name} holds {shown}, "
                                     "not a number as a recording writes it (none of them written)")
            fmt = formats[col] if rows.ndim == 2 and col < len(formats) else None
            if isinstance(cell, str) and fmt is not None and not _takes_text(fmt, cell):
                raise RecordingError(f"{where}: the rows to write: row {row + 1}, column {name} holds the text "
                                     f"{quote(cell)}, which its format {fmt!r} takes no text for (a text cell is "
                                     "written as it is: give the column no format, or '%s'; none of them written)")
        return rows
    values, problem = number_array(rows, f"{where}: the rows to write:", first_row=1)
    if problem is not None:
        raise RecordingError(f"{problem[0]} (none of them written)")
    return values


def _takes_text(fmt, cell):
    """Whether the %-format ``fmt`` formats the text ``cell`` (``%s`` does, ``%d`` and ``%g`` do not)."""
    try:
        fmt % cell
    except (TypeError, ValueError):
        return False
    return True


def _written_as_read(cell):
    """Whether the object-array ``cell`` is written as a number the reader reads: an int or a float
    (numpy's too, not a boolean), or text in plain decimal syntax with no blank around it
    (:func:`gyrofilter.inputs.is_plain_number`). ``float()`` takes more (``True``, ``'1_000'``,
    full-width digits, ``b'1'``), which the writer wrote as they are, in a file that did not read."""
    if isinstance(cell, str):
        return cell == cell.strip() and is_plain_number(cell)
    return type(cell) in (int, float) or isinstance(cell, (np.integer, np.floating))


class RecordingWriter(Closable):
    """Append rows to a recording, flushing at least every ``flush_interval_s`` seconds.

    Made for logging from a live source: after a crash or a pulled plug at most the last
    interval is lost, and the file still reads (the reader accepts a cut last line and a gzip
    stream without its end marker). ``close()`` (or leaving the ``with`` block, also on
    KeyboardInterrupt) ends the file cleanly. A write or flush that fails (an OSError: disk full,
    file size limit) or that an exception stops midway (KeyboardInterrupt) sets ``write_failed``; ``close()`` then cuts the file back to its last
    complete flush, so that it keeps whole lines and reads, ``rows_flushed`` rows of them, and
    writes nothing more. Header keys are written in the order given, after the version line
    (:func:`header_text`). ``compresslevel`` (1-9) applies to ``.gz`` files: 6, gzip's own default,
    wrote 1 h of 100-Hz three-axis noise in 1.5 s against 3.7 s for Python's default 9, for 1 %
    more bytes.

    Everything written reads back: the header is checked as the reader checks it before the
    file is created, rows holding NaN or +-inf are refused before any of them is written, and
    annotations are kept on one line.

    Parameters
    ----------
    path : str or path-like
        The file to create (overwritten); gzip-compressed when ``name`` (default: ``path``) ends in ``.gz``.
    header : dict
        Header keys -> values (written as text); needs ``sample_rate_hz`` (Hz) and ``gyro_unit`` (``dps``,
        ``rad/s`` or ``lsb``), and ``lsb_per_dps`` (LSB per deg/s) with ``lsb``. A
        ``gyrofilter-recording`` key is dropped (the version line is written first).
    columns : sequence of str
        Column names, which must include ``gx, gy, gz`` (``t`` in s and ``temp`` in deg C
        optional).
    formats : sequence of str or None, optional
        A %-format per column, or None for exact: the shortest text that reads back to the same
        float, integers without a decimal point (chosen per column for each :meth:`write`).
        Default: every column exact.
    flush_interval_s : float or None
        Longest time (s) between flushes while writing; None flushes only at the end.
    fsync : bool
        Also ``os.fsync`` at each flush (the data reach the disk, not just the OS).
    compresslevel : int
        gzip level 0-9 for ``.gz`` files (0: stored uncompressed); a whole number as
        :func:`~gyrofilter.inputs.check_number` takes it (10 ended in zlib's ValueError, 9.0 in a
        TypeError, True was taken as 1), as ``flush_interval_s`` (>= 0) is.
    name : str, optional
        The file as messages name it, and whose ``.gz`` ending chooses gzip (default ``path``; a writer
        to a temporary file names the user's).

    RecordingError for a bad header, column list or value, and for a ``t`` column the reader
    would refuse (:class:`TimeCheck`, rows named "row N of the output"): a window refused as
    :meth:`write` completes it (its chunk not written), a file shorter than one window by
    :meth:`close` (the file is complete; a caller writing through a temporary file drops it).
    """

    def __init__(self, path, header: dict, columns, *, formats=None, flush_interval_s=1.0, fsync=True,
                 compresslevel=6, name=None):
        self.path = os.fspath(path)
        self.name = self.path if name is None else os.fspath(name)
        refuse_unordered(columns, f"{self.name}: the columns are a list in the rows' order", RecordingError)
        self.columns = list(columns)
        text = header_text(header, self.columns, self.name)
        self._head = RecordingHead(header={k: str(v) for k, v in header.items()}, names=self.columns, path=self.name)
        self._times = TimeCheck(self._head, _NOT_WRITTEN) if "t" in self.columns else None
        self._formats = list(formats) if formats is not None else [None] * len(self.columns)
        if len(self._formats) != len(self.columns):
            raise RecordingError(f"{self.name}: {len(self._formats)} formats for {len(self.columns)} columns")
        self._flush_interval_s = None if flush_interval_s is None else check_number(flush_interval_s, "flush_interval_s", low=0)
        self._fsync = fsync
        compresslevel = check_number(compresslevel, "compresslevel", low=0, high=9, integer=True)
        self._raw = open(self.path, "wb")
        # no name stored (filename="", as gzip -n): the file object's is a partial's (.partial-PID.HOST-...)
        self._gz = gzip.GzipFile(filename="", fileobj=self._raw, mode="wb", mtime=0,
                                 compresslevel=compresslevel) if os.fsdecode(self.name).endswith(".gz") else None
        self._last_flush = time.monotonic()
        self.rows_written = 0
        self.rows_flushed = 0  # the rows in the file at the last flush: what a failed write keeps
        self._flushed_bytes = 0  # the file's size then (None when it cannot be told: a pipe)
        self.write_failed = False
        self._emit(text)
        self.flush()

    def _emit(self, text):
        data = text.encode("utf-8")
        with self._failing():
            (self._gz or self._raw).write(data)

    @contextlib.contextmanager
    def _failing(self):
        """Refuse to write after a failed write; note a new failure (``write_failed``), naming the
        file when the system's error does not (a write's or a close's). A write that anything else
        stops midway (KeyboardInterrupt: a second Ctrl-C, an immediate exit) is a failed one too: gzip
        may have taken bytes into its compressor that never reached the file, and closing that stream
        wrote garbage after them, a file refused whole (attack pass 37g); so the close cuts it back to
        its last flush."""
        if self.write_failed:
            raise OSError(errno.EIO, "an earlier write failed", self.name)
        try:
            yield
        except OSError as exc:
            self.write_failed = True
            if exc.filename is None:
                raise OSError(exc.errno, exc.strerror or str(exc), self.name) from None
            raise
        except BaseException:  # a second Ctrl-C inside a write: gzip may have compressed bytes it never wrote
            self.write_failed = True
            raise

    def write(self, rows):
        """Append rows, shape (n, number of columns), in the columns' order (n may be 0; another
        shape is refused); RecordingError (and none of them written) when one holds NaN or +-inf. The cells of an object array (text a
        converter formatted itself, say) go through their formats as they are (``%s`` where a column has
        none), once checked as numbers the reader reads (:func:`_written_as_read`)."""
        rows = _rows_of_numbers(rows, self.name, self.columns, self._formats)
        if rows.ndim != 2 or rows.shape[1] != len(self.columns):  # none of the right width, too
            raise RecordingError(f"{self.name}: rows must have shape (n, {len(self.columns)}), got {rows.shape}")
        if rows.size == 0:
            return
        try:
            values = rows.astype(float)
        except (TypeError, ValueError):
            raise RecordingError(f"{self.name}: rows to write must hold numbers") from None
        _check_finite(values, self.columns, self.name)
        check_rates(values, self._head, lambda row: f"row {row + 1} of the rows to write")
        if self._times is not None:
            self._times.add(self._head.column(values, "t"), lambda row: f"row {self.rows_written + row + 1} of the output")
        fmt = ",".join(f if f is not None else EXACT_FORMAT if rows.dtype == object else exact_format(values[:, i])
                       for i, f in enumerate(self._formats)) + "\n"
        self._emit("".join(fmt % tuple(r) for r in (rows if rows.dtype == object else values).tolist()))
        self.rows_written += len(rows)
        if self._flush_interval_s is not None and time.monotonic() - self._last_flush >= self._flush_interval_s:
            self.flush()

    def note(self, text):
        """Write an annotation line (``# text``, on one line: :func:`one_line_text`) between data
        rows, for example a gap; a text longer than :data:`~gyrofilter.recording.header.MAX_NOTE_CHARS` is cut there."""
        self._emit(note_line(text))

    def flush(self):
        """Push everything written so far to the disk, readable even if the process dies now."""
        with self._failing():
            if self._gz is not None:
                self._gz.flush(zlib.Z_SYNC_FLUSH)
            self._raw.flush()
        self.rows_flushed = self.rows_written
        self._flushed_bytes = self._raw.tell() if self._raw.seekable() else None
        if self._fsync:
            try:
                os.fsync(self._raw.fileno())
            except OSError:
                pass  # pipes and some special files cannot be synced; the flush above still happened
        self._last_flush = time.monotonic()

    def __exit__(self, exc_type, *exc):
        if exc_type is not None:  # the exception stands: no refusal of a short t at the close
            self._times = None
        return super().__exit__(exc_type, *exc)

    def _close(self):
        """End the file; a failure of its last writes (a disk that fills now) is a failed write
        like any other: the file is cut back to its last flush, then the OSError is raised."""
        if self.write_failed:
            self._cut_to_last_flush()
            return
        try:
            with self._failing():
                if self._gz is not None:
                    self._gz.close()
                self._raw.flush()
        except BaseException:  # an OSError, or a signal's KeyboardInterrupt inside gzip's last writes
            self._cut_to_last_flush()
            raise
        self._raw.close()
        self.rows_flushed = self.rows_written
        if self._times is not None:
            self._times.finish()

    def _cut_to_last_flush(self):
        """After a failed write: close without writing more, and cut what the failed write and the
        closing left beyond the last flush (a cut line, a broken gzip block)."""
        fd = os.dup(self._raw.fileno())
        try:
            for closing in (self._gz, self._raw):
                if closing is not None:
                    with contextlib.suppress(OSError):  # whatever it writes is cut below
                        closing.close()
        finally:  # also when a signal stops a close
            if self._flushed_bytes is not None:
                os.ftruncate(fd, self._flushed_bytes)
            os.close(fd)


def exact_format(values):
    """The exact format of a column's ``values`` (finite): ``%d`` when all are integers below 2^53
    in size (no decimal point), else :data:`EXACT_FORMAT`."""
    return "%d" if np.all((values == np.round(values)) & (np.abs(values) < _INTEGER_LIMIT)) else EXACT_FORMAT
