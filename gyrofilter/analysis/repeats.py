"""Repeated rows: how many rows of a quantized record repeat the previous row exactly on all three
axes, and how many would by chance at the record's quantization (issue 36).

A driver that polls a sensor faster than the sensor updates its output registers reads the same
registers twice: the row repeats the previous one on every axis (an MPU6050 polled without its
data-ready flag or FIFO). A repeat makes its difference zero, so the Allan variance at the
shortest tau reads (1 - f) of the noise's (the deviation about f/2 low), while a repeated sample
weighs twice in every longer average (the fitted white level N reads a little high: +0.8 % at
f = 2 %, +2.1 % at 5 %, 43 Hz records of 16 min, examples/models/repeated_samples.json). On a quantized record rows also
repeat by chance, when every axis's successive difference happens to be 0 LSB; this module
tells the two apart. The one home of the count: ``allan``, ``report`` and the gap detector
(:mod:`gyrofilter.analysis.gap.detectors.repeats`) use :func:`repeated_rows`.

The rule, per axis a, on the successive differences in steps (LSB) k_a[n] = (x_a[n] - x_a[n-1]) / q_a:

- The chance of a zero difference, p0_a = P(k_a = 0) without repeats, is read off the neighbouring
  differences: a still gyro's difference is white noise of variance 2 σ² (plus the quantization's
  q²/6), whose distribution at the integers is a sampled Gaussian, log c_j = A - B j² for the
  count c_j of |k| = j (the two signs averaged). A and B are fitted by weighted least squares on
  j = 1, 2, 3 (weights 2 c_j, the inverse variance of log c_j of a Poisson count), and
  p0_a = exp(A) / M with M = N - 1 differences. Repeats add to c_0 only, so p0_a is the chance
  level without them; var(log p0_a) = var(A) of the fit. The parabola holds at 0 only where the
  differences spread at least :data:`MIN_DIFF_SD_STEPS` steps (sqrt(1 / 2B)); nearer the step
  the count is "not applicable".
- Axes independent, a row equals the previous one by chance with p_chance = Π_a p0_a, and
  var(log p_chance) = Σ_a var(A_a).
- The count K of rows whose k_a = 0 on every axis is Binomial(M, p_chance) without repeats. With
  repeats at a fraction f, P(row equal) = f + (1 - f) p_chance, so
  f̂ = (K / M - p_chance) / (1 - p_chance) (the excess fraction), its 95 % interval from the
  Wilson interval of K / M and p_chance's (exp(±1.96 sd of log p_chance)), clipped at 0.
- The test: the binomial upper tail P(K' >= K) with K' ~ Binomial(M, p_test), p_test =
  p_chance · exp(2 sd(log p_chance)): the chance level's upper bound, so that the error of its
  estimate does not count as repeats (a one-sided binomial test against the chance level).

The quantization q_a: 1 / ``lsb_per_dps`` where the record gives it (``gyro_unit`` lsb), else the
step of the grid the values sit on (:func:`grid_step`); on a record off any grid the count says
nothing ("not applicable").
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..sim.hidden_effects import wilson
from ..units import AXES

#: fewest differences an axis needs at |k| = 1 and at |k| = 2 for the chance level
MIN_NEIGHBOUR_COUNT = 20
#: above this chance of an equal row the noise sits below the step: repeats cannot be told from chance
MAX_CHANCE = 0.25
#: least sd (in steps) of an axis's differences, as the fit's parabola gives it (sqrt(1 / 2B)), for
#: the sampled Gaussian to hold at 0: nearer the step the rounding makes its zero count far above
#: the parabola's (issue 37, attack 4: clean records of white noise of 0.3-0.62 LSB, means anywhere
#: on the step, 60000 rows, read an excess at p < 0.001 in up to half of them; 0 of 60 at 0.65, 0.7,
#: 0.8 and 1.0 LSB; the differences' sd is about sqrt(2 sigma^2 + 1/6), 1.0 at 0.65 LSB)
MIN_DIFF_SD_STEPS = 1.1
#: a grid: this share of the non-zero differences within GRID_TOLERANCE steps of a whole number of steps
GRID_SHARE = 0.999
GRID_TOLERANCE = 1e-3
#: the standard normal quantile of the 95 % intervals, and the width (sd of log p_chance) of the test's chance bound
Z95 = 1.96
CHANCE_BOUND_SD = 2.0


@dataclass(frozen=True)
class RepeatedRows:
    """The count of repeated rows of a record and its chance level (module docstring).

    ``applicable`` False: ``why`` says why (no grid, too few rows, noise below the step) and the
    numbers are None."""

    applicable: bool
    why: str = ""
    #: rows compared (N - 1) and rows equal to the previous one on every axis
    rows: int = 0
    repeated: int = 0
    #: K / M, the chance level p_chance and its 95 % interval
    fraction: float | None = None
    chance: float | None = None
    chance_ci95: tuple | None = None
    #: the excess fraction f̂ and its 95 % interval
    excess: float | None = None
    excess_ci95: tuple | None = None
    #: the one-sided binomial test's p-value
    p_value: float | None = None
    #: axis letter -> the step q_a (deg/s)
    step_dps: dict | None = None

    def more_than_chance(self, alpha):
        """Whether the record holds more repeated rows than chance at level ``alpha``."""
        return self.applicable and self.p_value < alpha

    def as_dict(self):
        """The JSON block (docs/formats.md, ``repeated_rows``): finite numbers or null."""
        if not self.applicable:
            return {"applicable": False, "why": self.why}
        return {"applicable": True, "rows": self.rows, "repeated": self.repeated, "fraction": self.fraction,
                "chance": self.chance, "chance_ci95": list(self.chance_ci95), "excess_fraction": self.excess,
                "excess_fraction_ci95": list(self.excess_ci95), "p_value": self.p_value,
                "step_dps": dict(self.step_dps)}


def grid_step(x_dps):
    """The step (deg/s) of the grid the values ``x_dps`` sit on, or None: the smallest non-zero
    |difference| of successive values, accepted where :data:`GRID_SHARE` of the non-zero
    differences are whole multiples of it (within :data:`GRID_TOLERANCE` of a step)."""
    d = np.abs(np.diff(np.asarray(x_dps, dtype=float)))
    d = d[d > 0]
    if d.size == 0:
        return None
    step = float(d.min())
    ratio = d / step
    if np.mean(np.abs(ratio - np.round(ratio)) <= GRID_TOLERANCE) < GRID_SHARE:
        return None
    return step


def _zero_chance(a):
    """``(log p0, var(log p0), sd)`` of one axis's absolute differences in steps ``a`` (whole
    numbers, floats; module docstring; ``sd`` = sqrt(1 / 2B), the spread of the fitted sampled
    Gaussian in steps, inf for B <= 0), or None when the counts at |k| = 1, 2 are below
    :data:`MIN_NEIGHBOUR_COUNT`."""
    counts = np.array([np.count_nonzero(a == j) / 2.0 for j in (1, 2, 3)])
    if counts[0] < MIN_NEIGHBOUR_COUNT or counts[1] < MIN_NEIGHBOUR_COUNT:
        return None
    use = counts > 0
    j2 = np.array([1.0, 4.0, 9.0])[use]
    w = 2.0 * counts[use]
    design = np.column_stack([np.ones(j2.size), -j2])
    normal = design.T @ (w[:, None] * design)
    cov = np.linalg.inv(normal)
    coef = cov @ (design.T @ (w * np.log(counts[use])))
    sd = math.sqrt(0.5 / coef[1]) if coef[1] > 0 else math.inf
    return float(coef[0]) - math.log(a.size), float(cov[0, 0]), sd


def binomial_upper_tail(k, m, p):
    """P(K >= k) for K ~ Binomial(m, p), summed in logs from k up to where the terms vanish (no
    scipy: ``allan`` and ``gap`` run on a core install). Exact up to float rounding."""
    if k <= 0:
        return 1.0
    if p <= 0.0:
        return 0.0
    if p >= 1.0:
        return 1.0
    mean, sd = m * p, math.sqrt(m * p * (1 - p))
    top = int(min(m, max(k, mean) + 40 * sd + 50))
    j = np.arange(k, top + 1, dtype=float)
    log_first = math.lgamma(m + 1) - math.lgamma(k + 1) - math.lgamma(m - k + 1) + k * math.log(p) + (m - k) * math.log1p(-p)
    steps = np.log((m - j[:-1]) / (j[:-1] + 1)) + math.log(p) - math.log1p(-p)
    logs = log_first + np.concatenate([[0.0], np.cumsum(steps)])
    return float(min(1.0, np.exp(logs).sum()))


def repeated_rows(gyro_dps, step_dps=None, axes=AXES):
    """The repeated rows of ``gyro_dps`` ((N, k) deg/s, or an iterable of k columns of N: the axes
    ``axes``) against their chance level (module docstring). ``step_dps``: the quantization step
    (deg/s, 1 / lsb_per_dps) when the record states it; None: each axis's grid (:func:`grid_step`).
    Returns a :class:`RepeatedRows`. Memory: one column and its differences at a time (a generator
    of columns is read one at a time: a day at 100 Hz in deg/s is 69 MB a column)."""
    with np.errstate(all="ignore"):  # values too large for float64 differences sit on no grid
        return _count(gyro_dps, step_dps, axes)


def _count(gyro_dps, step_dps, axes):
    """:func:`repeated_rows`'s work."""
    columns = (gyro_dps[:, i] for i in range(gyro_dps.shape[1])) if isinstance(gyro_dps, np.ndarray) else gyro_dps
    columns = iter(columns)
    equal, log_p, var_log, steps = None, 0.0, 0.0, []
    for a in axes:  # not zip(axes, columns): zip's reused result tuple would keep each column alive past its del
        x = next(columns, None)
        if x is None:
            break
        if equal is None:
            if len(x) < 3:
                return RepeatedRows(False, "too few rows")
            m = len(x) - 1
            equal = np.ones(m, dtype=bool)
        step = step_dps if step_dps else grid_step(x)
        if step is None:
            return RepeatedRows(False, f"the values of axis {a} sit on no grid (not quantized, or constant)")
        k = np.diff(np.asarray(x, dtype=float))
        del x
        k /= step
        np.rint(k, out=k)  # the differences in whole steps
        equal &= k == 0
        fit = _zero_chance(np.abs(k, out=k))
        if fit is None:
            return RepeatedRows(False, f"axis {a}: too few differences of 1 and 2 steps for the chance level "
                                       f"(the record is short, or its noise is far below or far above the step)")
        if fit[2] < MIN_DIFF_SD_STEPS:
            return RepeatedRows(False, f"axis {a}: its differences spread {fit[2]:.2g} steps (sd), below "
                                       f"{MIN_DIFF_SD_STEPS:g}: the noise sits too near the step for the chance level "
                                       "(rounding makes equal rows commoner than a sampled Gaussian says)")
        log_p, var_log = log_p + fit[0], var_log + fit[1]
        steps.append(float(step))
        del k
    if equal is None:
        return RepeatedRows(False, "too few rows")
    chance = math.exp(log_p)
    if chance > MAX_CHANCE:
        return RepeatedRows(False, f"a row equals the previous one by chance {chance:.0%} of the time: the noise sits "
                                   "below the step, repeats cannot be told from chance")
    repeated = int(np.count_nonzero(equal))
    sd = math.sqrt(var_log)
    chance_ci = (chance * math.exp(-Z95 * sd), min(1.0, chance * math.exp(Z95 * sd)))
    lo, hi = wilson(repeated, m)
    excess_ci = (max(0.0, (lo - chance_ci[1]) / (1 - chance_ci[1])) if chance_ci[1] < 1 else 0.0,
                 max(0.0, (hi - chance_ci[0]) / (1 - chance_ci[0])))
    return RepeatedRows(True, rows=m, repeated=repeated, fraction=repeated / m, chance=chance, chance_ci95=chance_ci,
                        excess=max(0.0, (repeated / m - chance) / (1 - chance)), excess_ci95=excess_ci,
                        p_value=binomial_upper_tail(repeated, m, min(1.0, chance * math.exp(CHANCE_BOUND_SD * sd))),
                        step_dps=dict(zip(axes, steps)))
