"""Numbers as an embedding programmer passes them (issue 37, attack pass 30a): every numeric or
boolean parameter of the documented Python API (docs/formats.md section 7, docs/settings.md,
docs/simulate.md, docs/allan.md, docs/live.md) given as numpy's scalars or a 0-d array gives what
the plain Python value gives (the same numbers, the same JSON-ready state), a value refused is
refused in the same words, and True/False are refused where a number is asked (the rule:
``inputs.check_number``, ``inputs.scalar``, ``inputs.python_value``). One seed, about 5 s."""
import collections
import dataclasses
import functools
import json
import math
from collections import namedtuple
from fractions import Fraction

import numpy as np
import pytest

from gyrofilter import GyroFilter, GyroFilterError, smooth
from gyrofilter.analysis.arma.bias_kf import BiasKalmanFilter
from gyrofilter.analysis.noise.allan import adev, chi2_interval, overlapping_adev
from gyrofilter.analysis.noise.fit import characterise_axis
from gyrofilter.filter.calibration import Calibration, calibrate
from gyrofilter.filter.settings import FilterSettings, SETTING_RANGES
from gyrofilter.filter.tempcomp import compensate
from gyrofilter.errors import SettingsError, SourceEnded
from gyrofilter.recording import Recording, RecordingWriter, iter_recording, read_recording, write_recording
from gyrofilter.sim.hidden_effects import hide_in_recording
from gyrofilter.sim.simulate import simulate, simulate_chunks
from gyrofilter.sources import open_source
from gyrofilter.sources.replay import ReplaySource
from gyrofilter.sources.simulated import SimulatedSource

RNG = np.random.default_rng(30)
STILL_DPS = np.array([-3.3, 1.1, -0.5]) + 0.1 * RNG.standard_normal((300, 3))


def model(bias_dps=0.5, **effect):
    """A small simulator model (docs/formats.md section 2), one effect on x when given."""
    axes = {a: {"bias_dps": bias_dps, "arw_dps_per_sqrt_hz": 0.01, "effects": []} for a in "xyz"}
    if effect:
        axes["x"]["effects"].append(effect)
    return {"sample_rate_hz": 50.0, "gyro_unit": "dps", "axes": axes}


MODEL = model()


def forms(value):
    """``value`` (a plain Python number or bool) as an embedding programmer may pass it: numpy's
    scalars of each kind that holds it exactly, and a 0-d array."""
    if isinstance(value, bool):
        return {"np.bool_": np.bool_(value)}
    out = {"np.float64": np.float64(value), "np.longdouble": np.longdouble(value), "0-d array": np.array(value)}
    if float(np.float32(value)) == value:
        out["np.float32"] = np.float32(value)
    if float(value).is_integer():
        out["np.int64"] = np.int64(value)
        if abs(value) < 2**31:
            out["np.int32"] = np.int32(value)
        if 0 <= value < 256:
            out["np.uint8"] = np.uint8(value)
    return out


def outcome(call, value):
    """What ``call(value)`` gives, comparable: ("ok", its result as JSON text) or ("refused", the
    error's type and words). JSON text: a result that holds a numpy scalar where Python's would
    hold a float (a settings dict) fails to be written, as it fails a user's ``json.dumps``."""
    try:
        result = call(value)
    except GyroFilterError as exc:
        return ("refused", type(exc).__name__, str(exc))
    return ("ok", json.dumps(result, sort_keys=True, default=_array))


