"""Tests for gyrofilter.analysis.noise.model and the modules of its fit (noise.fit, noise.intervals, noise.readoff,
noise.screen, noise.export): model identities, NNLS oracle, seeded round trips on
simulated noise with known coefficients, unit conversions, bad input, JSON and Kalibr export."""
import math
import subprocess
import sys

import numpy as np
import pytest

from gyrofilter.effects import BIAS_INSTABILITY, RATE_RAMP, RATE_RANDOM_WALK
from gyrofilter.analysis.noise.allan import AllanInputError, cluster_sizes, default_cluster_sizes, overlapping_adev
from gyrofilter.errors import GyroFilterError, SettingsError
from gyrofilter.analysis.noise.export import kalibr_yaml, to_json
from gyrofilter.cli.allan import print_coefficients
from gyrofilter.analysis.noise.fit import characterise, characterise_axis, fit, nnls_weighted
from gyrofilter.analysis.noise.intervals import fitted_intervals, reduced_chi2
from gyrofilter.analysis.noise.model import (ANGLE_RANDOM_WALK, FLICKER_FLOOR, GYROSCOPE_TERMS, QUANTIZATION, UNIT_FACTORS,
                                             arw_from_white_std,
                                             basis, convert, model_adev, white_std_from_arw)
from support import RECORDINGS, REPO, tool

SYMBOL_TERM = {"Q": QUANTIZATION, "N": ANGLE_RANDOM_WALK, "B": BIAS_INSTABILITY, "K": RATE_RANDOM_WALK, "R": RATE_RAMP}


# --- a minimal noise generator (the tests' own; independent of the package's simulator) -------

def flicker(n, rng):
    """1/f noise by Kasdin & Walter's fractional differencing (Proc. IEEE 1992): white noise of
    unit variance convolved with h_0 = 1, h_k = h_{k-1} (alpha/2 + k - 1) / k, alpha = 1, via FFT.
    Its one-sided PSD is ~ 1 / (pi f) (per sample), so B * flicker has Allan floor 0.664 B."""
    k = np.arange(1, n)
    h = np.concatenate([[1.0], np.cumprod((0.5 + k - 1) / k)])
    size = 1 << int(math.ceil(math.log2(2 * n)))
    w = rng.normal(0.0, 1.0, n)
    return np.fft.irfft(np.fft.rfft(h, size) * np.fft.rfft(w, size), size)[:n]


def simulate(n, fs, rng, Q=0.0, N=0.0, B=0.0, K=0.0, R=0.0):
    """Rate series (deg/s) with quantization Q (white angle noise of std Q: sigma^2 = 3Q^2/tau^2
    ... for the angle-difference rate), ARW N, bias instability B, RRW K and ramp R."""
    x = np.zeros(n)
    if N:
        x += rng.normal(0.0, N * math.sqrt(fs), n)          # per-sample std N sqrt(fs)
    if B:
        x += B * flicker(n, rng)
    if K:
        x += np.cumsum(rng.normal(0.0, K / math.sqrt(fs), n))  # increments K sqrt(tau0)
    if R:
        x += R * np.arange(n) / fs
    if Q:
        x += np.diff(rng.normal(0.0, Q, n + 1)) * fs        # rate of white angle noise
    return x


# --- model identities -------------------------------------------------------------------------

def test_model_terms_meet_their_read_off_points():
    # paper 000: sigma = sqrt(3) Q / tau, N / sqrt(tau), 0.664 B, K sqrt(tau/3), R tau / sqrt(2)
    assert model_adev([2.0, 0, 0, 0, 0], [math.sqrt(3)])[0] == pytest.approx(2.0)
    assert model_adev([0, 2.0, 0, 0, 0], [1.0])[0] == pytest.approx(2.0)
    assert model_adev([0, 0, 2.0, 0, 0], [1e-3, 1e3]) == pytest.approx([2.0 * 0.6643, 2.0 * 0.6643], rel=1e-4)
    assert model_adev([0, 0, 0, 2.0, 0], [3.0])[0] == pytest.approx(2.0)
    assert model_adev([0, 0, 0, 0, 2.0], [math.sqrt(2)])[0] == pytest.approx(2.0)
    assert FLICKER_FLOOR == pytest.approx(math.sqrt(2 * math.log(2) / math.pi))


def test_generator_levels_match_the_model():
    # the tests' generator against the model it is meant to produce (one long seed per term)
    from gyrofilter.analysis.noise.allan import overlapping_adev
    rng = np.random.default_rng(11)
    tau, dev = overlapping_adev(simulate(400000, 10.0, rng, B=0.01), 10.0, [10.0, 100.0])
    np.testing.assert_allclose(dev, 0.01 * FLICKER_FLOOR, rtol=0.1)
    tau, dev = overlapping_adev(simulate(200000, 10.0, rng, Q=0.01), 10.0, [1.0, 10.0])
    np.testing.assert_allclose(dev, math.sqrt(3) * 0.01 / tau, rtol=0.05)


def test_nnls_matches_scipy():
    optimize = pytest.importorskip("scipy.optimize")
    rng = np.random.default_rng(3)
    for _ in range(20):
        a = basis(np.logspace(-2, 3, 30))
        truth = np.abs(rng.normal(size=5)) * (rng.random(5) < 0.6)
        y = a @ truth * (1 + 0.2 * rng.normal(size=30))
        w = rng.uniform(0.5, 2.0, 30) / np.maximum(np.abs(y), 1e-12) ** 2
        ours = nnls_weighted(a, y, w)
        sw = np.sqrt(w)
        scale = np.linalg.norm(a * sw[:, None], axis=0)
        ref, _ = optimize.nnls(a * sw[:, None] / scale, y * sw)
        np.testing.assert_allclose(ours, ref / scale, rtol=1e-6, atol=1e-12 * np.max(ref / scale))


