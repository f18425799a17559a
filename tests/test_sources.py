"""SOURCE syntax, the replay and simulated sources, the serial line parser, and `gyrofilter run`."""
import subprocess
import sys

import numpy as np
import pytest

from gyrofilter import GyroFilter
from gyrofilter.errors import DeviceError, SettingsError, SourceEnded
from gyrofilter.recording import Recording, read_recording, write_recording
from gyrofilter.sources import open_source, parse_source
from gyrofilter.sources.serial_protocol import LineParser


# ----------------------------------------------------------------------------- SOURCE syntax


@pytest.mark.parametrize("spec, kind, kwargs", [
    ("mpu6050", "mpu6050", {}),
    ("mpu6050:bus=3,addr=0x69,rate=1000,range=500,dlpf=3,temp=0,allow_chip=0x70", "mpu6050",
     {"bus": 3, "address": 0x69, "sample_rate_hz": 1000.0, "range_dps": 500, "dlpf": 3, "temperature": False, "allow_chip": 0x70}),
    ("serial:/dev/ttyUSB0,baud=115200", "serial", {"port": "/dev/ttyUSB0", "baudrate": 115200}),
    ("serial:/dev/ttyACM0,unit=lsb,lsb_per_dps=131,rate=100", "serial",
     {"port": "/dev/ttyACM0", "gyro_unit": "lsb", "lsb_per_dps": 131.0, "sample_rate_hz": 100.0}),
    ("/dev/ttyUSB1,baud=9600", "serial", {"port": "/dev/ttyUSB1", "baudrate": 9600}),
    ("replay:rec.csv.gz,realtime,speed=2", "replay", {"path": "rec.csv.gz", "realtime": True, "speed": 2.0}),
    ("some/rec.csv", "replay", {"path": "some/rec.csv"}),
    ("sim", "sim", {}),
    ("sim:seed=4,realtime=no,duration=10", "sim", {"seed": 4, "realtime": False, "duration_s": 10.0}),
    ("sim:model.json,seed=1", "sim", {"model": "model.json", "seed": 1}),
    ("sim,realtime=0", "sim", {"realtime": False}),          # no ARG: the keys may follow KIND directly
    ("mpu6050,rate=200", "mpu6050", {"sample_rate_hz": 200.0}),
])
def test_parse_source(spec, kind, kwargs):
    assert parse_source(spec) == (kind, kwargs)


@pytest.mark.parametrize("spec, words", [
    ("mpu6050:bux=1", ["'bux'", "known: bus"]),
    ("mpu6050:rate=fast", ["'fast'", "'rate'"]),
    ("serial:baud=9600", ["needs a port"]),
    ("serial:/dev/ttyS0,unit=furlong", ["'furlong'", "'unit'"]),
    ("replay", ["needs a path"]),
    ("sim:seed", ["'seed' needs a value"]),
    ("gps:/dev/ttyS0", ["unknown kind 'gps'"]),
    ("nothing-here", ["no such file"]),
    ("", ["empty source"]),
])
def test_parse_source_errors_name_the_problem(spec, words):
    with pytest.raises(SettingsError) as info:
        parse_source(spec)
    for word in words:
        assert word in str(info.value)


