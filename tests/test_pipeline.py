import os
import re
import tracemalloc

import numpy as np
import pytest

from gyrofilter import GyroFilter
from gyrofilter.filter.calibration import Calibration
from gyrofilter.errors import CalibrationError, SampleError, SettingsError
from gyrofilter.filter.jit import numba_available
from support.plain_filter import plain_filter
from support import stream

BACKENDS = ["python"] + (["numba"] if numba_available() else [])


def noisy(n, seed=0, bias=(1.5, -0.7, 3.0), sigma=0.1, spikes=0.0):
    rng = np.random.default_rng(seed)
    x = np.asarray(bias) + rng.normal(0, sigma, (n, 3))
    if spikes:
        hit = rng.random((n, 3)) < spikes
        x[hit] += rng.choice([-2.5, 2.5], hit.sum())
    return x


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(
    "settings",
    [{}, {"qr_stat": "std"}, {"qr_window": 0}, {"r_source": "calibration", "fit_order": 1}, {"block_len": 3, "fifo_depth": 4},
     {"preset": "recommended"}, {"hold": True}, {"preset": "adaptive_kalman"}, {"guard_blocks": 2}],
)
def test_update_and_filter_give_the_same_numbers(backend, settings):
    x = noisy(3000, spikes=0.02)
    x[1500:2200] += np.linspace(0, 30, 700)[:, None]  # motion: the hold stage switches
    settings = {"preset": "paper", **settings}
    a = stream(GyroFilter(100.0, backend=backend, **settings), x)
    b = GyroFilter(100.0, backend=backend, **settings).filter(x)
    assert a.shape == b.shape
    assert np.array_equal(a, b)


@pytest.mark.parametrize("preset", ["paper", "recommended", "adaptive_kalman"])
def test_mixed_calls_continue_the_same_state(preset):
    x = noisy(4000, seed=2, spikes=0.01)
    whole = GyroFilter(100.0, preset=preset).filter(x)
    f = GyroFilter(100.0, preset=preset)
    parts = [f.filter(x[:150]), stream(f, x[150:1003]), f.filter(x[1003:2999]), stream(f, x[2999:3001]), f.filter(x[3001:])]
    assert np.array_equal(np.concatenate(parts), whole)


@pytest.mark.skipif(len(BACKENDS) < 2, reason="numba not installed")
@pytest.mark.parametrize("preset", ["paper", "recommended", "adaptive_kalman"])
def test_numba_and_python_backends_agree_bit_for_bit(preset):
    x = noisy(5000, seed=4, spikes=0.02)
    x[2000:2500] += 15.0
    python = GyroFilter(100.0, preset=preset, backend="python").filter(x)
    assert np.array_equal(python, GyroFilter(100.0, preset=preset, backend="numba").filter(x))


def test_recommended_holds_at_rest_and_follows_a_step_within_a_block():
    x = noisy(12000, seed=11)
    x[8000:] += 10.0  # a step to 10 deg/s at block (8000 - 200) / 5 = 1560
    f = GyroFilter(100.0, preset="recommended")
    out = f.filter(x)
    paper = GyroFilter(100.0, preset="paper").filter(x)
    rest = slice(100, 1500)
    assert np.all(out[rest].std(axis=0) < paper[rest].std(axis=0) / 3)
    np.testing.assert_allclose(out[1560:1565], 10.0, atol=0.2)  # from the step's own block on (a step > 3 q: no clip)
    np.testing.assert_allclose(out[1700:].mean(axis=0), 10.0, atol=0.02)


@pytest.mark.parametrize("backend", BACKENDS)
def test_one_block_with_two_gross_errors_does_not_knock_the_default_out_of_rest(backend):
    x = noisy(6000, seed=5, sigma=0.05)  # sigma_b = 0.022 deg/s
    # two 1.6-deg/s spikes in block (3000 - 200) / 5 = 560: each is 0.96 deg/s from the block's mean, within
    # q = 1, so paper 001's rule keeps both and the block mean is 0.64 deg/s (29 sigma_b) off
    x[3001] += 1.6
    x[3003] += 1.6
    out = GyroFilter(100.0, backend=backend).filter(x)
    rest_mean = out[400:550].mean(axis=0)
    # out of rest the output would follow the block means for 20 blocks, 0.64 deg/s off at block 560
    assert np.abs(out[550:700] - rest_mean).max() < 0.01


