"""Fuzz of the real-time filter's inputs and settings (issue 22, part C).

Properties, over drawn inputs:

(a) ``--set NAME=VALUE`` texts (every setting name, values of every kind: huge, negative, zero,
    fractional numbers, bools, text, lists, JSON garbage; repeated keys) either build a filter
    whose settings are all in range, or raise SettingsError with one short line;
(b) any sequence of ``update()`` / ``filter()`` calls with drawn samples (finite up to and beyond
    MAX_RATE_DPS, ints, huge ints, NaN, inf, wrong shapes and types, any chunk sizes) gives rows
    that are all finite, or SettingsError when (and only when) a sample breaks the rule; after a
    SettingsError the filter is as if the call had never been made (a live source goes on);
(c) samples anywhere within +-MAX_RATE_DPS never give a non-finite row, for every preset and the
    default, with the Python kernels and numba's.

Each runs a few examples by default (derandomized, so CI is reproducible) and many more under
``-m slow``.
"""
import json
import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from gyrofilter import GyroFilter
from gyrofilter.filter.calibration import MAX_NOISE_STD_DPS, Calibration
from gyrofilter.cli import main
from gyrofilter.cli.filtering import make_filter
from gyrofilter.errors import CalibrationError, FilterDiverged, SettingsError
from gyrofilter.filter.jit import numba_available
from gyrofilter.filter.settings import SETTING_NAMES, SETTING_RANGES
from gyrofilter.filter.presets import PRESETS
from gyrofilter.units import MAX_RATE_DPS, TEMP_RANGE_C

BACKENDS = ["python"] + (["numba"] if numba_available() else [])
RATE_HZ = 100.0
FAST = dict(deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))


def _one_line(exc):
    text = str(exc)
    assert text and "\n" not in text and "Traceback" not in text and len(text) <= 300, text
    return text


def _still(n, seed=0):
    return np.random.default_rng(seed).normal([0.5, -0.3, 0.2], 0.05, (n, 3))


# ---------------------------------------------------------------------------- (a) --set texts

_CHOICES = ["paper", "adaptive", "variance", "std", "window", "calibration", "auto", "python", "numba", "kalman",
            "block_mean", "median_slope", "by_model", "recommended"]
_value_texts = st.one_of(
    st.integers(-(10 ** 450), 10 ** 450).map(str),
    st.integers(-5, 200).map(str),
    st.floats().map(repr),  # nan, inf, 1e+300, -0.0, 5e-324 ...
    st.floats(-10, 10).map(lambda v: f"{v:.3g}"),
    st.fractions(min_value=-1000, max_value=1000, max_denominator=7).map(lambda f: str(float(f))),
    st.sampled_from(["true", "false", "True", "False", "TRUE", "null", "NaN", "-Infinity", "1e999", "1_000", "0x10", ".5",
                     "5.", "", " ", "[", "{", "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]",
                     '{"a": 1}', "[1, 2, 3]", "[0.01, 0.02, 0]", "0.01,0.02,0", "0.01,0.02", "[true, 1, 2]", '"paper"']),
    st.sampled_from(_CHOICES),
    st.lists(st.one_of(st.integers(-3, 3), st.floats(-1, 1), st.booleans(), st.text(max_size=3)), max_size=4).map(json.dumps),
    st.text(max_size=12),
)
_names = st.one_of(st.sampled_from(SETTING_NAMES), st.sampled_from(SETTING_NAMES).map(lambda n: f" {n} "),
                   st.sampled_from(["sample_rate_hz", "calibration", "preset", "Block_len", ""]), st.text(max_size=8))
_set_texts = st.lists(st.one_of(st.tuples(_names, _value_texts).map("=".join), st.text(max_size=10)), max_size=4)


