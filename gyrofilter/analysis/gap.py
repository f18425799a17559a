"""Model-gap analysis: what the baseline simulation gets wrong, the cause, and the gain.

``analyse_gap(rec)`` writes the gap report of docs/formats.md (section 3) in five steps:

1. **Baseline fit** per axis (the package's plain simulation): constant bias ``b`` = mean of
   the rate; white noise of per-sample standard deviation ``sigma`` = the standard deviation of
   the high-passed rate ``x - moving_mean(x, W)`` (W = max(64 samples, 0.5 s), divided by
   ``sqrt(1 - 1/W)``, spikes removed), less the quantization variance ``q^2 / 12`` that the
   simulator adds back (``q = 1 / lsb_per_dps`` for ``gyro_unit: lsb``, else 0);
   ``arw_dps_per_sqrt_hz = sigma / sqrt(f_s)`` (white noise per sample ``N sqrt(f_s)``,
   IEEE Std 952-1997 annex C).
2. **Simulated spread**: the baseline is simulated ``n_sims`` times (seeded; common random
   numbers with the extended model) with :func:`gyrofilter.sim.simulate.simulate`, and the same
   features are computed on the measurement and on every run (:func:`features`): the
   overlapping Allan deviation at log-spaced tau (:func:`gyrofilter.analysis.allan.overlapping_adev`),
   band powers of the periodogram in log-spaced bands, the largest periodogram line over the
   local noise level, the lag-1 autocorrelation of the high-passed noise and the spike count.
   Each feature's departure is ``z = (f_meas - mean_sims) / max(sd_sims, floor)``.
3. **Causes**: :mod:`gyrofilter.analysis.detectors` maps departures to effects of the table, in a fixed
   decision order (outliers, sinusoid, narrow-band noise, colored noise, slow bias effects; see
   there for how ramp / random walk / warm-up / Gauss-Markov / bias instability / step /
   temperature are told apart), each with its own significance threshold, and estimates the
   parameters. A narrow band's variance is taken out of the white noise (N'^2 = N^2 - rms^2 / f_s)
   and its lag-1 and lag-2 correlations out of the colored noise's (:func:`detectors.lags_from_highpassed`).
4. **Gain**: the discrepancy ``D = mean_k z_k^2`` over the features of the axis (lower is
   better; about 1 when the model explains the measurement) is computed against the baseline's
   runs (``before``) and against runs of the baseline extended by one finding (``after``); a
   finding is kept only if ``after < before`` (a real gain). The overall figure uses the model
   extended by every kept finding. Where an axis's D after is still above
   :data:`~gyrofilter.analysis.detectors.OUTSIDE_NULL_D`, a **composite stochastic part** is tried: a GMWM-style fit
   (:mod:`gyrofilter.analysis.gmwm`; Guerrier et al. 2013) of white noise, an optional rate random walk
   and 0-3 Gauss-Markov terms to the Haar wavelet variance of the series cleaned of the
   deterministic findings, at tau >= max(1 s, 16 samples) (shorter scales belong to the colored
   noise and the bands), the model chosen by Q + 2p (not WVIC). Its terms replace the axis's
   slow stochastic findings (and its colored noise, if that is better without it), its N
   becomes the white level (the colored noise then keeps the long-tau level, ``preserve:
   arw``, and, if D is lower so, the per-sample variance too: :func:`_composite_lags`), and
   the replacement is kept only if D falls below :data:`~gyrofilter.analysis.detectors.COMPOSITE_MIN_GAIN` times its value.
5. The report: a JSON-ready dict with ``baseline``, ``findings`` (effect, axis, params,
   evidence, gain), ``extended_model`` (runs in ``gyrofilter simulate``), per-axis feature
   departures and the discrepancies; where an axis's D after is still above
   :data:`~gyrofilter.analysis.detectors.OUTSIDE_NULL_D`, a note names the feature that departs most from the extended model
   and what its sign says (:func:`_still_departs`).
"""
from __future__ import annotations

import math
import time

import numpy as np

from . import detectors as det
from ..errors import RecordingError
from ..units import AXES, MIN_NOISE_DPS, check_sample_rate_hz

METRIC = "mean squared z-score of the Allan deviation, band powers, spectral line, lag-1 and spike count vs model simulations"
#: minimum samples for any analysis
MIN_SAMPLES = 256
#: floors of the feature spreads (log units for log features)
_LOG_FLOOR = 0.02


def default_n_sims(n_samples):
    """Baseline runs: 24 up to 200 000 samples per axis, then fewer (at least 12) so that
    hours of data stay fast; the spread of a feature is estimated to about +-20 % from 12 runs."""
    return int(max(12, min(24, round(24 * 200_000 / max(n_samples, 1)))))


# ---------------------------------------------------------------------------------------------
# features