# --- round trips ---------------------------------------------------------------------------------

CASES = {
    # name: (samples at 10 Hz, true coefficients)
    "white": (50000, {"N": 0.05}),
    "flicker": (131072, {"N": 0.05, "B": 0.01}),
    "random_walk": (65536, {"N": 0.05, "K": 0.002}),
    "ramp": (131072, {"N": 0.05, "R": 1e-4}),
    QUANTIZATION: (50000, {"Q": 0.01, "N": 0.01}),
}


def _battery(case, seeds):
    n, truth = CASES[case]
    inside = {k: 0 for k in truth}
    spurious = 0
    for seed in seeds:
        r = characterise_axis(simulate(n, 10.0, np.random.default_rng(10_000 + seed), **truth), 10.0)
        for sym, value in truth.items():
            c = r.fitted[SYMBOL_TERM[sym]]
            inside[sym] += bool(c.value is not None and c.low <= value <= c.high)
        spurious += sum(r.fitted[SYMBOL_TERM[s]].value is not None for s in "QNBKR" if s not in truth)
    return inside, spurious


@pytest.mark.parametrize("case", [pytest.param(c, marks=pytest.mark.slow) if CASES[c][0] > 100000 else c
                                  for c in sorted(CASES)])  # the 2^17-sample cases are slow
def test_round_trip_recovers_each_coefficient_inside_its_interval(case):
    seeds = range(30)
    inside, spurious = _battery(case, seeds)
    for sym, hits in inside.items():
        assert hits >= 27, f"{case}: {sym} inside its 95 % interval in only {hits}/30 seeds"
    # terms that are absent should rarely be reported as resolved
    assert spurious <= 4, f"{case}: {spurious} absent terms reported as resolved in 30 seeds"


@pytest.mark.slow
@pytest.mark.parametrize("case", sorted(CASES))
def test_round_trip_battery_200_seeds(case):
    seeds = range(100, 300)
    inside, spurious = _battery(case, seeds)
    for sym, hits in inside.items():
        assert hits >= 180, f"{case}: {sym} inside its interval in {hits}/200 seeds (< 90 %)"
    assert spurious <= 40


def test_short_record_leaves_slow_terms_unresolved():
    # 100 s of white noise cannot show bias instability, rate random walk or a ramp
    r = characterise_axis(simulate(10000, 100.0, np.random.default_rng(5), N=0.009), 100.0)
    assert r.fitted[ANGLE_RANDOM_WALK].value == pytest.approx(0.009, rel=0.03)
    for term in ("bias_instability", RATE_RANDOM_WALK, "rate_ramp"):
        c = r.fitted[term]
        assert c.value is None and c.upper is not None and c.upper > 0
        assert "not resolved" in c.note
    assert r.readoff["bias_instability"].value is None  # still falling: no flat minimum


def test_read_off_white_noise_gives_n_at_one_second():
    # paper 002's N = sigma(1 s) sqrt(1 s) with the chi-square interval of that point: on pure
    # white noise it covers the truth in about 95 % of seeds (>= 26 of 30 here)
    hits = 0
    for seed in range(30):
        r = characterise_axis(simulate(20000, 100.0, np.random.default_rng(seed), N=0.01), 100.0)
        c = r.readoff[ANGLE_RANDOM_WALK]
        assert c.tau_s == pytest.approx(1.0, rel=0.15)
        hits += bool(c.low <= 0.01 <= c.high)
        assert r.readoff["quantization"].value is None
    assert hits >= 26


def test_fit_covers_bias_instability_more_often_than_the_read_off():
    # paper 000's B = sigma_min / 0.664 takes the lowest of many noisy points (biased low) and
    # ignores the white part at the minimum; the fit models both
    n, truth = CASES["flicker"]
    fit_hits = ro_hits = 0
    for seed in range(12):
        r = characterise_axis(simulate(n, 10.0, np.random.default_rng(seed), **truth), 10.0)
        f, ro = r.fitted["bias_instability"], r.readoff["bias_instability"]
        fit_hits += bool(f.value is not None and f.low <= truth["B"] <= f.high)
        ro_hits += bool(ro.value is not None and ro.low <= truth["B"] <= ro.high)
    assert fit_hits >= 11
    assert fit_hits > ro_hits


# --- units ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("term, unit", sorted(UNIT_FACTORS))
def test_unit_conversions_round_trip(term, unit):
    for value in (1e-6, 0.0123, 7.5):
        there = convert(value, term, unit)
        assert convert(there, term, unit, to_base=True) == pytest.approx(value, rel=1e-14)


def test_unit_conversion_values():
    assert convert(1.0, ANGLE_RANDOM_WALK, "deg/sqrt(h)") == pytest.approx(60.0)
    assert convert(0.005, ANGLE_RANDOM_WALK, "deg/sqrt(h)") == pytest.approx(0.3)            # MPU6050 datasheet
    assert convert(1.0, "bias_instability", "deg/h") == pytest.approx(3600.0)
    assert convert(1.0, RATE_RANDOM_WALK, "deg/h/sqrt(h)") == pytest.approx(216000.0)
    assert convert(0.01, ANGLE_RANDOM_WALK, "rad/s/sqrt(Hz)") == pytest.approx(0.01 * math.pi / 180)  # Kalibr
    assert convert(1.0, RATE_RANDOM_WALK, "rad/s^2/sqrt(Hz)") == pytest.approx(math.pi / 180)
    assert convert(None, ANGLE_RANDOM_WALK, "deg/sqrt(h)") is None
    # paper 000's NAV440 ARW 0.174 deg/sqrt(h) = 0.0029 deg/sqrt(s)
    assert convert(0.174, ANGLE_RANDOM_WALK, "deg/sqrt(h)", to_base=True) == pytest.approx(0.0029)
    assert white_std_from_arw(arw_from_white_std(0.1, 100.0), 100.0) == pytest.approx(0.1)
    assert arw_from_white_std(0.1, 100.0) == pytest.approx(0.01)
    with pytest.raises(SettingsError, match="known"):
        convert(1.0, ANGLE_RANDOM_WALK, "furlongs")


