"""The serial source through pyserial on a real pseudo-terminal (os.openpty()).

A writer thread plays the microcontroller: it answers '?' with the header, then streams lines
at 1 kHz on its own schedule, with garbage and a cut line injected and some lines split over
two writes; closing the master end is the cable being pulled.
"""
import os
import select
import threading
import time
import tty

import numpy as np
import pytest

from gyrofilter.errors import DeviceError, SourceEnded
from gyrofilter.recording import read_recording
from gyrofilter.sources import open_source
from gyrofilter.sources.serial.port import SerialSource
from support import wait_until_read

pytest.importorskip("serial")

HEADER = b"# gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps=131 sample_rate_hz=1000 sensor=MPU6050 fields=counter,gx,gy,gz,temp temp_unit=mpu6050_raw\n"
#: the header of a six-axis device: the accelerometer as raw MPU6050 LSB at +-2 g, after the temperature
HEADER_ACCEL = HEADER.replace(b"gz,temp ", b"gz,temp,ax,ay,az accel_unit=lsb lsb_per_g=16384 ")
RATE_HZ = 1000


def line(i, gx=None, raw_temp=True, accel=False):
    """Line i of the device: its temperature as the MPU6050's raw register (what HEADER says), or
    in deg C (a device without a header: the reader takes deg C, and refuses -2000 as absurd);
    with ``accel``, the accelerometer's ax, ay, az (:func:`accel_values`) after it."""
    gx = (i * 7) % 2001 - 1000 if gx is None else gx
    temp = -2000 + i % 50 if raw_temp else 25 + (i % 50) / 100
    tail = "".join(f",{int(v)}" for v in accel_values(i)[0]) if accel else ""
    return f"{i},{gx},{-(i % 300)},{(i * i) % 97 - 48},{temp}{tail}\n".encode()


def values(i):
    i = np.asarray(i)
    return np.column_stack([(i * 7) % 2001 - 1000, -(i % 300), (i * i) % 97 - 48]).astype(float)


def accel_values(i):
    """ax, ay, az (LSB) of line i: each differs from the gyro values and from the others."""
    i = np.asarray(i).reshape(-1)
    return np.column_stack([(i * 13) % 4001 - 2000, 500 - i % 1000, 16384 - (i * 3) % 700]).astype(float)


