"""The bytes of a gzip file as pieces (:func:`pieces`): its data, the runs of padding in it (a power cut pads a file
with zeros on an SD card, 0xFF on erased flash) and at its end, the text it ends in (a note written after it);
:class:`Padded` gives them to :mod:`~gyrofilter.recording.gzipped`'s reader, a block at a time, and again from a run.
No I/O but reading the open file it is given."""
from __future__ import annotations

import collections
import re

from ..inputs import READ_BYTES

#: the shortest run of one byte, 0x00 or 0xFF, that starts a trial (deflate data of recordings with a time column,
#: levels 1-9, flushed every 1 to 1000 lines, hold none, but for a flush's marker, a member's header and 4 zeros
#: in the block headers of constant rows: measured, tools/gzip_runs.py)
RUN_BYTES = 5
#: memory a kept piece costs beside its bytes (a tuple and a bytes object, in CPython): counted against TRIAL_BYTES
#: (a run of 5 zeros and a byte, repeated, held 27 bytes a byte, attack pass 61)
_PIECE_BYTES = 100
#: a flush's empty stored block after a run of zeros (LEN 00 00, NLEN FF FF), not more FF
_FLUSH_MARK = re.compile(rb"\xff\xff(?!\xff)")
#: the fewest bytes of text (printable ASCII, tab, CR, LF, UTF-8) the file ends in that are a note written after its
#: gzip data (``echo "stopped at 10:42" >> rec.csv.gz``), not the stream's: ending in a line end, or without one
#: (``printf``; a shorter note is among the last bytes held back, gzipped.HOLD_BYTES); a cut stream's compressed bytes
#: so end about one time in 10^6 (measured: 12 bytes of text, a line end aside, end 151 of 3.1 million cuts, 17 bytes 1)
TEXT_END_BYTES = 12
TEXT_END_BARE_BYTES = 17
#: the file's last bytes that are text, read backwards (a UTF-8 sequence's continuation bytes before its lead byte)
_TEXT_BACKWARDS = re.compile(rb"(?:[\t\n\r\x20-\x7e]|[\x80-\xbf][\xc2-\xdf]|[\x80-\xbf]{2}[\xe0-\xef]|[\x80-\xbf]{3}[\xf0-\xf4])*")


def pieces(fh, first, shortest=RUN_BYTES):
    """The file's bytes (``first``, then ``fh``'s blocks) as ``(kind, byte or bytes, count)``: ``("data", bytes,
    0)``; ``("run", byte, count)``, a run of at least ``shortest`` bytes of one byte 0x00 or 0xFF that more bytes
    follow (not a flush's marker: :func:`_run_ends`, told by the bytes after it, across blocks too); ``("end", byte,
    count)``, the run of zeros or of 0xFF, at least ``shortest``, the file ends in (a shorter one is data: a
    whole stream's last bytes, or a cut one's, whose text is left out, attack pass 64); ``("text", bytes, 0)``, the text the file ends in (:func:`_text_end`). A run is counted, never held: a GB
    of zeros costs a block. Each block is scanned once, by
    ``bytes.find``; the next is read before it is given (its first bytes may tell a run's kind)."""
    run_byte, run_count, block, text = None, 0, first, b""  # the run the last block ended in (any count)
    while block:
        nxt, at = fh.read(READ_BYTES), 0
        if 0 < len(nxt) < READ_BYTES and is_text(nxt.rstrip(b"\0\xff")):  # the last block, all text: a note may
            size = len(trailing_text(block))  # begin in this one (attack pass 65)
            if 0 < size < len(block):
                block, nxt = block[:-size], block[-size:] + nxt
        if run_count:  # does the run go on?
            at = len(block) - len(block.lstrip(run_byte))
            run_count += at
            if at == len(block):
                block = nxt
                continue
            yield from _run_ends(run_byte, run_count, (block[at:at + 3] + nxt[:3])[:3], shortest)
            run_count = 0
        for start, end in _runs(block, at, shortest):
            if end == len(block):
                break  # it may go on in the next block
            if start > at:
                yield "data", block[at:start], 0
            yield from _run_ends(block[start:start + 1], end - start, (block[end:end + 3] + nxt[:3])[:3], shortest)
            at = end
        tail = block[at:]
        last = tail[-1:]
        if last in (b"\0", b"\xff"):  # the run the block ends in, any count: it may go on
            kept = tail.rstrip(last)
            run_byte, run_count, tail = last, len(tail) - len(kept), kept
        text = _text_end(tail) if not nxt else b""  # (before padding too: a note a C writer ended with NUL)
        if len(tail) > len(text):
            yield "data", tail[:len(tail) - len(text)], 0
        if text:
            yield "text", text, 0
        block = nxt
    if run_count >= shortest or run_count and text:  # (after a note: its own)
        yield "end", run_byte, run_count
    elif run_count:  # a flush's FF FF, a trailer's high zeros, a cut stream's own: the file's last bytes
        yield "data", run_byte * run_count, 0


