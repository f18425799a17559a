"""The text of a gzip file (a recording, another tool's log), a block at a time, every member, as a power cut leaves it.

A stream cut short (no end marker: a recorder killed) is read to its cut, with a warning. Damaged data (corrupt
blocks, a checksum or length that does not match) are an error. Padding is told apart from the stream: a run of
at least :data:`RUN_BYTES` bytes 0x00 or 0xFF (an SD card's unwritten blocks read as zeros, erased flash as 0xFF;
deflate data of text hold no such run, but for the empty stored block of a flush, ``00 00 FF FF`` after a zero
or two, and the zeros of a member's header). Padding at the file's end is never given to zlib (which reads it
after a cut stream as more data: back-references that copy earlier text, rows invented, attack pass 58); text
that zlib makes of bytes after a run of padding, in a stream that then ends cut short or does not decompress, is
left out (zeros, then a byte, attack pass 59): it is not the recorder's.
"""
from __future__ import annotations

import os
import re
import zlib

from ..errors import RecordingError
from ..inputs import READ_BYTES
from .header import MAX_LINE_BYTES

#: most decompressed bytes at a time (a block of text: about 36 000 lines of five columns); the
#: longest line, so that only the line the blocks so far have not ended needs a length check
_TEXT_BYTES = MAX_LINE_BYTES
GZIP_MAGIC = b"\x1f\x8b"
#: the shortest run of one byte, 0x00 or 0xFF, that is padding, not compressed data (deflate data of text, levels
#: 1-9, flushed every 1 to 1000 lines, hold none, but for a flush's marker, a member's header and 4 zeros in the
#: block headers of highly repetitive text: measured, tools/bench_reader.py --gzip-runs)
RUN_BYTES = 5
#: compressed bytes, or bytes of text, after a run of padding that, once they decompress, make its stream's text
#: trusted again (junk after padding fails within tens of bytes and makes a line or two; a run inside a real stream,
#: as highly repetitive text makes, costs at most this much text of a stream cut short after it)
TRUST_BYTES = 1024
TRUST_TEXT_BYTES = 1 << 16
#: a flush's empty stored block after a run of zeros (LEN 00 00, NLEN FF FF), not more FF
_FLUSH_MARK = re.compile(rb"\xff\xff(?!\xff)")
#: a member's start before its header's zeros (magic, method, perhaps its flags)
_MEMBER_START = re.compile(rb"\x1f\x8b\x08.?\Z", re.DOTALL)


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
            raw = fh.read(READ_BYTES)
            if raw[:2] == GZIP_MAGIC:
                for _ in gunzipped(fh, raw, path, []):
                    pass
    except _GzipDamage as exc:
        return exc.reason
    except OSError:
        pass
    return None


def gunzipped(fh, first, path, warnings):
    """The text of the gzip file ``path`` open as ``fh`` (``first``: its first bytes, already read), every member, in
    blocks of at most ``_TEXT_BYTES`` (a gzip bomb never holds more); what was left out said in ``warnings``. The
    one gzip reader of recordings and of other tools' logs (``logtext.log_lines``)."""
    return _gunzip(_Padded(fh, first), path, warnings)


def _pieces(fh, first, shortest=RUN_BYTES):
    """The file's bytes (``first``, then ``fh``'s blocks) as ``(kind, byte or bytes, count)``: ``("data", bytes,
    0)``; ``("run", byte, count)``, a run of at least ``shortest`` bytes of one byte 0x00 or 0xFF that more bytes
    follow (not a flush's marker, not a member header's zeros); ``("end", byte, count)``, the run of zeros (any
    count) or of 0xFF (at least ``shortest``) the file ends in. A run is counted, never held: a GB of zeros costs a
    block. Each block is scanned once, by a regular expression."""
    run_byte, run_count, before = None, 0, b""  # the run the last block ended in (any count), the 4 bytes before it
    block = first
    while block:
        at = 0
        if run_count:  # does the run go on?
            at = len(block) - len(block.lstrip(run_byte))
            run_count += at
            if at == len(block):
                block = fh.read(READ_BYTES)
                continue
            yield from _run_ends(run_byte, run_count, before, block[at:at + 3], shortest)
            run_count = 0
        for start, end in _runs(block, at, shortest):
            if end == len(block):
                break  # it may go on in the next block
            if start > at:
                yield "data", block[at:start], 0
            yield from _run_ends(block[start:start + 1], end - start, block[max(0, start - 4):start],
                                 block[end:end + 3], shortest)
            at = end
        tail = block[at:]
        last = tail[-1:]
        if last in (b"\0", b"\xff"):  # the run the block ends in, any count: it may go on
            kept = tail.rstrip(last)
            run_byte, run_count, before = last, len(tail) - len(kept), kept[-4:]
            tail = kept
        if tail:
            yield "data", tail, 0
        block = fh.read(READ_BYTES)
    if run_count >= shortest or run_byte == b"\0" and run_count:
        yield "end", run_byte, run_count
    elif run_count:
        yield "data", run_byte * run_count, 0  # a flush's FF FF, the file's last bytes


