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
  the better fit of the block means decides (``Delta chi^2 - k ln n``), and the shape must hold
  beside the temperature: what the temperature leaves of it passes the time shapes' test against
  flicker (:func:`_shape_beats_temperature`). A covariate reading that needs a wander where the time reading explains the record by a
  shape alone is the more complex reading: the time reading is returned first, with the covariate
  reading riding on it. Otherwise the covariate reading is returned first, with the time reading
  riding on the temperature candidate.
* *Weighing on D* (:func:`weigh_readings`): both readings are simulated with the axis's other
  findings and scored by D. The reading returned first is kept unless the other is clearly
  better (``D_other < D_first - s``); where both explain about equally, the other reading is
  listed on the first finding of the one named as ``alternatives`` (each entry: effect, params,
  and D of the axis with the whole other reading in its place), and the evidence says that the
  record cannot tell them apart and how the other reading would look. When the other reading is
  clearly better, it replaces the first and a note says so.
* *Suggested, not established* (:func:`suggested_temperature`): a temperature coefficient that
  fits the block means (``Delta chi^2 > DETERMINISTIC_THRESHOLD``) but is not significant under the
  wander the record shows (GLS ``z^2`` at most ``JOINT_THRESHOLD``, at least
  ``SUGGESTED_Z2``) is not named: the wander could have drawn that trend. The report lists it
  under ``uncertain`` with its GLS interval, so that a record too short to decide still says
  what it suggests.
* *Not named where its interval holds 0* (:func:`unnamed_temperature`): a temperature is named
  where the record establishes it, by its own GLS test or by the settling it explains established
  against flicker (above), **and** its coefficient's 95 % interval (the bootstrap's,
  :mod:`gyrofilter.analysis.gap.intervals`) does not hold 0: a named cause whose interval holds 0
  contradicts itself (the shipped 655-s log's y axis named -0.0123 deg/s per deg C, its interval
  [-0.045, 0.011], for a settling the temperature explained at GLS z = 0.7). Such a finding moves
  to ``uncertain`` after the bootstrap (:func:`gyrofilter.analysis.gap.keep.set_aside_uncertain`),
  its axis's other findings stay, and D of the axis is re-scored without it (a note says so). The
  GLS interval the detector has at hand is no earlier stand-in: beside the wander it is computed
  under the wander fitted to what the least-squares fit leaves, and on the default model's records
  it held 0 where the bootstrap's did not and the other way round (docs/gap.md).
* *Keeping without a gain alone* (:func:`kept_without_gain`): a finding with no gain alone is kept
  when the axis's other findings do better with it, or where D with it is within the allowance of
  D without it, with the axis's other findings or, alone on its axis, against the baseline: D
  cannot tell, and the detector's own test, calibrated against clean records, named it. A small
  temperature coefficient or bias instability on a 10-minute record moves D less than D's own
  noise, so a gain-or-not decision there was a coin toss on the simulations' streams (the shipped
  655-s log's y axis kept its bias instability with one seed's runs and dropped it with
  another's). A finding is dropped where D is clearly worse with it (beyond the allowance).

**2. Bias instability or Gauss-Markov** (:data:`CONFUSABLE_WANDERS`, :func:`weigh_wanders`). A
Gauss-Markov spectrum is flat below its corner ``1/(2 pi tau)`` and falls like 1/f^2 above it;
with the corner among the record's frequencies it bends across them about as a bias
instability's 1/f falls, and its Allan deviation, a broad hump near ``1.9 tau``, fits the flat
floor of a bias instability over a decade or two. Where the slow detector finds both significant,
both are weighed on D: the Gauss-Markov is named only where it is clearly better; otherwise the
bias instability, which has one parameter fewer, with the Gauss-Markov as its alternative where
the two are about equal.

