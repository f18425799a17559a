"""Fuzz the simulator's model and the numeric options of simulate and allan (issue 22, part E).

Property: a model mutated from examples/models/*.json (keys dropped, types changed, huge,
negative, zero, tiny or null values, long lists, unknown effect names) is either refused by
``validate_model`` with one SettingsError line naming the key path, or accepted; an accepted
model then simulates to finite values only, and the recording written from them reads back
equal. A numeric option of ``simulate``/``allan`` ends in exit 0 or exit 2 with a short message
naming the option, never a traceback.
"""
import copy
import glob
import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from gyrofilter.cli import main
from gyrofilter.errors import SettingsError
from gyrofilter.recording import read_recording, write_recording
from gyrofilter.sim.model import validate_model
from gyrofilter.sim.simulate import simulate
from gyrofilter.sources.simulated import DEFAULT_MODEL
from gyrofilter.filter.tempcomp import coefficients_from_model
from support import REPO

MODELS = [json.load(open(p)) for p in sorted(glob.glob(str(REPO / "examples" / "models" / "*.json")))]
MODELS.append(DEFAULT_MODEL)
MAX_SAMPLES = 400  # each example simulates at most this many samples (at most 2 s)

ODD_VALUES = [None, True, False, "0.02", "", [], {}, 0, -5, 1, 0.5, -0.5, 1e-320, 1e-7, 1e4, -1e4, 1e9, 1e12,
              1e308, -1e308, 10**400, [0.5] * 3000, [0.1] * 21, {"effect": "no_such_effect"}, "furlongs",
              {"effect": "arma", "sigma_a_dps": 0.1, "phi": [0.999999999]},
              {"effect": "narrowband", "center_hz": 10.0, "bandwidth_hz": 1e-6, "rms_dps": 1.0},
              {"effect": "bias_instability", "b_dps": 0.01, "tau_min_s": 1e-6, "tau_max_s": 1e9, "per_decade": 10},
              {"effect": "repeated_samples", "fraction": 0.02}, {"fraction": 0.5, "pattern": "beat"}]


def _paths(node, prefix=()):
    """Every (path, container) of a JSON document: the keys and indices below the top."""
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    out = []
    for key, child in items:
        out.append(prefix + (key,))
        if len(out) < 2000:
            out.extend(_paths(child, prefix + (key,)))
    return out


def _at(doc, path):
    for key in path:
        doc = doc[key]
    return doc


@st.composite
def mutated_models(draw):
    model = copy.deepcopy(draw(st.sampled_from(MODELS)))
    for _ in range(draw(st.integers(1, 4))):
        paths = _paths(model)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent = _at(model, path[:-1])
        action = draw(st.sampled_from(["drop", "set", "set", "set", "scale", "grow"]))
        if action == "drop":
            del parent[path[-1]]
        elif action == "set":
            parent[path[-1]] = copy.deepcopy(draw(st.sampled_from(ODD_VALUES)))
        elif action == "scale" and type(parent[path[-1]]) in (int, float) and abs(parent[path[-1]]) < 1e300:
            parent[path[-1]] = parent[path[-1]] * draw(st.sampled_from([-1.0, 0.0, 1e-9, 1e3, 1e9, 1e300]))
        elif action == "grow" and isinstance(parent[path[-1]], list) and parent[path[-1]]:
            parent[path[-1]] = parent[path[-1]] * draw(st.sampled_from([2, 30, 200]))
    return model


def _check_model(model, tmp_path):
    try:  # --temp-model reads the same documents for their coefficients
        spec, _ = validate_model(model, coefficients_only=True)
        assert all(math.isfinite(c) for c in coefficients_from_model(spec))
    except SettingsError as exc:
        assert str(exc).startswith("model: ") and "\n" not in str(exc) and len(str(exc)) <= 300, str(exc)
    try:
        spec, _ = validate_model(model)
    except SettingsError as exc:
        text = str(exc)
        assert text.startswith("model: ") and "\n" not in text and len(text) <= 300, text
        event("refused")
        return
    event("accepted")
    duration_s = min(2.0, MAX_SAMPLES / spec["sample_rate_hz"])
    rec = simulate(model, duration_s, seed=7)
    for name, values in rec.columns.items():
        assert np.isfinite(values).all(), name
    path = tmp_path / "sim.csv"
    if path.exists():
        path.unlink()
    write_recording(path, rec)
    back = read_recording(path)
    assert list(back.columns) == list(rec.columns)
    for name, values in rec.columns.items():
        assert np.allclose(back.columns[name], values, rtol=1e-8, atol=0.0), name