@pytest.mark.parametrize("spec, words", [
    ("sim,seed=1,seed=2", ["key 'seed' repeats key 'seed'"]),
    ("mpu6050:addr=0x68,address=0x69", ["key 'address' repeats key 'addr'"]),
    ("sim:m.json,model=n.json", ["key 'model' repeats the model"]),
    ("sim,model=", ["key 'model' has an empty value"]),
    ("replay:r.csv,realtime=", ["key 'realtime' has an empty value"]),
    ("sim,rate=1_000", ["key 'rate' must be a plain decimal number", "'1_000'"]),
    ("sim,duration=nan", ["key 'duration' must be a plain decimal number", "'nan'"]),
    ("sim,duration=1e400", ["key 'duration' must be a finite number"]),
    ("sim,seed=0b101", ["key 'seed' must be a plain decimal number"]),
    ("sim,seed=1.5", ["key 'seed' must be a whole number"]),
    ("sim,seed=" + "9" * 5000, ["key 'seed' must be a plain decimal number", "(5000 characters)"]),
    ("mpu6050:bus=-1", ["key 'bus' must be in [0, 65535]"]),
    ("mpu6050:addr=0x1000", ["key 'addr' must be in [0, 127]"]),
    ("mpu6050:allow_chip=0x123456789", ["key 'allow_chip' must be a plain decimal number"]),
    ("mpu6050:temp=maybe", ["key 'temp' must be 1/0, yes/no"]),
    ("x" * 500 + ":a", ["unknown kind", "(500 characters)"]),
])
def test_parse_source_refuses_repeated_empty_and_unplain_values_in_one_short_line(spec, words):
    """Issue 22: a repeated key used to win silently, ``model=`` to open the default model,
    ``1_000`` or 5000 digits to be read by int()/float(); every refusal is one line of at most
    300 characters that names the key."""
    with pytest.raises(SettingsError) as info:
        parse_source(spec)
    text = str(info.value)
    assert all(word in text for word in words), text
    assert text.startswith("source '") and len(text) <= 300 and "\n" not in text


def test_open_source_passes_only_given_keys_to_the_mpu6050_driver(monkeypatch):
    import gyrofilter.sources.mpu6050 as mpu

    seen = {}
    monkeypatch.setattr(mpu, "open_mpu6050", lambda **kw: seen.update(kw) or "opened")
    assert open_source("mpu6050:addr=0x69,dlpf=2", gyro_unit="lsb") == "opened"
    assert seen == {"address": 0x69, "dlpf": 2}  # gyro_unit is not an MPU6050 option: dropped


# ----------------------------------------------------------------------------- replay


def _recording(tmp_path, name="rec.csv", n=2500, gap_at=None, gap=0, notes=()):
    rng = np.random.default_rng(7)
    gyro = np.round(rng.normal(0, 30, size=(n, 3)))
    idx = np.arange(n)
    if gap_at is not None:
        idx[gap_at:] += gap
    rec = Recording.from_dps(gyro / 131.0, 100.0, t_s=idx / 100.0, temp_c=25 + idx / 1000.0,
                             header={"sensor": "MPU6050", "chip_id": "0x68"})
    rec.notes = list(notes)
    path = tmp_path / name
    write_recording(path, rec)
    return path, read_recording(path)


def _drain(source, limit=100000):
    rows, notes = [], []
    for _ in range(limit):
        try:
            rows.append(source.read())
        except SourceEnded:
            break
        notes += source.pop_notes()
    else:
        raise AssertionError("source did not end")
    return np.concatenate(rows), notes


def test_replay_gives_the_file_back_and_reports_its_gap(tmp_path):
    path, rec = _recording(tmp_path, gap_at=1234, gap=37)
    src = open_source(str(path))
    assert src.columns == ["t", "gx", "gy", "gz", "temp"]
    assert src.header["sensor"] == "MPU6050" and src.header["chip_id"] == "0x68"
    rows, notes = _drain(src)
    np.testing.assert_array_equal(rows[:, 0], rec.t_s)
    np.testing.assert_array_equal(rows[:, 1:4], rec.gyro)
    np.testing.assert_array_equal(rows[:, 4], rec.temp_c)
    assert src.stats["lost_samples"] == 37 and src.stats["gaps"] == 1
    assert notes == [f"gap: 37 samples lost before t={(1234 + 37) / 100:.6g} s (in the replayed file)"]
    with pytest.raises(SourceEnded):
        src.read()


