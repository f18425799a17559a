"""`gyrofilter record` in a subprocess, stopped by SIGINT, SIGTERM and SIGKILL mid-run.

The source is a seeded simulation paced in real time (or a paced replay), so the test knows
every sample the source delivered; whatever the signal, the file reads back and its samples
equal the source's from the first one up to the last flush.
"""
import os
import re
import resource
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from gyrofilter.cli import main
from gyrofilter.errors import RecordingError
from gyrofilter.recording import Recording, read_recording, write_recording
from gyrofilter.sim.simulate import simulate
from gyrofilter.sources.simulated import DEFAULT_MODEL, DEFAULT_MODEL_PATH
from support import RECORDINGS, play_lossy_device, play_serial_then_stop

SIM_SECONDS = 60.0  # the source's own length; the recording is stopped long before
RATE_HZ = 500.0


def start_record(source, out, *extra):
    cmd = [sys.executable, "-m", "gyrofilter", "record", "--source", source, "--out", str(out), *extra]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_for_rows(path, rows, proc, timeout_s=30.0):
    """Wait until the file on disk (flushed data only) holds at least ``rows`` samples."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise AssertionError(f"record exited early ({proc.returncode}): {proc.stderr.read()}")
        try:
            if len(read_recording(path)) >= rows:
                return
        except (RecordingError, OSError):
            pass  # not written yet
        time.sleep(0.1)
    raise AssertionError(f"{path} did not reach {rows} rows in {timeout_s} s")


@pytest.fixture(scope="module")
def expected():
    return simulate(DEFAULT_MODEL, SIM_SECONDS, sample_rate_hz=RATE_HZ, seed=21)


@pytest.mark.parametrize("sig, name, suffix", [
    (signal.SIGINT, "SIGINT", ".csv.gz"), (signal.SIGKILL, "SIGKILL", ".csv"),  # the other four pairs are slow
    (signal.SIGHUP, "SIGHUP", ".csv"),  # a dropped SSH session: exit 130 without the end note (issue 22, hostile 5-11)
    *(pytest.param(sig, name, suffix, marks=pytest.mark.slow) for sig, name, suffix in [
        (signal.SIGTERM, "SIGTERM", ".csv.gz"), (signal.SIGKILL, "SIGKILL", ".csv.gz"),
        (signal.SIGINT, "SIGINT", ".csv"), (signal.SIGTERM, "SIGTERM", ".csv")])])
def test_record_stopped_by_a_signal_keeps_a_readable_exact_prefix(tmp_path, expected, sig, name, suffix):
    out = tmp_path / f"rec{suffix}"
    proc = start_record(f"sim:seed=21,rate={RATE_HZ:g},duration={SIM_SECONDS:g}", out)
    try:
        wait_for_rows(out, 300, proc)
        flushed_before = len(read_recording(out))
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    rec = read_recording(out)
    n = len(rec)
    assert n >= flushed_before >= 300  # nothing that had been flushed is lost
    np.testing.assert_array_equal(rec.gyro, expected.gyro[:n])
    np.testing.assert_allclose(rec.t_s, expected.t_s[:n], rtol=0, atol=1e-9)
    np.testing.assert_allclose(rec.temp_c, expected.temp_c[:n], rtol=0, atol=5e-5)  # written with 4 decimals
    for key in ("sample_rate_hz", "gyro_unit", "lsb_per_dps", "sensor", "start_time_utc", "simulated_seed"):
        assert key in rec.header
    if sig == signal.SIGKILL:
        assert proc.returncode == -signal.SIGKILL
        # at most the data since the last flush is missing; a cut line/stream is only a warning
        assert all("interrupted" in w or "cut short" in w for w in rec.warnings)
    else:
        assert proc.returncode == 0, err
        assert rec.warnings == []  # closed cleanly
        assert rec.notes[-1][1].startswith(f"end: stopped by {name}")
        assert f"stopped by {name}" in err and f"wrote {n} samples" in err and "lost 0 samples" in err


def _file_size_limit(limit_bytes):
    """preexec_fn: files of this process may grow to ``limit_bytes`` (a write beyond fails with EFBIG)."""
    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))
    return limit


@pytest.mark.parametrize("suffix, limit_bytes", [(".csv", 30_000), (".csv.gz", 12_000)])
def test_record_that_cannot_write_keeps_the_flushed_samples_and_says_how_many(tmp_path, expected, suffix, limit_bytes):
    """Issue 22 (6): a write error (here the file size limit) deleted the samples already written."""
    out = tmp_path / f"rec{suffix}"
    proc = subprocess.run([sys.executable, "-m", "gyrofilter", "record", "--source",
                           f"sim:seed=21,rate={RATE_HZ:g},duration={SIM_SECONDS:g}", "--out", str(out)],
                          capture_output=True, text=True, timeout=60, preexec_fn=_file_size_limit(limit_bytes))
    assert proc.returncode == 2
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    kept = re.fullmatch(rf"gyrofilter: error: {re.escape(str(out))}: File too large; kept the first (\d+) samples", lines[0])
    assert kept, lines[0]
    n = int(kept.group(1))
    rec = read_recording(out)
    assert len(rec) == n > 0 and os.path.getsize(out) <= limit_bytes
    np.testing.assert_array_equal(rec.gyro, expected.gyro[:n])
    if suffix == ".csv":
        assert rec.warnings == [] and out.read_bytes().endswith(b"\n")  # whole lines only
    else:
        assert all("interrupted" in w or "cut short" in w for w in rec.warnings)  # a gzip stream without its end
    assert os.listdir(tmp_path) == [out.name]


def test_record_duration_and_replay_source(tmp_path):
    rng = np.random.default_rng(2)
    n = 1000
    idx = np.arange(n)
    idx[600:] += 25  # the replayed file has a gap of 25 samples
    src_rec = Recording.from_dps(np.round(rng.normal(0, 40, (n, 3))) / 131.0, 200.0, t_s=idx / 200.0)
    src_path = tmp_path / "src.csv"
    write_recording(src_path, src_rec)
    out = tmp_path / "out.csv"
    proc = subprocess.run([sys.executable, "-m", "gyrofilter", "record", "--source", f"replay:{src_path}",
                           "--out", str(out), "--duration", "3.5"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    rec = read_recording(out)
    keep = idx / 200.0 < 3.5
    assert len(rec) == keep.sum() == 675
    np.testing.assert_allclose(rec.gyro_dps, src_rec.gyro_dps[keep], rtol=1e-8)
    texts = [t for _, t in rec.notes]
    assert texts[0] == "gap: 25 samples lost before t=3.125 s (in the replayed file)"
    assert texts[-1].startswith("end: duration reached")
    assert "lost 25 samples" in proc.stderr
    # the file is not overwritten without --force
    again = subprocess.run([sys.executable, "-m", "gyrofilter", "record", "--source", f"replay:{src_path}",
                            "--out", str(out)], capture_output=True, text=True, timeout=60)
    assert again.returncode == 2 and "--force" in again.stderr and "Traceback" not in again.stderr
    assert len(read_recording(out)) == 675


def test_record_paced_replay_killed_mid_run(tmp_path):
    """A replayed real log, paced 5x: SIGTERM mid-run gives the file's first samples exactly."""
    src_path = str(RECORDINGS / "mpu6050_static_100s.csv.gz")
    if not os.path.exists(src_path):
        pytest.skip("recordings/mpu6050_static_100s.csv.gz not present")
    src = read_recording(src_path)
    out = tmp_path / "replayed.csv.gz"
    proc = start_record(f"replay:{src_path},realtime,speed=5", out)
    try:
        wait_for_rows(out, 200, proc)
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0
    rec = read_recording(out)
    n = len(rec)
    assert 200 <= n < len(src)
    np.testing.assert_array_equal(rec.gyro, src.gyro[:n])
    assert rec.header["lsb_per_dps"] == "131" and rec.header["live_source"].startswith("replay:")


