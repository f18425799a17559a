"""The models of the gap analysis (:mod:`gyrofilter.analysis.gap.pipeline`, steps 1 and 2) and their
simulated features.

The baseline fit per axis (:func:`baseline_model`): constant bias ``b`` = mean of the rate;
white noise of per-sample standard deviation ``sigma`` = the standard deviation of the
high-passed rate ``x - moving_mean(x, W)`` (W = max(64 samples, 0.5 s), divided by
``sqrt(1 - 1/W)``, spikes removed), less the quantization variance ``q^2 / 12`` that the
simulator adds back (``q = 1 / lsb_per_dps`` for ``gyro_unit: lsb``; in another unit the step
the values sit on, :func:`recorded_lsb_per_dps`; else 0);
``arw_dps_per_sqrt_hz = sigma / sqrt(f_s)`` (white noise per sample ``N sqrt(f_s)``, IEEE Std
952-1997 annex C). The extended model's axis is re-fitted the same way on the series cleaned of
its findings (:func:`extended_axis`; with ``heavy_tails`` no sample is masked: the tails are part of
the white noise's variance, which the effect keeps); a finding enters the model as an entry of the effect table
(:func:`effect_entry`). The models are simulated one axis of one seeded run at a time
(:func:`sim_features`), the features computed on each run.
"""
from __future__ import annotations

import functools
import math
import time

import numpy as np

from ...effects import (BIAS_STEP, COLORED_NOISE, HEAVY_TAILS, NARROWBAND, RATE_RAMP, RESONANCE, TEMPERATURE, WANDERING_TONE,
                        WANDERS, WARMUP)
from .. import stats
from . import detectors as det
from .features import features
from ...recording import GYRO_COLUMNS
from ...sim.model import validate_model
from ...sim.simulate import simulate_axis_dps
from ...units import AXES, LSB_PER_DPS_RANGE, to_dps

# ---------------------------------------------------------------------------------------------
# the models


#: fewest baseline runs from which D is judged (``gap --sims`` refuses fewer; the library notes
#: it). Measured on pure white noise (10 seeds x 3 axes, D after, issue 37): from 2, 3, 5, 8, 10
#: runs the 95th percentile of D is 36, 12, 3.0, 1.6, 1.5 on 5-minute records (axes above
#: OUTSIDE_NULL_D = 2, "does not close": 30, 18, 6, 0, 0 of 30) and 3.1, 3.0, 2.6, 2.1 from
#: 6, 7, 8, 10 runs on 30-s records (max 7.5, 7.8, 8.0, 4.1); the default's 12 to 24: 1.6-2.0
MIN_SIMS = 10


#: most baseline simulations a gap analysis runs (the default is 12-24; the spread is known to
#: +-3 % from 1000); the library also runs 2 to MIN_SIMS - 1, and a note says D is not judged
MAX_SIMS = 1000


#: a quantized rate whose white noise is below this many steps is read by its codes' histogram
#: (:func:`sub_lsb_fit`); above, the additive model of quantization holds (sigma 0.6 steps: the
#: high-passed estimate within 1 %)
SUB_LSB_SIGMA = 0.5
#: the codes of the histogram fit: within this many steps of the commonest
SUB_LSB_CODES = 3
#: ... holding at least this share of the samples (else the noise spreads over many steps)
SUB_LSB_MIN_SHARE = 0.5
#: samples of the first look at that share (evenly spread), and the margin below it at which the
#: probe alone says no (35 standard errors of the share of 131 072 samples): the codes of a noisy
#: record are not sorted whole (0.05-0.23 s a day-long axis, 2-5 ms with the probe, in
#: every bootstrap run)
SUB_LSB_PROBE = 1 << 17
SUB_LSB_PROBE_MARGIN = 0.05


#: gap's default baseline runs: DEFAULT_SIMS up to SIMS_IN_FULL_UP_TO samples per axis, then fewer
#: in proportion, at least FEWEST_DEFAULT_SIMS (:func:`default_n_sims`)
DEFAULT_SIMS = 24
SIMS_IN_FULL_UP_TO = 200_000
FEWEST_DEFAULT_SIMS = 12


