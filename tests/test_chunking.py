"""Live sources hand over a few samples per read: any chunking of the input, mixed with update()
calls, must give the rows of one filter() call over the whole array, bit for bit."""
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gyrofilter import GyroFilter
from gyrofilter.filter.presets import PRESETS

RATE_HZ = 100.0
N = 720  # 2 s of calibration + 520 samples: 104 blocks of 5


def _signal(seed, n=N):
    """Still for the calibration, then a turn, a vibration and spikes: every stage (rejection, the range-following
    q, fallback, hold) acts."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE_HZ
    x = 0.3 + 0.05 * rng.standard_normal((n, 3))
    moving = t > 3.0
    x[moving, 0] += 40 * np.sin(2 * np.pi * 0.7 * (t[moving] - 3.0))
    x[moving, 2] += 12.0 + 4 * np.sin(2 * np.pi * 19.0 * t[moving])  # a vibration: the range-following q acts
    spikes = (rng.random((n, 3)) < 0.03) & (t >= 2.0)[:, None]  # none in the calibration window, which must pass as still
    x[spikes] += rng.choice([-1, 1], spikes.sum()) * rng.uniform(2, 30, spikes.sum())
    temp = 25 + 0.5 * t / t[-1] + 0.01 * rng.standard_normal(n)
    return x, temp


CASES = [(name, {}) for name in PRESETS] + [
    ("paper", {"outlier_rule": "median_slope"}),
    ("recommended", {"outlier_rule": "median_slope"}),
    ("paper", {"temp_coefficient_dps_per_c": (0.02, -0.01, 0.005)}),
    ("recommended", {"temp_coefficient_dps_per_c": 0.03}),
    ("paper", {"block_len": 7, "qr_window": 0}),
    ("paper", {"outlier_range_k": 2.0, "outlier_range_blocks": 5}),
]


def _feed(filt, x, temp, plan):
    """Feed x in the pieces plan gives: ("filter", k) = a filter() call on k samples, ("update", k) = k update() calls."""
    rows, ends, i = [], [], 0
    for how, k in plan:
        k = min(k, len(x) - i)
        t = temp[i : i + k]  # always: without compensation the calibration keeps their mean
        if how == "filter":
            out = filt.filter(x[i : i + k], t)
            rows.extend(out)
            ends.extend(filt.block_end_indices(len(out)))
        else:
            for j in range(i, i + k):
                row = filt.update(tuple(x[j]), t[j - i])
                if row is not None:
                    rows.append(np.array(row))
                    ends.extend(filt.block_end_indices(1))
        i += k
    assert i == len(x), "the plan must feed every sample"
    return np.array(rows).reshape(-1, 3), np.array(ends)


pieces = st.lists(st.tuples(st.sampled_from(["filter", "filter", "update"]), st.integers(1, 23)), min_size=1, max_size=60)


@pytest.mark.parametrize("preset,extra", CASES, ids=[f"{p}-{'-'.join(e) or 'defaults'}" for p, e in CASES])
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(plan=pieces, seed=st.integers(0, 2**16))
def test_any_chunking_equals_one_call(preset, extra, plan, seed):
    x, temp = _signal(seed)
    whole = GyroFilter(RATE_HZ, preset=preset, **extra)
    expected = whole.filter(x, temp)
    assert len(expected) == (N - 200) // whole.settings.block_len
    # repeat the plan until every sample is fed
    plan = plan * (N // sum(k for _, k in plan) + 1)
    chunked = GyroFilter(RATE_HZ, preset=preset, **extra)
    got, ends = _feed(chunked, x, temp, plan)
    np.testing.assert_array_equal(got, expected)
    # each row's last input sample: calibration (200), then blocks of block_len
    length = whole.settings.block_len
    np.testing.assert_array_equal(ends, 200 + length * np.arange(len(expected)) + length - 1)
    np.testing.assert_array_equal(whole.block_end_indices(len(expected)), ends)
    assert chunked.samples_in == whole.samples_in == N
    assert chunked.pending_samples == whole.pending_samples
    assert chunked.rejected.tolist() == whole.rejected.tolist()
    assert chunked.calibration.temp_c == whole.calibration.temp_c == pytest.approx(temp[:200].mean())


@pytest.mark.parametrize("size", [1, 2, 3, 4, 6, 7, 12, 13])
def test_fixed_small_reads_lose_nothing(size):
    """The live case: a source delivering `size` samples per read (2 per read = MPU6050 at 100 Hz)."""
    x, _ = _signal(7, n=3000)
    expected = GyroFilter(RATE_HZ, preset="paper").filter(x)
    f = GyroFilter(RATE_HZ, preset="paper")
    got = np.concatenate([f.filter(x[i : i + size]) for i in range(0, len(x), size)])
    assert len(got) == (3000 - 200) // 5
    np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("bad", [np.array([["a", "b", "c"]] * 10), [["1", "2", "3"]] * 10,
                                 np.zeros((10, 3), dtype=object), np.zeros((10, 3), dtype=bool)])
def test_filter_takes_numbers_only_as_update_does(bad):
    f = GyroFilter(RATE_HZ)
    with pytest.raises(ValueError, match="must be numbers in deg/s"):
        f.filter(bad)
    assert f.samples_in == 0


def test_bad_sample_changes_nothing():
    """A NaN, None or a wrong shape passed to update() raises and leaves the filter as it was."""
    x, _ = _signal(3)
    good = GyroFilter(RATE_HZ, preset="paper")
    bad = GyroFilter(RATE_HZ, preset="paper")
    rows_good, rows_bad = [], []
    for i, sample in enumerate(x):
        if i in (5, 150, 203, 400):  # while calibrating, mid-block and at a block start after it
            for wrong in ((np.nan, 0.0, 0.0), None, ("a", 0, 0), np.zeros((3, 1)), (1.0, 2.0), (0.0, np.inf, 0.0)):
                with pytest.raises(ValueError, match="3 finite numbers"):
                    bad.update(wrong)
        rows_good.append(good.update(tuple(sample)))
        rows_bad.append(bad.update(tuple(sample)))
    assert rows_bad == rows_good
    assert all(np.isfinite(good.bias_dps)) and bad.bias_dps == good.bias_dps


@pytest.mark.parametrize("size", [1, 3, 5, 7, 64, N])
def test_filter_timed_stamps_each_row_with_its_blocks_last_sample(size):
    """t of row k = t of input sample 200 + (k + 1) L - 1, whatever the chunking (uneven times, so
    an off-by-one sample shows)."""
    x, _ = _signal(3)
    t_s = np.cumsum(np.linspace(0.009, 0.011, N))
    f = GyroFilter(RATE_HZ, preset="paper")
    assert f.first_block_index is None
    got_t, got = [], []
    for i in range(0, N, size):
        t_rows, rows = f.filter_timed(x[i : i + size], t_s[i : i + size])
        assert len(t_rows) == len(rows)
        got_t.extend(t_rows)
        got.extend(rows)
    np.testing.assert_array_equal(np.array(got), GyroFilter(RATE_HZ, preset="paper").filter(x))
    np.testing.assert_array_equal(got_t, t_s[200 + 5 * np.arange(len(got)) + 4])
    assert f.first_block_index == 200


def test_first_block_index_follows_a_calibration_retry():
    """A first window that moved is refused: the blocks start after the second window (400)."""
    x = 0.3 + 0.05 * np.random.default_rng(5).standard_normal((1000, 3))
    x[50:80] += 50.0  # a jolt in the first calibration window (0.3 s: beyond the 10 % of gross errors it leaves out)
    f = GyroFilter(RATE_HZ, preset="paper", calibration_retry_s=4.0)
    rows = f.filter(x[:700])
    assert f.first_block_index == 400 and len(rows) == 60
    np.testing.assert_array_equal(f.block_end_indices(len(rows)), 400 + 5 * np.arange(60) + 4)


@pytest.mark.parametrize("n_rows", [61, 10**6, -1, 2.5, True, "3", None])
def test_block_end_indices_takes_only_a_whole_number_up_to_the_rows_output(n_rows):
    """It invented rows before the first (10**6 gave negative indices) and took 2.5, True and -1
    (issue 22, hostile case 1-6): only 0 <= n_rows <= blocks_out is answered."""
    from gyrofilter.errors import SettingsError

    f = GyroFilter(RATE_HZ, preset="paper")
    rows = f.filter(0.3 + 0.05 * np.random.default_rng(2).standard_normal((500, 3)))
    assert len(rows) == f.blocks_out == 60
    with pytest.raises(SettingsError, match=r"n_rows of block_end_indices .* must be (in \[0, 60\]|a)"):
        f.block_end_indices(n_rows)
    assert f.block_end_indices(np.int64(60))[0] == 200 + 4 and f.block_end_indices(0).size == 0


def test_filter_timed_refuses_times_of_another_length_before_filtering():
    x, _ = _signal(1)
    f = GyroFilter(RATE_HZ)
    with pytest.raises(ValueError, match=r"t_s must have shape \(720,\)"):
        f.filter_timed(x, np.arange(719.0))
    assert f.samples_in == 0
