"""The text of a gzip file (a recording, another tool's log), a block at a time, every member, as a power cut leaves it.

A stream cut short (no end marker: a recorder killed) is read to its cut, with a warning. Damaged data (corrupt
blocks, a checksum or length that does not match) are an error. Padding (an SD card's unwritten blocks read as
zeros, erased flash as 0xFF) is told apart from the stream, for zlib reads it as more of a stream cut short (zeros
in a block of constant rows are its code for "the same again": rows invented, attack passes 58 and 60):

- padding the file ends in is never given to zlib (but the zeros a whole stream's trailer takes: :func:`_padded_end`);
- padding after a whole member is left out, with a warning; a member after it is read;
- from a run of at least :data:`~gyrofilter.recording.gzip_bytes.RUN_BYTES` bytes 0x00 or 0xFF that more bytes
  follow, inside a stream, the stream is on trial (:func:`_member`): its text is used only once it ends whole
  (checked by zlib: its checksum and length), else it ends at the run, a stream cut short. The compressed data of
  recordings with a time column hold no such run (``tools/gzip_runs.py``, a flush's marker and a member's header
  aside); constant rows without a time column do, and a stream of them cut short is read to its first run, with a warning;
- bytes written after a cut decode as more of the stream: the text of a stream's last :data:`HOLD_BYTES` bytes is
  left out where it is cut short at the file's end, padding after them or not (not after a flush's marker, nor
  where the checksum in them checks out: :func:`_checks_out`), a member that
  starts right after a cut ends it (:func:`_cut_at_run`), and a member whose last bytes state its length is damaged,
  not cut (:func:`_states_length`; attack pass 63); text the file ends in (:data:`TEXT_END_BYTES` or more: a note
  written after it, attack pass 64) is never given to zlib, unless the stream ends whole with it or it is a stored
  block's own (:func:`_own_text`).
"""
from __future__ import annotations

import math
import os
import zlib

from ..errors import RecordingError
from ..inputs import READ_BYTES, quote
from .gzip_bytes import TEXT_END_BYTES, Padded, counted, end_zeros, is_text, skip_padding, trailing_text
from .header import MAX_LINE_BYTES

#: most decompressed bytes at a time (a block of text: about 36 000 lines of five columns); the
#: longest line, so that only the line the blocks so far have not ended needs a length check
_TEXT_BYTES = MAX_LINE_BYTES
GZIP_MAGIC = b"\x1f\x8b"
#: most compressed bytes (runs aside, which are counted), and bytes of text, of a stream on trial: the bytes are
#: kept to be read again once it ends whole; a stream longer on trial ends at its run (zeros after a cut decode to
#: up to 2 kB of text a byte: 4 GB of them, TBs)
TRIAL_BYTES = 64 << 20
TRIAL_TEXT_BYTES = 1 << 30
#: the most bytes of a member's header looked at (a name or comment longer than this ends it there)
_MAX_HEADER_BYTES = 1 << 20
#: the last bytes of a flush's marker (an empty stored block's LEN and NLEN): a writer's own last bytes
_FLUSH_END = b"\x00\x00\xff\xff"
#: the last compressed bytes held back from zlib till more follow (:func:`_member`): where the stream is cut short,
#: their text is left out (a deflate code is at most 6 bytes: bytes written after a cut that are fewer than this make
#: none of the text kept)
HOLD_BYTES = 16


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
    except (OSError, RecordingError):  # not damage (a stream too long on trial)
        pass
    return None


def gunzipped(fh, first, path, warnings):
    """The text of the gzip file ``path`` open as ``fh`` (``first``: its first bytes, already read), every member, in
    blocks of at most ``_TEXT_BYTES`` (a gzip bomb never holds more); what was left out said in ``warnings``, the
    first :data:`MAX_WARNINGS` of them (100 000 members cut short made 17 MB of warnings, attack pass 62). The one
    gzip reader of recordings and of other tools' logs (``logtext.log_lines``)."""
    notes = _Notes()
    try:
        yield from _gunzip(Padded(fh, first), path, notes)
    finally:
        warnings.extend(notes + ([f"{path}: {notes.more} more warnings of its gzip data like these"] if notes.more else []))


#: the most warnings of one gzip file kept (the rest counted)
MAX_WARNINGS = 20


