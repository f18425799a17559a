"""The spectral effects of the simulator (``narrowband``, ``arma``) and several effects on one axis.

Oracles: the filter's closed-form PSD and variance (noise_terms.filter_psd, filter_variance),
the AR(1) Allan variance closed form, and the superposition of independently keyed streams.
All random tests are seeded; tolerances are several standard errors.
"""
import math

import numpy as np
import pytest
from scipy.signal import welch

from gyrofilter.sim import noise_terms as nt
from gyrofilter.analysis.noise.allan import overlapping_adev
from gyrofilter.errors import SettingsError
from gyrofilter.sim.model import validate_model
from gyrofilter.sim.simulate import simulate


def one_axis(effects, fs=200.0, arw=0.0):
    return {"sample_rate_hz": fs, "axes": {"z": {"arw_dps_per_sqrt_hz": arw, "effects": effects}}}


def test_narrowband_filter_has_its_centre_width_and_rms():
    fs, f0, bw, rms = 200.0, 35.0, 2.0, 0.05
    b, a = nt.narrowband_filter(rms, f0, bw, fs)
    assert math.isclose(nt.filter_variance(b, a), rms**2, rel_tol=1e-9)
    f = np.linspace(0.0, fs / 2, 200_001)
    psd = nt.filter_psd(b, a, f, fs)
    assert abs(f[np.argmax(psd)] - f0) < 0.05
    half = f[psd >= psd.max() / 2]
    assert math.isclose(half[-1] - half[0], bw, rel_tol=0.03)
    # the two-sided PSD integrates to the variance over (-fs/2, fs/2)
    assert math.isclose(2 * psd.sum() * (f[1] - f[0]), rms**2, rel_tol=1e-3)


def test_simulated_narrowband_matches_its_psd_and_rms():
    fs, f0, bw, rms = 200.0, 35.0, 2.0, 0.05
    rec = simulate(one_axis([{"effect": "narrowband", "center_hz": f0, "bandwidth_hz": bw, "rms_dps": rms}], fs), 600.0, seed=3)
    z = rec.gyro_dps[:, 2]
    assert abs(z.std() / rms - 1) < 0.05  # ~3800 correlation times: se of the std ~1.2 %
    f, p = welch(z, fs=fs, nperseg=4096, return_onesided=True)
    b, a = nt.narrowband_filter(rms, f0, bw, fs)
    theory = 2 * nt.filter_psd(b, a, f, fs)  # one-sided
    band = (f > 25) & (f < 45)
    ratio = p[band].sum() / theory[band].sum()
    assert abs(ratio - 1) < 0.05
    assert abs(f[np.argmax(p)] - f0) < 0.5


def test_arma_effect_variance_and_autocorrelation_match_theory():
    phi, theta, sigma = [1.2, -0.5], [0.3], 0.1
    b, a = nt.arma_filter(phi, theta, sigma)
    rec = simulate(one_axis([{"effect": "arma", "sigma_a_dps": sigma, "phi": phi, "theta": theta}]), 500.0, seed=8)
    z = rec.gyro_dps[:, 2]
    # theory: impulse response h, autocovariance R(k) = sigma^2-scaled sum h[n] h[n+k]
    from scipy.signal import lfilter
    h = lfilter(b, a, np.r_[1.0, np.zeros(2000)])
    r_theory = np.array([np.einsum("i,i->", h[: len(h) - k], h[k:]) for k in range(4)])
    assert math.isclose(r_theory[0], nt.filter_variance(b, a), rel_tol=1e-9)
    zc = z - z.mean()
    r_sample = np.array([np.einsum("i,i->", zc[: len(zc) - k], zc[k:]) / len(zc) for k in range(4)])
    assert abs(r_sample[0] / r_theory[0] - 1) < 0.05
    assert np.allclose(r_sample[1:] / r_sample[0], r_theory[1:] / r_theory[0], atol=0.03)


def test_filtered_noise_starts_stationary():
    """The first sample of many runs has the stationary variance (no burn-in transient)."""
    b, a = nt.narrowband_filter(1.0, 10.0, 0.5, 100.0)  # slow: a zero start would show for ~60 samples
    rng = np.random.default_rng(1)
    first = np.array([nt.FilteredNoise(b, a, np.random.default_rng(rng.integers(2**32))).next(np.zeros(3), None)[:3]
                      for _ in range(3000)])
    assert np.all(np.abs(first.var(axis=0) - 1.0) < 0.1)  # se of a variance from 3000 draws: 0.026


def test_arma_of_order_1_is_the_gauss_markov_allan_curve():
    fs, phi, sigma_a = 100.0, 0.95, 0.02
    rec = simulate(one_axis([{"effect": "arma", "sigma_a_dps": sigma_a, "phi": [phi]}], fs), 2000.0, seed=5)
    m = np.array([1, 4, 16, 64, 256])
    _, adev = overlapping_adev(rec.gyro_dps[:, 2], fs, m / fs)
    theory = np.sqrt(nt.ar1_allan_variance(phi, sigma_a**2 / (1 - phi**2), m))
    assert np.all(np.abs(adev / theory - 1) < 0.1)


def test_several_effects_on_one_axis_add_up():
    effects = [{"effect": "narrowband", "center_hz": 31.0, "bandwidth_hz": 1.0, "rms_dps": 0.02},
               {"effect": "narrowband", "center_hz": 38.0, "bandwidth_hz": 3.0, "rms_dps": 0.01},
               {"effect": "arma", "sigma_a_dps": 0.005, "phi": [0.9], "theta": [0.2]},
               {"effect": "gauss_markov", "sigma_dps": 0.01, "tau_s": 20.0},
               {"effect": "sinusoid", "frequency_hz": 5.0, "amplitude_dps": 0.03}]
    together = simulate(one_axis(effects, arw=0.004), 60.0, seed=2).gyro_dps[:, 2]
    white = simulate(one_axis([], arw=0.004), 60.0, seed=2).gyro_dps[:, 2]
    parts = []
    for i in range(len(effects)):
        # keep the occurrence index of repeated effects: the streams are keyed by (effect, occurrence)
        alone = [dict(e, rms_dps=0.0) if j < i and e["effect"] == effects[i]["effect"] else e
                 for j, e in enumerate(effects[: i + 1]) if j == i or e["effect"] == effects[i]["effect"]]
        parts.append(simulate(one_axis(alone), 60.0, seed=2).gyro_dps[:, 2])
    assert np.allclose(together, white + np.sum(parts, axis=0), atol=1e-12)
    assert not np.allclose(parts[0], 0) and not np.allclose(parts[1], 0)
    assert abs(np.corrcoef(parts[0], parts[1])[0, 1]) < 0.1  # two lines: independent streams


@pytest.mark.parametrize("effect, message", [
    ({"effect": "narrowband", "center_hz": 60.0, "bandwidth_hz": 1.0, "rms_dps": 0.1}, "below the Nyquist"),
    ({"effect": "narrowband", "center_hz": 10.0, "bandwidth_hz": 0.0, "rms_dps": 0.1}, "bandwidth_hz"),
    ({"effect": "arma", "sigma_a_dps": 0.1, "phi": [1.0]}, "stationary AR part"),
    ({"effect": "arma", "sigma_a_dps": 0.1, "phi": 0.5}, "expected a list"),
    ({"effect": "arma", "sigma_a_dps": 0.1, "theta": [0.1, "x"]}, r"theta\[1\]"),
])
def test_bad_spectral_effects_raise(effect, message):
    with pytest.raises(SettingsError, match=message):
        validate_model(one_axis([effect], fs=100.0))