def test_record_from_the_mpu6050_register_model(tmp_path, monkeypatch, capsys):
    """`record --source mpu6050:...` through the real driver and smbus2, with the register-level
    model behind smbus2's ioctl: the header carries what an analysis needs, and the samples are
    the model's, contiguous (nothing lost or doubled), on the sensor's clock."""
    from gyrofilter.sources.mpu6050.model import FakeI2CBus, MPU6050Model, VirtualClock

    import gyrofilter.sources.mpu6050.driver as mpu
    from gyrofilter.cli import main

    clock = VirtualClock()
    table = np.random.default_rng(9).integers(-30000, 30000, size=(4000, 3))
    model = MPU6050Model(clock, gyro_lsb=table, temp_c=31.0)
    FakeI2CBus({0x68: model}, clock=clock).install(monkeypatch)
    real_open = mpu.open_mpu6050
    monkeypatch.setattr(mpu, "open_mpu6050", lambda **kw: real_open(clock=clock.now, sleep=clock.sleep, **kw))
    model.fail(121, times=2)  # two transient NACKs during start-up: retried, counted
    out = tmp_path / "mpu.csv.gz"
    code = main(["record", "--source", "mpu6050:bus=1,addr=0x68,rate=200,range=500,dlpf=3", "--out", str(out), "--duration", "5"])
    assert code == 0
    rec = read_recording(out)
    head = rec.header
    assert (head["sensor"], head["sample_rate_hz"], head["gyro_unit"], head["lsb_per_dps"]) == ("MPU6050", "200", "lsb", "65.5")
    assert head["full_scale_dps"] == "500" and head["dlpf_cfg"] == "3" and "chip_id" in head and "start_time_utc" in head
    assert len(rec) == 1000  # 5 s at 200 Hz
    k0 = int(np.flatnonzero((table == rec.gyro[0]).all(axis=1))[0])
    np.testing.assert_array_equal(rec.gyro, table[(k0 + np.arange(1000)) % len(table)])
    np.testing.assert_allclose(rec.t_s - rec.t_s[0], np.arange(1000) / 200.0, atol=1e-9)
    np.testing.assert_allclose(rec.temp_c, 31.0, atol=1 / 340)
    assert "retries 2" in capsys.readouterr().err


