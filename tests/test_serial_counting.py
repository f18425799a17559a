"""Headerless serial lines: their fields are inferred from the width (counter,gx,gy,gz[,temp]) only once the
first value of the first lines counts (gyrofilter.sources.serial.counter.first_value_counts). Attack pass 37b: a
device sending gx,gy,gz,temp lines had its gx read as the counter and its temperature as gz: "lost 194, restarts
56, duplicates 33" and a recording of wrong numbers."""
import os
import threading

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from gyrofilter.errors import DeviceError
from gyrofilter.sources.serial.counter import COUNTING_LINES
from gyrofilter.sources.serial.protocol import LineParser

FAST = settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
OPTIONS = {"gyro_unit": "lsb", "lsb_per_dps": 131, "sample_rate_hz": 100}


def _gyro_temp_lines(n, seed=0):
    """n lines of an MPU6050 at rest sending gx,gy,gz,temp (LSB, deg C): biases, 6.5 LSB of noise."""
    rng = np.random.default_rng(seed)
    gyro = np.round(np.array([-12, 40, 3]) + 6.5 * rng.standard_normal((n, 3))).astype(int)
    temp = np.round(25 + 0.1 * rng.standard_normal(n), 2)
    return b"".join(b"%d,%d,%d,%s\n" % (*g, str(t).encode()) for g, t in zip(gyro, temp))


def _feed(parser, data, cuts=()):
    """Rows of ``data`` fed in the pieces that ``cuts`` (byte offsets) make, then finish()."""
    edges = [0, *sorted(set(c for c in cuts if 0 < c < len(data))), len(data)]
    rows = [parser.feed(data[a:b]) for a, b in zip(edges[:-1], edges[1:])]
    rows = [r for r in [*rows, parser.finish()] if len(r)]  # (0, 4) until the columns are known
    return np.concatenate(rows) if rows else np.empty((0, len(parser.columns or "t,gx,gy,gz".split(","))))


def test_headerless_gx_gy_gz_temp_lines_are_refused_naming_the_header_that_names_them():
    parser = LineParser(**OPTIONS)
    with pytest.raises(DeviceError) as info:
        parser.feed(_gyro_temp_lines(50))
    text = str(info.value)
    assert "the first value of the lines does not count" in text and "4 values are counter,gx,gy,gz" in text
    assert "`# gyrofilter-serial: 1 fields=gx,gy,gz,temp`" in text and "\n" not in text
    assert parser.stats["samples"] == 0


def test_a_millis_time_stamp_first_is_told_the_fields_a_header_may_name_and_one_line_is_not_called_not_counting():
    """Attack pass 37c: a `millis,gx,gy,gz` device was told to send a header naming its fields, which no header can
    (no time stamp field); a single line then an end was said "does not count" (one value shows nothing)."""
    parser = LineParser(**OPTIONS)
    with pytest.raises(DeviceError) as info:
        parser.feed(b"".join(b"%d,1,2,3\n" % (1000 + 10 * i) for i in range(20)))
    assert "the fields a header may name: counter, gx, gy, gz, temp, ax, ay, az" in str(info.value)
    parser = LineParser(**OPTIONS)
    parser.feed(b"cut line\n10,1,2,3\n")
    with pytest.raises(DeviceError) as info:
        parser.finish()
    assert "ended after one line (10 first): one value cannot show a counter counting" in str(info.value)
    assert "does not count" not in str(info.value)


@pytest.mark.parametrize("temp", [False, True])
@pytest.mark.parametrize("jump_at", [None, 1, 3, 7])
def test_a_headerless_counter_is_accepted_also_with_a_loss_among_its_first_lines(temp, jump_at):
    counters = list(range(1000, 1030))
    if jump_at is not None:
        counters = counters[:jump_at] + [c + 5 for c in counters[jump_at:]]  # 5 samples lost
    data = b"0,0,0,0" + (b",20" if temp else b"") + b"\n"  # the first line is dropped (the port opens mid-line)
    data += b"".join(b"%d,%d,-1,2" % (c, c % 7) + (b",20.5" if temp else b"") + b"\n" for c in counters)
    parser = LineParser(**OPTIONS)
    rows = _feed(parser, data)
    assert parser.columns == ["t", "gx", "gy", "gz"] + (["temp"] if temp else [])
    np.testing.assert_allclose(rows[:, 0] * 100, np.array(counters) - 1000)
    np.testing.assert_array_equal(rows[:, 1], np.array(counters) % 7)
    assert parser.stats["lost_samples"] == (0 if jump_at is None else 5) and parser.stats["samples"] == 30


