"""Tests of the gyro simulator: every term has the statistics its docstring claims.

Oracles: closed forms (deterministic terms, AR(1) Allan variance), the Allan deviation of
gyrofilter.analysis.noise.allan (itself tested against allantools), and sample statistics with tolerances
of several standard errors. All random tests are seeded.
"""
import json
import math
import re
from statistics import NormalDist

import numpy as np
import pytest

from gyrofilter.sim import noise_terms as nt
from gyrofilter.analysis.noise.allan import overlapping_adev
from gyrofilter.errors import SettingsError
from gyrofilter.recording import read_recording, write_recording
from gyrofilter.effects import ROWS
from gyrofilter.sim.model import EFFECTS, validate_model
from gyrofilter.sim.simulate import simulate, simulate_axis_dps, simulate_chunks
from gyrofilter.units import DEG_PER_RAD


def model(effects=(), *, fs=100.0, unit="dps", bias=0.0, arw=0.0, axes="xyz", **top):
    m = {"sample_rate_hz": fs, "gyro_unit": unit, **top, "axes": {}}
    for a in axes:
        m["axes"][a] = {"bias_dps": bias, "arw_dps_per_sqrt_hz": arw, "effects": [dict(e) for e in effects]}
    return m


ALL_EFFECTS = [
    {"effect": "bias_instability", "b_dps": 0.01},
    {"effect": "rate_random_walk", "k_dps_per_sqrt_s": 0.002},
    {"effect": "rate_ramp", "r_dps_per_s": 1e-4},
    {"effect": "gauss_markov", "sigma_dps": 0.02, "tau_s": 5.0},
    {"effect": "sinusoid", "frequency_hz": 7.3, "amplitude_dps": 0.05, "phase_rad": 0.3},
    {"effect": "temperature", "coefficient_dps_per_c": 0.01},
    {"effect": "bias_step", "time_s": 30.0, "size_dps": 0.1},
    {"effect": "warmup", "amplitude_dps": 0.5, "tau_s": 20.0},
    {"effect": "outliers", "rate": 0.002, "magnitude_dps": 2.0},
    {"effect": "colored_noise", "lag1": 0.5},
    {"effect": "narrowband", "center_hz": 33.0, "bandwidth_hz": 2.0, "rms_dps": 0.03},
    {"effect": "arma", "sigma_a_dps": 0.01, "phi": [1.2, -0.5], "theta": [0.3]},
    {"effect": "heavy_tails", "fraction": 0.05, "scale_ratio": 8.0},
    {"effect": "resonance", "center_hz": 12.0, "q": 3.0, "rms_dps": 0.02},
    {"effect": "ringing", "center_hz": 20.0, "q": 2.0, "shock_rate_hz": 0.5, "shock_dps": 0.5},
    {"effect": "wandering_tone", "center_hz": 19.7, "spread_hz": 0.8, "wander_s": 30.0, "amplitude_dps": 0.05},
    {"effect": "compression", "gamma_per_dps2": 1.0, "rms_dps": 0.1},
]
TEMP = {"start_c": 25.0, "end_c": 32.0, "tau_s": 60.0, "noise_c": 0.02, "resolution_c": 1 / 340}


def full_model(**kw):
    return model(ALL_EFFECTS, bias=-3.3, arw=0.009, unit="lsb", lsb_per_dps=131.0, full_scale_dps=250.0,
                 temperature=TEMP, **kw)


def test_every_effect_of_the_table_is_supported():
    assert list(EFFECTS) == ["bias_instability", "rate_random_walk", "rate_ramp", "gauss_markov", "sinusoid",
                             "temperature", "bias_step", "warmup", "outliers", "colored_noise", "narrowband", "arma",
                             "heavy_tails", "repeated_samples", "resonance", "ringing", "wandering_tone", "compression"]
    # the whole-row effects are top-level keys of a model (tests/test_repeats.py), not effects of an axis
    assert {e["effect"] for e in ALL_EFFECTS} == set(EFFECTS) - set(ROWS)


# ---------------------------------------------------------------------------------------------
# determinism, chunking, header


@pytest.mark.parametrize("chunk", [1, 7, 1000])
def test_chunked_equals_one_shot_bit_for_bit(chunk):
    m = full_model()
    duration = 2.0 if chunk == 1 else 61.37
    one = simulate(m, duration, seed=11, chunk_samples=10**7)
    parts = list(simulate_chunks(m, duration, seed=11, chunk_samples=chunk))
    t = np.concatenate([p[0] for p in parts])
    gyro = np.concatenate([p[1] for p in parts])
    temp = np.concatenate([p[2] for p in parts])
    assert np.array_equal(t, one.t_s)
    assert np.array_equal(gyro, one.gyro)
    assert np.array_equal(temp, one.temp_c)
    assert max(len(p[0]) for p in parts) <= chunk


@pytest.mark.parametrize("chunk", [0, -5])
def test_a_block_size_below_one_sample_is_refused(chunk):
    from gyrofilter.sim.simulate import simulate_axis_dps

    for blocks in (simulate_chunks(full_model(), 1.0, seed=1, chunk_samples=chunk),
                   simulate_axis_dps(full_model(), 1.0, 0, seed=1, chunk_samples=chunk)):
        with pytest.raises(SettingsError, match="chunk_samples must be >= 1"):
            next(blocks)


def test_same_seed_same_numbers_and_different_seed_differs():
    m = full_model()
    a, b, c = (simulate(m, 10.0, seed=s).gyro for s in (5, 5, 6))
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    r1 = simulate(m, 10.0, rng=np.random.default_rng(3)).gyro
    r2 = simulate(m, 10.0, rng=np.random.default_rng(3)).gyro
    assert np.array_equal(r1, r2)
    with pytest.raises(SettingsError, match="seed or rng"):
        simulate(m, 1.0, seed=1, rng=np.random.default_rng(1))


