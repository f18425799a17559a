"""The board's resonance (issue 36): the ``resonance`` hump and the ``ringing`` of shocks, their
simulator terms (gyrofilter.sim.resonance) and detectors (gap.detectors.resonance, .ringing):
a hump named with its centre inside its interval and D after <= 2, shocks that ring named as one
cause (no outliers or heavy tails beside them), a narrow line still a narrow band, clean records
naming neither. Extra seeds are ``slow``."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.signal import freqz, lfilter

import gyrofilter.sim.hidden_effects as he
from gyrofilter.analysis.gap.detectors import (RESONANCE_THRESHOLD, RINGING_THRESHOLD, detect_narrowband,
                                               detect_resonance, detect_ringing, resonance_fit, ring_fit)
from gyrofilter.analysis.gap.pipeline import analyse_gap
from gyrofilter.sim.model import validate_model
from gyrofilter.sim.noise_terms import filter_variance
from gyrofilter.sim.resonance import band_pass, band_pass_energy, resonance_filter, ringing_variance
from gyrofilter.sim.simulate import simulate

SIMS = 10


def _axis_only(effect, sample_rate_hz=100.0):
    return {"sample_rate_hz": sample_rate_hz, "gyro_unit": "dps",
            "axes": {a: {"bias_dps": 0.0, "arw_dps_per_sqrt_hz": 0.0, "effects": [effect] if a == "x" else []}
                     for a in "xyz"}}


def test_resonator_peaks_at_its_centre_with_width_centre_over_q():
    # oracle: scipy's frequency response of the filter; the half-power points of the analog
    # band pass, Omega_2 - Omega_1 = Omega_0 / Q, warped by the bilinear transform (Omega = tan(pi f / f_s))
    fs, f0, q = 100.0, 12.0, 4.0
    b, a = band_pass(f0, q, fs)
    f, h = freqz(b, a, worN=200_001, fs=fs)
    power = np.abs(h) ** 2
    assert f[np.argmax(power)] == pytest.approx(f0, abs=1e-3)
    assert power.max() == pytest.approx(1.0, rel=1e-6)
    above = f[power >= 0.5]
    warped = np.tan(np.pi * np.array([above.min(), above.max(), f0]) / fs)
    assert warped[1] - warped[0] == pytest.approx(warped[2] / q, rel=1e-3)
    assert warped[1] * warped[0] == pytest.approx(warped[2] ** 2, rel=1e-3)  # geometric centre
    assert above.max() - above.min() == pytest.approx(f0 / q, rel=0.1)
    assert power[0] < 1e-12 and power[-1] < 1e-12  # zeros at 0 Hz and f_s / 2


@pytest.mark.parametrize("seed", [1, 2])
def test_the_resonators_energy_in_closed_form_is_the_lyapunov_one(seed):
    """Σ h² = α / (1 + α) (band_pass_energy) against the state-space Lyapunov solution, over
    centres from 0.1 % to 99 % of Nyquist and Q from 0.5 to 30."""
    rng = np.random.default_rng(seed)
    for _ in range(50):
        fs = float(rng.uniform(10, 2000))
        f0, q = float(rng.uniform(0.001, 0.99)) * fs / 2, float(math.exp(rng.uniform(math.log(0.5), math.log(30))))
        assert band_pass_energy(f0, q, fs) == pytest.approx(filter_variance(*band_pass(f0, q, fs)), rel=1e-7)


@pytest.mark.parametrize("seed", [1, 2])
def test_simulated_resonance_and_ringing_have_their_variance(seed):
    fs = 100.0
    hump = {"effect": "resonance", "center_hz": 10.0, "q": 2.0, "rms_dps": 0.05}
    x = simulate(_axis_only(hump), 1200.0, seed=seed).gyro_dps[:, 0]
    assert x.std() == pytest.approx(0.05, rel=0.05)
    b, a = resonance_filter(0.05, 10.0, 2.0, fs)
    assert filter_variance(b, a) == pytest.approx(0.05 ** 2, rel=1e-9)
    ring = {"effect": "ringing", "center_hz": 10.0, "q": 3.0, "shock_rate_hz": 0.5, "shock_dps": 1.0}
    y = simulate(_axis_only(ring), 3600.0, seed=seed).gyro_dps[:, 0]
    assert y.var() == pytest.approx(ringing_variance(0.5, 1.0, 10.0, 3.0, fs), rel=0.15)
    # a ring peaks at the shock's size: the largest |y| is about the largest of 1800 shocks, log-normal
    # about 1 (sd 0.25 in ln: beyond 4, 5.5 sd, once in 10^4 records; two rings can overlap)
    assert 1.0 < np.abs(y).max() < 4.0


def test_model_checks_the_resonators_centre_and_q():
    from gyrofilter.errors import SettingsError

    with pytest.raises(SettingsError, match="center_hz"):
        validate_model(_axis_only({"effect": "resonance", "center_hz": 50.0, "q": 2.0, "rms_dps": 0.1}))
    with pytest.raises(SettingsError, match="q"):
        validate_model(_axis_only({"effect": "ringing", "center_hz": 5.0, "q": 0.0, "shock_rate_hz": 1.0,
                                   "shock_dps": 1.0}))


@pytest.mark.parametrize("effect", ["resonance", "ringing"])
def test_a_resonator_centred_near_0_hz_is_refused_naming_its_centre(tmp_path, capsys, effect):
    """Issue 37 (attack 4): a resonance at center_hz 1e-300 (100 Hz) failed with "gyrofilter: error:
    A singular matrix detected: slice(s) [0] are singular." (no file, no parameter); at 1e-4 Hz it
    simulated with scipy's LinAlgWarning on stderr (its start's variance from an ill-conditioned
    solve); a ringing at 1e-300 Hz rang without decay. Below 1e-4 times the rate: refused; at it, Q
    1000, no warning."""
    import warnings

    from gyrofilter.cli import main

    params = {"q": 1000.0, "rms_dps": 0.02} if effect == "resonance" else {"q": 1000.0, "shock_rate_hz": 0.1, "shock_dps": 0.5}
    path = tmp_path / "m.json"
    path.write_text(json.dumps(_axis_only({"effect": effect, "center_hz": 1e-300, **params})))
    assert main(["simulate", "--model", str(path), "--duration", "10", "--out", str(tmp_path / "o.csv")]) == 2
    assert capsys.readouterr().err == (f"gyrofilter: error: {path}: model: axes.x.effects[0] ({effect}).center_hz: expected "
                                       "a frequency >= 0.01 Hz (0.0001 times the sample rate), got 1e-300\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        x = simulate(_axis_only({"effect": effect, "center_hz": 0.01, **params}), 60.0, seed=1).gyro_dps
    assert np.isfinite(x).all()


def _hump_case(seed, fraction, duration_s=900.0):
    """A clean MPU6050-like case with a hump at ``fraction`` of the Nyquist frequency, Q 1.5-4, its
    peak 0.5-1.5 times the white level, on a random axis."""
    case = he.draw_case(seed, effect="none", duration_s=duration_s)
    rng = np.random.default_rng(seed + 7)
    axis = "xyz"[rng.integers(3)]
    fs = case["model"]["sample_rate_hz"]
    centre, q = fraction * fs / 2.0, float(rng.uniform(1.5, 4.0))
    sigma = case["model"]["axes"][axis]["arw_dps_per_sqrt_hz"] * math.sqrt(fs)
    rms = math.sqrt(float(rng.uniform(0.5, 1.5)) * filter_variance(*band_pass(centre, q, fs))) * sigma
    params = {"center_hz": centre, "q": q, "rms_dps": rms}
    case["model"]["axes"][axis]["effects"].append(dict(effect="resonance", **params))
    return case, axis, params


def _named(report, effect, axis, true):
    """The finding of ``effect`` on ``axis``, the only finding, its centre's interval holding the
    estimate and of the right scale: the true centre within two half-widths of the estimate. A 95 %
    interval misses one case in twenty (the merged registry redrew cases 110 and the 15-Hz hump:
    4.2133 against an upper end of 4.2112 Hz, 15.0 against 14.94), a miss beyond two half-widths is
    a 4-sd event for a right interval; the coverage over many cases is tools/gap_coverage.py's."""
    got = [(f["effect"], f["axis"], f["params"]) for f in report["findings"]]
    hit = [f for f in report["findings"] if f["effect"] == effect and f["axis"] == axis]
    assert hit, f"{effect} {true} on {axis} not named; got {got}"
    assert [f["effect"] for f in report["findings"]] == [effect], got
    low, high = hit[0]["params_ci95"]["center_hz"]
    est = hit[0]["params"]["center_hz"]
    assert low <= est <= high and abs(true["center_hz"] - est) <= high - low, (hit[0]["params_ci95"], true)
    return hit[0]