#: a run of one byte, from where it starts
_SAME = {0: re.compile(rb"\x00+"), 0xFF: re.compile(rb"\xff+")}


def _runs(block, at, shortest):
    """(start, end) of each run of at least ``shortest`` bytes 0x00 or 0xFF in ``block`` from ``at``: found by
    ``bytes.find`` (a regular expression of either run tries each position: 1 s for 20 MB), each byte's search
    going on from where its last ended."""
    found = {byte: block.find(bytes([byte]) * shortest, at) for byte in _SAME}
    while any(i >= 0 for i in found.values()):
        start, byte = min((i, byte) for byte, i in found.items() if i >= 0)
        end = _SAME[byte].match(block, start).end()
        yield start, end
        for other, i in found.items():
            if 0 <= i < end:
                found[other] = block.find(bytes([other]) * shortest, end)


def _run_ends(byte, count, before, after, shortest):
    """The piece of a run of ``count`` bytes ``byte`` between the bytes ``before`` and ``after`` (their first
    three): data when shorter than ``shortest``, a zero run before a flush's marker (at most 6 zeros: a header byte,
    LEN, perhaps data bytes of zeros) or in a member's header, else a run."""
    if count < shortest or byte == b"\0" and (count <= 6 and _FLUSH_MARK.match(after) or _MEMBER_START.search(before)):
        yield "data", byte * count, 0
    else:
        yield "run", byte, count


class _Padded:
    """The bytes of a gzip file for :func:`_gunzip`, in blocks (:func:`_pieces`): ``read()`` gives the next (b"" at
    the end), ``offset`` counts those given, ``runs`` the runs of padding more bytes followed, ``run`` the last
    (offset, byte, count); ``held`` and ``held_byte``: the padding the file ends in, never given."""

    def __init__(self, fh, first):
        self.pieces = _pieces(fh, first)
        self.offset, self.runs, self.run, self.held, self.held_byte = 0, 0, None, 0, b"\0"
        self._left = 0  # bytes of the current run still to give

    def read(self):
        if self._left:
            out = self.run[1] * min(self._left, READ_BYTES)
            self._left -= len(out)
        else:
            kind, data, count = next(self.pieces, (None, b"", 0))
            if kind is None:  # read past the end
                return b""
            if kind == "end":
                self.held, self.held_byte = count, data
                return b""
            if kind == "run":
                self.runs, self.run, self._left = self.runs + 1, (self.offset, data, count), count
                return self.read()
            out = data
        self.offset += len(out)
        return out


