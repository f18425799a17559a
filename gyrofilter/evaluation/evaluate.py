"""Measured filter comparison: static noise, synthetic motion on real noise, real motion vs optics.

Every filter is a function ``run(samples_dps (N, 3), sample_rate_hz, calibration_s) ->
FilterOutput``. Row k of ``FilterOutput.y_dps`` describes the input samples
``start + k L .. start + (k+1) L - 1`` (L = ``block_len``: 5 for the paper-001 pipeline and the
block average, 1 for filters at the input rate); ``start`` is the number of calibration samples,
round(calibration_s * sample_rate_hz) (:func:`gyrofilter.filter.calibration.calibration_samples`). All filters remove the same start-up bias: the mean of the
calibration window (paper 001, 2.1).

Alignment: a filtered row is compared with the truth *averaged over the same L samples* (the
block the row was computed from), so the block average itself has zero lag by construction and
every delay a filter adds shows up as error and as lag.

Metrics
-------
* **static std reduction** (per axis): std(x_i - b) over the samples after calibration divided
  by std(y_k) over the filtered rows (paper 001's before/after std ratio, table in section 4).
  Evaluated on every static MPU6050 recording in ``recordings/``.
* **dynamic RMSE** (deg/s): sqrt(mean over rows and axes of (y_k - truth_k)^2) for a profile of
  :mod:`gyrofilter.sim.profiles` added to each axis of 90 s of a real static recording (the first
  90 s of every static recording at least 90 s long; RMSE pooled over them).
* **lag** (s): for each segment of a profile where the rate changes, the shift d that minimises
  the mean squared difference between the filtered rows and the block-averaged *delayed* truth
  w(t - d) over the segment plus 1 s (grid 10 ms, refined to 1 ms; equivalent
  to maximising the cross-correlation for a pure delay); taken per axis and noise recording,
  their median per segment; **worst lag** = the largest over the segments. Positive = late,
  negative = early (a lead: a filter that extrapolates, or, within one sample interval, a
  sampled step).
  The search is limited per segment (3 s for ramps and steps, under half the period of a sine:
  0.45 s at 1 Hz), where a delayed copy is unambiguous.
* **BROAD RMSE** (deg/s) against the optical reference rate (:mod:`gyrofilter.evaluation.reference`,
  block-averaged over the same samples; blocks with a missing reference sample are left out),
  bias calibrated on the first rest phase (its first ``rest - 1`` s), split into blocks entirely
  in motion, entirely at rest (after calibration, and more than 1.5 s from a change of the
  movement flag, which lags the real start and end of motion by up to ~1 s), and all valid blocks. At rest the reference's
  own differentiation noise (1-3 deg/s) dominates, so ``rms_rest_vs_zero_dps`` (the output's rms
  at rest, where the true rate is 0) is reported too, and the **lag** behind the reference
  (:func:`reference_lag_s`: the shift of :func:`segment_lag_s` over the whole trial, median over
  the axes; searched within +-0.3 s).

Held-out split used to tune the hold and adaptive_kalman presets (:data:`TUNE_SPLIT`): tuned on the
sensor-fusion static recordings (655 s, 123 s, 64 s), the profiles ``paper001`` and ``steps``
and the BROAD trials 02 and 07; held out: the ImuCalibration static recordings (449 s, 100 s),
the profiles ``sine_1hz`` and ``chirp``, BROAD 05 and 09 (the trials with rest breaks).
"""
from __future__ import annotations

import glob
import math
import os
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..errors import SettingsError
from ..filter.calibration import calibration_samples
from ..sim.profiles import PROFILES, get_profile
from ..recording import read_recording
from .reference import block_mean_masked, reference_from_recording

DEFAULT_CALIBRATION_S = 2.0
NOISE_SEGMENT_S = 90.0
PAPER_CLAIM_REDUCTION = 12.6

TUNE_SPLIT = {
    "static": ("mpu6050_static_655s", "mpu6050_static_123s", "mpu6050_static_64s_set1"),
    "profiles": ("paper001", "steps"),
    "broad": ("broad_02_slow", "broad_07_fast"),
}
HOLDOUT_SPLIT = {
    "static": ("mpu6050_static_449s", "mpu6050_static_100s"),
    "profiles": ("sine_1hz", "chirp"),
    "broad": ("broad_05_slow_breaks", "broad_09_fast_breaks"),
}


# ---------------------------------------------------------------------------------------------
# filters


