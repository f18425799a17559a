"""Steps 4 and 5 of the gap analysis (:mod:`gyrofilter.analysis.gap.pipeline`): which findings
are kept. A finding is kept on its gain alone, or where D cannot tell without it, less one that
makes its axis worse with the others (the rules: :mod:`gyrofilter.analysis.gap.confound`); a kept
finding whose defining parameter the record does not determine, or a temperature whose interval
holds 0, is set aside as uncertain."""
from __future__ import annotations

from dataclasses import replace

from ...effects import BY_NAME
from ...units import AXES
from .confound import kept_without_gain, unnamed_temperature, worse_together
from .features import d_shown
from .state import Kept


def keep_findings(inp, state, scorer):
    """Step 4: gain per finding, the axis extended by this finding alone (the contract's gain);
    a finding that shows no gain alone is still kept where leaving it out of the model with the
    axis's other candidates (alone on its axis: the baseline) does not lower D beyond its null
    spread (:func:`gyrofilter.analysis.gap.confound.kept_without_gain`).
    Then D of each axis extended by all its kept findings, less a finding that makes it worse
    (:func:`gyrofilter.analysis.gap.confound.worse_together`)."""
    cands, before, notes = state.candidates, inp.before, []
    single = {}

    def d_of(i, ks, label):
        return scorer.discrepancy(i, state.model(inp, i, ks), label)

    for k, (i, c) in enumerate(cands):
        if k in state.excluded:
            continue
        label = f"gain of {c.effect} on {AXES[i]} ({k + 1}/{len(cands)})"
        inp.say(label)
        try:
            single[k] = d_of(i, [k], label)
        except (ValueError, FloatingPointError) as exc:
            notes.append(f"{c.effect} on {AXES[i]}: extended model could not run ({exc})")
    kept = []
    for k, (i, c) in enumerate(cands):
        if k not in single:
            continue
        after = single[k]
        if after < before[i]:
            kept.append(Kept(k, i, c, after))
            continue
        others = [k2 for k2, (i2, _) in enumerate(cands) if i2 == i and k2 != k and k2 in single]
        if others:
            label = f"{c.effect} on {AXES[i]} with and without the axis's other findings"
            inp.say(label)
            try:
                with_all = d_of(i, others + [k], label)
                without = d_of(i, others, label)
            except (ValueError, FloatingPointError):
                with_all = without = float("inf")
            why = kept_without_gain(c.effect, with_all, without, lambda: max(
                scorer.null_spread(i, state.model(inp, i, others + [k]), label),
                scorer.null_spread(i, state.model(inp, i, others), label)))
            if why is not None:
                kept.append(Kept(k, i, c, after))
                notes.append(f"{c.effect} on {AXES[i]}: no gain alone ({d_shown(before[i])} -> {d_shown(after)}) but kept: with the "
                             f"axis's other findings D = {d_shown(with_all)}, without it {d_shown(without)}{why}")
                continue
        else:  # alone on its axis: weighed against the baseline the same way
            label = f"{c.effect} on {AXES[i]} against the baseline"
            why = kept_without_gain(c.effect, after, before[i], lambda: max(
                scorer.null_spread(i, state.model(inp, i, [k]), label), scorer.null_spread(i, None, label)))
            if why:
                kept.append(Kept(k, i, c, after))
                notes.append(f"{c.effect} on {AXES[i]}: no gain ({d_shown(before[i])} -> {d_shown(after)}) but kept{why}")
                continue
        notes.append(f"{c.effect} on {AXES[i]} dropped: no gain (discrepancy {d_shown(before[i])} -> {d_shown(after)})")
    state = replace(state, kept=tuple(kept), single=single).with_notes(*notes)
    after = list(before)
    if kept:
        inp.say("overall gain of the extended model")
        for i in sorted({row.axis for row in kept}):
            ks, label = state.kept_on(i), f"extended model on {AXES[i]}"
            after[i] = d_of(i, ks, label)
            drop = worse_together(ks, single, after[i], lambda k: d_of(i, [j for j in ks if j != k], label),
                                  lambda: scorer.null_spread(i, state.model(inp, i, ks), label))
            if drop is not None:
                k, after[i], why = drop
                state = replace(state, kept=tuple(r for r in state.kept if r.k != k)).with_notes(
                    f"{cands[k][1].effect} on {AXES[i]} dropped: {why}")
    return replace(state, after=tuple(after))


def set_aside_uncertain(inp, state, scorer, found):
    """Step 5: a kept finding the record does not establish is not named: one whose defining
    parameter (:attr:`gyrofilter.effects.Effect.defining`) the record does not determine
    (``found``: the :class:`~gyrofilter.analysis.gap.intervals.Intervals`, whose ``undetermined``
    says so and why), or a temperature whose coefficient's interval holds 0
    (:func:`gyrofilter.analysis.gap.confound.unnamed_temperature`, a note saying so). It moves
    from ``kept`` to ``uncertain``, and D after of its axis is that of the axis extended by the
    findings that stay (the baseline's where none does), which keep the parameters and intervals
    fitted beside it."""
    moved, holding_zero = [], set()
    for row in state.kept:
        defining = BY_NAME[row.cand.effect].defining
        if defining in found.undetermined.get(row.k, {}):
            moved.append((row, f"its defining parameter {defining} is not determined by this record "
                               f"({found.undetermined[row.k][defining]})"))
        elif (why := unnamed_temperature(row.cand, found.findings.get(row.k, {}).get(defining))) is not None:
            moved.append((row, why))
            holding_zero.add(row.k)
    if not moved:
        return state
    gone = {row.k for row, _ in moved}
    state = replace(state, kept=tuple(row for row in state.kept if row.k not in gone),
                    uncertain=state.uncertain + tuple(
                        {"effect": row.cand.effect, "axis": AXES[row.axis], "params": row.cand.plain_params(),
                         "params_ci95": found.findings[row.k], "why": why} for row, why in moved))
    after = list(state.after)
    for i in sorted({row.axis for row, _ in moved}):
        ks = state.kept_on(i)
        after[i] = scorer.discrepancy(i, state.model(inp, i, ks), f"extended model on {AXES[i]}") if ks else inp.before[i]
        state = state.with_notes(*(
            f"{row.cand.effect} on {AXES[i]} not named, its interval holding 0: D of the axis re-scored without it, "
            f"{d_shown(state.after[i])} -> {d_shown(after[i])}; its other findings keep the parameters and intervals "
            f"fitted beside it" for row, _ in moved if row.axis == i and row.k in holding_zero))
    return replace(state, after=tuple(after))
