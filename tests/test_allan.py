"""Tests for gyrofilter.analysis.noise.allan: Stable32/NBS14 reference values, allantools as oracle, bad input."""
import math
import re

import numpy as np
import pytest

from gyrofilter.analysis.noise.allan import (AllanInputError, adev, default_cluster_sizes, overlapping_adev)
from gyrofilter.errors import GyroFilterError, SettingsError

# NBS14 frequency data set with Stable32 results (NIST SP 1065 Table 31; used by allantools).
NBS14 = np.array([892, 809, 823, 798, 671, 644, 883, 903, 677], dtype=float)


def test_nbs14_non_overlapping_adev_matches_stable32():
    tau, dev = adev(NBS14, 1.0, taus_s=[1, 2])
    assert tau.tolist() == [1.0, 2.0]
    assert dev[0] == pytest.approx(91.22945, rel=1e-7)
    assert dev[1] == pytest.approx(115.8082, rel=1e-6)


def test_nbs14_overlapping_adev_matches_stable32():
    tau, dev = overlapping_adev(NBS14, 1.0, taus_s=[1, 2])
    assert dev[0] == pytest.approx(91.22945, rel=1e-7)  # m = 1: overlapping = non-overlapping
    assert dev[1] == pytest.approx(85.95287, rel=1e-6)


def test_matches_allantools_oadev_on_random_data():
    allantools = pytest.importorskip("allantools")
    rng = np.random.default_rng(4)
    fs = 100.0
    x = 0.3 + rng.normal(0.0, 0.05, 20000) + np.cumsum(rng.normal(0.0, 1e-4, 20000))
    tau, dev = overlapping_adev(x, fs)
    t_ref, d_ref, _, _ = allantools.oadev(x, rate=fs, data_type="freq", taus=tau)
    np.testing.assert_array_equal(t_ref, tau)
    np.testing.assert_allclose(dev, d_ref, rtol=1e-9, atol=0)


def test_chunked_sums_equal_direct_formula_across_chunk_boundaries():
    # 150000 samples spans several 65536-sample chunks of the cumulative sum and the work buffer
    rng = np.random.default_rng(1)
    x = rng.normal(-3.3, 0.1, 150000)
    taus = np.array([1, 7, 1000, 40000]) / 50.0
    _, dev = overlapping_adev(x, 50.0, taus)
    phase = np.concatenate([[0.0], np.cumsum(x - x.mean())]) / 50.0
    for m, d in zip([1, 7, 1000, 40000], dev):
        diff = phase[2 * m:] - 2 * phase[m:-m] + phase[:-2 * m]
        ref = math.sqrt(np.mean(diff ** 2) / 2) / (m / 50.0)
        assert d == pytest.approx(ref, rel=1e-10)


def test_white_noise_level_and_slope():
    rng = np.random.default_rng(7)
    fs, arw = 100.0, 0.01  # deg/sqrt(s) -> per-sample std arw * sqrt(fs)
    x = rng.normal(0.0, arw * math.sqrt(fs), 200000)
    tau, dev = overlapping_adev(x, fs)
    # sigma(tau) = N / sqrt(tau) (paper 000); within a few % over the well-averaged taus
    ok = tau <= 20
    np.testing.assert_allclose(dev[ok] * np.sqrt(tau[ok]), arw, rtol=0.08)


def test_default_taus_ten_per_decade_up_to_a_ninth():
    m = default_cluster_sizes(90000)
    assert m[0] == 1 and m[-1] == 10000
    assert 35 <= m.size <= 41  # 4 decades, ~10 per decade (small m merge after rounding)
    tau, dev = overlapping_adev(np.random.default_rng(0).normal(size=90000), 10.0)
    assert tau[-1] == pytest.approx(1000.0)
    assert np.all(np.diff(tau) > 0)


def test_constant_data_gives_zero_deviation():
    tau, dev = overlapping_adev(np.full(100, 2.5), 1.0)
    assert np.all(dev == 0.0)


@pytest.mark.parametrize("x, rate, taus, match", [
    (np.array([1.0, np.nan, 2.0, 3.0] * 5), 1.0, None, "NaN"),
    (np.array([1.0, 2.0]), 1.0, None, "at least 3"),
    (np.ones((100, 3)), 1.0, None, "1-D"),
    (np.ones(100), 1.0, [60.0], "too short"),
    (np.ones(100), 1.0, [0.2], "shorter than one sample"),
    (np.ones(5), 1.0, None, "fewer than 9 clusters"),
])
def test_bad_input_raises_clear_error(x, rate, taus, match):
    with pytest.raises(AllanInputError, match=match):
        overlapping_adev(x, rate, taus)


@pytest.mark.parametrize("rate", [None, 0.0, -1.0, float("nan"), "fast"])
def test_missing_or_bad_rate(rate):
    with pytest.raises(SettingsError, match="sample_rate_hz"):
        overlapping_adev(np.ones(100), rate)
    assert issubclass(SettingsError, GyroFilterError)