def test_fitted_arw_converts_to_the_per_sample_noise():
    # discrete-time std sigma_d = N sqrt(fs): the conversion Kalibr users get wrong
    fs = 200.0
    x = simulate(100000, fs, np.random.default_rng(9), N=0.004)
    n_fit = characterise_axis(x, fs).fitted[ANGLE_RANDOM_WALK].value
    assert white_std_from_arw(n_fit, fs) == pytest.approx(np.std(x), rel=0.02)


# --- bad input ------------------------------------------------------------------------------------

def test_constant_axis_is_refused():
    with pytest.raises(AllanInputError, match="constant"):
        characterise_axis(np.full(1000, -3.3), 100.0, axis="y")


def test_nan_is_refused_with_position():
    x = np.zeros(1000)
    x[5] = 1.0
    x[17] = np.nan
    with pytest.raises(AllanInputError, match="sample 17"):
        characterise_axis(x, 100.0)


def test_missing_axis_is_refused():
    with pytest.raises(AllanInputError, match="axis is missing"):
        characterise(np.random.default_rng(0).normal(size=(1000, 2)), 100.0)


def test_missing_rate_is_refused():
    with pytest.raises(SettingsError, match="sample_rate_hz"):
        characterise_axis(np.random.default_rng(0).normal(size=1000), None)


def test_too_short_for_a_fit():
    with pytest.raises(AllanInputError, match="too short|fewer than 9"):
        characterise_axis(np.random.default_rng(0).normal(size=12), 100.0)
    assert issubclass(AllanInputError, GyroFilterError)


def test_taus_with_fewer_than_nine_clusters_are_shown_but_not_fitted():
    x = simulate(2000, 10.0, np.random.default_rng(2), N=0.05)
    r = characterise_axis(x, 10.0, taus_s=[0.1, 1.0, 10.0, 50.0, 90.0])  # 90 s: 2 clusters
    assert r.n_clusters.tolist() == [2000, 200, 20, 4, 2]
    assert r.fit_used.tolist() == [True, True, True, False, False]
    assert any("fewer than 9 clusters" in w and "not fitted" in w for w in r.warnings)


def test_lowering_min_clusters_says_so():
    x = simulate(2000, 10.0, np.random.default_rng(2), N=0.05)
    r = characterise_axis(x, 10.0, taus_s=[0.1, 1.0, 10.0, 50.0], min_clusters=3)
    assert r.fit_used.all()
    assert any("as few as 4 clusters" in w for w in r.warnings)


# --- export ---------------------------------------------------------------------------------------

def test_json_document_follows_interfaces_section_3():
    rng = np.random.default_rng(4)
    g = np.column_stack([simulate(20000, 100.0, rng, N=n) for n in (0.008, 0.01, 0.012)])
    doc = to_json(characterise(g, 100.0), 100.0)
    assert doc["sample_rate_hz"] == 100.0
    assert set(doc["axes"]) == {"x", "y", "z"}
    for name, truth in zip("xyz", (0.008, 0.01, 0.012)):
        ax = doc["axes"][name]
        assert len(ax["tau_s"]) == len(ax["adev_dps"]) > 10
        coef = ax["coefficients"]
        assert set(coef) == {"quantization_deg", "arw_dps_per_sqrt_hz", "bias_instability_dps",
                             "rrw_dps_per_sqrt_s", "rate_ramp_dps_per_s"}
        arw = coef["arw_dps_per_sqrt_hz"]
        assert arw["low"] <= arw["value"] <= arw["high"]
        assert arw["value"] == pytest.approx(truth, rel=0.05)
        assert coef["rrw_dps_per_sqrt_s"] is None and coef["rate_ramp_dps_per_s"] is None
        assert ax["details"]["arw_dps_per_sqrt_hz"]["customary"]["unit"] == "deg/sqrt(h)"
    assert doc["method"]["units"]["arw_dps_per_sqrt_hz"] == "deg/s/sqrt(Hz)"


def test_kalibr_yaml_uses_continuous_time_si_units_and_the_largest_axis():
    """The plain values (comments) are the largest fitted N and K bound over the axes in rad/s;
    the values written are the bounding pair (tests/test_kalibr.py): on or above every axis's
    deviation over the range, touching it; here close to the plain N (white noise only)."""
    rng = np.random.default_rng(6)
    g = np.column_stack([simulate(20000, 100.0, rng, N=n) for n in (0.008, 0.01, 0.012)])
    res = characterise(g, 100.0)
    text = kalibr_yaml(res, 100.0)
    values = dict(line.split("#")[0].split(":", 1) for line in text.splitlines()
                  if line and not line.startswith("#"))
    plain, = [line for line in text.splitlines() if line.startswith("# gyroscope, plain (largest over the axes)")]
    plain_nd, plain_rw = (float(plain.split(f"{key} ")[1].split(",")[0]) for key in ("noise_density", "random_walk"))
    assert plain_nd == pytest.approx(max(r.fitted[ANGLE_RANDOM_WALK].value for r in res.values()) * math.pi / 180, rel=1e-6)
    assert plain_rw == pytest.approx(max(r.fitted[RATE_RANDOM_WALK].upper for r in res.values()) * math.pi / 180, rel=1e-6)
    assert float(values["update_rate"]) == 100.0
    nd, rw = (float(values[key]) * 180 / math.pi for key in ("gyroscope_noise_density", "gyroscope_random_walk"))
    tau = res["x"].tau_s
    inside = (tau >= 0.1) & (tau <= 100.0)
    ratio = np.sqrt(nd ** 2 / tau[inside] + rw ** 2 * tau[inside] / 3) / np.max([r.adev[inside] for r in res.values()], axis=0)
    # on or above, close; K's loose bound is its floor: 200 s of white noise bound K at 1.4x the value
    # the bound had before it was a covering one (intervals.upper_bound), the pair rising to 2.03x at 100 s
    assert 1 - 1e-6 <= ratio.min() < 1.01 and ratio.max() < 2.5
    assert nd == pytest.approx(plain_nd * 180 / math.pi, rel=0.1)
    assert "upper bound: K not resolved" in text
    assert "the default range 0.1 .. 100 s cut to the record's 0.1 .. 22.22 s" in text


