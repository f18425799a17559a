"""How well a model explains the measurement: the discrepancy D of one axis extended by some
findings, from ``n_ext`` seeded runs of that model (common random numbers with the baseline's
runs), and its null spread (:mod:`gyrofilter.analysis.gap.features`).

Every step that weighs a finding scores a model through one :class:`Scorer`: it simulates each
distinct axis model once (an axis's departures depend only on that axis's model, whose random
streams are its own), so a model scored by two steps costs one set of runs.
"""
from __future__ import annotations

import copy

import numpy as np

from ...sim.model import TEMPERATURE_PROFILE
from ...units import AXES
from .baseline import sim_features, temperature_table
from .features import departures, discrepancy, discrepancy_error, null_spread


def _frozen(value):
    """A hashable copy of a model spec (dicts as sorted items, lists as tuples)."""
    if isinstance(value, dict):
        return tuple(sorted((k, _frozen(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple, np.ndarray)):
        return tuple(_frozen(v) for v in value)
    return value


class Scorer:
    """D of axis models against the measurement of a :class:`~gyrofilter.analysis.gap.state.GapInput`."""

    def __init__(self, inp):
        self.inp = inp
        self._deps = {}
        self._sims = {}

    def _key(self, i, spec, with_temperature, rows, label):
        """The cache key of a model, its runs simulated and scored the first time; ``rows``: the
        model's top-level whole-row entries (``{name: params}``: repeated rows)."""
        key = (i, _frozen(spec), with_temperature, _frozen(rows))
        if key not in self._deps:
            inp = self.inp
            model = copy.deepcopy(inp.base)
            model.update(copy.deepcopy(rows))
            model["axes"][AXES[i]] = spec
            if with_temperature:
                model[TEMPERATURE_PROFILE] = temperature_table(inp.rec, inp.temp)
            sims = sim_features(model, inp.n, inp.sample_rate_hz, inp.seeds[:inp.n_ext], [i], inp.taus, inp.bands,
                                inp.say, label)[i]
            self._deps[key] = departures(inp.meas_feats[i], sims, inp.n, (inp.deps[i], inp.n_sims))
            self._sims[key] = sims
        return key

    def departures(self, i, model, label):
        """Departures of the measured axis ``i`` from the runs of ``model`` = ``(spec,
        with_temperature, rows)`` (:meth:`gyrofilter.analysis.gap.state.GapState.model`)."""
        return self._deps[self._key(i, *model, label)]

    def discrepancy(self, i, model, label):
        return discrepancy(self.departures(i, model, label))

    def discrepancy_error(self, i, model, label):
        """The sampling error of D of ``model`` on axis ``i``, D before's where ``model`` is None
        (:func:`gyrofilter.analysis.gap.features.discrepancy_error`)."""
        inp = self.inp
        if model is None:
            return discrepancy_error(inp.meas_feats[i], inp.base_sims[i], inp.n)
        key = self._key(i, *model, label)
        return discrepancy_error(inp.meas_feats[i], self._sims[key], inp.n, (inp.deps[i], inp.n_sims))

    def null_spread(self, i, model, label):
        """The null spread of D of ``model`` (:func:`gyrofilter.analysis.gap.features.null_spread`
        of its runs; the baseline's where ``model`` is None)."""
        if model is None:
            return null_spread(self.inp.base_sims[i], self.inp.n)
        key = self._key(i, *model, label)
        return null_spread(self._sims[key], self.inp.n, (self.inp.deps[i], self.inp.n_sims))
