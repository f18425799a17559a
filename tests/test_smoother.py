"""The forward-backward smoother (gyrofilter.filter.smoother) and ``gyrofilter replay --smooth``."""
import numpy as np
import pytest

from gyrofilter import GyroFilter
from gyrofilter.errors import SettingsError
from gyrofilter.sim.profiles import get_profile
from gyrofilter.recording import read_recording
from gyrofilter.filter import smoother
from gyrofilter.filter.smoother import Smoother, combine, smooth

FS = 100.0
CAL = 200  # 2 s of calibration at 100 Hz
SIGMA = 0.05


def still(n, seed, sigma=SIGMA):
    return np.random.default_rng(seed).normal(0.0, sigma, (n, 3))


def block_means(x):
    return GyroFilter(FS, preset="paper", tracker="block_mean").filter(x)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_at_rest_every_block_gets_the_mean_of_the_whole_rest_phase(seed):
    # forward: running mean from P = R / n0 (n0 = 40 calibration blocks of 0); backward: the LS
    # model for 20 blocks, then the mean of the latest 10 of those 20 (hold.recent_mean) and a
    # running mean. Their combination is the mean of the n0 zeros and every block mean but the
    # last 10 (the backward filter's first), wherever the backward filter is at rest
    m = 300
    x = still(CAL + 5 * m, seed)
    n0 = CAL // 5
    out = smooth(x, FS, backend="python")
    y = block_means(x)
    expected = y[: m - 10].sum(axis=0) / (n0 + m - 10)
    np.testing.assert_allclose(out[: m - 20], np.broadcast_to(expected, (m - 20, 3)), rtol=0, atol=1e-12)


def test_chunks_and_backends_give_the_same_smoothed_rows(monkeypatch):
    rng = np.random.default_rng(7)
    t = np.arange(CAL + 5 * 400) / FS
    x = still(len(t), 8) + get_profile("paper001").rate_dps(t * 4)[:, None]
    whole = smooth(x, FS, backend="python")
    f = GyroFilter(FS, backend="auto")
    s = Smoother(f)
    i = 0
    while i < len(x):
        n = int(rng.integers(1, 40))
        if n == 1:
            f.update(x[i])
        else:
            f.filter(x[i : i + n])
        i += n
    np.testing.assert_allclose(s.smooth(), whole, rtol=0, atol=1e-12)
    assert len(whole) == (len(x) - CAL) // 5
    # the backward pass in chunks of any size: the same numbers
    monkeypatch.setattr(smoother, "BACKWARD_CHUNK", 7)
    np.testing.assert_array_equal(smooth(x, FS, backend="python"), whole)


