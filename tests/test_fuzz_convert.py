"""Fuzz of ``gyrofilter convert`` (issue 38): generated logs of other tools' shapes (column
names, separators, time units, broken cells), and arbitrary text.

Properties: ``gyrofilter convert LOG --out REC`` exits 0 with a REC that reads back holding the
log's gyro values exactly (and ``t`` from its time stamps; its temperature and accelerometer
columns, named with their units, as ``temp`` and ``ax, ay, az``), or exits 2 with one line on stderr
naming the log, and no REC; a log with a broken row (a cell that is not a plain number, a short
row) is always refused, naming that row's line, unless it is a last line without its line end,
which is left out (a log cut short), as every such line.
"""
import contextlib
import io
import os
import tempfile
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gyrofilter.cli import main
from gyrofilter.recording import read_recording

FAST = settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
SLOW = settings(max_examples=1000, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])

STYLES = [("timestamp", "gyro_x", "gyro_y", "gyro_z"), ("t", "gx", "gy", "gz"), ("%time", "field.angular_velocity.x",
          "field.angular_velocity.y", "field.angular_velocity.z"), ("Time (s)", "Gyroscope x (rad/s)",
          "Gyroscope y (rad/s)", "Gyroscope z (rad/s)"), ("millis", "wx", "wy", "wz"), ("time_us", "omega_x", "omega_y", "omega_z")]
TIME_SECONDS = {"timestamp": None, "t": None, "%time": 1e-9, "Time (s)": 1.0, "millis": 1e-3, "time_us": 1e-6}
BROKEN_CELLS = ["", "nan", "inf", "x", "1_0", "0x10", "1.2.3", "--1"]
#: temperature columns named in deg C (or deg F, converted exactly), and accelerometer columns named
#: with their unit (the unit; mg converted exactly to g)
TEMPERATURES = ["TempC", "temp_c", "Temperature (C)", "TEMP [°C]", "Temp (°F)"]
ACCELEROMETERS = [(("AccX (g)", "AccY (g)", "AccZ (g)"), "g"), (("ax_mps2", "ay_mps2", "az_mps2"), "m/s^2"),
                  (("acc_x_mg", "acc_y_mg", "acc_z_mg"), "mg"),
                  (("field.linear_acceleration.x", "field.linear_acceleration.y", "field.linear_acceleration.z"), None)]


@st.composite
def logs(draw):
    """(text, gyro values written, line of the first broken row or None, CLI options, the temperature
    written or None, the accelerometer written or None)."""
    names = draw(st.sampled_from(STYLES))
    temp_name = draw(st.sampled_from([None] + TEMPERATURES))
    accel_names, accel_unit = draw(st.sampled_from([((), None)] + ACCELEROMETERS))
    names = names + ((temp_name,) if temp_name else ()) + accel_names
    sep = draw(st.sampled_from([",", ";", " ", "\t"])) if "(" not in names[0] else ","
    cell_names = [f'"{n}"' if " " in n else n for n in names] if sep == "," else names
    if sep in " \t" and any(" " in n for n in names):
        sep = ","
    step_s = draw(st.sampled_from([0.01, 0.005, 0.002]))
    seconds = TIME_SECONDS[names[0]] or draw(st.sampled_from([1.0, 1e-9]))  # an unstated unit is inferred
    n = draw(st.integers(0, 30))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    gyro = np.round(rng.normal(0, 0.1, (n, 3)), draw(st.integers(1, 9)))
    temp = np.round(rng.uniform(-40, 85, n), draw(st.integers(0, 4))) if temp_name else np.empty(n)
    accel = np.round(rng.normal(0, 5, (n, 3)), draw(st.integers(0, 6))) if accel_names else np.empty((n, 0))
    stamps = np.round((1000.0 + np.arange(n) * step_s * (1 + 0.001 * rng.uniform(-1, 1, n))) / seconds, 6)
    lines = [sep.join(cell_names)]
    broken_row = draw(st.integers(0, max(n - 1, 0))) if n and draw(st.integers(0, 2)) == 0 else None
    broken = None
    for i in range(n):
        cells = ([repr(float(stamps[i])) if seconds > 1e-6 else str(int(stamps[i]))] + [repr(v) for v in gyro[i].tolist()]
                 + ([repr(float(temp[i]))] if temp_name else []) + [repr(v) for v in accel[i].tolist()])
        if draw(st.integers(0, 9)) == 0:
            lines.append(draw(st.sampled_from(["# note", "", "// x"])))
        if i == broken_row:
            if draw(st.booleans()):
                cells[draw(st.integers(0, len(cells) - 1))] = draw(st.sampled_from(BROKEN_CELLS))
            else:
                cells = cells[:draw(st.integers(1, len(cells) - 1))]
            broken = len(lines) + 1
        lines.append(sep.join(cells))
    options = ([] if "(rad/s)" in names[1] else ["--unit", "rad/s"]) + ([] if not accel_names or accel_unit else
                                                                     ["--accel-unit", "m/s^2"])
    end = draw(st.sampled_from(["\n", "\r\n", ""]))
    if not end and n:  # a last line without its line end is left out (a log cut short), broken or not
        gyro, temp, accel, broken = gyro[:-1], temp[:-1], accel[:-1], None if broken == len(lines) else broken
    if temp_name and "°F" in temp_name:
        temp = np.array([float((Fraction(repr(float(v))) - 32) * 5 / 9) for v in temp])
    if accel_unit == "mg":
        accel, accel_unit = np.array([[float(Fraction(repr(v)) / 1000) for v in row] for row in accel.tolist()]), "g"
    return ("\n".join(lines) + end, gyro, broken, options, temp if temp_name else None,
            (accel, accel_unit or "m/s^2") if accel_names else None)


