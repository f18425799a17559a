"""A still record's spikes are gross errors, not motion (a new user's finding): the stillness check
(gyrofilter.analysis.still.moved / not_static, shared by allan, arma, gap, report and the fleet) judges
the record without them, while a real turn still reads as motion."""
import numpy as np
import pytest

from gyrofilter.analysis.still import moved

FS_HZ, N = 100.0, 60_000  # 600 s at 100 Hz: blocks of 118 samples


def still(rng):
    """A still MPU6050-like axis (deg/s): bias, a slow walk, white noise of 0.08 deg/s, 1/131 deg/s steps."""
    x = -3.3 + np.cumsum(rng.normal(0, 5e-5, N)) + rng.normal(0, 0.08, N)
    return np.round(x * 131) / 131


def spiked(seed):
    """1 to 10 spikes of 5 to 500 deg/s (log-uniform, either sign) on a still axis."""
    rng = np.random.default_rng(seed)
    x = still(rng)
    k = int(rng.integers(1, 11))
    at = rng.choice(np.arange(2, N - 3), size=k, replace=False)
    x[at] += rng.choice([-1, 1], k) * np.exp(rng.uniform(np.log(5), np.log(500), k))
    return x


def turned(seed, kind):
    """A still axis with a real motion: a 1-s turn at 5 deg/s, 10 s at 1.5 deg/s, or a slow tilt (20 deg
    over 10 s, a Hann-shaped rate of peak 4 deg/s)."""
    rng = np.random.default_rng(seed)
    x = still(rng)
    s = int(rng.integers(1000, N - 3000))
    profile = {"turn": np.full(100, 5.0), "rotation": np.full(1000, 1.5),
               "tilt": 4.0 * np.sin(np.pi * np.arange(1000) / 1000) ** 2}[kind]
    x[s:s + profile.size] += profile
    return x


def test_one_spike_of_150_dps_does_not_make_a_still_record_moved():
    x = still(np.random.default_rng(2))
    x[30_000] += 150.0  # the user's one_spike.csv: 150 / 118 = 1.27 deg/s on one block's mean
    assert moved(x, FS_HZ) is None
    x[45_000:45_002] += 150.0  # two side by side: the screen finds one sample of four alike
    assert moved(x, FS_HZ) is None


@pytest.mark.parametrize("kind", ["turn", "rotation", "tilt"])
def test_a_real_turn_still_reads_as_motion(kind):
    assert "does not look static" in moved(turned(0, kind), FS_HZ)


@pytest.mark.slow
def test_spiked_still_records_never_read_moved_and_turns_always_do():
    """Before: 157 of 200 seeds read "moved" (1-10 spikes of 5-500 deg/s); after: 0."""
    assert [s for s in range(100) if moved(spiked(s), FS_HZ) is not None] == []
    for kind in ("turn", "rotation", "tilt"):
        assert [s for s in range(100) if moved(turned(s, kind), FS_HZ) is None] == [], kind


# --- the gap analysis: a few isolated spikes of any size are outliers, never heavy tails


def _gap_axis(seed, n=60_000):
    """A still axis (deg/s) at 100 Hz: white noise of 0.08 deg/s on 1/131 deg/s steps."""
    return np.round(np.random.default_rng(seed).normal(-3.3, 0.08, n) * 131) / 131


def _tails_and_spikes(x):
    from gyrofilter.analysis.gap import detectors as det

    spikes, _ = det.detect_outliers(x, 1 / 131)
    tails, _ = det.detect_heavy_tails(x, 100.0, spikes_found=spikes is not None)
    return spikes, tails


def test_one_large_spike_is_outliers_not_heavy_tails():
    """The user's one_spike.csv: one 150 deg/s sample was heavy_tails (fraction 0.0017, scale ratio 201:
    the spike leaked through the tail residual's moving mean into 100 samples of 30 sd) and no outliers
    (three needed)."""
    x = _gap_axis(2)
    x[30_000] += 150.0
    spikes, tails = _tails_and_spikes(x)
    assert tails is None
    assert spikes is not None and 100 < spikes.params["magnitude_dps"] < 200, spikes and spikes.params


@pytest.mark.parametrize("sizes", [(150.0, 80.0), (20.0, 150.0, 500.0)])
def test_two_or_three_spikes_of_spread_sizes_are_outliers(sizes):
    x = _gap_axis(3)
    x[np.arange(len(sizes)) * 15_000 + 7_000] += np.array(sizes)
    spikes, tails = _tails_and_spikes(x)
    assert tails is None and spikes is not None and spikes.statistic == len(sizes)


@pytest.mark.parametrize("at", [0, -1])
def test_a_spike_on_the_first_or_last_sample_is_outliers(at):
    """Attack pass 37j: a 100 deg/s first or last sample (a start-up read's garbage) was no outlier (the
    gross errors were judged inner samples only); gap named it a bias_step of 100 deg/s at the record's
    end, or a warm-up of 11 deg/s."""
    x = _gap_axis(5)
    x[at] += 100.0
    spikes, tails = _tails_and_spikes(x)
    assert tails is None and spikes is not None and spikes.statistic == 1
    assert 60 < spikes.params["magnitude_dps"] < 160, spikes.params