# --- covariance model of the Allan variance estimates ---------------------------------------------

@pytest.mark.parametrize("kind, alpha", [("white", 0), ("random_walk", -2)])
def test_correlation_between_cluster_times_matches_monte_carlo(kind, alpha):
    from gyrofilter.analysis.noise.allan import overlapping_adev
    from gyrofilter.analysis.noise.intervals import avar_correlation
    m = np.array([1, 2, 5, 10, 20, 40])
    est = []
    for seed in range(400):
        rng = np.random.default_rng(seed)
        x = rng.normal(size=8000) if kind == "white" else np.cumsum(rng.normal(size=8000))
        est.append(overlapping_adev(x, 1.0, m)[1] ** 2)
    emp = np.corrcoef(np.array(est).T)
    model = avar_correlation(m[:, None], m[None, :], alpha)
    # 400 seeds: standard error of a correlation of 0.5 is about 0.04
    np.testing.assert_allclose(model, emp, atol=0.12)
    assert np.mean(np.abs(model - emp)) < 0.05


def test_discrete_and_continuous_correlation_agree_for_large_m():
    from gyrofilter.analysis.noise.intervals import _rho_table, avar_correlation
    for alpha in (0, -1, -2):
        log_r, rho = _rho_table(alpha)
        assert avar_correlation(30, 60, alpha) == pytest.approx(np.interp(math.log(2), log_r, rho), abs=0.01)
        assert avar_correlation(7, 7, alpha) == pytest.approx(1.0)


def test_fit_uncertainty_of_n_matches_the_spread_over_seeds():
    # the stated standard deviation of N^2 (from cov = G C G') against the spread of 60 fits
    est, sd = [], []
    for seed in range(60):
        r = characterise_axis(simulate(20000, 10.0, np.random.default_rng(seed), N=0.05), 10.0)
        c = r.fitted[ANGLE_RANDOM_WALK]
        est.append(c.value ** 2)
        sd.append((c.high ** 2 - c.low ** 2) / (2 * 1.96))
    ratio = np.std(est, ddof=1) / np.mean(sd)
    assert 0.75 < ratio < 1.35, ratio


def test_round_trip_through_the_package_simulator():
    # an independent generator: gyrofilter.sim.simulate (bias instability as a Gauss-Markov bank,
    # its own random streams) with the shared model schema; every coefficient inside its interval
    simulate_dps = pytest.importorskip("gyrofilter.sim.simulate").simulate_dps
    model = {"sample_rate_hz": 10.0, "gyro_unit": "dps", "axes": {
        "x": {"bias_dps": 0.0, "arw_dps_per_sqrt_hz": 0.05,
              "effects": [{"effect": "bias_instability", "b_dps": 0.01}]},
        "y": {"bias_dps": 1.0, "arw_dps_per_sqrt_hz": 0.05,
              "effects": [{"effect": "rate_random_walk", "k_dps_per_sqrt_s": 0.002}]},
        "z": {"bias_dps": -1.0, "arw_dps_per_sqrt_hz": 0.05,
              "effects": [{"effect": "rate_ramp", "r_dps_per_s": 1e-4}]}}}
    truth = [("x", ANGLE_RANDOM_WALK, 0.05), ("x", "bias_instability", 0.01), ("y", ANGLE_RANDOM_WALK, 0.05),
             ("y", RATE_RANDOM_WALK, 0.002), ("z", ANGLE_RANDOM_WALK, 0.05), ("z", "rate_ramp", 1e-4)]
    hits = {key: 0 for key in truth}
    for seed in range(12):
        g, _ = simulate_dps(model, 13107.2, seed=seed)
        res = characterise(g, 10.0)
        for axis, term, value in truth:
            c = res[axis].fitted[term]
            hits[(axis, term, value)] += bool(c.value is not None and c.low <= value <= c.high)
    assert all(h >= 10 for h in hits.values()), hits


def test_gross_errors_find_spikes_and_absurd_rates_but_not_noise_or_drift():
    from gyrofilter.analysis.noise.screen import gross_errors

    rng = np.random.default_rng(12)
    n = 200_000  # several of the function's blocks
    t = np.arange(n) / 100.0
    still = 0.1 * rng.normal(size=n)
    # real drift: a 5 deg/s warm-up and a 2 deg/s ramp, 50 and 20 noise sigmas, smooth per sample
    drifting = still + 5.0 * np.exp(-t / 300.0) + 2.0 * t / t[-1]
    assert gross_errors(still).size == 0 and gross_errors(drifting).size == 0
    spiked = drifting.copy()
    where = [0, 65_533, 65_536, 123_457, n - 1]  # block edges and the series' ends
    spiked[where] += [8.0, -9.0, 30.0, 1e30, -7.0]
    spiked[150_000:150_002] = 1e308  # a burst beyond any full scale
    assert gross_errors(spiked).tolist() == sorted(where + [150_000, 150_001])


