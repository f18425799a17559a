"""The adaptive Kalman filter (preset "adaptive_kalman", and the tracker of "recommended"): paper
001's least-squares prior (:mod:`gyrofilter.filter.kalman`) with noise statistics estimated so that
the loop stays stable, and a constant-rate model at rest.

Two models per axis, one of them in use (a two-model switch, the hard-decision limit of an
interacting multiple model, Blom & Bar-Shalom 1988), both with C = 1 and the measurement
variance R = sigma_b^2 fixed at the block-mean noise of the still calibration window (``r``;
never a window that contains motion: paper 001's eq. 12 is what makes its gain collapse):

constant-rate model (rest, steady turns):
    x-_k = x_(k-1),  P-_k = P_(k-1)                         (A = 1, Q = 0)
    K_k = P-_k / (P-_k + R),  x_k = x-_k + K_k (y_k - x-_k),  P_k = max((1 - K_k) P-_k, R / N)
  from P = R / n this is the running mean of the last n block means (K = 1/(n + 1)), with its
  memory bounded at N = ``max_blocks`` (an exponential mean beyond): the hold's average.
LS model (motion), paper 001 eqs. 4-10 with the noise statistics of covariance matching:
    x-_k = sum_i w_i x_(k-n+i)                              LS quadratic over the FIFO (eqs. 8-10)
    nu_k = y_k - x-_k,  C_k = (1 - a) C_(k-1) + a nu_k^2   innovation variance, forgetting a
    P-_k = max(P_(k-1), C_k - R)                            (Mehra 1970: E nu^2 = P- + R)
    K_k = max(P-_k / (P-_k + R), K_min),  x_k = x-_k + K_k nu_k,
    P_k = (1 - K_k)^2 P-_k + K_k^2 R        (Joseph form: right for any gain, also K_min and 1)
  The innovation of the current block is in C_k (as in the strong tracking filter, Zhou &
  Frank 1996), so a change of motion opens the gain in the block it appears.
measurement-only model (fast motion): when P-_k > m R (m = ``prior_var_max``; 0 = never)
  the LS prior is not used, K_k = 1 and x_k = y_k. Covariance matching assumes the prior's
  error is white; in fast motion it is the fit's systematic error (a 1-Hz sine moves too much
  over the 10 blocks of the FIFO), and a gain of 1 - R / C still leaves a small systematic
  part of it in the output. m = 4: the prior would carry at most 1/5 of the weight.

Stability: with a constant gain K the LS loop is x_k = (1 - K) sum_i w_i x_(k-n+i) + K y_k,
characteristic polynomial z^n - (1 - K) sum_i w_i z^i; the 10-point quadratic weights have a
triple root at z = 1 for K = 0 and the largest root modulus is < 1 only for K > 0.335
(:func:`gyrofilter.filter.predictor.closed_loop_radius`). K_min = ``gain_min`` keeps the loop in
that region (0.6: radius 0.91, and the loop's white-noise variance gain sum h_j^2 is 0.55,
its minimum over K); the constant-rate model is stable for any K in (0, 1].

Switching (per axis, the tests of :mod:`gyrofilter.filter.hold`): constant-rate -> LS when a
two-sided CUSUM (Page 1954) of the innovation, Huber-clipped (Huber 1964) where gross errors can
explain it, passes h:

    e_k = y_k - x-_k,  d_k = e_k / sigma_b, clipped to [-c, c] if |e_k| <= b,
    g+_k = max(0, g+_(k-1) + d_k - kappa),  g-_k = max(0, g-_(k-1) - d_k - kappa),
    switch when g+_k > h or g-_k > h.

c = ``cusum_clip`` = 6 with kappa = 0.5, h = 10: one such block adds at most c - kappa = 5.5 < h,
two consecutive ones 11 > h. b = ``cusum_clip_within_q`` q = 3 q: paper 001's rule keeps a sample
within q of its block's mean, so j equal gross errors s kept in a block of L (the clean samples
rejected) need s (1 - j / L) <= q and move the block mean by at most q L / (L - j): 2.5 q for
3 of 5. Where two or three gross errors in one block defeat the rule (its mean then ~30 sigma_b
off), that single block no longer knocks the axis out of rest; a change of more than b (a step,
a fast sine) is still caught in its first block, a slower onset (a ramp) one block later. After
one clipped block g is at most 5.5 and white noise (drift -kappa) adds the missing 4.5 with
probability about 1 % (simulated: 0.9 %; Brownian approximation exp(-2 kappa 4.5) = 1.1 %).
On white noise |d| > 6 is rare: the false-alarm rate is that of the unclipped test.
LS -> constant-rate when the last W block means are a constant plus white noise
((W - 1) s^2 / R below ``chi2_limit``, no trend: :func:`gyrofilter.filter.hold.trend_free`) and x_k
is within ``agree_z`` sigma_b of their mean m:
then x_k = the mean of the latest W / 2 of them, P_k = R / (W / 2) (the hold's rule,
:func:`gyrofilter.filter.hold.recent_mean`). On the switch to the LS model C = P + R.

Written in the subset of Python that numba compiles (:mod:`gyrofilter.filter.jit`), like
:func:`gyrofilter.filter.kalman.run_blocks`: the streaming and the batch filter execute the same
arithmetic, interpreted or compiled.
"""
import math

