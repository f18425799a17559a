"""95 % intervals of every finding's parameters and of the baseline's, by parametric bootstrap of
the extended model (:mod:`gyrofilter.analysis.gap.pipeline`, step 5, before the findings are written).

For each axis with findings, the axis of the extended model (the baseline's bias and white noise
re-fitted, every kept finding, the record's temperature profile where a finding needs it) is
simulated ``B`` times with the record's length and rate (seeded, streams of their own), and the
estimator of every finding of the axis is run on each replicate
(:func:`gyrofilter.analysis.gap.reestimate.reestimate_axis`), as are the baseline's (the mean and
the high-passed white-noise level, :func:`gyrofilter.analysis.gap.baseline.noise_sigma`). This is
the parametric bootstrap GMWM uses for its intervals (Guerrier et al. 2013, sec. 4; Efron &
Tibshirani 1993, ch. 6).

The interval is the **bias-corrected normal interval on a transformed scale with the Student
quantile** (Efron & Tibshirani 1993, sec. 13.3 and 10.6): with ``u = g(theta)`` (``g`` = log for a
positive scale parameter, atanh for an autocorrelation, the identity for a signed one; see
:data:`SCALES`), ``u*_b`` the replicates' estimates, ``bias = mean(u*) - u_hat`` and ``s`` their
standard deviation,

    u in  u_hat - bias  +-  t_{0.975, B-1} sqrt(1 + 1/B) s,     mapped back by g^-1.

Why this and not the percentile interval: the replicates are simulated from the *estimated*
model, so an estimator that is biased (the slow spectra on block means, the spike magnitude
corrected for the threshold, a tau scanned on a grid) shows its bias in the replicates; the
percentile interval would carry it twice, the basic and this one remove it. The log and atanh
scales make the estimators' spread about constant in the parameter (a scale parameter's error is
relative). With few replicates the 2.5 % and 97.5 % percentiles are poor (B = 19: the smallest
and largest), while ``t_{B-1} sqrt(1 + 1/B)`` is the exact factor for a normal ``u``: the spread
``s`` and the bias come from B draws, the estimate is one more draw, so
``(u_hat - bias - u) / (s sqrt(1 + 1/B))`` is Student-t with B - 1 degrees of freedom. Circular
``phase_rad`` uses the deviations wrapped to (-pi, pi] and is reported unwrapped (the truth lies in
the interval modulo 2 pi). A replicate whose estimator has nothing to estimate is left out.

**An interval always holds its estimate**: the interval given is the hull of the bias-corrected
interval and the estimate, ``[min(low, theta_hat), max(high, theta_hat)]`` (on any scale: ``g`` is
monotone; a phase in the unwrapped frame of the interval). Where the replicates' bias is larger
than their spread (a spike magnitude corrected for the threshold, a scale ratio of heavy tails, a
lag-1 correlation shrunk by a band: ``scale_ratio=10.42 [11.75, 13.13]`` on a real record), the
bias-corrected interval alone lies wholly on one side of the estimate. The bias is the
estimator's at the estimate, not at the unknown truth, and it is itself estimated from B runs;
Efron & Tibshirani (1993, sec. 10.6) call a correction by a bias that is large against the
standard error dangerous (it may add more error than it removes, and a large bias says the
estimator is a poor one there). The hull keeps the correction's direction and never claims the
estimate itself is ruled out; it contains the bias-corrected interval, so its coverage is at
least that interval's (a superset covers whenever the set does) and only rises. The basic and
BCa intervals were no way out: the basic one ``[2 u_hat - q_0.975, 2 u_hat - q_0.025]`` holds
``u_hat`` only when ``u_hat`` lies between the replicates' 2.5 % and 97.5 % points, which a bias
larger than the spread breaks, and BCa's ends are quantiles of the replicates, all of which lie
on one side of the estimate then (Efron & Tibshirani 1993, sec. 14.3).

**Not determined** (``null`` in ``params_ci95`` and a note saying why): a parameter whose estimator
ran on fewer than half of the B replicates (:data:`MIN_SHARE`; and never on fewer than
:data:`MIN_REPLICATES`): when most records simulated from the record's own extended model give
the estimator nothing to estimate, the record's estimate is the exception under its own model,
and the replicates that did run are a selected subset whose spread is not the estimator's (the
spike rate of only the runs that happened to hold spikes); half is where they stop being the
typical run. And a positive (log-scale) parameter whose interval spans more than a factor
:data:`MAX_SPAN_RATIO` (two decades): the record then bounds neither its order of magnitude nor
whether it matters (``b_dps 0.0033 in [3.4e-7, 1412]``). A signed parameter (a temperature
coefficient, a step size, a warm-up amplitude, a ramp) is not determined by the failing-runs
rule only; its interval holding 0 is not taken to mean that: each of these effects was named
by its detector's own test of exactly that parameter against 0, at a calibrated false-alarm rate
(the clean batteries, docs/gap.md) and far beyond 95 %, and confirmed by the gain in D; a second,
looser two-sided test on the bootstrap would overrule a calibrated decision with an uncalibrated
one, while the interval, even across 0, still bounds the effect's size, which a two-decade span
of a scale parameter does not. The temperature is the exception, a rule of the confounded causes
(:func:`gyrofilter.analysis.gap.confound.unnamed_temperature`): below its GLS test it may be named
for a settling it explains, which tests the settling, not the coefficient, so one whose interval
holds 0 is not named. That end moves with the replicates drawn (with B = 20 its Monte Carlo sd is
0.41 times theirs, :func:`end_mc_error`), so where it lies within 2 such errors of 0 the axis takes
more runs, the same first B and new ones, up to 4 B or until it is clear (:func:`unclear_decision`),
and gives and decides by the interval widened by 2 such errors (the 655-s log's y was named on 2
seeds of 10, now on none; unwidened, 80 runs left named coefficients of 2-min records outside).

A finding whose **defining** parameter (:attr:`gyrofilter.effects.Effect.defining`, its size) is
not determined is not named: :func:`gyrofilter.analysis.gap.keep.set_aside_uncertain` moves it
from the findings to ``uncertain`` and takes it out of the extended model. The other findings of
its axis keep the intervals computed here, with it in the simulated model (a second bootstrap
without it would double the step's cost for a change within the intervals' own noise).

**The wander a temperature finding's axis holds but does not name**: a temperature coefficient
is a slow drift's regression on the temperature, and its spread is set by the slow wander of the
axis (a bias instability's drift over the record's length) as much as by the white noise. Where
the axis names no wander (a record too short, or a bias instability below its test), the extended
model is white noise about the coefficient and its replicates are too tight: on the package
model's 10-minute records (gyrofilter/data/mpu6050_model.json, seeds 0-19) the coefficient lay
inside its interval in 35 of 45 findings, and every miss was on an axis without a named wander
(11 of 21 there, 24 of 24 where one was named). A parametric bootstrap simulates the nuisance at
its estimate, not at the 0 its test could not reject: with the replicates of such an axis carrying
a bias instability at its maximum likelihood level on the axis less its findings (the slow
detector's Whittle fit), 44 of 45 were inside. That was not enough on records of a few minutes:
the temperature's fit then takes the wander's drift as its own (the two are both slow ramps over
120 s), the wander's estimate left is mostly 0, and a coefficient named there is the selected
large one (issue 37, 120-s records of that model, seeds 0-199: named on 31 of 600 axes at 1.5-5
times the true coefficient, whose estimate unselected is unbiased; inside its interval on 16 of
31). So the wander is simulated at the **upper end of its confidence set** (:func:`wander_upper`:
the largest level the Whittle profile likelihood does not reject at one-sided 95 %), the
nuisance's worst case over that set (Berger & Boos 1994: the coefficient's spread grows with the
wander, so its interval holds its level wherever the true wander lies in the set, as it does on
95 % of records). On the same records: named on 18, inside on 16 of 18 (89 %, Clopper-Pearson
65-99 %); 13 more move to ``uncertain``, their wider intervals holding 0
(:func:`gyrofilter.analysis.gap.confound.unnamed_temperature`); 600-s records,
seeds 0-44: 95 of 96 inside (94 of 99 before), three of the weakest (z, 0.01 deg/s per deg C) uncertain.
A selection-adjusted interval (the estimate's distribution conditional on its naming, a truncated
normal, Weinstein, Fithian & Benjamini 2013) is not built: all 31 are named by the GLS test
(:func:`~gyrofilter.analysis.gap.detectors.covariate.temperature_first`, z > 5 under the white
noise the residual shows), a threshold on the estimate in units of its white-noise spread, but
the truncated normal's inversion needs the estimate's own spread, which the unnamed wander sets:
the same nuisance.

**Gauss-Markov findings: one step of test inversion** (Carpenter 1999, "Test inversion bootstrap
confidence intervals", JRSS B 61: 159-172). The spread and the bias of a Gauss-Markov estimate
grow with its correlation time (a record holds T / tau correlation times: the sd of log sigma-hat
is about sqrt(tau / T)), so the replicates simulated at an estimate whose tau came out short are
too tight and too little biased, and the interval above misses on short records (85.8 % on
10-minute records, 60 cases). The exact interval's upper end theta_U is where the estimator,
simulated at theta_U, puts the estimate at its lower 2.5 %; one step towards it: the model is
simulated again at the interval's upper ends (sigma and tau together: their estimates are
positively correlated), and the upper end moves by one secant step of that equation, its bias and
spread taken linear between the estimate's replicates and these (:func:`inversion_step`; a plain
step to ``u_hat - bias_U + t s_U`` overshoots); the same at the lower ends for the lower end. This
costs two more sets of replicates on an axis with such a finding.

A **wandering tone** takes the same step: its frequency track is a Gauss-Markov process (spread
sigma_f, correlation time T), whose spread and wander read short on a record of few correlation
times. Its centre, a location parameter (:data:`LOCATED`), keeps the plain interval: simulated at
the ends, the centre's own value moves the replicates without changing their spread, which grows
with sigma_f and T instead (the track's mean over a record of length L wanders by about
sigma_f sqrt(2 T / L)); a secant step on it is noise. Measured (`tools/gap_coverage.py --effects
wandering_tone --seed 16000`): on 30-60-min records, 40 cases, 91.9 % of the parameters inside before
the step and 96.1 % with it (the wander not determined on 5); on 10-min records, 80 cases, 86.8 % and
91.6 % (the wander not determined on 34 of 74: a record of 2-20 correlation times does not bound it
within a factor 100). The centre's interval covers 39 of 40 on the long records but 60 of 74 on the
10-min ones: where the record holds fewer than about ten correlation times the track's mean lies
where the tone dwelt, and its spread and wander read short (docs/gap.md, "Coverage").

An axis without findings has the baseline's model, white noise: its bias interval is
``mean +- z s / sqrt(N)`` (s the per-sample std, quantization included) and its white-noise
level's ``sigma^2 (1 +- z sqrt(2 / N) (sigma^2 + q^2/12) / sigma^2)`` (the variance of a sample
variance, 2 s^4 / N), z = 1.96.
"""
from __future__ import annotations