class _Notes(list):
    """A gzip file's warnings: the first :data:`MAX_WARNINGS` kept, the rest counted (``more``)."""

    more = 0

    def append(self, text):
        if len(self) < MAX_WARNINGS:
            super().append(text)
        else:
            self.more += 1

    def extend(self, texts):
        for text in texts:
            self.append(text)
        return self

    __iadd__ = extend


def _gunzip(source, path, warnings):
    """The text of the gzip file read by ``source`` (:class:`Padded`), every member (:func:`_member`), in blocks of
    at most ``_TEXT_BYTES``. Padding (bytes 0x00, 0xFF) after a member, or between two, is left out with a warning,
    and so is text the file ends in (``source.end_text``, not the stream's own); other bytes after it that do not
    start a member are damage (:class:`_GzipDamage`)."""
    produced, raw = 0, source.read()
    while True:
        raw, produced = yield from _member(source, raw, path, warnings, produced)
        if raw is None:  # the file ended inside the member
            break
        count, seen, raw = skip_padding(source, raw)
        if not raw:
            if count:
                warnings.append(_padding_warning(path, count, seen, True))
            break
        if raw[:2] != GZIP_MAGIC and not GZIP_MAGIC.startswith(raw):  # (a 1f alone may start a member cut short)
            note = _text_to_end(source, raw)
            if note is None:
                raise _GzipDamage(path, "bytes after the end of the gzip stream that are not gzip", produced)
            source.end_text = note  # a short note after a whole stream (``printf 'stopped' >> rec.csv.gz``)
            break
        if count:
            warnings.append(f"{path}: {counted(count, seen)} between gzip members ignored (block padding)")
    if source.end_text:
        warnings.append(f"{path}: the {len(source.end_text)} byte{'s' * (len(source.end_text) != 1)} of text it ends in ({quote(source.end_text.decode(errors='replace').strip())}) "
                        "left out: text written after its gzip data (a note), not gzip")


def _text_to_end(source, raw):
    """The text of ``raw`` and the rest of the file read by ``source``, where it is all text and padding (0x00, 0xFF),
    at most ``_NOTE_BYTES`` (:func:`~gyrofilter.recording.gzip_bytes.is_text`), else None."""
    note = raw
    while len(note) <= _NOTE_BYTES and (more := source.read()):
        note += more
    note += source.end_text
    text = note.replace(b"\0", b"").replace(b"\xff", b"")  # (padding after it, or between notes: attack pass 66)
    return text if len(note) <= _NOTE_BYTES and text and is_text(text) else None


#: the most bytes of text after a whole gzip stream read as a note written after it (more: damage)
_NOTE_BYTES = 4096