**3. One spectral line: a sinusoid or a narrow band** (:func:`same_line`, :func:`weigh_lines`). The
sinusoid detector takes the coherent part of a line out of the series and the narrow-band detector
then finds what is left of it, so a vibration whose frequency wanders a little is found twice: a
sinusoid and a band at the same frequency (the band's centre within its half-power width of the
sinusoid's frequency). It is one line, and one finding: the line as a tone (the sinusoid, the
band's power returned to the white noise) and as a band of noise (the band holding the sinusoid's
power as well, ``rms'^2 = rms^2 + A^2 / 2``) are weighed on D with the axis's other findings, and
with both where both may be there. The band is named where it is clearly better, both only where
both together are clearly better than either; otherwise the sinusoid (a line no wider than the
record needs is a tone), with the band as its alternative where the two are about equal. A band
whose values are distributed as a tone's (arcsine-like, excess kurtosis below 0;
:mod:`gyrofilter.analysis.gap.detectors.tone`) is read as a
wandering tone, and that reading is weighed on D against the band as Gaussian noise
(:func:`weigh_tones`): the tone is named unless the band is clearly better, the band listed as its
alternative where the two are about equal.

**4. Heavy tails or isolated spikes** (:func:`tails_or_spikes`). A heavy-tailed noise and a few
gross errors both widen the tails of the noise's distribution. The likelier of the two models of
the tails is named, by at least ``HEAVY_TAILS_OVER_SPIKES`` (2 Delta log L = 10, very strong
evidence, Kass & Raftery 1995) where the outlier detector has found spikes beyond its gross-error
threshold: spikes far outside the noise are direct evidence of gross errors, replaced by a
heavy-tailed noise only on strong evidence. Where the two fit within that margin, the finding, or
a note, says that the other explains the tails about as well.

