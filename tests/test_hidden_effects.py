"""gyrofilter.sim.hidden_effects: hiding one effect in a recording built in code refuses what the
simulator's model refuses (attack pass 22: a colored noise of lag1 NaN gave a recording of NaN
rates, an axis 'w' a KeyError, lag1 1.5 a math domain error)."""
import numpy as np
import pytest

from gyrofilter.effects import COLORED_NOISE, COMPRESSION, HEAVY_TAILS, REPEATED_SAMPLES, SINUSOID
from gyrofilter.errors import SettingsError
from gyrofilter.recording import Recording, write_recording
from gyrofilter.sim.hidden_effects import hide_in_recording


def record():
    return Recording.from_dps(np.random.default_rng(0).normal(size=(500, 3)), 100.0)


@pytest.mark.parametrize("effect,params", [(COLORED_NOISE, {"lag1": float("nan")}), (COLORED_NOISE, {"lag1": 1.5}),
                                           (HEAVY_TAILS, {"fraction": 2.0, "scale_ratio": 3.0}),
                                           (HEAVY_TAILS, {"fraction": float("nan"), "scale_ratio": 3.0})])
def test_parameters_the_model_refuses_are_refused(effect, params):
    with pytest.raises(SettingsError, match=rf"model: axes.x.effects\[0\] \({effect}\)"):
        hide_in_recording(record(), effect, "x", params)


def test_an_axis_that_is_none_is_refused():
    with pytest.raises(SettingsError, match="axis must be one of x, y, z, got 'w'"):
        hide_in_recording(record(), COLORED_NOISE, "w", {"lag1": 0.3})


def test_a_valid_colored_noise_keeps_the_axis_finite():
    out = hide_in_recording(record(), COLORED_NOISE, "x", {"lag1": 0.3})
    assert np.all(np.isfinite(out.gyro_dps))


@pytest.mark.parametrize("params", [{"fraction": 5.0}, {"fraction": float("nan")}, {"fraction": -1.0}, {},
                                    {"fraction": 0.1, "pattern": "bogus"}, {"fraction": "0.1"}])
def test_repeated_samples_parameters_the_model_refuses_are_refused(params):
    """Attack pass 23: pass 22's check skipped the whole-row effect: a fraction of 5 repeated
    every row, NaN or -1 none, a pattern 'bogus' ran as 'random', a string was taken as a
    number, and no fraction ended in a KeyError."""
    with pytest.raises(SettingsError, match=r"model: repeated_samples"):
        hide_in_recording(record(), REPEATED_SAMPLES, "xyz", params)


def test_a_six_axis_record_gives_a_recording_that_writes(tmp_path):
    """Attack pass 24: a six-axis record's effect-added copy (gyro and temp only) kept the header's
    accel_unit without its columns ax, ay, az: write_recording refused the recording it made. The
    copy keeps the accelerometer now, with its unit keys (pass 24's note)."""
    rng = np.random.default_rng(3)
    rec = Recording.from_dps(rng.normal(0, 0.1, (300, 3)), 100.0, accel=rng.normal(0, 1, (300, 3)), accel_unit="lsb",
                             lsb_per_g=16384, temp_c=np.full(300, 25.0))
    out = hide_in_recording(rec, "sinusoid", "x", {"frequency_hz": 1.0, "amplitude_dps": 0.1})
    write_recording(tmp_path / "hidden.csv", out)
    assert out.accel_unit == "lsb" and out.lsb_per_g == 16384 and np.array_equal(out.accel_mps2, rec.accel_mps2)


@pytest.mark.parametrize("effect, axis, params", [("sinusoid", "y", {"amplitude_dps": 0.1, "frequency_hz": 3.0}),
                                                  (HEAVY_TAILS, "z", {"fraction": 0.05, "scale_ratio": 4.0}),
                                                  (REPEATED_SAMPLES, None, {"fraction": 0.2})])