# --- confidence intervals -------------------------------------------------------------------
from gyrofilter.analysis.noise.allan import chi2_interval, edf_mixture, edf_oavar, simple_interval  # noqa: E402


@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
@pytest.mark.parametrize("n, m", [(1000, 1), (1000, 7), (100000, 250), (500, 55)])
def test_edf_matches_allantools_edf_simple(alpha, n, m):
    ci = pytest.importorskip("allantools.ci")
    # allantools takes the number of phase points (= samples + 1)
    assert float(edf_oavar(n, m, alpha)) == pytest.approx(max(ci.edf_simple(n + 1, m, alpha), 1.0), rel=1e-12)


def test_white_fm_edf_m1_is_two_thirds_of_n():
    # Var of the m = 1 overlapping estimate for white noise is 3 sigma^4 / N -> edf = 2N/3
    assert float(edf_oavar(30000, 1, 0)) == pytest.approx(20000, rel=1e-3)


def test_mixture_edf_pure_and_bounded():
    m = np.array([1, 10, 100])
    pure = edf_mixture(10000, m, [[1, 1, 1], [0, 0, 0]], [0, -1])
    np.testing.assert_allclose(pure, edf_oavar(10000, m, 0))
    mixed = edf_mixture(10000, m, [[1, 1, 1], [1, 1, 1]], [0, -1])
    assert np.all(mixed <= np.maximum(edf_oavar(10000, m, 0), edf_oavar(10000, m, -1)) + 1e-9)
    assert np.all(mixed >= np.minimum(edf_oavar(10000, m, 0), edf_oavar(10000, m, -1)) - 1e-9)


def test_chi2_interval_matches_scipy_and_covers_white_noise():
    stats = pytest.importorskip("scipy.stats")
    low, high = chi2_interval(2.0, 10.0, 0.9)
    assert low == pytest.approx(20.0 / stats.chi2.ppf(0.95, 10))
    assert high == pytest.approx(20.0 / stats.chi2.ppf(0.05, 10))
    # coverage on white noise at a large tau (few clusters): the true AVAR N^2 / tau must fall
    # inside the 95 % interval in about 95 % of seeds (at least 88 % of 60)
    fs, n, m = 10.0, 2000, 150
    hits = 0
    for seed in range(60):
        x = np.random.default_rng(seed).normal(0.0, 1.0, n)
        tau, dev = overlapping_adev(x, fs, [m / fs])
        lo, hi = chi2_interval(dev ** 2, edf_oavar(n, m, 0), 0.95)
        truth = 1.0 / fs / tau[0]  # white: sigma^2 = s^2 tau0 / tau
        hits += bool(lo[0] <= truth <= hi[0])
    assert hits >= 53


def test_simple_interval_paper_000_example():
    low, high, rel = simple_interval(1.0, 10000, 100)
    assert float(rel) == pytest.approx(0.0711, abs=5e-5)
    assert float(high) == pytest.approx(1.0711, abs=5e-5)


