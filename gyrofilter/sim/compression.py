"""The ``compression`` effect: a cubic compression of an axis's fast terms about its slow level.

Per axis, with e[n] the sum of the fast terms (the white or colored noise with its heavy tails,
an ARMA process, and the lines: sinusoid, narrow band, resonance, ringing, wandering tone) and
l[n] the slow level (the bias and the slow terms: the wanders, the shapes in time, the
temperature; :data:`gyrofilter.effects.SLOW`):

    ω[n] = l[n] + g · c(e[n]),   c(e) = e - γ e³ for |e| <= e_max,   c(±e_max) beyond,
    e_max = 1 / sqrt(3 γ),       g = 1 / sqrt(1 - 6 κ + 15 κ²),   κ = γ σ²

(γ = ``gamma_per_dps2`` in (deg/s)⁻², σ = ``rms_dps``, the stated rms of e). The transfer is odd
and saturating, as a sensing chain that compresses large excursions; beyond e_max, where the cubic
would turn back, it holds its peak (a monotone transfer). g keeps the variance of a Gaussian e of
rms σ: E (e - γ e³)² = σ² (1 - 6 κ + 15 κ²), so the spectrum moves only by O(γ²) while the
distribution is lightened (excess kurtosis about -24 κ) and the bands are locked in phase
(intermodulation: the products of the terms' frequencies; docs/gap.md, "What lightens the z axes'
tails", measured the cause on the ADIS16405 z axes with the same cubic, ``tools/tails_cause.py``).
g is fixed by the stated σ, not by the run's own variance, so the map is the same sample by
sample and a run cut into chunks equals the one-shot run bit for bit. The model's validation
keeps κ <= :data:`MAX_COMPRESSION` (e_max at 3.3 σ or more: the cut touches 1e-3 of a Gaussian's
samples at most, so g holds).

**Why the fast terms about the slow level**: the compression acts on the vibration and the noise
about the sensor's operating point; the bias and its slow wander move that point, they are not
what is compressed (a cubic of the whole rate would turn a bias into a change of gain and let
the slow wander modulate the fast terms' distribution). Isolated ``outliers`` are added after the
compression (spikes on top, e.g. of the bus, not through the sensing chain: a cubic would fold
them at e_max), and saturation and quantization act on the sum, as without it.
"""
from __future__ import annotations

import math

import numpy as np

#: the largest κ = γ σ² a model takes (:func:`gyrofilter.sim.model.validate_model`): the cubic's
#: turning point e_max = σ / sqrt(3 κ) at 3.3 σ or more
MAX_COMPRESSION = 0.03


def compression_kappa(gamma_per_dps2, rms_dps):
    """κ = γ σ² (module docstring), as the model's validation holds it to :data:`MAX_COMPRESSION`."""
    return float(gamma_per_dps2) * float(rms_dps) ** 2


#: the relative rounding of κ = γ σ² within which it is taken as at the bound: 3 (deg/s)⁻² at 0.1 deg/s
#: is κ = 0.030000000000000002 in floats, the documented 0.03 for whoever wrote it
_KAPPA_ROUNDING = 1e-12


def compression_too_strong(gamma_per_dps2, rms_dps):
    """True when κ = :func:`compression_kappa` exceeds :data:`MAX_COMPRESSION` by more than the
    rounding of its product (:data:`_KAPPA_ROUNDING`): the one test of the bound."""
    return compression_kappa(gamma_per_dps2, rms_dps) > MAX_COMPRESSION * (1.0 + _KAPPA_ROUNDING)


def max_gamma_per_dps2(rms_dps):
    """The largest γ ((deg/s)⁻²) a model takes at σ = ``rms_dps``: MAX_COMPRESSION / σ², whose γ σ² is
    within a few ulps of the bound, inside :func:`compression_too_strong`'s rounding slack."""
    return MAX_COMPRESSION / float(rms_dps) ** 2


def compression_gain(gamma_per_dps2, rms_dps):
    """g = 1 / sqrt(1 - 6 κ + 15 κ²), κ = γ σ²: the gain that keeps the variance of a Gaussian
    of rms σ through e - γ e³ (module docstring)."""
    kappa = compression_kappa(gamma_per_dps2, rms_dps)
    return 1.0 / math.sqrt(1.0 - 6.0 * kappa + 15.0 * kappa * kappa)


class Compression:
    """The map of the module docstring, applied in place to a block of the fast terms' sum.

    ``gamma_per_dps2``: γ ((deg/s)⁻², >= 0; 0 leaves e unchanged but for g = 1);
    ``rms_dps``: σ (deg/s, > 0), the stated rms of e that fixes g."""

    def __init__(self, gamma_per_dps2, rms_dps):
        self.gamma = float(gamma_per_dps2)
        self.gain = compression_gain(gamma_per_dps2, rms_dps)
        self.limit_dps = 1.0 / math.sqrt(3.0 * self.gamma) if self.gamma > 0.0 else math.inf

    def apply(self, e):
        """``e`` (deg/s, this block's own array) replaced by g c(e); returns it."""
        if self.gamma > 0.0:
            np.clip(e, -self.limit_dps, self.limit_dps, out=e)
            e -= self.gamma * e ** 3
        e *= self.gain
        return e
