"""Tests of the simulator's accelerometer (gyrofilter/sim/accel.py and its wiring in
sim/simulate.py, sim/model.py, the ``sim`` source and ``gyrofilter simulate``).

Oracles: the gyro columns of the code before the accelerometer (their SHA-256, pinned), the same
model without its accelerometer, the one-shot run against any chunking, closed forms (gravity,
temperature coefficient, quantization) and the Allan fit of gyrofilter.analysis.noise against the
model's coefficients. All random tests are seeded.
"""
import copy
import json

import numpy as np
import pytest

from gyrofilter.analysis.noise.fit import characterise_axis
from gyrofilter.cli import main
from gyrofilter.errors import SettingsError
from gyrofilter.recording import read_recording
from gyrofilter.sim import simulate as simulate_module
from gyrofilter.sim.model import validate_model
from gyrofilter.sim.simulate import (recording_columns, recording_header, simulate, simulate_axis_dps, simulate_chunks,
                                     simulate_dps)
from gyrofilter.sources.simulated import DEFAULT_MODEL, SimulatedSource
from gyrofilter.units import STANDARD_GRAVITY_MPS2 as G

ACCEL = ["ax", "ay", "az"]


def six_axis(accel_axes, *, unit="dps", up="z", **top):
    """A model of white gyro noise and the accelerometer ``accel_axes`` (axis -> its keys)."""
    model = {"sample_rate_hz": 100.0, "gyro_unit": unit, **top,
             "axes": {a: {"arw_dps_per_sqrt_hz": 0.01} for a in "xyz"},
             "accelerometer": {"up": up, "axes": accel_axes}}
    if unit == "lsb":
        model["lsb_per_dps"] = 131.0
        model["accelerometer"]["lsb_per_g"] = 16384.0
    return model


#: the default model's gx, gy, gz (sums of their LSB) and temp (sum, deg C) for 60 s, written by the simulator before it
#: had an accelerometer (commit f3d794a): the gyro stream of a model and seed stays what it was. Sums, not the
#: bits: a float's last bit differs between machines and numpy versions (their SIMD paths for the sines and
#: sums), which moves about 1 quantized sample in 2000 by 1 LSB (numpy 1.24: 1-3 of 6000 per axis, the sums by
#: up to 3; one of the two seeds' SHA-256 differed between two x86-64 machines with the same packages), while
#: another stream moves a 60-s sum by hundreds of LSB (the noise's 400 LSB over 6000 samples)
GYRO_SUMS = {1: (-2592488, 856224, -393023, 147587.32647058825), 2: (-2592175, 857364, -390165, 147587.67352941175)}
SUM_TOLERANCE_LSB = 20


@pytest.mark.parametrize("seed", sorted(GYRO_SUMS))
def test_the_default_models_gyro_samples_are_those_of_the_gyro_only_simulator(seed):
    rec = simulate(DEFAULT_MODEL, 60.0, seed=seed)
    assert list(rec.columns) == ["t", "gx", "gy", "gz", "temp", *ACCEL]
    sums = [float(np.sum(rec.columns[c])) for c in ("gx", "gy", "gz", "temp")]
    assert np.all(np.abs(np.subtract(sums[:3], GYRO_SUMS[seed][:3])) <= SUM_TOLERANCE_LSB), (sums, GYRO_SUMS[seed])
    assert sums[3] == pytest.approx(GYRO_SUMS[seed][3], abs=1e-6)


def test_adding_an_accelerometer_leaves_every_other_column_unchanged():
    without = copy.deepcopy(DEFAULT_MODEL)
    del without["accelerometer"]
    rec, alone = simulate(DEFAULT_MODEL, 30.0, seed=8), simulate(without, 30.0, seed=8)
    assert list(alone.columns) == ["t", "gx", "gy", "gz", "temp"]
    for name in alone.columns:
        assert np.array_equal(rec.columns[name], alone.columns[name]), name


@pytest.mark.parametrize("chunk", [1, 97, 4096])
def test_the_accelerometer_does_not_depend_on_the_chunking(chunk):
    model = copy.deepcopy(DEFAULT_MODEL)
    model["repeated_samples"] = {"fraction": 0.05}  # whole rows repeat, the accelerometer's too
    one = simulate(model, 20.0, seed=5, chunk_samples=10**7)
    parts = list(simulate_chunks(model, 20.0, seed=5, chunk_samples=chunk))
    accel = np.concatenate([block.accel for block in parts])
    assert np.array_equal(accel, np.column_stack([one.columns[c] for c in ACCEL]))
    repeated = np.all(np.diff(np.column_stack([one.columns[c] for c in ("gx", "gy", "gz", *ACCEL)]), axis=0) == 0, axis=1)
    assert np.array_equal(np.all(np.diff(accel, axis=0) == 0, axis=1), repeated) and repeated.sum() > 20