import copy
import math
import time
from statistics import NormalDist
from typing import NamedTuple

import numpy as np

from ...effects import (BIAS_INSTABILITY, BY_NAME, COLORED_NOISE, GAUSS_MARKOV, OUTLIERS, REGISTRY, TEMPERATURE, WANDERS,
                        WANDERING_TONE)
from ..stats import block_means
from .confound import unnamed_temperature
from .baseline import Progress, axis_dps, simulate_axis, noise_sigma, temperature_table
from .detectors.outliers import clean_spikes, detect_outliers
from .detectors.slow import periodogram_detrended
from .reestimate import SUPPORTED, reestimate_axis
from ...sim.model import TEMPERATURE_PROFILE, param_bounds, validate_model
from ...units import AXES

#: the two-sided level of every interval
CONFIDENCE = 0.95
#: bootstrap replicates per axis with findings (``gyrofilter gap --bootstrap``) up to
#: :data:`FEWER_BOOTSTRAP_FROM` samples per axis; fewer above (:func:`default_bootstrap`)
DEFAULT_BOOTSTRAP = 20
#: from this many samples per axis the default number of replicates falls, to 10 at twice as many
FEWER_BOOTSTRAP_FROM = 1_000_000
#: the most replicates ``--bootstrap`` takes
MAX_BOOTSTRAP = 1000
#: a parameter's interval needs at least this many replicates where its estimator ran
MIN_REPLICATES = 5
#: ... and at least this share of the replicates (module docstring: fewer, it is not determined)
MIN_SHARE = 0.5
#: a positive (log-scale) parameter whose interval spans more than this factor is not determined
MAX_SPAN_RATIO = 100
#: a naming decided by an interval end against 0 (the temperature's) within this many of the end's
#: Monte Carlo standard errors takes more bootstrap runs (:func:`unclear_decision`) ...
MC_CLEAR_K = 2.0
#: ... doubling them up to this many times B (and :data:`MAX_BOOTSTRAP`)
MC_MOST = 4
#: the profile-likelihood drop of the unnamed wander's upper bound (:func:`wander_upper`): chi^2_1's
#: 90 % point, the one-sided 95 % bound of a level on its boundary (Self & Liang 1987)
WANDER_LEVEL = 2.705543
#: effects whose intervals take one step of test inversion (module docstring)
INVERTED = (GAUSS_MARKOV, WANDERING_TONE)
#: per inverted effect, its location parameters, which keep the plain interval (module docstring)
LOCATED = {WANDERING_TONE: ("center_hz",)}
#: per effect, the scale on which each parameter's interval is computed (the registry's
#: ``interval_scales``: ``log`` for positive scale parameters, ``atanh`` for autocorrelations in (-1, 1),
#: ``phase`` for radians, else ``linear``: signed parameters, times, frequencies), and the baseline's
SCALES = {**{e.name: e.interval_scales for e in REGISTRY if e.interval_scales},
          "baseline": {"arw_dps_per_sqrt_hz": "log"}}
