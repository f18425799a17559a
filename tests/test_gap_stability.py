"""Gap answers that hold (issue 35): one spectral line is one finding, a temperature confounded with
a settling is weighed rather than dropped, a temperature the record suggests but cannot establish
is reported as uncertain, and the default model's own records name no cause twice."""
from __future__ import annotations

import copy

import numpy as np
import pytest

from gyrofilter.analysis.gap.confound import same_line
from gyrofilter.analysis.gap.pipeline import analyse_gap
from gyrofilter.analysis.gap.report import d_text
from gyrofilter.recording import read_recording
from gyrofilter.sim.simulate import simulate
from gyrofilter.sources.simulated import DEFAULT_MODEL
from support import REPO


def _line_findings(rep, axis):
    return [f for f in rep["findings"] if f["axis"] == axis and f["effect"] in ("sinusoid", "narrowband")]


def _one_line_each(rep):
    """No axis names a sinusoid and a narrow band at the same frequency, unless a note says both
    together were clearly better."""
    for a in "xyz":
        found = _line_findings(rep, a)
        sins = [f for f in found if f["effect"] == "sinusoid"]
        bands = [f for f in found if f["effect"] == "narrowband"]
        for s in sins:
            for b in bands:
                if abs(s["params"]["frequency_hz"] - b["params"]["center_hz"]) <= b["params"]["bandwidth_hz"]:
                    assert any(f"axis {a}: one line" in n and "both are named" in n for n in rep["notes"]), \
                        f"axis {a}: {s['params']} and {b['params']} are one line named twice"


@pytest.mark.parametrize("name, axis", [("mpu6050_static_655s", "z"), ("mpu6050_static_123s", "z")])
def test_a_wandering_vibration_line_is_one_finding(name, axis):
    """The shipped logs' 31-Hz line on z (a vibration whose frequency wanders) was named twice: a
    sinusoid (its coherent part) and a narrow band at the same frequency (the rest). One line, one
    finding: the narrow band holding the sinusoid's power, the clearly better reading on D."""
    rep = analyse_gap(read_recording(str(REPO / "recordings" / f"{name}.csv.gz")), seed=0, bootstrap=0)
    found = _line_findings(rep, axis)
    assert [f["effect"] for f in found] == ["narrowband"], found
    band = found[0]["params"]
    assert 31.0 < band["center_hz"] < 31.6 and 0.055 < band["rms_dps"] < 0.07, band
    _one_line_each(rep)


def _hidden_line_record(seed):
    """The default model's gyro (no temperature) with a line on a random axis: a narrow band
    (random centre, width and rms) or a sinusoid whose frequency wanders (a narrow band and a
    sinusoid at the same frequency), 300 s at 100 Hz."""
    rng = np.random.default_rng(seed)
    model = copy.deepcopy(DEFAULT_MODEL)
    model.pop("temperature", None)
    model.pop("accelerometer", None)  # its temperature coefficients need the profile; the gyro is analysed
    axis = "xyz"[rng.integers(3)]
    for a in "xyz":
        model["axes"][a]["effects"] = []
    center = float(rng.uniform(5.0, 40.0))
    model["axes"][axis]["effects"] = [
        {"effect": "narrowband", "center_hz": center, "bandwidth_hz": float(rng.uniform(0.05, 0.4)),
         "rms_dps": float(rng.uniform(0.01, 0.05))},
        {"effect": "sinusoid", "frequency_hz": center, "amplitude_dps": float(rng.uniform(0.0, 0.03))}]
    return simulate(model, 300.0, seed=seed), axis


@pytest.mark.parametrize("seed", [0, pytest.param(1, marks=pytest.mark.slow), pytest.param(2, marks=pytest.mark.slow),
                                  pytest.param(3, marks=pytest.mark.slow)])
def test_a_hidden_line_is_named_once(seed):
    rec, axis = _hidden_line_record(seed)
    rep = analyse_gap(rec, seed=seed, bootstrap=0)
    assert _line_findings(rep, axis), f"the line on {axis} is not found"
    _one_line_each(rep)


def test_same_line_is_the_band_width_around_the_sinusoid():
    class C:
        def __init__(self, **params):
            self.params = params
    band = C(center_hz=31.34, bandwidth_hz=0.38, rms_dps=0.06)
    assert same_line(C(frequency_hz=31.19, amplitude_dps=0.02), band)
    assert not same_line(C(frequency_hz=30.9, amplitude_dps=0.02), band)


def _default_record(seed):
    return simulate(DEFAULT_MODEL, 600.0, seed=seed)


def test_a_temperature_with_a_wander_is_weighed_against_a_warmup_not_dropped():
    """The default model's 10-minute record, seed 3: x holds a temperature coefficient (0.02) and a
    bias instability; the temperature warms like an exponential, so a warm-up in time alone fits
    too. The covariate reading (temperature + bias instability) was dropped unweighed as the more
    complex reading and x named a warm-up the model does not have; weighed on D it is clearly
    better."""
    rep = analyse_gap(_default_record(3), seed=0, bootstrap=0)
    named = {f["effect"]: f for f in rep["findings"] if f["axis"] == "x"}
    assert "temperature" in named and "warmup" not in named, sorted(named)
    assert 0.01 < named["temperature"]["params"]["coefficient_dps_per_c"] < 0.03


