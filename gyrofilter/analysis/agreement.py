"""allan and gap on one record: where the two analyses' noise terms disagree, one sentence each.

:func:`compare` takes the ``allan --json`` document (docs/formats.md, section 4) and the ``gap
--json`` document (section 3) of the same record and, per axis and per term, holds allan's
fit against gap's estimate:

=====  ===========================================  ==========================================
term   allan (``details.<key>``: value [low, high],  gap
       or ``upper_bound`` when not resolved)
=====  ===========================================  ==========================================
N      ``arw_dps_per_sqrt_hz``                      the baseline's ``arw_dps_per_sqrt_hz``
B      ``bias_instability_dps``                     a ``bias_instability`` finding's ``b_dps``
K      ``rrw_dps_per_sqrt_s``                       a ``rate_random_walk`` finding's ``k_dps_per_sqrt_s``
R      ``rate_ramp_dps_per_s``                      a ``rate_ramp`` finding's ``r_dps_per_s`` (its size)
=====  ===========================================  ==========================================

each with its 95 % interval (gap's ``params_ci95``, by bootstrap; none with ``--bootstrap 0``).
The two packages' terms are the same quantities, so they are compared as they stand: the
simulator's ``b_dps`` is B of the Allan floor sigma = sqrt(2 ln 2 / pi) B
(:data:`gyrofilter.sim.flicker.FLICKER_ADEV_PER_B`, the Allan model's
:data:`~gyrofilter.analysis.noise.model.FLICKER_FLOOR`), its ``k_dps_per_sqrt_s`` is K of
sigma = K sqrt(tau / 3) (:class:`gyrofilter.sim.noise_terms.RateRandomWalk`) and its ramp R of
sigma = R tau / sqrt(2), as in :mod:`gyrofilter.analysis.noise.model`; N is deg/s/sqrt(Hz) in both.

The rules (issue 35: "allan and gap tell one story"), a sentence for each break:

1. gap names a term above allan's upper bound of it (allan does not resolve it);
2. both estimate a term and their intervals do not overlap (gap's value, where it has no interval);
3. allan's fit resolves B, K or R where gap names no such finding on the axis.

Each sentence says why the two may differ where the documents show a known reason: gap's
baseline white level holds the fast effects gap names (lines, bands, colored noise, tails), while
allan's N is the tau^-1/2 slope at longer cluster times; gap models slow effects (a warm-up, a
step, the temperature, a Gauss-Markov wander, ...) that allan's five terms can only absorb into
B, K and R; gap's reading is one of several that explain the record as well (its
``alternatives``); allan's bound comes from a fit without the term over cluster times up to a
ninth of the record; allan's fit leaves a misfit (``fit_reduced_chi2``, already in its intervals).
Agreement gives no sentence. Numbers in, sentences out: nothing here reads a file or prints.
"""
from __future__ import annotations

from ..effects import BIAS_INSTABILITY, BY_NAME, RATE_RAMP, RATE_RANDOM_WALK, SLOW, of_kind
from .noise.allan import MIN_CLUSTERS
from .noise.export import JSON_KEY
from .noise.model import ANGLE_RANDOM_WALK, TERM_SYMBOL, TERM_UNIT

#: the terms compared, in the Allan model's order
COMPARED = (ANGLE_RANDOM_WALK, BIAS_INSTABILITY, RATE_RANDOM_WALK, RATE_RAMP)
#: gap's parameter of each slow term: its effect's (one) required parameter in the registry
GAP_PARAM = {t: next(iter(BY_NAME[t].required)) for t in (BIAS_INSTABILITY, RATE_RANDOM_WALK, RATE_RAMP)}
#: the effects that gap's baseline white level holds (faster than its white-noise read, about 0.5 s)
FAST = of_kind("line", "noise", "tails")


def compare(allan, gap):
    """The sentences where ``allan`` (the allan document) and ``gap`` (the gap document) of one
    record disagree (module docstring): a list of ``{"axis", "term", "text"}`` (``term`` the
    symbol N, B, K or R), empty where they tell one story. Axes only one document has are skipped."""
    out = []
    for axis, ax in allan["axes"].items():
        if axis not in gap.get("baseline", {}).get("axes", {}):
            continue
        findings = [f for f in gap.get("findings", []) if f["axis"] == axis]
        for term in COMPARED:
            text = _sentence(axis, term, ax, gap, findings)
            if text:
                out.append({"axis": axis, "term": TERM_SYMBOL[term], "text": text})
    return out


def _sentence(axis, term, ax, gap, findings):
    """The sentence of one axis and term, or None where allan and gap agree."""
    d = ax["details"][JSON_KEY[term]]
    named = _gap_estimate(term, gap["baseline"]["axes"][axis], findings)
    sym, unit = TERM_SYMBOL[term], TERM_UNIT[term]
    if named is None:
        if d["value"] is None or term == ANGLE_RANDOM_WALK:
            return None
        return (f"axis {axis}: allan's fit needs {sym} = {_interval(d['value'], d['low'], d['high'])} {unit} where gap "
                f"names none" + _why(term, axis, ax, gap, findings, allan_only=True) + ".")
    value, ci, finding = named
    if d["value"] is None:
        bound = d.get("upper_bound")
        if bound is None or value <= bound:
            return None
        return (f"axis {axis}: gap names {sym} = {_interval(value, *ci)} {unit}, above allan's bound {sym} < "
                f"{bound:.3g} {unit}" + _why(term, axis, ax, gap, findings, finding=finding, bounded=True) + ".")
    low, high = (ci if ci[0] is not None else (value, value))
    if low <= d["high"] and d["low"] <= high:
        return None
    return (f"axis {axis}: {sym} from allan {_interval(d['value'], d['low'], d['high'])} and from gap "
            f"{_interval(value, *ci)} {unit}: the intervals do not overlap" + _why(term, axis, ax, gap, findings, finding=finding)
            + ".")


