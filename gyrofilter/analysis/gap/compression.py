"""The compression step of the gap analysis (:mod:`gyrofilter.analysis.gap.pipeline`, step 4, after
the composite stochastic part): an axis whose tails are lighter than its extended model's.

No term added to the rate makes a noise lighter-tailed than a Gaussian while keeping its spectrum;
a transfer does: the simulator's ``compression`` (:mod:`gyrofilter.sim.compression`), a cubic
of the axis's fast terms about its slow level, y = l + g (e - gamma e^3), g keeping the variance.
It is what lightens the ADIS16405 z axes' tails (docs/gap.md, "What lightens the z axes' tails":
fitted to their tail statistic it reproduces fourth-order cross terms it was not fitted to).

**When it is tried**: where an axis's D after is still above
:data:`~gyrofilter.analysis.gap.detectors.OUTSIDE_NULL_D` and the record's tail statistic
(:func:`~gyrofilter.analysis.gap.detectors.tails_statistic`, a feature of D) departs from the
extended model's runs by z below :data:`~gyrofilter.analysis.gap.detectors.COMPRESSION_TAILS_Z`
(lighter tails than the model's; its runs' spread as D pools it), unless the record lies on a
lattice of more than :data:`~gyrofilter.analysis.gap.detectors.TAILS_MAX_STEP_SD` noise sd
(:func:`~gyrofilter.analysis.gap.detectors.tails.tail_step`): so coarse a quantizer makes the
distribution lighter by itself, and where the model does not carry it (a record in deg/s or
rad/s without its LSB) a compression would stand for it. The BROAD rest phases (36 s at 286 Hz,
steps of 0.62-0.68 noise sd, no LSB in their header) had it named on 4 axes, 3 of them not on every
stream, before this rule; the ADIS16405 records are at 0.11-0.15.

**gamma** (1-D): the runs' mean tail statistic T(gamma) falls with gamma; gamma is where it meets
the record's T, by secant steps from T(0) (the extended model's runs) and a first trial at the
Gaussian value ``(T(0) - T) / (8 sigma^2)`` (the excess kurtosis of a compressed Gaussian is
about -24 gamma sigma^2, a log-kurtosis of -8 gamma sigma^2; the tail statistic's prewhitening
spreads each sample's shape over a few and reads less), at most :data:`MAX_TRIALS` model
evaluations (each the extended model's ``n_ext`` runs), stopping when T is within one sd of the
runs, then one more secant step, not evaluated; gamma at most
:func:`~gyrofilter.sim.compression.max_gamma_per_dps2` (MAX_COMPRESSION / sigma^2, the simulator's bound). **sigma** (``rms_dps``, which fixes the gain) is the rms of the record's fast
part: its high-pass (:func:`~gyrofilter.analysis.gap.detectors.highpassed`) less the quantizer's
q^2 / 12.

**Kept** by the composite step's rule: D falls below
:data:`~gyrofilter.analysis.gap.detectors.COMPOSITE_MIN_GAIN` times its value and by more than
:data:`~gyrofilter.analysis.gap.confound.CONFOUNDED_SPREADS` null spreads of D of the axis's
extended model (a smaller gain is one the record cannot vouch for); then it is a finding of the
axis (in the extended model, its gain D alone beside the baseline's refit), else a note.

**Its interval**: the bootstrap of every finding (:mod:`gyrofilter.analysis.gap.intervals`), with a
linearised re-estimator (:mod:`gyrofilter.analysis.gap.reestimate`): on a replicate of tail
statistic T_b, ``gamma_b = gamma + (T_b - T(gamma)) / T'`` with T(gamma) and the slope T' of the
fit (:attr:`~gyrofilter.analysis.gap.detectors.Candidate.calibration`): the spread of the
replicates' tail statistic carried to gamma, without a fit of gamma per replicate (each would
cost the trials' runs).
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...effects import COMPRESSION
from ...sim.compression import max_gamma_per_dps2
from ...sim.model import param_bounds
from ...units import AXES
from . import detectors as det
from .baseline import MIN_SIMS, axis_dps
from .composite import short_of_a_clear_gain
from .detectors.tails import tail_step
from .features import d_shown
from .state import Kept

#: the most model evaluations (each ``n_ext`` runs) the fit of gamma takes
MAX_TRIALS = 3
_STATISTIC = "tail statistic's departure (z) from the extended model's runs"


def fast_rms(x, sample_rate_hz, q_dps):
    """sigma (deg/s): the rms of the record's fast part, its high-pass less the quantizer's
    q^2 / 12 (module docstring); at least a tenth of the high-pass's."""
    e = det.highpassed(np.asarray(x, dtype=float), sample_rate_hz)[0]
    var = float(np.var(e))
    return math.sqrt(max(var - (q_dps or 0.0) ** 2 / 12.0, 0.01 * var))


def compression_step(inp, state, scorer):
    """The step of the module docstring on every axis; returns the new state."""
    if inp.n_sims < MIN_SIMS:  # D is not judged
        return state
    for i, a in enumerate(AXES):
        if a in inp.idle or state.after[i] <= det.OUTSIDE_NULL_D:
            continue
        ks = state.kept_on(i)
        deps = scorer.departures(i, state.model(inp, i, ks), f"extended model on {a}") if ks else inp.deps[i]
        z, t0, sd = (float(v[0]) for v in deps["tails"])
        if not z < det.COMPRESSION_TAILS_Z:
            continue
        step = tail_step(axis_dps(inp.rec, i), inp.sample_rate_hz)
        if step > det.TAILS_MAX_STEP_SD:
            state = state.with_notes(f"axis {a}: its tails are lighter than the extended model's (z = {z:+.1f}), but the "
                                     f"rate is quantized in steps of {step:.2g} noise sd: its distribution is the "
                                     "quantizer's, no compression is fitted")
            continue
        inp.say(f"compression fit on {a}")
        state = _with_compression(inp, state, scorer, i, ks, (z, t0, max(sd, 1.0 / math.sqrt(inp.n))))
    return state


