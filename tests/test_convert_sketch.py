"""`gyrofilter convert` of the classic Arduino MPU6050 sketch's CSV (``millis,AcX,AcY,AcZ,Tmp,GyX,GyY,GyZ``):
its gyro, accelerometer and temperature found by name; what is left out, said with why; refusals
that name this file's own columns and read as the other unit refusals do."""
import numpy as np
import pytest

from gyrofilter.cli import main
from gyrofilter.recording import read_recording

SKETCH = "millis,AcX,AcY,AcZ,Tmp,GyX,GyY,GyZ"


def _log(tmp_path, names=SKETCH, rows=200):
    rng = np.random.default_rng(3)
    values = np.round(np.array([7, -20, 16367, -2981, -480, 193, -83]) + 5 * rng.standard_normal((rows, 7))).astype(int)
    text = names + "\n" + "".join(f"{10 * i}," + ",".join(map(str, v)) + "\n" for i, v in enumerate(values.tolist()))
    path = tmp_path / "arduino.csv"
    path.write_text(text)
    return str(path)


def _convert(path, tmp_path, *options):
    out = tmp_path / "out.csv.gz"
    return main(["convert", path, "--out", str(out), "--force", "--unit", "lsb", "--lsb-per-dps", "131", *options]), out


def test_the_sketch_columns_are_found_by_name(tmp_path, capsys):
    rc, out = _convert(_log(tmp_path), tmp_path, "--temp-unit", "mpu6050", "--accel-unit", "lsb", "--lsb-per-g", "16384")
    err = capsys.readouterr().err
    assert rc == 0, err
    rec = read_recording(str(out))
    assert rec.gyro_dps[0, 0] == pytest.approx(rec.columns["gx"][0] / 131)
    assert {"ax", "ay", "az", "temp"} <= set(rec.columns)
    assert 20 < float(np.mean(rec.columns["temp"])) < 35  # -2981 counts: 27.8 deg C
    assert "left out" not in err


def test_what_is_left_out_is_said_with_why(tmp_path, capsys):
    rc, _ = _convert(_log(tmp_path), tmp_path)
    err = " ".join(capsys.readouterr().err.split())
    assert rc == 0, err
    assert "column 'Tmp' left out: its unit is not stated" in err and "--temp-unit mpu6050" in err
    assert "left out: 'AcX', 'AcY', 'AcZ' (unit not stated: --accel-unit), 'Tmp' (unit not stated: --temp-unit)" in err



def test_a_column_no_rule_reads_is_left_out_saying_so(tmp_path, capsys):
    path = tmp_path / "log.csv"
    path.write_text("t,gx,gy,gz,foo\n0,1,2,3,4\n0.01,1,2,3,4\n0.02,1,2,3,4\n")
    assert main(["convert", str(path), "--unit", "dps", "--out", str(tmp_path / "o.csv.gz")]) == 0
    assert "left out: 'foo' (not a column convert reads)" in " ".join(capsys.readouterr().err.split())


def test_no_gyro_column_suggests_this_files_own_names(tmp_path, capsys):
    rc, _ = _convert(_log(tmp_path, "millis,AcX,AcY,AcZ,Tmp,a,b,c"), tmp_path)
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1
    assert "e.g. --columns millis,a,b,c" in err and "wx" not in err


def test_an_accelerometer_unit_convert_does_not_read_is_refused_as_the_gyros_is(tmp_path, capsys):
    path = tmp_path / "log.csv"
    path.write_text("t,gx,gy,gz,acc_x (ft/s^2),acc_y (ft/s^2),acc_z (ft/s^2)\n0,1,2,3,1,2,32\n0.01,1,2,3,1,2,32\n")
    assert main(["convert", str(path), "--unit", "dps", "--out", str(tmp_path / "o.csv.gz")]) == 2
    err = capsys.readouterr().err
    assert "'ft/s^2', a unit convert does not read" in err and "only if it means one of them" in err


def test_whole_numbers_given_as_deg_per_s_are_said_to_look_like_raw_counts(tmp_path, capsys):
    """A new user's trial: the sketch's raw counts (mean about -427) given as --unit dps converted without a word."""
    path = _log(tmp_path)
    assert main(["convert", path, "--out", str(tmp_path / "o.csv.gz"), "--unit", "dps", "--columns", "millis,GyX,GyY,GyZ"]) == 0
    err = " ".join(capsys.readouterr().err.split())
    assert "every value of the gyro columns 'GyX', 'GyY', 'GyZ' is a whole number" in err and "--unit lsb" in err
    assert main(["convert", path, "--out", str(tmp_path / "o.csv.gz"), "--force", "--unit", "lsb", "--lsb-per-dps", "131"]) == 0
    assert "whole number" not in capsys.readouterr().err


@pytest.mark.parametrize("first", ["Fs,100", "time,a,b"])
def test_no_gyro_column_among_too_few_suggests_no_columns_that_cannot_be_the_gyro(tmp_path, capsys, first):
    """Attack pass 31a: a log whose first line holds fewer than three columns besides the time (a preamble
    ``Fs,100`` before the column row, as an MPU6050 calibration logger writes) was told ``e.g. --columns Fs,100``
    (refused: 2 columns) or ``--columns time,a,b``, which reads the time column as the gyro's x."""
    path = tmp_path / "log.csv"
    path.write_text(first + "\nax,ay,az,gx,gy,gz\n1,2,3,4,5,6\n")
    assert main(["convert", str(path), "--out", str(tmp_path / "o.csv")]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert "e.g. --columns" not in err and "a gyro has three" in err, err
