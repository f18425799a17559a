"""The serial line protocol (gyrofilter.sources.serial.protocol.LineParser): rows however the bytes are
split, the counter arithmetic, the refused lines and the counts that reconcile."""
import re

import numpy as np
import pytest
from gyrofilter.errors import DeviceError, SettingsError
from gyrofilter.sources.serial.protocol import LineParser, UnitsConflict
from support import REPO

HEADER = b"# gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps=131 sample_rate_hz=100 sensor=MPU6050\n"


def _lines(counters, temp=False):
    out = b""
    for c in counters:
        out += f"{c},{c % 50 - 25},{-c % 7},{3 * c % 11}".encode() + (f",{-1500 + c}".encode() if temp else b"") + b"\n"
    return out


def _expected(counters):
    c = np.asarray(counters)
    return np.column_stack([c % 50 - 25, -c % 7, 3 * c % 11]).astype(float)


def test_parser_same_rows_however_the_bytes_are_split():
    data = HEADER + _lines(range(200))
    whole = LineParser()
    a = whole.feed(data)
    rng = np.random.default_rng(3)
    cuts = np.sort(rng.choice(np.arange(1, len(data)), size=150, replace=False))
    split = LineParser()
    parts = [split.feed(bytes(chunk)) for chunk in np.split(np.frombuffer(data, np.uint8), cuts)]
    b = np.concatenate(parts)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a[:, 1:4], _expected(range(200)))
    np.testing.assert_allclose(a[:, 0], np.arange(200) / 100.0)
    assert whole.header["sensor"] == "MPU6050" and whole.columns == ["t", "gx", "gy", "gz"]


def test_parser_fast_and_slow_paths_agree():
    p = LineParser()
    p.feed(HEADER + _lines([0]))
    fast = p.feed(_lines(range(1, 101)))  # plain CSV: the numpy path
    q = LineParser()
    q.feed(HEADER + _lines([0]))
    slow = q.feed(b"# a device message\n" + _lines(range(1, 101)))  # '#' forces the line-by-line path
    np.testing.assert_array_equal(fast, slow)
    assert q.stats["device_messages"] == 1 and q.pop_notes() == ["device: a device message"]


def test_parser_counts_jumps_duplicates_restarts_and_keeps_t_on_the_sensor_clock():
    p = LineParser()
    rows = p.feed(HEADER + _lines([5, 6, 7, 10, 10, 11, 2, 3]))
    # 10 after 7: 2 lost; the second 10 is a duplicate; 2 after 11: device restart, t continues
    np.testing.assert_allclose(rows[:, 0] * 100, [0, 1, 2, 5, 6, 7, 8])
    np.testing.assert_array_equal(rows[:, 1:4], _expected([5, 6, 7, 10, 11, 2, 3]))
    assert (p.stats["lost_samples"], p.stats["counter_jumps"], p.stats["duplicates"], p.stats["restarts"]) == (2, 1, 1, 1)
    notes = p.pop_notes()
    assert notes[0] == "gap: 2 samples lost before t=0.05 s (counter 7 -> 10)"
    assert "restarted" in notes[1]


def test_parser_counter_wraps_at_counter_bits():
    p = LineParser()
    head = HEADER.replace(b"\n", b" counter_bits=16\n")
    rows = p.feed(head + _lines([65534, 65535, 0, 1]))
    np.testing.assert_allclose(rows[:, 0] * 100, [0, 1, 2, 3])
    assert p.stats["lost_samples"] == 0 and p.stats["restarts"] == 0


def _reconciles(parser):
    """Every line received is a delivered sample or counted as something else, exactly once."""
    from gyrofilter.sources.serial.protocol import LINE_OUTCOMES

    return parser.stats["lines"] == sum(parser.stats[k] for k in LINE_OUTCOMES)


def test_parser_refuses_and_counts_every_line_whose_counter_is_not_an_integer_in_range():
    """Issue 22 (7): negative, fractional and too large counters each refuse their line, counted;
    the original counted three of them at most and reconciled nothing."""
    p = LineParser()
    counters = [0, 1, -1, -1, -1, -1, 2, 2.5, 4294967296, -7, 3]
    rows = p.feed(HEADER + b"".join(f"{c},1,2,3\n".encode() for c in counters))
    np.testing.assert_allclose(rows[:, 0] * 100, [0, 1, 2, 3])
    assert p.stats["bad_lines"] == 7 and p.stats["samples"] == 4 and p.stats["lines"] == 12
    assert _reconciles(p)
    assert any("counter is not an integer in [0, 4294967296)" in n for n in p.pop_notes())


@pytest.mark.parametrize("bits", ["-3", "0", "7", "33", "64", "100000", "16.5", "x", "1e400", "0x10"])
def test_parser_refuses_a_header_whose_counter_bits_is_not_an_integer_in_8_to_32(bits):
    """Issue 22 (7, 11): counter_bits=-3 used to drop every line, 64 or 100000 to end in an
    OverflowError at the first gap; now the header is refused, naming the key and the value."""
    p = LineParser()
    with pytest.raises(DeviceError, match="counter_bits must be") as info:
        p.feed(HEADER.replace(b"\n", f" counter_bits={bits}\n".encode()) + _lines([0, 1, 5]))
    assert bits.lstrip("-")[:2] in str(info.value) and "\n" not in str(info.value)


