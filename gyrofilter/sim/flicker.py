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

The components a level keeps at its own rate (5 at level 0 by default: 1 to 100 samples) are drawn
by groups as one ARMA filter with the law of their sum (:func:`sum_of_ar1_filter`): one normal draw
and one recursion per sample for the group instead of one per component.

Random streams: each filter draws from its own generator, seeded from the term's ``rng`` when the
term is built (one draw of as many seeds as components; a group uses its first component's), so a
block-by-block run equals a one-shot run bit for bit, whatever the blocks. References: Kasdin 1995 (flicker noise as a sum of
first-order processes), Gelb, Applied Optimal Estimation, table 3.8-1 (exact AR(1) discretisation).
"""
from __future__ import annotations

import math

import numpy as np

from .noise_terms import FilteredNoise

#: Allan deviation of flicker (1/f) rate noise in its flat region, in units of B:
#: σ(τ) = sqrt(2 ln 2 / π) · B ≈ 0.664 B (IEEE Std 952-1997, eq. C.16).
FLICKER_ADEV_PER_B = math.sqrt(2.0 * math.log(2.0) / math.pi)
#: S: samples between a level's knots, in units of the next finer level's (a power of 2, so the
#: interpolation fractions are exact in binary floating point).
KNOT_STEP = 4
#: K: the least correlation time of an interpolated component, in knot intervals of its level.
KNOT_PERIODS = 32.0
#: at most this many components of a level are drawn as one filter (:func:`sum_of_ar1_filter`)
GROUP = 5
#: the relative error of the joint filter's spectrum that :func:`sum_of_ar1_filter` accepts (the
#: default bank's level 0 gives 2e-6, from rounding where N(z)'s terms cancel near ω = 0; close
#: poles, e.g. 10 components per decade, fail and are drawn one by one)
SPECTRUM_RTOL = 1e-5


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


def sum_of_ar1_filter(phis, gains):
    """(b, a) of one ARMA filter whose output, driven by one unit white noise, has the law of
    Σ_i x_i, x_i[n] = φ_i x_i[n-1] + g_i w_i[n] (independent unit white w_i); None when the
    factorization below does not reproduce the spectrum to :data:`SPECTRUM_RTOL` (or a pole is below
    0.01).

    The sum's spectrum is Σ_i g_i² / |1 - φ_i z⁻¹|² = N(z) / |A(z)|², A(z) = Π_i (1 - φ_i z⁻¹) and
    N(z) = Σ_i g_i² P_i(z⁻¹) P_i(z), P_i = Π_{j≠i} (1 - φ_j z⁻¹), a symmetric Laurent polynomial of
    degree k - 1 positive on |z| = 1. Spectral factorization (Box & Jenkins, Time Series Analysis,
    sec. 4.2.3): N(z) = s² B(z⁻¹) B(z) with B(z⁻¹) = Π (1 - r_j z⁻¹) over the k - 1 roots of N
    inside the unit circle (``np.roots``, polished by two Newton steps: its eigenvalues alone missed the check by
    LAPACK build, CI 2026-12-02) and s² = N(1) / B(1)². A stationary Gaussian process is fixed by its
    spectrum, so (b, a) = (s B, A) driven by one white noise has the sum's law (its spectrum to
    :data:`SPECTRUM_RTOL`, checked on 513 frequencies): one draw and one recursion per sample instead
    of k. ``phis``, ``gains``: the φ_i and g_i (deg/s)."""
    phis, gains = np.asarray(phis, dtype=float), np.asarray(gains, dtype=float)
    k = phis.size
    if k > 1 and phis.min() < 0.01:  # T < 0.22 / f_s (T_min set far below 1/f_s): N's ends vanish
        return None
    den = np.poly(phis)
    num = np.zeros(2 * k - 1)
    for i in range(k):
        part = np.atleast_1d(np.poly(np.delete(phis, i)))  # np.poly of no roots is the scalar 1
        num += gains[i] ** 2 * np.convolve(part, part[::-1])
    roots = np.roots(num) if k > 1 else np.zeros(0)
    slope = np.polyder(num)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for _ in range(2):  # Newton steps: np.roots' eigenvalues of roots near the unit circle hold ~1e-6 (a check failed)
            roots = roots - np.polyval(num, roots) / np.polyval(slope, roots)
    inside = roots[np.abs(roots) < 1.0]
    if inside.size != k - 1:
        return None
    monic = np.atleast_1d(np.real(np.poly(inside)))
    z = np.exp(-1j * np.linspace(0.0, math.pi, 513))
    target = sum(g * g / np.abs(1.0 - p * z) ** 2 for p, g in zip(phis, gains))
    if not (np.all(np.isfinite(target)) and np.all(target > 0)):  # zero gains (B = 0): one filter per component
        return None
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        got = np.abs(np.polyval(monic[::-1], z)) ** 2 / np.abs(np.polyval(den[::-1], z)) ** 2
        got *= target[-1] / got[-1]  # s² from ω = π, where N's terms add (at ω = 0 they cancel)
        close = np.abs(got / target - 1.0) < SPECTRUM_RTOL
    if not np.all(close):
        return None
    return math.sqrt(target[-1] / (np.abs(np.polyval(monic[::-1], -1.0)) ** 2 / np.abs(np.polyval(den[::-1], -1.0)) ** 2)) * monic, den


class _Level:
    """The components of one level (knots every ``KNOT_STEP**level`` samples) and the coarser
    levels interpolated onto its knots. ``periods``: the correlation times of this level's and the
    coarser levels' components in samples of this level; ``levels``: their level relative to
    this one; ``q_dps``: q; ``seeds``: one per component.

    A level's components are drawn by groups of up to :data:`GROUP`, each group as one filter
    (:func:`sum_of_ar1_filter`; component by component where the factorization fails its check),
    each filter a :class:`~gyrofilter.sim.noise_terms.FilteredNoise` started stationary, with the
    generator of its first component's seed."""

    def __init__(self, periods, levels, q_dps, seeds):
        here = np.flatnonzero(levels == 0)
        self.filters = []
        for g0 in range(0, here.size, GROUP):
            idx = here[g0:g0 + GROUP]
            phis = np.exp(-1.0 / periods[idx])
            gains = q_dps * np.sqrt(-np.expm1(-2.0 / periods[idx]))  # q sqrt(1 - φ²)
            joint = sum_of_ar1_filter(phis, gains)
            parts = [(joint, idx[0])] if joint else [(([g], [1.0, -p]), i) for p, g, i in zip(phis, gains, idx)]
            self.filters += [FilteredNoise(b, a, np.random.default_rng(seeds[i])) for (b, a), i in parts]
        self.coarser = None
        if here.size < periods.size:
            rest = levels != 0
            self.coarser = _Level(periods[rest] / KNOT_STEP, levels[rest] - 1, q_dps, seeds[rest])
        self.done = 0  # knots of this level handed out so far
        self.knots = np.zeros(0)  # the coarser level's knots from index knot0 on, drawn already
        self.knot0 = 0

    def next(self, n):
        """The next ``n`` knots of this level (the sum of its components and the coarser
        levels interpolated), (n,) deg/s."""
        out = np.zeros(n)
        if n == 0:  # (lfilter of no samples does not hand its state back unchanged)
            return out
        for f in self.filters:
            out += f.next(range(n), None)  # FilteredNoise takes the block's length from its times
        if self.coarser is not None:
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