**5. Shocks that ring: one cause of spikes and a hump** (:func:`one_cause_of_spikes`,
:func:`ring_or_hump`). Shocks through the board's resonance leave spikes (the rings' peaks, which
the spike and tail detectors take for ``outliers`` or ``heavy_tails``) and a hump of power at the
resonance (the rings' spectrum, which the hump detector takes for a ``resonance``). Where the
ringing detector finds rings that explain the spikes' neighbourhoods beyond isolated spikes
(:mod:`gyrofilter.analysis.gap.detectors.ringing`), the ringing is the one cause named: the spike
and tail findings are not named beside it, nor a hump whose centre lies within the ring's
half-power band (its half-width f0 / (2Q)) of the ring's centre.

**6. A finding that makes its axis worse** (:func:`worse_together`). Each finding is kept on its
gain alone; two findings that each gain alone can still compete for one feature (a hump fitted
beside a wandering tone: the tone alone D 0.91, the tone with the hump 2.08, a new user's example
model). Where the axis with all its kept findings has D above the best of them alone by more than
the allowance, the finding whose leaving out lowers D most is dropped where that lowers D beyond
the allowance (once per axis; the check costs nothing where the findings add up, the common case).
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...effects import (BIAS_INSTABILITY, BIAS_STEP, BY_NAME, COLORED_NOISE, GAUSS_MARKOV, NARROWBAND, RATE_RAMP, SHAPES,
                       SINUSOID, TEMPERATURE, WANDERING_TONE, WANDERS)
from ...units import AXES

#: two readings explain a record about equally when their D differ by at most this many null
#: spreads of D (module docstring). Measured on the example model (docs/gap.md, "Confounded causes")
CONFOUNDED_SPREADS = 2.0
#: 2 Delta log L by which a heavy-tailed noise must beat isolated spikes where the outlier detector
#: found spikes (10: "very strong" evidence, Kass & Raftery 1995, sec. 3.2); also the margin within
#: which the two explain the tails about as well
HEAVY_TAILS_OVER_SPIKES = 10.0
#: GLS z^2 of a temperature coefficient from which a coefficient not significant under the record's
#: wander is still reported as suggested (:func:`suggested_temperature`): 3 sd, two-sided p = 0.003
SUGGESTED_Z2 = 9.0
#: the two stationary slow wanders whose spectra a record may not tell apart (1/f and a Lorentzian
#: whose corner lies near the record's lowest frequencies)
CONFUSABLE_WANDERS = (BIAS_INSTABILITY, GAUSS_MARKOV)


def covariate_or_time(time_reading, covariate, stats, n_blocks):
    """The reading the slow detector returns for an axis with a recorded temperature (module
    docstring, 1.): ``time_reading`` (a list of candidates) or ``covariate`` (the covariate
    reading, the temperature candidate first; None where the temperature is not significant),
    the other reading riding on the first candidate (``other_reading``) for :func:`weigh_readings`.
    ``stats``: the shapes' Delta chi^2 of the block means (and ``beside_temperature_p``);
    ``n_blocks``: the number of block means."""
    line_or_jump = time_reading[0].effect if time_reading and time_reading[0].effect in (RATE_RAMP, BIAS_STEP) else None
    if line_or_jump and _shape_beats_temperature(line_or_jump, stats, n_blocks):
        # a line or a jump is not a settling: against them the better fit of the block means decides
        return time_reading
    if covariate is None:
        return time_reading
    if not time_reading:
        return covariate
    if (any(c.effect in WANDERS for c in covariate[1:]) and not any(c.effect in WANDERS for c in time_reading)
            and not _explained_by_temperature(stats)):
        # a covariate reading that needs a wander where a shape in time alone explains the record is
        # the more complex reading (a ramp read as the temperature's settling plus a random walk for
        # the difference): the time reading first, the covariate reading weighed against it; unless
        # the shape does not hold beside the temperature (a settling the temperature explains, the
        # wander the bias instability's)
        return [replace(time_reading[0], other_reading=covariate)] + time_reading[1:]
    return [replace(covariate[0], other_reading=time_reading)] + covariate[1:]


def _explained_by_temperature(stats):
    """Whether the time reading's shape does not hold beside the temperature (``stats``'s
    ``explained_by_temperature``: what the temperature leaves of it flicker draws in more than
    ``FLICKER_ALPHA`` of records, :func:`gyrofilter.analysis.gap.detectors.covariate.beside_covariate_p`)."""
    return stats.get("explained_by_temperature", False)


def _shape_beats_temperature(name, stats, n):
    """Whether the time shape ``name`` (a ramp or a step) is the reading to return in the place of
    the temperature (``stats``: their Delta chi^2 of the block means in units of the white level,
    and ``beside_temperature_p``). It must fit the block means better by BIC (``Delta chi^2 - k ln
    n``) and hold beside the temperature: what the temperature leaves of it must pass the time
    shapes' test against flicker (:func:`gyrofilter.analysis.gap.detectors.covariate.beside_covariate_p`,
    at most ``FLICKER_ALPHA``). A temperature settling over a long time constant is nearly a line,
    and a bias instability's excursion beside it is shaped like a line or a jump about as often as
    not (the default model's records); where the shape does not hold beside the temperature, the
    measured covariate is the cause to name and the shape rides on it as the alternative, weighed
    on D by :func:`weigh_readings`. ``n``: the number of block means."""
    d_shape, d_temp = stats[name], stats.get(TEMPERATURE, 0.0)
    if d_shape - BY_NAME[name].n_params * math.log(n) < d_temp - math.log(n):
        return False
    return not _explained_by_temperature(stats)


def suggested_temperature(stats, axis):
    """The ``uncertain`` entry of a temperature the slow detector did not name (module docstring,
    1.) from its statistics ``stats`` (:func:`gyrofilter.analysis.gap.detectors.detect_slow`), or
    None: where the coefficient fits the block means (the detector reaches its GLS test only then)
    and its GLS ``z^2`` under the axis's wander lies in [SUGGESTED_Z2, the detector's threshold].
    Its interval is the GLS one, ``a +- 1.96 sqrt(Var a)``."""
    if "temperature_gls" not in stats:
        return None
    a, var, wander, threshold_z2 = stats["temperature_gls"]
    z2 = a * a / var
    if not SUGGESTED_Z2 <= z2 <= threshold_z2:
        return None
    half = 1.959964 * math.sqrt(var)
    words = {None: "white noise", BIAS_INSTABILITY: "the bias instability", GAUSS_MARKOV: "the Gauss-Markov wander"}.get(
        wander, "the random walk")
    return {"effect": TEMPERATURE, "axis": axis, "params": {"coefficient_dps_per_c": a},
            "params_ci95": {"coefficient_dps_per_c": [a - half, a + half]},
            "why": (f"the bias follows the temperature ({a:+.3g} deg/s per deg C fits the block means by Delta chi^2 "
                    f"{stats[TEMPERATURE]:.0f}), but under {words} the record also shows the coefficient is "
                    f"{math.sqrt(z2):.1f} standard errors from 0, not the {math.sqrt(threshold_z2):.0f} the gap "
                    "analysis requires: a wander could have drawn this trend; a longer record, or one where the "
                    "temperature moves otherwise, decides")}


def unnamed_temperature(cand, ends):
    """Why the kept finding ``cand`` is not named (module docstring, 1.): a temperature whose
    coefficient's 95 % interval ``ends`` (``[low, high]``) holds 0; None where it is no
    temperature, has no interval (``--bootstrap 0``; not determined: set aside by that rule) or
    its interval does not hold 0."""
    if cand.effect != TEMPERATURE or not ends or not ends[0] <= 0.0 <= ends[1]:
        return None
    why = ("its coefficient's 95 % interval holds 0: the record does not establish that the bias follows the "
           "temperature, and a cause is named only where its interval does not hold 0")
    return why + "".join(f"; the time reading {_show(c)} explains this record about as well (D {d:.3g})"
                         for c, d in cand.alternatives[:1])


def allowance_text(spread):
    """The allowance ``spread`` (:data:`CONFOUNDED_SPREADS` null spreads of D) as every note and
    evidence of a weighing writes it: "allowance 0.89 (2 null spreads of D)"."""
    return f"allowance {spread:.2g} ({CONFOUNDED_SPREADS:g} null spreads of D)"


def kept_without_gain(effect, with_all, without, spread_of):
    """Why a finding with no gain alone is kept (module docstring, 1.): ``""`` where the axis's
    other findings do better with it (``with_all < without``); the reason where D with it is
    within the allowance of D without it (``spread_of()``: the larger null spread of D of the two
    models, computed only then); None where it is dropped."""
    if with_all < without:
        return ""
    if np.isfinite(with_all):
        spread = CONFOUNDED_SPREADS * spread_of()
        if with_all <= without + spread:
            what = "the measured covariate" if effect == TEMPERATURE else "what its detector's test names"
            return f", within the {allowance_text(spread)}: {what} is kept where D cannot tell"
    return None


def worse_together(ks, single, with_all, without_of, spread_of):
    """The kept finding of an axis to drop (module docstring, 6.): ``(k, D without it, why)`` or
    None. ``ks``: the axis's kept findings, ``single[k]``: D of the axis with k alone,
    ``with_all``: D with all of ``ks``, ``without_of(k)``: D with all but k, ``spread_of()``: the
    null spread of D of the model with all (both computed only where the check applies)."""
    best = min(single[k] for k in ks) if ks else math.inf
    if len(ks) < 2 or not np.isfinite(with_all) or with_all <= best:
        return None
    spread = CONFOUNDED_SPREADS * spread_of()
    if with_all <= best + spread:
        return None
    d, k = min((without_of(k), k) for k in ks)
    why = (f"the axis's other findings do better without it (D {d:.3g} against {with_all:.3g} with it, beyond "
           f"the {allowance_text(spread)})")
    return (k, d, why) if d < with_all - spread else None


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
                 BIAS_INSTABILITY: "it has one parameter fewer",
                 SINUSOID: "a line no wider than the record needs is a tone",
                 WANDERING_TONE: "the band's values are distributed as a tone's: arcsine-like, excess kurtosis below 0",
                 **dict.fromkeys(SHAPES, "the temperature reading needs a wander besides, this one does not")}