def _member(source, raw, path, warnings, produced):
    """The text of the gzip member whose first bytes are ``raw``, the rest read from ``source``; returns (the bytes
    after it, None when the file ends inside it; the bytes of text so far, ``produced`` those before it).

    A member that ends before its end marker (an interrupted recording) ends the text with a warning
    (:func:`_cut_end`). Damaged data are an error (:class:`_GzipDamage`): corrupt compressed blocks, a checksum or
    length that does not match (the text may look fine: a changed digit in a stored block). From a run of padding
    (``source.run``) on, the member is on trial: decompressed on, its text not used, its bytes kept, until it ends
    whole (its checksum and length, RFC 1952, checked by zlib: then read again from the run, every byte its own) or
    not (it ends at the run: :func:`_cut_at_run`); at most :data:`TRIAL_BYTES` compressed bytes and
    :data:`TRIAL_TEXT_BYTES` of text are tried (more: it ends at the run too, the rest unchecked).

    The last :data:`HOLD_BYTES` bytes so far are held back from zlib: where the stream is cut short at the file's end,
    their text is left out, for bytes written after a cut (``echo >> rec.csv.gz``) decode as more of the stream
    (attack pass 63: a made-up last row), padding after them or not (a note before padding, pass 67), unless they end
    in a flush's marker (a recorder's own last write) or its checksum checks out (:func:`_checks_out`); where it ends
    at a run that more bytes follow, they are its own, or hold another member's first bytes (:func:`_cut_at_run`)."""
    d, line, header = zlib.decompressobj(16 + zlib.MAX_WBITS), _LastLine(), _Header()
    first, trial, tried, sure, run, at = produced, None, 0, False, None, header.add(raw)  # trial: (d, hold, the run)
    hold, feed, ending, last, before_end = b"", None, b"", b"", None  # ending: the bytes held at the file's end, fed (to
    # before_end, a copy of the decompressor); last: their text
    while True:
        if feed is None:  # new bytes: the last HOLD_BYTES of them held back
            if run and trial is None and not sure and not header.holds(at):
                trial, tried = (d.copy(), hold, source.keep(), at), 0
            data = hold + raw
            feed, hold = data[:-HOLD_BYTES], data[-HOLD_BYTES:]
        prior = d.copy() if trial else None
        try:
            out = d.decompress(feed, _TEXT_BYTES)
        except zlib.error as exc:
            if trial is None and ending and "data check" not in str(exc) and (  # (the stream's end, its text wrong:
                    "length check" in str(exc) or _appended(before_end, ending)):  # damage, attack pass 66)
                # bytes written after a cut (attack pass 65), or a cut in the trailer (its text checked: the CRC)
                _cut_end(None, source, path, warnings, last, ending, produced - first, str(exc))
                yield from line.end(False, path, warnings)
                return None, produced
            if trial is None:
                raise _GzipDamage(path, str(exc), produced) from None
            ended = "incorrect data check" in str(exc) and _own_end(prior, feed + hold, produced - first + tried, source)
            return (yield from _cut_at_run(trial, source, path, warnings, line, produced, first,
                                           f"does not decompress ({exc})", (str(exc), produced) if ended else None))
        if trial is None and ending:
            last += out
        elif trial is None:
            produced += len(out)
            yield from line.blocks(out)
        else:
            tried += len(out)
            if source.kept_bytes > TRIAL_BYTES or tried > TRIAL_TEXT_BYTES:  # (zeros after a cut may make TBs of text)
                how = (f"goes on past what a trial holds ({TRIAL_BYTES >> 20} MiB of kept pieces or "
                       f"{TRIAL_TEXT_BYTES >> 30} GiB of text), unchecked")
                return (yield from _cut_at_run(trial, source, path, warnings, line, produced, first, how))
        run = None
        if not d.eof:
            if d.unconsumed_tail or len(out) == _TEXT_BYTES:  # (text zlib holds back is the input's before more)
                feed = d.unconsumed_tail
                continue
            feed, raw = None, source.read()
            if raw:
                run, at = source.run, header.add(raw)
                continue
            if trial is None and _own_text(d, hold, source.end_text, end_zeros(source)):
                raw, source.end_text = source.end_text, b""
                run, at = None, header.add(raw)
                continue
            if hold:  # the file's end: the bytes held fed now, their text kept apart till the stream is whole or cut
                feed, ending, hold, before_end = hold, hold, b"", d.copy()
                continue
            if trial is None:
                out = _cut_end(d, source, path, warnings, last, ending, produced - first)
                yield from line.blocks(out)
                yield from line.end(False, path, warnings)
                return None, produced + len(out)
            if not _padded_end(d, end_zeros(source))[0]:
                return (yield from _cut_at_run(trial, source, path, warnings, line, produced, first, "ends cut short"))
        if trial is None:
            yield from line.blocks(last)
            yield from line.end(False, path, warnings)
            return d.unused_data + hold, produced + len(last)
        (d, hold, _, _), trial, sure, feed, ending, last = trial, None, True, None, b"", b""  # it ends whole: read again
        source.rewind()
        raw = source.read()


def _cut_at_run(trial, source, path, warnings, line, produced, first, how, damage=None):
    """The member on trial (``trial``: the decompressor before the run, the bytes held back before it, the run)
    ``how`` (ends cut short, does not decompress): it ends at the run (:func:`_trial_failed`), the text of the bytes
    held before it used (padding follows a writer's own bytes), or, where they hold a member's first bytes (a recorder
    started again, its header's zeros the run: attack pass 63, a row made of that header), the stream ends there and
    that member is read. Returns as :func:`_member` does."""
    d, hold, run, run_at = trial
    at = hold.find(GZIP_MAGIC + b"\x08", max(0, len(hold) - run_at + 1))  # (not the member's own header: pass 64, a loop)
    if damage and at < 0:  # it reached its own end: whatever follows (attack pass 62: a member after padding excused it)
        raise _GzipDamage(path, *damage)  # (not another member's end, read as its own)
    try:
        text = d.decompress(hold[:at] if at >= 0 else hold)
    except zlib.error as exc:
        raise _GzipDamage(path, str(exc), produced) from None
    yield from line.blocks(text)
    if at >= 0:
        source.rewind()
        warnings.append(f"{path}: gzip stream cut short (no end marker) at byte {run[0] - len(hold) + at}, where another "
                        "gzip member begins")
        yield from line.end(True, path, warnings)
        return hold[at:], produced + len(text)
    after = _trial_failed(source, run, path, warnings, produced + len(text) > first, how)
    yield from line.end(after is not None, path, warnings)
    return after, produced + len(text)