@dataclass
class FilterOutput:
    """Filtered rows and which input samples each describes (see the module docstring)."""

    y_dps: np.ndarray
    block_len: int
    start: int


@dataclass
class FilterSpec:
    """A filter of the comparison: its ``name``, ``family``, a one-line ``description`` and
    ``run(samples_dps, sample_rate_hz, calibration_s) -> FilterOutput`` (module docstring)."""

    name: str
    family: str  # "baseline", "paper", "candidate" or "offline" (not real time: the smoother)
    description: str
    run: Callable = field(repr=False)


def startup_bias(x_dps, sample_rate_hz, calibration_s):
    """Bias = mean of the first ``calibration_s`` seconds of ``x_dps`` ((N, 3), deg/s, sampled at
    ``sample_rate_hz``, Hz) (paper 001, 2.1): (bias (3,) in deg/s, samples)."""
    c = calibration_samples(sample_rate_hz, calibration_s)
    if c < 1 or c > len(x_dps):
        raise SettingsError(f"calibration of {calibration_s} s needs 1..{len(x_dps)} samples, got {c}")
    return x_dps[:c].mean(axis=0), c


def run_raw(x_dps, sample_rate_hz, calibration_s):
    """The samples ``x_dps`` ((N, 3), deg/s, at ``sample_rate_hz``, Hz) after the calibration,
    minus its bias (:func:`startup_bias` over ``calibration_s``, s): one row per sample."""
    bias, c = startup_bias(x_dps, sample_rate_hz, calibration_s)
    return FilterOutput(x_dps[c:] - bias, 1, c)


def run_block_mean(x_dps, sample_rate_hz, calibration_s, block_len=5):
    """Plain mean of non-sliding blocks of L = ``block_len`` samples (paper 001, 2.2 without the
    rejection) of ``x_dps`` ((N, 3), deg/s, at ``sample_rate_hz``, Hz) after the calibration
    window of ``calibration_s`` (s), its bias removed."""
    bias, c = startup_bias(x_dps, sample_rate_hz, calibration_s)
    return FilterOutput(block_mean_masked(x_dps - bias, block_len, start=c), block_len, c)


def moving_average(width):
    """Causal moving average of the last ``width`` samples, y_i = (1/w) sum_{j<w} x_(i-j)."""

    def run(x_dps, sample_rate_hz, calibration_s):
        bias, c = startup_bias(x_dps, sample_rate_hz, calibration_s)
        z = x_dps - bias
        csum = np.cumsum(np.vstack([np.zeros((1, 3)), z]), axis=0)
        i = np.arange(c, len(z))
        lo = np.maximum(i + 1 - width, 0)
        y = (csum[i + 1] - csum[lo]) / (i + 1 - lo)[:, None]
        return FilterOutput(y, 1, c)

    return run


def first_order_lowpass(tau_s):
    """y_i = y_(i-1) + a (x_i - y_(i-1)), a = dt / (tau + dt) (RC low-pass, backward Euler), y = 0 at
    start; tau = ``tau_s`` (s). Returns the filter's ``run`` (module docstring)."""

    def run(x_dps, sample_rate_hz, calibration_s):
        from scipy.signal import lfilter

        bias, c = startup_bias(x_dps, sample_rate_hz, calibration_s)
        dt = 1.0 / sample_rate_hz
        a = dt / (tau_s + dt)
        y = lfilter([a], [1.0, -(1.0 - a)], x_dps[c:] - bias, axis=0)
        return FilterOutput(y, 1, c)

    return run


