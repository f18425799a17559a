"""The metrics of the comparison (:mod:`gyrofilter.evaluation.evaluate`).

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
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import SettingsError
from .reference import block_mean_masked, reference_from_recording
from ..sim.profiles import get_profile
from ..units import AXES, one_value

DEFAULT_CALIBRATION_S = 2.0
#: a static std reduction beyond this is no filter's: the rows are constant but for the float's rounding
MAX_STATIC_REDUCTION = 1e6


# ---------------------------------------------------------------------------------------------
# static noise and synthetic motion


def static_reduction(spec, x_dps, sample_rate_hz, calibration_s=DEFAULT_CALIBRATION_S):
    """Per-axis std(raw after calibration, bias removed) / std(filtered) of the filter ``spec``
    (a FilterSpec) run on ``x_dps`` ((N, 3), deg/s, at ``sample_rate_hz``, Hz) with a
    calibration of ``calibration_s`` (s). SettingsError when fewer than 2 rows follow the
    calibration (a record not much longer than its window: the standard deviations would be NaN), an
    axis whose samples after the calibration are all equal (0 / 0) and rows constant on an axis
    whose samples are not (a std of 0 or rounding: beyond :data:`MAX_STATIC_REDUCTION`)."""
    out = spec.run(x_dps, sample_rate_hz, calibration_s)
    if len(out.y_dps) < 2:
        raise SettingsError(f"{len(x_dps)} samples ({len(x_dps) / sample_rate_hz:g} s) leave {len(out.y_dps)} filtered "
                            f"row(s) of {spec.name} after its {calibration_s:g}-s calibration: too short to measure a "
                            "reduction")
    after = x_dps[out.start :]
    raw_std, filt_std = np.std(after, axis=0), np.std(out.y_dps, axis=0)
    for i, axis in enumerate(AXES):  # a stuck axis is refused whole (datasets); stuck after the window is 0 / 0
        if one_value(after[:, i].min(), after[:, i].max()):
            raise SettingsError(f"axis {axis}: the {len(after)} samples after the calibration all equal {after[0, i]:g} "
                                "deg/s (a stuck axis): no noise for the filters to reduce")
        if not filt_std[i] * MAX_STATIC_REDUCTION > raw_std[i]:  # 'infx' in the table, None in the JSON
            raise SettingsError(f"axis {axis}: the rows of {spec.name} are constant (std {filt_std[i]:.3g} deg/s, the "
                                f"samples' {raw_std[i]:.3g}): no reduction to measure")
    return raw_std / filt_std


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


def dynamic_metrics(spec, profile, segments, calibration_s=DEFAULT_CALIBRATION_S, with_lag=True):
    """RMSE (deg/s, pooled over noise segments and axes) and per-segment lags (s) of the filter
    ``spec`` for one ``profile`` added to the noise ``segments`` (:func:`noise_segments`), with a
    calibration of ``calibration_s`` (s); lags only ``with_lag``."""
    profile = get_profile(profile) if isinstance(profile, str) else profile
    sq_sum = 0.0
    count = 0
    lags = {seg[2]: [] for seg in profile.segments}
    runs = []
    for name, noise, sample_rate_hz in segments:
        n = len(noise)
        t = np.arange(n) / sample_rate_hz
        truth = profile.rate_dps(t)
        x = noise + truth[:, None]
        out = spec.run(x, sample_rate_hz, calibration_s)
        tb = truth_blocks(profile.rate_dps, sample_rate_hz, n, out)
        err = out.y_dps - tb[:, None]
        sq_sum += float(np.sum(err**2))
        count += err.size
        runs.append((name, sample_rate_hz, out, tb))
        if with_lag:
            for t0, t1, label, max_lag in profile.segments:
                for a in range(3):
                    lags[label].append(segment_lag_s(out.y_dps[:, a], profile.rate_dps, sample_rate_hz, n, out, t0, t1,
                                                     max_lag_s=max_lag))
    seg_lags = {label: float(np.nanmedian(v)) if v else float("nan") for label, v in lags.items()}
    worst = max(seg_lags.values()) if with_lag and seg_lags else float("nan")
    return {"rmse_dps": math.sqrt(sq_sum / count), "lags_s": seg_lags, "worst_lag_s": worst, "runs": runs}


# ---------------------------------------------------------------------------------------------
# real motion against the optical reference


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
    REST_GUARD_S from a flag change; all: every block with a complete reference. SettingsError
    (which evaluate names the file in) for a trial with no block in motion or none at rest to
    score: its RMSE there would be NaN, 'nan' in the table.
    """
    sample_rate_hz = rec.sample_rate_hz
    cal_s = broad_calibration_s(rec)
    x = rec.gyro_dps
    ref = reference_from_recording(rec)
    move = np.asarray(rec.columns["movement"], dtype=float)
    rest_s = _rest_mask(move, sample_rate_hz).astype(float)
    out = spec.run(x, sample_rate_hz, cal_s)
    m = len(out.y_dps)
    ref_b = block_mean_masked(ref, out.block_len, start=out.start, n_blocks=m)
    move_b = block_mean_masked(move, out.block_len, start=out.start, n_blocks=m)
    rest_b = block_mean_masked(rest_s, out.block_len, start=out.start, n_blocks=m) == 1
    valid = np.isfinite(ref_b).all(axis=1)
    err = out.y_dps - ref_b
    if not (valid & (move_b == 1)).any():
        raise SettingsError("no block in motion with a complete optical reference (ref_x, ref_y, ref_z) after the "
                            "calibration: nothing to score the filters on in motion")
    if not (valid & rest_b).any():
        raise SettingsError(f"no block at rest with a complete optical reference after the calibration, {REST_GUARD_S:g} s "
                            "or more from a change of the movement flag: nothing to score the filters on at rest")
    res = {}
    for key, sel in (("motion", valid & (move_b == 1)), ("rest", valid & rest_b), ("all", valid)):
        res[f"rmse_{key}_dps"] = float(np.sqrt(np.mean(err[sel] ** 2)))  # every set holds a block (checked above)
    # at rest the optical reference's differentiation noise dominates; the rate there is 0
    res["rms_rest_vs_zero_dps"] = float(np.sqrt(np.mean(out.y_dps[rest_b] ** 2)))
    res["lag_s"] = reference_lag_s(out, ref, sample_rate_hz)
    res["calibration_s"] = cal_s
    return res