def test_parser_gap_arithmetic_at_32_counter_bits_and_a_refused_repeated_header():
    """The widest counter: a wrap and a gap near 2**32 count exactly (no overflow); a repeated
    header with counter_bits=64 is one refused line, and the counter keeps its 32 bits."""
    p = LineParser()
    top = 2 ** 32
    rows = p.feed(HEADER.replace(b"\n", b" counter_bits=32\n") + _lines([top - 3, top - 1, 1])
                  + HEADER.replace(b"\n", b" counter_bits=64\n") + _lines([2, 0]))
    rows = np.concatenate([rows, p.finish()])  # the last line, a restart, waits for a next line or the end
    np.testing.assert_allclose(rows[:, 0] * 100, [0, 2, 4, 5, 6])
    assert (p.stats["lost_samples"], p.stats["counter_jumps"], p.stats["restarts"], p.stats["bad_lines"]) == (2, 2, 1, 1)
    assert _reconciles(p)


def test_parser_a_malformed_number_in_a_plain_chunk_is_one_refused_line():
    """numpy 2.4 raises ValueError where numpy 1.24 stopped reading at "--4" (a ValueError
    traceback from the serial stream before; found by tests/test_fuzz_sources.py)."""
    p = LineParser()
    p.feed(HEADER + _lines([0]))
    rows = p.feed(_lines([1]) + b"--4,0,0,0\n" + _lines([2]))
    np.testing.assert_array_equal(rows[:, 1:4], _expected([1, 2]))
    assert p.stats["bad_lines"] == 1 and _reconciles(p)


def test_parser_never_hands_out_an_infinite_t():
    """A rate of 1e-300 Hz made t = counter / rate infinite; the one rate check refuses it."""
    p = LineParser()
    with pytest.raises(DeviceError, match=r"sample_rate_hz must be a number of Hz in \[0.001, 100000\], got 1e-300"):
        p.feed(b"# gyrofilter-serial: 1 gyro_unit=dps sample_rate_hz=1e-300\n" + _lines([0]))
    p = LineParser()
    p.feed(b"# gyrofilter-serial: 1 gyro_unit=dps sample_rate_hz=0.001\n" + _lines([0]))
    p.feed(_lines([2 ** 31 - 1]))  # the largest jump, the last line: it waits for the next line or the end
    assert p.finish()[-1, 0] == (2 ** 31 - 1) / 0.001  # finite


def test_parser_counts_reconcile_whatever_the_lines():
    p = LineParser()
    data = (b"junk before the header\n" + HEADER + b"\r\n" + _lines(range(5)) + b"# note\n" + b"x" * 300
            + b"\n" + b"5,1,2\n" + _lines([5, 5, 9]) + b"1,2,3,4,5,6\n" + b"7,1,2,3")
    for i in range(0, len(data), 7):
        p.feed(data[i:i + 7])
    p.finish()
    s = p.stats
    assert (s["samples"], s["duplicates"], s["bad_lines"], s["partial_lines"], s["lost_samples"]) == (7, 1, 2, 2, 3)
    assert (s["lines_before_header"], s["headers"], s["empty_lines"], s["device_messages"]) == (1, 1, 1, 1)
    assert s["lines"] == 16 and _reconciles(p)


def test_parser_skips_bad_lines_and_never_raises_on_garbage():
    p = LineParser()
    rng = np.random.default_rng(5)
    junk = bytes(rng.integers(0, 256, 3000, dtype=np.uint8))
    data = (HEADER + _lines(range(10)) + b"10,1,2\n" + b"\xff\xfe\x00zz\n" + b"12,1,,3\n"
            + b"13,a,b,c\n" + b"14,1,2,3,4,5\n" + b"15,nan,1,1\n" + _lines(range(16, 20)))
    rows = p.feed(data)
    np.testing.assert_array_equal(rows[:, 1:4], _expected(list(range(10)) + list(range(16, 20))))
    s = p.stats
    assert s["partial_lines"] == 2 and s["bad_lines"] == 4
    assert s["lost_samples"] == 6  # 10..15 never arrived as good lines
    p.feed(junk)  # arbitrary bytes: counted, no exception
    p.feed(b"\n" + _lines([20]))
    assert p.stats["samples"] == 15


@pytest.mark.parametrize("header, beyond, edge", [
    (HEADER, b"13100001", b"13100000"),  # lsb at 131 LSB per deg/s: 100000.0076 and 100000 deg/s
    (b"# gyrofilter-serial: 1 gyro_unit=rad/s sample_rate_hz=100\n", b"1e308", b"1745.3"),  # overflows deg/s
    (b"# gyrofilter-serial: 1 gyro_unit=dps sample_rate_hz=100\n", b"-200000", b"-100000"),
])
def test_parser_refuses_a_line_beyond_the_rate_range_like_any_bad_line(header, beyond, edge):
    """One value beyond +-100000 deg/s went on as a sample and the recording's writer refused it,
    ending the whole recording (hostile 5-3); it is a corrupt line: counted, noted, skipped, in
    the fast path (all plain CSV) and the line-by-line one alike."""
    for extra in (b"", b"# a device message\n"):  # the second chunk goes line by line
        p = LineParser()
        p.feed(header + _lines(range(3)))
        rows = p.feed(extra + b"3,1," + beyond + b",2\n" + b"4,0,0," + edge + b"\n" + _lines(range(5, 8)))
        np.testing.assert_array_equal(rows[:, 0], np.array([4, 5, 6, 7]) / 100)  # t from the counter: 3 is a lost sample
        assert rows[0, 3] == float(edge)
        assert p.stats["bad_lines"] == 1 and p.stats["lost_samples"] == 1 and _reconciles(p)
        assert any("bad line (a gyro value beyond +-100000 deg/s, a temperature outside [-100, 200] deg C or an "
                   "acceleration beyond +-1e+07 m/s^2): 3,1,"
                   in note for note in p.pop_notes())


