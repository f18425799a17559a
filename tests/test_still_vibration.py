"""A turn under a continuous fast vibration reads as motion (attack pass 37l): the vibration raised the
white level of the first differences, and so the stillness limit 8 sigma / sqrt(L), while it averages
out in the block means; the block means' own scatter (gyrofilter.analysis.still.means_spread) now
bounds the limit from above, never from below."""
import math

import numpy as np
import pytest

from gyrofilter.analysis.still import SPREAD_BLOCKS, STATIC_LIMIT_MPS2, means_spread, moved


def vibrating(fs_hz, freq_hz, amplitude, *, seconds=120.0, turn=0.0, white=0.1, seed=0):
    """A still axis (white noise ``white``) under a vibration ``amplitude`` sin(2 pi f t) the whole record,
    with a 5-s turn at ``turn`` from 60 s (deg/s, or m/s^2 for an accelerometer)."""
    rng = np.random.default_rng(seed)
    n = int(fs_hz * seconds)
    x = white * rng.standard_normal(n) + amplitude * np.sin(2 * np.pi * freq_hz * np.arange(n) / fs_hz)
    x[int(60 * fs_hz):int(65 * fs_hz)] += turn
    return x


@pytest.mark.parametrize("fs_hz, freq_hz, amplitude, turn", [
    (100.0, 23.7, 10.0, 10.0),   # the attack's record: a 50-degree turn read still (limit 11.1 deg/s)
    (200.0, 81.0, 50.0, 30.0),   # 150 degrees under 50 deg/s at 81 Hz (limit 55.8 deg/s)
])
def test_a_turn_under_a_continuous_vibration_reads_as_motion(fs_hz, freq_hz, amplitude, turn):
    assert "does not look static" in moved(vibrating(fs_hz, freq_hz, amplitude, turn=turn), fs_hz)


@pytest.mark.parametrize("fs_hz, freq_hz, amplitude", [
    (100.0, 23.7, 10.0), (200.0, 81.0, 50.0), (100.0, 10.0, 10.0), (100.0, 49.0, 10.0)])
def test_a_still_record_under_the_same_vibration_reads_still(fs_hz, freq_hz, amplitude):
    """Without the turn the block means stay within a third of the limit (at f_s/10 the vibration
    averages out slowest: 1.47 deg/s against 8 sigma / sqrt(L) = 5.05, which holds there)."""
    assert moved(vibrating(fs_hz, freq_hz, amplitude), fs_hz) is None


def test_an_accelerometer_tilt_under_a_vibration_reads_as_motion():
    """The same function judges an accelerometer against 0.5 m/s^2: a 3 m/s^2 shift (an 18-degree tilt of
    a level axis) for 5 s under 5 m/s^2 at 23.7 Hz read still before (limit 5.5 m/s^2, now 2.5)."""
    accel = {"limit": STATIC_LIMIT_MPS2, "unit": "m/s^2", "what": "acceleration"}
    assert "does not look static" in moved(vibrating(100.0, 23.7, 5.0, turn=3.0, white=0.05), 100.0, **accel)
    assert moved(vibrating(100.0, 23.7, 5.0, white=0.05), 100.0, **accel) is None


def heavy_tailed(seed, n):
    """Still noise with 6 % of the samples at 30 times the others' (examples/models/heavy_tails.json's z
    axis, 100 Hz), a bias of -0.5 deg/s, in steps of 1/131 deg/s."""
    rng = np.random.default_rng(seed)
    x = 0.092 * rng.standard_normal(n) * np.where(rng.random(n) < 0.06, 30.0, 1.0)
    return np.round((x - 0.5) * 131) / 131


def test_heavy_tailed_noise_is_judged_by_its_spread_not_a_robust_one():
    """20 s: a robust scale (1.4826 MAD) of the block means' differences reads 0.1 deg/s where their sd
    reads 0.6, and its limit (1 deg/s) called such records moved in 100 of 100 seeds."""
    x = heavy_tailed(7, 2000)
    assert moved(x, 100.0) is None
    assert means_spread(x) == pytest.approx(np.std(np.diff(x)) / math.sqrt(2))


def test_the_block_means_scatter_tightens_the_limit_only_beyond_its_own_sampling_scatter():
    """7 s of heavy-tailed noise (blocks of 2): its s_y fell below the white prediction by chance and the
    record read moved (8 of 300 seeds more than without s_y), 0 with SPREAD_MARGIN."""
    assert moved(heavy_tailed(247, 700), 100.0) is None


def test_too_few_block_means_leave_the_white_level_alone():
    assert means_spread(np.arange(SPREAD_BLOCKS - 1.0)) == math.inf
    assert means_spread(np.r_[np.zeros(SPREAD_BLOCKS // 2), np.ones(SPREAD_BLOCKS // 2)]) < math.inf


def vibrating_short(fs_hz, seconds, freq_hz, turn, *, amplitude=20.0, seed=7):
    """The attack's records (pass 37n): white noise 0.05 deg/s, a bias of 0.2, ``amplitude`` sin(2 pi f t) the whole
    record and a 5-s turn at ``turn`` deg/s from its middle."""
    rng = np.random.default_rng(seed)
    n = int(fs_hz * seconds)
    x = 0.2 + 0.05 * rng.standard_normal(n) + amplitude * np.sin(2 * np.pi * freq_hz * np.arange(n) / fs_hz)
    x[n // 2:n // 2 + int(5 * fs_hz)] += turn
    return x


#: (f_s, seconds, vibration frequency, turn): each read still with the block means of L samples alone
SHORT_REPROS = [(100.0, 30.0, 12.4, 20.0), (50.0, 60.0, 10.0, 15.0), (1000.0, 20.0, 139.5, 10.0)]


@pytest.mark.parametrize("fs_hz, seconds, freq_hz, turn", SHORT_REPROS)
def test_a_turn_under_a_vibration_reads_as_motion_on_a_short_record(fs_hz, seconds, freq_hz, turn):
    """Short blocks keep much of the vibration in their means, and their own spread with it (L = 6 at 100 Hz
    over 30 s: 8 min(3.10, 5.82) = 24.8 deg/s against the turn's 24.5); the means of 16 blocks (0.96 s) judge
    it: 6.2 deg/s."""
    assert "does not look static" in moved(vibrating_short(fs_hz, seconds, freq_hz, turn), fs_hz)


@pytest.mark.parametrize("fs_hz, seconds, freq_hz, turn", SHORT_REPROS)
def test_a_short_still_record_under_the_same_vibration_reads_still(fs_hz, seconds, freq_hz, turn):
    assert moved(vibrating_short(fs_hz, seconds, freq_hz, 0.0), fs_hz) is None