def cv_kalman_design(sample_rate_hz, r_dps2, q_spectral_density, order=2):
    """A filterpy constant-velocity (``order`` 2) or constant-acceleration (3) Kalman filter, one
    axis, at ``sample_rate_hz`` (Hz).

    State (rate, rate', ...), F the kinematic transition, H = [1, 0, ...], R = r_dps2 (the sample
    noise variance), Q = filterpy ``Q_continuous_white_noise(order, dt, q_spectral_density)``
    ((deg/s^2)^2/Hz for order 2), set on a filterpy ``KalmanFilter``. Its steady state: the prior
    covariance P solves the discrete algebraic Riccati equation P = F (P - P H' (H P H' + R)^-1
    H P) F' + Q (scipy ``solve_discrete_are``), K = P H' (H P H' + R)^-1. Returns (kf, A, K, H),
    A = (I - K H) F, for the recursion x_k = A x_(k-1) + K z_k with output H x_k.
    """
    from filterpy.common import Q_continuous_white_noise
    from filterpy.kalman import KalmanFilter
    from scipy.linalg import solve_discrete_are

    dt = 1.0 / sample_rate_hz
    kf = KalmanFilter(dim_x=order, dim_z=1)
    F = np.eye(order)
    for i in range(order):
        for j in range(i + 1, order):
            F[i, j] = dt ** (j - i) / math.factorial(j - i)
    kf.F = F
    kf.H = np.zeros((1, order))
    kf.H[0, 0] = 1.0
    kf.R = np.array([[r_dps2]])
    kf.Q = Q_continuous_white_noise(order, dt, q_spectral_density)
    P = solve_discrete_are(kf.F.T, kf.H.T, kf.Q, kf.R)
    K = P @ kf.H.T / (kf.H @ P @ kf.H.T + kf.R)
    A = (np.eye(order) - K @ kf.H) @ kf.F
    return kf, A, K, kf.H.copy()


def cv_kalman(q_spectral_density, order=2):
    """Steady-state filterpy CV (CA) Kalman filter per axis at the input rate, R from calibration;
    ``q_spectral_density`` and ``order`` as for :func:`cv_kalman_design`. Returns the filter's ``run``.

    The run applies the filter's steady-state gain (the time-varying filter converges within
    about a second of the start, which falls in the still phase after calibration); the test
    compares it with filterpy's time-varying predict/update after convergence.
    """

    def run(x_dps, sample_rate_hz, calibration_s):
        from scipy.signal import lfilter, ss2tf

        bias, c = startup_bias(x_dps, sample_rate_hz, calibration_s)
        z = x_dps[c:] - bias
        var = np.maximum(np.var(x_dps[:c], axis=0, ddof=1), 1e-12)
        y = np.empty_like(z)
        for a in range(3):
            _, A, K, H = cv_kalman_design(sample_rate_hz, var[a], q_spectral_density, order)
            # s_(k+1) = A s_k + K z_k, y_k = H A s_k + H K z_k  (s_k = x_(k-1))
            b, den = ss2tf(A, K, H @ A, H @ K)
            y[:, a] = lfilter(b[0], den, z[:, a])
        return FilterOutput(y, 1, c)

    return run


def gyrofilter_run(preset="paper", **settings):
    """The package pipeline :class:`gyrofilter.GyroFilter` (batch ``filter``) with ``preset`` and
    ``settings``; returns the filter's ``run``, whose rows start at the filter's
    ``first_block_index``."""

    def run(x_dps, sample_rate_hz, calibration_s):
        from ..filter.pipeline import GyroFilter

        f = GyroFilter(sample_rate_hz, calibration_s, preset=preset, **settings)
        y = f.filter(x_dps)
        return FilterOutput(y, f.settings.block_len, f.first_block_index)

    return run


def gyrofilter_smooth(preset="recommended", **settings):
    """The offline forward-backward smoother :func:`gyrofilter.filter.smoother.smooth` with ``preset`` and
    ``settings`` (same rows as :func:`gyrofilter_run`); returns the filter's ``run``."""

    def run(x_dps, sample_rate_hz, calibration_s):
        from ..filter.pipeline import GyroFilter
        from ..filter.smoother import Smoother

        f = GyroFilter(sample_rate_hz, calibration_s, preset=preset, **settings)
        smoother = Smoother(f)
        f.filter(x_dps)
        return FilterOutput(smoother.smooth(), f.settings.block_len, f.first_block_index)

    return run