def test_axes_are_independent_draws():
    rec = simulate(model(arw=0.01), 100.0, seed=1)
    g = rec.gyro_dps
    corr = np.corrcoef(g.T)
    assert np.all(np.abs(corr[np.triu_indices(3, 1)]) < 0.05)  # 10000 samples: se 0.01


def test_adding_an_effect_keeps_the_other_draws_common_random_numbers():
    base = model([{"effect": "gauss_markov", "sigma_dps": 0.1, "tau_s": 1.0}], arw=0.01)
    ext = json.loads(json.dumps(base))
    sine = {"effect": "sinusoid", "frequency_hz": 1.5, "amplitude_dps": 0.2}
    ext["axes"]["y"]["effects"].insert(0, sine)
    a = simulate(base, 20.0, seed=4)
    b = simulate(ext, 20.0, seed=4)
    expected = 0.2 * np.sin(2 * math.pi * 1.5 * a.t_s)
    assert np.allclose(b.gyro_dps[:, 1] - a.gyro_dps[:, 1], expected, atol=1e-12)
    assert np.array_equal(a.gyro_dps[:, [0, 2]], b.gyro_dps[:, [0, 2]])


def test_header_carries_the_model_and_survives_a_file_round_trip(tmp_path):
    m = full_model()
    rec = simulate(m, 5.0, seed=2)
    assert rec.header["sensor"] == "simulated"
    assert rec.header["gyro_unit"] == "lsb" and float(rec.header["lsb_per_dps"]) == 131.0
    assert json.loads(rec.header["simulated_model"]) == json.loads(json.dumps(m))
    assert rec.header["simulated_seed"] == "2"
    assert list(rec.columns) == ["t", "gx", "gy", "gz", "temp"]
    path = tmp_path / "sim.csv.gz"
    write_recording(path, rec)
    back = read_recording(path)
    assert np.array_equal(back.gyro, rec.gyro)
    assert np.allclose(back.temp_c, rec.temp_c, atol=1e-6)
    assert json.loads(back.header["simulated_model"])["axes"]["x"]["bias_dps"] == -3.3


def test_rate_override_and_sample_count():
    rec = simulate(model(), 2.5, sample_rate_hz=40.0, seed=0)
    assert rec.sample_rate_hz == 40.0 and len(rec) == 100
    assert np.allclose(np.diff(rec.t_s), 1 / 40.0)
    assert json.loads(rec.header["simulated_model"])["sample_rate_hz"] == 40.0


# ---------------------------------------------------------------------------------------------
# validation


@pytest.mark.parametrize("mutate, message", [
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "flicker", "b_dps": 1}), r"axes.x.effects\[0\].effect: unknown effect \"flicker\""),
    (lambda m: m["axes"]["y"]["effects"].append({"effect": "gauss_markov", "sigma_dps": 1}), r"axes.y.effects\[0\] \(gauss_markov\): missing parameter 'tau_s'"),
    (lambda m: m["axes"]["z"]["effects"].append({"effect": "gauss_markov", "sigma_dps": 1, "tau_s": -2}), r"tau_s: expected a number > 0, got -2"),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "outliers", "rate": 1.5, "magnitude_dps": 1}), r"rate: expected a number in \[0, 1\]"),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "sinusoid", "frequency_hz": "7", "amplitude_dps": 1}), r"frequency_hz: expected a number >= 0, got \"7\""),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "colored_noise", "lag1": 1.0}), r"lag1: expected a number in \(-1, 1\)"),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "heavy_tails", "fraction": 0.6, "scale_ratio": 5}), r"\(heavy_tails\).fraction: expected a number <= 0.5"),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "heavy_tails", "fraction": 0.1, "scale_ratio": 0.5}), r"\(heavy_tails\).scale_ratio: expected a number >= 1"),
    (lambda m: m["axes"]["y"]["effects"].extend([{"effect": "heavy_tails", "fraction": 0.1, "scale_ratio": 5}] * 2), r"axes.y.effects: at most one heavy_tails per axis"),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "colored_noise", "lag1": 0.6, "lag2": 0.0}),
     r"\(colored_noise\).lag2: no first-order ARMA noise has lag-1 autocorrelation 0.6 and lag-2 0"),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "colored_noise", "lag1": 0.2, "lag2": 0.3}),
     r"lag2: no first-order ARMA noise .* \(expected \|lag2\| < \|lag1\|"),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "temperature", "coefficient_dps_per_c": 0.1}), r"needs the model's 'temperature' profile"),
    (lambda m: m["axes"].update(w={}), r"axes.w: unknown axis \(expected x, y or z\)"),
    (lambda m: m["axes"]["x"].update(bias=1.0), r"axes.x.bias: unknown key"),
    (lambda m: m["axes"]["x"].update(arw_dps_per_sqrt_hz=-0.1), r"axes.x.arw_dps_per_sqrt_hz: expected a number >= 0"),
    (lambda m: m.update(gyro_unit="deg"), r"gyro_unit: expected one of dps, rad/s, lsb"),
    (lambda m: m.update(gyro_unit="lsb"), r"lsb_per_dps: missing"),
    (lambda m: m.pop("sample_rate_hz"), r"sample_rate_hz: missing"),
    (lambda m: m.update(full_scale_dps=0), r"full_scale_dps: expected a number > 0"),
    (lambda m: m.update(temperature={"end_c": 30}), r"temperature.start_c: missing"),
    (lambda m: m.update(temperature={"t_s": [0, 0], "temp_c": [1, 2]}), r"temperature.t_s\[1\]: expected strictly increasing times, got 0 after 0$"),
    (lambda m: m.update(samplerate=3), r"samplerate: unknown key"),
])
def test_bad_models_raise_one_clear_error(mutate, message):
    m = model(axes="xyz")
    mutate(m)
    with pytest.raises(SettingsError, match=message) as info:
        validate_model(m)
    assert "\n" not in str(info.value)


