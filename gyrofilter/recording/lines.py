"""A recording file as lines of text, a block at a time: the bytes read (gunzipped when the file
starts with the gzip magic, every member), a UTF-8 byte-order mark dropped, split into lines at
``\\n`` and decoded. Memory: one block, whatever the file; a line longer than
:data:`~gyrofilter.recording.header.MAX_LINE_BYTES` is refused as soon as that many bytes are
read. Damaged gzip data are an error; a stream cut short (an interrupted recording) is a warning.
"""
from __future__ import annotations

import codecs
import re

from ..errors import RecordingError
from ..inputs import MAX_QUOTE_CHARS, READ_BYTES, open_input, quote
from .gzipped import GZIP_MAGIC, gunzipped
from .header import MAX_LINE_BYTES

_BOM = b"\xef\xbb\xbf"


def _byte_blocks(path, warnings):
    """The file's bytes in blocks of at most ``READ_BYTES``, gunzipped (:func:`~gyrofilter.recording.gzipped.gunzipped`) when it
    starts with the gzip magic."""
    fh = open_input(path)
    with fh:
        raw = fh.read(READ_BYTES)
        if raw[:2] == GZIP_MAGIC:
            yield from gunzipped(fh, raw, path, warnings)
            return
        while raw:
            yield raw
            raw = fh.read(READ_BYTES)


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
    a UTF-8 character); a file whose line ends are CR only is refused (:func:`refuse_cr_only`).
    A last line without its line end is not used (warning), unless it is the file's only line.
    A line longer than :data:`MAX_LINE_BYTES` is an error as soon as
    that many bytes are read (a line inside a block is shorter than the block, at most as
    long as the limit: only the line that the blocks so far have not ended needs a check)."""
    pending = b""
    first = 1  # number of the next line
    for block in _without_bom(_byte_blocks(path, warnings)):
        if first == 1:  # a block before the first LF: up to it (all of it, when it holds none)
            refuse_cr_only(block.partition(b"\n")[0], path)
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
            refuse_cr_only(pending, path, first)
            warnings.append(f"{path}: line {first}: last line has no line end (recording interrupted?); "
                            f"it is not used: {quote(pending.decode('utf-8', 'replace'), 60)}")
        else:
            yield first, [_decode(pending, path, first)]


#: a CR that ends no line (not before an LF, not the last byte read): a file whose line ends are CR only
_BARE_CR = re.compile(rb"\r(?!\n|$)")


def refuse_cr_only(first_line, path, line=None):
    """Refuse the file ``path`` (a recording or another tool's log) when ``first_line``, the bytes
    of its first line (or its first bytes, when no LF ends a line in them), holds a CR that ends
    no line: line ends of CR only (classic Mac OS), where the whole file would read as one line
    (a header missing its keys, one line of column names, or one too long). No first line holds
    such a CR otherwise: a recording's header values write a control character as its escape.
    With ``line`` (its number), ``first_line`` is a last line that no LF ends: lines whose ends
    turn CR only there (a log of CR lines appended to one of LF lines) are refused from that line,
    not dropped as a line an interruption cut (they were, with all their rows). Bytes that are no
    text (NUL bytes, not UTF-8: a file gzipped twice, an xz file, junk a power cut left) hold a CR
    by chance, not as a line end: they are left to the refusals of binary data (or the warning of
    a cut last line), whose words help where "convert them to LF" cannot."""
    if _BARE_CR.search(first_line) and _is_text(first_line):
        where = f"{path}: line {line}: line ends are CR only from there on" if line else f"{path}: line ends are CR only"
        raise RecordingError(f"{where} (old Mac): convert them to LF (e.g. tr '\\r' '\\n')")


def _is_text(data):
    """Whether ``data`` (a file's first bytes, perhaps cut inside a UTF-8 character at its end)
    reads as UTF-8 text without NUL bytes."""
    try:
        codecs.getincrementaldecoder("utf-8")().decode(data, final=False)
    except UnicodeDecodeError:
        return False
    return b"\0" not in data


def refuse_nul(data, path, first_line):
    """Refuse ``data`` (bytes of whole lines, the first being line ``first_line`` of ``path``)
    when it holds a NUL byte: no text holds one, and a file cut by a power failure (an SD card's
    unwritten blocks) starts or goes on with them; the first line that holds one is named."""
    at = data.find(b"\0")
    if at >= 0:
        line = first_line + data.count(b"\n", 0, at)
        if looks_utf16(data[max(0, at - 64):at + 64]):
            raise RecordingError(f"{path}: line {line}: UTF-16 text (every other byte NUL): save it as UTF-8")
        raise RecordingError(f"{path}: line {line}: NUL bytes (binary data, e.g. blocks a power cut left on an SD card), not text")


def looks_utf16(data):
    """Whether ``data`` reads as UTF-16 text (after a byte-order mark, if any): at least 90 % of its
    bytes at even or at odd offsets are NUL while at most 10 % of the others are (ASCII as UTF-16
    puts a NUL beside every character; a power cut's blocks are NUL throughout)."""
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        data = data[2:]
    if len(data) < 8:
        return False
    even, odd = data[0::2], data[1::2]
    share = lambda b: b.count(0) / len(b)  # noqa: E731
    return (share(even) >= 0.9 and share(odd) <= 0.1) or (share(odd) >= 0.9 and share(even) <= 0.1)


def _decode(data, path, first_line):
    """``data`` (whole lines, the first being line ``first_line``) as text, or RecordingError
    (not UTF-8, or UTF-8 holding NUL bytes: :func:`refuse_nul`)."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = first_line + data[:exc.start].count(b"\n")
        if looks_utf16(data[:64]):
            raise RecordingError(f"{path}: line {line}: UTF-16 text: save it as UTF-8") from None
        raise RecordingError(f"{path}: line {line}: not UTF-8 text") from None
    refuse_nul(data, path, first_line)
    return text