@pytest.mark.parametrize("seed", [1, pytest.param(5, marks=pytest.mark.slow)])
def test_the_default_models_temperature_is_named_listed_or_suggested_on_every_axis(seed):
    """Every axis of the default model has a temperature coefficient; in 10 minutes under its bias
    instability the smaller ones are not significant (GLS z 3-4). Each axis names it, lists it as
    an alternative, or reports it under ``uncertain``, whose GLS interval holds the true value."""
    truth = {a: next(e["coefficient_dps_per_c"] for e in DEFAULT_MODEL["axes"][a]["effects"]
                     if e["effect"] == "temperature") for a in "xyz"}
    rep = analyse_gap(_default_record(seed), seed=0, bootstrap=0)
    for a in "xyz":
        named = [f for f in rep["findings"] if f["axis"] == a and f["effect"] == "temperature"]
        listed = [f for f in rep["findings"] if f["axis"] == a
                  and any(alt["effect"] == "temperature" for alt in f.get("alternatives", []))]
        suggested = [u for u in rep["uncertain"] if u["axis"] == a and u["effect"] == "temperature"]
        assert named or listed or suggested, f"axis {a}: temperature neither named, listed nor suggested"
        for u in suggested:
            lo, hi = u["params_ci95"]["coefficient_dps_per_c"]
            assert lo <= u["params"]["coefficient_dps_per_c"] <= hi
            assert lo <= truth[a] <= hi, f"axis {a}: {truth[a]} outside [{lo:.4g}, {hi:.4g}]"
            assert "standard errors from 0" in u["why"]


def test_no_temperature_is_suggested_where_the_record_has_none():
    """The suggestion needs a trend that fits the temperature: the default model without its
    coefficients (the temperature recorded, the bias not following it) suggests none."""
    model = copy.deepcopy(DEFAULT_MODEL)
    for a in "xyz":
        model["axes"][a]["effects"] = [e for e in model["axes"][a]["effects"] if e["effect"] != "temperature"]
    for seed in (1, 3):
        rep = analyse_gap(simulate(model, 600.0, seed=seed), seed=0, bootstrap=0)
        assert not [u for u in rep["uncertain"] if u["effect"] == "temperature"], rep["uncertain"]
        assert not [f for f in rep["findings"] if f["effect"] == "temperature"]


@pytest.mark.parametrize("value, se, text", [(85.17, 4.1, "85 +- 4"), (1.3264, 0.18, "1.33 +- 0.18"),
                                             (5.02, 0.61, "5.0 +- 0.6"), (0.858, 0.0, "0.858"),
                                             (19364.6, 1273.7, "19365 +- 1274")])
def test_d_is_printed_with_the_digits_its_sampling_error_supports(value, se, text):
    assert d_text(value, se) == text


def test_the_commands_answer_does_not_depend_on_the_seed(tmp_path):
    """The commands draw every simulation from fixed streams (pipeline.COMMAND_SEED): ``gap --seed
    0`` and ``--seed 5`` write the same report (its runtime aside) on the shipped 449-s log, whose y
    axis weighs one line as a tone or a band; the library's ``seed`` does move D (other streams)."""
    import json
    import subprocess
    import sys

    path = str(REPO / "recordings" / "mpu6050_static_449s.csv.gz")
    docs = []
    for seed in ("0", "5"):
        out = tmp_path / f"gap{seed}.json"
        proc = subprocess.run([sys.executable, "-m", "gyrofilter", "gap", path, "--json", str(out), "--seed", seed,
                               "--bootstrap", "5"], check=True, capture_output=True, text=True, timeout=300)
        assert "gyrofilter: warning: --seed has no effect" in proc.stderr  # the user is told
        doc = json.loads(out.read_text())
        doc.pop("runtime_s")
        doc["intervals"].pop("runtime_s", None)
        docs.append(doc)
    assert docs[0] == docs[1]
    rec = read_recording(path)
    assert analyse_gap(rec, seed=1, bootstrap=0)["discrepancy"]["before"] != docs[0]["discrepancy"]["before"]