def test_the_other_columns_and_notes_are_kept(tmp_path, effect, axis, params):
    """Attack pass 24's note: hide_in_recording dropped `t`, the accelerometer and any other column
    (and the notes); they are kept, repeated with the rates where whole rows are repeated, `t` and a
    counter as they were (the logger's clock goes on), and the result writes."""
    rng = np.random.default_rng(5)
    n = 1500
    accel = rng.normal(0, 1, (n, 3)) + [0, 0, 9.8]
    rec = Recording.from_dps(rng.normal(0, 0.1, (n, 3)), 100.0, t_s=np.arange(n) / 100 + 7, temp_c=np.linspace(25, 26, n),
                             accel=accel, accel_unit="m/s^2", extra={"count": np.arange(n, dtype=float)})
    rec.notes = [("line", "moved the cable")]
    out = hide_in_recording(rec, effect, axis, params, seed=2)
    assert list(out.columns) == ["t", "gx", "gy", "gz", "temp", "ax", "ay", "az", "count"]
    assert out.header["accel_unit"] == "m/s^2" and [n[1] for n in out.notes] == ["moved the cable"]
    assert np.array_equal(out.columns["t"], rec.columns["t"]) and np.array_equal(out.columns["count"], rec.columns["count"])
    held = out.accel_mps2
    if effect == REPEATED_SAMPLES:
        repeated = np.flatnonzero(np.all(np.diff(out.gyro_dps, axis=0) == 0, axis=1)) + 1
        assert repeated.size > 0.1 * n and np.array_equal(held[repeated], held[repeated - 1])
        assert np.array_equal(out.temp_c[repeated], out.temp_c[repeated - 1])
    else:
        assert np.array_equal(held, accel) and np.array_equal(out.temp_c, rec.temp_c)
    write_recording(tmp_path / "out.csv", out)


def test_a_temperature_hidden_in_a_recording_without_one_is_the_package_s_refusal():
    """Attack pass 26: hide_in_recording(rec without temp, "temperature", ...) raised a plain
    ValueError (a program catching GyroFilterError got a traceback)."""
    from gyrofilter.errors import GyroFilterError
    from gyrofilter.recording import Recording
    rec = Recording.from_dps(np.zeros((100, 3)), 100.0)
    with pytest.raises(GyroFilterError, match="recording: the effect temperature needs a temp column"):
        hide_in_recording(rec, "temperature", "x", {"coefficient_dps_per_c": 0.5})


@pytest.mark.parametrize("rows", [1, 30, 63])
def test_heavy_tails_in_a_record_shorter_than_its_window(rows):
    """Attack pass 29b: heavy tails hidden in a record of fewer than 64 samples (the moving
    mean's window) ended in numpy's "operands could not be broadcast together"."""
    rec = Recording.from_dps(np.random.default_rng(1).normal(size=(rows, 3)), 100.0)
    out = hide_in_recording(rec, HEAVY_TAILS, "x", {"fraction": 0.5, "scale_ratio": 4.0})
    assert len(out) == rows and np.all(np.isfinite(out.gyro_dps))


def test_heavy_tails_scale_the_noise_not_the_bias_at_the_ends():
    """Attack pass 29b: the fast noise was the rate less its moving mean over 64 samples taken
    with zeros beyond the record: within 32 samples of either end it held about half the bias,
    scaled as noise (a -3.3 deg/s bias: changes of 1.9 deg/s there, 0.19 elsewhere)."""
    rng = np.random.default_rng(0)
    rec = Recording.from_dps(-3.3 + rng.normal(0, 0.05, (2000, 3)), 100.0)
    change = hide_in_recording(rec, HEAVY_TAILS, "x", {"fraction": 0.2, "scale_ratio": 10.0}, seed=3).gyro_dps[:, 0] \
        - rec.gyro_dps[:, 0]
    middle = np.abs(change[100:-100]).max()
    assert np.abs(change[:100]).max() < 2 * middle and np.abs(change[-100:]).max() < 2 * middle


@pytest.mark.parametrize("effect, axis, params, named", [
    (COLORED_NOISE, "x", {"lag1": 0.3, "lag_2": 0.2}, "unknown parameter 'lag_2'; did you mean lag2"),
    (REPEATED_SAMPLES, None, {"fraction": 0.2, "patern": "beat"}, "unknown parameter 'patern'"),
    (COLORED_NOISE, "x", {"lag1": 0.3, "preserve": "arw"}, "preserve \"std\"")])
def test_parameters_hiding_would_not_use_are_refused(effect, axis, params, named):
    """Attack pass 29b: a misspelt optional parameter was dropped without a word (the model's
    warning went nowhere): the default's effect was hidden (no lag2, the random pattern), and a
    colored noise's preserve "arw" was filtered keeping the variance."""
    with pytest.raises(SettingsError, match=named):
        hide_in_recording(record(), effect, axis, params)