def default_filters():
    """The filters of the comparison table (baselines, the faithful filter, candidates)."""
    return [
        FilterSpec("raw", "baseline", "bias-corrected samples", run_raw),
        FilterSpec("block mean 5", "baseline", "mean of blocks of 5 (no rejection, no KF)", run_block_mean),
        FilterSpec("moving avg 5", "baseline", "causal moving average of 5 samples", moving_average(5)),
        FilterSpec("moving avg 25", "baseline", "causal moving average of 25 samples", moving_average(25)),
        FilterSpec("low-pass 0.05 s", "baseline", "first-order low-pass, tau 0.05 s", first_order_lowpass(0.05)),
        FilterSpec("low-pass 0.2 s", "baseline", "first-order low-pass, tau 0.2 s", first_order_lowpass(0.2)),
        FilterSpec("CV Kalman q=1e2", "baseline", "filterpy constant-velocity KF, q = 1e2 (deg/s^2)^2/Hz", cv_kalman(1e2)),
        FilterSpec("CV Kalman q=1e4", "baseline", "filterpy constant-velocity KF, q = 1e4 (deg/s^2)^2/Hz", cv_kalman(1e4)),
        FilterSpec("paper001", "paper", "faithful paper-001 GyroFilter(preset='paper')", gyrofilter_run("paper")),
        FilterSpec("paper, linear fit", "candidate", "GyroFilter(fit_order=1)", gyrofilter_run("paper", fit_order=1)),
        FilterSpec("paper, constant fit", "candidate", "GyroFilter(fit_order=0)", gyrofilter_run("paper", fit_order=0)),
        FilterSpec("paper, R calibration", "candidate", "GyroFilter(r_source='calibration')",
                   gyrofilter_run("paper", r_source="calibration")),
        FilterSpec("paper KF + hold", "candidate", "GyroFilter(hold=True): paper-001 output + constant-rate hold",
                   gyrofilter_run("paper", hold=True)),
        FilterSpec("hold preset", "candidate",
                   "GyroFilter(preset='hold') = hold=True, tracker='block_mean': constant-rate hold, block means while the rate changes",
                   gyrofilter_run("hold")),
        FilterSpec("recommended preset", "candidate",
                   "GyroFilter(preset='recommended') = adaptive_kalman: paper 001's LS prior with adaptive noise statistics, "
                   "constant-rate model at rest, divergence guard",
                   gyrofilter_run("recommended")),
        FilterSpec("recommended, smoothed (offline)", "offline",
                   "gyrofilter.smooth(): forward-backward smoother over the recommended filter, each row from the "
                   "whole recording (not real time)", gyrofilter_smooth("recommended")),
        FilterSpec("recommended, paper's rule", "candidate",
                   "GyroFilter(preset='recommended', outlier_rule='paper'): paper 001's gross-error rule in motion too",
                   gyrofilter_run("recommended", outlier_rule="paper")),
    ]


# ---------------------------------------------------------------------------------------------
# data


def _stem(path):
    name = os.path.basename(path)
    for ext in (".csv.gz", ".csv"):
        if name.endswith(ext):
            return name[: -len(ext)]
    return name


def find_static_recordings(recordings_dir):
    """Real static MPU6050 recordings in the folder ``recordings_dir``: sensor MPU6050 and a
    description starting with 'static' (or, without a description, 'static' in the file name)."""
    out = []
    for path in sorted(glob.glob(os.path.join(recordings_dir, "*.csv*"))):
        rec = read_recording(path)
        if "mpu6050" not in rec.header.get("sensor", "").lower():
            continue
        desc = rec.header.get("description", "").strip().lower()
        if desc.startswith("static") or (not desc and "static" in os.path.basename(path).lower()):
            out.append(rec)
    return out


def find_broad_recordings(recordings_dir):
    """The BROAD trials (``broad_*.csv*``, with optical reference) in the folder ``recordings_dir``, read."""
    return [read_recording(p) for p in sorted(glob.glob(os.path.join(recordings_dir, "broad_*.csv*")))]


# ---------------------------------------------------------------------------------------------
# metrics


def static_reduction(spec, x_dps, sample_rate_hz, calibration_s=DEFAULT_CALIBRATION_S):
    """Per-axis std(raw after calibration, bias removed) / std(filtered) of the filter ``spec``
    (a FilterSpec) run on ``x_dps`` ((N, 3), deg/s, at ``sample_rate_hz``, Hz) with a
    calibration of ``calibration_s`` (s)."""
    out = spec.run(x_dps, sample_rate_hz, calibration_s)
    raw_std = np.std(x_dps[out.start :], axis=0)
    return raw_std / np.std(out.y_dps, axis=0)


def truth_blocks(rate_fn, sample_rate_hz, n_samples, out, shift_s=0.0):
    """Truth w(t_i - shift) at t_i = i / fs averaged over each output row's samples, (M,) in deg/s:
    w = ``rate_fn`` (of t in s), fs = ``sample_rate_hz`` (Hz), shift = ``shift_s`` (s), i < ``n_samples``;
    the rows are those of ``out`` (a FilterOutput)."""
    t = np.arange(n_samples) / sample_rate_hz
    w = rate_fn(t - shift_s)
    m = len(out.y_dps)
    return block_mean_masked(w, out.block_len, start=out.start, n_blocks=m)


