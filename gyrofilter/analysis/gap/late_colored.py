"""The late colored noise of the gap analysis (:mod:`gyrofilter.analysis.gap.pipeline`, step 4, after
the gain per finding): a short correlation too weak for the detector's own threshold on an axis
whose model does not close because of it.

The colored-noise detector names a lag-1 autocorrelation of the high-passed noise at
:data:`~gyrofilter.analysis.gap.detectors.COLORED_Z` = 6 standard errors (1/sqrt(N)) or more: in
a 2.8-h record that is 0.004, in 18 s at 286 Hz 0.08. The BROAD rest phases' x axes hold a
negative lag-1 of -0.05 to -0.08 with a lag-2 of about 0 (white noise plus a differenced part of
about a tenth of its variance), 3.1-5.7 standard errors on 16-37 s: unnamed, the white model's
Haar wavelet variance is too low at one sample and too high by 3-8 % at 2-32 samples, the
lag-1 departs most from the model's runs and D stays above 2 (docs/gap_closure.md, held out).

**When it is proposed**: where an axis's D after is above
:data:`~gyrofilter.analysis.gap.detectors.OUTSIDE_NULL_D` (clean records stay below it in 95 %
of runs), the axis has no colored noise, and the feature furthest outside its extended model's
runs (:func:`~gyrofilter.analysis.gap.features.departs_most`) is the lag-1 autocorrelation, by
:data:`~gyrofilter.analysis.gap.detectors.COLORED_LATE_Z` sd or more: then the detector's
candidate at that z (its ``reserve``, measured on the axis's cleaned series, less its bands'
and wander's correlation as usual: :func:`~gyrofilter.analysis.gap.detectors.detect_colored`
with ``z_min``) is scored. A clean record must be outside the null band (about 5 % of them) and
have its largest departure, 3 sd or more, in the one lag-1 feature among some thirty. Where
another feature departs more, the lag-1 may be its side effect: the first half of the BROAD
rest phase ``broad_09`` z (13.6 s) holds a band near 25 Hz too weak to name there, whose
correlation reads as a lag-1 of +0.09 (5.8 standard errors) while the Allan deviation at 0.0175 s
departs most (z +6.0); a low pass in its place lowered D (5.13 -> 2.53) but put the wavelet
variance at 2-32 samples further from the other half's (held out 1.75 -> 2.34).

**Kept** by the composite step's rule (:func:`~gyrofilter.analysis.gap.composite.short_of_a_clear_gain`):
D falls below :data:`~gyrofilter.analysis.gap.detectors.COMPOSITE_MIN_GAIN` times its value and by
more than two null spreads of D of the extended model; then it is a finding of the axis, else a
note. The axis's white level is the one measured without it (the colored noise's high-pass
correction, :func:`~gyrofilter.analysis.gap.baseline.highpass_loss`, moves it by less than 0.2 %
at |lag1| < 0.1).
"""
from __future__ import annotations

from dataclasses import replace

from ...effects import COLORED_NOISE
from ...units import AXES
from . import detectors as det
from .baseline import MIN_SIMS
from .composite import short_of_a_clear_gain
from .features import d_shown, departs_most
from .state import Kept


def late_colored_step(inp, state, scorer):
    """The step of the module docstring on every axis; returns the new state."""
    if inp.n_sims < MIN_SIMS:  # D is not judged
        return state
    for i, a in enumerate(AXES):
        reserve = state.axes[i].reserve if state.axes else None
        if reserve is None or a in inp.idle or state.after[i] <= det.OUTSIDE_NULL_D:
            continue
        ks = state.kept_on(i)
        if any(state.candidates[k][1].effect == COLORED_NOISE for k in ks):
            continue
        deps = scorer.departures(i, state.model(inp, i, ks), f"extended model on {a}") if ks else inp.deps[i]
        worst = departs_most(deps, inp.taus, inp.bands)
        if worst["feature"] != "lag1" or not abs(worst["z"]) >= det.COLORED_LATE_Z:
            continue
        inp.say(f"late colored noise on {a}")
        state = _with_reserve(inp, state, scorer, i, ks, worst["z"])
    return state


def _with_reserve(inp, state, scorer, i, ks, z):
    """The state with axis ``i``'s reserve colored noise kept where it lowers D enough; a note
    either way. ``ks``: the axis's kept findings; ``z``: its lag-1's departure from their model."""
    a, after = AXES[i], state.after[i]
    k = len(state.candidates)
    cand = state.axes[i].reserve
    cand = replace(cand, evidence_notes=cand.evidence_notes + (
        f"proposed late: D after {d_shown(after)} stays above {det.OUTSIDE_NULL_D:g} and the lag-1 departs most from the "
        f"extended model's runs (z = {z:+.1f}, at least {det.COLORED_LATE_Z:g}; the detector's own threshold is "
        f"{det.COLORED_Z:g} standard errors)",))
    trial = replace(state, candidates=state.candidates + ((i, cand),))
    s_ext = scorer.null_spread(i, state.model(inp, i, ks) if ks else None, f"extended model on {a}")
    d_with = scorer.discrepancy(i, trial.model(inp, i, ks + [k]), f"late colored noise on {a}")
    lag1 = cand.params["lag1"]
    short = short_of_a_clear_gain(d_with, after, s_ext)
    if short:  # not a candidate of the state: the axis's models stay as they were
        return state.with_notes(
            f"axis {a}: a colored noise (lag1 = {lag1:+.3f}, {cand.statistic:.1f} standard errors) matches the lag-1 "
            f"but did not lower D enough {short}; not used")
    state = trial
    alone = scorer.discrepancy(i, state.model(inp, i, [k]), f"gain of the late colored noise on {a}") if ks else d_with
    return replace(state, kept=state.kept + (Kept(k, i, cand, alone),), single={**state.single, k: alone},
                   after=state.after[:i] + (d_with,) + state.after[i + 1:]).with_notes(
        f"axis {a}: a colored noise (lag1 = {lag1:+.3f}, {cand.statistic:.1f} standard errors, below the detector's "
        f"{det.COLORED_Z:g}) lowers D from {d_shown(after)} to {d_shown(d_with)}: the lag-1 departed most (z = {z:+.1f})")