def _with_compression(inp, state, scorer, i, ks, tails):
    """The state with axis ``i``'s compression fitted (:func:`fit_gamma`) and, where it lowers D
    enough, kept; a note either way. ``tails``: ``(z, the runs' mean, their sd)`` of the tail
    statistic against the extended model of the kept findings ``ks``."""
    a, after = AXES[i], state.after[i]
    z, t0, sd = tails
    target = float(inp.meas_feats[i]["tails"][0])
    sigma = fast_rms(axis_dps(inp.rec, i), inp.sample_rate_hz, inp.q)
    k = len(state.candidates)
    first = det.Candidate(effect=COMPRESSION, params={"gamma_per_dps2": 0.0, "rms_dps": sigma}, statistic=z,
                          threshold=det.COMPRESSION_TAILS_Z, statistic_name=_STATISTIC, evidence="")
    state = replace(state, candidates=state.candidates + ((i, first),))

    def mean_tails(gamma):
        trial = state.with_candidate(k, replace(first, params={"gamma_per_dps2": gamma, "rms_dps": sigma}))
        deps = scorer.departures(i, trial.model(inp, i, ks + [k]), f"compression on {a}")
        return float(deps["tails"][1][0])

    gamma, t_gamma, slope = fit_gamma(mean_tails, t0, target, sd, sigma)
    if gamma is None:
        return state.with_notes(f"axis {a}: its tails are lighter than the extended model's (z = {z:+.1f}), "
                                "but no compression lightens the runs' (no compression fitted)")
    cand = replace(first, params={"gamma_per_dps2": gamma, "rms_dps": sigma}, calibration=(t_gamma, slope),
                   evidence=(f"the tail statistic {target:+.4f} departs from the extended model's runs ({t0:+.4f}) by "
                             f"z = {z:+.1f} (threshold {det.COMPRESSION_TAILS_Z:g}): lighter tails than the model's; "
                             f"a cubic compression of the fast terms about the slow level, gamma = {gamma:.3g} "
                             f"(deg/s)^-2 at their rms {sigma:.3g} deg/s, puts the runs' at {t_gamma:+.4f}"))
    state = state.with_candidate(k, cand)
    s_ext = scorer.null_spread(i, state.model(inp, i, ks) if ks else None, f"extended model on {a}")
    d_with = scorer.discrepancy(i, state.model(inp, i, ks + [k]), f"compression on {a}")
    short = short_of_a_clear_gain(d_with, after, s_ext)
    if short:
        return state.with_notes(f"axis {a}: a compression (gamma = {gamma:.3g} (deg/s)^-2) matches the tails but did "
                                f"not lower D enough {short}; not used")
    alone = scorer.discrepancy(i, state.model(inp, i, [k]), f"gain of the compression on {a}")
    return replace(state, kept=state.kept + (Kept(k, i, cand, alone),), single={**state.single, k: alone},
                   after=state.after[:i] + (d_with,) + state.after[i + 1:]).with_notes(
        f"axis {a}: a compression (gamma = {gamma:.3g} (deg/s)^-2) lightens the runs' tails to the record's and lowers "
        f"D from {d_shown(after)} to {d_shown(d_with)}")


def fit_gamma(mean_tails, t0, target, sd, sigma_dps):
    """``(gamma, T(gamma), T'(gamma))``: gamma where the runs' mean tail statistic
    ``mean_tails(gamma)`` meets ``target`` (module docstring: secant steps from ``(0, t0)``, at
    most :data:`MAX_TRIALS` evaluations, stopping within ``sd``, then the last secant's step
    taken without a further evaluation, so that the linearised re-estimator returns gamma itself on
    the record), with T read off that secant and its slope; ``(None, None, None)`` where the runs
    do not lighten (a slope >= 0). Gamma stays within the model's bound of its key as well (a record of 1e-12 deg/s
    asked for 7e21 and the model refused it, naming no file: attack pass 53)."""
    top = min(max_gamma_per_dps2(sigma_dps), param_bounds(COMPRESSION, "gamma_per_dps2")[1])
    points = [(0.0, t0)]
    gamma = min((t0 - target) / (8.0 * sigma_dps ** 2), top)
    for _ in range(MAX_TRIALS):
        points.append((gamma, mean_tails(gamma)))
        (g0, f0), (g1, f1) = points[-2], points[-1]
        slope = (f1 - f0) / (g1 - g0) if g1 != g0 else 0.0
        if not slope < 0.0:
            return None, None, None
        if abs(f1 - target) <= sd:
            break
        step = min(max(g1 + (target - f1) / slope, 0.0), top)
        if step == g1:  # at the bound
            break
        gamma = step
    g, f = points[-1]
    gamma = min(max(g + (target - f) / slope, 0.0), top)  # the last secant's own step, as the re-estimator reads
    return gamma, f + slope * (gamma - g), slope