class _Header:
    """Where a gzip member's header ends (RFC 1952, 2.3.1: 10 bytes, then the fields its flags name: FEXTRA, FNAME,
    FCOMMENT, FHCRC), from its bytes as they come (:meth:`add`): zeros in it are its fields (a modification time of
    90 s, an extra field of zeros), never padding (attack pass 62: such a member cut short was refused)."""

    def __init__(self):
        self.start, self.fed, self.end = b"", 0, None

    def add(self, chunk):
        """Note the member's next bytes ``chunk``; returns their offset in the member."""
        at, self.fed = self.fed, self.fed + len(chunk)
        if self.end is None:
            self.start += chunk[:_MAX_HEADER_BYTES - len(self.start)]
            self.end = _header_length(self.start) or (len(self.start) if len(self.start) >= _MAX_HEADER_BYTES else None)
        return at

    def holds(self, at):
        """Whether the member's byte ``at`` is (or may be) in its header."""
        return self.end is None or at < self.end


def _header_length(start):
    """The length of the gzip header that ``start`` begins with, or None while ``start`` does not hold all of it."""
    if len(start) < 10:
        return None
    flags, end = start[3], 10
    if flags & 4:  # FEXTRA: its length, then it
        end = 12 + int.from_bytes(start[10:12], "little") if len(start) >= 12 else math.inf
    for flag in (8, 16):  # FNAME, FCOMMENT: zero-terminated
        if flags & flag:
            nul = start.find(b"\0", end) if end < len(start) else -1
            end = nul + 1 if nul >= 0 else math.inf
    end += 2 if flags & 2 else 0  # FHCRC
    return end if end <= len(start) else None


class _LastLine:
    """The text of a member after its last line end, held until the member ends: a member cut short before another
    member (a recorder started again) would join it to that member's first line, a row made of two."""

    def __init__(self):
        self.parts, self.size = [], 0

    def blocks(self, out):
        """The blocks of text to give for ``out``, the member's next: up to its last line end (a line too long to hold
        is given: the reader refuses it), each at most ``_TEXT_BYTES``."""
        cut = out.rfind(b"\n") + 1
        if not cut and self.size + len(out) <= _TEXT_BYTES:
            self.parts.append(out)
            self.size += len(out)
            return []
        cut = cut or len(out)
        blocks = [b"".join(self.parts), out[:cut]]
        self.parts, self.size = [out[cut:]], len(out) - cut
        return [block for block in blocks if block]

    def end(self, dropped, path, warnings):
        """The text held, at the member's end; none when ``dropped`` (said in ``warnings``)."""
        held, self.parts, self.size = b"".join(self.parts), [], 0
        if held and dropped:
            warnings.append(f"{path}: the last {len(held)} bytes of text of that stream (a line without its end) left "
                            "out: the next member's text does not go on from them")
        return [held] if held and not dropped else []


def _appended(d, held):
    """Whether the ``held`` bytes that the decompressor ``d`` fails on at the file's end end in bytes written after
    a cut, without which they decode: a run of 0x00 or 0xFF (padding, 1 to 4 bytes), text (a short note,
    ``echo "# stopped" >> rec.csv.gz``: attack pass 65, refused as damage; ``printf``'s, pass 66), or both; a bit
    changed in a member's last block fails without them too (damage; a wrong checksum is never asked here)."""
    kept = held
    while True:  # each shorter: its padding, its text, in turn as they come from the end
        shorter = kept.rstrip(b"\0\xff")
        if shorter == kept:
            shorter = kept[:len(kept) - len(trailing_text(kept))]
        if shorter == kept:
            return False
        kept = shorter
        try:
            d.copy().decompress(kept)
            return True
        except zlib.error:
            pass