def _gap_estimate(term, baseline, findings):
    """gap's estimate of ``term`` on one axis: (value, (low, high) or (None, None), the finding or
    None), or None where gap names no such finding. R is compared as a size: its sign is the
    ramp's direction, which allan's R^2 does not have."""
    if term == ANGLE_RANDOM_WALK:
        if baseline.get("arw_dps_per_sqrt_hz") is None:  # an analysis that could not run
            return None
        ci = (baseline.get("params_ci95") or {}).get("arw_dps_per_sqrt_hz") or (None, None)
        return baseline["arw_dps_per_sqrt_hz"], tuple(ci), None
    finding = next((f for f in findings if f["effect"] == term), None)
    if finding is None:
        return None
    key = GAP_PARAM[term]
    value = finding["params"].get(key)
    if value is None:
        return None
    ci = (finding.get("params_ci95") or {}).get(key) or (None, None)
    if term == RATE_RAMP:
        value = abs(value)
        if ci[0] is not None:
            ci = (0.0, max(abs(ci[0]), abs(ci[1]))) if ci[0] < 0 < ci[1] else tuple(sorted((abs(ci[0]), abs(ci[1]))))
    return value, tuple(ci), finding


def _why(term, axis, ax, gap, findings, *, finding=None, bounded=False, allan_only=False):
    """The known reasons why allan and gap may differ on ``term`` of ``axis``, as the sentence's tail
    (": reason; reason"), or a tail saying none is known."""
    reasons = []
    if term == ANGLE_RANDOM_WALK:
        fast = sorted({f["effect"] for f in findings if f["effect"] in FAST})
        extended = ((gap.get("extended_model") or {}).get("axes", {}).get(axis) or {}).get("arw_dps_per_sqrt_hz")
        if fast:
            d = ax["details"][JSON_KEY[term]]
            inside = extended is not None and d["value"] is not None and d["low"] <= extended <= d["high"]
            reasons.append(f"gap's baseline white level is the per-sample scatter of the noise faster than about 0.5 s, "
                           f"which holds the {', '.join(fast)} gap names here"
                           + (f" (its extended model's white level, without them, is {extended:.3g}"
                              + (": inside allan's interval)" if inside else ")") if extended is not None else "")
                           + "; allan's N is the tau^-1/2 slope at longer cluster times")
        else:
            reasons.append("gap's white level is the per-sample scatter of the noise faster than about 0.5 s, allan's N "
                           "the tau^-1/2 slope at longer cluster times: they agree for white noise, so the noise is not "
                           "white between those time scales")
    else:
        slow = sorted({f["effect"] for f in findings if f["effect"] in SLOW and f["effect"] != term})
        suggested = next((u for u in gap.get("uncertain", []) if u["axis"] == axis and u["effect"] == term), None)
        if suggested is not None and allan_only:
            value = suggested["params"].get(GAP_PARAM[term])
            reasons.append(f"gap suggests {TERM_SYMBOL[term]} = {value:.3g} {TERM_UNIT[term]} but does not establish it "
                           f"({suggested['why']})")
        elif slow and allan_only:
            reasons.append(f"gap explains the slow part with {', '.join(slow)}, which allan's five terms can only hold "
                           f"as B, K and R")
        elif slow:
            reasons.append(f"gap models {', '.join(slow)} as well, which allan's five terms absorb into B, K and R")
        elif allan_only:
            reasons.append("gap finds no slow effect beyond its baseline's spread on this axis")
        if finding is not None and finding.get("alternatives"):
            alt = ", ".join(sorted({a["effect"] for a in finding["alternatives"]}))
            reasons.append(f"gap's reading is one of two that explain the record about as well (the other: {alt})")
        if bounded and ax["details"][JSON_KEY[term]].get("model_value", 0.0) == 0.0:
            longest = max((t for t, k in zip(ax["tau_s"], ax["n_clusters"]) if k >= MIN_CLUSTERS), default=None)
            if longest is not None:
                reasons.append(f"allan's bound is that of a fit without {TERM_SYMBOL[term]} over cluster times up to "
                               f"{longest:.3g} s")
    chi2 = ax.get("fit_reduced_chi2")
    if chi2 is not None and chi2 > 1.0:
        reasons.append(f"allan's fit leaves a misfit (reduced chi-square {chi2:.3g}, already in its intervals)")
    if not reasons:
        return ": no reason the documents show; one of the two analyses is wrong on this record"
    return ": " + "; ".join(reasons)


def _interval(value, low, high):
    """``value [low, high]`` (3 significant digits), the value alone without an interval."""
    return f"{value:.3g}" + (f" [{low:.3g}, {high:.3g}]" if low is not None else "")
