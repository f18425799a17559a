"""The reader of recording format v1: :func:`iter_recording` reads a file in chunks of lines
(memory: one chunk, whatever the length of the file); :func:`read_recording` collects its chunks
into a :class:`~gyrofilter.recording.content.Recording`. Every line is checked (module
:mod:`gyrofilter.recording` says what is refused and what is tolerated).
"""
from __future__ import annotations

import math
import os
import re

import numpy as np

from ..errors import RecordingError, SettingsError
from ..inputs import BLANKS, check_number, is_plain_number, quote
from .checks import TimeCheck, check_rates
from .content import Note, Recording, RecordingHead
from .header import (MAX_HEADER_LINES, MAX_LINE_BYTES, MAX_NOTES, NOT_A_RECORDING, check_accelerometer, check_columns,
                     check_header, refuse_invisible, refuse_rowless)
from .gzipped import blame_gzip_damage
from .lines import line_chunks

#: most lines per chunk of :func:`iter_recording` (a chunk also ends with each block of text)
CHUNK_ROWS = 1 << 16
_BLOCK_ROWS = 1 << 19   # rows per block of collect_columns


def read_recording(path, *, columns=None, compact=False) -> Recording:
    """Read a format-v1 recording (``.csv`` or gzip, detected by content) from ``path``: the
    chunks of :func:`iter_recording` gathered by :func:`collect_columns`.

    ``columns``: None (every column), the names to keep, or a function of the file's column names
    that returns them (every line is still read and checked; the other columns are dropped as
    they are read; a text is refused: its letters are no list of names). ``compact``: keep a column in float32 where every value of it reads back exactly
    from float32 (:func:`collect_columns`): an analysis that needs only some columns of a long
    record holds half the memory, with the same numbers."""
    chunks = iter_recording(path)
    head = next(chunks)
    if isinstance(columns, (str, bytes)):
        chunks.close()
        raise SettingsError(f"{head.path}: the columns to keep are a list of names or a function of the file's names, "
                            f"got the text {quote(columns)}")
    names = head.names if columns is None else list(columns(list(head.names)) if callable(columns) else columns)
    return Recording(columns=collect_columns(head, chunks, names, compact=compact), header=head.header, path=head.path,
                     warnings=head.warnings, notes=head.notes, t_gaps=head.t_gaps)


def collect_columns(head, chunks, names, compact=False):
    """The columns ``names`` of the remaining ``chunks`` of :func:`iter_recording` as one float64
    array each (file units); ``head`` is the :class:`RecordingHead` it yielded first. With
    ``compact``, a column whose every value is exactly a float32 (``float64(float32(v)) == v``:
    the integers of an ``lsb`` column up to 2^24, a value with few binary digits) is kept in
    float32, half the memory, and gives the same numbers when converted back (``np.asarray(column,
    dtype=float)``); the first value that is not turns that column to float64.

    Values are copied into blocks (16 Ki rows, doubling up to ``_BLOCK_ROWS`` = 4 MB; large
    blocks are memory mappings of their own, so the many short-lived chunk buffers do not
    fragment the heap around them) and each column's blocks are joined at the end, one column
    at a time: the peak is the arrays with their last blocks' spare room, one more column and
    one chunk.

    A recording that does not fit in memory (a few MB of gzip can hold 10^9 rows) is a
    RecordingError naming the file and the rows read, not a MemoryError's traceback. ``names``
    that are not distinct columns of the file: SettingsError naming them.
    """
    if len(set(names)) != len(names) or not set(names) <= set(head.names):
        raise SettingsError(f"{head.path}: the columns to keep must be distinct columns of the file "
                            f"({', '.join(head.names)}), got {names!r}")
    try:
        return _gather(head, chunks, names, compact)
    except MemoryError:
        if hasattr(chunks, "close"):
            chunks.close()
        raise RecordingError(f"{head.path}: does not fit in memory: out of memory after {head.rows} rows of "
                             f"{len(names)} columns; analyse a part of it (split it into shorter files)") from None


