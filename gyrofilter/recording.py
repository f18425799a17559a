"""Recording format version 1: reader and writers.

The format (docs/formats.md, section 1) is CSV text, optionally gzip-compressed::

    # gyrofilter-recording: 1
    # sample_rate_hz: 100
    # gyro_unit: lsb            (dps, rad/s or lsb)
    # lsb_per_dps: 131          (required when gyro_unit is lsb)
    t,gx,gy,gz,temp
    0.00,12,-3,40,25.31

Header lines start with ``#`` and hold ``key: value``, each key once; unknown keys are kept;
numbers are plain decimal text (:func:`~gyrofilter.inputs.parse_number`). Columns ``gx, gy,
gz`` are required; ``t`` (s, strictly increasing, its typical step ``1 / sample_rate_hz`` within
5 %) and ``temp`` (deg C) are optional; any other column is carried along unchanged. Lines
starting with ``#`` after the column row are annotations (for example a gap note written by
``gyrofilter record``); they are kept in :attr:`Recording.notes` and are not samples, and
neither are blank lines. No line is longer than :data:`MAX_LINE_BYTES`.

Bad input never shifts, drops or invents samples: an empty cell, ``nan``, a short or long row, a
cell that is not a plain decimal number (``0.0_1``), damaged gzip data (a failed checksum too)
raise :class:`RecordingError` naming the file, the line and the reason (user text quoted
short). The one tolerated defect is the one an interrupted recording leaves: a last line
without its line end, or a gzip stream that ends before its end marker. Those are reported in
:attr:`Recording.warnings` and every complete line is used. A UTF-8 byte-order mark before the
first line is ignored.

The writers (:class:`RecordingWriter`, :func:`write_recording`) write only what reads back:
one header writer (:func:`header_text`) checked by the reader's own checks, finite values only,
``t`` and raw data exactly (the shortest text of each float), header values and annotations on
one line.

:func:`iter_recording` reads a file in chunks of lines (memory: one chunk, whatever the
length of the file); :func:`read_recording` collects its chunks into a :class:`Recording`.
"""
from __future__ import annotations

import bisect
import contextlib
import errno
import gzip
import math
import os
import re
import time
import zlib
from dataclasses import dataclass, field

import numpy as np

from .closable import Closable
from .errors import RecordingError, SettingsError
from .inputs import MAX_QUOTE_CHARS, is_plain_number, parse_number, quote
from .units import GYRO_UNITS, MAX_RATE_DPS, RATE_TOLERANCE, check_sample_rate_hz, from_dps, to_dps, utf8_text

FORMAT_VERSION = "1"
GYRO_COLUMNS = ("gx", "gy", "gz")
#: the start of the annotation with which ``record`` and ``run`` end their output (``# end: why; ...``):
#: how that output ended, so a replay of the file does not pass it on as its own
END_NOTE = "end: "
_GZIP_MAGIC = b"\x1f\x8b"


class _HeaderFacts:
    """Sample rate and units as the ``header`` of a recording states them."""

    @property
    def sample_rate_hz(self) -> float:
        """The header's ``sample_rate_hz`` as a float (Hz)."""
        return float(self.header["sample_rate_hz"])

    @property
    def gyro_unit(self) -> str:
        """The header's ``gyro_unit``: ``dps``, ``rad/s`` or ``lsb`` (the gyro columns' unit)."""
        return self.header["gyro_unit"]

    @property
    def lsb_per_dps(self):
        """The header's ``lsb_per_dps`` as a float (LSB per deg/s), or None when absent."""
        value = self.header.get("lsb_per_dps")
        return None if value is None else float(value)


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
    ``t_gaps`` the steps of a file's ``t`` longer than 1.5 sample intervals (:func:`warn_about_gaps`).
    """

    columns: dict
    header: dict
    path: str | None = None
    warnings: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    t_gaps: int = 0

    def __len__(self):
        return len(self.columns["gx"])

    @property
    def gyro(self) -> np.ndarray:
        """Angular rate, shape (N, 3), in the file's ``gyro_unit``."""
        return np.column_stack([self.columns[c] for c in GYRO_COLUMNS])

    @property
    def gyro_dps(self) -> np.ndarray:
        """Angular rate, shape (N, 3), in deg/s."""
        return to_dps(self.gyro, self.gyro_unit, self.lsb_per_dps)

    @property
    def t_s(self):
        """Sample times in seconds: the ``t`` column, or uniform times from the sample rate."""
        if "t" in self.columns:
            return self.columns["t"]
        return np.arange(len(self)) / self.sample_rate_hz

    @property
    def temp_c(self):
        """Sensor temperature in deg C, or None without a ``temp`` column."""
        return self.columns.get("temp")

    @property
    def duration_s(self) -> float:
        """Number of samples / ``sample_rate_hz`` (s)."""
        return len(self) / self.sample_rate_hz

    @classmethod
    def from_dps(cls, gyro_dps, sample_rate_hz, *, t_s=None, temp_c=None, extra=None, header=None):
        """Build an in-memory recording with ``gyro_unit: dps`` from ``gyro_dps``, an (N, 3) array
        in deg/s, at ``sample_rate_hz`` (Hz); optional ``t_s`` (N,) times (s), ``temp_c`` (N,)
        temperatures (deg C), ``extra`` further columns (name -> (N,) array) and ``header`` keys."""
        gyro_dps = np.asarray(gyro_dps, dtype=float)
        if gyro_dps.ndim != 2 or gyro_dps.shape[1] != 3:
            raise RecordingError(f"gyro_dps must have shape (N, 3), got {gyro_dps.shape}")
        head = {"gyrofilter-recording": FORMAT_VERSION}
        head.update(dps_header(header or {}, sample_rate_hz))
        columns = {}
        if t_s is not None:
            columns["t"] = np.asarray(t_s, dtype=float)
        for i, name in enumerate(GYRO_COLUMNS):
            columns[name] = gyro_dps[:, i].copy()
        if temp_c is not None:
            columns["temp"] = np.asarray(temp_c, dtype=float)
        for name, values in (extra or {}).items():
            columns[name] = np.asarray(values, dtype=float)
        for name, values in columns.items():
            if len(values) != len(gyro_dps):
                raise RecordingError(f"column {name!r} has {len(values)} values, gyro has {len(gyro_dps)}")
        return cls(columns=columns, header=head)


