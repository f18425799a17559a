"""The real MPU6050 recordings shipped in recordings/ (made by tools/convert_mpu6050.py).

Oracles: the row counts and statistics measured independently on the upstream CSVs and written
down in ../shared/data/mpu6050_*/SOURCE.md, and (when ../shared is beside the repo) the upstream
CSVs themselves.
"""
from __future__ import annotations

import importlib.util
import warnings

import numpy as np
import pytest

from gyrofilter.recording import read_recording
from support import REPO, RECORDINGS, SHARED_DATA


# name: (rows, source csv under ../shared/data, gyro mean deg/s or None, gyro std deg/s)
# numbers from SOURCE.md (3 decimals; std of the motion files to 0.1 / 0.01 as written there)
EXPECTED = {
    "mpu6050_static_655s": (65067, "mpu6050_sensorfusion/static_10min_set2.csv",
                            [4.535, 0.047, 1.122], [0.126, 0.091, 0.113]),
    "mpu6050_static_123s": (12243, "mpu6050_sensorfusion/static_2min_set2.csv", None, None),
    "mpu6050_static_64s_set1": (6383, "mpu6050_sensorfusion/static_1min_set1.csv", None, None),
    "mpu6050_rotate_z_24s": (2393, "mpu6050_sensorfusion/dynamic_rotate_ccw_z_set2.csv", None, None),
    "mpu6050_static_449s": (44930, "mpu6050_imucalibration/example_data_tinit_calc.csv",
                            [-3.345, 1.089, -0.498], [0.075, 0.111, 0.094]),
    "mpu6050_static_100s": (9986, "mpu6050_imucalibration/imu_static_test.csv",
                            [-3.268, 1.118, -0.504], [0.075, 0.112, 0.094]),
    "mpu6050_multipose_102s": (10245, "mpu6050_imucalibration/example_data_calibration.csv",
                               None, [28.4, 25.6, 29.4]),
    "mpu6050_rotate_x90_100s": (9987, "mpu6050_imucalibration/imu_90_x_rot.csv", None, [4.66, 1.38, 0.97]),
}
SENSORFUSION = [n for n, v in EXPECTED.items() if v[1].startswith("mpu6050_sensorfusion")]
IMUCALIBRATION = [n for n, v in EXPECTED.items() if v[1].startswith("mpu6050_imucalibration")]
PROVENANCE_KEYS = ("sensor", "source", "licence", "full_scale_dps", "description", "modified")

needs_shared = pytest.mark.skipif(not SHARED_DATA.is_dir(), reason="../shared/data (upstream CSVs) not present")

_cache = {}


def load(name):
    if name not in _cache:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a Python warning while reading fails the test
            _cache[name] = read_recording(RECORDINGS / f"{name}.csv.gz")
    return _cache[name]