def test_replay_passes_annotation_notes_on_at_their_row(tmp_path):
    path = tmp_path / "notes.csv"
    path.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 10\n# gyro_unit: dps\n"
                    "gx,gy,gz\n1,1,1\n2,2,2\n# something happened\n3,3,3\n")
    src = open_source(f"replay:{path}")
    first = src.read()  # no read runs past a note: it stops before the row the note precedes
    assert first.shape == (2, 4) and src.pop_notes() == []
    np.testing.assert_array_equal(first[:, 0], [0.0, 0.1])  # t made from the rate
    assert src.read().shape == (0, 4) and src.pop_notes() == ["something happened"]  # the note, then its row
    np.testing.assert_array_equal(src.read(), [[0.2, 3, 3, 3]])


def test_replay_streams_the_same_reads_whatever_the_file_chunking(tmp_path):
    """Gaps and notes land with the same reads however the file is cut into chunks (1 row, a few, all),
    and the source holds a chunk, not the file."""

    from gyrofilter.sources.replay import ReplaySource

    n = 20000
    idx = np.arange(n)
    idx[999:] += 5  # a gap before row 999 (the first read's last row) ...
    idx[1000:] += 2  # ... and one before row 1000 (the second read's first)
    idx[15321:] += 40
    gyro = np.round(np.random.default_rng(3).normal(0, 30, size=(n, 3)))
    lines = [f"{i / 100:.2f},{x:.0f},{y:.0f},{z:.0f},{25 + i / 1000:.3f}" for i, (x, y, z) in zip(idx, gyro)]
    for row in (n, 7777, 2000, 0):
        lines.insert(row, f"# {'after the last row' if row == n else f'before row {row}'}")
    path = tmp_path / "long.csv"
    path.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: lsb\n# lsb_per_dps: 131\n"
                    "t,gx,gy,gz,temp\n" + "\n".join(lines) + "\n")

    def reads(chunk_rows):
        src = ReplaySource(path, chunk_rows=chunk_rows)
        out = []
        while True:
            try:
                rows = src.read()
            except SourceEnded:
                return out, src.stats
            out.append((rows, src.pop_notes()))

    whole, stats = reads(10**6)
    assert [notes for _, notes in whole if notes] == [
        ["before row 0"], ["gap: 5 samples lost before t=10.04 s (in the replayed file)"],
        ["gap: 2 samples lost before t=10.07 s (in the replayed file)"],
        ["before row 2000"], ["before row 7777"],
        ["gap: 40 samples lost before t=153.68 s (in the replayed file)"], ["after the last row"]]
    # each note goes out with the read that starts at the row it precedes (record writes it before them)
    at, placed = 0, []
    for rows, notes in whole:
        placed += [at] * len(notes)
        at += len(rows)
    assert placed == [0, 999, 1000, 2000, 7777, 15321, n]
    assert stats["lost_samples"] == 47 and stats["gaps"] == 3
    np.testing.assert_array_equal(np.concatenate([r for r, _ in whole])[:, 1:4], gyro)
    for chunk_rows in (1, 3, 7, 1000, 4999):
        got, got_stats = reads(chunk_rows)
        assert got_stats == stats and len(got) == len(whole)
        for (rows, notes), (want_rows, want_notes) in zip(got, whole):
            np.testing.assert_array_equal(rows, want_rows)
            assert notes == want_notes


def test_replay_source_memory_does_not_grow_with_the_file(tmp_path):
    """The source holds about one block of the file, whatever its length (the old one held it all)."""
    import tracemalloc

    from gyrofilter.sources.replay import ReplaySource

    def peak_of_replay(n):
        path = tmp_path / f"r{n}.csv"
        body = "\n".join(f"{i / 1000:.3f},{i % 97 - 48},{i % 89 - 44},{i % 83 - 41},25.{i % 1000:03d}" for i in range(n))
        path.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 1000\n# gyro_unit: lsb\n# lsb_per_dps: 131\n"
                        "t,gx,gy,gz,temp\n" + body + "\n")
        del body
        tracemalloc.start()
        src = ReplaySource(path)
        total = 0
        while True:
            try:
                total += len(src.read())
            except SourceEnded:
                break
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert total == n
        return peak

    small, large = peak_of_replay(100_000), peak_of_replay(400_000)
    assert large < 1.1 * small, f"peak {large} bytes for 400 000 rows vs {small} for 100 000"