def dps_header(header, sample_rate_hz):
    """``header`` with ``sample_rate_hz`` and ``gyro_unit: dps`` (no ``lsb_per_dps``), for rates in deg/s."""
    head = dict(header)
    head.update({"sample_rate_hz": format_number(float(sample_rate_hz)), "gyro_unit": "dps"})
    head.pop("lsb_per_dps", None)
    return head


# ---------------------------------------------------------------------------------------------
# reading

#: most lines per chunk of :func:`iter_recording` (a chunk also ends with each block of text)
CHUNK_ROWS = 1 << 16
_READ_BYTES = 1 << 20   # bytes read from the file at a time
_TEXT_BYTES = 1 << 20   # most decompressed bytes at a time (a block of text: about 36 000 lines of five columns)
_BOM = b"\xef\xbb\xbf"
_BLOCK_ROWS = 1 << 19   # rows per block of collect_columns
#: longest line (bytes, without its line end) of a recording: a data row is about 100 bytes, a
#: header line holding a model or the filter settings as JSON a few KB. A longer line is refused
#: once that many bytes are read (a gzip bomb of one endless line, /dev/zero): memory stays one
#: block of text. Equal to the block size, so a line inside a block is never longer.
MAX_LINE_BYTES = _TEXT_BYTES
#: most lines before the column-name row (the header, with its blank ``#`` lines); together they
#: hold at most MAX_LINE_BYTES bytes as well
MAX_HEADER_LINES = 1000


@dataclass
class RecordingHead(_HeaderFacts):
    """A recording being read by :func:`iter_recording`: header, column names and path.

    ``warnings`` and ``notes`` (:class:`Note`: ``(line, text)`` and ``row``) grow while the chunks are read, ``rows`` counts
    the samples read so far and ``t_gaps`` the steps of the ``t`` column longer than 1.5 sample
    intervals (lost samples). :meth:`line_of_row` gives the file line of a sample read so far.
    """

    header: dict
    names: list
    path: str
    warnings: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    rows: int = 0
    t_gaps: int = 0
    _line_starts: list = field(default_factory=list, repr=False)  # (row, line) where line - row changes

    def column(self, chunk, name):
        """Column ``name`` of ``chunk`` (a view), or None when the file has no such column."""
        return chunk[:, self.names.index(name)] if name in self.names else None

    def gyro_dps(self, chunk):
        """Angular rate of ``chunk``, shape (k, 3), in deg/s."""
        return to_dps(chunk[:, [self.names.index(c) for c in GYRO_COLUMNS]], self.gyro_unit, self.lsb_per_dps)

    def t_s(self, chunk, first_row):
        """Times (s) of ``chunk`` whose first sample is sample ``first_row`` of the file: the ``t``
        column, or ``row / sample_rate_hz``."""
        t = self.column(chunk, "t")
        return t if t is not None else np.arange(first_row, first_row + len(chunk)) / self.sample_rate_hz

    def line_of_row(self, row):
        """File line number (1-based) of sample ``row`` (0-based), for the samples read so far."""
        k = bisect.bisect_right(self._line_starts, (row, math.inf)) - 1
        first_row, first_line = self._line_starts[k]
        return first_line + row - first_row

    def _add_rows(self, lines):
        """Count the next samples, read from the file lines ``lines`` (increasing ints)."""
        if not len(lines):
            return
        offsets = np.asarray(lines) - np.arange(self.rows, self.rows + len(lines))
        for k in (0, *(np.flatnonzero(np.diff(offsets)) + 1).tolist()):
            if not self._line_starts or self.line_of_row(self.rows + k) != lines[k]:
                self._line_starts.append((self.rows + k, int(lines[k])))
        self.rows += len(lines)


def read_recording(path) -> Recording:
    """Read a format-v1 recording (``.csv`` or gzip, detected by content) from ``path``: the
    chunks of :func:`iter_recording` gathered by :func:`collect_columns`."""
    chunks = iter_recording(path)
    head = next(chunks)
    columns = collect_columns(head, chunks, head.names)
    return Recording(columns=columns, header=head.header, path=head.path, warnings=head.warnings, notes=head.notes,
                     t_gaps=head.t_gaps)


def collect_columns(head, chunks, names):
    """The columns ``names`` of the remaining ``chunks`` of :func:`iter_recording` as one float64
    array each (file units); ``head`` is the :class:`RecordingHead` it yielded first.

    Values are copied into blocks (16 Ki rows, doubling up to ``_BLOCK_ROWS`` = 4 MB; large
    blocks are memory mappings of their own, so the many short-lived chunk buffers do not
    fragment the heap around them) and each column's blocks are joined at the end, one column
    at a time: the peak is the arrays with their last blocks' spare room, one more column and
    one chunk.
    """
    where = [head.names.index(name) for name in names]
    blocks = {name: [] for name in names}
    size = fill = 0
    for chunk in chunks:
        pos = 0
        while pos < len(chunk):
            if fill == size:  # a new block, twice the last one up to _BLOCK_ROWS
                size = min(_BLOCK_ROWS, max(1 << 14, 2 * size))
                for name in names:
                    blocks[name].append(np.empty(size))
                fill = 0
            take = min(size - fill, len(chunk) - pos)
            for name, i in zip(names, where):
                blocks[name][-1][fill:fill + take] = chunk[pos:pos + take, i]
            fill += take
            pos += take
    columns = {}
    for name in names:
        parts = blocks.pop(name)
        if parts:
            parts[-1] = parts[-1][:fill]
        columns[name] = np.concatenate(parts) if len(parts) > 1 else (parts[0].copy() if parts else np.empty(0))
    return columns


