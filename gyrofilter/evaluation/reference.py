"""Reference angular rate from an orientation (quaternion) series, and its time alignment.

An optical motion-capture system gives the orientation q_k of the sensor body with respect to a
fixed frame (BROAD: IMU with respect to ENU, Hamilton quaternions ``w, x, y, z``), so that a
vector in body coordinates maps to the fixed frame as v_E = q v_B q*. If the body turns at the
body-frame rate omega, q(t + dt) = q(t) (x) exp(omega dt / 2), hence the body-frame rate over an
interval is

    omega = rotvec(q_a^-1 (x) q_b) / (t_b - t_a)                                     (1)

(rotvec: rotation vector = axis * angle of the relative rotation; the quaternion sign is chosen
with w >= 0, the shortest rotation). This is the rate a strapdown gyro measures, in its own
frame, up to bias and noise (Laidig et al., BROAD, Data 6(7) 2021, section on the OMC reference).

:func:`body_rate_from_quaternions` uses the *central* difference over a half span of h samples,

    omega_k = rotvec(q_{k-h}^-1 (x) q_{k+h}) * fs / (2 h),                              (2)

the mean rate over [t_{k-h}, t_{k+h}], centred on sample k, so the reference is on the gyro's
sample instants with no half-sample shift (a forward difference q_k^-1 q_{k+1} would describe
t_k + dt/2). A larger h smooths the differentiation noise of the optical data (the noise of (2)
falls as 1/h) at the cost of averaging fast motion (a moving average of width 2h).

Missing optical data (marker occlusion, NaN quaternions) is never bridged: omega_k is NaN unless
every quaternion in [k-h, k+h] is finite, and the first and last h samples are NaN. Metrics must
mask NaN reference samples (:func:`block_mean_masked` propagates them).

:func:`estimate_time_offset_s` checks the synchronisation of reference and gyro by normalised
cross-correlation over the samples where both are finite, summed over the three axes, with a
parabolic fit through the peak for a sub-sample estimate.
"""
from __future__ import annotations

import numpy as np

from ..errors import SettingsError
from ..units import check_sample_rate_hz, plain, to_dps


def quat_multiply(p, q):
    """Hamilton product p (x) q of quaternion arrays (..., 4) ordered w, x, y, z."""
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    pw, px, py, pz = np.moveaxis(p, -1, 0)
    qw, qx, qy, qz = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        axis=-1,
    )


def quat_conjugate(q):
    """Conjugate of quaternions ``q`` (..., 4), w, x, y, z order (the inverse of a unit quaternion)."""
    q = np.asarray(q, dtype=float)
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def quat_from_rotvec(rotvec):
    """Unit quaternion exp(rotvec / 2) for rotation vectors (..., 3) in radians."""
    rotvec = np.asarray(rotvec, dtype=float)
    angle = np.linalg.norm(rotvec, axis=-1)
    half = 0.5 * angle
    # sin(a/2)/a, with its limit 1/2 (series 1/2 - a^2/48) for tiny angles
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(angle > 1e-8, np.sin(half) / np.where(angle > 1e-8, angle, 1.0), 0.5 - angle**2 / 48.0)
    return np.concatenate([np.cos(half)[..., None], rotvec * scale[..., None]], axis=-1)