class _FailingSource:
    """Delivers 3 reads of 10 rows and a gap note, then fails like an unplugged I2C device."""

    header = {"sample_rate_hz": "100", "gyro_unit": "dps", "sensor": "test"}
    sample_rate_hz, gyro_unit, lsb_per_dps = 100.0, "dps", None
    columns = ["t", "gx", "gy", "gz"]

    def __init__(self):
        self.reads = 0
        self.stats = {"samples": 0, "lost_samples": 0, "retries": 4}
        self.closed = False

    def read(self):
        from gyrofilter.errors import DeviceError

        if self.reads == 3:
            raise DeviceError("MPU6050 at /dev/i2c-1 0x68: read failed after 5 retries (errno 121)")
        k = np.arange(10 * self.reads, 10 * self.reads + 10)
        self.reads += 1
        self.stats["samples"] += 10
        return np.column_stack([k / 100.0, k, -k, k * 0.5])

    def pop_notes(self):
        return ["gap: 0 samples lost (test note)"] if self.reads == 2 else []

    def close(self):
        self.closed = True


def test_record_keeps_everything_when_the_device_fails(tmp_path, monkeypatch, capsys):
    import gyrofilter.cli.live as live
    from gyrofilter.cli import main

    src = _FailingSource()
    monkeypatch.setattr(live, "open_source", lambda spec, **kw: src)
    out = tmp_path / "fail.csv"
    assert main(["record", "--source", "mpu6050", "--out", str(out)]) == 1
    rec = read_recording(out)
    assert rec.warnings == [] and src.closed
    np.testing.assert_array_equal(rec.columns["gx"], np.arange(30))
    texts = [t for _, t in rec.notes]
    assert texts[0] == "gap: 0 samples lost (test note)"
    assert texts[-1].startswith("end: stopped: device error: MPU6050 at /dev/i2c-1 0x68: read failed")
    err = capsys.readouterr().err
    assert "wrote 30 samples (0.30 s at 100 Hz" in err and "retries 4" in err


def test_record_of_a_simulation_with_duration_equals_simulate(tmp_path, capsys):
    """sim without duration= and record --duration D: the samples, temperatures and header of
    simulate --duration D (the model's terms depend on the run's length)."""
    from gyrofilter.cli import main

    model = str(DEFAULT_MODEL_PATH)
    sim, out = tmp_path / "sim.csv", tmp_path / "rec.csv"
    assert main(["simulate", "--model", model, "--duration", "3", "--seed", "5", "--out", str(sim)]) == 0
    assert main(["record", "--source", f"sim:{model},seed=5,realtime=0", "--duration", "3", "--out", str(out)]) == 0
    a, b = read_recording(sim), read_recording(out)
    np.testing.assert_array_equal(b.columns["t"], a.columns["t"])
    np.testing.assert_array_equal(b.gyro, a.gyro)
    np.testing.assert_array_equal(b.temp_c, a.temp_c)
    assert b.header["simulated_duration_s"] == a.header["simulated_duration_s"] == "3"


def test_record_creates_missing_folders(tmp_path):
    from gyrofilter.cli import main

    out = tmp_path / "new" / "folder" / "rec.csv.gz"
    assert main(["record", "--source", "sim:seed=1,realtime=0,duration=1", "--out", str(out)]) == 0
    assert len(read_recording(out)) == 100