def _array(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def _filter(**kw):
    f = GyroFilter(100.0, **{"calibration_s": 1.0, **kw})
    return {"state": f.state_dict(), "rows": f.filter(STILL_DPS)}


def _cal(**kw):
    """A calibration given in code: its file's text and a filter started from it."""
    args = dict(bias_dps=(-3.3, 1.1, -0.5), noise_std_dps=(0.1, 0.1, 0.1), samples=200, sample_rate_hz=100.0)
    cal = Calibration(**{**args, **kw})
    f = GyroFilter(100.0, calibration=cal)
    saved = json.loads(cal.to_json())
    saved.pop("created_utc")  # the clock's
    return {"file": saved, "rows": f.filter(STILL_DPS), "state": f.state_dict()}


@functools.lru_cache(maxsize=1)
def _recording():
    """A 2-s recording of MODEL (seeded), made once."""
    return simulate(MODEL, 2.0, seed=1)


def _replay(tmp, **kw):
    src = ReplaySource(_written(tmp), **kw)
    try:
        return {"rate": src.sample_rate_hz, "rows": np.asarray(src.read()).tolist()}
    finally:
        src.close()


def _written(tmp):
    path = tmp / "rec.csv"
    if not path.exists():
        write_recording(path, _recording())
    return path


def _read(tmp, **kw):
    rec = read_recording(_written(tmp), **kw)
    return {"header": rec.header, "gx": rec.columns["gx"]}


def _rewritten(tmp, **kw):
    path = tmp / "rewritten.csv.gz"
    write_recording(path, _recording(), **kw)
    return {"gx": read_recording(path).columns["gx"]}


def _writer(tmp, **kw):
    path = tmp / "writer.csv.gz"
    rec = _recording()
    with RecordingWriter(path, rec.header, list(rec.columns), **kw) as w:
        w.write(np.column_stack([rec.columns[c] for c in rec.columns]))
    return {"gx": read_recording(path).columns["gx"]}


def _opened(spec, **defaults):
    with open_source(spec, **defaults) as src:
        return {"rate": src.sample_rate_hz, "rows": np.asarray(src.read()).tolist()}


def _simulated(**kw):
    src = SimulatedSource(model=MODEL, **{"seed": 1, "realtime": False, "duration_s": 1.0, **kw})
    try:
        chunks = []
        try:
            while True:
                chunks.append(np.asarray(src.read()).tolist())
        except SourceEnded:
            return chunks
    finally:
        src.close()


def _filter_setting_cases():
    """Every numeric and boolean setting of FilterSettings: its default (and True/False for a bool)."""
    for field in dataclasses.fields(FilterSettings):
        if isinstance(field.default, bool):
            for v in (True, False):
                yield f"GyroFilter({field.name})", (lambda name: lambda v: _filter(**{name: v}))(field.name), v, None
        elif field.name in SETTING_RANGES and isinstance(field.default, (int, float)):
            bounds = SETTING_RANGES[field.name]
            bad = bounds["high"] * 2 if bounds.get("high") is not None else -1
            yield f"GyroFilter({field.name})", (lambda name: lambda v: _filter(**{name: v}))(field.name), field.default, bad


def cases(tmp):
    """(name, call of one value, a valid value, an invalid value or None). Small and fast."""
    yield from _filter_setting_cases()
    yield "GyroFilter(sample_rate_hz)", lambda v: GyroFilter(v, calibration_s=1.0).filter(STILL_DPS), 100, 0
    yield "GyroFilter(calibration_s, positional)", lambda v: GyroFilter(100.0, v).filter(STILL_DPS), 1, -1
    yield "GyroFilter(temp_coefficient_dps_per_c)", lambda v: GyroFilter(100.0, 1.0, temp_coefficient_dps_per_c=v).state_dict(), 0.5, 100
    yield "GyroFilter.update(sample)", lambda v: _update_rows(lambda s, last: (v, s[1], s[2]) if last else s), 1, 1e9
    yield "GyroFilter.update(temp_c)", lambda v: _update_rows(lambda s, last: s, temp_c=v), 25, 1000
    yield "GyroFilter.filter(temp_c)", lambda v: GyroFilter(100.0, 1.0).filter(STILL_DPS, temp_c=np.full(len(STILL_DPS), v)), 25, 1000
    yield "GyroFilter.block_end_indices(n)", lambda v: _filtered().block_end_indices(v), 3, -1
    yield "smooth(sample_rate_hz)", lambda v: smooth(STILL_DPS, v, 1.0), 100, 0
    yield "smooth(calibration_s)", lambda v: smooth(STILL_DPS, 100.0, v), 1, -1
    yield "Calibration(samples)", lambda v: _cal(samples=v), 200, -1
    yield "Calibration(sample_rate_hz)", lambda v: _cal(sample_rate_hz=v), 100, 0
    yield "Calibration(temp_c)", lambda v: _cal(temp_c=v), 25, 1000
    yield "Calibration(bias_dps x)", lambda v: _cal(bias_dps=(v, 1.1, -0.5)), -3, 100
    yield "Calibration(noise_std_dps x)", lambda v: _cal(noise_std_dps=(v, 0.1, 0.1)), 0.5, -1
    # attack pass 31b: calibrate's rate and Recording.from_dps's were taken as True (1 Hz), calibrate's as 0
    yield "calibrate(sample_rate_hz)", lambda v: dataclasses.asdict(calibrate(STILL_DPS, v)), 100, 0
    yield "calibrate(stillness_threshold)", lambda v: dataclasses.asdict(calibrate(STILL_DPS, 100.0, stillness_threshold=v)), 6, -1
    yield "calibrate(max_bias_dps)", lambda v: dataclasses.asdict(calibrate(STILL_DPS, 100.0, max_bias_dps=v)), 20, -1
    yield "Recording.from_dps(sample_rate_hz)", lambda v: Recording.from_dps(STILL_DPS, v).header, 100, 0
    yield "BiasKalmanFilter(sample_rate_hz)", lambda v: BiasKalmanFilter(v).filter(STILL_DPS), 100, 0
    for name, good in (("calibration_s", 1), ("bias_sigma_dps", 0.5), ("still_window_s", 0.5), ("still_gate_sigma", 4),
                       ("bias_tau_s", 100), ("bias_walk_dps_per_sqrt_s", 0.01), ("rate_walk_dps_per_sqrt_s", 50),
                       ("noise_std_dps", 0.1), ("zero_rate_std_dps", 0.002), ("still_enter_ratio", 2), ("still_exit_ratio", 3),
                       ("still_max_offset_dps", 1), ("initial_bias_std_dps", 0.01)):
        yield f"BiasKalmanFilter({name})", (lambda n: lambda v: dataclasses.asdict(BiasKalmanFilter(100.0, **{n: v}).settings))(name), good, -1
    yield "simulate(model bias_dps)", lambda v: simulate(model(bias_dps=v), 1.0, seed=1).gyro_dps, 2, None
    yield "simulate(model effect)", lambda v: simulate(model(effect="sinusoid", frequency_hz=v, amplitude_dps=0.1),
                                                       1.0, seed=1).gyro_dps, 5, -1
    yield "simulate(duration_s)", lambda v: simulate(MODEL, v, seed=1).gyro_dps, 1, -1
    yield "simulate(seed)", lambda v: simulate(MODEL, 1.0, seed=v).gyro_dps, 7, -1
    yield "simulate(sample_rate_hz)", lambda v: simulate(MODEL, 1.0, seed=1, sample_rate_hz=v).gyro_dps, 25, -1
    yield "simulate(chunk_samples)", lambda v: simulate(MODEL, 1.0, seed=1, chunk_samples=v).gyro_dps, 16, 0
    yield "simulate(accelerometer)", lambda v: simulate(MODEL, 1.0, seed=1, accelerometer=v).gyro_dps, False, None
    yield "simulate_chunks(chunk_samples)", lambda v: [c.gyro for c in simulate_chunks(MODEL, 1.0, seed=1, chunk_samples=v)], 16, 0
    yield "SimulatedSource(seed)", lambda v: _simulated(seed=v), 3, -1
    yield "SimulatedSource(duration_s)", lambda v: _simulated(duration_s=v), 1, -1
    yield "SimulatedSource(sample_rate_hz)", lambda v: _simulated(sample_rate_hz=v), 25, 0
    yield "SimulatedSource(realtime)", lambda v: _simulated(realtime=v, sleep=lambda s: None), False, None
    yield "ReplaySource(speed)", lambda v: _replay(tmp, speed=v), 2, -1
    yield "ReplaySource(realtime)", lambda v: _replay(tmp, realtime=v, sleep=lambda s: None), False, None
    yield "ReplaySource(chunk_rows)", lambda v: _replay(tmp, chunk_rows=v), 16, 0
    yield "open_source(sim, seed=)", lambda v: _opened("sim:realtime=0,duration=1", seed=v), 3, -1
    yield "open_source(sim, sample_rate_hz=)", lambda v: _opened("sim:realtime=0,duration=1,seed=1", sample_rate_hz=v), 25, 0
    yield "read_recording(compact)", lambda v: _read(tmp, compact=v), True, None
    yield "iter_recording(chunk_rows)", lambda v: list(iter_recording(_written(tmp), chunk_rows=v))[1:], 16, 0
    yield "write_recording(compresslevel)", lambda v: _rewritten(tmp, compresslevel=v), 9, 10
    yield "RecordingWriter(flush_interval_s)", lambda v: _writer(tmp, flush_interval_s=v), 2, -1
    yield "RecordingWriter(fsync)", lambda v: _writer(tmp, fsync=v), False, None
    yield "RecordingWriter(compresslevel)", lambda v: _writer(tmp, compresslevel=v), 1, 10
    yield "compensate(coefficient_dps_per_c)", lambda v: compensate(STILL_DPS, np.full(len(STILL_DPS), 30.0), v, 25.0), 0.5, np.nan
    yield "compensate(reference_temp_c)", lambda v: compensate(STILL_DPS, np.full(len(STILL_DPS), 30.0), 0.5, v), 25, np.nan
    yield "overlapping_adev(sample_rate_hz)", lambda v: overlapping_adev(STILL_DPS[:, 0], v), 100, 0
    yield "adev(sample_rate_hz)", lambda v: adev(STILL_DPS[:, 0], v), 100, 0
    yield "chi2_interval(confidence)", lambda v: chi2_interval(np.array([1.0, 2.0]), np.array([5.0, 9.0]), v), 0.5, 2
    yield "characterise_axis(sample_rate_hz)", lambda v: _characterised(sample_rate_hz=v), 100, 0
    yield "characterise_axis(confidence)", lambda v: _characterised(confidence=v), 0.5, 2
    yield "characterise_axis(min_clusters)", lambda v: _characterised(min_clusters=v), 9, 1
    yield "hide_in_recording(seed)", lambda v: hide_in_recording(_recording(), "outliers", "x",
                                                                 {"rate": 0.01, "magnitude_dps": 2.0}, seed=v).gyro_dps, 3, -1
    yield "hide_in_recording(params)", lambda v: hide_in_recording(_recording(), "outliers", "x",
                                                                   {"rate": 0.01, "magnitude_dps": v}, seed=1).gyro_dps, 2, -1
    yield from _model_cases()
    yield from _hidden_cases()
    # attack pass 32a: one element of the arrays smooth and filter_timed take
    yield "smooth(temp_c element)", lambda v: smooth(STILL_DPS, 100.0, 1.0, temp_c=[25.0] * 299 + [v],
                                                     temp_coefficient_dps_per_c=0.1), 30, 1000
    yield "GyroFilter.filter_timed(t_s element)", lambda v: _timed(v), 3.5, -1


#: attack pass 32a: every number of the simulator's model (docs/formats.md section 2), by effect:
#: (its parameters, a valid value), one case a parameter; the invalid value 1e9 is beyond the limits
#: of all but times (-1 for them)
EFFECT_PARAMS = {
    "bias_instability": {"b_dps": 0.01, "tau_min_s": 0.1, "tau_max_s": 10, "per_decade": 2},
    "rate_random_walk": {"k_dps_per_sqrt_s": 0.01}, "rate_ramp": {"r_dps_per_s": 0.01},
    "gauss_markov": {"sigma_dps": 0.02, "tau_s": 3}, "sinusoid": {"frequency_hz": 5, "amplitude_dps": 0.1, "phase_rad": 0.5},
    "temperature": {"coefficient_dps_per_c": 0.02, "reference_c": 25}, "bias_step": {"time_s": 0.5, "size_dps": 0.2},
    "warmup": {"amplitude_dps": 0.5, "tau_s": 2}, "outliers": {"rate": 0.05, "magnitude_dps": 2, "spread_ln": 0.25},
    "colored_noise": {"lag1": 0.5, "lag2": 0.25}, "narrowband": {"center_hz": 10, "bandwidth_hz": 1, "rms_dps": 0.1},
    "heavy_tails": {"fraction": 0.125, "scale_ratio": 5},
    "wandering_tone": {"center_hz": 10, "spread_hz": 0.5, "wander_s": 1, "amplitude_dps": 0.1,
                       "excursion_hz": 1, "excursion_s": 0.25, "excursion_period_s": 0.5},
    "arma": {"sigma_a_dps": 0.1, "phi": [0.5], "theta": [0.25]}, "resonance": {"center_hz": 10, "q": 2, "rms_dps": 0.1},
    "ringing": {"center_hz": 10, "q": 2, "shock_rate_hz": 1, "shock_dps": 1},
    "compression": {"gamma_per_dps2": 0.5, "rms_dps": 0.125}}
TEMPERATURE = {"start_c": 24.5, "end_c": 27.5, "tau_s": 1, "cycle_amplitude_c": 0.5, "cycle_period_s": 0.5, "noise_c": 0.03,
               "resolution_c": 0.5}
ACCEL_AXIS = {"bias_mps2": 0.25, "vrw_mps_per_sqrt_s": 0.01, "b_mps2": 0.01, "k_mps2_per_sqrt_s": 0.01,
              "coefficient_mps2_per_c": 0.01}


def _with(path, value, doc):
    """``doc`` (a JSON-like model, copied) with the number at ``path`` (keys and list indices) set to ``value``."""
    doc = json.loads(json.dumps(doc))
    *parents, last = path
    node = functools.reduce(lambda d, k: d[k], parents, doc)
    node[last] = value
    return doc


def _simulated_model(doc):
    rec = simulate(doc, 0.5, seed=1)
    return {name: rec.columns[name] for name in rec.columns}


def _model_cases():
    """One case a number of the model: the top-level keys, the temperature profile (both
    forms), the accelerometer, an axis and every effect's parameters (an element of a list)."""
    warm = {**model(), "temperature": TEMPERATURE}
    top = [(("sample_rate_hz",), 50, model()), (("lsb_per_dps",), 131, {**model(), "gyro_unit": "lsb", "lsb_per_dps": 131}),
           (("full_scale_dps",), 250, model()), (("repeated_samples", "fraction"), 0.125, {**model(), "repeated_samples": {}}),
           (("axes", "y", "bias_dps"), 0.5, model()), (("axes", "y", "arw_dps_per_sqrt_hz"), 0.01, model()),
           (("temperature", "t_s", 1), 0.25, {**model(), "temperature": {"t_s": [0, 0.25], "temp_c": [25, 26]}}),
           (("temperature", "temp_c", 1), 26, {**model(), "temperature": {"t_s": [0, 0.25], "temp_c": [25, 26]}}),
           (("accelerometer", "lsb_per_g", ), 16384, {**warm, "accelerometer": {}})]
    top += [(("temperature", key), value, warm) for key, value in TEMPERATURE.items()]
    top += [(("accelerometer", "axes", "x", key), value, {**warm, "accelerometer": {"axes": {"x": {}}}})
            for key, value in ACCEL_AXIS.items()]
    for effect, params in EFFECT_PARAMS.items():
        doc = model(**{"effect": effect, **params}) if effect != "temperature" else \
            {**model(**{"effect": effect, **params}), "temperature": TEMPERATURE}
        for key, value in params.items():
            path = ("axes", "x", "effects", 0, key) + ((0,) if isinstance(value, list) else ())
            top.append((path, value[0] if isinstance(value, list) else value, doc))
    for path, good, doc in top:
        call = (lambda p, d: lambda v: _simulated_model(_with(p, v, d)))(path, doc)
        # times (a table's, a time constant's) take any length, a lsb_per_g up to 3e9
        bad = -1 if path[-2:] == ("t_s", 1) or str(path[-1]).endswith("_s") and "per_s" not in str(path[-1]) else 0.1 if path[-1] == "lsb_per_g" else 1e9
        yield f"simulate(model {'.'.join(map(str, path))})", call, good, bad


def _hidden_cases():
    """hide_in_recording's parameters of the effects it hides in a recording's own noise, and
    of an effect it simulates (an element of a list): one case a parameter."""
    hidden = {"colored_noise": {"lag1": 0.5, "lag2": 0.25}, "heavy_tails": {"fraction": 0.125, "scale_ratio": 5},
              "compression": {"gamma_per_dps2": 0.5, "rms_dps": 0.0625}, "arma": {"sigma_a_dps": 0.1, "phi": [0.5], "theta": [0.25]},
              "repeated_samples": {"fraction": 0.125}}
    for effect, params in hidden.items():
        for key, value in params.items():
            def call(v, effect=effect, key=key, params=params):
                given = {**params, key: [v] if isinstance(params[key], list) else v}
                return hide_in_recording(_recording(), effect, "x", given, seed=1).gyro_dps
            yield f"hide_in_recording({effect} {key})", call, value[0] if isinstance(value, list) else value, 1e9


def _timed(t_last):
    """filter_timed of STILL_DPS with its last time ``t_last`` (s), the others 0.01 s apart."""
    t_s = [i / 100.0 for i in range(len(STILL_DPS) - 1)] + [t_last]
    t_rows_s, rows = GyroFilter(100.0, 1.0).filter_timed(STILL_DPS, t_s)
    return {"t": t_rows_s, "rows": rows}


def _update_rows(sample_of, temp_c=None):
    f = GyroFilter(100.0, 1.0)
    rows = [f.update(sample_of(tuple(s), i == len(STILL_DPS) - 1), temp_c) for i, s in enumerate(STILL_DPS)]
    return [r for r in rows if r is not None], f.state_dict()


def _filtered():
    f = GyroFilter(100.0, 1.0)
    f.filter(STILL_DPS)
    return f


def _characterised(**kw):
    kw = {"sample_rate_hz": 100.0, **kw}
    x = 0.1 * np.random.default_rng(2).standard_normal(2000)
    result = characterise_axis(x, kw.pop("sample_rate_hz"), **kw)
    return result if isinstance(result, (dict, list)) else repr(result)


def _ids(tmp):
    return [c[0] for c in cases(tmp)]


@pytest.fixture(scope="module")
def tmp(tmp_path_factory):
    return tmp_path_factory.mktemp("numbers")


@pytest.mark.parametrize("index", range(len(_ids(None))), ids=_ids(None))
def test_numpy_numbers_are_the_numbers_they_hold(tmp, index):
    name, call, good, bad = list(cases(tmp))[index]
    for value in (good, bad) if bad is not None else (good,):
        plain = outcome(call, value)
        if value is good:
            assert plain[0] == "ok", f"{name}={value!r} (plain Python) refused: {plain}"
        else:
            assert plain[0] == "refused", f"{name}={value!r} (out of range) taken"
        for form, given in forms(value).items():
            held = np.asarray(given).item()  # the Python number it holds: an int for np.int64(2.0)
            held = float(held) if isinstance(held, np.floating) else held  # a longdouble's item() is itself
            expected = plain if type(held) is type(value) else outcome(call, held)
            assert outcome(call, given) == expected, f"{name} given {form}({value!r})"
    if not isinstance(good, bool):
        for flag in (True, False, np.bool_(True)):
            got = outcome(call, flag)
            assert got[0] == "refused", f"{name}={flag!r} taken as a number: {got[1][:200]}"


def test_the_cases_of_pass_29b_stay_fixed():
    """Pass 29b's numbers, one by one: a longdouble and a namedtuple of coefficients kept in the
    settings (json.dumps failed; a TypeError), a text duration and minimum of clusters (Python's or
    numpy's TypeError), numpy's True for hold (refused as "hold=True")."""
    xyz = namedtuple("xyz", "x y z")
    for c in (np.longdouble(0.01), xyz(0.01, 0.02, np.float32(0.5)), np.array([0.01, 0.02, 0.5])):
        json.dumps(GyroFilter(100.0, temp_coefficient_dps_per_c=c).state_dict())
    assert GyroFilter(100.0, hold=np.array(True)).settings.hold is True
    for bad in ("5", True, -1):
        with pytest.raises(SettingsError, match="duration_s"):
            SimulatedSource(model=MODEL, duration_s=bad, realtime=False)
    for bad in ("9", None, True, 2.5):
        with pytest.raises(GyroFilterError, match="min_clusters"):
            _characterised(min_clusters=bad)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(5))