def _set_builds_or_refuses(texts, repeat, preset):
    texts = texts + texts[:1] if repeat else texts
    args = SimpleNamespace(set=texts, preset=preset, calibration_s=None, calibration=None, temp_model=None,
                           save_calibration=None)
    try:
        filt = make_filter(args, RATE_HZ)
    except SettingsError as exc:
        _one_line(exc)
        return
    names = [t.partition("=")[0].strip() for t in texts]
    assert len(set(names)) == len(names), "a repeated --set key must be refused"
    for name, bounds in SETTING_RANGES.items():
        value = getattr(filt.settings, name)
        assert type(value) in (int, float) and bounds["low"] <= value <= bounds["high"], (name, value)
    try:
        out = filt.filter(_still(400), np.full(400, 25.0))
    except CalibrationError:  # a strict stillness_z or max_bias_dps may refuse even this still window
        return
    assert np.isfinite(out).all()


@settings(max_examples=250, **FAST)
@given(texts=_set_texts, repeat=st.booleans(), preset=st.sampled_from(sorted(PRESETS)))
def test_set_texts_build_a_filter_or_are_refused_in_one_line(texts, repeat, preset):
    _set_builds_or_refuses(texts, repeat, preset)


@pytest.mark.slow
@settings(max_examples=5000, **FAST)
@given(texts=_set_texts, repeat=st.booleans(), preset=st.sampled_from(sorted(PRESETS)))
def test_set_texts_build_a_filter_or_are_refused_in_one_line_many(texts, repeat, preset):
    _set_builds_or_refuses(texts, repeat, preset)


@pytest.mark.parametrize("sets,refused", [
    (["block_len=4", "outlier_rule=median_slope"], None),
    (["stillness_z=true"], "setting stillness_z must be a finite number, got True"),
    (["qr_window=" + "7" * 400], "setting qr_window must be a finite number (a whole number)"),
    (["hold_window=1e12", "hold=true"], "setting hold_window must be in [2, 1000], got 1000000000000.0"),
    (["guard_k_sigma=2", "guard_k_sigma=3"], "--set guard_k_sigma: given twice"),
])
def test_replay_of_the_bundled_recording_with_set(tmp_path, capsys, sets, refused):
    out = tmp_path / "out.csv"
    argv = ["replay", "--out", str(out)] + [a for s in sets for a in ("--set", s)]
    assert main(argv) == (0 if refused is None else 2)
    err = capsys.readouterr().err
    if refused is None:
        assert out.exists()
    else:
        assert _one_line(err.strip()).startswith("gyrofilter: error: ") and refused in err and not out.exists()


# ---------------------------------------------------------------------------- (b) update() and filter() calls

def _is_rate(v):
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_)) and -MAX_RATE_DPS <= v <= MAX_RATE_DPS


def _is_sample(sample):
    """The rule of update(), written out: a tuple, list or array of shape (3,) of rates."""
    if isinstance(sample, np.ndarray):
        return sample.shape == (3,) and all(map(_is_rate, sample.tolist()))
    return isinstance(sample, (tuple, list)) and len(sample) == 3 and all(map(_is_rate, sample))


def _is_temperature(t):
    if t is None or isinstance(t, float) and math.isnan(t):
        return True
    return isinstance(t, (int, float)) and not isinstance(t, bool) and TEMP_RANGE_C[0] <= t <= TEMP_RANGE_C[1]


def _is_block(x):
    """The rule of filter(): an (N, 3) array of numbers, each a rate."""
    try:
        a = np.asarray(x)
    except ValueError:
        return False
    return a.dtype.kind in "iuf" and a.ndim == 2 and a.shape[1] == 3 and bool((np.abs(a.astype(float)) <= MAX_RATE_DPS).all())


_rates = st.one_of(st.floats(-MAX_RATE_DPS, MAX_RATE_DPS), st.integers(-100_000, 100_000), st.sampled_from([MAX_RATE_DPS, -MAX_RATE_DPS, 0.0]))
_absurd = st.one_of(st.floats(min_value=MAX_RATE_DPS, exclude_min=True), st.floats(max_value=-MAX_RATE_DPS, exclude_max=True),
                    st.sampled_from([math.nan, math.inf, -math.inf, 10 ** 400, -(10 ** 20), 100_001, True, None, "1", b"1"]))