def test_gross_errors_leave_the_still_recordings_alone():
    from gyrofilter.analysis.noise.screen import gross_errors
    from gyrofilter.recording import read_recording

    for path in sorted(RECORDINGS.glob("mpu6050_static_*.csv.gz")):
        g = read_recording(path).gyro_dps
        assert all(gross_errors(g[:, a]).size == 0 for a in range(3)), path


@pytest.mark.parametrize("exponent", [-3, 40, 90])
def test_the_fit_is_scale_free_down_to_the_noise_floor(exponent):
    """The same noise times 10^-k gives the same coefficients times 10^-k: the fit's weights
    (1 / Allan variance^2) overflowed below deviations of 1e-75 deg/s (a failed SVD), and its
    covariances silently lost the intervals below that (issue 22, hostile case 3-1)."""
    rng = np.random.default_rng(5)
    x = rng.normal(size=6000) + 0.01 * np.cumsum(rng.normal(size=6000))
    ref = characterise_axis(x, 100.0)
    scale = 10.0 ** -exponent
    got = characterise_axis(x * scale, 100.0)
    np.testing.assert_allclose(got.adev / scale, ref.adev, rtol=1e-9)
    np.testing.assert_allclose(got.ci_low / scale, ref.ci_low, rtol=1e-9)
    for term, c in ref.fitted.items():
        g = got.fitted[term]
        assert (g.value is None) == (c.value is None), term
        for mine, theirs in ((g.value, c.value), (g.low, c.low), (g.high, c.high), (g.upper, c.upper)):
            assert (mine is None and theirs is None) or math.isclose(mine / scale, theirs, rel_tol=1e-6), term


@pytest.mark.parametrize("noise", [1e-120, 1e-300, 5e-320])
def test_noise_below_the_floor_is_refused_naming_the_axis(noise):
    x = np.random.default_rng(3).normal(size=3000) * noise
    with pytest.raises(AllanInputError, match=r"axis y: the Allan deviation is below 1e-100 deg/s"):
        characterise_axis(x, 100.0, axis="y")


def test_deviations_exactly_zero_give_a_result_not_a_failed_svd():
    """+-1 alternating data: the Allan deviation is exactly 0 at every even cluster size, which
    made the fit's weights infinite (issue 22, hostile case 3-1); now every term is unresolved."""
    x = (-1.0) ** np.arange(5000)
    res = characterise_axis(x, 100.0)
    assert np.all(res.adev[1::2][:2] == 0) and res.adev[0] == pytest.approx(math.sqrt(2))
    assert all(c.value is None for c in res.fitted.values())
    assert np.all(np.isfinite(res.ci_low)) and np.all(np.isfinite(res.ci_high)) and np.all(np.isfinite(res.edf))


def test_a_read_off_of_a_deviation_of_zero_is_not_determined_not_a_bound_of_zero(capsys):
    """Issue 37 (attack passes 12-14): +-0.1 alternating data (deviation 0 at every even cluster
    size) had the slope read-off "B < 0": a bound of 0 (no bias instability) that a curve of 0
    does not show. B is "not determined" there, in the JSON's note and on the console."""
    res = characterise_axis(0.1 * (-1.0) ** np.arange(60_000), 100.0)
    b = res.readoff[BIAS_INSTABILITY]
    assert (b.value, b.upper) == (None, None) and b.note == (f"not determined: the Allan deviation is 0 at tau = "
                                                           f"{b.tau_s:g} s (every cluster average equal there)")
    assert res.adev[np.flatnonzero(res.tau_s == b.tau_s)[0]] == 0.0
    print_coefficients({"x": res}, GYROSCOPE_TERMS, 0.95, 9)
    row = next(line for line in capsys.readouterr().out.splitlines() if line.strip().startswith("B "))
    assert row.endswith(" not determined") and "< 0" not in row


# --- the fit's misfit (noise.intervals.reduced_chi2) widens its intervals --------------------

def _fitted_curve(bump, widen=True, n=200_000, fs=100.0):
    """The fit of an exact five-term curve (N = 0.01, B = 0.003, K = 2e-4: not resolved in 2000 s), with ``bump``: the
    Allan variance raised by that fraction around tau = 1 s (a Gaussian in log tau, which no term
    has the shape of); returns (coefficients, chi2_nu, dof)."""
    m = default_cluster_sizes(n)
    tau = m / fs
    avar = model_adev((0.0, 0.01, 0.003, 2e-4, 0.0), tau) ** 2
    avar = avar * (1.0 + bump * np.exp(-0.5 * (np.log(tau) / 0.4) ** 2))
    theta, used, _, _ = fit(tau, np.sqrt(avar), m, n)
    return fitted_intervals(theta, tau, m, n, used, 0.95, avar, widen=widen)