def test_drawn_settings_in_every_numpy_form(seed):
    """The bigger sweep: values drawn in and beyond each setting's range (seeded), every form gives
    the plain value's settings or its refusal in its words."""
    rng = np.random.default_rng(seed)
    for name, bounds in SETTING_RANGES.items():
        low, high = bounds.get("low", -1e6), bounds.get("high", 1e6)
        for _ in range(4):
            value = float(rng.uniform(low - 0.1 * (high - low), high + 0.1 * (high - low)))
            value = round(value) if bounds.get("integer") and rng.random() < 0.8 else value
            call = lambda v, name=name: GyroFilter(100.0, **{name: v}).state_dict()  # noqa: E731
            plain = outcome(call, value)
            for form, given in forms(value).items():
                held = np.asarray(given).item()
                held = float(held) if isinstance(held, np.floating) else held
                assert outcome(call, given) == (plain if type(held) is type(value) else outcome(call, held)), \
                    f"{name} given {form}({value!r})"


@pytest.mark.parametrize("where", ["filter", "filter temp_c", "filter_timed t_s", "smooth temp_c", "overlapping_adev",
                                   "Recording.from_dps"])
def test_a_bool_among_the_numbers_of_a_list_is_refused(where):
    """Attack pass 32a: ``update((1.0, True, 0.5))`` is refused (True is no number), but a list
    of numbers holding one True was taken as 1 where an array is asked (numpy makes it 1.0): a
    temperature of 1 deg C compensated, a rate of 1 deg/s filtered, without a word. Refused
    naming the row, as a bool array is (``inputs.number_array``)."""
    rows = STILL_DPS.tolist()
    rows[7] = [rows[7][0], True, rows[7][2]]
    temps = [25.0] * len(rows)
    temps[7] = np.bool_(True)
    times = [i / 100.0 for i in range(len(rows))]
    times[7] = True
    calls = {"filter": lambda: GyroFilter(100.0, 1.0).filter(rows),
             "filter temp_c": lambda: GyroFilter(100.0, 1.0, temp_coefficient_dps_per_c=0.1).filter(STILL_DPS, temps),
             "filter_timed t_s": lambda: GyroFilter(100.0, 1.0).filter_timed(STILL_DPS, times),
             "smooth temp_c": lambda: smooth(STILL_DPS, 100.0, 1.0, temp_c=temps[:7] + [np.array(True)] + temps[8:],
                                             temp_coefficient_dps_per_c=0.1),  # a 0-d array of a bool
             "overlapping_adev": lambda: overlapping_adev([r[1] for r in rows], 100.0),
             "Recording.from_dps": lambda: Recording.from_dps(rows, 100.0)}
    with pytest.raises(GyroFilterError, match="row 7.*True"):
        calls[where]()


