"""Kalman filter with a least-squares-prediction prior (paper 001, section 2.3), three axes.

Per axis and per averaged measurement y_k (the block mean of :mod:`gyrofilter.averaging`):

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

:func:`run_blocks` is written in the subset of Python that numba compiles
(:mod:`gyrofilter.jit`); the streaming filter calls it one block at a time and the batch filter
once for all blocks, interpreted or compiled, so both paths execute the same arithmetic.
"""
import math

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


def run_blocks(y, out, w_table, fifo, p, qbuf, rbuf, sums, counters, r0, p0, window, use_std, r_fixed):
    """Filter the block means y (M, 3) into out (M, 3), updating the state arrays in place.

    State: fifo (3, D) ring of posteriors; p (3,) posterior variance; qbuf, rbuf (3, max(W, 1))
    rings of differences and measurements; sums (4, 3) running sums; counters (6,) int64.
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
