"""A mechanical resonance of the board in the rate: the ``resonance`` effect (white noise through
the resonator: a steady hump of noise power) and the ``ringing`` effect (the same resonator rung
by random shocks: bursts that decay). Both follow the ``next`` protocol of
:mod:`gyrofilter.sim.noise_terms`.

The resonator is the second-order band pass H(s) = (ω₀/Q) s / (s² + (ω₀/Q) s + ω₀²) (peak gain
1 at ω₀, half-power full width ω₀ / Q), discretised by the bilinear transform prewarped
at f₀ (R. Bristow-Johnson, "Audio EQ Cookbook", band-pass with constant 0 dB peak gain):
ω = 2π f₀ / f_s, α = sin ω / (2Q),

    H(z) = (α - α z⁻²) / ((1 + α) - 2 cos ω z⁻¹ + (1 - α) z⁻²),

so the peak lies exactly at f₀ and the zeros at 0 Hz and f_s / 2 (a hump adds no power at DC,
where the white level and the slow effects are read, nor at the Nyquist frequency). Q is the
analog prototype's: the half-power frequencies f₁, f₂ satisfy
tan(π f₂ / f_s) - tan(π f₁ / f_s) = tan(π f₀ / f_s) / Q, so the width is f₀ / Q as f₀ << f_s
and narrower by the warping above (for Q = 4: 9 % at f₀ = 0.12 f_s, 25 % at 0.2 f_s;
docs/simulate.md tabulates it, tools/docs.py's block ``resonance-width``).
"""
from __future__ import annotations

import math

import numpy as np


#: log-spread of a shock's size about its median (natural-log units; as an outlier's default)
SHOCK_SPREAD_LN = 0.25
#: samples of the impulse response kept (lags, peak, energy): until it decays below 1e-9 of its peak
_RESPONSE_DECAY = 1e-9


def band_pass(center_hz, q, sample_rate_hz):
    """(b, a) of the resonator (module docstring), peak gain 1 at ``center_hz`` (a₀ = 1)."""
    w = 2.0 * math.pi * float(center_hz) / sample_rate_hz
    alpha = math.sin(w) / (2.0 * float(q))
    a0 = 1.0 + alpha
    return np.array([alpha, 0.0, -alpha]) / a0, np.array([a0, -2.0 * math.cos(w), 1.0 - alpha]) / a0


def band_pass_energy(center_hz, q, sample_rate_hz):
    """Σ h² of the resonator :func:`band_pass` (its output variance for unit white input), in closed
    form: ``α / (1 + α)``, ``α = sin(ω₀) / (2Q)``. With ``b = b₀ (1, 0, -1)``, the output is
    ``b₀ (u[n] - u[n-2])`` for the AR(2) ``u`` of the denominator (φ₁ = -a₁, φ₂ = -a₂), so
    Σ h² = 2 b₀² γ₀ (1 - ρ₂), with γ₀ = (1 - φ₂) / ((1 + φ₂)((1 - φ₂)² - φ₁²)),
    ρ₂ = φ₁² / (1 - φ₂) + φ₂ (Box, Jenkins & Reinsel, sec. 3.2.4), which reduces to α / (1 + α)
    (checked against :func:`~gyrofilter.sim.noise_terms.filter_variance`'s Lyapunov solution in
    the tests). The hump's fit evaluates it thousands of times."""
    alpha = math.sin(2.0 * math.pi * float(center_hz) / sample_rate_hz) / (2.0 * float(q))
    return alpha / (1.0 + alpha)


def resonance_filter(rms_dps, center_hz, q, sample_rate_hz):
    """(b, a) of the ``resonance`` effect for :class:`~gyrofilter.sim.noise_terms.FilteredNoise`:
    the resonator with its gain set so the stationary std is ``rms_dps`` (:func:`band_pass_energy`,
    Σ h² of the unit resonator)."""
    b, a = band_pass(center_hz, q, sample_rate_hz)
    return b * (float(rms_dps) / math.sqrt(band_pass_energy(center_hz, q, sample_rate_hz))), a