#: why the covariate is named where a reading in time explains a record as well (the end of such a
#: temperature finding's evidence; the HTML report says it once for all its findings)
WHY_THE_COVARIATE = (f"The temperature is named because {NAMED_BECAUSE[TEMPERATURE]}; "
                     "read in time, the bias would settle the same way after every power-on whatever the temperature "
                     "does, and a record where the temperature moves without a power-up (heating, a cold start) tells "
                     "them apart")


def weigh_readings(inp, state, scorer):
    """Choose per axis between the covariate and the time reading of a confounded temperature
    (module docstring, 1.); returns the new state: the reading not chosen excluded, the other
    reading where it is as good riding on the first candidate of the reading named as its
    ``alternatives``. The reading the detector returned first (the covariate reading, or the time
    reading where it is the simpler) is named unless the other is clearly better."""
    for i, reading in sorted(state.readings.items()):
        a = AXES[i]
        first_ks = reading.first
        others = [k for k, (ci, _) in enumerate(state.candidates) if ci == i and k not in first_ks and k not in state.excluded]
        covariate_first = any(state.candidates[k][1].effect == TEMPERATURE for k in first_ks)
        k_head = next((k for k in first_ks if state.candidates[k][1].effect == TEMPERATURE), first_ks[0])
        start = len(state.candidates)
        other_cands = [replace(c, reading="other") for c in reading.other]
        state = replace(state, candidates=state.candidates + tuple((i, c) for c in other_cands)).with_axis(
            i, other=reading.ext_axis)
        other_ks = list(range(start, len(state.candidates)))
        label = f"covariate and time readings on {a}"
        inp.say(label)
        first_model, other_model = state.model(inp, i, others + first_ks), state.model(inp, i, others + other_ks)
        d_first = scorer.discrepancy(i, first_model, label)
        d_other = scorer.discrepancy(i, other_model, label)
        spread = CONFOUNDED_SPREADS * max(scorer.null_spread(i, first_model, label),
                                          scorer.null_spread(i, other_model, label))
        shown = " + ".join(_show(c) for c in reading.other)
        shown_first = " + ".join(_show(state.candidates[k][1]) for k in first_ks)
        d_cov, d_time = (d_first, d_other) if covariate_first else (d_other, d_first)
        time_shown, cov_shown = (shown, shown_first) if covariate_first else (shown_first, shown)
        weighed = (f"axis {a}: readings weighed on D: with the temperature ({cov_shown}) {d_cov:.3g}, in time "
                   f"({time_shown}) {d_time:.3g}; {allowance_text(spread)}")
        first_named, other_named = ("the temperature", "the time reading") if covariate_first else \
            ("the time reading", "the temperature")
        if d_other < d_first - spread:
            state = replace(state, excluded=state.excluded | set(first_ks)).with_axis(i, ext=reading.ext_axis, wv=reading.wv)
            for k in other_ks:
                state = state.with_candidate(k, replace(state.candidates[k][1], reading=""))
            state = state.with_notes(weighed + f": {other_named} is clearly better, {first_named} is not named")
            continue
        state = replace(state, excluded=state.excluded | set(other_ks))
        if d_other > d_first + spread:
            state = state.with_notes(weighed + f": {first_named} is clearly better, {other_named} is not listed")
            continue
        why = ("the temperature reading is preferred, the time reading listed as its alternatives (the temperature "
               "itself is named only where its coefficient's interval does not hold 0)" if covariate_first else
               "the time reading is named (the temperature reading needs a wander besides, the time reading does "
               "not), the temperature reading listed as its alternatives")
        state = state.with_notes(weighed + f": the record cannot tell them apart; {why}")
        head = state.candidates[k_head][1]
        about = (f"the time reading {shown} explains this record about as well (D {d_time:.3g} against {d_cov:.3g}, "
                 f"within the {allowance_text(spread)}): the temperature follows a warm-up itself, so this "
                 f"record cannot tell them apart. {WHY_THE_COVARIATE}") if covariate_first else (
                 f"the temperature reading {shown} explains this record about as well (D {d_cov:.3g} against "
                 f"{d_time:.3g}, within the {allowance_text(spread)}): the temperature follows a warm-up "
                 "itself, so this record cannot tell them apart; the reading in time is named because the "
                 "temperature reading needs a wander besides and the reading in time does not")
        state = state.with_candidate(k_head, replace(head, alternatives=tuple((c, d_other) for c in other_cands),
                                                     in_place_of=tuple(state.candidates[k][1].effect for k in first_ks),
                                                     evidence_notes=head.evidence_notes + (about,)))
    return state