def test_parser_refuses_a_line_with_a_temperature_out_of_range_like_any_bad_line():
    """A temperature of 1e300 went on as a sample: record wrote it (replay then stopped at that
    line) and run stopped on it; it is a corrupt line, counted and skipped."""
    p = LineParser()
    rows = p.feed(HEADER + b"0,1,2,3,25.5\n1,1,2,3,1e300\n2,1,2,3,-150\n3,1,2,3,26\n")
    rows = np.concatenate([rows, p.finish()])  # 3 after 0, the last line: it waits for a next line or the end
    np.testing.assert_array_equal(rows[:, 4], [25.5, 26.0])
    assert p.stats["bad_lines"] == 2 and p.stats["lost_samples"] == 2 and _reconciles(p)


def test_parser_temperature_raw_and_celsius():
    raw = LineParser()
    rows = raw.feed(HEADER.replace(b"\n", b" fields=counter,gx,gy,gz,temp temp_unit=mpu6050_raw\n") + _lines([0, 1], temp=True))
    np.testing.assert_allclose(rows[:, 4], np.array([-1500, -1499]) / 340.0 + 36.53)
    c = LineParser()
    rows = c.feed(HEADER + b"0,1,2,3,25.5\n")
    assert c.columns == ["t", "gx", "gy", "gz", "temp"] and rows[0, 4] == 25.5


def test_parser_units_from_options_drop_the_first_line_and_check_a_later_header():
    p = LineParser(gyro_unit="dps", sample_rate_hz=50)
    more = b"".join(b"%d,1,1,1\n" % i for i in range(2, 8))  # 8 lines: the first value counts (no header)
    rows = p.feed(b"3,4.5,1,1\n" + b"0,0.25,0.5,-0.125\n1,1,1,1\n" + more)
    assert p.stats["partial_lines"] == 1  # the first line may be cut: not used
    np.testing.assert_array_equal(rows[:2, 1:4], [[0.25, 0.5, -0.125], [1, 1, 1]])
    np.testing.assert_allclose(rows[:2, 0], [0, 0.02])
    with pytest.raises(DeviceError, match="sample_rate_hz"):
        p.feed(b"# gyrofilter-serial: 1 gyro_unit=dps sample_rate_hz=100\n")


def test_parser_header_changing_units_mid_stream_is_refused():
    p = LineParser()
    p.feed(HEADER + _lines([0, 1]))
    p.feed(HEADER + _lines([0, 1]))  # same header again (device restart): fine
    assert p.stats["restarts"] == 1
    with pytest.raises(DeviceError, match="changed the units"):
        p.feed(HEADER.replace(b"131", b"65.5"))
    q = LineParser()
    q.feed(HEADER)
    q.feed(b"# gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps=1\xff1\n")  # garbled repeat: skipped
    assert q.stats["bad_lines"] == 1


def test_a_header_changing_the_units_hands_out_the_rows_before_it_in_its_chunk():
    """Attack pass 25: the rows of the lines before a header that changes the units, in the same
    chunk of bytes, were lost with the UnitsConflict (300 sent, 296 written)."""
    p = LineParser()
    p.feed(HEADER + _lines([0]))
    with pytest.raises(UnitsConflict, match="changed the units") as info:
        p.feed(_lines([1, 2, 3]) + HEADER.replace(b"131", b"65.5") + _lines([4]))
    np.testing.assert_array_equal(info.value.rows[:, 1:4], _expected([1, 2, 3]))
    np.testing.assert_allclose(info.value.rows[:, 0], [0.01, 0.02, 0.03])


@pytest.mark.parametrize("split", [False, True])
def test_a_header_changing_the_units_hands_out_a_line_whose_counter_jumped_before_it(split):
    """Attack pass 37e: the last line before a header that changes the units, whose counter jumped (held for the
    next line to judge it), was dropped with the UnitsConflict: 20 samples sent, 19 written, and the line counted
    in no outcome. The header ends the stream in those units: that line is judged as at the stream's end."""
    p = LineParser()
    p.feed(HEADER + _lines([0, 1, 2]))
    rows = [p.feed(_lines([3, 50]))] if split else []
    with pytest.raises(UnitsConflict, match="changed the units") as info:
        p.feed(_lines([] if split else [3, 50]) + HEADER.replace(b"131", b"65.5") + _lines([51]))
    rows = np.concatenate(rows + [info.value.rows])
    np.testing.assert_array_equal(rows[:, 1:4], _expected([3, 50]))
    np.testing.assert_allclose(rows[:, 0], [0.03, 0.5])
    assert p.stats["samples"] == 5 and p.stats["lost_samples"] == 46


def test_parser_first_header_errors():
    with pytest.raises(DeviceError, match="version"):
        LineParser().feed(b"# gyrofilter-serial: 2 gyro_unit=dps sample_rate_hz=1\n")
    with pytest.raises(SettingsError, match="lsb_per_dps"):
        LineParser().feed(b"# gyrofilter-serial: 1 gyro_unit=lsb sample_rate_hz=100\n")


@pytest.mark.parametrize("value", ["1e308", "1e-308"])
def test_lsb_per_dps_outside_what_a_gyro_can_be_is_refused(value):
    """Issue 37 (attack): any positive lsb_per_dps was taken, from the device's header or the options."""
    with pytest.raises(DeviceError, match=r"lsb_per_dps must be a number of LSB per deg/s in \[0.1, 1e\+08\]"):
        LineParser().feed(HEADER.replace(b"131", value.encode()))
    with pytest.raises(SettingsError, match=r"lsb_per_dps must be a number of LSB per deg/s in \[0.1, 1e\+08\]"):
        LineParser(gyro_unit="lsb", lsb_per_dps=float(value), sample_rate_hz=100)


