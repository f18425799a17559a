"""Fuzz of the recording format (issue 22): generated recordings, valid and broken.

Properties:

- what :func:`write_recording` writes reads back exactly (every float, ``t`` included; header
  values as :func:`one_line_text` writes them);
- :func:`read_recording` of any generated text (header lines, cells, line ends, gzip framing)
  either raises RecordingError with one line of at most 300 characters naming the file, or returns
  exactly the rows written (a prefix of them, with a warning, for a gzip stream cut short or a
  last line without its line end); a file with a broken part is always refused;
- ``gyrofilter replay FILE --out OUT`` exits 0 with an OUT that reads back, or exits 2 with one
  line on stderr and no OUT.

Fast by default (a few hundred examples in all); the ``slow`` copies run thousands.
"""
import contextlib
import gzip
import io
import math
import os
import re
import tempfile
import zlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gyrofilter.cli import main
from gyrofilter.errors import RecordingError
from gyrofilter.recording import Recording, one_line_text, read_recording, write_recording
from gyrofilter.units import MAX_RATE_DPS

FAST = settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
SLOW = settings(max_examples=2000, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])

# what the reader must take as a number: plain decimal syntax, ASCII digits, blanks around
_PLAIN = re.compile(r"[ \t]*[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?[ \t]*")


def _check_refusal(exc, path):
    text = str(exc)
    assert isinstance(exc, RecordingError), repr(exc)
    assert text.startswith(f"{path}: ") and "\n" not in text and len(text) <= 300 and "Traceback" not in text, text


# --- 1. what write_recording writes reads back exactly ------------------------------------------

finite = st.floats(allow_nan=False, allow_infinity=False)
rates = st.floats(-MAX_RATE_DPS, MAX_RATE_DPS)  # what a gyro reads (deg/s): the reader refuses more
header_text = st.text(st.characters(codec="utf-8", exclude_categories=["Cs"]), max_size=40)


@st.composite
def recordings(draw):
    n = draw(st.integers(0, 40))
    rate_hz = draw(st.sampled_from([0.001, 1.0, 100.0, 285.7142857142857, 1000.0, 8000.0]))
    gyro = np.array(draw(st.lists(st.tuples(rates, rates, rates), min_size=n, max_size=n)), dtype=float).reshape(n, 3)
    t_s = None
    if draw(st.booleans()):
        t0 = draw(st.floats(-1e9, 2e9))
        t_s = t0 + np.arange(n) / rate_hz
    temp = np.array(draw(st.lists(st.floats(-40, 125), min_size=n, max_size=n))) if draw(st.booleans()) else None
    extra_keys = draw(st.dictionaries(st.from_regex(r"[a-z][a-z0-9_]{0,11}", fullmatch=True), header_text, max_size=4))
    return Recording.from_dps(gyro, rate_hz, t_s=t_s, temp_c=temp, header=extra_keys)


def _round_trip(rec, name):
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, name)
        write_recording(path, rec)
        back = read_recording(path)
        compact = read_recording(path, columns=lambda names: names[::-2], compact=True)
    assert list(back.columns) == list(rec.columns) and back.warnings == []
    for column, values in rec.columns.items():
        np.testing.assert_array_equal(back.columns[column], values)
    assert back.header == {k: one_line_text(v) for k, v in rec.header.items()}
    # the columns asked for, float32 only where every value is exactly one: the same numbers
    assert list(compact.columns) == list(rec.columns)[::-2]
    for column, values in compact.columns.items():
        assert np.array_equal(np.asarray(values, dtype=float), rec.columns[column])
        with np.errstate(over="ignore"):
            exact = np.array_equal(rec.columns[column].astype(np.float32), rec.columns[column])
        assert values.dtype == (np.float32 if exact else np.float64)


@FAST
@given(rec=recordings(), name=st.sampled_from(["r.csv", "r.csv.gz"]))
def test_what_write_recording_writes_reads_back_exactly(rec, name):
    _round_trip(rec, name)


@pytest.mark.slow
@SLOW
@given(rec=recordings(), name=st.sampled_from(["r.csv", "r.csv.gz"]))
def test_what_write_recording_writes_reads_back_exactly_many(rec, name):
    _round_trip(rec, name)


# --- 2. any generated text: the rows written, or one short line ---------------------------------

