"""A recording file as lines of text, a block at a time: the bytes read (gunzipped when the file
starts with the gzip magic, every member), a UTF-8 byte-order mark dropped, split into lines at
``\\n`` and decoded. Memory: one block, whatever the file; a line longer than
:data:`~gyrofilter.recording.header.MAX_LINE_BYTES` is refused as soon as that many bytes are
read. Damaged gzip data are an error; a stream cut short (an interrupted recording) is a warning.
"""
from __future__ import annotations

import errno
import io
import os
import select
import stat
import time
import zlib

from ..errors import RecordingError
from ..inputs import MAX_QUOTE_CHARS, quote
from .header import MAX_LINE_BYTES

_READ_BYTES = 1 << 20   # bytes read from the file at a time
#: most decompressed bytes at a time (a block of text: about 36 000 lines of five columns); the
#: longest line, so that only the line the blocks so far have not ended needs a length check
_TEXT_BYTES = MAX_LINE_BYTES
_BOM = b"\xef\xbb\xbf"
_GZIP_MAGIC = b"\x1f\x8b"


class _GzipDamage(RecordingError):
    """Damaged gzip data: what was read from them cannot be trusted. ``reason``: what zlib said."""

    def __init__(self, path, reason, produced):
        super().__init__(f"{path}: damaged gzip data ({reason}) after {produced} bytes of text; "
                         "nothing read from it is trusted")
        self.reason = reason


def blame_gzip_damage(path, exc):
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
    if not os.path.isfile(path):  # a pipe was read once, as it came
        return None
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


def sibling_hint(path, exc):
    """"; there is NAME" when ``exc`` says ``path`` does not exist but its sibling with or without
    ``.gz`` does (``rec.csv`` for ``rec.csv.gz``, and the other way round), else ""."""
    if not isinstance(exc, FileNotFoundError):
        return ""
    path = os.fspath(path)
    sibling = path[:-3] if path.endswith(".gz") else path + ".gz"
    return f"; there is {sibling}" if os.path.isfile(sibling) else ""


#: seconds an input that is a pipe (a FIFO made by ``mkfifo``, ``<(zcat log.gz)``) is waited for:
#: its writer's first bytes, or the writer itself
PIPE_WAIT_S = 5.0


def open_input(path, *, fd=None):
    """The input file ``path`` open for reading (binary), the one place inputs are opened (a
    recording, another tool's log). Opening never blocks (``O_NONBLOCK``: a FIFO that nobody
    writes to would block ``open`` forever): a regular file or a device is read as it is; a
    pipe (a FIFO, ``<(zcat log.gz)``, the standard input given as ``fd``) is read once, as it
    comes, when within :data:`PIPE_WAIT_S` s its writer is there (a read that would wait) or its
    first bytes come, and refused as "not a regular file" otherwise, the bytes read meanwhile
    kept; a folder is refused. ``fd``: the input open already (the standard input, whose writer
    is the shell's pipeline: read as it is). RecordingError naming ``path``."""
    given = fd is not None
    try:
        if not given:
            fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
        mode = os.fstat(fd).st_mode
    except OSError as exc:
        raise RecordingError(f"{path}: cannot read: {exc.strerror or exc}{sibling_hint(path, exc)}") from None
    if stat.S_ISDIR(mode):
        os.close(fd)
        raise RecordingError(f"{path}: cannot read: {os.strerror(errno.EISDIR)}")
    if given or not stat.S_ISFIFO(mode):
        os.set_blocking(fd, True)
        return open(fd, "rb")
    try:
        first = _first_pipe_bytes(fd, path)
    except BaseException:
        os.close(fd)
        raise
    os.set_blocking(fd, True)
    return io.BufferedReader(_Prefixed(fd, first), _READ_BYTES)


def _first_pipe_bytes(fd, path):
    """What the pipe ``fd`` (non-blocking) holds first: its first bytes, or b"" when its writer is
    there but has written nothing yet; waited for :data:`PIPE_WAIT_S` s (a read that finds no
    writer returns at once with nothing: the writer of a FIFO may come later), then refused."""
    deadline = time.monotonic() + PIPE_WAIT_S
    while True:
        try:
            first = os.read(fd, _READ_BYTES)
        except BlockingIOError:
            return b""
        if first:
            return first
        left = deadline - time.monotonic()
        if left <= 0:
            raise RecordingError(f"{path}: not a regular file (a pipe or FIFO) and nothing was written to it in "
                                 f"{PIPE_WAIT_S:g} s; give the file itself")
        select.select([fd], [], [], min(left, 0.05))


class _Prefixed(io.RawIOBase):
    """The pipe ``fd`` read as a raw stream, ``first`` (its bytes read already) ahead of the rest."""

    def __init__(self, fd, first):
        self.fd, self.first = fd, first

    def readable(self):
        return True

    def readinto(self, buffer):
        if self.first:
            n = min(len(buffer), len(self.first))
            buffer[:n], self.first = self.first[:n], self.first[n:]
            return n
        data = os.read(self.fd, len(buffer))
        buffer[:len(data)] = data
        return len(data)

    def fileno(self):
        return self.fd

    def close(self):
        if not self.closed:
            os.close(self.fd)
        super().close()


def _byte_blocks(path, warnings):
    """The file's bytes in blocks of at most ``_READ_BYTES``, gunzipped (:func:`_gunzip`) when it
    starts with the gzip magic."""
    fh = open_input(path)
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


def line_chunks(path, chunk_rows, warnings):
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


def refuse_nul(data, path, first_line):
    """Refuse ``data`` (bytes of whole lines, the first being line ``first_line`` of ``path``)
    when it holds a NUL byte: no text holds one, and a file cut by a power failure (an SD card's
    unwritten blocks) starts or goes on with them; the first line that holds one is named."""
    at = data.find(b"\0")
    if at >= 0:
        line = first_line + data.count(b"\n", 0, at)
        raise RecordingError(f"{path}: line {line}: NUL bytes (binary data, e.g. blocks a power cut left on an SD card), not text")


def _decode(data, path, first_line):
    """``data`` (whole lines, the first being line ``first_line``) as text, or RecordingError
    (not UTF-8, or UTF-8 holding NUL bytes: :func:`refuse_nul`)."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = first_line + data[:exc.start].count(b"\n")
        raise RecordingError(f"{path}: line {line}: not UTF-8 text") from None
    refuse_nul(data, path, first_line)
    return text