def row_times_s(out, sample_rate_hz):
    """Centre time (s) of the samples of each row of ``out`` (a FilterOutput) at ``sample_rate_hz`` (Hz)."""
    k = np.arange(len(out.y_dps))
    return (out.start + k * out.block_len + (out.block_len - 1) / 2.0) / sample_rate_hz


def segment_lag_s(y, rate_fn, sample_rate_hz, n_samples, out, t0, t1, tail_s=1.0, max_lag_s=3.0):
    """Shift d (s) minimising mean (y - block-averaged w(t - d))^2 over rows in [t0, t1 + tail].

    ``y``: the rows of ``out`` (a FilterOutput) on one axis (deg/s); w = ``rate_fn`` (truth, of t
    in s) sampled at ``sample_rate_hz`` (Hz) for ``n_samples``; t0, t1 (s): the segment; tail =
    ``tail_s`` (s).

    d is searched in [-min(0.3, max_lag_s), max_lag_s] on a 10 ms grid, then refined to 1 ms; a
    result at the upper end means "at least max_lag_s" (or no delayed copy of the truth fits).
    A sampled step fixes the delay only to within one sample interval.
    """
    times = row_times_s(out, sample_rate_hz)
    rows = (times >= t0) & (times <= t1 + tail_s)
    if rows.sum() < 3:
        return float("nan")
    L = out.block_len
    idx = out.start + np.flatnonzero(rows)[:, None] * L + np.arange(L)[None, :]
    t_samples = idx / sample_rate_hz
    yr = y[rows]

    def cost(d):
        truth = rate_fn(t_samples - d).mean(axis=1)
        return np.mean((yr - truth) ** 2)

    grid = np.arange(-min(0.3, max_lag_s), max_lag_s + 1e-9, 0.01)
    costs = [cost(d) for d in grid]
    best = grid[int(np.argmin(costs))]
    fine = np.arange(max(best - 0.01, grid[0]), min(best + 0.01, max_lag_s) + 1e-9, 0.001)
    costs = [cost(d) for d in fine]
    return float(fine[int(np.argmin(costs))])


def noise_segments(static_recs, duration_s=NOISE_SEGMENT_S, names=None):
    """(name, x_dps (n, 3), fs): the first ``duration_s`` (s) of each recording of ``static_recs``
    long enough (only those named in ``names``, when given)."""
    segs = []
    for rec in static_recs:
        name = _stem(rec.path or "")
        if names is not None and name not in names:
            continue
        n = int(round(duration_s * rec.sample_rate_hz))
        if len(rec) >= n:
            segs.append((name, rec.gyro_dps[:n], rec.sample_rate_hz))
    return segs


def dynamic_metrics(spec, profile, segments, calibration_s=DEFAULT_CALIBRATION_S, with_lag=True):
    """RMSE (deg/s, pooled over noise segments and axes) and per-segment lags (s) of the filter
    ``spec`` for one ``profile`` added to the noise ``segments`` (:func:`noise_segments`), with a
    calibration of ``calibration_s`` (s); lags only ``with_lag``."""
    profile = get_profile(profile) if isinstance(profile, str) else profile
    sq_sum = 0.0
    count = 0
    lags = {seg[2]: [] for seg in profile.segments}
    runs = []
    for name, noise, fs in segments:
        n = len(noise)
        t = np.arange(n) / fs
        truth = profile.rate_dps(t)
        x = noise + truth[:, None]
        out = spec.run(x, fs, calibration_s)
        tb = truth_blocks(profile.rate_dps, fs, n, out)
        err = out.y_dps - tb[:, None]
        sq_sum += float(np.sum(err**2))
        count += err.size
        runs.append((name, fs, out, tb))
        if with_lag:
            for t0, t1, label, max_lag in profile.segments:
                for a in range(3):
                    lags[label].append(segment_lag_s(out.y_dps[:, a], profile.rate_dps, fs, n, out, t0, t1, max_lag_s=max_lag))
    seg_lags = {label: float(np.nanmedian(v)) if v else float("nan") for label, v in lags.items()}
    worst = max(seg_lags.values()) if with_lag and seg_lags else float("nan")
    return {"rmse_dps": math.sqrt(sq_sum / count), "lags_s": seg_lags, "worst_lag_s": worst, "runs": runs}