GOOD_HEADER = [("gyrofilter-recording", "1"), ("sample_rate_hz", "100"), ("gyro_unit", "dps")]
BAD_HEADER_LINES = [
    "# gyro_unit: dps",  # repeated
    "# sample_rate_hz: 50",  # repeated
    "# sample_rate_hz 100",  # no colon: not key: value
    "# : 5",  # no key
]
BAD_RATES = ["1_00", "inf", "nan", "0x10", "1e-300", "0", "-100", "1e9", "\u0661\u0660\u0660", "100 Hz", ""]
PYTHON_ONLY = ["0.0_1", "1_000", "nan", "inf", "-Infinity", "0x1", "1d5", "\u0661", "1e5e3", "--1", "1.2.3", "", "e5", "1e999"]


def _cell(value, style):
    return {"repr": repr(value), "g17": "%.17g" % value, "blanks": f" {value!r}\t", "plus": ("+" if math.copysign(1.0, value) > 0 else "") + repr(value),
            "upper": repr(value).upper()}[style]


@st.composite
def texts(draw, valid=False):
    """(text, rows written, what is broken or None, whether the last line has no line end);
    ``valid``: nothing broken, every line ended."""
    broken = None
    header = list(GOOD_HEADER)
    free = draw(st.lists(st.tuples(st.from_regex(r"[a-z][a-z0-9_]{0,8}", fullmatch=True),
                                   st.text(st.characters(codec="utf-8", exclude_characters="\n\x00", exclude_categories=["Cs"]), max_size=20)),
                         max_size=3, unique_by=lambda kv: kv[0]))
    header += [(k, v) for k, v in free if k not in dict(GOOD_HEADER)]
    lines = [f"# {k}: {v}" for k, v in header]
    mutation = "none" if valid else draw(st.sampled_from(["none"] * 4 + ["bad line", "bad rate", "missing", "bad input rate",
                                                                         "nul"]))
    if mutation == "bad line":
        lines.insert(draw(st.integers(1, len(lines))), draw(st.sampled_from(BAD_HEADER_LINES)))
        broken = "header"
    elif mutation == "bad rate":
        lines[1] = f"# sample_rate_hz: {draw(st.sampled_from(BAD_RATES))}"
        broken = "rate"
    elif mutation == "missing":
        del lines[draw(st.integers(0, 2))]
        broken = "missing key"
    elif mutation == "bad input rate":  # a filtered output's: a rate, and not below sample_rate_hz (100)
        at = draw(st.integers(1, len(lines)))  # with filtered_from, without which the key alone is refused
        lines[at:at] = ["# filtered_from: raw.csv", f"# input_sample_rate_hz: {draw(st.sampled_from(BAD_RATES + ['99.9']))}"]
        broken = "input rate"
    elif mutation == "nul":  # NUL bytes in a header or note line (an SD card after a power cut): refused
        lines.insert(draw(st.integers(1, len(lines))), "# " + "\x00" * draw(st.integers(1, 4)))
        broken = "NUL bytes"
    lines.append(draw(st.sampled_from(["gx,gy,gz", "gx, gy ,gz", "gz,gx,gy"])))
    names = [c.strip() for c in lines[-1].split(",")]
    rows = []
    for _ in range(draw(st.integers(0, 12))):
        kind = draw(st.sampled_from(["row"] * 6 + ["note", "blank"] + ([] if valid else ["python", "garbage", "short"])))
        if kind == "note":
            lines.append("# " + draw(st.text(st.characters(codec="utf-8", exclude_characters="\n\r\x00", exclude_categories=["Cs"]), max_size=20)))
            continue
        if kind == "blank":
            lines.append(draw(st.sampled_from(["", " ", "\t"])))
            continue
        values = draw(st.lists(rates if valid else finite, min_size=3, max_size=3))
        cells = [_cell(v, draw(st.sampled_from(["repr", "g17", "blanks", "plus", "upper"]))) for v in values]
        if kind == "python":
            cells[draw(st.integers(0, 2))] = draw(st.sampled_from(PYTHON_ONLY))
        elif kind == "garbage":
            cell = draw(st.text("0123456789.eE+- _xabnif\t", min_size=0, max_size=8))
            k = draw(st.integers(0, 2))
            cells[k] = cell
            if _PLAIN.fullmatch(cell) and math.isfinite(float(cell)):
                values[k] = float(cell)
            else:
                kind = "python"
        elif kind == "short":
            cells = cells[:draw(st.integers(1, 2))] if draw(st.booleans()) else cells + ["1"]
        lines.append(",".join(cells))
        rows.append((dict(zip(names, values)), kind))
    end = draw(st.sampled_from(["\n", "\r\n"]))
    text = end.join(lines) + end
    cut_last = not valid and bool(rows) and not lines[-1].startswith("#") and lines[-1].strip() and draw(st.booleans())
    if cut_last:  # an interrupted recording: the last line is not used
        text = text[:-len(end)]
        rows = rows[:-1]
    if broken is None and any(kind in ("python", "short") for _, kind in rows):
        broken = "cell"
    if broken is None and any(abs(v) > MAX_RATE_DPS for r, _ in rows for v in r.values()):
        broken = "beyond a gyro's rates"
    expected = np.array([[r[c] for c in ("gx", "gy", "gz")] for r, _ in rows]).reshape(-1, 3)
    return text, expected, broken, cut_last


