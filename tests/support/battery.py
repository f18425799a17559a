"""The slow tests' ten-minute hidden-effect battery, each case analysed once per test session:
the batteries that score the same cases (the intervals' coverage per kind, the heavy tails told
from spikes) share the runs instead of drawing and analysing cases of their own.

Case ``k`` hides the kind ``EFFECTS[k % len(EFFECTS)]`` (:mod:`gyrofilter.sim.hidden_effects`:
axis and parameters drawn from the seed ``SEED0 + k``) in a record of ``DURATION_S``, analysed
with ``SIMS`` baseline simulations and the default bootstrap, the analysis seeded by the case.
"""
from __future__ import annotations

import functools

import gyrofilter.sim.hidden_effects as he
from gyrofilter.analysis.gap.pipeline import analyse_gap
from gyrofilter.sim.model import validate_model

SEED0 = 7000
DURATION_S = 600.0
SIMS = 8
#: cases of each kind the slow tests score (the intervals' coverage, the rate named in tolerance)
PER_KIND = 8


@functools.lru_cache(maxsize=None)
def run(seed, effect):
    """(case, gap report) of the case drawn at ``seed`` with ``effect`` ("none": a clean record),
    analysed once per session: the caller must not change them."""
    case = he.draw_case(seed, effect=effect, duration_s=DURATION_S)
    report = analyse_gap(he.simulate_case(case), seed=case["seed"], n_sims=SIMS)
    validate_model(report["extended_model"])  # the model a gap report writes stays inside the simulator's bounds
    return case, report


def case(effect, j):
    """The battery's ``j``-th case of ``effect`` (from 0), seed ``SEED0 + k`` with
    ``k = EFFECTS.index(effect) + j * len(EFFECTS)``: its (case, gap report)."""
    return run(SEED0 + he.EFFECTS.index(effect) + j * len(he.EFFECTS), effect)


def cases(effect, n):
    """The battery's first ``n`` cases of ``effect``: a list of (case, gap report)."""
    return [case(effect, j) for j in range(n)]
