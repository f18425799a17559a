"""Motion-aware switching: hold a constant rate while the data allow it, track otherwise.

A pure stage at the block rate, after the averaging stage (paper 001, section 2.2) and next to
the Kalman filter (2.3). It does not replace the Kalman filter; it decides, per axis and per
block, whether the output is

* **hold**: the mean m of the block means since the rate last changed (at most ``max_blocks``
  of them, then an exponential mean with the same memory), or
* **track**: the tracking filter's output x_k (the paper-001 Kalman filter).

Why: a constant rate (the sensor at rest, or turning steadily) is best estimated by averaging
everything since it became constant, which cuts white noise by sqrt(n). The paper-001 filter
cannot do that: its prior is a least-squares extrapolation of its own last 10 posteriors, and
extrapolating amplifies the noise in them (the 10-point quadratic extrapolation has white-noise
gain sum(w_i^2) = 1.38, the linear one 0.47, the constant one 0.1), so the Kalman gain must stay
large and the output keeps about a third of the block-mean noise. Averaging for longer
(``fit_order=0``) would remove the noise but lags every change. Switching gets both: long
averages while the rate is constant and the unchanged paper-001 output as soon as it is not.

Change detection (hold -> track), per axis: a two-sided CUSUM (Page 1954) of the normalised
innovation of the held value,

    d_k = (y_k - m_(k-1)) / sigma_b
    g+_k = max(0, g+_(k-1) + d_k - kappa),   g-_k = max(0, g-_(k-1) - d_k - kappa)
    change when g+_k > h or g-_k > h,

with sigma_b the standard deviation of a block mean at rest (from the start-up calibration).
kappa = 0.5 and h = 10 give an average run length between false alarms on white noise of about
1e5 blocks per side (simulated; Siegmund's approximation (exp(2 kappa b) - 2 kappa b - 1) /
(2 kappa^2), b = h + 1.166, gives 1.4e5), i.e. over an hour per axis and side at 20 blocks/s;
a false alarm costs a block or two of tracking output, as the last window is usually consistent
at once. A step of 1 deg/s (20 sigma_b) is caught in the same block and a 2 deg/s/s ramp within
3-4 blocks.

Constancy test (track -> hold): the last W = ``window_blocks`` block means are consistent with a
constant plus white noise of sigma_b, (W - 1) s^2 / sigma_b^2 below the chi-square quantile
(probability ``accept_p``, Wilson-Hilferty approximation), their least-squares slope is within
``agree_z`` of its standard error (:func:`trend_free`), and the tracking output agrees with
their mean within ``agree_z`` standard errors. Then m = the mean of the latest W / 2 of them
(:func:`recent_mean`), n = W / 2: under a vibration sigma_b is large and the test passes with the
tail of a turn still in the window's older half, whose mean then stayed in the held value (a
new user's trial: +0.3 deg/s for 7 s after a 90-degree turn under 4-5 deg/s; the latest half:
0.02, as the block means).

At start the sensor has just passed the calibration's stillness check and the bias is removed,
so the stage starts in hold with m = 0 and n = ``initial_blocks`` (0 = start in track).

State is fixed-size (a ring of W block means per axis, a few scalars), so it can run for days.
"""
from __future__ import annotations

import math

import numpy as np

from .calibration import white_noise_std
from ..errors import SettingsError
from .jit import choose_kernel
from ..units import plain

#: the stage's settings by default, the one statement of them (FilterSettings' hold_h, hold_window
#: and hold_max_blocks take theirs from here, and the adaptive Kalman filter's switch the rest)
DEFAULTS = {
    "cusum_kappa": 0.5,
    # the adaptive Kalman filter's only (gyrofilter.filter.adaptive_kalman): the Huber clip c of d_k, applied where
    # |y_k - x-_k| <= this many q (gross errors that paper 001's rule keeps move a block mean up to 2.5 q)
    "cusum_clip": 6.0,
    "cusum_clip_within_q": 3.0,
    "cusum_h": 10.0,
    "window_blocks": 20,
    "max_blocks": 400,
    "accept_p": 0.999,
    "agree_z": 4.0,
}