def test_a_device_cannot_give_the_keys_gyrofilter_writes_about_provenance():
    """Attack pass (issue 37): a device's header word ``filtered_from=x`` was copied into the
    recording, and replay then refused the raw recording as a filtered output; ``time_origin`` and
    ``t_meaning`` could lie about its times. Those keys are dropped, with a note naming each."""
    p = LineParser()
    p.feed(b"# gyrofilter-serial: 1 gyro_unit=dps sample_rate_hz=100 filtered_from=x time_origin=5 sensor=ok\n"
           + _lines([0, 1]))
    assert "filtered_from" not in p.header and "time_origin" not in p.header and p.header["sensor"] == "ok"
    assert [n for n in p.notes if "gyrofilter's own" in n] == [
        "serial: the device's header key filtered_from is gyrofilter's own (where the samples came from): ignored",
        "serial: the device's header key time_origin is gyrofilter's own (where the samples came from): ignored"]


@pytest.mark.parametrize("word", [b"Gyro_Unit=rad/s", b"SAMPLE_RATE_HZ=200", b"Lsb_Per_Dps=65.5",
                                  b"Fields=counter,gz,gy,gx", b"Temp_Unit=mpu6050_raw", b"Counter_Bits=8",
                                  b"TempUnit=mpu6050_raw", b"counterBits=16", b"GyroUnit=rad/s",
                                  b"temp_units=mpu6050_raw", b"temperature_unit=mpu6050_raw"])
def test_a_device_key_gyrofilter_reads_spelt_otherwise_is_refused_naming_the_header_line(word):
    """Attack pass 46: a recording's header refuses a key it reads spelt in another case; from a device the
    refusal named the output file (record --out rec.csv) and asked to rename a key the firmware sends. A device's
    descriptive key in another case (``Sensor=MPU6050``) is its own key, kept beside gyrofilter's. Pass 47: the
    protocol's own keys too (``Fields=counter,gz,gy,gx`` was ignored and x and z swapped without a word); pass 48:
    with nothing for ``_`` (``TempUnit=mpu6050_raw`` read raw temperature counts as deg C); pass 49: plural, or
    ``temperature`` for ``temp``."""
    key = word.split(b"=")[0].decode()
    with pytest.raises(DeviceError, match=re.escape(f"header line: key '{key}': gyrofilter reads")):
        LineParser().feed(HEADER.rstrip(b"\n") + b" " + word + b"\n")
    p = LineParser()
    p.feed(HEADER.rstrip(b"\n") + b" Sensor=MPU6050-2\n" + _lines([0, 1]))
    assert p.header["Sensor"] == "MPU6050-2" and p.header["sensor"] == "MPU6050"


@pytest.mark.parametrize("word,meant", [
    (b"field=counter,gz,gy,gx", "fields"), (b"Field=counter,gz,gy,gx", "fields"), (b"feilds=counter,gz,gy,gx", "fields"),
    (b"fileds=counter,gz,gy,gx", "fields"), (b"fieldz=counter,gz,gy,gx", "fields"),
    (b"fields_list=counter,gz,gy,gx", "fields"), (b"field_names=counter,gz,gy,gx", "fields"),
    (b"columns=counter,gz,gy,gx", "fields"), (b"temprature_unit=mpu6050_raw", "temp_unit"),
    (b"temperture_unit=mpu6050_raw", "temp_unit"), (b"t_unit=mpu6050_raw", "temp_unit"), (b"temp_scale=c", "temp_unit"),
    (b"temp_fmt=c", "temp_unit"), (b"raw_temp=mpu6050_raw", "temp_unit"), (b"count_bits=8", "counter_bits"),
    (b"cnt_bits=8", "counter_bits"), (b"ctr_bits=8", "counter_bits"), (b"counter_width=8", "counter_bits"),
    (b"seq_bits=8", "counter_bits"), (b"counter_modulo=256", "counter_bits"), (b"counter_type=uint8", "counter_bits"),
    (b"counter_max=255", "counter_bits"), (b"wrap_bits=8", "counter_bits"), (b"idx_bits=8", "counter_bits"),
    (b"order=counter;gz;gy;gx", "fields"), (b"axis_order=zyx", "fields"), (b"axes=z,y,x", "fields"),
    (b"temp_raw=1", "temp_unit"), (b"raw_temp=true", "temp_unit"), (b"temp_mode=raw", "temp_unit"),
    (b"temp=raw", "temp_unit"), (b"names=counter,gyro_z,gyro_y,gyro_x", "fields"), (b"fmt=seq,z,y,x,t", "fields"),
    (b"remap=zyx", "fields"), (b"orientation=zyx", "fields"), (b"swap_xy=1", "fields"), (b"invert_z=1", "fields")])
def test_a_device_word_that_means_a_protocol_key_is_refused(word, meant):
    """Attack pass 51: a device's word kept as a descriptive key changed nothing without a word: ``field=`` or
    ``field_names=counter,gz,gy,gx`` left the default order (x and z swapped), ``temprature_unit=mpu6050_raw`` read
    counts as deg C, ``count_bits=8`` read a byte counter's wrap as a restart; pass 52: ``seq_bits=8`` and
    ``counter_max=255`` too. Refused, naming the key meant; the
    same stream with the protocol's key reads, and descriptive keys like them stay the device's own."""
    key = word.split(b"=")[0].decode()
    with pytest.raises(DeviceError, match=re.escape(f"header line: key '{key}': gyrofilter reads '{meant}'")):
        LineParser().feed(HEADER.rstrip(b"\n") + b" " + word + b"\n")
    valid = {"fields": b"counter,gz,gy,gx", "temp_unit": b"mpu6050_raw", "counter_bits": b"8"}[meant]
    p = LineParser()
    p.feed(HEADER.rstrip(b"\n") + b" " + meant.encode() + b"=" + valid + b"\n")
    assert p.header is not None
    own = (b"temp_offset=1.5 sample_count=9 temp_sensor=die temp2_unit=c counter=yes adc_bits=16 mag_field_ut=50 "
           b"sensor_index=0 baud_rate=115200 gyro_output_rate_hz=8000")
    p = LineParser()
    p.feed(HEADER.rstrip(b"\n") + b" " + own + b"\n" + _lines([0, 1]))
    assert {w.split(b"=")[0].decode() for w in own.split()} <= set(p.header)


