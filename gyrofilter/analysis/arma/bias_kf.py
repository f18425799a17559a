"""Bias-augmented Kalman filter with zero-rate updates at rest (paper 003, section 2).

Paper 003 augments its navigation Kalman filter with one ARMA(1, 1) bias state per gyro axis so
that the bias is estimated online. Without GNSS, the only thing that makes a gyro's bias
observable is knowing the true rate; here that knowledge is stillness: while the sensor is
detected at rest, a zero-rate pseudo-measurement ("zero-velocity update" for a gyro) is added.

Per axis the state is x = [r, d]: the true rate r and the bias deviation d = b - b0 from the
start-up calibration b0 (deg/s). Per sample (dt = 1/fs)::

    r_k = r_{k-1} + w_r,        w_r ~ N(0, q_r),  q_r = (rate_walk_dps_per_sqrt_s)^2 dt
    d_k = phi d_{k-1} + eta,    eta ~ N(0, q_b)                      (Gauss-Markov bias, 003 eq. 3)
    z_k = r_k + b0 + d_k + v,   v ~ N(0, sigma^2)                    (the gyro)
    0   = r_k + v0,             v0 ~ N(0, sigma0^2)   only while still (zero-rate update)

phi = exp(-dt / tau) and q_b = bias_sigma^2 (1 - phi^2), or phi = 1 and q_b = K^2 dt for a
random-walk bias (tau = inf). These come from the ARMA(1, 1) of :mod:`gyrofilter.analysis.arma.identify`
(:meth:`BiasKFSettings.from_bias_model`) or from settings. sigma is the white-noise level
measured during the start-up calibration (first differences, :mod:`gyrofilter.filter.calibration`).

Stillness is judged from the data: over the last ``still_window_s`` of raw samples, per axis,
the variance s^2 and the mean m. Still is entered when for every axis s^2 < enter * sigma^2 and
|m - b| < ``still_max_offset_dps`` (b: current bias estimate) and left when any s^2 > exit *
sigma^2 or |m - b| exceeds the offset (hysteresis: exit > enter). A sample gets the zero-rate
update only while still and if its own |z - b| < ``still_gate_sigma`` * sigma, so the first
samples of a motion do not leak into the bias before the window notices. A constant rotation
slower than ``still_max_offset_dps`` cannot be told from a bias by a gyro alone; it would be
learnt as bias.

During motion the filter does the ordinary update with z only; the bias is then nearly
unobservable and its gain is about P_dd / (P_rr + sigma^2), tiny because q_r >> q_b, so the bias
estimate holds (tested).

The filter is one kernel (``_step``) used sample by sample by :meth:`BiasKalmanFilter.update`
and in a loop by :meth:`BiasKalmanFilter.run` / :meth:`BiasKalmanFilter.filter`, so both give
the same numbers. The kernel is three 2-state filters in plain float arithmetic with the
equations written out (about 30 us per 3-axis sample on a busy PC, ~10x less than numpy on
length-3 arrays); the stillness window keeps running sums of z - b0, recomputed exactly every
``RESUM_EVERY`` samples. ``engine="filterpy"`` runs the same model through
``filterpy.kalman.KalmanFilter`` (one per axis, Joseph-form update as here; ~6x slower) and is
the oracle of the tests (agreement to 1e-14).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ...filter.calibration import Calibration, calibrate, calibration_samples, without_gross_errors
from ...filter.samples import check_sample, check_samples
from ...errors import SettingsError
from ...filter.settings import MAX_CALIBRATION_S
from ...inputs import axis_values, check_number, python_value
from ...units import MAX_RATE_DPS, check_sample_rate_hz, plain

RESUM_EVERY = 10_000  # samples between exact recomputations of the window sums


@dataclass(frozen=True)
class BiasKFSettings:
    """Settings of :class:`BiasKalmanFilter` (units in the names)."""

    calibration_s: float = 2.0  # start-up calibration window (sensor still)
    bias_tau_s: float = math.inf  # Gauss-Markov correlation time of the bias; inf = random walk
    bias_sigma_dps: float = 0.05  # stationary std of the Gauss-Markov bias (used when tau is finite)
    bias_walk_dps_per_sqrt_s: float = 0.002  # random-walk drive of the bias (used when tau is inf)
    rate_walk_dps_per_sqrt_s: float = 100.0  # how fast the true rate may change (motion model)
    noise_std_dps: tuple | None = None  # white noise per sample; None: from the calibration
    zero_rate_std_dps: float = 0.002  # residual motion at rest (the zero-rate update's noise)
    still_window_s: float = 0.5
    still_enter_ratio: float = 2.0  # window variance / sigma^2 below this on every axis: still
    still_exit_ratio: float = 3.0  # above this on any axis: moving
    still_max_offset_dps: float = 1.0  # |window mean - bias| beyond this on any axis: moving
    still_gate_sigma: float = 4.0  # per-sample gate for the zero-rate update
    initial_bias_std_dps: float | None = None  # None: sigma / sqrt(calibration samples)
    engine: str = "numpy"  # or "filterpy"

    def checked(self) -> "BiasKFSettings":
        """The settings with every number a plain Python float (a per-axis one a float or a tuple
        of 3), or SettingsError naming the first bad one: each a number (never a bool: True was
        taken as 1; numpy's numbers and 0-d arrays are the numbers they hold), finite and in its
        range of :data:`SETTING_RANGES` (``bias_tau_s`` > 0 or inf, a random walk; a negative
        ``bias_sigma_dps`` or ``still_window_s`` was taken without a word); the rule:
        :func:`~gyrofilter.inputs.check_number`."""
        numbers = {name: _checked_value(getattr(self, name), name, bounds) for name, bounds in SETTING_RANGES.items()}
        return replace(self, **numbers, engine=python_value(self.engine))

    @classmethod
    def from_bias_model(cls, model, **overrides):
        """Settings whose bias model is ``model`` (a :class:`gyrofilter.analysis.arma.identify.BiasModel`, or per-axis list of them)."""
        models = model if isinstance(model, (list, tuple)) else [model] * 3
        taus = [m.tau_s for m in models]
        if any(not m.valid for m in models):
            raise SettingsError("bias model is not valid (ARMA(1, 1) without a Gauss-Markov decomposition); give the bias settings explicitly")
        kw = dict(
            bias_tau_s=tuple(taus),
            bias_sigma_dps=tuple(0.0 if math.isinf(m.bias_sigma_dps) else m.bias_sigma_dps for m in models),
            bias_walk_dps_per_sqrt_s=tuple(m.bias_walk_dps_per_sqrt_s for m in models),
        )
        kw.update(overrides)
        return cls(**kw)


@dataclass
class BiasKFTrace:
    """Per-sample outputs of :meth:`BiasKalmanFilter.run` after the calibration window."""

    rate_dps: np.ndarray  # (M, 3) rate estimates
    bias_dps: np.ndarray  # (M, 3) bias estimates after each sample
    bias_std_dps: np.ndarray  # (M, 3) their standard deviations
    still: np.ndarray  # (M,) bool: zero-rate update applied at this sample
    calibration: Calibration = field(default=None)


#: the range of each number of :class:`BiasKFSettings` (the bounds of
#: :func:`~gyrofilter.inputs.check_number`); ``per_axis``: one number or 3 (x, y, z); ``none``: None
#: is taken (from the calibration); ``inf``: +inf is taken
SETTING_RANGES = {
    "calibration_s": dict(low=0, high=MAX_CALIBRATION_S),
    "bias_tau_s": dict(low=0, low_open=True, per_axis=True, inf=True),
    "bias_sigma_dps": dict(low=0, high=MAX_RATE_DPS, per_axis=True),
    "bias_walk_dps_per_sqrt_s": dict(low=0, high=MAX_RATE_DPS, per_axis=True),
    "rate_walk_dps_per_sqrt_s": dict(low=0, high=MAX_RATE_DPS),
    "noise_std_dps": dict(low=0, high=MAX_RATE_DPS, per_axis=True, none=True),
    "zero_rate_std_dps": dict(low=0, high=MAX_RATE_DPS),
    "still_window_s": dict(low=0, low_open=True, high=MAX_CALIBRATION_S),
    "still_enter_ratio": dict(low=0, low_open=True, high=1e6),
    "still_exit_ratio": dict(low=0, low_open=True, high=1e6),
    "still_max_offset_dps": dict(low=0, high=MAX_RATE_DPS),
    "still_gate_sigma": dict(low=0, low_open=True, high=1e6),
    "initial_bias_std_dps": dict(low=0, high=MAX_RATE_DPS, none=True),
}


def _checked_value(value, name, bounds):
    """One setting of :data:`SETTING_RANGES` checked (see :meth:`BiasKFSettings.checked`)."""
    bounds = dict(bounds)
    per_axis, none, inf = bounds.pop("per_axis", False), bounds.pop("none", False), bounds.pop("inf", False)
    value = axis_values(value) if per_axis else python_value(value)
    if value is None and none:
        return None
    if per_axis and isinstance(value, (tuple, list)):
        if len(value) != 3:
            raise SettingsError(f"{name} must be a number or 3 numbers, got {plain(value)}")
        return tuple(_checked_value(v, name, {**bounds, "inf": inf}) for v in value)
    if inf and isinstance(value, float) and value == math.inf:
        return math.inf
    return float(check_number(value, name, **bounds))


def _per_axis(value, name):
    arr = np.broadcast_to(np.asarray(value, dtype=float), (3,)).copy()
    if arr.shape != (3,):
        raise SettingsError(f"{name} must be a number or 3 numbers, got {plain(value)}")
    return arr


class BiasKalmanFilter:
    """Rate + bias Kalman filter per axis with zero-rate updates at detected rest.

    ``sample_rate_hz``: input sample rate (Hz); ``settings``: a :class:`BiasKFSettings` (default:
    its defaults), with any of its fields overridden by keyword (``**kw``); ``calibration``: a
    :class:`~gyrofilter.filter.calibration.Calibration` that skips the start-up calibration.

    >>> f = BiasKalmanFilter(100.0)              # 2 s start-up calibration, then online bias
    >>> y = f.update((gx, gy, gz))               # None while calibrating, else rates (deg/s)
    >>> f.bias_dps                               # current bias estimate, 3-tuple (deg/s)
    """

    def __init__(self, sample_rate_hz, settings: BiasKFSettings | None = None, *, calibration: Calibration | None = None, **kw):
        self.sample_rate_hz = check_sample_rate_hz(sample_rate_hz)
        self.settings = s = replace(settings or BiasKFSettings(), **kw).checked()
        if s.engine not in ("numpy", "filterpy"):
            raise SettingsError(f"engine must be 'numpy' or 'filterpy', got {s.engine!r}")
        if not s.still_exit_ratio > s.still_enter_ratio > 0:
            raise SettingsError(f"need still_exit_ratio > still_enter_ratio > 0, got {s.still_exit_ratio} and {s.still_enter_ratio}")
        dt = 1.0 / self.sample_rate_hz
        tau = _per_axis(s.bias_tau_s, "bias_tau_s")
        if np.any(tau <= 0):
            raise SettingsError(f"bias_tau_s must be positive (inf = random walk), got {plain(s.bias_tau_s)}")
        finite = np.isfinite(tau)
        # bias transition phi = exp(-dt/tau) and its process noise q_b (Gauss-Markov or random walk)
        self._phi = np.where(finite, np.exp(-dt / np.where(finite, tau, 1.0)), 1.0)
        q_gm = _per_axis(s.bias_sigma_dps, "bias_sigma_dps") ** 2 * (1 - self._phi**2)
        q_rw = _per_axis(s.bias_walk_dps_per_sqrt_s, "bias_walk_dps_per_sqrt_s") ** 2 * dt
        self._q_b = np.where(finite, q_gm, q_rw)
        self._q_r = np.full(3, s.rate_walk_dps_per_sqrt_s**2 * dt)
        self._r0 = s.zero_rate_std_dps**2
        self._window = max(2, int(round(s.still_window_s * self.sample_rate_hz)))
        self._n_cal = calibration_samples(self.sample_rate_hz, s.calibration_s)
        self._cal_buffer = []
        self._ring = np.zeros((self._window, 3))
        self._ring_count = 0
        self._still = False
        self.calibration = None
        self._kfs = None
        if calibration is not None:  # held to a start-up calibration's limits, as GyroFilter holds one
            self._start(calibration.checked("the calibration"))
        elif self._n_cal < 20:
            raise SettingsError(f"calibration_s = {s.calibration_s} s gives {self._n_cal} samples; need 20, or pass calibration=")

    # -- start-up -------------------------------------------------------------------------

    def _start(self, cal: Calibration):
        s = self.settings
        self.calibration = cal
        self._b0 = np.asarray(cal.bias_dps, float)
        sigma = np.asarray(s.noise_std_dps if s.noise_std_dps is not None else cal.noise_std_dps, float)
        self._sigma = np.maximum(_per_axis(sigma, "noise_std_dps"), 1e-6)
        self._rv = self._sigma**2
        p_b = (self._sigma / math.sqrt(max(cal.samples, 1))) ** 2 if s.initial_bias_std_dps is None else np.full(3, s.initial_bias_std_dps**2)
        # state [r, d] per axis and its covariance [[Prr, Prd], [Prd, Pdd]], as Python floats
        # (three 2-state filters: scalar arithmetic is ~10x faster than numpy on length-3 arrays)
        p_b = np.broadcast_to(np.asarray(p_b, float), (3,))
        self._x = [[0.0, 0.0, float(self._rv[i]), 0.0, float(p_b[i])] for i in range(3)]  # r, d, Prr, Prd, Pdd
        self._coef = [(float(self._phi[i]), float(self._q_r[i]), float(self._q_b[i]), float(self._rv[i]), float(self._b0[i]),
                       float(self._sigma[i])) for i in range(3)]
        if s.engine == "filterpy":
            self._kfs = [self._make_filterpy(i) for i in range(3)]

    def _make_filterpy(self, i):
        from filterpy.kalman import KalmanFilter

        kf = KalmanFilter(dim_x=2, dim_z=1)
        kf.x = np.zeros((2, 1))
        kf.F = np.array([[1.0, 0.0], [0.0, self._phi[i]]])
        kf.Q = np.diag([self._q_r[i], self._q_b[i]])
        kf.H = np.array([[1.0, 1.0]])
        kf.R = np.array([[self._rv[i]]])
        kf.P = np.array([[self._x[i][2], 0.0], [0.0, self._x[i][4]]])
        return kf

    # -- public ---------------------------------------------------------------------------

    @property
    def bias_dps(self):
        """Current bias estimate per axis (deg/s); the calibration's until it ends, None before."""
        if self.calibration is None:
            return None
        return tuple(float(v) for v in self._b0 + self._d_now())

    @property
    def bias_std_dps(self):
        """Standard deviation of the bias estimate per axis (deg/s), or None while calibrating."""
        if self.calibration is None:
            return None
        return tuple(float(v) for v in np.sqrt(self._pdd_now()))

    @property
    def still(self) -> bool:
        """The rest detector's state after the last sample (with its hysteresis): True at rest;
        a zero-rate update is applied when the sample also passes the gate on every axis."""
        return self._still

    def update(self, sample_dps):
        """One sample ``sample_dps`` (gx, gy, gz) in deg/s -> None while calibrating, else the rate
        estimate (3-tuple, deg/s). SampleError, the filter's (:func:`~gyrofilter.filter.samples.check_sample`),
        for a sample that is not 3 finite numbers within +-MAX_RATE_DPS: a NaN after the calibration
        window made every later estimate NaN."""
        z = np.array(check_sample(sample_dps), dtype=float)
        if self.calibration is None:
            self._cal_buffer.append(z)
            if len(self._cal_buffer) == self._n_cal:
                self._start(calibrate(np.array(self._cal_buffer), self.sample_rate_hz))
                self._ring_count = 0
                window = without_gross_errors(self._cal_buffer)[0]  # as the calibration measured it
                for row in window[-self._window:]:
                    self._push(row)
                self._cal_buffer = []
            return None
        rate, _ = self._step(z)
        return tuple(float(v) for v in rate)

    def run(self, samples_dps) -> BiasKFTrace:
        """Batch: ``samples_dps`` (N, 3) deg/s -> per-sample trace after the calibration window (same
        numbers as update); the samples are checked as ``GyroFilter.filter()`` checks them (a masked
        value, one that is not finite or beyond +-MAX_RATE_DPS: SampleError naming its row)."""
        x = check_samples(samples_dps)
        rates, biases, stds, still = [], [], [], []
        for row in x:
            if self.calibration is None:
                self.update(row)
                continue
            rate, was_still = self._step(row)
            rates.append(rate)
            biases.append(self._b0 + self._d_now())
            stds.append(np.sqrt(self._pdd_now()))
            still.append(was_still)
        shape = (len(rates), 3)
        return BiasKFTrace(np.array(rates).reshape(shape), np.array(biases).reshape(shape),
                           np.array(stds).reshape(shape), np.array(still, dtype=bool), self.calibration)

    def filter(self, samples_dps) -> np.ndarray:
        """Batch: ``samples_dps`` (N, 3) deg/s -> (N - calibration samples, 3) rate estimates (deg/s)."""
        return self.run(samples_dps).rate_dps

    # -- kernel ---------------------------------------------------------------------------

    def _push(self, z):
        """Add a raw sample (deg/s) to the stillness window; running sums of z - b0 per axis."""
        w = self._window
        slot = self._ring_count % w
        if self.calibration is None:
            self._ring[slot] = z
            self._ring_count += 1
            return
        if self._ring_count == 0 or self._ring_count % RESUM_EVERY == 0:
            self._resum()
        old = self._ring[slot]
        full = self._ring_count >= w
        for i in range(3):
            v = z[i] - self._coef[i][4]
            self._s1[i] += v
            self._s2[i] += v * v
            if full:
                o = old[i] - self._coef[i][4]
                self._s1[i] -= o
                self._s2[i] -= o * o
        self._ring[slot] = z
        self._ring_count += 1

    def _resum(self):
        """Exact sums over the window (also every RESUM_EVERY samples, against rounding drift)."""
        n = min(self._ring_count, self._window)
        v = self._ring[:n] - self._b0 if n else np.zeros((0, 3))
        self._s1 = [float(a) for a in v.sum(axis=0)] if n else [0.0, 0.0, 0.0]
        self._s2 = [float(a) for a in (v * v).sum(axis=0)] if n else [0.0, 0.0, 0.0]

    def _detect(self, z):
        """Stillness with hysteresis from the window of raw samples (module docstring)."""
        s = self.settings
        self._push(z)
        if self._ring_count < self._window:
            self._still = False
            return False
        w = self._window
        gate = True
        enter_all = True
        exit_any = False
        offset_big = False
        for i in range(3):
            coef = self._coef[i]
            d = self._d_axis(i)
            mean = self._s1[i] / w  # mean of z - b0
            var = max(self._s2[i] / w - mean * mean, 0.0)
            ratio = var / coef[3]
            if abs(mean - d) > s.still_max_offset_dps:
                offset_big = True
            if ratio > s.still_exit_ratio:
                exit_any = True
            if not ratio < s.still_enter_ratio:
                enter_all = False
            if not abs(z[i] - coef[4] - d) < s.still_gate_sigma * coef[5]:
                gate = False
        if offset_big:
            self._still = False
        elif self._still:
            self._still = not exit_any
        else:
            self._still = enter_all
        return bool(self._still and gate)

    def _step(self, z):
        z = [float(z[0]), float(z[1]), float(z[2])]
        zero_rate = self._detect(z)
        if self._kfs is not None:
            return self._step_filterpy(z, zero_rate), zero_rate
        out = np.empty(3)
        r0 = self._r0
        for i in range(3):
            phi, q_r, q_b, rv, b0, _ = self._coef[i]
            r, d, prr, prd, pdd = self._x[i]
            # predict: r_k = r_{k-1}; d_k = phi d_{k-1};  P = F P F' + Q
            d = phi * d
            prr = prr + q_r
            prd = phi * prd
            pdd = phi * phi * pdd + q_b
            # gyro update, h = [1, 1]: y = z - b0 - (r + d)
            r, d, prr, prd, pdd = _scalar_update(r, d, prr, prd, pdd, z[i] - b0, 1.0, 1.0, rv)
            if zero_rate:
                # zero-rate pseudo-measurement, h = [1, 0]: 0 = r + v0
                r, d, prr, prd, pdd = _scalar_update(r, d, prr, prd, pdd, 0.0, 1.0, 0.0, r0)
            self._x[i] = [r, d, prr, prd, pdd]
            out[i] = r
        return out, zero_rate

    def _step_filterpy(self, z, zero_rate):
        out = np.empty(3)
        for i, kf in enumerate(self._kfs):
            kf.predict()
            kf.update(np.array([[z[i] - self._b0[i]]]))
            if zero_rate:
                kf.update(np.array([[0.0]]), R=np.array([[self._r0]]), H=np.array([[1.0, 0.0]]))
            out[i] = kf.x[0, 0]
        return out

    def _d_axis(self, i):
        if self._kfs is not None:
            return float(self._kfs[i].x[1, 0])
        return self._x[i][1]

    def _d_now(self):
        return np.array([self._d_axis(i) for i in range(3)])

    def _pdd_now(self):
        if self._kfs is not None:
            return np.array([kf.P[1, 1] for kf in self._kfs])
        return np.array([self._x[i][4] for i in range(3)])


def _scalar_update(r, d, prr, prd, pdd, z, hr, hd, rv):
    """Kalman update with one scalar measurement z = hr r + hd d + v, v ~ N(0, rv), Joseph form.

    S = h P h' + R;  K = P h' / S;  x += K (z - h x);  P = (I - K h) P (I - K h)' + K R K'
    (filterpy's ``update`` uses the same Joseph form.)
    """
    ph_r = prr * hr + prd * hd
    ph_d = prd * hr + pdd * hd
    s = hr * ph_r + hd * ph_d + rv
    k_r = ph_r / s
    k_d = ph_d / s
    y = z - (hr * r + hd * d)
    r = r + k_r * y
    d = d + k_d * y
    # A = I - K h
    a11, a12 = 1 - k_r * hr, -k_r * hd
    a21, a22 = -k_d * hr, 1 - k_d * hd
    # A P A'
    t11 = a11 * prr + a12 * prd
    t12 = a11 * prd + a12 * pdd
    t21 = a21 * prr + a22 * prd
    t22 = a21 * prd + a22 * pdd
    n_rr = t11 * a11 + t12 * a12 + k_r * k_r * rv
    n_rd = t11 * a21 + t12 * a22 + k_r * k_d * rv
    n_dd = t21 * a21 + t22 * a22 + k_d * k_d * rv
    return r, d, n_rr, n_rd, n_dd
