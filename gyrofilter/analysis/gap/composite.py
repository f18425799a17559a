"""The composite stochastic part of the gap analysis (:mod:`gyrofilter.analysis.gap.pipeline`, step 4).

Where an extended axis's D stays above :data:`~gyrofilter.analysis.gap.detectors.OUTSIDE_NULL_D`,
a GMWM-style fit (:mod:`gyrofilter.analysis.noise.gmwm`; Guerrier et al. 2013) of white noise, an
optional rate random walk, an optional bias instability (the simulator's flicker bank, whose
wavelet variance is flat: no sum of a few Gauss-Markov terms is, so without it a 1/f bias reads as
three of them) and 0-3 Gauss-Markov terms to the Haar wavelet variance of the series
cleaned of the deterministic findings, at tau >= max(1 s, 16 samples) (shorter scales belong to
the colored noise and the bands), the model chosen by the WVIC (Guerrier et al. 2016;
:func:`gyrofilter.analysis.noise.gmwm.select_model`), replaces the axis's slow stochastic findings (and its colored noise, if that is better without it); its N becomes
the white level (the colored noise then keeps the long-tau level, ``preserve: arw``, and, if D
is lower so, the per-sample variance too: :func:`composite_lags`). The replacement is kept
only if D falls below :data:`~gyrofilter.analysis.gap.detectors.COMPOSITE_MIN_GAIN` times its value
and by more than two null spreads of D of the axis's extended model (as two readings are
weighed in :mod:`gyrofilter.analysis.gap.confound`: a smaller gain the record cannot vouch for).
Where the axis has ``outliers`` the wavelet variance is the robust M-estimate
(:mod:`gyrofilter.analysis.noise.wv_robust`), so that spikes the outlier detector missed do not pull the
fit; where it has ``heavy_tails`` the classical one, which is consistent for that noise (its tails
are part of the model's variance) and at the composite's scales (1 s and more: a hundred samples
and more per coefficient, nearly Gaussian) more precise than the robust one (``tools/robust_gmwm.py``,
docs/gap.md), while the WVIC's bootstrap simulates the heavy-tailed noise, so that the selection
sees how much noisier it makes the short scales.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...effects import (BIAS_INSTABILITY, COLORED_NOISE, GAUSS_MARKOV, HEAVY_TAILS, OUTLIERS, RATE_RANDOM_WALK,
                            WANDERS)
from . import detectors as det
from .confound import CONFOUNDED_SPREADS
from .features import d_shown
from .state import Kept
from ..noise import gmwm
from ...sim import noise_terms as nt
from ...units import AXES

#: the optional terms of the composite fit (of :data:`gyrofilter.analysis.noise.gmwm.TERMS`, named as the effects they become)
COMPOSITE_TERMS = (RATE_RANDOM_WALK, BIAS_INSTABILITY)
#: the composite fit uses the wavelet variance at tau >= max(1 s, 16 samples): shorter scales
#: carry the colored noise's low-pass shape and the narrow bands, which have their own terms
COMPOSITE_MIN_TAU_S = 1.0
_COMPOSITE_STATISTIC = "D of the extended axis without the composite stochastic part / D with it"


def composite_step(inp, state, scorer):
    """Step 4, continued, on the gap analysis's state (returns the new one): where an extended axis is still far
    outside the null band (D above :data:`~gyrofilter.analysis.gap.detectors.OUTSIDE_NULL_D`), a
    composite stochastic part (:func:`_composite_candidates`) replaces the axis's slow
    stochastic findings, and its colored noise if that is better without it, when D falls below
    :data:`~gyrofilter.analysis.gap.detectors.COMPOSITE_MIN_GAIN` times its value and by more than
    ``k s_ext``, ``s_ext`` the null spread of D of the axis's extended model and ``k`` =
    :data:`~gyrofilter.analysis.gap.confound.CONFOUNDED_SPREADS` (:mod:`gyrofilter.analysis.gap.confound`):
    D of that model moves that much between records it explains exactly, so a smaller gain is
    one the record cannot vouch for (a bias instability was replaced by a 10-s Gauss-Markov term,
    2.31 -> 1.5 against 2 x 0.83, on the example model's hour at 100 Hz, seed 3, x)."""
    for i, a in enumerate(AXES):
        models = state.axes[i]
        if state.after[i] <= det.OUTSIDE_NULL_D or models.wv is None:
            continue
        why = gmwm.unfittable(models.wv)
        if why is not None:
            state = state.with_notes(f"axis {a}: no composite stochastic fit: {why}")
            continue
        inp.say(f"composite stochastic fit on {a}")
        fit, comp = _composite_candidates(models.wv, inp.sample_rate_hz)
        if not comp:
            continue
        state = _with_composite(inp, state, scorer, i, fit, comp)
    return state


def short_of_a_clear_gain(d_new, after, s_ext):
    """Why a model's D ``d_new`` is not a clear gain on the axis's D after ``after`` (the rule of
    this step and of the compression's: below :data:`~gyrofilter.analysis.gap.detectors.COMPOSITE_MIN_GAIN`
    times it and by more than :data:`~gyrofilter.analysis.gap.confound.CONFOUNDED_SPREADS` null
    spreads ``s_ext`` of D of the extended model), in parentheses; "" where it is one."""
    spread = CONFOUNDED_SPREADS * s_ext
    if d_new < det.COMPOSITE_MIN_GAIN * after and d_new < after - spread:
        return ""
    return (f"({d_shown(after)} -> {d_shown(d_new)}; it must fall below {det.COMPOSITE_MIN_GAIN:g} times its value "
            f"and by more than {CONFOUNDED_SPREADS:g} null spreads of D of the extended model, {spread:.2g})")


def _with_composite(inp, state, scorer, i, fit, comp):
    """The state with axis ``i``'s slow stochastic findings replaced by the composite fit's
    candidates ``comp`` where that lowers D enough (:func:`composite_step`); the candidates are
    appended either way."""
    a, after = AXES[i], state.after[i]
    s_ext = scorer.null_spread(i, state.model(inp, i, state.kept_on(i)), f"extended model on {a}") if state.kept_on(i) else 0.0
    keep_k = [row.k for row in state.kept if row.axis == i and row.cand.effect not in WANDERS]
    first = len(state.candidates)
    state = replace(state, candidates=state.candidates + tuple((i, c) for c in comp))
    comp_k = list(range(first, len(state.candidates)))
    trial = state
    for k in keep_k:  # the axis's other findings join the composite model
        trial = trial.with_candidate(k, replace(trial.candidates[k][1], composite=True))
    trial = trial.with_axis(i, composite=dict(state.axes[i].ext, arw_dps_per_sqrt_hz=fit.arw_dps_per_sqrt_hz))

    def d_of(model_state, ks):
        return scorer.discrepancy(i, model_state.model(inp, i, ks), f"composite model on {a}")

    d_comp = d_of(trial, keep_k + comp_k)
    colored_k = [k for k in keep_k if trial.candidates[k][1].effect == COLORED_NOISE]
    dropped_colored = False
    if colored_k:
        # the colored noise re-solved to keep the per-sample variance as well
        lags = composite_lags(trial.axes[i].ext, trial.axes[i].composite, trial.candidates[colored_k[0]][1].params)
        if lags is not None:
            d_alt = d_of(trial.with_axis(i, lags=lags), keep_k + comp_k)
            if d_alt < d_comp:
                d_comp, trial = d_alt, trial.with_axis(i, lags=lags)
        # a fast Gauss-Markov term of the composite may be what the colored noise stood for
        d_alt = d_of(trial, [k for k in keep_k if k not in colored_k] + comp_k)
        if d_alt < d_comp:
            d_comp = d_alt
            trial = trial.with_candidate(colored_k[0], replace(trial.candidates[colored_k[0]][1], composite=False))
            keep_k = [k for k in keep_k if k not in colored_k]
            dropped_colored = True
    short = short_of_a_clear_gain(d_comp, after, s_ext)
    if short:
        return state.with_notes(f"axis {a}: a composite stochastic fit ({fit.name}) did not lower D enough {short}; not used")
    notes = []
    if dropped_colored:  # said only where the composite model is used
        notes.append(f"colored_noise on {a} dropped: the composite stochastic part explains the correlation without it")
    single_k = {k: scorer.discrepancy(i, trial.model(inp, i, [k]), f"gain of the composite's {trial.candidates[k][1].effect} on {a}")
                for k in comp_k}
    wv = state.axes[i].wv
    notes.append(
        f"axis {a}: the composite stochastic fit ({fit.name}, chosen by WVIC on the "
        f"{'robust ' if wv.robust else ''}wavelet variance at "
        f"tau >= {wv.tau_s[0]:.3g} s) lowers D from {d_shown(after)} to {d_shown(d_comp)}; it replaces the "
        "axis's slow stochastic findings")
    for k in comp_k:
        trial = trial.with_candidate(k, replace(trial.candidates[k][1], statistic=after / d_comp))
    lags = trial.axes[i].lags
    if lags and colored_k and colored_k[0] in keep_k:
        colored = trial.candidates[colored_k[0]][1]
        trial = trial.with_candidate(colored_k[0], replace(
            colored, params={**colored.params, **lags},
            evidence_notes=colored.evidence_notes + ("in the composite model its lags are re-solved to keep both the "
                                                     "per-sample variance and the composite fit's white level",)))
    kept = ([row for row in state.kept if row.axis != i] + [Kept(k, i, trial.candidates[k][1], state.single[k]) for k in keep_k]
            + [Kept(k, i, trial.candidates[k][1], single_k[k]) for k in comp_k])
    return replace(trial, kept=tuple(kept), after=state.after[:i] + (d_comp,) + state.after[i + 1:]).with_notes(*notes)


def slow_wavelet_variance(xc, sample_rate_hz, cands=()):
    """Haar wavelet variance (:func:`gyrofilter.analysis.noise.gmwm.haar_wv`) of the cleaned series at the
    dyadic scales tau >= max(:data:`COMPOSITE_MIN_TAU_S`, 16 / f_s); None when fewer than 4. The
    robust estimate where the axis's candidates ``cands`` hold ``outliers``; with ``heavy_tails``
    the classical one, marked with the noise's fraction and scale ratio for the WVIC's bootstrap
    (module docstring)."""
    m_min = max(16, int(math.ceil(COMPOSITE_MIN_TAU_S * sample_rate_hz)))
    if (xc.size - 2 * m_min * 8 + 1) / (2.0 * m_min * 8) < 2.0:
        return None
    tails = next((c for c in cands if c.effect == HEAVY_TAILS), None)
    wv = gmwm.haar_wv(xc, sample_rate_hz, min_m=m_min, robust=any(c.effect == OUTLIERS for c in cands),
                      tails=(tails.params["fraction"], tails.params["scale_ratio"]) if tails is not None else None)
    return wv if wv.tau_s.size >= 4 else None


def _composite_candidates(wv, sample_rate_hz):
    """GMWM-style composite fit (:func:`gyrofilter.analysis.noise.gmwm.select_model`, Guerrier et al. 2013) of
    white noise + optionally a rate random walk and a bias instability + 0..3 Gauss-Markov terms
    to ``wv``, the model chosen by the WVIC (see gyrofilter.analysis.noise.gmwm). Returns
    ``(fit, candidates)``: one ``gauss_markov`` per Gauss-Markov term, a ``rate_random_walk`` and a
    ``bias_instability`` if the fit has them, marked ``composite``; the fit's N is the
    composite model's white level."""
    fit, _ = gmwm.select_model(wv, terms_allowed=COMPOSITE_TERMS, starts=3, seed=0)
    out = []
    evidence = (f"composite fit {fit.name} to the {'robust ' if wv.robust else ''}Haar wavelet variance at tau = "
                f"{wv.tau_s[0]:.3g}-{wv.tau_s[-1]:.3g} s (weighted objective Q = {fit.objective:.3g} over {wv.tau_s.size} "
                f"scales, model chosen by WVIC = Q + {fit.optimism:.3g})")
    for sigma_dps, tau_s in fit.gauss_markov:
        out.append(det.Candidate(effect=GAUSS_MARKOV, params={"sigma_dps": sigma_dps, "tau_s": tau_s},
                                 statistic=0.0, threshold=1.0 / det.COMPOSITE_MIN_GAIN, statistic_name=_COMPOSITE_STATISTIC,
                                 evidence=f"Gauss-Markov term (sigma {sigma_dps:.3g} deg/s, tau {tau_s:.3g} s) of a " + evidence,
                                 composite=True))
    if fit.rrw_dps_per_sqrt_s is not None:
        out.append(det.Candidate(effect=RATE_RANDOM_WALK, params={"k_dps_per_sqrt_s": fit.rrw_dps_per_sqrt_s},
                                 statistic=0.0, threshold=1.0 / det.COMPOSITE_MIN_GAIN, statistic_name=_COMPOSITE_STATISTIC,
                                 evidence=f"random-walk term (K {fit.rrw_dps_per_sqrt_s:.3g} deg/s/sqrt(s)) of a " + evidence,
                                 composite=True))
    if fit.bias_instability_dps is not None:
        out.append(det.Candidate(effect=BIAS_INSTABILITY, params={"b_dps": fit.bias_instability_dps},
                                 statistic=0.0, threshold=1.0 / det.COMPOSITE_MIN_GAIN, statistic_name=_COMPOSITE_STATISTIC,
                                 evidence=f"flicker term (B {fit.bias_instability_dps:.3g} deg/s) of a " + evidence,
                                 composite=True))
    return fit, out


def composite_lags(ext_axis, composite_axis, lags):
    """The colored noise's lags in a composite model, re-solved so that with ``preserve: arw``
    it keeps both the composite fit's long-tau level N and the per-sample variance s^2 of the
    extended axis's colored noise (its ``preserve: std`` level): the short scales of the wavelet
    variance depend on s^2, the long ones on N, so its long-run ratio (1 + 2 sum rho_k) must be
    L = N^2 f_s / s^2. A low pass (``lags`` without ``lag2``) stays one: the AR(1) of ratio L
    has rho = (L - 1) / (L + 1). A first-order ARMA keeps its measured lag1 as well and moves
    its pole (:func:`gyrofilter.sim.noise_terms.arma11_for_lag1_and_ratio`). None when no such
    noise exists."""
    ratio = composite_axis["arw_dps_per_sqrt_hz"] ** 2 / ext_axis["arw_dps_per_sqrt_hz"] ** 2
    if "lag2" not in lags:
        return {"lag1": float(np.clip((ratio - 1.0) / (ratio + 1.0), -0.99, 0.99))}
    pair = nt.arma11_for_lag1_and_ratio(lags["lag1"], ratio, near_phi=lags["lag2"] / lags["lag1"])
    if pair is None:
        return None
    return dict(zip(("lag1", "lag2"), (float(v) for v in nt.arma11_lags(*pair))))