def test_a_bool_in_another_sequence_of_numbers_is_refused():
    """Attack pass 33a: the bool check read lists and tuples only; a ``collections.deque`` (or
    any sequence numpy converts) of temperatures holding a True was compensated as 1 deg C,
    without a word. What is not already an array (no dtype of its own) is checked alike."""
    temps = collections.deque([25.0] * len(STILL_DPS))
    temps[7] = True
    with pytest.raises(GyroFilterError, match="row 7.*True"):
        GyroFilter(100.0, 1.0, temp_coefficient_dps_per_c=0.1).filter(STILL_DPS, temps)


#: attack pass 32a: numbers of other kinds than Python's and numpy's, and values no setting takes
OTHER_KINDS = {"Fraction": Fraction, "text": str, "complex": complex, "nan": lambda v: math.nan, "inf": lambda v: math.inf,
               "an int beyond a float": lambda v: 10**400}


@pytest.mark.parametrize("index", range(len(_ids(None))), ids=_ids(None))
def test_other_kinds_of_number_are_refused_or_the_number(tmp, index):
    """Attack pass 32a: a Fraction, a text, a complex, NaN, inf or an int beyond a float's range
    gives the plain value's result or a refusal (GyroFilterError), never a traceback; NaN only
    where it means "none" (a temperature), with no NaN in the result. ``calibrate``'s
    ``stillness_threshold`` took NaN (every window still), inf and a complex, and ended in numpy's
    UFuncTypeError for a text (``max_bias_dps`` alike): checked as the settings ``stillness_z``
    and ``max_bias_dps`` are."""
    name, call, good, _ = list(cases(tmp))[index]
    if isinstance(good, bool):
        return
    for kind, make in OTHER_KINDS.items():
        if kind == "inf" and name == "BiasKalmanFilter(bias_tau_s)":
            continue  # inf is a random walk (its default)
        got = outcome(call, make(good))
        if got[0] == "ok" and kind == "nan":
            assert "NaN" not in got[1], f"{name} given NaN: NaN in its result"
        elif got[0] == "ok":
            assert got == outcome(call, good), f"{name} given {kind} ({make(good)!r}) taken as another value"