def _run(text, options):
    with tempfile.TemporaryDirectory() as folder:
        src, dst = os.path.join(folder, "log.csv"), os.path.join(folder, "rec.csv")
        with open(src, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            rc = main(["convert", src, "--out", dst, *options])
        rec = read_recording(dst) if os.path.exists(dst) else None
        return rc, err.getvalue(), rec, src


def _check(case):
    text, gyro, broken, options, temp, accel = case
    rc, err, rec, src = _run(text, options)
    if rc == 0:
        assert broken is None and rec is not None
        np.testing.assert_array_equal(rec.gyro, gyro)
        if temp is None:
            assert "temp" not in rec.columns
        else:
            np.testing.assert_array_equal(rec.temp_c, temp)
        if accel is None:
            assert rec.accel_unit is None and "ax" not in rec.columns
        else:
            assert rec.accel_unit == accel[1]
            np.testing.assert_array_equal(np.column_stack([rec.columns[c] for c in ("ax", "ay", "az")]), accel[0])
        return
    assert rc == 2 and rec is None, err
    assert err.count("\n") == 1 and f"{src}: " in err and "Traceback" not in err, err
    if broken is not None and len(gyro) >= 2:
        assert f"line {broken}" in err or "a recording needs at least 2" in err, err


@FAST
@given(case=logs())
def test_a_log_converts_to_its_values_or_is_refused_naming_the_line(case):
    _check(case)


@pytest.mark.slow
@SLOW
@given(case=logs())
def test_a_log_converts_to_its_values_or_is_refused_naming_the_line_many(case):
    _check(case)


@FAST
@given(text=st.text(st.characters(codec="utf-8", exclude_categories=["Cs"]), max_size=200),
       options=st.sampled_from([[], ["--unit", "dps"], ["--unit", "dps", "--sample-rate-hz", "100"],
                                ["--unit", "lsb", "--lsb-per-dps", "131", "--columns", "1,2,3"],
                                ["--unit", "dps", "--sample-rate-hz", "100", "--temp-unit", "mpu6050", "--accel-unit", "lsb",
                                 "--lsb-per-g", "16384"]]))
def test_any_text_converts_or_is_refused_in_one_line(text, options):
    rc, err, rec, src = _run(text, options)
    assert (rc == 0 and rec is not None) or (rc == 2 and rec is None and err.count("\n") == 1), (rc, err)
