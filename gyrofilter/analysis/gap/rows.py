"""The gap analysis's whole-row findings (:data:`gyrofilter.effects.ROWS`): repeated rows, a
property of the record rather than of an axis (issue 36).

The record-level detector (:func:`~gyrofilter.analysis.gap.detectors.repeats.detect_repeats`)
counts on every axis at once before the axes' detectors (step 2, :attr:`GapInput.repeats`: the
colored noise's detector takes the repeats' lag-1 correlation out); :func:`weigh_repeats` weighs
it after the axes' findings are decided (the decision order of
:mod:`gyrofilter.analysis.gap.detectors`): a candidate is kept where the extended model with the repeats (the model's top-level
``repeated_samples`` at the estimated excess fraction, random pattern) lowers the mean D over the
analysed axes (its gain; every axis's D after then reflects it), or, where the excess fraction is
beyond the largest a model takes (50 %), whatever its gain, at that cap, with a note that no model
reproduces the record and its other findings are not to be trusted (issue 37). Its interval is the count's own
(the binomial interval of the excess fraction, :func:`gyrofilter.analysis.repeats.repeated_rows`),
not a bootstrap: the fraction is a count.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...effects import REPEATED_SAMPLES
from ...units import AXES
from . import detectors as det
from .features import METRIC, d_shown
from .state import RowsFinding


def weigh_repeats(inp, state, scorer):
    """The state with the repeated-rows finding kept (:attr:`GapState.rows`, D after of every
    analysed axis with it) where the detector names one and it lowers the mean D over the analysed
    axes; a note where it is found but shows no gain. The record is read a column at a time."""
    analysed = [i for i, a in enumerate(AXES) if a not in inp.idle]
    if not analysed:
        return state
    counted, cand = inp.repeats
    if cand is None:
        return state
    entry = {REPEATED_SAMPLES: {"fraction": float(cand.params["fraction"])}}
    after = list(state.after)
    for i in analysed:
        spec, with_temperature, _ = state.extended(inp, i) or (inp.base["axes"][AXES[i]], False, {})
        after[i] = scorer.discrepancy(i, (spec, with_temperature, entry), f"extended model on {AXES[i]}")
    before_mean = float(np.mean([state.after[i] for i in analysed]))
    after_mean = float(np.mean([after[i] for i in analysed]))
    if det.beyond_model(counted):  # named at the model's cap whatever its gain: no model holds the record to weigh it
        state = state.with_notes(det.beyond_model_text(counted))
    elif not after_mean < before_mean:
        return state.with_notes(f"{REPEATED_SAMPLES} dropped: no gain (mean discrepancy over the axes {d_shown(before_mean)} "
                                f"-> {d_shown(after_mean)})")
    return replace(state, rows=RowsFinding(cand, counted, entry, before_mean, after_mean), after=tuple(after))


def rows_findings(state):
    """The report's finding of the kept whole-row effect (docs/formats.md, section 3; ``axis``:
    ``xyz``, every axis at once), in a list: empty when there is none."""
    if state.rows is None:
        return []
    cand, counted = state.rows.cand, state.rows.counted
    return [{"effect": cand.effect, "axis": "".join(AXES), "params": cand.plain_params(),
             "evidence": cand.evidence_text(),
             "gain": {"metric": f"discrepancy D ({METRIC}), mean over the analysed axes", "before": state.rows.before,
                      "after": state.rows.after},
             "statistic": {"name": cand.statistic_name, "value": float(cand.statistic), "threshold": float(cand.threshold)},
             "alternatives": [], "params_ci95": {"fraction": [min(float(v), det.max_fraction()) for v in counted.excess_ci95]}}]