def test_hold_needs_a_calibration():
    with pytest.raises(SettingsError, match="hold=True"):
        GyroFilter(100.0, preset="paper", calibration_s=0, hold=True)


@pytest.mark.parametrize("preset", ["recommended", "adaptive_kalman"])
def test_the_adaptive_filter_needs_a_calibration_and_works_with_a_loaded_one(preset):
    with pytest.raises(SettingsError, match="kalman_noise='adaptive' needs a start-up calibration"):
        GyroFilter(100.0, preset=preset, calibration_s=0)
    still = noisy(1200, seed=4)
    first = GyroFilter(100.0, preset=preset)
    first.filter(still[:200])
    # a loaded calibration with calibration_s=0 is refused since issue 22 (it has nothing to do): none given
    assert GyroFilter(100.0, preset=preset, calibration=first.calibration).filter(still[200:]).shape == (200, 3)


@pytest.mark.parametrize("calibration_s", [1e308, 3600.5, float("inf")])
def test_an_impossible_calibration_window_is_a_settings_error(calibration_s):
    with pytest.raises(SettingsError, match="calibration_s"):
        GyroFilter(1000.0, calibration_s=calibration_s)


@pytest.mark.parametrize("settings", [{}, {"qr_stat": "std"}])
def test_equals_the_plain_filterpy_and_polyfit_implementation(settings):
    x = noisy(1500, seed=5, spikes=0.02)
    x[700:1500:97, 1] += 40.0  # spikes beyond L*q: the median fallback
    ours = GyroFilter(100.0, preset="paper", **settings).filter(x)
    plain = plain_filter(x, 100.0, use_std=settings.get("qr_stat") == "std")
    np.testing.assert_allclose(ours, plain, rtol=1e-9, atol=1e-9)