_component = st.one_of(_rates, _rates, _rates, _rates, _rates, _rates, _absurd)
_samples = st.one_of(
    st.tuples(_component, _component, _component),
    st.lists(_component, min_size=3, max_size=3),
    st.lists(_rates, min_size=3, max_size=3).map(np.array),
    st.lists(_component, max_size=5),
    st.sets(st.integers(-10, 10), min_size=3, max_size=3),
    st.dictionaries(st.integers(0, 2), st.floats(-10, 10), min_size=3, max_size=3),
    st.sampled_from([None, 1.0, "1,2,3", np.zeros((3, 1)), np.zeros(3, dtype=bool), np.array(["1", "2", "3"])]),
)
_temps = st.one_of(st.none(), st.none(), st.none(), st.floats(-400, 600), st.sampled_from([math.nan, math.inf, 10 ** 400, "25", True]))
_blocks = st.one_of(
    hnp.arrays(np.float64, st.tuples(st.integers(0, 40), st.just(3)), elements=st.floats(-MAX_RATE_DPS, MAX_RATE_DPS)),
    hnp.arrays(np.float64, st.tuples(st.integers(1, 40), st.just(3)),
               elements=st.one_of(st.floats(-10, 10), st.floats(-10, 10), st.floats(allow_nan=True, allow_infinity=True))),
    hnp.arrays(np.int64, st.tuples(st.integers(0, 20), st.just(3)), elements=st.integers(-200_000, 200_000)),
    hnp.arrays(np.float64, st.tuples(st.integers(0, 5), st.integers(0, 4))),
    st.lists(st.lists(st.one_of(_rates, _absurd), min_size=2, max_size=4), max_size=6),
    st.sampled_from([None, "abc", {1, 2, 3}, np.zeros(3), np.zeros((2, 3), dtype=bool), [[1, 2, 3], [1, 2]]]),
)
_calls = st.lists(st.one_of(st.tuples(st.just("update"), _samples, _temps), st.tuples(st.just("filter"), _blocks, st.none())),
                  max_size=40)


def _new_filter(preset, loaded):
    if loaded:
        return GyroFilter(RATE_HZ, preset=preset, calibration=Calibration((0.5, -0.3, 0.2), (0.05, 0.05, 0.05), 200, RATE_HZ))
    filt = GyroFilter(RATE_HZ, preset=preset)
    filt.filter(_still(200))
    return filt


def _rows_of(call):
    """The rows ``call()`` returns (None: no row), or those before the first beyond the rates any gyro reads, which
    it raises with (FilterDiverged: attack pass 68), and that row's sample; every row finite and within them."""
    try:
        rows, at = call(), None
    except FilterDiverged as exc:
        rows, at = exc.rows, exc.sample
    assert rows is None or np.all(np.abs(rows) <= MAX_RATE_DPS * (1 + 1e-10)), rows
    return (None if rows is None else np.asarray(rows)), at


def _calls_finish_or_refuse(calls, preset, loaded):
    """Filter a gets every call; filter b only those a accepted: their rows and states must agree."""
    a, b = _new_filter(preset, loaded), _new_filter(preset, loaded)
    for kind, value, temp in calls:
        valid = _is_sample(value) and _is_temperature(temp) if kind == "update" else _is_block(value)
        try:
            rows, at = _rows_of(lambda: a.update(value, temp) if kind == "update" else a.filter(value))
        except SettingsError as exc:
            _one_line(exc)
            assert not valid, (kind, value, temp, str(exc))
            continue
        assert valid, (kind, value, temp)
        expected, expected_at = _rows_of(lambda: b.update(value, temp) if kind == "update" else b.filter(value))
        assert (rows is None) == (expected is None) and (rows is None or np.array_equal(rows, expected)) and at == expected_at
    assert (a.samples_in, a.pending_samples, a.blocks_out) == (b.samples_in, b.pending_samples, b.blocks_out)
    assert np.array_equal(a.rejected, b.rejected) and a.guard_reseeds == b.guard_reseeds
    tail = _still(7, seed=1)  # the next valid samples give the same rows as if the refused ones were never sent
    (rows, at), (expected, expected_at) = _rows_of(lambda: a.filter(tail)), _rows_of(lambda: b.filter(tail))
    assert np.array_equal(rows, expected) and at == expected_at