def test_a_bump_no_term_fits_widens_every_interval_by_the_root_of_the_misfit():
    clean, chi2_clean, _ = _fitted_curve(0.0)
    bumped, chi2, dof = _fitted_curve(0.1)
    assert chi2_clean < 1e-6 < 1.3 < chi2 and 0 < dof
    unwidened, chi2_again, _ = _fitted_curve(0.1, widen=False)
    assert chi2_again == chi2
    for term in (ANGLE_RANDOM_WALK, BIAS_INSTABILITY):
        c, b, u = clean[term], bumped[term], unwidened[term]
        width = [x.high - x.low for x in (c, b, u)]
        # against the same fit unwidened (the clean curve is fitted exactly: which zero terms its
        # NNLS keeps, so its effective dof and widths, is a numerical tie that numpy 1.24 breaks
        # otherwise than 2.x; it is no reference for the widening)
        assert width[1] > width[2], (term, width)
        # the variance scale chi2_nu: about sqrt(chi2_nu) on the coefficient's interval (same value)
        assert 0.8 * math.sqrt(chi2) < width[1] / width[2] < 1.2 * math.sqrt(chi2), (term, width, chi2)
    for term in (QUANTIZATION, RATE_RANDOM_WALK, RATE_RAMP):  # and every bound
        assert bumped[term].upper > unwidened[term].upper
    # a larger bump: B, resolved on the stated scatter alone, is within the widened uncertainty of zero
    bumped, chi2, _ = _fitted_curve(0.3)
    unwidened, _, _ = _fitted_curve(0.3, widen=False)
    assert chi2 > 4 and unwidened[BIAS_INSTABILITY].value is not None and bumped[BIAS_INSTABILITY].value is None
    assert bumped[BIAS_INSTABILITY].upper > unwidened[BIAS_INSTABILITY].high


def test_a_fit_within_its_stated_scatter_keeps_its_intervals():
    # white noise: chi2_nu about 1 or below; a value <= 1 changes nothing (no narrowing either)
    for seed in range(4):
        x = simulate(20000, 10.0, np.random.default_rng(700 + seed), N=0.05)
        tau, dev = overlapping_adev(x, 10.0)
        m = cluster_sizes(x.size, 10.0, tau)
        theta, used, _, _ = fit(tau, dev, m, x.size)
        widened, chi2, _ = fitted_intervals(theta, tau, m, x.size, used, 0.95, dev ** 2)
        plain_, _, _ = fitted_intervals(theta, tau, m, x.size, used, 0.95, dev ** 2, widen=False)
        if chi2 <= 1.0:
            assert widened == plain_
        else:
            assert widened[ANGLE_RANDOM_WALK].high > plain_[ANGLE_RANDOM_WALK].high
    clean, chi2_clean, _ = _fitted_curve(0.0)
    assert clean == _fitted_curve(0.0, widen=False)[0] and chi2_clean <= 1.0


def test_the_misfit_counts_taus_minus_terms_for_independent_estimates_and_fewer_when_correlated():
    rng = np.random.default_rng(5)
    tau = np.logspace(-1, 2, 20)
    a = basis(tau)
    theta = np.array([0.0, 1.0, 0.5, 0.0, 0.0])
    y = a @ theta * (1.0 + 0.1 * rng.standard_normal(tau.size))
    sd = 0.1 * (a @ theta)
    w = 1.0 / sd ** 2
    active = theta > 0
    chi2, dof = reduced_chi2(a, y, theta, w, np.diag(sd ** 2), active)
    assert dof == pytest.approx(tau.size - 2)
    assert chi2 == pytest.approx(float(np.sum(w * (y - a @ theta) ** 2)) / (tau.size - 2))
    rho = 0.9 ** np.abs(np.subtract.outer(np.arange(tau.size), np.arange(tau.size)))
    _, dof_corr = reduced_chi2(a, y, theta, w, rho * np.outer(sd, sd), active)
    assert 0 < dof_corr < tau.size - 2
    assert reduced_chi2(a[:2], y[:2], theta, w[:2], np.diag(sd[:2] ** 2), active) == (None, None)


def test_a_term_left_out_is_bounded_above_what_the_data_give_it():
    # K in the data but left out of the fit: its bound is at least the forced-in least-squares K
    n, fs = 200_000, 100.0
    m = default_cluster_sizes(n)
    tau = m / fs
    avar = model_adev((0.0, 0.01, 0.0, 1e-4, 0.0), tau) ** 2
    theta, used, _, _ = fit(tau, np.sqrt(avar), m, n, terms=(ANGLE_RANDOM_WALK,))
    coeffs, _, _ = fitted_intervals(theta, tau, m, n, used, 0.95, avar)
    a = basis(tau[used])[:, [1, 3]]
    w = 1.0 / avar[used] ** 2
    ls = np.linalg.lstsq(a * np.sqrt(w)[:, None], avar[used] * np.sqrt(w), rcond=None)[0]
    assert coeffs[RATE_RANDOM_WALK].value is None
    assert coeffs[RATE_RANDOM_WALK].upper >= math.sqrt(ls[1]) > 0.5e-4


def test_a_term_the_data_give_0_with_no_scatter_of_the_others_is_bounded_not_searched_for_ever():
    """Attack pass 15: `allan` on 20 samples that switch between -32768 and 32767 LSB never ended
    (axis z, 12 minutes and on): the bound's bisection of a term whose forced-in estimate is 0 while
    the other terms' mixture is 0 (no scatter) excludes every value above 0, and halved its upper
    end down to the smallest float, where half of it is 0 and the interval no longer shrinks. The
    bound of such a term is the search's smallest value, at once. A subprocess, so that the old
    code fails by its timeout instead of hanging the suite."""
    code = ("import numpy as np\n"
            "from gyrofilter.analysis.noise.intervals import avar_covariance, upper_bound\n"
            "from gyrofilter.analysis.noise.model import basis\n"
            "tau, m = np.array([0.01, 0.02, 0.04, 0.08]), np.array([1, 2, 4, 8])\n"
            "active = np.array([False, True, False, False, False])\n"
            "print(repr(upper_bound(basis(tau), np.ones(4), np.zeros(4), active, 3, 0.95,\n"
            "                       lambda mix: avar_covariance(tau, m, 1000, mix)[1])[0]))\n")
    try:
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=REPO)
    except subprocess.TimeoutExpired:
        pytest.fail("upper_bound searched for ever")
    assert out.returncode == 0, out.stderr
    assert 0.0 < float(out.stdout) <= 1e-16


