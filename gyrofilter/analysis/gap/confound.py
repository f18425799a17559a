"""Confounded causes: where two causes explain a record about equally, which one the gap
analysis names, why, and how it says so. Every such rule of the gap analysis lives here, with
its thresholds and its wording, so that "why the temperature and not a warm-up here?" is answered
by this module alone.

**The allowance.** Two readings explain a record about equally when their discrepancies differ
by at most

    ``s = k max(s_1, s_2)``,  ``k = CONFOUNDED_SPREADS = 2``,

``s_M`` the **null spread of D** of model M (:func:`gyrofilter.analysis.gap.features.null_spread`):
the standard deviation of D over M's own simulated runs, each run scored like the measurement
against the other runs (leave one out). It is how much D moves between records that M explains
exactly (``k = 2``: the band D keeps in about 95 % of them), so a difference within it is a
difference the record cannot vouch for. With the 6-12 runs of the extended models the
leave-one-out D also carries the scatter of a spread estimated from one run fewer, so ``s`` errs
wide: towards calling two readings equal, that is towards the cause named below with the other
listed. The composite stochastic part must beat the extended model by the same allowance
(:mod:`gyrofilter.analysis.gap.composite`).

**1. Temperature or time.** Where a temperature is recorded and follows a warm-up itself, a bias
warm-up in time, a ramp or a slow wander can fit the block means as well as a temperature
coefficient. The measured covariate is the cause to name: it predicts the bias at the next
power-up, an exponential in time does not (:data:`WHY_THE_COVARIATE`). Three places decide:

* *Detection* (:func:`covariate_or_time`, called by the slow detector
  :func:`gyrofilter.analysis.gap.detectors.detect_slow` with its two readings: the covariate
  reading, the temperature first and the time shapes and spectra in what it leaves, and the time
  reading without the temperature). A line or a jump is not a settling: against a ramp or a step
  the better fit of the block means decides (``Delta chi^2 - k ln n``), and a ramp must win by more
  than the null spread of that difference (:func:`_shape_beats_temperature`, ``RAMP_SPREAD_Z``
  sd). A covariate reading that needs a wander where the time reading explains the record by a
  shape alone is the more complex reading and is not returned. Otherwise the covariate reading is
  returned with the time reading riding on the temperature candidate.
* *Weighing on D* (:func:`weigh_readings`): both readings are simulated with the axis's other
  findings and scored by D. The covariate reading is kept unless the time reading is clearly
  better (``D_time < D_cov - s``); where both explain about equally, the time reading is listed on
  the temperature finding as ``alternatives`` (each entry: effect, params, and D of the axis with
  the whole time reading in place of the covariate reading), and the evidence says that the
  record cannot tell them apart and how the other reading would look. When the time reading is
  clearly better, it replaces the covariate reading and a note says so.
* *Keeping without a gain alone* (:func:`kept_without_gain`): a finding with no gain alone is kept
  when the axis's other findings do better with it; a temperature also where D with it is within
  the allowance of D without it (the measured covariate is kept where D cannot tell).

**2. Bias instability or Gauss-Markov** (:data:`CONFUSABLE_WANDERS`, :func:`weigh_wanders`). A
Gauss-Markov spectrum is flat below its corner ``1/(2 pi tau)`` and falls like 1/f^2 above it;
with the corner among the record's frequencies it bends across them about as a bias
instability's 1/f falls, and its Allan deviation, a broad hump near ``1.9 tau``, fits the flat
floor of a bias instability over a decade or two. Where the slow detector finds both significant,
both are weighed on D: the Gauss-Markov is named only where it is clearly better; otherwise the
bias instability, which has one parameter fewer, with the Gauss-Markov as its alternative where
the two are about equal.

**3. Heavy tails or isolated spikes** (:func:`tails_or_spikes`). A heavy-tailed noise and a few
gross errors both widen the tails of the noise's distribution. The likelier of the two models of
the tails is named, by at least ``HEAVY_TAILS_OVER_SPIKES`` (2 Delta log L = 10, very strong
evidence, Kass & Raftery 1995) where the outlier detector has found spikes beyond its gross-error
threshold: spikes far outside the noise are direct evidence of gross errors, replaced by a
heavy-tailed noise only on strong evidence. Where the two fit within that margin, the finding, or
a note, says that the other explains the tails about as well.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...effects import BIAS_INSTABILITY, BIAS_STEP, BY_NAME, GAUSS_MARKOV, RATE_RAMP, TEMPERATURE, WANDERS
from ...units import AXES
from ..stats import block_means

#: two readings explain a record about equally when their D differ by at most this many null
#: spreads of D (module docstring). Measured on the example model (docs/gap.md, "Confounded causes")
CONFOUNDED_SPREADS = 2.0
#: two-sided 95 % normal quantile: a ramp's better fit over the temperature's counts when it is
#: beyond this many sd of the difference's null spread (:func:`_shape_beats_temperature`)
RAMP_SPREAD_Z = 1.96
#: 2 Delta log L by which a heavy-tailed noise must beat isolated spikes where the outlier detector
#: found spikes (10: "very strong" evidence, Kass & Raftery 1995, sec. 3.2); also the margin within
#: which the two explain the tails about as well
HEAVY_TAILS_OVER_SPIKES = 10.0
#: the two stationary slow wanders whose spectra a record may not tell apart (1/f and a Lorentzian
#: whose corner lies near the record's lowest frequencies)
CONFUSABLE_WANDERS = (BIAS_INSTABILITY, GAUSS_MARKOV)


def covariate_or_time(time_reading, covariate, stats, x, temp_c):
    """The reading the slow detector returns for an axis with a recorded temperature (module
    docstring, 1.): ``time_reading`` (a list of candidates) or ``covariate`` (the covariate
    reading, the temperature candidate first; None where the temperature is not significant),
    the time reading riding on the temperature candidate (``time_reading``).
    ``stats``: the shapes' Delta chi^2 of the block means; ``x``, ``temp_c``: the axis's series."""
    line_or_jump = time_reading[0].effect if time_reading and time_reading[0].effect in (RATE_RAMP, BIAS_STEP) else None
    if line_or_jump and _shape_beats_temperature(line_or_jump, stats, x, temp_c):
        # a line or a jump is not a settling: against them the better fit of the block means decides
        return time_reading
    if covariate is None or (any(c.effect in WANDERS for c in covariate[1:])
                             and not any(c.effect in WANDERS for c in time_reading)):
        # a covariate reading that needs a wander where a shape in time alone explains the
        # record is the more complex reading (a ramp read as the temperature's settling plus a
        # random walk for the difference)
        return time_reading
    if time_reading:
        return [replace(covariate[0], time_reading=time_reading)] + covariate[1:]
    return covariate


def _shape_beats_temperature(name, stats, x, temp_c):
    """Whether the time shape ``name`` (a ramp or a step) fits the block means better than the
    temperature (``stats``: their Delta chi^2 in units of the white level).

    A step wins by BIC (``Delta chi^2 - k ln n``). A ramp must also beat the temperature by more
    than the null spread of the difference: for two one-column fits of white block means
    ``y = beta g_T + e`` (``g`` the unit-norm, mean-free regressors, ``rho = g_R . g_T``),
    ``a = g_T . y`` and ``b = g_R . y`` are N(beta, 1) and N(rho beta, 1) with correlation rho, and
    ``a^2 - b^2 = (a - b)(a + b)`` has sd ``2 |beta| sqrt(1 - rho^2)`` to first order (Vuong 1989,
    non-nested models). A temperature settling over a long time constant is nearly a line, and
    a ramp then fits it within that spread about as often as not: the measured covariate is the
    cause to name (the ramp rides on it as the alternative, weighed on D by :func:`weigh_readings`)."""
    y, _ = block_means(x)
    n = y.size
    d_shape, d_temp = stats[name], stats.get(TEMPERATURE, 0.0)
    if d_shape - BY_NAME[name].n_params * math.log(n) < d_temp - math.log(n):
        return False
    if name != RATE_RAMP:
        return True
    tb, _ = block_means(np.asarray(temp_c, dtype=float))
    if tb.size != n or not np.ptp(tb) > 0:
        return True
    g_t = tb - tb.mean()
    g_r = np.arange(n) - 0.5 * (n - 1)
    rho = float(np.dot(g_t, g_r) / math.sqrt(np.dot(g_t, g_t) * np.dot(g_r, g_r)))
    spread = 2.0 * math.sqrt(max(1.0 - rho * rho, 0.0) * max(d_shape, d_temp))
    return d_shape - d_temp > RAMP_SPREAD_Z * spread


def kept_without_gain(effect, with_all, without, spread_of):
    """Why a finding with no gain alone is kept (module docstring, 1.): ``""`` where the axis's
    other findings do better with it (``with_all < without``); for a temperature, the reason where
    D with it is within the allowance of D without it (``spread_of()``: the larger null spread of
    D of the two models, computed only then); None where it is dropped."""
    if with_all < without:
        return ""
    if effect == TEMPERATURE and np.isfinite(with_all):
        spread = CONFOUNDED_SPREADS * spread_of()
        if with_all <= without + spread:
            return f", within the null spread of D ({spread:.2g}): the measured covariate is kept where D cannot tell"
    return None


def tails_or_spikes(over, spikes_found, fits, heavier):
    """Heavy tails or isolated spikes (module docstring, 3.), from ``over`` = 2 (log L_mixture -
    log L_spikes) of the noise's tails (``fits``: :func:`gyrofilter.analysis.gap.detectors.tail_fits`;
    ``heavier``: the sentence saying how heavy they are). Returns ``(named, note, evidence_end)``:
    whether heavy tails are named, a note where they are not but the tails say something, and what
    the heavy-tail finding's evidence ends with."""
    margin = HEAVY_TAILS_OVER_SPIKES if spikes_found else 0.0
    close = abs(over) < HEAVY_TAILS_OVER_SPIKES
    if over < margin:
        if spikes_found and not close:
            return False, None, ""  # isolated spikes, as the outlier detector says
        if close:
            return False, (f"{heavier} and a heavy-tailed noise (fraction {fits['fraction']:.3g}, scale ratio "
                           f"{fits['scale_ratio']:.3g}) explains them about as well as isolated spikes (2 Delta log L = "
                           f"{over:+.1f}, margin {HEAVY_TAILS_OVER_SPIKES:g})"), ""
        return False, (f"{heavier}; isolated spikes (about {fits['magnitude']:.2g} robust sd, a fraction "
                       f"{fits['rate']:.2g} of the samples) explain them better than a heavy-tailed noise (2 Delta log L = "
                       f"{-over:.1f}) but too few lie beyond the gross-error threshold to name outliers"), ""
    end = (f" (below {HEAVY_TAILS_OVER_SPIKES:g}: isolated spikes of about "
           f"{fits['magnitude']:.2g} robust sd explain the tails about as well)") if close else ""
    return True, None, end


