"""SOURCE syntax, and the replay and simulated sources."""

import numpy as np
import pytest

from gyrofilter.errors import SettingsError, SourceEnded
from gyrofilter.recording import Recording, read_recording, write_recording
from gyrofilter.sources import open_source, parse_source
from support import lsb_recording


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
    # issue 37: '=' in a partitioned folder's name is the path's, not a key's
    ("replay:data/date=2024-01-01/imu.csv.gz,realtime", "replay", {"path": "data/date=2024-01-01/imu.csv.gz", "realtime": True}),
    ("data/Date=2024-01-01/imu.csv.gz", "replay", {"path": "data/Date=2024-01-01/imu.csv.gz"}),
    ("sim:models/v=2.json,seed=1", "sim", {"model": "models/v=2.json", "seed": 1}),
])
def test_parse_source(spec, kind, kwargs):
    assert parse_source(spec) == (kind, kwargs)


@pytest.mark.parametrize("spec, path, rest", [
    ("replay:{d}/a,b/imu,2.csv.gz", "{d}/a,b/imu,2.csv.gz", {}),
    ("replay:{d}/a,b/imu,2.csv.gz,realtime,speed=3", "{d}/a,b/imu,2.csv.gz", {"realtime": True, "speed": 3.0}),
    ("{d}/a,b/imu,2.csv.gz,speed=3", "{d}/a,b/imu,2.csv.gz", {"speed": 3.0}),
    ("replay:{d}/x=1,y/imu.csv.gz,realtime", "{d}/x=1,y/imu.csv.gz", {"realtime": True}),
])
def test_a_file_whose_path_holds_commas_is_taken_whole(tmp_path, spec, path, rest):
    """Attack pass (issue 37): ``replay:logs/a,b/imu.csv.gz`` (a comma in a folder's or file's name)
    was split at the comma ("'b/imu' is not a key of replay"): no SOURCE could name that file. The
    path is the longest comma-joined start that is an existing file; what follows is keys."""
    for folder in ("a,b", "x=1,y"):
        (tmp_path / folder).mkdir()
    for name in ("a,b/imu,2.csv.gz", "x=1,y/imu.csv.gz"):
        (tmp_path / name).write_bytes(b"")
    assert parse_source(spec.format(d=tmp_path)) == ("replay", {"path": path.format(d=tmp_path), **rest})
    with pytest.raises(SettingsError, match="unknown key 'sped' for replay"):
        parse_source(spec.format(d=tmp_path) + ",sped=3")