SIGMA_B_FLOOR_DPS = 1e-6  # a perfectly constant (simulated) input must not give sigma_b = 0

_Z_BY_P = {0.9: 1.2816, 0.95: 1.6449, 0.99: 2.3263, 0.999: 3.0902, 0.9999: 3.7190}


def chi2_quantile(p, dof):
    """Wilson-Hilferty approximation of the chi-square quantile of probability ``p`` (one of
    0.9, 0.95, 0.99, 0.999, 0.9999; z its normal quantile) with ``dof`` degrees of freedom:
    dof (1 - 2/(9 dof) + z sqrt(2/(9 dof)))^3."""
    if p not in _Z_BY_P:
        raise SettingsError(f"accept_p must be one of {sorted(_Z_BY_P)}, got {plain(p)}")
    return _wilson_hilferty(_Z_BY_P[p], dof)


def chi2_lower_quantile(p, dof):
    """The chi-square quantile of probability 1 - ``p`` (the lower tail; ``p`` as for :func:`chi2_quantile`)."""
    return _wilson_hilferty(-_Z_BY_P[p], dof)


def _wilson_hilferty(z, dof):
    a = 2.0 / (9.0 * dof)
    return dof * (1.0 - a + z * math.sqrt(a)) ** 3


def cusum_false_alarm_blocks(kappa, h):
    """Siegmund's approximation of the one-sided CUSUM's average run length (blocks) on N(0, 1)
    data, for allowance ``kappa`` and threshold ``h`` (noise units; module docstring)."""
    b = h + 1.166
    return (math.exp(2 * kappa * b) - 2 * kappa * b - 1) / (2 * kappa * kappa)


# indices into the integer state vector of hold_blocks
FILLED, HEAD, HOLDING, COUNT, SWITCHES = 0, 1, 2, 5, 8


def recent_mean(ring, a, head):
    """The mean of the latest half (W // 2 >= 1) of the block means of axis ``a`` in ``ring`` (3, W), the latest at
    ``head``: where a held value starts when the constancy test passes (module docstring)."""
    window = ring.shape[1]
    half = window // 2
    total = 0.0
    for j in range(half):
        total += ring[a, (head - j) % window]
    return total / half


def trend_free(ring, a, head, sigma, z):
    """Whether the block means of axis ``a`` in ``ring`` (3, W), the latest at ``head``, have no trend: their
    least-squares slope within ``z`` of its standard error for white noise of std ``sigma``,

        |sum_j (j - (W - 1) / 2) y_j| < z sigma sqrt(W (W^2 - 1) / 12)     (j = 0 the oldest)

    The chi-square of the constancy test has little power against a ramp where sigma_b is large (a vibration):
    a ramp of 20 -> 0 deg/s in 3 s under 5 deg/s at 33 Hz passed it, and the rest read +0.25 deg/s for 10 s
    (attack pass 39); on white noise this test rejects a window 1 time in 16 000 (z = 4)."""
    window = ring.shape[1]
    centre = (window - 1) / 2.0
    total = 0.0
    for j in range(window):
        total += (j - centre) * ring[a, (head + 1 + j) % window]
    return abs(total) < z * sigma * math.sqrt(window * (window * window - 1) / 12.0)