REST_GUARD_S = 1.5


def broad_calibration_s(rec):
    """Calibration length (s) for the BROAD trial ``rec``: its first rest phase minus 1 s (the
    movement flag switches on up to ~1 s after motion starts)."""
    move = np.asarray(rec.columns["movement"])
    first = int(np.flatnonzero(move == 1)[0])
    return max(first / rec.sample_rate_hz - 1.0, 1.0)


def _rest_mask(move, sample_rate_hz, guard_s=REST_GUARD_S):
    """movement == 0 and at least guard_s away from every change of the flag (the upstream flag
    lags the motion by up to ~1 s at starts and ends)."""
    move = np.asarray(move)
    n = len(move)
    changes = np.flatnonzero(np.diff(move) != 0) + 1
    near = np.zeros(n, dtype=bool)
    g = int(round(guard_s * sample_rate_hz))
    for c in changes:
        near[max(0, c - g) : c + g] = True
    return (move == 0) & ~near


def reference_lag_s(out, ref_dps, sample_rate_hz, max_lag_s=0.3):
    """Lag (s) of the filtered rows of ``out`` behind the reference rate ``ref_dps`` (N, 3), deg/s,
    sampled at ``sample_rate_hz`` (Hz), searched up to ``max_lag_s`` (s): per axis the shift of
    :func:`segment_lag_s` over the whole record (the reference linearly interpolated over its
    missing samples), the median over the axes."""
    t = np.arange(len(ref_dps)) / sample_rate_hz
    t_end = (out.start + len(out.y_dps) * out.block_len) / sample_rate_hz
    lags = []
    for a in range(3):
        ok = np.isfinite(ref_dps[:, a])
        if ok.sum() < 2:
            continue
        rate_fn = lambda s, a=a, ok=ok: np.interp(s, t[ok], ref_dps[ok, a])  # noqa: E731
        lags.append(segment_lag_s(out.y_dps[:, a], rate_fn, sample_rate_hz, len(ref_dps), out, out.start / sample_rate_hz,
                                  t_end, tail_s=0.0, max_lag_s=max_lag_s))
    return float(np.median(lags)) if lags else float("nan")


def broad_metrics(spec, rec):
    """RMSE (deg/s) of the filter ``spec`` against the optical reference of the BROAD trial ``rec``:
    motion, rest, all valid blocks.

    motion: blocks entirely flagged as movement; rest: blocks entirely at rest and more than
    REST_GUARD_S from a flag change; all: every block with a complete reference.
    """
    fs = rec.sample_rate_hz
    cal_s = broad_calibration_s(rec)
    x = rec.gyro_dps
    ref = reference_from_recording(rec)
    move = np.asarray(rec.columns["movement"], dtype=float)
    rest_s = _rest_mask(move, fs).astype(float)
    out = spec.run(x, fs, cal_s)
    m = len(out.y_dps)
    ref_b = block_mean_masked(ref, out.block_len, start=out.start, n_blocks=m)
    move_b = block_mean_masked(move, out.block_len, start=out.start, n_blocks=m)
    rest_b = block_mean_masked(rest_s, out.block_len, start=out.start, n_blocks=m) == 1
    valid = np.isfinite(ref_b).all(axis=1)
    err = out.y_dps - ref_b
    res = {}
    for key, sel in (("motion", valid & (move_b == 1)), ("rest", valid & rest_b), ("all", valid)):
        res[f"rmse_{key}_dps"] = float(np.sqrt(np.mean(err[sel] ** 2))) if sel.any() else float("nan")
    # at rest the optical reference's differentiation noise dominates; the rate there is 0
    res["rms_rest_vs_zero_dps"] = float(np.sqrt(np.mean(out.y_dps[rest_b] ** 2))) if rest_b.any() else float("nan")
    res["lag_s"] = reference_lag_s(out, ref, fs)
    res["calibration_s"] = cal_s
    return res


# ---------------------------------------------------------------------------------------------
# the whole evaluation