METHOD = ("parametric bootstrap of the extended model (each axis with findings simulated B times with the record's "
          "length, rate and temperature; every finding's estimator re-run on each run); bias-corrected normal interval "
          "on the log scale (positive parameters), atanh (autocorrelations) or linear, with the Student quantile of "
          "B - 1 degrees of freedom, widened to hold the estimate; not determined (null) where the estimator ran on "
          f"fewer than half of the runs or a positive parameter's interval spans over a factor {MAX_SPAN_RATIO}; a "
          f"temperature whose interval's end lies within {MC_CLEAR_K:g} Monte Carlo errors of 0: up to {MC_MOST} B runs, then "
          "widened by them; axes "
          "without findings: the white-noise baseline's analytic intervals")


class Interval(NamedTuple):
    """A parameter's 95 % interval: ``ends`` ``[low, high]`` (holding the estimate), or None and
    ``why``, a clause saying why the record does not determine the parameter."""

    ends: list | None
    why: str | None = None


class Intervals(NamedTuple):
    """What :func:`bootstrap_intervals` found: the report's ``intervals`` block; per kept finding
    (its candidate index) ``{param: [low, high] or None}`` (empty with no bootstrap); per axis
    the baseline's; per kept finding ``{param: why}`` of the parameters not determined; notes."""

    block: dict
    findings: dict
    baseline: dict
    undetermined: dict
    notes: list


