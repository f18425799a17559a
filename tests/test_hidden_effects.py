"""gyrofilter.sim.hidden_effects: hiding one effect in a recording built in code refuses what the
simulator's model refuses (attack pass 22: a colored noise of lag1 NaN gave a recording of NaN
rates, an axis 'w' a KeyError, lag1 1.5 a math domain error)."""
import numpy as np
import pytest

from gyrofilter.effects import COLORED_NOISE, HEAVY_TAILS, REPEATED_SAMPLES
from gyrofilter.errors import SettingsError
from gyrofilter.recording import Recording, write_recording
from gyrofilter.sim.hidden_effects import hide_in_recording


def record():
    return Recording.from_dps(np.random.default_rng(0).normal(size=(500, 3)), 100.0)


@pytest.mark.parametrize("effect,params", [(COLORED_NOISE, {"lag1": float("nan")}), (COLORED_NOISE, {"lag1": 1.5}),
                                           (HEAVY_TAILS, {"fraction": 2.0, "scale_ratio": 3.0}),
                                           (HEAVY_TAILS, {"fraction": float("nan"), "scale_ratio": 3.0})])
def test_parameters_the_model_refuses_are_refused(effect, params):
    with pytest.raises(SettingsError, match=rf"model: axes.x.effects\[0\] \({effect}\)"):
        hide_in_recording(record(), effect, "x", params)


def test_an_axis_that_is_none_is_refused():
    with pytest.raises(SettingsError, match="axis must be one of x, y, z, got 'w'"):
        hide_in_recording(record(), COLORED_NOISE, "w", {"lag1": 0.3})


def test_a_valid_colored_noise_keeps_the_axis_finite():
    out = hide_in_recording(record(), COLORED_NOISE, "x", {"lag1": 0.3})
    assert np.all(np.isfinite(out.gyro_dps))


@pytest.mark.parametrize("params", [{"fraction": 5.0}, {"fraction": float("nan")}, {"fraction": -1.0}, {},
                                    {"fraction": 0.1, "pattern": "bogus"}, {"fraction": "0.1"}])
def test_repeated_samples_parameters_the_model_refuses_are_refused(params):
    """Attack pass 23: pass 22's check skipped the whole-row effect: a fraction of 5 repeated
    every row, NaN or -1 none, a pattern 'bogus' ran as 'random', a string was taken as a
    number, and no fraction ended in a KeyError."""
    with pytest.raises(SettingsError, match=r"model: repeated_samples"):
        hide_in_recording(record(), REPEATED_SAMPLES, "xyz", params)


def test_a_six_axis_record_gives_a_recording_that_writes(tmp_path):
    """Attack pass 24: a six-axis record's effect-added copy (gyro and temp only) kept the header's
    accel_unit without its columns ax, ay, az: write_recording refused the recording it made."""
    rng = np.random.default_rng(3)
    rec = Recording.from_dps(rng.normal(0, 0.1, (300, 3)), 100.0, accel=rng.normal(0, 1, (300, 3)), accel_unit="lsb",
                             lsb_per_g=16384, temp_c=np.full(300, 25.0))
    out = hide_in_recording(rec, "sinusoid", "x", {"frequency_hz": 1.0, "amplitude_dps": 0.1})
    write_recording(tmp_path / "hidden.csv", out)
    assert "accel_unit" not in out.header and "lsb_per_g" not in out.header