def test_output_count_bias_and_rate():
    x = noisy(1234)
    f = GyroFilter(sample_rate_hz=100.0, preset="paper", calibration_s=2.0)
    out = f.filter(x)
    assert out.shape == ((1234 - 200) // 5, 3)
    assert f.pending_samples == (1234 - 200) % 5
    np.testing.assert_allclose(f.bias_dps, x[:200].mean(axis=0))
    assert f.output_rate_hz == 20.0


def test_still_noise_is_reduced_and_a_constant_rate_is_tracked():
    x = noisy(20000, seed=7)
    out = GyroFilter(100.0, preset="paper").filter(x)
    assert np.all(out[50:].std(axis=0) < 0.1 / 2.5)
    moving = x.copy()
    moving[2000:] += 20.0
    f = GyroFilter(100.0, preset="paper")
    out = f.filter(moving)
    expected = moving[2000 + 2500 :].mean(axis=0) - f.bias_dps
    np.testing.assert_allclose(out[500:].mean(axis=0), expected, atol=0.003)
    np.testing.assert_allclose(expected, 20.0, atol=0.05)


def test_gross_errors_are_rejected_and_counted():
    x = noisy(5200, seed=8)
    x[1000, 1] += 50.0
    f = GyroFilter(100.0, preset="paper")
    out = f.filter(x)
    assert f.rejected.tolist() == [0, 1, 0]
    assert np.abs(out[:, 1]).max() < 0.2


def test_calibration_refuses_a_moving_sensor_and_retries_when_asked():
    x = noisy(3000, seed=9)
    x[50:120, 0] += 5.0  # moved during the first window
    with pytest.raises(CalibrationError):
        GyroFilter(100.0, preset="paper").filter(x)
    f = GyroFilter(100.0, preset="paper", calibration_retry_s=4.0)
    out = f.filter(x)
    np.testing.assert_allclose(f.bias_dps, x[200:400].mean(axis=0))
    assert len(out) == (3000 - 400) // 5
    with pytest.raises(CalibrationError):
        stream(GyroFilter(100.0, preset="paper"), x)


def test_saved_calibration_skips_the_start_up_window(tmp_path):
    x = noisy(2000, seed=10)
    f = GyroFilter(100.0, preset="paper")
    f.filter(x)
    f.calibration.save(tmp_path / "cal.json")
    g = GyroFilter(100.0, preset="paper", calibration=tmp_path / "cal.json")
    assert g.bias_dps == f.bias_dps and not g.calibrating
    assert len(g.filter(x)) == 2000 // 5
    assert GyroFilter(100.0, preset="paper", calibration=Calibration.load(tmp_path / "cal.json")).bias_dps == f.bias_dps


@pytest.mark.parametrize("bad", [2, True, 2.5, b"cal.json", {"bias_dps": [0, 0, 0]}, ["cal.json"]])
def test_calibration_is_a_calibration_or_a_path_and_nothing_else(tmp_path, bad):
    """An int was read as a file descriptor and closed (calibration=2 closed stderr), a dict raised
    TypeError (issue 22, hostile cases 2-1 and 3-4): SettingsError naming the type, no fd touched."""
    with pytest.raises(SettingsError, match=rf"calibration must be a Calibration or the path of a saved one .*got {type(bad).__name__}"):
        GyroFilter(100.0, calibration=bad)
    os.fstat(2)  # stderr is still open


@pytest.mark.parametrize("calibration_s", [0, 2.0])
def test_a_loaded_calibration_with_a_calibration_window_is_refused(tmp_path, calibration_s):
    """The CLI refused --calibration with --calibration-s; the library took both (hostile kind 5)."""
    f = GyroFilter(100.0, preset="paper")
    f.filter(noisy(400, seed=3))
    f.calibration.save(tmp_path / "cal.json")
    for given, shown in ((tmp_path / "cal.json", f"calibration {tmp_path / 'cal.json'}"), (f.calibration, "the calibration")):
        with pytest.raises(SettingsError, match=rf"^{re.escape(shown)} replaces the start-up calibration, so a calibration "
                                                rf"window \(calibration_s={calibration_s:g}(\.0)?\) has nothing to do; give one of them"):
            GyroFilter(100.0, calibration_s, preset="paper", calibration=given)
    assert GyroFilter(100.0, preset="paper", calibration=str(tmp_path / "cal.json")).bias_dps == f.bias_dps


def test_state_does_not_grow_with_time():
    f = GyroFilter(100.0, preset="paper", backend="python")
    for sample in noisy(2000).tolist():
        f.update(tuple(sample))
    sample = (0.1, 0.2, 0.3)
    tracemalloc.start()
    before = tracemalloc.take_snapshot()
    for _ in range(5000):
        f.update(sample)
    after = tracemalloc.take_snapshot()
    tracemalloc.stop()
    grown = sum(s.size_diff for s in after.compare_to(before, "filename") if "gyrofilter" in str(s.traceback))
    assert grown < 4096


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"block_len": 0}, "block_len"),
        ({"outlier_q_dps": -1}, "outlier_q_dps"),
        ({"qr_window": 1}, "qr_window"),
        ({"qr_stat": "sigma"}, "qr_stat"),
        ({"fifo_depth": 2.5}, "fifo_depth"),
        ({"calibration_s": float("nan")}, "calibration_s"),
        ({"bogus": 1}, "unknown setting"),
        ({"blok_len": 5}, r"unknown setting\(s\) blok_len; did you mean block_len\?; known: "),  # issue 38: as --set does
        ({"preset": "best"}, "unknown preset"),
        ({"kalman_noise": "sage"}, "kalman_noise"),
        ({"kalman_noise": "adaptive", "gain_min": 0.3}, "unstable .*1.009.* stable above 0.335"),
        ({"kalman_noise": "adaptive", "gain_min": 1.5}, "gain_min"),
        ({"innovation_forgetting": 0}, "innovation_forgetting"),
        ({"prior_var_max_r": -1}, "prior_var_max_r"),
        ({"guard_blocks": -1}, "guard_blocks"),
        ({"guard_k_sigma": 0}, "guard_k_sigma"),
    ],
)
def test_bad_settings_are_refused_at_construction(kwargs, match):
    with pytest.raises(SettingsError, match=match):
        GyroFilter(100.0, **{"preset": "paper", **kwargs})
    with pytest.raises(SettingsError, match="sample_rate_hz"):
        GyroFilter(0.0)


