"""gyrofilter.tempscreen: the read glitches of a temperature column (a die's temperature is smooth) and
their replacement by the interpolation of their good neighbours."""
import json
import importlib.resources

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from gyrofilter.sim.simulate import simulate
from gyrofilter.tempscreen import (MAX_GLITCH_FRACTION, TEMP_GLITCH_HALF_WIDTH, replace_glitches, screened_temp,
                                   temp_glitches)

CODE_C = 1 / 340  # one MPU6050 TEMP_OUT code (register map section 4.18)


def _codes(t):
    return np.round(np.asarray(t) / CODE_C) * CODE_C


def test_a_step_of_one_code_is_never_a_glitch():
    flat = np.full(2000, 25.0)
    for at in (0, 1, 3, 1000, 1998, 1999):
        t = flat.copy()
        t[at:] += CODE_C
        assert temp_glitches(t, 100.0).size == 0, at
        one = flat.copy()
        one[at] += CODE_C  # a lone code up and back: toggling, not a glitch
        assert temp_glitches(one, 100.0).size == 0, at
    toggling = 25.0 + 0.14 * np.random.default_rng(0).integers(0, 3, 5000)  # ADIS16405 codes, 0.14 deg C
    assert temp_glitches(toggling, 100.0).size == 0


@pytest.mark.parametrize("tau_s, noise_c", [(20.0, 0.02), (5.0, 0.0), (60.0, 0.0)])
def test_a_warm_up_of_10_c_in_60_s_at_1_khz_has_no_glitch(tau_s, noise_c):
    t_s = np.arange(60_000) / 1000.0
    rise = 10.0 * (1 - np.exp(-t_s / tau_s)) / (1 - np.exp(-60.0 / tau_s))
    temp = _codes(25.0 + rise + np.random.default_rng(1).normal(0, noise_c, t_s.size))
    assert temp_glitches(temp, 1000.0).size == 0
    assert temp_glitches(temp[::-1], 1000.0).size == 0  # a cool-down


def test_simulated_warm_ups_have_no_glitch():
    model = json.loads((importlib.resources.files("gyrofilter") / "data" / "mpu6050_model.json").read_text())
    for seed, (rate_hz, profile) in enumerate([(100.0, dict(start_c=20, end_c=45, tau_s=60, noise_c=0.05, resolution_c=0.14,
                                                            cycle_amplitude_c=3, cycle_period_s=120)),
                                               (10.0, dict(start_c=25, end_c=-10, tau_s=100, resolution_c=CODE_C)),
                                               (100.0, dict(model["temperature"], tau_s=30.0))]):
        rec = simulate(dict(model, temperature=profile, sample_rate_hz=rate_hz), 300.0, seed=seed)
        assert temp_glitches(rec.temp_c, rate_hz).size == 0, profile


@pytest.mark.parametrize("at", [0, 2, 777, 1999])
@pytest.mark.parametrize("size_c, rate_hz", [(0.5, 1000.0), (-0.5, 1000.0), (-84.0, 100.0), (-84.0, 10.0)])
def test_a_spike_is_a_glitch_where_ever_it_is(at, size_c, rate_hz):
    """Within k samples of an end the threshold grows by the die's fastest rate times the samples to the
    window's centre (1 deg C at sample 0 at 100 Hz): a 0.5-deg C spike is found there at 1 kHz."""
    rng = np.random.default_rng(3)
    temp = _codes(np.linspace(25.0, 26.0, 2000) + rng.normal(0, 0.01, 2000))
    temp[at] += size_c
    assert temp_glitches(temp, rate_hz).tolist() == [at]


@pytest.mark.parametrize("size_c", [0.5, -0.5])
def test_a_spike_of_half_a_degree_is_a_glitch_at_100_hz(size_c):
    rng = np.random.default_rng(4)
    temp = _codes(np.linspace(25.0, 26.0, 2000) + rng.normal(0, 0.01, 2000))
    temp[[5, 777]] += size_c
    assert temp_glitches(temp, 100.0).tolist() == [5, 777]