def _detached(state, k, field):
    """Candidate ``k``'s other reading held in ``field`` (``wander_alternative``,
    ``band_alternative``), taken off it: ``(new state, (axis, candidate, the reading))``, or
    ``(new state, None)`` where it holds none or the candidate is excluded."""
    i, c = state.candidates[k]
    reading = getattr(c, field)
    if reading is None:
        return state, None
    c = replace(c, **{field: None})
    state = state.with_candidate(k, c)
    return state, (None if k in state.excluded else (i, c, reading))


def weigh_wanders(inp, state, scorer):
    """Choose per axis between a bias instability and a Gauss-Markov wander where the slow
    detector found both significant (the candidate's ``wander_alternative``): each is simulated
    with the axis's other findings and scored by D, as the readings of a confounded temperature
    are (module docstring, 2.). The Gauss-Markov is named only where it is clearly better
    (``D_gm < D_bi - s``); otherwise the bias instability, which has one parameter fewer, and where
    the two are about equal the Gauss-Markov rides on it as its ``alternatives``. Returns the new
    state, the reading not chosen excluded."""
    for k in range(len(state.candidates)):
        state, taken = _detached(state, k, "wander_alternative")
        if taken is None:
            continue
        i, c, alt = taken
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
                   f"{d_gm:.3g}; {allowance_text(spread)}")
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
                f"{d_bi:.3g}, within the {allowance_text(spread)}): its spectrum, flat below its corner "
                f"1/(2 pi tau) = {corner_hz:.2g} Hz and falling like 1/f^2 above it, bends across this record's "
                "frequencies about as the 1/f of a bias instability falls, so the record cannot tell them apart; "
                "the bias instability is named, with one parameter fewer",)))
    return state