def iter_recording(path, chunk_rows=CHUNK_ROWS):
    """Read the format-v1 recording at ``path`` in chunks: yields a :class:`RecordingHead` first, then float
    arrays of shape (k, number of columns), columns in file order and units, k <= ``chunk_rows``.

    The file is read a block (about 1 MB of text) at a time; the complete lines of a block, at
    most ``chunk_rows`` at a time, are parsed by ``numpy.loadtxt`` on their list; when that fails, or gives fewer rows than lines or non-finite values (annotations, blank lines
    or a bad line), the chunk's lines are classified one by one, so that annotations are kept
    and a bad line is named by its file line number and reason (module docstring). A cut last
    line or a gzip stream without its end marker is added to ``head.warnings`` when the end is
    reached. A UTF-8 byte-order mark at the start is skipped. The ``t`` column is checked as
    :class:`_TimeCheck` says (increasing, its typical step agreeing with ``sample_rate_hz``).
    """
    path = os.fspath(path)
    if not (isinstance(chunk_rows, int) and chunk_rows >= 1):
        raise SettingsError(f"chunk_rows must be a whole number >= 1, got {chunk_rows!r}")
    warnings = []
    parts = _line_chunks(path, chunk_rows, warnings)
    try:
        head, first, lines = _read_header(parts, path, warnings)
    except RecordingError as exc:
        raise _blame_gzip_damage(path, exc) from None
    yield head
    times = _TimeCheck(head) if "t" in head.names else None
    while True:
        if lines:
            try:
                data, line_numbers = _parse_chunk(lines, first, head)
                _check_rates(data, head, lambda row: f"line {line_numbers[row]}")
                if len(data) and times is not None:
                    times.add(head.column(data, "t"), lambda row: f"line {line_numbers[row]}")
            except RecordingError as exc:
                raise _blame_gzip_damage(path, exc) from None
            if len(data):
                head._add_rows(line_numbers)
                yield data
        try:
            first, lines = next(parts)
        except StopIteration:
            if times is not None:
                times.finish()
            return
        except RecordingError as exc:
            raise _blame_gzip_damage(path, exc) from None


def _check_rates(data, head, where):
    """Refuse a gyro value beyond +-MAX_RATE_DPS once in deg/s (1e308 rad/s, a tiny lsb_per_dps):
    no gyro reads it, and it would overflow every analysis. One vectorised pass over ``data``, a
    chunk in ``head``'s columns and units; ``where(row)`` names a row ("line 12"). The reader and
    the writers share it, so that nothing is written that would not read back."""
    with np.errstate(over="ignore"):
        ok = np.abs(head.gyro_dps(data)) <= MAX_RATE_DPS
    if not ok.all():
        row, axis = (int(i[0]) for i in np.nonzero(~ok))
        name = GYRO_COLUMNS[axis]
        raise RecordingError(f"{head.path}: {where(row)}: column {name!r} is "
                             f"{format_number(data[row, head.names.index(name)])} {head.gyro_unit}, beyond the "
                             f"+-{MAX_RATE_DPS:g} deg/s any gyro reads")


class _GzipDamage(RecordingError):
    """Damaged gzip data: what was read from them cannot be trusted. ``reason``: what zlib said."""

    def __init__(self, path, reason, produced):
        super().__init__(f"{path}: damaged gzip data ({reason}) after {produced} bytes of text; "
                         "nothing read from it is trusted")
        self.reason = reason


def _blame_gzip_damage(path, exc):
    """``exc`` (a bad line), or, when ``path`` is a gzip file whose data are damaged (its
    checksum or its compressed blocks wrong), an error saying so: the bad line is then text
    the damage made, not what was written."""
    if isinstance(exc, _GzipDamage):
        return exc
    damage = _gzip_damage(path)
    if damage is None:
        return exc
    where = str(exc).removeprefix(path + ": ").partition(": ")[0]
    return RecordingError(f"{path}: damaged gzip data ({damage}); the text read from it is garbage (first noticed at {where})")


def _gzip_damage(path):
    """The zlib error decompressing the whole gzip file ``path`` (every member) meets, or None
    (not gzip, intact, or only cut short as an interrupted recording leaves it). Memory: one
    block at a time, as when reading."""
    try:
        with open(path, "rb") as fh:
            raw = fh.read(_READ_BYTES)
            if raw[:2] == _GZIP_MAGIC:
                for _ in _gunzip(fh, raw, path, []):
                    pass
    except _GzipDamage as exc:
        return exc.reason
    except OSError:
        pass
    return None


def _byte_blocks(path, warnings):
    """The file's bytes in blocks of at most ``_READ_BYTES``, gunzipped (:func:`_gunzip`) when it
    starts with the gzip magic."""
    try:
        fh = open(path, "rb")
    except OSError as exc:
        raise RecordingError(f"{path}: cannot read: {exc.strerror or exc}") from None
    with fh:
        raw = fh.read(_READ_BYTES)
        if raw[:2] == _GZIP_MAGIC:
            yield from _gunzip(fh, raw, path, warnings)
            return
        while raw:
            yield raw
            raw = fh.read(_READ_BYTES)