def test_unknown_effect_parameter_is_a_warning_and_defaults_are_filled():
    m = model([{"effect": "sinusoid", "frequency_hz": 1, "amplitude_dps": 1, "amp": 3, "_note": "x"}], axes="x")
    spec, warnings = validate_model(m)
    assert warnings == ["model: axes.x.effects[0] (sinusoid): unknown parameter 'amp' ignored"]
    assert spec["axes"]["x"]["effects"][0]["phase_rad"] == 0.0
    assert spec["axes"]["y"] == {"bias_dps": 0.0, "arw_dps_per_sqrt_hz": 0.0, "effects": []}


def test_a_misspelt_parameter_is_named_with_the_parameter_it_is_like():
    """A parameter name off by a spelling or a case: the warning says which parameter it is like
    (the did-you-mean of effect names), and a required one missing names the unknown key beside it."""
    hump = {"effect": "resonance", "center_hz": 12.0, "q": 4.0, "rms_dps": 0.02}
    _, warnings = validate_model(model([dict(hump, Q=5.0)], axes="x"))
    assert warnings == ["model: axes.x.effects[0] (resonance): unknown parameter 'Q' ignored; did you mean q?"]
    misspelt = {k: v for k, v in hump.items() if k != "center_hz"} | {"centre_hz": 12.0}
    with pytest.raises(SettingsError) as info:
        validate_model(model([misspelt], axes="x"))
    assert str(info.value) == ("model: axes.x.effects[0] (resonance): missing parameter 'center_hz' (expected a number > 0); "
                               "the unknown 'centre_hz' is ignored: did you mean center_hz?")
    with pytest.raises(SettingsError) as info:  # a key like none of the parameters: the missing one alone
        validate_model(model([{k: v for k, v in hump.items() if k != "q"} | {"width": 3.0}], axes="x"))
    assert str(info.value).endswith("missing parameter 'q' (expected a number in [0.05, 1000])")
    _, warnings = validate_model(model(repeated_samples={"fraction": 0.02, "patern": "beat"}))  # a whole-row effect's key
    assert warnings == ["model: repeated_samples: unknown parameter 'patern' ignored; did you mean pattern?"]


@pytest.mark.parametrize("effect, reach", [
    ({"effect": "sinusoid", "frequency_hz": 60.0, "amplitude_dps": 0.1}, "frequency_hz 60 Hz"),
    ({"effect": "wandering_tone", "center_hz": 10.0, "spread_hz": 1e5, "wander_s": 1.0, "amplitude_dps": 0.1},
     "center_hz + 3 spread_hz 300010 Hz"),
    ({"effect": "narrowband", "center_hz": 45.0, "bandwidth_hz": 20.0, "rms_dps": 0.1}, "center_hz + bandwidth_hz / 2 55 Hz"),
])
def test_a_frequency_past_nyquist_warns_that_it_aliases(effect, reach):
    """Issue 37: every effect whose frequencies can pass the Nyquist frequency (a wandering tone's
    centre plus 3 spreads, a narrowband line's upper half-power edge) gets the sinusoid's warning
    (a wandering tone of spread 1e5 Hz at 100 Hz simulated silently); just below it, none."""
    _, warnings = validate_model(model([effect], axes="x", fs=100.0))
    assert warnings == [f"model: axes.x.effects[0] ({effect['effect']}): {reach} is above the Nyquist frequency 50 Hz "
                        "and will alias"]
    key = {"sinusoid": "frequency_hz", "wandering_tone": "spread_hz", "narrowband": "bandwidth_hz"}[effect["effect"]]
    below = dict(effect, **{key: {"sinusoid": 49.99, "wandering_tone": 13.0, "narrowband": 10.0}[effect["effect"]]})
    assert validate_model(model([below], axes="x", fs=100.0))[1] == []


@pytest.mark.parametrize("phase_rad, peak", [(0.0, "0"), (0.5236, "0.05")])
def test_a_sinusoid_at_nyquist_says_what_its_samples_hold(phase_rad, peak):
    """Attack pass 36: a sinusoid at exactly f_s / 2 (1 deg/s at 50 Hz, 100 Hz) samples A sin(phase) (-1)^n:
    at the default phase 0 every sample was 0, the effect gone without a word (only above it warned)."""
    effect = {"effect": "sinusoid", "frequency_hz": 50.0, "amplitude_dps": 0.1, "phase_rad": phase_rad}
    _, warnings = validate_model(model([effect], axes="x", fs=100.0))
    assert warnings == ["model: axes.x.effects[0] (sinusoid): frequency_hz 50 Hz is the Nyquist frequency: its samples "
                        f"are amplitude_dps sin(phase_rad) (-1)^n, {peak} deg/s peak, not 0.1"]


@pytest.mark.parametrize("effect, words", [({"effect": "colored_noise", "lag1": 0.6}, "lag1 and lag2 are autocorrelations"),
                                           ({"effect": "arma", "sigma_a_dps": 0.1, "phi": [0.9]}, "phi and theta are coefficients")])
def test_a_per_sample_effect_at_another_rate_than_the_models_is_said(effect, words):
    """Attack pass 37a: `simulate --sample-rate-hz 1000` of a model stated at 100 Hz (simulate.md's example runs a gap
    report's extended model so) applied a colored noise's lag1 0.9 (or an arma's phi) per sample of the new rate: its
    correlation time 10 times shorter than the model's (lag 10 at 1000 Hz 0.34, not 0.9), without a word."""
    m = model([effect], axes="x", fs=100.0, arw=0.01)
    assert validate_model(m)[1] == [] and validate_model(m, sample_rate_hz=100.0)[1] == []
    _, warnings = validate_model(m, sample_rate_hz=1000.0)
    assert warnings == [f"model: axes.x.effects[0] ({effect['effect']}): {words} per sample, stated at the model's "
                        "sample_rate_hz 100 Hz: at 1000 Hz they describe a time scale 0.1 times the model's"]


