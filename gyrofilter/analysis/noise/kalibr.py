"""Kalibr's IMU noise model and the white + random-walk pair that bounds a measured Allan deviation.

Kalibr (and VINS, OpenVINS) model each sensor axis as white noise of density ``nd`` plus a bias
random walk of density ``rw``; the Allan variance of that model is the N and K terms of the
five-term model (:mod:`~gyrofilter.analysis.noise.model`; IEEE Std 952, paper 000 eqs. 4-8)::

    sigma^2(tau) = nd^2 / tau + rw^2 tau / 3

Read off a real MEMS curve (the fit's N and K, the *plain* values), the model falls below the
measured deviation where bias instability (flicker) lifts it between the two slopes, so a filter
that trusts it is overconfident there; Kalibr's wiki and allan_variance_ros advise inflating the
values 10-20x by guesswork. :func:`bounding_pair` gives the smallest pair whose model lies on or
above the measured deviation of every axis over a range of integration times, with the factor
stated. The module is sensor-agnostic: a sensor is named by the unit of its Allan deviation
(:data:`KALIBR_SENSORS`), and :func:`kalibr_sensor` gives one sensor's plain and bounding values
in Kalibr's SI units.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import SettingsError
from ...inputs import check_number
from ...units import DEG_PER_RAD
from .model import ANGLE_RANDOM_WALK, RATE_RANDOM_WALK

#: the default range of integration times (s) the bounding pair covers (issue 39: 0.1-100 s, the
#: camera-IMU intervals of a visual-inertial system up to a long stand-still)
DEFAULT_TAU_RANGE_S = (0.1, 100.0)
#: relative slack when a tau is compared with a range end (the taus are m / sample_rate_hz): 1e-5, beyond
#: the 5e-6 of a tau printed to 6 digits (%g, as the refusals and the yaml give them), so that a range
#: given as printed is the one it names (at 7.3 Hz, 0.136986 for 1/7.3 = 0.1369863.. s, which 1e-9 refused)
_TAU_SLACK = 1e-5


@dataclass(frozen=True)
class KalibrSensor:
    """A sensor as Kalibr's imu.yaml names it: ``name`` (the keys' prefix, ``gyroscope`` or
    ``accelerometer``), ``to_si`` (the factor from the Allan deviation's unit to Kalibr's SI
    unit) and the units of its ``noise_density`` and ``random_walk`` keys."""

    name: str
    to_si: float
    density_unit: str
    walk_unit: str


GYROSCOPE = KalibrSensor("gyroscope", 1.0 / DEG_PER_RAD, "rad/s/sqrt(Hz)", "rad/s^2/sqrt(Hz)")   # deg/s -> rad/s
ACCELEROMETER = KalibrSensor("accelerometer", 1.0, "m/s^2/sqrt(Hz)", "m/s^3/sqrt(Hz)")
#: the unit of a sensor's Allan deviation -> the sensor in Kalibr's terms
KALIBR_SENSORS = {"deg/s": GYROSCOPE, "m/s^2": ACCELEROMETER}


@dataclass(frozen=True)
class BoundingPair:
    """The result of :func:`bounding_pair`, in the Allan deviation's unit D: ``noise_density``
    (D sqrt(s) = D/sqrt(Hz)) and ``random_walk`` (D/sqrt(s)); ``excess``: the largest ratio of the
    model's deviation to the measured one (the largest axis's) over the range, >= 1; ``least``: the
    smallest such ratio (1 unless a floor raised the pair) and ``touch_tau_s`` the taus where the
    ratio is ``least``; ``upper_ratio``: the smallest ratio of the model
    to the largest axis's upper confidence bound over the range (None without bounds); ``tau_s``:
    the measured taus covered (s)."""

    noise_density: float
    random_walk: float
    excess: float
    least: float
    touch_tau_s: tuple
    upper_ratio: float | None
    tau_s: tuple


def kalibr_adev(noise_density, random_walk, tau_s):
    """Kalibr's model deviation ``sqrt(nd^2 / tau + rw^2 tau / 3)`` at ``tau_s`` (s), in the unit D of
    ``noise_density`` (D/sqrt(Hz)) and ``random_walk`` (D/sqrt(s))."""
    tau = np.asarray(tau_s, dtype=np.float64)
    return np.sqrt(noise_density ** 2 / tau + random_walk ** 2 * tau / 3.0)


def check_tau_range_s(tau_range_s, what="--kalibr-tau-s"):
    """``tau_range_s`` (two numbers, low and high in s) as a tuple of floats, checked: finite, with
    0 < low < high, else SettingsError naming ``what``."""
    values = tuple(tau_range_s)
    if len(values) != 2:
        raise SettingsError(f"{what} must be two times LOW,HIGH in s, got {len(values)} numbers")
    low, high = (check_number(v, what) for v in values)
    if not 0.0 < low < high:
        raise SettingsError(f"{what} must be two times LOW,HIGH in s with 0 < LOW < HIGH, got {low:g},{high:g}")
    return low, high


def tau_range(tau_s, tau_range_s=None, what="--kalibr-tau-s"):
    """The range (low, high) in s that :func:`bounding_pair` covers for a record whose Allan
    deviation is measured at ``tau_s`` (s, ascending), and whether it was cut: ``(low, high, cut)``.

    ``tau_range_s`` None: :data:`DEFAULT_TAU_RANGE_S` cut to the record's taus (``cut`` True when
    the record is too short or too coarse for it). A range given (low, high) must lie within the
    record's taus and hold at least two of them, else SettingsError naming ``what``."""
    tau = np.asarray(tau_s, dtype=np.float64)
    first, last = float(tau[0]), float(tau[-1])
    if tau_range_s is None:
        low, high = DEFAULT_TAU_RANGE_S
        low_cut, high_cut = max(low, first), min(high, last)
        cut = (low_cut, high_cut) != (low, high)
        low, high = low_cut, high_cut
    else:
        low, high = check_tau_range_s(tau_range_s, what)
        cut = False
        if low < first * (1.0 - _TAU_SLACK) or high > last * (1.0 + _TAU_SLACK):
            raise SettingsError(f"{what} {low:g},{high:g} s reaches beyond the record's cluster times {first:g} .. "
                                f"{last:g} s (one sample to the longest tau with enough clusters; a longer record "
                                "reaches longer times)")
    inside = _inside(tau, low, high)
    if np.count_nonzero(inside) < 2:
        if tau_range_s is None:  # the default range cut to a record too short for it (low may pass high)
            lo, hi = DEFAULT_TAU_RANGE_S
            raise SettingsError(f"--kalibr: the record's cluster times ({first:g} .. {last:g} s) hold "
                                f"{np.count_nonzero(inside)} of the default range {lo:g} .. {hi:g} s; the bounding pair "
                                f"needs at least 2: a longer record, or {what} within {first:g} .. {last:g} s")
        raise SettingsError(f"{what} {low:g},{high:g} s holds {np.count_nonzero(inside)} of the record's cluster times "
                            f"({first:g} .. {last:g} s); the bounding pair needs at least 2: give a wider range")
    return low, high, cut


