"""The text of another tool's gyro log, for :mod:`gyrofilter.recording.foreign`: the log opened to
be read more than once (:func:`open_log`: a file where it is, a pipe copied first, within a bound,
its first line checked as its first bytes come) and its lines (:func:`log_lines`: numbered,
checked for length and UTF-8, the first for line ends of CR only, runs of empty lines read past a block at a time).
"""
from __future__ import annotations

import contextlib
import errno
import io
import os
import re
import shutil
import sys
import tempfile
import zlib

from ..errors import RecordingError
from ..inputs import BLANKS, READ_BYTES, open_input, quote
from .header import MAX_LINE_BYTES
from .gzipped import cut_short_warning, gunzipped
from .lines import refuse_cr_only, refuse_nul

#: most bytes of a pipe copied to the temporary folder (a pipe cannot be read twice; a file is read
#: where it is): 4 GiB, a 1 kHz log of about 40 h
MAX_PIPE_COPY_BYTES = 4 << 30
#: most bytes read from a pipe at a time
PIPE_BLOCK_BYTES = 1 << 20
#: the log name that means the standard input (``zcat log.gz | gyrofilter convert - --out rec.csv.gz``)
STDIN = "-"



def open_log(path, on_line=None):
    """The log ``path`` (``-``: the standard input) open for reading twice (binary): the file itself, or, when it cannot seek
    (a pipe: ``<(zcat log.gz)``, /dev/stdin), an anonymous temporary copy of its bytes (in the
    system's temporary folder, gone when closed), made one block at a time and bounded
    (:func:`_copy_pipe`); ``on_line(text, lines)`` sees the lines of a pipe as they are copied
    (:class:`_LineWatch`), until it returns True, so that a rule on the log's first lines (no data
    row in 64 MB) refuses it as it comes, not after copying GBs."""
    try:  # a closed standard input (``<&-``): sys.stdin is None, or fd 0 is no open file
        fd = None if path != STDIN else os.dup(sys.stdin.fileno()) if sys.stdin is not None else os.dup(0)
    except OSError as exc:
        raise RecordingError(f"{path}: cannot read: {exc.strerror or exc}") from None
    raw = open_input(path, fd=fd)
    if raw.seekable():
        return raw
    with raw:
        return _copy_pipe(raw, path, _LineWatch(on_line))


def _copy_pipe(raw, path, watch):
    """The pipe ``raw`` copied to an anonymous temporary file, rewound. The copy holds at most
    :data:`MAX_PIPE_COPY_BYTES` and at most half of the space free in the temporary folder
    (``TMPDIR``) when it starts, so that a piped log of many GB never fills that folder: a longer
    pipe, or a folder that fills all the same, is refused with what to do instead (give the
    log as a file, which is read where it is, or a roomier ``TMPDIR``). Its first block is
    checked as it comes (:func:`_first_line_ends`): a pipe of bytes that are no log (``cat
    /dev/zero``) is refused at once, not after 4 GiB; each block goes to ``watch`` (its refusal stops the copy)."""
    folder = tempfile.gettempdir()
    limit = min(MAX_PIPE_COPY_BYTES, shutil.disk_usage(folder).free // 2)
    instead = "save the log to a file and convert that (a file is read where it is, not copied), or set TMPDIR to a roomier folder"
    copy = tempfile.TemporaryFile()
    try:
        copied, start, check_at = 0, b"", 0  # start: the first blocks, until the first line is checked, when it doubles
        while block := raw.read1(PIPE_BLOCK_BYTES):  # what has come, at most a block
            if start is not None:
                start += block
                if len(start) >= check_at:  # (each check reads start anew: when it doubles, not each block, pass 62)
                    start = None if _first_line_ends(start, path) or len(start) > MAX_FIRST_CHECK_BYTES else start
                    check_at = 2 * check_at or PIPE_BLOCK_BYTES
            watch.feed(block)
            copied += len(block)
            if copied > limit:
                raise RecordingError(f"{path}: a pipe is copied to {folder} to be read twice, and this one holds more than "
                                     f"{limit} bytes (at most {MAX_PIPE_COPY_BYTES / 2**30:g} GiB and half of the space free "
                                     f"there); {instead}")
            copy.write(block)
        copy.flush()
        copy.seek(0)
    except OSError as exc:
        copy.close()
        where = "copying it to " + folder if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG) else "cannot read"
        raise RecordingError(f"{path}: {where}: {exc.strerror or exc}; {instead}") from None
    except BaseException:
        copy.close()
        raise
    return copy