def _gunzip(fh, raw, path, warnings):
    """The text of the gzip file ``fh`` (``raw``: its first bytes, already read), every member,
    in blocks of at most ``_TEXT_BYTES`` (a gzip bomb never holds more).

    A stream that ends before its end marker (an interrupted recording) ends the text with a
    warning. Damaged data are an error (:class:`_GzipDamage`): corrupt compressed blocks, a
    checksum or length that does not match (the text may look fine: a changed digit in a
    stored block), or bytes after a member that do not start another member."""
    d = zlib.decompressobj(16 + zlib.MAX_WBITS)
    produced = 0  # bytes of text so far
    while True:
        try:
            out = d.decompress(raw, _TEXT_BYTES)
            if not raw and not out and not d.eof:  # the file ended: what zlib still holds, then the verdict
                out = d.flush()
        except zlib.error as exc:
            raise _GzipDamage(path, str(exc), produced) from None
        if out:
            produced += len(out)
            yield out
        if d.eof:  # a member ended: another may follow
            raw = d.unused_data or fh.read(_READ_BYTES)
            if not raw:
                return
            if raw[:2] != _GZIP_MAGIC and not _GZIP_MAGIC.startswith(raw):  # (a 1f alone may start a member cut short)
                raise _GzipDamage(path, "bytes after the end of the gzip stream that are not gzip", produced)
            d = zlib.decompressobj(16 + zlib.MAX_WBITS)
        elif d.unconsumed_tail:
            raw = d.unconsumed_tail
        elif raw or out:
            raw = fh.read(_READ_BYTES)
        else:
            warnings.append(f"{path}: gzip stream cut short (no end marker), as an interrupted recording leaves it")
            return


def _without_bom(blocks):
    """The byte blocks with a UTF-8 byte-order mark at the very start removed."""
    start = b""
    for block in blocks:
        if start is None:
            yield block
            continue
        start += block
        if len(start) >= len(_BOM):
            yield start[len(_BOM):] if start.startswith(_BOM) else start
            start = None
    if start:
        yield start[len(_BOM):] if start.startswith(_BOM) else start


def _line_chunks(path, chunk_rows, warnings):
    """(number of the first line, list of at most ``chunk_rows`` lines without their line ends),
    a block of the file at a time (lines are split at b"\\n" before decoding, which never cuts
    a UTF-8 character). A last line without its line end is not used (warning), unless it is
    the file's only line. A line longer than :data:`MAX_LINE_BYTES` is an error as soon as
    that many bytes are read (a line inside a block is shorter than the block, at most as
    long as the limit: only the line that the blocks so far have not ended needs a check)."""
    pending = b""
    first = 1  # number of the next line
    for block in _without_bom(_byte_blocks(path, warnings)):
        cut = block.rfind(b"\n")
        open_bytes = len(pending) + (len(block) if cut < 0 else block.find(b"\n"))  # of the line not yet ended
        if open_bytes > MAX_LINE_BYTES:
            raise RecordingError(f"{path}: line {first}: longer than {MAX_LINE_BYTES} bytes, not a line of a recording "
                                 f"(it starts {quote((pending + block)[:MAX_QUOTE_CHARS].decode('utf-8', 'replace'))})")
        if cut < 0:
            pending += block
            continue
        lines = _decode(pending + block[:cut], path, first).split("\n")
        pending = block[cut + 1:]
        if len(lines) <= chunk_rows:
            yield first, lines
        else:
            for i in range(0, len(lines), chunk_rows):
                yield first + i, lines[i:i + chunk_rows]
        first += len(lines)
    if pending:
        if first > 1:
            warnings.append(f"{path}: line {first}: last line has no line end (recording interrupted?); "
                            f"it is not used: {quote(pending[:60].decode('utf-8', 'replace'))}")
        else:
            yield first, [_decode(pending, path, first)]