class FakeClock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now

    def sleep(self, s):
        assert 0 < s <= 0.1 + 1e-12  # a source never waits longer than 0.1 s per read
        self.now += s


def test_replay_realtime_hands_out_only_the_samples_that_are_due(tmp_path):
    from gyrofilter.sources.replay import ReplaySource

    path, rec = _recording(tmp_path, n=300)
    clock = FakeClock()
    src = ReplaySource(path, realtime=True, speed=2.0, clock=clock, sleep=clock.sleep)
    got = []
    while True:
        try:
            rows = src.read()
        except SourceEnded:
            break
        assert np.all(rows[:, 0] <= (clock.now - src._start) * 2.0 + 1e-9)  # nothing early
        got.append(rows)
        clock.now += 0.013  # the consumer's own work
    allrows = np.concatenate(got)
    np.testing.assert_array_equal(allrows[:, 1:4], rec.gyro)  # nothing lost or doubled
    assert 2.99 / 2 < clock.now - src._start < 3.0 / 2 + 0.2  # 300 samples at 100 Hz, twice as fast


# ----------------------------------------------------------------------------- simulation


def test_simulated_source_equals_the_simulator_whatever_the_pacing():
    from gyrofilter.sim.simulate import simulate
    from gyrofilter.sources.simulated import DEFAULT_MODEL, SimulatedSource

    rec = simulate(DEFAULT_MODEL, 3.0, sample_rate_hz=200.0, seed=11)
    fast, _ = _drain(open_source("sim:seed=11,duration=3,rate=200,realtime=0"))
    clock = FakeClock()
    paced_src = SimulatedSource(seed=11, duration_s=3.0, sample_rate_hz=200.0, clock=clock, sleep=clock.sleep)
    paced, _ = _drain(paced_src)
    for rows in (fast, paced):
        np.testing.assert_array_equal(rows[:, 0], rec.t_s)
        np.testing.assert_array_equal(rows[:, 1:4], rec.gyro)
        np.testing.assert_array_equal(rows[:, 4], rec.temp_c)
    assert paced_src.header["simulated_seed"] == "11" and paced_src.header["gyro_unit"] == "lsb"


def test_unseeded_simulation_records_a_seed_that_repeats_it():
    a = open_source("sim:realtime=0,duration=1")
    seed = int(a.header["simulated_seed"])
    b = open_source(f"sim:realtime=0,duration=1,seed={seed}")
    np.testing.assert_array_equal(_drain(a)[0], _drain(b)[0])


@pytest.mark.parametrize("spec, words", [
    ("mpu6050:rate=0", ["source 'mpu6050:rate=0': rate must be", "[0.001, 100000]"]),
    ("mpu6050:bus=1,range=300", ["range=300 is not an MPU6050 full scale"]),
    ("sim:seed=-1", ["source 'sim:seed=-1'", "seed must be an integer in [0, 2^63 - 1]"]),
    ("sim:seed=99999999999999999999", ["seed must be an integer in [0, 2^63 - 1], got 99999999999999999999"]),
    ("sim,rate=-3", ["source 'sim,rate=-3'", "rate must be"]),
    ("serial:/dev/null,baud=-5", ["baud rate (bit/s, e.g. 115200) must be in [50, 1.2e+07]", "got -5"]),
    ("serial:/dev/null,baud=100000000", ["baud rate (bit/s, e.g. 115200) must be in [50, 1.2e+07]", "got 100000000"]),
    ("serial:/dev/null,header_timeout=-1", ["header_timeout (s) must be in (0, 3600]", "got -1.0"]),
])
def test_an_openers_error_names_the_source_and_its_keys(spec, words):
    """A value the parser accepts but the source refuses is told in the SOURCE text's terms,
    before any device is touched (no dialout advice for a bad baud rate)."""
    with pytest.raises(SettingsError) as info:
        open_source(spec)
    text = str(info.value)
    for word in words:
        assert word in text, text
    assert "rate_hz" not in text and "range_dps" not in text and "dialout" not in text