@pytest.mark.parametrize("duration", [0.0, -1.0, float("nan"), 1e308, 1e10])
def test_bad_duration(duration):
    with pytest.raises(SettingsError, match="duration"):
        simulate(model(), duration, seed=0)


def test_a_duration_beyond_the_bound_is_refused_not_an_overflow():
    """Issue 22 (15): 1e308 s made round(duration * rate) an OverflowError; durations are at most 1e9 s."""
    from gyrofilter.sim.simulate import sample_count
    from gyrofilter.sources.simulated import SimulatedSource

    with pytest.raises(SettingsError, match=r"duration_s must be in \(0, 1e\+09\], got 1e\+308"):
        sample_count(1e308, 100.0)
    assert sample_count(1e9, 100.0) == 10**11  # a stream's count (simulate_chunks); a whole run is held to MAX_SAMPLES
    with pytest.raises(SettingsError, match=r"must be in \(0, 1e\+09\]"):
        SimulatedSource(None, seed=1, realtime=False, duration_s=1e308)


@pytest.mark.parametrize("effect, message", [
    # each made inf or nan in the recording, a ZeroDivisionError or an OverflowError before issue 22 (9)
    ({"effect": "sinusoid", "frequency_hz": 1, "amplitude_dps": 1e308}, r"\(sinusoid\).amplitude_dps: expected a number <= 100000, got 1e\+308"),
    ({"effect": "warmup", "amplitude_dps": -1e307, "tau_s": 1}, r"\(warmup\).amplitude_dps: expected a number >= -100000"),
    ({"effect": "outliers", "rate": 1, "magnitude_dps": 1, "spread_ln": 1000}, r"\(outliers\).spread_ln: expected a number <= 5"),
    ({"effect": "gauss_markov", "sigma_dps": 1, "tau_s": 5e-324}, r"\(gauss_markov\).tau_s: expected a number >= 1e-06 s"),
    ({"effect": "narrowband", "center_hz": 10, "bandwidth_hz": 1e-300, "rms_dps": 1},
     r"\(narrowband\).bandwidth_hz: expected a width in \[1e-07, 100\] Hz"),
    ({"effect": "bias_instability", "b_dps": 0.01, "per_decade": 1e-5}, r"\(bias_instability\).per_decade: expected a number >= 0.1"),
    ({"effect": "bias_instability", "b_dps": 0.01, "tau_max_s": 1e300}, r"\(bias_instability\).tau_max_s: expected a number <= 1e\+09 s"),
    ({"effect": "bias_step", "time_s": 10**400, "size_dps": 1}, r"\(bias_step\).time_s: expected a number >= 0, got 1000000000.*\(401 characters\)"),
    ({"effect": "temperature", "coefficient_dps_per_c": 1.0, "reference_c": -300}, r"\(temperature\).reference_c: expected a number >= -100 deg C"),
    ({"effect": "sinusoid", "frequency_hz": 1e6, "amplitude_dps": 1}, r"\(sinusoid\).frequency_hz: expected a number <= 100000 Hz"),
])
def test_model_numbers_are_bounded_so_no_signal_is_infinite(effect, message):
    m = model([effect], axes="x", temperature={"start_c": 25.0})
    with pytest.raises(SettingsError, match=message) as info:
        validate_model(m)
    assert str(info.value).startswith("model: axes.x.effects[0] (") and len(str(info.value)) < 300


@pytest.mark.parametrize("mutate, message", [
    # issue 22 (19): 3000 AR coefficients took over a minute for 2 s; a million flicker components 24 GB
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "arma", "sigma_a_dps": 0.1, "phi": [0.0] * 3000}),
     r"^model: axes.x.effects\[0\] \(arma\).phi: at most 20 coefficients, got 3000$"),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "arma", "sigma_a_dps": 0.1, "theta": [0.1] * 21}),
     r"\(arma\).theta: at most 20 coefficients, got 21$"),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "bias_instability", "b_dps": 0.01, "per_decade": 1e9}),
     r"\(bias_instability\).per_decade: expected a number <= 10, got 1e\+09"),
    (lambda m: m["axes"]["y"]["effects"].extend([{"effect": "rate_ramp", "r_dps_per_s": 0.0}] * 101),
     r"^model: axes.y.effects: at most 100 effects, got 101$"),
    (lambda m: m.update(temperature={"t_s": list(range(100_001)), "temp_c": [25.0] * 100_001}),
     r"^model: temperature.t_s: at most 100000 points, got 100001$"),
    (lambda m: m.update(lsb_per_dps=1e-9), r"^model: lsb_per_dps: expected a number >= 0.1, got 1e-09$"),
    # null where the default is a number was taken as None and crashed the simulation (found by tests/test_fuzz_model.py)
    (lambda m: m.update(temperature={"start_c": None, "end_c": 30.0}), r"^model: temperature.start_c: missing"),
    (lambda m: m.update(temperature={"start_c": 25.0, "tau_s": None}), r"^model: temperature.tau_s: expected a number > 0, got null$"),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "bias_instability", "b_dps": 0.01, "per_decade": None}),
     r"\(bias_instability\).per_decade: expected a number in \[0.1, 10\], got null$"),
    # issue 37: the range a key actually takes, not its kind's ([0, 1] for a fraction of at most 0.5)
    (lambda m: m.update(repeated_samples={"fraction": -0.1}), r"^model: repeated_samples.fraction: expected a number in \[0, 0.5\], got -0.1$"),
    (lambda m: m["axes"]["x"]["effects"].append({"effect": "heavy_tails", "fraction": 2.0, "scale_ratio": 3.0}),
     r"\(heavy_tails\).fraction: expected a number in \[0, 0.5\], got 2.0$"),
])
def test_model_sizes_are_bounded_naming_the_key(mutate, message):
    m = model(axes="xyz")
    mutate(m)
    with pytest.raises(SettingsError, match=message):
        validate_model(m)