def test_bad_samples_name_the_problem():
    f = GyroFilter(100.0, preset="paper", calibration_s=0)
    with pytest.raises(SettingsError, match="shape"):
        f.filter(np.zeros((10, 2)))
    x = noisy(20)
    x[7, 2] = np.nan
    with pytest.raises(SettingsError, match="row 7"):
        f.filter(x)
    for s in x[:7].tolist():
        f.update(tuple(s))
    with pytest.raises(SettingsError, match="finite"):
        for s in x[7:12].tolist():
            f.update(tuple(s))
    for bad in [(1.0, 2.0), 3.0, (1, 2, 3, 4)]:
        with pytest.raises(SettingsError, match="one sample"):
            f.update(bad)


# ---------------------------------------------------------------------------------- issue 22 (part C)


@pytest.mark.parametrize("seed", range(3))
def test_a_row_beyond_the_rates_any_gyro_reads_raises_with_the_rows_before_it(seed):
    """Attack pass 68: the paper's filter on a fast oscillation (300 to 3000 deg/s, 5 to 24 Hz at 100 Hz) grew past
    +-100000 deg/s within minutes and then gave NaN rows, with no error: stdout, --realtime and UDP passed them on
    (exit 0). update(), filter() and filter_timed() now raise FilterDiverged once they have taken the call's samples,
    with the call's good rows before the first bad one and that row's block's last sample: the same, whatever the
    chunking. The default preset follows the same motion within range (it never diverges in motion)."""
    from gyrofilter.errors import FilterDiverged
    from gyrofilter.units import MAX_RATE_DPS

    rng = np.random.default_rng(seed)
    n = 40000
    amp, w = rng.uniform(300, 3000), rng.uniform(0.3, 1.5)
    x = rng.normal(0, 0.1, (n, 3))
    x[300:] += amp * np.sin(w * np.arange(n - 300))[:, None]
    default = GyroFilter(100.0).filter(x)
    assert np.all(np.abs(default) <= MAX_RATE_DPS)
    with pytest.raises(FilterDiverged) as whole:
        GyroFilter(100.0, preset="paper").filter(x)
    rows, sample = whole.value.rows, whole.value.sample
    assert len(rows) > 100 and np.all(np.abs(rows) <= MAX_RATE_DPS)
    assert f"sample {sample}: the filter's output left the rates any gyro reads: its row {len(rows)} has g" in str(whole.value)
    f, got, at = GyroFilter(100.0, preset="paper"), [], 0
    t = np.arange(n) / 100.0
    with pytest.raises(FilterDiverged) as chunked:
        while True:
            size = int(rng.integers(1, 2000))
            got.append(f.filter_timed(x[at:at + size], t[at:at + size])[1])
            at += size
    got.append(chunked.value.rows)
    np.testing.assert_array_equal(np.concatenate(got), rows)
    assert chunked.value.sample == sample and f.samples_in == at + min(size, n - at)  # the call's samples taken
    ends = sample - f.settings.block_len * np.arange(len(chunked.value.rows), 0, -1)  # its good rows' blocks
    np.testing.assert_array_equal(chunked.value.t_rows_s, t[ends])
    g, one = GyroFilter(100.0, preset="paper"), []
    with pytest.raises(FilterDiverged) as single:
        for s in x.tolist():
            r = g.update(s)
            if r is not None:
                one.append(r)
    np.testing.assert_array_equal(np.array(one), rows)
    assert single.value.sample == sample == g.samples_in - 1 and len(single.value.rows) == 0


def test_a_sample_beyond_max_rate_is_refused_before_it_poisons_the_filter():
    """A finite but absurd sample (1e300 deg/s) used to reach the Kalman filter's squares: a block of
    them made every later row NaN/inf. Now update() and filter() refuse it, naming it (filter: its
    row), and the filter goes on as if it had never been sent."""
    from gyrofilter.errors import SampleError
    from gyrofilter.units import MAX_RATE_DPS

    x = noisy(1000)
    for preset in ("paper", "recommended"):
        bad = x.copy()
        bad[600:605] = 1e300  # a whole block of them: the averaging stage's median cannot hide it
        f = GyroFilter(100.0, preset=preset)
        with pytest.raises(SampleError, match=r"samples_dps row 600: gx \(deg/s\) must be in \[-100000, 100000\], got 1e\+300") as info:
            f.filter(bad)
        assert info.value.row == 600 and f.samples_in == 0
        g = GyroFilter(100.0, preset=preset)
        rows = [g.update(tuple(s)) for s in x[:600].tolist()]
        for sample in ((1e300, 0.0, 0.0), (0.0, -MAX_RATE_DPS * 1.0001, 0.0), (0.0, 0.0, 10 ** 400)):
            with pytest.raises(SampleError, match="update\\(\\) takes one sample .* within \\+-100000"):
                g.update(sample)
        rows += [g.update(tuple(s)) for s in x[600:].tolist()]
        assert np.array_equal(np.array([r for r in rows if r is not None]), f.filter(x))
    edge = GyroFilter(100.0, preset="paper", calibration_s=0)
    assert np.isfinite(edge.filter(np.full((50, 3), MAX_RATE_DPS) * [1, -1, 1])).all()  # the bound itself is a sample