def default_bootstrap(n_samples):
    """Replicates per axis with findings when ``--bootstrap`` is not given:
    ``max(10, min(20, round(20 M / N)))``, M = :data:`FEWER_BOOTSTRAP_FROM`: 20 up to a million
    samples per axis (3 h at 100 Hz), 10 from two million (6 h at 100 Hz, 1 h at 1 kHz). Each
    replicate is a simulation and a re-estimation of the whole record, so on long records they
    are most of the analysis's time. The interval's Student factor ``t_{B-1} sqrt(1 + 1/B)``
    (module docstring) keeps the coverage with fewer replicates: with 10 the intervals are on
    average 11 % wider than with 20 (2.37 against 2.14 times the replicates' sd), on records
    whose intervals are already sqrt(N / 360 000) times narrower than those of an hour at 100 Hz."""
    return int(max(10, min(DEFAULT_BOOTSTRAP, round(DEFAULT_BOOTSTRAP * FEWER_BOOTSTRAP_FROM / max(n_samples, 1)))))


def bootstrap_intervals(inp, state, n_boot, seed):
    """The 95 % intervals of every kept finding's parameters (the gap analysis's ``inp`` and
    ``state`` after step 4) and of the baseline's axes, from ``n_boot`` replicates per axis with
    findings (none with ``n_boot`` 0; None: :func:`default_bootstrap` of the record's length):
    an :class:`Intervals`. A parameter not determined (module docstring) has None, its ``why`` in
    ``undetermined`` and a note."""
    n_boot = default_bootstrap(inp.n) if n_boot is None else n_boot
    t0 = time.perf_counter()
    found = Intervals({"confidence": CONFIDENCE, "bootstrap_runs": int(n_boot)}, {}, {}, {}, [])
    if n_boot <= 0:
        found.block["method"] = "none: --bootstrap 0 asked for no intervals"
        return found
    found.block["method"] = METHOD
    found.block["bootstrap_runs_by_axis"] = {}
    seeds_all = np.random.default_rng([int(seed), 24]).integers(0, 2**31, size=int(n_boot))
    most = max(int(n_boot), min(MC_MOST * int(n_boot), MAX_BOOTSTRAP))  # the runs an unclear decision may take
    # ... drawn from a stream of their own after the first B, which stay the same (:func:`unclear_decision`)
    seeds_all = np.concatenate((seeds_all, np.random.default_rng([int(seed), 24, 1]).integers(0, 2**31, size=most - n_boot)))
    for i, a in enumerate(AXES):
        here = [row for row in state.kept if row.axis == i]
        if not here:
            found.baseline[a] = _baseline_analytic(inp, i)
            continue
        for row in here:
            found.findings[row.k] = dict.fromkeys(row.cand.params)
            if row.cand.effect not in SUPPORTED:
                found.notes.append(f"intervals: no estimator for {row.cand.effect} on {a}; its parameters have no interval")
        cands = [row.cand for row in here]
        seeds = seeds_all[:n_boot]
        try:
            estimates = _replicates(inp, state, i, cands, seeds)
            while len(seeds) < most and (unclear := [row.cand.effect for j, row in enumerate(here) if unclear_decision(
                    row.cand, [e[j] for e in estimates["findings"]]) is not None]):
                added = seeds_all[len(seeds):min(2 * len(seeds), most)]
                found.notes.append(f"intervals on {a}: the {unclear[0]} interval's end lies within {MC_CLEAR_K:g} Monte Carlo "
                                   f"standard errors of 0, which decides its naming: bootstrap runs {len(seeds)} -> "
                                   f"{len(seeds) + len(added)}")
                extra = _replicates(inp, state, i, cands, added)
                estimates = {key: estimates[key] + extra[key] for key in estimates}
                seeds = seeds_all[:len(seeds) + len(added)]
        except (ValueError, ArithmeticError) as exc:  # a singular fit: never lose the findings for it
            found.notes.append(f"intervals on {a}: the bootstrap could not run ({exc}); no intervals")
            continue
        found.block["bootstrap_runs_by_axis"][a] = int(len(seeds))
        for j, row in enumerate(here):
            if row.cand.effect not in SUPPORTED:
                continue
            c = row.cand
            params = c.plain_params()
            reps = [e[j] for e in estimates["findings"]]
            got = {name: _interval(value, [r.get(name) if r else None for r in reps],
                                   SCALES.get(c.effect, {}).get(name, "linear"), param_bounds(c.effect, name))
                   for name, value in params.items()}
            if c.effect in INVERTED and all(g.ends for g in got.values()):
                got = {**_invert(inp, state, i, cands, j, c.effect, params, reps, seeds),
                       **{name: got[name] for name in LOCATED.get(c.effect, ())}}
            found.findings[row.k] = {name: g.ends for name, g in got.items()}
            if (wide := unclear_decision(c, reps, widen=len(seeds) > n_boot)) is not None:  # it carries its MC error
                found.findings[row.k][BY_NAME[c.effect].defining] = wide
                found.notes.append(f"{c.effect} on {a}: after {len(seeds)} bootstrap runs its interval is widened by "
                                   f"{MC_CLEAR_K:g} Monte Carlo standard errors, and decides so")
            for name, g in got.items():
                if g.ends is None:
                    found.undetermined.setdefault(row.k, {})[name] = g.why
                    found.notes.append(f"{c.effect} on {a}: {name} not determined by this record ({g.why})")
        got = {name: _interval(inp.base["axes"][a][name], estimates[name], SCALES["baseline"].get(name, "linear"))
               for name in ("bias_dps", "arw_dps_per_sqrt_hz")}
        found.baseline[a] = {name: g.ends for name, g in got.items()}
        found.notes.extend(f"baseline on {a}: {name} not determined by this record ({g.why})"
                           for name, g in got.items() if g.ends is None)
    found.block["runtime_s"] = time.perf_counter() - t0
    return found