def default_n_sims(n_samples):
    """Baseline runs: 24 up to 200 000 samples per axis, then fewer (at least 12) so that
    hours of data stay fast; the spread of a feature is estimated to about +-20 % from 12 runs:
    ``max(12, min(24, round(24 * 200 000 / n)))``."""
    return int(max(FEWEST_DEFAULT_SIMS, min(DEFAULT_SIMS, round(DEFAULT_SIMS * SIMS_IN_FULL_UP_TO / max(n_samples, 1)))))


def default_n_sims_why(n_samples):
    """Why gap ran :func:`default_n_sims` baseline runs on ``n_samples`` samples per axis, for a
    reader who gave no ``--sims``."""
    return (f"gap's default for {n_samples} samples per axis: {DEFAULT_SIMS} up to {SIMS_IN_FULL_UP_TO}, fewer above "
            f"(at least {FEWEST_DEFAULT_SIMS}) so that hours of data stay fast")


def axis_dps(rec, i, pass_samples=1 << 16):
    """Axis ``i`` of ``rec.gyro_dps`` in float64: the column itself for a float64 ``gyro_unit:
    dps`` column, else a new array converted a pass at a time (:func:`~gyrofilter.units.to_dps`,
    the same numbers, one N-sample array): the analysis never holds the three axes in deg/s at
    once."""
    column = rec.columns[GYRO_COLUMNS[i]]
    if rec.gyro_unit == "dps" and column.dtype == np.float64:
        return column
    out = np.empty(column.size)
    for lo in range(0, column.size, pass_samples):
        out[lo:lo + pass_samples] = to_dps(column[lo:lo + pass_samples], rec.gyro_unit, rec.lsb_per_dps)
    return out


def noise_sigma(x, sample_rate_hz, q_dps, mask_spikes=True):
    """Per-sample white-noise std of the baseline (see module docstring); ``mask_spikes=False``
    keeps every sample (a heavy-tailed noise, whose tails are part of its variance). A constant
    series has none: 0 (its high-pass would give the float rounding of the moving mean). A
    quantized series whose noise is below half a step is read by its codes (:func:`sub_lsb_fit`)."""
    return _white_noise(x, sample_rate_hz, q_dps, mask_spikes)[0]


def _white_noise(x, sample_rate_hz, q_dps, mask_spikes=True):
    """``(sigma, sub-LSB fit or None)``: :func:`noise_sigma`, with the fit of :func:`sub_lsb_fit`
    where it applies (its mean is the baseline's bias there), so that the fit is made once."""
    if not np.ptp(x) > 0:
        return 0.0, None
    fit = sub_lsb_fit(x, q_dps) if q_dps > 0 else None
    if fit is not None:
        return fit[0], fit
    w = det.colored_window(x.size, sample_rate_hz)
    mask, _, _ = det.outlier_statistic(x, q_dps) if mask_spikes else (None, None, None)
    e = det.highpassed(x, sample_rate_hz)[0]
    var = _variance(e, None if mask is None or not mask.any() else ~mask) / max(1.0 - 1.0 / w, 0.5)
    var = max(var - (q_dps ** 2) / 12.0, 0.25 * var)
    return math.sqrt(var), None