def test_a_masked_sample_is_refused_not_filtered_as_data():
    """Issue 37: np.asarray drops a masked array's mask, so a masked 5000 deg/s went through as a
    sample. Now filter(), filter_timed() and the temperatures refuse the first masked row; a mask
    with nothing masked is plain data."""
    from gyrofilter.errors import SampleError

    x = noisy(1000)
    x[700, 1] = 5000.0
    masked = np.ma.masked_array(x, mask=np.abs(x) > 1000)
    f = GyroFilter(100.0)
    with pytest.raises(SampleError, match=r"samples_dps row 700 is masked") as info:
        f.filter(masked)
    assert info.value.row == 700 and f.samples_in == 0
    with pytest.raises(SampleError, match=r"samples_dps row 700 is masked"):
        f.filter_timed(masked, np.arange(1000) / 100.0)
    temps = np.ma.masked_array(np.full(1000, 30.0), mask=np.arange(1000) == 3)
    with pytest.raises(SampleError, match=r"temp_c row 3 is masked"):
        f.filter(x[:600], temp_c=temps[:600])
    assert f.samples_in == 0
    plain = np.ma.masked_array(x[:600], mask=False)
    assert np.array_equal(f.filter(plain), GyroFilter(100.0).filter(x[:600]))


@pytest.mark.parametrize("sample", [{1.0, 2.0, 3.0}, {0: 1.0, 1: 2.0, 2: 3.0}, {"x": 1.0, "y": 2.0, "z": 3.0}, "1,2", (True, 0.0, 0.0),
                                    np.zeros(3, dtype=bool), ("1", 2.0, 3.0), iter((1.0, 2.0, 3.0)), np.zeros((1, 3))])
def test_update_takes_a_sequence_of_three_numbers_only(sample):
    """A set or a dict has no order of axes (a set of 3 numbers was used as x, y, z in whatever
    order it iterated, a dict's keys as the sample); bools, text and iterators are no samples either."""
    f = GyroFilter(100.0, preset="paper", calibration_s=0)
    with pytest.raises(SettingsError, match="update\\(\\) takes one sample"):
        f.update(sample)
    assert f.samples_in == 0
    assert f.update([1, 2, 3]) is None and f.update(np.array([1.0, 2.0, 3.0], dtype=np.float32)) is None
    assert f.samples_in == 2


def test_temperatures_out_of_range_are_refused():
    """temp_c = 10**400 raised OverflowError, 1e300 made the calibration's temperature inf."""
    from gyrofilter.errors import SampleError

    f = GyroFilter(100.0, preset="paper")
    for temp in (10 ** 400, 1e300, -300.0, float("inf"), "30"):
        with pytest.raises(SampleError, match="temp_c"):
            f.update((0.0, 0.0, 0.0), temp)
    temps = np.full(300, 25.0)
    temps[150] = 1e300
    with pytest.raises(SampleError, match="temp_c row 150") as info:
        f.filter(noisy(300), temps)
    assert info.value.row == 150 and f.samples_in == 0
    temps[150] = np.nan  # NaN is "no temperature": the calibration then keeps none
    f.filter(noisy(300), temps)
    assert f.calibration.temp_c is None