def end_mc_error(half, b):
    """The Monte Carlo standard error of an end ``u_hat - bias +- half`` of the interval of the
    module docstring from ``b`` replicates (``half = t_{0.975, b-1} sqrt(1 + 1/b) s``): the ends
    move with the replicates drawn, not with the record. The bias ``mean(u*)`` has Monte Carlo
    variance ``s^2 / b`` and the spread ``s`` has ``s^2 / (2 (b - 1))`` (normal replicates; the two
    are independent), so

        se_end = sqrt(s^2 / b + half^2 / (2 (b - 1))),   s = half / (t_{0.975, b-1} sqrt(1 + 1/b)),

    0.41 s with b = 20, 0.19 s with b = 80 (Efron & Tibshirani 1993, ch. 19, the Monte Carlo error
    of a bootstrap estimate as the replicates' own sampling error; Andrews & Buchinsky 2000, "A
    three-step method for choosing the number of bootstrap repetitions", Econometrica 68: 23-51,
    who choose b from that error)."""
    from scipy.stats import t as student_t

    factor = float(student_t.ppf(0.5 + CONFIDENCE / 2, b - 1)) * math.sqrt(1 + 1 / b)
    s = half / factor
    return math.sqrt(s * s / b + half * half / (2 * (b - 1)))


def unclear_decision(cand, replicates, decides=unnamed_temperature, widen=False):
    """The defining parameter's interval widened by its Monte Carlo error (below), or None where
    the decision is clear (``widen``: wherever an interval decides the naming). Unclear: the naming
    of the finding ``cand`` rests on its defining parameter's interval
    (``decides(cand, ends)``, None where it is named: the temperature's rule,
    :func:`~gyrofilter.analysis.gap.confound.unnamed_temperature`, whether the interval holds 0)
    and that decision is within the Monte Carlo error of the ``replicates`` (its estimates per
    run, dicts or None): the interval's ends moved out by :data:`MC_CLEAR_K` times their Monte
    Carlo standard error (:func:`end_mc_error`) and moved in by as much (at most to its centre)
    decide differently. The bootstrap then takes more runs (:func:`bootstrap_intervals`, doubling
    up to :data:`MC_MOST` times B): a verdict that flips with the seed of the replicates is the
    simulation's, not the record's (Andrews & Buchinsky 2000). An axis that took more runs gives
    and decides by the widened interval (module docstring)."""
    name = BY_NAME[cand.effect].defining
    value = cand.plain_params().get(name)
    if value is None or decides(cand, [-math.inf, math.inf]) is None:  # no interval decides its naming
        return None
    values = [r.get(name) if r else None for r in replicates]
    spread = _spread(value, values, SCALES.get(cand.effect, {}).get(name, "linear"))
    if isinstance(spread, str):
        return None
    scale, u_hat, bias, half = spread
    b = int(np.isfinite(_forward([np.nan if v is None else float(v) for v in values], scale)).sum())
    k_se = MC_CLEAR_K * end_mc_error(half, b)
    bounds = param_bounds(cand.effect, name)
    wide, narrow = (_finish(u_hat - bias - h, u_hat - bias + h, value, scale, bounds).ends
                    for h in (half + k_se, max(half - k_se, 0.0)))
    if wide is None or narrow is None or not widen and (decides(cand, wide) is None) == (decides(cand, narrow) is None):
        return None
    return wide


