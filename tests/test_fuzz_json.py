"""Fuzz: the JSON files a user hands in (a calibration, a simulator model) end in a right result or a clear refusal.

Documents are drawn by hypothesis: any JSON (nested objects and lists, huge integers, floats,
strings, booleans, null), deep nesting and NaN/Infinity tokens, and mutations of a valid
calibration and of the package's model gyrofilter/data/mpu6050_model.json (a key deleted, a value of another type, huge,
negative, tiny or non-finite numbers, long strings). The property, for ``Calibration.load``,
``load_model`` + ``validate_model`` and the commands (``replay REC --calibration F --out O``,
``simulate --model F --duration 1 --out O``): either a result whose values read back equal, or
the library's GyroFilterError / exit 2 with one line of at most 300 characters naming the file,
and no output file. The default run is short (derandomized); the ``slow`` copies draw thousands.
"""
import contextlib
import copy
import io
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gyrofilter.filter.calibration import MAX_BIAS_DPS, MAX_NOISE_STD_DPS, Calibration
from gyrofilter.cli import main
from gyrofilter.errors import CalibrationError, GyroFilterError
from gyrofilter.recording import Recording, read_recording, write_recording
from gyrofilter.sim.model import load_model, validate_model
from gyrofilter.sim.simulate import simulate
from gyrofilter.sources.simulated import DEFAULT_MODEL_PATH
from gyrofilter.units import TEMP_RANGE_C

MODEL_FILE = Path(str(DEFAULT_MODEL_PATH))
MODEL = json.loads(MODEL_FILE.read_text())
CALIBRATION = {"gyrofilter-calibration": 1, "bias_dps": [0.5, -1.25, 0.0], "noise_std_dps": [0.05, 0.06, 0.07],
               "samples": 200, "sample_rate_hz": 100.0, "temp_c": 25.5, "created_utc": "2026-11-26T00:00:00+00:00"}
MAX_LINE_CHARS = 300

FAST = settings(max_examples=150, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
FAST_CLI = settings(FAST, max_examples=60)
SLOW = settings(max_examples=3000, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])

# ------------------------------------------------------------------------------ documents

ODD_NUMBERS = st.sampled_from([
    0, -1, 1, 2, 3, 20, -20, 20.000001, 1e6, -1e300, 1e300, 10**400, -(10**400), 2**63, 5e-324, -0.0, 1e-320,
    99999.0, 100000, 100001, 200, 201, -100, -101, math.nan, math.inf, -math.inf,
]) | st.integers() | st.floats(allow_nan=True, allow_infinity=True)
SCALARS = (st.none() | st.booleans() | st.integers() | st.integers(min_value=10**300, max_value=10**400)
           | st.floats(allow_nan=False, allow_infinity=False) | st.text(max_size=20) | ODD_NUMBERS
           | st.sampled_from(["", "x" * 10_000, "nan", "1e400", "\u0661", "\x00"]))
DOCS = st.recursive(SCALARS, lambda children: st.lists(children, max_size=4)
                    | st.dictionaries(st.text(max_size=12), children, max_size=4), max_leaves=20)


def _places(doc):
    """Every (container, key) inside ``doc``: where a mutation may strike."""
    found, stack = [], [doc]
    while stack:
        node = stack.pop()
        items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
        for key, child in items:
            found.append((node, key))
            stack.append(child)
    return found


@st.composite
def mutations(draw, base):
    """``base`` with 1 to 3 changes: a key deleted, a value of another type, an odd number, a long string."""
    doc = copy.deepcopy(base)
    for _ in range(draw(st.integers(1, 3))):
        places = _places(doc)
        if not places:
            break
        container, key = draw(st.sampled_from(places))
        change = draw(st.sampled_from(["delete", "replace", "number", "number", "string", "wrap"]))
        if change == "delete":
            del container[key]
        elif change == "replace":
            container[key] = draw(DOCS)
        elif change == "number":
            container[key] = draw(ODD_NUMBERS)
        elif change == "string":
            container[key] = draw(st.sampled_from(["x" * 10_000, "", "1", "0.5", "NaN"]))
        else:
            container[key] = [container[key]]
    return doc