def test_simulation_model_errors_are_settings_errors(tmp_path):
    bad = tmp_path / "m.json"
    bad.write_text('{"sample_rate_hz": 100, "axes": {"w": {}}}')
    with pytest.raises(SettingsError, match="axes.w"):
        open_source(f"sim:{bad}")
    with pytest.raises(SettingsError, match="cannot read the model file"):
        open_source(f"sim:{tmp_path / 'missing.json'}")


# ----------------------------------------------------------------------------- serial line parser

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
    from gyrofilter.sources.serial_protocol import LINE_OUTCOMES

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
    assert p.feed(_lines([2 ** 31 - 1]))[-1, 0] == (2 ** 31 - 1) / 0.001  # the largest jump: finite


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
        assert any("bad line (a gyro value beyond +-100000 deg/s or a temperature outside [-100, 200] deg C): 3,1,"
                   in note for note in p.pop_notes())


def test_parser_refuses_a_line_with_a_temperature_out_of_range_like_any_bad_line():
    """A temperature of 1e300 went on as a sample: record wrote it (replay then stopped at that
    line) and run stopped on it; it is a corrupt line, counted and skipped."""
    p = LineParser()
    rows = p.feed(HEADER + b"0,1,2,3,25.5\n1,1,2,3,1e300\n2,1,2,3,-150\n3,1,2,3,26\n")
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
    rows = p.feed(b"3,4.5,1,1\n" + b"0,0.25,0.5,-0.125\n1,1,1,1\n")
    assert p.stats["partial_lines"] == 1  # the first line may be cut: not used
    np.testing.assert_array_equal(rows[:, 1:4], [[0.25, 0.5, -0.125], [1, 1, 1]])
    np.testing.assert_allclose(rows[:, 0], [0, 0.02])
    with pytest.raises(DeviceError, match="sample_rate_hz"):
        p.feed(b"# gyrofilter-serial: 1 gyro_unit=dps sample_rate_hz=100\n")


def test_parser_header_changing_units_mid_stream_is_refused():
    p = LineParser()
    p.feed(HEADER + _lines([0, 1]))
    p.feed(HEADER + _lines([0]))  # same header again (device restart): fine
    assert p.stats["restarts"] == 1
    with pytest.raises(DeviceError, match="changed the units"):
        p.feed(HEADER.replace(b"131", b"65.5"))
    q = LineParser()
    q.feed(HEADER)
    q.feed(b"# gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps=1\xff1\n")  # garbled repeat: skipped
    assert q.stats["bad_lines"] == 1


def test_parser_first_header_errors():
    with pytest.raises(DeviceError, match="version"):
        LineParser().feed(b"# gyrofilter-serial: 2 gyro_unit=dps sample_rate_hz=1\n")
    with pytest.raises(SettingsError, match="lsb_per_dps"):
        LineParser().feed(b"# gyrofilter-serial: 1 gyro_unit=lsb sample_rate_hz=100\n")


# ----------------------------------------------------------------------------- commands