def _invert(inp, state, i, cands, j, effect, params, reps, seeds):
    """One step of test inversion (module docstring) for the finding ``j`` of ``cands`` on axis
    ``i`` (an ``effect`` with estimates ``params``; ``reps``: its replicates' estimates at them):
    ``{name: Interval}``, its ends re-made with replicates simulated at its lower and at its upper ends."""
    def replicates_at(at):
        return [e[j] for e in _replicates(inp, state, i, cands, seeds, {j: at}, wanted=[j])["findings"]]

    return inversion_step(params, reps, replicates_at, SCALES.get(effect, {}),
                          {name: param_bounds(effect, name) for name in params})


def inversion_step(params, replicates, replicates_at, scales, bounds=None):
    """``{name: Interval}`` of the estimates ``params`` after one secant step of test
    inversion (module docstring). ``replicates``: the estimates (dicts, or None) of replicates
    simulated at ``params``; ``replicates_at(at)`` returns those of replicates simulated at the
    parameters ``at``, and is called at the interval's lower ends and at its upper ends.

    On the parameter's scale, with bias b(u) and half-width h(u) of the estimator simulated at u
    (:func:`_spread`), the lower end solves ``u_hat = u + b(u) + h(u)`` and the upper end
    ``u_hat = u + b(u) - h(u)``; with b and h linear between the estimate (b0, h0) and the plain
    interval's end u1 (b1, h1), ``k_b = (b1 - b0) / (u1 - u_hat)``, ``k_h = (h1 - h0) / (u1 - u_hat)``:

        lower: u_hat - (b0 + h0) / (1 + k_b + k_h),   upper: u_hat + (h0 - b0) / (1 + k_b - k_h),

    the plain interval where k_b = k_h = 0. A denominator below 1/2 is taken as 1/2 (an end moves at
    most twice as far as the plain one); a parameter with too few replicates at an end keeps its
    plain end there. The result holds the estimate and is cut to each parameter's domain ``bounds``
    (``{name: (low, high)}``), or is not determined (:func:`_finish`)."""
    out = {}
    first = {name: _spread(value, [r.get(name) if r else None for r in replicates], scales.get(name, "linear"))
             for name, value in params.items()}
    plain = {name: None if isinstance(f, str) else (f[1] - f[2] - f[3], f[1] - f[2] + f[3]) for name, f in first.items()}
    ends = {}
    for side in (0, 1):
        if any(p is None for p in plain.values()):
            break
        at = {name: _back(plain[name][side], first[name][0]) for name in params}
        reps = replicates_at(at)
        ends[side] = {name: _spread(params[name], [r.get(name) if r else None for r in reps], first[name][0], at=at[name])
                      for name in params}
    for name in params:
        if plain[name] is None:
            out[name] = Interval(None, first[name])
            continue
        scale, u_hat, b0, h0 = first[name]
        ends_u = list(plain[name])
        for side, sign in ((0, -1.0), (1, 1.0)):
            end = ends.get(side, {}).get(name)
            if end is None or isinstance(end, str) or end[0] != scale or ends_u[side] == u_hat:
                continue
            k_b, k_h = ((end[2] - b0) / (ends_u[side] - u_hat), (end[3] - h0) / (ends_u[side] - u_hat))
            ends_u[side] = u_hat + (sign * h0 - b0) / max(1.0 + k_b + sign * -k_h, 0.5)
        out[name] = _finish(ends_u[0], ends_u[1], params[name], scale, (bounds or {}).get(name, (-math.inf, math.inf)))
    return out