def _text(doc):
    """``doc`` as JSON text; non-finite floats become NaN/Infinity tokens (which the loader refuses)."""
    return json.dumps(doc, allow_nan=True)


def deep_text(depth):
    return "[" * depth + "]" * depth


def texts_around(base):
    """JSON texts: any document, a mutation of ``base``, deep nesting, huge integers spelled out, cut text."""
    cut = st.builds(lambda doc, n: _text(doc)[:n], mutations(base), st.integers(0, 400))
    return (st.builds(_text, DOCS) | st.builds(_text, mutations(base)) | st.builds(_text, mutations(base))
            | st.builds(deep_text, st.sampled_from([31, 32, 33, 1000, 200_000]))
            | st.builds(lambda n: _text(base).replace("100", "1" + "0" * n, 1), st.sampled_from([2, 310, 400, 5000]))
            | cut)


# ------------------------------------------------------------------------------ the property


def assert_one_line(text, path):
    """A refusal: one line of at most MAX_LINE_CHARS characters besides ``path``, which it names."""
    assert "\n" not in text.strip() and "Traceback" not in text, text
    assert len(text.strip()) - len(str(path)) <= MAX_LINE_CHARS, text
    assert str(path) in text, text


@contextlib.contextmanager
def folder():
    with tempfile.TemporaryDirectory() as name:
        yield name


def check_calibration_text(text):
    with folder() as where:
        path = os.path.join(where, "cal.json")
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
        try:
            cal = Calibration.load(path)
        except CalibrationError as exc:
            assert_one_line(str(exc), path)
            return
        doc = json.loads(text)  # what was accepted is plain JSON with the values read
        assert cal.bias_dps == tuple(float(v) for v in doc["bias_dps"])
        assert cal.noise_std_dps == tuple(float(v) for v in doc["noise_std_dps"])
        assert cal.samples == doc["samples"] and cal.sample_rate_hz == float(doc["sample_rate_hz"])
        assert cal.temp_c == (None if doc.get("temp_c") is None else float(doc["temp_c"]))
        assert all(abs(b) <= MAX_BIAS_DPS for b in cal.bias_dps) and all(0 <= s <= MAX_NOISE_STD_DPS for s in cal.noise_std_dps)
        assert cal.temp_c is None or TEMP_RANGE_C[0] <= cal.temp_c <= TEMP_RANGE_C[1]
        again = os.path.join(where, "again.json")
        cal.save(again)
        assert Calibration.load(again) == cal


def check_model_reading(text):
    """load_model: the document as JSON reads it (an extended_model taken out of a gap report), or
    a SettingsError naming the file."""
    with folder() as where:
        path = os.path.join(where, "model.json")
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
        try:
            model = load_model(path)
        except GyroFilterError as exc:
            assert_one_line(str(exc), path)
            return
        doc = json.loads(text)
        if isinstance(doc, dict) and "axes" not in doc and isinstance(doc.get("extended_model"), dict):
            doc = doc["extended_model"]
        assert model == doc


def check_model_text(text):
    with folder() as where:
        path = os.path.join(where, "model.json")
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
        try:
            model = load_model(path)
            spec, _ = validate_model(model)
        except GyroFilterError as exc:
            assert "\n" not in str(exc) and len(str(exc)) <= MAX_LINE_CHARS, str(exc)
            return
        # a model that validates simulates finite numbers that read back equal from a recording
        rec = simulate(model, 20 / spec["sample_rate_hz"], seed=3)
        assert np.isfinite(rec.gyro_dps).all()
        out = os.path.join(where, "sim.csv")
        write_recording(out, rec)
        back = read_recording(out)
        np.testing.assert_allclose(back.gyro_dps, rec.gyro_dps, rtol=1e-8, atol=1e-12)


def run_command(argv):
    """``gyrofilter argv`` in this process: (exit status, stderr)."""
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, err.getvalue()