@pytest.mark.parametrize("word", [b"unit=rad/s", b"rate=200", b"odr_hz=200", b"gyro=rad/s", b"units=rad/s",
                                  b"rate=200Hz", b"period_ms=5", b"samplerate=200", b"dt=0.005", b"gyro_scale=rad/s",
                                  b"logging_rate=200", b"sensor_odr=200", b"dt=20msec"])  # passes 55, 56
def test_a_device_word_that_states_another_unit_or_rate_stops_the_stream(word):
    """Attack pass 52: with the units given as options (``serial:PORT,unit=dps,rate=100``), a device's ``unit=rad/s``
    was kept as a descriptive key and the rows read as deg/s, without a word. Its first header stops the stream,
    the rows before it kept, as one that changes the units does; without options it is refused too."""
    p = LineParser(gyro_unit="dps", sample_rate_hz=100)
    with pytest.raises(UnitsConflict, match=re.escape(f"header key '{word.split(b'=')[0].decode()}' says")) as caught:
        p.feed(_lines(range(9)) + b"# gyrofilter-serial: 1 sample_rate_hz=100 " + word + b"\n9,1,2,3\n")
    assert len(caught.value.rows) == 8  # the first line discarded (the port may open mid-line)
    with pytest.raises(DeviceError, match="gyrofilter reads it only from"):
        LineParser().feed(b"# gyrofilter-serial: 1 gyro_unit=dps sample_rate_hz=100 " + word + b"\n")
    p = LineParser(gyro_unit="dps", sample_rate_hz=100)
    p.feed(b"# gyrofilter-serial: 1 sample_rate_hz=100 unit=dps rate=100\n0,1,2,3\n")
    assert p.header["unit"] == "dps"
    p = LineParser()  # a full scale is no sensitivity (pass 55)
    p.feed(b"# gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps=131 sample_rate_hz=100 gyro_scale=2000dps\n0,1,2,3\n")
    assert p.header["gyro_scale"] == "2000dps"


def test_parser_with_options_uses_a_header_that_comes_first():
    p = LineParser(gyro_unit="lsb", lsb_per_dps=131, sample_rate_hz=100)
    rows = p.feed(HEADER + _lines([0, 1]))  # the header is a whole line: nothing is dropped
    np.testing.assert_array_equal(rows[:, 1:4], _expected([0, 1]))
    assert p.stats["partial_lines"] == 0 and p.header["sensor"] == "MPU6050"


@pytest.mark.parametrize("bad", [b"1.2.3", b"1..2", b"+-4", b"--4", b"4-"])
def test_a_malformed_last_cell_in_a_block_of_its_own_is_refused(bad):
    """A chunk that completes one data line whose last cell is malformed went the numpy path, and
    numpy 1.24 read "1.2.3" as 1.2 without a word (the fuzz test of the chunking found it on the Pi
    configuration): such a line is refused and counted whatever the numpy, and the next one read."""
    p = LineParser()
    p.feed(HEADER + b"0,1,2,3\n")
    rows = [p.feed(b"1,-1000,-1," + bad[:1]), p.feed(bad[1:] + b"\n"), p.feed(b"2,0,0,0\n"), p.finish()]
    got = np.concatenate(rows)
    np.testing.assert_array_equal(got[:, 1:], [[0.0, 0.0, 0.0]])
    assert p.stats["bad_lines"] == 1 and p.stats["samples"] == 2


ACCEL = b"fields=counter,gx,gy,gz,ax,ay,az accel_unit=g"


@pytest.mark.parametrize("unit,lsb_per_g", [(b"g", None), (b"m/s^2", None), (b"lsb", b"16384")])
def test_parser_accelerometer_fields_come_after_the_gyro_in_the_header_unit(unit, lsb_per_g):
    words = ACCEL.replace(b"=g", b"=" + unit) + (b" lsb_per_g=" + lsb_per_g if lsb_per_g else b"")
    p = LineParser()
    rows = p.feed(HEADER.replace(b"\n", b" " + words + b"\n") + b"0,1,2,3,0.5,-0.25,9.5\n1,4,5,6,7,8,9\n")
    assert p.columns == ["t", "gx", "gy", "gz", "ax", "ay", "az"]
    np.testing.assert_array_equal(rows, [[0, 1, 2, 3, 0.5, -0.25, 9.5], [0.01, 4, 5, 6, 7, 8, 9]])
    assert p.header["accel_unit"] == unit.decode() and p.header.get("lsb_per_g") == (lsb_per_g and lsb_per_g.decode())
    assert p.feed(b"2,1,2,3,4,5\n").shape == (0, 7) and p.stats["partial_lines"] == 1  # an accel value missing


