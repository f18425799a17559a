"""The pieces that make the gap analysis linear in the record length and bounded in memory
give the numbers of the plain computations they replace (seeded; no timings here: speed and
memory are printed by ``tools/bench_gap.py``)."""
import math
import re

import numpy as np
import pytest

from gyrofilter.analysis import stats
from gyrofilter.analysis.gap import detectors as det
from gyrofilter.analysis.gap import pipeline as gap
from gyrofilter.analysis.gap import features as gap_features
from gyrofilter.analysis.gap.detectors import sinusoid
from gyrofilter.analysis.noise.allan import overlapping_adev
from gyrofilter.sim.simulate import simulate, simulate_axis_dps

MODEL = {"sample_rate_hz": 100.0, "gyro_unit": "lsb", "lsb_per_dps": 131.0,
         "temperature": {"start_c": 25.0, "end_c": 31.0, "tau_s": 200.0, "noise_c": 0.01},
         "axes": {"x": {"bias_dps": -3.3, "arw_dps_per_sqrt_hz": 0.009,
                        "effects": [{"effect": "warmup", "amplitude_dps": 0.2, "tau_s": 30.0},
                                    {"effect": "colored_noise", "lag1": 0.3}]},
                  "y": {"bias_dps": 1.1, "arw_dps_per_sqrt_hz": 0.012,
                        "effects": [{"effect": "bias_instability", "b_dps": 0.004},
                                    {"effect": "outliers", "rate": 1e-3, "magnitude_dps": 1.5}]},
                  "z": {"bias_dps": 0.4, "arw_dps_per_sqrt_hz": 0.008,
                        "effects": [{"effect": "temperature", "coefficient_dps_per_c": 0.01},
                                    {"effect": "sinusoid", "frequency_hz": 7.3, "amplitude_dps": 0.02}]}}}


@pytest.mark.parametrize("unit", ["lsb", "dps", "rad/s"])
def test_one_axis_simulation_equals_that_axis_of_the_full_run(unit):
    model = dict(MODEL, gyro_unit=unit)
    full = simulate(model, 250.0, seed=5).gyro_dps
    for i in range(3):
        blocks = list(simulate_axis_dps(model, 250.0, i, seed=5, chunk_samples=4096))
        assert max(b.size for b in blocks) == 4096
        assert np.array_equal(np.concatenate(blocks), full[:, i])


