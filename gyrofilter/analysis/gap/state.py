"""What the gap analysis's steps read and what they decide (:mod:`gyrofilter.analysis.gap.pipeline`
runs them in order).

- :class:`GapInput` (steps 1 and 2, fixed before the first decision): the record, the baseline
  model, the features of the measurement and their departures from the baseline's runs, the
  seeds of every simulation.
- :class:`GapState` (steps 3 to 5): the candidates found so far, which are excluded, which are
  kept with their gain, which are set aside as uncertain, the models each axis's candidates
  extend (:class:`AxisModels`) and the notes. A step takes a state and returns a new one (:func:`dataclasses.replace`); it changes
  neither the state it was given nor a candidate in it (a candidate that changes is replaced).
- :meth:`GapState.model`: the extended model of an axis with some of its candidates, the one
  thing every step scores (:class:`gyrofilter.analysis.gap.scoring.Scorer`).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable, NamedTuple

import numpy as np

from ...effects import COLORED_NOISE, TEMPERATURE
from ...recording import Recording
from ...units import AXES
from .baseline import effect_entry, start_bias, white_less_wanders
from .detectors import Candidate


@dataclass(frozen=True)
class GapInput:
    """The record and its baseline, fixed before the first decision (steps 1 and 2)."""

    rec: Recording
    sample_rate_hz: float
    #: samples per axis
    n: int
    #: the record's temperature (deg C) per sample, or None (none recorded, or not finite)
    temp: np.ndarray | None
    #: the baseline model (:func:`gyrofilter.analysis.gap.baseline.baseline_model`)
    base: dict
    #: the recorded unit's step in deg/s (an LSB), or None
    q: float | None
    #: the features' tau (s) and band edges (Hz)
    taus: np.ndarray
    bands: np.ndarray
    #: the baseline's simulations and their seeds; the extended models use the first ``n_ext``
    n_sims: int
    seeds: np.ndarray
    n_ext: int
    #: per axis: the measurement's features, their departures from the baseline's runs, D before
    meas_feats: list
    deps: list
    before: list
    #: per axis: the features of the baseline's runs (D before's sampling error, its null spread)
    base_sims: list
    #: the record's repeated rows: ``(the count, a repeated_samples Candidate or None)``
    #: (:func:`gyrofilter.analysis.gap.detectors.repeats.detect_repeats`)
    repeats: tuple
    #: axis letter -> why it has nothing to analyse (a constant signal, noise below float64's reach):
    #: no detector runs on it and its D enters no overall figure
    idle: dict
    #: progress lines
    say: Callable[[str], None]


@dataclass(frozen=True)
class AxisModels:
    """The axis specs an axis's candidates extend (the baseline's bias and white noise re-fitted
    on the series cleaned of the findings, before the findings themselves)."""

    #: the detectors' reading (the time reading's where that is chosen over a temperature)
    ext: dict
    #: the other reading of a confounded temperature (:mod:`gyrofilter.analysis.gap.confound`)
    other: dict | None = None
    #: the composite stochastic fit's white level (:mod:`gyrofilter.analysis.gap.composite`)
    composite: dict | None = None
    #: the colored noise's lags re-solved for a composite model, or None
    lags: dict | None = None
    #: the Haar wavelet variance of the cleaned series at the composite's scales, or None
    wv: object = None
    #: a colored noise measured below the detector's threshold, for the late step
    #: (:mod:`gyrofilter.analysis.gap.late_colored`), or None
    reserve: object = None


@dataclass(frozen=True)
class OtherReading:
    """The two readings of a confounded temperature on one axis (:mod:`gyrofilter.analysis.gap.confound`):
    the indices of the candidates of the reading the detector returned (``first``: the covariate
    reading, or the time reading where it is the simpler), the other reading's candidates (not yet
    in the state), its axis spec and wavelet variance."""

    first: list
    other: list
    ext_axis: dict
    wv: object


class Kept(NamedTuple):
    """A kept finding: its index among the candidates, its axis, the candidate, and D of the axis
    extended by it alone."""

    k: int
    axis: int
    cand: Candidate
    after: float


@dataclass(frozen=True)
class GapState:
    """What the steps have decided (module docstring)."""

    #: (axis index, candidate), in the order found; an index into it names a candidate
    candidates: tuple = ()
    #: the models of each axis
    axes: tuple = ()
    #: axis index -> its :class:`OtherReading`
    readings: dict = field(default_factory=dict)
    #: indices of the candidates of a reading not chosen
    excluded: frozenset = frozenset()
    #: the kept findings (:class:`Kept`), in the report's order
    kept: tuple = ()
    #: candidate index -> D of its axis extended by it alone
    single: dict = field(default_factory=dict)
    #: D per axis after extension by its kept findings
    after: tuple = ()
    notes: tuple = ()
    #: the report's ``uncertain`` entries (dicts: effect, axis, params, why, params_ci95 where known):
    #: effects the record suggests but does not establish, none of them in ``kept``
    uncertain: tuple = ()
    #: the kept whole-row finding (:func:`gyrofilter.analysis.gap.rows.weigh_repeats`): its
    #: :class:`RowsFinding`, or None; every model scored after it carries its top-level entry
    rows: object = None

    def with_notes(self, *notes):
        return replace(self, notes=self.notes + tuple(notes))

    def with_candidate(self, k, cand):
        """The state with candidate ``k`` replaced by ``cand`` (the kept rows follow)."""
        candidates = list(self.candidates)
        candidates[k] = (candidates[k][0], cand)
        kept = tuple(row._replace(cand=cand) if row.k == k else row for row in self.kept)
        return replace(self, candidates=tuple(candidates), kept=kept)

    def with_axis(self, i, **changes):
        axes = list(self.axes)
        axes[i] = replace(axes[i], **changes)
        return replace(self, axes=tuple(axes))

    def on_axis(self, i):
        """Indices of the candidates of axis ``i`` that are not excluded."""
        return [k for k, (ci, _) in enumerate(self.candidates) if ci == i and k not in self.excluded]

    def kept_on(self, i):
        """Indices of the kept findings of axis ``i``, in the report's order."""
        return [row.k for row in self.kept if row.axis == i]

    def spec(self, inp, i, ks):
        """Axis ``i``'s spec extended by the candidates ``ks`` (the composite's white level, its
        re-solved lags and ``preserve: arw`` when one of them belongs to a composite model; the
        other reading's spec when one belongs to it)."""
        models = self.axes[i]
        cands = [self.candidates[k][1] for k in ks]
        composite = any(c.composite for c in cands)
        other_reading = any(c.reading == "other" for c in cands)
        spec = dict(models.composite if composite else models.other if other_reading else models.ext)
        spec["bias_dps"] = start_bias(spec["bias_dps"], cands, inp.n / inp.sample_rate_hz)
        spec["effects"] = [effect_entry(c, preserve="arw" if composite else "std") for c in cands]
        if not composite:  # the white level was measured with the wanders' high-frequency part in it
            colored = next((c for ci, c in self.candidates if ci == i and c.effect == COLORED_NOISE), None)
            spec["arw_dps_per_sqrt_hz"] = white_less_wanders(spec["arw_dps_per_sqrt_hz"], spec["effects"], colored,
                                                             inp.n, inp.sample_rate_hz)
        if composite and models.lags:
            for entry in spec["effects"]:
                if entry["effect"] == COLORED_NOISE:
                    entry.update(models.lags)
        return spec

    def model(self, inp, i, ks):
        """``(spec, with_temperature, rows)``: axis ``i`` extended by the candidates ``ks`` in the
        order scored (sorted), whether it needs the record's temperature profile, and the kept
        whole-row entries (``{name: params}``, empty before :attr:`rows`)."""
        ks = sorted(ks)
        return (self.spec(inp, i, ks), any(self.candidates[k][1].effect == TEMPERATURE for k in ks),
                self.rows.entry if self.rows is not None else {})

    def extended(self, inp, i):
        """Axis ``i``'s extended model as the report gives it: its kept findings and the kept
        whole-row entries (:meth:`model`), the baseline's axis with those entries where it has no
        finding of its own, None where it is the baseline itself."""
        ks = self.kept_on(i)
        if ks:
            return self.model(inp, i, ks)
        if self.rows is not None:
            return dict(inp.base["axes"][AXES[i]]), False, self.rows.entry
        return None


class RowsFinding(NamedTuple):
    """A kept whole-row finding: the candidate, the count it came from
    (:class:`gyrofilter.analysis.repeats.RepeatedRows`), its top-level model entry
    (``{name: params}``) and the mean D over the analysed axes before and after it."""

    cand: Candidate
    counted: object
    entry: dict
    before: float
    after: float

