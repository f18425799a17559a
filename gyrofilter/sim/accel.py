"""The simulator's accelerometer: the specific force of a sensor at rest, per axis, in m/s^2.

The model's ``accelerometer`` object (docs/formats.md, section 2; checked by
:func:`gyrofilter.sim.model.validate_model`) gives per axis a (x, y, z) the coefficients below.
Per axis and sample n (t = n / f_s), in m/s^2:

    a[n] = s_a g + b_a + e[n] + f[n] + r[n] + c_a (T(t) - T(0))

    g = 9.80665 m/s^2 (standard gravity), s_a = +1 on the axis named by ``up``, -1 when ``up`` is
        that axis with a minus (``-z``: the board upside down), 0 on the others: at rest an
        accelerometer reads the specific force, +1 g along the direction that points up
    b_a                           turn-on bias (``bias_mps2``), constant over the run
    e[n] = N_v sqrt(f_s) w[n]     velocity random walk: white noise of density N_v
                                  (``vrw_mps_per_sqrt_s``, m/s/sqrt(s) = m/s^2/sqrt(Hz));
                                  Allan deviation σ(τ) = N_v / sqrt(τ) (IEEE Std 952-1997 C.1 for
                                  the gyro's N; IEEE Std 1293 states the same terms for accelerometers)
    f[n]                          bias instability: flicker (1/f) noise of flat Allan deviation
                                  0.664 B (B = ``b_mps2``; :class:`gyrofilter.sim.flicker.BiasInstability`,
                                  T_min = 1/f_s, T_max = the run's length, 2 components per decade)
    r[n] = r[n-1] + (K / sqrt(f_s)) w'[n], r[-1] = 0
                                  bias random walk (K = ``k_mps2_per_sqrt_s``, m/s^2/sqrt(s));
                                  σ(τ) = K sqrt(τ / 3), read at τ = 3 s (IEEE Std 952-1997 C.4)
    c_a (T(t) - T(0))             temperature coefficient (``coefficient_mps2_per_c``) on the true
                                  temperature of the model's ``temperature`` profile, T(0) its start

w, w' are independent unit normal draws, each term from its own random stream (:mod:`gyrofilter.sim.simulate`
keys the accelerometer's streams apart from the gyro's, so a model's gyro samples do not change when an
accelerometer is added). The terms are the gyro's
(:mod:`gyrofilter.sim.noise_terms`, :mod:`gyrofilter.sim.flicker`): their arithmetic has no unit, so
given m/s^2 they give m/s^2.

Then the output (:func:`accel_output`): quantization by L = ``lsb_per_g`` (LSB per g), when given,

    a ← round(a L / g) g / L

and the unit (:func:`accel_unit`): the integers round(a L / g) (``lsb``) when the gyro is written
in LSB, else m/s^2. No saturation: the model describes a sensor at rest.
"""
from __future__ import annotations

import numpy as np

from ..units import AXES, STANDARD_GRAVITY_MPS2
from .flicker import BiasInstability
from .noise_terms import Constant, RateRandomWalk, TemperatureCoefficient, WhiteNoise

#: the accelerometer's unit in a recording: LSB when the gyro is written in LSB, else m/s^2
#: (docs/formats.md, section 1: ``accel_unit``)
LSB_UNIT, MPS2_UNIT = "lsb", "m/s^2"
#: the random terms of an axis, in the order of their streams (:class:`Accelerometer`'s ``rngs``)
RANDOM_TERMS = ("vrw_mps_per_sqrt_s", "b_mps2", "k_mps2_per_sqrt_s")


def accel_unit(gyro_unit):
    """The unit the accelerometer is written in for a model whose gyro is written in ``gyro_unit``:
    ``lsb`` with ``lsb``, else ``m/s^2``."""
    return LSB_UNIT if gyro_unit == "lsb" else MPS2_UNIT


def gravity_signs(up):
    """s_a of the module docstring for ``up`` (``x``, ``y``, ``z``, or one of them with a leading
    ``-``): a (3,) array with +1 or -1 on that axis, 0 on the others."""
    signs = np.zeros(3)
    signs[AXES.index(up[-1])] = -1.0 if up.startswith("-") else 1.0
    return signs


def accel_output(a_mps2, lsb_per_g, unit):
    """The written values of the accelerations ``a_mps2`` (array, m/s^2; changed in place and
    returned): quantized to 1/``lsb_per_g`` g when ``lsb_per_g`` (LSB per g) is given, in ``unit``
    (``lsb``: round(a L / g); ``m/s^2``: round(a L / g) g / L, or a itself without L)."""
    if lsb_per_g is not None:
        np.multiply(a_mps2, lsb_per_g / STANDARD_GRAVITY_MPS2, out=a_mps2)
        np.round(a_mps2, out=a_mps2)
        if unit != LSB_UNIT:
            a_mps2 *= STANDARD_GRAVITY_MPS2 / lsb_per_g
    return a_mps2


class Accelerometer:
    """The three axes of the accelerometer of the module docstring, block by block.

    ``spec``: the validated ``accelerometer`` object (:func:`gyrofilter.sim.model.validate_model`:
    ``up``, ``lsb_per_g``, ``accel_unit`` and per axis ``bias_mps2``, ``vrw_mps_per_sqrt_s``,
    ``b_mps2``, ``k_mps2_per_sqrt_s``, ``coefficient_mps2_per_c``); ``sample_rate_hz``: f_s (Hz);
    ``duration_s``: the run's length (s; the flicker bank's longest correlation time);
    ``rngs``: per axis, one ``numpy.random.Generator`` per term of :data:`RANDOM_TERMS`;
    ``reference_c``: T(0) (deg C), or None without a temperature profile. A term whose
    coefficient is 0 is not built (it draws nothing).
    """

    def __init__(self, spec, sample_rate_hz, duration_s, rngs, reference_c):
        self.spec = spec
        self.gravity_mps2 = STANDARD_GRAVITY_MPS2 * gravity_signs(spec["up"])
        self.axes = []
        for i, axis in enumerate(AXES):
            p, (white, flicker, walk) = spec["axes"][axis], rngs[i]
            terms = [Constant(p["bias_mps2"] + self.gravity_mps2[i])]
            if p["vrw_mps_per_sqrt_s"]:
                terms.append(WhiteNoise(p["vrw_mps_per_sqrt_s"], sample_rate_hz, white))
            if p["b_mps2"]:
                tau_min_s = 1.0 / sample_rate_hz
                terms.append(BiasInstability(p["b_mps2"], sample_rate_hz, flicker, tau_min_s, max(duration_s, tau_min_s)))
            if p["k_mps2_per_sqrt_s"]:
                terms.append(RateRandomWalk(p["k_mps2_per_sqrt_s"], sample_rate_hz, walk))
            if p["coefficient_mps2_per_c"]:
                terms.append(TemperatureCoefficient(p["coefficient_mps2_per_c"], reference_c))
            self.axes.append(terms)

    def next(self, t_s, true_c):
        """The next block, (n, 3) in the model's accelerometer unit, at times ``t_s`` (s) and true
        temperatures ``true_c`` (deg C, or None without a profile)."""
        out = np.empty((len(t_s), 3))
        for i, terms in enumerate(self.axes):
            a_mps2 = terms[0].next(t_s, true_c)
            for term in terms[1:]:
                a_mps2 += term.next(t_s, true_c)
            out[:, i] = accel_output(a_mps2, self.spec["lsb_per_g"], self.spec["accel_unit"])
        return out