# --- the warning that the noise is not just Q/N/B/K/R ----------------------------------------

NOT_FIVE_TERMS = "the noise is not just Q/N/B/K/R"


def test_ten_minutes_of_white_noise_and_bias_instability_are_not_called_more_than_five_terms():
    # the warning judged the model drawn, from which an unresolved B is dropped: it lay below the
    # intervals of the longest taus and the warning fired on 22 % of such records (seed 5, y: 32 %
    # of the taus outside); judged on the full fit, on under 1 % (tools/allan_consistency.py)
    simulate_dps = pytest.importorskip("gyrofilter.sim.simulate").simulate_dps
    axes = [r for seed in range(6)
            for r in characterise(simulate_dps(tool("allan_consistency").null_model(), 600.0, seed=seed)[0], 100.0).values()]
    assert not [w for r in axes for w in r.warnings if NOT_FIVE_TERMS in w]
    assert min(r.full_fit_consistency() for r in axes) >= 0.8
    # the case the rule is about: B fitted, then dropped as not resolved
    assert sum(r.full_fit_values[2] > 0 and r.fit_values[2] == 0 for r in axes) >= 3


def test_a_tone_is_still_called_more_than_five_terms_on_its_axis_only():
    from support import REPO

    from gyrofilter.sim.model import load_model

    simulate_dps = pytest.importorskip("gyrofilter.sim.simulate").simulate_dps
    g, _ = simulate_dps(load_model(str(REPO / "examples" / "models" / "sinusoid.json")), 600.0, seed=0)
    res = characterise(g, 100.0)
    assert [a for a, r in res.items() if any(NOT_FIVE_TERMS in w for w in r.warnings)] == ["z"]
    doc = to_json(res, 100.0)["axes"]
    assert doc["z"]["full_fit_consistency"] == res["z"].full_fit_consistency() < 0.8 <= doc["x"]["full_fit_consistency"]
    # gap analyses the gyro only: the warning points there for the gyro, not for an accelerometer
    assert [w for w in res["z"].warnings if NOT_FIVE_TERMS in w and "(see `gyrofilter gap`)" in w]
    accel = characterise_axis(g[:, 2], 100.0, axis="az", unit="m/s^2").warnings
    assert [w for w in accel if NOT_FIVE_TERMS in w] and not [w for w in accel if "gyrofilter gap" in w]


def test_the_bound_of_a_random_walk_the_record_does_not_resolve_holds_it():
    """An hour of white noise and a random walk (K = 5e-5, 1e-4, 2e-4 deg/s/sqrt(s) on x, y, z,
    tools/allan_coverage.py's white + random walk case), seeds 1-6: K's interval, or its 95 % upper
    bound where it is not resolved, holds the simulated K on at least 16 of the 18 axes (measured 18;
    the bound at the fitted mixture held it on 14: 9 of the 13 not resolved), and no B is resolved."""
    coverage = tool("allan_coverage")
    rows = [row for seed in range(1, 7) for row in coverage.run(("white-rw", 60, seed))]
    k = [row for row in rows if row["term"] == RATE_RANDOM_WALK]
    assert sum(map(coverage.covered, k)) >= 16 and sum(row["value"] is None for row in k) >= 9
    assert all(row["value"] is None for row in rows if row["term"] == BIAS_INSTABILITY)


def test_a_random_walk_with_a_bias_instability_not_resolved_is_held_by_its_interval():
    """Issue 37 (attack pass 34a): 10 min of white noise, flicker and a random walk together
    (N = 0.01, B = 0.005, K = 0.003; tools/allan_coverage.py's white-flicker-rw case), seed 5: B is
    not resolved on z, and held at 0 it left its flat share of the long taus to K, whose interval
    sat above the truth (low 0.00312 for 0.003). With an unresolved B freed in the others'
    intervals, as K and R are, K's interval reaches down to 0.00257 and holds it."""
    from gyrofilter.sim.simulate import simulate as simulate_model
    coverage = tool("allan_coverage")
    fitted = characterise_axis(simulate_model(coverage.white_flicker_rw_model(), 600.0, seed=5).gyro_dps[:, 2],
                               100.0).fitted
    k, true_k = fitted[RATE_RANDOM_WALK], coverage.WHITE_FLICKER_RW["k_dps_per_sqrt_s"]
    assert fitted[BIAS_INSTABILITY].value is None and k.value is not None
    assert k.low <= true_k <= k.high, (k.low, k.high)


@pytest.mark.slow
def test_a_random_walk_with_a_bias_instability_not_resolved_is_covered_on_short_records():
    """Issue 37: the white-flicker-rw case (N = 0.01, B = 0.005, K = 0.003), 10 min, seeds 1-14:
    K's interval, or its bound where not resolved, holds K on at least 38 of the 42 axes (measured
    40; 33 with an unresolved B held at 0 in K's interval, the pass's 84 %), and N's and B's as
    often as before (42 and 40)."""
    coverage = tool("allan_coverage")
    rows = [row for seed in range(1, 15) for row in coverage.run(("white-flicker-rw", 10, seed))]
    held = {term: sum(coverage.covered(r) for r in rows if r["term"] == term)
            for term in (ANGLE_RANDOM_WALK, BIAS_INSTABILITY, RATE_RANDOM_WALK)}
    assert held[RATE_RANDOM_WALK] >= 38 and held[ANGLE_RANDOM_WALK] >= 40 and held[BIAS_INSTABILITY] >= 38, held