#: why a finding with ``alternatives`` is the one named, by its effect (the reports' line under it:
#: :func:`gyrofilter.analysis.gap.report.indistinguishable_text`)
NAMED_BECAUSE = {TEMPERATURE: "it is measured and predicts the bias at the next power-up",
                 BIAS_INSTABILITY: "it has one parameter fewer"}

#: why the covariate is named where a reading in time explains a record as well (the end of such a
#: temperature finding's evidence; the HTML report says it once for all its findings)
WHY_THE_COVARIATE = (f"The temperature is named because {NAMED_BECAUSE[TEMPERATURE]}; "
                     "read in time, the bias would settle the same way after every power-on whatever the temperature "
                     "does, and a record where the temperature moves without a power-up (heating, a cold start) tells "
                     "them apart")


def weigh_readings(inp, state, scorer):
    """Choose per axis between the covariate and the time reading of a confounded temperature
    (module docstring, 1.); returns the new state: the reading not chosen excluded, a time reading
    that is as good riding on the temperature candidate as its ``alternatives``."""
    for i, reading in sorted(state.readings.items()):
        a = AXES[i]
        cov_ks = reading.covariate
        others = [k for k, (ci, _) in enumerate(state.candidates) if ci == i and k not in cov_ks and k not in state.excluded]
        k_temp = next(k for k in cov_ks if state.candidates[k][1].effect == TEMPERATURE)
        first = len(state.candidates)
        time_cands = [replace(c, reading="time") for c in reading.time]
        state = replace(state, candidates=state.candidates + tuple((i, c) for c in time_cands)).with_axis(i, time=reading.ext_axis)
        time_ks = list(range(first, len(state.candidates)))
        label = f"covariate and time readings on {a}"
        inp.say(label)
        cov_model, time_model = state.model(inp, i, others + cov_ks), state.model(inp, i, others + time_ks)
        d_cov = scorer.discrepancy(i, cov_model, label)
        d_time = scorer.discrepancy(i, time_model, label)
        spread = CONFOUNDED_SPREADS * max(scorer.null_spread(i, cov_model, label), scorer.null_spread(i, time_model, label))
        shown = " + ".join(_show(c) for c in reading.time)
        weighed = (f"axis {a}: readings weighed on D: with the temperature {d_cov:.3g}, in time ({shown}) {d_time:.3g}; "
                   f"allowance {spread:.2g} ({CONFOUNDED_SPREADS:g} null spreads of D)")
        if d_time < d_cov - spread:
            state = replace(state, excluded=state.excluded | set(cov_ks)).with_axis(i, ext=reading.ext_axis, wv=reading.wv)
            for k in time_ks:
                state = state.with_candidate(k, replace(state.candidates[k][1], reading=""))
            state = state.with_notes(weighed + ": the time reading is clearly better, the temperature is not named")
            continue
        state = replace(state, excluded=state.excluded | set(time_ks))
        if d_time > d_cov + spread:
            state = state.with_notes(weighed + ": the temperature is clearly better, the time reading is not listed")
            continue
        state = state.with_notes(weighed + ": the record cannot tell them apart; the temperature is named, the time "
                                 "reading listed as its alternatives")
        temp = state.candidates[k_temp][1]
        state = state.with_candidate(k_temp, replace(
            temp, alternatives=tuple((c, d_time) for c in time_cands),
            evidence_notes=temp.evidence_notes + (
                f"the time reading {shown} explains this record about as well (D {d_time:.3g} against {d_cov:.3g}, "
                f"within the null spread of D, {spread:.2g}): the temperature follows a warm-up itself, so this "
                f"record cannot tell them apart. {WHY_THE_COVARIATE}",)))
    return state