def _hump_named(seed, fraction):
    """D after of a hump case whose hump is named with its parameters (centre in its interval)."""
    case, axis, true = _hump_case(seed, fraction)
    report = analyse_gap(he.simulate_case(case), seed=seed, n_sims=SIMS)
    hit = _named(report, "resonance", axis, true)
    assert 1 / 2.0 < hit["params"]["q"] / true["q"] < 2.0, (hit["params"], true)  # a weak hump's width is loose
    assert abs(hit["params"]["rms_dps"] / true["rms_dps"] - 1) < 0.3, (hit["params"], true)
    return report["discrepancy"]["after"][axis]


@pytest.mark.slow  # about a minute: the fast run names humps in test_the_example_hump_read_a_little_narrow_is_still_the_hump
def test_a_hump_is_named_with_its_centre_in_its_interval():
    assert _hump_named(0, 0.2) <= 2.0


@pytest.mark.slow
def test_humps_from_5_to_40_percent_of_nyquist_are_named():
    # D after <= 2 is where clean records stay in 95 % of runs: one case of five may pass it
    # (measured: a weak Q-4 hump at 5 %, D before 4.0, reads 2.35 after), none by far
    after = [_hump_named(seed, fraction) for seed, fraction in ((1, 0.05), (2, 0.4), (3, 0.1), (4, 0.3), (5, 0.05))]
    assert sum(d > 2.0 for d in after) <= 1 and max(after) < 3.0, after


