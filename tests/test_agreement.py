"""Tests for gyrofilter.analysis.agreement: allan's and gap's noise terms held against each other on
constructed documents (the keys of docs/formats.md, sections 3 and 4): agreement says nothing, each
rule's break one sentence with its reason."""
import copy

import pytest

from gyrofilter.analysis.agreement import compare
from gyrofilter.analysis.noise.export import JSON_KEY
from gyrofilter.analysis.noise.model import TERMS
from gyrofilter.effects import BIAS_INSTABILITY, NARROWBAND, RATE_RAMP, RATE_RANDOM_WALK, SINUSOID, WARMUP


def _term(value=None, low=None, high=None, upper=None):
    """One ``details`` entry of the allan document: resolved (value, low, high) or bounded (upper)."""
    return {"value": value, "low": low, "high": high, "upper_bound": upper,
            "model_value": value if value is not None else 0.0}


def _allan(chi2=0.9, **terms):
    """An allan document of one axis x: N = 0.01 [0.0098, 0.0102], every other term bounded at
    1e-3 unless given (``terms``: JSON key -> details entry)."""
    details = {JSON_KEY[t]: _term(upper=1e-3) for t in TERMS}
    details["arw_dps_per_sqrt_hz"] = _term(0.01, 0.0098, 0.0102)
    details.update(terms)
    return {"axes": {"x": {"details": details, "tau_s": [0.1, 1.0, 10.0, 100.0], "n_clusters": [9000, 900, 90, 9],
                           "fit_reduced_chi2": chi2}}}


def _gap(arw=0.01, arw_ci=(0.0099, 0.0101), findings=(), extended_arw=None):
    """A gap document of one axis x: the baseline white level with its interval, the findings
    (``(effect, params, params_ci95)``), the extended model's white level."""
    return {"baseline": {"axes": {"x": {"bias_dps": 0.1, "arw_dps_per_sqrt_hz": arw,
                                        "params_ci95": {"arw_dps_per_sqrt_hz": list(arw_ci)} if arw_ci else {}}}},
            "findings": [{"effect": e, "axis": "x", "params": p, **({"params_ci95": ci} if ci else {})}
                         for e, p, ci in findings],
            "extended_model": {"axes": {"x": {"arw_dps_per_sqrt_hz": extended_arw or arw}}}}


def test_two_analyses_that_agree_say_nothing():
    allan = _allan(bias_instability_dps=_term(0.004, 0.003, 0.005))
    gap = _gap(findings=[(BIAS_INSTABILITY, {"b_dps": 0.0045}, {"b_dps": [0.0041, 0.0052]}),
                         (RATE_RAMP, {"r_dps_per_s": -4e-4}, {"r_dps_per_s": [-6e-4, -2e-4]})])
    assert compare(allan, gap) == []
    # gap without intervals (--bootstrap 0): its values inside allan's
    assert compare(allan, _gap(arw_ci=None, findings=[(BIAS_INSTABILITY, {"b_dps": 0.0045}, None)])) == []


def test_gap_naming_a_term_above_allans_bound_is_one_sentence_with_its_reason():
    gap = _gap(findings=[(RATE_RANDOM_WALK, {"k_dps_per_sqrt_s": 2e-3}, {"k_dps_per_sqrt_s": [1.5e-3, 2.6e-3]}),
                         (WARMUP, {"amplitude_dps": 0.05, "tau_s": 300.0}, None)])
    said = compare(_allan(), gap)
    assert [(s["axis"], s["term"]) for s in said] == [("x", "K")]
    text = said[0]["text"]
    assert "gap names K = 0.002 [0.0015, 0.0026]" in text and "above allan's bound K < 0.001" in text
    assert "warmup" in text  # the slow effect gap models apart, which allan's terms absorb
    assert "a fit without K over cluster times up to 100 s" in text  # the longest tau with 9 clusters
    # at the bound or below it: no sentence
    gap["findings"][0]["params"]["k_dps_per_sqrt_s"] = 1e-3
    assert compare(_allan(), gap) == []