def _read(path):
    try:
        return read_recording(path), None
    except Exception as exc:  # noqa: BLE001 -- anything but a RecordingError fails the check
        _check_refusal(exc, path)
        return None, exc


def _check_text(case):
    text, expected, broken, cut_last = case
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "r.csv")
        with open(path, "wb") as fh:
            fh.write(text.encode("utf-8"))
        rec, exc = _read(path)
    if broken is not None:
        assert rec is None, f"{broken} not refused"
        return
    assert exc is None, exc
    np.testing.assert_array_equal(rec.gyro, expected)
    assert any("no line end" in w for w in rec.warnings) == bool(cut_last)


@FAST
@given(case=texts())
def test_any_text_reads_as_written_or_is_refused_in_one_line(case):
    _check_text(case)


@pytest.mark.slow
@SLOW
@given(case=texts())
def test_any_text_reads_as_written_or_is_refused_in_one_line_many(case):
    _check_text(case)


# --- 3. gzip framing ----------------------------------------------------------------------------

@st.composite
def framings(draw):
    """(gzip bytes, valid text, its rows, framing kind, bytes after the stream)."""
    text, expected, _, _ = draw(texts(valid=True))
    data = text.encode("utf-8")
    level = draw(st.sampled_from([0, 1, 9]))
    packed = gzip.compress(data, compresslevel=level, mtime=0)
    kind = draw(st.sampled_from(["whole", "cut", "flip", "members", "trailing"]))
    after = b""
    if kind == "cut":
        at = draw(st.integers(0, len(packed) - 1))
        packed = packed[:at]
    elif kind == "flip":
        at = draw(st.integers(0, len(packed) - 1))
        packed = packed[:at] + bytes([packed[at] ^ draw(st.integers(1, 255))]) + packed[at + 1:]
    elif kind == "members":
        at = draw(st.integers(0, len(data)))
        packed = gzip.compress(data[:at], compresslevel=level) + gzip.compress(data[at:], compresslevel=level)
    elif kind == "trailing":
        after = draw(st.binary(min_size=1, max_size=12))
        packed += after
    return packed, text, expected, kind, after


def _rows_or_cut_short(rec, expected):
    """``rec`` holds the rows written, or a prefix of them and says the stream was cut short."""
    np.testing.assert_array_equal(rec.gyro, expected[:len(rec)])
    if len(rec) < len(expected) or rec.warnings:
        assert any("cut short" in w for w in rec.warnings), rec.warnings


def _check_framing(case):
    packed, text, expected, kind, after = case
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "r.csv.gz")
        with open(path, "wb") as fh:
            fh.write(packed)
        rec, exc = _read(path)
    if kind in ("whole", "members"):
        assert exc is None, exc
        np.testing.assert_array_equal(rec.gyro, expected)
        assert rec.warnings == []
    elif kind == "trailing":  # refused, unless the bytes start a gzip member (one cut short)
        if rec is not None:
            assert after.startswith(b"\x1f"), "data after the gzip stream not refused"
            _rows_or_cut_short(rec, expected)
    elif kind == "flip":
        # refused; or a flip zlib does not check (mtime, OS): the same rows; or one that makes the
        # stream end before its end marker, which is what a cut leaves: a prefix, with a warning
        if rec is not None:
            _rows_or_cut_short(rec, expected)
    else:  # cut short: the complete lines of what was written, with a warning; refused only before the column row
        prefix = zlib.decompressobj(16 + zlib.MAX_WBITS).decompress(packed)
        complete = prefix[:prefix.rfind(b"\n") + 1].decode("utf-8")
        assert complete == text[:len(complete)]
        if rec is None:
            assert all(ln.startswith("#") for ln in complete.split("\n")[:-1]), exc
        else:
            _rows_or_cut_short(rec, expected)


