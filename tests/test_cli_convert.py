"""``gyrofilter convert``: logs shaped like common tools' (a phone logger's CSV with time stamps in
ns or s and rates in rad/s, a ROS bag export, an Arduino sketch's blank-separated raw LSB) become
recordings that read back with the very values of the log; every refusal is one line naming the
file, the line and the column, exit 2, no output."""
import contextlib
import errno
from fractions import Fraction
import gzip
import io
import json
import os
import subprocess
import sys
import tempfile
import threading
import types
import zlib

import numpy as np
import pytest

from gyrofilter.cli import main
from gyrofilter.recording import read_recording
from gyrofilter.recording.gzip_bytes import RUN_BYTES
from gyrofilter.recording.gzipped import HOLD_BYTES
from gyrofilter.recording.foreign import TIME_UNITS
from support import REPO

N = 1500  # 15 s at 100 Hz: past the filter's 2 s start-up calibration


def _rates(seed, scale):
    rng = np.random.default_rng(seed)
    return np.round((np.array([-3.3, 1.1, -0.5]) + 0.05 * rng.standard_normal((N, 3))) * scale, 6)


def _jittered_ns(seed, rate_hz=100.0):
    """Phone time stamps: ns since 1970, each step the nominal one +-0.2 %."""
    rng = np.random.default_rng(seed)
    steps = np.round(1e9 / rate_hz * (1 + 0.002 * rng.uniform(-1, 1, N - 1))).astype(np.int64)
    return 1_732_000_000_123_456_789 + np.concatenate(([0], np.cumsum(steps)))


def _convert(tmp_path, text, *options, name="log.csv", out="rec.csv.gz"):
    src = tmp_path / name
    src.write_text(text)
    dst = tmp_path / out
    return main(["convert", str(src), "--out", str(dst), *options]), dst


def _check_same(rec, gyro, t_s=None):
    assert np.array_equal(rec.gyro, gyro)  # the values as they are: unit in the header, nothing rounded
    if t_s is not None:
        assert np.allclose(rec.t_s, t_s, rtol=0, atol=1e-9)


def test_phone_logger_csv_in_rad_per_s_with_ns_time_stamps(tmp_path, capsys):
    gyro = _rates(1, np.pi / 180)
    stamps = _jittered_ns(2)
    rows = "\n".join(f"{s},{x},{y},{z}" for s, (x, y, z) in zip(stamps.tolist(), gyro.tolist()))
    rc, dst = _convert(tmp_path, "timestamp,gyro_x,gyro_y,gyro_z\n" + rows + "\n", "--unit", "rad/s")
    assert rc == 0, capsys.readouterr().err
    err = capsys.readouterr().err
    assert "in ns (inferred" in err and "jitter" in err
    rec = read_recording(dst)
    assert rec.gyro_unit == "rad/s" and abs(rec.sample_rate_hz - 100.0) < 0.01
    assert rec.header["time_origin"] == f"{stamps[0]} ns (timestamp)"
    _check_same(rec, gyro, (stamps - stamps[0]) * 1e-9)  # integer stamps subtracted exactly
    assert main(["replay", str(dst)]) == 0
    bias_line = next(ln for ln in capsys.readouterr().out.splitlines() if "bias (" in ln)
    assert abs(float(bias_line.split(":")[1].split(",")[0]) + 3.3) < 0.02  # in deg/s: the unit went through


def test_phone_logger_with_seconds_elapsed_and_bare_axes_in_its_own_order(tmp_path, capsys):
    """Sensor Logger's gyroscope file: time (ns), seconds_elapsed (s), then z, y, x."""
    gyro = _rates(3, np.pi / 180)
    stamps = _jittered_ns(4)
    rows = "\n".join(f"{s},{(s - stamps[0]) / 1e9},{z},{y},{x}" for s, (x, y, z) in zip(stamps.tolist(), gyro.tolist()))
    rc, dst = _convert(tmp_path, "time,seconds_elapsed,z,y,x\n" + rows + "\n", "--unit", "rad/s")
    assert rc == 0, capsys.readouterr().err
    rec = read_recording(dst)
    _check_same(rec, gyro, (stamps - stamps[0]) * 1e-9)
    assert "seconds_elapsed" in rec.header["time_origin"]


def test_phyphox_export_states_its_units_in_the_names(tmp_path, capsys):
    gyro = _rates(5, np.pi / 180)
    t_s = np.arange(N) / 100.0
    rows = "\n".join(f"{t},{x},{y},{z},{np.hypot(x, y)}" for t, (x, y, z) in zip(t_s.tolist(), gyro.tolist()))
    head = '"Time (s)","Gyroscope x (rad/s)","Gyroscope y (rad/s)","Gyroscope z (rad/s)","Absolute (rad/s)"\n'
    rc, dst = _convert(tmp_path, head + rows + "\n")  # no --unit: the names say rad/s
    assert rc == 0, capsys.readouterr().err
    _check_same(read_recording(dst), gyro, t_s)
    assert "left out: 'Absolute (rad/s)' (not a column convert reads)" in capsys.readouterr().err
    rc, _ = _convert(tmp_path, head + rows + "\n", "--unit", "dps", out="other.csv")
    assert rc == 2 and "--unit dps, but the column names say rad/s" in capsys.readouterr().err


def test_ros_bag_export(tmp_path, capsys):
    """``rostopic echo -p /imu``: %time and header.stamp in ns, quaternions, covariances, a frame id."""
    gyro = _rates(6, np.pi / 180)
    stamps = _jittered_ns(7, rate_hz=200.0)
    head = ("%time,field.header.seq,field.header.stamp,field.header.frame_id,field.orientation.x,field.orientation.y,"
            "field.orientation.z,field.orientation.w,field.angular_velocity.x,field.angular_velocity.y,"
            "field.angular_velocity.z,field.linear_acceleration.x,field.linear_acceleration.y,field.linear_acceleration.z\n")
    rows = "\n".join(f"{s + 150000},{i},{s},imu_link,0,0,0,1,{x},{y},{z},0.01,-0.02,9.81"
                     for i, (s, (x, y, z)) in enumerate(zip(stamps.tolist(), gyro.tolist())))
    rc, dst = _convert(tmp_path, head + rows + "\n", "--unit", "rad/s")
    assert rc == 0, capsys.readouterr().err
    rec = read_recording(dst)
    assert abs(rec.sample_rate_hz - 200.0) < 0.05 and rec.header["time_origin"].endswith("ns (%time)")
    _check_same(rec, gyro, (stamps - stamps[0]) * 1e-9)


def test_arduino_blank_separated_raw_lsb_without_column_names(tmp_path, capsys):
    rng = np.random.default_rng(8)
    lsb = np.round(np.array([-432.0, 144.0, -65.0]) + 6 * rng.standard_normal((N, 3)))
    millis = 12345 + np.cumsum(np.r_[0, 10 + rng.integers(-1, 2, N - 1)])  # millis() of a 100 Hz loop
    text = "# MPU6050 ready\n"
    text += "\n".join(f"{m}\t{int(x)} {int(y)} {int(z)}" for m, (x, y, z) in zip(millis.tolist(), lsb.tolist())) + "\n"
    rc, _ = _convert(tmp_path, text, "--unit", "lsb", "--lsb-per-dps", "131", name="log.txt")
    assert rc == 2 and "line 2: numbers but no column names; give the columns by number" in capsys.readouterr().err
    rc, dst = _convert(tmp_path, text, "--unit", "lsb", "--lsb-per-dps", "131", "--columns", "1,2,3,4", name="log.txt")
    assert rc == 0, capsys.readouterr().err
    rec = read_recording(dst)
    assert rec.lsb_per_dps == 131 and rec.header["time_origin"] == "12345 ms (1)"
    _check_same(rec, lsb, (millis - millis[0]) * 1e-3)
    assert "1 blank or comment line(s) skipped" in capsys.readouterr().err


@pytest.mark.parametrize("text, options, expected", [
    ("t,gx,gy,gz\n0,1,2,3\n0.01,1,x,3\n", ["--unit", "dps"], "log.csv: line 3, column 3 ('gy'): not a plain decimal number: 'x'"),
    ("t,gx,gy,gz\n0,1,2,3\n0.01,1,,3\n", ["--unit", "dps"], "line 3, column 3 ('gy'): not a plain decimal number: ''"),
    ("t,gx,gy,gz\n0,1,2,3\n0.01,1,3\n", ["--unit", "dps"], "line 3: 3 values, but 4 columns (line 1)"),
    ("t,gx,gy,gz\n0,1,2,3\n0.01,1,2,3\n0.01,1,2,3\n", ["--unit", "dps"], "line 4, column 1 ('t'): t does not increase"),
    ("t,gx,gy,gz\n0,1,2,3\n0.01,1,2,3\n", [], "the gyro unit is not stated by --unit or the column names (a comment is not read as one); give --unit"),
    ("t,gx,gy,gz\n0,1,2,3\n0.01,1,2,3\n", ["--unit", "lsb"], "--unit lsb needs --lsb-per-dps"),
    ("a,b,c\n0,1,2\n1,2,3\n", ["--unit", "dps"], "no column for the gyro's x among 'a, b, c'; name the three"),
    ("gyro_x,wx,gy,gz\n0,1,2,3\n1,2,3,4\n", ["--unit", "dps"], "columns 'gyro_x', 'wx' could each be the gyro's x"),
    ("gx,gy,gz\n0,1,2\n1,2,3\n", ["--unit", "dps"], "no time column among 'gx, gy, gz'; give the rate in --sample-rate-hz"),
    ("t,gx,gy,gz\n0,1,2,3\n0.01,1e9,2,3\n", ["--unit", "dps"], "line 3, column 2 ('gx'): 1000000000 dps is beyond"),
    ("t,gx,gy,gz\n0,1,2,3\n", ["--unit", "dps"], "1 data row(s); a recording needs at least 2"),
    ("t,gx,gy,gz\n0,1,2,3\n1,1,2,3\n", ["--unit", "dps", "--columns", "gx,gy,nope"], "--columns: no column 'nope'"),
])
def test_refusals_name_the_line_and_the_column(tmp_path, capsys, text, options, expected):
    rc, dst = _convert(tmp_path, text, *options)
    err = capsys.readouterr().err
    assert rc == 2 and expected in err and err.count("\n") == 1, err
    assert not dst.exists()


def test_time_steps_that_are_not_one_rate_are_refused_naming_the_line(tmp_path, capsys):
    """The first 1000 steps at 100 Hz, the next 1500 at 50 Hz: no window of the second part agrees."""
    t_s = np.concatenate((np.arange(1001) * 0.01, 10 + np.arange(1, 1501) * 0.02))
    rows = "\n".join(f"{t},1,2,3" for t in t_s.tolist())
    rc, dst = _convert(tmp_path, "time_s,gx,gy,gz\n" + rows + "\n", "--unit", "dps")
    err = capsys.readouterr().err
    assert rc == 2 and "column 1 ('time_s')" in err and "not one rate" in err and not dst.exists(), err
    match = int(err.split("steps from line ")[1].split(",")[0])
    assert 2 <= match <= 1503


def test_given_rate_without_time_column_and_gzip_input(tmp_path, capsys):
    gyro = _rates(9, 1.0)
    text = "gx;gy;gz\n" + "\n".join(f"{x};{y};{z}" for x, y, z in gyro.tolist()) + "\n"
    src = tmp_path / "log.csv.gz"
    src.write_bytes(gzip.compress(text.encode()))
    dst = tmp_path / "rec.csv"
    assert main(["convert", str(src), "--out", str(dst), "--unit", "dps", "--sample-rate-hz", "250"]) == 0
    rec = read_recording(dst)
    assert rec.sample_rate_hz == 250 and "t" not in rec.columns
    _check_same(rec, gyro)
    assert main(["convert", str(src), "--out", str(dst), "--unit", "dps", "--sample-rate-hz", "250"]) == 2  # exists
    assert "--force" in capsys.readouterr().err


def test_units_stated_by_name_suffixes(tmp_path, capsys):
    """``time_ms`` and ``gyro_x_dps``: no --unit, no inference."""
    rows = "\n".join(f"{1000 + 10 * i},{i % 3},{-(i % 5)},0.5" for i in range(N))
    rc, dst = _convert(tmp_path, "time_ms,gyro_x_dps,gyro_y_dps,gyro_z_dps\n" + rows + "\n")
    assert rc == 0, capsys.readouterr().err
    rec = read_recording(dst)
    assert rec.gyro_unit == "dps" and rec.sample_rate_hz == 100 and rec.header["time_origin"] == "1000 ms (time_ms)"
    assert "(as its name states" in capsys.readouterr().err
    # attack pass 17: the unit given by --time-unit was said to be the name's
    rc, dst = _convert(tmp_path, "time,gyro_x_dps,gyro_y_dps,gyro_z_dps\n" + rows + "\n", "--time-unit", "ms", "--force")
    err = capsys.readouterr().err
    assert rc == 0 and "(as --time-unit states" in err and "name states" not in err, err


def test_unit_deg_per_s_is_taken_as_dps(tmp_path, capsys):
    """The new user's `--unit deg/s` was refused (the format's name is dps)."""
    gyro = _rates(3, 1.0)
    rows = "\n".join(f"{k * 0.01:.2f},{x},{y},{z}" for k, (x, y, z) in enumerate(gyro.tolist()))
    rc, dst = _convert(tmp_path, "t,gx,gy,gz\n" + rows + "\n", "--unit", "deg/s")
    assert rc == 0, capsys.readouterr().err
    rec = read_recording(dst)
    assert rec.gyro_unit == "dps"
    _check_same(rec, gyro)