def _inside(tau, low, high):
    return (tau >= low * (1.0 - _TAU_SLACK)) & (tau <= high * (1.0 + _TAU_SLACK))


def bounding_pair(tau_s, adev, tau_range_s, *, adev_high=None, floor=(0.0, 0.0)):
    """The smallest white + random-walk pair (nd, rw) whose Kalibr model lies on or above the
    measured Allan deviation of every axis at the taus within ``tau_range_s`` (low, high; s).

    ``tau_s`` (n,): the cluster times (s), the same for every axis; ``adev`` (k, n) or (n,): the
    measured (estimated) deviation of k axes in a unit D; ``adev_high``: their upper confidence
    bounds, the same shape (only reported, as ``upper_ratio``). With ``s_j`` the largest axis's
    deviation at tau_j and the model ``m^2(tau) = nd^2 / tau + rw^2 tau / 3``, the rule is::

        minimise  F = max_j m(tau_j) / s_j   subject to   m(tau_j) >= s_j for every j in the range

    "Smallest" is the least worst-case overstatement: F (``excess``) is the most by which the model
    overstates the sensor's noise at any integration time in the range, and no other pair that
    bounds the data has a smaller one (so if any pair meets issue 39's "at most 4x the worst
    axis", this one does). The pair is minimal in both values as well: the model touches the data
    (ratio 1) at a tau where both terms are positive, so lowering either value breaks the bound.
    Other rules weigh the two ends (e.g. the deviation at the range's ends, or one factor applied
    to the plain values) and overstate one end by more than F to spare the other.

    ``floor`` (nd0, rw0), in the same units: the pair is the least F with nd >= nd0 and rw >= rw0
    (the plain values, :func:`kalibr_sensor`): where the optimum above lies below a floor, that
    value is held at its floor and the other is the least that still bounds the data
    (:func:`_floored`), so the model still touches the data. Without floors a range the white noise
    dominates gives rw = 0 (a bias that never moves, which Kalibr must not be told), and one that
    starts where flicker dominates nd = 0.

    Solution (exact): the ratios ``g_j = m^2(tau_j) / s_j^2`` are linear in (nd^2, rw^2) and
    homogeneous, so with the shape ``p = nd^2 / (nd^2 + rw^2)`` and the scale chosen so that
    ``min_j g_j = 1``, F^2 = ``max_j g_j(p) / min_j g_j(p)``, a ratio of two piecewise-linear
    functions of p in [0, 1]. Between the points where two lines g_i, g_j cross, it is one
    linear-fractional function, which is monotone: its minimum is at one of those crossings or at
    p = 0 or 1, all of which are tried.

    The pair bounds the **estimate** (``adev``), not its upper confidence bound: the yaml should
    describe the sensor as measured, as the plain values do (fitted to the same estimates); the
    upper bound adds the sampling error of each point, which grows to the long taus where few
    clusters are averaged, and would set rw by the record's length more than by the sensor; and
    the largest of the axes' noisy estimates at each tau already leans upward. ``upper_ratio``
    states where the model stands against the upper bounds. A tau where every axis's deviation is
    0 (cluster averages all equal: a gyro that alternates between two values, at every even
    cluster size) is left out: every model lies on or above it, and ``s_j`` = 0 would divide by
    0. Raises SettingsError when the range holds fewer than two taus with a deviation above 0.
    """
    tau = np.asarray(tau_s, dtype=np.float64)
    dev = np.atleast_2d(np.asarray(adev, dtype=np.float64))
    low, high = tau_range_s
    inside = _inside(tau, low, high) & (np.max(dev, axis=0) > 0.0)  # a deviation of 0 bounds nothing
    if np.count_nonzero(inside) < 2:
        raise SettingsError(f"the range {low:g} .. {high:g} s holds fewer than 2 cluster times with a deviation above 0; "
                            "the bounding pair needs 2")
    t = tau[inside]
    v = np.max(dev[:, inside], axis=0) ** 2
    white, walk = 1.0 / t / v, t / 3.0 / v            # g_j(p) = walk_j + p (white_j - walk_j)
    slope = white - walk
    i, j = np.triu_indices(t.size, 1)
    crossing = np.full(i.size, -1.0)
    parallel = slope[i] == slope[j]
    np.divide(walk[j] - walk[i], slope[i] - slope[j], out=crossing, where=~parallel)
    p = np.concatenate([[0.0, 1.0], crossing[(crossing > 0.0) & (crossing < 1.0)]])
    g = walk[None, :] + p[:, None] * slope[None, :]
    spread = g.max(axis=1) / g.min(axis=1)
    best = int(np.argmin(spread))
    scale = 1.0 / g[best].min()
    nd, rw = _floored(white, walk, scale * p[best], scale * (1.0 - p[best]), *(float(f) ** 2 for f in floor))
    ratio = kalibr_adev(nd, rw, t) / np.sqrt(v)
    upper = None
    if adev_high is not None:
        top = np.max(np.atleast_2d(np.asarray(adev_high, dtype=np.float64))[:, inside], axis=0)
        upper = float(np.min(kalibr_adev(nd, rw, t) / top))
    touch = tuple(float(x) for x in t[np.isclose(ratio, ratio.min(), rtol=1e-9, atol=0.0)])
    return BoundingPair(nd, rw, float(ratio.max()), float(ratio.min()), touch, upper, tuple(float(x) for x in t))