def _strided_adev(x, fs, taus):
    """NIST SP 1065 eq. 11 over the start points j = 0, s, 2s, ... (s = max(1, m // 8)), by
    fancy indexing."""
    phase = np.concatenate(([0.0], np.cumsum(x - x.mean()))) / fs
    out = []
    for m in np.round(np.asarray(taus) * fs).astype(int):
        j = np.arange(0, x.size - 2 * m + 1, max(1, m // 8))
        d = phase[j + 2 * m] - 2 * phase[j + m] + phase[j]
        out.append(math.sqrt(np.mean(d ** 2) / 2) / (m / fs))
    return np.array(out)


def test_feature_adev_is_the_strided_overlapping_estimator():
    rng = np.random.default_rng(3)
    x = rng.normal(0.5, 0.1, 100_003) + np.cumsum(rng.normal(0, 1e-4, 100_003))
    taus = gap_features.feature_taus(x.size, 100.0)
    got = gap_features.feature_adev(x, 100.0, taus)
    assert np.allclose(got, _strided_adev(x, 100.0, taus), rtol=1e-9, atol=0)
    m = np.round(taus * 100.0).astype(int)
    small = m < gap_features.ADEV_STARTS  # every start point: the fully overlapping estimator
    assert small.sum() >= 4
    assert np.allclose(got[small], overlapping_adev(x, 100.0, taus[small])[1], rtol=1e-9, atol=0)
    # fewer start points for long taus: the same expectation, close on one record
    assert np.allclose(got, overlapping_adev(x, 100.0, taus)[1], rtol=0.15, atol=0)


def test_feature_adev_caps_the_terms_in_evenly_spread_runs(monkeypatch):
    """Past ADEV_MAX_TERMS start points, the sum keeps runs of consecutive ones: the same
    formula on that subset, and close to the full estimator, also on a sinusoid whose period
    divides the stride a coarser lattice would take (aliasing)."""
    monkeypatch.setattr(gap_features, "_ADEV_CHUNK", 1000)
    monkeypatch.setattr(gap_features, "ADEV_MAX_TERMS", 8000)
    rng = np.random.default_rng(11)
    n, fs = 120_001, 100.0
    x = rng.normal(0.0, 0.1, n) + 0.3 * np.sin(2 * math.pi * 12.5 * np.arange(n) / fs)  # period 8 samples
    taus = gap_features.feature_taus(n, fs)
    got = gap_features.feature_adev(x, fs, taus)
    phase = np.concatenate(([0.0], np.cumsum(x - x.mean()))) / fs
    for tau, value in zip(taus, got):
        m = int(round(tau * fs))
        step = max(1, m // 8)
        k = (n - 2 * m) // step + 1
        runs = gap_features._adev_runs(k)
        idx = np.concatenate([np.arange(a, b) for a, b in runs]) * step
        assert idx.size == min(k, 8000) and np.unique(idx).size == idx.size
        assert idx[0] == 0 and idx[-1] == (k - 1) * step
        d = phase[idx + 2 * m] - 2 * phase[idx + m] + phase[idx]
        assert value == pytest.approx(math.sqrt(np.mean(d ** 2) / 2) / (m / fs), rel=1e-9)
    capped = (n - 2 * np.round(taus * fs)) // np.maximum(1, np.round(taus * fs) // 8) + 1 > 8000
    assert capped.sum() >= 5
    assert np.allclose(got[capped], _strided_adev(x, fs, taus[capped]), rtol=0.03, atol=0)


def test_dft_amplitude_equals_the_direct_sum_near_the_peak():
    rng = np.random.default_rng(4)
    n, fs, f0 = 300_007, 100.0, 7.31
    t = np.arange(n) / fs
    x = rng.normal(0, 0.1, n) + 0.02 * np.sin(2 * math.pi * f0 * t + 0.4)
    xc = x - x.mean()
    amp = det.dft_amplitude(xc, fs, f0)
    for f in (f0, f0 + 0.6 * fs / n, f0 - fs / n):
        direct = abs(np.sum(xc * np.exp(-2j * math.pi * f * t)))
        assert amp(f) == pytest.approx(direct, rel=1e-8)


def test_moving_mean_and_spike_mask_equal_their_index_formulas():
    rng = np.random.default_rng(6)
    for n in (40, 1000, 65_537):
        x = rng.normal(0, 0.1, n)
        for w in (1, 4, 5, 64, n + 3):
            c = np.concatenate(([0.0], np.cumsum(x)))
            lo = np.clip(np.arange(n) - w // 2, 0, n)
            hi = np.clip(np.arange(n) - w // 2 + w, 0, n)
            assert np.allclose(stats.moving_mean(x, w), (c[hi] - c[lo]) / (hi - lo), rtol=0, atol=1e-12)
        x[rng.integers(0, n, 8)] += 3.0
        x[0] += 3.0
        r = np.empty(n)
        r[1:-1] = x[1:-1] - 0.5 * (x[:-2] + x[2:])
        r[0], r[-1] = x[0] - x[1], x[-1] - x[-2]
        mask, k, sd_r = det.outlier_statistic(x)
        a = np.abs(r)
        left, right = np.concatenate(([0.0], a[:-1])), np.concatenate((a[1:], [0.0]))
        assert mask.any() and np.array_equal(mask, (a > k * sd_r) & (a >= left) & (a >= right))


def test_running_medians_equal_the_median_of_each_window_and_the_median_filter():
    """stats.window_medians (the narrow-band background's running median, O(log W) a bin) gives
    np.median of each window exactly: windows that slide, that shrink from the left (the edge
    background's) and that jump, on values with ties (a quantized spectrum); and over the series
    extended by its end values, scipy's median filter of mode "nearest"."""
    from scipy.ndimage import median_filter

    rng = np.random.default_rng(8)
    for values in (rng.exponential(size=300), np.round(rng.normal(size=300) * 2.0) / 2.0):
        spans = [(i, i + 41) for i in range(100)] + [(120 + 2 * k, 201) for k in range(30)] + [(250, 261), (260, 299)]
        assert np.array_equal(stats.window_medians(values, spans), [np.median(values[lo:hi]) for lo, hi in spans])
        padded = np.concatenate((np.full(20, values[0]), values, np.full(20, values[-1])))
        assert np.array_equal(stats.window_medians(padded, [(i, i + 41) for i in range(300)]),
                              median_filter(values, size=41, mode="nearest"))
    for spans in ([(0, 4)], [(5, 10), (4, 11)], [(0, 11), (1, 10)]):
        with pytest.raises(ValueError, match="even length or moves back"):
            stats.window_medians(np.arange(20.0), spans)


def test_least_squares_and_detrend_equal_lstsq():
    rng = np.random.default_rng(8)
    n = 2 * det.CHUNK_SAMPLES + 12_345  # the normal equations are summed over three pieces
    t = np.arange(n) / 100.0
    g = np.exp(-t / 60.0)
    x = 0.3 * g + 0.01 * t + rng.normal(0, 0.1, n)
    columns = lambda lo, hi: (g[lo:hi], t[lo:hi] - t.mean())  # noqa: E731
    coef = det.least_squares(columns, x)
    ref, *_ = np.linalg.lstsq(np.column_stack([g, t - t.mean(), np.ones(n)]), x, rcond=None)
    assert np.allclose(coef, ref, rtol=1e-9, atol=1e-12)
    assert np.allclose(det.fitted(columns, coef[:2], n), coef[0] * g + coef[1] * (t - t.mean()), rtol=0, atol=1e-12)
    line = np.polyval(np.polyfit(t, x, 1), t)
    assert np.allclose(stats.detrend_line(x), x - line, rtol=0, atol=1e-10)


def test_sinusoid_fit_in_pieces_equals_the_full_fit():
    rng = np.random.default_rng(10)
    n, fs, f_hz = 3 * det.CHUNK_SAMPLES - 7, 100.0, 7.31
    w = np.arange(n) * (2 * math.pi * f_hz / fs)
    x = 0.02 * np.sin(w + 0.4) + 0.3 + rng.normal(0, 0.05, n)
    amp, phase, fit = det.sinusoid_fit(x, fs, f_hz)
    (a, b, c), *_ = np.linalg.lstsq(np.column_stack([np.cos(w), np.sin(w), np.ones(n)]), x, rcond=None)
    assert math.isclose(amp, math.hypot(a, b), rel_tol=1e-9)
    assert math.isclose(phase, math.atan2(a, b), rel_tol=1e-9)
    assert np.allclose(fit, a * np.cos(w) + b * np.sin(w), rtol=0, atol=1e-12)


def test_band_edges_find_the_bins_of_searchsorted():
    rng = np.random.default_rng(9)
    for _ in range(200):
        n = int(rng.integers(300, 3_000_000))
        fs = float(rng.choice([1.0, 99.3171, 100.0, 1000.0]))
        size = n // 2 + 1
        freqs = np.concatenate([gap_features.feature_bands(n, fs), np.arange(0, size, size // 7 + 1) * fs / n])
        assert np.array_equal(gap_features._first_bins(freqs, size, n, fs), np.searchsorted(np.arange(size) * fs / n, freqs))


def test_progress_gives_fraction_and_time_left_and_the_extended_model_reuses_the_gain_runs():
    model = {"sample_rate_hz": 100.0, "gyro_unit": "lsb", "lsb_per_dps": 131.0,
             "axes": {"x": {"bias_dps": 0.1, "arw_dps_per_sqrt_hz": 0.01, "effects": []},
                      "y": {"bias_dps": 0.2, "arw_dps_per_sqrt_hz": 0.01, "effects": []},
                      "z": {"bias_dps": 0.3, "arw_dps_per_sqrt_hz": 0.01,
                            "effects": [{"effect": "sinusoid", "frequency_hz": 3.3, "amplitude_dps": 0.03}]}}}
    lines = []
    report = gap.analyse_gap(simulate(model, 600.0, seed=2), seed=1, n_sims=6, progress=lines.append)
    steps = [s for s in lines if re.search(r": \d+/\d+ \(\d+ %, about \d+ s left\)$", s)]
    assert any(s.startswith("baseline simulations") and "18/18 (100 %" in s for s in steps), lines
    assert any(s.startswith("gain of sinusoid on z") for s in steps), lines
    (finding,) = report["findings"]
    # one finding on z: the extended model's z is the model of that finding's gain
    assert report["discrepancy"]["after"]["z"] == finding["gain"]["after"]


@pytest.mark.parametrize("n", [777, 2048, 61_440, 1_000_000])
def test_periodogram_equals_numpys_rfft_of_the_detrended_series(n):
    """The four-step transform and its unpacking (several blocks of rows, the first with its
    self-partnered row 0) give |rfft|^2 / N of the detrended series; odd N takes rfft itself."""
    x = np.random.default_rng(n).normal(0.3, 0.1, n) + 1e-5 * np.arange(n)
    size = det.periodogram_length(n)
    t = np.arange(size)
    r = x[:size] - np.polyval(np.polyfit(t, x[:size], 1), t)
    ref = np.abs(np.fft.rfft(r)) ** 2 / size
    got = det.periodogram(x.copy())
    assert got.shape == ref.shape
    assert np.max(np.abs(got - ref)) <= 1e-11 * ref.mean()


def test_peak_ratio_equals_the_argmax_over_every_bins_level():
    """The line statistic searches stretches by a bound (``_peak_ratio``); it must give the ratio and
    bin of the plain search over the level at every bin, ties and all-zero spectra included, the
    last bin too (halved as the Nyquist bin of an even record)."""
    rng = np.random.default_rng(12)
    for trial in range(400):
        n = int(rng.integers(41, 80)) if trial % 10 == 0 else int(rng.integers(41, 100_000))
        spec = rng.exponential(1.0, n) * (np.arange(n) + 1.0) ** rng.uniform(-2, 1)
        if trial % 3 == 0:
            spec[rng.integers(8, n)] *= rng.uniform(1, 50)
        if trial % 7 == 0:
            spec[rng.integers(0, n, size=n // 3)] = 0.0
        if trial % 50 == 0:
            spec[:] = 0.0
        level = sinusoid._level_at(np.arange(n), sinusoid._band_levels(spec, 8))
        ratio = spec / level
        ratio[:8] = 0.0
        nyquist = trial % 2 == 1
        if nyquist:
            ratio[-1] /= 2.0
        j = int(np.argmax(ratio))
        got = sinusoid._peak_ratio(spec, 8, nyquist)
        assert got[1] == j and got[0] == pytest.approx(float(ratio[j]), rel=1e-12, abs=0), (n, trial)


def test_periodogram_length_is_the_largest_11_smooth_length():
    def smooth(v):
        for p in (2, 3, 5, 7, 11):
            while v % p == 0:
                v //= p
        return v == 1

    for n in list(range(64, 3000)) + [333_269, 1_000_003, 3_599_999]:
        got = det.periodogram_length(n)
        assert got <= n and smooth(got), n
        assert not any(smooth(v) for v in range(got + 1, n + 1)), n
    assert det.periodogram_length(333_269) == 332_750  # 2 5^3 11^3


def _traced_peak(fn):
    import tracemalloc

    tracemalloc.start()
    try:
        out = fn()
        return tracemalloc.get_traced_memory()[1], out
    finally:
        tracemalloc.stop()


def _axis_with_spikes_and_a_line(n, fs, seed):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    x = np.round((0.4 + rng.normal(0, 0.1, n) + 0.02 * np.sin(2 * math.pi * 7.3 * t)) * 131.0) / 131.0
    x[rng.integers(0, n, 40)] += 1.5
    return x


def test_features_and_detectors_hold_a_few_series_not_a_copy_per_statistic():
    """The memory design of long records (docs/gap.md, "Speed and memory"): the features of a run
    and the detectors of an axis need about one series of work space besides the series itself
    (numpy reports its buffers to tracemalloc), whatever the number of statistics. The features:
    the growth of the peak from 1 to 2 million samples per added series; the detectors that work
    on the whole series (the slow ones work on at most 2048 block means), their peak at 2
    million. Before issue 24 the features took 3.75 series (the tail statistic 3.1, numpy's rfft
    three more outside tracemalloc's sight) and the sinusoid detector 3.3; a regression that
    keeps an N-sample copy per statistic fails here."""
    fs = 100.0
    peaks = {}
    for n in (1_000_000, 2_000_000):
        x = _axis_with_spikes_and_a_line(n, fs, 11)
        taus, bands = gap_features.feature_taus(n, fs), gap_features.feature_bands(n, fs)
        peaks[n], _ = _traced_peak(lambda: gap_features.features(x.copy(), fs, taus, bands, overwrite=True))
    per_series = (peaks[2_000_000] - peaks[1_000_000]) / (1_000_000 * 8)
    assert per_series < 2.8, f"features: {per_series:.2f} series (the run itself is 1)"
    series = x.nbytes
    # each detector is run once on a short series first: what its first call sets up (the modules it
    # imports) is not work space, and run alone (numpy 2.4) the narrow-band detector read 2.80 series
    for name, call in [("outliers", lambda s: det.detect_outliers(s)),
                       ("heavy tails", lambda s: det.detect_heavy_tails(s, fs, spikes_found=True, tails_z=0.0)),
                       ("sinusoid", lambda s: det.detect_sinusoid(s, fs)),
                       ("narrow band", lambda s: det.detect_narrowband(s, fs)),
                       ("colored noise", lambda s: det.detect_colored(s, fs)),
                       # the record's three axes made one at a time, as the pipeline hands them over (a
                       # list of the three held 3 series at once: 555 MB for a day at 100 Hz, not 381)
                       ("repeated rows", lambda s: det.detect_repeats((s + 0.0 for _ in range(3)), 1.0 / 131.0))]:
        call(x[:20_000])
        peak, _ = _traced_peak(lambda: call(x))
        assert peak < 2.5 * series, f"{name} detector: {peak / series:.2f} series besides the axis"