DTYPES = ("float16", "float32", "int8", "uint8", "int64", "uint64", "object", "complex128", "datetime64[s]", "bool")


@pytest.mark.parametrize("where", ["filter samples", "filter temp_c", "filter_timed t_s", "smooth temp_c"])
def test_arrays_of_every_dtype_are_their_numbers_or_refused(where):
    """Attack pass 32a: an array given to the filter (samples, temperatures, times) in any dtype
    gives what its float64 copy gives, or a refusal (GyroFilterError) naming the argument: an
    object, complex (even of 0 imaginary part), datetime or bool array is refused, float16
    times are refused (docs/formats.md section 7)."""
    whole = np.round(STILL_DPS)  # whole numbers: every numeric dtype holds them
    calls = {"filter samples": lambda a: GyroFilter(100.0, 1.0).filter(a),
             "filter temp_c": lambda a: GyroFilter(100.0, 1.0, temp_coefficient_dps_per_c=0.1).filter(STILL_DPS, a),
             "filter_timed t_s": lambda a: GyroFilter(100.0, 1.0).filter_timed(STILL_DPS, a),
             "smooth temp_c": lambda a: smooth(STILL_DPS, 100.0, 1.0, temp_c=a, temp_coefficient_dps_per_c=0.1)}
    values = {"filter samples": np.abs(whole), "filter temp_c": np.full(len(STILL_DPS), 25.0),
              "filter_timed t_s": np.arange(len(STILL_DPS), dtype=float) + 1, "smooth temp_c": np.full(len(STILL_DPS), 25.0)}
    plain = outcome(calls[where], values[where])
    assert plain[0] == "ok"
    for dtype in DTYPES:
        given = values[where].astype(np.int64).astype(dtype) if dtype.startswith("datetime") else values[where].astype(dtype)
        got = outcome(calls[where], given)
        if dtype in ("object", "complex128", "datetime64[s]", "bool") or (dtype == "float16" and where == "filter_timed t_s") \
                or (dtype in ("int8", "uint8") and where == "filter_timed t_s"):  # 300 times wrap around: not increasing
            assert got[0] == "refused" and ("t_s" in got[2] or "temp_c" in got[2] or "samples_dps" in got[2]), (dtype, got)
        else:
            assert got == plain, f"{where} as {dtype}"