def test_damaged_gzip_log_is_one_refusal_line(tmp_path, capsys):
    """Corrupt compressed blocks (not a stream cut short) raise zlib.error, not BadGzipFile/EOFError:
    it went through as a traceback."""
    rows = "".join(f"{i * 0.01:.2f},{0.1 * (i % 7)},0.2,0.3\n" for i in range(3000))
    data = gzip.compress(("t,gx_dps,gy_dps,gz_dps\n" + rows).encode())
    src = tmp_path / "log.csv.gz"
    src.write_bytes(data[:10] + b"x" * 50 + data[60:])
    dst = tmp_path / "rec.csv.gz"
    assert main(["convert", str(src), "--out", str(dst)]) == 2
    err = capsys.readouterr().err
    assert "damaged gzip data" in err and str(src) in err and len(err.strip().splitlines()) == 1
    assert not dst.exists()


@pytest.mark.parametrize("step, name", [(1, "t"), (0.5, "time"), (1, "timestamp"), (500, "stamp"), (200, "time"),
                                        (125, "stamp"), (100, "t"), (0.2, "time"), (0.125, "t")])
def test_a_time_column_whose_steps_read_in_two_units_is_refused(tmp_path, capsys, step, name):
    """Attack pass 59: a 1 Hz log stamped in s (``t`` = 0, 1, 2 ...) was written at 1000 Hz (3 s), the stamps inferred
    to be ms, every Allan time 1000 times off: steps of 1 are 1 Hz in s or 1 kHz in ms (500: 2 Hz in ms or 2 kHz
    in us). Pass 60: only the unit before the one taken was looked at: the MPU6050's 8 kHz in us (steps of 125) was
    written at 8 Hz, read as ms, and 5 Hz in ms (0.2) at 5 Hz in s. Such a log is refused, naming both; --time-unit
    decides."""
    rows = "".join(f"{i * step:g},0.1,0.2,0.3\n" for i in range(300))
    code, dst = _convert(tmp_path, f"{name},gx,gy,gz\n{rows}", "--unit", "dps")
    err = capsys.readouterr().err
    slow, fast = ("s", "ms") if step < 100 else ("ms", "us")
    assert code == 2 and not dst.exists() and err.startswith(
        f"gyrofilter: error: {tmp_path / 'log.csv'}: the time column '{name}' steps by {step:g}: "), err
    assert f"; give --time-unit {slow} or {fast} (or --sample-rate-hz)\n" in err
    code, dst = _convert(tmp_path, f"{name},gx,gy,gz\n{rows}", "--unit", "dps", "--time-unit", slow)
    assert code == 0 and read_recording(dst).sample_rate_hz == pytest.approx(1.0 / (step * TIME_UNITS[slow]))
    capsys.readouterr()
    code, dst = _convert(tmp_path, f"{name},gx,gy,gz\n" + rows.replace(f"{step:g},", f"{step * 10:g},", 1), "--unit",
                         "dps", out="again.csv")
    assert code == 2  # one step changed, the median the same


def test_a_32_khz_log_stamped_in_whole_us_is_refused_and_the_sample_rate_settles_the_unit(tmp_path, capsys):
    """A new user's 32 kHz log stamped in whole us (steps of 31 and 32: 32.3 kHz) was written at 32 Hz, read as ms:
    32.3 kHz was above the fastest gyro's 32 kHz. The band of a gyro's rates is held within 5 %, as a rate's
    statements are; --sample-rate-hz, which only one unit gives, settles the unit (it was refused too)."""
    rows = "".join(f"{round(i * 31.25)},0.1,0.2,0.3\n" for i in range(3000))
    code, dst = _convert(tmp_path, f"time,gx,gy,gz\n{rows}", "--unit", "dps")
    err = capsys.readouterr().err
    assert code == 2 and "steps by 31: 32.2581 Hz in ms or 32258.1 Hz in us; give --time-unit ms or us" in err, err
    code, dst = _convert(tmp_path, f"time,gx,gy,gz\n{rows}", "--unit", "dps", "--sample-rate-hz", "32000")
    err = capsys.readouterr().err
    assert code == 0 and read_recording(dst).sample_rate_hz == 32000.0 and "in us (inferred: the unit giving " \
        "--sample-rate-hz" in " ".join(err.split()), err
    code, dst = _convert(tmp_path, f"time,gx,gy,gz\n{rows}", "--unit", "dps", "--sample-rate-hz", "100", out="b.csv")
    err = " ".join(capsys.readouterr().err.split())  # pass 62: it asked for the --sample-rate-hz it was given
    assert code == 2 and "give --time-unit ms or us (--sample-rate-hz 100 is neither: is it right?)" in err, err


def test_a_time_column_in_ms_at_100_hz_is_still_inferred(tmp_path, capsys):
    """Steps of 10 are 0.1 Hz in s (no gyro logs so slowly) or 100 Hz in ms: ms, said in the summary."""
    rows = "".join(f"{i * 10},0.1,0.2,0.3\n" for i in range(300))
    code, dst = _convert(tmp_path, f"time,gx,gy,gz\n{rows}", "--unit", "dps")
    assert code == 0 and read_recording(dst).sample_rate_hz == 100.0
    assert "column 'time' in ms (inferred" in capsys.readouterr().err


def test_decimal_epoch_seconds_are_subtracted_exactly(tmp_path, capsys):
    """A phone's stamps in s since 1970 with 9 decimals: as floats their steps are off by up to 2.4e-7 s
    (the rate read 399.991 Hz for 400 Hz); subtracted as decimals every ns is kept."""
    stamps_ns = 1_700_000_000_000_000_000 + 2_500_000 * np.arange(N)
    rows = "".join(f"{s // 10**9}.{s % 10**9:09d},0.1,0.2,0.3\n" for s in stamps_ns.tolist())
    rc, dst = _convert(tmp_path, "timestamp,gx_dps,gy_dps,gz_dps\n" + rows)
    assert rc == 0, capsys.readouterr().err
    rec = read_recording(dst)
    assert rec.sample_rate_hz == 400.0
    assert np.allclose(rec.t_s, (stamps_ns - stamps_ns[0]) * 1e-9, rtol=0, atol=1e-12)


@pytest.mark.parametrize("stamp", ["1e400", "-1e99999"])
@pytest.mark.parametrize("first", [False, True])
def test_a_time_stamp_too_far_for_a_float_is_refused_naming_its_line(tmp_path, capsys, stamp, first):
    """Issue 37 (attack): a first stamp of 1e400 was blamed on the next line ("time stamp '0.01' is
    too far from the first ('1e400')"); the line named is the one holding the stamp."""
    rows = [f"{i * 0.01:.2f},0.1,0.2,0.3\n" for i in range(300)]
    rows.insert(0 if first else 300, f"{stamp},0,0,0\n")
    rc, dst = _convert(tmp_path, "t,gx_dps,gy_dps,gz_dps\n" + "".join(rows))
    assert rc == 2 and not dst.exists()
    err = capsys.readouterr().err.strip()
    line = 2 if first else 302
    assert f"line {line}, column 1 ('t'): time stamp '{stamp}' is beyond the range of a float" in err
    assert len(err.splitlines()) == 1


def test_a_time_stamp_too_far_from_the_first_is_refused_naming_its_line(tmp_path, capsys):
    rc, dst = _convert(tmp_path, "t,gx_dps,gy_dps,gz_dps\n-1e308,0,0,0\n0,0,0,0\n1e308,0,0,0\n")
    assert rc == 2 and not dst.exists()
    assert "line 4, column 1 ('t'): time stamp '1e308' is too far from the first ('-1e308')" in capsys.readouterr().err


@pytest.mark.parametrize("zipped", [False, True])
def test_a_log_read_from_a_pipe_keeps_its_first_rows(tmp_path, capsys, zipped):
    """`convert <(zcat log.gz)`: the log was opened twice (once for the gzip magic), and a pipe
    cannot be read twice: its first block (256 rows of 16 bytes here, at a line end) was lost
    with exit 0 and a time origin 256 ms late."""
    text = "".join(f"{i:05d},{i % 10},0.2,0.3\n" for i in range(3000)).encode()
    read_end, write_end = os.pipe()  # as the shell makes <(...): /dev/fd/N, the pipe's read end

    def feed():
        with open(write_end, "wb") as fh:
            fh.write(gzip.compress(text) if zipped else text)

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    dst = tmp_path / "rec.csv"
    try:
        rc = main(["convert", f"/dev/fd/{read_end}", "--columns", "1,2,3,4", "--unit", "dps", "--time-unit", "ms", "--out", str(dst)])
    finally:
        os.close(read_end)
    writer.join(timeout=10)
    assert rc == 0, capsys.readouterr().err
    rec = read_recording(dst)
    assert len(rec) == 3000 and rec.header["time_origin"] == "00000 ms (1)"
    assert np.array_equal(rec.gyro[:, 0], np.arange(3000) % 10)


def _convert_pipe(tmp_path, data):
    """``convert /dev/fd/N`` of a pipe fed ``data`` by a thread (stopped by a closed read end); (rc, out)."""
    read_end, write_end = os.pipe()

    def feed():
        with contextlib.suppress(BrokenPipeError), open(write_end, "wb") as fh:
            fh.write(data)

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    dst = tmp_path / "rec.csv"
    try:
        rc = main(["convert", f"/dev/fd/{read_end}", "--columns", "1,2,3,4", "--unit", "dps", "--time-unit", "ms",
                   "--out", str(dst)])
    finally:
        os.close(read_end)
    writer.join(timeout=10)
    assert not writer.is_alive()
    return rc, dst


_PIPED = "".join(f"{i:06d},{i % 10},0.2,0.3\n" for i in range(20000)).encode()  # 340000 bytes


@pytest.mark.parametrize("limit, free, held", [(100_000, 10**12, False), (10**12, 300_000, False),
                                               (len(_PIPED), 2 * len(_PIPED), True)])
def test_a_pipe_is_copied_within_a_bound_or_refused(tmp_path, capsys, monkeypatch, limit, free, held):
    """Issue 37 (leftover): ``zcat huge.gz | convert /dev/stdin`` copied the whole pipe to the
    temporary folder first (a pipe cannot be read twice), filling /tmp with a log of many GB.
    The copy holds at most MAX_PIPE_COPY_BYTES and half the free space of that folder; beyond,
    one line says what to do, no output is written and the temporary folder keeps nothing."""
    from gyrofilter.recording import logtext

    monkeypatch.setattr(logtext, "MAX_PIPE_COPY_BYTES", limit)
    monkeypatch.setattr(logtext.shutil, "disk_usage", lambda folder: types.SimpleNamespace(free=free))
    rc, dst = _convert_pipe(tmp_path, _PIPED)
    err = capsys.readouterr().err
    if held:
        assert rc == 0 and len(read_recording(dst)) == 20000, err
        return
    assert rc == 2 and not dst.exists() and len(err.strip().splitlines()) == 1
    assert f"a pipe is copied to {tempfile.gettempdir()} to be read twice, and this one holds more than " \
           f"{min(limit, free // 2)} bytes" in err
    assert "save the log to a file and convert that" in err