def _floored(white, walk, a, b, a0, b0):
    """The least-F pair (nd, rw) with nd^2 >= ``a0`` and rw^2 >= ``b0``, given the unconstrained
    optimum (``a``, ``b``) = (nd^2, rw^2) of :func:`bounding_pair` and its lines ``g_j = white_j a +
    walk_j b`` (the model's variance over the data's at tau_j; every ``g_j >= 1`` bounds). ``max_j
    g_j`` is convex and the bounding set is convex, so where (a, b) lies outside the floors the
    optimum lies on a floor's line; along it every g_j grows with the other value, so the best
    point there is the least value that keeps every g_j >= 1 (and its own floor):
    ``a = max(a0, max_j (1 - walk_j b0) / white_j)`` on rw = rw0, alike for rw on nd = nd0. The
    better of the feasible ones (least max g) is returned."""
    if a >= a0 and b >= b0:
        return float(np.sqrt(a)), float(np.sqrt(b))
    on_walk = (max(a0, float(np.max((1.0 - walk * b0) / white))), b0)  # rw held at its floor
    on_white = (a0, max(b0, float(np.max((1.0 - white * a0) / walk))))  # nd held at its floor
    pa, pb = min((on_walk, on_white), key=lambda q: float(np.max(white * q[0] + walk * q[1])))
    return float(np.sqrt(pa)), float(np.sqrt(pb))