def _own_text(d, hold, text, zeros):
    """Whether ``text``, the file's last bytes after ``hold`` (:data:`HOLD_BYTES`) of the stream of the decompressor
    ``d``, before ``zeros`` zero bytes, is the stream's own: it ends the stream whole (with the zeros a trailer's
    length may take), or its last bytes decode to themselves (a stored block's, level 0, whose header's bytes may read
    as text too); a note written after the data decodes to other text."""
    if not text:
        return False
    try:
        probe = d.copy()
        probe.decompress(hold)
        if probe.eof:
            return False  # it ended before the text
        if probe.decompress(text)[-TEXT_END_BYTES:] == text[-TEXT_END_BYTES:] or probe.eof:
            return True
        return _padded_end(probe, zeros)[0] > 0
    except zlib.error:
        return False


def _own_end(prior, raw, length, source):
    """Whether the end of a gzip member whose checksum zlib found wrong in ``raw`` (fed to the decompressor ``prior``,
    which had made ``length`` bytes of the member's text; the bytes after ``raw`` read from ``source``) is the
    stream's own, its text damaged (a changed digit before a run of zeros was read with a warning, attack pass 61),
    not bytes after padding that zlib read on to an end by chance (random bytes end a block of fixed codes one time in
    128): its trailer states the member's length (RFC 1952: ISIZE, the 4 bytes after the checksum, the text's length
    mod 2^32; 1 time in 2^32 by chance), or it ends where the file, its padding or another member begins. Fed a byte
    at a time, only on such a failure."""
    probe = prior.copy()
    for i in range(len(raw)):
        try:
            length += len(probe.decompress(raw[i:i + 1]))
        except zlib.error:
            after, padding = raw[i + 1:], False  # its ISIZE, then what follows it
            while len(after) < 6 and (more := source.read()):  # (kept: the trial's end rewinds them)
                padding = padding or source.run is not None and len(after) <= 4  # padding from its ISIZE's end on
                after += more
            after += bytes(max(0, min(4 - len(after), end_zeros(source))))  # its high bytes of zeros, held as padding
            stated, follows = after[:4], after[4:]
            return len(stated) == 4 and (int.from_bytes(stated, "little") == length % (1 << 32) or padding
                                         or not follows or follows[:2] == GZIP_MAGIC)
    return False


def _trial_failed(source, run, path, warnings, had_text, how):
    """The member on trial since the run of padding ``run`` (offset, byte, count) ``how`` (ends cut short, does not
    decompress): it ends at the run, a stream cut short, with a warning. Returns the bytes of a member that starts
    after padding (a recorder started again: right after the run, or after padding further on), or None: the file
    ends in padding, or other bytes follow, left out. Damage (:class:`_GzipDamage`) when the member made no text before
    the run (nothing in it to keep)."""
    source.rewind()
    count, seen, raw = skip_padding(source, b"")
    offset, byte, run_count = run
    if raw[:3] == GZIP_MAGIC + b"\x08":
        warnings.append(f"{path}: gzip stream cut short (no end marker) at byte {offset}, where {counted(count, seen)} "
                        "(padding, as a power cut leaves an SD card) and another gzip member begin")
        return raw
    if not raw:
        warnings += [_padding_warning(path, count, seen, False), cut_short_warning(path)]
        return None
    if not had_text:
        raise _GzipDamage(path, f"{counted(run_count, {byte[0]})} at byte {offset}, then a stream that {how}", 0)
    after, at = _member_after_padding(source)  # its own run came first, the padding later (pass 61: the member lost)
    warnings += [f"{path}: {counted(run_count, {byte[0]})} at byte {offset}, then more bytes, in a gzip stream that "
                 f"{how}: without its end marker its own bytes cannot be told from padding (as a power cut leaves an "
                 f"SD card) and what follows it, so its text is read to byte {offset} (zcat reads on, unchecked)",
                 cut_short_warning(path)] + ([f"{path}: another gzip member at byte {at}, after padding: read"] if after else [])
    return after or None


def _member_after_padding(source):
    """(the first bytes of a gzip member that comes after a run of padding further on in the file read by ``source``,
    the member's byte offset), the bytes before it passed over; or (b"", None): none."""
    while chunk := source.read():
        if source.run:
            _, _, raw = skip_padding(source, chunk)
            if raw[:3] == GZIP_MAGIC + b"\x08":
                return raw, source.offset - len(raw)
    return b"", None