def _decode(data, path, first_line):
    """``data`` (whole lines, the first being line ``first_line``) as text, or RecordingError."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = first_line + data[:exc.start].count(b"\n")
        raise RecordingError(f"{path}: line {line}: not UTF-8 text") from None


def _read_header(parts, path, warnings):
    """Header and column names from the first lines: (head, number of the next line, the rest
    of its chunk). The lines before the column row may be at most :data:`MAX_HEADER_LINES`."""
    header_lines = []
    size = 0  # characters of the header lines
    blank = True  # only blank lines so far
    for first, lines in parts:
        for j, ln in enumerate(lines):
            blank = blank and not ln.strip()
            if not ln.startswith("#") and not blank:
                header = _parse_header(header_lines, path)
                names = [c.strip() for c in ln.split(",")]
                _check_columns(names, f"{path}: line {first + j}")
                head = RecordingHead(header=header, names=names, path=path, warnings=warnings)
                return head, first + j + 1, lines[j + 1:]
            header_lines.append(ln)
            size += len(ln) + 1
            if len(header_lines) > MAX_HEADER_LINES or size > MAX_LINE_BYTES:
                raise RecordingError(f"{path}: line {first + j}: no column-name row within {MAX_HEADER_LINES} lines "
                                     f"or {MAX_LINE_BYTES} bytes of header; not a recording")
    if blank:
        raise RecordingError(f"{path}: empty file (expected a '# gyrofilter-recording: 1' header)")
    _parse_header(header_lines, path)
    raise RecordingError(f"{path}: line {len(header_lines) + 1}: missing the column-name row after the header")


def _parse_header(lines, path):
    """The header (key -> value text) of a file's first ``lines`` (its ``#`` lines, line 1 first),
    checked by :func:`_check_header`; a line that is not ``key: value`` or repeats a key is an
    error naming its line."""
    header, line_of = {}, {}
    for i, ln in enumerate(lines):
        if not ln.startswith("#"):
            break
        body = ln[1:].strip()
        if not body:
            continue
        key, sep, value = body.partition(":")
        key = key.strip()
        if not sep or not key:
            raise RecordingError(f"{path}: line {i + 1}: header line is not 'key: value': {quote(ln)}")
        if key in header:
            raise RecordingError(f"{path}: line {i + 1}: header key {quote(key)} repeated (first on line {line_of[key]})")
        header[key], line_of[key] = value.strip(), i + 1
    _check_header(header, path)
    return header


def _check_header(header, where):
    """Refuse a header (key -> value text) that is not one of format v1, with RecordingError
    naming ``where`` (the file): the version, the required keys, ``sample_rate_hz`` a plain
    decimal number (:func:`~gyrofilter.inputs.parse_number`) checked by
    :func:`~gyrofilter.units.check_sample_rate_hz`, ``gyro_unit`` one of :data:`GYRO_UNITS`,
    ``lsb_per_dps`` a positive number with ``lsb``. The one check of a header: the reader's and
    the writers' (:func:`header_text`)."""
    missing = [key for key in ("gyrofilter-recording", "sample_rate_hz", "gyro_unit") if key not in header]
    if missing:
        raise RecordingError(f"{where}: line 1: missing header key(s) {', '.join(map(repr, missing))}; a recording starts with "
                             "'# gyrofilter-recording: 1', '# sample_rate_hz: RATE', '# gyro_unit: dps|rad/s|lsb' "
                             "lines (docs/formats.md, section 1)")
    version = header["gyrofilter-recording"]
    if version != FORMAT_VERSION:
        raise RecordingError(f"{where}: unsupported recording version {quote(version)} (this gyrofilter reads version {FORMAT_VERSION})")
    rate_hz = parse_number(header["sample_rate_hz"], f"{where}: sample_rate_hz", error=RecordingError)
    check_sample_rate_hz(rate_hz, f"{where}: sample_rate_hz", RecordingError)
    if header["gyro_unit"] not in GYRO_UNITS:
        raise RecordingError(f"{where}: gyro_unit {quote(header['gyro_unit'])} is not one of {', '.join(GYRO_UNITS)}")
    if header["gyro_unit"] == "lsb":
        if "lsb_per_dps" not in header:
            raise RecordingError(f"{where}: gyro_unit is lsb but header key 'lsb_per_dps' is missing")
        parse_number(header["lsb_per_dps"], f"{where}: lsb_per_dps", low=0, low_open=True, error=RecordingError)


#: column names that look like time stamps but are not ``t``: refused, so that a user's own file
#: with a "time" column is not read as uniform samples at the header's rate with its times ignored
TIME_LIKE_NAMES = frozenset({"time", "times", "timestamp", "timestamps", "time_s", "t_s", "seconds", "secs", "sec",
                             "stamp", "stamps"})


def _check_columns(names, where):
    """Refuse column names (as read: split at commas, spaces dropped) that are empty, repeated,
    lack ``gx, gy, gz`` or look like time stamps not named ``t`` (:data:`TIME_LIKE_NAMES`, any
    case: ``T`` too); ``where`` is the file and line."""
    if any(not n for n in names):
        raise RecordingError(f"{where}: empty column name in {quote(','.join(names))}")
    seen = set()
    dupes = sorted({n for n in names if n in seen or seen.add(n)})
    if dupes:
        raise RecordingError(f"{where}: duplicate column(s) {quote(', '.join(dupes))}")
    missing = [c for c in GYRO_COLUMNS if c not in seen]
    if missing:
        hint = ("; columns are separated by commas" if len(names) == 1 and any(c in names[0] for c in ";\t ") else
                "; names are lower case" if all(c.upper() in map(str.upper, names) for c in missing) else "")
        raise RecordingError(f"{where}: missing column(s) {', '.join(missing)} (have {quote(', '.join(names))}){hint}")
    times = [n for n in names if n.lower() in TIME_LIKE_NAMES or n == "T"]
    if times:
        raise RecordingError(f"{where}: column {quote(times[0])} looks like time stamps, which a recording holds "
                             "in a column named 't' (seconds); rename it t to use them, or to something else to keep "
                             "it as an extra column")


def _parse_chunk(lines, first, head):
    """(data, file line of each row) for ``lines``, the first being file line ``first``.

    Fast path: ``numpy.loadtxt`` on the list of lines, accepted when it gives one finite row per
    line. (Its parser, numpy >= 1.23, reads a finite number only in plain decimal syntax, as
    :func:`~gyrofilter.inputs.parse_number` does: ``0.0_1``, ``0x1``, ``1d5`` fail it.) Otherwise
    the lines are classified one by one: ``#`` lines are notes, blank lines are skipped, and the
    data lines are parsed again (loadtxt, then, if that still fails, line by line so that the
    first bad line is named).
    """
    n = len(head.names)
    if lines[0].strip() and not lines[0].startswith("#"):
        data = _loadtxt(lines, n)
        if data is not None:
            return data, np.arange(first, first + len(lines))
    rows, numbers = [], []
    for j, ln in enumerate(lines):
        if ln.startswith("#"):
            head.notes.append(Note(first + j, ln[1:].strip(), head.rows + len(rows)))
        elif ln.strip():
            rows.append(ln)
            numbers.append(first + j)
    numbers = np.array(numbers, dtype=np.int64)
    if not rows:
        return np.empty((0, n)), numbers
    data = _loadtxt(rows, n)
    if data is None:
        data = np.array([_parse_line(ln, line, head) for ln, line in zip(rows, numbers.tolist())])
    return data, numbers


def _loadtxt(lines, n):
    """``numpy.loadtxt`` of data lines with n columns, or None unless it gives len(lines) finite rows."""
    try:
        data = np.loadtxt(lines, delimiter=",", comments=None, ndmin=2, dtype=np.float64)
    except ValueError:
        return None
    return data if data.shape == (len(lines), n) and np.isfinite(data).all() else None