def hold_blocks(y, x, out, sigma, ring, mean, g_pos, g_neg, ints, kappa, h, max_blocks, chi2_limit, agree_z):
    """The stage over M blocks: y (M, 3) block means, x (M, 3) tracking outputs -> out (M, 3), deg/s.

    ``sigma``: sigma_b per axis (deg/s); ``kappa``, ``h``: the CUSUM's allowance and threshold;
    ``max_blocks``: memory of the held mean; ``chi2_limit``: the constancy test's chi-square
    quantile; ``agree_z``: the agreement limit (standard errors); see the module docstring.

    State arrays are updated in place (ring (3, W) of block means, mean, g_pos, g_neg (3,),
    ints (11,) int64: filled, head, holding[3], count[3], switches[3]). Written in the subset of
    Python numba compiles; :class:`ConstantRateHold` calls it one block at a time (streaming) or
    once for all blocks (batch), so both give the same numbers.
    """
    window = ring.shape[1]
    for k in range(y.shape[0]):
        head = ints[HEAD]
        for a in range(3):
            ring[a, head] = y[k, a]
        ints[HEAD] = (head + 1) % window
        if ints[FILLED] < window:
            ints[FILLED] += 1
        for a in range(3):
            ya = y[k, a]
            xa = x[k, a]
            s = sigma[a]
            if ints[HOLDING + a] == 1:
                # hold: two-sided CUSUM of the innovation of the held value
                d = (ya - mean[a]) / s
                g_pos[a] = max(0.0, g_pos[a] + d - kappa)
                g_neg[a] = max(0.0, g_neg[a] - d - kappa)
                if g_pos[a] > h or g_neg[a] > h:
                    ints[HOLDING + a] = 0
                    ints[SWITCHES + a] += 1
                    out[k, a] = xa
                    continue
                n = ints[COUNT + a] + 1
                if n > max_blocks:
                    n = max_blocks
                ints[COUNT + a] = n
                mean[a] += (ya - mean[a]) / n
                out[k, a] = mean[a]
            else:
                out[k, a] = xa
                if ints[FILLED] == window:
                    # track: are the last W block means a constant plus white noise?
                    m = 0.0
                    for j in range(window):
                        m += ring[a, j]
                    m /= window
                    ss = 0.0
                    for j in range(window):
                        ss += (ring[a, j] - m) * (ring[a, j] - m)
                    if ss / (s * s) < chi2_limit and abs(xa - m) < agree_z * s and trend_free(ring, a, head, s, agree_z):
                        ints[HOLDING + a] = 1
                        ints[SWITCHES + a] += 1
                        mean[a] = recent_mean(ring, a, head)
                        ints[COUNT + a] = window // 2
                        g_pos[a] = 0.0
                        g_neg[a] = 0.0
                        out[k, a] = mean[a]
    return out


_compiled = None