@dataclass(frozen=True)
class KalibrValues:
    """One sensor's imu.yaml values (:func:`kalibr_sensor`), in Kalibr's SI units (``sensor``'s
    ``density_unit``, ``walk_unit``): ``per_axis`` {axis: :func:`plain_values`}, the ``plain``
    pair (the largest over the axes; a value None where an axis has neither value nor bound),
    the ``bound`` (:class:`BoundingPair` in the Allan deviation's unit), ``noise_density`` and
    ``random_walk`` (the bounding pair in SI: what the yaml writes), the range covered
    ``tau_range_s``, whether the default range was ``cut`` to the record, and ``held`` (for the
    noise density and the random walk): the tau (s) at which a value was held at the record's
    bound (:func:`record_bounds`: no positive plain value floored it and the pair set it to 0),
    else None."""

    sensor: KalibrSensor
    per_axis: dict
    plain: tuple
    bound: BoundingPair
    noise_density: float
    random_walk: float
    tau_range_s: tuple
    cut: bool
    held: tuple = (None, None)

    def held_texts(self):
        """For the noise density and the random walk: why the value is the record's bound
        (``held``), one short clause, or None."""
        return tuple(None if at is None else f"no plain value and 0 bounds the data, which Kalibr cannot take: the record's "
                     f"bound, the {what} whose own deviation reaches the largest axis's at tau {at:.4g} s"
                     for at, what in zip(self.held, ("white noise", "random walk")))

    def factors(self):
        """(bounding / plain) for the noise density and the random walk; None where the plain value
        is None or zero."""
        return tuple(None if not p else b / p for b, p in zip((self.noise_density, self.random_walk), self.plain))


def plain_values(r, sensor):
    """The plain Kalibr values of one axis ``r`` (an AxisNoise) of ``sensor`` (a :class:`KalibrSensor`),
    in its SI units: ``noise_density`` = the fitted N (the white term) and ``random_walk`` = the
    fitted K (B, bias instability, is *not* Kalibr's random walk); the upper bound of a term the fit
    does not resolve stands in for it, flagged ``noise_density_is_upper_bound`` and
    ``random_walk_is_upper_bound``. A value without value or bound is None."""
    n, k = r.fitted[ANGLE_RANDOM_WALK], r.fitted[RATE_RANDOM_WALK]
    nd = n.value if n.value is not None else n.upper
    rw = k.value if k.value is not None else k.upper
    return {"noise_density": None if nd is None else nd * sensor.to_si,
            "random_walk": None if rw is None else rw * sensor.to_si,
            "noise_density_is_upper_bound": n.value is None, "random_walk_is_upper_bound": k.value is None}