def feature_taus(n, fs):
    """Log-spaced cluster times (s), 6 per decade, one sample to a ninth of the record."""
    m_max = max(1, n // 9)
    m = np.unique(np.round(np.logspace(0, math.log10(m_max), max(2, int(6 * math.log10(max(m_max, 2))) + 1))).astype(int))
    return m / fs


def feature_bands(n, fs, count=24):
    """Log-spaced frequency band edges (Hz) from 8 / T to f_s / 2."""
    f_lo = 8.0 * fs / n
    f_hi = fs / 2
    if f_lo >= f_hi:
        return np.array([0.0, f_hi])
    return np.geomspace(f_lo, f_hi, count + 1)


#: the Allan feature starts a second difference every max(1, m // ADEV_STARTS) samples
ADEV_STARTS = 8


def feature_adev(x, fs, taus_s):
    """Overlapping Allan deviation with the second differences started every
    ``s = max(1, m // 8)`` samples instead of every sample:

    ``sigma^2(m tau0) = sum_{j = 0, s, 2s, ... <= N - 2m} (X_{j+2m} - 2 X_{j+m} + X_j)^2 /
    (2 (m tau0)^2 K)``, ``X`` the integral of the mean-removed rate, ``K`` the number of terms
    (NIST SP 1065 eq. 11 on a subset of its start points). The expectation is that of the
    fully overlapping estimator; neighbouring second differences overlap in all but ``s`` of
    ``2m`` samples, so keeping 8 per cluster length loses almost nothing: on white noise and on
    a random walk (300 runs of 60 000 samples, m = 1 to 6666) the spread of log sigma was
    within 2 % of the fully overlapping one. The cost falls from one pass over the record per
    tau to about 9 passes for all taus together (the record length no longer multiplies the
    number of taus). The measurement and its simulations use the same estimator."""
    n = x.size
    phase = np.empty(n + 1)
    phase[0] = 0.0
    np.subtract(x, float(np.mean(x)), out=phase[1:])
    np.cumsum(phase[1:], out=phase[1:])
    phase /= fs
    m_all = np.round(np.asarray(taus_s, dtype=float) * fs).astype(np.int64)
    out = np.empty(m_all.size)
    buf = np.empty(_ADEV_CHUNK)
    for i, m in enumerate(m_all):
        m = int(m)
        step = max(1, m // ADEV_STARTS)
        k = (n - 2 * m) // step + 1
        total = 0.0
        for a in range(0, k, _ADEV_CHUNK):  # in chunks, into one buffer: no N-long temporaries
            b = min(k, a + _ADEV_CHUNK)
            d = buf[:b - a]
            np.multiply(phase[m + a * step:m + (b - 1) * step + 1:step], -2.0, out=d)
            d += phase[2 * m + a * step:2 * m + (b - 1) * step + 1:step]
            d += phase[a * step:(b - 1) * step + 1:step]
            total += float(det.dot(d, d))
        out[i] = math.sqrt(total / (2.0 * k)) / (m / fs)
    return out


_ADEV_CHUNK = 1 << 15


def features(x, fs, taus_s, bands_hz):
    """Feature vector of one axis: (log ADEV per tau (:func:`feature_adev`), log band powers,
    log line ratio, lag1, log(1 + spikes)). Returns a dict of arrays."""
    adev = feature_adev(x, fs, taus_s)
    line, _, _, spec = det.sinusoid_statistic(x, fs, return_spectrum=True)
    n_p = det.periodogram_length(x.size)  # the samples the periodogram uses
    if spec is None:
        spec = np.abs(np.fft.rfft(det.detrend_line(x[:n_p]))) ** 2 / n_p
    idx = _first_bins(bands_hz, spec.size, n_p, fs)
    bp = np.array([spec[a:b].mean() if b > a else np.nan for a, b in zip(idx[:-1], idx[1:])])
    r1, _ = det.lag1_statistic(x, fs)
    mask, _, _ = det.outlier_statistic(x)
    return {"adev": np.log(np.maximum(adev, 1e-300)), "band": np.log(np.maximum(bp, 1e-300)),
            "line": np.array([math.log(max(line, 1.0))]), "lag1": np.array([r1]),
            "spikes": np.array([math.log1p(float(mask.sum()))])}


def _first_bins(freqs_hz, size, n, fs):
    """For each frequency, the first periodogram bin ``j`` (of ``size``) with
    ``j f_s / N >= f``: ``searchsorted(arange(size) f_s / N, f)`` without the array."""
    idx = np.clip(np.ceil(np.asarray(freqs_hz, dtype=float) * n / fs).astype(np.int64), 0, size)
    for i, f in enumerate(np.asarray(freqs_hz, dtype=float)):  # settle float rounding at the edge
        while idx[i] > 0 and (idx[i] - 1) * fs / n >= f:
            idx[i] -= 1
        while idx[i] < size and idx[i] * fs / n < f:
            idx[i] += 1
    return idx


_FLOORS = {"adev": _LOG_FLOOR, "band": _LOG_FLOOR, "line": 0.3, "lag1": None, "spikes": 0.5}


def departures(meas, sims, n):
    """z-scores of the measured features against the simulated runs (dict of arrays)."""
    out = {}
    for key, value in meas.items():
        stack = np.array([s[key] for s in sims])
        mean = np.nanmean(stack, axis=0)
        sd = np.nanstd(stack, axis=0, ddof=1) if len(sims) > 1 else np.zeros_like(mean)
        floor = _FLOORS[key] if _FLOORS[key] is not None else 1.0 / math.sqrt(n)
        z = (value - mean) / np.maximum(sd, floor)
        out[key] = (np.where(np.isfinite(z), z, 0.0), mean, sd)
    return out


def discrepancy(deps):
    """``D = mean z^2`` over all features of one axis (lower is better)."""
    z = np.concatenate([v[0] for v in deps.values()])
    return float(np.mean(z ** 2)) if z.size else 0.0


# ---------------------------------------------------------------------------------------------
# baseline


def _noise_sigma(x, fs, q_dps):
    """Per-sample white-noise std of the baseline (see module docstring)."""
    w = det.colored_window(x.size, fs)
    e = x - det.moving_mean(x, w)
    mask, _, _ = det.outlier_statistic(x)
    if mask.any():
        e = e[~mask]
    var = float(np.var(e)) / max(1.0 - 1.0 / w, 0.5)
    var = max(var - (q_dps ** 2) / 12.0, 0.25 * var)
    return math.sqrt(var)


def baseline_model(rec, gyro_dps=None):
    """The baseline simulator model (shared schema) fitted to ``rec`` (or to the (N, 3) rates
    ``gyro_dps``)."""
    fs = rec.sample_rate_hz
    unit = rec.gyro_unit
    lsb = rec.lsb_per_dps if unit == "lsb" else None
    q = 1.0 / lsb if lsb else 0.0
    model = {"sample_rate_hz": fs, "gyro_unit": "lsb" if lsb else "dps"}
    if lsb:
        model["lsb_per_dps"] = lsb
    model["axes"] = {}
    for i, a in enumerate(AXES):
        x = _axis_dps(rec, i) if gyro_dps is None else gyro_dps[:, i]
        sigma = _noise_sigma(x, fs, q)
        model["axes"][a] = {"bias_dps": float(np.mean(x)),
                            "arw_dps_per_sqrt_hz": float(sigma / math.sqrt(fs)), "effects": []}
    return model


def _copy_model(model):
    import copy

    return copy.deepcopy(model)


def _temperature_table(rec, max_points=1000):
    t = rec.t_s - rec.t_s[0] if "t" in rec.columns else np.arange(len(rec)) / rec.sample_rate_hz
    temp = np.asarray(rec.temp_c, dtype=float)
    step = max(1, temp.size // max_points)
    # block means keep the quantized column's level without its read noise
    n = (temp.size // step) * step
    tt = t[:n].reshape(-1, step).mean(axis=1) if n else t
    tc = temp[:n].reshape(-1, step).mean(axis=1) if n else temp
    return {"t_s": [float(v) for v in tt], "temp_c": [float(v) for v in tc]}


def _effect_entry(cand, preserve="std"):
    """The effect-table entry of a finding; a colored noise keeps the per-sample std of the
    axis's white noise (``preserve="std"``) or, in a composite model whose white level N comes
    from the wavelet-variance fit, its long-tau level (``"arw"``)."""
    entry = {"effect": cand.effect}
    entry.update({k: float(v) for k, v in cand.params.items()})
    if cand.effect == "colored_noise":
        entry["preserve"] = preserve
    if cand.effect == "temperature":
        entry["reference_c"] = cand.extra.get("reference_c")
    return entry


# ---------------------------------------------------------------------------------------------
# simulation of features


def _simulate_axis(spec, n, fs, seed, axis):
    """One run of one axis of the validated model ``spec``: ``n`` samples in deg/s, filled
    block by block (:func:`gyrofilter.sim.simulate.simulate_axis_dps`; the same numbers as that
    axis of a full :func:`~gyrofilter.sim.simulate.simulate` run with this seed)."""
    from ..sim.simulate import simulate_axis_dps

    x = np.empty(n)
    pos = 0
    for block in simulate_axis_dps(spec, n / fs, axis, seed=int(seed), validated=spec):
        k = min(block.size, n - pos)
        x[pos:pos + k] = block[:k]
        pos += k
    return x[:pos]


class _Progress:
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


def _sim_features(model, n, fs, seeds, axes_idx, taus, bands, say=None, label="simulations"):
    """Features of ``len(seeds)`` runs of ``model`` (list per axis index). Each run simulates
    only the axes asked for, one at a time, so memory holds one axis of one run."""
    from ..sim.model import validate_model

    spec, _ = validate_model(model)
    axes_idx = list(axes_idx)
    out = {i: [] for i in axes_idx}
    bar = _Progress(say, label, len(seeds) * len(axes_idx))
    for k, s in enumerate(seeds):
        for j, i in enumerate(axes_idx):
            out[i].append(features(_simulate_axis(spec, n, fs, s, i), fs, taus, bands))
            bar.step(k * len(axes_idx) + j + 1)
    return out


# ---------------------------------------------------------------------------------------------
# main entry


def analyse_gap(rec, *, seed=0, n_sims=None, progress=None, recording_name=None):
    """Run the gap analysis on a :class:`~gyrofilter.recording.Recording`; returns the report
    dict of docs/formats.md section 3 (with ``discrepancy``, ``departures``,
    ``runtime_s``). ``progress(text)`` is called with short status lines."""
    import warnings

    from ..errors import GyroFilterError

    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            return _analyse_gap(rec, seed=seed, n_sims=n_sims, progress=progress, recording_name=recording_name)
        except GyroFilterError:
            raise
        except (ValueError, ArithmeticError) as exc:  # a statistic that cannot run numerically (a singular
            # fit, a series too short for a spectrum): not the user's error, no findings; any other
            # exception (ImportError, TypeError, ...) is a bug or a broken install and is raised
            g = np.asarray(rec.gyro_dps, dtype=float)
            base = baseline_model(rec, g) if len(g) >= 2 else {}
            name = recording_name if recording_name is not None else (rec.path or "")
            return {"recording": name, "sample_rate_hz": float(rec.sample_rate_hz),
                    "duration_s": len(g) / float(rec.sample_rate_hz),
                    "baseline": {"description": "constant bias + white noise (+ quantization of the recorded unit)",
                                 "axes": {a: dict(base.get("axes", {}).get(a, {})) for a in AXES}, "model": base},
                    "findings": [], "extended_model": base,
                    "notes": [f"the analysis could not run ({type(exc).__name__}: {exc}); no findings reported"]}


def _axis_dps(rec, i):
    """Axis ``i`` of ``rec.gyro_dps``, converted from its column when asked (the column
    itself for ``gyro_unit: dps``): the analysis never holds the three axes in deg/s at once."""
    from ..recording import GYRO_COLUMNS
    from ..units import to_dps

    return to_dps(rec.columns[GYRO_COLUMNS[i]], rec.gyro_unit, rec.lsb_per_dps)


def _analyse_gap(rec, *, seed, n_sims, progress, recording_name):
    """The five steps of the module docstring, one function each, on a shared :class:`_GapRun`."""
    t_start = time.perf_counter()
    run = _GapRun(rec, seed=seed, n_sims=n_sims, say=progress or (lambda text: None), recording_name=recording_name)
    if run.n >= MIN_SAMPLES:
        _baseline_spread(run)       # 2.
        _detect(run)                # 3.
        _keep_findings(run)         # 4., gain per finding
        _composite_step(run)        # 4., composite stochastic part where D stays high
        _write_findings(run)        # 5.
    run.report["runtime_s"] = time.perf_counter() - t_start
    return run.report


class _GapRun:
    """One gap analysis: the recording, the baseline fit (step 1, done here), the simulation
    seeds and features, the candidates and the per-axis departures of every model tried
    (computed once per set of findings: an axis's departures depend only on that axis's model,
    whose random streams are its own)."""

    def __init__(self, rec, *, seed, n_sims, say, recording_name):
        where = rec.path or "recording"
        fs = check_sample_rate_hz(rec.sample_rate_hz, f"{where}: sample_rate_hz", RecordingError)
        n = len(rec)
        if n < 2:
            raise RecordingError(f"{where}: {n} sample(s) after the header: a gap analysis needs data rows")
        self.rec, self.fs, self.n, self.say = rec, fs, n, say
        self.report = report = {
            "recording": recording_name if recording_name is not None else (rec.path or ""),
            "sample_rate_hz": fs, "duration_s": n / fs,
            "baseline": {"description": "constant bias + white noise (+ quantization of the recorded unit)",
                         "axes": {a: {} for a in AXES}},
            "findings": [], "extended_model": {}, "notes": []}
        if not all(np.all(np.isfinite(_axis_dps(rec, i))) for i in range(3)):
            raise RecordingError(f"{where}: gyro columns hold non-finite values")
        self.base = base = baseline_model(rec)
        report["baseline"]["model"] = base
        self.q = q = 1.0 / base["lsb_per_dps"] if base.get("lsb_per_dps") else None
        for a in AXES:
            report["baseline"]["axes"][a] = {"bias_dps": base["axes"][a]["bias_dps"],
                                             "arw_dps_per_sqrt_hz": base["axes"][a]["arw_dps_per_sqrt_hz"],
                                             "quantization_dps": q}
        report["extended_model"] = _copy_model(base)
        if n < MIN_SAMPLES:
            report["notes"].append(f"only {n} samples (< {MIN_SAMPLES}): too short to tell anything beyond the baseline")
            return
        temp = rec.temp_c
        self.temp = None if temp is None else np.asarray(temp, dtype=float)
        if self.temp is not None and not np.all(np.isfinite(self.temp)):
            self.temp = None
            report["notes"].append("temp column has non-finite values: temperature not analysed")
        _static_notes(self)
        self.taus = feature_taus(n, fs)
        self.bands = feature_bands(n, fs)
        self.m = default_n_sims(n) if n_sims is None else int(n_sims)
        self.seeds = np.random.default_rng(seed).integers(0, 2**31, size=self.m)
        self.n_ext = max(6, self.m // 2)
        self.candidates = []  # (axis index, Candidate)
        self.ext_axes = {}  # axis name -> the extended axis spec before its effects
        self.composite_axes = {}  # axis name -> the same with the composite fit's white level
        self.wvs = [None, None, None]  # wavelet variance of each cleaned axis at the composite's scales
        self.kept = []  # (candidate index, axis index, Candidate, D of the axis with it alone)
        self.resolved_lags = [None, None, None]  # composite model: the colored noise's lags from _composite_lags
        self._deps_cache = {}

    def axis_spec(self, i, ks):
        """Axis ``i``'s spec extended by the candidates ``ks`` (the composite's white level and
        ``preserve: arw`` when one of them belongs to a composite model)."""
        a = AXES[i]
        cands = [self.candidates[k][1] for k in ks]
        composite = any(c.extra.get("composite") for c in cands)
        spec = dict(self.composite_axes[a] if composite else self.ext_axes[a])
        spec["effects"] = [_effect_entry(c, preserve="arw" if composite else "std") for c in cands]
        if composite and self.resolved_lags[i]:
            for entry in spec["effects"]:
                if entry["effect"] == "colored_noise":
                    entry.update(self.resolved_lags[i])
        return spec

    def axis_deps(self, i, ks, label):
        """Departures of the measured axis ``i`` from ``n_ext`` runs of the baseline with axis
        ``i`` extended by the candidates ``ks``."""
        key = (i, tuple(sorted(ks)), tuple(sorted((self.resolved_lags[i] or {}).items())))
        if key not in self._deps_cache:
            model = _copy_model(self.base)
            model["axes"][AXES[i]] = self.axis_spec(i, key[1])
            if any(self.candidates[k][1].effect == "temperature" for k in key[1]):
                model["temperature"] = _temperature_table(self.rec)
            sims_k = _sim_features(model, self.n, self.fs, self.seeds[:self.n_ext], [i], self.taus, self.bands,
                                   self.say, label)[i]
            self._deps_cache[key] = departures(self.meas_feats[i], sims_k, self.n)
        return self._deps_cache[key]

    def axis_discrepancy(self, i, ks, label):
        return discrepancy(self.axis_deps(i, ks, label))

    def kept_on(self, i):
        return [k for k, ci, _, _ in self.kept if ci == i]


def _static_notes(run):
    """A note per axis whose block means move more than a still gyro's would."""
    from .still import not_static

    for i, a in enumerate(AXES):
        moved = not_static(_axis_dps(run.rec, i), run.fs, run.base["axes"][a]["arw_dps_per_sqrt_hz"] * math.sqrt(run.fs))
        if moved:
            run.report["notes"].append(f"axis {a}: {moved}; the analysis models a still gyro, so its findings describe the motion")


def _baseline_spread(run):
    """Step 2: features of the measurement and of ``m`` baseline runs; departures and D before."""
    n, fs = run.n, run.fs
    run.say(f"baseline: {run.m} simulations of {n / fs:.0f} s at {fs:g} Hz")
    run.meas_feats = [features(_axis_dps(run.rec, i), fs, run.taus, run.bands) for i in range(3)]
    sims = _sim_features(run.base, n, fs, run.seeds, range(3), run.taus, run.bands, run.say,
                         "baseline simulations (runs x axes)")
    run.deps = [departures(run.meas_feats[i], sims[i], n) for i in range(3)]
    del sims
    run.before = [discrepancy(d) for d in run.deps]
    run.report["departures"] = {a: _departure_summary(run.deps[i], run.meas_feats[i], run.taus, run.bands)
                                for i, a in enumerate(AXES)}


def _detect(run):
    """Step 3: the detectors per axis, in the decision order; the extended model's white noise
    and bias re-fitted on the series cleaned of the axis's findings, and that series' wavelet
    variance kept for the composite step."""
    for i, a in enumerate(AXES):
        run.say(f"detectors on {a}")
        x = _axis_dps(run.rec, i)
        idle = ("constant signal" if not np.ptp(x) > 0 else
                f"noise below {MIN_NOISE_DPS:g} deg/s (too small for the detectors in float64)"
                if not np.std(x) >= MIN_NOISE_DPS else None)
        if idle:
            run.report["notes"].append(f"axis {a}: {idle}, nothing to analyse")
            run.ext_axes[a] = dict(run.base["axes"][a], effects=[])
            continue
        try:
            cands, xc = _detect_axis(x, run.fs, run.temp)
        except (ValueError, FloatingPointError, np.linalg.LinAlgError) as exc:  # never crash
            run.report["notes"].append(f"axis {a}: detectors could not run ({exc})")
            cands, xc = [], x
        for c in cands:
            if c.effect == "temperature":
                c.extra["reference_c"] = float(np.mean(run.temp))
            run.candidates.append((i, c))
        run.ext_axes[a] = _extended_axis(run.base["axes"][a], cands, xc, run.fs, run.q)
        run.wvs[i] = _slow_wavelet_variance(xc, run.fs)
        del x, xc


def _keep_findings(run):
    """Step 4: gain per finding, the axis extended by this finding alone (the contract's gain);
    a finding that shows no gain alone is still kept when the axis has other candidates and
    leaving it out of the model with all of them raises the discrepancy (leave-one-out). Then D
    of each axis extended by all its kept findings."""
    cands, before, notes = run.candidates, run.before, run.report["notes"]
    run.single = single = {}
    for k, (i, c) in enumerate(cands):
        label = f"gain of {c.effect} on {AXES[i]} ({k + 1}/{len(cands)})"
        run.say(label)
        try:
            single[k] = run.axis_discrepancy(i, [k], label)
        except (ValueError, FloatingPointError) as exc:
            notes.append(f"{c.effect} on {AXES[i]}: extended model could not run ({exc})")
    for k, (i, c) in enumerate(cands):
        if k not in single:
            continue
        after = single[k]
        if after < before[i]:
            run.kept.append((k, i, c, after))
            continue
        others = [k2 for k2, (i2, _) in enumerate(cands) if i2 == i and k2 != k and k2 in single]
        if others:
            label = f"{c.effect} on {AXES[i]} with and without the axis's other findings"
            run.say(label)
            try:
                with_all = run.axis_discrepancy(i, others + [k], label)
                without = run.axis_discrepancy(i, others, label)
            except (ValueError, FloatingPointError):
                with_all = without = float("inf")
            if with_all < without:
                run.kept.append((k, i, c, after))
                notes.append(f"{c.effect} on {AXES[i]}: no gain alone ({before[i]:.3g} -> {after:.3g}) but kept: with the "
                             f"axis's other findings D = {with_all:.3g}, without it {without:.3g}")
                continue
        notes.append(f"{c.effect} on {AXES[i]} dropped: no gain (discrepancy {before[i]:.3g} -> {after:.3g})")
    run.after = list(before)
    if run.kept:
        run.say("overall gain of the extended model")
        for i in sorted({i for _, i, _, _ in run.kept}):
            run.after[i] = run.axis_discrepancy(i, run.kept_on(i), f"extended model on {AXES[i]}")


def _composite_step(run):
    """Step 4, continued: where an extended axis is still far outside the null band (D above
    :data:`~gyrofilter.analysis.detectors.OUTSIDE_NULL_D`), a composite stochastic part (:func:`_composite_candidates`)
    replaces the axis's slow stochastic findings, and its colored noise if that is better
    without it, when D falls below :data:`~gyrofilter.analysis.detectors.COMPOSITE_MIN_GAIN` times its value."""
    cands, notes = run.candidates, run.report["notes"]
    for i, a in enumerate(AXES):
        if run.after[i] <= det.OUTSIDE_NULL_D or run.wvs[i] is None:
            continue
        run.say(f"composite stochastic fit on {a}")
        fit, comp = _composite_candidates(run.wvs[i], run.fs)
        if not comp:
            continue
        keep_k = [k for k, ci, c, _ in run.kept if ci == i and c.effect not in det.STOCHASTIC_MODELS]
        first = len(cands)
        cands.extend((i, c) for c in comp)
        comp_k = list(range(first, len(cands)))
        for k in keep_k:  # the axis's other findings join the composite model
            cands[k][1].extra["composite"] = True
        run.composite_axes[a] = dict(run.ext_axes[a], arw_dps_per_sqrt_hz=fit.arw_dps_per_sqrt_hz)
        d_comp = run.axis_discrepancy(i, keep_k + comp_k, f"composite model on {a}")
        colored_k = [k for k in keep_k if cands[k][1].effect == "colored_noise"]
        if colored_k:
            # the colored noise re-solved to keep the per-sample variance as well
            run.resolved_lags[i] = _composite_lags(run.ext_axes[a], run.composite_axes[a], cands[colored_k[0]][1].params)
            if run.resolved_lags[i] is not None:
                d_alt = run.axis_discrepancy(i, keep_k + comp_k, f"composite model on {a}")
                if d_alt < d_comp:
                    d_comp = d_alt
                else:
                    run.resolved_lags[i] = None
            # a fast Gauss-Markov term of the composite may be what the colored noise stood for
            d_alt = run.axis_discrepancy(i, [k for k in keep_k if k not in colored_k] + comp_k, f"composite model on {a}")
            if d_alt < d_comp:
                d_comp = d_alt
                cands[colored_k[0]][1].extra.pop("composite")
                keep_k = [k for k in keep_k if k not in colored_k]
                notes.append(f"colored_noise on {a} dropped: the composite stochastic part explains the "
                             "correlation without it")
        if d_comp < det.COMPOSITE_MIN_GAIN * run.after[i]:
            single_k = {k: run.axis_discrepancy(i, [k], f"gain of the composite's {cands[k][1].effect} on {a}")
                        for k in comp_k}
            notes.append(
                f"axis {a}: the composite stochastic fit ({fit.name}, chosen by Q + 2p on the wavelet variance at "
                f"tau >= {run.wvs[i].tau_s[0]:.3g} s) lowers D from {run.after[i]:.3g} to {d_comp:.3g}; it replaces the "
                "axis's slow stochastic findings")
            for k in comp_k:
                cands[k][1].statistic = run.after[i] / d_comp
            if run.resolved_lags[i] and colored_k and colored_k[0] in keep_k:
                colored = cands[colored_k[0]][1]
                colored.params.update(run.resolved_lags[i])
                colored.evidence += ("; in the composite model its lags are re-solved to keep both the per-sample "
                                     "variance and the composite fit's white level")
            run.kept = [row for row in run.kept if row[1] != i] + \
                [(k, i, cands[k][1], run.single[k]) for k in keep_k] + [(k, i, cands[k][1], single_k[k]) for k in comp_k]
            run.after[i] = d_comp
        else:
            run.resolved_lags[i] = None
            for k in keep_k:
                cands[k][1].extra.pop("composite")
            notes.append(f"axis {a}: a composite stochastic fit ({fit.name}) did not lower D enough "
                         f"({run.after[i]:.3g} -> {d_comp:.3g}); not used")


def _write_findings(run):
    """Step 5: the extended model, the findings with evidence and gain, the extended model's
    spread in the departure summaries, and the discrepancies."""
    report, kept, before = run.report, run.kept, run.before
    ext = _copy_model(run.base)
    for i, a in enumerate(AXES):
        ks = run.kept_on(i)
        if ks:
            ext["axes"][a] = run.axis_spec(i, ks)
    if any(c.effect == "temperature" for _, _, c, _ in kept):
        ext["temperature"] = _temperature_table(run.rec)
    report["extended_model"] = ext
    for _, i, c, after in kept:
        z_info = _strongest(run.deps[i], run.taus, run.bands)
        report["findings"].append({
            "effect": c.effect, "axis": AXES[i],
            "params": {k: float(v) for k, v in c.params.items()},
            "evidence": c.evidence + (f"; baseline simulations: {z_info}" if z_info else ""),
            "gain": {"metric": "discrepancy D (" + METRIC + ")", "before": before[i], "after": after},
            "statistic": {"name": c.statistic_name, "value": float(c.statistic), "threshold": float(c.threshold)},
        })
    for i in range(3):
        if run.after[i] > det.OUTSIDE_NULL_D:
            deps_e = run.axis_deps(i, run.kept_on(i), f"extended model on {AXES[i]}") if run.kept_on(i) else run.deps[i]
            report["notes"].append(_still_departs(AXES[i], run.after[i], deps_e, run.taus, run.bands))
    for i in sorted({i for _, i, _, _ in kept}):
        deps_e = run.axis_deps(i, run.kept_on(i), f"extended model on {AXES[i]}")
        summ = report["departures"][AXES[i]]
        summ["extended_adev_sim_mean_log"] = [float(v) for v in deps_e["adev"][1]]
        summ["extended_adev_sim_sd_log"] = [float(v) for v in deps_e["adev"][2]]
        summ["extended_band_sim_mean_log"] = [float(v) for v in deps_e["band"][1]]
        summ["extended_band_sim_sd_log"] = [float(v) for v in deps_e["band"][2]]
        summ["extended_discrepancy"] = run.after[i]
    report["discrepancy"] = {"metric": METRIC,
                             "definition": "D = mean over features of z^2, z = (measured - mean of simulations) / max(sd of simulations, floor)",
                             "before": {a: before[i] for i, a in enumerate(AXES)},
                             "after": {a: run.after[i] for i, a in enumerate(AXES)},
                             "overall_before": float(np.mean(before)),
                             "overall_after": float(np.mean(run.after))}
    report["n_simulations"] = run.m
    n, fs = run.n, run.fs
    if n / fs < 300:
        report["notes"].append(f"record of {n / fs:.0f} s: slow bias effects (drift, random walk, bias instability) "
                               "cannot be told apart from white noise beyond tau ~ {:.0f} s".format(n / fs / 9))


#: the composite fit uses the wavelet variance at tau >= max(1 s, 16 samples): shorter scales
#: carry the colored noise's low-pass shape and the narrow bands, which have their own terms
COMPOSITE_MIN_TAU_S = 1.0
_COMPOSITE_STATISTIC = "D of the extended axis without the composite stochastic part / D with it"


def _slow_wavelet_variance(xc, fs):
    """Haar wavelet variance (:func:`gyrofilter.analysis.gmwm.haar_wv`) of the cleaned series at the
    dyadic scales tau >= max(:data:`COMPOSITE_MIN_TAU_S`, 16 / f_s); None when fewer than 4."""
    from . import gmwm

    m_min = max(16, int(math.ceil(COMPOSITE_MIN_TAU_S * fs)))
    if (xc.size - 2 * m_min * 8 + 1) / (2.0 * m_min * 8) < 2.0:
        return None
    wv = gmwm.haar_wv(xc, fs, min_m=m_min)
    return wv if wv.tau_s.size >= 4 else None


def _composite_candidates(wv, fs):
    """GMWM-style composite fit (:func:`gyrofilter.analysis.gmwm.select_model`, Guerrier et al. 2013) of
    white noise + optionally a rate random walk + 0..3 Gauss-Markov terms to ``wv``, the model
    chosen by Q + 2p (not WVIC: see gyrofilter.analysis.gmwm). Returns ``(fit, candidates)``: one
    ``gauss_markov`` per Gauss-Markov term and a ``rate_random_walk`` if the fit has one, marked
    ``extra["composite"]``; the fit's N is the composite model's white level."""
    from . import gmwm

    fit, _ = gmwm.select_model(wv, terms_allowed=("rrw",), starts=3, seed=0)
    out = []
    evidence = (f"composite fit {fit.name} to the Haar wavelet variance at tau = {wv.tau_s[0]:.3g}-{wv.tau_s[-1]:.3g} s "
                f"(weighted objective Q = {fit.objective:.3g} over {wv.tau_s.size} scales, model chosen by Q + 2p)")
    for sigma_dps, tau_s in fit.gauss_markov:
        out.append(det.Candidate(effect="gauss_markov", params={"sigma_dps": sigma_dps, "tau_s": tau_s},
                                 statistic=0.0, threshold=1.0 / det.COMPOSITE_MIN_GAIN, statistic_name=_COMPOSITE_STATISTIC,
                                 evidence=f"Gauss-Markov term (sigma {sigma_dps:.3g} deg/s, tau {tau_s:.3g} s) of a " + evidence,
                                 extra={"composite": True}))
    if fit.rrw_dps_per_sqrt_s is not None:
        out.append(det.Candidate(effect="rate_random_walk", params={"k_dps_per_sqrt_s": fit.rrw_dps_per_sqrt_s},
                                 statistic=0.0, threshold=1.0 / det.COMPOSITE_MIN_GAIN, statistic_name=_COMPOSITE_STATISTIC,
                                 evidence=f"random-walk term (K {fit.rrw_dps_per_sqrt_s:.3g} deg/s/sqrt(s)) of a " + evidence,
                                 extra={"composite": True}))
    return fit, out


def _composite_lags(ext_axis, composite_axis, lags):
    """The colored noise's lags in a composite model, re-solved so that with ``preserve: arw``
    it keeps both the composite fit's long-tau level N and the per-sample variance s^2 of the
    extended axis's colored noise (its ``preserve: std`` level): the short scales of the wavelet
    variance depend on s^2, the long ones on N, so its long-run ratio (1 + 2 sum rho_k) must be
    L = N^2 f_s / s^2. A low pass (``lags`` without ``lag2``) stays one: the AR(1) of ratio L
    has rho = (L - 1) / (L + 1). A first-order ARMA keeps its measured lag1 as well and moves
    its pole (:func:`gyrofilter.sim.noise_terms.arma11_for_lag1_and_ratio`). None when no such
    noise exists."""
    from ..sim import noise_terms as nt

    ratio = composite_axis["arw_dps_per_sqrt_hz"] ** 2 / ext_axis["arw_dps_per_sqrt_hz"] ** 2
    if "lag2" not in lags:
        return {"lag1": float(np.clip((ratio - 1.0) / (ratio + 1.0), -0.99, 0.99))}
    pair = nt.arma11_for_lag1_and_ratio(lags["lag1"], ratio, near_phi=lags["lag2"] / lags["lag1"])
    if pair is None:
        return None
    return dict(zip(("lag1", "lag2"), (float(v) for v in nt.arma11_lags(*pair))))


def _extended_axis(base_axis, cands, xc, fs, q):
    """The extended model's axis spec before its effects: white noise re-fitted on the
    series ``xc`` cleaned of the findings ``cands`` (corrected for the colored noise's
    high-pass loss), and the bias of the cleaned series less the mean of the deterministic
    components that were fitted mean-free. Without findings, the baseline's axis."""
    spec = dict(base_axis)
    spec["effects"] = []
    if not cands:
        return spec
    n = xc.size
    sigma = _noise_sigma(xc, fs, q or 0.0)
    for c in cands:  # narrow bands (above the high-pass) are noise of their own: N'^2 = N^2 - rms^2
        if c.effect == "narrowband":
            sigma = math.sqrt(max(sigma**2 - c.params["rms_dps"] ** 2, 0.05 * sigma**2))
    colored = next((c for c in cands if c.effect == "colored_noise"), None)
    if colored is not None:
        # the high-pass of _noise_sigma also removed the variance fraction c = L / W of a
        # correlated noise (L its long-run ratio; detectors.lags_from_highpassed)
        w = det.colored_window(n, fs)
        frac = min(det.long_run_ratio(colored.params["lag1"], colored.params.get("lag2")) / w, 0.9)
        sigma *= math.sqrt((1 - 1.0 / w) / (1 - frac))
    spec["arw_dps_per_sqrt_hz"] = float(sigma / math.sqrt(fs))
    spec["bias_dps"] = float(np.mean(xc))
    T = n / fs
    for c in cands:  # deterministic components were fitted mean-free
        if c.effect == "bias_step":
            spec["bias_dps"] -= c.params["size_dps"] * (1 - c.params["time_s"] / T)
        elif c.effect == "rate_ramp":
            spec["bias_dps"] -= c.params["r_dps_per_s"] * T / 2
        elif c.effect == "warmup":
            tau = c.params["tau_s"]
            spec["bias_dps"] -= c.params["amplitude_dps"] * tau / T * (1 - math.exp(-T / tau))
    return spec


def _detect_axis(x, fs, temp):
    """Run the detectors of one axis in the decision order; returns (candidates, cleaned x).
    Each finding's component is subtracted from a private copy of ``x`` and then dropped, so
    the axis costs two series of memory besides the detectors' own."""
    cands = []
    c, mask = det.detect_outliers(x)
    if c is not None:
        cands.append(c)
        x = det.clean_spikes(x, mask)  # a copy
    del mask
    owned = bool(cands)
    c = det.detect_sinusoid(x, fs)
    if c is not None:
        cands.append(c)
        x, owned = _subtract_component(x, c, owned), True
    band = det.detect_narrowband(x, fs)
    if band is not None:
        cands.append(band)
    c = det.detect_colored(x, fs, band)
    if c is not None:
        cands.append(c)
    slow, _ = det.detect_slow(x, fs, temp)
    cands.extend(slow)
    for s in slow:
        if s.component is not None:
            x, owned = _subtract_component(x, s, owned), True
    return cands, x


def _subtract_component(x, cand, owned):
    """``x`` less the candidate's component, in place when ``x`` is the axis's own copy
    (``owned``); the component is dropped (it is N samples)."""
    if owned:
        x -= cand.component
    else:
        x = x - cand.component
    cand.component = None
    return x


def _departure_summary(deps, meas, taus, bands):
    """Per-axis departures: z per feature, and the measured and simulated values (natural
    logs for the Allan deviation in deg/s and the band powers in (deg/s)^2 per bin)."""
    fl = lambda v: [float(u) for u in v]  # noqa: E731
    return {"adev_tau_s": fl(taus), "adev_z": fl(deps["adev"][0]),
            "adev_meas_log": fl(meas["adev"]),
            "adev_sim_mean_log": fl(deps["adev"][1]), "adev_sim_sd_log": fl(deps["adev"][2]),
            "band_edges_hz": fl(bands), "band_z": fl(deps["band"][0]),
            "band_meas_log": fl(meas["band"]),
            "band_sim_mean_log": fl(deps["band"][1]), "band_sim_sd_log": fl(deps["band"][2]),
            "line_z": float(deps["line"][0][0]), "lag1_z": float(deps["lag1"][0][0]),
            "spikes_z": float(deps["spikes"][0][0]), "discrepancy": discrepancy(deps)}


def _furthest(deps, taus, bands):
    """(feature key, z, index, description) of the feature furthest outside the simulations' spread."""
    best = None
    for key, (z, mean, sd) in deps.items():
        j = int(np.argmax(np.abs(z)))
        if best is None or abs(z[j]) > abs(best[1]):
            best = (key, float(z[j]), j)
    key, z, j = best
    where = {"adev": lambda: f"Allan deviation at tau = {taus[j]:.3g} s",
             "band": lambda: f"spectrum band {bands[j]:.3g}-{bands[j + 1]:.3g} Hz",
             "line": lambda: "largest spectral line",
             "lag1": lambda: "lag-1 autocorrelation",
             "spikes": lambda: "spike count"}[key]()
    return key, z, j, where


def _strongest(deps, taus, bands):
    """A sentence on where the measurement is furthest outside the simulations' spread ("" below
    :data:`~gyrofilter.analysis.detectors.REPORTED_DEPARTURE_Z` sd)."""
    _, z, _, where = _furthest(deps, taus, bands)
    if abs(z) < det.REPORTED_DEPARTURE_Z:
        return ""
    return f"largest departure in the {where}, z = {z:+.1f} sd of the simulated spread"


def _still_departs(axis, d_after, deps, taus, bands):
    """The note on an axis whose D after extension is above :data:`~gyrofilter.analysis.detectors.OUTSIDE_NULL_D`: the feature
    furthest outside the extended model's simulations, and what its sign says. For the Allan
    deviation and the band powers, fast (tau < 1 s or above 1 Hz: the white, colored and band
    noise) or slow scales (the bias terms); above the simulations, more power than the model
    holds there (an effect the table lacks or too weak to name), below, a fitted term too strong
    at that scale."""
    key, z, j, where = _furthest(deps, taus, bands)
    text = (f"axis {axis}: after extension D = {d_after:.3g}, above {det.OUTSIDE_NULL_D:g} (clean records of 27 s "
            f"to 2.8 h stay below it in 95 % of runs): the model does not close here. The {where} departs most "
            f"(z = {z:+.1f} sd of the extended model's simulations)")
    if key in ("adev", "band"):
        fast = taus[j] < 1.0 if key == "adev" else bands[j] >= 1.0
        scale = "fast scales: the white, colored or band noise" if fast else "slow scales: the bias terms"
        if z > 0:
            return text + f"; the measurement holds more power there than the model ({scale} miss a part)"
        return text + f"; the model puts too much power there ({scale} are too strong at that scale)"
    return text + {"line": "; a spectral line the model lacks", "lag1": "; the noise's short correlation differs",
                   "spikes": "; spikes the model lacks or overstates"}[key]