def _parse_line(ln, line, head):
    """The values of data line ``ln`` (file line ``line``), or RecordingError naming the reason:
    each cell a finite number in plain decimal syntax (:func:`~gyrofilter.inputs.is_plain_number`)."""
    path, names = head.path, head.names
    cells = ln.split(",")
    if len(cells) != len(names):
        raise RecordingError(f"{path}: line {line}: {len(cells)} values, expected {len(names)} "
                             f"({quote(','.join(names))})")
    values = []
    for name, cell in zip(names, cells):
        text = cell.strip()
        if not text:
            raise RecordingError(f"{path}: line {line}: column {quote(name)} is empty")
        plain = is_plain_number(text)
        try:
            value = float(text)
        except ValueError:
            raise RecordingError(f"{path}: line {line}: column {quote(name)} is not a number: {quote(text)}") from None
        if not math.isfinite(value):
            raise RecordingError(f"{path}: line {line}: column {quote(name)} is {quote(text)} (not a finite number)")
        if not plain:  # Python's extras: 0.0_1, other scripts' digits
            raise RecordingError(f"{path}: line {line}: column {quote(name)} is not a plain decimal number "
                                 f"(like 12, -0.5 or 1e-3): {quote(text)}")
        values.append(value)
    return values


#: the number of consecutive steps of ``t`` in each window whose median is compared with ``1 / sample_rate_hz``
RATE_CHECK_STEPS = 1000


