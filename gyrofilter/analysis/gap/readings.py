"""Confounded causes in the gap analysis (:mod:`gyrofilter.analysis.gap.pipeline`, step 3, continued):
which reading of a slow departure to name when the temperature and a shape in time (or a slow
wander) explain it about equally, and which of two slow wanders, a bias instability or a
Gauss-Markov (:func:`weigh_wanders`).

Where a temperature is recorded and follows a warm-up itself, the slow detector
(:func:`gyrofilter.analysis.gap.detectors.detect_slow`) gives two readings of an axis: the
*covariate reading* (the temperature coefficient first, the time shapes and stochastic spectra
in what it leaves) and the *time reading* (the same detector without the temperature). Each is
simulated with the axis's other findings and scored by the discrepancy D (``D_cov``,
``D_time``). They explain the record **about equally** when

    ``|D_cov - D_time| <= s``,  ``s = k max(s_cov, s_time)``,  ``k = CONFOUNDED_SPREADS = 2``,

``s_M`` the **null spread of D** of model M (:func:`null_spread`): the standard deviation of D
over M's own simulated runs, each run scored like the measurement against the other runs
(leave one out). It is how much D moves between records that M explains exactly (``k = 2``:
the band D keeps in about 95 % of them), so a difference within it is a difference the record
cannot vouch for. With the 6-12 runs of the extended models the leave-one-out D also carries the
scatter of a spread estimated from one run fewer, so ``s`` errs wide: towards calling two
readings equal, that is towards the measured covariate with the other reading listed.

The covariate reading is kept unless the time reading is clearly better (``D_time < D_cov - s``):
it is the measured cause, and it predicts the bias at the next power-up, which an exponential in
time does not. When both explain about equally, the time reading is listed on the temperature
finding as ``alternatives`` (each entry: effect, params, and D of the axis with the whole time
reading in place of the covariate reading), and the evidence says that the record cannot tell
them apart and how the other reading would look. When the time reading is clearly better, it
replaces the covariate reading and a note says so.
"""
from __future__ import annotations

import numpy as np

from ...effects import BIAS_INSTABILITY, TEMPERATURE
from . import detectors as det
from .features import departures, discrepancy
from ...units import AXES


def null_spread(sims, n, pool=None):
    """The null spread of D of a model from its simulated runs' features ``sims`` (a list, one
    dict of features per run): ``sd_j(D_j)`` with ``D_j`` the discrepancy of run ``j`` against
    the other runs (:func:`gyrofilter.analysis.gap.features.departures`, with the measurement's
    ``pool``), ``n`` the samples per run. 0 with fewer than 3 runs."""
    if len(sims) < 3:
        return 0.0
    d = [discrepancy(departures(sims[j], sims[:j] + sims[j + 1:], n, pool)) for j in range(len(sims))]
    return float(np.std(d, ddof=1))


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


def weigh_readings(run):
    """Choose per axis between the covariate and the time reading of a confounded temperature
    (module docstring) on the gap analysis ``run``; the reading not chosen goes to
    ``run.excluded``, a time reading that is as good rides on the temperature candidate as
    ``extra["alternatives"]``."""
    cands, notes = run.candidates, run.report["notes"]
    for i, reading in sorted(run.readings.items()):
        a = AXES[i]
        cov_ks = reading["covariate"]
        others = [k for k, (ci, _) in enumerate(cands) if ci == i and k not in cov_ks and k not in run.excluded]
        temp = next(cands[k][1] for k in cov_ks if cands[k][1].effect == TEMPERATURE)
        first = len(cands)
        for c in reading["time"]:
            c.extra["reading"] = "time"
            cands.append((i, c))
        time_ks = list(range(first, len(cands)))
        run.alt_axes[a] = reading["ext_axis"]
        label = f"covariate and time readings on {a}"
        run.say(label)
        d_cov = run.axis_discrepancy(i, others + cov_ks, label)
        d_time = run.axis_discrepancy(i, others + time_ks, label)
        spread = det.CONFOUNDED_SPREADS * max(run.null_spread(i, others + cov_ks, label),
                                              run.null_spread(i, others + time_ks, label))
        shown = " + ".join(_show(c) for c in reading["time"])
        weighed = (f"axis {a}: readings weighed on D: with the temperature {d_cov:.3g}, in time ({shown}) {d_time:.3g}; "
                   f"allowance {spread:.2g} ({det.CONFOUNDED_SPREADS:g} null spreads of D)")
        if d_time < d_cov - spread:
            run.excluded.update(cov_ks)
            run.ext_axes[a], run.wvs[i] = reading["ext_axis"], reading["wv"]
            for c in reading["time"]:
                c.extra.pop("reading")
            notes.append(weighed + ": the time reading is clearly better, the temperature is not named")
            continue
        run.excluded.update(time_ks)
        if d_time > d_cov + spread:
            notes.append(weighed + ": the temperature is clearly better, the time reading is not listed")
            continue
        notes.append(weighed + ": the record cannot tell them apart; the temperature is named, the time reading "
                     "listed as its alternatives")
        temp.extra["alternatives"] = [(c, d_time) for c in reading["time"]]
        temp.evidence += (f"; the time reading {shown} explains this record about as well (D {d_time:.3g} against "
                          f"{d_cov:.3g}, within the null spread of D, {spread:.2g}): the temperature follows a "
                          f"warm-up itself, so this record cannot tell them apart. {WHY_THE_COVARIATE}")


