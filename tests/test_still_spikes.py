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