def test_quiet_keeps_the_status_line_off_a_terminal(tmp_path):
    """The status line shows on a terminal (a real pseudo-terminal here) unless --quiet."""
    seen = {}
    for extra in ([], ["--quiet"]):
        primary, secondary = os.openpty()
        out = tmp_path / f"rec{len(extra)}.csv"
        cmd = [sys.executable, "-m", "gyrofilter", "record", "--source", "sim:realtime=1,seed=1,rate=200",
               "--duration", "2.5", "--out", str(out), *extra]
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=secondary, timeout=60)
        os.close(secondary)
        chunks = []
        while True:
            try:
                data = os.read(primary, 4096)
            except OSError:  # EIO: the terminal's other end is closed and drained
                break
            if not data:
                break
            chunks.append(data)
        os.close(primary)
        assert proc.returncode == 0
        seen[bool(extra)] = b"".join(chunks).decode(errors="replace")
        assert len(read_recording(out)) == 500
    assert "samples/s (nominal 200)" in seen[False]
    assert "samples/s" not in seen[True]


def test_record_of_a_replay_keeps_every_note_at_its_row_and_adds_no_gap_note_twice(tmp_path):
    """The replay source handed a read's notes out with rows up to 1000 past them, so record wrote
    them early (a note before row 10 came before row 0), and each re-recording added another copy
    of the file's own gap note."""
    t = np.arange(3000) / 100.0
    t[1500:] += 0.05  # 5 samples lost before row 1500
    rows = "".join(f"{ti!r},1,2,{k}\n" + ("# marker before row 10\n" if k == 9 else "") for k, ti in enumerate(t.tolist()))
    src = tmp_path / "in.csv"
    src.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\nt,gx,gy,gz\n" + rows)
    for generation in (1, 2):
        out = tmp_path / f"gen{generation}.csv"
        assert main(["record", "--source", f"replay:{src}", "--out", str(out), "--quiet"]) == 0
        rec = read_recording(out)
        notes = {text.split(" (")[0]: note.row for note in rec.notes for text in [note.text] if not text.startswith("end:")}
        assert notes == {"marker before row 10": 10, "gap: 5 samples lost before t=15.05 s": 1500}, rec.notes
        np.testing.assert_array_equal(rec.t_s, t)
        src = out