@pytest.mark.parametrize("words,message", [
    (b"fields=counter,gx,gy,gz,ax,ay accel_unit=g", "names ax, ay but not az: the accelerometer is all of ax, ay, az or none"),
    (b"fields=counter,gx,gy,gz,ax,ay,az", "fields name ax, ay, az but the header gives no accel_unit"),
    (b"fields=counter,gx,gy,gz,ax,ay,az accel_unit=mg", "accel_unit 'mg' is not one of m/s^2, g, lsb"),
    (b"fields=counter,gx,gy,gz,ax,ay,az accel_unit=lsb", "accel_unit=lsb needs lsb_per_g"),
    (b"fields=counter,gx,gy,gz,ax,ay,az accel_unit=lsb lsb_per_g=0", "lsb_per_g must be"),
    (b"fields=counter,gx,gy,gz,ax,ay,az accel_unit=g lsb_per_g=16384", "lsb_per_g with accel_unit=g"),
])
def test_parser_refuses_an_accelerometer_header_in_one_line(words, message):
    with pytest.raises(DeviceError, match=message.replace("^", "\\^")):
        LineParser().feed(HEADER.replace(b"\n", b" " + words + b"\n"))


@pytest.mark.parametrize("words, beyond, edge", [
    (b"accel_unit=g", b"1e300", b"1019716"),  # 1e7 m/s^2 is 1019716.2 g
    (b"accel_unit=m/s^2", b"-20000000", b"-10000000"),
    (b"accel_unit=lsb lsb_per_g=16384", b"1e300", b"16000000000"),  # 1.6e10 LSB: 9.58e6 m/s^2
])
def test_parser_refuses_a_line_with_an_acceleration_beyond_the_range_like_any_bad_line(words, beyond, edge):
    """An accelerometer value of 1e300 g went on as a sample (only the gyro and the temperature
    were checked), and the recording's writer refused it, ending the whole recording with every
    later line lost (attack pass 11): it is a corrupt line, counted and skipped, as a gyro's."""
    head = HEADER.replace(b"\n", b" fields=counter,gx,gy,gz,ax,ay,az " + words + b"\n")
    for extra in (b"", b"# a device message\n"):  # the second chunk goes line by line
        p = LineParser()
        p.feed(head + b"0,1,2,3,0,0,1\n1,1,2,3,0,0,1\n")
        rows = p.feed(extra + b"2,1,2,3,0," + beyond + b",1\n3,1,2,3,0,0," + edge + b"\n4,1,2,3,0,0,1\n")
        np.testing.assert_array_equal(rows[:, 0], [0.03, 0.04])  # 2 is a lost sample
        assert rows[0, 6] == float(edge) and p.stats["bad_lines"] == 1 and p.stats["lost_samples"] == 1
        assert any("acceleration beyond +-1e+07 m/s^2): 2,1,2,3,0," in note for note in p.pop_notes())


@pytest.mark.parametrize("words", [b"accel_unit=lsb lsb_per_g=16384", b"accel_unit=g", b"fields=counter,gx,gy,gz accel_unit=g"])
def test_parser_drops_accelerometer_units_of_a_stream_without_its_fields(tmp_path, words):
    """A six-axis firmware with the accelerometer off still saying ``accel_unit``: its units went into the
    header without ``ax, ay, az`` columns, so `record` exited 2 before its first row with the recording's
    words ("header key 'accel_unit' is given but the column row (line 13) has no accelerometer columns") about
    a file it never wrote, while `run` took the same device (attack pass 37g): they describe no field, ignored."""
    from gyrofilter.recording import RecordingWriter, read_recording
    p = LineParser()
    rows = p.feed(HEADER.replace(b"\n", b" " + words + b"\n") + b"0,1,2,3\n1,4,5,6\n")
    assert "accel_unit" not in p.header and "lsb_per_g" not in p.header and p.columns == ["t", "gx", "gy", "gz"]
    assert any("accel_unit" in note and "ignored" in note for note in p.pop_notes())
    with RecordingWriter(tmp_path / "r.csv", p.device_header, p.columns) as out:
        out.write(rows)
    np.testing.assert_array_equal(read_recording(tmp_path / "r.csv").gyro, [[1, 2, 3], [4, 5, 6]])


@pytest.mark.parametrize("first, second", [(b" temp_unit=c", b" temp_unit=mpu6050_raw"), (b" temp_unit=mpu6050_raw", b""),
                                           (b"", b" temp_unit=mpu6050_raw")])
def test_parser_header_changing_the_temperature_unit_mid_stream_is_refused(first, second):
    """A restarted device's banner without the first one's temp_unit=mpu6050_raw (or with it where the first had
    none): the temperatures after it were read in the other unit, 30 deg C then 36.6 in one column, without a
    word (attack pass 37g). As a change of the gyro's units, it stops the stream, the rows before it kept."""
    head = HEADER.replace(b"\n", b" fields=counter,gx,gy,gz,temp")
    p = LineParser()
    rows = p.feed(head + first + b"\n0,1,2,3,30\n1,1,2,3,30\n")
    p.feed(head + first + b"\n")  # the same header again: fine
    with pytest.raises(UnitsConflict, match="changed temp_unit mid-stream") as info:
        p.feed(b"2,1,2,3,30\n" + head + second + b"\n3,1,2,3,30\n")
    np.testing.assert_array_equal(np.concatenate([rows, info.value.rows])[:, 4], [rows[0, 4]] * 3)
    fresh = LineParser()  # before any sample the header may still say it
    fresh.feed(head + first + b"\n")
    assert fresh.feed(head + second + b"\n0,1,2,3,30\n").shape == (1, 5)


def test_parser_header_changing_the_accelerometer_unit_mid_stream_is_refused():
    p = LineParser()
    p.feed(HEADER.replace(b"\n", b" " + ACCEL + b"\n") + b"0,1,2,3,4,5,6\n")
    p.feed(HEADER.replace(b"\n", b" " + ACCEL + b"\n"))  # the same header again: fine
    with pytest.raises(DeviceError, match=r"changed the units mid-stream \(accel_unit g -> m/s\^2\); start a new"):
        p.feed(HEADER.replace(b"\n", b" " + ACCEL.replace(b"=g", b"=m/s^2") + b"\n"))