def _replicates(inp, state, i, cands, seeds, at=None, wanted=None):
    """Axis ``i`` of the extended model simulated once per seed: each run's finding estimates
    (a list per run, in the order of ``cands``) and the baseline's ``bias_dps`` and
    ``arw_dps_per_sqrt_hz``. ``at``: ``{index into cands: params}`` simulated in place of those
    findings' estimates. ``wanted``: only these findings' estimates are read (the others' may be
    None: :func:`~gyrofilter.analysis.gap.reestimate.reestimate_axis`), and not the baseline's
    (left empty)."""
    a = AXES[i]
    model = copy.deepcopy(inp.base)
    model["axes"][a] = state.spec(inp, i, state.kept_on(i))
    model["axes"][a].setdefault("effects", []).extend(unnamed_wander(inp, i, cands))
    for j, params in (at or {}).items():
        model["axes"][a]["effects"][j].update(params)
    if any(c.effect == TEMPERATURE for c in cands):
        model[TEMPERATURE_PROFILE] = temperature_table(inp.rec, inp.temp)
    spec, _ = validate_model(model)
    temp = inp.temp if any(c.effect == TEMPERATURE for c in cands) else None
    resolved = bool(state.axes[i].lags) and any(c.effect == COLORED_NOISE and c.composite for c in cands)
    out = {"findings": [], "bias_dps": [], "arw_dps_per_sqrt_hz": []}
    bar = Progress(inp.say, f"intervals on {a}: bootstrap runs", len(seeds))
    for k, s in enumerate(seeds):
        x = simulate_axis(spec, inp.n, inp.sample_rate_hz, s, i)
        if wanted is None:
            out["bias_dps"].append(float(np.mean(x)))
            out["arw_dps_per_sqrt_hz"].append(noise_sigma(x, inp.sample_rate_hz, inp.q or 0.0) / math.sqrt(inp.sample_rate_hz))
        try:
            out["findings"].append(reestimate_axis(x, inp.sample_rate_hz, temp, cands, resolved, inp.q or 0.0, owned=True,
                                                   wanted=wanted))
        except (ValueError, ArithmeticError):  # a fit that cannot run on this replicate
            out["findings"].append([None] * len(cands))
        del x  # the next run is made while this one would still be held: two series of the record's length
        bar.step(k + 1)
    return out


def unnamed_wander(inp, i, cands):
    """The slow wander a temperature finding's replicates of axis ``i`` are simulated with where
    its findings ``cands`` name none (module docstring): ``[{"effect": "bias_instability",
    "b_dps": B}]``, ``B^2`` the largest level the record does not rule out (:func:`wander_upper`)
    on the block means of the axis less its findings' components and its named spikes; ``[]`` where the axis has no
    temperature finding, names a wander, or the record rules out any (B = 0)."""
    if not any(c.effect == TEMPERATURE for c in cands) or any(c.effect in WANDERS for c in cands):
        return []
    x = axis_dps(inp.rec, i).astype(float)  # a new array: the findings' components come off in place
    if any(c.effect == OUTLIERS for c in cands):  # the spikes too, as the replicates' estimators take them off
        x = clean_spikes(x, detect_outliers(x, inp.q or 0.0)[1], in_place=True)
    for c in cands:
        if c.component is not None:
            x -= c.component
    y, _ = block_means(x)
    if y.size < 16:
        return []
    b_dps = math.sqrt(wander_upper(y))
    return [{"effect": BIAS_INSTABILITY, "b_dps": b_dps}] if b_dps > 0 else []