class _TimeCheck:
    """The checks of a recording's ``t`` column, chunk by chunk (:meth:`add`), cheap and vectorised;
    the reader and the writer share them, so that what is written reads back:

    - ``t`` increases strictly, also across chunks;
    - steps longer than 1.5 sample intervals are counted in ``head.t_gaps`` (lost samples: legal);
    - the typical step of every window of :data:`RATE_CHECK_STEPS` consecutive steps, their lower
      median, is ``1 / sample_rate_hz`` within :data:`RATE_TOLERANCE`, in both directions: a ``t``
      that runs faster or slower than the header says, anywhere in the file, would make every
      time constant and Allan cluster time wrong. The windows start every half window (steps
      1-1000, 501-1500, 1001-2000, ...), so a stretch at the wrong rate as long as a window is
      caught wherever it lies; at the end, the steps after the last whole window are checked
      when there are half a window of them, and a file shorter than one window on all its steps
      (:meth:`finish`). Gaps lengthen some steps, not the median, unless they are most of a
      window's steps.

    ``head``: what the messages name (``head.path``) and where gaps are counted; ``why``: the
    advice a refusal ends with (the writer says why its rows would come out so).
    """

    def __init__(self, head, why="is sample_rate_hz or t wrong, or were most samples lost here?"):
        self.head = head
        self.why = why
        self.max_step_s = 1.5 / head.sample_rate_hz
        self.t_last = None
        self.last_where = None  # where the last sample of the previous chunk is
        self.phases = [_WindowPhase(0), _WindowPhase(RATE_CHECK_STEPS // 2)]

    def add(self, t, where):
        """Check the times ``t`` of a chunk; ``where(i)`` names its row ``i`` ("line 12")."""
        head = self.head
        if self.t_last is None:
            prev, cur, row0 = t[:-1], t[1:], 1
        else:
            prev, cur, row0 = np.concatenate(([self.t_last], t[:-1])), t, 0
        step = cur - prev
        bad = np.flatnonzero(step <= 0)
        if bad.size:
            k = int(bad[0])
            raise RecordingError(f"{head.path}: {where(k + row0)}: t does not increase "
                                 f"({float(cur[k])!r} after {float(prev[k])!r})")
        head.t_gaps += int(np.count_nonzero(step > self.max_step_s))
        last_where = self.last_where

        def step_start(i):  # where the sample a step of this chunk starts from is
            return where(i + row0 - 1) if i + row0 >= 1 else last_where

        for phase in self.phases:
            phase.add(step, step_start, self)
        self.t_last = float(t[-1])
        self.last_where = where(len(t) - 1)

    def finish(self):
        """At the end: the steps after the last whole window, when half a window or more (all of
        them in a file shorter than one window)."""
        whole_file = self.phases[0].windows == 0
        for phase in self.phases:
            if len(phase.pending) and (whole_file or len(phase.pending) >= RATE_CHECK_STEPS // 2):
                median = float(_lower_medians(phase.pending[None, :])[0])
                if self._off(median):
                    self._refuse(median, len(phase.pending), phase.pending_where, first=whole_file)
            if whole_file:
                break

    def _off(self, typical_s):
        expected_s = 1.0 / self.head.sample_rate_hz
        return np.abs(typical_s - expected_s) > RATE_TOLERANCE * expected_s

    def _refuse(self, typical_s, n, start, first):
        head = self.head
        which = "its first" if first else "the"
        raise RecordingError(
            f"{head.path}: t steps by {typical_s:.6g} s (median of {which} {n} steps from {start}), "
            f"but sample_rate_hz {head.sample_rate_hz:g} means {1.0 / head.sample_rate_hz:.6g} s: more than "
            f"{RATE_TOLERANCE:.0%} apart ({self.why})")


class _WindowPhase:
    """The whole windows of :data:`RATE_CHECK_STEPS` steps that start ``skip`` steps into the file."""

    def __init__(self, skip):
        self.skip = skip  # steps still to pass before the first window
        self.pending = np.empty(0)  # the steps after the last whole window
        self.pending_where = None  # where the first of them starts
        self.windows = 0  # the whole windows checked

    def add(self, step, step_start, check):
        first = min(self.skip, len(step))
        self.skip -= first
        step = step[first:]
        if len(self.pending) == 0 and len(step):
            self.pending_where = step_start(first)
        steps = np.concatenate((self.pending, step))
        whole = len(steps) // RATE_CHECK_STEPS * RATE_CHECK_STEPS
        if whole:
            medians = _lower_medians(steps[:whole].reshape(-1, RATE_CHECK_STEPS))
            wrong = np.flatnonzero(check._off(medians))
            if wrong.size:
                j = int(wrong[0])
                start = j * RATE_CHECK_STEPS - len(self.pending)
                check._refuse(float(medians[j]), RATE_CHECK_STEPS,
                              self.pending_where if start < 0 else step_start(first + start),
                              first=self.windows + j == 0 and self.skip == 0 and first == 0)
            self.windows += len(medians)
            if whole < len(steps):
                self.pending_where = step_start(first + whole - len(self.pending))
        self.pending = steps[whole:]


def _lower_medians(windows):
    """The lower median of each row of ``windows`` (2-D)."""
    k = (windows.shape[1] - 1) // 2
    return np.partition(windows, k, axis=1)[:, k]


# ---------------------------------------------------------------------------------------------
# writing


def format_number(x):
    """``x`` as header text that reads back to the same float: ``100`` for 100.0, else ``repr``."""
    return repr(int(x)) if float(x).is_integer() and abs(x) < 1e15 else repr(float(x))


#: %-format of a value written exactly: ``str`` of a float (a numpy scalar too) is the shortest
#: text that reads back to the same float
EXACT_FORMAT = "%s"
#: %-format of the filtered rates that ``run`` and ``replay`` write: 9 significant digits, on purpose
#: (far below the filter's noise; the raw data they come from are written exactly)
FILTERED_FORMAT = "%.9g"
_INTEGER_LIMIT = 2.0 ** 53  # integral floats below it are written as integers (exact, short)
#: control characters (line ends, tabs, ...), which header values and annotations never hold
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def one_line_text(text):
    """``text`` as a header value or an annotation holds it: each control character (a line end,
    a tab, ...) written as its escape (``\\n``), and each lone surrogate (a file name that is not
    UTF-8) as :func:`~gyrofilter.units.utf8_text` writes it (``\\udcff``), spaces at both ends
    dropped; that is what the reader reads back."""
    return _CONTROL.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"), utf8_text(str(text))).strip()


def header_text(header, columns, where):
    """The start of a recording as text: the version line, ``# key: value`` for each item of
    ``header`` in order (a ``gyrofilter-recording`` key is dropped), the column-name row.

    The one writer of recording headers (files, and stdout of ``run`` and ``replay --realtime``).
    Values are written as :func:`one_line_text` makes them. RecordingError naming ``where`` (the
    output) for what would not read back as written: a key that is empty, holds ``:``, spaces or
    control characters; a column name that is empty, holds ``,``, spaces or control characters
    (or the first one starting with ``#``); a line longer than :data:`MAX_LINE_BYTES`; and
    everything the reader refuses (:func:`_check_header`, :func:`_check_columns`: the same checks).
    """
    head = {"gyrofilter-recording": FORMAT_VERSION}
    for key, value in header.items():
        if key == "gyrofilter-recording":
            continue
        if not isinstance(key, str) or not key or _CONTROL.search(key) or ":" in key or key.split() != [key]:
            raise RecordingError(f"{where}: header key {quote(key)} is not a name (no ':', spaces or control characters)")
        head[key] = one_line_text(value)
    _check_header(head, where)
    columns = list(columns)
    for i, name in enumerate(columns):
        if (not isinstance(name, str) or _CONTROL.search(name) or "," in name or name.split() != [name]
                or (i == 0 and name.startswith("#"))):
            raise RecordingError(f"{where}: column name {quote(name)} is not a name (no ',', spaces or control characters)")
    _check_columns(columns, where)
    lines = [f"# {k}: {v}" for k, v in head.items()] + [",".join(columns)]
    for ln in lines:
        if len(ln.encode("utf-8")) > MAX_LINE_BYTES:
            raise RecordingError(f"{where}: header line {quote(ln)} is longer than {MAX_LINE_BYTES} bytes")
    return "\n".join(lines) + "\n"


def write_recording(path, rec: Recording, *, compresslevel=6):
    """Write ``rec`` to ``path`` (gzip at ``compresslevel`` when the name ends in ``.gz``), whole, in
    one go: every value exactly (it reads back as the same float), the notes after the data.
    The header, the values and ``t`` are checked before the file is created (:class:`RecordingWriter`)."""
    names = list(rec.columns)
    data = np.column_stack([rec.columns[c] for c in names]) if names else np.empty((0, 0))
    _check_finite(data, names, path)
    header_text(rec.header, names, path)
    if len(data):
        head = RecordingHead(header=rec.header, names=names, path=os.fspath(path))
        _check_rates(data, head, lambda row: f"row {row + 1} of the rows to write")
        if "t" in names:
            times = _TimeCheck(head, _NOT_WRITTEN)
            times.add(head.column(data, "t"), lambda row: f"row {row + 1} of the output")
            times.finish()
    with RecordingWriter(path, rec.header, names, flush_interval_s=None, compresslevel=compresslevel) as writer:
        writer.write(data)
        for line, text in rec.notes:
            writer.note(text)


#: what a writer's refusal of its ``t`` column says by default
_NOT_WRITTEN = "not written: it would not read back"


def _check_finite(rows, columns, where):
    """Refuse rows (n, len(columns)) holding NaN or +-inf, naming the first: a recording holds finite numbers."""
    bad = np.argwhere(~np.isfinite(rows))
    if bad.size:
        row, col = (int(i) for i in bad[0])
        raise RecordingError(f"{where}: column {quote(columns[col])} of row {row + 1} of the rows to write is "
                             f"{float(rows[row, col])!r}; a recording holds finite numbers only (those rows not written)")


class RecordingWriter(Closable):
    """Append rows to a recording, flushing at least every ``flush_interval_s`` seconds.

    Made for logging from a live source: after a crash or a pulled plug at most the last
    interval is lost, and the file still reads (the reader accepts a cut last line and a gzip
    stream without its end marker). ``close()`` (or leaving the ``with`` block, also on
    KeyboardInterrupt) ends the file cleanly. A write or flush that fails (an OSError: disk full,
    file size limit) sets ``write_failed``; ``close()`` then cuts the file back to its last
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
        The file to create (overwritten); gzip-compressed when the name ends in ``.gz``.
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
        gzip level 1-9 for ``.gz`` files.
    name : str, optional
        The file as messages name it (default ``path``; a writer to a temporary file names the user's).
    t_advice : str, optional
        What a refusal of the ``t`` column ends with: why the writer's rows could come out so
        (default: "not written: it would not read back").

    RecordingError for a bad header, column list or value, and for a ``t`` column the reader
    would refuse (:class:`_TimeCheck`, rows named "row N of the output"): a window refused as
    :meth:`write` completes it (its chunk not written), a file shorter than one window by
    :meth:`close` (the file is complete; a caller writing through a temporary file drops it).
    """

    def __init__(self, path, header: dict, columns, *, formats=None, flush_interval_s=1.0, fsync=True,
                 compresslevel=6, name=None, t_advice=None):
        self.path = os.fspath(path)
        self.name = self.path if name is None else os.fspath(name)
        self.columns = list(columns)
        text = header_text(header, self.columns, self.name)
        self._head = RecordingHead(header={k: str(v) for k, v in header.items()}, names=self.columns, path=self.name)
        self._times = _TimeCheck(self._head, t_advice or _NOT_WRITTEN) if "t" in self.columns else None
        self._formats = list(formats) if formats is not None else [None] * len(self.columns)
        if len(self._formats) != len(self.columns):
            raise RecordingError(f"{self.name}: {len(self._formats)} formats for {len(self.columns)} columns")
        self._flush_interval_s = flush_interval_s
        self._fsync = fsync
        self._raw = open(self.path, "wb")
        self._gz = gzip.GzipFile(fileobj=self._raw, mode="wb", mtime=0,
                                 compresslevel=compresslevel) if self.path.endswith(".gz") else None
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
        """Refuse to write after a failed write; note a new failure (``write_failed``)."""
        if self.write_failed:
            raise OSError(errno.EIO, "an earlier write failed", self.name)
        try:
            yield
        except OSError:
            self.write_failed = True
            raise

    def write(self, rows):
        """Append rows, shape (n, number of columns), in the columns' order; RecordingError (and
        none of them written) when one holds NaN or +-inf. The cells of an object array (text a
        converter formatted itself, say) go through their formats as they are, once checked as numbers."""
        rows = np.asarray(rows)
        if rows.size == 0:
            return
        if rows.ndim != 2 or rows.shape[1] != len(self.columns):
            raise RecordingError(f"{self.name}: rows must have shape (n, {len(self.columns)}), got {rows.shape}")
        try:
            values = rows.astype(float)
        except (TypeError, ValueError):
            raise RecordingError(f"{self.name}: rows to write must hold numbers") from None
        _check_finite(values, self.columns, self.name)
        _check_rates(values, self._head, lambda row: f"row {row + 1} of the rows to write")
        if self._times is not None:
            self._times.add(self._head.column(values, "t"), lambda row: f"row {self.rows_written + row + 1} of the output")
        fmt = ",".join(f if f is not None else _exact_format(values[:, i]) for i, f in enumerate(self._formats)) + "\n"
        self._emit("".join(fmt % tuple(r) for r in (rows if rows.dtype == object else values).tolist()))
        self.rows_written += len(rows)
        if self._flush_interval_s is not None and time.monotonic() - self._last_flush >= self._flush_interval_s:
            self.flush()

    def note(self, text):
        """Write an annotation line (``# text``, on one line: :func:`one_line_text`) between data
        rows, for example a gap; a text longer than :data:`MAX_NOTE_CHARS` is cut there."""
        self._emit(f"# {note_text(text)}\n")

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
        if self.write_failed:
            self._cut_to_last_flush()
            return
        if self._gz is not None:
            self._gz.close()
        self._raw.flush()
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
            if self._flushed_bytes is not None:
                os.ftruncate(fd, self._flushed_bytes)
        finally:
            os.close(fd)


#: longest annotation text a writer writes (characters; a gap note is about 60)
MAX_NOTE_CHARS = 4000


def note_text(text):
    """``text`` as an annotation line holds it: on one line (:func:`one_line_text`), cut at :data:`MAX_NOTE_CHARS`."""
    text = one_line_text(text)
    return text if len(text) <= MAX_NOTE_CHARS else f"{text[:MAX_NOTE_CHARS]}... (cut: {len(text)} characters)"


def _exact_format(values):
    """The exact format of a column's ``values`` (finite): ``%d`` when all are integers below 2^53
    in size (no decimal point), else :data:`EXACT_FORMAT`."""
    return "%d" if np.all((values == np.round(values)) & (np.abs(values) < _INTEGER_LIMIT)) else EXACT_FORMAT


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
    (its ``t_gaps`` counts the steps of ``t`` longer than 1.5 sample intervals); ``consequence``: text appended to the
    warning; ``warn``: a callable taking one line of text. Returns None; warns at most once.
    """
    if head.t_gaps:
        warn(f"{head.path}: t shows {head.t_gaps} gap(s) longer than 1.5 sample intervals; {consequence}")