def test_the_largest_allowed_models_simulate_finite():
    """At the bounds (the largest rates, 100 effects, 20 stationary AR coefficients, the widest
    flicker bank) the signal stays finite, and quickly: nothing absurd passes validate_model."""
    big = [{"effect": "sinusoid", "frequency_hz": 1, "amplitude_dps": 1e5}] * 50 + [
        {"effect": "rate_ramp", "r_dps_per_s": 1e5}, {"effect": "warmup", "amplitude_dps": -1e5, "tau_s": 1e-6},
        {"effect": "arma", "sigma_a_dps": 1e5, "phi": [0.0] * 19 + [0.9], "theta": [1e6] * 20},
        {"effect": "bias_instability", "b_dps": 1e5, "tau_min_s": 1e-6, "tau_max_s": 1e9, "per_decade": 10},
        {"effect": "outliers", "rate": 1, "magnitude_dps": 1e5, "spread_ln": 5},
        {"effect": "narrowband", "center_hz": 49.9, "bandwidth_hz": 2e-7, "rms_dps": 1e5}]
    rec = simulate(model(big, arw=1e5, bias=1e5, axes="x"), 2.0, seed=3)
    assert np.isfinite(rec.gyro).all() and np.abs(rec.gyro).max() > 1e5


def test_a_non_finite_rate_is_refused_as_the_last_guard(monkeypatch):
    """Should a term ever give inf or nan, the simulator raises instead of writing it (issue 22, 9)."""
    monkeypatch.setattr(nt.RateRamp, "next", lambda self, t_s, temp_c: np.where(t_s > 0.5, np.inf, 0.0))
    with pytest.raises(SettingsError, match=r"^simulate: the model gives a non-finite rate at t = 0.51 s$"):
        simulate(model([{"effect": "rate_ramp", "r_dps_per_s": 1.0}], axes="x"), 2.0, seed=0)


# ---------------------------------------------------------------------------------------------
# baseline terms


def test_constant_bias_and_white_noise_level():
    n_arw, fs = 0.01, 100.0
    rec = simulate(model(bias=1.5, arw=n_arw, fs=fs), 1000.0, seed=7)  # 100000 samples per axis
    g = rec.gyro_dps
    sigma = n_arw * math.sqrt(fs)  # per-sample std = N sqrt(fs) = 0.1 deg/s
    assert np.allclose(g.mean(axis=0), 1.5, atol=5 * sigma / math.sqrt(len(g)))
    assert np.allclose(g.std(axis=0), sigma, rtol=0.01)  # se of std: 0.22 %
    for i in range(3):
        tau, ad = overlapping_adev(g[:, i], fs, taus_s=[0.1, 1.0, 10.0])
        assert np.allclose(ad * np.sqrt(tau), n_arw, rtol=0.08)  # sigma(tau) = N / sqrt(tau)
    lag1 = [np.corrcoef(g[:-1, i], g[1:, i])[0, 1] for i in range(3)]
    assert np.all(np.abs(lag1) < 0.015)


def test_quantization_rounds_to_integer_lsb():
    # noise-free ramp through many LSB: the output is exactly round(rate * lsb_per_dps)
    m = model([{"effect": "rate_ramp", "r_dps_per_s": 0.013}], bias=-0.4, unit="lsb", lsb_per_dps=131.0)
    rec = simulate(m, 100.0, seed=0)
    expected = np.round((-0.4 + 0.013 * rec.t_s) * 131.0)
    assert np.array_equal(rec.gyro[:, 0], expected)
    assert np.all(rec.gyro == np.round(rec.gyro))
    # in deg/s with lsb_per_dps: the same steps, written in deg/s
    m2 = dict(m, gyro_unit="dps")
    assert np.allclose(simulate(m2, 100.0, seed=0).gyro[:, 0], expected / 131.0, atol=1e-12)


def test_quantization_noise_of_a_noisy_signal():
    # with noise much larger than one LSB, rounding adds variance LSB^2/12 (Widrow)
    m = model(arw=0.05, unit="lsb", lsb_per_dps=2.0)  # sigma 0.5 deg/s = 1 LSB
    g = simulate(m, 1000.0, seed=3).gyro_dps
    expected = math.sqrt(0.5**2 + (0.5**2) / 12)
    assert np.allclose(g.std(axis=0), expected, rtol=0.01)


def test_saturation_clips_at_full_scale():
    m = model([{"effect": "sinusoid", "frequency_hz": 0.5, "amplitude_dps": 400.0}], unit="lsb", lsb_per_dps=131.0,
              full_scale_dps=250.0)
    rec = simulate(m, 4.0, seed=0)
    g = rec.gyro[:, 0]
    assert g.max() == 32750 and g.min() == -32750
    raw = 400.0 * np.sin(2 * math.pi * 0.5 * rec.t_s)
    inside = np.abs(raw) < 249.0
    assert np.array_equal(g[inside], np.round(raw[inside] * 131.0))
    assert np.all(g[raw > 250.0] == 32750)


def test_rad_per_s_output():
    m = model(bias=10.0, unit="rad/s")
    rec = simulate(m, 1.0, seed=0)
    assert np.allclose(rec.gyro, 10.0 / DEG_PER_RAD) and np.allclose(rec.gyro_dps, 10.0)


# ---------------------------------------------------------------------------------------------
# deterministic effects: exact closed forms