def test_a_six_axis_line_longer_than_a_line_may_be_is_refused_in_a_block_as_alone():
    """Eight cells, seven of 41 characters (a plain-looking block, 295 bytes a line): the numpy path took
    it whole, the line-by-line path refuses a line beyond 256 bytes; both refuse it now."""
    head = HEADER.replace(b"\n", b" fields=counter,gx,gy,gz,temp,ax,ay,az accel_unit=g\n")
    cell = b"1" * 20 + b"." + b"2" * 20
    long_line = b",".join([b"1"] + [cell] * 7) + b"\n"
    good = b"0,1,2,3,4,5,6,7\n"
    assert len(long_line) - 1 > 256
    whole, alone = LineParser(), LineParser()
    rows = np.concatenate([whole.feed(head + good + long_line + b"2,1,2,3,4,5,6,7\n"), whole.finish()])
    parts = [alone.feed(x) for x in (head, good, long_line, b"2,1,2,3,4,5,6,7\n")] + [alone.finish()]  # 0 -> 2: held
    np.testing.assert_array_equal(rows, np.concatenate(parts))
    assert len(rows) == 2 and whole.stats == alone.stats and whole.stats["bad_lines"] == 1


@pytest.mark.parametrize("lost", [False, True])
@pytest.mark.parametrize("corrupt", ["81000", "1900", "100", "10000", "0"])
def test_one_corrupt_counter_digit_is_one_refused_line_not_a_gap_and_shifted_times(corrupt, lost):
    """Counter 1000 received as 81000 (one corrupt digit) made the source count 80000 lost
    samples, shift every later t by 800 s and note a device restart (attack pass 10): a counter that
    jumps while the next line's continues the one before it is a corrupt line, refused; the
    others keep their own times, however the bytes arrive."""
    counters = [str(c) for c in range(995, 1010)]
    counters[5] = corrupt  # counter 1000
    sent = [i for i in range(15) if not (lost and i == 4)]  # counter 999 lost on the way as well
    data = HEADER + b"".join(f"{counters[i]},{i},{-i},3\n".encode() for i in sent)
    for cut in (len(data), len(HEADER) + 50, len(HEADER) + 60, len(data) - 10):
        p = LineParser()
        rows = np.concatenate([p.feed(data[:cut]), p.feed(data[cut:]), p.finish()])
        kept = [i for i in sent if i != 5]
        np.testing.assert_allclose(rows[:, 0] * 100, kept)  # t on the sensor's clock: no shift
        np.testing.assert_array_equal(rows[:, 1], kept)
        assert (p.stats["bad_lines"], p.stats["lost_samples"], p.stats["restarts"]) == (1, 1 + lost, 0)
        assert _reconciles(p)


def test_a_real_gap_or_restart_as_the_last_line_waits_for_the_next_line_or_the_end():
    """A jump the next line follows is a gap (or a restart), as before; a last line that jumps is
    handed out by the next feed or by finish(), never lost."""
    p = LineParser()
    rows = [p.feed(HEADER + _lines([5, 6, 10]))]
    assert len(rows[0]) == 2
    rows.append(p.feed(_lines([11, 0])))
    rows.append(p.finish())
    rows = np.concatenate(rows)
    np.testing.assert_allclose(rows[:, 0] * 100, [0, 1, 5, 6, 7])
    assert (p.stats["lost_samples"], p.stats["restarts"], p.stats["bad_lines"]) == (3, 1, 0)
    assert _reconciles(p)


SKETCH = REPO / "tools" / "arduino" / "gyrofilter_stream" / "gyrofilter_stream.ino"


def _sketch_output(frame):
    """What tools/arduino/gyrofilter_stream prints: its header line, read off ``sendHeader``'s prints
    (``F("...")`` literals; a #define, ``ARRAY[INDEX]`` of its constant arrays, ``chip_id`` 0x68),
    and the data line of the FIFO ``frame`` ({variable: value}) in the order ``loop`` prints them."""
    text = SKETCH.read_text()
    names = dict(re.findall(r"^#define (\w+) (\S+)", text, re.M))
    names["chip_id"] = "0x68"
    for name, values in re.findall(r"static const \w+ (\w+)\[\d+\] = \{([^}]*)\}", text):
        for i, v in enumerate(values.split(",")):
            names[f"{name}[{i}]"] = v.strip()

    def value(expr):
        expr = re.sub(r"\[(\w+)\]", lambda m: f"[{names[m.group(1)]}]", expr.split(",")[0].strip())
        return names[expr]

    def prints(body):
        return re.findall(r"Serial\.print(?:ln)?\((.*?)\);", body)

    body = text.split("static void sendHeader() {", 1)[1].split("\n}", 1)[0]
    header = "".join(p[3:-2] if p.startswith('F("') else value(p).removeprefix("0x") for p in prints(body))
    loop = text.split("for (uint16_t f = 0; f < frames; f++) {", 1)[1].split("\n  }", 1)[0]
    line = "".join("," if p == "','" else str(frame[p.rstrip("+")]) for p in prints(loop))
    return header, line


def test_the_arduino_sketch_sends_the_accelerometer_in_the_protocol():
    """Issue 39 (trial): the sketch sent counter,gx,gy,gz,temp only; it sends ax, ay, az too, named by
    its header's fields, with accel_unit=lsb and lsb_per_g of its range, in the order it prints them;
    the header stays one line the parser takes (at most MAX_LINE_BYTES: 297 bytes were refused)."""
    frame = {"counter": 7, "gx": -433, "gy": 151, "gz": -62, "temp": -1520, "ax": 312, "ay": -96, "az": 16544}
    header, line = _sketch_output(frame)
    p = LineParser()
    rows = p.feed(f"{header}\n{line}\n".encode())
    assert p.columns == ["t", "gx", "gy", "gz", "temp", "ax", "ay", "az"]
    assert p.header["accel_unit"] == "lsb" and p.header["lsb_per_g"] == "16384" and p.stats["bad_lines"] == 0
    np.testing.assert_allclose(rows[0][[1, 2, 3, 5, 6, 7]], [-433, 151, -62, 312, -96, 16544])
    assert rows[0][4] == pytest.approx(-1520 / 340 + 36.53)