def _cut_end(d, source, path, warnings, last, held, produced, failed=None):
    """The last text of the member of the decompressor ``d`` at the end of the file ``source`` read, ``last`` the text
    of the bytes ``held`` back (:data:`HOLD_BYTES`), fed: with what it makes of the zero padding it takes to end whole
    (:func:`_padded_end`); cut short, ``last`` only where ``held`` ends in a flush's marker or its checksum checks out
    (:func:`_checks_out`), else left out (padding after them or not: attack pass 67), and none where zlib ``failed``
    on them (its error: bytes written after a cut, attack pass 65, were refused as damage). The padding, the text
    left out and a stream cut short said in ``warnings``. A member whose last bytes state its length (:func:`_states_length`; ``produced``: its text before ``last``) is whole and damaged."""
    byte, count = source.end_run or (b"\0", 0)
    whole, out = _padded_end(d, end_zeros(source)) if failed is None else (0, b"")
    if count > whole:
        warnings.append(_padding_warning(path, count - whole, {byte[0]}, whole))
    if whole:
        return last + out
    if _states_length(held, end_zeros(source), produced + len(last)):
        raise _GzipDamage(path, "its last bytes state its length, but its data do not end there", produced)
    warnings.append(cut_short_warning(path))
    if failed is not None:
        warnings.append(f"{path}: its last {len(held)} compressed bytes do not decompress ({failed}): left out (bytes "
                        "written after a cut)")
        return b""
    if last and not held.endswith(_FLUSH_END) and not _checks_out(d, produced + len(last)):
        warnings.append(f"{path}: the {len(last)} bytes of text its last {len(held)} compressed bytes decode to left "
                        "out (bytes written after a cut decode as more of a stream)")
        return b""
    return last


#: how far the length a damaged member's trailer states may be from the text its damaged data decode to
_LENGTH_SLACK = 64


def _states_length(held, zeros, length):
    """Whether the last bytes of a member that does not end whole (``held``, then ``zeros`` zero bytes the file ends
    in) are a trailer: its ISIZE (RFC 1952: the text's length mod 2^32, 4 bytes) within :data:`_LENGTH_SLACK` of
    ``length`` (the text its damaged data decode to: a changed bit in its last block made up rows, attack pass 63),
    of at least 2^16 (one or no high zero byte among the padding: a cut stream's last bytes so state a length about
    one time in 2^24 / 129; with more, one time in 500; a small length, read from a cut's own last bytes and 1 to 4
    bytes after them, refused 1 % to 4 % of interrupted recordings: attack pass 67)."""
    if held.endswith(_FLUSH_END):
        return False  # a flush's marker and a padding zero state 0x00FFFF00 (attack pass 64: a false refusal)
    for high in range(min(zeros, 1) + 1):
        size = int.from_bytes((held + bytes(high))[-4:], "little") if len(held) >= 4 - high else -1
        if size >= 1 << 16 and abs(size - length % (1 << 32)) <= _LENGTH_SLACK:
            return True
    return False


def _checks_out(d, length):
    """Whether the stream of the decompressor ``d``, fed up to its trailer's checksum (RFC 1952: CRC-32, then ISIZE,
    the text's ``length`` mod 2^32), ends whole with the rest of its ISIZE: the checksum its bytes state is that of
    its text (bytes after a cut pass so one time in 2^32). A member cut in its length keeps its last text."""
    size = (length % (1 << 32)).to_bytes(4, "little")
    for given in range(4):
        trial = d.copy()
        try:
            trial.decompress(size[given:])
        except zlib.error:
            continue
        if trial.eof and not trial.unused_data:
            return True
    return False


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


def _padding_warning(path, count, seen, after_stream):
    """The warning of ``count`` bytes of padding (of the values ``seen``: 0x00, 0xFF) left out at the end of the gzip
    file ``path``, ``after_stream`` a whole one or after one cut short."""
    return (f"{path}: {counted(count, seen)} " + ("after the end of the gzip stream ignored (block padding, as gzip ignores it)"
                                                  if after_stream else "at its end ignored (block padding, as a power cut leaves an SD card)"))


def cut_short_warning(path):
    """The warning of a gzip file ``path`` whose stream ends before its end marker (an interrupted
    recording or log): its text so far is read, complete lines only. The one rule of a recording
    (:func:`~gyrofilter.recording.lines.line_chunks`) and of another tool's log (``logtext.log_lines``)."""
    return f"{path}: gzip stream cut short (no end marker), as an interrupted recording leaves it"