def same_line(sinusoid, band):
    """Whether a sinusoid and a narrow-band candidate are one spectral line (module docstring, 3.):
    the band's centre lies within its half-power full width of the sinusoid's frequency (that
    width is at least the Welch resolution, the width a pure line shows)."""
    return abs(sinusoid.params["frequency_hz"] - band.params["center_hz"]) <= band.params["bandwidth_hz"]


def weigh_lines(inp, state, scorer):
    """Choose per axis between a sinusoid and a narrow band that are one line (:func:`same_line`;
    module docstring, 3.): the tone (the sinusoid; the band's variance back in the white level,
    ``N'^2 = N^2 + rms^2 / f_s``), the band (``rms'^2 = rms^2 + A^2 / 2``: the sinusoid's power in
    it) and both, each simulated with the axis's other findings and scored by D. Returns the new
    state, the readings not chosen excluded; a band as good as the tone rides on the sinusoid as its
    ``alternatives``."""
    for i, a in enumerate(AXES):
        on = state.on_axis(i)
        k_sin = next((k for k in on if state.candidates[k][1].effect == SINUSOID), None)
        k_band = next((k for k in on if state.candidates[k][1].effect == NARROWBAND), None)
        if k_sin is None or k_band is None or not same_line(state.candidates[k_sin][1], state.candidates[k_band][1]):
            continue
        sin, band = state.candidates[k_sin][1], state.candidates[k_band][1]
        rms = math.hypot(band.params["rms_dps"], sin.params["amplitude_dps"] / math.sqrt(2.0))
        whole = replace(band, params=dict(band.params, rms_dps=rms), evidence_notes=band.evidence_notes + (
            f"with the sinusoid at {sin.params['frequency_hz']:.4g} Hz that the sinusoid detector took out of it, its "
            f"rms is {rms:.3g} deg/s ({band.params['rms_dps']:.3g} without it)",))
        state = replace(state, candidates=state.candidates + ((i, whole),))
        k_whole = len(state.candidates) - 1
        others = [k for k in on if k not in (k_sin, k_band)]
        ext = state.axes[i].ext
        tone_ext = dict(ext, arw_dps_per_sqrt_hz=math.sqrt(
            ext["arw_dps_per_sqrt_hz"] ** 2 + band.params["rms_dps"] ** 2 / inp.sample_rate_hz))
        label = f"sinusoid and narrow-band readings of the line on {a}"
        inp.say(label)
        tone_state = state.with_axis(i, ext=tone_ext)
        models = {"tone": tone_state.model(inp, i, others + [k_sin]), "band": state.model(inp, i, others + [k_whole]),
                  "both": state.model(inp, i, others + [k_sin, k_band])}
        d = {name: scorer.discrepancy(i, m, label) for name, m in models.items()}
        spread = CONFOUNDED_SPREADS * max(scorer.null_spread(i, m, label) for m in models.values())
        weighed = (f"axis {a}: one line weighed on D (the sinusoid's {sin.params['frequency_hz']:.4g} Hz, the band's "
                   f"{band.params['center_hz']:.4g} Hz): as a sinusoid {d['tone']:.3g}, "
                   f"as a narrow band {d['band']:.3g}, as both {d['both']:.3g}; {allowance_text(spread)}")
        if d["both"] < min(d["tone"], d["band"]) - spread:
            state = replace(state, excluded=state.excluded | {k_whole}).with_notes(
                weighed + ": both together are clearly better, both are named")
            continue
        if d["band"] < d["tone"] - spread:
            state = replace(state, excluded=state.excluded | {k_sin, k_band}).with_notes(
                weighed + ": the narrow band is clearly better, the sinusoid is not named")
            continue
        state = replace(state, excluded=state.excluded | {k_band, k_whole}).with_axis(i, ext=tone_ext)
        if d["tone"] < d["band"] - spread:
            state = state.with_notes(weighed + ": the sinusoid is clearly better, the narrow band is not listed")
            continue
        state = state.with_notes(weighed + f": the record cannot tell them apart; the sinusoid is named "
                                 f"({NAMED_BECAUSE[SINUSOID]}), the narrow band listed as its alternative")
        state = state.with_candidate(k_sin, replace(sin, alternatives=((whole, d["band"]),), evidence_notes=(
            sin.evidence_notes + (f"the line read as a narrow band, {_show(whole)}, explains this record about as "
                                  f"well (D {d['band']:.3g} against {d['tone']:.3g}, within the {allowance_text(spread)}); "
                                  f"the sinusoid is named: {NAMED_BECAUSE[SINUSOID]}",))))
    return state