def record_bounds(tau_s, adev, covered_tau_s):
    """The record's bounds of the pair's two values, ``((nd0, tau_low), (rw0, tau_high))``: the
    white noise whose own deviation ``nd0 / sqrt(tau)`` equals the largest axis's measured
    deviation ``s`` at the shortest covered tau, and the random walk whose own deviation
    ``rw0 sqrt(tau / 3)`` equals it at the longest (IEEE Std 952's N and K terms): a larger value
    would lift the model's curve above the data there, so the record allows nothing above them.
    ``tau_s`` and ``adev`` (k, n) as :func:`bounding_pair` takes them; ``covered_tau_s``: the taus
    a :class:`BoundingPair` covers (each with a deviation above 0). :func:`kalibr_sensor` writes
    them where the pair would set a value to 0 and no positive plain value floors it: Kalibr's
    model needs both values positive (a white noise or a bias random walk of 0 is a sensor that
    never errs or whose bias never moves), and the bound is the most the record allows."""
    tau = np.asarray(tau_s, dtype=np.float64)
    largest = np.max(np.atleast_2d(np.asarray(adev, dtype=np.float64)), axis=0)
    low, high = covered_tau_s[0], covered_tau_s[-1]
    s_low, s_high = (float(largest[np.argmin(np.abs(tau - t))]) for t in (low, high))
    return (s_low * np.sqrt(low), low), (s_high * np.sqrt(3.0 / high), high)


def kalibr_sensor(results, unit, tau_range_s=None):
    """One sensor's Kalibr values (a :class:`KalibrValues`) from its Allan results ``results``
    ({axis: AxisNoise}, the deviation in ``unit``, a key of :data:`KALIBR_SENSORS`: ``deg/s`` for
    a gyroscope, ``m/s^2`` for an accelerometer) over ``tau_range_s`` ((low, high) in s, or None:
    the default range cut to the record, :func:`tau_range`): the bounding pair with the plain
    values as its floor (:func:`bounding_pair`). A value that no positive plain value floors and
    that the pair sets to 0 (the white noise alone bounds the range: a gyro that alternates
    between two values, whose fit resolves nothing) is held at the record's bound instead
    (:func:`record_bounds`), the other value then the least that bounds; ``held`` says so."""
    sensor = KALIBR_SENSORS[unit]
    axes = list(results.values())
    tau = axes[0].tau_s
    if any(r.tau_s.shape != tau.shape or np.any(r.tau_s != tau) for r in axes[1:]):
        raise SettingsError("the axes' Allan deviations are at different cluster times; the bounding pair needs one set")
    low, high, cut = tau_range(tau, tau_range_s)
    per_axis = {a: plain_values(r, sensor) for a, r in results.items()}
    plain = tuple(None if any(v[key] is None for v in per_axis.values()) else max(v[key] for v in per_axis.values())
                  for key in ("noise_density", "random_walk"))
    adevs, highs = [r.adev for r in axes], [r.ci_high for r in axes]
    floor = tuple(0.0 if v is None else v / sensor.to_si for v in plain)
    bound = bounding_pair(tau, adevs, (low, high), adev_high=highs, floor=floor)
    bounds = record_bounds(tau, adevs, bound.tau_s)
    held = tuple(at if f <= 0.0 and value <= 0.0 else None
                 for f, value, (_, at) in zip(floor, (bound.noise_density, bound.random_walk), bounds))
    if any(at is not None for at in held):
        floor = tuple(f if at is None else b for f, at, (b, _) in zip(floor, held, bounds))
        bound = bounding_pair(tau, adevs, (low, high), adev_high=highs, floor=floor)
    return KalibrValues(sensor, per_axis, plain, bound, bound.noise_density * sensor.to_si,
                        bound.random_walk * sensor.to_si, (low, high), cut, held)