class _LineWatch:
    """The lines of a log as its bytes come (gzip decompressed as they come, member after member,
    a block of text at a time), each handed to ``on_line(text, lines)`` (its line end dropped,
    UTF-8 with bad bytes replaced; a run of empty lines, ``\\n`` or ``\\r\\n`` alone, at once as
    ``("", run)``) until it returns True. A line longer than MAX_LINE_BYTES, or gzip data that do
    not decompress, end the watch: the reading refuses them, naming the line."""

    def __init__(self, on_line):
        self.on_line, self.done = on_line, on_line is None
        self.start, self.zipped, self.inflate, self.rest = b"", None, None, b""

    def feed(self, block):
        if self.done:
            return
        if self.zipped is None:  # gzip or not: its first two bytes say
            self.start += block
            if len(self.start) < 2:
                return
            self.zipped, block, self.start = self.start[:2] == b"\x1f\x8b", self.start, b""
        for text in self._inflated(block) if self.zipped else (block,):
            self._lines(text)
            if self.done:
                return

    def _inflated(self, data):
        while not self.done:
            self.inflate = self.inflate or zlib.decompressobj(31)
            try:
                text = self.inflate.decompress(data, PIPE_BLOCK_BYTES)
            except zlib.error:
                self.done = True
                return
            yield text
            if self.inflate.eof:  # the next member, if any
                data, self.inflate = self.inflate.unused_data, None
            else:
                data = self.inflate.unconsumed_tail
            if not data and len(text) < PIPE_BLOCK_BYTES:
                return

    def _lines(self, text):
        buf, at = self.rest + text, 0
        while not self.done:
            run = _LINE_ENDS.match(buf, at)  # a character class: a run of MBs matched at C speed, no stack
            if run and b"\n" in run.group():
                self.done, at = bool(self.on_line("", buf.count(b"\n", at, run.end()))), run.end()
                continue
            end = buf.find(b"\n", at)
            if end < 0:
                break
            self.done, at = bool(self.on_line(buf[at:end].rstrip(b"\r").decode("utf-8", "replace"), 1)), end + 1
        self.rest = buf[at:]
        self.done = self.done or len(self.rest) > MAX_LINE_BYTES


#: the most bytes of a pipe its first line is checked in as they come (gzip of zeros, padding after a cut in line 1,
#: holds no text: past this the reading decides, after the copy)
MAX_FIRST_CHECK_BYTES = 1 << 26


def _first_line_ends(start, path):
    """True when ``start``, the first bytes of a log (gzip-compressed or not), holds the end of
    its first line within MAX_LINE_BYTES + 1 bytes of text; False while it holds fewer bytes of
    text and no line end; a refusal when :func:`log_lines` would refuse line 1 whatever follows (no
    line end in that many bytes, gzip data that do not decompress)."""
    text = start
    if start[:2] == b"\x1f\x8b":  # by the reader's rules (padding after a cut is no text: attack pass 61)
        text = b""
        for block in gunzipped(io.BytesIO(b""), start, path, []):
            text += block
            if b"\n" in text or len(text) > MAX_LINE_BYTES:
                break
        if b"\n" not in text and len(text) <= MAX_LINE_BYTES:  # its text after a run of padding is on trial: zlib's
            with contextlib.suppress(zlib.error):                # alone refuses it where it holds no line either way
                plain = zlib.decompressobj(31).decompress(start, MAX_LINE_BYTES + 1)  # (gzip of NUL bytes holds runs)
                text = plain if b"\n" not in plain and len(plain) > MAX_LINE_BYTES else text
        text = text[:MAX_LINE_BYTES + 1]
    refuse_cr_only(text.split(b"\n", 1)[0], path)
    if b"\n" in text:
        return True
    if len(text) > MAX_LINE_BYTES:
        raise _too_long(path, 1)
    return False


def _too_long(path, number):
    """The refusal of the log's line ``number``, longer than MAX_LINE_BYTES bytes."""
    return RecordingError(f"{path}: line {number}: longer than {MAX_LINE_BYTES} bytes, not a line of a log")


