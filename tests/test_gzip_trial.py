"""The gzip reader from a run of padding on (``recording.gzipped``): a stream is on trial, its text used only once
it ends whole (attack pass 60). Cut points, padding, the bytes after it and the rows are drawn at random, seeded."""
import gzip
import itertools
import os
import struct
import threading
import zlib

import numpy as np
import pytest

from gyrofilter.errors import RecordingError
from gyrofilter.inputs import READ_BYTES
from gyrofilter.recording import gzip_bytes, gzipped, read_recording

HEADER = "# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: lsb\n# lsb_per_dps: 131\n"


def _rows_decoded(data):
    """Whole rows zlib decodes from the gzip bytes ``data`` (the first member), header and column lines aside."""
    return zlib.decompressobj(16 + zlib.MAX_WBITS).decompress(data).count(b"\n") - HEADER.count("\n") - 1


def _constant_rows(rng, rows, level=9):
    """(values, gzip bytes at ``level``) of ``rows`` rows of one constant row without a time column, of 7, 9, 13 or
    17 bytes with its line end (a stuck sensor): deflate data of such rows hold long runs of zeros (drawn until they
    do: rows of other lengths may not)."""
    while True:
        sizes = rng.multinomial(int(rng.choice([7, 9, 13, 17])) - 6, [1 / 3] * 3) + 1  # characters of each value
        row = [_value(rng, n) for n in sizes]
        text = (HEADER + "gx,gy,gz\n" + (",".join(map(str, row)) + "\n") * rows).encode()
        data = gzip.compress(text, compresslevel=level, mtime=0)
        if any(kind == "run" for _, (kind, _, _) in _offsets(data)):
            return np.tile(row, (rows, 1)), data


def _value(rng, chars):
    """An integer of ``chars`` characters, sign and digits."""
    if chars > 1 and rng.random() < 0.5:
        return -int(rng.integers(10 ** (chars - 2), 10 ** (chars - 1)))
    return int(rng.integers(10 ** (chars - 1), 10 ** chars))


def _timed_rows(rng, rows, start=0):
    values = rng.integers(-999, 1000, (rows, 3))
    body = "".join(f"{(start + i) / 100:.2f},{a},{b},{c}\n" for i, (a, b, c) in enumerate(values))
    return values, body


def _read(path):
    """(the recording, None), or (None, the error) where it is refused as damaged gzip data."""
    try:
        return read_recording(path), None
    except RecordingError as exc:
        assert "damaged gzip data" in str(exc), exc
        return None, exc