def _ringing_case(seed, duration_s=600.0):
    case = he.draw_case(seed, effect="ringing", duration_s=duration_s)
    return case, case["axis"], case["params"]


@pytest.mark.parametrize("seed", [103, pytest.param(104, marks=pytest.mark.slow),
                                  pytest.param(110, marks=pytest.mark.slow)])
def test_shocks_that_ring_are_one_cause(seed):
    case, axis, true = _ringing_case(seed)
    report = analyse_gap(he.simulate_case(case), seed=seed, n_sims=SIMS)
    # one cause: neither the spikes nor the hump are named beside the rings
    hit = _named(report, "ringing", axis, true)
    assert report["discrepancy"]["after"][axis] <= 2.0, report["discrepancy"]
    assert 1 / 1.6 < hit["params"]["shock_rate_hz"] / true["shock_rate_hz"] < 1.6, (hit["params"], true)
    assert abs(hit["params"]["shock_dps"] / true["shock_dps"] - 1) < 0.35, (hit["params"], true)


def _spiky(seed, effect, n=60_000, fs=100.0, hump=False):
    """White noise (sd 1) with iid spikes (``outliers``) or a Gaussian scale mixture
    (``heavy_tails``), and with ``hump`` a Gaussian hump at 10-30 Hz beside them."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=n)
    if effect == "outliers":
        hit = rng.random(n) < 1e-3
        x[hit] += np.where(rng.random(hit.sum()) < 0.5, -1.0, 1.0) * rng.uniform(8.0, 30.0, hit.sum())
    else:
        x *= np.where(rng.random(n) < 0.03, 10.0, 1.0) / math.sqrt(0.97 + 0.03 * 100.0)
    if hump:
        b, a = band_pass(rng.uniform(10.0, 30.0), rng.uniform(1.5, 4.0), fs)
        x += lfilter(b, a, rng.normal(size=n))
    return x


@pytest.mark.parametrize("seed", [0, 1, pytest.param(2, marks=pytest.mark.slow), pytest.param(3, marks=pytest.mark.slow)])
def test_iid_spikes_and_heavy_tails_do_not_ring(seed):
    # an isolated spike projects on a ring by at most 1/<g, g> of its energy: the statistic is
    # negative on iid spikes and heavy tails, also beside a Gaussian hump at which they are fitted
    fs = 100.0
    for effect in ("outliers", "heavy_tails"):
        x = _spiky(seed, effect, hump=True)
        hump = resonance_fit(x, fs)
        rings = ring_fit(x, fs, hump["center_hz"], hump["q"])
        assert rings is None or rings["statistic"] < 0, (effect, rings and rings["statistic"])
        assert detect_ringing(x, fs) is None, effect
    assert RINGING_THRESHOLD > 0


def test_a_narrow_line_stays_a_narrow_band():
    # Q = f0 / B of about 15: a line, not a hump; it is named narrowband and the hump's fit
    # leaves its bins out
    from gyrofilter.sim.noise_terms import narrowband_filter

    rng = np.random.default_rng(5)
    fs, n = 100.0, 180_000
    b, a = narrowband_filter(0.8, 30.0, 2.0, fs)
    x = rng.normal(size=n) + lfilter(b, a, rng.normal(size=n + 2000))[2000:]
    band = detect_narrowband(x, fs)
    assert band is not None
    hump, kept = detect_resonance(x, fs, band)
    assert hump is None and kept is band


@pytest.mark.parametrize("seeds", [range(0, 3), pytest.param(range(3, 25), marks=pytest.mark.slow)])
def test_clean_records_name_no_hump(seeds):
    # white, AR(1) colored and quantized MPU6050-like noise (the hidden-effect baseline):
    # the statistic stays below the threshold on every axis
    for seed in seeds:
        case = he.draw_case(500 + seed, effect="none", duration_s=[600.0, 1800.0][seed % 2])
        rec = he.simulate_case(case)
        for i in range(3):
            x = rec.gyro_dps[:, i]
            hump, _ = detect_resonance(x, rec.sample_rate_hz)
            assert hump is None, (seed, i, hump and hump.params)
        rho = np.random.default_rng(seed).uniform(0.3, 0.8)
        y = lfilter([1.0 - rho], [1.0, -rho], np.random.default_rng(seed + 1).normal(size=120_000))
        fit = resonance_fit(y, 100.0)
        assert fit["statistic"] < RESONANCE_THRESHOLD or not 0.7 <= fit["q"] <= 5.0, (seed, fit)


@pytest.mark.parametrize("seed", [3, 6])
def test_the_example_hump_read_a_little_narrow_is_still_the_hump(seed):
    # a new user's trial of examples/models/resonance.json (12 Hz, Q 4, 1.5 times the level; 10 min):
    # seed 3's hump fit read Q 5.3 and the narrow-band detector found no line: nothing was named
    # (D after 3.0); seed 6's narrow-band detector read a band of Q 6.9 and named a narrowband
    from pathlib import Path

    model = json.loads((Path(__file__).parent.parent / "examples" / "models" / "resonance.json").read_text())
    report = analyse_gap(simulate(model, 600.0, seed=seed), seed=0)
    got = [(f["axis"], f["effect"]) for f in report["findings"]]
    assert got == [("y", "resonance")], report["findings"]
    low, high = report["findings"][0]["params_ci95"]["center_hz"]
    assert low <= 12.0 <= high and report["discrepancy"]["after"]["y"] <= 2.0