class ConstantRateHold:
    """The switching stage; see the module docstring. Three axes; fixed-size state.

    ``sigma_block_dps``: standard deviation of a block mean at rest per axis (deg/s), e.g.
    :func:`block_noise_std` of the calibration window. ``initial_blocks``: n at start (start in
    hold with m = 0; 0 = start in track); ``cusum_kappa``, ``cusum_h``: the CUSUM's kappa and h
    (noise units); ``window_blocks``: W of the constancy test; ``max_blocks``: memory of the held
    mean (blocks); ``accept_p``: the constancy test's probability; ``agree_z``: its agreement
    limit (standard errors); see the module docstring. ``backend``: "auto" (numba when
    installed), "python" or "numba".
    """

    def __init__(self, sigma_block_dps, *, initial_blocks=0, cusum_kappa=DEFAULTS["cusum_kappa"],
                 cusum_h=DEFAULTS["cusum_h"], window_blocks=DEFAULTS["window_blocks"],
                 max_blocks=DEFAULTS["max_blocks"], accept_p=DEFAULTS["accept_p"], agree_z=DEFAULTS["agree_z"],
                 backend="auto"):
        sigma = np.asarray(sigma_block_dps, dtype=float).reshape(-1)
        if sigma.shape != (3,) or not np.all(np.isfinite(sigma)) or np.any(sigma <= 0):
            raise SettingsError(f"sigma_block_dps must be 3 positive numbers, got {plain(sigma_block_dps)}")
        for name, value in (("cusum_kappa", cusum_kappa), ("cusum_h", cusum_h), ("agree_z", agree_z)):
            if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0):
                raise SettingsError(f"setting {name}={plain(value)}: must be a number > 0")
        for name, value, low in (("window_blocks", window_blocks, 2), ("max_blocks", max_blocks, 1), ("initial_blocks", initial_blocks, 0)):
            if not (isinstance(value, (int, np.integer)) and not isinstance(value, bool) and value >= low):
                raise SettingsError(f"setting {name}={plain(value)}: must be an integer >= {low}")
        if backend not in ("auto", "python", "numba"):
            raise SettingsError(f"setting backend={backend!r}: must be 'auto', 'python' or 'numba'")
        self.sigma = sigma.copy()
        self.kappa = float(cusum_kappa)
        self.h = float(cusum_h)
        self.max_blocks = int(max_blocks)
        self.chi2_limit = chi2_quantile(accept_p, int(window_blocks) - 1)
        self.agree_z = float(agree_z)
        self.ring = np.zeros((3, int(window_blocks)))
        self.mean = np.zeros(3)
        self.g_pos = np.zeros(3)
        self.g_neg = np.zeros(3)
        self.ints = np.zeros(11, dtype=np.int64)
        if initial_blocks > 0:
            self.ints[HOLDING : HOLDING + 3] = 1
            self.ints[COUNT : COUNT + 3] = min(int(initial_blocks), self.max_blocks)
        self._kernel = choose_kernel(hold_blocks, backend)
        # the kernel's state arguments, bound once: the arrays are updated in place
        self._args = (self.sigma, self.ring, self.mean, self.g_pos, self.g_neg, self.ints,
                      self.kappa, self.h, self.max_blocks, self.chi2_limit, self.agree_z)
        self._y1 = np.zeros((1, 3))
        self._x1 = np.zeros((1, 3))
        self._o1 = np.zeros((1, 3))

    @property
    def holding(self):
        """Per axis: True while the stage holds a constant rate."""
        return [bool(v) for v in self.ints[HOLDING : HOLDING + 3]]

    @property
    def switches(self):
        """Per axis: number of hold <-> track switches so far."""
        return [int(v) for v in self.ints[SWITCHES : SWITCHES + 3]]

    def _call(self, y, x, out):
        return self._kernel(y, x, out, *self._args)

    def step(self, y_dps, x_dps, out_dps):
        """Fast path for a pipeline: (M, 3) float64 C arrays in, ``out_dps`` (M, 3) written in
        place (it may be ``x_dps`` or ``y_dps`` itself: each element is read before it is
        written); no checks, no allocation."""
        self._kernel(y_dps, x_dps, out_dps, *self._args)

    def update(self, y_block_dps, x_track_dps):
        """One block: the block mean y = ``y_block_dps`` (3,) and the tracking filter's output
        x = ``x_track_dps`` (3,), deg/s -> output (3,), deg/s."""
        self._y1[0] = y_block_dps
        self._x1[0] = x_track_dps
        self._call(self._y1, self._x1, self._o1)
        return tuple(self._o1[0].tolist())

    def run(self, y_blocks_dps, x_track_dps):
        """Batch form: ``y_blocks_dps`` (M, 3) block means and ``x_track_dps`` (M, 3) tracking
        outputs, deg/s -> (M, 3); same numbers as update()."""
        y = np.ascontiguousarray(y_blocks_dps, dtype=float)
        x = np.ascontiguousarray(x_track_dps, dtype=float)
        if y.shape != x.shape or y.ndim != 2 or y.shape[1] != 3:
            raise SettingsError(f"block means {y.shape} and tracking output {x.shape} must both be (M, 3)")
        out = np.empty_like(y)
        if len(y):
            self._call(y, x, out)
        return out


#: the calibration window's blocks from which a vibration's scatter of the block means is trusted (block_noise_std)
VIBRATION_MIN_BLOCKS = 36
#: the block means' scatter, over sigma_w / sqrt(L), below which the window is a vibration's (block_noise_std)
VIBRATION_SCATTER = 0.4
#: how far below sigma_w / sqrt(L) a vibration can bring sigma_b (block_noise_std)
VIBRATION_SIGMA_FLOOR = 0.25