def test_a_wander_the_record_does_not_hold_is_estimated_as_zero_not_as_a_tiny_level():
    """The Whittle fit of a bias instability or a rate random walk to white block means that it
    does not improve (2 Delta log L = 0) is the boundary's estimate, 0: the optimiser on the log
    of the level stopped at an arbitrary ~1e-6 deg/s, and one such bootstrap replicate among 20
    (the 449-s log's y) made b_dps's interval span 0.00013 to 0.22 on some seeds and 0.0018 to
    0.0076 on others, so the bias instability was named or not by the seed."""
    from gyrofilter.analysis.gap.detectors.slow import stochastic_fits, stochastic_params

    rng = np.random.default_rng(5)
    at_boundary = inside = 0
    for _ in range(40):
        fits, _ = stochastic_fits(0.01 * rng.standard_normal(1000), 0.45)
        for name in ("bias_instability", "rate_random_walk"):
            gain, theta, _ = fits[name]
            level = next(iter(stochastic_params(name, theta, 0.45).values()))
            if gain == 0:
                at_boundary += 1
                assert level == 0.0, (name, level)
            else:
                inside += 1
                assert level > 1e-5, (name, gain, level)
    assert at_boundary >= 10 and inside >= 10  # both cases drawn


def test_a_zero_estimate_is_left_out_of_a_positive_parameters_interval():
    """Replicates whose estimator found nothing (0 on a log scale) are left out, as a replicate
    with no estimate is: one of 20 does not make the interval span decades."""
    from gyrofilter.analysis.gap import intervals as gi

    rng = np.random.default_rng(3)
    reps = list(0.003 * np.exp(0.25 * rng.standard_normal(19))) + [0.0]
    got = gi._interval(0.003, reps, "log", (0.0, np.inf))
    assert got.ends is not None and got.ends[1] < 10 * got.ends[0], got


@pytest.mark.slow
def test_the_449s_logs_bias_instability_is_named_whatever_the_seed():
    """The y axis of the shipped 449-s log: the same findings with seeds 0, 1 and 2 (seeds 0 and 1
    set its bias instability aside as not determined before the boundary estimate was a zero)."""
    rec = read_recording(REPO / "recordings" / "mpu6050_static_449s.csv.gz")
    named = [sorted(f["effect"] for f in analyse_gap(rec, seed=seed)["findings"] if f["axis"] == "y")
             for seed in (0, 1, 2)]
    assert named[0] == named[1] == named[2] and "bias_instability" in named[0], named


def test_an_alternative_says_which_findings_of_the_named_reading_it_replaces():
    """A temperature read with a wander beside it, weighed as a whole against a warm-up: the
    warm-up's entry says it stands in place of both (so the wander is not a cause of its own), less
    a member no longer named; the report's line says so; a lone finding's entry names itself."""
    from gyrofilter.analysis.gap.confound import alternatives_entry
    from gyrofilter.analysis.gap.detectors import Candidate
    from gyrofilter.analysis.gap.report import indistinguishable_text
    from gyrofilter.sim.hidden_effects import check

    warm = Candidate("warmup", {"amplitude_dps": -0.15, "tau_s": 250.0}, 0.0, 0.0, "")
    temp = Candidate("temperature", {"coefficient_dps_per_c": 0.49}, 0.0, 0.0, "", alternatives=((warm, 0.48),),
                     in_place_of=("temperature", "bias_instability"))
    entry = alternatives_entry(temp, {"temperature", "bias_instability"})
    assert entry[0]["in_place_of"] == ["temperature", "bias_instability"] and entry[0]["D"] == 0.48
    assert alternatives_entry(temp, {"temperature"})[0]["in_place_of"] == ["temperature"]
    finding = {"effect": "temperature", "axis": "x", "params": temp.params, "alternatives": entry}
    assert "(D of the axis with it in place of temperature + bias_instability," in indistinguishable_text(finding)
    wander = {"effect": "bias_instability", "axis": "x", "params": {"b_dps": 0.002}, "alternatives": []}
    case = {"effect": "warmup", "axis": "x", "params": {"amplitude_dps": -0.15, "tau_s": 250.0}, "duration_s": 600.0}
    assert check(case, {"findings": [finding, wander]})[2] == []
    finding["alternatives"] = alternatives_entry(temp, {"temperature"})
    assert check(case, {"findings": [finding, wander]})[2] == [wander]  # a wander outside the reading is a false cause


def test_a_wander_fitted_alone_is_fitted_as_among_the_others():
    """The bootstrap re-estimates one wander per finding (gap.reestimate): its Whittle fit, and a
    Gauss-Markov's exact time-domain fit, asked for alone are those of the fits of every wander,
    bit for bit (each fit is its own), and the others are not made."""
    from gyrofilter.analysis.gap.detectors.slow import exact_stochastic_gain, stochastic_fits

    rng = np.random.default_rng(8)
    y = np.cumsum(0.002 * rng.standard_normal(400)) + 0.01 * rng.standard_normal(400)
    every, s0 = stochastic_fits(y, 1.0)
    exact = exact_stochastic_gain(y, every, 1.0)
    for name in ("bias_instability", "rate_random_walk", "gauss_markov"):
        assert stochastic_fits(y, 1.0, (name,)) == ({name: every[name]}, s0)
    alone, _ = stochastic_fits(y, 1.0, ("gauss_markov",))
    assert exact_stochastic_gain(y, alone, 1.0, ("gauss_markov",)) == {"gauss_markov": exact["gauss_markov"]}