def wander_upper(y):
    """The largest bias instability level ``h`` (``S(omega) = s0 + h / omega``, ``b_dps = sqrt(h)``
    as the slow detector's fit, :func:`~gyrofilter.analysis.gap.detectors.slow.slow_spectrum`) the
    block means ``y`` do not rule out: the largest ``h`` of the Whittle profile likelihood on their
    detrended periodogram ``I_j`` (:func:`~gyrofilter.analysis.gap.detectors.slow.periodogram_detrended`)

        l(h) = min_s0 sum_j log S_j + I_j / S_j   (Whittle 1953),   2 (l(h) - min_h l) <= WANDER_LEVEL,

    :data:`WANDER_LEVEL` the chi^2_1 90 % point, 2.71: the one-sided 95 % bound of a level whose
    null lies on its boundary 0 (Self & Liang 1987). The nuisance at the upper end of its
    confidence set, not at its estimate, is Berger & Boos's (1994) worst case: the coefficient's
    spread grows with the wander, so its interval holds at least its level whenever the wander
    lies inside that set (module docstring). ``h`` on a grid of ratio 10^(1/8) over six decades
    about ``s0 omega_1`` (the level at which the wander reaches the white level at the lowest
    frequency); 0 where the record rules out every ``h > 0`` of the grid."""
    from scipy.optimize import minimize_scalar

    spec, omega = periodogram_detrended(np.asarray(y, dtype=float))
    s_hf = float(spec[spec.size // 2:].mean())
    if not s_hf > 0:
        return 0.0

    def profile(h):
        def nll(log_s0):
            s = math.exp(log_s0) + h / omega
            return float(np.sum(np.log(s) + spec / s))
        return float(minimize_scalar(nll, bounds=(math.log(s_hf) - 5, math.log(s_hf) + 2), method="bounded").fun)

    grid = np.concatenate(([0.0], s_hf * omega[0] * np.logspace(-3, 3, 49)))
    nll = np.array([profile(float(h)) for h in grid])
    inside = np.flatnonzero(2 * (nll - np.nanmin(nll)) <= WANDER_LEVEL) if np.isfinite(nll).any() else []
    return float(grid[max(inside)]) if len(inside) else 0.0


def _forward(values, scale):
    v = np.asarray(values, dtype=float)
    if scale == "log":
        return np.log(np.where(v > 0, v, np.nan))
    if scale == "atanh":
        return np.arctanh(np.where(np.abs(v) < 1, v, np.nan))
    return v


def _back(u, scale):
    if scale == "log":
        return math.exp(u)
    if scale == "atanh":
        return math.tanh(u)
    return u


def _interval(estimate, replicates, scale, bounds=(-math.inf, math.inf)):
    """The :class:`Interval` of the module docstring: the bias-corrected normal-t interval widened
    to hold ``estimate`` and cut to the parameter's domain ``bounds``, or not determined
    (:func:`_spread`, :func:`_finish`)."""
    spread = _spread(estimate, replicates, scale)
    if isinstance(spread, str):
        return Interval(None, spread)
    scale, u_hat, bias, half = spread
    return _finish(u_hat - bias - half, u_hat - bias + half, estimate, scale, bounds)


def _finish(u_low, u_high, estimate, scale, bounds):
    """The :class:`Interval` of the ends ``u_low``, ``u_high`` on ``scale``: mapped back, their hull
    with the ``estimate`` itself (module docstring; the estimate, not its image mapped back and
    forth, which may miss it by a rounding), cut to the parameter's domain ``bounds``
    (:func:`~gyrofilter.sim.model.param_bounds`: the log scale keeps a fraction positive, not
    below 0.5); not determined where a log-scale interval spans more than :data:`MAX_SPAN_RATIO`,
    or where the estimate itself lies outside the domain (the hull then does too)."""
    low, high = min(_back(u_low, scale), estimate), max(_back(u_high, scale), estimate)
    if high < bounds[0] or low > bounds[1]:
        return Interval(None, "its estimate lies outside the values a model takes")
    low, high = max(low, bounds[0]), min(high, bounds[1])
    if scale == "log" and high > MAX_SPAN_RATIO * low:
        return Interval(None, f"its 95 % interval spans {low:.2g} to {high:.2g}, over a factor {MAX_SPAN_RATIO}")
    return Interval([low, high])


def _spread(estimate, replicates, scale, at=None):
    """``(scale, g(estimate), bias, half-width)`` of the replicates on the parameter's scale (a
    log scale falls back to linear for an estimate <= 0), the bias ``mean(u*) - g(at)`` (``at``:
    the value they were simulated at, the estimate by default); or, where the replicates do not
    determine the parameter, a clause saying why: fewer than :data:`MIN_SHARE` of them (and
    fewer than :data:`MIN_REPLICATES`) have it, or the estimate has no value on the scale."""
    from scipy.stats import t as student_t

    values = [np.nan if r is None else float(r) for r in replicates]
    if scale == "log" and not estimate > 0:
        scale = "linear"
    u_hat = float(_forward([estimate], scale)[0])
    u_at = u_hat if at is None else float(_forward([at], scale)[0])
    u = _forward(values, scale)
    u = u[np.isfinite(u)]
    if u.size < max(MIN_REPLICATES, MIN_SHARE * len(values)):
        return f"its estimator ran on {u.size} of {len(values)} bootstrap runs, fewer than " + (
            "half" if MIN_SHARE * len(values) > MIN_REPLICATES else f"the {MIN_REPLICATES} an interval needs")
    if not (math.isfinite(u_hat) and math.isfinite(u_at)):
        return f"its estimate has no value on the {scale} scale"
    dev = u - u_at
    if scale == "phase":
        dev = (dev + math.pi) % (2 * math.pi) - math.pi
    b = u.size
    half = float(student_t.ppf(0.5 + CONFIDENCE / 2, b - 1)) * math.sqrt(1 + 1 / b) * float(np.std(dev, ddof=1))
    return scale, u_hat, float(np.mean(dev)), half


def _baseline_analytic(inp, i):
    """Intervals of the white-noise baseline of axis ``i`` (module docstring): ``{param: [low,
    high]}``, or None for a constant axis."""
    n = inp.n
    base_axis = inp.base["axes"][AXES[i]]
    z = NormalDist().inv_cdf(0.5 + CONFIDENCE / 2)
    q2 = (inp.q or 0.0) ** 2 / 12.0
    sigma2 = (base_axis["arw_dps_per_sqrt_hz"] ** 2) * inp.sample_rate_hz
    total = sigma2 + q2
    if not total > 0:
        return None
    se_mean = math.sqrt(total / n)
    bias = base_axis["bias_dps"]
    rel = z * math.sqrt(2.0 / n) * total / max(sigma2, 1e-300)
    return {
        "bias_dps": [bias - z * se_mean, bias + z * se_mean],
        "arw_dps_per_sqrt_hz": [base_axis["arw_dps_per_sqrt_hz"] * math.sqrt(max(1 - rel, 0.0)),
                                base_axis["arw_dps_per_sqrt_hz"] * math.sqrt(1 + rel)]}
