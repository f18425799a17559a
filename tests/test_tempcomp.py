"""Temperature compensation: gain on a simulated warm-up, coefficient fit, model lookup, the pipeline."""
import numpy as np
import pytest

from gyrofilter import GyroFilter
from gyrofilter.filter import tempcomp
from gyrofilter.tempscreen import running_medians, temperature_history
from gyrofilter.errors import SettingsError

FS = 100.0
C = np.array([0.03, -0.02, 0.01])
BIAS = np.array([-3.3, 1.1, -0.5])


def warmup(seed, duration_s=600.0):
    """Static sensor warming 25 -> 35 C (tau 120 s, 0.094 C steps like the MPU6050), bias = b + c (T - 25)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration_s * FS)) / FS
    temp = 35.0 - 10.0 * np.exp(-t / 120.0)
    temp_q = np.round(temp / 0.0941) * 0.0941
    x = BIAS + np.outer(temp - 25.0, C) + rng.normal(0, 0.1, (len(t), 3))
    return t, temp_q, x


def test_compensation_removes_the_temperature_drift():
    t, temp, x = warmup(0)
    n_cal = int(2 * FS)
    bias0 = x[:n_cal].mean(axis=0)
    t0 = temp[:n_cal].mean()
    plain = x - bias0
    comp = tempcomp.compensate(x, temp, C, t0) - bias0
    last = slice(-int(60 * FS), None)
    err_plain = np.abs(plain[last].mean(axis=0))
    err_comp = np.abs(comp[last].mean(axis=0))
    # the sensor warmed ~9.9 C: the start-up bias is off by c * 9.9 on each axis
    assert err_plain == pytest.approx(np.abs(C) * 9.9, rel=0.1)
    assert np.all(err_comp < 0.02)
    assert np.all(err_comp < err_plain / 5)


def test_fit_coefficient_recovers_c():
    _, temp, x = warmup(1)
    c, se = tempcomp.fit_coefficient(x, temp)
    assert np.allclose(c, C, atol=5 * se.max())
    assert np.all(se < 0.001)
    with pytest.raises(SettingsError, match="spans only"):
        tempcomp.fit_coefficient(x[:10], np.full(10, 25.0))


def test_coefficients_from_model():
    model = {"axes": {"x": {"effects": [{"effect": "temperature", "coefficient_dps_per_c": 0.03}]},
                      "y": {"effects": [{"effect": "sinusoid", "frequency_hz": 1, "amplitude_dps": 1}]},
                      "z": {}}}
    assert tempcomp.coefficients_from_model(model) == (0.03, 0.0, 0.0)


@pytest.mark.parametrize("doc, message", [
    # issue 22 (10): true was taken as 1.0, "0.02" and rate -5 accepted, null and a missing coefficient a traceback
    ({"axes": {"x": {"effects": [{"effect": "temperature", "coefficient_dps_per_c": True}]}}},
     "(temperature).coefficient_dps_per_c: expected a finite number, got true"),
    ({"axes": {"x": {"effects": [{"effect": "temperature", "coefficient_dps_per_c": "0.02"}]}}},
     "(temperature).coefficient_dps_per_c: expected a finite number, got \"0.02\""),
    ({"axes": {"x": {"effects": [{"effect": "temperature", "coefficient_dps_per_c": None}]}}},
     "(temperature).coefficient_dps_per_c: expected a finite number, got null"),
    ({"axes": {"x": {"effects": [{"effect": "temperature"}]}}}, "(temperature): missing parameter 'coefficient_dps_per_c'"),
    ({"sample_rate_hz": -5, "axes": {"x": {}}}, "model: sample_rate_hz must be a number of Hz"),
    ({"gyro_unit": "furlongs", "axes": {"x": {}}}, "model: gyro_unit: expected one of dps, rad/s, lsb, got \"furlongs\""),
    ({"axes": {"x": {"effects": "str"}}}, "model: axes.x.effects: expected a list of effect objects, got \"str\""),
    ({"axes": {"x": []}}, "model: axes.x: expected an object"),
    ({"axes": {"x": {"effects": [{"effect": "temperature", "coefficient_dps_per_c": 1e9}]}}},
     "(temperature).coefficient_dps_per_c: expected a number <= 100000"),
])
def test_temp_model_goes_through_the_model_validator(tmp_path, capsys, doc, message):
    import json

    from gyrofilter.cli import main
    from gyrofilter.recording import Recording, write_recording

    src = tmp_path / "warm.csv"
    write_recording(src, Recording.from_dps(np.full((500, 3), 0.1), FS, temp_c=np.linspace(25.0, 26.0, 500)))
    model = tmp_path / "model.json"
    model.write_text(json.dumps(doc))
    assert main(["replay", str(src), "--temp-model", str(model), "--out", str(tmp_path / "out.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{model}: " in err and message in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.json", "warm.csv"]
    # a good one without a sample rate or a temperature profile is taken (only its coefficients are used)
    model.write_text(json.dumps({"axes": {"y": {"effects": [{"effect": "temperature", "coefficient_dps_per_c": 0.04}]}}}))
    assert main(["replay", str(src), "--temp-model", str(model), "--out", str(tmp_path / "out.csv")]) == 0
    assert "temperature compensated (0, 0.04, 0 deg/s/degC)" in capsys.readouterr().out


def test_by_hand_and_the_pipeline_applies_the_same_correction():
    y = tempcomp.compensate([[1.0, 2.0, 3.0]], [30.0], [0.1, 0.2, 0.3], 25.0)
    assert np.allclose(y, [[0.5, 1.0, 1.5]])
    _, temp, x = warmup(2, duration_s=60.0)
    # GyroFilter compensates after its calibration window (calibrated on the raw samples), with T0 = the
    # window's mean temperature and T the running median of the latest 11 temperatures
    inside = GyroFilter(FS, preset="recommended", temp_coefficient_dps_per_c=tuple(C)).filter(x, temp)
    t_med = running_medians(temperature_history(), temp, temp[:200].mean())
    by_hand = np.concatenate([x[:200], tempcomp.compensate(x[200:], t_med[200:], C, temp[:200].mean())])
    before = GyroFilter(FS, preset="recommended").filter(by_hand)
    assert np.allclose(inside, before, rtol=0, atol=1e-9)
    with pytest.raises(SettingsError):
        tempcomp.compensate(np.zeros((3, 2)), np.zeros(3), C, 25.0)


def test_what_is_not_finite_is_refused_not_carried_into_the_rates():
    """Attack pass 22: compensate() with a reference temperature of NaN gave NaN rates, fit_coefficient()
    with a NaN temperature (or rate) NaN coefficients, without a word; compensate() refused a NaN temp_c."""
    rng = np.random.default_rng(0)
    g = rng.normal(0, 0.05, (1000, 3))
    t = 25 + np.linspace(0, 3, 1000)
    with pytest.raises(SettingsError, match="reference_temp_c"):
        tempcomp.compensate(g, t, [0.01, 0.01, 0.01], float("nan"))
    t_nan = t.copy()
    t_nan[5] = np.nan
    with pytest.raises(SettingsError, match="temp_c holds NaN"):
        tempcomp.fit_coefficient(g, t_nan)
    g_nan = g.copy()
    g_nan[7, 1] = np.inf
    with pytest.raises(SettingsError, match="gyro_dps holds NaN"):
        tempcomp.fit_coefficient(g_nan, t)


def _masked_at_5(values):
    values = np.ma.masked_array(values, mask=np.zeros(np.shape(values), bool))
    values.mask[5] = True
    values.data[5] = 1e4
    return values


def test_what_is_not_a_rate_or_a_temperature_is_refused():
    """Attack pass 23: pass 22's rule for the arrays: a masked value's hidden 1e4 was taken as data
    (fit_coefficient's x coefficient -9.8 deg/s/C, not 0.03; compensate gave row 5 as 1e4 deg/s
    or -300 deg/s), complex temperatures lost their imaginary part, a temperature of 1e12 C (beyond
    TEMP_RANGE_C, which the reference and the filter keep to) gave rates of -3e10 deg/s and one of
    1e200 an overflow: refused, naming the argument."""
    t, temp, x = warmup(0, duration_s=20.0)
    for gyro, temps, name in ((_masked_at_5(x), temp, "gyro_dps"), (x, _masked_at_5(temp), "temp_c")):
        with pytest.raises(SettingsError, match=f"{name} row 5 is masked"):
            tempcomp.fit_coefficient(gyro, temps)
        with pytest.raises(SettingsError, match=f"{name} row 5 is masked"):
            tempcomp.compensate(gyro, temps, C, 25.0)
    with pytest.raises(SettingsError, match="temp_c must be numbers in deg C, got an array of complex128"):
        tempcomp.fit_coefficient(x, temp + 0j)
    for huge in (1e12, 1e200):
        with pytest.raises(SettingsError, match=r"temp_c row 0: temp_c \(deg C\) must be in \[-100, 200\]"):
            tempcomp.compensate(x, temp * 0 + huge, C, 25.0)
        with pytest.raises(SettingsError, match=r"temp_c row 0: temp_c \(deg C\) must be in \[-100, 200\]"):
            tempcomp.fit_coefficient(x, np.r_[huge, temp[1:]])
    x[3, 1] = 1e6
    with pytest.raises(SettingsError, match=r"gyro_dps row 3: gy \(deg/s\) must be in \[-100000, 100000\]"):
        tempcomp.fit_coefficient(x, temp)


def test_too_few_samples_or_temperatures_of_another_length_are_refused():
    """Attack pass 23: fit_coefficient on 2 samples gave a standard error of NaN, on 0 numpy's
    "zero-size array" ValueError; compensate with 5 temperatures for 4 samples a broadcasting error."""
    for n in (0, 2):
        with pytest.raises(SettingsError, match=f"fit_coefficient needs at least 3 samples, got {n}"):
            tempcomp.fit_coefficient(np.zeros((n, 3)), 20.0 + np.arange(n))
    with pytest.raises(SettingsError, match=r"temp_c must be one temperature or one per sample, shape \(4,\), got \(5,\)"):
        tempcomp.compensate(np.zeros((4, 3)), np.full(5, 30.0), C, 25.0)


@pytest.mark.parametrize("coef", [np.float32(0.01), np.int64(0), [np.float32(0.01), 0, np.int8(0)], np.longdouble(0.01),
                                  __import__("collections").namedtuple("Axes", "x y z")(0.01, 0, 0)])
def test_a_numpy_number_as_the_temperature_coefficient_is_the_number_it_holds(coef):
    """Attack pass 28b: ``temp_coefficient_dps_per_c=np.float32(0.01)`` (or ``np.int64(0)``) passed
    the settings' check and ended in Python's "'numpy.float32' object is not iterable"; the
    settings hold it as plain floats (``state_dict`` is plain Python, as its docstring says).
    Attack pass 29b: an ``np.longdouble`` stayed one (its ``item()`` is itself): not JSON; a
    namedtuple of 3 ended in a TypeError (its type was called on a generator)."""
    import json
    f = GyroFilter(100.0, temp_coefficient_dps_per_c=coef)
    x, temp = np.zeros((210, 3)), np.full(210, 25.0)
    assert len(f.filter(x, temp)) == 10 // f.settings.block_len
    plain = f.settings.temp_coefficient_dps_per_c
    assert all(type(v) in (int, float) for v in (plain if isinstance(plain, (tuple, list)) else [plain]))
    json.dumps(f.state_dict())


@pytest.mark.parametrize("coef", [1e308, (0.0, 0.0, -1e308), 1e300, 10.5])
def test_a_coefficient_beyond_the_filters_bound_is_refused_not_infinite_rates(coef):
    """Attack pass 31b: ``compensate(x, 200.0, 1e308, -100.0)`` returned inf rates (numpy's
    overflow warning only), 1e300 rates of 3e302 deg/s: the filter's bound,
    +-MAX_TEMP_COEFFICIENT_DPS_PER_C, one rule for both (``GyroFilter`` refused 1e308 already)."""
    with pytest.raises(SettingsError, match="coefficient_dps_per_c"):
        tempcomp.compensate(np.zeros((2, 3)), np.array([30.0, 200.0]), coef, -100.0)
    assert np.all(np.isfinite(tempcomp.compensate(np.zeros((2, 3)), np.array([30.0, 200.0]), 10.0, -100.0)))


@pytest.mark.parametrize("preset", ["recommended", "paper", "hold"])
@pytest.mark.parametrize("run", [1, 2, 3, 5])
def test_read_glitches_in_the_temperature_do_not_move_the_rates(preset, run):
    """Attack passes 37l/37m: the compensation took each temperature as read, so TEMP_OUT = 0x8000
    (-59.85 deg C) moved that sample by c x 85 deg C: 2 glitches moved the paper preset's y by 0.28 deg/s
    (8 times its filtered sd) for 600 rows; 3 in a block read 4.5 deg/s where the rate was -0.18. T is the
    running median of the latest 11 temperatures: runs of up to 5 glitches move nothing."""
    rng = np.random.default_rng(run)
    n, c = 6000, (0.03, -0.015, 0.1)
    temp = 25 + np.arange(n) / n + rng.normal(0, 0.01, n)
    x = np.array([-3.3, 1.1, -0.5]) + 0.1 * rng.standard_normal((n, 3)) + np.outer(temp - 25, c)
    glitched = temp.copy()
    glitched[3000:3000 + run] = -32768 / 340 + 36.53
    clean = GyroFilter(FS, preset=preset, temp_coefficient_dps_per_c=c)
    hit = GyroFilter(FS, preset=preset, temp_coefficient_dps_per_c=c)
    a, b = clean.filter(x, temp), hit.filter(x, glitched)
    assert np.abs(a - b).max() < 0.002  # c x a neighbour's temperature noise, not c x 85 deg C
    assert hit.rejected.tolist() == clean.rejected.tolist()


def test_fit_coefficient_leaves_out_read_glitches():
    """Attack pass 37l: one TEMP_OUT of 0x8000 (-59.85 deg C) took the fitted coefficient from 0.0300 to
    0.0248, five to 0.0137."""
    _, temp, x = warmup(1)
    c, _ = tempcomp.fit_coefficient(x, temp)
    for at in ([len(temp) // 2], [0, 7, 1000, 2000, len(temp) - 1]):
        hit = temp.copy()
        hit[at] = -32768 / 340 + 36.53
        assert np.allclose(tempcomp.fit_coefficient(x, hit)[0], c, rtol=0, atol=1e-4), at


@pytest.mark.parametrize("at", [1, 2, 3])
def test_a_glitch_right_after_a_loaded_calibration_moves_nothing(at):
    """Attack pass 37n: after a loaded calibration the running median of T starts with fewer temperatures,
    and a glitch on the second sample (the lower middle of two) was the T compensated: a row moved by
    2.5 deg/s. Of an even count the middle one nearer T0 is taken (the first sample alone is its own)."""
    rng = np.random.default_rng(at)
    n, c = 3000, (0.01, -0.005, 0.008)  # c x 85 deg C under q = 1 deg/s: into the block mean, not rejected
    temp = 25 + np.arange(n) / n + rng.normal(0, 0.01, n)
    x = np.array([-3.3, 1.1, -0.5]) + 0.1 * rng.standard_normal((n, 3)) + np.outer(temp - 25, c)
    cal = GyroFilter(FS, temp_coefficient_dps_per_c=c)
    cal.filter(x[:200], temp[:200])
    glitched = temp.copy()
    glitched[200 + at] = -32768 / 340 + 36.53
    filters = [GyroFilter(FS, calibration=cal.calibration, temp_coefficient_dps_per_c=c) for _ in range(2)]
    rows = [f.filter(x[200:], t[200:]) for f, t in zip(filters, (temp, glitched))]
    assert np.abs(rows[0] - rows[1]).max() < 0.001
    assert filters[0].rejected.tolist() == filters[1].rejected.tolist()
