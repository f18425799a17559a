"""Units helpers: conversions, the sample-rate check, and plain numbers in error messages."""
import math
import tracemalloc

import numpy as np
import pytest

from gyrofilter import GyroFilter
from gyrofilter.errors import GyroFilterError, SettingsError
from gyrofilter.recording import read_recording
from gyrofilter.evaluation.reference import body_rate_from_quaternions
from gyrofilter.filter.tempcomp import compensate
from gyrofilter.units import MIN_SAMPLE_RATE_HZ, check_sample_rate_hz, from_dps, json_ready, plain, to_dps, to_mps2


def test_plain_writes_numpy_scalars_as_the_numbers_they_hold():
    assert plain(np.float64(14.99)) == "14.99"
    assert plain(np.int64(7)) == "7"
    assert plain(np.float32(0.5)) == "0.5"
    assert plain((np.float64(1.5), 2)) == "(1.5, 2)"
    assert plain(np.array([1.0, -2.0])).startswith("array([")  # says it is an array
    assert plain("abc") == "'abc'" and plain(None) == "None"


def test_lsb_round_trip_and_bad_unit():
    x = np.array([[131.0, -262.0, 0.0]])
    assert np.allclose(from_dps(to_dps(x, "lsb", 131.0), "lsb", 131.0), x)
    with pytest.raises(GyroFilterError, match="got -131.0$"):
        to_dps(x, "lsb", np.float64(-131.0))


@pytest.mark.parametrize("convert, args", [(to_dps, ("lsb", 131.0)), (to_dps, ("rad/s",)), (to_mps2, ("g",)),
                                            (to_mps2, ("lsb", 16384.0))])
def test_a_conversion_spends_only_its_own_float64_copy(convert, args):
    """A float32 or int16 column is converted in its float64 copy (one array, not two: issue 39's
    memory); a float64 one, the caller's, is left as it was. The numbers are the same either way."""
    x = np.array([131.0, -262.0, 3.0, 0.0])
    want = convert(x.copy(), *args)
    assert np.array_equal(x, [131.0, -262.0, 3.0, 0.0]) and want is not x
    for narrow in (x.astype(np.float32), x.astype(np.int16)):
        got = convert(narrow, *args)
        assert got.dtype == np.float64 and np.array_equal(got, want) and narrow[0] == 131
    column = np.ones(1_000_000, dtype=np.float32)
    tracemalloc.start()
    try:
        convert(column, *args)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1.1 * 8 * column.size  # one float64 array (two before)


RECORDING_T_BACKWARDS = """# gyrofilter-recording: 1
# sample_rate_hz: 100
# gyro_unit: dps
t,gx,gy,gz
15.0,0,0,0
14.99,0,0,0
"""


def _read_text(text):
    """read_recording of ``text`` written to a fresh temporary file."""
    import tempfile
    from pathlib import Path

    path = Path(tempfile.mkdtemp()) / "rec.csv"
    path.write_text(text, encoding="utf-8")
    return read_recording(path)


@pytest.mark.parametrize("call, expected", [
    (lambda: _read_text(RECORDING_T_BACKWARDS), "(14.99 after 15.0)"),
    (lambda: check_sample_rate_hz(np.float64(-14.99)), "got -14.99"),
    (lambda: body_rate_from_quaternions(np.ones((4, 4)), 100.0, half_span=np.float64(1.5)), "got 1.5"),
    (lambda: compensate(np.zeros((2, 3)), np.zeros(2), np.float64(np.nan), 25.0), "got nan"),
    (lambda: GyroFilter(np.float64(100.0), calibration_s=np.float64(0.01)), "calibration_s=0.01 gives 1"),
], ids=["recording-t", "sample-rate", "reference", "tempcomp", "pipeline"])
def test_error_messages_print_numpy_scalars_as_plain_numbers(call, expected):
    with pytest.raises(GyroFilterError) as info:
        call()
    assert expected in str(info.value) and "np." not in str(info.value)


def test_json_ready_gives_what_strict_json_takes():
    import json

    value = {1: (np.float64(np.nan), np.inf, -np.inf), "a": np.arange(2), "b": [np.float32(0.5), np.bool_(True), None, "s"]}
    text = json.dumps(json_ready(value), allow_nan=False)
    assert json.loads(text) == {"1": [None, None, None], "a": [0, 1], "b": [0.5, True, None, "s"]}


def test_json_ready_takes_a_longdouble():
    """Attack pass 29b: a longdouble's ``tolist()`` is itself: json_ready recursed until Python's
    RecursionError (an array of them too)."""
    import json

    value = {"a": np.longdouble(1.5), "b": np.array([np.longdouble(0.25), np.longdouble("inf")])}
    assert json.loads(json.dumps(json_ready(value), allow_nan=False)) == {"a": 1.5, "b": [0.25, None]}