def test_intervals_that_do_not_overlap_are_said_with_the_fast_effects_gap_names():
    gap = _gap(arw=0.0125, arw_ci=(0.0123, 0.0127), extended_arw=0.0101,
               findings=[(SINUSOID, {"frequency_hz": 31.0, "amplitude_dps": 0.01}, None),
                         (NARROWBAND, {"center_hz": 31.0, "bandwidth_hz": 0.3, "rms_dps": 0.05}, None)])
    said = compare(_allan(chi2=4.0), gap)
    assert [s["term"] for s in said] == ["N"]
    text = said[0]["text"]
    assert "N from allan 0.01 [0.0098, 0.0102] and from gap 0.0125 [0.0123, 0.0127]" in text
    assert "narrowband, sinusoid" in text and "0.0101: inside allan's interval" in text
    assert "reduced chi-square 4" in text
    # overlapping intervals agree, even with different values
    assert compare(_allan(), _gap(arw=0.0104, arw_ci=(0.0101, 0.0107))) == []


def test_a_term_allan_resolves_and_gap_does_not_name_is_said():
    said = compare(_allan(rrw_dps_per_sqrt_s=_term(1e-3, 8e-4, 1.3e-3)),
                   _gap(findings=[(BIAS_INSTABILITY, {"b_dps": 5e-4}, {"b_dps": [4e-4, 6e-4]})]))
    assert [s["term"] for s in said] == ["K"]
    assert said[0]["text"].startswith("axis x: allan's fit needs K = 0.001 [0.0008, 0.0013] deg/s/sqrt(s) where gap "
                                      "names none: gap explains the slow part with bias_instability")


def test_a_ramp_is_compared_by_its_size_and_an_unknown_reason_is_said_so():
    allan = _allan(rate_ramp_dps_per_s=_term(3e-4, 2e-4, 4e-4))
    assert compare(allan, _gap(findings=[(RATE_RAMP, {"r_dps_per_s": -3.5e-4}, {"r_dps_per_s": [-4.5e-4, -2.5e-4]})])) == []
    said = compare(allan, _gap(findings=[(RATE_RAMP, {"r_dps_per_s": -9e-4}, {"r_dps_per_s": [-1e-3, -8e-4]})]))
    assert [s["term"] for s in said] == ["R"]
    assert "from gap 0.0009 [0.0008, 0.001]" in said[0]["text"] and "no reason the documents show" in said[0]["text"]


@pytest.mark.parametrize("drop", ["axis", "arw"])
def test_what_one_document_lacks_is_not_compared(drop):
    allan, gap = _allan(), _gap(arw=0.02, arw_ci=(0.019, 0.021))
    assert len(compare(allan, gap)) == 1
    gap = copy.deepcopy(gap)
    if drop == "axis":
        gap["baseline"]["axes"] = {"y": gap["baseline"]["axes"].pop("x")}
    else:  # a gap analysis that could not run has a baseline without numbers
        gap["baseline"]["axes"]["x"] = {}
    assert compare(allan, gap) == []


def test_a_term_gap_suggests_but_does_not_establish_is_said_so():
    """A new user saw "gap finds no slow effect" where gap listed the very bias instability under
    ``uncertain`` (its b_dps not determined by a 10-minute record)."""
    gap = _gap()
    gap["uncertain"] = [{"effect": BIAS_INSTABILITY, "axis": "x", "params": {"b_dps": 0.00345},
                         "params_ci95": {"b_dps": None}, "why": "its defining parameter b_dps is not determined"}]
    said = compare(_allan(bias_instability_dps=_term(0.0035, 0.0026, 0.0055)), gap)
    assert [s["term"] for s in said] == ["B"]
    assert "gap suggests B = 0.00345 deg/s but does not establish it (its defining parameter" in said[0]["text"]
    assert "no slow effect" not in said[0]["text"]