def test_deterministic_effects_match_their_equations():
    effects = [
        {"effect": "rate_ramp", "r_dps_per_s": -0.002},
        {"effect": "sinusoid", "frequency_hz": 2.0, "amplitude_dps": 0.3, "phase_rad": 1.0},
        {"effect": "bias_step", "time_s": 12.34, "size_dps": -0.7},
        {"effect": "warmup", "amplitude_dps": 1.1, "tau_s": 8.0},
    ]
    for eff in effects:
        rec = simulate(model([eff], bias=0.25, axes="z"), 40.0, seed=0)
        t = rec.t_s
        expected = {
            "rate_ramp": -0.002 * t,
            "sinusoid": 0.3 * np.sin(2 * math.pi * 2.0 * t + 1.0),
            "bias_step": np.where(t >= 12.34, -0.7, 0.0),
            "warmup": 1.1 * np.exp(-t / 8.0),
        }[eff["effect"]]
        assert np.allclose(rec.gyro_dps[:, 2], 0.25 + expected, atol=1e-12), eff["effect"]
        assert np.all(rec.gyro_dps[:, :2] == 0.0)


def test_rate_ramp_allan_slope():
    # sigma(tau) = R tau / sqrt(2) (IEEE 952 C.6) for a pure ramp
    rec = simulate(model([{"effect": "rate_ramp", "r_dps_per_s": 0.001}], axes="x"), 1000.0, seed=0)
    tau, ad = overlapping_adev(rec.gyro_dps[:, 0], 100.0, taus_s=[1.0, 10.0, 100.0])
    assert np.allclose(ad, 0.001 * tau / math.sqrt(2), rtol=1e-6)


# ---------------------------------------------------------------------------------------------
# stochastic effects


def test_bias_instability_simulated_allan_floor():
    # three independent realisations (axes) of pure flicker: the mean Allan deviation is flat at
    # 0.664 B within 10 % from tau = 1 s to 100 s (2 decades); a single Gauss-Markov is not flat
    fs, duration, b = 10.0, 20000.0, 0.01
    rec = simulate(model([{"effect": "bias_instability", "b_dps": b}], fs=fs), duration, seed=21)
    taus = np.logspace(0, 2, 9)
    curves = [overlapping_adev(rec.gyro_dps[:, i], fs, taus_s=taus)[1] for i in range(3)]
    mean = np.mean(curves, axis=0)
    assert np.all(np.abs(mean / (0.664 * b) - 1) < 0.10), mean / (0.664 * b)
    slope = np.polyfit(np.log10(taus), np.log10(mean), 1)[0]
    assert abs(slope) < 0.05


def test_gauss_markov_stationary_std_and_correlation_time():
    sigma, tau, fs = 0.5, 2.0, 50.0
    rec = simulate(model([{"effect": "gauss_markov", "sigma_dps": sigma, "tau_s": tau}], fs=fs), 4000.0, seed=5)
    g = rec.gyro_dps
    assert np.allclose(g.std(axis=0), sigma, rtol=0.06)  # se ~ sqrt(tau / T) = 2 %
    lag = int(tau * fs)
    rho = np.mean([np.corrcoef(g[:-lag, i], g[lag:, i])[0, 1] for i in range(3)])
    assert abs(rho - math.exp(-1)) < 0.03
    rho1 = np.mean([np.corrcoef(g[:-1, i], g[1:, i])[0, 1] for i in range(3)])
    assert abs(rho1 - math.exp(-1 / (fs * tau))) < 0.002
    # the Allan deviation follows the exact AR(1) oracle
    taus_s, ad = overlapping_adev(g[:, 0], fs, taus_s=[0.2, 2.0, 20.0])
    oracle = np.sqrt(nt.ar1_allan_variance(math.exp(-1 / (fs * tau)), sigma**2, np.round(taus_s * fs)))
    assert np.allclose(ad, oracle, rtol=0.12)


def test_rate_random_walk_reads_k_at_3_s_with_half_slope():
    k, fs = 0.01, 10.0
    rec = simulate(model([{"effect": "rate_random_walk", "k_dps_per_sqrt_s": k}], fs=fs), 6000.0, seed=9)
    taus = np.array([3.0, 30.0])
    curves = np.array([overlapping_adev(rec.gyro_dps[:, i], fs, taus_s=taus)[1] for i in range(3)])
    at3 = curves[:, 0].mean()
    assert abs(at3 / k - 1) < 0.08
    slope = np.log10(curves[:, 1] / curves[:, 0]).mean()
    assert abs(slope - 0.5) < 0.08
    # starts at the bias: x[-1] = 0
    assert np.all(np.abs(rec.gyro_dps[0]) < 5 * k / math.sqrt(fs))


def test_outliers_rate_magnitude_and_sign():
    rate, mag = 0.01, 2.0
    rec = simulate(model([{"effect": "outliers", "rate": rate, "magnitude_dps": mag}], fs=100.0), 1000.0, seed=13)
    g = rec.gyro_dps
    spikes = g[g != 0.0]
    n = g.size  # 300000 samples
    assert abs(spikes.size - rate * n) < 4 * math.sqrt(rate * n)
    assert abs(np.median(np.abs(spikes)) / mag - 1) < 0.03
    assert abs(np.mean(spikes > 0) - 0.5) < 0.04
    # |spike| is log-normal with log-spread 0.25 (default spread_ln)
    assert abs(np.log(np.abs(spikes)).std() / 0.25 - 1) < 0.06