def _gather(head, chunks, names, compact):
    """The work of :func:`collect_columns`."""
    where = [head.names.index(name) for name in names]
    blocks = {name: [] for name in names}
    dtypes = {name: np.float32 if compact else np.float64 for name in names}
    size = fill = 0
    for chunk in chunks:
        pos = 0
        while pos < len(chunk):
            if fill == size:  # a new block, twice the last one up to _BLOCK_ROWS
                size = min(_BLOCK_ROWS, max(1 << 14, 2 * size))
                for name in names:
                    blocks[name].append(np.empty(size, dtype=dtypes[name]))
                fill = 0
            take = min(size - fill, len(chunk) - pos)
            for name, i in zip(names, where):
                values = chunk[pos:pos + take, i]
                if dtypes[name] is np.float32 and not _exact_in_float32(values):
                    dtypes[name] = np.float64  # not exact in float32: this column in float64 from its start
                    with np.errstate(invalid="ignore"):  # the unfilled end of the last block is not yet data
                        blocks[name] = [b.astype(np.float64) for b in blocks[name]]
                blocks[name][-1][fill:fill + take] = values
            fill += take
            pos += take
    columns = {}
    for name in names:
        parts = blocks.pop(name)
        if parts:
            parts[-1] = parts[-1][:fill]
        columns[name] = np.concatenate(parts) if len(parts) > 1 else (parts[0].copy() if parts else np.empty(0, dtypes[name]))
    return columns


def _exact_in_float32(values):
    """Every value is a float32 exactly (a value beyond float32's range is not)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.array_equal(values.astype(np.float32), values)


def iter_recording(path, chunk_rows=CHUNK_ROWS):
    """Read the format-v1 recording at ``path`` in chunks: yields a :class:`RecordingHead` first, then float
    arrays of shape (k, number of columns), columns in file order and units, k <= ``chunk_rows``.

    The file is read a block (about 1 MB of text) at a time; the complete lines of a block, at
    most ``chunk_rows`` at a time, are parsed by ``numpy.loadtxt`` on their list; when that fails, or gives fewer rows than lines or non-finite values (annotations, blank lines
    or a bad line), the chunk's lines are classified one by one, so that annotations are kept
    and a bad line is named by its file line number and reason (:mod:`gyrofilter.recording`). A cut last
    line or a gzip stream without its end marker is added to ``head.warnings`` when the end is
    reached. A UTF-8 byte-order mark at the start is skipped. The ``t`` column is checked as
    :class:`TimeCheck` says (increasing, its typical step agreeing with ``sample_rate_hz``). A
    file whose blank and annotation lines after the header pass
    :data:`~gyrofilter.recording.header.MAX_BYTES_BEFORE_ROWS` before any row is refused then.
    """
    path = os.fspath(path)
    chunk_rows = check_number(chunk_rows, "chunk_rows", low=1, integer=True)
    warnings = []
    parts = line_chunks(path, chunk_rows, warnings)
    try:
        head, first, lines = _read_header(parts, path, warnings)
    except RecordingError as exc:
        raise blame_gzip_damage(path, exc) from None
    yield head
    times = TimeCheck(head) if "t" in head.names else None
    before_rows = 0  # bytes of the blank and annotation lines before the first row
    while True:
        if lines:
            try:
                data, line_numbers = _parse_chunk(lines, first, head)
                if not (head.rows or len(data)):
                    before_rows += sum(map(len, lines)) + len(lines)
                    refuse_rowless(path, before_rows)
                check_rates(data, head, lambda row: f"line {line_numbers[row]}")
                if len(data) and times is not None:
                    times.add(head.column(data, "t"), lambda row: f"line {line_numbers[row]}")
            except RecordingError as exc:
                raise blame_gzip_damage(path, exc) from None
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
            raise blame_gzip_damage(path, exc) from None


def _read_header(parts, path, warnings):
    """Header and column names from the first lines: (head, number of the next line, the rest
    of its chunk). The lines before the column row may be at most :data:`MAX_HEADER_LINES`."""
    header_lines = []
    size = 0  # characters of the header lines
    blank = True  # only blank lines so far
    for first, lines in parts:
        for j, ln in enumerate(lines):
            blank = blank and not ln.strip(BLANKS)
            if not ln.startswith("#") and not blank:
                header, line_of = _parse_header(header_lines, path)
                names = [c.strip(BLANKS) for c in ln.split(",")]
                check_columns(names, f"{path}: line {first + j}")
                check_accelerometer(header, names, path, line_of, first + j)
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
    checked by :func:`check_header`, and the line of each key; a line that is not ``key: value`` or repeats a key is an
    error naming its line."""
    header, line_of = {}, {}
    for i, ln in enumerate(lines):
        if not ln.startswith("#"):
            break
        body = ln[1:].strip(BLANKS)
        if not body:
            continue
        key, sep, value = body.partition(":")
        key = key.strip(BLANKS)
        if not sep or not key:
            hint = f"; {NOT_A_RECORDING}" if i == 0 else ""  # line 1 is the version's: another file altogether
            raise RecordingError(f"{path}: line {i + 1}: header line is not 'key: value': {quote(ln)}{hint}")
        refuse_invisible(key, "header key", f"{path}: line {i + 1}")  # before the repeat: 'k\u200b' shows as 'k'
        if key in header:
            raise RecordingError(f"{path}: line {i + 1}: header key {quote(key)} repeated (first on line {line_of[key]})")
        header[key], line_of[key] = value.strip(BLANKS), i + 1
    check_header(header, path)
    return header, line_of