@dataclass
class Evaluation:
    """What :func:`evaluate` measured, per filter name: static reductions, dynamic RMSE and lags
    (per profile), BROAD RMSE (per trial)."""

    filters: list
    static_names: list
    static: dict  # filter -> {recording: (3,) reductions}
    profiles: list
    dynamic: dict  # filter -> {profile: {"rmse_dps", "worst_lag_s", "lags_s"}}
    broad_names: list
    broad: dict  # filter -> {trial: {"rmse_motion_dps", ...}}
    families: dict = field(default_factory=dict)  # filter -> family

    def static_min(self, name, only=None):
        """The smallest static std reduction of filter ``name`` over axes and recordings (those in
        ``only``, when given); NaN when there is none."""
        vals = [v for rec, v in self.static[name].items() if only is None or rec in only]
        return float(np.min(vals)) if vals else float("nan")

    def static_geomean(self, name, only=None):
        """Geometric mean of the static std reductions of filter ``name`` (recordings in ``only``)."""
        vals = np.concatenate([v for rec, v in self.static[name].items() if only is None or rec in only])
        return float(np.exp(np.mean(np.log(vals))))

    def dynamic_geomean(self, name, only=None):
        """Geometric mean of the dynamic RMSE (deg/s) of filter ``name`` over profiles (those in ``only``)."""
        vals = [d["rmse_dps"] for p, d in self.dynamic[name].items() if only is None or p in only]
        return float(np.exp(np.mean(np.log(vals))))


def evaluate(filters=None, recordings_dir="recordings", profiles=None, with_lag=True, progress=None,
             static_names=None, broad_names=None):
    """Run every filter on every data set; returns an :class:`Evaluation`.

    ``filters``: FilterSpecs (default :func:`default_filters`); ``recordings_dir``: the folder
    of recordings; ``profiles``: names of :mod:`gyrofilter.sim.profiles` (default all);
    ``with_lag``: estimate lags; ``static_names``, ``broad_names``: only these recordings (file
    stems; default all); ``progress``: optional callable(str) told what runs (the CLI prints it
    on stderr).
    """
    filters = default_filters() if filters is None else filters
    profiles = list(PROFILES) if profiles is None else list(profiles)
    static_recs = find_static_recordings(recordings_dir)
    if static_names is not None:
        static_recs = [r for r in static_recs if _stem(r.path) in static_names]
    if not static_recs:
        raise SettingsError(f"{recordings_dir}: no static MPU6050 recordings found")
    broad_recs = find_broad_recordings(recordings_dir)
    if broad_names is not None:
        broad_recs = [r for r in broad_recs if _stem(r.path) in broad_names]
    segments = noise_segments(static_recs)
    if profiles and not segments:
        raise SettingsError(f"{recordings_dir}: no static recording lasts the {NOISE_SEGMENT_S:g} s of noise "
                            "the synthetic-motion profiles need")
    ev = Evaluation([f.name for f in filters], [_stem(r.path) for r in static_recs], {}, profiles, {},
                    [_stem(r.path) for r in broad_recs], {}, {f.name: f.family for f in filters})
    for spec in filters:
        if progress:
            progress(f"evaluating {spec.name}")
        ev.static[spec.name] = {
            _stem(r.path): static_reduction(spec, r.gyro_dps, r.sample_rate_hz) for r in static_recs
        }
        ev.dynamic[spec.name] = {}
        for p in profiles:
            d = dynamic_metrics(spec, p, segments, with_lag=with_lag)
            d.pop("runs")
            ev.dynamic[spec.name][p] = d
        ev.broad[spec.name] = {_stem(r.path): broad_metrics(spec, r) for r in broad_recs}
    return ev


def dominates(ev, candidate, reference="paper001", claim=PAPER_CLAIM_REDUCTION, static_only=None,
              profiles=None, broad_only=None):
    """Does ``candidate`` Pareto-dominate ``reference`` in the :class:`Evaluation` ``ev``? Returns
    (bool, list of reasons it fails). ``static_only``, ``profiles``, ``broad_only``: consider only
    these static recordings, profiles and BROAD trials (default all).

    Criteria (issue 5): static std reduction >= ``claim`` on every axis of every static
    recording considered, and dynamic RMSE <= the reference's on every profile and every BROAD
    trial (all valid blocks).
    """
    fails = []
    for rec, red in ev.static[candidate].items():
        if static_only is not None and rec not in static_only:
            continue
        if np.min(red) < claim:
            fails.append(f"static {rec}: reduction {np.min(red):.2f} < {claim}")
    for label, table, key, only in (("profile", ev.dynamic, "rmse_dps", profiles), ("BROAD", ev.broad, "rmse_all_dps", broad_only)):
        for name, d in table[candidate].items():
            ref = table[reference][name][key]
            if (only is None or name in only) and d[key] > ref:
                fails.append(f"{label} {name}: RMSE {d[key]:.4f} > {ref:.4f}")
    return (not fails), fails