def test_the_smoother_is_closer_to_the_truth_than_the_real_time_filter():
    # paper 001's profile (rest, ramps, steady turns, a slow sine) on white noise, 8 seeds pooled:
    # where the rate is constant the smoother averages the whole phase, the real-time filter only
    # its past; in motion both follow the block means
    profile = get_profile("paper001")
    t = np.arange(CAL + int(profile.duration_s * FS)) / FS
    truth = profile.rate_dps(t - CAL / FS)
    blocks = truth[CAL : CAL + 5 * ((len(t) - CAL) // 5)].reshape(-1, 5)
    constant = np.ptp(blocks, axis=1) == 0
    constant = constant & np.roll(constant, 20) & np.roll(constant, -20)  # a second from every change
    assert constant.sum() > 600
    sq_rt, sq_s = [], []
    for seed in range(8):
        x = still(len(t), 100 + seed, sigma=0.1) + truth[:, None]
        # the error of the start-up bias (the calibration's mean of the noise) is common to both: left out
        target = blocks.mean(axis=1)[:, None] - x[:CAL].mean(axis=0)
        sq_rt.append((GyroFilter(FS).filter(x) - target) ** 2)
        sq_s.append((smooth(x, FS) - target) ** 2)
    sq_rt, sq_s = np.array(sq_rt), np.array(sq_s)
    ratio_constant = np.sqrt(sq_s[:, constant].mean() / sq_rt[:, constant].mean())
    assert ratio_constant < 0.6
    assert np.all(sq_s.mean(axis=(0, 1)) < sq_rt.mean(axis=(0, 1)))


@pytest.mark.parametrize("seed", [1, 2])
def test_a_filter_fed_sample_by_sample_smooths_as_one_call(seed):
    # fast motion with spikes: the rule by model uses both gross-error rules, and the backward
    # pass needs both rules' block means whichever the forward filter took
    rng = np.random.default_rng(seed)
    t = np.arange(CAL + 5 * 600) / FS
    x = still(len(t), seed) + np.where(t > 3, 60 * np.sin(2 * np.pi * 1.3 * t), 0.0)[:, None]
    spikes = rng.random(x.shape) < 0.02
    x[spikes] += rng.choice([-1, 1], spikes.sum()) * rng.uniform(2, 20, spikes.sum())
    whole = smooth(x, FS, backend="python")
    f = GyroFilter(FS, backend="python")
    s = Smoother(f)
    rows = [f.update(sample) for sample in x]
    np.testing.assert_array_equal(np.array([r for r in rows if r is not None]), GyroFilter(FS, backend="python").filter(x))
    np.testing.assert_array_equal(s.smooth(), whole)


def test_a_filter_fed_block_by_block_logs_a_block_in_about_the_documented_memory():
    """Attack pass 25: the log kept four small arrays per kernel call, so a filter fed by update()
    (one call per block, a live source) held about 640 bytes per block and one fed by filter() in
    5-sample reads about 1700, against the 12 floats (96 bytes) of the module docstring: a day at
    100 Hz would have taken 1-3 GB, not 0.17."""
    import tracemalloc
    rng = np.random.default_rng(0)
    x = 0.05 * rng.standard_normal((210 + 5 * 2000, 3))
    f = GyroFilter(100.0)
    s = Smoother(f)
    for row in x[:210]:  # the calibration and two blocks: a kernel compiled by numba, once
        f.update(row)
    tracemalloc.start()
    try:
        for row in x[210:]:
            f.update(row)
        held, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert f.blocks_out == 2002 and held / 2000 < 2 * 96
    np.testing.assert_array_equal(s.smooth(), smooth(x, 100.0))


def test_combine_is_the_inverse_variance_mean():
    np.testing.assert_allclose(combine(np.array([1.0]), np.array([1.0]), np.array([3.0]), np.array([3.0])), [1.5])
    np.testing.assert_allclose(combine(np.array([2.0]), np.array([0.5]), np.array([-4.0]), np.array([0.5])), [-1.0])


def test_the_smoother_needs_the_adaptive_kalman_filter_attached_from_the_start():
    for preset in ("paper", "hold"):
        with pytest.raises(SettingsError, match="adaptive Kalman filter"):
            Smoother(GyroFilter(FS, preset=preset))
    f = GyroFilter(FS)
    f.filter(still(CAL + 10, 1))
    with pytest.raises(SettingsError, match="before the filter's first block; this filter has produced 2"):
        Smoother(f)
    f = GyroFilter(FS)
    assert Smoother(f).smooth().shape == (0, 3)
    with pytest.raises(SettingsError, match="already has a Smoother"):
        Smoother(f)
    with pytest.raises(SettingsError, match="needs a GyroFilter, got str"):
        Smoother("abc")


def test_replay_smooth_writes_the_smoothed_rows_with_the_real_time_rows_times(tmp_path, capsys):
    from gyrofilter.cli import main
    from gyrofilter.recording import Recording, write_recording

    x = still(CAL + 5 * 123 + 3, 5)
    x[CAL + 5 * 60 :, 2] += 10.0
    path = tmp_path / "in.csv"
    write_recording(path, Recording({"gx": x[:, 0], "gy": x[:, 1], "gz": x[:, 2]},
                                    {"sample_rate_hz": "100", "gyro_unit": "dps", "sensor": "test"}))
    assert main(["replay", str(path), "--out", str(tmp_path / "rt.csv")]) == 0
    assert main(["replay", str(path), "--smooth", "--out", str(tmp_path / "sm.csv")]) == 0
    text = capsys.readouterr().out
    assert "preset recommended, smoothed forward-backward, 123 output rows" in text
    rt, sm = read_recording(tmp_path / "rt.csv"), read_recording(tmp_path / "sm.csv")
    np.testing.assert_array_equal(sm.columns["t"], rt.columns["t"])
    np.testing.assert_allclose(sm.gyro_dps, smooth(x, FS), rtol=1e-8, atol=1e-9)  # 9 significant digits
    assert sm.header["smoothed"].startswith("forward-backward")
    assert main(["replay", str(path), "--smooth", "--realtime"]) == 2
    assert "cannot run with --realtime" in capsys.readouterr().err
