"""Flicker (1/f) rate noise, the ``bias_instability`` effect: a bank of Gauss-Markov processes,
the slow ones drawn at a lower rate and interpolated.

The bank (:func:`flicker_bank`) has ~15 components for a day at 100 Hz; drawing every one at
every sample costs 15 normal draws and 15 recursive filters per sample. A component whose
correlation time is many samples long has almost nothing at the sample scale, so
:class:`BiasInstability` draws it only at knots and linearly interpolates between them:

* Levels: level l has knots every S^l samples (S = :data:`KNOT_STEP`). A component of
  correlation time P = f_s T samples lives at the highest level l with P >= K S^l
  (K = :data:`KNOT_PERIODS`, level 0 when P < K S): at least K knot intervals per correlation time.
* At its knots a component is the exact AR(1) of the full-rate one, x_j = ψ x_{j-1} + q sqrt(1 - ψ²)
  w_j with ψ = φ^(S^l) = exp(-S^l / P), started stationary: its law at the knots is that of the
  full-rate component at those samples.
* A level's sum is interpolated linearly onto the next finer level's knots (every S^(l-1)
  samples), which contain its own, so a level-l component is, on the sample grid, the straight
  line between its knots S^l samples apart.

What the interpolation loses is the component's wander between its knots. The Allan variance
of the interpolated AR(1), computed exactly (``tests/test_flicker.py``'s oracle), is lower than
the full-rate component's by at most 0.19 q² S^l / P <= 0.19 q² / K at every τ, the loss peaking
near τ = S^l / f_s: with K = 32, 0.6 % of q². Near a given τ lie about 0.6 p components (p per
decade, 0.6 decade per level) of q² = 0.83 σ_B² · 2 / p each, so the loss does not grow with p: the
bank's Allan variance stays within 1 % (its deviation within 0.5 %) of the full-rate bank's at every
τ (exactly computed: at most 0.8 % for p = 1, 2, 5, 10 at 100 Hz over an hour; tested at 100 Hz and
1 kHz), and the Allan floor keeps the flatness stated in :class:`BiasInstability`.

Random streams: each component draws from its own generator, seeded from the term's ``rng``
when the term is built (one draw of as many seeds as components), so a block-by-block run equals a
one-shot run bit for bit, whatever the blocks. References: Kasdin 1995 (flicker noise as a sum of
first-order processes), Gelb, Applied Optimal Estimation, table 3.8-1 (exact AR(1) discretisation).
"""
from __future__ import annotations

import math

import numpy as np

#: Allan deviation of flicker (1/f) rate noise in its flat region, in units of B:
#: σ(τ) = sqrt(2 ln 2 / π) · B ≈ 0.664 B (IEEE Std 952-1997, eq. C.16).
FLICKER_ADEV_PER_B = math.sqrt(2.0 * math.log(2.0) / math.pi)
#: S: samples between a level's knots, in units of the next finer level's (a power of 2, so the
#: interpolation fractions are exact in binary floating point).
KNOT_STEP = 4
#: K: the least correlation time of an interpolated component, in knot intervals of its level.
KNOT_PERIODS = 32.0


def flicker_bank(b_dps, sample_rate_hz, tau_min_s, tau_max_s, per_decade=2.0):
    """Time constants and per-component std of the Gauss-Markov bank that makes 1/f noise.

    A sum of independent Gauss-Markov processes with log-spaced correlation times
    T_i = T_min r^i (ratio r = 10^(1/per_decade)) and equal variance q² has the one-sided PSD
    S(f) = Σ 4 q² T_i / (1 + (2π f T_i)²) ≈ q² / (f ln r) for 1/(2π T_max) << f << 1/(2π T_min)
    (the sum approximates ∫ dT/(T ln r)). Flicker rate noise S(f) = h₋₁ / f has the flat Allan
    variance σ² = 2 ln 2 · h₋₁ (NIST SP 1065 table 5); the gyro convention σ = 0.664 B
    (IEEE Std 952-1997 C.3: S(f) = B²/(π f) one-sided) gives h₋₁ = B²/π, so q² = B² ln r / π.

    Returns (tau_s array, q_dps). The Allan floor is flat (within a few per cent) for
    about 3 T_min < τ < T_max / 3.

    ``b_dps``: B (deg/s); ``sample_rate_hz``: f_s (Hz; not used by the bank itself);
    ``tau_min_s``, ``tau_max_s``: T_min and T_max (s), > 0; ``per_decade``: components per decade
    of T. ``tau_s`` are the T_i (s) and ``q_dps`` the std q (deg/s) of each component.
    """
    ratio = 10.0 ** (1.0 / per_decade)
    count = max(1, int(math.ceil(math.log(tau_max_s / tau_min_s) / math.log(ratio) - 1e-9)) + 1)
    taus_s = tau_min_s * ratio ** np.arange(count)
    q_dps = float(b_dps) * math.sqrt(math.log(ratio) / math.pi)
    return taus_s, q_dps