def pareto_front(points):
    """Indices of the points (error, reduction) not dominated: lower error and higher reduction."""
    idx = []
    for i, (e, r) in enumerate(points):
        if not any((e2 <= e and r2 >= r) and (e2 < e or r2 > r) for j, (e2, r2) in enumerate(points) if j != i):
            idx.append(i)
    return idx


def format_table(ev):
    """One Markdown table of the :class:`Evaluation` ``ev``: a row per filter."""
    head = ["filter", "static reduction min / geo-mean"]
    head += [f"{p} RMSE / worst lag" for p in ev.profiles]
    head += [f"{b} RMSE motion / rest / lag" for b in ev.broad_names]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name in ev.filters:
        row = [name, f"{ev.static_min(name):.2f} / {ev.static_geomean(name):.2f}x"]
        for p in ev.profiles:
            d = ev.dynamic[name][p]
            lag = d["worst_lag_s"]
            row.append(f"{d['rmse_dps']:.3f} / {lag * 1e3:.0f} ms" if math.isfinite(lag) else f"{d['rmse_dps']:.3f}")
        for b in ev.broad_names:
            d = ev.broad[name][b]
            row.append(f"{d['rmse_motion_dps']:.2f} / {d['rmse_rest_dps']:.2f} / {d['lag_s'] * 1e3:.0f} ms")
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def plot_pareto(ev, path, reference="paper001"):
    """Static std reduction (geometric mean) against dynamic RMSE (geometric mean over profiles)
    of the :class:`Evaluation` ``ev``, drawn to the figure file ``path``; ``reference``: the
    filter the others are compared with.

    The Pareto front is drawn through the real-time filters; offline ones (the smoother) are
    stars beside it. Labels that would overlap are moved down, one line at a time."""
    from ..plots import pyplot

    plt = pyplot()
    pts = [(ev.dynamic_geomean(n), ev.static_geomean(n)) for n in ev.filters]
    fam = ev.families
    realtime = [i for i, n in enumerate(ev.filters) if fam.get(n) != "offline"]
    front = {realtime[j] for j in pareto_front([pts[i] for i in realtime])}
    fig, ax = plt.subplots(figsize=(9, 6))
    ax.set_xscale("log")
    ax.set_yscale("log")
    colors = {"baseline": "tab:gray", "paper": "tab:red", "candidate": "tab:blue", "offline": "tab:green"}
    for i, (e, r) in enumerate(pts):
        family = fam.get(ev.filters[i], "candidate")
        ax.scatter([e], [r], color=colors.get(family, "tab:blue"), marker="*" if family == "offline" else "o",
                   s=120 if family == "offline" else (60 if i in front else 30),
                   edgecolor="k" if i in front else "none", zorder=3)
    fig.canvas.draw()
    placed = []  # label boxes in display pixels
    for i in sorted(range(len(pts)), key=lambda i: (-pts[i][1], pts[i][0])):
        x_px, y_px = ax.transData.transform(pts[i])
        width, height = 5.5 * len(ev.filters[i]), 11.0
        dy = 3.0
        while any(abs(x_px + 5 - bx) < max(width, bw) and abs(y_px + dy - by) < height for bx, by, bw in placed):
            dy -= height
        placed.append((x_px + 5, y_px + dy, width))
        ax.annotate(ev.filters[i], pts[i], textcoords="offset points", xytext=(5, dy * 72 / fig.dpi), fontsize=8)
    fr = sorted(pts[i] for i in front)
    ax.plot([p[0] for p in fr], [p[1] for p in fr], "k--", lw=0.8, zorder=2, label="Pareto front (real-time filters)")
    ax.axhline(PAPER_CLAIM_REDUCTION, color="tab:red", lw=0.8, ls=":", label="paper 001 claim 12.6x")
    if reference in ev.filters:
        e0, _ = pts[ev.filters.index(reference)]
        ax.axvline(e0, color="tab:red", lw=0.8, ls="-.", label="paper001 dynamic RMSE")
    ax.set_xlabel("dynamic RMSE, geometric mean over profiles (deg/s)  - lower is better")
    ax.set_ylabel("static std reduction, geometric mean (x)  - higher is better")
    ax.set_title("Noise reduction vs tracking error (real MPU6050 noise)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