def test_a_given_calibration_with_absurd_numbers_is_refused():
    good = dict(bias_dps=(0.1, 0.2, 0.3), noise_std_dps=(0.1, 0.1, 0.1), samples=200, sample_rate_hz=100.0)
    for change, name in (({"bias_dps": (1e300, 0.0, 0.0)}, "bias_dps x"), ({"noise_std_dps": (0.1, 1e200, 0.1)}, "noise_std_dps y"),
                         ({"temp_c": 1e300}, "temp_c"), ({"bias_dps": (0.0, 0.0)}, "bias_dps")):
        with pytest.raises(CalibrationError, match=f"the calibration: {name}"):
            GyroFilter(100.0, calibration=Calibration(**{**good, **change}))
    assert np.isfinite(GyroFilter(100.0, calibration=Calibration(**good)).filter(noisy(100))).all()


@pytest.mark.parametrize("name", ["block_len", "fifo_depth", "fit_order", "qr_window", "hold_window", "hold_max_blocks",
                                  "guard_blocks"])
def test_every_size_setting_has_an_upper_bound(name):
    """fifo_depth, hold_window = 1e12 ended in MemoryError; qr_window = 1e12 in a 24-TB lazily
    allocated ring. Each size or count now has a range, and the message gives it."""
    from gyrofilter.filter.settings import SETTING_RANGES

    high = SETTING_RANGES[name]["high"]
    low = SETTING_RANGES[name]["low"]
    with pytest.raises(SettingsError, match=re.escape(f"setting {name} must be in [{low}, {high:g}], got 1000000000000")):
        GyroFilter(100.0, preset="paper", **{name: 10 ** 12})
    settings = {name: high, **({"kalman_noise": "adaptive"} if name == "hold_window" else {})}
    assert GyroFilter(100.0, preset="paper", **settings).settings.__getattribute__(name) == high


@pytest.mark.parametrize("value", [True, False, float("nan"), float("inf"), -float("inf"), 1e300, 10 ** 400, None, "1"])
def test_numeric_settings_refuse_bools_non_finite_and_huge_values(value):
    """stillness_z=True was used as 1; NaN, inf, 1e300 or 10**400 (OverflowError) in a setting."""
    from gyrofilter.filter.settings import SETTING_RANGES

    for name in SETTING_RANGES:
        if value is None and name == "calibration_s":  # GyroFilter's calibration_s=None: the preset's
            continue
        with pytest.raises(SettingsError, match=f"setting {name} must be"):
            GyroFilter(100.0, preset="paper", **{name: value})


def test_an_integer_setting_may_be_written_as_a_whole_float():
    f = GyroFilter(100.0, preset="paper", block_len=4.0, fifo_depth=np.int64(8))
    assert type(f.settings.block_len) is int and type(f.settings.fifo_depth) is int
    assert len(f.filter(noisy(400))) == (400 - 200) // 4


def test_after_a_refused_calibration_the_next_samples_start_a_new_window():
    """update() after a CalibrationError raised IndexError (the full window was never emptied). Now
    the refused window is dropped and the next samples calibrate again, as a new filter would."""
    still = noisy(1000, seed=5)
    moving = noisy(200, seed=6) + np.linspace(0, 10, 200)[:, None]
    for feed in ("update", "filter"):
        f = GyroFilter(100.0, preset="paper")
        with pytest.raises(CalibrationError, match="moved"):
            if feed == "update":
                stream(f, moving)
            else:
                f.filter(np.concatenate([moving, still[:50]]))  # the samples after the refused window are dropped
        assert f.calibrating and f.samples_in == 200
        with pytest.raises(CalibrationError, match="moved"):  # every refused window raises: a live caller can keep trying
            stream(f, moving)
        rows = stream(f, still) if feed == "update" else f.filter(still)
        assert np.array_equal(rows, GyroFilter(100.0, preset="paper").filter(still))
        assert f.first_block_index == 600 and f.samples_in == 1400  # 2 refused windows, then 2 s of calibration


def test_the_calibration_window_held_in_memory_is_bounded_in_samples():
    """An hour at 100 kHz was accepted: a lazily allocated 8.6 GB window, filled sample by sample."""
    from gyrofilter.filter.settings import MAX_CALIBRATION_SAMPLES

    with pytest.raises(SettingsError, match="setting calibration_s=3600.0 gives 360000000 samples at 100000 Hz; "
                                            "the still window is held in memory: at most 3600000 samples"):
        GyroFilter(100_000.0, calibration_s=3600.0)
    assert GyroFilter(1000.0, calibration_s=MAX_CALIBRATION_SAMPLES / 1000.0).calibrating