def test_real_heavy_tails_stay_heavy_tails():
    """Student-t noise (3 degrees of freedom) and 1 % of the samples at 10 times the noise: heavy tails."""
    rng = np.random.default_rng(4)
    for x in (0.08 * rng.standard_t(3, 60_000), 0.08 * rng.normal(size=60_000) * np.where(rng.random(60_000) < 0.01, 10, 1)):
        assert _tails_and_spikes(x)[1] is not None


@pytest.mark.slow
def test_few_spikes_of_any_size_are_outliers_and_heavy_tails_stay_over_seeds():
    """Before: 1-3 spikes of 20-500 deg/s were heavy_tails on 32 of 40 seeds, outliers on 1 (5-20 deg/s:
    17 heavy_tails, 6 outliers); after: outliers on all. Student-t (3-5 degrees of freedom) and 1 % at
    10 times the noise stay heavy_tails on every seed."""
    for seed in range(20):
        rng = np.random.default_rng(seed)
        x = _gap_axis(seed)
        k = int(rng.integers(1, 4))
        at = rng.choice(np.arange(5, x.size - 5), k, replace=False)
        x[at] += rng.choice([-1, 1], k) * np.exp(rng.uniform(np.log(5), np.log(500), k))
        spikes, tails = _tails_and_spikes(x)
        assert tails is None and spikes is not None, seed
    for seed in range(6):
        rng = np.random.default_rng(100 + seed)
        noise = (0.08 * rng.standard_t(3 + seed % 3, 60_000),
                 0.08 * rng.normal(size=60_000) * np.where(rng.random(60_000) < 0.01, 10, 1))
        assert all(_tails_and_spikes(x)[1] is not None for x in noise), seed


@pytest.mark.parametrize("kind", ["vibrating turn", "short turn"])
def test_a_turn_made_of_spikes_still_reads_as_motion(kind):
    """Attack pass 37j: a 5-s turn at 10 deg/s (50 degrees) under a 10-Hz vibration of 100 deg/s, and a
    50-degree turn in 5 samples (1000 deg/s), were left out whole as "spikes and the samples beside
    them" and read still (gap analysed the turn as ringing and narrowband). Only isolated spikes (a
    run of at most a pair's four alike and two beside) are left out; a longer run is judged."""
    x = still(np.random.default_rng(1))
    if kind == "vibrating turn":
        x[30_000:30_500] += 10.0 + 100.0 * np.cos(2 * np.pi * 10.0 * np.arange(500) / FS_HZ)
    else:
        x[30_000:30_005] += 1000.0
    assert "does not look static" in moved(x, FS_HZ)


def test_a_pair_of_unequal_spikes_is_left_out():
    x = still(np.random.default_rng(3))
    x[20_000], x[20_001] = x[20_000] + 150.0, x[20_001] + 140.0  # the screen finds two of the four
    x[40_000:40_002] += 300.0
    assert moved(x, FS_HZ) is None


@pytest.mark.parametrize("apart", [3, 4, 5, 6, 9])
def test_two_spikes_a_few_samples_apart_are_left_out(apart):
    """Attack pass 37k: two 150 deg/s spikes 4 or 5 samples apart made one run of 9 or 10 samples beside
    them, longer than a pair's, and the still record read "moved" (gap refused it, the fleet skipped it)."""
    x = still(np.random.default_rng(apart))
    x[30_000] += 150.0
    x[30_000 + apart] -= 150.0 if apart % 2 else -150.0
    x[40_000:40_002] += 120.0  # a pair and a spike 4 samples after it
    x[40_005] += 200.0
    assert moved(x, FS_HZ) is None


@pytest.mark.parametrize("samples", [5, 6, 7, 10])
def test_a_short_fast_turn_still_reads_as_motion(samples):
    """A turn at 150 deg/s in 5 or more samples: its edges are the spikes the screen finds, a run of 9
    or more; its plateau is raised, so the run is motion, not two spikes."""
    x = still(np.random.default_rng(samples))
    x[30_000:30_000 + samples] += 150.0
    assert "does not look static" in moved(x, FS_HZ)


def test_simulated_outliers_never_make_a_still_record_moved():
    """Attack pass 37k: the simulator's outliers at a rate of 0.005 (spikes of about 100 deg/s) made 8 of
    10 still 600-s records read "moved": spikes a few samples apart joined into runs longer than a pair's."""
    rng = np.random.default_rng(37)
    found = []
    for seed in range(10):
        x = still(np.random.default_rng(seed))
        at = np.flatnonzero(rng.random(N) < 0.005)
        x[at] += rng.choice([-1, 1], at.size) * 100.0 * np.exp(rng.normal(0, 0.5, at.size))
        found.append(moved(x, FS_HZ))
    assert found == [None] * 10