def test_exactly_the_expected_mpu6050_files_ship():
    shipped = sorted(p.name[: -len(".csv.gz")] for p in RECORDINGS.glob("mpu6050_*.csv.gz"))
    assert shipped == sorted(EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_reads_cleanly_with_provenance(name):
    rec = load(name)
    assert rec.warnings == [] and rec.notes == []
    assert len(rec) == EXPECTED[name][0]
    assert rec.gyro_unit == "lsb" and rec.lsb_per_dps == 131.0
    for key in PROVENANCE_KEYS:
        assert rec.header.get(key), f"{name}: header key {key!r} missing or empty"
    assert rec.header["sensor"] == "MPU6050" and rec.header["full_scale_dps"] == "250"
    assert "t" not in rec.columns  # uniform sampling in every file (see recordings/README.md)
    assert np.array_equal(rec.gyro, np.round(rec.gyro))  # integer LSB
    assert np.all(np.abs(rec.gyro) <= 32768)
    licence_file = rec.header["licence"].rsplit("recordings/LICENSES/", 1)[1]
    assert (RECORDINGS / "LICENSES" / licence_file).is_file()


@pytest.mark.parametrize("name", [n for n, v in EXPECTED.items() if v[2] is not None or v[3] is not None])
def test_statistics_match_source_md(name):
    rec = load(name)
    _, _, mean_dps, std_dps = EXPECTED[name]
    g = rec.gyro_dps
    if mean_dps is not None:
        np.testing.assert_allclose(g.mean(axis=0), mean_dps, atol=0.002)
        np.testing.assert_allclose(g.std(axis=0), std_dps, atol=0.002)
    else:  # motion files: SOURCE.md gives the std to 3 significant digits
        np.testing.assert_allclose(g.std(axis=0), std_dps, rtol=0.005)


@pytest.mark.parametrize("name", ["mpu6050_static_123s", "mpu6050_static_64s_set1"])
def test_other_sensorfusion_static_files_match_source_md(name):
    # SOURCE.md: "same bias level (gyro X ~ 4.53-4.54 deg/s), std 0.07-0.13 deg/s"
    g = load(name).gyro_dps
    assert 4.525 <= g[:, 0].mean() <= 4.545
    assert np.all((g.std(axis=0) >= 0.065) & (g.std(axis=0) <= 0.135))


def test_multipose_saturates_as_source_md_says():
    g = load("mpu6050_multipose_102s").gyro
    saturated = ((g >= 32767) | (g <= -32768)).sum(axis=0)
    assert saturated.tolist() == [12, 0, 6]


def test_sensorfusion_rate_and_columns():
    for name in SENSORFUSION:
        rec = load(name)
        assert list(rec.columns) == ["gx", "gy", "gz", "temp", "ax", "ay", "az", "host_t"]
        host_t = rec.columns["host_t"]
        assert np.all(np.diff(host_t) > 0)
        # sample_rate_hz is the mean rate of the host timestamps (to the 6 digits written)
        mean_rate_hz = (len(rec) - 1) / (host_t[-1] - host_t[0])
        assert rec.sample_rate_hz == pytest.approx(mean_rate_hz, rel=1e-5)
        assert 99.0 < rec.sample_rate_hz < 100.5
    temp = load("mpu6050_static_655s").temp_c
    assert temp.min() == pytest.approx(25.14, abs=0.005) and temp.max() == pytest.approx(25.61, abs=0.005)
    # set-1 accel reads +1 g on Z, set-2 -1 g (the axis conventions noted in the header)
    assert load("mpu6050_static_64s_set1").columns["az"].mean() > 0.9
    assert load("mpu6050_static_655s").columns["az"].mean() < -0.9


def test_rotate_z_integrates_to_about_two_turns():
    rec = load("mpu6050_rotate_z_24s")
    angle_deg = np.sum(rec.gyro_dps[:, 2] - 1.122) / rec.sample_rate_hz
    assert angle_deg == pytest.approx(703, abs=3)  # SOURCE.md: 703 deg with uniform dt (nominal 720)


def test_imucalibration_columns_and_accel_in_g():
    for name in IMUCALIBRATION:
        rec = load(name)
        assert list(rec.columns) == ["gx", "gy", "gz", "ax", "ay", "az"]
        assert rec.sample_rate_hz == 100.0 and rec.header["accel_unit"] == "g"
        accel_lsb = np.column_stack([rec.columns[c] for c in ("ax", "ay", "az")]) * 16384
        assert np.abs(accel_lsb - np.round(accel_lsb)).max() < 1e-4
    assert load("mpu6050_multipose_102s").header["upstream_logging_type"].startswith("0")
    assert load("mpu6050_static_449s").header["upstream_logging_type"].startswith("1")
    # SOURCE.md: static raw accel mean [2644, -643, 14791] LSB
    rec = load("mpu6050_static_449s")
    accel_mean_lsb = [rec.columns[c].mean() * 16384 for c in ("ax", "ay", "az")]
    np.testing.assert_allclose(accel_mean_lsb, [2644, -643, 14791], atol=1)


@needs_shared
@pytest.mark.parametrize("name", SENSORFUSION)
def test_sensorfusion_lossless_against_upstream_csv(name):
    src = np.loadtxt(SHARED_DATA / EXPECTED[name][1], delimiter=",", skiprows=1, ndmin=2)
    rec = load(name)
    err = np.abs(rec.gyro_dps - src[:, 4:7])
    assert np.all(err <= 1e-9 * np.maximum(1.0, np.abs(src[:, 4:7])))
    for column, i in (("host_t", 0), ("ax", 1), ("ay", 2), ("az", 3), ("temp", 7)):
        assert np.array_equal(rec.columns[column], src[:, i]), column


@needs_shared
@pytest.mark.parametrize("name", IMUCALIBRATION)
def test_imucalibration_lossless_against_upstream_csv(name):
    src = np.loadtxt(SHARED_DATA / EXPECTED[name][1], delimiter=",", skiprows=5, dtype=np.int64, ndmin=2)
    rec = load(name)
    assert np.array_equal(rec.gyro, src[:, 3:6])
    accel = np.column_stack([rec.columns[c] for c in ("ax", "ay", "az")])
    assert np.array_equal(np.round(accel * 16384).astype(np.int64), src[:, 0:3])


def _converter():
    spec = importlib.util.spec_from_file_location("convert_mpu6050", REPO / "tools" / "convert_mpu6050.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
@needs_shared
def test_converter_reproduces_the_shipped_files_byte_for_byte(tmp_path, capsys):
    assert _converter().main(["--shared", str(SHARED_DATA.parent), "--out", str(tmp_path)]) == 0
    for name in EXPECTED:
        new = (tmp_path / f"{name}.csv.gz").read_bytes()
        assert new == (RECORDINGS / f"{name}.csv.gz").read_bytes(), name


def test_converter_refuses_values_off_the_lsb_grid(tmp_path):
    conv = _converter()
    good = np.array([[625 / 131, -1 / 131, 11642 / 131]])
    assert conv.quantize_lossless(good, 131, "gyro", "x.csv").tolist() == [[625, -1, 11642]]
    bad = good + np.array([[0.0, 0.0, 1e-6]])
    with pytest.raises(conv.ConversionError, match=r"x.csv: data row 1, gyro column 2"):
        conv.quantize_lossless(bad, 131, "gyro", "x.csv")


def test_the_readmes_commands_filter_the_recording_that_turns_from_its_first_sample(tmp_path, monkeypatch, capsys):
    """A new user's trial: `gyrofilter replay recordings/mpu6050_rotate_z_24s.csv.gz` is refused ("the sensor
    moved": it turns from its first sample) and recordings/README.md did not say what to do. Its commands (run
    word for word from the repository) save a calibration from a still recording and filter the turning one
    with it: two turns of 360 degrees about z (the upstream's "two 360-degree CCW turns")."""
    import shlex

    from gyrofilter.cli import main

    text = (RECORDINGS / "README.md").read_text(encoding="utf-8")
    commands = [shlex.split(line) for line in text.split("```sh\n", 1)[1].split("```", 1)[0].splitlines()]
    assert [c[:2] for c in commands] == [["gyrofilter", "replay"]] * 2
    monkeypatch.chdir(REPO)
    out = tmp_path / "rows.csv"
    names = {"cal655.json": str(tmp_path / "cal655.json")}  # the README's file, written outside the repository
    assert main(["replay", commands[1][2]]) == 2
    assert "the sensor moved" in capsys.readouterr().err
    for command in commands:
        assert main([names.get(a, a) for a in command[1:]] + (["--out", str(out)] if command is commands[1] else [])) == 0
    rows = read_recording(out)
    turned = rows.gyro_dps[:, 2].sum() / rows.sample_rate_hz
    assert 690 < turned < 730, turned