def test_header_and_columns_state_the_accelerometers_unit():
    spec = validate_model(DEFAULT_MODEL)[0]
    header = recording_header(DEFAULT_MODEL, 10.0, seed=1, validated=spec)
    assert (header["accel_unit"], header["lsb_per_g"]) == ("lsb", "16384")
    assert recording_columns(spec)[-3:] == ACCEL and recording_columns(DEFAULT_MODEL)[-3:] == ACCEL
    head = recording_header(six_axis({"x": {"vrw_mps_per_sqrt_s": 0.004}}), 10.0, seed=1)
    assert head["accel_unit"] == "m/s^2" and "lsb_per_g" not in head
    gyro_only = {"sample_rate_hz": 100.0}
    assert "accel_unit" not in recording_header(gyro_only, 1.0) and recording_columns(gyro_only) == ["t", "gx", "gy", "gz"]


@pytest.mark.parametrize("up, signs", [("z", (0, 0, 1)), ("-y", (0, -1, 0)), ("x", (1, 0, 0))])
def test_gravity_is_on_the_axis_that_points_up(up, signs):
    bias = {"x": 0.2, "y": -0.3, "z": 0.45}
    rec = simulate(six_axis({a: {"bias_mps2": b, "vrw_mps_per_sqrt_s": 0.004} for a, b in bias.items()}, up=up), 100.0,
                   seed=2)
    for name, a, sign in zip(ACCEL, "xyz", signs):
        x = rec.columns[name]
        assert abs(x.mean() - (sign * G + bias[a])) < 5 * 0.004 * 10 / np.sqrt(x.size)  # 5 standard errors


def test_lsb_output_is_the_rounded_acceleration_and_mps2_output_its_quantized_value():
    axes = {"x": {"bias_mps2": 0.123456}, "y": {"bias_mps2": -0.0001}}
    lsb = simulate(six_axis(axes, unit="lsb"), 1.0, seed=0)
    expect = np.round(np.array([0.123456, -0.0001, G]) * 16384.0 / G)
    assert np.array_equal(np.column_stack([lsb.columns[c] for c in ACCEL])[0], expect)
    model = six_axis(axes)
    model["accelerometer"]["lsb_per_g"] = 16384.0
    mps2 = simulate(model, 1.0, seed=0)
    assert np.allclose(np.column_stack([mps2.columns[c] for c in ACCEL])[0], expect * G / 16384.0, rtol=0, atol=1e-15)
    plain = simulate(six_axis(axes), 1.0, seed=0)
    assert plain.columns["ax"][0] == 0.123456


def test_the_temperature_coefficient_follows_the_true_temperature():
    temp = {"start_c": 20.0, "end_c": 30.0, "tau_s": 50.0}
    rec = simulate(six_axis({"y": {"coefficient_mps2_per_c": 0.005}}, up="x", temperature=temp), 200.0, seed=1)
    t = rec.columns["t"]
    true_c = 30.0 - 10.0 * np.exp(-t / 50.0)
    assert np.allclose(rec.columns["ay"], 0.005 * (true_c - 20.0), rtol=0, atol=1e-12)


def test_the_allan_deviation_recovers_the_models_vrw_bias_instability_and_random_walk():
    vrw, b, k = 0.0039227, 0.002, 2e-4
    model = six_axis({"x": {"bias_mps2": 0.2, "vrw_mps_per_sqrt_s": vrw, "b_mps2": b},
                      "y": {"vrw_mps_per_sqrt_s": vrw, "k_mps2_per_sqrt_s": k}}, unit="lsb")
    rec = simulate(model, 3600.0, seed=1)
    to_mps2 = G / float(rec.header["lsb_per_g"])
    fx = characterise_axis(rec.columns["ax"] * to_mps2, 100.0, axis="x").fitted
    fy = characterise_axis(rec.columns["ay"] * to_mps2, 100.0, axis="y").fitted
    assert fx["angle_random_walk"].value == pytest.approx(vrw, rel=0.03)
    assert fx["bias_instability"].value == pytest.approx(b, rel=0.2)
    assert fy["angle_random_walk"].value == pytest.approx(vrw, rel=0.03)
    assert fy["rate_random_walk"].value == pytest.approx(k, rel=0.3)
    assert not fy["bias_instability"].resolved and not fx["rate_random_walk"].resolved