def weigh_wanders(inp, state, scorer):
    """Choose per axis between a bias instability and a Gauss-Markov wander where the slow
    detector found both significant (the candidate's ``wander_alternative``): each is simulated
    with the axis's other findings and scored by D, as the readings of a confounded temperature
    are (module docstring, 2.). The Gauss-Markov is named only where it is clearly better
    (``D_gm < D_bi - s``); otherwise the bias instability, which has one parameter fewer, and where
    the two are about equal the Gauss-Markov rides on it as its ``alternatives``. Returns the new
    state, the reading not chosen excluded."""
    for k in range(len(state.candidates)):
        i, c = state.candidates[k]
        alt = c.wander_alternative
        if alt is None:
            continue
        c = replace(c, wander_alternative=None)
        state = state.with_candidate(k, c)
        if k in state.excluded:
            continue
        state = replace(state, candidates=state.candidates + ((i, alt),))
        k_alt = len(state.candidates) - 1
        a = AXES[i]
        others = [j for j, (ci, _) in enumerate(state.candidates)
                  if ci == i and j not in (k, k_alt) and j not in state.excluded]
        label = f"bias instability and Gauss-Markov readings on {a}"
        inp.say(label)
        bi, gm = ((k, c), (k_alt, alt)) if c.effect == BIAS_INSTABILITY else ((k_alt, alt), (k, c))
        bi_model, gm_model = state.model(inp, i, others + [bi[0]]), state.model(inp, i, others + [gm[0]])
        d_bi = scorer.discrepancy(i, bi_model, label)
        d_gm = scorer.discrepancy(i, gm_model, label)
        spread = CONFOUNDED_SPREADS * max(scorer.null_spread(i, bi_model, label), scorer.null_spread(i, gm_model, label))
        weighed = (f"axis {a}: readings of the slow wander weighed on D: {_show(bi[1])} {d_bi:.3g}, {_show(gm[1])} "
                   f"{d_gm:.3g}; allowance {spread:.2g} ({CONFOUNDED_SPREADS:g} null spreads of D)")
        if d_gm < d_bi - spread:
            state = replace(state, excluded=state.excluded | {bi[0]}).with_notes(
                weighed + ": the Gauss-Markov is clearly better, the bias instability is not named")
            continue
        state = replace(state, excluded=state.excluded | {gm[0]})
        if d_bi < d_gm - spread:
            state = state.with_notes(weighed + ": the bias instability is clearly better, the Gauss-Markov is not listed")
            continue
        state = state.with_notes(weighed + ": the record cannot tell them apart; the bias instability is named (one "
                                 "parameter fewer), the Gauss-Markov listed as its alternative")
        corner_hz = 1.0 / (2.0 * np.pi * gm[1].params["tau_s"])
        state = state.with_candidate(bi[0], replace(
            bi[1], alternatives=((gm[1], d_gm),),
            evidence_notes=bi[1].evidence_notes + (
                f"the wander reading {_show(gm[1])} explains this record about as well (D {d_gm:.3g} against "
                f"{d_bi:.3g}, within the null spread of D, {spread:.2g}): its spectrum, flat below its corner "
                f"1/(2 pi tau) = {corner_hz:.2g} Hz and falling like 1/f^2 above it, bends across this record's "
                "frequencies about as the 1/f of a bias instability falls, so the record cannot tell them apart; "
                "the bias instability is named, with one parameter fewer",)))
    return state


def _show(c):
    """``effect (k=v, ...)`` of a candidate."""
    return f"{c.effect} (" + ", ".join(f"{k}={v:.3g}" for k, v in c.params.items()) + ")"


def alternatives_entry(cand):
    """The ``alternatives`` of a finding in the gap report: per entry of the other reading its
    effect, params and D (of the axis with that whole reading in place of the finding's)."""
    return [{"effect": c.effect, "params": {k: float(v) for k, v in c.params.items()}, "D": float(d)}
            for c, d in cand.alternatives]
