"""The simulator's ``compression`` effect (gyrofilter.sim.compression): the cubic of an axis's fast
terms about its slow level, its gain, chunking and validation."""
import copy

import numpy as np
import pytest

from gyrofilter.errors import SettingsError
from gyrofilter.sim.compression import MAX_COMPRESSION, Compression, compression_gain
from gyrofilter.sim.simulate import simulate, simulate_chunks

RATE_HZ = 100.0
TONE = {"effect": "wandering_tone", "center_hz": 20.0, "spread_hz": 0.5, "wander_s": 5.0, "amplitude_dps": 0.3}


def model(z_effects, bias_z=0.0, lsb_per_dps=None):
    m = {"sample_rate_hz": RATE_HZ,
         "axes": {"x": {"arw_dps_per_sqrt_hz": 0.03, "effects": [{"effect": "bias_instability", "b_dps": 0.01}]},
                  "y": {"arw_dps_per_sqrt_hz": 0.03},
                  "z": {"bias_dps": bias_z, "arw_dps_per_sqrt_hz": 0.03, "effects": list(z_effects)}}}
    if lsb_per_dps is not None:
        m["lsb_per_dps"] = lsb_per_dps
    return m


def compressed(gamma, rms=0.37):
    return {"effect": "compression", "gamma_per_dps2": gamma, "rms_dps": rms}


def test_the_gain_keeps_a_gaussians_variance():
    rng = np.random.default_rng(4)
    e = rng.normal(0.0, 0.5, 2_000_000)
    for gamma in (0.02, 0.06, 0.12):  # kappa 0.005 to 0.03
        y = Compression(gamma, 0.5).apply(e.copy())
        assert y.var() == pytest.approx(e.var(), rel=3e-3)
        kurt = np.mean(y ** 4) / y.var() ** 2 - 3.0
        assert kurt == pytest.approx(-24.0 * gamma * 0.25, rel=0.25)  # excess kurtosis about -24 kappa
    assert compression_gain(0.0, 1.0) == 1.0


def test_the_transfer_is_monotone_beyond_its_turning_point():
    c = Compression(0.1, 1.0)
    e = np.linspace(-10.0, 10.0, 2001)
    y = c.apply(e.copy())
    assert np.all(np.diff(y) >= 0.0)
    assert y[-1] == pytest.approx(c.gain * (2.0 / 3.0) / np.sqrt(0.3))


@pytest.mark.parametrize("chunk", [1, 333, 4096])
def test_a_chunked_run_equals_the_whole_one(chunk):
    m = model([{"effect": "rate_random_walk", "k_dps_per_sqrt_s": 0.001}, TONE, compressed(0.05),
               {"effect": "outliers", "rate": 0.001, "magnitude_dps": 3.0}], bias_z=0.5, lsb_per_dps=20.0)
    duration = 3.0 if chunk == 1 else 300.0
    one = simulate(m, duration, seed=5, chunk_samples=10**7).gyro
    parts = np.concatenate([b.gyro for b in simulate_chunks(m, duration, seed=5, chunk_samples=chunk)])
    assert np.array_equal(parts, one)


def test_without_it_the_run_is_the_same_and_the_other_axes_never_change():
    plain = model([TONE, {"effect": "bias_instability", "b_dps": 0.01}], bias_z=0.5)
    with_it = copy.deepcopy(plain)
    with_it["axes"]["z"]["effects"].append(compressed(0.05))
    a = simulate(plain, 600.0, seed=3).gyro_dps
    b = simulate(with_it, 600.0, seed=3).gyro_dps
    assert np.array_equal(a[:, :2], b[:, :2])
    assert not np.array_equal(a[:, 2], b[:, 2])
    # the fast terms are compressed, their variance kept, their tails lightened; the slow level is not
    fast_a, fast_b = a[:, 2] - a[:, 2].mean(), b[:, 2] - b[:, 2].mean()
    assert fast_b.var() == pytest.approx(fast_a.var(), rel=0.01)
    assert np.mean(fast_b ** 4) / fast_b.var() ** 2 < np.mean(fast_a ** 4) / fast_a.var() ** 2 - 0.1
    assert b[:, 2].mean() == pytest.approx(0.5, abs=0.02)


def test_the_slow_level_is_left_out_of_the_cubic():
    """A bias of 3 deg/s with a compression whose turning point is at 2.6 deg/s: compressed with
    the rate, it would be cut; about the slow level, the mean stays the bias."""
    m = model([TONE, compressed(0.05), {"effect": "rate_ramp", "r_dps_per_s": 1e-3}], bias_z=3.0)
    z = simulate(m, 600.0, seed=2).gyro_dps[:, 2]
    t = np.arange(z.size) / RATE_HZ
    slope, intercept = np.polyfit(t, z, 1)
    assert intercept == pytest.approx(3.0, abs=0.02)
    assert slope == pytest.approx(1e-3, rel=0.05)


@pytest.mark.parametrize("effects, key", [
    ([compressed(MAX_COMPRESSION / 0.37 ** 2 * 1.01)], "gamma_per_dps2"),
    ([compressed(0.05), compressed(0.05)], "effects"),
    ([compressed(-0.01)], "gamma_per_dps2"),
    ([compressed(0.01, rms=0.0)], "rms_dps"),
])
def test_a_model_out_of_bounds_is_refused_naming_the_key(effects, key):
    with pytest.raises(SettingsError, match=key):
        simulate(model(effects), 1.0, seed=1)


@pytest.mark.parametrize("gamma, rms", [(3.0, 0.1), (0.75, 0.2), (30.0, 0.1 ** 0.5 / 10)])
def test_a_compression_at_the_documented_bound_is_taken(gamma, rms):
    """Attack pass 37a: gamma_per_dps2 3 with rms_dps 0.1 (gamma sigma^2 = 0.03, the bound the docs give as "at most
    0.03") was refused as "expected gamma_per_dps2 * rms_dps^2 <= 0.03, got 3 * 0.1^2 = 0.03": 3 * 0.01 is
    0.030000000000000002 in floats."""
    from gyrofilter.sim.model import validate_model

    validate_model({"sample_rate_hz": 100.0, "axes": {"x": {"arw_dps_per_sqrt_hz": 0.01, "effects": [
        {"effect": "compression", "gamma_per_dps2": gamma, "rms_dps": rms}]}}})
    with pytest.raises(SettingsError, match="gamma_per_dps2"):
        validate_model({"sample_rate_hz": 100.0, "axes": {"x": {"effects": [
            {"effect": "compression", "gamma_per_dps2": gamma * (1 + 1e-6), "rms_dps": rms}]}}})