def weigh_tones(inp, state, scorer):
    """Choose per axis between a wandering tone and the narrow band it was read from (the
    candidate's ``band_alternative``: the band and the colored noise left beside it; module
    docstring, 3.): one line, read as a tone of constant amplitude (the detector's evidence: the
    band's distribution and its moving peak) with the colored noise left beside the tone's line, or
    as Gaussian noise in the band with the colored noise left beside the band, each simulated with
    the axis's other findings and scored by D. The band reading puts its own variance in place of
    the tone's in the white level (``N'^2 = N^2 + (A^2 / 2 - rms^2) / f_s``). The tone is named
    unless the band is clearly better (``D_band < D_tone - s``): then the band, and a note says
    so; where the two are about equal, the band rides on the tone as its ``alternatives``.
    Returns the new state, the reading not chosen excluded."""
    for k in range(len(state.candidates)):
        state, taken = _detached(state, k, "band_alternative")
        if taken is None:
            continue
        i, c, reading = taken
        band = reading[0]
        k_colored = [j for j, (ci, cj) in enumerate(state.candidates)
                     if ci == i and cj.effect == COLORED_NOISE and j not in state.excluded]
        first = len(state.candidates)
        state = replace(state, candidates=state.candidates + tuple((i, r) for r in reading))
        k_band = list(range(first, first + len(reading)))
        a = AXES[i]
        others = [j for j, (ci, _) in enumerate(state.candidates)
                  if ci == i and j != k and j not in k_colored + k_band and j not in state.excluded]
        ext = state.axes[i].ext
        arw2 = ext["arw_dps_per_sqrt_hz"] ** 2
        arw2_band = arw2 + (c.params["amplitude_dps"] ** 2 / 2.0 - band.params["rms_dps"] ** 2) / inp.sample_rate_hz
        band_state = state.with_axis(i, ext=dict(ext, arw_dps_per_sqrt_hz=math.sqrt(max(arw2_band, 0.05 * arw2))))
        label = f"tone and narrow-band readings of the line on {a}"
        inp.say(label)
        tone_model = state.model(inp, i, others + [k] + k_colored)
        band_model = band_state.model(inp, i, others + k_band)
        d_tone, d_band = scorer.discrepancy(i, tone_model, label), scorer.discrepancy(i, band_model, label)
        spread = CONFOUNDED_SPREADS * max(scorer.null_spread(i, tone_model, label),
                                          scorer.null_spread(i, band_model, label))
        weighed = (f"axis {a}: one line weighed on D (the tone's {c.params['center_hz']:.4g} Hz, the band's "
                   f"{band.params['center_hz']:.4g} Hz): as a wandering tone "
                   f"{d_tone:.3g}, as a narrow band {d_band:.3g}; {allowance_text(spread)}")
        if d_band < d_tone - spread:
            state = replace(band_state, excluded=band_state.excluded | {k, *k_colored}).with_notes(
                weighed + ": the narrow band is clearly better, the tone is not named")
            continue
        state = replace(state, excluded=state.excluded | set(k_band))
        if d_tone < d_band - spread:
            state = state.with_notes(weighed + ": the tone is clearly better, the narrow band is not listed")
            continue
        state = state.with_notes(weighed + ": the record cannot tell them apart on D; the tone is named "
                                 f"({NAMED_BECAUSE[WANDERING_TONE]}), the narrow band listed as its alternative")
        state = state.with_candidate(k, replace(c, alternatives=((band, d_band),), evidence_notes=c.evidence_notes + (
            f"the line read as Gaussian noise in the band, {_show(band)}, explains this record about as well on D "
            f"(D {d_band:.3g} against {d_tone:.3g}, within the {allowance_text(spread)}); the tone is named: "
            f"{NAMED_BECAUSE[WANDERING_TONE]}",)))
    return state


