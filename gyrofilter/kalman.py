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

Paper 001's noise statistics make the gain collapse in motion, and its loop is unstable for
gains below 0.335 (:func:`gyrofilter.predictor.closed_loop_radius`): it diverges. Two additions,
both off in preset "paper": the divergence guard (:func:`_guard`, in both kernels) and
:func:`run_blocks_adaptive`, the same LS prior with R from the calibration, covariance matching of
the innovations, a gain kept in the stable region and a constant-rate model at rest (preset
"adaptive_kalman").

:func:`run_blocks` is written in the subset of Python that numba compiles
(:mod:`gyrofilter.jit`); the streaming filter calls it one block at a time and the batch filter
once for all blocks, interpreted or compiled, so both paths execute the same arithmetic; so is
:func:`run_blocks_adaptive`.
"""
import math

import numpy as np

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

    Settings: ``w_table`` the LS extrapolation weights (:func:`gyrofilter.predictor.weight_table`);
    ``r0`` (3,) the initial Q and R ((deg/s)^2, or deg/s with ``use_std``); ``p0`` P0
    ((deg/s)^2); ``window`` W of eqs. 11-12 (0 = all); ``use_std``: sigma is the standard
    deviation (``qr_stat="std"``); ``r_fixed``: R stays r0 (``r_source="calibration"``);
    ``guard_sigma`` (3,) sigma_b (deg/s), ``guard_k`` and ``guard_n``: the guard's limit in
    sigma_b and its run length (:func:`_guard`).

    State: fifo (3, D) ring of posteriors; p (3,) posterior variance; qbuf, rbuf (3, max(W, 1))
    rings of differences and measurements; sums (4, 3) running sums; counters (6,) int64;
    guard_run (6,) int64: per axis the guard's run length and its re-seed count (guard_n = 0:
    no guard, the faithful filter; see :func:`_guard`).
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
            if guard_n > 0 and _guard(x, ya, a, guard_sigma[a] * guard_k, guard_n, guard_run):
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


def _guard(x, ya, a, limit, n_blocks, guard_run):
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


# ---------------------------------------------------------------------------------------------
# adaptive Kalman filter (preset "adaptive_kalman"): the paper's LS prior, noise statistics
# estimated so that the loop stays stable; see run_blocks_adaptive

# rows of the float state fstate (3 rows, one column per axis)
C_HAT, G_POS, G_NEG = range(3)
# indices into the int state istate (14,)
A_COUNT, A_HEAD, R_FILLED, R_RING_HEAD = range(4)
MODE, SWITCHES = 4, 7  # istate[MODE + a]: 0 = constant-rate model (rest, steady turn), 1 = LS model
REST, MOTION = 0, 1
A_INTS = 10
# fields of the trace, trace[k, field, axis]: the posterior variance, the prior and its variance
POST_VAR, PRIOR, PRIOR_VAR = range(3)
NO_TRACE = np.empty((0, 3, 3))
NO_USED = np.empty((0, 3), dtype=np.int64)


def run_blocks_adaptive(y, y_motion, out, w_table, fifo, p, fstate, istate, ring, r, gain_min, forgetting, prior_var_max,
                        kappa, h, chi2_limit, agree_z, max_blocks, guard_k, guard_n, guard_run, trace, used):
    """Adaptive Kalman filter over the block means y (M, 3) -> out (M, 3); state updated in place.

    Measurement per block and axis: y[k, a] while the axis is in the constant-rate model at the
    start of block k, ``y_motion[k, a]`` while it is in the LS model (the block means of two
    gross-error rules, ``outlier_rule="by_model"``; pass y twice for one rule). ``used``: (M, 3)
    int64 to receive that model per block and axis (REST / MOTION), or :data:`NO_USED`.

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
    (:func:`gyrofilter.predictor.closed_loop_radius`). K_min = ``gain_min`` keeps the loop in
    that region (0.6: radius 0.91, and the loop's white-noise variance gain sum h_j^2 is 0.55,
    its minimum over K); the constant-rate model is stable for any K in (0, 1].

    Switching (per axis, the tests of :mod:`gyrofilter.adaptive`): constant-rate -> LS when a
    two-sided CUSUM of d_k = (y_k - x-_k) / sigma_b passes h (drift ``kappa``, Page 1954);
    LS -> constant-rate when the last W block means are a constant plus white noise
    ((W - 1) s^2 / R below ``chi2_limit``) and x_k is within ``agree_z`` sigma_b of their mean m:
    then x_k = m, P_k = R / W. On the switch to the LS model C = P + R.

    Divergence guard: :func:`_guard` (limit ``guard_k`` sigma_b, run length ``guard_n``; 0 = off);
    a re-seed also puts the axis in the LS model with C = R. ``w_table``: the LS extrapolation
    weights (:func:`gyrofilter.predictor.weight_table`).

    State (fixed size): fifo (3, D) posteriors, p (3,), fstate (3, 3) rows C, g+, g-; istate
    (10,) int64 (FIFO count and head, block-mean ring fill and head, model and switch count per
    axis); ring (3, W) block means; guard_run (6,) int64.

    ``trace``: (M, 3, 3) to be filled with trace[k, POST_VAR | PRIOR | PRIOR_VAR, axis] (P_k,
    x-_k, P-_k of the model in use; for the forward-backward smoother,
    :mod:`gyrofilter.smoother`), or :data:`NO_TRACE` (no rows: nothing written).
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
                    if ss / ra < chi2_limit and abs(x - m) < agree_z * sigma:
                        istate[MODE + a] = REST
                        istate[SWITCHES + a] += 1
                        x = m
                        p_post = ra / window
            if guard_n > 0 and _guard(x, ya, a, guard_k * sigma, guard_n, guard_run):
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


class PaperKalman:
    """Paper 001's Kalman stage for three axes: :func:`run_blocks` with its state.

    ``settings`` is a :class:`gyrofilter.pipeline.FilterSettings`; ``sigma_b_dps`` (3,) is the
    standard deviation of a block mean at rest (deg/s) that the divergence guard measures in,
    an array the caller keeps and may update in place. The state has a fixed size (see
    :func:`run_blocks`) and is updated in place by :meth:`run`; :meth:`start` sets the initial
    Q and R once the calibration's noise is known.
    """

    def __init__(self, settings, sigma_b_dps):
        from .jit import choose_kernel
        from .predictor import weight_table

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


class AdaptiveKalman:
    """The adaptive Kalman stage for three axes: :func:`run_blocks_adaptive` with its state.

    ``settings`` is a :class:`gyrofilter.pipeline.FilterSettings`. The state has a fixed size
    (see :func:`run_blocks_adaptive`) and is updated in place by :meth:`run`; :meth:`start`
    sets R and the starting model once sigma_b, the standard deviation of a block mean at rest,
    is known. The forward-backward smoother runs a second instance over the reversed block
    means (:mod:`gyrofilter.smoother`).
    """

    def __init__(self, settings):
        from .adaptive import DEFAULTS, chi2_quantile
        from .jit import choose_kernel
        from .predictor import weight_table

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
            float(s.hold_h), chi2_quantile(DEFAULTS["accept_p"], s.hold_window - 1), DEFAULTS["agree_z"],
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
