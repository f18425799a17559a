"""Kalman filter with a least-squares-prediction prior (paper 001, section 2.3), three axes.

Per axis and per averaged measurement y_k (the block mean of :mod:`gyrofilter.filter.averaging`):

    prior      x-_k = sum_i w_i x_(k-n+i)           LS quadratic fit of the last n posteriors
                                                      evaluated at the next step (eqs. 8-10)
    prior var  P-_k = P_(k-1) + Q_k                  eq. 4 with A = 1 (our reading: the LS
                                                      prediction replaces A x, P is carried over)
    gain       K_k  = P-_k / (P-_k + R_k)            eq. 5 with C = 1
    posterior  x_k  = x-_k + K_k (y_k - x-_k)        eq. 6
    post. var  P_k  = (1 - K_k) P-_k                 eq. 7

    Q_k = sigma(x_j - x-_j)   over the last W differences before step k        (eq. 11)
    R_k = sigma(y_j)          over the last W measurements, y_k included        (eq. 12)

Readings of what the paper leaves open (each alternative is a setting of GyroFilter):

* ``sigma`` in eqs. 11-12: the paper's tables label the standard deviation "Variance sigma
  (deg/s)", but the text says variance and a Kalman filter needs variances. Default: the
  sample variance (ddof = 1); ``qr_stat="std"`` uses the standard deviation as written.
* The samples sigma is taken over: the last W = ``qr_window`` values (default 10, the FIFO
  depth, the only window the paper names); ``qr_window=0`` uses every value since start.
  Running sums keep the cost fixed per step (no growth with time).
* ``r_source="calibration"`` fixes R at the calibration noise variance / L instead.
* Start: the first prior is 0 deg/s (the bias is removed and the sensor is still) with
  variance P0 = ``p0_dps2``. While fewer than n posteriors exist, the fit uses the k available
  points with order min(order, k - 1). Until a window holds 2 values, Q and R take the initial
  value r0 (the calibration's white-noise variance / L). Variances are floored at 1e-12 dps^2
  so that a perfectly constant input cannot divide 0 by 0.

Paper 001's noise statistics make the gain collapse in motion, and its loop is unstable for
gains below 0.335 (:func:`gyrofilter.filter.predictor.closed_loop_radius`): it diverges. Two additions,
both off in preset "paper": the divergence guard (:func:`guard`, here, used by both filters) and
the adaptive Kalman filter of :mod:`gyrofilter.filter.adaptive_kalman` (the same LS prior with R
from the calibration, covariance matching of the innovations, a gain kept in the stable region
and a constant-rate model at rest; preset "adaptive_kalman").

:func:`run_blocks` is written in the subset of Python that numba compiles
(:mod:`gyrofilter.filter.jit`); the streaming filter calls it one block at a time and the batch filter
once for all blocks, interpreted or compiled, so both paths execute the same arithmetic.
"""
import math

import numpy as np

from .jit import choose_kernel
from .predictor import weight_table

VAR_FLOOR = 1e-12

# indices into the integer state vector
COUNT, HEAD, Q_COUNT, Q_HEAD, R_COUNT, R_HEAD = range(6)
# rows of the running-sum state array (each row holds x, y, z)
Q_SUM, Q_SUMSQ, R_SUM, R_SUMSQ = range(4)


def _window_stat(s1, s2, n, use_std):
    var = (s2 - s1 * s1 / n) / (n - 1)
    if var < 0.0:
        var = 0.0
    if use_std:
        var = math.sqrt(var)
    if var < VAR_FLOOR:
        var = VAR_FLOOR
    return var