def block_noise_std(window_dps, block_len):
    """Standard deviation of a block mean at rest (deg/s), per axis, from ``window_dps``, a still
    (n, 3) window in deg/s, for blocks of L = ``block_len`` samples.

    sigma_b = max(s_b, sigma_w / sqrt(L)), where s_b is the std of the means of the window's m complete
    blocks and sigma_w = std(first differences) / sqrt(2) the white-noise level: the first term sees
    correlated noise (a low-pass stage makes block means noisier than sigma_w / sqrt(L)), the
    second keeps a short window's few blocks from underestimating sigma_b. A window of fewer
    than 2 blocks (a low sample rate) has only the second.

    A vibration the blocks average out makes sigma_w / sqrt(L) far larger than the block means' scatter
    (5 deg/s at 45 Hz, 100 Hz: 2.2 deg/s against s_b = 0.5), and the rest model then misses a small motion and
    holds the tail of it (+0.36 deg/s for seconds after 5 -> 0 deg/s in 1 s). Where the window has m >= 36
    blocks (the default 2-s calibration from 90 Hz: a "100-Hz" MPU6050 log at 99.3 Hz has 39) and
    s_b < 0.4 sigma_w / sqrt(L),

        sigma_b = max(s_b sqrt((m - 1) / chi2_0.05(m - 1)), sigma_w / (4 sqrt(L))),

    the upper 95 % bound of the block means' scatter, down to a quarter of the white-noise level (a half, tried
    first, still missed small turns under a vibration: a 1-deg/s turn under 10 deg/s at 45 Hz cost up to 5 degrees
    of heading, a quarter 3.6; the block means 0.3: docs/evaluate.md). A tone's block means scatter at 0.18-0.41
    of the white level (23-49 Hz at 100 Hz; 10-13 Hz, half a period a block, far above it). A still sensor's
    never fell below 0.45 with 39-40 blocks (every 10th start of the five static MPU6050 logs, every 50th of two
    ADIS16405 logs: 53 000 windows), but to 0.33 with 20 (attack pass 43: at 0.5 with 20 blocks a still log's
    z got a sigma_b of 0.6, 4 false switches and 3x the output std); a chi-square test at probability 0.001
    (tried first) took the 655-s log's z window at 0.61. The limits are also from attack
    pass 40, where sigma_b = the bound alone failed: a quiet quantised sensor's few blocks (m = 2-10) can have
    equal means (sigma_b 0: no averaging at all), and a 2-s window misses the slow beat of a vibration near a
    multiple of the block rate (49.9 Hz at 100 Hz), which a small sigma_b then follows.
    """
    x = np.asarray(window_dps, dtype=float)
    L = int(block_len)
    m = len(x) // L
    white = white_noise_std(x) / math.sqrt(L)
    if m < 2:
        return white
    means = x[: m * L].reshape(m, L, 3).mean(axis=1)
    sb_blocks = means.std(axis=0, ddof=1)
    sigma_b = np.maximum(sb_blocks, white)
    if m < VIBRATION_MIN_BLOCKS:
        return sigma_b
    vibrating = sb_blocks < VIBRATION_SCATTER * white
    bound = np.maximum(sb_blocks * math.sqrt((m - 1) / chi2_lower_quantile(0.95, m - 1)), VIBRATION_SIGMA_FLOOR * white)
    return np.where(vibrating, bound, sigma_b)


def make_hold(block_len, *, calibration_window_dps=None, noise_std_dps=None, **options):
    """The stage as a pipeline would build it after its start-up calibration.

    With ``calibration_window_dps``, the calibration window (n, 3) in deg/s: sigma_b =
    :func:`block_noise_std` of it, and
    the stage starts in hold with ``initial_blocks`` = n // block_len (the window passed the
    stillness check and the bias is removed). With only ``noise_std_dps`` (a calibration loaded
    from a file): sigma_b = noise_std / sqrt(block_len) and the stage starts in track, since
    nothing says the sensor is still now. ``options``: the ConstantRateHold settings.
    """
    L = int(block_len)
    if calibration_window_dps is not None:
        window = np.asarray(calibration_window_dps, dtype=float)
        sigma_b = block_noise_std(window, L)
        options.setdefault("initial_blocks", len(window) // L)
    elif noise_std_dps is not None:
        sigma_b = np.asarray(noise_std_dps, dtype=float) / math.sqrt(L)
        options.setdefault("initial_blocks", 0)
    else:
        raise SettingsError("make_hold needs the calibration window or the calibration's noise_std_dps")
    return ConstantRateHold(np.maximum(sigma_b, SIGMA_B_FLOOR_DPS), **options)