def test_parameters_naming_another_effect_are_refused():
    """Attack pass 30b: ``params`` holding ``"effect": "warmup"`` (a model's effect entry) hid a
    warm-up where a sinusoid was asked for (the entry's key replaced the argument), exit 0."""
    with pytest.raises(SettingsError, match="params name the effect 'warmup', not 'sinusoid'"):
        hide_in_recording(record(), SINUSOID, "x", {"effect": "warmup", "amplitude_dps": 1.0, "tau_s": 5.0})
    entry = {"effect": SINUSOID, "frequency_hz": 1.0, "amplitude_dps": 0.1}  # a model's entry of that effect: taken
    assert hide_in_recording(record(), SINUSOID, "x", entry).gyro_dps.shape == record().gyro_dps.shape


def test_a_compression_hidden_in_a_recording_compresses_its_noise():
    """Attack pass 32a: a compression acts on the axis's fast terms, of which the simulated part
    has none (no white noise): the recording came back unchanged, nothing hidden, no word. It
    compresses the recording's fast noise about its slow level, as heavy tails scale it: the
    tails lighter (excess kurtosis about -24 gamma sigma^2), the bias and the other axes kept."""
    rng = np.random.default_rng(0)
    rec = Recording.from_dps(np.array([-3.3, 1.1, -0.5]) + rng.normal(0, 0.3, (4000, 3)), 100.0)
    out = hide_in_recording(rec, COMPRESSION, "x", {"gamma_per_dps2": 0.3, "rms_dps": 0.3}).gyro_dps
    before, after = rec.gyro_dps[:, 0], out[:, 0]
    kurtosis = [np.mean((v - v.mean()) ** 4) / np.var(v) ** 2 - 3 for v in (before, after)]
    assert kurtosis[1] < kurtosis[0] - 0.4
    assert abs(after.mean() - before.mean()) < 0.01 and abs(after.std() / before.std() - 1) < 0.05
    assert np.array_equal(out[:, 1:], rec.gyro_dps[:, 1:])


def test_a_compression_s_rms_is_the_recording_s_own():
    """Attack pass 33a: the gain and the model's bound (gamma rms^2 <= 0.03: the cubic's turning
    point at 3.3 rms or beyond) read the stated ``rms_dps``, but what is compressed is the
    recording's noise: stated 0.05 on a noise of rms 0.3, the turning point fell at 0.55 rms and
    most samples were clipped (the std 0.305 made 0.115), without a word. A stated rms off the
    recording's fast noise's by more than 5 % is refused naming it; that one is taken."""
    rng = np.random.default_rng(0)
    rec = Recording.from_dps(np.array([-3.3, 1.1, -0.5]) + rng.normal(0, 0.3, (4000, 3)), 100.0)
    with pytest.raises(SettingsError, match=r"rms_dps 0.05 .* give rms_dps=0.30") as refused:
        hide_in_recording(rec, COMPRESSION, "x", {"gamma_per_dps2": 11.9, "rms_dps": 0.05})
    rms = float(str(refused.value).split("give rms_dps=")[1].split()[0])
    out = hide_in_recording(rec, COMPRESSION, "x", {"gamma_per_dps2": 0.3, "rms_dps": rms}).gyro_dps
    assert abs(out[:, 0].std() / rec.gyro_dps[:, 0].std() - 1) < 0.01
    flat = Recording.from_dps(np.ones((50, 3)), 100.0)
    with pytest.raises(SettingsError, match="no fast noise on x"):
        hide_in_recording(flat, COMPRESSION, "x", {"gamma_per_dps2": 0.3, "rms_dps": 0.3})


def test_a_colored_noise_s_lag2_of_none_is_its_default():
    """Attack pass 32a: the model takes ``lag2: null`` as not given (lag1 squared); hidden in a
    recording it ended in Python's TypeError (``float(None)``)."""
    given = hide_in_recording(record(), COLORED_NOISE, "x", {"lag1": 0.5, "lag2": None, "preserve": "std"}).gyro_dps
    assert np.array_equal(given, hide_in_recording(record(), COLORED_NOISE, "x", {"lag1": 0.5}).gyro_dps)


def test_repeated_samples_hidden_in_a_record_of_no_rows():
    """Attack pass 32a: repeated rows hidden in a recording of 0 samples (built in code) ended in
    numpy's IndexError (the first row repeated where there is none): no rows, none repeated."""
    rec = Recording.from_dps(np.zeros((0, 3)), 100.0, temp_c=np.zeros(0))
    assert len(hide_in_recording(rec, REPEATED_SAMPLES, None, {"fraction": 0.3})) == 0