@pytest.mark.parametrize("seed", range(8))
def test_constant_rows_cut_short_then_padded_invent_no_row(tmp_path, seed):
    """Attack pass 60: a recording of constant rows without a time column, cut short, padded with zeros and a byte
    after them, was read with 156549 rows zlib made of the zeros (in a block of constant rows they are its code for
    "the same again"): the text after the run was trusted once 64 KiB of it decompressed. Now it is used only once its
    stream ends whole: every row read is one zlib decodes from the bytes before the cut."""
    rng = np.random.default_rng(seed)
    path = tmp_path / "r.csv.gz"
    for _ in range(6):
        values, data = _constant_rows(rng, int(rng.integers(20_000, 200_000)), int(rng.integers(4, 10)))
        cut = int(rng.integers(len(data) // 10, len(data) - 9))
        pad = bytes([int(rng.choice([0, 0xFF]))]) * int(rng.choice([5, 64, 4096, 70_000]))
        path.write_bytes(data[:cut] + pad + bytes(rng.integers(1, 255, int(rng.integers(1, 4))).astype(np.uint8)))
        rec, _ = _read(path)
        if rec is not None:
            assert len(rec) <= max(_rows_decoded(data[:cut]), 0), (seed, cut, len(pad))
            np.testing.assert_array_equal(rec.columns["gx"], values[:len(rec), 0])
            assert any("cut short" in w for w in rec.warnings)


@pytest.mark.parametrize("seed", range(4))
def test_a_whole_stream_with_runs_of_zeros_in_it_is_read_whole(tmp_path, seed):
    """The runs of zeros in the deflate data of constant rows (hundreds of bytes: tools/gzip_runs.py) put the stream
    on trial; it ends whole, so every row is read, none twice, with no warning, from a file and from a pipe, one
    member or several."""
    rng = np.random.default_rng(100 + seed)
    values, data = _constant_rows(rng, 100_000)
    if seed % 2:
        data += gzip.compress((",".join(map(str, values[0])) + "\n").encode() * 50_000, mtime=0)
        values = np.vstack([values, values[:50_000]])
    path = tmp_path / "r.csv.gz"
    path.write_bytes(data)
    if seed >= 2:
        fifo = tmp_path / "fifo"
        os.mkfifo(fifo)
        feeder = threading.Thread(target=lambda: fifo.write_bytes(data))
        feeder.start()
        rec = read_recording(fifo)
        feeder.join()
    else:
        rec = read_recording(path)
    assert len(rec) == len(values) and rec.warnings == []
    np.testing.assert_array_equal(rec.columns["gz"], values[:, 2])


@pytest.mark.parametrize("seed", range(4))
def test_constant_rows_cut_short_after_a_run_of_their_own_are_read_to_it_with_a_warning(tmp_path, seed):
    """Attack pass 60 read a run in a stream's own data, in a stream later cut short, as padding: rows after it left
    out. Without the end marker the run cannot be told from padding (the case above): the stream is read to it, and
    the warning says so, names its byte and that zcat reads on; every row read is the row written."""
    rng = np.random.default_rng(200 + seed)
    lines = [f"{int(v)},1,2\n" for v in rng.integers(-99, 100, 3000)]
    text = (HEADER + "gx,gy,gz\n" + "".join(lines[:1500]) + "11,-1,-1\n" * 100_000 + "".join(lines[1500:])).encode()
    data = gzip.compress(text, compresslevel=9, mtime=0)
    run = next((offset, count) for offset, (kind, _, count) in _offsets(data) if kind == "run")
    path = tmp_path / "r.csv.gz"
    path.write_bytes(data[:len(data) - 40])  # cut short among the last rows, after the run
    rec = read_recording(path)
    written = np.array([int(line.split(",")[0]) for line in lines[:1500]] + [11] * 100_000)
    assert len(rec) <= 1500 + 100_000
    np.testing.assert_array_equal(rec.columns["gx"], written[:len(rec)])
    assert f"{run[1]} zero bytes at byte {run[0]}, then more bytes, in a gzip stream that ends cut short" in " ".join(rec.warnings)
    assert "zcat reads on" in " ".join(rec.warnings)


def _offsets(data):
    """(byte offset, piece) of each piece of the gzip bytes ``data`` after its 10-byte header (the reader parses a
    member's header: its zeros are no padding)."""
    offset = 10
    for piece in gzip_bytes.pieces(open(os.devnull, "rb"), data[offset:]):
        yield offset, piece
        offset += len(piece[1]) if piece[0] in ("data", "text") else piece[2]


@pytest.mark.parametrize("seed", range(6))
def test_a_recording_cut_short_then_long_padding_then_bytes_keeps_every_row_before_the_cut(tmp_path, seed):
    """Attack pass 60: a recording cut short, 32 KiB or more of zeros and then any byte, was refused (zlib's text of
    the zeros, garbage, was trusted after 64 KiB and made a bad line); zeros and then 0xFF at the end were refused
    too. Every row zlib decodes before the cut is read, with a warning, whatever follows the padding (where only
    padding follows, those of the cut's last HOLD_BYTES bytes may be left out: a short note before padding, pass 67)."""
    rng = np.random.default_rng(300 + seed)
    values, body = _timed_rows(rng, 20_000)
    data = gzip.compress((HEADER + "t,gx,gy,gz\n" + body).encode(), mtime=0)
    path = tmp_path / "r.csv.gz"
    for _ in range(4):
        cut = int(rng.integers(len(data) // 10, len(data) - 20))
        byte = bytes([int(rng.choice([0, 0xFF]))])
        after = [b"\x07", bytes(rng.integers(0, 256, 40).astype(np.uint8)), b"\xff" * 20_000, b"\0" * 3 + b"\xff" * 50]
        tail = after[int(rng.integers(0, 4))]
        path.write_bytes(data[:cut] + byte * int(rng.choice([32_768, 100_000])) + tail)
        rec = read_recording(path)
        assert _rows_decoded(data[:cut - gzipped.HOLD_BYTES]) <= len(rec) <= _rows_decoded(data[:cut])
        if tail.strip(b"\0\xff"):  # more bytes after the padding: the cut's last bytes are its own
            assert len(rec) == _rows_decoded(data[:cut])
        np.testing.assert_array_equal(rec.gyro, values[:len(rec)])
        assert any("cut short" in w for w in rec.warnings)


def test_a_member_header_at_a_block_boundary_is_no_padding(tmp_path):
    """Attack pass 60: a member whose header's first bytes (1f 8b 08) ended a read block had its header's zeros, at
    the next block's start, read as padding (the bytes before a run were looked for in its block only): a member cut
    short soon after lost every row. The bytes before a run are those of the blocks before too."""
    rng = np.random.default_rng(4)
    values, body = _timed_rows(rng, 3000)
    first = gzip.compress((HEADER + "t,gx,gy,gz\n" + body[:body.index("10.00,")]).encode(), mtime=0)
    second = gzip.compress(body[body.index("10.00,"):].encode(), compresslevel=9, mtime=0)[:700]
    for shift in (-2, 0, 1, 2):
        data = first + _empty_members(READ_BYTES - len(first) - 3 + shift) + second
        assert data[READ_BYTES - 3 + shift:READ_BYTES + shift] == b"\x1f\x8b\x08"
        path = tmp_path / "r.csv.gz"
        path.write_bytes(data)
        rec = read_recording(path)
        kept = second[:-gzipped.HOLD_BYTES]  # the text of a cut's last bytes is left out (attack pass 63)
        assert len(rec) == 1000 + zlib.decompressobj(16 + zlib.MAX_WBITS).decompress(kept).count(b"\n"), shift
        np.testing.assert_array_equal(rec.gyro, values[:len(rec)])


def _empty_members(size):
    """Empty gzip members of ``size`` bytes in all, an extra field (RFC 1952 FEXTRA) of 'a's filling each."""
    out = b""
    while size:
        n = size if size < 60_000 else 50_000
        extra = n - 22
        out += b"\x1f\x8b\x08\x04" + bytes(5) + b"\xff" + struct.pack("<H", extra) + b"a" * extra + b"\x03\x00" + bytes(8)
        size -= n
    return out


def test_padding_after_and_between_whole_members_is_left_out_with_a_warning(tmp_path):
    """Attack pass 60: a whole recording, 50 zeros and 50 0xFF after it, was refused ("bytes after the end of the gzip
    stream that are not gzip"). Padding of both bytes after a member is left out with a warning; between members too,
    the next member read."""
    rng = np.random.default_rng(5)
    values, body = _timed_rows(rng, 2000)
    text = (HEADER + "t,gx,gy,gz\n" + body).encode()
    half = text.index(b"10.00,")
    path = tmp_path / "r.csv.gz"
    path.write_bytes(gzip.compress(text) + bytes(50) + b"\xff" * 50)
    rec = read_recording(path)
    assert len(rec) == 2000 and rec.warnings == [f"{path}: 100 bytes 0x00 and 0xFF after the end of the gzip stream "
                                                 "ignored (block padding, as gzip ignores it)"]
    path.write_bytes(gzip.compress(text[:half]) + bytes(700) + gzip.compress(text[half:]))
    rec = read_recording(path)
    np.testing.assert_array_equal(rec.gyro, values)
    assert rec.warnings == [f"{path}: 700 zero bytes between gzip members ignored (block padding)"]


@pytest.mark.parametrize("seed", range(3))
def test_a_member_after_a_stream_cut_short_and_its_padding_is_read(tmp_path, seed):
    """A recorder started again after a power cut: a stream cut short, padding, a new member. The cut stream is read to
    its last whole line (its last line, cut, would join the new member's first), the new member after it; both said."""
    rng = np.random.default_rng(400 + seed)
    values, body = _timed_rows(rng, 4000)
    split = body.index("20.00,")
    first = gzip.compress((HEADER + "t,gx,gy,gz\n" + body[:split]).encode(), mtime=0)
    first = first[:int(rng.integers(len(first) // 2, len(first) - 20))]
    kept = _rows_decoded(first)
    path = tmp_path / "r.csv.gz"
    path.write_bytes(first + bytes(int(rng.choice([5, 512, 4096]))) + gzip.compress(body[split:].encode(), mtime=0))
    rec = read_recording(path)
    np.testing.assert_array_equal(rec.gyro, np.vstack([values[:kept], values[2000:]]))
    said = " ".join(rec.warnings)
    assert "and another gzip member begin" in said and "a line without its end) left out" in said


def test_many_short_runs_after_a_cut_are_read_to_the_cut(tmp_path):
    """Attack pass 60: 800 kB of 5 zeros and a line end after a stream cut short took 42 s (20 MB: more than 11 min)
    and ended in a bad line. The stream is on trial from the first run: read to it, with a warning."""
    rng = np.random.default_rng(6)
    values, body = _timed_rows(rng, 20_000)
    data = gzip.compress((HEADER + "t,gx,gy,gz\n" + body).encode(), mtime=0)
    cut = len(data) // 2
    path = tmp_path / "r.csv.gz"
    path.write_bytes(data[:cut] + (bytes(5) + b"\n") * 300_000)
    rec = read_recording(path)
    assert len(rec) == _rows_decoded(data[:cut])
    np.testing.assert_array_equal(rec.gyro, values[:len(rec)])


@pytest.mark.parametrize("bound", ["TRIAL_TEXT_BYTES", "TRIAL_BYTES"])
def test_a_stream_on_trial_past_its_bound_is_read_to_its_run(tmp_path, monkeypatch, bound):
    """A stream whose end, which alone tells its run from padding, comes after more than a trial holds (zeros after a
    cut may decode to TBs of text) ends at the run, with a warning naming it and saying the rest is unchecked; every
    row before it read (the bounds are small here)."""
    monkeypatch.setattr(gzipped, bound, 1 << 16)
    rng = np.random.default_rng(7)
    values, body = _timed_rows(rng, 3000)
    noise = "".join(f"{int(v)},1,2\n" for v in rng.integers(-999, 1000, 60_000))
    for stuck in (100_000, 150_000, 200_000, 300_000):  # rows of a stuck sensor, as many as make a run
        text = (HEADER + "gx,gy,gz\n" + "".join(f"{a},{b},{c}\n" for a, b, c in values) + "11,-1,-1\n" * stuck + noise)
        data = gzip.compress(text.encode(), compresslevel=9, mtime=0)
        run = next(((offset, count) for offset, (kind, _, count) in _offsets(data) if kind == "run"), None)
        if run:
            break
    path = tmp_path / "r.csv.gz"
    path.write_bytes(data)
    rec = read_recording(path)
    assert 3000 <= len(rec) < 3000 + stuck
    np.testing.assert_array_equal(rec.gyro[:3000], values)
    said = " ".join(rec.warnings)
    assert f"{run[1]} zero bytes at byte {run[0]}, then more bytes, in a gzip stream that goes on past what a trial holds" in said
    assert "unchecked" in said and "gzip stream cut short" in said


def test_the_documented_bounds_of_a_trial_are_the_readers():
    """docs/formats.md section 1 states the run length and a trial's bounds; they are the reader's constants."""
    from support import REPO

    text = " ".join((REPO / "docs" / "formats.md").read_text().split())
    assert f"From a run of {gzip_bytes.RUN_BYTES} or more zero or 0xFF bytes" in text
    assert f"at most {gzipped.TRIAL_BYTES >> 20} MiB, and {gzipped.TRIAL_TEXT_BYTES >> 30} GiB of text" in text


def _stored(text):
    """Deflate stored blocks (not final) of ``text``: its bytes as they are, byte-aligned (RFC 1951, 3.2.4)."""
    return b"".join(b"\x00" + struct.pack("<HH", len(part), len(part) ^ 0xFFFF) + part
                    for part in (text[i:i + 65535] for i in range(0, len(text), 65535)))


@pytest.mark.parametrize("seed", range(3))
def test_a_damaged_digit_before_a_run_of_the_streams_own_is_damage(tmp_path, capsys, seed):
    """Attack pass 61: a recording's first rows in stored blocks, then constant rows whose deflate data hold a run of
    zeros, one stored digit changed: the stream on trial from the run failed its checksum at its end, and that was
    read as padding, a warning, the changed digit used (convert wrote it without a word). A stream that reaches its end
    and fails its checksum while its trailer states its length is damage; junk after padding that zlib reads to an
    end states another length (the test above keeps such a recording's rows); a digit inserted, the length wrong too:
    the stream's end is where the file's is."""
    from gyrofilter.cli import main

    rng = np.random.default_rng(700 + seed)
    rows, damage = int(rng.integers(50_000, 300_000)), ["digit", "inserted"][seed % 2]
    path, log = tmp_path / "r.csv.gz", tmp_path / "log.csv.gz"
    for name, top in ((path, HEADER + "gx,gy,gz\n"), (log, "gx,gy,gz\n")):  # a recording, another tool's log
        name.write_bytes(_damaged_before_a_run(np.random.default_rng(seed), top, rows, damage))
    assert any(kind == "run" for _, (kind, _, _) in _offsets(path.read_bytes()))
    with pytest.raises(RecordingError, match="damaged gzip data .*incorrect data check"):
        read_recording(path)
    assert main(["convert", str(log), "--unit", "lsb", "--lsb-per-dps", "131", "--sample-rate-hz", "100",
                 "--out", str(tmp_path / "out.csv")]) == 2
    assert "damaged gzip data" in capsys.readouterr().err and not (tmp_path / "out.csv").exists()
    path.write_bytes(_damaged_before_a_run(np.random.default_rng(seed), HEADER + "gx,gy,gz\n", rows, None))
    assert len(read_recording(path)) == 3000 + 10 + rows  # undamaged: read whole


def _damaged_before_a_run(rng, top, rows, damage):
    """gzip bytes of ``top``, 3000 rows in stored blocks, then 10 rows and ``rows`` constant rows in deflate data that
    hold a run of zeros, damaged after the checksum and length were taken (``damage``): a stored digit changed
    (``"digit"``: the length the trailer states holds) or one inserted (``"inserted"``: it does not), or None."""
    first = (top + "".join(f"{int(v)},0,0\n" for v in rng.integers(1, 10, 3000))).encode()
    z = zlib.compressobj(9, zlib.DEFLATED, -15)
    stuck = b"12,3,4\n" * 10 + b"11,-1,-1\n" * rows  # (a few other rows first: their deflate data hold a run)
    text = bytearray(first + stuck)
    trailer = struct.pack("<II", zlib.crc32(bytes(text)), len(text) & 0xFFFFFFFF)
    at = len(top) + 6 * int(rng.integers(10, 2000))  # the digit of a row (6 bytes each)
    if damage == "digit":
        text[at] = ord("1") + (text[at] - ord("1") + 1) % 9
    elif damage == "inserted":
        text[at:at] = b"7"
    stored = bytes(text[:len(text) - len(stuck)])
    return b"\x1f\x8b\x08\x00" + bytes(5) + b"\xff" + _stored(stored) + z.compress(stuck) + z.flush() + trailer


def test_a_member_after_padding_after_a_run_of_the_cut_streams_own_is_read(tmp_path):
    """Attack pass 61: constant rows (their deflate data hold runs of zeros) cut short, 4096 zero bytes, then a whole
    member of 100 rows: the member was lost, as only the bytes right after the first run were looked at for one. It
    is read, with warnings that say the cut stream ends at its run and where the member starts."""
    rng = np.random.default_rng(8)
    values, data = _constant_rows(rng, 200_000)
    offset, count = next((offset, piece[2]) for offset, piece in _offsets(data) if piece[0] == "run")
    cut = data[:offset + count + 3]  # cut among the bytes after its own run: the padding comes later
    rows = rng.integers(-99, 100, (100, 3))
    member = gzip.compress("".join(f"{a},{b},{c}\n" for a, b, c in rows).encode(), mtime=0)
    path = tmp_path / "r.csv.gz"
    path.write_bytes(cut + bytes(4096) + member)
    rec = read_recording(path)
    np.testing.assert_array_equal(rec.gyro[-100:], rows)
    np.testing.assert_array_equal(rec.gyro[:-100], values[:len(rec) - 100])
    said = " ".join(rec.warnings)
    assert f"another gzip member at byte {len(cut) + 4096}, after padding: read" in said and "cut short" in said


def test_the_pieces_a_trial_keeps_count_against_its_bound(tmp_path, monkeypatch):
    """Attack pass 61: stored blocks of 5 zeros and a byte, repeated, kept two pieces (tuples) a 6 bytes on trial and
    counted only their 1-byte data against TRIAL_BYTES: 27 bytes of memory a byte of file, 3 GB for 120 MB. Each kept
    piece counts what it costs; past the bound the stream ends at its run (the bound is small here)."""
    monkeypatch.setattr(gzipped, "TRIAL_BYTES", 1 << 20)
    rng = np.random.default_rng(9)
    values, body = _timed_rows(rng, 2000)
    text = (HEADER + "t,gx,gy,gz\n" + body).encode()
    data = b"\x1f\x8b\x08\x00" + bytes(5) + b"\xff" + _stored(text + (bytes(5) + b"\x01") * 50_000)  # cut: no end
    path = tmp_path / "r.csv.gz"
    path.write_bytes(data)
    rec = read_recording(path)
    np.testing.assert_array_equal(rec.gyro, values)
    assert "goes on past what a trial holds (1 MiB of kept pieces" in " ".join(rec.warnings)


def test_convert_reads_a_padded_gzip_log_from_a_pipe_as_from_its_file(tmp_path):
    """Attack pass 61: a gzip log cut short and padded with 4096 zeros converted from its file but, from a pipe
    (``cat log | convert /dev/stdin``), was refused as damaged gzip data: the check of its first line read the first
    block with zlib alone, padding and all. Same output either way, cut points drawn."""
    import subprocess
    import sys

    rng = np.random.default_rng(10)
    text = "t,gx,gy,gz\n" + "".join(f"{i / 100:.2f},{a},{b},{c}\n" for i, (a, b, c) in enumerate(rng.integers(-99, 100, (3000, 3))))
    data = gzip.compress(text.encode(), mtime=0)
    args = ["--unit", "lsb", "--lsb-per-dps", "131", "--force"]
    for cut in rng.integers(len(data) // 4, len(data) - 10, 4):
        log = tmp_path / "log.csv.gz"
        log.write_bytes(data[:cut] + bytes(4096))
        runs = [subprocess.run([sys.executable, "-m", "gyrofilter", "convert", src, *args, "--out", str(tmp_path / out)],
                               input=log.read_bytes(), capture_output=True, timeout=120)
                for src, out in ((str(log), "file.csv"), ("/dev/stdin", "pipe.csv"))]
        assert [r.returncode for r in runs] == [0, 0], [r.stderr for r in runs]
        file, pipe = read_recording(tmp_path / "file.csv"), read_recording(tmp_path / "pipe.csv")
        assert len(file) > 100
        np.testing.assert_array_equal(file.gyro, pipe.gyro)


def test_a_file_of_many_cut_members_keeps_a_few_warnings_and_counts_the_rest(tmp_path):
    """Attack pass 62: 100 000 tiny members each cut in its trailer and padded kept 100 001 warnings (17 MB; replay
    printed them all). Every row is read; the first warnings are kept and the rest counted."""
    rng = np.random.default_rng(11)
    values, body = _timed_rows(rng, 2000)
    lines = (HEADER + "t,gx,gy,gz\n" + body).encode().splitlines(keepends=True)
    data = gzip.compress(b"".join(lines[:5]), mtime=0)
    for line in lines[5:]:
        data += gzip.compress(line, mtime=0)[:-4] + bytes(5)  # cut in its trailer, padded
    path = tmp_path / "r.csv.gz"
    path.write_bytes(data)
    rec = read_recording(path)
    np.testing.assert_array_equal(rec.gyro, values)
    assert len(rec.warnings) == gzipped.MAX_WARNINGS + 1 and rec.warnings[-1].startswith(f"{path}: ")
    assert "more warnings of its gzip data like these" in rec.warnings[-1]


def _flushed(text, every, level=6):
    """gzip bytes of ``text`` (zlib's header: a modification time of 0) with a sync flush every ``every`` lines, as a
    recorder writes them."""
    c = zlib.compressobj(level, zlib.DEFLATED, 31)
    lines = text.splitlines(keepends=True)
    return b"".join(c.compress("".join(lines[i:i + every]).encode()) + c.flush(zlib.Z_SYNC_FLUSH)
                    for i in range(0, len(lines), every)) + c.flush()


def _prefix_or_refused(path, values):
    """The rows read from ``path``, each the row written, in order (or None: refused as damaged gzip data)."""
    rec, _ = _read(path)
    if rec is not None:
        assert len(rec) <= len(values)
        np.testing.assert_array_equal(rec.gyro, values[:len(rec)])
    return rec


@pytest.mark.parametrize("seed", range(6))
def test_bytes_written_after_a_cut_make_no_row(tmp_path, seed):
    """Attack pass 63: a recording cut short, then a few bytes (``echo >> rec.csv.gz``: a line end; ``\\0\\n``), was
    read with a made-up last row (zlib decodes the bytes as more of the stream), the "no line end" warning gone. The
    text of a cut stream's last HOLD_BYTES bytes is left out: no such tail makes a row, and a cut at a flush's end
    keeps every row."""
    rng = np.random.default_rng(600 + seed)
    values, body = _timed_rows(rng, 3000)
    data = _flushed(HEADER + "t,gx,gy,gz\n" + body, int(rng.choice([1, 10, 100])))
    path = tmp_path / "r.csv.gz"
    for _ in range(40):
        cut = int(rng.integers(len(data) // 4, len(data) - 20))
        tail = [b"\n", b"\0\n", b"\0\0\0\n", bytes(rng.integers(1, 256, int(rng.integers(1, gzipped.HOLD_BYTES + 1))).astype(np.uint8))][int(rng.integers(0, 4))]
        path.write_bytes(data[:cut] + tail)
        _prefix_or_refused(path, values)
    flush_end = data.rfind(b"\0\0\xff\xff", 0, len(data) - 50) + 4  # a recorder killed after a flush
    path.write_bytes(data[:flush_end])
    rec = read_recording(path)
    assert len(rec) == _rows_decoded(data[:flush_end]) and not any("left out" in w for w in rec.warnings)


@pytest.mark.parametrize("seed", range(4))
def test_a_member_appended_right_after_a_cut_is_read_and_makes_no_row_of_its_header(tmp_path, seed):
    """Attack pass 63: a stream cut short and a member right after it (a logger's ``gzip >> log.gz`` the next time;
    zlib's header: 5 zeros) read the header's first bytes as the stream's (a made-up row) and its zeros as padding
    (the member's rows lost). The stream now ends where the member begins, and the member is read."""
    rng = np.random.default_rng(700 + seed)
    values, body = _timed_rows(rng, 3000)
    more, more_body = _timed_rows(rng, 200, 3500)
    data = _flushed(HEADER + "t,gx,gy,gz\n" + body, 10)
    for _ in range(10):
        cut = int(rng.integers(len(data) // 4, len(data) - 20))
        path = tmp_path / "r.csv.gz"
        path.write_bytes(data[:cut] + _flushed(more_body, 10))
        rec = read_recording(path)
        kept = _rows_decoded(data[:cut])
        assert len(rec) in (kept + 200, kept - 1 + 200), (cut, len(rec), kept)
        np.testing.assert_array_equal(rec.gyro, np.vstack([values[:len(rec) - 200], more]))
        assert any("where another gzip member begins" in w for w in rec.warnings)


@pytest.mark.parametrize("seed", range(4))
def test_a_bit_flipped_in_a_whole_members_last_bytes_makes_no_row(tmp_path, seed):
    """Attack pass 63: one bit flipped in a whole member's last deflate block (the trailer then read as more data)
    made up rows, read as a stream cut short. Every flip of the last 24 bytes is refused or reads only rows written;
    where the member's text is 64 KiB or more its trailer, at the file's end, tells a damaged member from a cut one."""
    rng = np.random.default_rng(800 + seed)
    rows = int(rng.choice([2000, 6000]))
    values, body = _timed_rows(rng, rows)
    data = _flushed(HEADER + "t,gx,gy,gz\n" + body, int(rng.choice([10, 100])))
    path = tmp_path / "r.csv.gz"
    for at in range(len(data) - 64, len(data) - 8):  # (pass 66: damage in the last 64 bytes of a small member)
        for bit in rng.choice(8, 3, replace=False):
            damaged = bytearray(data)
            damaged[at] ^= 1 << int(bit)
            path.write_bytes(damaged)
            _prefix_or_refused(path, values)


def test_constant_rows_with_a_bit_flipped_before_the_trailer_are_refused(tmp_path):
    """Attack pass 63's case: 5000 constant rows, a bit of the last block flipped: 5001 rows read, the last made of
    the trailer's bytes. The file's last bytes state the member's length: damaged, not cut short."""
    text = HEADER + "gx,gy,gz\n" + "0.5,-0.25,100\n" * 5000
    data = bytearray(_flushed(text, 100))
    path = tmp_path / "r.csv.gz"
    refused = 0
    for at in range(len(data) - 14, len(data) - 8):
        damaged = bytearray(data)
        damaged[at] ^= 0x80
        path.write_bytes(damaged)
        rec = _prefix_or_refused(path, np.tile([0.5, -0.25, 100], (5000, 1)))
        refused += rec is None
    assert refused >= 3


@pytest.mark.parametrize("padding", [b"\0" * 5, b"\0" * 512, b"\xff" * 8])
def test_a_member_killed_in_its_first_bytes_then_padding_then_a_recording_is_read(tmp_path, padding):
    """Attack pass 64: a member whose run of padding starts within 16 bytes of its start held its own header among the
    bytes before the run, read as another member's, again and again: every command hung."""
    rng = np.random.default_rng(900)
    values, body = _timed_rows(rng, 500)
    whole = _flushed(HEADER + "t,gx,gy,gz\n" + body, 10)
    path = tmp_path / "r.csv.gz"
    for killed in (11, 12, 15):
        path.write_bytes(whole[:killed] + padding + whole)
        rec = read_recording(path)  # (hung)
        assert len(rec) == 500
        np.testing.assert_array_equal(rec.gyro, values)


def test_a_flush_marker_and_padding_are_no_stated_length():
    """Attack pass 64: a recording killed after a flush and padded with zeros, its text within 64 bytes of 16 776 960,
    was refused as damaged: the marker's FF FF and a padding zero read as a length of 0x00FFFF00."""
    assert not gzipped._states_length(b"\x12" * 12 + b"\0\0\xff\xff", 512, 0x00FFFF00)
    assert gzipped._states_length(b"\x12" * 12 + b"\x00\xff\xff\x01", 0, 0x01FFFF00)


_NOTES = ["# stopped by user at 10:42\n", "interrupted: power loss\n", "# arrêté à 10:42 par l’opérateur\n",
          "note: the cable came loose here, ignore the rest of this run please\n", "END OF RUN 7\r\n",
          "# stopped by me at 10:42"]  # (printf: no line end)


@pytest.mark.parametrize("seed", range(4))
def test_a_note_written_after_a_cut_makes_no_row_and_is_named(tmp_path, seed):
    """Attack pass 64: a note typed after a recording was killed (``echo "# stopped ..." >> rec.csv.gz``), longer
    than HOLD_BYTES, decoded as more of the stream: a made-up row in 0.5 % of cuts. Text the file ends in is not
    given to zlib (unless it ends the stream whole, or is a stored block's own): every cut reads only rows written,
    the note named; a whole recording and one killed after a flush keep every row."""
    rng = np.random.default_rng(900 + seed)
    values, body = _timed_rows(rng, 3000)
    data = _flushed(HEADER + "t,gx,gy,gz\n" + body, int(rng.choice([1, 10, 100])))
    path = tmp_path / "r.csv.gz"
    for _ in range(150):
        note = _NOTES[int(rng.integers(0, len(_NOTES)))].encode()
        path.write_bytes(data[:int(rng.integers(len(data) // 4, len(data) - 20))] + note)
        rec = _prefix_or_refused(path, values)
        assert rec is not None and any("bytes of text it ends in" in w for w in rec.warnings)  # (the cut's last
        # bytes too where they read as text)
    flush_end = data.rfind(b"\0\0\xff\xff", 0, len(data) - 50) + 4
    for note, (whole, end) in itertools.product((_NOTES[0], "stopped"), ((True, len(data)), (False, flush_end))):
        path.write_bytes(data[:end] + note.encode())
        rec = _prefix_or_refused(path, values)
        if whole or note == _NOTES[0]:  # (after a cut, a short note is among the last 16 bytes held back: said so)
            assert len(rec) == (3000 if whole else _rows_decoded(data[:end]))
            assert [w for w in rec.warnings if "left out" in w] == [f"{path}: the {len(note)} bytes of text it ends in ({note.strip()!r}) left out: text "
                            "written after its gzip data (a note), not gzip"]


@pytest.mark.parametrize("seed", range(3))
def test_a_cut_streams_own_last_zeros_are_not_padding(tmp_path, seed):
    """Attack pass 64: a stream cut just after 1 to 4 zero bytes of its own was read as padded (a false "zero bytes
    at its end ignored") and lost the text of the 16 bytes before them too: 19 of 87 264 cuts lost a row. Fewer
    zeros than RUN_BYTES are the stream's last bytes: every cut after one keeps what zlib decodes from all but its
    last HOLD_BYTES bytes, and says nothing of padding."""
    rng = np.random.default_rng(1000 + seed)
    values, body = _timed_rows(rng, 3000)
    data = _flushed(HEADER + "t,gx,gy,gz\n" + body, int(rng.choice([1, 10, 100])))
    cuts = [n for n in range(len(data) // 4, len(data) - 20) if data[n - 1] == 0 and data[n] != 0][:40]
    path = tmp_path / "r.csv.gz"
    for n in cuts:
        path.write_bytes(data[:n])
        rec = _prefix_or_refused(path, values)
        assert rec is not None and len(rec) >= _rows_decoded(data[:n - gzipped.HOLD_BYTES]), n
        assert not any("at its end ignored" in w for w in rec.warnings), (n, rec.warnings)


_AFTER_A_CUT = [b"# stopped\n", b"x\n", b"\0", b"\0\0\0", b"\xff\xff", b"# stopped at 10:42\n\0", b"# stopped\n\0\0",
                b"\0\0# stopped\n", b"# stopped at 10:42", b"# stopped by me at 10:42 " * 3 + b"\n" + bytes(600),
                b"stopped", b"stopped" + bytes(451)]  # (printf's short note, alone or before padding: attack pass 66)


@pytest.mark.parametrize("seed", range(4))
def test_what_is_written_after_a_cut_is_neither_damage_nor_rows(tmp_path, seed):
    """Attack pass 65: a cut stream with a short note (``# stopped\\n``, under 12 bytes), 1 to 4 bytes of padding, a
    note ending in a NUL or followed by padding, or a note without a line end of 17 to 19 bytes, was refused whole as
    damaged gzip data (zlib fails on the bytes held back at the end) or read with a made-up last row. Every such file
    reads only rows written, as many as zlib decodes from all but the last HOLD_BYTES of the stream's own bytes."""
    rng = np.random.default_rng(1100 + seed)
    values, body = _timed_rows(rng, 3000)
    data = _flushed(HEADER + "t,gx,gy,gz\n" + body, int(rng.choice([1, 10, 100])), level=int(rng.choice([1, 6, 9])))
    path = tmp_path / "r.csv.gz"
    for _ in range(120):
        cut = int(rng.integers(len(data) // 4, len(data) - 20))
        path.write_bytes(data[:cut] + _AFTER_A_CUT[int(rng.integers(0, len(_AFTER_A_CUT)))])
        rec = _prefix_or_refused(path, values)
        assert rec is not None and len(rec) >= _rows_decoded(data[:cut - gzipped.HOLD_BYTES]) - 1, cut


@pytest.mark.parametrize("seed", range(3))
def test_a_short_note_before_padding_makes_no_row(tmp_path, seed):
    """Attack pass 67: a cut stream, a short note (``echo >>``'s lone line end, 1 to 5 bytes without one, a Latin-1
    line) and then 5 or more bytes of padding (a power cut after the note) was read with rows made of the note: the
    text of the cut's last HOLD_BYTES bytes was kept wherever padding followed (2 to 3 % of such cuts of rows without
    a time column). It is left out now, padding after it or not, unless the stream's checksum checks out."""
    rng = np.random.default_rng(1300 + seed)
    values = rng.integers(-40, 41, (3000, 3))
    data = gzip.compress((HEADER + "gx,gy,gz\n" + "".join(f"{a},{b},{c}\n" for a, b, c in values)).encode(), mtime=0)
    path = tmp_path / "r.csv.gz"
    read = 0
    for _ in range(150):
        cut = int(rng.integers(400, len(data) - 8))
        note = [b"\n", bytes(rng.choice(list(b"abxyz# 0123"), int(rng.integers(1, 6))).astype(np.uint8)),
                "# arrêté\n".encode("latin-1")]
        pad = bytes([int(rng.choice([0, 0xFF]))]) * int(rng.integers(5, 600))
        path.write_bytes(data[:cut] + note[int(rng.integers(0, 3))] + pad)
        read += _prefix_or_refused(path, values) is not None
    assert read >= 100


def test_a_member_cut_in_its_length_keeps_its_last_row(tmp_path):
    """A member cut after its checksum, in its length (RFC 1952's ISIZE), ends a file: its checksum tells its last
    bytes are its own, and its last row is read (the text of a cut's last bytes is otherwise left out)."""
    rng = np.random.default_rng(14)
    values, body = _timed_rows(rng, 500)
    data = gzip.compress((HEADER + "t,gx,gy,gz\n" + body).encode(), mtime=0)
    path = tmp_path / "r.csv.gz"
    for lost in (1, 2, 3, 4):
        for pad in (b"", bytes(64), b"\xff" * 64):
            path.write_bytes(data[:-lost] + pad)
            rec = read_recording(path)
            np.testing.assert_array_equal(rec.gyro, values)  # (zeros after it may end it whole: its high bytes)
    path.write_bytes(data[:-5])  # in the checksum: its last bytes' text is left out
    assert len(read_recording(path)) == _rows_decoded(data[:-5 - gzipped.HOLD_BYTES])


def test_a_note_across_the_last_read_block_is_left_out(tmp_path):
    """Attack pass 65: a note that begins in the file's last but one read block (READ_BYTES) was given to zlib."""
    rng = np.random.default_rng(12)
    values, body = _timed_rows(rng, 200_000)
    data = _flushed(HEADER + "t,gx,gy,gz\n" + body, 10)
    assert len(data) > READ_BYTES + 100
    note = b"# " + b"stopped by the operator at 10:42 " * 4 + b"\n"
    path = tmp_path / "r.csv.gz"
    for before_boundary in (5, 40, len(note) - 13):
        cut = READ_BYTES - before_boundary
        path.write_bytes(data[:cut] + note)
        rec = read_recording(path)
        np.testing.assert_array_equal(rec.gyro, values[:len(rec)])
        assert any("bytes of text it ends in ('" in w and "stopped by the operator" in w for w in rec.warnings)


def test_a_wrong_checksum_is_damage_whatever_the_trailer_looks_like(tmp_path):
    """Attack pass 66: a whole member with a bit flipped (its checksum wrong) whose trailer ends in bytes that look
    like text (a length of 0x0a09: ``\\t\\n``, then a checksum's printable last byte) was read as a cut stream with a
    note after it: the damaged row kept. A wrong checksum is the stream's own end: damage, never bytes after a cut."""
    rng = np.random.default_rng(66)
    values, body = _timed_rows(rng, 60)
    text = (HEADER + "t,gx,gy,gz\n" + body).encode()
    for k in range(1000):  # a comment that makes the text 0x0a09 bytes and the checksum's last byte printable
        head = text.replace(b"t,gx", b"# " + b"%d" % k + b" " * (0x0a09 - len(text) - 3 - len(b"%d" % k)) + b"\nt,gx", 1)
        if len(head) == 0x0a09 and 0x20 <= zlib.crc32(head) >> 24 < 0x7f:
            break
    data = gzip.compress(head, mtime=0)
    assert data[-8:].endswith(b"\x09\x0a\0\0")
    path = tmp_path / "r.csv.gz"
    flips = 0
    for at in range(len(data) // 2, len(data) - 30):
        damaged = bytearray(data)
        damaged[at] ^= 0x04
        try:
            zlib.decompress(bytes(damaged), 31)
        except zlib.error as exc:
            if "data check" not in str(exc):
                continue
        else:
            continue
        path.write_bytes(bytes(damaged))
        with pytest.raises(RecordingError, match="damaged gzip data"):
            read_recording(path)
        flips += 1
    assert flips > 10


@pytest.mark.parametrize("tail", [b"# stop\n\0", b"stopped\n\0\0\0", b"# stop\n\xff", b"# a\n\xff# b\n", b"stopped" + bytes(600)])
def test_a_short_note_and_padding_after_a_whole_stream_are_left_out(tmp_path, tail):
    """Attack pass 66: a whole recording, a short note and padding after it was refused as damaged gzip data (only
    text alone after a whole stream was a note)."""
    values, body = _timed_rows(np.random.default_rng(3), 500)
    path = tmp_path / "r.csv.gz"
    path.write_bytes(_flushed(HEADER + "t,gx,gy,gz\n" + body, 10) + tail)
    rec = read_recording(path)
    np.testing.assert_array_equal(rec.gyro, values)
    assert any("of text it ends in" in w for w in rec.warnings), rec.warnings


@pytest.mark.parametrize("rows", [20, 60, 119])
def test_an_interrupted_small_recording_is_never_refused_for_its_last_bytes(tmp_path, rows):
    """Attack pass 67: a small member's last 4 bytes read as its stated length (a cut just after a flush's ``00 00``,
    or 1 to 4 bytes after a cut: two zeros make a 16-bit number) refused 1 % to 4 % of interrupted recordings as
    damaged. Every such cut of a small recording reads, each row its own."""
    values, body = _timed_rows(np.random.default_rng(rows), rows)
    data = _flushed(HEADER + "t,gx,gy,gz\n" + body, 1)
    path = tmp_path / "r.csv.gz"
    marks = [i + 2 for i in range(60, len(data) - 20) if data[i:i + 4] == b"\0\0\xff\xff" and _rows_decoded(data[:i + 2]) > 0]
    assert len(marks) > 10
    start = min(marks)
    cuts = marks + list(np.random.default_rng(rows).integers(start, len(data) - 10, 400))
    for cut, tail in itertools.product(cuts, (b"", b"\0\0", b"# stop\n\0\0")):
        path.write_bytes(data[:cut] + tail)
        rec = read_recording(path)
        np.testing.assert_array_equal(rec.gyro, values[:len(rec)])