def test_heavy_tails_keep_the_variance_and_have_the_mixture_s_tails():
    """A Gaussian scale mixture of the white noise's variance: per-sample sd and the Allan
    deviation stay N sqrt(f_s) and N / sqrt(tau); the kurtosis and the fraction beyond 6 core sd
    are the mixture's (noise_terms.ScaleMixtureNormal); the normals are the baseline's own
    (common random numbers: the same sign at every sample)."""
    n_arw, fs, p, c = 0.01, 100.0, 0.06, 30.0
    tails = [{"effect": "heavy_tails", "fraction": p, "scale_ratio": c}]
    g = simulate(model(tails, arw=n_arw, fs=fs), 2000.0, seed=21).gyro_dps
    plain = simulate(model([], arw=n_arw, fs=fs), 2000.0, seed=21).gyro_dps
    assert np.array_equal(np.sign(g), np.sign(plain))
    assert np.allclose(g.std(axis=0), n_arw * math.sqrt(fs), rtol=0.03)  # 200 000 samples, kurtosis 48: se 1.1 %
    ad = np.array([overlapping_adev(g[:, i], fs, taus_s=[0.01, 1.0])[1] for i in range(3)]).mean(axis=0)
    assert np.allclose(ad * np.sqrt([0.01, 1.0]), n_arw, rtol=0.03)
    k0 = 1 / math.sqrt(1 - p + p * c * c)
    kurt = np.mean([np.mean(g[:, i] ** 4) / np.mean(g[:, i] ** 2) ** 2 for i in range(3)])
    assert abs(kurt / (3 * (1 - p + p * c**4) / (1 - p + p * c * c) ** 2) - 1) < 0.15
    beyond = np.mean(np.abs(g) > 6 * k0 * n_arw * math.sqrt(fs))
    assert abs(beyond / (2 * p * NormalDist().cdf(-6 / c)) - 1) < 0.05  # about 30 000 samples


def test_colored_noise_lag1_and_meaning_of_arw():
    n_arw, fs, rho = 0.01, 100.0, 0.6
    eff = [{"effect": "colored_noise", "lag1": rho}]
    g = simulate(model(eff, arw=n_arw, fs=fs), 2000.0, seed=17).gyro_dps
    lag1 = np.mean([np.corrcoef(g[:-1, i], g[1:, i])[0, 1] for i in range(3)])
    assert abs(lag1 - rho) < 0.01
    # preserve="arw": long-tau Allan deviation is N / sqrt(tau); per-sample std shrinks
    assert np.allclose(g.std(axis=0), n_arw * math.sqrt(fs) * math.sqrt((1 - rho) / (1 + rho)), rtol=0.02)
    ad = np.mean([overlapping_adev(g[:, i], fs, taus_s=[10.0])[1][0] for i in range(3)])
    assert abs(ad * math.sqrt(10.0) / n_arw - 1) < 0.08
    # preserve="std": per-sample std N sqrt(fs) is kept instead
    eff_std = [{"effect": "colored_noise", "lag1": rho, "preserve": "std"}]
    g2 = simulate(model(eff_std, arw=n_arw, fs=fs), 500.0, seed=17).gyro_dps
    assert np.allclose(g2.std(axis=0), n_arw * math.sqrt(fs), rtol=0.03)



@pytest.mark.parametrize("lag1, lag2", [(0.2, 0.0), (0.45, 0.05), (-0.3, 0.05), (0.5, 0.4)])
def test_colored_noise_with_lag2_is_the_first_order_arma_of_both_autocorrelations(lag1, lag2):
    from gyrofilter.sim.noise_terms import arma11_from_lags

    n_arw, fs = 0.01, 100.0
    phi, _ = arma11_from_lags(lag1, lag2)
    eff = [{"effect": "colored_noise", "lag1": lag1, "lag2": lag2}]
    m = model(eff, arw=n_arw, fs=fs)
    g = simulate(m, 3000.0, seed=5).gyro_dps
    x = g - g.mean(axis=0)
    acf = [np.mean(np.sum(x[k:] * x[:-k], axis=0) / np.sum(x * x, axis=0)) for k in (1, 2, 3)]
    assert acf[0] == pytest.approx(lag1, abs=0.01)
    assert acf[1] == pytest.approx(lag2, abs=0.01)
    assert acf[2] == pytest.approx(phi * lag2, abs=0.01)  # rho_3 = phi rho_2: first order beyond lag 1
    # preserve="arw": long-tau Allan deviation N / sqrt(tau)
    ad = np.mean([overlapping_adev(g[:, i], fs, taus_s=[10.0])[1][0] for i in range(3)])
    assert abs(ad * math.sqrt(10.0) / n_arw - 1) < 0.08
    # preserve="std": the per-sample std N sqrt(f_s)
    g2 = simulate(model([dict(eff[0], preserve="std")], arw=n_arw, fs=fs), 500.0, seed=5).gyro_dps
    assert np.allclose(g2.std(axis=0), n_arw * math.sqrt(fs), rtol=0.03)
    # streamed in blocks of 7 samples: the same run bit for bit
    parts = list(simulate_chunks(m, 20.0, seed=5, chunk_samples=7))
    one = simulate(m, 20.0, seed=5, chunk_samples=10**7)
    assert np.array_equal(np.concatenate([p[1] for p in parts]), one.gyro_dps)



@pytest.mark.parametrize("lag1, ratio", [(0.196, 1.42), (0.196, 1.30), (0.3, 3.0), (-0.2, 0.5)])
def test_first_order_arma_with_a_given_lag1_and_long_run_ratio(lag1, ratio):
    from gyrofilter.sim import noise_terms as nt

    phi, mu = nt.arma11_for_lag1_and_ratio(lag1, ratio)
    assert nt.arma11_lags(phi, mu)[0] == pytest.approx(lag1, abs=1e-9)
    assert nt.arma11_long_run_ratio(phi, mu) == pytest.approx(ratio, rel=1e-9)
    assert abs(phi) < 1 and abs(mu) < 1
    # the ratio against a direct sum of the autocorrelations, 1 + 2 sum_k rho_k (rho_k = phi^(k-1) rho_1)
    assert 1 + 2 * lag1 / (1 - phi) == pytest.approx(ratio, rel=1e-9)


# ---------------------------------------------------------------------------------------------
# temperature


def test_temperature_profile_column_noise_and_resolution():
    spec = {"start_c": 20.0, "end_c": 30.0, "tau_s": 100.0, "noise_c": 0.05, "resolution_c": 1 / 340}
    rec = simulate(model(temperature=spec, fs=10.0), 1000.0, seed=3)
    temp = rec.temp_c
    assert np.allclose(temp * 340, np.round(temp * 340), atol=1e-6)  # MPU6050 steps of 1/340 C
    true = 30.0 - 10.0 * np.exp(-rec.t_s / 100.0)
    resid = temp - true
    assert abs(resid.mean()) < 0.003
    assert abs(resid.std() / math.sqrt(0.05**2 + (1 / 340) ** 2 / 12) - 1) < 0.03


