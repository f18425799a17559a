"""The state the run loop feeds and the live view reads: raw block means, the history kept, the
counters, and an inbox that drops (and counts) what the view could not keep up with."""
import numpy as np
import pytest

from gyrofilter.view import state as state_module
from gyrofilter.view.sink import RunInfo, Step
from gyrofilter.view.state import HISTORY_S, LiveState

RATE_HZ = 100.0
BLOCK = 5
INFO = RunInfo(source="sim", sample_rate_hz=RATE_HZ, block_len=BLOCK, output_rate_hz=RATE_HZ / BLOCK, preset="paper")


def steps(n_samples, seed, chunk_max=23, bias=(0.5, -0.2, 0.1)):
    """The steps a run loop would hand over for n_samples samples read in seeded pieces; the filtered
    rows are stand-ins (the block means minus the bias), the counters the running totals."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_samples) / RATE_HZ
    x = np.array(bias) + 0.05 * rng.standard_normal((n_samples, 3))
    temp = 25.0 + 0.001 * np.arange(n_samples)
    out, i = [], 0
    while i < n_samples:
        k = int(rng.integers(0, chunk_max))
        j = min(n_samples, i + k)
        ends = np.arange(i, j)[(np.arange(i, j) + 1) % BLOCK == 0]
        rows = np.array([x[e - BLOCK + 1 : e + 1].mean(axis=0) - bias for e in ends]).reshape(-1, 3)
        out.append(Step(t_s=t[i:j], gyro_dps=x[i:j], temp_c=temp[i:j], rows_t_s=t[ends], rows_dps=rows,
                        samples_in=j, rows_out=(j // BLOCK), lost_samples=0, rejected_outliers=(1, 0, 2),
                        calibration="calibrated", bias_dps=bias))
        i = j
    return t, x, out


def test_raw_block_means_rows_and_counters():
    t, x, fed = steps(1003, seed=1)
    state = LiveState()
    state.start(INFO)
    got_rows, got_raw = [], []
    for k, step in enumerate(fed):
        state.feed(step)
        if k % 7 == 0:
            rows, raw = state.drain()
            got_rows.append(rows)
            got_raw.append(raw)
    rows, raw = state.drain()
    rows, raw = np.concatenate(got_rows + [rows]), np.concatenate(got_raw + [raw])
    means = x[:1000].reshape(200, BLOCK, 3).mean(axis=1)
    np.testing.assert_allclose(raw[:, 1:], means, rtol=1e-12)
    np.testing.assert_array_equal(raw[:, 0], t[BLOCK - 1 :: BLOCK][:200])
    np.testing.assert_allclose(rows[:, 1:], means - (0.5, -0.2, 0.1), rtol=1e-12, atol=1e-15)
    status = state.status()
    assert status["samples_in"] == 1003 and status["rows_out"] == 200 and status["rejected_outliers"] == [1, 0, 2]
    assert status["calibration"] == "calibrated" and status["bias_dps"] == [0.5, -0.2, 0.1]
    assert status["temp_c"] == pytest.approx(25.0 + 0.001 * 1002) and status["t_s"] == pytest.approx(10.02)
    assert status["allan"]["pairs"][0] == 199 and status["view_dropped_reads"] == 0


def test_history_keeps_the_last_60_seconds():
    _, _, fed = steps(int(90 * RATE_HZ), seed=2, chunk_max=200)
    state = LiveState()
    state.start(INFO)
    for step in fed:
        state.feed(step)
        state.drain()
    history = state.history()
    t_rows = [r[0] for r in history["rows"]]
    t_raw = [r[0] for r in history["raw"]]
    assert t_rows == t_raw and len(t_rows) == HISTORY_S * RATE_HZ / BLOCK
    assert t_rows[-1] == pytest.approx(89.99) and t_rows[0] > t_rows[-1] - HISTORY_S


def test_a_view_that_falls_behind_drops_whole_reads_and_counts_them(monkeypatch):
    monkeypatch.setattr(state_module, "INBOX_STEPS", 10)
    _, _, fed = steps(600, seed=3)
    state = LiveState()
    state.start(INFO)
    for step in fed:  # the publisher never ran
        state.feed(step)
    rows, raw = state.drain()
    kept = fed[-10:]
    assert state.inbox_dropped == len(fed) - 10 == state.status()["view_dropped_reads"]
    np.testing.assert_array_equal(rows[:, 0], np.concatenate([s.rows_t_s for s in kept]))
    assert state.status()["samples_in"] == 600
    # no block mean mixes samples from before and after the lost reads
    assert len(raw) == sum(len(s.t_s) for s in kept) // BLOCK


def test_the_inbox_holds_a_bounded_number_of_samples(monkeypatch):
    monkeypatch.setattr(state_module, "INBOX_SAMPLES", 100)
    _, _, fed = steps(600, seed=5)
    state = LiveState()
    state.start(INFO)
    for step in fed:
        state.feed(step)
    state.drain()
    status = state.status()
    kept = len(fed) - state.inbox_dropped
    assert 0 < kept < len(fed) and sum(len(s.t_s) for s in fed[-kept:]) <= 100 < sum(len(s.t_s) for s in fed[-kept - 1 :])
    assert status["samples_in"] == 600


def test_the_state_keeps_copies_of_what_it_is_fed():
    _, _, fed = steps(50, seed=4)
    state = LiveState()
    state.start(INFO)
    step = fed[0]
    state.feed(step)
    step.gyro_dps[:] = 1e9  # the run loop reuses its buffer
    step.rows_dps[:] = 1e9
    rows, raw = state.drain()
    assert np.all(np.abs(raw[:, 1:]) < 10) and np.all(np.abs(rows[:, 1:]) < 10)