def test_lines_waiting_when_a_header_names_other_fields_are_lines_before_it():
    parser = LineParser(**OPTIONS)
    rows = parser.feed(_gyro_temp_lines(5))  # 1 dropped, 4 waiting: no verdict yet
    assert len(rows) == 0 and parser.waiting_lines == 4
    rows = parser.feed(b"# gyrofilter-serial: 1 fields=gx,gy,gz,temp\n" + b"1,2,3,24.5\n")
    assert parser.columns == ["t", "gx", "gy", "gz", "temp"] and parser.stats["lines_before_header"] == 4
    np.testing.assert_array_equal(rows, [[0, 1, 2, 3, 24.5]])


def test_a_headerless_gx_gy_gz_temp_device_on_a_pseudo_terminal_is_refused_at_start_in_one_line(tmp_path, capsys):
    pytest.importorskip("serial")
    import tty

    from gyrofilter.cli import main

    master, slave = os.openpty()
    tty.setraw(slave)
    stop = threading.Event()
    lines = _gyro_temp_lines(400, seed=1).splitlines(keepends=True)

    def device():  # 400 lines, then the cable is pulled (a recording that took them ends)
        os.set_blocking(master, False)  # a full buffer (the port closed) drops lines instead of blocking
        try:
            for i in range(0, len(lines), 10):
                if stop.wait(0.005):
                    return
                try:
                    os.write(master, b"".join(lines[i:i + 10]))
                except BlockingIOError:
                    pass
        finally:
            os.close(master)

    writer = threading.Thread(target=device, daemon=True)
    writer.start()
    out = tmp_path / "rec.csv.gz"
    try:
        code = main(["record", "--source", f"serial:{os.ttyname(slave)},unit=lsb,lsb_per_dps=131,rate=100",
                     "--out", str(out)])
    finally:
        stop.set()
        writer.join(10)
        os.close(slave)
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()
    assert len(err.strip().splitlines()) == 1 and "does not count" in err and "fields=gx,gy,gz,temp" in err


@FAST
@given(st.data())
def test_random_gyro_triples_and_a_temperature_are_refused_however_the_bytes_arrive(data):
    n = data.draw(st.integers(COUNTING_LINES + 1, 40))
    cells = data.draw(st.lists(st.tuples(*[st.integers(-32768, 32767)] * 3, st.integers(-40, 85)), min_size=n, max_size=n))
    first = np.array([c[0] for c in cells[1:COUNTING_LINES + 1]])  # the first line is dropped
    # a gyro that steps by +1 in at most half its first steps (what a counter never does)
    assume(np.count_nonzero(np.diff(first) == 1) <= (COUNTING_LINES - 1) // 2)
    raw = b"".join(b"%d,%d,%d,%d\n" % c for c in cells)
    cuts = data.draw(st.lists(st.integers(1, len(raw) - 1), max_size=6))
    parser = LineParser(**OPTIONS)
    with pytest.raises(DeviceError, match="does not count"):
        _feed(parser, raw, cuts)
    assert parser.stats["samples"] == 0


@FAST
@given(st.data())
def test_counting_streams_are_accepted_and_the_same_however_the_bytes_arrive(data):
    n = data.draw(st.integers(2, 60))
    start = data.draw(st.integers(0, 2 ** 32 - 1))
    counters = (start + np.arange(n)) % 2 ** 32
    jump_at = data.draw(st.none() | st.integers(1, COUNTING_LINES - 1))  # a loss among the first lines
    jump = data.draw(st.integers(2, 1000))
    if jump_at is not None and n >= COUNTING_LINES:  # a stream that ends sooner shows all its steps +1
        counters[jump_at:] = (counters[jump_at:] + jump - 1) % 2 ** 32
    temp = data.draw(st.booleans())
    gyro = np.random.default_rng(data.draw(st.integers(0, 2 ** 16))).integers(-32768, 32768, (n, 3))
    raw = b"9,9,9,9\n" + b"".join(b"%d,%d,%d,%d" % (c, *g) + (b",21" if temp else b"") + b"\n"
                                  for c, g in zip(counters, gyro))
    cuts = data.draw(st.lists(st.integers(1, len(raw) - 1), max_size=6))
    whole, split = LineParser(**OPTIONS), LineParser(**OPTIONS)
    a = _feed(whole, raw)
    b = _feed(split, raw, cuts)
    np.testing.assert_array_equal(a, b)
    assert len(a) == n and whole.stats == split.stats
    np.testing.assert_array_equal(a[:, 1:4], gyro)