@pytest.mark.parametrize("spec, words", [
    ("mpu6050:bux=1", ["'bux'", "known: bus"]),
    ("sim:sed=1", ["unknown key 'sed' for sim"]),     # a mistyped key is no file name
    ("replay:bux=1", ["unknown key 'bux' for replay"]),
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
    import gyrofilter.sources.mpu6050.driver as mpu

    seen = {}
    monkeypatch.setattr(mpu, "open_mpu6050", lambda **kw: seen.update(kw) or "opened")
    assert open_source("mpu6050:addr=0x69,dlpf=2", gyro_unit="lsb") == "opened"
    assert seen == {"address": 0x69, "dlpf": 2}  # gyro_unit is not an MPU6050 option: dropped


# ----------------------------------------------------------------------------- replay


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
    path, rec = lsb_recording(tmp_path, gap_at=1234, gap=37)
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

    path, rec = lsb_recording(tmp_path, n=300)
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


def test_a_paced_simulation_starts_its_clock_at_its_first_sample():
    """Issue 38: ``run --source sim`` reported 0.3 samples/s and then 390.7 (nominal 100): the
    pacing clock started before the first block was simulated, so the time that took came out
    as a backlog handed out at once. A first block that takes 3 s now delays the start instead."""
    from gyrofilter.sources.simulated import SimulatedSource

    clock = FakeClock()
    src = SimulatedSource(seed=11, duration_s=10.0, sample_rate_hz=100.0, clock=clock, sleep=clock.sleep)
    make_block = src._more

    def slow_first_block():
        clock.now += 3.0 if src.stats["samples"] == 0 and not len(src._buf) else 0.0
        return make_block()

    src._more = slow_first_block
    first_two_reads = len(src.read()) + len(src.read())
    assert first_two_reads <= 5, first_two_reads  # the 300 samples of those 3 s came out at once


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


# ----------------------------------------------------------------------------- commands


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


def test_a_file_in_a_partitioned_folder_is_recorded(tmp_path, monkeypatch):
    """Issue 37: a SOURCE path holding '=' (date=2024-01-01/) could not be given at all; an
    existing file named key=value is taken too, relative to the working folder."""
    from gyrofilter.cli import main

    folder = tmp_path / "date=2024-01-01"
    folder.mkdir()
    rec = Recording.from_dps(np.random.default_rng(11).normal(0, 0.05, (500, 3)), 100.0)
    write_recording(folder / "imu.csv", rec)
    write_recording(tmp_path / "v=2", rec)
    write_recording(tmp_path / "speed=2.csv", rec)  # named as a key of replay: the existing file wins (pass 12)
    monkeypatch.chdir(tmp_path)
    for source in (f"replay:{folder / 'imu.csv'}", "date=2024-01-01/imu.csv", "replay:v=2,realtime=0",
                   "speed=2.csv", "replay:speed=2.csv,speed=3"):
        out = tmp_path / "out.csv"
        assert main(["record", "--source", source, "--out", str(out), "--force"]) == 0, source
        np.testing.assert_array_equal(read_recording(out).gyro_dps, rec.gyro_dps)


@pytest.mark.parametrize("speed, said", [(np.float32(2.0), None), (np.array(2.0), None), (0, "replay speed must be >= 0.001"),
                                         (1e-300, "replay speed must be >= 0.001, got 1e-300"),
                                         (float("nan"), "replay speed must be a finite number"),
                                         (True, "replay speed must be a finite number"), ("2", "replay speed must be a finite number")])
def test_a_numpy_speed_is_the_number_it_holds(tmp_path, speed, said):
    """Attack pass 29b: ReplaySource(speed=np.float32(2.0)) was refused as "must be a positive
    number, got 2.0"; True was taken as 1. Pass 59: speed=1e-300 waited 1e298 s for the first sample."""
    from gyrofilter.sources.replay import ReplaySource
    path = tmp_path / "r.csv"
    write_recording(path, Recording.from_dps(np.zeros((20, 3)), 100.0))
    if said is None:
        with ReplaySource(path, realtime=True, speed=speed) as source:
            assert source.speed == 2.0
    else:
        with pytest.raises(SettingsError, match=said):
            ReplaySource(path, speed=speed)


@pytest.mark.parametrize("duration", ["5", True, 0, -0.0, float("nan"), 1e300])
def test_a_simulated_source_checks_its_duration_as_simulate_does(duration):
    """Attack pass 29b: SimulatedSource(duration_s="5") ended in Python's "must be real number,
    not str", and True ran 1 s."""
    from gyrofilter.sources.simulated import SimulatedSource
    with pytest.raises(SettingsError, match="sim: duration_s must be"):
        SimulatedSource(duration_s=duration, realtime=False, seed=1)


def test_a_simulated_sources_model_warnings_reach_the_user(tmp_path, capsys):
    """Attack pass 37a: `record`/`run`/`report --source sim:MODEL` kept the model's warnings (a misspelt parameter
    ignored, a frequency that aliases, per-sample parameters at another rate) in the source and never said them:
    `phase_radd` ran the sinusoid at phase 0 without a word, where `simulate` warns. They are the source's first notes,
    warnings on stderr and in the file, as a replayed file's are."""
    from gyrofilter.cli import main

    model = tmp_path / "typo.json"
    model.write_text('{"sample_rate_hz": 100, "axes": {"x": {"arw_dps_per_sqrt_hz": 0.01, "effects": [{"effect": '
                     '"sinusoid", "frequency_hz": 7, "amplitude_dps": 1, "phase_radd": 1.5}]}}}')
    out = tmp_path / "r.csv"
    assert main(["record", "--source", f"sim:{model},seed=1,realtime=0", "--duration", "1", "--out", str(out)]) == 0
    said = f"sim: {model}: model: axes.x.effects[0] (sinusoid): unknown parameter 'phase_radd' ignored; did you mean phase_rad?"
    assert said in " ".join(capsys.readouterr().err.split())
    assert f"# warning: {said}" in out.read_text()