def _gunzip(source, path, warnings):
    """The text of the gzip file read by ``source`` (:class:`_Padded`), every member, in blocks of at most
    ``_TEXT_BYTES``.

    A stream that ends before its end marker (an interrupted recording) ends the text with a
    warning. Damaged data are an error (:class:`_GzipDamage`): corrupt compressed blocks, a
    checksum or length that does not match (the text may look fine: a changed digit in a
    stored block), or bytes after a member that do not start another member. Padding at the end is left out with a
    warning; a whole stream whose last bytes of length are zeros takes them back (:func:`_padded_end`). Text made
    of the bytes after a run of padding is held until its stream ends whole (checked by zlib) or TRUST_BYTES more
    bytes decompress (or make TRUST_TEXT_BYTES of text); a stream that ends cut short or does not decompress before then ends at the run, its held
    text left out with a warning (:func:`_after_run_warning`)."""
    d = zlib.decompressobj(16 + zlib.MAX_WBITS)
    produced, trusted, held = 0, 0, []  # bytes of text so far; source.runs trusted; text after a run not yet trusted
    raw = source.read()
    while True:
        try:
            out = d.decompress(raw, _TEXT_BYTES)
        except zlib.error as exc:
            if source.runs == trusted:
                raise _GzipDamage(path, str(exc), produced) from None
            warnings.append(_after_run_warning(path, source.run, held, "does not decompress"))
            return
        if source.runs > trusted:
            held.append(out)
            if (d.eof or source.offset - source.run[0] - source.run[2] >= TRUST_BYTES
                    or sum(map(len, held)) >= TRUST_TEXT_BYTES):
                out, held, trusted = b"".join(held), [], source.runs
        if out and source.runs == trusted:
            produced += len(out)
            yield out
        if d.eof:  # a member ended: another may follow
            raw = d.unused_data or source.read()
            if not raw:
                if source.held:
                    warnings.append(_padding_warning(path, source.held, source.held_byte, True))
                return
            if raw[:2] != GZIP_MAGIC and not GZIP_MAGIC.startswith(raw):  # (a 1f alone may start a member cut short)
                raise _GzipDamage(path, "bytes after the end of the gzip stream that are not gzip", produced)
            d = zlib.decompressobj(16 + zlib.MAX_WBITS)
        elif d.unconsumed_tail or len(out) == _TEXT_BYTES:  # (text zlib holds back is the input's before more)
            raw = d.unconsumed_tail
        elif raw := source.read():
            continue
        else:
            yield from _cut_end(d, source, path, warnings, held if source.runs > trusted else None)
            return


def _cut_end(d, source, path, warnings, held):
    """The end of the file ``source`` read, inside the stream of the decompressor ``d``: the text it takes from
    zero padding to end whole (:func:`_padded_end`), or the warnings of a stream cut short; ``held``: the text
    after a run of padding not yet trusted (None: none), left out."""
    whole, out = _padded_end(d, source.held if source.held_byte == b"\0" else 0)
    if held is not None:
        if whole:
            yield b"".join(held) + out
        else:
            warnings.append(_after_run_warning(path, source.run, held, "ends cut short"))
    elif out:
        yield out
    if source.held > whole:
        warnings.append(_padding_warning(path, source.held - whole, source.held_byte, whole))
    if not whole:
        warnings.append(cut_short_warning(path))


def _padded_end(d, padding):
    """``(how many of the ``padding`` zero bytes the stream of the decompressor ``d`` takes to end whole, its last
    text)``: the high bytes of its checksum and length (RFC 1952) are zeros, and an empty member's last deflate
    byte; or ``(0, b"")`` where it does not end so (cut short: zeros read as its data would be garbage, or damage)."""
    trial, out = d.copy(), b""
    for taken in range(1, min(16, padding) + 1):
        try:
            out += trial.decompress(b"\0")
        except zlib.error:
            return 0, b""
        if trial.eof:
            return taken, out
    return 0, b""


def _padding_warning(path, count, byte, after_stream):
    """The warning of ``count`` bytes ``byte`` (0x00 or 0xFF) left out at the end of the gzip file ``path``,
    ``after_stream`` a whole one or after one cut short."""
    what = "zero bytes" if byte == b"\0" else "0xFF bytes"
    return (f"{path}: {count} {what} " + ("after the end of the gzip stream ignored (block padding, as gzip ignores it)"
                                          if after_stream else "at its end ignored (block padding, as a power cut leaves an SD card)"))


def _after_run_warning(path, run, held, how):
    """The warning of the text after the run of padding ``run`` (offset, byte, count) in a stream that then ``how``
    (ends cut short, does not decompress): ``held``, its text made of the bytes after the run, left out."""
    offset, byte, count = run
    text = sum(map(len, held))
    return (f"{path}: {count} bytes 0x{byte[0]:02X} at byte {offset} (padding), then bytes that are not the stream's: "
            f"it {how} there; {text} bytes of text zlib made of them not used")


def cut_short_warning(path):
    """The warning of a gzip file ``path`` whose stream ends before its end marker (an interrupted
    recording or log): its text so far is read, complete lines only. The one rule of a recording
    (:func:`~gyrofilter.recording.lines.line_chunks`) and of another tool's log (``logtext.log_lines``)."""
    return f"{path}: gzip stream cut short (no end marker), as an interrupted recording leaves it"