class Device(threading.Thread):
    """Stream ``n`` lines at ``RATE_HZ`` into the master side of a pty (``pty_pair``), with faults
    injected; it closes its side once the reader has taken every line."""

    def __init__(self, pty_pair, n, *, header=True, wait_for_query=True, garbage_at=(), cut_at=(), split_every=97, beyond_at=(),
                 accel=False):
        super().__init__(daemon=True)
        self.accel = accel  # send HEADER_ACCEL and lines with the accelerometer
        (self.master, self.port), self.n, self.header, self.wait_for_query = pty_pair, n, header, wait_for_query
        self.garbage_at, self.cut_at, self.split_every = set(garbage_at), set(cut_at), split_every
        self.beyond_at = set(beyond_at)  # these lines carry gx = 2**31 LSB (16 million deg/s): a corrupt value
        self.sent_good = []
        self.query = b""
        self.error = None
        self.rng = np.random.default_rng(1)

    def run(self):
        try:
            self._run()
        except Exception as exc:  # noqa: BLE001 - reported by the test
            self.error = exc
        finally:
            os.close(self.master)

    def _run(self):
        if self.wait_for_query:
            ready, _, _ = select.select([self.master], [], [], 10.0)
            if ready:
                self.query = os.read(self.master, 16)
        if self.header:
            os.write(self.master, HEADER_ACCEL if self.accel else HEADER)
        start = time.monotonic()
        for i in range(self.n):
            due = start + i / RATE_HZ
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            if i in self.garbage_at:
                junk = bytes(self.rng.integers(0x80, 0x100, 40, dtype=np.uint8)) + b"garbage!" + b"\n"
                os.write(self.master, junk)
            data = line(i, raw_temp=self.header, accel=self.accel)
            if i in self.beyond_at:
                os.write(self.master, line(i, gx=2 ** 31))
                continue
            if i in self.cut_at:  # the line loses its tail on the wire
                os.write(self.master, data[: len(data) // 2] + b"\n")
                continue
            if self.split_every and i % self.split_every == 0:
                os.write(self.master, data[:5])
                time.sleep(0.002)
                os.write(self.master, data[5:])
            else:
                os.write(self.master, data)
            self.sent_good.append(i)
        wait_until_read(self.port)


@pytest.fixture
def pty_pair():
    master, slave = os.openpty()
    tty.setraw(slave)
    name = os.ttyname(slave)
    yield master, name
    os.close(slave)


def drain(source, limit_s=60.0):
    rows = []
    deadline = time.monotonic() + limit_s
    with pytest.raises(SourceEnded) as info:
        while time.monotonic() < deadline:
            rows.append(source.read())
        raise AssertionError("the source did not end after the device went away")
    return np.concatenate(rows), str(info.value)


def test_every_good_line_arrives_once_in_order_at_1khz(pty_pair):
    name = pty_pair[1]
    n = 4000  # 4 s at 1 kHz
    dev = Device(pty_pair, n, garbage_at=(700, 2500), cut_at=(1500,))
    dev.start()
    src = open_source(f"serial:{name},baud=115200,header_timeout=10")
    assert src.header["lsb_per_dps"] == "131" and src.header["sensor"] == "MPU6050"
    assert src.columns == ["t", "gx", "gy", "gz", "temp"]
    rows, message = drain(src)
    dev.join(10)
    assert dev.error is None and dev.query == b"?"
    good = np.array(dev.sent_good)
    assert len(good) == n - 1
    # every intact line, once, in order; t from the counter (the cut line 1500 is a 1-sample gap)
    np.testing.assert_array_equal(rows[:, 1:4], values(good))
    np.testing.assert_allclose(rows[:, 0], good / RATE_HZ)
    np.testing.assert_allclose(rows[:, 4], (-2000 + good % 50) / 340.0 + 36.53)
    s = src.stats
    assert s["samples"] == n - 1 and s["lost_samples"] == 1 and s["counter_jumps"] == 1
    assert s["partial_lines"] == 1 and s["bad_lines"] >= 2 and s["garbage_bytes"] >= 2 * 48
    assert s["disconnects"] == 1 and "disconnected" in message and f"after {n - 1} samples" in message
    notes = src.pop_notes()
    assert "gap: 1 samples lost before t=1.501 s (counter 1499 -> 1501)" in notes
    src.close()


def test_device_without_header_uses_the_options(pty_pair):
    name = pty_pair[1]
    dev = Device(pty_pair, 1500, header=False, wait_for_query=False, split_every=0)
    dev.start()
    src = open_source(f"serial:{name}", gyro_unit="lsb", lsb_per_dps=131.0, sample_rate_hz=1000.0)
    rows, _ = drain(src)
    dev.join(10)
    assert src.header["gyro_unit"] == "lsb" and src.header["lsb_per_dps"] == "131"
    # lines before the port opened are gone and the first one received is dropped (it may be
    # cut); from then on every line, in order, consecutive
    counters = np.round(rows[:, 0] * RATE_HZ).astype(int)
    first = int(np.flatnonzero((values(np.arange(1500)) == rows[0, 1:4]).all(axis=1))[0])
    np.testing.assert_array_equal(rows[:, 1:4], values(np.arange(first, 1500)))
    np.testing.assert_array_equal(counters, np.arange(len(rows)))
    assert src.stats["lost_samples"] == 0 and len(rows) > 1000


def test_no_header_and_no_options_is_a_clear_error(pty_pair):
    master, name = pty_pair
    with pytest.raises(DeviceError) as info:
        open_source(f"serial:{name},header_timeout=0.3")
    text = str(info.value)
    assert "no '# gyrofilter-serial: 1 ...' header within 0.3 s" in text and "unit=lsb" in text
    os.close(master)


def test_missing_port_is_a_clear_error(tmp_path):
    with pytest.raises(DeviceError, match="cannot open the serial port.*dialout"):
        open_source(f"serial:{tmp_path / 'ttyNONE'}")


def test_record_from_serial_keeps_everything_when_the_cable_is_pulled(pty_pair, tmp_path, capsys):
    from gyrofilter.cli import main

    name = pty_pair[1]
    dev = Device(pty_pair, 2000, cut_at=(999,))
    dev.start()
    out = tmp_path / "serial.csv.gz"
    code = main(["record", "--source", f"serial:{name}", "--out", str(out)])
    dev.join(10)
    assert code == 1  # the recording ended because the device went away
    rec = read_recording(out)
    assert rec.warnings == []  # closed cleanly
    good = np.array(dev.sent_good)
    np.testing.assert_array_equal(rec.gyro, values(good))
    np.testing.assert_allclose(rec.t_s, good / RATE_HZ)
    texts = [t for _, t in rec.notes]
    assert any(t.startswith("gap: 1 samples lost before t=1 s") for t in texts)
    assert texts[-1].startswith("end: source ended:") and "disconnected" in texts[-1]
    assert rec.header["sensor"] == "MPU6050" and rec.header["serial_port"] == name
    err = capsys.readouterr().err
    assert f"wrote {len(good)} samples" in err and "lost 1 samples" in err


class _Port:
    """A port that has ``data`` waiting at once, then nothing."""

    def __init__(self, data):
        self.data = data

    @property
    def in_waiting(self):
        return len(self.data)

    def read(self, n):
        out, self.data = self.data[:n], self.data[n:]
        return out

    def write(self, data):
        pass

    def close(self):
        pass


@pytest.mark.parametrize("ends", ["deadline", "disconnect"])
def test_lines_that_give_no_sample_before_the_stream_starts_are_named(ends):
    """Attack pass 37b: a device without a header sending gx,gy,gz lines (no counter), units given as options,
    was refused with "no data lines within 5 s after the header" (no header came; 800 lines did) or
    "serial port disconnected ... before the stream started": the refusal says what came instead."""
    data = b"".join(b"%d,%d,1\r\n" % (i, -i) for i in range(50))
    ticks = iter(range(100))

    class Gone(_Port):
        def read(self, n):
            if not self.data:
                raise OSError("device reports readiness to read but returned no data")
            return super().read(n)

    port = (_Port if ends == "deadline" else Gone)(data)
    with pytest.raises(DeviceError) as info:
        SerialSource("fake", serial_port=port, gyro_unit="lsb", lsb_per_dps=131, sample_rate_hz=100,
                     header_timeout_s=5, clock=lambda: next(ticks))
    text = str(info.value)
    assert "no data lines" not in text and "after the header" not in text
    assert "50 lines received, none a sample: 1 partial lines, 49 bad lines" in text  # the first: the port may open mid-line
    assert "3 values before the field count is known, expected 4 or 5:" in text and "fields=gx,gy,gz" in text


def test_a_slow_headerless_counter_waiting_past_the_deadline_is_told_the_timeout_that_lets_it_start():
    """fix37c: headerless lines make rows once COUNTING_LINES of them count; a device slower than
    COUNTING_LINES / header_timeout_s reaches the deadline with lines waiting: the refusal names the option that
    lets it start, and that option does."""
    from gyrofilter.sources.serial.counter import COUNTING_LINES

    data = b"".join(b"%d,%d,%d,1\n" % (i, i, -i) for i in range(COUNTING_LINES + 1))
    ticks = iter(range(100))  # one second per read: one line per second
    slow = type("Slow", (_Port,), {"read": lambda self, n: _Port.read(self, min(n, self.data.index(b"\n") + 1))})
    with pytest.raises(DeviceError) as info:
        SerialSource("fake", serial_port=slow(data), gyro_unit="lsb", lsb_per_dps=131, sample_rate_hz=1,
                     header_timeout_s=5, clock=lambda: next(ticks))
    assert "header_timeout=" in str(info.value) and "waiting" in str(info.value)
    ticks = iter(range(100))
    source = SerialSource("fake", serial_port=slow(data), gyro_unit="lsb", lsb_per_dps=131, sample_rate_hz=1,
                          header_timeout_s=2 * COUNTING_LINES, clock=lambda: next(ticks))
    assert source.sample_rate_hz == 1


def test_a_headerless_counter_that_disconnects_before_the_counting_lines_keeps_its_samples():
    """Attack pass 37c: a device without a header that sent fewer than COUNTING_LINES lines of
    counter,gx,gy,gz and went away had them counted as samples at the disconnect (its first values count) but
    refused: "before the stream started (6 lines received, none a sample: 5 samples, ...)", exit 2, no file.
    They are rows, then the end: "... after 5 samples; everything received is kept"."""
    data = b"".join(b"%d,%d,%d,1\n" % (100 + i, 10 * i, -i) for i in range(6))

    class Gone(_Port):
        def read(self, n):
            if not self.data:
                raise OSError("device reports readiness to read but returned no data")
            return super().read(n)

    source = SerialSource("fake", serial_port=Gone(data), gyro_unit="dps", sample_rate_hz=100, header_timeout_s=5)
    rows = source.read()
    np.testing.assert_array_equal(rows[:, 1], [10, 20, 30, 40, 50])  # the first line dropped (the port may open mid-line)
    np.testing.assert_allclose(rows[:, 0], np.arange(5) / 100)  # t from the first counter kept
    with pytest.raises(SourceEnded, match="after 5 samples; everything received is kept"):
        source.read()


def test_a_header_changing_the_units_ends_the_source_after_the_rows_before_it():
    """Attack pass 25: the samples that came in one read with a header changing the units were lost."""
    head = b"# gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps=131 sample_rate_hz=100\n"
    data = head + b"".join(b"%d,%d,1,2\n" % (i, i) for i in range(5))
    src = SerialSource("fake", serial_port=_Port(data), header_timeout_s=1)
    src._port.data = b"".join(b"%d,%d,1,2\n" % (i, i) for i in range(5, 9)) + head.replace(b"131", b"65.5")
    rows = [src.read()]
    with pytest.raises(DeviceError, match="changed the units"):
        for _ in range(3):
            rows.append(src.read())
    np.testing.assert_array_equal(np.concatenate(rows)[:, 1], np.arange(9))


def test_a_header_changing_the_units_in_the_first_read_ends_the_source_after_the_rows_before_it():
    """Attack pass 28a: pass 25's case in the read that brought the first header (a device that sends a
    burst on connecting): the source refused at its opening, its samples lost (no file, exit 2)."""
    head = b"# gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps=131 sample_rate_hz=100\n"
    data = head + b"".join(b"%d,%d,1,2\n" % (i, i) for i in range(5)) + head.replace(b"131", b"65.5")
    src = SerialSource("fake", serial_port=_Port(data), header_timeout_s=1)
    rows = [src.read()]
    with pytest.raises(DeviceError, match="changed the units"):
        src.read()
    np.testing.assert_array_equal(np.concatenate(rows)[:, 1], np.arange(5))


def test_record_from_serial_skips_a_value_beyond_the_range_and_goes_on(pty_pair, tmp_path, capsys):
    """One corrupt line with a value beyond +-100000 deg/s ended the whole recording (exit 2,
    no end note, every later line lost); it is a bad line like any other: skipped, counted."""
    from gyrofilter.cli import main

    name = pty_pair[1]
    dev = Device(pty_pair, 600, beyond_at=(300,), split_every=0)
    dev.start()
    out = tmp_path / "serial.csv"
    code = main(["record", "--source", f"serial:{name}", "--out", str(out)])
    dev.join(10)
    assert code == 1 and dev.error is None  # ended by the device going away, not by the corrupt line
    rec = read_recording(out)
    good = np.array(dev.sent_good)
    assert len(good) == 599 and 300 not in good
    np.testing.assert_array_equal(rec.gyro, values(good))
    texts = [t for _, t in rec.notes]
    assert any("bad line (a gyro value beyond +-100000 deg/s, a temperature outside [-100, 200] deg C or an "
               "acceleration beyond +-1e+07 m/s^2): 300,2147483648," in t for t in texts), texts
    assert texts[-1].startswith("end: source ended:")
    capsys.readouterr()


@pytest.mark.device
def test_real_serial_device_streams_clean_lines():
    """A microcontroller running tools/arduino/gyrofilter_stream on GYROFILTER_SERIAL_PORT
    (default /dev/ttyACM0; GYROFILTER_SERIAL_BAUD, default 115200). Run: pytest -m device."""
    port = os.environ.get("GYROFILTER_SERIAL_PORT", "/dev/ttyACM0")
    baud = int(os.environ.get("GYROFILTER_SERIAL_BAUD", "115200"))
    with open_source(f"serial:{port},baud={baud},header_timeout=5") as src:
        rate = float(src.header["sample_rate_hz"])
        got = []
        t_end = time.monotonic() + 3.0
        while time.monotonic() < t_end:
            got.append(src.read())
        rows = np.concatenate(got)
        assert src.stats["lost_samples"] == 0 and src.stats["bad_lines"] == 0
        assert 0.8 * 3 * rate <= len(rows) <= 1.2 * 3 * rate + 1
        np.testing.assert_allclose(np.diff(rows[:, 0]), 1.0 / rate)


def test_six_axis_device_every_good_line_once_with_its_accelerometer(pty_pair):
    """ax, ay, az fields (issue 39) through a real pty at 1 kHz, with garbage and a cut line: every
    intact line's seven values arrive once, in order, in the columns the header names."""
    name = pty_pair[1]
    n = 2000
    dev = Device(pty_pair, n, garbage_at=(400,), cut_at=(1200,), accel=True)
    dev.start()
    src = open_source(f"serial:{name},baud=115200,header_timeout=10")
    assert src.columns == ["t", "gx", "gy", "gz", "temp", "ax", "ay", "az"]
    assert (src.header["accel_unit"], src.header["lsb_per_g"]) == ("lsb", "16384")
    rows, _ = drain(src)
    dev.join(10)
    good = np.array(dev.sent_good)
    assert dev.error is None and len(good) == n - 1
    np.testing.assert_array_equal(rows[:, 1:4], values(good))
    np.testing.assert_array_equal(rows[:, 5:8], accel_values(good))
    np.testing.assert_allclose(rows[:, 0], good / RATE_HZ)
    assert src.stats["partial_lines"] == 1 and src.stats["lost_samples"] == 1
    src.close()


def test_record_from_a_six_axis_device_writes_the_accelerometer(pty_pair, tmp_path, capsys):
    from gyrofilter.cli import main

    name = pty_pair[1]
    dev = Device(pty_pair, 800, accel=True, split_every=0)
    dev.start()
    out = tmp_path / "serial.csv"
    code = main(["record", "--source", f"serial:{name}", "--out", str(out)])
    dev.join(10)
    assert code == 1 and dev.error is None
    rec = read_recording(out)
    good = np.array(dev.sent_good)
    np.testing.assert_array_equal(rec.gyro, values(good))
    np.testing.assert_array_equal(np.column_stack([rec.columns[c] for c in ("ax", "ay", "az")]), accel_values(good))
    assert (rec.header["accel_unit"], rec.header["lsb_per_g"]) == ("lsb", "16384")
    capsys.readouterr()


@pytest.mark.parametrize("before", [0, 3])
def test_a_sensor_change_in_the_first_read_leaves_the_recording_header_the_first_headers(before):
    """Attack pass 29a: a device's burst on connecting whose second header changed `sensor=` (after 0 or 3
    samples) gave the recording's header the second header's sensor, while the note said it keeps the first's."""
    head = b"# gyrofilter-serial: 1 gyro_unit=dps sample_rate_hz=100 sensor=A\n"
    lines = [b"%d,%d,1,2\n" % (i, i) for i in range(6)]
    data = head + b"".join(lines[:before]) + head.replace(b"=A", b"=B") + b"".join(lines[before:])
    src = SerialSource("fake", serial_port=_Port(data), header_timeout_s=1)
    rows = src.read()
    np.testing.assert_array_equal(rows[:, 1], np.arange(6))
    assert src.header["sensor"] == "A"
    assert src.pop_notes() == [f"serial: the device's header says sensor=B after sample {before} "
                               "(the recording's header keeps sensor=A)"]