def test_temperature_table_profile_and_cycle():
    table = {"t_s": [0.0, 10.0, 20.0], "temp_c": [25.0, 35.0, 30.0]}
    rec = simulate(model(temperature=table), 30.0, seed=0)
    assert np.allclose(rec.temp_c, np.interp(rec.t_s, table["t_s"], table["temp_c"]))
    cyc = {"start_c": 25.0, "cycle_amplitude_c": 2.0, "cycle_period_s": 10.0}
    rec = simulate(model(temperature=cyc), 30.0, seed=0)
    assert np.allclose(rec.temp_c, 25.0 + 2.0 * np.sin(2 * math.pi * rec.t_s / 10.0))


def test_temperature_coefficient_drives_the_bias():
    spec = {"start_c": 20.0, "end_c": 30.0, "tau_s": 100.0, "noise_c": 0.05, "resolution_c": 1 / 340}
    c = 0.03
    eff = [{"effect": "temperature", "coefficient_dps_per_c": c}]
    rec = simulate(model(eff, bias=1.0, temperature=spec, fs=10.0), 600.0, seed=3)
    true = 30.0 - 10.0 * np.exp(-rec.t_s / 100.0)
    assert np.allclose(rec.gyro_dps[:, 0], 1.0 + c * (true - 20.0), atol=1e-12)  # reference = start temperature
    slope = np.polyfit(rec.temp_c, rec.gyro_dps[:, 0], 1)[0]
    assert abs(slope / c - 1) < 0.01
    eff_ref = [{"effect": "temperature", "coefficient_dps_per_c": c, "reference_c": 0.0}]
    rec0 = simulate(model(eff_ref, temperature=spec, fs=10.0), 10.0, seed=3)
    assert np.allclose(rec0.gyro_dps[0, 0], c * 20.0)


def test_without_temperature_profile_there_is_no_temp_column():
    assert simulate(model(arw=0.01), 1.0, seed=0).temp_c is None
    assert list(next(simulate_chunks(model(), 1.0, seed=0))[2:]) == [None, None]


def test_numpy_scalars_are_accepted_as_parameters():
    m = model([{"effect": "gauss_markov", "sigma_dps": np.float32(0.1), "tau_s": np.int64(2)}], bias=np.float64(0.5))
    m["sample_rate_hz"] = np.int64(50)
    spec, _ = validate_model(m)
    assert spec["sample_rate_hz"] == 50.0 and spec["axes"]["x"]["effects"][0]["tau_s"] == 2.0
    with pytest.raises(SettingsError, match=r"sigma_dps: expected a number >= 0, got array"):
        validate_model(model([{"effect": "gauss_markov", "sigma_dps": np.array([1.0]), "tau_s": 1}]))


@pytest.mark.parametrize("duration_s, sample_rate_hz", [(1e9, 1000.0), (1e6 + 0.5, 1000.0), (2e4, 1e5)])
def test_a_run_held_whole_beyond_the_sample_limit_is_refused_before_any_allocation(duration_s, sample_rate_hz):
    """Issue 37 (leftover): ``simulate(model, 1e9)`` at 1 kHz tried to hold 1e12 samples (32 TB:
    MemoryError or the OOM killer). The API and ``gyrofilter simulate`` share one limit,
    MAX_SAMPLES (1e9, about 32 GB in memory), refused as a ValueError naming the parameter and it."""
    from gyrofilter.sim.simulate import MAX_SAMPLES, sample_count

    n_total = sample_count(duration_s, sample_rate_hz)
    assert n_total > MAX_SAMPLES == 10**9
    expected = f"duration_s: {duration_s:g} s at {sample_rate_hz:g} Hz is {n_total:.3g} samples; a simulated recording holds at most 1e+09"
    with pytest.raises(ValueError, match=re.escape(expected)):
        simulate(model(fs=sample_rate_hz), duration_s, seed=1)


def test_a_run_held_whole_equals_its_blocks():
    """simulate() fills its arrays block by block: the same numbers as the blocks of
    simulate_chunks, with and without a temperature column, whatever the block size."""
    m = full_model()
    rec = simulate(m, 3.0, seed=4, chunk_samples=7)
    parts = list(simulate_chunks(m, 3.0, seed=4, chunk_samples=64))
    assert rec.temp_c is not None and len(rec) == 300
    assert np.array_equal(rec.t_s, np.concatenate([p[0] for p in parts]))
    assert np.array_equal(rec.gyro, np.concatenate([p[1] for p in parts]))
    assert np.array_equal(rec.temp_c, np.concatenate([p[2] for p in parts]))


@pytest.mark.parametrize("axis, chunk_samples", [(1.7, 100), (True, 100), ("x", 100), (3, 100), (-1, 100), (0, 0.5), (0, "8")])
def test_simulate_axis_dps_refuses_an_axis_or_chunk_that_is_not_one(axis, chunk_samples):
    """Attack pass 23: axis 1.7 (or True) simulated y, "x" ended in int()'s ValueError, 3 in an
    IndexError and -1 in numpy's "expected non-negative integer"; a chunk_samples of 0.5 was
    refused as "got 0" and "8" was taken as 8."""
    model = {"sample_rate_hz": 100.0, "axes": {"x": {"arw_dps_per_sqrt_hz": 0.01}}}
    with pytest.raises(SettingsError, match=r"simulate: (axis \(0, 1 or 2: x, y, z\)|chunk_samples) must be"):
        next(simulate_axis_dps(model, 1.0, axis, seed=1, chunk_samples=chunk_samples))