@FAST
@given(case=framings())
def test_gzip_framing_reads_as_written_a_prefix_when_cut_or_is_refused(case):
    _check_framing(case)


@pytest.mark.slow
@SLOW
@given(case=framings())
def test_gzip_framing_reads_as_written_a_prefix_when_cut_or_is_refused_many(case):
    _check_framing(case)


# --- 3b. six axes: the accelerometer's header keys and columns -------------------------------------

ACCEL_UNIT_TEXTS = ["m/s^2", "g", "lsb", "G", "m/s2", "", "LSB", "mps2"]
LSB_PER_G_TEXTS = ["16384", "2048", "0.5", "3e9", "0", "-16384", "0.4", "4e9", "nan", "1_0", "x", ""]


@st.composite
def six_axis_texts(draw):
    """(text, whether it is a six-axis recording the reader must take, its ax, ay, az): drawn
    accel_unit and lsb_per_g text (either may be absent), some of ax, ay, az among the columns,
    rows of values an accelerometer reads (within 16 g in every unit)."""
    unit = draw(st.sampled_from([None] + ACCEL_UNIT_TEXTS))
    lsb_per_g = draw(st.sampled_from([None] + LSB_PER_G_TEXTS))
    accel = draw(st.sampled_from([(), ("ax",), ("ax", "az"), ("ax", "ay", "az"), ("az", "ay", "ax")]))
    names = draw(st.permutations(["gx", "gy", "gz", *accel]))
    rows = np.array(draw(st.lists(st.lists(st.integers(-16, 16).map(float), min_size=len(names), max_size=len(names)),
                                  min_size=1, max_size=5)))
    lines = [f"# {k}: {v}" for k, v in GOOD_HEADER]
    lines += [f"# {k}: {v}" for k, v in (("accel_unit", unit), ("lsb_per_g", lsb_per_g)) if v is not None]
    lines += [",".join(names)] + [",".join(repr(v) for v in row) for row in rows.tolist()]
    scale_ok = lsb_per_g is not None and _PLAIN.fullmatch(lsb_per_g) and 0.5 <= float(lsb_per_g) <= 3e9
    readable = unit is None or (unit in ("m/s^2", "g", "lsb") and (unit != "lsb" or bool(scale_ok)) and len(accel) == 3)
    return "\n".join(lines) + "\n", readable, rows, names


@FAST
@given(case=six_axis_texts())
def test_a_six_axis_header_reads_or_is_refused_in_one_line_naming_a_line(case):
    text, readable, rows, names = case
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "six.csv")
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
        rec, exc = _read(path)
    if not readable:
        assert rec is None and re.match(rf"{re.escape(path)}: line \d+: ", str(exc)), exc
        return
    assert exc is None, exc
    for i, name in enumerate(names):
        np.testing.assert_array_equal(rec.columns[name], rows[:, i])


# --- 4. the command line: replay FILE --out OUT --------------------------------------------------

def _check_replay(case):
    text = case[0]
    with tempfile.TemporaryDirectory() as folder:
        path, out = os.path.join(folder, "in.csv"), os.path.join(folder, "out.csv")
        with open(path, "wb") as fh:
            fh.write(text.encode("utf-8"))
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            code = main(["replay", path, "--out", out, "--calibration-s", "0.01", "--set", "block_len=1"])
        if code == 0:
            read_recording(out)
        else:
            lines = err.getvalue().splitlines()
            assert code == 2 and len(lines) == 1 and len(lines[0]) <= 300 + len("gyrofilter: error: "), err.getvalue()
            assert not os.path.exists(out)


@settings(max_examples=25, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(case=texts())
def test_replay_out_reads_back_or_exits_2_with_one_line_and_no_file(case):
    _check_replay(case)


@pytest.mark.slow
@settings(max_examples=500, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(case=texts())
def test_replay_out_reads_back_or_exits_2_with_one_line_and_no_file_many(case):
    _check_replay(case)