def run_blocks(y, out, w_table, fifo, p, qbuf, rbuf, sums, counters, r0, p0, window, use_std, r_fixed,
               guard_sigma, guard_k, guard_n, guard_run):
    """Filter the block means y (M, 3) into out (M, 3), deg/s, updating the state arrays in place.

    Settings: ``w_table`` the LS extrapolation weights (:func:`gyrofilter.filter.predictor.weight_table`);
    ``r0`` (3,) the initial Q and R ((deg/s)^2, or deg/s with ``use_std``); ``p0`` P0
    ((deg/s)^2); ``window`` W of eqs. 11-12 (0 = all); ``use_std``: sigma is the standard
    deviation (``qr_stat="std"``); ``r_fixed``: R stays r0 (``r_source="calibration"``);
    ``guard_sigma`` (3,) sigma_b (deg/s), ``guard_k`` and ``guard_n``: the guard's limit in
    sigma_b and its run length (:func:`guard`).

    State: fifo (3, D) ring of posteriors; p (3,) posterior variance; qbuf, rbuf (3, max(W, 1))
    rings of differences and measurements; sums (4, 3) running sums; counters (6,) int64;
    guard_run (6,) int64: per axis the guard's run length and its re-seed count (guard_n = 0:
    no guard, the faithful filter; see :func:`guard`).
    """
    depth = fifo.shape[1]
    for k in range(y.shape[0]):
        count = counters[COUNT]
        head = counters[HEAD]
        for a in range(3):
            ya = y[k, a]
            # prior: LS extrapolation of the FIFO (oldest first), or 0 with variance P0 at start
            if count == 0:
                prior = 0.0
                p_prior = p0
            else:
                n = count if count < depth else depth
                prior = 0.0
                for j in range(n):
                    prior += w_table[n - 1, j] * fifo[a, (head - n + j) % depth]
                if counters[Q_COUNT] >= 2:
                    q = _window_stat(sums[Q_SUM, a], sums[Q_SUMSQ, a], counters[Q_COUNT], use_std)
                else:
                    q = r0[a]
                p_prior = p[a] + q
            # measurement noise: statistic of the recent measurements, y_k included
            # (the R and Q ring updates are written out twice on purpose: a shared helper made
            # the numba batch path 22 % slower, tools/bench.py pipeline)
            if window > 0 and counters[R_COUNT] == window:
                old = rbuf[a, counters[R_HEAD]]
                sums[R_SUM, a] -= old
                sums[R_SUMSQ, a] -= old * old
            if window > 0:
                rbuf[a, counters[R_HEAD]] = ya
            sums[R_SUM, a] += ya
            sums[R_SUMSQ, a] += ya * ya
            n_r = counters[R_COUNT] + 1
            if window > 0 and n_r > window:
                n_r = window
            if r_fixed or n_r < 2:
                r = r0[a]
            else:
                r = _window_stat(sums[R_SUM, a], sums[R_SUMSQ, a], n_r, use_std)
            # update (eqs. 5-7)
            gain = p_prior / (p_prior + r)
            x = prior + gain * (y[k, a] - prior)
            p[a] = (1.0 - gain) * p_prior
            if guard_n > 0 and guard(x, ya, a, guard_sigma[a] * guard_k, guard_n, guard_run):
                x = ya
                p[a] = r
                for j in range(depth):
                    fifo[a, j] = ya
            out[k, a] = x
            fifo[a, head] = x
            # process noise sample for the next step: posterior - prior (eq. 11)
            if count > 0:
                d = x - prior
                if window > 0 and counters[Q_COUNT] == window:
                    old = qbuf[a, counters[Q_HEAD]]
                    sums[Q_SUM, a] -= old
                    sums[Q_SUMSQ, a] -= old * old
                if window > 0:
                    qbuf[a, counters[Q_HEAD]] = d
                sums[Q_SUM, a] += d
                sums[Q_SUMSQ, a] += d * d
        # advance the shared ring positions and counts once per block
        counters[HEAD] = (head + 1) % depth
        counters[COUNT] = count + 1
        if window > 0:
            counters[R_HEAD] = (counters[R_HEAD] + 1) % window
            counters[R_COUNT] = min(counters[R_COUNT] + 1, window)
        else:
            counters[R_COUNT] += 1
        if count > 0:
            if window > 0:
                counters[Q_HEAD] = (counters[Q_HEAD] + 1) % window
                counters[Q_COUNT] = min(counters[Q_COUNT] + 1, window)
            else:
                counters[Q_COUNT] += 1
    return out


# ---------------------------------------------------------------------------------------------
# divergence guard (all Kalman settings but the faithful "paper" preset)

GUARD_RUN, GUARD_RESEEDS = 0, 3  # guard_run[GUARD_RUN + a], guard_run[GUARD_RESEEDS + a]


def guard(x, ya, a, limit, n_blocks, guard_run):
    """Divergence guard, one axis and block: True when the filter must be re-seeded.

    Counts the blocks in a row with |x_k - y_k| > k sigma_b (``limit`` = k sigma_b, sigma_b the
    standard deviation of a block mean at rest); after ``n_blocks`` of them the caller re-seeds
    the filter from the block mean: x_k = y_k, every FIFO slot = y_k (so the next LS prior is
    y_k), P_k = R. A filter that follows the data is never k sigma_b from it for long; one
    that diverges (paper 001's filter in fast motion: the gain collapses and the quadratic
    extrapolation runs away) is.
    """
    if abs(x - ya) > limit:
        guard_run[GUARD_RUN + a] += 1
    else:
        guard_run[GUARD_RUN + a] = 0
    if guard_run[GUARD_RUN + a] >= n_blocks:
        guard_run[GUARD_RUN + a] = 0
        guard_run[GUARD_RESEEDS + a] += 1
        return True
    return False


class PaperKalman:
    """Paper 001's Kalman stage for three axes: :func:`run_blocks` with its state.

    ``settings`` is a :class:`gyrofilter.filter.settings.FilterSettings`; ``sigma_b_dps`` (3,) is the
    standard deviation of a block mean at rest (deg/s) that the divergence guard measures in,
    an array the caller keeps and may update in place. The state has a fixed size (see
    :func:`run_blocks`) and is updated in place by :meth:`run`; :meth:`start` sets the initial
    Q and R once the calibration's noise is known.
    """

    def __init__(self, settings, sigma_b_dps):
        s = settings
        self.settings = s
        width = max(s.qr_window, 1)
        self.r0 = np.full(3, s.p0_dps2)
        self.guard_run = np.zeros(6, dtype=np.int64)
        self._kernel = choose_kernel(run_blocks, s.backend)
        # bound once: the arrays are updated in place
        self._args = (
            weight_table(s.fifo_depth, s.fit_order), np.zeros((3, s.fifo_depth)), np.zeros(3), np.zeros((3, width)), np.zeros((3, width)),
            np.zeros((4, 3)), np.zeros(6, dtype=np.int64), self.r0, s.p0_dps2, s.qr_window, s.qr_stat == "std",
            s.r_source == "calibration", sigma_b_dps, float(s.guard_k_sigma), s.guard_blocks, self.guard_run,
        )

    def start(self, noise_std_dps):
        """Initial Q and R (paper 001): the variance of a block mean of the calibration's white
        noise, r0 = max(sigma^2 / L, VAR_FLOOR) per axis (``noise_std_dps``: sigma per axis,
        deg/s; L = block_len); its square root with ``qr_stat="std"``."""
        s = self.settings
        self.r0[:] = [max(n * n / s.block_len, VAR_FLOOR) for n in noise_std_dps]
        if s.qr_stat == "std":
            np.sqrt(self.r0, out=self.r0)

    def run(self, y, out):
        """Block means y (M, 3) -> out (M, 3) (deg/s), the state updated in place."""
        self._kernel(y, out, *self._args)