def rotvec_from_quat(q):
    """Rotation vector (axis * angle, rad) of unit quaternions (..., 4), shortest rotation.

    angle = 2 atan2(|v|, w) with the sign of q chosen so that w >= 0; rotvec = v * angle / |v|,
    which tends to 2 v / w as |v| -> 0.
    """
    q = np.asarray(q, dtype=float)
    q = np.where(q[..., :1] < 0, -q, q)
    w = q[..., 0]
    v = q[..., 1:]
    n = np.linalg.norm(v, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(n > 1e-12, 2.0 * np.arctan2(n, w) / np.where(n > 1e-12, n, 1.0), 2.0 / w)
    return v * scale[..., None]


def body_rate_from_quaternions(quat_wxyz, sample_rate_hz, half_span=1):
    """Body-frame angular rate (rad/s), shape (N, 3), from quaternions ``quat_wxyz`` (N, 4; w, x,
    y, z) sampled at ``sample_rate_hz`` (Hz), by equation (2).

    ``half_span`` h >= 1 samples: central difference over 2h sample intervals (see the module
    docstring). Row k is NaN when any quaternion in [k-h, k+h] is missing or k is within h of an
    end; nothing is interpolated. Quaternions are normalised first; their sign may flip freely.
    """
    q = np.asarray(quat_wxyz, dtype=float)
    if q.ndim != 2 or q.shape[1] != 4:
        raise SettingsError(f"quat_wxyz must have shape (N, 4) (w, x, y, z), got {q.shape}")
    h = int(half_span)
    if h < 1 or h != half_span:
        raise SettingsError(f"half_span must be a positive integer number of samples, got {plain(half_span)}")
    check_sample_rate_hz(sample_rate_hz)
    n = len(q)
    out = np.full((n, 3), np.nan)
    if n <= 2 * h:
        return out
    norm = np.linalg.norm(q, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        q = q / norm
    finite = np.isfinite(q).all(axis=1)
    # valid[k] = every sample in [k-h, k+h] finite (sliding count of missing samples)
    bad = np.concatenate([[0], np.cumsum(~finite)])
    window_bad = bad[2 * h + 1 :] - bad[: n - 2 * h]  # for centres k = h .. n-h-1
    centre_ok = window_bad == 0
    rel = quat_multiply(quat_conjugate(q[: n - 2 * h]), q[2 * h :])
    rate = rotvec_from_quat(rel) * (sample_rate_hz / (2.0 * h))
    rate[~centre_ok] = np.nan
    out[h : n - h] = rate
    return out


def block_mean_masked(values, block_len, start=0, n_blocks=None):
    """Means of non-overlapping blocks ``values[start + k L : start + (k+1) L]`` along axis 0
    (L = ``block_len`` samples; ``start``: index of the first block's first sample).

    A block containing any NaN gives NaN (no partial blocks, nothing invented). Returns
    (n_blocks, ...) with n_blocks = (len - start) // L unless given.
    """
    values = np.asarray(values, dtype=float)
    L = int(block_len)
    avail = (len(values) - start) // L
    n_blocks = avail if n_blocks is None else int(n_blocks)
    if n_blocks > avail:
        raise SettingsError(f"{n_blocks} blocks of {L} from sample {start} need {start + n_blocks * L} samples, have {len(values)}")
    seg = values[start : start + n_blocks * L]
    return seg.reshape((n_blocks, L) + values.shape[1:]).mean(axis=1)


def estimate_time_offset_s(gyro, reference, sample_rate_hz, max_lag_s=0.1, mask=None):
    """Delay of ``reference`` relative to ``gyro`` (s) by normalised cross-correlation.

    ``gyro`` and ``reference``: (N, 3) rates in one unit, sampled at ``sample_rate_hz`` (Hz).
    For integer lags l in [-m, m] (m = max_lag_s * fs), the correlation
    c(l) = sum_axes sum_i g_i r_{i+l} / sqrt(sum g_i^2 sum r_{i+l}^2) is taken over the pairs where
    both are finite (and ``mask`` is true at i, if given); the peak is refined by a parabola
    through its neighbours. Positive = the reference lags the gyro (shift it earlier by that much).
    Returns (offset_s, peak_correlation). Subtract the gyro bias first: a constant offset biases c.
    """
    g = np.asarray(gyro, dtype=float)
    r = np.asarray(reference, dtype=float)
    if g.shape != r.shape:
        raise SettingsError(f"gyro {g.shape} and reference {r.shape} must have the same shape")
    if g.ndim == 1:
        g, r = g[:, None], r[:, None]
    n = len(g)
    ok_g = np.isfinite(g).all(axis=1)
    if mask is not None:
        ok_g &= np.asarray(mask, dtype=bool)
    ok_r = np.isfinite(r).all(axis=1)
    m = max(1, int(round(max_lag_s * sample_rate_hz)))
    lags = np.arange(-m, m + 1)
    corr = np.full(len(lags), np.nan)
    g0 = np.where(ok_g[:, None], g, 0.0)
    r0 = np.where(ok_r[:, None], r, 0.0)
    for j, lag in enumerate(lags):
        if lag >= 0:
            a, b = slice(0, n - lag), slice(lag, n)
        else:
            a, b = slice(-lag, n), slice(0, n + lag)
        both = ok_g[a] & ok_r[b]
        if both.sum() < 10:
            continue
        ga = g0[a][both]
        rb = r0[b][both]
        corr[j] = np.sum(ga * rb) / np.sqrt(np.sum(ga * ga) * np.sum(rb * rb))
    if not np.isfinite(corr).any():
        raise SettingsError("no overlap of finite gyro and reference samples to correlate")
    j = int(np.nanargmax(corr))
    shift = 0.0
    if 0 < j < len(lags) - 1 and np.isfinite(corr[j - 1]) and np.isfinite(corr[j + 1]):
        denom = corr[j - 1] - 2 * corr[j] + corr[j + 1]
        if denom < 0:
            shift = 0.5 * (corr[j - 1] - corr[j + 1]) / denom
    return float((lags[j] + shift) / sample_rate_hz), float(corr[j])


def reference_from_recording(rec):
    """Reference rate (N, 3) in deg/s from the ``ref_x, ref_y, ref_z`` columns of ``rec`` (a
    :class:`~gyrofilter.recording.Recording`).

    The columns are in the recording's ``gyro_unit``; where a ``ref_valid`` column is 0 the
    reference could not be derived (occlusion) and the rows come back as NaN.
    """
    missing = [c for c in ("ref_x", "ref_y", "ref_z") if c not in rec.columns]
    if missing:
        raise SettingsError(f"{rec.path}: no reference-rate column(s) {', '.join(missing)}")
    ref = np.column_stack([rec.columns[c] for c in ("ref_x", "ref_y", "ref_z")])
    ref = to_dps(ref, rec.gyro_unit, rec.lsb_per_dps).copy()
    if "ref_valid" in rec.columns:
        ref[np.asarray(rec.columns["ref_valid"]) == 0] = np.nan
    return ref