import numpy as np

from .hold import DEFAULTS, chi2_quantile, recent_mean, trend_free
from .jit import choose_kernel
from .kalman import guard
from .predictor import weight_table

# rows of the float state fstate (3 rows, one column per axis)
C_HAT, G_POS, G_NEG = range(3)
# indices into the int state istate (A_INTS,)
A_COUNT, A_HEAD, R_FILLED, R_RING_HEAD = range(4)
MODE, SWITCHES = 4, 7  # istate[MODE + a]: 0 = constant-rate model (rest, steady turn), 1 = LS model
REST, MOTION = 0, 1
A_INTS = 10
# fields of the trace, trace[k, field, axis]: the posterior variance, the prior and its variance
POST_VAR, PRIOR, PRIOR_VAR = range(3)
NO_TRACE = np.empty((0, 3, 3))
NO_USED = np.empty((0, 3), dtype=np.int64)


def run_blocks_adaptive(y, y_motion, out, w_table, fifo, p, fstate, istate, ring, r, gain_min, forgetting, prior_var_max,
                        kappa, clip, clip_within_dps, h, chi2_limit, agree_z, max_blocks, guard_k, guard_n, guard_run,
                        trace, used):
    """Adaptive Kalman filter over the block means y (M, 3) -> out (M, 3); state updated in place.

    Measurement per block and axis: y[k, a] while the axis is in the constant-rate model at the
    start of block k, ``y_motion[k, a]`` while it is in the LS model (the block means of two
    gross-error rules, ``outlier_rule="by_model"``; pass y twice for one rule). ``used``: (M, 3)
    int64 to receive that model per block and axis (REST / MOTION), or :data:`NO_USED`.

    The equations and the switching are in the module docstring.

    Divergence guard: :func:`gyrofilter.filter.kalman.guard` (limit ``guard_k`` sigma_b, run length ``guard_n``; 0 = off);
    a re-seed also puts the axis in the LS model with C = R. ``w_table``: the LS extrapolation
    weights (:func:`gyrofilter.filter.predictor.weight_table`).

    State (fixed size): fifo (3, D) posteriors, p (3,), fstate (3, 3) rows C, g+, g-; istate
    (10,) int64 (FIFO count and head, block-mean ring fill and head, model and switch count per
    axis); ring (3, W) block means; guard_run (6,) int64.

    ``trace``: (M, 3, 3) to be filled with trace[k, POST_VAR | PRIOR | PRIOR_VAR, axis] (P_k,
    x-_k, P-_k of the model in use; for the forward-backward smoother,
    :mod:`gyrofilter.filter.smoother`), or :data:`NO_TRACE` (no rows: nothing written).
    """
    tracing = trace.shape[0] > 0
    telling = used.shape[0] > 0
    depth = fifo.shape[1]
    window = ring.shape[1]
    for k in range(y.shape[0]):
        count = istate[A_COUNT]
        head = istate[A_HEAD]
        rh = istate[R_RING_HEAD]
        for a in range(3):
            ring[a, rh] = y[k, a] if istate[MODE + a] == REST else y_motion[k, a]
            if telling:
                used[k, a] = istate[MODE + a]
        istate[R_RING_HEAD] = (rh + 1) % window
        if istate[R_FILLED] < window:
            istate[R_FILLED] += 1
        n = count if count < depth else depth
        for a in range(3):
            ya = ring[a, rh]
            ra = r[a]
            sigma = math.sqrt(ra)
            x = 0.0
            p_post = 0.0
            prior = 0.0
            p_prior = 0.0
            if istate[MODE + a] == REST:
                prior = fifo[a, (head - 1) % depth] if n > 0 else 0.0
                d = (ya - prior) / sigma
                if abs(ya - prior) <= clip_within_dps:
                    d = max(-clip, min(clip, d))
                fstate[G_POS, a] = max(0.0, fstate[G_POS, a] + d - kappa)
                fstate[G_NEG, a] = max(0.0, fstate[G_NEG, a] - d - kappa)
                if fstate[G_POS, a] > h or fstate[G_NEG, a] > h:
                    istate[MODE + a] = MOTION
                    istate[SWITCHES + a] += 1
                    fstate[G_POS, a] = 0.0
                    fstate[G_NEG, a] = 0.0
                    fstate[C_HAT, a] = p[a] + ra
                else:
                    p_prior = p[a]
                    gain = p_prior / (p_prior + ra)
                    x = prior + gain * (ya - prior)
                    p_post = (1.0 - gain) * p_prior
                    if p_post < ra / max_blocks:
                        p_post = ra / max_blocks
            if istate[MODE + a] == MOTION:
                prior = 0.0
                for j in range(n):
                    prior += w_table[n - 1, j] * fifo[a, (head - n + j) % depth]
                nu = ya - prior
                c = (1.0 - forgetting) * fstate[C_HAT, a] + forgetting * nu * nu
                fstate[C_HAT, a] = c
                p_prior = p[a]
                if c - ra > p_prior:
                    p_prior = c - ra
                gain = p_prior / (p_prior + ra)
                if gain < gain_min:
                    gain = gain_min
                if prior_var_max > 0.0 and p_prior > prior_var_max * ra:
                    gain = 1.0
                x = prior + gain * nu
                p_post = (1.0 - gain) * (1.0 - gain) * p_prior + gain * gain * ra
                if istate[R_FILLED] == window:
                    m = 0.0
                    for j in range(window):
                        m += ring[a, j]
                    m /= window
                    ss = 0.0
                    for j in range(window):
                        ss += (ring[a, j] - m) * (ring[a, j] - m)
                    if ss / ra < chi2_limit and abs(x - m) < agree_z * sigma and trend_free(ring, a, rh, sigma, agree_z):
                        istate[MODE + a] = REST
                        istate[SWITCHES + a] += 1
                        x = recent_mean(ring, a, rh)
                        p_post = ra / (window // 2)
            if guard_n > 0 and guard(x, ya, a, guard_k * sigma, guard_n, guard_run):
                x = ya
                p_post = ra
                for j in range(depth):
                    fifo[a, j] = ya
                istate[MODE + a] = MOTION
                fstate[C_HAT, a] = ra
                fstate[G_POS, a] = 0.0
                fstate[G_NEG, a] = 0.0
            p[a] = p_post
            out[k, a] = x
            fifo[a, head] = x
            if tracing:
                trace[k, POST_VAR, a] = p_post
                trace[k, PRIOR, a] = prior
                trace[k, PRIOR_VAR, a] = p_prior
        istate[A_HEAD] = (head + 1) % depth
        istate[A_COUNT] = count + 1 if count < depth else depth
    return out


class AdaptiveKalman:
    """The adaptive Kalman stage for three axes: :func:`run_blocks_adaptive` with its state.

    ``settings`` is a :class:`gyrofilter.filter.settings.FilterSettings`. The state has a fixed size
    (see :func:`run_blocks_adaptive`) and is updated in place by :meth:`run`; :meth:`start`
    sets R and the starting model once sigma_b, the standard deviation of a block mean at rest,
    is known. The forward-backward smoother runs a second instance over the reversed block
    means (:mod:`gyrofilter.filter.smoother`).
    """

    def __init__(self, settings):
        s = settings
        self.settings = s
        self.fifo = np.zeros((3, s.fifo_depth))
        self.p = np.zeros(3)
        self.fstate = np.zeros((3, 3))
        self.istate = np.zeros(A_INTS, dtype=np.int64)
        self.ring = np.zeros((3, s.hold_window))
        self.r_dps2 = np.ones(3)
        self.guard_run = np.zeros(6, dtype=np.int64)
        self._kernel = choose_kernel(run_blocks_adaptive, s.backend)
        # bound once: the arrays are updated in place
        self._args = (
            weight_table(s.fifo_depth, s.fit_order), self.fifo, self.p, self.fstate, self.istate, self.ring, self.r_dps2,
            float(s.gain_min), float(s.innovation_forgetting), float(s.prior_var_max_r), DEFAULTS["cusum_kappa"],
            DEFAULTS["cusum_clip"], DEFAULTS["cusum_clip_within_q"] * float(s.outlier_q_dps), float(s.hold_h),
            chi2_quantile(DEFAULTS["accept_p"], s.hold_window - 1), DEFAULTS["agree_z"],
            s.hold_max_blocks, float(s.guard_k_sigma), s.guard_blocks, self.guard_run,
        )

    def start(self, sigma_b_dps, still_blocks):
        """R = sigma_b^2 per axis (sigma_b = ``sigma_b_dps``, deg/s). After n = ``still_blocks`` still blocks (the calibration's,
        bias removed: x = 0) start in the constant-rate model with P = R / min(n, N), the mean of
        n zeros; with n = 0 (nothing known of the motion now) in the LS model with P = P0 and
        C = P0 + R."""
        s = self.settings
        self.r_dps2[:] = np.asarray(sigma_b_dps, dtype=float) ** 2
        if still_blocks > 0:
            self.istate[A_COUNT] = s.fifo_depth
            self.istate[MODE : MODE + 3] = REST
            self.p[:] = self.r_dps2 / min(still_blocks, s.hold_max_blocks)
        else:
            self.istate[MODE : MODE + 3] = MOTION
            self.p[:] = s.p0_dps2
            self.fstate[C_HAT] = s.p0_dps2 + self.r_dps2

    def run(self, y, out, trace=NO_TRACE, y_motion=None, used=NO_USED):
        """Block means y (M, 3) -> out (M, 3); ``trace``, ``y_motion`` (default: y) and ``used`` as
        in :func:`run_blocks_adaptive`."""
        self._kernel(y, y if y_motion is None else y_motion, out, *self._args, trace, used)

    def modes(self):
        """Per axis: the model the next block starts in (REST or MOTION), a list of 3 ints."""
        return self.istate[MODE : MODE + 3].tolist()

    @property
    def switches(self):
        """Per axis: how often the filter changed between its constant-rate and LS models."""
        return self.istate[SWITCHES : SWITCHES + 3].tolist()