def log_lines(raw, path, warnings=None):
    """(line number, text, lines) of the open log ``raw`` (the file ``path``; gzip when it starts
    with the gzip magic), from its start, line ends dropped, each line at most MAX_LINE_BYTES
    bytes and UTF-8; ``lines`` is 1, or for a run of empty lines (``\\n`` or ``\\r\\n`` alone) the
    number of them, one item with ``text`` "" numbered by the first (a line holding a NUL byte:
    :func:`~gyrofilter.recording.lines.refuse_nul`): a run is skipped in bulk
    (:func:`_skip_empty_lines`), so that 30 MB of line ends (30 kB of gzip) cost no more than a
    few blocks, not a Python step each (17 s). The first bytes are peeked at, not read.
    A last line without its line end (a log whose writer was stopped mid-line, cut inside a
    number) is not used, unless it is the log's only line or blank, and said in ``warnings`` (a
    list, when given): the rule of a recording's (:func:`~gyrofilter.recording.lines.line_chunks`).
    gzip is read by the recording's reader (:func:`~gyrofilter.recording.gzipped.gunzipped`): a stream
    cut short (no end marker) has its lines up to the cut read, and ``warnings`` says so with the last
    line read; zero bytes at its end (block padding) are left out, never read as more of the stream."""
    raw.seek(0)
    gzip_notes = []
    zipped = raw.peek(2)[:2] == b"\x1f\x8b"
    fh = io.BufferedReader(_Blocks(gunzipped(raw, raw.read(READ_BYTES), path, gzip_notes)), PIPE_BLOCK_BYTES) if zipped else raw
    last = 0  # the number of the last line read
    for number, text, lines in _numbered(fh, path, warnings):
        yield number, text, lines
        last = number + lines - 1
    if warnings is not None:
        warnings.extend(f"{note}; read to line {last}" if note == cut_short_warning(path) else note for note in gzip_notes)


def _numbered(fh, path, warnings):
    """The items of :func:`log_lines` read from ``fh``, the log's text."""
    number = 0
    while True:
        data = fh.readline(MAX_LINE_BYTES + 1)
        if not data:
            return
        number += 1
        if number > 1 and not data.endswith(b"\n") and data.strip(BLANKS.encode()) and len(data) <= MAX_LINE_BYTES:
            refuse_cr_only(data, path, number)
            if warnings is not None:
                warnings.append(f"{path}: line {number}: last line has no line end (log interrupted?); it is "
                                f"not used: {quote(data.decode('utf-8', 'replace'), 60)}")
            return
        if data in (b"\n", b"\r\n"):
            run = 1 + _skip_empty_lines(fh)
            yield number, "", run
            number += run - 1
            continue
        refuse_nul(data, path, number)
        if number == 1:
            refuse_cr_only(data, path)
        if len(data.rstrip(b"\r\n")) > MAX_LINE_BYTES:
            raise _too_long(path, number)
        try:
            yield number, data.decode("utf-8-sig" if number == 1 else "utf-8").rstrip("\r\n"), 1
        except UnicodeDecodeError:
            raise RecordingError(f"{path}: line {number}: not UTF-8 text") from None


class _Blocks(io.RawIOBase):
    """A readable stream of the byte blocks ``blocks`` yields (a gzip file's text), for a buffered reader's
    ``readline`` and ``peek``."""

    def __init__(self, blocks):
        super().__init__()
        self.blocks, self.block, self.at = blocks, b"", 0

    def readable(self):
        return True

    def readinto(self, buffer):
        while self.at >= len(self.block):
            self.block, self.at = next(self.blocks, None), 0
            if self.block is None:
                self.block = b""
                return 0
        n = min(len(buffer), len(self.block) - self.at)
        buffer[:n] = memoryview(self.block)[self.at:self.at + n]
        self.at += n
        return n


_EMPTY_LINES = re.compile(rb"(?:\r?\n)+")
#: line ends (and CRs) in a row: empty lines, for :class:`_LineWatch`
_LINE_ENDS = re.compile(rb"[\r\n]+")


#: most bytes of empty lines one item of :func:`log_lines` stands for: a longer run comes as
#: several, so that a reader counting what it skipped sees it grow (2 GiB of line ends)
MAX_RUN_BYTES = 16 << 20


def _skip_empty_lines(fh):
    """Read past the empty lines (``\\n`` or ``\\r\\n`` alone) that come next in ``fh``, a buffered
    block at a time (``peek``), at most :data:`MAX_RUN_BYTES`; how many there were."""
    skipped = read = 0
    while read < MAX_RUN_BYTES:
        ahead = fh.peek(PIPE_BLOCK_BYTES)
        run = _EMPTY_LINES.match(ahead)
        if run is None:
            return skipped
        fh.read(run.end())
        read += run.end()
        skipped += run.group().count(b"\n")
        if run.end() < len(ahead):
            return skipped
    return skipped