@settings(max_examples=150, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(model=mutated_models())
def test_a_mutated_model_is_refused_in_one_line_or_simulates_finite_and_reads_back(tmp_path, model):
    _check_model(model, tmp_path)


@pytest.mark.slow
@settings(max_examples=3000, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(model=mutated_models())
def test_a_mutated_model_is_refused_in_one_line_or_simulates_finite_and_reads_back_many(tmp_path, model):
    _check_model(model, tmp_path)


NUMBERS = st.sampled_from(["0", "-1", "1", "2", "0.5", "nan", "inf", "-inf", "1e308", "1e-320", "1e400", "3000",
                           "99999999999999999999999", "0x10", "1_0", "", " ", "1e6", "0.999999"])
SIMULATE_OPTIONS = ["--duration", "--seed", "--chunk", "--sample-rate-hz"]
ALLAN_OPTIONS = ["--confidence", "--min-clusters"]


def _check_command(argv, option, capsys):
    try:
        rc = main(argv)
    except SystemExit as exc:  # argparse: its own 'argument --x: ...' message
        rc = exc.code
    err = capsys.readouterr().err
    assert rc in (0, 2), err
    if rc == 2:
        last = err.strip().splitlines()[-1]
        assert "Traceback" not in err and len(last) <= 300, err
        assert option in last, last


@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(option=st.sampled_from(SIMULATE_OPTIONS), value=NUMBERS)
def test_a_numeric_option_of_simulate_is_taken_or_refused_naming_it(tmp_path, capsys, option, value):
    model = tmp_path / "m.json"
    model.write_text(json.dumps({"sample_rate_hz": 100.0, "axes": {"x": {"arw_dps_per_sqrt_hz": 0.01}}}))
    out = tmp_path / "o.csv"
    argv = ["simulate", "--model", str(model), "--duration", "1", "--out", str(out), "--force", f"{option}={value}"]
    if option == "--duration":
        argv = ["simulate", "--model", str(model), "--out", str(out), "--force", "--sample-rate-hz", "0.01",
                f"{option}={value}"]
    _check_command(argv, option, capsys)


@settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(option=st.sampled_from(ALLAN_OPTIONS), value=NUMBERS)
def test_a_numeric_option_of_allan_is_taken_or_refused_naming_it(tmp_path, capsys, option, value):
    rec = tmp_path / "r.csv"
    if not rec.exists():
        write_recording(rec, simulate({"sample_rate_hz": 100.0, "axes": {"x": {"arw_dps_per_sqrt_hz": 0.01}}}, 20.0, seed=1))
    _check_command(["allan", str(rec), "--axes", "x", f"{option}={value}"], option, capsys)


@settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(low=NUMBERS | st.just("0.05"), high=NUMBERS | st.just("2"))
def test_allans_kalibr_tau_range_is_taken_or_refused_naming_it(tmp_path, capsys, low, high):
    """--kalibr-tau-s LOW,HIGH: two plain numbers, 0 < LOW < HIGH, within the record's cluster
    times (20 s: 0.01 .. 2.2 s) and holding two of them; else one line naming the option."""
    rec = tmp_path / "r.csv"
    if not rec.exists():
        write_recording(rec, simulate({"sample_rate_hz": 100.0, "axes": {"x": {"arw_dps_per_sqrt_hz": 0.01}}}, 20.0, seed=1))
    _check_command(["allan", str(rec), "--axes", "x", "--kalibr", str(tmp_path / "imu.yaml"), "--force",
                    f"--kalibr-tau-s={low},{high}"], "--kalibr-tau-s", capsys)