def test_a_source_failing_midway_says_in_its_one_error_line_what_the_recording_kept(tmp_path, monkeypatch, capsys):
    """record --force of a replay with a bad line far in exited 2 with only the input's error,
    its output already holding the rows before it: the one error line now says so."""
    monkeypatch.setattr("gyrofilter.cli.live.FLUSH_INTERVAL_S", 0.0)
    n = 70000  # the bad line lies beyond the reader's first chunk
    lines = [f"{k % 7},1,2" for k in range(n)]
    lines[n - 5] = "1,x,2"
    src = tmp_path / "bad.csv"
    src.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\ngx,gy,gz\n" + "\n".join(lines) + "\n")
    out = tmp_path / "out.csv"
    out.write_text("old")
    assert main(["record", "--source", f"replay:{src}", "--out", str(out), "--force", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    kept = len(read_recording(out))
    assert len(err) == 1 and f"line {n - 5 + 5}: column 'gy' is not a number" in err[0], err
    assert err[0].endswith(f"{out}: kept the first {kept} samples") and 0 < kept < n - 5


def test_a_recording_replaced_by_another_command_while_it_runs_is_told(tmp_path):
    """record kept writing to a file another command had replaced (--force): it said 'wrote N
    samples to live.csv' while live.csv held the other command's data."""
    from gyrofilter.cli import live

    out = tmp_path / "live.csv"
    writer = live.LiveOutput(str(out), {"sample_rate_hz": 100, "gyro_unit": "dps"}, ["gx", "gy", "gz"], None, "sample")
    writer.write(np.ones((10, 3)))
    writer.flush()  # published under its name
    other = tmp_path / "other.csv"
    write_recording(other, Recording.from_dps(np.zeros((3, 3)), 100.0))
    os.replace(other, out)
    with pytest.raises(FileExistsError, match="was replaced by another program while this command wrote it: its 10 samples"):
        writer.close(failed=False)
    assert len(read_recording(out)) == 3


@pytest.mark.parametrize("old", [None, "precious\n"])
def test_a_recording_without_a_sample_is_refused_and_leaves_no_file(tmp_path, capsys, old):
    """``--duration`` shorter than one sample wrote a header alone and exited 0: a file no command
    reads (they all say "no samples"). Now exit 2 with one line naming the source and the duration;
    no file, or the one ``--force`` would have replaced left as it was."""
    out = tmp_path / "r.csv"
    if old is not None:
        out.write_text(old)
    args = ["record", "--source", "sim", "--duration", "0.001", "--out", str(out)] + (["--force"] if old else [])
    assert main(args) == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    left = f"{out} is left as it was" if old else f"the empty {out} is not kept"
    assert last == f"gyrofilter: error: sim: no sample was recorded in --duration 0.001 s; {left}"
    assert os.listdir(tmp_path) == (["r.csv"] if old else [])
    assert old is None or out.read_text() == old


def _header_only_serial(out, *extra):
    """``record`` in a subprocess on a real pseudo-terminal whose device sends its header (with
    ``fields``, so the source opens) and then no sample. Returns the process and the terminal's end."""
    primary, secondary = os.openpty()
    port = os.ttyname(secondary)
    proc = start_record(f"serial:{port},header_timeout=20", out, "--quiet", *extra)
    assert os.read(primary, 1) == b"?"  # the port is open (and its input flushed): the source asks for the header
    os.write(primary, b"# gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps=131 sample_rate_hz=100 fields=counter,gx,gy,gz\n")
    return proc, primary, port, secondary


@pytest.mark.parametrize("lines, counts", [(b"", "lines 1, headers 1"),
                                           (b"".join(b"%d,99999999,0,0\n" % i for i in range(50)),
                                            "lines 51, bad lines 50, headers 1")])
def test_a_stop_before_the_first_sample_says_what_stopped_it_not_the_duration(tmp_path, lines, counts):
    """A --duration of 60 s that a SIGTERM ends before the device sent a sample said "no sample
    was recorded in --duration 60 s", as if the duration had run out: the line names the stop.
    Attack pass 25: and the source's counts: a device whose every line is refused (here a rate
    beyond +-100000 deg/s; a raw temperature sent without ``temp_unit`` alike) said no more, the
    file and its notes saying why not kept."""
    out = tmp_path / "r.csv"
    proc, primary, port, secondary = _header_only_serial(out, "--duration", "60")
    try:
        os.write(primary, lines)
        time.sleep(1.0)  # a stop before the first sample, whenever it comes
        proc.send_signal(signal.SIGTERM)
        err = proc.communicate(timeout=30)[1]
    finally:
        os.close(primary)
        os.close(secondary)
    assert proc.returncode == 2, err
    assert err.strip().splitlines() == [
        f"gyrofilter: error: serial:{port},header_timeout=20: no sample was recorded (stopped by SIGTERM); "
        f"{counts}; the empty {out} is not kept"]
    assert os.listdir(tmp_path) == []


def test_a_source_that_ends_at_once_is_named_as_the_cause_not_the_duration(tmp_path, capsys):
    """A header-only recording replayed with --duration 10: the source ended, the duration did not."""
    src = tmp_path / "header_only.csv"
    src.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\nt,gx,gy,gz\n")
    out = tmp_path / "r.csv"
    assert main(["record", "--source", str(src), "--duration", "10", "--out", str(out)]) == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last == (f"gyrofilter: error: {src}: no sample was recorded (source ended: end of {src} (0 samples)); "
                    f"the empty {out} is not kept")
    assert sorted(os.listdir(tmp_path)) == ["header_only.csv"]


def test_no_sample_leaves_no_folder_the_recording_made(tmp_path, capsys):
    """--out in folders that do not exist yet: record makes them for the file; when no file is
    kept (no sample, or the device failing before the first) the folders it made go too, and
    a folder that existed stays."""
    (tmp_path / "had").mkdir()
    assert main(["record", "--source", "sim", "--duration", "0.001", "--out", str(tmp_path / "new" / "sub" / "r.csv")]) == 2
    assert main(["record", "--source", "sim", "--duration", "0.001", "--out", str(tmp_path / "had" / "sub" / "r.csv")]) == 2
    assert sorted(os.listdir(tmp_path)) == ["had"] and os.listdir(tmp_path / "had") == []
    out = tmp_path / "gone" / "r.csv"
    proc, primary, port, secondary = _header_only_serial(out)
    deadline = time.monotonic() + 30
    while not out.parent.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)  # the source is open and the recording started
    os.close(primary)  # the device goes away before its first sample
    err = proc.communicate(timeout=30)[1]
    os.close(secondary)
    assert proc.returncode == 1 and f"{out}: not written, no sample was kept" in err, err
    assert sorted(os.listdir(tmp_path)) == ["had"]


@pytest.mark.parametrize("command, suffix, row_name", [("record", ".csv", "sample"), ("run", ".csv", "filtered row")])
def test_a_disk_that_fills_at_the_last_flush_names_the_file_and_what_it_kept(tmp_path, command, suffix, row_name):
    """Issue 37 (4): the file size limit just below the whole file's size fails the last flush,
    at the close (a plain file: its size does not depend on when the flushes came): one line
    naming the file and what it kept, which reads back; no hidden
    partial file is left (it was "[Errno 27] File too large" alone). ``--quiet``: on a loaded
    machine the run lasts over a second and ``run``'s status line would come first."""
    args = [command, "--source", "sim:seed=4,realtime=0,duration=20", "--quiet"]
    whole = tmp_path / f"whole{suffix}"
    assert main(args + ["--out", str(whole)]) == 0
    (tmp_path / "cut").mkdir()
    out = tmp_path / "cut" / f"out{suffix}"
    proc = subprocess.run([sys.executable, "-m", "gyrofilter", *args, "--out", str(out)], capture_output=True,
                          text=True, timeout=60, preexec_fn=_file_size_limit(os.path.getsize(whole) - 4))
    lines = proc.stderr.splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    said = re.fullmatch(rf"gyrofilter: error: {re.escape(str(out))}: File too large; "
                        rf"(kept the first (\d+) {row_name}s|not written, no {row_name} was kept)", lines[0])
    assert said, lines[0]
    if said.group(2):
        n = int(said.group(2))
        assert os.listdir(out.parent) == [out.name]
        np.testing.assert_array_equal(read_recording(out).gyro, read_recording(whole).gyro[:n])
    else:
        assert os.listdir(out.parent) == []



@pytest.mark.parametrize("lines, delivered, steps_s, duration_s, fields", [
    pytest.param(b"5,0,0,0\n6,nan,0,0\n7,0.1,0.2,0.3\n", [[0, 0, 0], [0.1, 0.2, 0.3]], [0.02, 0.01], 3, b"",
                 id="one of three lost, a short file"),
    pytest.param(b"5,0,0,0\n6,nan,0,0\n7,0.1,0.2,0.3\n8,nan,0,0\n9,0.4,0.5,0.6\n",
                 [[0, 0, 0], [0.1, 0.2, 0.3], [0.4, 0.5, 0.6]], [0.02, 0.02, 0.01], 22, b"",
                 id="two of five lost, windows"),
    # attack pass 33b: without a counter a refused line of the full width is a lost sample too (not
    # dropped with every later t one interval early); a line of another width changes no t
    pytest.param(b"0,0,0\nnan,0,0\n0.1,0.2,0.3\n200000,0,0\n0.4,0.5,0.6\n1,2\n0.7,0.8,0.9\n1.2.3,0,0\n",
                 [[0, 0, 0], [0.1, 0.2, 0.3], [0.4, 0.5, 0.6], [0.7, 0.8, 0.9]], [0.02, 0.02, 0.01, 0.02], 3,
                 b"gx,gy,gz", id="no counter, three of seven lost")])
def test_a_serial_device_that_loses_samples_is_recorded_whole_with_its_gaps(tmp_path, lines, delivered, steps_s, duration_s,
                                                                            fields):
    """Issue 37 (attack 3): a device on a real pseudo-terminal that sends counters 5, 6 (a NaN
    line, refused), 7, ... over and over (samples lost, then a restart) gave a t whose steps were
    mostly 0.02 s in a 100-Hz file; record exited 2 ("t steps by 0.02 s ... not written") and kept
    nothing (of a short file) or stopped at the first window. Every sample it delivered is in
    the file, which reads, its gaps in t counted and noted."""
    out = tmp_path / "lossy.csv"
    primary, secondary = os.openpty()
    port = os.ttyname(secondary)
    proc = start_record(f"serial:{port}", out, "--quiet", "--duration", str(duration_s))

    err = play_lossy_device(primary, secondary, proc, lines, int(2 * duration_s / sum(steps_s)), fields)
    assert proc.returncode == 0, err
    rec = read_recording(out)
    n = len(rec)
    assert n == int(re.search(r"wrote (\d+) samples", err).group(1)) > 100 * duration_s / 2
    np.testing.assert_array_equal(rec.gyro_dps, np.tile(delivered, (n, 1))[:n])
    steps = np.tile(steps_s, n)[:n - 1]
    np.testing.assert_allclose(np.diff(rec.t_s), steps, atol=1e-9)
    gap_notes = sum(text.startswith("gap: 1 samples lost before") for _, text in rec.notes)
    assert rec.t_gaps == np.count_nonzero(steps > 0.015) and gap_notes >= rec.t_gaps  # notes may run ahead of the cut
    # attack pass 33c: --duration stops it with lines read past the cut; the summary and the end note
    # counted their lost samples too (534 where the file showed 387): a number stated is the file's
    in_file = round(np.sum(steps) * 100) - (n - 1)
    assert int(re.search(r"lost (\d+) samples", err).group(1)) == in_file, err
    end = [text for _, text in rec.notes if text.startswith("end:")]
    assert end and (f"lost samples {in_file}," in end[-1] + "," if in_file else "lost samples" not in end[-1]), end


SERIAL_HEADER = b"# gyrofilter-serial: 1 gyro_unit=dps sample_rate_hz=100 fields=counter,gx,gy,gz\n"


def test_a_recording_whose_last_12_s_lost_every_other_sample_is_kept_whole(tmp_path):
    """Attack pass 11: a device (a real pseudo-terminal) that sent 30 s of samples, then lost
    every other one for 12 s (its counter's gaps): the last 1000 steps held gaps only, the writer
    judged them a t at half the rate at its close, and the recording was removed whole. Every
    sample delivered is kept, its gaps counted (the last line, whose counter jumped, waits for
    a next one: at the stop it is written too, test_a_line_held_at_ctrl_c_is_written)."""
    counters = np.concatenate((np.arange(3000), 3000 + 2 * np.arange(1, 1201)))
    rec = _record_device(tmp_path / "lossy.csv", counters)
    np.testing.assert_array_equal(rec.gyro_dps[:, 0], counters[:len(rec)] % 7)
    assert rec.t_gaps == len(rec) - 3000


def _record_device(out, counters):
    """`record` from a device on a real pseudo-terminal sending one line per counter (gx = counter
    mod 7), stopped by Ctrl-C once the file holds all but the last; its recording, every row's t
    the counter's, checked."""
    lines = b"".join(b"%d,%d,0,0\n" % (c, c % 7) for c in counters.tolist())
    primary, secondary = os.openpty()
    proc = start_record(f"serial:{os.ttyname(secondary)}", out, "--quiet")
    err = play_serial_then_stop(primary, secondary, proc, SERIAL_HEADER, lines, out, len(counters) - 1)
    assert proc.returncode == 0, err
    rec = read_recording(out)
    assert len(rec) >= len(counters) - 1
    np.testing.assert_array_equal(rec.t_s, counters[:len(rec)] / 100.0)
    return rec


def test_a_device_that_lost_every_other_sample_from_its_first_line_is_kept(tmp_path):
    """Attack pass 14: a device (a real pseudo-terminal) whose counter stepped by 2 from its first
    line, 15 s: no window showed the rate, the writer judged the whole file a t at half the rate
    at its close and removed it (exit 2, every sample lost). Its header says t is the device's
    counter (t_from), whose jumps are samples the device lost: kept, its gaps counted."""
    rec = _record_device(tmp_path / "halved.csv", 2 * np.arange(1500))
    assert rec.header["t_from"] == "device counter" and rec.t_gaps == len(rec) - 1


def test_a_device_that_lost_10_of_every_11_samples_from_its_first_line_is_kept(tmp_path):
    """Attack pass 15: a device whose counter stepped by 11 from its first line (a serial line too
    slow for its rate) gave steps of 11 intervals, more than the 10 whose rate a window of gaps
    only can tell: refused at the close as a t off the rate and removed whole (exit 2, every
    sample lost). Its t is the device's counter (t_from): kept, every step a gap."""
    rec = _record_device(tmp_path / "eleventh.csv", 11 * np.arange(1500))
    assert rec.header["t_from"] == "device counter" and rec.t_gaps == len(rec) - 1


def test_a_device_without_a_counter_that_lost_every_other_line_from_its_first_is_kept(tmp_path):
    """Attack pass 33b: without a counter, a refused line of the full width is a lost sample, so a
    device whose every other line was refused (NaN) from its first gives steps of 2 intervals in
    every window: without the header's t_from (t counts the lines the device sent) the writer
    judged it a t at half the rate at its close and removed it whole (exit 2). Kept, every step a gap."""
    out = tmp_path / "halved.csv"
    lines = b"".join(b"%d,0,0\nnan,0,0\n" % (i % 7) for i in range(1500))
    primary, secondary = os.openpty()
    proc = start_record(f"serial:{os.ttyname(secondary)}", out, "--quiet")
    header = SERIAL_HEADER.replace(b"counter,", b"")
    err = play_serial_then_stop(primary, secondary, proc, header, lines, out, 1499)
    assert proc.returncode == 0, err
    rec = read_recording(out)
    assert rec.header["t_from"] == "device lines" and len(rec) >= 1499 and rec.t_gaps == len(rec) - 1, err
    np.testing.assert_array_equal(rec.t_s, 2 * np.arange(len(rec)) / 100.0)
    assert re.search(r"lost (\d+) samples", err).group(1) == str(len(rec) - 1), err


@pytest.mark.parametrize("cut", [b"", b"506,1,"])
def test_a_line_held_at_ctrl_c_is_written(tmp_path, cut):
    """A serial line whose counter jumped waits for the next line to tell a gap from a corrupt
    counter; at Ctrl-C it was dropped without a word (pass 11), where a disconnect writes it.
    A stop ends the stream as a disconnect does: the line is written, its gap noted and counted
    in the summary; a line cut off by the stop is counted as a cut line."""
    counters = [*range(500), 505]
    lines = b"".join(b"%d,%d,0,0\n" % (c, c % 7) for c in counters) + cut
    out = tmp_path / "held.csv"
    primary, secondary = os.openpty()
    proc = start_record(f"serial:{os.ttyname(secondary)}", out, "--quiet")
    err = play_serial_then_stop(primary, secondary, proc, SERIAL_HEADER, lines, out, 500)
    assert proc.returncode == 0, err
    rec = read_recording(out)
    np.testing.assert_array_equal(rec.t_s, np.array(counters) / 100.0)
    assert rec.t_gaps == 1 and any(text.startswith("gap: 5 samples lost before t=5.05 s") for _, text in rec.notes)
    assert "wrote 501 samples" in err and "lost 5 samples" in err, err
    assert ("partial lines 1" in err) == bool(cut), err


def test_a_live_file_refused_at_its_close_does_not_stay(tmp_path):
    """Issue 37 (attack 3): `run --out` from a device that loses samples wrote filtered rows whose
    steps (0.08 s at 20 Hz) the writer refuses at the close of a file shorter than one window,
    saying "not written", while the file it had published at its first flush stayed, a file the
    reader refuses. The refused file goes, and the folder made for it."""
    from gyrofilter.cli import live

    out = tmp_path / "made" / "filtered.csv"
    writer = live.LiveOutput(str(out), {"sample_rate_hz": 20, "gyro_unit": "dps"}, ["t", "gx", "gy", "gz"], None,
                             "filtered row")
    rows = np.column_stack([0.08 * np.arange(100), np.zeros((100, 3))])
    writer.write(rows)
    writer.flush()  # published under its name
    assert out.exists()
    with pytest.raises(RecordingError, match="not written: it would not read back"):
        writer.close(failed=False)
    assert not out.exists() and not out.parent.exists()



@pytest.mark.parametrize("command, case", [("record", "exists"), ("run", "exists"), ("record", "is the output"),
                                           ("run", "is an input")])
def test_a_spy_url_file_is_an_output_checked_before_the_port_opens(tmp_path, capsys, command, case):
    """Attack pass 33b: `serial:spy://PORT?file=F` (pyserial's spy) emptied F without --force:
    pyserial opens F for writing before the port opens, so F was truncated even when the port then
    failed, and F was never checked against the command's files. F is an output like --out: an
    existing F needs --force, F may be neither the output nor an input; refused in one line naming
    F, before the port opens, F as it was."""
    pytest.importorskip("serial")
    out, calibration = tmp_path / "out.csv", tmp_path / "cal.json"
    spy = {"exists": tmp_path / "spy.txt", "is the output": out, "is an input": calibration}[case]
    spy.write_text("keep me\n")
    primary, secondary = os.openpty()
    try:
        assert main([command, "--source", f"serial:spy://{os.ttyname(secondary)}?file={spy},header_timeout=0.5",
                     "--out", str(out), *(["--force"] if case != "exists" else []),
                     *(["--calibration", str(calibration)] if case == "is an input" else [])]) == 2
    finally:
        os.close(primary)
        os.close(secondary)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(spy) in err[0], err
    assert spy.read_text() == "keep me\n"


def test_a_spy_url_file_that_exists_is_replaced_with_force(tmp_path):
    """The spy file is an output like --out: with --force an existing one is replaced by the spy's
    log of the session, and the recording is written."""
    pytest.importorskip("serial")
    out, spy = tmp_path / "out.csv", tmp_path / "spy.txt"
    spy.write_text("old\n")
    primary, secondary = os.openpty()
    proc = start_record(f"serial:spy://{os.ttyname(secondary)}?file={spy}", out, "--quiet", "--force")
    lines = b"".join(b"%d,1,0,0\n" % c for c in range(50))
    err = play_serial_then_stop(primary, secondary, proc, SERIAL_HEADER, lines, out, 49)
    assert proc.returncode == 0, err
    assert len(read_recording(out)) >= 49 and " TX " in spy.read_text() and "old" not in spy.read_text()
