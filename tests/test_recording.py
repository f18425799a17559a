import gzip
import os
import threading
import json
import re
import sys
import warnings
import zlib

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gyrofilter.errors import RecordingError, SettingsError
from gyrofilter.recording import Note, Recording, RecordingWriter, iter_recording, read_recording, write_recording
from gyrofilter.recording.gzip_bytes import RUN_BYTES
from support import REPO

HEADER = "# gyrofilter-recording: 1\n# sensor: MPU6050\n# sample_rate_hz: 100\n# gyro_unit: lsb\n# lsb_per_dps: 131\n"


def write(tmp_path, text, name="r.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_reads_the_interfaces_example_with_units_and_extra_columns(tmp_path):
    path = write(tmp_path, HEADER + "# any_other_key: free text\nt,gx,gy,gz,temp,ax\n0.00,12,-3,40,25.31,0.1\n0.01,15,-1,37,25.31,0.2\n")
    rec = read_recording(path)
    assert rec.sample_rate_hz == 100.0 and rec.gyro_unit == "lsb" and len(rec) == 2
    np.testing.assert_allclose(rec.gyro_dps, np.array([[12, -3, 40], [15, -1, 37]]) / 131)
    np.testing.assert_allclose(rec.t_s, [0, 0.01])
    np.testing.assert_allclose(rec.temp_c, [25.31, 25.31])
    np.testing.assert_allclose(rec.columns["ax"], [0.1, 0.2])
    assert rec.header["any_other_key"] == "free text" and rec.warnings == []


def test_rad_per_s_and_uniform_times(tmp_path):
    path = write(tmp_path, "# gyrofilter-recording: 1\n# sample_rate_hz: 50\n# gyro_unit: rad/s\ngz,gy,gx\n1,0,0\n0,0,3.14159265358979\n")
    rec = read_recording(path)
    np.testing.assert_allclose(rec.gyro_dps[:, 2], [57.29577951308232, 0])
    np.testing.assert_allclose(rec.gyro_dps[1, 0], 180.0)
    np.testing.assert_allclose(rec.t_s, [0, 0.02])


@pytest.mark.parametrize("name", ["r.csv", "r.csv.gz"])
def test_write_read_round_trip(tmp_path, name):
    rng = np.random.default_rng(0)
    rec = Recording.from_dps(rng.normal(size=(500, 3)), 100.0, temp_c=25 + rng.random(500), extra={"ref_x": rng.normal(size=500)}, header={"sensor": "sim"})
    write_recording(tmp_path / name, rec)
    back = read_recording(tmp_path / name)
    assert back.header["sensor"] == "sim" and list(back.columns) == ["gx", "gy", "gz", "temp", "ref_x"]
    np.testing.assert_allclose(back.gyro_dps, rec.gyro_dps, rtol=1e-8)
    np.testing.assert_allclose(back.columns["ref_x"], rec.columns["ref_x"], rtol=1e-8)


@pytest.mark.parametrize(
    "text,match",
    [
        ("", "empty file"),
        ("# sample_rate_hz: 100\n# gyro_unit: dps\ngx,gy,gz\n1,2,3\n", r"missing header key\(s\) 'gyrofilter-recording'"),
        ("# gyrofilter-recording: 1\n# gyro_unit: dps\ngx,gy,gz\n1,2,3\n", r"missing header key\(s\) 'sample_rate_hz'"),
        ("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: deg\ngx,gy,gz\n1,2,3\n", "gyro_unit 'deg'"),
        ("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: lsb\ngx,gy,gz\n1,2,3\n", "lsb_per_dps"),
        ("# gyrofilter-recording: 2\n# sample_rate_hz: 100\n# gyro_unit: dps\ngx,gy,gz\n1,2,3\n", "version '2'"),
        ("# gyrofilter-recording: 1\n# sample_rate_hz: fast\n# gyro_unit: dps\ngx,gy,gz\n", "sample_rate_hz must be a plain decimal number"),
        (HEADER + "gx,gy\n1,2\n", "missing column.*gz"),
        (HEADER + "gx,gy,gz\n1,2,3\n4,5\n6,7,8\n", "line 8: 2 values, expected 3"),
        (HEADER + "gx,gy,gz\n1,2,3\n4,x5,6\n", "line 8: column 'gy' is not a number: 'x5'"),
        (HEADER + "gx,gy,gz\n1,2,3\n4,nan,6\n", "line 8: column 'gy' is 'nan'"),
        (HEADER + "gx,gy,gz\n1,,3\n", "line 7: column 'gy' is empty"),
        (HEADER + "t,gx,gy,gz\n0,1,2,3\n0.02,1,2,3\n0.01,1,2,3\n", "line 9: t does not increase"),
    ],
)
def test_bad_input_names_file_line_and_reason(tmp_path, text, match):
    path = write(tmp_path, text)
    with pytest.raises(RecordingError, match=match) as info:
        read_recording(path)
    assert str(path) in str(info.value)


def test_a_cut_last_line_is_a_warning_and_the_rest_is_used(tmp_path):
    rec = read_recording(write(tmp_path, HEADER + "gx,gy,gz\n1,2,3\n4,5,6\n7,8"))
    assert len(rec) == 2 and "no line end" in rec.warnings[0] and "line 9" in rec.warnings[0]


def test_gzip_cut_short_keeps_every_complete_line(tmp_path):
    body = HEADER + "gx,gy,gz\n" + "".join(f"{i},{i + 1},{i + 2}\n" for i in range(5000))
    data = gzip.compress(body.encode())
    path = tmp_path / "cut.csv.gz"
    path.write_bytes(data[: len(data) * 2 // 3])
    rec = read_recording(path)
    assert 100 < len(rec) < 5000
    np.testing.assert_array_equal(rec.columns["gx"], np.arange(len(rec)))
    assert any("cut short" in w for w in rec.warnings)


def test_writer_flushes_readable_data_before_close_and_keeps_notes(tmp_path):
    path = tmp_path / "live.csv.gz"
    w = RecordingWriter(path, {"sample_rate_hz": 100, "gyro_unit": "lsb", "lsb_per_dps": 131}, ["t", "gx", "gy", "gz"], formats=["%.2f", "%d", "%d", "%d"])
    w.write(np.array([[0.0, 1, 2, 3], [0.01, 4, 5, 6]]))
    w.note("gap: 3 samples lost before t=0.05 s")
    w.write(np.array([[0.05, 7, 8, 9]]))
    w.flush()  # the process could die here: no gzip trailer yet
    rec = read_recording(path)
    assert len(rec) == 3 and rec.notes == [(8, "gap: 3 samples lost before t=0.05 s")]
    assert any("cut short" in x for x in rec.warnings)
    w.close()
    assert read_recording(path).warnings == []


def test_a_write_interrupted_midway_leaves_the_file_as_at_its_last_flush(tmp_path, monkeypatch):
    """A second Ctrl-C (an immediate exit: KeyboardInterrupt) between gzip compressing a write and writing its
    bytes: the close wrote the rest of a stream whose compressor had taken data the file never got, garbage
    from there on ("line 24223: 16 values"), and the whole recording was refused, while `record` said it kept
    the first 26000 samples (attack pass 37g). The close now cuts the file back to its last flush, as after a
    failed write: it reads, a gzip one saying it was cut short, and keeps what was flushed."""
    import zlib

    real, trip = zlib.compressobj, []

    class Interrupted:  # compresses, then the signal arrives before the bytes are written
        def __init__(self, *args, **kwargs):
            self._compressor = real(*args, **kwargs)

        def compress(self, data):
            out = self._compressor.compress(data)
            if trip:
                raise trip.pop()
            return out

        def flush(self, *args):
            return self._compressor.flush(*args)

    monkeypatch.setattr(zlib, "compressobj", Interrupted)
    rows = np.column_stack([np.arange(3000) / 100, np.random.default_rng(1).integers(-30000, 30000, (3000, 3))])
    w = RecordingWriter(tmp_path / "live.csv.gz", {"sample_rate_hz": 100, "gyro_unit": "lsb", "lsb_per_dps": 131}, ["t", "gx", "gy", "gz"])
    with pytest.raises(KeyboardInterrupt):
        with w:
            w.write(rows[:1000])
            w.flush()
            w.write(rows[1000:2000])
            trip.append(KeyboardInterrupt())
            w.write(rows[2000:])
    rec = read_recording(tmp_path / "live.csv.gz")
    np.testing.assert_array_equal(rec.gyro, rows[:1000, 1:])
    assert w.rows_flushed == 1000 and any("cut short" in x for x in rec.warnings)


def test_blank_lines_are_not_samples(tmp_path):
    rec = read_recording(write(tmp_path, HEADER + "gx,gy,gz\n1,2,3\n\n4,5,6\n"))
    np.testing.assert_array_equal(rec.columns["gx"], [1, 4])


def test_unreadable_and_binary_files(tmp_path):
    with pytest.raises(RecordingError, match="cannot read"):
        read_recording(tmp_path / "missing.csv")
    path = tmp_path / "bin.csv"
    path.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(RecordingError, match="not UTF-8"):
        read_recording(path)


# --- chunked reading -------------------------------------------------------------------------

def _lines_file(tmp_path, body_lines, name="c.csv"):
    """A dps recording with a t column: header (6 lines), then ``body_lines``; returns (path, first body line)."""
    head = "# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\n# sensor: test\n# note_free: yes\nt,gx,gy,gz\n"
    path = tmp_path / name
    text = head + "".join(ln + "\n" for ln in body_lines)
    if name.endswith(".gz"):
        path.write_bytes(gzip.compress(text.encode()))
    else:
        path.write_text(text)
    return path, 7


def _read_chunked(path, chunk_rows):
    chunks = iter_recording(path, chunk_rows=chunk_rows)
    head = next(chunks)
    parts = list(chunks)
    assert all(1 <= len(c) <= chunk_rows for c in parts)
    return head, (np.concatenate(parts) if parts else np.empty((0, len(head.names))))


@pytest.mark.parametrize("name", ["c.csv", "c.csv.gz"])
@pytest.mark.parametrize("chunk_rows", [1, 7, 1 << 16])
def test_chunked_reader_gives_read_recordings_arrays(tmp_path, name, chunk_rows):
    rng = np.random.default_rng(5)
    body = [f"{i / 100:.2f},{a:.6f},{b:.6f},{c:.6f}" for i, (a, b, c) in enumerate(rng.normal(0, 1, (200, 3)))]
    body[50:50] = ["# gap: 3 samples lost"]
    body[120:120] = [""]
    path, _ = _lines_file(tmp_path, body, name)
    whole = read_recording(path)
    head, data = _read_chunked(path, chunk_rows)
    assert head.names == list(whole.columns) and head.header == whole.header and head.rows == len(whole) == 200
    for i, name_ in enumerate(head.names):
        np.testing.assert_array_equal(data[:, i], whole.columns[name_])
    assert head.notes == whole.notes == [(57, "gap: 3 samples lost")]
    # file line of each sample, across the note and the blank line
    assert [head.line_of_row(r) for r in (0, 49, 50, 118, 119, 199)] == [7, 56, 58, 126, 128, 208]


BAD_LINES = {
    "short row": ("1.5,2,3", "3 values, expected 4"),
    "long row": ("1.5,2,3,4,5", "5 values, expected 4"),
    "empty cell": ("1.5,2,,4", "column 'gy' is empty"),
    "nan": ("1.5,2,nan,4", "column 'gy' is 'nan'"),
    "not a number": ("1.5,2,3,x4", "column 'gz' is not a number: 'x4'"),
    "t goes back": (None, "t does not increase"),
}


@pytest.mark.parametrize("kind", sorted(BAD_LINES))
@pytest.mark.parametrize("chunk_rows,bad_row", [(1, 30), (7, 0), (7, 6), (7, 7), (7, 29), (1 << 16, 29)])
def test_each_bad_line_is_named_in_any_chunk(tmp_path, kind, chunk_rows, bad_row):
    text, reason = BAD_LINES[kind]
    body = [f"{i + 1},{i},{i},{i}" for i in range(40)]
    if kind == "t goes back":  # row i has t = i + 1: the bad row steps back half a second
        bad_row = max(bad_row, 1)
        text = f"{bad_row - 0.5},1,2,3"
    body[bad_row] = text
    path, first = _lines_file(tmp_path, body, "b.csv.gz")
    with pytest.raises(RecordingError, match=f"{path}: line {first + bad_row}: .*{reason}"):
        _read_chunked(path, chunk_rows)


def test_byte_order_mark_is_accepted(tmp_path):
    path = tmp_path / "bom.csv"
    path.write_bytes(b"\xef\xbb\xbf" + (HEADER + "gx,gy,gz\n1,2,3\n").encode())
    rec = read_recording(path)
    assert rec.gyro_unit == "lsb" and rec.columns["gx"].tolist() == [1.0]


def test_cut_last_line_and_gzip_end_in_chunks(tmp_path):
    body = HEADER + "gx,gy,gz\n" + "".join(f"{i},{i + 1},{i + 2}\n" for i in range(3000))
    path = tmp_path / "cut.csv.gz"
    path.write_bytes(gzip.compress((body + "7,8").encode()))
    head, data = _read_chunked(path, 7)
    assert len(data) == 3000 and "line 3007" in head.warnings[0] and "no line end" in head.warnings[0]
    data_gz = gzip.compress(body.encode())
    path.write_bytes(data_gz[: len(data_gz) // 2])
    head, data = _read_chunked(path, 7)
    np.testing.assert_array_equal(data[:, 0], np.arange(len(data)))
    assert any("cut short" in w for w in head.warnings)


def test_reader_memory_is_a_small_multiple_of_the_arrays(tmp_path):
    """tracemalloc peak of read_recording on 10 minutes at 500 Hz, five columns (the old reader,
    which held the text and a list of its lines: 13x)."""
    import tracemalloc

    n = 300_000
    rng = np.random.default_rng(6)
    rec = Recording.from_dps(rng.normal(0, 0.1, (n, 3)), 500.0, t_s=np.arange(n) / 500.0, temp_c=25 + rng.random(n))
    path = tmp_path / "ten_minutes.csv.gz"
    write_recording(path, rec, compresslevel=1)
    tracemalloc.start()
    try:
        back = read_recording(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(back) == n
    assert peak < 3.5 * n * 5 * 8


def test_damaged_gzip_data_are_named_as_such_not_as_a_bad_line(tmp_path):
    """Bytes changed inside a gzip recording make garbage text before the checksum fails: the
    error names the file and the damaged gzip data, not a short line. (Where zlib itself saw the
    damage, the data before it were used with a warning: now an error too, issue 22.)"""
    rng = np.random.default_rng(5)
    rec = Recording.from_dps(np.round(rng.normal(0, 300, (60_000, 3))), 100.0, t_s=np.arange(60_000) / 100.0)
    good = tmp_path / "good.csv.gz"
    write_recording(good, rec)
    data = good.read_bytes()
    named = 0
    for k in range(6):
        bad = tmp_path / f"bad{k}.csv.gz"
        damaged = bytearray(data)
        pos = len(data) // 10 * (k + 1)
        damaged[pos:pos + 8] = bytes(b ^ 0xFF for b in damaged[pos:pos + 8])
        bad.write_bytes(bytes(damaged))
        with pytest.raises(RecordingError) as info:
            read_recording(bad)
        assert str(info.value).startswith(f"{bad}: damaged gzip data"), info.value
        named += "garbage" in str(info.value)  # noticed as a bad line first
    assert named >= 1


@pytest.mark.parametrize("chunk_rows", [1, 7, 1 << 16])
def test_notes_know_the_sample_they_precede(tmp_path, chunk_rows):
    body = [f"{i / 100:.2f},{i},0,0" for i in range(20)]
    body[5:5] = ["# a"]
    body[12:12] = ["", "# b", "# c"]
    body.append("# end")
    path, _ = _lines_file(tmp_path, body, "n.csv")
    head, _ = _read_chunked(path, chunk_rows)
    assert [(note.text, note.row) for note in head.notes] == [("a", 5), ("b", 11), ("c", 11), ("end", 20)]
    assert [(note.text, note.row) for note in read_recording(path).notes] == [("a", 5), ("b", 11), ("c", 11), ("end", 20)]


# --- issue 22: nothing silently wrong (the format's reader and writers) --------------------------

def _dps_file(tmp_path, body, header="", name="r.csv", rate_hz=100):
    path = tmp_path / name
    text = f"# gyrofilter-recording: 1\n# sample_rate_hz: {rate_hz}\n# gyro_unit: dps\n{header}t,gx,gy,gz\n{body}"
    path.write_bytes(gzip.compress(text.encode(), compresslevel=0) if name.endswith(".gz") else text.encode())
    return path


@pytest.mark.parametrize("name", ["r.csv", "r.csv.gz"])
def test_clock_time_stamps_and_every_value_round_trip_exactly(tmp_path, name):
    """t of a clock (1.7e9 s + 1-ms steps) was written with 10 digits: every stamp one value."""
    rng = np.random.default_rng(22)
    n = 3000
    t = 1.7e9 + np.arange(n) / 1000.0
    rec = Recording.from_dps(rng.normal(0, 1, (n, 3)), 1000.0, t_s=t, temp_c=25 + rng.random(n),
                             extra={"count": np.arange(n) * 3.0 - 7})
    write_recording(tmp_path / name, rec)
    back = read_recording(tmp_path / name)
    assert len(np.unique(back.t_s)) == n
    for column in rec.columns:
        np.testing.assert_array_equal(back.columns[column], rec.columns[column])


def test_a_gzip_whose_checksum_fails_is_an_error_not_a_wrong_value(tmp_path):
    """Stored blocks (level 0) with a digit changed near the start decode to plausible text; only
    the CRC at the end tells. It was a warning and a wrong value (exit 0)."""
    body = "".join(f"{i / 100:.2f},{i % 7},1,2\n" for i in range(3000))
    path = _dps_file(tmp_path, body, name="r.csv.gz")
    data = bytearray(path.read_bytes())
    pos = data.index(b"0.01,1,1,2")
    data[pos + 5] = ord("9")  # gx of the second sample: 1 -> 9
    path.write_bytes(bytes(data))
    with pytest.raises(RecordingError, match="damaged gzip data") as info:
        read_recording(path)
    assert str(info.value).startswith(f"{path}: ") and "\n" not in str(info.value)


@pytest.mark.parametrize("what", ["trailing garbage", "corrupt deflate", "zeros, then garbage"])
def test_any_damaged_gzip_data_are_an_error(tmp_path, what):
    body = "".join(f"{i / 100:.2f},{i % 7},1,2\n" for i in range(30000))
    path = _dps_file(tmp_path, "", name="r.csv.gz")
    text = gzip.decompress(path.read_bytes()) + body.encode()
    data = bytearray(gzip.compress(text))
    if what == "trailing garbage":
        data += b"\x8bnot gzip"  # (text alone is a note written after it: left out, said)
    elif what.startswith("zeros"):
        data += bytes(70_000) + b"\x01"  # past a read block: the byte after the zeros is seen
    else:
        data[len(data) // 2] ^= 0x55
    path.write_bytes(bytes(data))
    with pytest.raises(RecordingError, match=f"{path}: damaged gzip data"):
        read_recording(path)


@pytest.mark.parametrize("zeros", [1, 4096, 200_000])
def test_zero_bytes_after_a_gzip_stream_are_block_padding_read_with_a_warning(tmp_path, zeros):
    """Attack pass 56: a whole gzip recording with an SD card's block padding (zero bytes) after it was refused as
    damaged, while gzip -t accepts it: its rows are read, every one, with a warning naming the zeros."""
    body = "".join(f"{i / 100:.2f},{i},1,2\n" for i in range(3000))
    path = _dps_file(tmp_path, body, name="r.csv.gz")
    path.write_bytes(path.read_bytes() + bytes(zeros))
    rec = read_recording(path)
    np.testing.assert_array_equal(rec.columns["gx"], np.arange(3000))
    assert f"{path}: {zeros} zero byte{'s' * (zeros > 1)} after the end of the gzip stream ignored" in " ".join(rec.warnings)


@pytest.mark.parametrize("zeros, piped", [(1, False), (100, False), (511, False), (512, False), (4096, False),
                                          (70_000, False), (100, True), (600, True)])
def test_a_gzip_cut_short_then_padded_with_zeros_reads_to_the_cut(tmp_path, zeros, piped):
    """Attack pass 57: a recording cut by a power cut (kill -9) and padded to the SD card's block with zero bytes was
    refused as damaged gzip data (zlib read the zeros as more of the stream), as docs/formats.md section 1 promises
    it is not; pass 58: with fewer zeros, or from a pipe, zlib read them as back-references, rows copied from earlier
    text read as new samples. The zeros at its end are never given to zlib: left out with a warning, the stream
    read to its cut, every row its own (a stored block's text, level 0, before even one zero: tests/test_gzip_trial.py
    has compressed data, whose fewer than RUN_BYTES zeros are the stream's own)."""
    body = "".join(f"{i / 100:.2f},{i},1,2\n" for i in range(30000))
    path = _dps_file(tmp_path, body, name="r.csv.gz")
    data = path.read_bytes()
    path.write_bytes(data[:len(data) // 2] + bytes(zeros))
    if piped:
        fifo = tmp_path / "fifo"
        os.mkfifo(fifo)
        feeder = threading.Thread(target=lambda: fifo.write_bytes(path.read_bytes()))
        feeder.start()
        path = fifo
    rec = read_recording(path)
    if piped:
        feeder.join()
    np.testing.assert_array_equal(rec.columns["gx"], np.arange(len(rec)))
    assert 1000 < len(rec) < 30000 and any("cut short" in w for w in rec.warnings)
    assert any(f"{zeros} zero byte{'s' * (zeros > 1)} at its end ignored" in w for w in rec.warnings)


def _synced_gzip(text, every):
    """``text`` as ``gyrofilter record`` writes it: gzip, a sync flush every ``every`` lines."""
    z = zlib.compressobj(6, zlib.DEFLATED, 16 + zlib.MAX_WBITS)
    lines = text.encode().splitlines(keepends=True)
    parts = [z.compress(b"".join(lines[i:i + every])) + z.flush(zlib.Z_SYNC_FLUSH) for i in range(0, len(lines), every)]
    return b"".join(parts) + z.flush()


@pytest.mark.parametrize("seed", range(6))
def test_a_gzip_cut_short_then_padding_then_other_bytes_invents_no_row(tmp_path, seed):
    """Attack pass 59: a recording cut short, padded with zero bytes (or 0xFF, as erased flash reads) and then a byte
    that is not padding (a newline ``echo >>`` adds, stale data) came back with its last row changed (row 774 read
    (7.74, 29, 44, -327), written (7.74, 29, 443, 137)) or one more, with only "cut short" said: the zeros, once a byte
    followed them, went to zlib as more of the stream. Text made of bytes after a run of padding is now held until
    its stream proves whole; a stream cut short there ends at the run, the text left out with a warning. Cut points,
    padding and the byte after it drawn at random: every row read is the row written, none beyond what the cut
    stream holds."""
    rng = np.random.default_rng(seed)
    values = rng.integers(-999, 1000, (3000, 3))
    body = "".join(f"{i / 100:.2f},{a},{b},{c}\n" for i, (a, b, c) in enumerate(values))
    data = _synced_gzip(_dps_file(tmp_path, body).read_text(), int(rng.choice([1, 20, 1000])))
    path = tmp_path / "r.csv.gz"
    for _ in range(25):
        cut = int(rng.integers(len(data) // 10, len(data) - 20))
        pad = bytes([int(rng.choice([0, 0xFF]))]) * int(rng.choice([5, 7, 64, 512, 4096]))
        tail = bytes(rng.integers(1, 255, int(rng.choice([1, 2, 40]))).astype(np.uint8))
        path.write_bytes(data[:cut] + pad + tail)
        decodable = zlib.decompressobj(16 + zlib.MAX_WBITS).decompress(data[:cut]).count(b"\n") - 4  # rows, header aside
        try:
            rec = read_recording(path)
        except RecordingError as exc:  # junk that no stream holds may be refused as damage, never read
            assert "damaged gzip data" in str(exc), exc
            continue
        assert len(rec) <= decodable, (cut, pad[:1], len(pad), tail)
        np.testing.assert_array_equal(rec.gyro_dps, values[:len(rec)])
        assert any("cut short" in w for w in rec.warnings)


@pytest.mark.parametrize("count", [5, 16, 512, 70_000])
def test_0xff_padding_after_a_gzip_stream_is_left_out_with_a_warning(tmp_path, count):
    """Attack pass 59: a recording cut short and padded with 0xFF (erased flash) gained an invented or altered last
    row (51 rows read where zlib decodes 50, the last (0.5041, 12, -3, 40), written (0.50, 13, -2, 41)); after a
    whole stream such padding was refused as damage. A run of 0xFF at the end is padding, as zeros are."""
    body = "".join(f"{i / 100:.2f},{i},1,2\n" for i in range(3000))
    whole = _dps_file(tmp_path, body, name="r.csv.gz").read_bytes()
    path = tmp_path / "p.csv.gz"
    for data, cut in ((whole, False), (whole[:len(whole) // 2], True)):
        path.write_bytes(data + b"\xff" * count)
        rec = read_recording(path)
        np.testing.assert_array_equal(rec.columns["gx"], np.arange(len(rec)))
        assert (len(rec) < 3000) == cut and any(f"{count} 0xFF bytes" in w for w in rec.warnings)


def test_an_empty_gzip_member_after_a_recording_adds_no_warning(tmp_path):
    """Attack pass 59: a whole recording followed by an empty gzip member (``gzip < /dev/null >> rec.csv.gz``) was read
    with "9 zero bytes ... ignored" and "gzip stream cut short": the member's last nine bytes are zeros."""
    body = "".join(f"{i / 100:.2f},{i},1,2\n" for i in range(300))
    path = _dps_file(tmp_path, body, name="r.csv.gz")
    path.write_bytes(path.read_bytes() + gzip.compress(b"", mtime=0) + gzip.compress(b"", mtime=0))
    rec = read_recording(path)
    assert len(rec) == 300 and rec.warnings == []


def test_no_run_in_the_compressed_data_of_a_recording_with_a_time_column_is_as_long_as_padding():
    """``recording.gzip_bytes.RUN_BYTES``, the shortest run of 0x00 or 0xFF from which a stream is on trial, is longer
    than any run in deflate data of recordings with a time column (tools/gzip_runs.py measures it on more rows):
    shorter, such a recording cut short would be read only to the run (4 zeros come in the block headers of constant
    rows). Constant rows without a time column hold long runs (attack pass 60: a stream of them cut short is read to
    its first run, tests/test_gzip_trial.py)."""
    sys.path.insert(0, str(REPO / "tools"))
    try:
        import gzip_runs
    finally:
        sys.path.remove(str(REPO / "tools"))

    longest = gzip_runs.longest_runs(4000)
    assert max(n for name, n in longest.items() if gzip_runs.timed(name)) == RUN_BYTES - 1, longest
    assert min(n for name, n in longest.items() if not gzip_runs.timed(name)) > 10 * RUN_BYTES, longest


def test_a_gzip_cut_short_is_still_a_warning_and_a_prefix(tmp_path):
    body = "".join(f"{i / 100:.2f},{i},1,2\n" for i in range(3000))
    path = _dps_file(tmp_path, body, name="r.csv.gz")
    path.write_bytes(path.read_bytes()[:-20])
    rec = read_recording(path)
    np.testing.assert_array_equal(rec.columns["gx"], np.arange(len(rec)))
    assert 2000 < len(rec) < 3000 and any("cut short" in w for w in rec.warnings)


@pytest.mark.parametrize("line, refused", [("temp_unit: F", True), ("temperature_unit: K", True),
                                           ("Temp units: fahrenheit", True), ("temp: raw", True),
                                           ("temp_unit: C", False), ("temp_unit: degC", False),
                                           ("temp_sensor: on-die", False), ("temp_offset: 36.53", False)])
def test_a_header_key_stating_another_temperature_unit_is_refused(tmp_path, line, refused):
    """Attack pass 59: ``# temp_unit: F`` above a temp column of 77 read as 77 deg C, without a word: a recording's
    ``temp`` is in deg C, and a key that says otherwise is refused as the rate's and the units' are."""
    path = _dps_file(tmp_path, "".join(f"{i / 100:.2f},0.1,0.2,0.3,77\n" for i in range(50)), header=f"# {line}\n")
    path.write_text(path.read_text().replace("t,gx,gy,gz\n", "t,gx,gy,gz,temp\n"))
    if refused:
        with pytest.raises(RecordingError, match=f"header key .* but a recording's temp column is in deg C"):
            read_recording(path)
    else:
        assert read_recording(path).columns["temp"][0] == 77.0


@pytest.mark.parametrize("key", ["gyro_unit", "sample_rate_hz", "sensor"])
def test_a_repeated_header_key_is_refused_naming_its_line(tmp_path, key):
    value = {"gyro_unit": "rad/s", "sample_rate_hz": "50", "sensor": "b"}[key]
    path = _dps_file(tmp_path, "0,1,2,3\n", header=f"# sensor: a\n# {key}: {value}\n")
    with pytest.raises(RecordingError, match=f"{path}: line 5: header key '{key}' repeated \\(first on line [234]\\)"):
        read_recording(path)


def test_a_t_step_beyond_a_float_is_refused_without_a_warning(tmp_path):
    """Issue 37 (attack): t from -1e308 to 1e308 printed numpy's "RuntimeWarning: overflow
    encountered in subtract" above the one-line refusal."""
    path = _dps_file(tmp_path, "-1e308,0,0,0\n1e308,0,0,0\n1.1e308,0,0,0\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(RecordingError, match=f"{path}: t steps by "):
            read_recording(path)


@pytest.mark.parametrize("step_s", [0.001, 0.0094, 0.0106, 0.1])
def test_t_that_disagrees_with_the_sample_rate_is_refused_both_ways(tmp_path, step_s):
    """A 100-Hz header with 1-ms steps of t read silently (Allan taus 10x off)."""
    body = "".join(f"{i * step_s!r},0,0,0\n" for i in range(50))
    path = _dps_file(tmp_path, body)
    with pytest.raises(RecordingError, match=f"{path}: t steps by {step_s:g} s .*sample_rate_hz 100 means 0.01 s"):
        read_recording(path)


@pytest.mark.parametrize("chunk_rows", [1, 64, 1 << 16])
def test_t_with_gaps_and_jitter_within_5_percent_still_reads(tmp_path, chunk_rows):
    rng = np.random.default_rng(4)
    steps = rng.uniform(0.0096, 0.0104, 5000)
    steps[rng.choice(5000, 1500, replace=False)] *= 3  # 30 % of the steps lost two samples
    t = np.cumsum(steps)
    rec = Recording.from_dps(np.zeros((5000, 3)), 100.0, t_s=t)
    write_recording(tmp_path / "gaps.csv", rec)
    head, data = _read_chunked(tmp_path / "gaps.csv", chunk_rows)
    np.testing.assert_array_equal(data[:, 0], t)
    assert head.t_gaps == 1500


@pytest.mark.parametrize("chunk_rows", [1, 700, 1 << 16])
def test_t_of_a_device_that_lost_most_samples_reads_with_its_gaps_counted(tmp_path, chunk_rows):
    """Issue 37 (attack 3): a serial device that lost two samples of three, restarting its
    counter each time, gave steps of 0.02 s and 0.01 s in turn (median 0.02 s in a 100-Hz file):
    refused, so that its recording kept nothing. The typical step is the median of the steps
    that are not gaps; the gaps are counted."""
    steps = np.tile([0.02, 0.01], 1500)
    steps[::7] = 0.03  # and a few longer gaps
    head, data = _read_chunked(_dps_file(tmp_path, _t_body(steps)), chunk_rows)
    np.testing.assert_array_equal(data[:, 0], np.concatenate(([0.0], np.cumsum(steps))))
    assert head.t_gaps == np.count_nonzero(steps > 0.015)


def _t_body(steps_s):
    """Data lines of a recording whose t has the steps ``steps_s`` (gyro values all 0)."""
    t = np.concatenate(([0.0], np.cumsum(steps_s)))
    return "".join(f"{v!r},0,0,0\n" for v in t.tolist())


@pytest.mark.parametrize("chunk_rows", [1, 700, 1 << 16])
@pytest.mark.parametrize("late_step_s, late_from", [pytest.param(0.001, 2300, id="t runs 10x fast"),
                                                     pytest.param(0.025, 2000, id="t at 40 Hz from step 2000")])
def test_t_is_checked_against_the_rate_in_every_window_not_only_the_first(tmp_path, chunk_rows, late_step_s, late_from):
    """Only the first 1000 steps were checked: a t that ran 10x fast from step 2300 on, or at
    40 Hz from step 2000 on (a window of gaps only, each 2.5 sample intervals: no whole number of
    samples lost), read silently with the header's rate. Windows are steps 1-1000, 1001-2000, ...;
    the third (mostly late steps) starts at sample 2000, file line 2005. (Every other sample lost
    from step 2000 on reads, its gaps counted: a device's counter gaps look so,
    test_a_stretch_of_gaps_only_where_the_file_shows_its_rate_is_lost_samples.)"""
    steps = np.full(4000, 0.01)
    steps[late_from:] = late_step_s
    path = _dps_file(tmp_path, _t_body(steps))
    said = (f"{path}: t steps by {late_step_s:g} s (median of the 1000 steps from line 2005), but sample_rate_hz "
            "100 means 0.01 s: more than 5% apart (is sample_rate_hz or t wrong, or were most samples lost here?)")
    if late_step_s < 0.01:  # caught a window sooner by its span (200 fast steps: 180 rows more than it has room for)
        said = (f"{path}: t's 1000 steps from line 1505 span 8.2 s, but 1000 sample intervals at sample_rate_hz 100 "
                "take 10 s: more rows than the rate has room for")
    with pytest.raises(RecordingError, match=re.escape(said) + (f"|{re.escape(str(path))}: t steps by 0.001 s" if late_step_s < 0.01 else "")):
        _read_chunked(path, chunk_rows)


@pytest.mark.parametrize("chunk_rows", [1, 999, 1 << 16])
def test_the_steps_after_the_last_whole_window_and_a_short_file_are_checked_as_before(tmp_path, chunk_rows):
    """A file longer than a window: a minority of odd steps in its tail reads (gaps there are
    legal), a majority of the last half window or more does not; a file shorter than a window:
    the median of all its steps is checked."""
    steps = np.full(2500, 0.01)
    steps[2300:] = 0.001  # 200 fast steps: a minority of every window and of the tail
    steps[2299] += 200 * 0.009  # after a stall of 1.8 s: samples that catch up, the rate kept (they would not fit else)
    head, data = _read_chunked(_dps_file(tmp_path, _t_body(steps)), chunk_rows)
    assert len(data) == 2501 and head.t_gaps == 1
    steps[2100:] = 0.001  # 400 of the last 500 steps: the tail runs at another rate (was read before)
    with pytest.raises(RecordingError, match=r"t steps by 0.001 s \(median of the 500 steps from line 2005\)"
                                             r"|t's 1000 steps from line 1505 span 6.4 s, but 1000 sample intervals"):
        _read_chunked(_dps_file(tmp_path, _t_body(steps), name="tail.csv"), chunk_rows)
    with pytest.raises(RecordingError, match=r"t steps by 0.001 s \(median of its first 999 steps from line 5\)"):
        _read_chunked(_dps_file(tmp_path, _t_body(np.full(999, 0.001)), name="short.csv"), chunk_rows)


@pytest.mark.parametrize("chunk_rows", [1, 999, 1 << 16])
@pytest.mark.parametrize("stall_at, caught_up", [(4900, 200), (5000, 200), (5000, 60), (7700, 200)])
def test_samples_that_catch_up_after_a_stall_read_wherever_a_window_starts(tmp_path, chunk_rows, stall_at, caught_up):
    """A stall of 2 s at 100 Hz whose 200 samples then arrive 1 ms apart (stamped as they came):
    a window that started among them (steps 5001-6000) spanned 8.2 s for its 1000 intervals and
    the record was refused as holding rows the rate has no room for (attack pass 11: 17 of 50 such
    stalls at random places; 0.6 s stalls too, its window 9.46 s). The stall's gap lies in the half
    window before: with it the steps span their intervals. Rows inserted without a stall before
    them are still refused."""
    steps = np.full(8000, 0.01)
    steps[stall_at - 1] += caught_up * 0.009
    steps[stall_at:stall_at + caught_up] = 0.001
    head, data = _read_chunked(_dps_file(tmp_path, _t_body(steps)), chunk_rows)
    assert len(data) == 8001 and head.t_gaps == 1
    steps[stall_at - 1] = 0.01  # no stall: 180 rows more than the rate has room for (54: within the slack)
    if caught_up < 100:
        return
    with pytest.raises(RecordingError, match=r"more rows than the rate has room for"):
        _read_chunked(_dps_file(tmp_path, _t_body(steps), name="inserted.csv"), chunk_rows)


@pytest.mark.parametrize("chunk_rows", [1, 999, 1 << 16])
def test_a_tail_that_lost_every_other_sample_reads_as_gaps_as_it_does_inside_the_file(tmp_path, chunk_rows):
    """The steps after the last whole window were checked alone: a tail of 700 steps of which every
    other sample was lost showed half the rate and was refused, where the same steps inside the
    file are gaps; the writer refused it at its close, and a live recording (a serial device that
    lost every other line over its last 7 s) was removed whole (attack pass 11). The last window
    is the 1000 steps that end the file, judged as any window: rows inserted in the tail are still
    refused, by its span."""
    steps = np.concatenate((np.full(5000, 0.01), np.full(700, 0.02)))
    head, data = _read_chunked(_dps_file(tmp_path, _t_body(steps)), chunk_rows)
    assert len(data) == 5701 and head.t_gaps == 700
    head, data = _read_chunked(_dps_file(tmp_path, _t_body(np.concatenate((steps, np.full(5000, 0.01)))),
                                         name="inside.csv"), chunk_rows)
    assert len(data) == 10701 and head.t_gaps == 700
    path = tmp_path / "written.csv"
    t = np.concatenate(([0.0], np.cumsum(steps)))
    with RecordingWriter(path, {"sample_rate_hz": 100, "gyro_unit": "dps"}, ["t", "gx", "gy", "gz"]) as writer:
        for i in range(0, len(t), chunk_rows):
            writer.write(np.column_stack((t[i:i + chunk_rows], np.zeros((len(t[i:i + chunk_rows]), 3)))))
    assert len(read_recording(path).t_s) == 5701
    with pytest.raises(RecordingError, match=r"t's 1000 steps up to line 5305 span 7.3 s, but 1000 sample intervals"):
        _read_chunked(_dps_file(tmp_path, _t_body(np.concatenate((np.full(5000, 0.01), np.full(300, 0.001)))),
                                name="inserted.csv"), chunk_rows)


@pytest.mark.parametrize("chunk_rows", [1, 999, 1 << 16])
@pytest.mark.parametrize("lost_step_s, where", [(0.02, "tail"), (0.03, "tail"), (0.02, "inside"), (0.02, "start"),
                                                 (0.02, "start, the rate shown by the last window")])
def test_a_stretch_of_gaps_only_where_the_file_shows_its_rate_is_lost_samples(tmp_path, chunk_rows, lost_step_s, where):
    """A device that lost every other sample (or two of three) over its last 12 s, its counter's
    gaps: the last window held gaps only and was compared with the rate as a t at half the rate,
    and the live recording was refused at its close and removed whole (attack pass 11: 50 s of
    samples lost); inside the file, or at its start, such a window ended the recording. Where
    another window shows the rate (most of its steps one interval), a window of gaps only is lost
    samples when its steps are whole sample intervals (up to 10); a t at half the rate throughout
    (a step of one interval at its start or not), at 40 Hz (2.5 intervals) or 15 intervals apart
    is still refused, by the reader and the writer alike."""
    lost = np.full(1200 if where == "tail" else 1500, lost_step_s)
    steps = {"tail": lambda: np.concatenate((np.full(5000, 0.01), lost)),
             "inside": lambda: np.concatenate((np.full(5000, 0.01), lost, np.full(2000, 0.01))),
             "start": lambda: np.concatenate((lost, np.full(5000, 0.01))),
             "start, the rate shown by the last window": lambda: np.concatenate((lost[:1200], np.full(600, 0.01)))
             }[where]()
    head, data = _read_chunked(_dps_file(tmp_path, _t_body(steps)), chunk_rows)
    assert len(data) == len(steps) + 1 and head.t_gaps == np.count_nonzero(steps > 0.015)
    path = tmp_path / "written.csv"
    t = np.concatenate(([0.0], np.cumsum(steps)))
    with RecordingWriter(path, {"sample_rate_hz": 100, "gyro_unit": "dps"}, ["t", "gx", "gy", "gz"]) as writer:
        for i in range(0, len(t), chunk_rows if chunk_rows > 1 else 7):
            part = t[i:i + (chunk_rows if chunk_rows > 1 else 7)]
            writer.write(np.column_stack((part, np.zeros((len(part), 3)))))
    np.testing.assert_array_equal(read_recording(path).t_s, t)
    for first in ([], [0.01]):  # t at half the rate, a step of one interval at its start or not
        with pytest.raises(RecordingError, match=r"t steps by 0.02 s \(median of "):
            _read_chunked(_dps_file(tmp_path, _t_body(np.concatenate((first, np.full(3000, 0.02)))), name="half.csv"),
                          chunk_rows)
    for odd_s in (0.025, 0.15):
        steps[steps > 0.015] = odd_s
        with pytest.raises(RecordingError, match=rf"t steps by {odd_s:g} s"):
            _read_chunked(_dps_file(tmp_path, _t_body(steps), name="odd.csv"), chunk_rows)


@pytest.mark.parametrize("chunk_rows", [1, 999, 1 << 16])
@pytest.mark.parametrize("count", [3000, 600])
def test_a_t_of_the_device_counter_at_whole_intervals_throughout_is_lost_samples(tmp_path, chunk_rows, count):
    """Attack pass 14: a serial device that lost every other sample from its first line gives steps
    of 2 intervals throughout, the same t as one at half the rate: no window shows the rate and
    the writer refused the live recording at its close, removed whole. A header that says t is
    the device's counter (t_from: device counter, written by record) makes them lost samples, its
    gaps counted, by the reader and the writer alike; without it, or at 2.5 intervals, still
    refused."""
    steps = np.full(count, 0.02)
    counted = "# t_from: device counter\n"
    head, data = _read_chunked(_dps_file(tmp_path, _t_body(steps), header=counted), chunk_rows)
    assert len(data) == count + 1 and head.t_gaps == count
    path = tmp_path / "written.csv"
    t = np.concatenate(([0.0], np.cumsum(steps)))
    with RecordingWriter(path, {"sample_rate_hz": 100, "gyro_unit": "dps", "t_from": "device counter"},
                         ["t", "gx", "gy", "gz"]) as writer:
        for i in range(0, len(t), chunk_rows if chunk_rows > 1 else 7):
            part = t[i:i + (chunk_rows if chunk_rows > 1 else 7)]
            writer.write(np.column_stack((part, np.zeros((len(part), 3)))))
    np.testing.assert_array_equal(read_recording(path).t_s, t)
    with pytest.raises(RecordingError, match=r"t steps by 0.02 s \(median of "):
        _read_chunked(_dps_file(tmp_path, _t_body(steps), name="half.csv"), chunk_rows)
    with pytest.raises(RecordingError, match=r"t steps by 0.025 s"):
        _read_chunked(_dps_file(tmp_path, _t_body(np.full(count, 0.025)), header=counted, name="odd.csv"), chunk_rows)


@pytest.mark.parametrize("chunk_rows", [1, 999, 1 << 16])
@pytest.mark.parametrize("steps", [pytest.param(np.full(3000, 0.11), id="10 of 11 lost throughout"),
                                   pytest.param(np.r_[np.full(2000, 0.01), np.full(1500, 0.19), np.full(2000, 0.01)],
                                                id="18 of 19 lost over 1500 steps")])
def test_a_t_of_the_device_counter_more_than_10_intervals_apart_is_lost_samples(tmp_path, chunk_rows, steps):
    """Attack pass 15: a window of gaps only more than 10 intervals apart was refused at once
    (every such step is within 5 % of a whole number of intervals, so that says nothing of the
    rate), also where t is the device's counter: a device that lost 10 of every 11 samples from
    its first line (a serial line too slow for its rate) had its live recording refused at the
    close and removed whole, one that did so for 1500 lines mid-recording stopped there. Each
    step of a device's counter is the whole number of samples it counted: lost samples, read and
    written; without the key still refused."""
    counted = "# t_from: device counter\n"
    head, data = _read_chunked(_dps_file(tmp_path, _t_body(steps), header=counted), chunk_rows)
    assert len(data) == len(steps) + 1 and head.t_gaps == np.count_nonzero(steps > 0.015)
    path = tmp_path / "written.csv"
    t = np.concatenate(([0.0], np.cumsum(steps)))
    with RecordingWriter(path, {"sample_rate_hz": 100, "gyro_unit": "dps", "t_from": "device counter"},
                         ["t", "gx", "gy", "gz"]) as writer:
        for i in range(0, len(t), chunk_rows):
            part = t[i:i + chunk_rows]
            writer.write(np.column_stack((part, np.zeros((len(part), 3)))))
    np.testing.assert_array_equal(read_recording(path).t_s, t)
    with pytest.raises(RecordingError, match=r"t steps by 0.(11|19) s \(median of "):
        _read_chunked(_dps_file(tmp_path, _t_body(steps), name="plain.csv"), chunk_rows)


@pytest.mark.parametrize("chunk_rows", [1, 700, 1 << 16])
def test_a_filtered_outputs_rows_whose_blocks_lost_samples_are_its_gaps(tmp_path, chunk_rows):
    """Issue 37 (attack 4): a filtered output (header input_sample_rate_hz, rows per block of 5
    input samples) from a device that lost a sample in every block steps by 0.06 s at 20 Hz: a
    window of gaps only. It reads, each such step a gap (longer than 0.05 + 0.005 s); the same t
    in a file of samples (no input_sample_rate_hz) is a t at the wrong rate; a row that comes
    faster than its block, or an input rate below the rows', is refused."""
    steps = np.full(2500, 0.06)
    steps[::7] = 0.05  # a block that lost nothing now and then: its step shows the rate
    filtered = "# filtered_from: raw.csv\n# input_sample_rate_hz: 100\n"
    head, data = _read_chunked(_dps_file(tmp_path, _t_body(steps), filtered, rate_hz=20), chunk_rows)
    assert len(data) == 2501 and head.t_gaps == np.count_nonzero(steps > 0.055)
    head, data = _read_chunked(_dps_file(tmp_path, _t_body(np.full(2500, 0.06)), filtered, rate_hz=20, name="all.csv"),
                               chunk_rows)  # every block lost a sample: windows of gaps only
    assert len(data) == 2501 and head.t_gaps == 2500
    with pytest.raises(RecordingError, match=r"t steps by 0.06 s \(median of its first 1000 steps from line 5\)"):
        _read_chunked(_dps_file(tmp_path, _t_body(np.full(2500, 0.06)), rate_hz=20, name="samples.csv"), chunk_rows)
    with pytest.raises(RecordingError, match=r"t steps by 0.04 s"):
        _read_chunked(_dps_file(tmp_path, _t_body(np.full(2500, 0.04)), filtered, rate_hz=20, name="fast.csv"), chunk_rows)
    with pytest.raises(RecordingError, match=r"input_sample_rate_hz 10 is below sample_rate_hz 20; a filtered output"):
        _read_chunked(_dps_file(tmp_path, "", "# filtered_from: raw.csv\n# input_sample_rate_hz: 10\n", rate_hz=20, name="below.csv"), chunk_rows)


@pytest.mark.parametrize("name", ["late.csv", "late.csv.gz"])
def test_a_recording_whose_line_ends_turn_cr_only_is_refused_from_that_line(tmp_path, name):
    """Attack pass 16 (issue 37): LF lines, then CR-only ones (a classic-Mac log appended) with no LF
    after them: the rest of the file read as one last line an interruption cut, dropped with a
    warning ("recording interrupted?"): 5 rows of 300 kept. Refused naming the line where they turn."""
    lf = "".join(f"{i / 100:.2f},0.1,-0.2,0.3\n" for i in range(5))
    cr = "".join(f"{i / 100:.2f},0.1,-0.2,0.3\r" for i in range(5, 300))
    data = f"# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\nt,gx,gy,gz\n{lf}{cr}".encode()
    (tmp_path / name).write_bytes(gzip.compress(data) if name.endswith(".gz") else data)
    with pytest.raises(RecordingError, match=re.escape(f"{tmp_path / name}: line 10: line ends are CR only from there on "
                                                       "(old Mac)")):
        read_recording(tmp_path / name)


@pytest.mark.parametrize("name", ["mac.csv", "mac.csv.gz"])
@pytest.mark.parametrize("rows", [300, 120_000])
def test_a_recording_whose_line_ends_are_cr_only_is_refused_naming_them(tmp_path, name, rows):
    """Issue 37 (attack passes 12-14): a recording saved with CR-only line ends (classic Mac OS)
    was one line: "line 1: missing header key(s) 'sample_rate_hz', 'gyro_unit' ... another tool's
    log: gyrofilter convert" (convert then refused it too), or past 1 MB "line 1: longer than
    1048576 bytes". Refused naming the file and the line ends, as convert refuses a log; the
    same text with LF or CRLF line ends reads."""
    body = "".join(f"{i / 100:.2f},0.1,-0.2,0.3\n" for i in range(rows))
    text = f"# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\nt,gx,gy,gz\n{body}"
    for ends, path in (("\r", tmp_path / name), ("\r\n", tmp_path / f"dos-{name}"), ("\n", tmp_path / f"unix-{name}")):
        data = text.replace("\n", ends).encode()
        path.write_bytes(gzip.compress(data, compresslevel=1) if name.endswith(".gz") else data)
    with pytest.raises(RecordingError, match=re.escape(f"{tmp_path / name}: line ends are CR only (old Mac): convert "
                                                       "them to LF (e.g. tr '\\r' '\\n')")):
        read_recording(tmp_path / name)
    for kind in ("dos", "unix"):
        rec = read_recording(tmp_path / f"{kind}-{name}")
        assert len(rec) == rows and rec.gyro_dps[-1].tolist() == [0.1, -0.2, 0.3]


def test_an_input_rate_without_filtered_from_is_refused_naming_the_file_and_key(tmp_path):
    """Issue 37 (attack passes 12-14): a file of samples whose header named input_sample_rate_hz
    (but no filtered_from) was read as a filtered output: its t checked as rows of blocks (a t at
    a tenth of the rate read, every step "a gap"). The key without filtered_from is refused,
    reading and writing; with it, the file reads as a filtered output."""
    tenth = _t_body(np.full(1500, 0.011))
    path = _dps_file(tmp_path, tenth, "# input_sample_rate_hz: 1000\n", name="liar.csv")
    with pytest.raises(RecordingError, match=r"liar.csv: header key 'input_sample_rate_hz' without 'filtered_from'"):
        read_recording(path)
    with pytest.raises(RecordingError, match=r"header key 'input_sample_rate_hz' without 'filtered_from'"):
        write_recording(tmp_path / "out.csv", Recording.from_dps(np.zeros((3, 3)), 100.0,
                                                                 header={"input_sample_rate_hz": "1000"}))
    assert not (tmp_path / "out.csv").exists()
    rec = read_recording(_dps_file(tmp_path, tenth, "# filtered_from: raw.csv\n# input_sample_rate_hz: 1000\n"))
    assert len(rec) == 1501 and rec.header["filtered_from"] == "raw.csv"


@pytest.mark.parametrize("runs", [[(1000, 0.01), (999, 0.001)], [(501, 0.01), (998, 0.001), (1501, 0.01)]])
def test_a_stretch_at_another_rate_as_long_as_a_window_is_caught_wherever_it_lies(tmp_path, runs):
    """Fixed windows 1-1000, 1001-2000 missed 998 fast steps straddling their border, and a fast
    tail of 999 steps: half a file at 10x the header's rate read without a word."""
    steps = np.concatenate([np.full(n, step) for n, step in runs])
    with pytest.raises(RecordingError, match=r"t steps by 0.001 s|more rows than the rate has room for"):
        _read_chunked(_dps_file(tmp_path, _t_body(steps)), 1 << 16)


def test_writers_refuse_a_t_the_reader_would_refuse(tmp_path):
    """What is written reads back: a t whose steps disagree with sample_rate_hz in some window."""
    steps = np.full(2999, 0.01)
    steps[1000:] = 0.025  # a window of gaps only, 2.5 sample intervals each: t at 40 Hz
    t = np.concatenate(([0.0], np.cumsum(steps)))
    rec = Recording.from_dps(np.zeros((3000, 3)), 100.0, t_s=t)
    with pytest.raises(RecordingError, match=r"late.csv: t steps by 0.025 s \(median of the 1000 steps from row 1001 of "
                                             r"the output\), .* \(not written: it would not read back\)"):
        write_recording(tmp_path / "late.csv", rec)
    assert not (tmp_path / "late.csv").exists()
    path = tmp_path / "live.csv"
    with RecordingWriter(path, {"sample_rate_hz": 100, "gyro_unit": "dps"}, ["t", "gx", "gy", "gz"], name="mine.csv") as writer:
        writer.write(np.column_stack([t[:1200], np.zeros((1200, 3))]))
        with pytest.raises(RecordingError, match=r"^mine.csv: t steps by 0.025 s \(median of the 1000 steps from row 1001 "
                                                 r"of the output\), .*\(not written: it would not read back\)$"):
            writer.write(np.column_stack([t[1200:], np.zeros((1800, 3))]))
    assert len(read_recording(path)) == 1200
    short = RecordingWriter(tmp_path / "short.csv", {"sample_rate_hz": 100, "gyro_unit": "dps"}, ["t", "gx", "gy", "gz"])
    short.write(np.column_stack([np.arange(50) * 0.03, np.zeros((50, 3))]))
    with pytest.raises(RecordingError, match=r"t steps by 0.03 s \(median of its first 49 steps from row 1 of the output\)"):
        short.close()


def test_writers_refuse_non_finite_values_before_anything_lands(tmp_path):
    rec = Recording.from_dps(np.array([[1.0, 2.0, 3.0], [1e308, np.inf, 0.0]]), 100.0)
    with pytest.raises(RecordingError, match=r"column 'gy' of row 2 .* is inf; a recording holds finite numbers only"):
        write_recording(tmp_path / "inf.csv", rec)
    assert not (tmp_path / "inf.csv").exists()
    path = tmp_path / "live.csv"
    with RecordingWriter(path, {"sample_rate_hz": 100, "gyro_unit": "dps"}, ["gx", "gy", "gz"]) as writer:
        writer.write(np.array([[1.0, 2.0, 3.0]]))
        with pytest.raises(RecordingError, match="column 'gz' of row 1 .* is nan"):
            writer.write(np.array([[4.0, 5.0, np.nan], [7.0, 8.0, 9.0]]))
    assert read_recording(path).columns["gx"].tolist() == [1.0]


def test_writers_refuse_rates_the_reader_would_refuse(tmp_path):
    """What is written reads back: a rate beyond +-MAX_RATE_DPS in deg/s is refused by the writers too."""
    rec = Recording.from_dps(np.array([[1.0, 2.0, 3.0], [0.0, -100000.5, 0.0]]), 100.0)
    with pytest.raises(RecordingError, match=r"row 2 of the rows to write: column 'gy' is -100000.5 dps, beyond"):
        write_recording(tmp_path / "big.csv", rec)
    assert not (tmp_path / "big.csv").exists()
    path = tmp_path / "live.csv"
    with RecordingWriter(path, {"sample_rate_hz": 100, "gyro_unit": "lsb", "lsb_per_dps": 0.25}, ["gx", "gy", "gz"]) as writer:
        writer.write(np.array([[1.0, 2.0, 25000.0]]))  # 100 000 deg/s: the bound itself
        with pytest.raises(RecordingError, match="row 1 of the rows to write: column 'gz' is 25001 lsb, beyond"):
            writer.write(np.array([[4.0, 5.0, 25001.0], [7.0, 8.0, 9.0]]))
    assert read_recording(path).columns["gz"].tolist() == [25000.0]


def test_a_gzip_bomb_of_one_long_line_is_refused_in_bounded_memory(tmp_path):
    """204 KB of gzip made one 200 MB line: 1.3 GB of memory and the whole line in the error."""
    import tracemalloc
    import zlib

    from gyrofilter.recording import MAX_LINE_BYTES

    path = tmp_path / "bomb.csv.gz"
    z = zlib.compressobj(9, zlib.DEFLATED, 16 + zlib.MAX_WBITS)
    parts = [z.compress(b"# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\ngx,gy,gz\n1,2,3\n")]
    parts += [z.compress(b"1" * (1 << 20)) for _ in range(32)]
    path.write_bytes(b"".join(parts) + z.compress(b",2,3\n") + z.flush())
    tracemalloc.start()
    try:
        with pytest.raises(RecordingError) as info:
            read_recording(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    text = str(info.value)
    assert text.startswith(f"{path}: line 6: longer than {MAX_LINE_BYTES} bytes") and len(text) < 300, text
    assert peak < 8 * MAX_LINE_BYTES


def test_dev_zero_ends_at_once_with_an_error():
    with pytest.raises(RecordingError, match="/dev/zero: line 1: longer than"):
        read_recording("/dev/zero")


@pytest.mark.parametrize("value", ["a\nb", "tab\there", "cr\r", "nul\x00", "sep\u2028", " spaces "])
def test_header_values_with_control_characters_read_back_as_written(tmp_path, value):
    path = tmp_path / "h.csv"
    with RecordingWriter(path, {"sample_rate_hz": 100, "gyro_unit": "dps", "source": value, "sensor": "x"},
                         ["gx", "gy", "gz"]) as writer:
        writer.write(np.ones((2, 3)))
        writer.note(f"warning: {value}")
    rec = read_recording(path)
    from gyrofilter.recording import one_line_text

    assert rec.header["source"] == one_line_text(value) and rec.header["sensor"] == "x" and len(rec) == 2
    assert "\\" in rec.header["source"] or value == " spaces "
    assert [n.text for n in rec.notes] == [one_line_text(f"warning: {value}")]


@pytest.mark.parametrize("header, match", [
    ({"sample_rate_hz": "1e9", "gyro_unit": "dps"}, r"sample_rate_hz must be a number of Hz in \[0.001, 100000\], got 1000000000.0"),
    ({"sample_rate_hz": "100", "gyro_unit": "dps", "sample_rate_hz:": "5"}, "header key 'sample_rate_hz:' is not a name"),
    ({"sample_rate_hz": "100", "gyro_unit": "dps", "my key": "5"}, "header key 'my key' is not a name"),
    ({"sample_rate_hz": "1_00", "gyro_unit": "dps"}, "sample_rate_hz must be a plain decimal number"),
    ({"sample_rate_hz": "100", "gyro_unit": "lsb", "lsb_per_dps": "-131"}, r"lsb_per_dps must be a number of LSB per deg/s in \[0.1, 1e\+08\]"),
    ({"sample_rate_hz": "100", "gyro_unit": "lsb", "lsb_per_dps": "1e308"}, r"lsb_per_dps must be a number of LSB per deg/s in \[0.1, 1e\+08\]"),
    ({"sample_rate_hz": "100", "gyro_unit": "dps", "simulated_model": "x" * (1 << 21)}, "longer than 1048576 bytes"),
])
def test_the_writer_refuses_what_the_reader_would_refuse_before_creating_the_file(tmp_path, header, match):
    path = tmp_path / "w.csv"
    with pytest.raises(RecordingError, match=match) as info:
        RecordingWriter(path, header, ["t", "gx", "gy", "gz"])
    assert not path.exists() and len(str(info.value)) < 300


@pytest.mark.parametrize("cell", ["0.0_1", "1_000", "0x1", "1d5", "\u0661", "infinity", "1e999", "--1", "1e5e3"])
@pytest.mark.parametrize("with_note", [False, True])
def test_cells_are_plain_decimal_numbers(tmp_path, cell, with_note):
    """Python's float() reads 0.0_1 as 0.01 and the Arabic-Indic one as 1: the per-line
    fallback (taken when a chunk holds a note) read them."""
    body = ("# a note\n" if with_note else "") + f"0,1,{cell},3\n0.01,1,2,3\n"
    path = _dps_file(tmp_path, body)
    with pytest.raises(RecordingError, match=f"{path}: line [56]: column 'gy' is "):
        read_recording(path)


@pytest.mark.parametrize("rate", ["1e-300", "0.0009"])
def test_a_header_rate_below_0_001_hz_is_refused(tmp_path, rate):
    path = _dps_file(tmp_path, "", rate_hz=rate).with_suffix(".csv")
    with pytest.raises(RecordingError, match=r"sample_rate_hz must be a number of Hz in \[0.001, 100000\]"):
        read_recording(path)


def test_long_values_in_errors_are_quoted_short(tmp_path):
    path = _dps_file(tmp_path, "0,1,2,3\n", header="# " + "d" * 5000 + "\n")
    with pytest.raises(RecordingError, match="line 4: header line is not 'key: value'") as info:
        read_recording(path)
    assert len(str(info.value)) < 300 and "5002 characters" in str(info.value)
    path = tmp_path / "cols.csv"
    path.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\n" + ",".join(f"c{i}" for i in range(3000)) + "\n")
    with pytest.raises(RecordingError, match="missing column") as info:
        read_recording(path)
    assert len(str(info.value)) < 300


@pytest.mark.parametrize("key, meant, both", [
    ("Gyro_Unit: rad/s", "gyro_unit", True), ("SAMPLE_RATE_HZ: 200", "sample_rate_hz", True),
    ("gyrofilter_recording: 1", "gyrofilter-recording", True), ("Accel_Unit: g", "accel_unit", False),
    ("Filtered-From: x.csv", "filtered_from", False), ("gyro unit: rad/s", "gyro_unit", True),
    ("ＧＹＲＯ＿ＵＮＩＴ: rad/s", "gyro_unit", True), ("Full-Scale-DPS: 250", "full_scale_dps", False),
    # letters outside ASCII that look like its own (attack pass 47): Cyrillic о, dotless ı, Turkish İ, an accent
    ("gyr\u043e_unit: rad/s", "gyro_unit", True), ("gyro_un\u0131t: rad/s", "gyro_unit", True),
    ("GYRO_UN\u0130T: rad/s", "gyro_unit", True), ("gyro\u0301_unit: rad/s", "gyro_unit", True),
    ("\u03c4_from: device counter", "t_from", False),
    # with nothing for "_" (pass 48): camelCase, run together
    ("GyroUnit: dps", "gyro_unit", True), ("sampleRateHz: 200", "sample_rate_hz", True),
    ("fullScaleDps: 2000", "full_scale_dps", False), ("lsbperdps: 65.5", "lsb_per_dps", False),
    # half its letters look-alikes; a letter more or fewer (pass 49)
    ("\u0455\u0430m\u0440l\u0435_r\u0430t\u0435_hz: 50", "sample_rate_hz", True), ("gyro_units: rad/s", "gyro_unit", True),
    ("accel_unt: g", "accel_unit", False),
    # two letters swapped (pass 50: report's clipping check was silently skipped)
    ("full_scale_dsp: 250", "full_scale_dps", False), ("gyro_uint: rad/s", "gyro_unit", True)])
def test_a_header_key_gyrofilter_reads_spelt_otherwise_is_refused_naming_it(tmp_path, key, meant, both):
    """Attack pass 45: `Gyro_Unit: rad/s` beside `gyro_unit: dps` was kept as an unrelated key without a word (the
    samples read as deg/s); alone, `Accel_Unit` left the accelerometer without its unit. Keys are case-sensitive:
    a key gyrofilter reads, spelt in another case or with "-" for "_", is refused, naming both spellings. Pass 47:
    `Full-Scale-DPS` was ignored by report's clipping check; look-alike letters kept `gyrо_unit` as another key.
    Pass 48: `GyroUnit: dps` beside `gyro_unit: lsb` was kept as another key."""
    name = key.split(":")[0]
    path = _dps_file(tmp_path, "0,1,2,3\n", header=f"# {key}\n")
    with pytest.raises(RecordingError, match=re.escape(f"header key '{name}': gyrofilter reads '{meant}', spelt exactly "
                                                       "so" + (" (the file has both)" if both else ""))):
        read_recording(path)


@pytest.mark.parametrize("key", ["Gerät", "温度", "传感器的型号和序列号", "τ", "gyro_units_note", "lsb_per_deg",
                                 "from", "t_offset", "sensor_serial", "full_scale", "temperature", "gyro2_unit",
                                 "sample_rate_hz2"])
def test_a_key_of_its_own_outside_ascii_is_kept(tmp_path, key):
    """Pass 47's look-alike check refuses a few foreign letters standing in a key gyrofilter reads, not every key
    outside ASCII, and pass 49's a letter more or fewer in a long key, not every key like one: unknown keys are kept
    (``sample_rate: x`` no longer: a key of rate words must state the file's rate, pass 53)."""
    path = _dps_file(tmp_path, "0,1,2,3\n", header=f"# {key}: x\n")
    assert read_recording(path).header[key] == "x"


def test_a_descriptive_key_in_another_case_is_a_key_of_its_own(tmp_path):
    """Attack pass 46: a serial device's `Sensor=MPU6050` was written beside gyrofilter's `sensor` and the files
    recorded so were refused after pass 45's key check; descriptive keys are not among the keys it compares."""
    path = _dps_file(tmp_path, "0,1,2,3\n", header="# sensor: serial device\n# Sensor: MPU6050\n# Chip_ID: 0x68\n")
    assert read_recording(path).header["Sensor"] == "MPU6050"


@pytest.mark.parametrize("first, hint", [("# gyrofilter\n\nReal-time filtering\n", True), ("# notes\n", True),
                                         ("# gyrofilter-recording: 1\n# sample_rate_hz 100\n", False)])
def test_a_file_whose_first_line_is_not_a_header_key_says_how_a_recording_starts(tmp_path, first, hint):
    """A new user's trial: `replay README.md` said only "line 1: header line is not 'key: value'", where a CSV
    of another tool got the recording's first lines and `gyrofilter convert`; a bad line further down is the
    recording's own, named alone."""
    path = tmp_path / "some.md"
    path.write_text(first + "0,1,2,3\n")
    with pytest.raises(RecordingError, match="header line is not 'key: value'") as info:
        read_recording(path)
    assert ("a recording starts with '# gyrofilter-recording: 1'" in str(info.value)) is hint
    assert ("gyrofilter convert" in str(info.value)) is hint


@pytest.mark.parametrize("unit, extra, cell", [("rad/s", "", "1e308"), ("dps", "", "-100000.5"),
                                               ("lsb", "# lsb_per_dps: 0.1\n", "10000.1")])
def test_a_rate_no_gyro_reads_is_refused_naming_its_line(tmp_path, unit, extra, cell):
    """1e308 rad/s read as inf deg/s (an overflow warning, then inf in every analysis); the reader
    refuses any value beyond +-MAX_RATE_DPS once in deg/s, naming the line."""
    path = tmp_path / "r.csv"
    rows = "".join(f"0.001,0.002,{cell if i == 7 else '0.003'}\n" for i in range(20))
    path.write_text(f"# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: {unit}\n{extra}gx,gy,gz\n{rows}")
    line = 5 + bool(extra) + 7
    with pytest.raises(RecordingError, match=rf"line {line}: column 'gz' is .* {re.escape(unit)}, beyond the \+-100000 deg/s"):
        read_recording(path)


@pytest.mark.parametrize("unit, meant", [("deg/s", " \\(write 'deg/s' as dps\\)$"), ("degrees", "$")])
def test_a_gyro_unit_of_another_spelling_is_refused_naming_the_one_meant(tmp_path, unit, meant):
    """A new user's trial: `convert --unit deg/s` is taken, a header's `gyro_unit: deg/s` was refused
    listing the units without saying which one it means."""
    path = tmp_path / "unit.csv"
    path.write_text(f"# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: {unit}\nt,gx,gy,gz\n0,1,2,3\n",
                    encoding="utf-8")
    with pytest.raises(RecordingError, match=f"gyro_unit '{unit}' is not one of dps, rad/s, lsb" + meant):
        read_recording(path)


def test_a_users_own_csv_is_told_what_a_recording_needs_in_one_go(tmp_path):
    """A spreadsheet export (time,gx,gy,gz, no header) was told one missing key per try, and once
    the keys were there its 'time' column was carried along unused: uniform samples at the header's
    rate, wrong times and taus without a word."""
    path = tmp_path / "sheet.csv"
    path.write_text("time,gx,gy,gz\n0.00,1,2,3\n0.02,1,2,3\n")
    with pytest.raises(RecordingError, match=r"missing header key\(s\) 'gyrofilter-recording', 'sample_rate_hz', "
                                             r"'gyro_unit'; a recording starts with '# gyrofilter-recording: 1'"):
        read_recording(path)
    header = "# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\n"
    for names, message in (("time,gx,gy,gz", r"column 'time' looks like time stamps, .* named 't'"),
                           ("gx,gy,gz,Timestamp", r"column 'Timestamp' looks like time stamps"),
                           ("T,gx,gy,gz", r"column 'T' looks like time stamps"),
                           ("t,GX,GY,GZ", r"missing column\(s\) gx, gy, gz .*; names are lower case"),
                           ("t;gx;gy;gz", r"missing column\(s\) gx, gy, gz .*; columns are separated by commas"),
                           # a new user's trial: their own names under a right header got no pointer to convert
                           ("time_ms,GyroX,GyroY,GyroZ", r"missing column\(s\) gx, gy, gz \(have .*\); another tool's "
                                                         r"log: gyrofilter convert"),
                           # a new user's trial: a temp_c column was carried along unread, no word
                           ("t,gx,gy,gz,temp_c", r"column 'temp_c' looks like a temperature, .* named 'temp' \(deg C\)"),
                           ("t,gx,gy,gz,Temperature", r"column 'Temperature' looks like a temperature"),
                           ("t,gx,gy,gz,TEMP", r"column 'TEMP' looks like a temperature")):
        path.write_text(header + names + "\n" + "0.00,1,2,3\n")
        with pytest.raises(RecordingError, match=message):
            read_recording(path)
    path.write_text(header + "t,gx,gy,gz,ref_time_offset\n0.00,1,2,3,4\n")  # a name that merely contains 'time' is kept
    assert read_recording(path).columns["ref_time_offset"].tolist() == [4.0]
    path.write_text(header + "t,gx,gy,gz,temp,board_temp_c\n0.00,1,2,3,25,30\n")  # and one that merely contains 'temp'
    assert read_recording(path).temp_c.tolist() == [25.0] and read_recording(path).columns["board_temp_c"].tolist() == [30.0]


@pytest.mark.parametrize("names, refused", [
    ("time_ms,gx,gy,gz", "time_ms"), ("gx,gy,gz,timestamp_ms", "timestamp_ms"), ("t_ms,gx,gy,gz", "t_ms"),
    ("t_us,gx,gy,gz", "t_us"), ("TimeStamp_ns,gx,gy,gz", "TimeStamp_ns"), ("Time(s),gx,gy,gz", "Time(s)"),
    ("t_sec,gx,gy,gz", "t_sec"), ("ts,gx,gy,gz", "ts"), ("elapsed_s,gx,gy,gz", "elapsed_s"),
    ("t,gx,gy,gz,Temperature(C)", "Temperature(C)"), ("t,gx,gy,gz,die_temperature", "die_temperature"),
    ("t,gx,gy,gz,imu_temp", "imu_temp"), ("t,gx,gy,gz,TempF", "TempF"), ("t,gx,gy,gz,temp_raw", "temp_raw"),
    ("t,gx,gy,gz,temperature_k", "temperature_k"), ("t(s),gx,gy,gz", "t(s)"), ("t[s],gx,gy,gz", "t[s]"),
    ("gx,gy,gz,zeit", "zeit"), ("tstamp,gx,gy,gz", "tstamp"), ("uptime,gx,gy,gz", "uptime"), ("dt,gx,gy,gz", "dt"),
    ("t,gx,gy,gz,degC", "degC"), ("t,gx,gy,gz,°C", "°C"), ("t,gx,gy,gz,t_c", "t_c"), ("t,gx,gy,gz,T_imu", "T_imu"),
    ("t,gx,gy,gz,temperatura", "temperatura"), ("t,gx,gy,gz,thermistor", "thermistor")])
def test_a_column_with_a_word_of_time_stamps_or_a_temperature_is_refused_where_none_is_read(tmp_path, names, refused):
    """Attack pass 52: ``time_ms`` (and ``t_us``, ``elapsed_s``, ...) was carried along as an extra column, the
    samples taken as uniform at the header's rate: 5 s of lost samples vanished, every later one shifted; ``imu_temp``
    or ``TempF`` were carried along unread. A column with a word of time stamps where none is ``t`` (of a
    temperature where none is ``temp``) is refused; beside ``t`` (``temp``) it is an extra column."""
    path = tmp_path / "own.csv"
    header = "# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\n"
    path.write_text(header + names + "\n" + ",".join("1" for _ in names.split(",")) + "\n")
    with pytest.raises(RecordingError, match=r"line 4: column " + re.escape(repr(refused)) + " looks like"):
        read_recording(path)
    beside = ("t,gx,gy,gz,temp," if names.startswith("t,") else "t,gx,gy,gz,") + refused
    path.write_text(header + beside + "\n" + ",".join("1" for _ in beside.split(",")) + "\n")
    assert read_recording(path).columns[refused].tolist() == [1.0]
    path.write_text(header + "t,gx,gy,gz,k,c,f,K,deg\n0,1,2,3,4,5,6,7,8\n")  # pass 54: a letter alone is no unit
    assert read_recording(path).columns["K"].tolist() == [7.0]


@pytest.mark.parametrize("line", ["gyro_sensitivity: 1e400", "gyro_sensitivity: 1e309 dps/LSB",
                                  "gyro_sensitivity: 4.9e-324 mdps/LSB", "acc_lsb_per_g: 1e309", "accel sensitivity: 1e400"])
def test_a_sensitivity_beyond_a_float_is_refused_not_a_traceback(tmp_path, line):
    """Attack pass 62: ``gyro_sensitivity: 1e400`` in an lsb recording's header ended replay in an OverflowError
    (the rounding of the printed number, 10 ** 400), ``4.9e-324 mdps/LSB`` in a ZeroDivisionError: refused as another
    sensitivity, naming the key."""
    path = tmp_path / "rec.csv"
    head = "# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: lsb\n# lsb_per_dps: 131\n# accel_unit: lsb\n# lsb_per_g: 16384\n"
    path.write_text(head + f"# {line}\nt,gx,gy,gz,ax,ay,az\n0,1,2,3,0,0,1\n")
    with pytest.raises(RecordingError, match=re.escape(f"header key '{line.split(':')[0]}' says ")):
        read_recording(path)


@pytest.mark.parametrize("line", ["unit: rad/s", "sample_rate: 200", "rate_hz: 200", "rate: 200", "gyro: rad/s",
                                  "odr_hz: 200", "rate_khz: 0.2", "units: deg/s", "rate: 200 Hz", "sample_rate: 0.2kHz",
                                  "rate: 0xC8", "rate: ２００", "rate: 200,0", "odr: fast", "dt: 0.005",
                                  "sampling_period_ms: 5", "Ts: 0.005 s", "samplerate: 200", "hz: 200", "imu_rate: 200",
                                  "gyro_scale: rad/s", "omega_unit: rad/s", "lsb_per_deg: 65.5",
                                  "gyro_sensitivity: 65.5 LSB/(deg/s)", "scale_factor: 65.5", "acc_unit: m/s^2",
                                  "gyr_scale: rad/s", "gyr\u043e_units: rad/s",  # two slips: a Cyrillic o, an s
                                  "logging_rate: 200", "sample_rate_hz_nominal: 200", "sensor_odr: 200 Hz",  # pass 55
                                  "\uff52\uff41\uff54\uff45: 200", "Sample Rate (samples/s): 200",
                                  "sample_period: 5000 \u00b5s", "rotation_rate_unit: rad/s"])
def test_a_header_key_that_states_another_rate_or_unit_is_refused(tmp_path, line):
    """Attack pass 52: ``# unit: rad/s`` beside ``gyro_unit: dps`` (``# rate: 200`` beside ``sample_rate_hz: 100``)
    was kept as an unrelated key and the file read in the other without a word; pass 53: with its unit (``200 Hz``),
    as a period (``dt``), a sensitivity (``lsb_per_deg`` beside ``lsb_per_dps``), the accelerometer's unit. Refused,
    naming both, and so is a value that does not read (``0xC8``); the same rate, period or unit, and keys of the
    chip's own rates or a filter's, are kept."""
    path = tmp_path / "rec.csv"
    unit = "lsb\n# lsb_per_dps: 131" if "65.5" in line else "rad/s" if "deg/s" in line else "dps"
    head = f"# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: {unit}\n# accel_unit: g\n"
    path.write_text(head + f"# {line}\nt,gx,gy,gz,ax,ay,az\n0,1,2,3,0,0,1\n")
    key = line.split(":")[0]
    with pytest.raises(RecordingError, match=re.escape(f"header key '{key}' says ") + ".* gyrofilter reads it only from"):
        read_recording(path)
    kept = ["unit: dps", "rate: 100", "rate_khz: 0.1", "data_rate: 100 Hz", "dt: 0.01", "sample_period_ms: 10",
            "gyro_output_rate_hz: 8000", "dlpf_bandwidth_hz: 44", "baud_rate: 115200", "rate2_hz: 200", "rate_dps: 90",
            "gyro: MPU6050", "gyro_sensitivity: 65.5", "acc_unit: g", "time: 2024-01-01", "odr: 100 sps",
            "ts: 2026-01-01T00:00:00", "step: 1",  # pass 54: no false refusals
            "units: s, dps, counts", "TS: 1700000000", "Unit: Unit-7", "gyro_range: \u00b1250 dps"]  # pass 55, 62
    path.write_text(head.replace(unit, "dps") + "".join(f"# {k}\n" for k in kept) + "t,gx,gy,gz,ax,ay,az\n0,1,2,3,0,0,1\n")
    assert read_recording(path).header["gyro_output_rate_hz"] == "8000"
    path.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: lsb\n# lsb_per_dps: 131\n"
                    "# gyro_scale: 131\n# scale: \u00b1250 dps\ngx,gy,gz\n1,2,3\n")  # the same sensitivity, a number:
    # no unit (pass 54); a full scale, no sensitivity (pass 55)
    assert read_recording(path).header["gyro_scale"] == "131"


@pytest.mark.parametrize("names, shown", [
    ("\ufefft,gx,gy,gz", r"'\\ufefft' holds the invisible character U\+FEFF \(ZERO WIDTH NO-BREAK SPACE"),
    ("t\u200b,gx,gy,gz", r"'t\\u200b' holds the invisible character U\+200B \(ZERO WIDTH SPACE"),
    ("t,gx,gy,gz,\u2066temp", r"'\\u2066temp' holds the invisible character U\+2066 \(LEFT-TO-RIGHT ISOLATE"),
    ("t,gx,gy,gz,temp\u3164", r"'temp\u3164' holds the invisible character U\+3164 \(HANGUL FILLER"),
    ("t,gx,gy,gz,te\xa0mp", r"'te\\xa0mp' holds the invisible character U\+00A0 \(NO-BREAK SPACE"),
])
def test_a_column_name_with_an_invisible_character_is_refused(tmp_path, names, shown):
    """Attack pass 20: a header written by hand with an Excel "CSV UTF-8" export appended (its
    byte-order mark now before the column row) read '\\ufefft' as an extra column: its times
    ignored without a word (the samples taken as uniform, gaps and all), as a 'time' column was."""
    path = tmp_path / "joined.csv"
    path.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\n" + names + "\n"
                    + "".join(f"{i / 100 + (1.0 if i > 4 else 0.0):.2f},1,2,3,25\n" for i in range(10)).replace(
                        ",25\n", ",25\n" if names.count(",") == 4 else "\n"), encoding="utf-8")
    with pytest.raises(RecordingError, match=r"joined.csv: line 4: column " + shown):
        read_recording(path)


@pytest.mark.parametrize("lines, shown", [
    ("# lsb_per_dps\u200b: 131\n# lsb_per_dps: 65.5\n", r"'lsb_per_dps\\u200b' holds the invisible character U\+200B"),
    ("# sample_rate_hz\ufeff: 50\n# lsb_per_dps: 131\n", r"'sample_rate_hz\\ufeff' holds the invisible character U\+FEFF"),
    ("# lsb_per_dps\u2800: 131\n# lsb_per_dps: 65.5\n", r"'lsb_per_dps\u2800' holds the invisible character U\+2800"),
])
def test_a_header_key_with_an_invisible_character_is_refused(tmp_path, lines, shown):
    """Attack pass 21 (pass 20's column rule, for the keys): 'lsb_per_dps\\u200b: 131' before
    'lsb_per_dps: 65.5' shows as a repeated key, which is refused; it was read as another key,
    kept, and the rates taken at 65.5 LSB per deg/s without a word. The writer refuses it too."""
    path = tmp_path / "keys.csv"
    path.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: lsb\n" + lines + "t,gx,gy,gz\n"
                    + "".join(f"{i / 100:.2f},1,2,3\n" for i in range(10)), encoding="utf-8")
    with pytest.raises(RecordingError, match=r"keys.csv: line [45]: header key " + shown):
        read_recording(path)
    key = lines[2:lines.index(":")]
    with pytest.raises(RecordingError, match=r"out.csv: header key " + shown):
        write_recording(tmp_path / "out.csv", Recording({c: np.zeros(2) for c in ("gx", "gy", "gz")},
                                                        {"sample_rate_hz": "100", "gyro_unit": "dps", key: "1"}))
    assert not (tmp_path / "out.csv").exists()


def test_compact_reading_keeps_the_numbers_and_the_columns_asked_for(tmp_path):
    """``read_recording(..., columns=, compact=True)``: an lsb column of integers is float32, a
    column that turns out not to be exact after two chunks is float64 from its start, and every
    value reads as in the file; the other columns are dropped."""
    n = 150_000  # more than two chunks of the reader and several blocks of collect_columns
    rng = np.random.default_rng(4)
    gx = np.round(rng.normal(0, 2000, n))
    gy = np.round(rng.normal(0, 2000, n))
    gy[-3] = 0.1  # not a float32: the whole column is float64
    rec = Recording(columns={"t": np.arange(n) / 100.0, "gx": gx, "gy": gy, "gz": -gx},
                    header={"gyrofilter-recording": "1", "sample_rate_hz": "100", "gyro_unit": "lsb", "lsb_per_dps": "131"})
    path = tmp_path / "r.csv.gz"
    write_recording(path, rec)
    back = read_recording(path, columns=lambda names: [c for c in names if c != "t"], compact=True)
    assert list(back.columns) == ["gx", "gy", "gz"]
    assert [back.columns[c].dtype for c in ("gx", "gy", "gz")] == [np.float32, np.float64, np.float32]
    for c in ("gx", "gy", "gz"):
        assert np.array_equal(np.asarray(back.columns[c], dtype=float), rec.columns[c])
    assert np.array_equal(back.gyro_dps, read_recording(path).gyro_dps)


#: names a Markdown viewer read as markup, or whose escapes read the same as another name's
MARKDOWN_NAMES = ["*a*b.csv", "_a_.csv", "x [click](http://e.example).csv", "![i](http://e.example/t.png)",
                  "t ~~s~~", "end #", "a|b", "`c`", "a&amp;b", "<img src=x>", "unit\\", "a\\nb", "a\nb",
                  'q"x', "\x85\u2028", "\udcff", " lead", "trail ", "a\\|b", "a\\*b", "a\\_b", "x_.y",
                  "mpu6050_static_100s", "é_ü", "&#65;", "\\u0041"]


def commonmark_text(shown):
    """What a CommonMark viewer shows of inline text that holds no markup but escapes and
    entities (CommonMark 0.31, sections 2.4 and 2.5): each backslash before ASCII punctuation
    dropped (one before anything else is shown), each entity decoded. None when markup is left
    (an unescaped markup character)."""
    import html

    plain = re.sub(r"\\[!-/:-@\[-`{-~]", "", shown)
    if re.search(r"[|`*\[\]~!#<>]", plain) or re.search(r"(?<![^\W_])_|_(?![^\W_])", plain):
        return None
    return html.unescape(re.sub(r"\\([!-/:-@\[-`{-~])", r"\1", shown))


@pytest.mark.parametrize("name", MARKDOWN_NAMES)
def test_a_name_in_markdown_is_shown_literally_and_reads_back_exactly(name):
    """Issue 37 (leftover): a file named ``*a*b.csv`` was shown as a<em>a</em>b, ``![i](URL)`` as an
    image fetched from URL, ``a<newline>b`` and ``a\\nb`` the same. What a Markdown page shows
    of a name is its JSON string's body, escaped so that it holds no markup: it reads back exactly."""
    from gyrofilter.recording.header import markdown_text

    shown = commonmark_text(markdown_text(name))
    assert shown is not None and json.loads(f'"{shown}"') == name


@given(st.text(st.characters(blacklist_categories=()), max_size=40))
def test_every_text_in_markdown_reads_back_by_the_commonmark_escape_rules(name):
    from gyrofilter.recording.header import markdown_text

    shown = commonmark_text(markdown_text(name))
    assert shown is not None and json.loads(f'"{shown}"') == name


def test_a_plain_name_is_shown_in_markdown_as_it_is():
    from gyrofilter.recording.header import markdown_text

    for name in ("logs/unit 7.csv.gz", "mpu6050_static_100s", "recordings/mpu6050_static_64s_set1.csv.gz", "é_ü"):
        assert markdown_text(name) == name


@pytest.mark.parametrize("name", MARKDOWN_NAMES)
def test_a_name_in_a_markdown_table_cell_and_heading_renders_as_itself(name):
    """The same through a CommonMark parser with tables and strikethrough (GitHub's)."""
    import html

    markdown_it = pytest.importorskip("markdown_it")
    from gyrofilter.recording.header import markdown_text

    md = markdown_it.MarkdownIt("commonmark").enable("table").enable("strikethrough")
    shown = markdown_text(name)
    cell = re.search(r"<td>(.*?)</td>", md.render(f"| h |\n|---|\n| {shown} |\n"), re.S).group(1)
    heading = re.search(r"<h1>report: (.*?)</h1>", md.render(f"# report: {shown}\n"), re.S).group(1)
    for rendered in (cell, heading):
        assert "<" not in rendered and json.loads(f'"{html.unescape(rendered)}"') == name


def test_annotations_beyond_the_cap_are_skipped_with_one_warning(tmp_path, monkeypatch):
    """Attack pass (issue 37): 15 million '#' lines (30 KB of gzip) were kept as notes, 4.9 GB of
    memory; the reader keeps the first MAX_NOTES and says so once, the samples all read."""
    from gyrofilter.recording import reader

    monkeypatch.setattr(reader, "MAX_NOTES", 10)
    lines = [f"{i / 100:.2f},0.{i % 7},0.2,0.3\n" for i in range(300)]
    notes = "".join(f"# note {k}\n" for k in range(25))
    path = tmp_path / "notes.csv.gz"
    with gzip.open(path, "wt") as fh:
        fh.write("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\nt,gx,gy,gz\n"
                 + "".join(lines[:100]) + notes + "".join(lines[100:]))
    rec = read_recording(path)
    assert len(rec) == 300 and [n.text for n in rec.notes] == [f"note {k}" for k in range(10)]
    first_skipped = 5 + 100 + 10
    assert rec.warnings == [f"{path}: line {first_skipped}: more than 10 annotation lines; the first are kept, "
                            "the others skipped"]


def test_a_fifo_nobody_writes_to_is_refused_and_one_written_later_is_read(tmp_path, monkeypatch):
    """Issue 37 (attack 6): a FIFO given as the recording (``mkfifo x.csv``) blocked ``replay``,
    ``gap``, ``allan`` and ``convert`` forever when nobody wrote to it: the open waited for a
    writer. Opened without blocking, it is refused after PIPE_WAIT_S with one line; a writer that
    comes within the wait is read as a pipe, once (its first bytes kept); a folder is refused."""
    import threading

    from gyrofilter import inputs
    from gyrofilter.recording.foreign import read_foreign
    monkeypatch.setattr(inputs, "PIPE_WAIT_S", 0.3)
    fifo = tmp_path / "x.csv"
    os.mkfifo(fifo)
    for read in (read_recording, read_foreign):
        with pytest.raises(RecordingError, match=re.escape(f"{fifo}: not a regular file (a pipe or FIFO) and nothing "
                                                           "was written to it in 0.3 s")):
            read(str(fifo))
    text = HEADER + "t,gx,gy,gz\n" + "".join(f"{i / 100:.2f},{i},-3,40\n" for i in range(50))
    monkeypatch.setattr(inputs, "PIPE_WAIT_S", 30.0)

    def write_late():
        with open(fifo, "w") as fh:
            fh.write(text)
    writer = threading.Timer(0.1, write_late)
    writer.start()
    rec = read_recording(str(fifo))
    writer.join()
    np.testing.assert_array_equal(rec.gyro[:, 0], np.arange(50))
    with pytest.raises(RecordingError, match=re.escape(f"{tmp_path}: cannot read: Is a directory")):
        read_recording(str(tmp_path))


@pytest.mark.parametrize("name", ["n.csv", "n.csv.gz"])
def test_nul_bytes_before_the_header_are_refused_naming_the_line(tmp_path, name):
    """Issue 37 (attack 6): a log starting with NUL bytes (an SD card after a power cut) was
    converted, the NULs becoming part of the time column's name (``--columns 1,2,3,4``); a
    recording so started was refused for missing header keys. Both name the line and the NULs;
    a NUL line later in the file too. A recording's last line cut short, NULs and all, is only
    warned about (its rows before it are kept)."""
    from gyrofilter.recording.foreign import read_foreign
    rows = "".join(f"{i / 100:.2f},{i},-3,40\n" for i in range(50))

    def put(text, file_name=name):
        path = tmp_path / file_name
        path.write_bytes(gzip.compress(text) if file_name.endswith(".gz") else text)
        return str(path)
    log = put(b"\0\0\0\0time_s,x_dps,y_dps,z_dps\n" + rows.encode())
    with pytest.raises(RecordingError, match=re.escape(f"{log}: line 1: NUL bytes")):
        read_foreign(log, columns=["1", "2", "3", "4"], unit="dps")
    log = put(b"# a comment\n\n\0\0\0\ntime_s,x_dps,y_dps,z_dps\n" + rows.encode(), "later_" + name)
    with pytest.raises(RecordingError, match=re.escape(f"{log}: line 3: NUL bytes")):
        read_foreign(log)
    recording = (HEADER + "t,gx,gy,gz\n" + rows).encode()
    path = put(b"\0" * 512 + recording, "rec_" + name)
    with pytest.raises(RecordingError, match=re.escape(f"{path}: line 1: NUL bytes")):
        read_recording(path)
    path = put(recording + b"\0" * 512, "tail_" + name)
    rec = read_recording(path)
    assert len(rec) == 50 and "last line has no line end" in rec.warnings[0]
    assert rec.warnings[0].endswith("... (512 characters)")  # its length, not the quote's (a new user read 60)


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-16-be"])
def test_utf16_text_is_refused_as_utf16_not_as_binary(tmp_path, encoding):
    """Attack pass 12: a recording or log saved as UTF-16 (Windows' "Unicode") was refused as "NUL
    bytes (binary data, ... SD card)" or "not UTF-8": the line says what it is and what to do; a
    power cut's NUL blocks are still called so."""
    from gyrofilter.recording.foreign import read_foreign
    rows = "".join(f"{i / 100:.2f},{i},-3,40\n" for i in range(50))
    path = tmp_path / "u.csv"
    path.write_bytes((HEADER + "t,gx,gy,gz\n" + rows).encode(encoding))
    with pytest.raises(RecordingError, match=re.escape(f"{path}: line 1: UTF-16 text") + ".*save it as UTF-8"):
        read_recording(str(path))
    log = tmp_path / "log.csv"
    log.write_bytes(("time_s,x_dps,y_dps,z_dps\n" + rows).encode(encoding))
    with pytest.raises(RecordingError, match=re.escape(f"{log}: line 1: UTF-16 text")):
        read_foreign(str(log))
    blocks = tmp_path / "b.csv"
    blocks.write_bytes(b"\0" * 512 + (HEADER + "t,gx,gy,gz\n" + rows).encode())
    with pytest.raises(RecordingError, match=re.escape(f"{blocks}: line 1: NUL bytes")):
        read_recording(str(blocks))


@pytest.mark.parametrize("chunk_rows", [1, 700, 1 << 16])
def test_a_header_naming_an_input_rate_gets_the_same_rate_check(tmp_path, chunk_rows):
    """Issue 37 (attack 6): a file of samples whose t runs at half the header's rate was
    refused, but read (its every step "a gap") once its header named an input_sample_rate_hz
    above the rate, even 100.001 at 100 Hz: a window of gaps only showed no rate in a filtered
    output. Now an input rate is a whole multiple of the rate (a row per block), and a window of
    gaps only whose steps are two row intervals or more (half the input samples lost, or t at
    half the rate) is refused there as in a file of samples; fewer lost samples still read."""
    half_rate = _t_body(np.full(2500, 0.02))
    for input_hz in ("100", "200", "1000"):
        with pytest.raises(RecordingError, match=re.escape("t steps by 0.02 s (median of its first 1000 steps")):
            _read_chunked(_dps_file(tmp_path, half_rate, f"# filtered_from: raw.csv\n# input_sample_rate_hz: {input_hz}\n", name=f"{input_hz}.csv"),
                          chunk_rows)
    for input_hz in ("100.001", "150"):
        with pytest.raises(RecordingError, match=re.escape(f"input_sample_rate_hz {input_hz} is not a whole multiple of "
                                                           "sample_rate_hz 100")):
            _read_chunked(_dps_file(tmp_path, half_rate, f"# filtered_from: raw.csv\n# input_sample_rate_hz: {input_hz}\n", name="odd.csv"), chunk_rows)
    lossy = _t_body(np.full(2500, 0.011))  # every block of 10 lost one input sample
    head, data = _read_chunked(_dps_file(tmp_path, lossy, "# filtered_from: raw.csv\n# input_sample_rate_hz: 1000\n", name="lossy.csv"), chunk_rows)
    assert len(data) == 2501 and head.t_gaps == 2500


@pytest.mark.parametrize("name", ["b.csv", "b.csv.gz"])
def test_a_recording_without_rows_is_refused_once_its_blank_lines_pass_the_bound(tmp_path, monkeypatch, name):
    """Issue 37 (attack 6): a recording whose header was followed by 300 MB of line ends (300 kB
    of gzip) took 31 s to say "no samples" (2 GiB: minutes), a Python step per line. Blank
    lines before the first row are counted and refused past MAX_BYTES_BEFORE_ROWS, as convert
    does; a chunk of empty lines is skipped at once; as many after a row are read, every row
    kept with its line number."""
    from gyrofilter.recording import header
    monkeypatch.setattr(header, "MAX_BYTES_BEFORE_ROWS", 1 << 20)
    head = HEADER + "t,gx,gy,gz\n"
    path = tmp_path / name
    body = (head + "\n" * (3 << 20)).encode()
    path.write_bytes(gzip.compress(body) if name.endswith(".gz") else body)
    with pytest.raises(RecordingError, match=re.escape(f"{path}: no data rows in the first 1 MB")):
        read_recording(path)
    body = (head + "0.00,1,2,3\n" + "\n" * (3 << 20) + "# a note\n0.01,4,5,6\n").encode()
    path.write_bytes(gzip.compress(body) if name.endswith(".gz") else body)
    rec = read_recording(path)
    np.testing.assert_array_equal(rec.gyro, [[1, 2, 3], [4, 5, 6]])
    assert rec.notes == [(7 + (3 << 20) + 1, "a note")]


def test_a_recording_that_does_not_fit_in_memory_is_one_error_naming_it(tmp_path, monkeypatch, capsys):
    """A gzip bomb of valid rows (3 MB holding 367 million rows of ``0,0,0``) ran out of memory
    while the reader gathered its columns: a MemoryError traceback, exit 1 (attack pass 10). The
    block allocation fails here after a few blocks, as it does when memory runs out."""
    from gyrofilter.cli import main
    from gyrofilter.recording import reader

    path = str(tmp_path / "bomb.csv.gz")
    write_recording(path, Recording.from_dps(np.zeros((200_000, 3)), 100.0))
    calls = []

    class _Numpy:  # numpy as the reader sees it, out of memory at the third block
        def __getattr__(self, name):
            return getattr(np, name)

        def empty(self, *args, **kwargs):
            calls.append(args)
            if len(calls) > 6:
                raise MemoryError("Unable to allocate 4.00 MiB")
            return np.empty(*args, **kwargs)

    monkeypatch.setattr(reader, "np", _Numpy())
    with pytest.raises(RecordingError, match=r"bomb\.csv\.gz: does not fit in memory: out of memory after \d+ rows"):
        read_recording(path)
    for command in (["allan", path], ["arma", path]):
        calls.clear()
        assert main(command) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("gyrofilter: error: ") and "memory" in err[0], err


@pytest.mark.parametrize("chunk_rows", [1, 999, 1 << 16])
@pytest.mark.parametrize("inserted", [0.2, 0.45])
def test_rows_the_rate_has_no_room_for_are_refused_even_when_the_typical_step_is_right(tmp_path, chunk_rows, inserted):
    """A copy of a row (new values) stamped 1 ulp after it, after 45 % of the rows: the typical step
    stayed 0.01 s, so 8600 rows over 60 s of t read as 86 s at 100 Hz without a word (every Allan
    tau 43 % off; attack pass 10). A window's steps must span its sample intervals, less 5 %."""
    rng = np.random.default_rng(3)
    t = np.arange(6000) / 100.0
    extra = np.sort(rng.choice(6000, int(inserted * 6000), replace=False))
    t = np.sort(np.concatenate([t, np.nextafter(t[extra], np.inf)]))
    body = "".join(f"{v!r},{g},0,0\n" for v, g in zip(t.tolist(), rng.normal(size=len(t)).tolist()))
    with pytest.raises(RecordingError, match=r"t's 1000 steps from line \d+ span [\d.]+ s, but 1000 sample intervals "
                                             r"at sample_rate_hz 100 take 10 s: more rows than the rate has room for"):
        _read_chunked(_dps_file(tmp_path, body), chunk_rows)


def _masked_at_10(shape):
    values = np.ma.masked_array(np.ones(shape), mask=np.zeros(shape, bool))
    values.mask[10] = True
    values.data[10] = 1e4
    return values


@pytest.mark.parametrize("argument", ["gyro_dps", "t_s", "temp_c", "accel", "extra"])
def test_from_dps_refuses_a_masked_value(argument):
    """Attack pass 22: Recording.from_dps took a masked value's hidden number as data (the mask
    dropped: every analysis of the recording used it), as the Allan functions and the filter
    refuse it (inputs.number_array)."""
    n = 100
    args = {"gyro_dps": np.zeros((n, 3)), "t_s": np.arange(n) / 100.0, "temp_c": np.full(n, 25.0),
            "accel": np.ones((n, 3)), "extra": {"ref_x": np.zeros(n)}}
    args[argument] = ({"ref_x": _masked_at_10(n)} if argument == "extra" else
                      _masked_at_10(args[argument].shape))
    gyro = args.pop("gyro_dps")
    with pytest.raises(RecordingError, match="row 10 is masked"):
        Recording.from_dps(gyro, 100.0, accel_unit="g", **args)


@pytest.mark.parametrize("values", [np.zeros((5, 3)) + 1j, np.zeros((5, 3), bool), [["1", "2", "3"]] * 5])
def test_from_dps_refuses_what_is_not_numbers(values):
    """Attack pass 22: complex rates lost their imaginary part, booleans and strings were read as numbers."""
    with pytest.raises(RecordingError, match="gyro_dps must be numbers"):
        Recording.from_dps(values, 100.0)


@pytest.mark.parametrize("name, kwargs", [("gx", {}), ("temp", {"temp_c": np.full(5, 25.0)}),
                                          ("t", {"t_s": np.arange(5) / 100.0})])
def test_from_dps_refuses_an_extra_column_named_as_one_of_its_own(name, kwargs):
    """Attack pass 25: ``extra={"gx": ...}`` replaced the x rates given in ``gyro_dps`` (and an
    extra ``temp`` or ``t`` the ``temp_c`` or ``t_s`` given) without a word: the recording held
    the extra column's values as the rates."""
    with pytest.raises(RecordingError, match=f"extra column '{name}' is a column from_dps makes"):
        Recording.from_dps(np.zeros((5, 3)), 100.0, extra={name: np.ones(5)}, **kwargs)


def test_a_recording_built_in_code_refuses_a_masked_column():
    """Attack pass 23: pass 22's rule of from_dps for the Recording built from its columns
    (a public class): a masked 1e4 in gx was its gyro_dps (the mask dropped by column_stack) and
    write_recording wrote it to the file as a sample."""
    with pytest.raises(RecordingError, match="column 'gx' row 10 is masked"):
        Recording(columns={"gx": _masked_at_10(100), "gy": np.zeros(100), "gz": np.zeros(100)},
                  header={"sample_rate_hz": "100", "gyro_unit": "dps"})


@pytest.mark.parametrize("values", [np.zeros(5) + 1j, np.zeros(5, bool), ["1"] * 5])
def test_a_recording_built_in_code_refuses_what_is_not_numbers(values):
    """Attack pass 23: a complex column was written without its imaginary part (one ComplexWarning)."""
    with pytest.raises(RecordingError, match="column 'gy' must be numbers"):
        Recording(columns={"gx": np.zeros(5), "gy": values, "gz": np.zeros(5)},
                  header={"sample_rate_hz": "100", "gyro_unit": "dps"})


def test_a_recording_built_in_code_refuses_columns_of_other_lengths():
    """Attack pass 23: write_recording ended in numpy's ValueError (column_stack) naming no column."""
    with pytest.raises(RecordingError, match="column 'gz' has 4 values, column 'gx' has 5"):
        Recording(columns={"gx": np.zeros(5), "gy": np.zeros(5), "gz": np.zeros(4)},
                  header={"sample_rate_hz": "100", "gyro_unit": "dps"})


@pytest.mark.parametrize("header, expected", [
    ({"gyro_unit": "dps"}, "recording: header key(s) 'sample_rate_hz' missing: a recording's header states"),
    ({"sample_rate_hz": "100"}, "recording: header key(s) 'gyro_unit' missing"),
    ({"sample_rate_hz": "0", "gyro_unit": "dps"}, "recording: sample_rate_hz must be a number of Hz in"),
    ({"sample_rate_hz": "fast", "gyro_unit": "dps"}, "recording: sample_rate_hz must be a plain decimal number"),
    ({"sample_rate_hz": "100", "gyro_unit": "deg/s"}, "recording: gyro_unit 'deg/s' is not one of dps, rad/s, lsb (write"),
    ({"sample_rate_hz": "100", "gyro_unit": "lsb"}, "recording: gyro_unit is lsb but header key 'lsb_per_dps' is missing"),
])
def test_a_recording_built_in_code_refuses_a_header_without_its_rate_and_units(header, expected):
    """Attack pass 24's note: a Recording built without gyro_unit or sample_rate_hz was taken and
    failed later, in an analysis, with a KeyError naming a key; its header is checked as a file's
    is (the version aside), naming what is missing or wrong."""
    with pytest.raises(RecordingError) as error:
        Recording(columns={c: np.zeros(5) for c in ("gx", "gy", "gz")}, header=header)
    assert str(error.value).startswith(expected)


def test_a_recording_without_a_gyro_column_has_a_length_and_says_what_it_lacks(tmp_path):
    """Attack pass 24's note: `read_recording(path, columns=...)` keeping only temp gave a Recording
    whose len() and gyro_dps were KeyErrors; its length is its columns' and gyro_dps names the columns."""
    path = tmp_path / "r.csv"
    write_recording(path, Recording.from_dps(np.zeros((7, 3)), 100.0, temp_c=np.full(7, 25.0)))
    rec = read_recording(path, columns=lambda names: ["temp"])
    assert len(rec) == 7 and rec.temp_c.tolist() == [25.0] * 7
    with pytest.raises(RecordingError, match=f"^{re.escape(str(path))}: no gyro column\\(s\\) gx, gy, gz$"):
        rec.gyro_dps


@pytest.mark.parametrize("column, refusal", [(_masked_at_10(100), "column 'gx' row 10 is masked"),
                                               (np.zeros(40), "column 'gx' has 40 values, column 't' has 100"),
                                               (np.array(["1"] * 100), "column 'gx' must be numbers")])
def test_a_recording_whose_column_is_replaced_later_is_checked_when_written_or_read(tmp_path, column, refusal):
    """Attack pass 25: the check of a Recording's columns ran when it was built only: a column
    replaced afterwards (``rec.columns["gx"] = ...``, a mutable dict) by a masked array had its
    hidden 1e4 written to the file as a sample by write_recording and taken by gyro_dps, exit 0;
    a shorter or a text column ended in numpy's ValueError or TypeError. Checked where used."""
    rec = Recording.from_dps(np.zeros((100, 3)), 100.0, t_s=np.arange(100) / 100.0)
    rec.columns["gx"] = column
    path = tmp_path / "rec.csv"
    with pytest.raises(RecordingError, match=re.escape(refusal)):
        write_recording(path, rec)
    assert not path.exists()
    for used in ("gyro_dps", "t_s", "temp_c"):
        with pytest.raises(RecordingError, match=re.escape(refusal)):
            getattr(rec, used)


@pytest.mark.parametrize("rows", [np.ma.masked_array(np.zeros((20, 3)), mask=np.eye(20, 3, k=-10, dtype=bool)),
                                  np.zeros((20, 3)) + 1j])
def test_recording_writer_refuses_masked_or_complex_rows(tmp_path, rows):
    """Attack pass 23: RecordingWriter.write wrote a masked value's hidden number and the real part
    of complex rows as samples."""
    if np.ma.isMaskedArray(rows):
        rows.data[10, 0] = 5e4
    path = tmp_path / "rec.csv"
    with RecordingWriter(path, {"sample_rate_hz": "100", "gyro_unit": "dps"}, ["gx", "gy", "gz"]) as writer:
        with pytest.raises(RecordingError, match="rows to write: (row 11 is masked; a masked value is no measurement|must be numbers)"):
            writer.write(rows)
    assert read_recording(path).gyro_dps.shape == (0, 3)


@pytest.mark.parametrize("keep", [["gx", "gx"], ["gx", "nope"], "gx"])
def test_read_recording_refuses_columns_to_keep_that_are_not_the_files(tmp_path, keep):
    """Attack pass 23: a column given twice ended in a KeyError, a name the file does not have
    (or a string, taken letter by letter) in list.index's "'nope' is not in list"."""
    path = _dps_file(tmp_path, "".join(f"{k * 0.01!r},1,2,3\n" for k in range(20)))
    with pytest.raises(SettingsError, match=r"r.csv: the columns to keep must be distinct columns of the file \(t, gx, gy, gz\), got"):
        read_recording(path, columns=lambda names: keep)


@pytest.mark.parametrize("cell, formats", [(True, ["%s"] * 3), ("1_000", ["%s"] * 3), ("\uff11\uff12", ["%s"] * 3),
                                           (b"1", ["%s"] * 3), ("12", None)])
def test_recording_writer_writes_text_cells_only_as_the_reader_reads_them(tmp_path, cell, formats):
    """Attack pass 24: an object array's cells were checked by float(), which takes True, '1_000',
    full-width digits and b'1': written as they are ('True', '1_000', ...), a file that does not
    read; a text cell in an integral column without a format ended in a TypeError of '%d'."""
    path = tmp_path / "rec.csv"
    rows = np.array([[cell, 1, 2]] * 3, dtype=object)
    with RecordingWriter(path, {"sample_rate_hz": "100", "gyro_unit": "dps"}, ["gx", "gy", "gz"], formats=formats) as writer:
        if cell == "12":
            writer.write(rows)
        else:
            with pytest.raises(RecordingError, match=r"rec.csv: the rows to write: row 1, column 'gx' holds .*, "
                                                     r"not a number as a recording writes it \(none of them written\)"):
                writer.write(rows)
    assert read_recording(path).columns["gx"].tolist() == ([12.0] * 3 if cell == "12" else [])


def test_write_recording_puts_each_note_back_before_its_sample(tmp_path):
    """Attack pass 24's note: write_recording wrote every note after the data, so a recording read
    and written again (hide_in_recording's, a tool's copy) moved "# moved the board" to the end."""
    src, copy = tmp_path / "src.csv", tmp_path / "copy.csv"
    with RecordingWriter(src, {"gyrofilter-recording": "1", "sample_rate_hz": "100", "gyro_unit": "dps"},
                         ["gx", "gy", "gz"]) as writer:
        writer.note("first")
        writer.write(np.zeros((3, 3)))
        writer.note("moved the board")
        writer.note("and again")
        writer.write(np.ones((2, 3)))
        writer.note("last")
    rec = read_recording(src)
    write_recording(copy, rec)
    again = read_recording(copy)
    assert [(n.text, n.row) for n in again.notes] == [("first", 0), ("moved the board", 3), ("and again", 3), ("last", 5)]
    assert copy.read_text() == src.read_text()


def test_notes_built_in_code_at_any_row_leave_every_sample_written_once(tmp_path):
    """The lead's attack on the notes put back at their rows: a note built in code at row -5 or
    beyond the data (or a plain pair) is written at the nearest end, never slicing a sample twice."""
    from gyrofilter.recording import Note

    rec = Recording.from_dps(np.arange(30.0).reshape(10, 3), 100.0)
    rec.notes = [Note(1, "before", -5), Note(2, "at three", 3), ("line", "plain"), Note(3, "far", 99)]
    write_recording(tmp_path / "n.csv", rec)
    back = read_recording(tmp_path / "n.csv")
    assert np.array_equal(back.gyro, rec.gyro)
    assert [(n.text, n.row) for n in back.notes] == [("before", 0), ("at three", 3), ("plain", 10), ("far", 10)]


@pytest.mark.parametrize("fmt", ["%d", "%.3f", "%g"])
def test_recording_writer_refuses_a_text_cell_its_columns_format_takes_no_text_for(tmp_path, fmt):
    """Attack pass 25: a text cell of an object array in a column given a number's format ended in
    Python's TypeError ("%d format: a real number is required, not str") and an unclosed file."""
    path = tmp_path / "rec.csv"
    rows = np.array([["1", "2", 3]] * 3, dtype=object)
    with RecordingWriter(path, {"sample_rate_hz": "100", "gyro_unit": "dps"}, ["gx", "gy", "gz"],
                         formats=[fmt, None, fmt]) as writer:
        with pytest.raises(RecordingError, match=f"rec.csv: the rows to write: row 1, column 'gx' holds the text '1', "
                                                 f"which its format {re.escape(repr(fmt))} takes no text for"):
            writer.write(rows)
        writer.write(np.array([[1, "2", 3.5]], dtype=object))
    assert read_recording(path).gyro_dps.shape == (1, 3)


def test_an_empty_array_of_the_wrong_width_is_refused_as_a_full_one_is(tmp_path):
    """Attack pass 26: write(np.empty((0, 5))) to a writer of 4 columns was taken without a word."""
    from gyrofilter.recording.writer import RecordingWriter
    header = {"gyrofilter-recording": 1, "gyro_unit": "dps", "sample_rate_hz": 100}
    with RecordingWriter(tmp_path / "r.csv", header, ["t", "gx", "gy", "gz"]) as writer:
        writer.write(np.empty((0, 4)))  # nothing, of the right width
        for rows, shape in ((np.empty((0, 5)), r"\(0, 5\)"), (np.empty((0,)), r"\(0,\)"), ([], r"\(0,\)")):
            with pytest.raises(RecordingError, match=rf"rows must have shape \(n, 4\), got {shape}"):
                writer.write(rows)
        writer.write(np.array([[0.0, 1, 2, 3]]))
    assert len(read_recording(tmp_path / "r.csv")) == 1


@pytest.mark.parametrize("key, value, said", [("sample_rate_hz", "0", "sample_rate_hz"), ("sample_rate_hz", "nan", "sample_rate_hz"),
                                              ("sample_rate_hz", "-100", "sample_rate_hz"), ("sample_rate_hz", "abc", "sample_rate_hz"),
                                              ("gyro_unit", "deg/s", "gyro_unit"), ("sample_rate_hz", None, "missing")])
def test_a_header_changed_after_the_recording_was_built_is_checked_where_read(key, value, said):
    """Attack pass 26: the header is a mutable dict; a rate changed to 0, nan or -100 after the
    Recording was built gave a ZeroDivisionError, nan or a negative duration (header.check_facts
    ran in __post_init__ only)."""
    rec = Recording.from_dps(np.zeros((100, 3)), 100.0)
    if value is None:
        del rec.header[key]
    else:
        rec.header[key] = value
    for read in (lambda: rec.sample_rate_hz, lambda: rec.duration_s, lambda: rec.t_s, lambda: rec.gyro_dps,
                 lambda: rec.input_sample_rate_hz):
        with pytest.raises(RecordingError, match=f"recording: .*{said}"):
            read()


@pytest.mark.parametrize("note", ["just text", ("only",), (1, 5), (1, "x", 3), (1, b"bytes")])
def test_a_note_that_is_no_line_and_text_pair_is_refused(tmp_path, note):
    """Attack pass 26: write_recording took a note's text as note[1]: a string note 'just text'
    was written as '# u', (1, 5) as '# 5', (1, 'x', 3) after the data, ('only',) an IndexError."""
    rec = Recording.from_dps(np.zeros((5, 3)), 100.0)
    rec.notes = [Note(1, "kept", row=2), note]
    with pytest.raises(RecordingError, match=r"r.csv: note 2 of the recording, .* is not a \(line, text\) pair"):
        write_recording(tmp_path / "r.csv", rec)
    assert not (tmp_path / "r.csv").exists()


def test_read_recording_takes_the_columns_as_names_too(tmp_path):
    """Attack pass 26: read_recording(columns=["t", "gx"]) ended in "'list' object is not callable"
    (a function of the file's names was the only form); a list of names is taken, a text refused."""
    path = tmp_path / "r.csv"
    write_recording(path, Recording.from_dps(np.ones((4, 3)), 100.0, t_s=np.arange(4) / 100.0))
    assert list(read_recording(path, columns=["t", "gx"]).columns) == ["t", "gx"]
    assert list(read_recording(path, columns=lambda names: names[1:]).columns) == ["gx", "gy", "gz"]
    with pytest.raises(SettingsError, match="columns to keep .* got the text 'gx'"):
        read_recording(path, columns="gx")
    with pytest.raises(SettingsError, match="distinct columns of the file"):
        read_recording(path, columns=["gx", "nope"])


def test_a_writer_refuses_its_columns_in_a_set(tmp_path):
    """Attack pass 26: RecordingWriter(path, header, {"gx", "gy", "gz"}) named the columns in the
    set's order (the hash seed's): rows written by position landed under other axes, exit 0."""
    with pytest.raises(RecordingError, match="the columns are a list in the rows' order, got a set"):
        RecordingWriter(tmp_path / "r.csv", {"sample_rate_hz": 100, "gyro_unit": "dps"}, {"gx", "gy", "gz"})
    assert not (tmp_path / "r.csv").exists()


def test_the_unit_spellings_table_is_one_reading_of_each_spelling():
    """recording/unit_words.py, the one table of the units a log's column names state: each spelling
    (and its form at the end of a normalised name: ``rad/s`` -> ``rad_s``) means one unit of its
    quantity, each unit is an option's value, and a converted unit is converted exactly."""
    import re
    from fractions import Fraction
    from gyrofilter.recording import unit_words as uw
    for quantity, words in uw.UNIT_WORDS.items():
        forms = {}
        for text, unit in words.items():
            assert text == uw.spelling(text) and (unit is None or unit in uw.units_of(quantity))
            form = re.sub(r"[^a-z0-9%]+", "_", text).strip("_")
            if text.isascii() and form:
                assert forms.setdefault(form, unit) == unit, (quantity, text, form)
                assert uw.known_unit(quantity, form) == unit
        assert re.fullmatch(f"(?:{uw.name_units(quantity)})", "rad_s" if quantity == "rate" else "ms" if quantity == "time"
                            else "degc" if quantity == "temp" else "m_s_2")
    assert uw.stated_unit("temp", "deg") == "deg" and uw.stated_unit("rate", "Deg / Sec") == "dps"
    assert uw.to_floats(["98.6", "-40", "212"], "f").tolist() == [37.0, -40.0, 100.0]
    assert uw.to_floats(["1", "0.3"], "mg").tolist() == [0.001, float(Fraction("0.3") / 1000)]
    assert uw.to_floats(["300.15"], "k").tolist() == [27.0] and uw.recorded("mdps") == "dps"


@pytest.mark.parametrize("name", ["rec.csv", "rec.csv.gz"])
def test_write_recording_that_fails_keeps_the_recording_that_was_there(tmp_path, monkeypatch, name):
    """Attack pass 28b: write_recording over a recording wrote in place: a write that failed (a
    full disk, a file size limit) left the header alone where the earlier recording was, a
    file that read as a recording of 0 samples without a word. It writes whole or not at all
    (gyrofilter.files, as Calibration.save does): the earlier file kept, no partial left."""
    import errno
    path = tmp_path / name
    write_recording(path, Recording.from_dps(np.arange(30.0).reshape(10, 3), 100.0))
    before = path.read_bytes()

    def full_disk(self, rows):
        raise OSError(errno.ENOSPC, "No space left on device", self.name)
    monkeypatch.setattr(RecordingWriter, "write", full_disk)
    with pytest.raises(OSError, match="No space") as info:
        write_recording(path, Recording.from_dps(np.ones((50, 3)), 100.0))
    assert info.value.filename == str(path)
    assert path.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == [name]
    monkeypatch.undo()
    os.chmod(path, 0o640)
    write_recording(path, Recording.from_dps(np.ones((50, 3)), 100.0))
    assert len(read_recording(path)) == 50 and os.stat(path).st_mode & 0o777 == 0o640


def test_write_recording_through_a_link_compresses_by_the_name_given(tmp_path):
    """Attack pass 28b: written whole, through a partial beside a link's target, the format is
    still the one the name given states (``.gz``), whatever the target's name."""
    os.symlink("target.dat", tmp_path / "rec.csv.gz")
    write_recording(os.fsencode(tmp_path / "rec.csv.gz"), Recording.from_dps(np.ones((5, 3)), 100.0))
    assert (tmp_path / "target.dat").read_bytes()[:2] == b"\x1f\x8b" and (tmp_path / "rec.csv.gz").is_symlink()
    assert len(read_recording(tmp_path / "rec.csv.gz")) == 5


def test_a_blank_line_after_every_row_keeps_the_reader_in_bounded_memory(tmp_path):
    """Attack pass 28b: iter_recording kept a (row, line) pair for every place where the file's
    lines and samples fell out of step: a logger that ends each row with a blank line (or a
    note) made it keep about 120 bytes a sample (a 75 kB .gz of 10^6 rows: 120 MB; a day at
    100 Hz: 1 GB), while its memory is one chunk whatever the length. A regular spacing is one
    entry; every sample still has its line."""
    import tracemalloc
    rows = 30_000
    path = tmp_path / "blank.csv.gz"
    with gzip.open(path, "wt", compresslevel=1) as fh:
        fh.write("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\ngx,gy,gz\n")
        fh.write("0.1,0.2,0.3\n\n" * rows)
    tracemalloc.start()
    try:
        chunks = iter_recording(path, chunk_rows=10_000)
        head = next(chunks)
        before = tracemalloc.get_traced_memory()[0]
        assert sum(len(c) for c in chunks) == rows
        kept = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert kept < 300_000, kept
    assert [head.line_of_row(r) for r in (0, 1, rows - 1)] == [5, 7, 5 + 2 * (rows - 1)]


def test_a_converted_cell_beyond_a_float_is_infinite_not_a_traceback():
    """Attack pass 28c: ``1e400`` in an mg, mdps, deg F or K column ended in Python's OverflowError
    (the exact fraction too large for a float), and ``1e-999999999`` built a fraction of 10^999999999
    (minutes a cell). Beyond a float's range a cell is +-inf (refused by the range checks, as an
    unconverted ``1e400`` is); far below it, zero."""
    from gyrofilter.recording import unit_words as uw
    assert uw.to_floats(["1e400", "-1e400", "1E999999999"], "mg").tolist() == [np.inf, -np.inf, np.inf]
    assert uw.to_floats(["1e-999999999", "-1e-999999999"], "mdps").tolist() == [0.0, 0.0]
    assert uw.to_floats(["-1e-999999999"], "f").tolist() == uw.to_floats(["0"], "f").tolist()
    assert uw.to_floats(["1e400", "0e999999999", "-0e-999999999"], "k").tolist() == [np.inf, -273.15, -273.15]


@pytest.mark.parametrize("name", ["twice.csv.gz", "junk.csv"])
def test_binary_bytes_holding_a_cr_are_not_called_cr_only_line_ends(tmp_path, name):
    """Attack pass 37i (issue 37): a recording gzipped twice (`gzip rec.csv.gz`, renamed back), or
    an xz file, was refused as "line ends are CR only (old Mac): convert them to LF (e.g. tr '\\r'
    '\\n')", advice that cannot help: its bytes are no text, a CR among them by chance. Bytes that
    are not UTF-8 text are refused as such; a last line without its line end that is no text
    (junk a power cut left) is dropped with the interruption's warning, as one without a CR."""
    body = "".join(f"{i / 100:.2f},0.1,-0.2,0.3\n" for i in range(300))
    text = f"# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\nt,gx,gy,gz\n{body}".encode()
    if name == "twice.csv.gz":
        inner = bytearray(gzip.compress(text, mtime=0))
        inner[4] = ord("\r")  # the gzip header's time stamp holds a CR byte before any LF
        (tmp_path / name).write_bytes(gzip.compress(bytes(inner), mtime=0))
        with pytest.raises(RecordingError, match=re.escape(f"{tmp_path / name}: line 1: not UTF-8 text")):
            read_recording(tmp_path / name)
        return
    (tmp_path / name).write_bytes(text + b"\xff\xfe\r\x01\x02")
    rec = read_recording(tmp_path / name)
    assert len(rec) == 300 and any("line 305: last line has no line end" in w for w in rec.warnings)


@pytest.mark.parametrize("blank", ["\x1f", "\x1c", "\x0b", "\x0c", "\x85", "\u2028", "\u3000", "\u00a0"])
@pytest.mark.parametrize("where", ["before", "after"])
@pytest.mark.parametrize("rows", [3, 3000])  # one line's own parse, numpy's loadtxt of a chunk
def test_a_control_or_other_blank_beside_a_number_is_refused(tmp_path, blank, where, rows):
    """Attack pass 63: Python's strip and numpy's loadtxt take controls (0x1c-0x1f, 0x0b, 0x0c, U+0085) and other
    blanks for spaces: a damaged gzip stream's ``\\x1f5`` was read as 5. Only spaces, tabs and a CRLF's CR are blanks."""
    cell = blank + "5" if where == "before" else "5" + blank
    body = "".join(f"{i / 100},1,2,3\n" for i in range(rows - 1)) + f"9,{cell},2,3\n"
    path = write(tmp_path, HEADER + "t,gx,gy,gz\n" + body)
    with pytest.raises(RecordingError, match=rf"line {6 + rows}: column 'gx' is not a"):
        read_recording(path)


@pytest.mark.parametrize("blank", ["\x1f", "\x0b", "\u3000"])
def test_a_control_in_a_header_value_is_refused(tmp_path, blank):
    """Attack pass 63: ``sample_rate_hz: \\x1f100``, ``lsb_per_dps: 131\\x0b`` read as 100 and 131."""
    for text in (HEADER.replace("100", blank + "100"), HEADER.replace("131", "131" + blank)):
        with pytest.raises(RecordingError, match="must be a plain decimal number"):
            read_recording(write(tmp_path, text + "t,gx,gy,gz\n0,1,2,3\n"))


@pytest.mark.parametrize("blank", ["\x1f", "\x0b", "\u3000"])
def test_a_control_in_a_key_a_column_name_or_alone_on_a_line_is_not_a_blank(tmp_path, blank):
    """Attack pass 64: a header key ``\x1csample_rate_hz`` and a column ``\x1fgx`` read as sample_rate_hz and gx, and a
    line of a control alone, among the rows, was skipped as blank: the one rule of blanks (inputs.BLANKS) is theirs too."""
    rows = "".join(f"{i / 100},1,2,3\n" for i in range(10))
    for text, refused in ((HEADER.replace("# sample_rate_hz", "# " + blank + "sample_rate_hz") + "t,gx,gy,gz\n" + rows,
                           "line 3: header key"), (HEADER + f"t,{blank}gx,gy,gz\n" + rows, "line 6: column"),
                          (HEADER + "t,gx,gy,gz\n" + rows + blank + "\n" + rows, "line 17: 1 values")):
        with pytest.raises(RecordingError, match=refused):
            read_recording(write(tmp_path, text))


def test_spaces_tabs_and_crlf_around_numbers_still_read(tmp_path):
    path = write(tmp_path, (HEADER + "t,gx,gy,gz\n0, 1 ,\t2,3\n0.01,4 , 5\t,6\n").replace("\n", "\r\n"))
    np.testing.assert_array_equal(read_recording(path).gyro, [[1, 2, 3], [4, 5, 6]])


_L3GD20 = "# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: lsb\n# lsb_per_dps: 14.2857\n"


@pytest.mark.parametrize("same, other", [
    ("mdps_per_lsb: 70", "mdps_per_lsb: 14.2857"), ("mdps per LSB: 70", "mdps per LSB: 14.2857"),
    ("mdps/LSB: 70", "mdps/LSB: 14.2857"), ("dps_per_lsb: 0.07", "dps_per_lsb: 14.2857"),
    ("deg_s_per_lsb: 0.07", "deg_s_per_lsb: 14.2857"), ("deg_per_lsb: 0.07", "deg_per_lsb: 14.2857"),
    ("counts per mdps: 0.0142857", "counts per mdps: 14.2857"), ("lsb_per_deg: 14.2857", "lsb_per_deg: 0.07"),
    ("sensitivity in mdps/LSB: 70", "sensitivity in mdps/LSB: 14.2857"),
    ("sensitivity: 0.0142857 LSB/mdps", "sensitivity: 14.2857 LSB/mdps"),
    ("sensitivity: 0.0142857 counts per millidegree per second", "sensitivity: 14.2857 counts per millidegree per second"),
    ("sensitivity: 818.5 LSB/(rad/s)", "sensitivity: 14.2857 LSB/(rad/s)"),
    ("sensitivity_mdps: 70", "sensitivity_mdps: 14.2857"), ("mdps_lsb: 70", "mdps_lsb: 14.2857"),  # pass 64
    ("gyro_scale_mdps_lsb: 70", "gyro_scale_mdps_lsb: 14.2857"), ("sensitivity mdps: 70", "sensitivity mdps: 14.2857"),
    ("sensitivity_dps: 0.07", "sensitivity_dps: 14.2857"), ("Sensitivity (mdps): 70", "Sensitivity (mdps): 14.2857"),
    ("scale_factor_dps: 0.07", "scale_factor_dps: 14.2857"), ("lsb_dps: 14.2857", "lsb_dps: 0.07"),
    ("mdps_sensitivity: 70", "mdps_sensitivity: 14.2857"), ("sensitivity-mdps: 70", "sensitivity-mdps: 14.2857"),  # 65
    ("sensitivityMdps: 70", "sensitivityMdps: 14.2857"), ("gyroSensitivityMdpsPerLsb: 70", "gyroSensitivityMdpsPerLsb: 14.2857"),
    ("mdps_lsb_gyro: 70", "mdps_lsb_gyro: 14.2857"), ("per_lsb_mdps: 70", "per_lsb_mdps: 14.2857"),
    ("sensitivity_mdps (typ): 70", "sensitivity_mdps (typ): 14.2857"), ("mdps_per_lsb_typ: 70", "mdps_per_lsb_typ: 14.2857"),
    ("mDPS per LSB: 70", "mDPS per LSB: 14.2857"), ("deg_per_sec_per_lsb: 0.07", "deg_per_sec_per_lsb: 14.2857"),
    ("sensitivity_rad: 0.00122173", "sensitivity_rad: 14.2857"), ("Sensitivity (mdps / LSB): 70", "Sensitivity (mdps / LSB): 14.2857"),
])
def test_a_sensitivity_key_or_value_is_read_the_way_round_it_is_written(tmp_path, same, other):
    """Attack pass 63: ``mdps_per_lsb: 70`` (an L3GD20 at 2000 deg/s: 14.3 LSB per deg/s) was read as 70 LSB per
    deg/s, and ``131 LSB/mdps`` as 131 LSB per deg/s: the unit in a key was not read, the one under LSB not scaled.
    Pass 64: nor a unit without ``per`` (``mdps_lsb``) or alone after a sensitivity's word (``sensitivity_mdps``);
    pass 65: nor one among the key's words spelt otherwise (``mdps_sensitivity``, ``sensitivityMdps``, ``mdps_lsb_gyro``)."""
    body = "t,gx,gy,gz\n" + "".join(f"{i / 100},1,2,3\n" for i in range(20))
    assert len(read_recording(write(tmp_path, _L3GD20 + f"# {same}\n" + body))) == 20
    with pytest.raises(RecordingError, match="but lsb_per_dps is '14.2857'"):
        read_recording(write(tmp_path, _L3GD20 + f"# {other}\n" + body))


@pytest.mark.parametrize("written", ["131 LSB/kdps", "131 LSB/(deg/min)", "131 LSB/deg/h", "131 LSB/(°/h)"])
def test_a_sensitivity_per_an_unknown_unit_is_not_read_as_per_deg_s(tmp_path, written):
    """Attack pass 63: any unit under LSB holding ``dps`` or ``deg`` was taken for deg/s."""
    body = "t,gx,gy,gz\n" + "".join(f"{i / 100},1,2,3\n" for i in range(20))
    with pytest.raises(RecordingError, match="does not read as a sensitivity"):
        read_recording(write(tmp_path, HEADER + f"# gyro_sensitivity: {written}\n" + body))