def test_filter_timed_refuses_float16_times():
    """Issue 37 (attack): float16 times (spaced 1 s apart from 1024 s, 2 s from 2048 s) were taken
    and the rows stamped with them: 100-Hz samples 2100 s in all read 2100 s. They are refused,
    the filter left as it was; float32 and float64 times are kept as given."""
    f = GyroFilter(sample_rate_hz=100.0, calibration_s=0.5)
    t = 2100.0 + np.arange(300) / 100.0
    with pytest.raises(SampleError, match="t_s is float16"):
        f.filter_timed(noisy(300), t.astype(np.float16))
    with pytest.raises(SampleError, match="t_s is float16"):
        f.filter_timed(noisy(300), list(t.astype(np.float16)))
    assert f.samples_in == 0
    t_rows, rows = f.filter_timed(noisy(300), t.astype(np.float32))
    assert len(rows) and np.all(np.diff(t_rows) > 0) and set(t_rows) <= set(t.astype(np.float32).astype(float))


def test_filter_timed_names_float32_when_its_times_repeat():
    """Attack pass 25: float32 times of a later hour or of the epoch (1.7e9 s, 128 s apart in
    float32) repeat; the refusal said only "must increase strictly", of times that increased
    before the caller's conversion (the docstring said float32 keeps them)."""
    f = GyroFilter(sample_rate_hz=100.0, calibration_s=0.5)
    t = 1.7e9 + np.arange(300) / 100.0
    with pytest.raises(SampleError, match="t_s is float32, whose 24 significant bits space times 128 s apart here: "
                                          "give them as float64"):
        f.filter_timed(noisy(300), t.astype(np.float32))
    assert f.samples_in == 0


@pytest.mark.parametrize("kind", ["repeated", "decreasing"])
def test_filter_timed_refuses_times_that_do_not_increase(kind):
    """Issue 37 (attack passes 12-14): a repeated or decreasing time was taken and the rows stamped
    with it (rows whose times repeat or go back). The first such time is refused naming its row,
    the filter left as it was; also from the last time of the call before."""
    f = GyroFilter(100.0, calibration_s=0.5)
    t = np.arange(300) / 100.0
    bad = t.copy()
    bad[150] = bad[149] if kind == "repeated" else bad[149] - 0.5
    with pytest.raises(ValueError, match=r"t_s row 150: t_s must increase strictly \(s\), got [0-9.]+ after row 149's 1\.49$"):
        f.filter_timed(noisy(300), bad)
    assert f.samples_in == 0
    t_rows, rows = f.filter_timed(noisy(300), t)
    assert f.samples_in == 300 and len(rows)
    with pytest.raises(SampleError, match=r"t_s row 0: .* got [0-9.]+ after 2\.99, the last time of the previous call") as caught:
        f.filter_timed(noisy(10), t[-10:] if kind == "repeated" else t[:10])
    assert caught.value.row == 0 and f.samples_in == 300
    assert len(f.filter_timed(noisy(300), t + 3.0)[1])


def test_filter_timed_refuses_times_that_are_not_finite():
    f = GyroFilter(100.0, preset="paper")
    t = np.arange(300) / 100.0
    t[250] = np.nan
    with pytest.raises(SettingsError, match="t_s row 250: t_s must be finite"):
        f.filter_timed(noisy(300), t)
    assert f.samples_in == 0
    with pytest.raises(SettingsError, match="t_s must have shape"):
        f.filter_timed(noisy(300), t[:10])
    with pytest.raises(SettingsError, match="samples_dps must be an array of numbers"):
        f.filter_timed([[1.0, 2.0, 3.0], [1.0]], t[:2])


def test_a_copy_of_a_filter_mid_stream_is_independent_of_it():
    """copy.copy shared the filter's arrays: feeding the copy changed the original's later rows."""
    import copy

    x = noisy(2000)
    reference = GyroFilter(100.0)
    want = reference.filter(x)
    f = GyroFilter(100.0)
    first = f.filter(x[:1000])
    twin = copy.copy(f)
    twin.filter(np.random.default_rng(9).normal(5.0, 1.0, (500, 3)))
    np.testing.assert_array_equal(np.vstack([first, f.filter(x[1000:])]), want)
