"""The paper-001 pipeline written the plain way: an oracle for tests and the benchmark baseline.

filterpy's KalmanFilter per axis and block, np.polyfit per prediction, np.var over explicit
windows. Slow and obvious on purpose; it shares no code with gyrofilter's kernel.
"""
import numpy as np
from filterpy.kalman import KalmanFilter


def plain_filter(samples_dps, sample_rate_hz, calibration_s=2.0, block_len=5, q_dps=1.0, depth=10, order=2, p0=1.0, window=10, use_std=False):
    """Paper 001's preset="paper" pipeline on ``samples_dps`` (N, 3) deg/s sampled at ``sample_rate_hz``.

    ``calibration_s`` of still start-up data give the bias and the noise, their gross errors (farther
    than max(``q_dps``, 6 robust sigmas) from their median) and their differences left out; blocks of ``block_len`` samples are
    averaged over the samples within ``q_dps`` deg/s of the block mean (of the median where
    none is); a Kalman filter per axis predicts with a degree-``order`` least-squares
    fit over the last ``depth`` posteriors, starts from P = ``p0``, and takes Q and R as the
    variance (standard deviation with ``use_std``) of the last ``window`` values.
    Returns the (M, 3) filtered block rates in deg/s, one row per block after calibration.
    """
    x = np.asarray(samples_dps, dtype=float)
    n_cal = int(round(calibration_s * sample_rate_hz))
    cal = x[:n_cal]
    bias, noise = np.empty(3), np.empty(3)
    for a in range(3):  # gross errors: beyond max(q, 6 x 1.4826 MAD) of the median, left out of both
        c = np.median(cal[:, a])
        ok = np.abs(cal[:, a] - c) <= max(q_dps, 6 * 1.4826 * np.median(np.abs(cal[:, a] - c)))
        bias[a] = cal[ok, a].mean()
        pairs = ok[1:] & ok[:-1]
        noise[a] = np.std(np.diff(cal[:, a])[pairs], ddof=1) / np.sqrt(2.0)
    r0 = np.maximum(noise**2 / block_len, 1e-12)
    if use_std:
        r0 = np.sqrt(r0)
    body = x[n_cal:]
    m = len(body) // block_len
    blocks = body[: m * block_len].reshape(m, block_len, 3)
    out = np.empty((m, 3))
    stat = (lambda v: max(np.std(v, ddof=1), 1e-12)) if use_std else (lambda v: max(np.var(v, ddof=1), 1e-12))
    for a in range(3):
        kf = KalmanFilter(dim_x=1, dim_z=1)
        kf.F[:] = 1.0
        kf.H[:] = 1.0
        posts, diffs, meas = [], [], []
        for k in range(m):
            b = blocks[k, :, a]
            mean = b.mean()
            center = mean
            keep = np.abs(b - center) <= q_dps
            if not keep.any():  # every sample rejected: re-centre on the median
                center = np.median(b)
                keep = np.abs(b - center) <= q_dps
            y = (b[keep].mean() if keep.any() else center) - bias[a]
            meas.append(y)
            if k == 0:
                prior, p_prior = 0.0, p0
            else:
                hist = np.array(posts[-depth:])
                t = np.arange(len(hist))
                coef = np.polyfit(t, hist, min(order, len(hist) - 1))
                prior = np.polyval(coef, len(hist))
                q = stat(diffs[-window:]) if len(diffs) >= 2 else r0[a]
                kf.x[:] = prior
                kf.Q[:] = q
                kf.predict()
                p_prior = kf.P[0, 0]
            r = stat(meas[-window:]) if len(meas) >= 2 else r0[a]
            kf.x[:] = prior
            kf.P[:] = p_prior
            kf.update(y, R=r)
            post = kf.x[0, 0]
            if k > 0:
                diffs.append(post - prior)
            posts.append(post)
            out[k, a] = post
    return out