def impulse_response(center_hz, q, sample_rate_hz):
    """The resonator's impulse response h[n] until its envelope exp(-π f₀ n / (Q f_s)) falls
    below :data:`_RESPONSE_DECAY` (at most 2^20 samples)."""
    from scipy.signal import lfilter

    decay = math.pi * center_hz / (q * sample_rate_hz)  # per sample
    n = int(min(1 << 20, max(16, math.ceil(-math.log(_RESPONSE_DECAY) / decay))))
    b, a = band_pass(center_hz, q, sample_rate_hz)
    return lfilter(b, a, np.r_[1.0, np.zeros(n - 1)])


def resonance_lags(center_hz, q, sample_rate_hz):
    """Lag-1 and lag-2 autocorrelations of the resonator's output for white input (of the
    ``resonance`` and, shocks being white, of the ``ringing`` effect): r_k = Σ h[n] h[n+k] / Σ h²."""
    h = impulse_response(center_hz, q, sample_rate_hz)
    e = float(np.dot(h, h))
    return float(np.dot(h[1:], h[:-1])) / e, float(np.dot(h[2:], h[:-2])) / e


def ringing_gain(center_hz, q, sample_rate_hz):
    """(g, Σ (g h)²): the gain g that makes a unit shock's ring peak at 1 (g = 1 / max |h|) and the
    energy of that ring, so a shock of size s rings with peak |s|."""
    h = impulse_response(center_hz, q, sample_rate_hz)
    g = 1.0 / float(np.max(np.abs(h)))
    return g, g * g * float(np.dot(h, h))


def ringing_variance(shock_rate_hz, shock_dps, center_hz, q, sample_rate_hz, spread_ln=SHOCK_SPREAD_LN):
    """Stationary variance of the ``ringing`` effect ((deg/s)²): shocks at p = ``shock_rate_hz`` / f_s
    per sample (a Bernoulli approximation of the Poisson process), E s² = m² exp(2 σ²) for the
    log-normal size of median m, each ringing with energy Σ (g h)² (:func:`ringing_gain`):
    p m² exp(2σ²) Σ (g h)² (Campbell's theorem for a shot noise)."""
    p = min(float(shock_rate_hz) / sample_rate_hz, 1.0)
    return p * float(shock_dps) ** 2 * math.exp(2.0 * spread_ln**2) * ringing_gain(center_hz, q, sample_rate_hz)[1]


class Ringing:
    """The ``ringing`` effect: the resonator rung by random shocks, y = g H(z) u.

    Each sample independently carries a shock with probability p = ``shock_rate_hz`` / f_s (a
    Poisson process of that rate, sampled); a shock is s · m · exp(σ_ln z) with s = ±1 equally
    likely, z ~ N(0, 1) (a log-normal size of median m = ``shock_dps``, as an outlier's,
    :class:`~gyrofilter.sim.noise_terms.Outliers`); u is the shocks' train, and the ring of a shock
    of size s peaks at |s| (g of :func:`ringing_gain`), decaying with the time constant
    Q / (π f₀). Streams block by block with the lfilter state.

    ``rng_where``: generator of the shock times, ``rng_size``: of their signs and sizes.
    """

    def __init__(self, shock_rate_hz, shock_dps, center_hz, q, sample_rate_hz, rng_where, rng_size,
                 spread_ln=SHOCK_SPREAD_LN):
        self.p = min(float(shock_rate_hz) / sample_rate_hz, 1.0)
        self.m, self.spread = float(shock_dps), float(spread_ln)
        self.b, self.a = band_pass(center_hz, q, sample_rate_hz)
        self.b = self.b * ringing_gain(center_hz, q, sample_rate_hz)[0]
        self.rng_where, self.rng_size = rng_where, rng_size
        self.state = np.zeros(2)

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the class docstring."""
        from scipy.signal import lfilter

        u = np.zeros(len(t_s))
        hit = np.flatnonzero(self.rng_where.random(len(t_s)) < self.p)
        if hit.size:
            draws = self.rng_size.standard_normal((hit.size, 2))
            u[hit] = np.where(draws[:, 0] < 0.0, -1.0, 1.0) * self.m * np.exp(self.spread * draws[:, 1])
        y, self.state = lfilter(self.b, self.a, u, zi=self.state)
        return y