@pytest.mark.parametrize("zipped", [False, True])
def test_a_pipe_whose_first_line_is_no_line_of_a_log_is_refused_before_it_is_copied(tmp_path, capsys, zipped):
    """Issue 37 (attack 3): ``cat /dev/zero | convert -`` copied up to 4 GiB to the temporary
    folder before refusing line 1. The first line must end within MAX_LINE_BYTES + 1 bytes (of
    text, gzip or not): checked on the first blocks as they come, refused at once. The pipe
    offers 64 MiB of zeros (text), or 2 GiB of them gzip-compressed, a block at a time."""
    from gyrofilter.recording.header import MAX_LINE_BYTES

    offered = 64 << 20
    fed = [0]  # bytes the pipe took before its reader went away
    read_end, write_end = os.pipe()

    def blocks():
        zeros = bytes(1 << 16)
        if not zipped:
            yield from (zeros for _ in range(offered // len(zeros)))
            return
        packer = zlib.compressobj(6, zlib.DEFLATED, 31)
        for _ in range((2 << 30) // len(zeros)):
            if packed := packer.compress(zeros):
                yield packed
        yield packer.flush()

    def feed():
        with contextlib.suppress(BrokenPipeError), open(write_end, "wb") as fh:
            for block in blocks():
                fh.write(block)
                fed[0] += len(block)
            fed.append("all")

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    try:
        rc = main(["convert", f"/dev/fd/{read_end}", "--unit", "dps", "--out", str(tmp_path / "rec.csv")])
    finally:
        os.close(read_end)
    writer.join(timeout=60)
    assert not writer.is_alive()
    err = capsys.readouterr().err
    assert rc == 2 and err == f"gyrofilter: error: /dev/fd/{read_end}: line 1: longer than {MAX_LINE_BYTES} bytes, not a line of a log\n"
    assert fed[-1] != "all" and fed[0] < 4 * MAX_LINE_BYTES, fed  # refused within the first blocks, not after the copy
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("chunks", [1, 3])
def test_a_time_that_does_not_increase_is_refused_where_it_is_read(tmp_path, capsys, chunks):
    """Issue 37 (attack 4): a gzip log of one row "0,0,0,0" 150 million times (1.8 MB) was read
    whole, 16 bytes a row (2.4 GB after 300 s), before its t, not increasing from line 3 on,
    was refused; a later line's own defect was named instead. The first stamp that does not
    increase is refused as it is read, in the first chunk or across chunks."""
    from gyrofilter.recording import CHUNK_ROWS

    first = max(1, CHUNK_ROWS * (chunks - 1))  # the row whose t goes back: the second, or the first of the third chunk
    # (then a chunk of such rows: the defect of the last line comes in a later chunk)
    rows = [f"{i * 0.01:.2f},0,0,0\n" for i in range(first)] + [f"{(first - 1) * 0.01:.2f},0,0,0\n"] * CHUNK_ROWS
    rc, dst = _convert(tmp_path, "t,gx,gy,gz\n" + "".join(rows) + "1e3,0,0\n", "--unit", "dps")
    assert rc == 2 and not dst.exists()
    stamp = f"{(first - 1) * 0.01:.2f}"
    assert capsys.readouterr().err.endswith(f"log.csv: line {first + 2}, column 1 ('t'): t does not increase "
                                            f"('{stamp}' after '{stamp}')\n")


@pytest.mark.parametrize("name", ["bomb.csv.gz", "bomb.csv"])
def test_runs_of_empty_lines_are_skipped_in_bulk_and_counted(tmp_path, capsys, monkeypatch, name):
    """Issue 37 (attack 3): 30 MB of line ends (30 kB of gzip) took 17-22 s, a Python step per
    line. A run of empty lines (\\n or \\r\\n alone) is read past a block at a time: a few
    hundred reads of a line for 4 million of them, every line still counted and numbered."""
    text = (b"\n\r\n# note\nt,gx,gy,gz\n" + b"\n" * 3_000_000 + b"0,1,2,3\r\n\r\n\r\n0.01,1,2,3\n\n# x\n"
            + b"\r\n" * 1_000_000 + b"0.02,1,2\n")
    path = tmp_path / name
    path.write_bytes(gzip.compress(text) if name.endswith(".gz") else text)
    calls = [0]
    readline = gzip.GzipFile.readline

    def counted(self, *args):
        calls[0] += 1
        return readline(self, *args)

    monkeypatch.setattr(gzip.GzipFile, "readline", counted)  # a gzip log's lines (a text file's: C code)
    assert main(["convert", str(path), "--unit", "dps", "--out", str(tmp_path / "rec.csv")]) == 2
    bad_line = text.count(b"\n")  # the last line, its number counted across the runs
    assert capsys.readouterr().err == f"gyrofilter: error: {path}: line {bad_line}: 3 values, but 4 columns (line 4)\n"
    assert calls[0] < 1000 if name.endswith(".gz") else calls[0] == 0, calls
    path.write_bytes(text.replace(b"0.02,1,2\n", b"0.02,1,2,3\n"))
    assert main(["convert", str(path), "--unit", "dps", "--out", str(tmp_path / "rec.csv")]) == 0
    assert "; 3 rows, 4000007 blank or comment line(s) skipped" in capsys.readouterr().err
    assert len(read_recording(tmp_path / "rec.csv")) == 3


def test_a_temporary_folder_that_fills_while_a_pipe_is_copied_is_said(tmp_path, capsys, monkeypatch):
    """The copy of a pipe meeting a full temporary folder (ENOSPC) said "cannot read", blaming the log."""
    from gyrofilter.recording import logtext

    class Full(io.BytesIO):
        def write(self, data):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(logtext.tempfile, "TemporaryFile", Full)
    rc, dst = _convert_pipe(tmp_path, _PIPED)
    err = capsys.readouterr().err
    assert rc == 2 and not dst.exists() and len(err.strip().splitlines()) == 1
    assert f"copying it to {tempfile.gettempdir()}: No space left on device; save the log to a file" in err


def test_a_log_on_the_standard_input_is_read_as_dash(tmp_path):
    """Attack pass (issue 37): ``zcat log.gz | gyrofilter convert - --out rec.csv.gz`` said
    "-: cannot read: No such file or directory"; ``-`` is the standard input (a pipe: copied
    within the bound), gzip or text."""
    text = "".join(f"{i:05d},{i % 10},0.2,0.3\n" for i in range(3000)).encode()
    for data, name in ((text, "a.csv"), (gzip.compress(text), "b.csv.gz")):
        dst = tmp_path / name
        done = subprocess.run([sys.executable, "-m", "gyrofilter", "convert", "-", "--columns", "1,2,3,4", "--unit", "dps",
                               "--time-unit", "ms", "--out", str(dst)], input=data, capture_output=True, timeout=120,
                              cwd=REPO)
        assert done.returncode == 0, done.stderr
        rec = read_recording(dst)
        assert len(rec) == 3000 and rec.header["converted_from"] == "-"
        assert np.array_equal(rec.gyro[:, 0], np.arange(3000) % 10)


def test_a_closed_standard_input_is_one_line(tmp_path):
    """Attack pass 8 (issue 37): ``convert - ... <&-`` (no standard input at all) ended in a
    traceback (AttributeError: sys.stdin is None); it is one line naming ``-``, and no file."""
    dst = tmp_path / "rec.csv"
    done = subprocess.run(["sh", "-c", f'exec "$0" -m gyrofilter convert - --unit dps --out {dst} <&-', sys.executable],
                          capture_output=True, text=True, timeout=120, cwd=REPO)
    assert done.returncode == 2 and done.stderr == "gyrofilter: error: -: cannot read: Bad file descriptor\n", done.stderr
    assert not dst.exists()


@pytest.mark.parametrize("period_ms", [9.7, 10.3, 4.3, 2.6])
def test_stamps_rounded_to_whole_ms_give_the_rate_they_span_or_a_refusal(tmp_path, capsys, period_ms):
    """Attack pass 8 (issue 37): an Arduino's millis() stamps of samples every 2.6 ms step by 2 or
    3 ms; the rate was 1 / the median step, 333.333 Hz written for 384.6 (4.3 ms: 250 for 232.6; 9.7
    ms: 100 for 103.1), exit 0, every later tau and density off by as much. The rate is 1 / the
    mean step (gaps aside); where the stamps' steps then stray more than 5 % from it, the log is
    refused as one whose steps are not one rate."""
    n = 6000
    stamps = np.floor(np.arange(n) * period_ms).astype(int)
    src = tmp_path / "arduino.csv"
    src.write_text("millis,gx,gy,gz\n" + "".join(f"{s},1,2,3\n" for s in stamps))
    dst = tmp_path / "rec.csv"
    rc = main(["convert", str(src), "--unit", "dps", "--out", str(dst)])
    err = capsys.readouterr().err
    true_hz = 1000 / period_ms
    if rc == 0:
        assert abs(read_recording(dst).sample_rate_hz / true_hz - 1) < 1e-4, err
    else:
        assert rc == 2 and "more than 5% apart" in err and not dst.exists(), err
    assert (rc == 0) == (period_ms > 9)  # a 1-ms step is within 5 % of a 10-ms period, not of 4.3 or 2.6


@pytest.mark.parametrize("column, stamps, said", [
    ("millis", [int(k * 1.4) for k in range(6000)], "steps by its stamps' last digit (1 ms), so its 2399 longer steps"),
    ("time_s", [f"{int(k * 1.2) / 1000:.3f}" for k in range(6000)], "steps by its stamps' last digit (1 ms), so its 1199"),
    ("micros", [10000 * (k // 4) + 50 * (k % 4) for k in range(6000)], "(steps over 1.5 median steps) span 98.5 % of it"),
])
def test_gaps_that_may_be_a_slower_rate_are_refused(tmp_path, capsys, column, stamps, said):
    """Attack pass 9 (issue 37): a gap is a step over 1.5 median steps, so stamps of a 714 Hz log
    rounded to whole ms (millis(): steps of 1 or 2 ms, median 1) were read as 1000 Hz with 2399
    lost samples (833 Hz in s with 3 decimals: 1000 too), and bursts of 4 samples stamped 50 us
    apart every 10 ms (100 Hz) as 20 kHz with most samples lost: exit 0, the rate 40 % or 200x
    off. Refused, asking for the rate; with it given, the check of t decides."""
    src = tmp_path / "log.csv"
    src.write_text(f"{column},gx,gy,gz\n" + "".join(f"{s},1,2,3\n" for s in stamps))
    dst = tmp_path / "rec.csv"
    assert main(["convert", str(src), "--unit", "dps", "--out", str(dst)]) == 2
    err = capsys.readouterr().err
    assert said in err and err.count("\n") == 1 and "--sample-rate-hz" in err and not dst.exists(), err
    rate = "1000" if column != "micros" else "20000"  # the user's word for the faster rate: taken, gaps counted
    assert main(["convert", str(src), "--unit", "dps", "--out", str(dst), "--sample-rate-hz", rate]) == 0
    assert read_recording(dst).sample_rate_hz == float(rate)


def test_whole_ms_stamps_of_1khz_with_a_few_lost_samples_keep_their_rate(tmp_path, capsys):
    """The other side of the refusal above: 2 % of the samples of a 1 kHz log in whole ms lost
    (steps of 2 ms put the rate they span 2 % below 1000 Hz, within the reader's tolerance of t)
    are gaps, not a slower rate."""
    rng = np.random.default_rng(4)
    stamps = np.cumsum(np.where(rng.random(6000) < 0.02, 2, 1))
    src = tmp_path / "log.csv"
    src.write_text("millis,gx,gy,gz\n" + "".join(f"{s},1,2,3\n" for s in stamps))
    dst = tmp_path / "rec.csv"
    assert main(["convert", str(src), "--unit", "dps", "--out", str(dst)]) == 0, capsys.readouterr().err
    rec = read_recording(dst)
    assert rec.sample_rate_hz == 1000 and rec.t_gaps == int(np.count_nonzero(np.diff(stamps) == 2))


def _late_then_caught_up(n, period_us, every):
    """Stamps every ``period_us``, but each ``every``-th sample 2 periods late and the next two
    stamped with it, 100 us apart (a logger that stamps as the samples arrive)."""
    steps = np.full(n - 1, float(period_us))
    steps[::every], steps[1::every], steps[2::every] = 3 * period_us - 200, 100, 100
    return np.concatenate([[0], np.cumsum(steps)]).astype(int)


@pytest.mark.parametrize("column, stamps, true_hz", [
    ("micros", _late_then_caught_up(6000, 5000, 100), 200),
    ("millis", np.concatenate([[0, 1, 2, 3, 4], 5 + 10 * np.arange(6000)]), 100),
    ("millis", np.concatenate([10 * np.arange(6000), [10 * 5999 + 500_000]]), 100),
])
def test_the_rate_of_a_log_with_odd_steps(tmp_path, capsys, column, stamps, true_hz):
    """Attack pass 9 (issue 37): the mean step kept the short steps, so samples stamped at once
    after a late one (2 % of the steps) wrote 204.04 Hz for 200 and a log's first 5 rows 1 ms
    apart 100.075 Hz for 100, exit 0; steps under half the median are now left out, as gaps are.
    A single long pause (500 s after 60 s) is a gap, not the bursts that are refused."""
    src = tmp_path / "log.csv"
    src.write_text(f"{column},gx,gy,gz\n" + "".join(f"{s},1,2,3\n" for s in stamps))
    dst = tmp_path / "rec.csv"
    assert main(["convert", str(src), "--unit", "dps", "--out", str(dst)]) == 0, capsys.readouterr().err
    assert read_recording(dst).sample_rate_hz == true_hz


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("rate", [[], ["--sample-rate-hz", "200"]])
def test_steps_with_none_near_their_median_are_one_refusal(tmp_path, capsys, rate):
    """Steps of 1 us and 10 ms by turns (an even count: the median, 5 ms, is neither): the mean
    of the steps near the median has none to take; refused in one line, no RuntimeWarning."""
    stamps = np.concatenate([[0], np.cumsum(np.tile([1, 10000], 3000))])
    src = tmp_path / "log.csv"
    src.write_text("micros,gx,gy,gz\n" + "".join(f"{s},1,2,3\n" for s in stamps))
    assert main(["convert", str(src), "--unit", "dps", "--out", str(tmp_path / "rec.csv"), *rate]) == 2
    err = capsys.readouterr().err
    said = "not at --sample-rate-hz (without it, the stamps' rate is taken)" if rate else "give the rate in --sample-rate-hz"
    assert err.count("gyrofilter: error: ") == 1 and said in err, err  # a new user's trial: not to give what was given


def test_a_given_rate_is_said_beside_the_stamps_rate(tmp_path, capsys):
    """Attack pass 9 (issue 37): --sample-rate-hz 104 for stamps 10 ms apart wrote 104 Hz (within the
    reader's 5 % tolerance of t), the summary saying only "rate 104 Hz as given" and a jitter of
    "-1.8e-11 % .. +5.3e-11 %" (float noise); it now states the stamps' rate beside the one given."""
    src = tmp_path / "log.csv"
    src.write_text("millis,gx,gy,gz\n" + "".join(f"{10 * k},1,2,3\n" for k in range(3000)))
    dst = tmp_path / "rec.csv"
    assert main(["convert", str(src), "--unit", "dps", "--out", str(dst), "--sample-rate-hz", "104"]) == 0
    err = capsys.readouterr().err
    assert "rate 104 Hz as given (the stamps' mean step: 100 Hz)" in err, err
    assert "within +0 % .. +0 % of the median (10 ms)" in err, err
    assert read_recording(dst).sample_rate_hz == 104


def test_times_are_written_as_the_stamps_decimal_values(tmp_path, capsys):
    """The new user's converted t column showed float noise (0.030286365000000003 for a stamp
    30286365 ns after the first): each time is now the exact decimal offset rounded once."""
    gyro = _rates(4, np.pi / 180)
    stamps = _jittered_ns(5)
    rows = "\n".join(f"{s},{x},{y},{z}" for s, (x, y, z) in zip(stamps.tolist(), gyro.tolist()))
    rc, dst = _convert(tmp_path, "timestamp,gyro_x,gyro_y,gyro_z\n" + rows + "\n", "--unit", "rad/s", out="rec.csv")
    assert rc == 0, capsys.readouterr().err
    t_texts = [line.split(",")[0] for line in dst.read_text().splitlines() if line[:1].isdigit()]
    assert len(t_texts) == N
    assert t_texts == [str(float(f"{(s - stamps[0]) / 1e9:.9f}")) for s in stamps.tolist()]


@pytest.mark.parametrize("digits", ["\uff11,\uff12,\uff13,\uff14", "\u00b9,2,3,4", "\u0661,2,3,4"])
def test_columns_in_other_scripts_digits_are_refused(tmp_path, capsys, digits):
    """Issue 37 (attack): ``--columns １,２,３,４`` (full-width digits) was read as 1,2,3,4 by
    str.isdigit/int, and ``¹`` (isdigit, but no int) ended in "invalid literal for int()"; a number
    a user gives is ASCII digits everywhere (gyrofilter.inputs)."""
    rows = "".join(f"{i * 0.01:.2f},0.1,0.2,0.3\n" for i in range(50))
    rc, dst = _convert(tmp_path, "a,b,c,d\n" + rows, "--unit", "dps", "--columns", digits)
    assert rc == 2 and not dst.exists()
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and f"--columns: no column '{digits[0]}'" in err
    rc, dst = _convert(tmp_path, "a,b,c,d\n" + rows, "--unit", "dps", "--columns", "1,2,3,4")
    assert rc == 0


#: run in a fresh interpreter: convert, then its own peak resident memory (VmHWM: this process
#: image's peak; ru_maxrss would carry the parent's across fork + exec)
_PEAK = """
import json, sys
from gyrofilter.cli import main
rc = main(sys.argv[1:])
peak_kb = next(int(ln.split()[1]) for ln in open("/proc/self/status") if ln.startswith("VmHWM:"))
print(json.dumps({"rc": rc, "peak_mb": peak_kb / 1024}))
"""


@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="needs /proc (Linux) for the peak memory")
def test_a_million_row_log_converts_in_bounded_memory(tmp_path):
    """Issue 37 (attack): convert held every cell as a Python string, 457 MB for 1,000,000 rows (a
    day at 1 kHz: ~37 GB, MemoryError); it reads in chunks now and keeps 16 bytes a row. The phone
    log's time unit is inferred (its offsets kept), and the output reads back with its values."""
    n = 1_000_000
    rng = np.random.default_rng(11)
    stamps = 1_732_000_000_123_456_789 + np.concatenate(([0], np.cumsum(rng.integers(999_000, 1_001_000, n - 1))))
    gyro = np.round(rng.standard_normal((n, 3)) * 0.01, 6)
    src, dst = tmp_path / "phone.csv", tmp_path / "rec.csv.gz"
    with open(src, "w") as fh:
        fh.write("timestamp,gyro_x,gyro_y,gyro_z\n")
        fh.writelines(f"{s},{x},{y},{z}\n" for s, (x, y, z) in zip(stamps.tolist(), gyro.tolist()))
    done = subprocess.run([sys.executable, "-c", _PEAK, "convert", str(src), "--out", str(dst), "--unit", "rad/s"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["rc"] == 0 and result["peak_mb"] < 200, result  # the whole-file reader's peak: 488 MB
    rec = read_recording(dst)
    _check_same(rec, gyro, (stamps - stamps[0]) * 1e-9)
    assert rec.header["time_origin"] == f"{stamps[0]} ns (timestamp)" and abs(rec.sample_rate_hz - 1000) < 0.01


@pytest.mark.parametrize("change", ["longer", "shorter", "not a number"])
def test_a_log_that_changes_between_the_passes_is_refused(tmp_path, change):
    """convert reads its log more than once (a checking pass first, then the writer's): a log
    changed in between is refused in one sentence, not written from rows nobody checked."""
    from gyrofilter.errors import RecordingError
    from gyrofilter.recording.foreign import read_foreign

    src = tmp_path / "log.csv"
    rows = [f"{i * 0.01:.2f},0.1,0.2,0.3\n" for i in range(300)]
    src.write_text("t,gx_dps,gy_dps,gz_dps\n" + "".join(rows))
    with read_foreign(src) as foreign:
        assert foreign.rows == 300
        if change == "not a number":
            rows[100] = "1.00,0.1,x,0.3\n"
        src.write_text("t,gx_dps,gy_dps,gz_dps\n" + "".join(rows[:299] if change == "shorter" else
                                                          rows + ["3.00,0,0,0\n"] if change == "longer" else rows))
        with pytest.raises(RecordingError, match="log.csv: changed while it was read"):
            for _ in foreign.chunks():
                pass


@pytest.mark.parametrize("how", ["file", "gzip"])
def test_a_log_whose_line_ends_turn_cr_only_is_refused_from_that_line(tmp_path, capsys, how):
    """Attack pass 16 (issue 37): LF lines, then CR-only ones with no LF after them: the rest read as
    one last line an interruption cut, dropped with a warning ("log interrupted?"), 4 rows of 300
    converted. Refused naming the line where the line ends turn."""
    data = ("t,gx,gy,gz\n" + "".join(f"{i / 100:.2f},1,2,3\n" for i in range(4))
            + "".join(f"{i / 100:.2f},1,2,3\r" for i in range(4, 300))).encode()
    src = tmp_path / "late.csv"
    src.write_bytes(gzip.compress(data) if how == "gzip" else data)
    assert main(["convert", str(src), "--out", str(tmp_path / "rec.csv"), "--unit", "dps"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"gyrofilter: error: {src}: line 6: line ends are CR only from there on (old Mac): convert them to LF (e.g. tr '\\r' '\\n')"
    assert not (tmp_path / "rec.csv").exists()


@pytest.mark.parametrize("rows, how", [(3, "file"), (3, "gzip"), (120_000, "file"), (120_000, "pipe")])
def test_a_log_of_cr_only_line_ends_is_refused_naming_them(tmp_path, capsys, rows, how):
    """Attack pass (issue 37): a log with CR-only line ends (classic Mac OS) read as one line of
    column names ("no column for the gyro's z among 't, gx, gy, gz\\r0, 1, ..."); past 1 MiB it was
    "line 1: longer than ... bytes". Now one line names the file and the line ends, read from a
    file, gzip or a pipe alike."""
    data = ("t,gx,gy,gz\r" + "".join(f"{i / 100:.2f},1,2,3\r" for i in range(rows))).encode()
    src = tmp_path / "mac.csv"
    src.write_bytes(gzip.compress(data) if how == "gzip" else data)
    if how == "pipe":
        rc, _ = _convert_pipe(tmp_path, data)
        src = "/dev/fd/"
    else:
        rc = main(["convert", str(src), "--out", str(tmp_path / "rec.csv"), "--unit", "dps"])
    assert rc == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"gyrofilter: error: {src}") and err.endswith(": line ends are CR only (old Mac): convert them "
                                                                          "to LF (e.g. tr '\\r' '\\n')")
    assert len(err.splitlines()) == 1


@pytest.mark.parametrize("zipped", [False, True])
@pytest.mark.parametrize("head", [b"", b"time_ms,gx_dps,gy_dps,gz_dps\n# a comment\r\n"])
def test_a_piped_log_without_rows_is_refused_as_it_is_copied(tmp_path, capsys, monkeypatch, head, zipped):
    """Attack pass 8 (issue 37's leftover): ``convert -`` copied a pipe whole (up to 4 GiB) before
    the bound on blank and comment lines before the first data row applied; the lines are now
    counted as the pipe is copied, and the copy stops at the bound. The pipe offers 4 MB of
    blank lines (gzip-compressed as a stream, flushed block by block, when ``zipped``) against a
    1 MB bound and stays open: the refusal comes before its end. A data row after as many
    blank lines within the bound is read."""
    from gyrofilter.recording import header
    monkeypatch.setattr(header, "MAX_BYTES_BEFORE_ROWS", 1 << 20)
    read_end, write_end = os.pipe()
    ended = threading.Event()

    def feed():
        packer = zlib.compressobj(6, zlib.DEFLATED, 31)
        with contextlib.suppress(BrokenPipeError), open(write_end, "wb", buffering=0) as fh:
            for block in [head] + [b"\n" * (1 << 16)] * 64:
                fh.write(packer.compress(block) + packer.flush(zlib.Z_SYNC_FLUSH) if zipped else block)
            ended.wait(60)  # the pipe stays open: a copy that waits for its end waits for this

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    dst, said = tmp_path / "rec.csv", []
    reader = threading.Thread(target=lambda: said.append(main(["convert", f"/dev/fd/{read_end}", "--unit", "dps",
                                                                 "--out", str(dst)])), daemon=True)
    reader.start()
    reader.join(timeout=30)
    refused_before_the_end = not reader.is_alive()
    ended.set()
    reader.join(timeout=30)
    os.close(read_end)
    writer.join(timeout=10)
    assert refused_before_the_end and said == [2] and not dst.exists()
    assert capsys.readouterr().err == (f"gyrofilter: error: /dev/fd/{read_end}: no data rows in the first 1 MB (only "
                                       "blank or comment lines); not a log of rates\n")
    text = head or b"time_ms,gx_dps,gy_dps,gz_dps\n"  # _convert_pipe gives --time-unit ms
    rc, dst = _convert_pipe(tmp_path, text + b"\n" * (900 << 10) + b"0,1,2,3\n0.01,1,2,3\n" + b"\n" * (3 << 20))
    assert rc == 0 and len(read_recording(dst)) == 2


@pytest.mark.parametrize("head", [b"", b"# a phone logger\ntime_s,gx_dps,gy_dps,gz_dps\n"])
def test_a_log_without_rows_is_refused_once_its_blank_lines_pass_the_bound(tmp_path, capsys, monkeypatch, head):
    """Issue 37 (attack 6): a gzip of 2 GiB of line ends took 64 s to refuse ("no data"), every
    run of them read past whole before anything was counted. The blank and comment lines before
    the first data row are counted as they are read (a run of them in items of at most
    MAX_RUN_BYTES) and refused past MAX_BYTES_BEFORE_ROWS; as many blank lines after a data row
    are read (the rows around them kept)."""
    from gyrofilter.recording import header, logtext
    monkeypatch.setattr(header, "MAX_BYTES_BEFORE_ROWS", 1 << 20)
    monkeypatch.setattr(logtext, "MAX_RUN_BYTES", 1 << 16)
    reads = [0]
    skip = logtext._skip_empty_lines

    def counted(fh):
        reads[0] += 1
        return skip(fh)
    monkeypatch.setattr(logtext, "_skip_empty_lines", counted)
    path = tmp_path / "blank.csv.gz"
    path.write_bytes(gzip.compress(head + b"\n" * (8 << 20)))
    assert main(["convert", str(path), "--out", str(tmp_path / "rec.csv")]) == 2
    assert capsys.readouterr().err == (f"gyrofilter: error: {path}: no data rows in the first 1 MB (only blank or "
                                       "comment lines); not a log of rates\n")
    assert reads[0] <= (1 << 20) // (1 << 16) + 1  # refused after 1 MB read, not the 8 MB
    path.write_bytes(gzip.compress(b"time_s,gx_dps,gy_dps,gz_dps\n0,1,2,3\n" + b"\n" * (3 << 20) + b"0.01,1,2,3\n"))
    assert main(["convert", str(path), "--out", str(tmp_path / "rec.csv")]) == 0
    assert len(read_recording(tmp_path / "rec.csv")) == 2


@pytest.mark.parametrize("zipped", [False, True])
def test_a_last_line_cut_short_is_left_out_with_a_warning(tmp_path, capsys, zipped):
    """Attack pass 12 (issue 37): a log whose writer was stopped mid-line (a logger killed, a
    power cut) ends in a line without its line end, cut inside a number: ``...,-0.09736`` kept as
    ``-0.09``, a plain decimal, so the sample was written with a wrong value and not a word. As the
    recording reader does (docs/formats.md, section 1), the last line without its line end is
    not used and a warning says so; every complete line is converted as before."""
    rows = [f"{i / 100:.2f},{i % 7 - 3}.25,0.5,-0.09736" for i in range(301)]
    data = ("time_s,gx_dps,gy_dps,gz_dps\n" + "\n".join(rows[:300]) + "\n" + rows[300][:-3]).encode()  # '-0.09'
    src = tmp_path / ("cut.csv.gz" if zipped else "cut.csv")
    src.write_bytes(gzip.compress(data) if zipped else data)
    assert main(["convert", str(src), "--out", str(tmp_path / "rec.csv")]) == 0
    err = " ".join(capsys.readouterr().err.split())  # a warning is wrapped at 100 columns
    assert f"gyrofilter: warning: {src}: line 302: last line has no line end (log interrupted?); it is not used" in err
    rec = read_recording(tmp_path / "rec.csv")
    assert len(rec) == 300 and np.all(rec.gyro[:, 2] == -0.09736)
    src.write_bytes(gzip.compress(data + b"\n") if zipped else data + b"\n")  # the line ended: a row like any
    assert main(["convert", str(src), "--out", str(tmp_path / "rec.csv"), "--force"]) == 0
    assert "warning" not in capsys.readouterr().err and len(read_recording(tmp_path / "rec.csv")) == 301


def test_a_gzip_log_cut_short_is_read_to_the_cut_with_a_warning_as_a_recording_is(tmp_path, capsys):
    """Issue 37 (attack passes 12-14): a gzip log whose stream ends before its end marker (a logger
    killed, a copy interrupted) was refused whole ("damaged gzip data (Compressed file ended before
    the end-of-stream marker was reached)"), while a recording so cut is read with a warning. One
    rule for both, the reader's: the complete lines before the cut are converted, a warning names
    the file and the last line read; the recording written reads back those rows."""
    rows = "".join(f"{i / 100:.2f},{i % 7 - 3}.25,0.5,-0.125\n" for i in range(20000))
    data = gzip.compress(("time_s,gx_dps,gy_dps,gz_dps\n" + rows).encode(), compresslevel=1)
    src, dst = tmp_path / "cut.csv.gz", tmp_path / "rec.csv"
    src.write_bytes(data[:len(data) // 2])
    kept = data[:len(data) // 2 - HOLD_BYTES]  # (the text of the last bytes before a cut is left out: attack pass 63)
    lines = zlib.decompressobj(16 + zlib.MAX_WBITS).decompress(kept).count(b"\n")  # complete lines
    assert main(["convert", str(src), "--out", str(dst)]) == 0
    err = " ".join(capsys.readouterr().err.split())
    assert (f"gyrofilter: warning: {src}: gzip stream cut short (no end marker), as an interrupted recording leaves "
            f"it; read to line {lines}") in err
    rec = read_recording(dst)
    assert len(rec) == lines - 1 and 1000 < len(rec) < 20000 and np.all(rec.gyro[:, 2] == -0.125)
    cut_recording = tmp_path / "cut-rec.csv.gz"
    whole = gzip.compress(dst.read_bytes(), compresslevel=1)
    cut_recording.write_bytes(whole[:len(whole) // 2])
    assert any(w.startswith(f"{cut_recording}: gzip stream cut short (no end marker), as an interrupted recording "
                            "leaves it") for w in read_recording(cut_recording).warnings)


@pytest.mark.parametrize("name", ["rec.csv", "rec.csv.gz"])
def test_a_gyrofilter_recording_is_refused_naming_its_header(tmp_path, capsys, name):
    """Attack pass 12 (issue 37): convert read a recording of format v1 as a log whose header lines
    were comments: ``gyro_unit: lsb`` and ``lsb_per_dps: 131`` skipped, ``--unit dps`` took LSB as
    deg/s (131 times the rate) and a filtered output lost its ``filtered_from`` (filtered again,
    its Kalibr yaml the filter's), without a word. A recording is read by every command as it is:
    convert refuses it, naming the line of its version key, and writes nothing."""
    text = ("# a note before it\n# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: lsb\n"
            "# lsb_per_dps: 131\nt,gx,gy,gz\n" + "".join(f"{i / 100:.2f},{i % 9 - 4},131,-262\n" for i in range(300)))
    src = tmp_path / name
    src.write_bytes(gzip.compress(text.encode()) if name.endswith(".gz") else text.encode())
    dst = tmp_path / "out.csv"
    assert main(["convert", str(src), "--unit", "dps", "--out", str(dst)]) == 2
    assert capsys.readouterr().err == (f"gyrofilter: error: {src}: line 2: already a gyrofilter recording (format v1; "
                                       "every command reads it as it is): convert is for other tools' logs\n")
    assert not dst.exists()
    src.write_text(text.replace("# gyrofilter-recording: 1", "# exported by gyrofilter-recording-tool 1"))
    assert main(["convert", str(src), "--unit", "lsb", "--lsb-per-dps", "131", "--out", str(dst), "--force"]) == 0


def test_a_column_named_twice_is_refused_when_columns_names_it(tmp_path, capsys):
    """Attack pass 25: a log of ``time,x,y,z,x,y,z`` (gyro, then accelerometer) is refused by name
    (two candidates for x), and the refusal says to name the three in --columns; ``--columns
    time,x,y,z`` then took the first of each pair without a word. Refused: give its number."""
    rows = "".join(f"{i / 100},{i},{-i},1,9.81,0.1,0.2\n" for i in range(20))
    rc, dst = _convert(tmp_path, "time,x,y,z,x,y,z\n" + rows, "--unit", "dps", "--columns", "time,x,y,z")
    assert rc == 2 and not dst.exists()
    assert "--columns: 'x' names columns 2 and 5; give its number" in capsys.readouterr().err
    rc, dst = _convert(tmp_path, "time,x,y,z,x,y,z\n" + rows, "--unit", "dps", "--columns", "1,2,3,4")
    assert rc == 0, capsys.readouterr().err


def test_a_time_unit_the_name_states_and_convert_does_not_know_is_refused(tmp_path, capsys):
    """Attack pass 25: ``time (min)`` was read as s (the first unit giving 5 Hz or more): 100 Hz written as 6000 Hz."""
    rows = "".join(f"{i / 6000:.8f},{i % 7},1,2\n" for i in range(600))
    rc, dst = _convert(tmp_path, "time (min),gx (deg/s),gy (deg/s),gz (deg/s)\n" + rows)
    assert rc == 2 and not dst.exists()
    assert "time column 'time (min)' states 'min', a unit convert does not read; give --time-unit s, ms, us, ns only if" \
        in capsys.readouterr().err
    rows = "".join(f"{10 * i},{i % 7},1,2\n" for i in range(600))
    rc, dst = _convert(tmp_path, "time (msec),gx (deg/s),gy (deg/s),gz (deg/s)\n" + rows)
    assert rc == 0 and "in ms (as its name states" in capsys.readouterr().err


# ------------------------------------------------------------------------ temperature and accelerometer

def _six_axis_log(temp_name="TempC", temp=None, accel_names=("AccX (g)", "AccY (g)", "AccZ (g)"), n=400, seed=3):
    """An Arduino-like log at 100 Hz in ms: t, three gyro columns in deg/s, a temperature and three
    accelerometer columns; (text, gyro, temp, accel)."""
    rng = np.random.default_rng(seed)
    gyro = np.round(rng.normal(0, 0.1, (n, 3)), 4)
    temp = np.round(25 + 0.01 * np.arange(n) / n, 3) if temp is None else temp
    accel = np.round(np.array([0.0, 0.0, 1.0]) + 0.002 * rng.standard_normal((n, 3)), 5)
    names = ["time_ms", "gx", "gy", "gz"] + ([temp_name] if temp_name else []) + list(accel_names)
    rows = [",".join([str(10 * i)] + [repr(v) for v in gyro[i].tolist()] + ([repr(float(temp[i]))] if temp_name else [])
                     + [repr(v) for v in accel[i].tolist()]) for i in range(n)]
    return ",".join(f'"{c}"' if " " in c else c for c in names) + "\n" + "\n".join(rows) + "\n", gyro, temp, accel


def test_a_temperature_in_deg_c_and_the_accelerometer_are_kept(tmp_path, capsys):
    """A new user's trial: convert said "left out: TempC" (and the accelerometer): the temperature
    compensation and the gap analysis's temperature reading had nothing to read. A column named
    like a temperature in deg C is the recording's temp, AccX/AccY/AccZ in g its ax, ay, az with
    accel_unit g: the values as they are."""
    text, gyro, temp, accel = _six_axis_log()
    rc, dst = _convert(tmp_path, text, "--unit", "dps")
    err = capsys.readouterr().err
    assert rc == 0, err
    rec = read_recording(dst)
    assert np.array_equal(rec.gyro, gyro) and np.array_equal(rec.temp_c, temp)
    assert rec.accel_unit == "g" and np.array_equal(np.column_stack([rec.columns[c] for c in ("ax", "ay", "az")]), accel)
    assert "left out" not in err and "temp 'TempC' in deg C" in err and "ax 'AccX (g)'" in err, err


def test_raw_mpu6050_temperature_counts_need_their_unit_said(tmp_path, capsys):
    """TEMP of raw MPU6050 counts has no unit in its name: left out, a warning naming --temp-unit
    (never written as deg C); with --temp-unit mpu6050, deg C = counts / 340 + 36.53 (register map 4.18)."""
    counts = np.arange(-2600, -2600 + 400, dtype=float)
    text, gyro, _, _ = _six_axis_log("TEMP", temp=counts, accel_names=("ax", "ay", "az"))
    text = text.replace(repr(-2600.0), "-2600")
    rc, dst = _convert(tmp_path, text, "--unit", "dps")
    err = capsys.readouterr().err
    assert rc == 0 and "temp" not in read_recording(dst).columns, err
    assert "'TEMP' left out: its unit is not stated" in err and "--temp-unit mpu6050" in err
    assert "--accel-unit" in err and "ax" not in read_recording(dst).columns  # ax, ay, az in no stated unit either
    rc, dst = _convert(tmp_path, text, "--unit", "dps", "--temp-unit", "mpu6050", "--accel-unit", "g", out="raw.csv")
    assert rc == 0, capsys.readouterr().err
    rec = read_recording(dst)
    np.testing.assert_allclose(rec.temp_c, counts / 340 + 36.53, rtol=0, atol=1e-12)
    assert rec.accel_unit == "g"


@pytest.mark.parametrize("names, options, said", [
    (("temp_c", "TEMP"), [], "columns 'temp_c', 'TEMP' could each be the temperature"),
    (("TempC",), ["--temp-unit", "mpu6050"], "--temp-unit mpu6050, but column 'TempC' states deg C"),
    (("gz_dummy",), ["--temp-unit", "c"], "--temp-unit c: no temperature column"),
    (("TempC", "acc_x"), [], "columns 'AccX (g)', 'acc_x' could each be the accelerometer's x"),
    (("TempC",), ["--accel-unit", "lsb"], "--accel-unit lsb, but the accelerometer columns state g"),
    (("TempC",), ["--lsb-per-g", "16384"], "--lsb-per-g goes with an accelerometer in lsb, not g"),
])
def test_ambiguous_temperature_and_accelerometer_columns_are_refused_naming_them(tmp_path, capsys, names, options, said):
    text, _, _, _ = _six_axis_log(names[0])
    if len(names) > 1:  # a second candidate, a copy of the first
        head, rest = text.split("\n", 1)
        text = head + f",{names[1]}\n" + "\n".join(f"{row},{row.split(',')[4]}" for row in rest.splitlines()) + "\n"
    rc, dst = _convert(tmp_path, text, "--unit", "dps", *options)
    err = capsys.readouterr().err
    assert rc == 2 and not dst.exists() and err.count("\n") == 1 and said in err, err


def test_a_temperature_beyond_any_die_is_refused_naming_its_line(tmp_path, capsys):
    """Raw counts in a column named in deg C (TempC of -2600) would be written as -2600 deg C."""
    text, _, _, _ = _six_axis_log(temp=np.full(400, -2600.0))
    rc, dst = _convert(tmp_path, text, "--unit", "dps")
    err = capsys.readouterr().err
    assert rc == 2 and not dst.exists() and err.count("\n") == 1, err
    assert "line 2, column 5 ('TempC'): -2600 deg C is beyond" in err and "--temp-unit none" in err, err


def test_an_accelerometer_in_lsb_needs_its_scale_and_a_partial_one_is_left_out_saying_so(tmp_path, capsys):
    text, _, _, _ = _six_axis_log(accel_names=("ax_lsb", "ay_lsb", "az_lsb"))
    rc, _ = _convert(tmp_path, text, "--unit", "dps")
    assert rc == 2 and "give --lsb-per-g" in capsys.readouterr().err
    rc, dst = _convert(tmp_path, text, "--unit", "dps", "--lsb-per-g", "16384")
    assert rc == 0 and read_recording(dst).lsb_per_g == 16384 and read_recording(dst).accel_unit == "lsb"
    capsys.readouterr()
    text, _, _, _ = _six_axis_log(accel_names=("AccX (g)", "AccY (g)", "other"))
    rc, dst = _convert(tmp_path, text, "--unit", "dps", out="partial.csv")
    err = capsys.readouterr().err
    assert rc == 0 and "ax" not in read_recording(dst).columns
    assert "accelerometer column(s) 'AccX (g)', 'AccY (g)' left out: no column for its z" in err, err


def test_a_time_unit_given_that_contradicts_the_name_is_refused_as_the_gyro_unit_is(tmp_path, capsys):
    """Attack pass 26: ``--time-unit s`` on ``time_ms`` overrode the name without a word (10 ms
    steps read as 10 s: 0.1 Hz written); a ``--unit`` that contradicts the names is refused, and so is this."""
    rows = "".join(f"{10 * i},{i % 7},1,2\n" for i in range(600))
    rc, dst = _convert(tmp_path, "time_ms,gx_dps,gy_dps,gz_dps\n" + rows, "--time-unit", "s")
    assert rc == 2 and not dst.exists()
    assert "--time-unit s, but the time column 'time_ms' states ms" in capsys.readouterr().err
    rc, dst = _convert(tmp_path, "time_ms,gx_dps,gy_dps,gz_dps\n" + rows, "--time-unit", "ms")
    assert rc == 0, capsys.readouterr().err
    # a unit the name states and convert does not know is what the option is for (its refusal asks for it)
    rows = "".join(f"{i / 100:.2f},{i % 7},1,2\n" for i in range(600))
    rc, dst = _convert(tmp_path, "time (sek),gx (deg/s),gy (deg/s),gz (deg/s)\n" + rows, "--time-unit", "s", "--force")
    assert rc == 0 and read_recording(dst).sample_rate_hz == 100, capsys.readouterr().err


@pytest.mark.parametrize("name, stated", [("time (seconds)", "s"), ("timestamp (millis)", "ms"),
                                          ("t [microseconds]", "us"), ("time (\u03bcs)", "us")])
def test_a_time_unit_spelled_out_in_brackets_is_the_unit_it_states(tmp_path, capsys, name, stated):
    """Attack pass 27: ``time (seconds)`` with ``--time-unit ms`` was read in ms (1000 x the rate,
    exit 0): a bracket's whole word (``seconds``, ``millis``, the Greek mu's ``μs``) was no unit
    convert knew, so the option took it over; it states its unit as ``time (s)`` does."""
    other = "ms" if stated != "ms" else "s"
    rows = "".join(f"{i},{i % 7},1,2\n" for i in range(600))
    rc, dst = _convert(tmp_path, f"{name},gx (deg/s),gy (deg/s),gz (deg/s)\n" + rows, "--time-unit", other)
    assert rc == 2 and not dst.exists()
    assert f"--time-unit {other}, but the time column '{name}' states {stated}" in capsys.readouterr().err


# ------------------------------------------------------------------------ unit spellings (issue 37 follow-up)

def _unit_log(names, cells, n=300):
    """A log at 100 Hz in ms of the columns ``names`` after ``time_ms``, every row the ``cells``."""
    return "time_ms," + ",".join(f'"{c}"' if " " in c or "," in c else c for c in names) + "\n" + "".join(
        f"{10 * i}," + ",".join(cells) + "\n" for i in range(n))


_GYRO = ["gx", "gy", "gz"]


def _gyro_named(unit):
    return [f"{g} ({unit})" for g in _GYRO]


@pytest.mark.parametrize("names, unit", [
    (_gyro_named("rad/sec"), "rad/s"), (_gyro_named("deg/sec"), "dps"), (["gyro_x (deg/sec)", "gyro_y (deg/sec)",
                                                                        "gyro_z (deg/sec)"], "dps"),
    (_gyro_named("°/s"), "dps"), (_gyro_named("°/sec"), "dps"), (_gyro_named("deg s-1"), "dps"),
    (_gyro_named("degrees/s"), "dps"), (_gyro_named("rad*s^-1"), "rad/s"), (_gyro_named("rad s^-1"), "rad/s"),
    ([f"{g} [rad s-1]" for g in _GYRO], "rad/s"), (["gx_deg_sec", "gy_deg_sec", "gz_deg_sec"], "dps"),
    (["gyro_x_rad_per_sec", "gyro_y_rad_per_sec", "gyro_z_rad_per_sec"], "rad/s"),
])
def test_common_spellings_of_a_gyro_unit_are_read_and_agree_with_the_option(tmp_path, capsys, names, unit):
    """Issue 37 follow-up: ``gx (rad/sec)``, ``gyro_x (deg/sec)``, ``gx [rad s-1]`` were "not stated",
    and the --unit the refusal asked for was then refused as contradicting them (a dead end)."""
    text = _unit_log(names, ["0.1", "0.2", "0.3"])
    rc, dst = _convert(tmp_path, text)
    assert rc == 0 and read_recording(dst).gyro_unit == unit, capsys.readouterr().err
    rc, dst = _convert(tmp_path, text, "--unit", unit, out="given.csv")
    assert rc == 0 and read_recording(dst).gyro_unit == unit, capsys.readouterr().err


def test_units_convert_converts_are_converted_exactly_and_said(tmp_path, capsys):
    """mg (ADXL/LIS logs) -> g, mdps (ST's) -> dps by 10^-3, deg F -> deg C by (F - 32) * 5/9, K by
    K - 273.15: each decimal converted exactly and rounded once (98.6 degF is 37, not 36.99999999999999)."""
    names = _gyro_named("mdps") + ["Temp (degF)", "ax (mg)", "ay (mg)", "az (mg)"]
    rc, dst = _convert(tmp_path, _unit_log(names, ["1500", "-0.3", "7", "98.6", "1", "-2", "1000.5"]))
    err = capsys.readouterr().err
    assert rc == 0, err
    rec = read_recording(dst)
    assert rec.gyro_unit == "dps" and rec.accel_unit == "g"
    assert rec.gyro[0].tolist() == [1.5, -0.0003, 0.007] and rec.temp_c[0] == 37.0
    assert [rec.columns[c][0] for c in ("ax", "ay", "az")] == [0.001, -0.002, 1.0005]
    assert "in dps (mdps, converted to dps: / 1000)" in err and "in g (mg, converted to g: / 1000)" in err
    assert "temp 'Temp (degF)' in deg F, converted to deg C: (F - 32) * 5/9" in err, err
    rc, dst = _convert(tmp_path, _unit_log(_GYRO + ["Temp (°F)"], ["1", "2", "3", "212"]), "--unit", "dps",
                       out="f.csv")
    assert rc == 0 and read_recording(dst).temp_c[0] == 100.0, capsys.readouterr().err
    rc, dst = _convert(tmp_path, _unit_log(_GYRO + ["temperature (K)"], ["1", "2", "3", "300.15"]), "--unit", "dps",
                       out="k.csv")
    assert rc == 0 and read_recording(dst).temp_c[0] == 27.0, capsys.readouterr().err


def test_milliradians_per_second_are_converted_and_an_unread_unit_is_said_as_one(tmp_path, capsys):
    """Attack pass 28c's note: ``gx (mrad/s)`` was refused as "the gyro unit is not stated", asking for
    --unit rad/s, which then wrote the values 1000 times too large. mrad/s is read (/ 1000 to rad/s),
    and a unit convert does not read is named as stated, --unit taken only as what it means."""
    rc, dst = _convert(tmp_path, _unit_log(_gyro_named("mrad/s"), ["1500", "-0.3", "7"]))
    err = capsys.readouterr().err
    assert rc == 0 and "in rad/s (mrad/s, converted to rad/s: / 1000)" in err, err
    rec = read_recording(dst)
    assert rec.gyro_unit == "rad/s" and rec.gyro[0].tolist() == [1.5, -0.0003, 0.007]
    rc, dst = _convert(tmp_path, _unit_log(_gyro_named("krad/s"), ["1", "2", "3"]), out="k.csv")
    assert rc == 2 and not dst.exists()
    assert "the gyro columns state 'krad/s', a unit convert does not read; give --unit dps, rad/s, mdps, mrad/s or " \
        "lsb (with --lsb-per-dps) only if it means one of them" in capsys.readouterr().err


def test_an_ambiguous_temperature_unit_is_resolved_by_the_option(tmp_path, capsys):
    """Issue 37 follow-up: ``temp (deg)`` asked for --temp-unit c, then refused it as contradicting "deg"."""
    text = _unit_log(_GYRO + ["temp (deg)"], ["1", "2", "3", "25.5"])
    rc, dst = _convert(tmp_path, text, "--unit", "dps")
    err = capsys.readouterr().err
    assert rc == 0 and "temp" not in read_recording(dst).columns and "--temp-unit c, f or k" in err, err
    rc, dst = _convert(tmp_path, text, "--unit", "dps", "--temp-unit", "c", out="c.csv")
    assert rc == 0 and read_recording(dst).temp_c[0] == 25.5, capsys.readouterr().err
    rc, dst = _convert(tmp_path, text, "--unit", "dps", "--temp-unit", "f", out="f.csv")
    assert rc == 0 and read_recording(dst).temp_c[0] == float((Fraction("25.5") - 32) * 5 / 9), capsys.readouterr().err


_ROW = ["1", "2", "3"]


@pytest.mark.parametrize("names, cells, options, suggested", [
    # the gyro: a unit not in the table, a unit given that contradicts the names', lsb without its scale
    (_gyro_named("rpm"), _ROW, [], ["--unit", "dps"]),
    (_gyro_named("deg/sec"), _ROW, ["--unit", "rad/s"], ["--unit", "dps"]),
    (_GYRO, _ROW, ["--unit", "lsb"], ["--unit", "lsb", "--lsb-per-dps", "131"]),
    # one gyro name's text no unit of the table (a typo, an invisible character): the option says it (pass 28c: a dead end)
    (["gx (dps)", "gy (dps)", "gz (dsp)"], _ROW, [], ["--unit", "dps"]),
    (["gx (dps)", "gy (d\u200bps)", "gz (dps)"], _ROW, ["--unit", "rad/s"], ["--unit", "dps"]),
    # the time
    (_gyro_named("dps"), _ROW, ["--time-unit", "s"], ["--time-unit", "ms"]),
    # the temperature: contradicted, beyond any die (stated, given), two candidates
    (_GYRO + ["TempC"], _ROW + ["25"], ["--unit", "dps", "--temp-unit", "mpu6050"], ["--unit", "dps", "--temp-unit", "c"]),
    (_GYRO + ["Temp (degF)"], _ROW + ["77"], ["--unit", "dps", "--temp-unit", "c"], ["--unit", "dps", "--temp-unit", "f"]),
    (_GYRO + ["TempC"], _ROW + ["-2600"], ["--unit", "dps"], ["--unit", "dps", "--temp-unit", "none"]),
    (_GYRO + ["TEMP"], _ROW + ["-2600"], ["--unit", "dps", "--temp-unit", "c"], ["--unit", "dps", "--temp-unit", "mpu6050"]),
    (_GYRO + ["temp_c", "TEMP"], _ROW + ["25", "25"], ["--unit", "dps"], ["--unit", "dps", "--temp-unit", "none"]),
    # the accelerometer: contradicted, a unit not in the table, units that differ, two candidates, lsb
    (_GYRO + ["ax (mg)", "ay (mg)", "az (mg)"], _ROW * 2, ["--unit", "dps", "--accel-unit", "g"],
     ["--unit", "dps", "--accel-unit", "mg"]),
    (_GYRO + ["ax (furlong)", "ay (furlong)", "az (furlong)"], _ROW * 2, ["--unit", "dps"],
     ["--unit", "dps", "--accel-unit", "m/s^2"]),
    (_GYRO + ["ax (g)", "ay (mg)", "az (g)"], _ROW * 2, ["--unit", "dps"], ["--unit", "dps", "--accel-unit", "none"]),
    (_GYRO + ["ax (m/s^2)", "ay (m/ss)", "az (m/s^2)"], _ROW * 2, ["--unit", "dps"], ["--unit", "dps", "--accel-unit", "m/s^2"]),
    (_GYRO + ["ax", "ay", "az", "acc_x"], _ROW * 2 + ["1"], ["--unit", "dps"], ["--unit", "dps", "--accel-unit", "none"]),
    (_GYRO + ["ax_lsb", "ay_lsb", "az_lsb"], _ROW * 2, ["--unit", "dps"], ["--unit", "dps", "--lsb-per-g", "16384"]),
])
def test_every_refusal_of_a_unit_names_an_option_that_is_then_taken(tmp_path, capsys, names, cells, options, suggested):
    """No dead ends (issue 37 follow-up): a refusal of the unit rules names an option and a value
    (``suggested``'s last option and value are in its line; a scale's value as its example), and the command with them is taken
    (or leaves the column out). Before: ``TempC`` of raw counts asked for --temp-unit mpu6050,
    then refused it as contradicting the name's deg C; ``ax (mg)`` asked for --accel-unit g, then refused it."""
    text = _unit_log(names, cells)
    rc, dst = _convert(tmp_path, text, *options)
    err = capsys.readouterr().err
    assert rc == 2 and not dst.exists() and err.count("\n") == 1, err
    said = f"{suggested[-2]} (LSB per" if "lsb-per" in suggested[-2] else " ".join(suggested[-2:])  # a scale: an example
    assert said in err and suggested[-1] in err, err
    rc, dst = _convert(tmp_path, text, *suggested, out="taken.csv")
    assert rc == 0, capsys.readouterr().err
    assert suggested[-1] != "none" or not {"temp", "ax"} & set(read_recording(dst).columns)


@pytest.mark.parametrize("name, cell, options, temp_c", [
    ("TempF", "98.6", [], 37.0), ("temp_k", "300.15", [], 27.0), ("Temperature_Fahrenheit", "212", [], 100.0),
    ("temp_k", "300.15", ["--temp-unit", "k"], 27.0)])
def test_a_temperature_named_in_f_or_k_is_converted(tmp_path, capsys, name, cell, options, temp_c):
    """Attack pass 28c: ``TempC`` was a temperature but ``TempF`` and ``temp_k`` were left out (the
    summary's "left out"), and ``--temp-unit k`` for ``temp_k`` was refused: "no temperature column
    among ..., temp_k" (a dead end: no command kept it)."""
    rc, dst = _convert(tmp_path, _unit_log(_GYRO + [name], _ROW + [cell]), "--unit", "dps", *options)
    err = capsys.readouterr().err
    assert rc == 0 and read_recording(dst).temp_c[0] == temp_c, err
    rc, dst = _convert(tmp_path, _unit_log(_GYRO + ["temp_raw"], _ROW + ["1335"]), "--unit", "dps", out="raw.csv")
    assert rc == 0 and "temp" not in read_recording(dst).columns, capsys.readouterr().err  # no die's counts guessed


@pytest.mark.parametrize("names, given, stated, taken, unit, row", [
    (["gyro1_x_mdps", "gyro1_y_mdps", "gyro1_z_mdps"], ["--unit", "dps"], "the column names say mdps", [], "dps",
     [0.001, 0.001, 0.002]),
    (["AngVelX_rad_s", "AngVelY_rad_s", "AngVelZ_rad_s"], ["--unit", "dps"], "the column names say rad/s", [], "rad/s",
     [1, 1, 2]),
    (["host_time_ms", "gx", "gy", "gz"], ["--unit", "dps", "--time-unit", "s"], "'host_time_ms' states ms",
     ["--unit", "dps"], "dps", [1, 1, 2]),
])
def test_a_unit_ending_a_name_given_in_columns_agrees_with_the_option(tmp_path, capsys, names, given, stated, taken,
                                                                      unit, row):
    """Attack pass 32b: a column named in --columns that convert's patterns do not read (``gyro1_x_mdps``
    of a log of two gyros, ``AngVelX_rad_s``, ``host_time_ms``) had its unit at the end unread: "the gyro
    unit is not stated", and ``--unit dps`` wrote millidegrees as degrees (``--time-unit s``: 0.1 Hz),
    exit 0, where ``gx (mdps)`` or ``gx_mdps`` are refused. The name's unit is read and must agree."""
    columns = ",".join(names if len(names) == 4 else ["time_ms"] + names)
    text = columns + "\n" + "".join(f"{10 * i},{i % 7},1,2\n" for i in range(300))
    rc, dst = _convert(tmp_path, text, "--columns", columns, *given)
    assert rc == 2 and not dst.exists()
    assert stated in capsys.readouterr().err
    rc, dst = _convert(tmp_path, text, "--columns", columns, *taken)
    assert rc == 0, capsys.readouterr().err
    rec = read_recording(dst)
    assert rec.gyro_unit == unit and rec.sample_rate_hz == 100 and rec.gyro[1].tolist() == row


@pytest.mark.parametrize("names, given, said", [
    (["t_ms", "gyro_x_mdps (filtered)", "gyro_y_mdps (filtered)", "gyro_z_mdps (filtered)"], ["--unit", "dps"],
     "the column names say mdps"),
    (["t_ms", "gx_mdps (v2)", "gy_mdps (v2)", "gz_mdps (v2)"], ["--unit", "dps"], "the column names say mdps"),
    (["t_ms", "gyro_x_mdps (deg/s)", "gyro_y_mdps (deg/s)", "gyro_z_mdps (deg/s)"], [], "different units (dps, mdps)"),
    (["time_ms (s)", "gx", "gy", "gz"], ["--unit", "dps"], "'time_ms (s)' states different units (ms, s)"),
    (["t_ms", "gx", "gy", "gz", "temp_c (F)"], ["--unit", "dps"], "'temp_c (F)' states different units (c, f)"),
    (["t_ms", "gx", "gy", "gz", "ax_g (mg)", "ay_g (mg)", "az_g (mg)"], ["--unit", "dps"], "different units (g, mg)"),
])
def test_a_unit_in_brackets_does_not_hide_the_unit_ending_the_name(tmp_path, capsys, names, given, said):
    """Attack pass 33a: a name with a text in brackets had the unit ending it unread (``gyro_x_mdps
    (filtered)`` with ``--unit dps`` wrote millidegrees as degrees, exit 0, where ``gyro_x_mdps`` is
    refused), and a name stating two units (``gyro_x_mdps (deg/s)``, ``time_ms (s)``, ``temp_c (F)``)
    was read in the one in brackets: both are the name's, and must agree."""
    columns = ",".join(names[:4])
    extra = {4: "", 5: ",25", 7: ",0,0,1"}[len(names)]  # a temperature, an accelerometer
    text = ",".join(names) + "\n" + "".join(f"{10 * i},{i % 7},1,2{extra}\n" for i in range(300))
    rc, dst = _convert(tmp_path, text, "--columns", columns, *given)
    assert rc == 2 and not dst.exists()
    assert said in capsys.readouterr().err


_STATED = {  # fact: (its spellings in a comment, (a value that agrees, one that does not), options, time column)
    "given rate": (["sample_rate_hz", "Sample rate", "rate", "odr_hz", "samplerate"], ("100", "200 Hz"),
                   ["--sample-rate-hz", "100", "--unit", "dps"], False),
    "stamped rate": (["sample_rate_hz", "Sampling frequency", "rate_hz"], ("100 Hz", "50"), ["--unit", "dps"], True),
    "period": (["dt", "sample_period_ms", "Ts"], (None, "0.02"), ["--sample-rate-hz", "100", "--unit", "dps"], False),
    "given unit": (["gyro_unit", "unit", "Gyro units", "gyro_scale"], ("deg/s", "rad/s"),
                   ["--sample-rate-hz", "100", "--unit", "dps"], False),
    "sensitivity": (["lsb_per_dps", "gyro_sensitivity", "lsb_per_deg"], ("131", "65.5"),
                    ["--sample-rate-hz", "100", "--unit", "lsb", "--lsb-per-dps", "131"], False),
}


@pytest.mark.parametrize("seed", range(12))
def test_a_comment_that_states_the_rate_or_unit_otherwise_is_refused_naming_its_line(tmp_path, capsys, seed):
    """Attack pass 53, item 11 (issue 37): a log's comment ``# sample_rate_hz: 200`` or ``# gyro_unit: rad/s`` was
    skipped beside ``--sample-rate-hz 100 --unit dps`` (the summary: "2 comment lines skipped"), the file written at
    the options' rate and unit. A comment before the first data row whose key states the rate, a period, the unit or
    the sensitivity must state what is written (the time column's rate within 5 %); its fact, key, style and line
    are drawn at random. Prose, a value that does not read and a comment after the first row are not read."""
    rng = np.random.default_rng(seed)
    fact = list(_STATED)[seed % len(_STATED)]
    keys, (agrees, disagrees), options, stamped = _STATED[fact]
    key, style = rng.choice(keys), rng.choice(["# {}: {}", "// {} = {}", "## {}:{}", "#{} = {}"])
    prose = ["# logged at 200 Hz in rad/s", "# note: the rate may be fast", "# rate: fast", "# date: 2026-12-02"]
    before, after = [str(p) for p in rng.permutation(prose)[:rng.integers(0, 3)]], rng.integers(0, 2)
    rows = ["".join((f"{i / 100:.2f}," if stamped else "") + f"{i % 7 - 3},131,-262\n" for i in part)
            for part in (range(300), range(300, 600))]
    names = ("t," if stamped else "") + "gx,gy,gz\n"

    def log(value):
        comment = style.format(key, value) + "\n"
        head = "\n".join(before) + ("\n" if before else "")
        return head + (names + comment if after else comment + names) + rows[0] + "# rate: 50\n" + rows[1]

    line = len(before) + 1 + after
    code, dst = _convert(tmp_path, log(disagrees), *options)
    err = capsys.readouterr().err
    assert code == 2 and not dst.exists()
    read = " (read as '65.5 lsb/deg/s')" if key == "lsb_per_deg" else ""  # (the unit in the key, pass 64)
    assert err.startswith(f"gyrofilter: error: {tmp_path / 'log.csv'}: line {line}: the comment "
                          f"'{style.format(key, disagrees)}'{read} disagrees with the conversion's "), err  # as in the file
    assert ("(from the time column's steps); correct the comment line" if stamped else
            "; correct the option or the comment line") in err.splitlines()[0]
    if agrees is not None:
        code, dst = _convert(tmp_path, log(agrees), *options)
        assert code == 0, capsys.readouterr().err
        assert read_recording(dst).sample_rate_hz == 100.0


@pytest.mark.parametrize("comment, options", [
    ("# gyro_unit: dps", ["--unit", "mdps"]), ("# Gyro units: rad/s", ["--unit", "mrad/s"]),  # the unit read, not written
    ("# Sample Rate (samples/s): 200", []), ("# Sampling rate [1/s]: 200", []), ("# Sample rate in Hz: 200", []),
    ("# Sample rate: 200 Hz (nominal)", []), ("# Sample rate: ~200 Hz", []), ("# Sample rate: 200 Hz.", []),
    ("# Sample rate: 200/s", []), ("# Sample rate: 200 samples per second", []), ("# fs=200 Hz; unit=rad/s", []),
    ('# sample_rate_hz: "200"', []), ("# sample_rate_hz: 200 # in firmware", []),
    ("# sample_rate_hz\uff1a200", []), ("# sample_rate_hz := 200", []), ('# {"sample_rate_hz": 200}', []),
    ("# Sample period: 5000 \u00b5s", []), ("# Logging rate: 200 Hz", []), ("# Acquisition rate: 200 Hz", []),
    ("# Gyro sample rate: 200 Hz", []), ("# \uff33\uff41\uff4d\uff50\uff4c\uff45\uff32\uff41\uff54\uff45: 200", []),
    ("# sensor_odr: 200 Hz", []), ("# sample_rate_hz_nominal: 200", []),
    ("# Sensitivity: 8.75 mdps/LSB", ["--unit", "lsb", "--lsb-per-dps", "8.75"]),  # pass 56: 114.29 LSB per deg/s
    ("# Rate: 200 Hz, FS: 2000 dps", []), ("# settings: fs=200 Hz", []), ("# IMU config: rate=200Hz; unit=dps", []),
    ("# unit=dps rate=200", []), ("# Sample period (us): ~20000", []), ("# Sample period (msec): 20", []),
    ("# Sample rate: approx. 200 Hz", []), ("# Update rate: 5 ms", []),
    ("# lsb_per_g: 8192", ["--unit", "dps", "--accel-unit", "lsb", "--lsb-per-g", "16384"]),
    ("# accel: m/s^2", ["--unit", "dps", "--accel-unit", "g"]),
    ("# Units: s, deg/s, m/s^2", ["--unit", "dps", "--accel-unit", "g"]),
    ('# {"device": "MPU6050", "sample_rate": 200, "units": "dps"}', []), ('# metadata = {"fs": 200}', []),
    ("# imu_node: {rate: 200, frame_id: imu}", []), ("# dt: 20 msec", []), ("# sampling period: 20 millis", []),
    ("# Recording rate: 200 Hz", []), ("# Sampling rate of IMU: 200 Hz", []),
    ("# sample_rate: 200/sec", []), ("# Rate: 200 Sa/s", []), ("# Sample rate: 200 per second", []),  # pass 57
    ("# ---- sample_rate: 200 ----", []), ("# ===== sample_rate: 200 =====", []), ("# Sample time (ms): 5", []),
    ("# LSB per dps = 65.5", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# Gyro sensitivity: 65.5 LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# Accel: range=2g, sensitivity=8192", ["--unit", "dps", "--accel-unit", "lsb", "--lsb-per-g", "16384"]),
    ("# gyro_mdps_per_lsb: 15.27", ["--unit", "lsb", "--lsb-per-dps", "131"]),  # pass 58: 65.5 LSB per deg/s
    ("# accel scale factor: 16384", ["--unit", "dps", "--accel-unit", "lsb", "--lsb-per-g", "4096"]),
    ("# Sampling time: 5 ms", []), ("# time step: 0.005 s", []), ("# Sample rate (nominal): 200", []),  # pass 59
    ("# f_s = 200 Hz", []), ("# Sample rate: 200/second", []), ("# sample rate: 200 readings/s", []),
    ("# gyro rate: 200 Hz", []), ("# unit: radians per second", []), ("# unit: rad per s", []),
    ("# units: \u00ba/s", ["--unit", "rad/s"]), ("# units: t[s], gyro[rad/s]", []),
    ("# counts per deg/s: 65.5", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# gyro sensitivity = 65.5 LSB/(\u00ba/s)", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# sensitivity: 0.000266 rad/s/LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# gyro: radians per second", []), ("# counts per degree per second: 65.5", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# gyro sensitivity: 0.0153 deg/s per LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),  # pass 60
    ("# Sample rate (nom.): 200", []), ("# rate: 200 s^-1", []), ("# Sample rate (per channel): 200", []),
    ("# Sample rate: 200 Hz (DLPF 44 Hz)", []), ("# Frequency: 200 Hz", []),  # a sample rate whatever the remark
    ("# sensitivity: 0.02 dps/LSB", ["--unit", "lsb", "--lsb-per-dps", "65.5"]),  # one digit: not within 1 %
    ("# unit: radian per second", []), ("# unit: millidegrees per second", []),  # pass 61: a singular, milli-
    ("# unit: degree per second", ["--unit", "rad/s"]), ("# unit: milliradians per second", ["--unit", "rad/s"]),
    ("# gyro_sensitivity: -70 mdps/LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),  # a sign passed any
    ("# gyro_sensitivity: 0 dps/LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),  # no sensitivity is 0
    ("# gyro_sensitivity: 1e2", ["--unit", "lsb", "--lsb-per-dps", "131"]), ("# scale_factor: 1E+2", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# gyro_sensitivity: 1e400", ["--unit", "lsb", "--lsb-per-dps", "131"]),  # pass 62: a traceback (OverflowError)
    ("# gyro_sensitivity: 1e309 dps/LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# gyro_sensitivity: 4.9e-324 mdps/LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),  # (ZeroDivisionError)
    ("# update rate: 200 Hz (low-pass 42 Hz)", []), ("# data rate: 200 Hz (DLPF on)", []),  # a rate, the remark aside
    ("# sensitivity: 131 deg/sec/LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),  # 1/131 LSB per deg/s
    ("# mdps_per_lsb: 70", ["--unit", "lsb", "--lsb-per-dps", "70"]),  # pass 63: the key's unit, 14.3 LSB per deg/s
    ("# counts per mdps: 14.2857", ["--unit", "lsb", "--lsb-per-dps", "14.2857"]),
    ("# sensitivity: 131 LSB/mdps", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# sensitivity_mdps: 70", ["--unit", "lsb", "--lsb-per-dps", "70"]),  # pass 64: a unit alone, per LSB
    ("# mdps_lsb: 70", ["--unit", "lsb", "--lsb-per-dps", "70"]), ("# Sensitivity (mdps): 70", ["--unit", "lsb", "--lsb-per-dps", "70"]),
])
def test_a_comment_written_as_people_write_it_is_read(tmp_path, capsys, comment, options):
    """Attack pass 55 (issue 37): each of these, above a log converted at 100 Hz in dps (or mdps, mrad/s), went through
    without a word: the unit compared was the one written (dps for mdps: 1000 times), and a value with a remark, a
    unit in the key's brackets, another separator or a full-width key did not read."""
    accel = "--accel-unit" in options
    rows = "".join(f"{i % 5 / 10},0.2,-0.1" + (",0,0,1" if accel else "") + "\n" for i in range(50))
    names = "gx,gy,gz" + (",ax,ay,az" if accel else "")
    code, dst = _convert(tmp_path, f"{comment}\n{names}\n{rows}", "--sample-rate-hz", "100", *(options or ["--unit", "dps"]))
    err = capsys.readouterr().err
    assert code == 2 and not dst.exists() and err.startswith(f"gyrofilter: error: {tmp_path / 'log.csv'}: line 1: the "
                                                             f"comment '{comment}' "), err


@pytest.mark.parametrize("comment, options, said", [
    ("# sensitivity: 0.0153", ["--lsb-per-dps", "65.5"], True), ("# accel sensitivity: 0.061", ["--lsb-per-g", "16384"], True),
    ("# sensitivity: 0.0153 dps/LSB", ["--lsb-per-dps", "131"], False), ("# mdps_per_lsb: 70", ["--lsb-per-dps", "70"], False),
])
def test_a_sensitivity_without_a_unit_says_how_it_was_read(tmp_path, capsys, comment, options, said):
    """A new user's ``# sensitivity: 0.0153`` (deg/s per LSB meant) was refused beside --lsb-per-dps 65.5 without
    saying that a number alone is read as LSB per deg/s (so 0.0153, not 65.4)."""
    accel = "--lsb-per-g" in options
    rows = "".join(f"{i % 5},2,-1" + (",0,0,1" if accel else "") + "\n" for i in range(50))
    unit = ["--unit", "dps", "--accel-unit", "lsb"] if accel else ["--unit", "lsb"]
    code, dst = _convert(tmp_path, f"{comment}\ngx,gy,gz{',ax,ay,az' if accel else ''}\n{rows}", "--sample-rate-hz",
                         "100", *unit, *options)
    err = capsys.readouterr().err
    assert code == 2 and not dst.exists() and err.count("\n") == 1
    assert ("a sensitivity without a unit read as LSB per " + ("g" if accel else "deg/s") in err) == said, err


@pytest.mark.parametrize("comment, options", [
    ("# gyro_unit: mdps", ["--unit", "mdps"]), ("# Gyro units: mrad/s", ["--unit", "mrad/s"]),
    ("# Sample period (\u00b5s): 10000", []), ("# units: s, deg/s, g", []), ("# Gyro scale: \u00b12000 dps", []),
    ("# TS: 1700000000", []), ("# Unit: IMU-07", []), ("# units: SI", []), ("# Sampling rate: Fastest", []),
    ("# Sample rate: 100 Hz (DLPF 44 Hz)", []), ("# sample_rate: 1e2", []), ("# Gyro range set to: +- 500 deg/s", []),
    ("# Units: rad/s (gyro), m/s^2 (accel)", ["--unit", "rad/s"]),
    ("# Gyro scale: 2000 dps", ["--unit", "lsb", "--lsb-per-dps", "16.4"]),
    ("# gyro_sensitivity: 131 LSB/(deg/s)", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# Sensitivity: 8.75 mdps/LSB", ["--unit", "lsb", "--lsb-per-dps", "114.2857"]),  # pass 56
    ("# Rate: 100 Hz, FS: 2000 dps", []), ("# Sample rate (Hz): 100 (nominal)", []), ('# Sample rate [Hz]: "100"', []),
    ("# Sample rate (kHz): ~0.1", []), ("# Target rate: 100 dps", []), ("# Sample rate: approx. 100 Hz", []),
    ("# Sample rate: 100 Hz +/- 1%", []), ("# Sample rate: 100 Hz, 16 bit", []), ("# Update rate: 10 ms", []),
    ("# Data rate: 115200 bps", []), ("# Sampling: 16x oversampling", []), ("# baud rate: 115200", []),
    ("# Date: 2026-01-01 12:00:00", []), ("# unit=dps rate=100", []), ("# TS: 512.3", []),
    ("# Gyro range: 250 LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),  # pass 57: its accelerometer's, not the gyro's
    ("# Accel: range=2g, sensitivity=16384", ["--unit", "dps", "--accel-unit", "lsb", "--lsb-per-g", "16384"]),
    ("# accel sensitivity = 16384", ["--unit", "dps", "--accel-unit", "lsb", "--lsb-per-g", "16384"]),
    ("# gyro_mdps_per_lsb: 7.633", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# Sample rate: 6000 per minute", []), ("# Sample rate: 6000 samples per minute", []),  # not read as 6000 Hz
    ("# Sample rate: 100 Hz per axis", []),
    ("# Sample rate (nominal): 100", []), ("# unit: degrees per second", []), ("# gyro rate: 100 dps", []),  # pass 59
    ("# sensitivity: 0.0001332 rad/s/LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]), ("# counts: 5000", []),
    ("# sensitivity: 0.0153 dps/LSB", ["--unit", "lsb", "--lsb-per-dps", "65.5"]),  # pass 60: datasheets' rounding
    ("# sensitivity: 15.3 mdps/LSB", ["--unit", "lsb", "--lsb-per-dps", "65.5"]),
    ("# Gyro sensitivity: 7.6 mdps/LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# sensitivity: 3.8 mdps/LSB", ["--unit", "lsb", "--lsb-per-dps", "262.4"]),
    ("# sensitivity: 0.000266 rad/s/LSB", ["--unit", "lsb", "--lsb-per-dps", "65.5"]),
    ("# gyro sensitivity: 0.0153 deg/s per LSB", ["--unit", "lsb", "--lsb-per-dps", "65.5"]),
    ("# counts per degree per second: 131", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# Sample rate (nom.): 100", []), ("# Sample rate (per channel): 100", []), ("# rate: 100 s^-1", []),
    ("# Frequency: 42 Hz (DLPF)", []), ("# frequency: 20 Hz (low-pass filter)", []),  # a filter's cut-off
    ("# gyro_sensitivity: -7.6 mdps/LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),  # an axis the other way round
    ("# gyro_sensitivity: 1.31e2", ["--unit", "lsb", "--lsb-per-dps", "131"]), ("# unit: degree per second", []),
    ("# sensitivity: 0.00763 (deg/s)/LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),  # pass 62: inverse spellings
    ("# sensitivity: 0.00763 deg/sec/LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# sensitivity: 7.63 mdps/count", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# sensitivity: 7.63 millidegrees per second per LSB", ["--unit", "lsb", "--lsb-per-dps", "131"]),
    ("# units: s, deg/s, counts", []),
    ("# mdps_per_lsb: 70", ["--unit", "lsb", "--lsb-per-dps", "14.2857"]),  # pass 63: an L3GD20 at 2000 deg/s
    ("# dps/LSB: 0.07", ["--unit", "lsb", "--lsb-per-dps", "14.2857"]),
    ("# sensitivity_mdps: 70", ["--unit", "lsb", "--lsb-per-dps", "14.2857"]),  # pass 64: was 70 LSB per deg/s
    ("# gyro_scale_dps: 2000", ["--unit", "lsb", "--lsb-per-dps", "16.4"]),  # a full scale in the key's unit
])
def test_a_comment_that_states_the_same_or_nothing_is_kept(tmp_path, capsys, comment, options):
    """Attack pass 55: these were refused, the same unit (mdps, given and stated), a period in the key's unit (us read
    as s), a list of units, a full scale (not a sensitivity), a time stamp (not a period), a device name."""
    accel = "--accel-unit" in options
    rows = "".join(f"{i % 5 / 10},0.2,-0.1" + (",0,0,1" if accel else "") + "\n" for i in range(50))
    names = "gx,gy,gz" + (",ax,ay,az" if accel else "")
    code, dst = _convert(tmp_path, f"{comment}\n{names}\n{rows}", "--sample-rate-hz", "100", *(options or ["--unit", "dps"]))
    assert code == 0, capsys.readouterr().err
    assert read_recording(dst).sample_rate_hz == 100.0


@pytest.mark.parametrize("comment, options, refused", [
    ("# temp unit: F", [], True), ("# Temperature units: K", ["--temp-unit", "c"], True),
    ("# temp unit: degC", [], False), ("# temp unit: F", ["--temp-unit", "f"], False),
    ("# temp: raw", ["--temp-unit", "mpu6050"], False), ("# temp sensor: on-die", [], False),
    ("# units: s, deg/s, \u00b0F", [], True), ("# units: s, deg/s, \u00b0C", [], False),  # pass 60
])
def test_a_comment_stating_another_temperature_unit_is_refused(tmp_path, capsys, comment, options, refused):
    """Attack pass 59: a comment stating the temperature's unit is checked against the unit read, as the gyro's is."""
    rows = "".join(f"{i / 100:.2f},0.1,0.2,0.3,{25 + i % 3}\n" for i in range(60))
    column = "temp" if options else "temp_c"  # a unit stated by the option or the name
    code, dst = _convert(tmp_path, f"{comment}\nt,gx,gy,gz,{column}\n{rows}", "--unit", "dps", *options)
    err = capsys.readouterr().err
    if refused:
        assert code == 2 and not dst.exists() and err.startswith(
            f"gyrofilter: error: {tmp_path / 'log.csv'}: line 1: the comment '{comment}' disagrees with the "
            "conversion's temp_unit "), err
    else:
        assert code == 0, err


def test_a_comment_or_header_value_with_a_long_run_of_blanks_is_read_in_one_pass(tmp_path):
    """Attack pass 56: ``# note: start`` + 300 000 blanks + ``end`` (a third of the 1 MB a line may hold) held convert,
    and replay on such a header value, for minutes: regular expressions over the run, tried at each blank. Runs of
    blanks read as one; the run in a subprocess is bounded, so that the old behaviour fails here, not hangs CI."""
    noise = np.round(np.random.default_rng(5).normal(0.0, 0.1, (300, 3)), 4)
    rows = "".join(f"{i / 100:.2f},{x},{y},{z}\n" for i, (x, y, z) in enumerate(noise))
    log = tmp_path / "log.csv"
    log.write_text("# note: start" + " " * 300_000 + "end\n# rate" + " " * 100_000 + ": 200\nt,gx,gy,gz\n" + rows)
    run = subprocess.run([sys.executable, "-m", "gyrofilter", "convert", str(log), "--unit", "dps", "--out",
                          str(tmp_path / "rec.csv")], capture_output=True, text=True, timeout=60)
    assert run.returncode == 2 and "line 2: the comment '# rate" in run.stderr  # read, and its 200 Hz refused
    rec = tmp_path / "own.csv"
    rec.write_text("# gyrofilter-recording: 1\n# sample_rate_hz: 100\n# gyro_unit: dps\n# note: start" + " " * 300_000
                   + "end\nt,gx,gy,gz\n" + rows)
    run = subprocess.run([sys.executable, "-m", "gyrofilter", "allan", str(rec), "--json", str(tmp_path / "a.json")],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr


def test_a_log_on_the_standard_input_is_not_overwritten_by_its_conversion(tmp_path):
    """Attack pass 56: ``convert - --out log.csv --force < log.csv`` wrote over the log it read (its accelerometer
    columns gone); ``-`` is the file the standard input reads, refused as an output as every input is."""
    log = tmp_path / "log.csv"
    log.write_text("gx,gy,gz,ax,ay,az\n" + "".join(f"{i % 5 / 10},0.2,-0.1,0,0,1\n" for i in range(50)))
    before = log.read_bytes()
    with open(log, "rb") as stdin:
        run = subprocess.run([sys.executable, "-m", "gyrofilter", "convert", "-", "--unit", "dps", "--sample-rate-hz",
                              "100", "--out", str(log), "--force"], stdin=stdin, capture_output=True, text=True, timeout=60)
    assert run.returncode == 2 and run.stderr == f"gyrofilter: error: {log}: is an input of this command; write the output to another file\n"
    assert log.read_bytes() == before


def test_a_gzip_log_cut_short_then_zeros_then_a_byte_converts_no_row_zlib_made_of_them(tmp_path):
    """Attack pass 59: a log cut short, 7 zero bytes and 0x01 after it, was converted with its last row changed
    ((0.09, 0.7433, 0.5, -0.567), written (0.09, 0.743, -0.581, -0.569)). The reader holds the text after a run of
    padding until its stream proves whole: cut short, every row converted is a row written."""
    rng = np.random.default_rng(59)
    values = np.round(rng.normal(0.0, 0.5, (400, 3)), 3)
    text = "t,gx,gy,gz\n" + "".join(f"{i / 100:.2f},{a:.3f},{b:.3f},{c:.3f}\n" for i, (a, b, c) in enumerate(values))
    data = gzip.compress(text.encode())
    src, dst = tmp_path / "log.csv.gz", tmp_path / "rec.csv"
    converted = 0
    for cut in rng.integers(len(data) // 4, len(data) - 20, 12):
        src.write_bytes(data[:cut] + bytes(7) + b"\x01")
        dst.unlink(missing_ok=True)
        if main(["convert", str(src), "--unit", "dps", "--out", str(dst)]) == 2:  # junk refused as damage
            continue
        rec = read_recording(dst)
        np.testing.assert_array_equal(rec.gyro_dps, values[:len(rec)])
        converted += 1
    assert converted >= 6


@pytest.mark.parametrize("zeros", [1, 100, 4096])
@pytest.mark.parametrize("piped", [False, True])
def test_a_gzip_log_cut_short_then_padded_with_zeros_is_read_to_its_cut(tmp_path, zeros, piped):
    """Attack pass 58: a gzip log cut by a power cut and padded with zero bytes was converted with rows zlib made of
    the zeros (back-references copying earlier text: 15 samples invented), with only the "cut short" warning; then it
    was refused (Python's gzip reads on into the zeros), and from a pipe refused as "5 values, but 4 columns". convert
    now reads gzip as the recording reader does (``recording.gzipped.gunzipped``): the zeros are left out with a warning,
    the rows up to the cut are converted, each its own, as many as without the zeros."""
    text = "gx,gy,gz\n" + "".join(f"{i},{i % 7},{i % 3}\n" for i in range(3000))
    data = gzip.compress(text.encode())[:2126]
    # (a cut's last bytes' text left out, padding after them or not (pass 67): fewer zeros than RUN_BYTES are its own)
    kept = (data + bytes(zeros) if zeros < RUN_BYTES else data)[:-HOLD_BYTES]
    complete = zlib.decompressobj(16 + zlib.MAX_WBITS).decompress(kept).count(b"\n") - 1  # whole rows before the cut
    src, dst = tmp_path / "log.csv.gz", tmp_path / "rec.csv"
    src.write_bytes(data + bytes(zeros))
    args = ["--unit", "lsb", "--lsb-per-dps", "131", "--sample-rate-hz", "100", "--out", str(dst)]
    run = subprocess.run([sys.executable, "-m", "gyrofilter", "convert", "-" if piped else str(src), *args],
                         input=src.read_bytes() if piped else b"", capture_output=True, timeout=120)
    err = " ".join(run.stderr.decode().split())
    name = "-" if piped else str(src)
    assert run.returncode == 0, err
    padding = f"{name}: {zeros} zero byte{'s' * (zeros > 1)} at its end ignored (block padding, as a power cut leaves an SD card)"
    assert (padding in err) == (zeros >= RUN_BYTES)
    assert f"{name}: gzip stream cut short (no end marker), as an interrupted recording leaves it; read to line {complete + 1}" in err
    rec = read_recording(dst)
    assert len(rec) == complete > 100
    np.testing.assert_array_equal(rec.gyro[:, 0], np.arange(complete))  # every row its own (LSB), none invented


@pytest.mark.parametrize("sep", [",", ";", " ", "\t"])
@pytest.mark.parametrize("blank", ["\x1f", "\x0b", "\u3000"])
def test_a_control_beside_a_number_in_a_log_is_refused(tmp_path, capsys, sep, blank):
    """Attack pass 63: convert read ``\\x1f7`` as 7 (Python's strip and split take controls for blanks); in a log split
    at blanks a leading control was a separator, its row read."""
    rows = [f"{i / 100}{sep}1{sep}2{sep}3" for i in range(50)]
    rows[30] = f"0.3{sep}{blank}7{sep}2{sep}3"
    code, dst = _convert(tmp_path, sep.join(["t", "gx", "gy", "gz"]) + "\n" + "\n".join(rows) + "\n", "--unit", "dps")
    err = capsys.readouterr().err
    assert code == 2 and not dst.exists() and "line 32" in err and err.count("\n") == 1, err
