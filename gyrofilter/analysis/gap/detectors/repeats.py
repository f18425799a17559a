"""``repeated_samples``: rows that repeat the previous row exactly on every axis more often than
chance at the record's quantization (a driver polling faster than the sensor updates). A
record-level detector: it reads every axis at once, runs before nothing and cleans nothing (the
gap analysis weighs it after the axes' findings, :func:`gyrofilter.analysis.gap.pipeline.weigh_repeats`).

The statistic is :func:`gyrofilter.analysis.repeats.repeated_rows`: the count K of the M rows
equal to the previous one on every axis, against the chance level p_chance = Π_a P(Δ_a = 0) read
off each axis's successive differences of ±1, ±2, ±3 steps (a sampled Gaussian); a one-sided
binomial test P(K' >= K), K' ~ Binomial(M, p_chance's upper bound), below
:data:`~gyrofilter.analysis.gap.detectors.common.REPEATS_ALPHA` names it, with the excess fraction
f = (K / M - p_chance) / (1 - p_chance) and its 95 % interval.
"""
from __future__ import annotations

import math

from ....effects import REPEATED_SAMPLES
from ....sim.model import param_bounds
from ...repeats import repeated_rows
from .common import REPEATS_ALPHA, REPEATS_MAX_STATISTIC, Candidate


def detect_repeats(gyro_dps, q_dps=None):
    """``(the RepeatedRows count, a Candidate or None)`` of the record ``gyro_dps`` ((N, 3) deg/s, or
    an iterable of its three columns, read one at a time) whose step is ``q_dps`` (deg/s; None:
    each axis's grid). The candidate's ``fraction`` is the
    excess fraction, at most the largest a model takes (:func:`max_fraction`: a record of 50.05 %
    or 90 % repeated rows failed the gap analysis, its extended model refused), its evidence
    saying so; its statistic -log10 of the test's p-value (at most
    :data:`~gyrofilter.analysis.gap.detectors.common.REPEATS_MAX_STATISTIC`)."""
    counted = repeated_rows(gyro_dps, q_dps)
    if not counted.more_than_chance(REPEATS_ALPHA):
        return counted, None
    statistic = min(REPEATS_MAX_STATISTIC, -math.log10(counted.p_value) if counted.p_value > 0 else REPEATS_MAX_STATISTIC)
    most = max_fraction()
    beyond = (f"; an excess of {counted.excess:.2%} is beyond the {most:.0%} a model simulates: the model's fraction is "
              f"{most:.0%}") if beyond_model(counted) else ""
    return counted, Candidate(
        REPEATED_SAMPLES, {"fraction": min(counted.excess, most)}, statistic, -math.log10(REPEATS_ALPHA),
        f"{counted.repeated} of {counted.rows} rows ({counted.fraction:.2%}) equal the previous row on every axis, "
        f"chance at this quantization {counted.chance:.2%}{beyond}", statistic_name="-log10 p of the binomial test of the equal rows")


def max_fraction():
    """The largest ``repeated_samples`` fraction a simulator model takes (:func:`~gyrofilter.sim.model.param_bounds`)."""
    return param_bounds(REPEATED_SAMPLES, "fraction")[1]


def beyond_model(counted):
    """Whether the count ``counted`` (a RepeatedRows) has more repeated rows beyond chance (its excess
    fraction) than a model holds (:func:`max_fraction`): then no model reproduces the record, and
    what is read off its rows (the Allan deviation, the gap's other findings) is not to be trusted."""
    return counted.applicable and counted.excess > max_fraction()


def beyond_model_text(counted):
    """What ``gap``'s note, ``allan``'s and ``report``'s warning say of a count :func:`beyond_model`."""
    return (f"the record repeats {counted.excess:.2%} of its rows beyond chance, more than the {max_fraction():.0%} "
            "the simulator's model holds: no model reproduces it, and what is read off these rows (the Allan "
            "deviation, the gap's other findings) is not to be trusted")


def repeats_warning(counted):
    """The warning of ``allan`` and ``report`` for the count ``counted`` (a RepeatedRows) when the
    record holds more repeated rows than chance (:data:`REPEATS_ALPHA`), else None: the count, the
    chance level and the excess with its interval (the test's p-value is in the JSON), and which way
    the Allan results are biased (:mod:`gyrofilter.analysis.repeats`: the shortest tau low, N high)."""
    if not counted.more_than_chance(REPEATS_ALPHA):
        return None
    lo, hi = counted.excess_ci95
    said = (f"{counted.repeated} of {counted.rows} rows ({counted.fraction:.2%}) repeat the previous row exactly on every "
            f"axis, chance {counted.chance:.2%} at this quantization: an excess of {counted.excess:.2%} "
            f"[95 %: {lo:.2%}, {hi:.2%}], a driver polling faster than the sensor updates; ")
    if beyond_model(counted):
        return said + beyond_model_text(counted)
    return said + "the Allan deviation at the shortest tau reads low (by about half the excess), N a little high"