def test_a_resolved_bias_instability_read_high_is_held_by_its_interval():
    """Issue 37: 10 min of N = 0.01, B = 0.005, K = 0.003 (tools/allan_coverage.py's
    white-flicker-rw case), seed 44, x: B is resolved and read high (0.0065), and its variance is
    mostly N's and K's; the chi-square interval with its edf at that estimate, [0.00506, 0.00917],
    sat above the truth. Inverted with the variance at each hypothesis, it reaches 0.0044 and holds it."""
    from gyrofilter.sim.simulate import simulate as simulate_model
    coverage = tool("allan_coverage")
    fitted = characterise_axis(simulate_model(coverage.white_flicker_rw_model(), 600.0, seed=44).gyro_dps[:, 0],
                               100.0).fitted
    b, true_b = fitted[BIAS_INSTABILITY], coverage.WHITE_FLICKER_RW["b_dps"]
    assert b.value is not None and b.value > 1.2 * true_b
    assert b.low <= true_b <= b.high, (b.low, b.high)


@pytest.mark.slow
def test_a_resolved_bias_instability_is_held_by_its_interval_on_short_records():
    """Issue 37: the white-flicker-rw case, 10 min, seeds 41-80 (docs/allan.md's table): where B
    is resolved, its interval holds B on at least 90 % of the axes (measured 56 of 61; 47 of 61
    with the chi-square interval at the estimate, every miss above the truth), and N's and K's
    intervals or bounds hold them as often as before (115 and 116 of 120)."""
    coverage = tool("allan_coverage")
    rows = [row for seed in range(41, 81) for row in coverage.run(("white-flicker-rw", 10, seed))]
    b = [r for r in rows if r["term"] == BIAS_INSTABILITY and r["value"] is not None]
    assert sum(map(coverage.covered, b)) >= 0.9 * len(b) and len(b) >= 40, (sum(map(coverage.covered, b)), len(b))
    held = {term: sum(coverage.covered(r) for r in rows if r["term"] == term)
            for term in (ANGLE_RANDOM_WALK, RATE_RANDOM_WALK)}
    assert held[ANGLE_RANDOM_WALK] >= 115 and held[RATE_RANDOM_WALK] >= 116, held


def test_the_bound_of_a_bias_instability_a_drift_fitted_as_k_takes_holds_it():
    """The default MPU6050 gyro, 30 min, seeds 15-18 (the user's trial): its temperature drift is
    fitted as a random walk K, which takes part of B's flat level once B is forced in; B's bound
    from that fit alone missed B on 4 of the 6 axes where B was not resolved (0.87-1.0x; seed 15
    x: 0.0013 for 0.0015). The bound is the largest over the fits with each K or R not resolved
    forced in and each K or R that the fit with B does not resolve left out: it holds B on every
    one, and stays within 2.5x of it."""
    coverage = tool("allan_coverage")
    rows = [row for seed in range(15, 19) for row in coverage.run(("default-gyro", 30, seed))
            if row["term"] == BIAS_INSTABILITY and row["value"] is None]
    assert len(rows) >= 5
    assert all(coverage.covered(row) for row in rows), [(r["seed"], r["axis"], r["upper"] / r["true"]) for r in rows]
    assert max(row["upper"] / row["true"] for row in rows) < 2.5


def _default_record(minutes, seed):
    from gyrofilter.sim.simulate import simulate as simulate_model
    return simulate_model(tool("allan_coverage").default_model(), 60.0 * minutes, seed=seed, accelerometer=True)


def test_the_accelerometers_notes_carry_its_units():
    """The notes of an accelerometer's terms read '95% upper bound 3e-05 deg', 'R = 1.59e-05 deg/s^2'
    where its unit fields said m/s, m/s^3: the notes take the sensor's units (default model, 30 min,
    seed 15, az: B within its uncertainty of zero once K, not resolved, is free)."""
    r = characterise_axis(_default_record(30, 15).accel_mps2[:, 2], 100.0, axis="az", unit="m/s^2")
    notes = {term: c.note for term, c in r.fitted.items() if c.note}
    assert len(notes) >= 3 and not [n for n in notes.values() if "deg" in n], notes
    assert "m/s^2" in notes[BIAS_INSTABILITY] and "once K (not resolved) is free" in notes[BIAS_INSTABILITY]
    assert r.fitted[BIAS_INSTABILITY].freed_by == (RATE_RANDOM_WALK,)
    assert "m/s^2/sqrt(s)" in notes[RATE_RANDOM_WALK] and "m/s^3" in notes[RATE_RAMP]
    with pytest.raises(SettingsError, match="unit must be"):
        characterise_axis(np.arange(100.0), 100.0, unit="rad/s")


@pytest.mark.parametrize("settings, said", [({"confidence": np.float32(0.9)}, None), ({"confidence": np.array(0.9)}, None),
                                            ({"min_clusters": "9"}, "min_clusters must be a finite number"),
                                            ({"min_clusters": None}, "min_clusters must be a finite number"),
                                            ({"min_clusters": 0}, r"min_clusters must be >= 2"),
                                            ({"min_clusters": 2.5}, "min_clusters must be a whole number")])
def test_numpy_numbers_taken_and_min_clusters_checked(settings, said):
    """Attack pass 29b: characterise_axis refused a float32 confidence of 0.9 as "not between 0
    and 1"; min_clusters "9" or None ended in numpy's or Python's TypeError, 0 or 2.5 taken."""
    x = np.random.default_rng(0).normal(0, 0.05, 2000)
    if said is None:
        assert characterise_axis(x, 100.0, **settings).confidence == pytest.approx(0.9)
    else:
        with pytest.raises(SettingsError, match=said):
            characterise_axis(x, 100.0, **settings)