def _show(c):
    """A candidate as the notes write it (:func:`effect_shown`)."""
    return effect_shown(c.effect, c.params)


def effect_shown(effect, params):
    """An effect and its parameters as the notes of the weighings and the reports write them (one
    format for all): ``narrowband (center_hz = 12.05, bandwidth_hz = 0.473)``, numbers to 4
    significant digits, ``-`` for a parameter not determined (None), other values as they are."""
    def value(v):
        if v is None:
            return "-"
        return f"{v:.4g}" if isinstance(v, float) else str(v)

    return f"{effect} (" + ", ".join(f"{k} = {value(v)}" for k, v in params.items()) + ")"


def alternatives_entry(cand, named):
    """The ``alternatives`` of a finding in the gap report: per entry of the other reading its
    effect, params, D (of the axis with that whole reading in place of the finding's) and
    ``in_place_of``, the effects of the finding's reading (``cand.in_place_of`` less those not
    among ``named``, the effects named on the axis; the finding's own where it is alone)."""
    in_place_of = [e for e in cand.in_place_of if e in named] or [cand.effect]
    return [{"effect": c.effect, "params": c.plain_params(), "D": float(d), "in_place_of": in_place_of}
            for c, d in cand.alternatives]


def one_cause_of_spikes(ring, spikes, tails, note):
    """Rule 5 (module docstring): ``(spikes, tails, note)`` as the axis keeps them beside the
    ringing candidate ``ring`` (None: all as found): none of them where the shocks ring."""
    return (spikes, tails, note) if ring is None else (None, None, None)


def ring_or_hump(ring, hump):
    """Rule 5 (module docstring): the hump candidate ``hump`` as the axis keeps it beside the
    ringing candidate ``ring``: None where the hump lies at the ring's resonance."""
    if ring is None or hump is None:
        return hump
    half = ring.params["center_hz"] / (2.0 * ring.params["q"])
    return None if abs(hump.params["center_hz"] - ring.params["center_hz"]) <= half else hump