@pytest.mark.parametrize("run", range(1, TEMP_GLITCH_HALF_WIDTH + 1))
def test_a_run_of_glitches_up_to_the_half_width_is_found_and_replaced(run):
    temp = np.linspace(25.0, 30.0, 1000)
    broken = temp.copy()
    broken[500:500 + run] = -59.85
    found = temp_glitches(broken, 100.0)
    assert found.tolist() == list(range(500, 500 + run))
    assert np.allclose(replace_glitches(broken, found), temp)  # linear: the interpolation is exact


def test_screened_temp_notes_and_refuses_a_broken_column():
    temp = np.linspace(25.0, 30.0, 1000)
    assert screened_temp(temp, 100.0) == (pytest.approx(temp), None)
    temp[[10, 20]] = -59.85
    fixed, note = screened_temp(temp, 100.0)
    assert note == "temp column: 2 glitch(es) replaced by their neighbours' interpolation, first at sample 11 (value -59.85 C)"
    assert np.allclose(fixed, np.linspace(25.0, 30.0, 1000)) and temp[10] == -59.85  # the input is left alone
    temp[100:1000:int(1 / MAX_GLITCH_FRACTION) // 2] = -59.85
    fixed, note = screened_temp(temp, 100.0)
    assert fixed is None and note.endswith("temperature not analysed") and "more than 1 %" in note


@pytest.mark.parametrize("n", [0, 1, 2, 3, 4, 11, 12])
def test_short_columns(n):
    temp = np.linspace(25.0, 26.0, n)
    assert temp_glitches(temp, 100.0).size == 0
    if n >= 3:
        temp[n // 2] = -59.85
        assert temp_glitches(temp, 100.0).tolist() == [n // 2]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-100, 200), min_size=0, max_size=80), st.sampled_from([1.0, 100.0, 1000.0]))
def test_any_column_gets_valid_indices_and_a_replacement_within_its_good_values(values, rate_hz):
    temp = np.array(values, dtype=float)
    found = temp_glitches(temp, rate_hz)
    assert np.all(np.diff(found) > 0) and np.all((found >= 0) & (found < temp.size))
    fixed = replace_glitches(temp, found)
    assert fixed.shape == temp.shape and np.all(np.isfinite(fixed))
    good = np.delete(temp, found)
    if good.size and found.size:
        assert good.min() <= fixed.min() and fixed.max() <= good.max()


@pytest.mark.parametrize("column", ["constant", "staircase"])
def test_a_glitch_on_a_column_that_never_departs_is_found(column):
    """Attack pass 37l: on a column on one code, or a noise-free staircase of 0.1 deg C codes, the only
    nonzero departures were the glitches', taken as the column's code: the limit became 4 times the
    glitch and nothing was found (gap's temperature flipped to warmup, a saved calibration's T0 moved)."""
    n = 30_000
    t = np.full(n, 25.0) if column == "constant" else np.round(20 + 10 * (1 - np.exp(-np.arange(n) / 20_000)), 1)
    at = [8000, 16000, 24000]
    t[at] = -32768 / 340 + 36.53
    assert temp_glitches(t, 100.0).tolist() == at


@pytest.mark.parametrize("at", [0, 1, 3598, 3599])
def test_a_glitch_at_either_end_of_a_slow_log_is_found(at):
    """Attack pass 37n: at 1 Hz the end allowance (20 deg C/s x 5 samples) granted 100 deg C, and a
    -59.85 deg C read on the first or last sample of a warming 1-Hz log went through (gap's temperature
    interval left out the true coefficient, or the finding turned into a warm-up and a step)."""
    t = np.arange(3600.0)
    temp = 25 + 8 * (1 - np.exp(-t / 600)) + np.random.default_rng(at).normal(0, 0.02, t.size)
    clean = temp_glitches(temp, 1.0).tolist()
    temp[at] = -32768 / 340 + 36.53
    assert temp_glitches(temp, 1.0).tolist() == sorted(clean + [at])
    temp[at] = temp[at - 1 if at else 1] + 11.5  # a read 11.5 deg C off (a zero read of a die at 25 deg C), at 5 Hz
    assert at in temp_glitches(temp, 5.0).tolist()