def test_help_does_not_import_device_libraries():
    code = (
        "import sys\n"
        "from gyrofilter.cli import main\n"
        "for argv in (['--help'], ['record', '--help'], ['run', '--help']):\n"
        "    try:\n"
        "        main(argv)\n"
        "    except SystemExit:\n"
        "        pass\n"
        "bad = [m for m in ('serial', 'smbus2') if m in sys.modules]\n"
        "print('IMPORTED', bad)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert "IMPORTED []" in out.stdout, out.stdout + out.stderr
    assert "serial:/dev/ttyUSB0" in out.stdout  # the SOURCE syntax is in --help


def test_run_on_a_replay_equals_the_batch_filter(tmp_path, capsys):
    from gyrofilter.cli import main

    path, rec = _recording(tmp_path, n=1000)
    out = tmp_path / "filtered.csv.gz"
    assert main(["run", "--source", str(path), "--out", str(out), "--quiet"]) == 0
    got = read_recording(out)
    want = GyroFilter(100.0, 2.0).filter(rec.gyro_dps)  # run and the library have the same default preset
    assert len(got) == len(want) == (1000 - 200) // 5
    np.testing.assert_allclose(got.gyro_dps, want, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(got.t_s, rec.t_s[200 + 4 :: 5][: len(want)])
    assert got.sample_rate_hz == 20.0
    err = capsys.readouterr().err
    assert "1000 samples in, 160 filtered rows out" in err
    # stdout is a readable recording too
    assert main(["run", "--source", str(path), "--quiet"]) == 0
    text = capsys.readouterr().out
    stdout_rec = (tmp_path / "stdout.csv")
    stdout_rec.write_text(text)
    np.testing.assert_allclose(read_recording(stdout_rec).gyro, got.gyro)


def test_run_refuses_to_overwrite_and_reports_bad_sources(tmp_path, capsys):
    from gyrofilter.cli import main

    path, _ = _recording(tmp_path, n=300)
    out = tmp_path / "exists.csv"
    out.write_text("keep me")
    assert main(["run", "--source", str(path), "--out", str(out)]) == 2
    assert out.read_text() == "keep me"
    assert main(["run", "--source", "mpu6050:speed=3"]) == 2
    err = capsys.readouterr().err
    assert "--force" in err and "unknown key 'speed'" in err


def test_parser_with_options_uses_a_header_that_comes_first():
    p = LineParser(gyro_unit="lsb", lsb_per_dps=131, sample_rate_hz=100)
    rows = p.feed(HEADER + _lines([0, 1]))  # the header is a whole line: nothing is dropped
    np.testing.assert_array_equal(rows[:, 1:4], _expected([0, 1]))
    assert p.stats["partial_lines"] == 0 and p.header["sensor"] == "MPU6050"


def test_sources_state_their_units_as_numbers_and_close_once(tmp_path):
    """The Source base: sample_rate_hz, gyro_unit, lsb_per_dps as attributes (the numbers, not
    header text), gyro_dps converts like Recording.gyro_dps, close() twice and `with` are safe."""
    from gyrofilter.sources.base import Source

    path = tmp_path / "lsb.csv"
    rec = Recording(columns={"gx": np.arange(10.0), "gy": -np.arange(10.0), "gz": np.zeros(10)},
                    header={"gyrofilter-recording": "1", "sample_rate_hz": "142.857142857142861",
                            "gyro_unit": "lsb", "lsb_per_dps": "65.5"})
    write_recording(path, rec)
    back = read_recording(path)
    for spec in (f"replay:{path}", "sim:realtime=0,duration=1,seed=2"):
        with open_source(spec) as src:
            assert isinstance(src, Source) and isinstance(src.sample_rate_hz, float)
            assert src.gyro_unit == src.header["gyro_unit"] == "lsb" and src.lsb_per_dps in (65.5, 131.0)
            rows = src.read()
            np.testing.assert_array_equal(src.gyro_dps(rows), rows[:, 1:4] / src.lsb_per_dps)
        src.close()  # closed already: nothing happens
        with pytest.raises(SourceEnded):
            src.read()
    assert open_source(f"replay:{path}").sample_rate_hz == back.sample_rate_hz == 1000.0 / 7


def test_the_sim_source_takes_a_seed_beyond_2_53_exactly():
    """seed=9007199254740993 went through float and became ...992: other data than
    simulate --seed 9007199254740993, which formats.md says the sim source hands out."""
    a = open_source("sim,seed=9007199254740993,realtime=0,duration=0.2")
    b = open_source("sim,seed=9007199254740992,realtime=0,duration=0.2")
    assert a.seed == 9007199254740993 and b.seed == 9007199254740992
    with a, b:
        assert not np.array_equal(a.read(), b.read())