def test_odd_series_and_taus_are_refused_in_one_sentence():
    """Attack pass (issue 37): a masked value was taken as data (the filter refuses it), values of
    1e300 gave an Allan deviation of inf/nan without a word, a tau of 1e300 s was "shorter than one
    sample" (after a RuntimeWarning of the int cast), and read_axes took axes="q" (a ValueError)."""
    import warnings

    from gyrofilter.analysis.still import characterise_recording

    x = np.random.default_rng(0).normal(0, 0.05, 3000)
    with pytest.raises(AllanInputError, match="x row 3 is masked; a masked value is no measurement"):
        overlapping_adev(np.ma.masked_array(x, mask=np.arange(3000) == 3), 100.0)
    assert np.array_equal(overlapping_adev(np.ma.masked_array(x), 100.0)[1], overlapping_adev(x, 100.0)[1])
    with pytest.raises(AllanInputError, match=r"values up to 1e\+300 overflow the squares"):
        overlapping_adev(np.sign(x) * 1e300, 100.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(AllanInputError, match=r"too short for tau = 1e\+300 s"):
            overlapping_adev(x, 100.0, [1e300])
        with pytest.raises(AllanInputError, match=r"too short for tau = 1e\+308 s"):  # attack 4: tau * rate overflowed, a RuntimeWarning
            overlapping_adev(x, 100.0, [1e308])
    with pytest.raises(SettingsError, match="^axes must be a subset of xyz such as xz, got 'q'$"):
        characterise_recording("never-read.csv", axes="q", warn=print)


@pytest.mark.parametrize("values", [np.arange(3000) * (1 + 1j), np.arange(3000) % 2 == 0, np.arange(3000).astype(str),
                                    np.arange(3000).astype(object)])
def test_what_is_not_numbers_is_refused_not_converted(values):
    """Attack pass (issue 37): complex rates lost their imaginary part with only a ComplexWarning,
    strings ('1') were parsed, booleans taken as 0/1, objects converted: the Allan deviation of
    something else. Ints and floats only, as the filter takes them (filter.samples.as_numbers)."""
    from gyrofilter.analysis.noise.fit import characterise

    shown = re.escape(str(values.dtype))
    with pytest.raises(AllanInputError, match=f"x must be numbers, got an array of {shown}"):
        overlapping_adev(values, 100.0)
    with pytest.raises(AllanInputError, match=f"gyro_dps must be numbers, got an array of {shown}"):
        characterise(np.stack([values] * 3, axis=1), 100.0)
    assert np.array_equal(overlapping_adev(np.arange(3000) % 7, 100.0)[1],
                          overlapping_adev((np.arange(3000) % 7).astype(float), 100.0)[1])


def test_a_masked_sample_of_three_axes_is_refused_not_taken_as_data():
    """Attack pass (issue 37): characterise() converted a masked (N, 3) array with asarray, so a
    masked sample (a dropout holding 1e4) entered every axis' Allan deviation."""
    from gyrofilter.analysis.noise.fit import characterise

    g = np.random.default_rng(5).normal(0, 0.05, (6000, 3))
    mask = np.zeros(g.shape, bool)
    mask[1234, 2] = True
    g[mask] = 1e4
    with pytest.raises(AllanInputError, match="gyro_dps row 1234 is masked"):
        characterise(np.ma.masked_array(g, mask=mask), 100.0)


def test_a_masked_sample_of_one_axis_is_refused_not_taken_as_data():
    """Attack pass 22: characterise_axis(), the one-axis entry, still converted with asarray: a
    masked 1e4 in 0.05 deg/s noise was taken as data, exit without a word (characterise() refused it)."""
    from gyrofilter.analysis.noise.fit import characterise_axis

    x = np.random.default_rng(5).normal(0, 0.05, 6000)
    x[1234] = 1e4
    with pytest.raises(AllanInputError, match="axis z: x_dps row 1234 is masked"):
        characterise_axis(np.ma.masked_array(x, mask=np.arange(6000) == 1234), 100.0, axis="z")
    with pytest.raises(AllanInputError, match="axis z: x_dps must be numbers"):
        characterise_axis(x + 1j, 100.0, axis="z")


@pytest.mark.parametrize("axes", [("x", "x"), (0, 1), {"x", "y"}])
def test_characterise_refuses_axes_that_are_not_distinct_axis_names(axes):
    """Attack pass 23: axes ("x", "x") analysed both columns and returned one, the second's,
    named x (the first column lost without a word); (0, 1) keyed the result by numbers. Attack
    pass 24: a set of axes named the columns in the set's order, which is the hash seed's
    (PYTHONHASHSEED=2 called the first column y): one check of axes, units.check_axes."""
    from gyrofilter.analysis.noise.fit import characterise

    g = np.random.default_rng(5).normal(0, 0.05, (3000, 2))
    with pytest.raises(AllanInputError, match=r"axes must be a subset of xyz such as xz, got"):
        characterise(g, 100.0, axes=axes)


@pytest.mark.parametrize("confidence", [0.9999999999999999, 1 - 1e-12])
def test_a_confidence_too_near_1_is_refused_not_an_infinite_interval(confidence):
    """Attack pass 31b: ``chi2_interval(..., 0.9999999999999999)`` returned (0, inf) with a
    RuntimeWarning (0.5 + c / 2 rounds to 1) and ``characterise_axis`` ended in statistics'
    StatisticsError; ``allan --confidence`` stopped at 0.9999 in a rule of its own. The library's
    one check (``check_confidence``) holds the command's bound."""
    from gyrofilter.analysis.noise.allan import MAX_CONFIDENCE, chi2_interval
    from gyrofilter.analysis.noise.fit import characterise_axis
    from gyrofilter.errors import SettingsError
    with pytest.raises(SettingsError, match="confidence"):
        chi2_interval(np.array([1.0]), np.array([1.0]), confidence)
    with pytest.raises(SettingsError, match="confidence"):
        characterise_axis(0.1 * np.random.default_rng(2).standard_normal(500), 100.0, confidence=confidence)
    low, high = chi2_interval(np.array([1.0]), np.array([1.0]), MAX_CONFIDENCE)
    assert 0 < low[0] < 1 < high[0] < np.inf


@pytest.mark.parametrize("taus_s", [[True], "0.1", ["a"], np.array([True])])
def test_taus_that_are_no_numbers_are_refused(taus_s):
    """Attack pass 31b: ``adev(x, fs, taus_s=[True])`` took tau 1 s, ``"0.1"`` 0.1 s, and ``["a"]``
    ended in numpy's ValueError: numbers only (``inputs.number_array``), naming ``taus_s``."""
    x = 0.1 * np.random.default_rng(2).standard_normal(500)
    with pytest.raises(SettingsError, match="taus_s"):
        adev(x, 100.0, taus_s=taus_s)