def _parse_chunk(lines, first, head):
    """(data, file line of each row) for ``lines``, the first being file line ``first``.

    Fast path: ``numpy.loadtxt`` on the list of lines, accepted when it gives one finite row per
    line. (Its parser, numpy >= 1.23, reads a finite number only in plain decimal syntax, as
    :func:`~gyrofilter.inputs.parse_number` does: ``0.0_1``, ``0x1``, ``1d5`` fail it.) Otherwise
    the lines are classified one by one (a chunk of empty lines only at once): ``#`` lines are notes (the first :data:`MAX_NOTES`; a
    warning says when more are skipped), blank lines are skipped, and the
    data lines are parsed again (loadtxt, then, if that still fails, line by line so that the
    first bad line is named).
    """
    n = len(head.names)
    if not any(lines):  # empty lines only (a run of line ends): nothing to classify one by one
        return np.empty((0, n)), np.empty(0, dtype=np.int64)
    if lines[0].strip(BLANKS) and not lines[0].startswith("#"):
        data = _loadtxt(lines, n)
        if data is not None:
            return data, np.arange(first, first + len(lines))
    rows, numbers = [], []
    for j, ln in enumerate(lines):
        if ln.startswith("#"):
            if len(head.notes) < MAX_NOTES:
                head.notes.append(Note(first + j, ln[1:].strip(BLANKS), head.rows + len(rows)))
            elif not head.notes_cut:
                head.notes_cut = True
                head.warnings.append(f"{head.path}: line {first + j}: more than {MAX_NOTES} annotation lines; "
                                     "the first are kept, the others skipped")
        elif ln.strip(BLANKS):
            rows.append(ln)
            numbers.append(first + j)
    numbers = np.array(numbers, dtype=np.int64)
    if not rows:
        return np.empty((0, n)), numbers
    data = _loadtxt(rows, n)
    if data is None:
        data = np.array([_parse_line(ln, line, head) for ln, line in zip(rows, numbers.tolist())])
    return data, numbers


#: a character no data line's numbers, commas and blanks (:data:`~gyrofilter.inputs.BLANKS`) hold
_NOT_PLAIN = re.compile(f"[^0-9eE+\\-.,{re.escape(BLANKS)}]")


def _loadtxt(lines, n):
    """``numpy.loadtxt`` of data lines with n columns, or None unless it gives len(lines) finite rows."""
    if _NOT_PLAIN.search("".join(lines)):
        return None  # (loadtxt takes controls for blanks: \x1f5 as 5) each line on its own says which cell
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
        text = cell.strip(BLANKS)
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