def sub_lsb_fit(x, q_dps):
    """``(sigma, mu)`` in deg/s: the white-noise sigma and the mean of the rate before rounding of
    ``x``, quantized in steps of ``q_dps``, where sigma is below :data:`SUB_LSB_SIGMA` steps, else
    None (mu is the baseline's bias there: the mean of the codes is pulled towards the commonest
    one, and a bias off by that moves every simulated sample's code). There the additive model of quantization (variance
    sigma^2 + q^2 / 12) fails: most samples sit on one code, the few beside it look like spikes to
    the outlier mask, and the variance left is far below the noise's (a quiet sensor read D ~ 5e8,
    issue 37). Instead sigma and the mean mu (in steps) are the maximum-likelihood fit of a
    Gaussian rounded to the grid, P(k) = Phi((k + 1/2 - mu) / sigma) - Phi((k - 1/2 - mu) / sigma),
    to the counts of the codes k within :data:`SUB_LSB_CODES` of the commonest (renormalised to
    that window, so that gross errors far out do not widen it); None where that window holds
    less than half of the samples (a noise spread over many steps). Where only two codes occur
    the record holds one number, the share of one of them, and sigma and mu are not separable:
    the fit is one of the pairs giving that share, and every such pair simulates the same white
    noise record (its samples are independent), which is what the baseline needs."""
    from scipy.optimize import minimize
    from scipy.special import ndtr

    x = np.asarray(x, dtype=float)
    if _window_share(x[::max(1, x.size // SUB_LSB_PROBE)], q_dps)[0] < SUB_LSB_MIN_SHARE - SUB_LSB_PROBE_MARGIN:
        return None  # a noise over many steps, told from evenly spread samples: no sort of the record
    share, k, n = _window_share(x, q_dps)
    if share < SUB_LSB_MIN_SHARE:
        return None
    low, high = k - 0.5, k + 0.5

    def mass(a, b):  # Phi(b) - Phi(a), from the nearer tail (no cancellation far above the mean)
        return np.where(a > 0, ndtr(-a) - ndtr(-b), ndtr(b) - ndtr(a))

    def nll(p):
        s = math.exp(p[1])
        prob = mass((low - p[0]) / s, (high - p[0]) / s)
        total = float(mass(np.array((low[0] - p[0]) / s), np.array((high[-1] - p[0]) / s)))
        return -float(np.dot(n, np.log(np.maximum(prob / max(total, 1e-300), 1e-300))))

    mean = float(np.dot(n, k) / n.sum())
    fits = [minimize(nll, [mean, math.log(start)], method="Nelder-Mead", options={"xatol": 1e-5, "fatol": 1e-7})
            for start in (0.05, 0.15, 0.4)]
    fit = min(fits, key=lambda f: f.fun)
    sigma_steps = math.exp(float(fit.x[1]))
    return (sigma_steps * q_dps, float(fit.x[0]) * q_dps) if sigma_steps < SUB_LSB_SIGMA else None


def _window_share(x, q_dps):
    """``(share, k, n)``: the codes ``k`` of ``x`` rounded to steps ``q_dps`` within
    :data:`SUB_LSB_CODES` of the commonest, their counts ``n`` and the share of the samples they hold."""
    values, counts = np.unique(np.rint(x / q_dps).astype(np.int64), return_counts=True)
    mode = int(values[np.argmax(counts)])
    k = np.arange(mode - SUB_LSB_CODES, mode + SUB_LSB_CODES + 1)
    n = np.array([counts[values == j].sum() for j in k], dtype=float)
    return float(n.sum()) / x.size, k, n


def _variance(e, keep=None, pass_samples=1 << 16):
    """The variance (ddof 0) of ``e``, or of its samples where ``keep`` is True, in two passes
    of ``pass_samples`` at a time (no N-sample temporary)."""
    parts = [(e[lo:lo + pass_samples], None if keep is None else keep[lo:lo + pass_samples])
             for lo in range(0, e.size, pass_samples)]
    count = e.size if keep is None else int(np.count_nonzero(keep))
    mean = sum(float(p.sum() if k is None else p[k].sum()) for p, k in parts) / count
    total = 0.0
    for p, k in parts:
        d = (p if k is None else p[k]) - mean
        total += float(stats.dot(d, d))
    return total / count


def baseline_model(rec, gyro_dps=None):
    """The baseline simulator model (shared schema) fitted to ``rec`` (or to the (N, 3) rates
    ``gyro_dps``)."""
    sample_rate_hz = rec.sample_rate_hz
    unit = rec.gyro_unit
    lsb = rec.lsb_per_dps if unit == "lsb" else None
    if lsb is None:
        lsb = recorded_lsb_per_dps(lambda i: axis_dps(rec, i) if gyro_dps is None else gyro_dps[:, i])
    q = 1.0 / lsb if lsb else 0.0
    model = {"sample_rate_hz": sample_rate_hz, "gyro_unit": "lsb" if unit == "lsb" else "dps"}
    if lsb:
        model["lsb_per_dps"] = lsb
    model["axes"] = {}
    for i, a in enumerate(AXES):
        x = axis_dps(rec, i) if gyro_dps is None else gyro_dps[:, i]
        sigma, fit = _white_noise(x, sample_rate_hz, q)
        # a constant axis's bias is its value, exactly (the mean of 6000 equal samples can be an ulp off,
        # and its constant simulations then differ from the record in every feature: D ~ 5e8)
        bias_dps = fit[1] if fit is not None else float(x[0]) if not np.ptp(x) > 0 else float(np.mean(x))
        model["axes"][a] = {"bias_dps": bias_dps,
                            "arw_dps_per_sqrt_hz": float(sigma / math.sqrt(sample_rate_hz)), "effects": []}
    return model


def recorded_lsb_per_dps(axis_dps_of):
    """LSB per deg/s of a record not stored in LSB whose three axes (``axis_dps_of(i)``: axis i in
    deg/s, one at a time) sit on one grid, or None. int16 codes stored as deg/s (k / 131) are as
    quantized as the codes, and a baseline without the step read their steps as spikes (D 6000
    and false outliers on every axis, issue 37). The step is that of the axes with three values
    or more (:func:`~gyrofilter.analysis.stats.grid_step`; the same within its tolerance); an
    axis with two values (a quiet one) must sit on it. None where an axis is off the grid, or
    constant, or where no axis has three values, or the step is outside
    :data:`~gyrofilter.units.LSB_PER_DPS_RANGE`."""
    steps = [stats.grid_step(axis_dps_of(i)) for i in range(3)]
    known = [s for s in steps if s is not None]
    if not known or max(known) - min(known) > stats.GRID_TOLERANCE * min(known):
        return None
    q = min(known)
    if any(s is None and stats.grid_step(axis_dps_of(i), q) is None for i, s in enumerate(steps)):
        return None
    lsb = 1.0 / q
    return lsb if LSB_PER_DPS_RANGE[0] <= lsb <= LSB_PER_DPS_RANGE[1] else None


def extended_axis(base_axis, cands, xc, sample_rate_hz, q):
    """The extended model's axis spec before its effects: white noise re-fitted on the
    series ``xc`` cleaned of the findings ``cands`` (corrected for the colored noise's
    high-pass loss), and the **mean** bias of the cleaned series (the deterministic components
    were fitted mean-free); :func:`start_bias` turns it into the model's bias at t = 0 for the
    findings a model holds. Without findings, the baseline's axis."""
    spec = dict(base_axis)
    spec["effects"] = []
    if not cands:
        return spec
    n = xc.size
    sigma = noise_sigma(xc, sample_rate_hz, q or 0.0, mask_spikes=not any(c.effect == HEAVY_TAILS for c in cands))
    for c in cands:  # bands, humps and tones (above the high-pass) are terms of their own: N'^2 = N^2 - rms^2
        if c.effect in (NARROWBAND, RESONANCE, WANDERING_TONE):
            rms2 = c.params["amplitude_dps"] ** 2 / 2.0 if c.effect == WANDERING_TONE else c.params["rms_dps"] ** 2
            sigma = math.sqrt(max(sigma**2 - rms2, 0.05 * sigma**2))
    colored = next((c for c in cands if c.effect == COLORED_NOISE), None)
    if colored is not None:
        w = det.colored_window(n, sample_rate_hz)
        sigma *= math.sqrt((1 - 1.0 / w) / (1 - highpass_loss(colored, w)))
    spec["arw_dps_per_sqrt_hz"] = float(sigma / math.sqrt(sample_rate_hz))
    spec["bias_dps"] = float(np.mean(xc))
    return spec


#: samples of the wander simulated alone by :func:`wander_highpassed` (the high-pass keeps
#: scales below a window of 64 samples or 0.5 s, so a stretch of this length holds thousands)
WANDER_SAMPLES = 1 << 18


def wander_highpassed(entry, sample_rate_hz, n):
    """``(v, r1, r2)``: the per-sample variance that the high-pass of :func:`noise_sigma`
    (``x - moving_mean(x, W)``, W = :func:`~gyrofilter.analysis.gap.detectors.colored_window` of
    ``n``) keeps of the wander ``entry`` (an effect-table entry of :data:`WANDERS`) alone, and
    its lag-1 and lag-2 autocorrelations there. A bias instability's 1/f spectrum reaches the
    highest frequencies: at 10 Hz with B = 0.008 and N = 0.0057 deg/s/sqrt(Hz) it is 18 % of
    the high-passed variance (2 % at 100 Hz), which the white level would otherwise take for its
    own, with a lag-1 of 0.65 that the colored detector would take for a colored noise's. The wander is simulated alone (no
    white noise, no bias, no quantization; seed 0) over min(n, :data:`WANDER_SAMPLES`) samples."""
    return _wander_highpassed(tuple(sorted((k, v) for k, v in entry.items())), float(sample_rate_hz), int(n))


@functools.lru_cache(maxsize=64)
def _wander_highpassed(items, sample_rate_hz, n):
    zero = {"bias_dps": 0.0, "arw_dps_per_sqrt_hz": 0.0, "effects": []}
    spec, _ = validate_model({"sample_rate_hz": sample_rate_hz, "gyro_unit": "dps",
                              "axes": {"x": dict(zero, effects=[dict(items)]), "y": dict(zero), "z": dict(zero)}})
    m = min(n, WANDER_SAMPLES)
    e = simulate_axis(spec, m, sample_rate_hz, 0, 0)
    e -= stats.moving_mean(e, det.colored_window(n, sample_rate_hz))
    e -= e.mean()
    v = float(stats.dot(e, e))
    return (v / m, float(stats.dot(e[1:], e[:-1])) / v, float(stats.dot(e[2:], e[:-2])) / v) if v > 0 else (0.0, 0.0, 0.0)


def white_less_wanders(arw_dps_per_sqrt_hz, entries, colored, n, sample_rate_hz):
    """The white level of a model holding the effect entries ``entries`` when ``arw`` was
    measured on the high-passed series (:func:`extended_axis`, with the axis's colored-noise
    candidate ``colored`` or None): less what the wanders among them put there,
    ``N'^2 f_s = N^2 f_s - g sum v_w`` (``v_w`` of :func:`wander_highpassed`; ``g`` the scaling
    of that variance to the white level: ``1 / (1 - 1/W)``, or ``1 / (1 - c)`` under a colored
    noise, whose correction :func:`extended_axis` made), at least a twentieth of the variance."""
    v = sum(wander_highpassed(e, sample_rate_hz, n)[0] for e in entries if e["effect"] in WANDERS)
    if not v > 0:
        return arw_dps_per_sqrt_hz
    w = det.colored_window(n, sample_rate_hz)
    g = 1.0 / (1.0 - highpass_loss(colored, w)) if colored is not None else 1.0 / max(1.0 - 1.0 / w, 0.5)
    s2 = arw_dps_per_sqrt_hz ** 2 * sample_rate_hz
    return float(math.sqrt(max(s2 - g * v, 0.05 * s2) / sample_rate_hz))


def highpass_loss(colored, w):
    """The fraction ``c = L / W`` (at most 0.9) of a colored noise's variance that the high-pass
    of :func:`noise_sigma` (a moving mean of ``w`` samples) removed with the white noise's
    ``1 / W`` (L its long-run ratio; :func:`gyrofilter.analysis.gap.detectors.lags_from_highpassed`)."""
    return min(det.long_run_ratio(colored.params["lag1"], colored.params.get("lag2")) / w, 0.9)


def start_bias(mean_bias_dps, cands, duration_s):
    """The model's constant bias b for the findings ``cands`` of a record of ``duration_s``
    whose mean bias is ``mean_bias_dps``: the mean less each deterministic shape's mean over the
    record (the simulator's shapes start at t = 0: a step s at t_0 has mean s (1 - t_0 / T), a
    ramp R t has R T / 2, a warm-up A e^(-t/tau) has A tau / T (1 - e^(-T/tau))). Only the
    findings the model holds move it: a shape that was dropped leaves the mean."""
    b, T = float(mean_bias_dps), float(duration_s)
    for c in cands:
        if c.effect == BIAS_STEP:
            b -= c.params["size_dps"] * (1 - c.params["time_s"] / T)
        elif c.effect == RATE_RAMP:
            b -= c.params["r_dps_per_s"] * T / 2
        elif c.effect == WARMUP:
            tau = c.params["tau_s"]
            b -= c.params["amplitude_dps"] * tau / T * (1 - math.exp(-T / tau))
    return b


def temperature_table(rec, temp_c, max_points=1000):
    """The simulations' temperature profile: ``temp_c`` (the record's column as the analysis took it,
    its read glitches replaced: :func:`gyrofilter.tempscreen.screened_temp`) against ``rec``'s times,
    in block means of at most ``max_points`` points."""
    t = rec.t_s - rec.t_s[0] if "t" in rec.columns else np.arange(len(rec)) / rec.sample_rate_hz
    temp = np.asarray(temp_c, dtype=float)
    step = max(1, temp.size // max_points)
    # block means keep the quantized column's level without its read noise
    n = (temp.size // step) * step
    tt = t[:n].reshape(-1, step).mean(axis=1) if n else t
    tc = temp[:n].reshape(-1, step).mean(axis=1) if n else temp
    return {"t_s": [float(v) for v in tt], "temp_c": [float(v) for v in tc]}


def effect_entry(cand, preserve="std"):
    """The effect-table entry of a finding; a colored noise keeps the per-sample std of the
    axis's white noise (``preserve="std"``) or, in a composite model whose white level N comes
    from the wavelet-variance fit, its long-tau level (``"arw"``)."""
    entry = {"effect": cand.effect}
    entry.update(cand.plain_params())
    if cand.effect == COLORED_NOISE:
        entry["preserve"] = preserve
    if cand.effect == TEMPERATURE:
        entry["reference_c"] = cand.reference_c
    return entry


# ---------------------------------------------------------------------------------------------
# simulated features


def simulate_axis(spec, n, sample_rate_hz, seed, axis):
    """One run of one axis of the validated model ``spec``: ``n`` samples in deg/s, filled
    block by block (:func:`gyrofilter.sim.simulate.simulate_axis_dps`; the same numbers as that
    axis of a full :func:`~gyrofilter.sim.simulate.simulate` run with this seed)."""
    x = np.empty(n)
    pos = 0
    for block in simulate_axis_dps(spec, n / sample_rate_hz, axis, seed=int(seed), validated=spec):
        k = min(block.size, n - pos)
        x[pos:pos + k] = block[:k]
        pos += k
    return x[:pos]


class Progress:
    """Status lines for a step of ``total`` units of work: the fraction done and the time
    left, ``left = elapsed (total - done) / done``, at most one line per ``every_s`` seconds
    (and the last)."""

    def __init__(self, say, label, total, every_s=2.0):
        self.say, self.label, self.total, self.every_s = say, label, total, every_s
        self.t0 = self.last = time.perf_counter()

    def step(self, done):
        now = time.perf_counter()
        if self.say is None or (now - self.last < self.every_s and done < self.total):
            return
        self.last = now
        left = (now - self.t0) * (self.total - done) / max(done, 1)
        self.say(f"{self.label}: {done}/{self.total} ({100 * done / self.total:.0f} %, about {left:.0f} s left)")


def sim_features(model, n, sample_rate_hz, seeds, axes_idx, taus, bands, say=None, label="simulations"):
    """Features of ``len(seeds)`` runs of ``model`` (list per axis index). Each run simulates
    only the axes asked for, one at a time, so memory holds one axis of one run."""
    spec, _ = validate_model(model)
    axes_idx = list(axes_idx)
    out = {i: [] for i in axes_idx}
    bar = Progress(say, label, len(seeds) * len(axes_idx))
    for k, s in enumerate(seeds):
        for j, i in enumerate(axes_idx):
            out[i].append(features(simulate_axis(spec, n, sample_rate_hz, s, i), sample_rate_hz, taus, bands,
                                   overwrite=True))
            bar.step(k * len(axes_idx) + j + 1)
    return out