def bank_levels(periods):
    """The level of each component of correlation time ``periods`` (in samples, array): the
    highest l >= 0 with P >= K S^l (module docstring); an int array of the shape of ``periods``."""
    periods = np.asarray(periods, dtype=float)
    with np.errstate(divide="ignore"):
        lv = np.floor(np.log(np.maximum(periods / KNOT_PERIODS, 1.0)) / math.log(KNOT_STEP)).astype(int)
    # guard the rounding of the logarithm at the boundaries: P >= K S^l must hold, P >= K S^(l+1) not
    lv -= periods < KNOT_PERIODS * float(KNOT_STEP) ** lv
    lv += periods >= KNOT_PERIODS * float(KNOT_STEP) ** (lv + 1)
    return np.maximum(lv, 0)


class _Level:
    """The components of one level (knots every ``KNOT_STEP**level`` samples) and the coarser
    levels interpolated onto its knots. ``periods``: the correlation times of this level's and the
    coarser levels' components in samples of this level; ``levels``: their level relative to
    this one; ``q_dps``: q; ``seeds``: one per component."""

    def __init__(self, periods, levels, q_dps, seeds):
        here = levels == 0
        self.phis = np.exp(-1.0 / periods[here])
        self.gains = q_dps * np.sqrt(-np.expm1(-2.0 / periods[here]))  # q sqrt(1 - φ²)
        self.rngs = [np.random.default_rng(s) for s in seeds[here]]
        self.state = np.array([q_dps * g.standard_normal() for g in self.rngs])  # stationary start
        self.coarser = None
        if not here.all():
            self.coarser = _Level(periods[~here] / KNOT_STEP, levels[~here] - 1, q_dps, seeds[~here])
        self.done = 0  # knots of this level handed out so far
        self.knots = np.zeros(0)  # the coarser level's knots from index knot0 on, drawn already
        self.knot0 = 0

    def next(self, n):
        """The next ``n`` knots of this level (the sum of its components and the coarser
        levels interpolated), (n,) deg/s."""
        from scipy.signal import lfilter

        out = np.zeros(n)
        for i, rng in enumerate(self.rngs):
            y, _ = lfilter([self.gains[i]], [1.0, -self.phis[i]], rng.standard_normal(n), zi=[self.phis[i] * self.state[i]])
            if n:
                self.state[i] = y[-1]
            out += y
        if self.coarser is not None and n:
            out += self._interpolated(n)
        self.done += n
        return out

    def _interpolated(self, n):
        """The coarser level at this level's next ``n`` knots: the straight line between its knots
        (every KNOT_STEP of ours), drawing the ones still missing."""
        lo, hi = self.done, self.done + n
        first, last = lo // KNOT_STEP, (hi - 1) // KNOT_STEP + 1  # the coarse knots needed
        drawn = self.knot0 + len(self.knots)
        knots = np.concatenate([self.knots[first - self.knot0:], self.coarser.next(last + 1 - drawn)])
        idx = np.arange(lo, hi)
        j = idx // KNOT_STEP
        frac = (idx - j * KNOT_STEP) / KNOT_STEP
        left = knots[j - first]
        self.knots, self.knot0 = knots[last - 1 - first:], last - 1  # the next block starts at or after knot last - 1
        return left + (knots[j - first + 1] - left) * frac


class BiasInstability:
    """Bias instability: flicker (1/f) rate noise with the flat Allan floor σ = 0.664 B.

    Built as a bank of independent Gauss-Markov processes (see :func:`flicker_bank`):
    x[n] = Σ_i x_i[n], x_i[n] = φ_i x_i[n-1] + q sqrt(1 - φ_i²) w_i[n], φ_i = exp(-1/(f_s T_i)),
    each started stationary, the slow ones drawn at knots and interpolated (module docstring:
    the Allan variance stays within 1 % of the full-rate bank's). Memory is a few numbers per
    component, so it streams. Defaults: T_min = 1/f_s, T_max = the record length, 2 components
    per decade (the Allan floor is then flat within 1 % from ~0.2 s to T_max / 9, and within 6 %
    from 3/f_s).

    ``b_dps``: B (deg/s); ``sample_rate_hz``: f_s (Hz); ``rng``: the term's generator (seeds
    the components' own); ``tau_min_s``, ``tau_max_s``: T_min and T_max (s); ``per_decade``:
    components per decade.
    """

    def __init__(self, b_dps, sample_rate_hz, rng, tau_min_s, tau_max_s, per_decade=2.0):
        self.taus_s, self.q_dps = flicker_bank(b_dps, sample_rate_hz, tau_min_s, tau_max_s, per_decade)
        periods = sample_rate_hz * self.taus_s
        self.levels = bank_levels(periods)
        self.bank = _Level(periods, self.levels, self.q_dps, rng.integers(0, 2**63, size=len(periods)))

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see :mod:`gyrofilter.sim.noise_terms`."""
        return self.bank.next(len(t_s))