@settings(max_examples=120, **FAST)
@given(calls=_calls, preset=st.sampled_from(["paper", "recommended", "hold"]), loaded=st.booleans())
def test_update_and_filter_give_finite_rows_or_refuse_and_change_nothing(calls, preset, loaded):
    _calls_finish_or_refuse(calls, preset, loaded)


@pytest.mark.slow
@settings(max_examples=3000, **FAST)
@given(calls=_calls, preset=st.sampled_from(sorted(PRESETS)), loaded=st.booleans())
def test_update_and_filter_give_finite_rows_or_refuse_and_change_nothing_many(calls, preset, loaded):
    _calls_finish_or_refuse(calls, preset, loaded)


# ---------------------------------------------------------------------------- (c) finite rows up to the bound

_edges = st.sampled_from([MAX_RATE_DPS, -MAX_RATE_DPS, 0.0, MAX_RATE_DPS / 3, -MAX_RATE_DPS / 7, 1e-300])
_patterns = hnp.arrays(np.float64, st.tuples(st.integers(1, 40), st.just(3)),
                       elements=st.one_of(_edges, _edges, st.floats(-MAX_RATE_DPS, MAX_RATE_DPS)))
_calibrations = st.one_of(
    st.none(),  # a start-up window of still samples
    st.builds(lambda bias, noise: Calibration((bias, -bias, 0.0), (noise,) * 3, 200, RATE_HZ),
              st.sampled_from([0.0, MAX_RATE_DPS, -MAX_RATE_DPS, 1.0]), st.sampled_from([0.0, 1e-3, 0.1, MAX_NOISE_STD_DPS])),
)


def _rows_are_finite(preset, backend, pattern, repeats, calibration, n_max):
    """The pattern repeated (adversarial periodic motion at the bound), fed in one call."""
    x = np.tile(pattern, (repeats, 1))[:n_max]
    chosen = {} if preset is None else {"preset": preset}
    # the largest bias a calibration may hold is the max_bias_dps setting's top, MAX_RATE_DPS
    filt = GyroFilter(RATE_HZ, backend=backend, calibration=calibration, max_bias_dps=MAX_RATE_DPS, **chosen)
    if calibration is None:
        filt.filter(_still(200))
    rows, at = _rows_of(lambda: filt.filter(x))  # finite, within the rates any gyro reads
    assert len(rows) == len(x) // filt.settings.block_len if at is None else len(rows) < len(x) // filt.settings.block_len


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("preset", [None, *sorted(PRESETS)], ids=["default", *sorted(PRESETS)])
@settings(max_examples=8, **FAST)
@given(pattern=_patterns, repeats=st.integers(1, 300), calibration=_calibrations)
def test_samples_up_to_the_bound_give_finite_rows(preset, backend, pattern, repeats, calibration):
    _rows_are_finite(preset, backend, pattern, repeats, calibration, n_max=3000)


@pytest.mark.slow
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("preset", [None, *sorted(PRESETS)], ids=["default", *sorted(PRESETS)])
@settings(max_examples=40, **FAST)
@given(pattern=_patterns, repeats=st.integers(1, 5_000), calibration=_calibrations)
def test_samples_up_to_the_bound_give_finite_rows_many(preset, backend, pattern, repeats, calibration):
    _rows_are_finite(preset, backend, pattern, repeats, calibration, n_max=50_000)


def test_a_numpy_bool_as_hold_is_the_bool_it_holds():
    """Attack pass 29b: ``GyroFilter(preset="hold", hold=np.bool_(True))`` was refused as
    "setting hold=True: must be True or False"; the settings hold a plain bool (state_dict is JSON)."""
    import json
    f = GyroFilter(100.0, preset="hold", hold=np.bool_(True))
    assert f.settings.hold is True
    json.dumps(f.state_dict())
