"""The Allan deviation of the still stretches that the live view shows, against the batch
non-overlapping Allan deviation (gyrofilter.analysis.noise.allan.adev) and a hand-pooled numpy sum."""
import numpy as np
import pytest

from gyrofilter.analysis.noise.allan import MIN_CLUSTERS, adev
from gyrofilter.view.still_allan import StillAllan

TAU0_S = 0.005
BIAS = np.array([-3.3, 1.2, -0.6])


def blocks(n, seed, start_s=0.0):
    """n still block means (deg/s) around BIAS with white noise and a slow wander, and their times."""
    rng = np.random.default_rng(seed)
    x = BIAS + 0.02 * rng.standard_normal((n, 3)) + np.cumsum(1e-4 * rng.standard_normal((n, 3)), axis=0)
    return start_s + TAU0_S * np.arange(1, n + 1), x


def feed(allan, t, x, seed):
    """Add (t, x) in random pieces, as the publisher drains them."""
    rng = np.random.default_rng(seed)
    i = 0
    while i < len(t):
        k = int(rng.integers(1, 60))
        allan.add(t[i : i + k], x[i : i + k], BIAS)
        i += k


def pooled(stretches, m):
    """sqrt(sum of squared differences of adjacent m-block cluster means over every stretch / (2 pairs))."""
    total, pairs = np.zeros(3), 0
    for x in stretches:
        k = len(x) // m
        means = x[: k * m].reshape(k, m, 3).mean(axis=1)
        d = np.diff(means, axis=0)
        total += (d * d).sum(axis=0)
        pairs += len(d)
    return np.sqrt(total / (2 * pairs)), pairs


def test_one_stretch_equals_the_non_overlapping_allan_deviation():
    t, x = blocks(3000, seed=1)
    allan = StillAllan(TAU0_S)
    feed(allan, t, x, seed=2)
    got = allan.result()
    taus = np.array(got["tau_s"])
    assert list(taus) == [TAU0_S * 2**k for k in range(len(taus))]
    assert got["pairs"] == [3000 // 2**k - 1 for k in range(len(taus))]
    assert min(got["pairs"]) >= MIN_CLUSTERS and 3000 // 2 ** len(taus) - 1 < MIN_CLUSTERS
    for axis in range(3):
        _, want = adev(x[:, axis], 1.0 / TAU0_S, taus)
        np.testing.assert_allclose(np.array(got["adev_dps"])[:, axis], want, rtol=1e-9)
    assert got["still_s"] == pytest.approx(3000 * TAU0_S)
    np.testing.assert_allclose(got["relative_error"], 1 / np.sqrt(2 * np.array(got["pairs"])))


def test_stretches_split_by_motion_and_by_lost_samples_are_pooled_not_joined():
    t1, x1 = blocks(700, seed=3)
    tm, xm = blocks(40, seed=4, start_s=t1[-1])
    xm[:, 1] += 30.0  # a turn: not still
    t2, x2 = blocks(900, seed=5, start_s=tm[-1])
    t3, x3 = blocks(500, seed=6, start_s=t2[-1] + 1.0)  # 1 s of samples lost before it
    allan = StillAllan(TAU0_S)
    feed(allan, np.concatenate([t1, tm, t2, t3]), np.concatenate([x1, xm, x2, x3]), seed=7)
    got = allan.result()
    for k, tau in enumerate(got["tau_s"]):
        want, pairs = pooled([x1, x2, x3], 2**k)
        assert got["pairs"][k] == pairs
        np.testing.assert_allclose(got["adev_dps"][k], want, rtol=1e-9)
    assert got["still_s"] == pytest.approx((700 + 900 + 500) * TAU0_S)
    # joined across the turn, the deviation at the short taus would be dominated by it
    assert max(got["adev_dps"][0]) < 0.1


def test_a_sensor_that_never_rests_has_no_figures():
    t, x = blocks(2000, seed=8)
    x[:, 2] += 5.0
    allan = StillAllan(TAU0_S)
    feed(allan, t, x, seed=9)
    assert allan.result() == {"tau_s": [], "adev_dps": [], "pairs": [], "relative_error": [], "still_s": 0.0}


def test_cut_ends_the_stretch():
    t, x = blocks(400, seed=10)
    allan = StillAllan(TAU0_S)
    allan.add(t[:200], x[:200], BIAS)
    allan.cut()
    allan.add(t[200:], x[200:], BIAS)
    want, pairs = pooled([x[:200], x[200:]], 1)
    assert allan.result()["pairs"][0] == pairs == 398
    np.testing.assert_allclose(allan.result()["adev_dps"][0], want, rtol=1e-9)