def test_header_changes_beyond_the_noted_ones_are_said_to_go_unnoted():
    """Attack pass 27: after 20 notes of a header's changed ``sensor=``, later changes were dropped
    without a word (the last note's sensor read as the device's to the end); the next change says
    that changes from there on are not noted."""
    p = LineParser()
    p.feed(HEADER + _lines([0]))
    p.pop_notes()
    for k in range(1, 25):
        p.feed(HEADER.replace(b"sensor=MPU6050", b"sensor=S%d" % k) + _lines([k]))
    notes = p.pop_notes()
    assert len(notes) == 21 and notes[19].startswith("serial: the device's header says sensor=S20 after sample 20")
    assert notes[20] == ("serial: the device's header changed again after sample 21; after 20 such notes, its "
                         "changes from here on are not noted")


def test_a_header_that_changes_a_key_that_is_no_unit_mid_stream_is_noted_at_its_row():
    """Attack pass 26: a repeated header that said ``sensor=ICM20602`` mid-stream was kept without
    a word (the recording's header keeps the first, MPU6050). The samples keep their units, so the
    stream goes on, and a note says what the device said and after how many samples; a header
    repeated as it was says nothing."""
    p = LineParser()
    p.feed(HEADER + _lines([0, 1, 2]))
    p.pop_notes()
    changed = HEADER.replace(b"sensor=MPU6050", b"sensor=ICM20602 dlpf_cfg=3")
    rows = p.feed(changed + _lines([3, 4]) + changed + HEADER + _lines([5]))
    assert len(rows) == 3 and p.stats["samples"] == 6
    assert p.pop_notes() == ["serial: the device's header says sensor=ICM20602, dlpf_cfg=3 after sample 3 (the "
                             "recording's header keeps sensor=MPU6050, no dlpf_cfg)",
                             "serial: the device's header says sensor=MPU6050, no dlpf_cfg after sample 5 (the "
                             "recording's header keeps sensor=MPU6050, no dlpf_cfg)"]


COUNTERLESS = b"# gyrofilter-serial: 1 gyro_unit=dps sample_rate_hz=100 fields=gx,gy,gz\n"
# each refused line of the full width (nan, beyond the range, a bad cell, garbage, an empty cell) between good ones
REFUSED_SAMPLES = [b"nan,0,0", b"200000,0,0", b"1.2.3,0,0", b"1x,0,0", b"1,,0"]


@pytest.mark.parametrize("chunked", [False, True])
def test_a_refused_line_of_the_full_width_without_a_counter_is_a_lost_sample_not_shifted_times(chunked):
    """Attack pass 33b: with fields=gx,gy,gz (no counter) a refused line of the full width was
    dropped and every later sample's t came one interval early ("lost 0 samples"); with a counter
    the same line is a gap. It is a sample the device sent: a gap in t, counted lost, its bad line
    noted; a line of another width (a message, a cut line) changes no t; before the first row
    none does (a counter's t starts at its first row too)."""
    lines = [b"nan,0,0", b"0,0,0"]
    for i, bad in enumerate(REFUSED_SAMPLES, start=1):
        lines += [bad, b"%d,0,0" % i, b"1,2"]
    data = COUNTERLESS + b"\n".join(lines) + b"\n"
    parser = LineParser()
    parts = [parser.feed(data[i:i + 7]) for i in range(0, len(data), 7)] if chunked else [parser.feed(data)]
    rows = np.concatenate([*parts, parser.finish()])
    np.testing.assert_array_equal(rows[:, 1], np.arange(6))
    np.testing.assert_allclose(rows[:, 0], 2 * np.arange(6) / 100.0)  # a refused sample before each good line
    s = parser.stats
    assert s["lost_samples"] == 5 and s["samples"] == 6 and s["bad_lines"] + s["partial_lines"] == 11, s
    notes = parser.pop_notes()
    assert sum(n.startswith("gap: 1 samples lost before t=") for n in notes) == 5, notes


@pytest.mark.parametrize("chunked", [False, True])
def test_a_line_of_words_alone_without_a_counter_is_a_message_not_a_lost_sample(chunked):
    """Attack pass 35: a device message of the full width sent without its "#" (``ERR,i2c,timeout``
    on fields=gx,gy,gz) was counted as a lost sample, a gap in t where the device lost none. A line
    in which no cell is a number is not a sample: refused and counted, t unshifted; a line of the
    full width with a number in it (``1x,0,0``, ``nan,0,0``) stays a lost sample."""
    lines = [b"0,0,0", b"ERR,i2c,timeout", b"1,0,0", b"ok,,", b"2,0,0", b"1x,0,0", b"3,0,0"]
    data = COUNTERLESS + b"\n".join(lines) + b"\n"
    parser = LineParser()
    parts = [parser.feed(data[i:i + 5]) for i in range(0, len(data), 5)] if chunked else [parser.feed(data)]
    rows = np.concatenate([*parts, parser.finish()])
    np.testing.assert_array_equal(rows[:, 1], np.arange(4))
    np.testing.assert_allclose(rows[:, 0], np.array([0, 1, 2, 4]) / 100.0)  # only 1x,0,0 was a sample
    s = parser.stats
    assert s["lost_samples"] == 1 and s["bad_lines"] + s["partial_lines"] == 3, s