def _text_end(block):
    """The text ``block`` (the file's last) ends in, where it is at least :data:`TEXT_END_BYTES` long and ends in a
    line end, or at least :data:`TEXT_END_BARE_BYTES`, else b"" (a note that begins in the block before is not seen)."""
    text = trailing_text(block)
    return text if len(text) >= (TEXT_END_BYTES if block.endswith(b"\n") else TEXT_END_BARE_BYTES) else b""


def trailing_text(data):
    """The text (printable ASCII, tab, CR, LF, UTF-8) ``data`` end in, of any length."""
    return data[len(data) - _TEXT_BACKWARDS.match(data[::-1]).end():]


def is_text(data):
    """Whether ``data`` are all text (printable ASCII, tab, CR, LF, UTF-8)."""
    return _TEXT_BACKWARDS.fullmatch(data[::-1]) is not None


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


def _run_ends(byte, count, after, shortest):
    """The piece of a run of ``count`` bytes ``byte`` before the bytes ``after`` (their first three): data when
    shorter than ``shortest`` or a zero run before a flush's marker (at most 6 zeros: a header byte, LEN, perhaps data
    bytes of zeros), else a run (a member header's zeros are told by :class:`_Header`)."""
    if count < shortest or byte == b"\0" and count <= 6 and _FLUSH_MARK.match(after):
        yield "data", byte * count, 0
    else:
        yield "run", byte, count


class Padded:
    """The bytes of a gzip file for :func:`_gunzip`, a piece of :func:`pieces` (of a run: a block) at a time.

    ``read()`` gives the next bytes (b"" at the end) and sets ``run`` to (offset, byte, count) when they start a run
    of padding that more bytes follow, else None; ``offset`` counts the bytes given; ``end_run`` is (byte, count) of
    the padding the file ends in, ``end_text`` the text it ends in (:func:`_text_end`), never given. ``keep()``, just after a run starts, keeps the pieces given from it on
    (``kept_bytes``: the memory they take, runs counted, not held) and ``rewind()`` gives them again."""

    def __init__(self, fh, first):
        self._pieces = pieces(fh, first)
        self._again = collections.deque()  # pieces to give again, before the file's next
        self._kept, self._from = None, None  # the pieces given since keep() (None: not kept), the run they start with
        self.kept_bytes, self.offset, self.run, self.end_run, self.end_text = 0, 0, None, None, b""
        self._byte, self._left = b"\0", 0  # the run being given, its bytes still to give

    def read(self):
        self.run = None
        if not self._left:
            piece = self._again.popleft() if self._again else next(self._pieces, None)
            if piece is None:
                return b""
            kind, data, count = piece
            if self._kept is not None:
                self._kept.append(piece)
                self.kept_bytes += (len(data) if kind == "data" else 0) + _PIECE_BYTES
            if kind == "end":
                self.end_run = data, count
                return self.read()  # (the file's last pieces, each set before either is looked at)
            if kind == "text":
                self.end_text = data
                return self.read()
            if kind == "data":
                self.offset += len(data)
                return data
            self.run, self._byte, self._left = (self.offset, data, count), data, count
        out = self._byte * min(self._left, READ_BYTES)
        self._left -= len(out)
        self.offset += len(out)
        return out

    def keep(self):
        """Keep the pieces given from the run the last ``read()`` started (``run``) on; returns that run."""
        offset, byte, count = self._from = self.run
        self._kept, self.kept_bytes = [("run", byte, count)], 0
        return self._from

    def rewind(self):
        """Give the pieces kept since ``keep()`` again, from the run's first byte; keep no more."""
        self._again.extendleft(reversed(self._kept))
        self.offset, self._left, self.end_run, self.end_text = self._from[0], 0, None, b""
        self._kept, self.kept_bytes = None, 0


def skip_padding(source, rest):
    """(count, byte values) of the padding (bytes 0x00 and 0xFF) that ``rest``, then the file read by ``source``,
    start with, and the bytes after it (b"": the file ends)."""
    count, seen = 0, set()
    while True:
        kept = rest.lstrip(b"\0\xff")
        skipped = rest[:len(rest) - len(kept)]
        count += len(skipped)
        seen |= {byte for byte in (0, 0xFF) if bytes([byte]) in skipped}
        if kept:
            return count, seen, kept
        rest = source.read()
        if not rest:
            if source.end_run:
                count += source.end_run[1]
                seen.add(source.end_run[0][0])
            return count, seen, b""


def end_zeros(source):
    """How many zero bytes the file read by ``source`` ends in (its padding, never given)."""
    return source.end_run[1] if source.end_run and source.end_run[0] == b"\0" else 0


def counted(count, seen):
    """``count`` bytes of the values ``seen`` (0x00, 0xFF), in words: ``5 zero bytes``, ``1 0xFF byte``."""
    name = {frozenset({0}): "zero byte", frozenset({0xFF}): "0xFF byte"}.get(frozenset(seen), "byte 0x00 and 0xFF")
    return f"{count} " + name.replace("byte", "byte" if count == 1 else "bytes", 1)
