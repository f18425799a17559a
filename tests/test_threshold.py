"""The gross-error threshold that follows a vibration (gyrofilter.filter.threshold): its equation, one block at a time
and an array at once bit for bit, and what it is for: a vibrating still sensor reads its bias through the default
filter (paper 001's fixed q took the vibration's extremes: -0.74 deg/s for a 20-Hz, 3-deg/s one at 100 Hz), while
occasional spikes are still judged against q."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gyrofilter import GyroFilter
from gyrofilter.filter.threshold import RangeThreshold


def _reference(blocks, q, k, n):
    """The module's equation, written out: the lower quartile (the (floor((n - 1) / 4) + 1)-th smallest) of the last n
    ranges (0 before the first), times k, at least q."""
    ranges = np.concatenate((np.zeros((n - 1, 3)), blocks.max(axis=1) - blocks.min(axis=1)))
    return np.array([np.maximum(q, k * np.sort(ranges[j : j + n], axis=0)[(n - 1) // 4]) for j in range(len(blocks))])


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**16), n=st.sampled_from([1, 2, 3, 4, 5, 15, 21]), k=st.sampled_from([0.5, 1.5, 3.0]),
       cuts=st.lists(st.integers(0, 40), max_size=6))
def test_one_block_at_a_time_and_arrays_in_any_split_follow_the_equation(seed, n, k, cuts):
    rng = np.random.default_rng(seed)
    blocks = rng.normal(0, 1, (40, 5, 3)) * rng.uniform(0.01, 5, (40, 1, 3))  # ranges that change from block to block
    expected = _reference(blocks, 1.0, k, n)
    one = RangeThreshold(1.0, k, n)
    np.testing.assert_array_equal([one.one(b.T.tolist()) for b in blocks], expected)
    many, parts = RangeThreshold(1.0, k, n), []
    for a, b in zip([0, *sorted(cuts)], [*sorted(cuts), len(blocks)]):
        parts.append(np.broadcast_to(many.many(blocks[a:b]), (b - a, 3)))
    np.testing.assert_array_equal(np.concatenate(parts), expected)


def test_k_zero_is_paper_001s_fixed_q():
    blocks = np.random.default_rng(1).normal(0, 10, (7, 5, 3))
    threshold = RangeThreshold(1.0, 0.0, 15)
    assert threshold.one(blocks[0].T.tolist()) == (1.0, 1.0, 1.0)
    assert threshold.many(blocks) == 1.0


def _vibrating_still(rng, fs, n_s, freq_hz, amp_dps, axis, bias):
    """A still sensor: bias, white noise of 0.05 deg/s, a vibration of freq_hz and amp_dps on one axis after 2 s."""
    n = int(n_s * fs)
    t = np.arange(n) / fs
    x = np.asarray(bias) + rng.normal(0, 0.05, (n, 3))
    x[int(2 * fs):, axis] += amp_dps * np.sin(2 * np.pi * freq_hz * t[int(2 * fs):] + rng.uniform(0, 2 * np.pi))
    return x


def _draw(seed):
    """A vibrating still record drawn at random: rate, frequency (every other seed near a multiple of the block rate,
    where paper 001's rule is biased the same way block after block), amplitude, axis and bias."""
    rng = np.random.default_rng(seed)
    fs = float(rng.choice([100.0, 200.0, 1000.0]))
    freq = rng.integers(1, 3) * fs / 5 + rng.uniform(-0.3, 0.3) if seed % 2 else rng.uniform(0.1, 0.49) * fs
    x = _vibrating_still(rng, fs, 60.0, freq, rng.uniform(1.5, 8.0), int(rng.integers(3)), rng.uniform(-2, 2, 3))
    return x, fs


def _worst_2s_mean(out, fs):
    """The largest |mean| of the rows over 2-s windows (from the vibration's fourth second on: the median needs 8 of
    its blocks), deg/s; the truth is 0 (the calibration removes the bias; a vibration's own 2-s mean is < 0.04)."""
    per = int(2 * fs / 5)
    rows = out[2 * per:]
    rows = rows[: len(rows) // per * per].reshape(-1, per, 3)
    return np.abs(rows.mean(axis=1)).max()


@pytest.mark.parametrize("seed", range(16))
def test_a_vibrating_still_sensor_reads_its_bias_through_the_default_filter(seed):
    x, fs = _draw(seed)
    assert _worst_2s_mean(GyroFilter(fs).filter(x), fs) < 0.06


def test_with_q_fixed_the_same_vibrations_are_biased():
    """The test above can fail: paper 001's fixed q (k = 0) takes the extremes of the vibrations near a multiple of
    the block rate, and their 2-s means read 0.3 deg/s or more off."""
    worst = [_worst_2s_mean(GyroFilter(fs, outlier_range_k=0).filter(x), fs) for x, fs in map(_draw, range(1, 16, 2))]
    assert np.median(worst) > 0.3, worst


@pytest.mark.parametrize("spike_share", [0.01, 0.04])
def test_spikes_at_rest_are_judged_as_paper_001_judges_them(spike_share):
    """Spikes on up to 4 % of the samples (a block in five holds one) raise only their blocks' ranges, and the lower
    quartile of 15 is a clean block's: q stays 1 deg/s, and the default filter gives the numbers it gives with q fixed
    (at 8 % it raises q in 1 block in 500 and the output's std by up to 10 %; at 12 %, 1.5x: docs/evaluate.md).
    (A median of 15 ranges let spikes on 4 % of the samples through where 8 of 15 blocks held one, and knocked the
    filter out of rest: tools/dynamic_test.py's spiky table lost up to 4.8x of its reduction.)"""
    rng = np.random.default_rng(5)
    x = np.array([0.4, -0.2, 1.0]) + rng.normal(0, 0.14, (60_000, 3))
    hit = (rng.random(x.shape) < spike_share) & (np.arange(len(x)) >= 200)[:, None]
    x[hit] += rng.choice([-1, 1], hit.sum()) * rng.uniform(1.6, 3.0, hit.sum())
    default, fixed = GyroFilter(100.0), GyroFilter(100.0, outlier_range_k=0)
    np.testing.assert_array_equal(default.filter(x), fixed.filter(x))
    np.testing.assert_array_equal(default.rejected, fixed.rejected)


def test_a_spike_on_a_vibrating_sensor_beyond_the_swing_is_still_rejected():
    rng = np.random.default_rng(8)
    x = _vibrating_still(rng, 100.0, 60.0, 20.0, 3.0, 1, (0.0, 0.0, 0.0))
    spikes = rng.choice(np.arange(1000, len(x)), 30, replace=False)
    x[spikes, 1] += 60.0
    f = GyroFilter(100.0)
    out = f.filter(x)
    assert f.rejected[1] >= 30
    assert abs(out[100:, 1].mean()) < 0.02


def test_the_calibration_window_seeds_the_ranges():
    """The last N - 1 blocks of the start-up window stand in for the blocks before the first (then every block's
    threshold follows the equation over the window's blocks and the stream's), and a vibration from power-up is
    followed from the first block: the first 2 s after the calibration read within 0.03 deg/s (with zeros seeded,
    12 blocks were judged with q = 1 deg/s and their bias held at rest: 0.2 deg/s, a new user's trial)."""
    rng = np.random.default_rng(4)
    window, blocks = rng.normal(0, 2, (203, 3)), rng.normal(0, 1, (30, 5, 3))
    seeded = RangeThreshold(1.0, 2.0, 15)
    seeded.seed(window, 5)
    every = np.concatenate((window[3:].reshape(-1, 5, 3), blocks))
    np.testing.assert_array_equal(seeded.many(blocks), _reference(every, 1.0, 2.0, 15)[-30:])
    worst = 0.0
    for seed, (freq, amp) in enumerate([(33.0, 5.0), (23.0, 3.0), (45.0, 4.0), (13.0, 5.0)]):
        rng = np.random.default_rng(seed)
        t = np.arange(1200) / 100.0
        x = np.array([0.5, -0.3, 0.2]) + rng.normal(0, 0.1, (1200, 3))
        x[:, 2] += amp * np.sin(2 * np.pi * freq * t + rng.uniform(0, 2 * np.pi))
        out = GyroFilter(100.0).filter(x)
        worst = max(worst, abs(out[:40, 2].mean()))
    assert worst < 0.03


def test_an_array_longer_than_a_chunk_gives_the_numbers_of_the_equation(monkeypatch):
    """many() works through the blocks a chunk at a time (memory): the chunks' seams change nothing."""
    from gyrofilter.filter import threshold
    monkeypatch.setattr(threshold, "_CHUNK_BLOCKS", 7)
    rng = np.random.default_rng(9)
    blocks = rng.normal(0, 1, (100, 5, 3)) * rng.uniform(0.01, 5, (100, 1, 3))
    np.testing.assert_array_equal(RangeThreshold(1.0, 2.0, 15).many(blocks), _reference(blocks, 1.0, 2.0, 15))


@pytest.mark.parametrize("n_blocks", [15, 60, 999])
def test_a_vibration_from_power_up_is_followed_whatever_the_window_of_ranges(n_blocks):
    """Attack pass 39: with more blocks of ranges than the calibration window has (40 in 2 s), the missing ones counted
    as 0 and a vibration from power-up was cut for 28 s (x +0.91 deg/s at N = 999); the window's blocks now stand in
    again for them."""
    rng = np.random.default_rng(6)
    t = np.arange(3000) / 100.0
    x = np.array([0.5, -0.3, 0.2]) + rng.normal(0, 0.05, (3000, 3))
    x += 3.0 * np.sin(2 * np.pi * 20.0 * t[:, None] + np.array([0.0, 1.0, 2.0]))
    f = GyroFilter(100.0, outlier_range_blocks=n_blocks)
    out = f.filter(x)
    assert f.rejected.max() == 0
    assert np.abs(out.mean(axis=0)).max() < 0.01