def check_command(argv, given_file, out, where):
    before = sorted(os.listdir(where))
    code, err = run_command(argv)
    if code == 0:
        assert "Traceback" not in err
        back = read_recording(out)  # the output reads back
        assert len(back) > 0 and np.isfinite(back.gyro_dps).all()
        return back
    assert code == 2, (code, err)
    assert err.startswith("gyrofilter: error: ") and err.count("\n") == 1, err
    assert_one_line(err, given_file)
    assert sorted(os.listdir(where)) == before  # no output file, no temporary left
    return None


@pytest.fixture(scope="module")
def still_recording(tmp_path_factory):
    path = tmp_path_factory.mktemp("fuzz") / "still.csv"
    x = np.random.default_rng(4).normal(0.0, 0.05, (300, 3)) + (0.5, -1.25, 0.0)
    write_recording(path, Recording.from_dps(x, 100.0))
    return path


def check_replay_calibration(text, recording):
    with folder() as where:
        path = os.path.join(where, "cal.json")
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
        out = os.path.join(where, "out.csv")
        back = check_command(["replay", str(recording), "--calibration", path, "--out", out], path, out, where)
        if back is not None:
            assert len(back) == 300 // 5  # every sample filtered: no start-up window with a loaded calibration
            assert Calibration.load(path).sample_rate_hz == pytest.approx(100.0, rel=0.05)


def check_simulate_model(text):
    with folder() as where:
        path = os.path.join(where, "model.json")
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
        out = os.path.join(where, "sim.csv")
        back = check_command(["simulate", "--model", path, "--duration", "1", "--seed", "5", "--out", out], path, out, where)
        if back is not None:
            spec, _ = validate_model(load_model(path))
            expected = simulate(load_model(path), 1.0, seed=5)
            assert len(back) == len(expected) and spec["sample_rate_hz"] == back.sample_rate_hz
            np.testing.assert_allclose(back.gyro_dps, expected.gyro_dps, rtol=1e-8, atol=1e-9)


# ------------------------------------------------------------------------------ the default run


@FAST
@given(texts_around(CALIBRATION))
def test_calibration_files(text):
    check_calibration_text(text)


@FAST_CLI
@given(text=texts_around(CALIBRATION))
def test_replay_with_a_calibration_file(still_recording, text):
    check_replay_calibration(text, still_recording)


@FAST
@given(texts_around(MODEL))
def test_model_files_are_read_or_refused_naming_the_file(text):
    check_model_reading(text)




@FAST
@given(texts_around(MODEL))
def test_model_files(text):
    check_model_text(text)


@FAST_CLI
@given(text=texts_around(MODEL))
def test_simulate_with_a_model_file(text):
    check_simulate_model(text)


def test_the_unchanged_files_are_accepted(still_recording):
    """The fuzz's starting points are good files: a refusal of every mutation would prove nothing."""
    check_calibration_text(_text(CALIBRATION))
    with folder() as where:
        path = os.path.join(where, "cal.json")
        with open(path, "w") as fh:
            fh.write(_text(CALIBRATION))
        assert Calibration.load(path).bias_dps == (0.5, -1.25, 0.0)
        out = os.path.join(where, "out.csv")
        assert check_command(["replay", str(still_recording), "--calibration", path, "--out", out], path, out, where) is not None
    check_model_reading(_text(MODEL))
    check_simulate_model(_text(MODEL))


# ------------------------------------------------------------------------------ the slow copies


@pytest.mark.slow
@SLOW
@given(texts_around(CALIBRATION))
def test_calibration_files_slow(text):
    check_calibration_text(text)


@pytest.mark.slow
@settings(SLOW, max_examples=1000)
@given(text=texts_around(CALIBRATION))
def test_replay_with_a_calibration_file_slow(still_recording, text):
    check_replay_calibration(text, still_recording)


@pytest.mark.slow
@SLOW
@given(texts_around(MODEL))
def test_model_files_are_read_or_refused_naming_the_file_slow(text):
    check_model_reading(text)


@pytest.mark.slow
@SLOW
@given(texts_around(MODEL))
def test_model_files_slow(text):
    check_model_text(text)


@pytest.mark.slow
@settings(SLOW, max_examples=1000)
@given(text=texts_around(MODEL))
def test_simulate_with_a_model_file_slow(text):
    check_simulate_model(text)