def weigh_wanders(run):
    """Choose per axis between a bias instability and a Gauss-Markov wander where the slow
    detector found both significant (:func:`gyrofilter.analysis.gap.detectors.slow._with_wander_alternative`):
    each is simulated with the axis's other findings and scored by D, as the readings of a
    confounded temperature are (module docstring). A Gauss-Markov spectrum is flat below its
    corner ``1/(2 pi tau)`` and falls like 1/f^2 above it; with the corner among the record's
    frequencies (tau below a fifth of the record) it bends across them about as a bias
    instability's 1/f falls, and its Allan deviation, a broad hump near ``1.9 tau``, fits the
    flat floor of a bias instability over a decade or two, so the two can explain a record
    equally. The Gauss-Markov is named only where it is clearly
    better (``D_gm < D_bi - s``); otherwise the bias instability, which has one parameter fewer,
    and where the two are about equal the Gauss-Markov rides on it as ``extra["alternatives"]``.
    The reading not chosen goes to ``run.excluded``."""
    cands, notes = run.candidates, run.report["notes"]
    for k in range(len(cands)):
        i, c = cands[k]
        alt = c.extra.pop("wander_alternative", None)
        if alt is None or k in run.excluded:
            continue
        cands.append((i, alt))
        k_alt = len(cands) - 1
        a = AXES[i]
        others = [j for j, (ci, _) in enumerate(cands) if ci == i and j not in (k, k_alt) and j not in run.excluded]
        label = f"bias instability and Gauss-Markov readings on {a}"
        run.say(label)
        bi, gm = ((k, c), (k_alt, alt)) if c.effect == BIAS_INSTABILITY else ((k_alt, alt), (k, c))
        d_bi = run.axis_discrepancy(i, others + [bi[0]], label)
        d_gm = run.axis_discrepancy(i, others + [gm[0]], label)
        spread = det.CONFOUNDED_SPREADS * max(run.null_spread(i, others + [bi[0]], label),
                                              run.null_spread(i, others + [gm[0]], label))
        weighed = (f"axis {a}: readings of the slow wander weighed on D: {_show(bi[1])} {d_bi:.3g}, {_show(gm[1])} "
                   f"{d_gm:.3g}; allowance {spread:.2g} ({det.CONFOUNDED_SPREADS:g} null spreads of D)")
        if d_gm < d_bi - spread:
            run.excluded.add(bi[0])
            notes.append(weighed + ": the Gauss-Markov is clearly better, the bias instability is not named")
            continue
        run.excluded.add(gm[0])
        if d_bi < d_gm - spread:
            notes.append(weighed + ": the bias instability is clearly better, the Gauss-Markov is not listed")
            continue
        notes.append(weighed + ": the record cannot tell them apart; the bias instability is named (one parameter "
                     "fewer), the Gauss-Markov listed as its alternative")
        bi[1].extra["alternatives"] = [(gm[1], d_gm)]
        corner_hz = 1.0 / (2.0 * np.pi * gm[1].params["tau_s"])
        bi[1].evidence += (f"; the wander reading {_show(gm[1])} explains this record about as well (D {d_gm:.3g} "
                           f"against {d_bi:.3g}, within the null spread of D, {spread:.2g}): its spectrum, flat "
                           f"below its corner 1/(2 pi tau) = {corner_hz:.2g} Hz and falling like 1/f^2 above it, "
                           "bends across this record's frequencies about as the 1/f of a bias instability falls, "
                           "so the record cannot tell them apart; the bias instability is named, with one "
                           "parameter fewer")


def _show(c):
    """``effect (k=v, ...)`` of a candidate."""
    return f"{c.effect} (" + ", ".join(f"{k}={v:.3g}" for k, v in c.params.items()) + ")"


def alternatives_entry(cand):
    """The ``alternatives`` of a finding in the gap report: per entry of the other reading its
    effect, params and D (of the axis with that whole reading in place of the finding's)."""
    return [{"effect": c.effect, "params": {k: float(v) for k, v in c.params.items()}, "D": float(d)}
            for c, d in cand.extra["alternatives"]]