def test_gyro_only_paths_do_not_compute_the_accelerometer(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("the accelerometer was built")

    monkeypatch.setattr(simulate_module, "Accelerometer", refuse)
    gyro, _ = simulate_dps(DEFAULT_MODEL, 5.0, seed=3)
    for axis in range(3):
        alone = np.concatenate(list(simulate_axis_dps(DEFAULT_MODEL, 5.0, axis, seed=3)))
        assert np.array_equal(alone, gyro[:, axis])
    with pytest.raises(AssertionError, match="accelerometer was built"):
        simulate(DEFAULT_MODEL, 5.0, seed=3)


@pytest.mark.parametrize("change, message", [
    (lambda a: a.pop("lsb_per_g"), "accelerometer.lsb_per_g: missing: gyro_unit 'lsb'"),
    (lambda a: a.update(up="up"), r"accelerometer.up: expected one of x, y, z, -x, -y, -z"),
    (lambda a: a.update(range_g=2), "accelerometer.range_g: unknown key"),
    (lambda a: a["axes"].update(w={}), "accelerometer.axes.w: unknown axis"),
    (lambda a: a["axes"]["x"].update(vrw=1.0), r"accelerometer.axes.x.vrw: unknown key \(expected bias_mps2"),
    (lambda a: a["axes"]["x"].update(vrw_mps_per_sqrt_s=-1.0), "vrw_mps_per_sqrt_s: expected a number >= 0"),
    (lambda a: a["axes"]["y"].update(bias_mps2=1e6), r"accelerometer.axes.y.bias_mps2: expected a number <= 100000"),
    (lambda a: a["axes"]["z"].update(b_mps2="0.1"), "accelerometer.axes.z.b_mps2: expected a number >= 0"),
    (lambda a: a.update(lsb_per_g=1e-300), "accelerometer.lsb_per_g: expected a number >= 0.5, got 1e-300"),
    (lambda a: a.update(axes=[]), "accelerometer.axes: expected an object"),
])
def test_a_bad_accelerometer_is_refused_naming_its_key(change, message):
    model = copy.deepcopy(DEFAULT_MODEL)
    change(model["accelerometer"])
    with pytest.raises(SettingsError, match=message):
        validate_model(model)


def test_a_temperature_coefficient_needs_the_temperature_profile():
    model = six_axis({"z": {"coefficient_mps2_per_c": 0.001}})
    with pytest.raises(SettingsError, match="accelerometer.axes.z.coefficient_mps2_per_c: needs the model's 'temperature'"):
        validate_model(model)
    assert validate_model(model, coefficients_only=True)[0]["accelerometer"]["axes"]["z"]["coefficient_mps2_per_c"] == 0.001


def test_the_sim_source_delivers_the_accelerometer_as_simulate_does():
    source = SimulatedSource(seed=4, realtime=False, duration_s=12.0)
    try:
        assert source.columns == ["t", "gx", "gy", "gz", "temp", *ACCEL]
        assert (source.header["accel_unit"], source.header["lsb_per_g"]) == ("lsb", "16384")
        rows = np.vstack([source.read() for _ in range(2)])
    finally:
        source.close()
    rec = simulate(DEFAULT_MODEL, 12.0, seed=4)
    assert np.array_equal(rows, np.column_stack([rec.columns[c] for c in source.columns])[:len(rows)])


def test_simulate_writes_the_accelerometer_columns_and_they_read_back(tmp_path, capsys):
    model_path, out = tmp_path / "m.json", tmp_path / "six.csv.gz"
    model_path.write_text(json.dumps(DEFAULT_MODEL))
    assert main(["simulate", "--model", str(model_path), "--duration", "3", "--seed", "6", "--chunk", "77",
                 "--out", str(out)]) == 0
    assert "gyro_unit lsb, accel_unit lsb, seed 6" in capsys.readouterr().out
    rec, one = read_recording(out), simulate(DEFAULT_MODEL, 3.0, seed=6)
    assert rec.header["accel_unit"] == "lsb" and rec.header["lsb_per_g"] == "16384"
    for name in one.columns:
        assert np.array_equal(rec.columns[name], one.columns[name]), name


def test_formats_md_states_the_accelerometers_bound():
    from gyrofilter.sim.model import MAX_MODEL_ACCEL_MPS2
    from support import REPO

    text = (REPO / "docs" / "formats.md").read_text(encoding="utf-8")
    row = "| a model's accelerometer numbers, in m/s² (and m/s² per √s or per °C, m/s per √s) |"
    assert f"{row} ±{MAX_MODEL_ACCEL_MPS2:g} |" in text
    assert f"Each number within ±{MAX_MODEL_ACCEL_MPS2:g} m/s²" in text


def test_record_from_the_sim_source_keeps_the_accelerometer(tmp_path):
    out = tmp_path / "six.csv"
    assert main(["record", "--source", "sim:seed=3,realtime=0", "--duration", "2", "--out", str(out), "--quiet"]) == 0
    rec, one = read_recording(out), simulate(DEFAULT_MODEL, 2.0, seed=3)
    assert list(rec.columns) == list(one.columns) and rec.header["accel_unit"] == "lsb"
    assert np.array_equal(np.column_stack([rec.columns[c] for c in ACCEL]), np.column_stack([one.columns[c] for c in ACCEL]))
