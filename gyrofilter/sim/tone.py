"""The ``wandering_tone`` term of the simulator: a vibration of constant amplitude whose frequency
wanders within a band (a motor or fan whose speed drifts; issue 36, the ADIS16405 z axes).

A term of the ``next`` protocol of :mod:`gyrofilter.sim.noise_terms` (its own module: that one
is full). Per sample n, in deg/s:

    x[n] = A sin(ψ[n]),   ψ[n+1] = ψ[n] + 2π f[n] / f_s,   f[n] = f_c + σ_f u[n],
    u[n] = φ u[n-1] + sqrt(1 - φ²) w[n],   φ = exp(-1 / (f_s T))

with ``amplitude_dps`` A, ``center_hz`` f_c, ``spread_hz`` σ_f (the standard deviation of the
instantaneous frequency) and ``wander_s`` T (the correlation time of its wander: u is a
unit-variance Gauss-Markov process, the exact discretisation of an Ornstein-Uhlenbeck process;
Gelb, Applied Optimal Estimation, table 3.8-1). u[-1] ~ N(0, 1) (stationary) and ψ[0] ~ U(0, 2π)
are the term's first draws. ψ is summed sample by sample, never wrapped (a run cut into chunks
equals the one-shot run bit for bit; after a day at 1 kHz of a 400-Hz tone ψ is about 2e8 rad, whose
rounding is 4e-8 rad). The rate's variance is A² / 2 whatever the wander, and its values
follow the arcsine law of a sine (excess kurtosis -3/2), unlike the Gaussian ``narrowband``
(excess kurtosis 0) of the same spectrum. Where σ_f T ≫ 1 (a slow wander) the spectrum is the
distribution of f[n]: a Gaussian line of standard deviation σ_f around f_c; σ_f = 0 is a
sinusoid of random phase.

The frequency may also carry a **periodic excursion** (a source whose speed is disturbed at a
fixed period on top of its slow wander: the ADIS16405's z axes, docs/gap.md "What the tone's
model does not yet hold"): with ``excursion_hz`` h > 0, ``excursion_period_s`` P and
``excursion_s`` D (0 < D < P),

    f[n] = f_c + σ_f u[n] + h · [((n / f_s + t_0) mod P) < D],   t_0 ~ U(0, P),

a step up by h for D seconds every P seconds, the cycle's phase t_0 drawn from the term's
second stream (``excursion_rng``), so that a tone without excursion (h = 0, the default) draws
and adds nothing: the term of before, bit for bit. The tone's variance stays A² / 2 and its
arcsine law; its spectrum gains a copy of the line h higher, of share D / P, and the power
beside the line comes and goes with the period P.
"""
from __future__ import annotations

import math

import numpy as np


class WanderingTone:
    """The ``wandering_tone`` term (module docstring). ``amplitude_dps``: A (deg/s);
    ``center_hz``: f_c (Hz); ``spread_hz``: σ_f (Hz); ``wander_s``: T (s), > 0;
    ``sample_rate_hz``: f_s (Hz); ``rng``: the term's generator; ``excursion_hz`` h (Hz),
    ``excursion_period_s`` P (s), ``excursion_s`` D (s) and ``excursion_rng`` (the generator of
    the cycle's phase): the periodic excursion (module docstring), none where h is 0."""

    def __init__(self, amplitude_dps, center_hz, spread_hz, wander_s, sample_rate_hz, rng,
                 excursion_hz=0.0, excursion_period_s=None, excursion_s=None, excursion_rng=None):
        self.a, self.center_hz, self.spread_hz = float(amplitude_dps), float(center_hz), float(spread_hz)
        self.sample_rate_hz = float(sample_rate_hz)
        self.phi = math.exp(-1.0 / (self.sample_rate_hz * float(wander_s)))
        self.rng = rng
        self.u = self.psi = None
        self.excursion_hz = float(excursion_hz or 0.0)
        self.excursion_period_s, self.excursion_s = excursion_period_s, excursion_s
        self.excursion_rng = excursion_rng
        self.t0_s = None
        self.count = 0  # samples drawn so far: the excursion's clock, n

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        if self.u is None:
            self.u = self.rng.standard_normal()
            self.psi = self.rng.uniform(0.0, 2.0 * math.pi)
        from scipy.signal import lfilter

        w = self.rng.standard_normal(len(t_s))
        u, _ = lfilter([math.sqrt(1.0 - self.phi ** 2)], [1.0, -self.phi], w, zi=[self.phi * self.u])
        if len(t_s):
            self.u = float(u[-1])
        freq_hz = self.center_hz + self.spread_hz * u
        if self.excursion_hz > 0.0:
            freq_hz = freq_hz + self.excursion_hz * self.in_excursion(len(t_s))
        step = (2.0 * math.pi / self.sample_rate_hz) * freq_hz
        ends, _ = lfilter([1.0], [1.0, -1.0], step, zi=[self.psi])  # ψ[n+1], summed sample by sample
        psi = np.concatenate(([self.psi], ends[:-1]))
        if len(t_s):
            self.psi = float(ends[-1])
        return self.a * np.sin(psi)

    def in_excursion(self, n):
        """Whether each of the next ``n`` samples is in the excursion, ((k / f_s + t_0) mod P) < D
        for their indices k (module docstring); advances the term's clock."""
        if self.t0_s is None:
            self.t0_s = self.excursion_rng.uniform(0.0, self.excursion_period_s)
        k = np.arange(self.count, self.count + n)
        self.count += n
        return np.mod(k / self.sample_rate_hz + self.t0_s, self.excursion_period_s) < self.excursion_s