@pytest.mark.parametrize("value, shown", [(float("inf"), "inf"), (-float("inf"), "-inf"), (float("nan"), "nan"), (0, "0.0"),
                                          (0.0, "0.0"), (-100.0, "-100.0"), (np.float64(-2.5), "-2.5"), ("100", "'100'"),
                                          (True, "True"), (1e6, "1000000.0"), (1e-320, "1e-320"), (0.0009, "0.0009"),
                                          (10**400, f"{str(10**400)[:80]}... (401 characters)")])
def test_check_sample_rate_hz_refuses_with_one_wording_naming_the_value(value, shown):
    with pytest.raises(SettingsError) as info:
        check_sample_rate_hz(value, "--sample-rate-hz")
    assert str(info.value) == f"--sample-rate-hz must be a number of Hz in [0.001, 100000], got {shown}"
    assert check_sample_rate_hz(np.int64(100)) == 100.0 and type(check_sample_rate_hz(8000)) is float


def _sample_rate_takers():
    """Every module that takes a sample rate, called with ``rate`` (what each checks first)."""
    from gyrofilter.analysis.noise.allan import overlapping_adev
    from gyrofilter.analysis.arma.identify import prepare_series
    from gyrofilter.analysis.arma.bias_kf import BiasKalmanFilter
    from gyrofilter.sim.profiles import profile_samples_dps
    from gyrofilter.sim.model import validate_model
    from gyrofilter.sources.mpu6050.driver import sample_rate_settings

    header = "# gyrofilter-recording: 1\n# sample_rate_hz: {}\n# gyro_unit: dps\ngx,gy,gz\n0,0,0\n"
    return {
        "pipeline": lambda rate: GyroFilter(rate),
        "recording": lambda rate: _read_text(header.format(rate)),
        "allan": lambda rate: overlapping_adev(np.ones(100), rate),
        "arma": lambda rate: prepare_series(np.zeros(200), rate),
        "bias_kf": lambda rate: BiasKalmanFilter(rate),
        "profiles": lambda rate: profile_samples_dps("steps", rate),
        "reference": lambda rate: body_rate_from_quaternions(np.tile([1.0, 0, 0, 0], (5, 1)), rate),
        "simulate": lambda rate: validate_model({"sample_rate_hz": rate}),
        "mpu6050": lambda rate: sample_rate_settings(rate, 3),
    }


@pytest.mark.parametrize("where", list(_sample_rate_takers()))
@pytest.mark.parametrize("rate", [float("inf"), float("nan"), 0.0, -1.0, 1e-300, 1e-320, 0.000999])
def test_every_sample_rate_taker_refuses_it_with_the_one_check(where, rate):
    """One wording everywhere; a recording's header is text, whose inf and nan are refused by the
    one reader of numbers in text (inputs.parse_number) before the rate is checked."""
    if where == "recording" and not math.isfinite(rate):
        expected = f"sample_rate_hz must be a plain decimal number .*, got '{rate}'"
    else:
        expected = r"rate_hz must be a number of Hz in \[0.001, 100000\], got " + str(rate)
    with pytest.raises(GyroFilterError, match=expected):
        _sample_rate_takers()[where](rate)


def test_the_lowest_sample_rate_is_accepted():
    assert check_sample_rate_hz(MIN_SAMPLE_RATE_HZ) == 0.001


@pytest.mark.parametrize("scale", [float("nan"), float("inf"), 1e-300, 1e300])
@pytest.mark.parametrize("convert", ["to_dps", "from_dps", "to_mps2"])
def test_a_scale_no_sensor_has_is_refused_by_the_conversions(convert, scale):
    """Attack pass 22: convert_gyro(rec, "lsb", nan) gave a recording of NaN rates, an lsb_per_dps of
    inf read every sample as 0 deg/s, 1e-300 as 6e-303 LSB: the conversions took any scale that is
    not <= 0, where the headers and options take LSB_PER_DPS_RANGE / LSB_PER_G_RANGE."""
    function = {"to_dps": to_dps, "from_dps": from_dps, "to_mps2": to_mps2}[convert]
    with pytest.raises(SettingsError, match="must be a number of LSB per"):
        function(np.ones((4, 3)), "lsb", scale)


def test_a_rate_or_scale_in_a_0d_array_is_the_number_it_holds():
    """Attack pass 26: GyroFilter(np.array(100.0)) said "sample_rate_hz must be a number of Hz in
    [0.001, 100000], got array(100.)" while calibration_s=np.array(2.0) was taken (inputs.scalar)."""
    from gyrofilter import GyroFilter
    from gyrofilter.units import check_lsb_per_g, check_sample_rate_hz
    assert check_sample_rate_hz(np.array(100.0)) == 100.0 and type(check_sample_rate_hz(np.array(100))) is float
    assert GyroFilter(np.array(100.0)).sample_rate_hz == 100.0
    assert check_lsb_per_g(np.array(16384.0), "lsb_per_g") == 16384.0
    with pytest.raises(SettingsError, match=r"got array\(\[100\.\]\)"):
        check_sample_rate_hz(np.array([100.0]))
