"""Model-gap analysis: what the baseline simulation gets wrong, the cause, and the gain.

``analyse_gap(rec)`` writes the gap report of docs/formats.md (section 3) in five steps, one
function each on a shared run (:class:`_GapRun`); the modules beside this one hold the parts:

1. **Baseline fit** per axis (the package's plain simulation: constant bias, white noise,
   quantization of the recorded unit; :func:`gyrofilter.analysis.gap_baseline.baseline_model`).
2. **Simulated spread**: the baseline is simulated ``n_sims`` times (seeded; common random
   numbers with the extended model; :func:`gyrofilter.analysis.gap_baseline.sim_features`),
   and the same features are computed on the measurement and on every run
   (:mod:`gyrofilter.analysis.gap_features`: the overlapping Allan deviation at log-spaced tau,
   band powers of the periodogram in log-spaced bands, the largest periodogram line over the
   local noise level, the lag-1 autocorrelation of the high-passed noise, the spike count and the tail
   statistic, a winsorized kurtosis).
   Each feature's departure is ``z = (f_meas - mean_sims) / max(sd_sims, floor)``.
3. **Causes**: :mod:`gyrofilter.analysis.detectors` maps departures to effects of the table, in a fixed
   decision order (outliers or heavy tails, sinusoid, narrow-band noise, colored noise, slow bias effects; see
   there for how ramp / random walk / warm-up / Gauss-Markov / bias instability / step /
   temperature are told apart), each with its own significance threshold, and estimates the
   parameters. A narrow band's variance is taken out of the white noise (N'^2 = N^2 - rms^2 / f_s)
   and its lag-1 and lag-2 correlations out of the colored noise's (:func:`detectors.lags_from_highpassed`).
   Where the temperature and a shape in time (or a slow wander) explain a slow departure, both
   readings are simulated and the measured covariate is kept unless the other is clearly better
   on D (:mod:`gyrofilter.analysis.gap_readings`); one as good is listed as ``alternatives``. A
   bias instability and a Gauss-Markov wander that both fit are weighed the same way (the bias
   instability, one parameter fewer, is named unless the Gauss-Markov is clearly better).
4. **Gain**: the discrepancy ``D = mean_k z_k^2`` over the features of the axis (lower is
   better; about 1 when the model explains the measurement) is computed against the baseline's
   runs (``before``) and against runs of the baseline extended by one finding (``after``); a
   finding is kept only if ``after < before`` (a real gain). The overall figure uses the model
   extended by every kept finding. Where an axis's D after is still above
   :data:`~gyrofilter.analysis.detectors.OUTSIDE_NULL_D`, a **composite stochastic part** is
   tried (:mod:`gyrofilter.analysis.gap_composite`: a GMWM-style fit of white noise, an optional
   rate random walk, an optional bias instability and 0-3 Gauss-Markov terms that replaces the axis's slow stochastic findings
   when it lowers D enough).
5. The report: a JSON-ready dict with ``baseline``, ``findings`` (effect, axis, params,
   evidence, gain), ``extended_model`` (runs in ``gyrofilter simulate``), per-axis feature
   departures and the discrepancies; where an axis's D after is still above
   :data:`~gyrofilter.analysis.detectors.OUTSIDE_NULL_D`, a note names the feature that departs
   most from the extended model and what its sign says
   (:func:`gyrofilter.analysis.gap_features.still_departs`); every parameter's 95 % interval
   (``params_ci95``), by parametric bootstrap of the extended model
   (:mod:`gyrofilter.analysis.gap_intervals`).
"""
from __future__ import annotations

import copy
import math
import time
import warnings

import numpy as np

from . import detectors as det
from .detectors import SLOW_EFFECTS
from .gap_baseline import (MIN_SIMS, WANDERS, axis_dps, baseline_model, default_n_sims, effect_entry, extended_axis, sim_features,
                           start_bias, temperature_table, wander_highpassed, white_less_wanders)
from .gap_composite import composite_step, slow_wavelet_variance
from .gap_readings import alternatives_entry, null_spread, weigh_readings, weigh_wanders
from .gap_features import (METRIC, departs_most, departure_summary, departures, discrepancy, feature_bands, feature_taus,
                           features, still_departs, strongest)
from .gap_intervals import add_intervals
from .still import not_static
from ..errors import GyroFilterError, RecordingError
from ..recording import GYRO_COLUMNS
from ..units import AXES, MIN_NOISE_DPS, check_sample_rate_hz, to_dps

#: minimum samples for any analysis
MIN_SAMPLES = 256


def gap_columns(names):
    """The columns of a file (with column ``names``) that the gap analysis uses: the gyro axes,
    and, where the file has ``temp``, ``temp`` and ``t`` (the temperature table's times). For
    ``read_recording(path, columns=gap_columns, compact=True)``: a day at 100 Hz in ``lsb`` is
    held in 3 float32 columns (104 MB) instead of 4-5 float64 ones (276-346 MB)."""
    return list(GYRO_COLUMNS) + ([c for c in ("t", "temp") if c in names] if "temp" in names else [])


def analyse_gap(rec, *, seed=0, n_sims=None, progress=None, recording_name=None, bootstrap=None):
    """Run the gap analysis on a :class:`~gyrofilter.recording.Recording`; returns the report
    dict of docs/formats.md section 3 (with ``discrepancy``, ``departures``,
    ``runtime_s``). ``progress(text)`` is called with short status lines. ``bootstrap``: runs
    per axis with findings for the parameters' intervals (:mod:`gyrofilter.analysis.gap_intervals`;
    0: none; None: :func:`~gyrofilter.analysis.gap_intervals.default_bootstrap` of the record's length)."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            return _analyse_gap(rec, seed=seed, n_sims=n_sims, progress=progress, recording_name=recording_name,
                                bootstrap=bootstrap)
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


def _analyse_gap(rec, *, seed, n_sims, progress, recording_name, bootstrap):
    """The five steps of the module docstring, one function each, on a shared :class:`_GapRun`."""
    t_start = time.perf_counter()
    run = _GapRun(rec, seed=seed, n_sims=n_sims, say=progress or (lambda text: None), recording_name=recording_name)
    if run.n >= MIN_SAMPLES:
        _baseline_spread(run)       # 2.
        _detect(run)                # 3.
        weigh_readings(run)         # 3., covariate or time reading of a confounded temperature
        weigh_wanders(run)          # 3., bias instability or Gauss-Markov
        _keep_findings(run)         # 4., gain per finding
        composite_step(run)         # 4., composite stochastic part where D stays high
        _write_findings(run)        # 5.
        add_intervals(run, bootstrap, seed)  # 5., the parameters' intervals
    run.report["runtime_s"] = time.perf_counter() - t_start
    return run.report


class _GapRun:
    """One gap analysis: the recording, the baseline fit (step 1, done here), the simulation
    seeds and features, the candidates and the per-axis departures of every model tried
    (computed once per set of findings: an axis's departures depend only on that axis's model,
    whose random streams are its own)."""

    def __init__(self, rec, *, seed, n_sims, say, recording_name):
        where = rec.path or "recording"
        sample_rate_hz = check_sample_rate_hz(rec.sample_rate_hz, f"{where}: sample_rate_hz", RecordingError)
        n = len(rec)
        if n < 2:
            raise RecordingError(f"{where}: {n} sample(s) after the header: a gap analysis needs data rows")
        self.rec, self.sample_rate_hz, self.n, self.say = rec, sample_rate_hz, n, say
        self.report = report = {
            "recording": recording_name if recording_name is not None else (rec.path or ""),
            "sample_rate_hz": sample_rate_hz, "duration_s": n / sample_rate_hz,
            "baseline": {"description": "constant bias + white noise (+ quantization of the recorded unit)",
                         "axes": {a: {} for a in AXES}},
            "findings": [], "extended_model": {}, "notes": []}
        if not all(np.isfinite(to_dps(rec.columns[c][lo:lo + (1 << 16)], rec.gyro_unit, rec.lsb_per_dps)).all()
                   for c in GYRO_COLUMNS for lo in range(0, n, 1 << 16)):  # in deg/s, a pass at a time
            raise RecordingError(f"{where}: gyro columns hold non-finite values")
        self.base = base = baseline_model(rec)
        report["baseline"]["model"] = base
        self.q = q = 1.0 / base["lsb_per_dps"] if base.get("lsb_per_dps") else None
        for a in AXES:
            report["baseline"]["axes"][a] = {"bias_dps": base["axes"][a]["bias_dps"],
                                             "arw_dps_per_sqrt_hz": base["axes"][a]["arw_dps_per_sqrt_hz"],
                                             "quantization_dps": q}
        report["extended_model"] = copy.deepcopy(base)
        if n < MIN_SAMPLES:
            report["notes"].append(f"only {n} samples (< {MIN_SAMPLES}): too short to tell anything beyond the baseline")
            return
        temp = rec.temp_c
        self.temp = None if temp is None else np.asarray(temp, dtype=float)
        if self.temp is not None and not np.all(np.isfinite(self.temp)):
            self.temp = None
            report["notes"].append("temp column has non-finite values: temperature not analysed")
        _static_notes(self)
        self.taus = feature_taus(n, sample_rate_hz)
        self.bands = feature_bands(n, sample_rate_hz)
        self.m = default_n_sims(n) if n_sims is None else int(n_sims)
        self.seeds = np.random.default_rng(seed).integers(0, 2**31, size=self.m)
        self.n_ext = max(6, self.m // 2)
        self.candidates = []  # (axis index, Candidate)
        self.ext_axes = {}  # axis name -> the extended axis spec before its effects
        self.composite_axes = {}  # axis name -> the same with the composite fit's white level
        self.wvs = [None, None, None]  # wavelet variance of each cleaned axis at the composite's scales
        self.kept = []  # (candidate index, axis index, Candidate, D of the axis with it alone)
        self.resolved_lags = [None, None, None]  # composite model: the colored noise's lags (gap_composite)
        self.readings = {}  # axis index -> the covariate and time readings of a confounded temperature (gap_readings)
        self.alt_axes = {}  # axis name -> the extended axis spec of the time reading
        self.excluded = set()  # candidate indices of the reading not chosen
        self._deps_cache = {}
        self._sims_cache = {}

    def axis_spec(self, i, ks):
        """Axis ``i``'s spec extended by the candidates ``ks`` (the composite's white level and
        ``preserve: arw`` when one of them belongs to a composite model)."""
        a = AXES[i]
        cands = [self.candidates[k][1] for k in ks]
        composite = any(c.extra.get("composite") for c in cands)
        time_reading = any(c.extra.get("reading") == "time" for c in cands)
        spec = dict(self.composite_axes[a] if composite else self.alt_axes[a] if time_reading else self.ext_axes[a])
        spec["bias_dps"] = start_bias(spec["bias_dps"], cands, self.n / self.sample_rate_hz)
        spec["effects"] = [effect_entry(c, preserve="arw" if composite else "std") for c in cands]
        if not composite:  # the white level was measured with the wanders' high-frequency part in it
            colored = next((c for ci, c in self.candidates if ci == i and c.effect == "colored_noise"), None)
            spec["arw_dps_per_sqrt_hz"] = white_less_wanders(spec["arw_dps_per_sqrt_hz"], spec["effects"], colored,
                                                             self.n, self.sample_rate_hz)
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
            model = copy.deepcopy(self.base)
            model["axes"][AXES[i]] = self.axis_spec(i, key[1])
            if any(self.candidates[k][1].effect == "temperature" for k in key[1]):
                model["temperature"] = temperature_table(self.rec)
            sims_k = sim_features(model, self.n, self.sample_rate_hz, self.seeds[:self.n_ext], [i], self.taus,
                                  self.bands, self.say, label)[i]
            self._deps_cache[key] = departures(self.meas_feats[i], sims_k, self.n, (self.deps[i], self.m))
            self._sims_cache[key] = sims_k
        return self._deps_cache[key]

    def null_spread(self, i, ks, label):
        """The null spread of D for axis ``i`` extended by the candidates ``ks``
        (:func:`gyrofilter.analysis.gap_readings.null_spread` of its simulated runs)."""
        self.axis_deps(i, ks, label)
        key = (i, tuple(sorted(ks)), tuple(sorted((self.resolved_lags[i] or {}).items())))
        return null_spread(self._sims_cache[key], self.n, (self.deps[i], self.m))

    def axis_discrepancy(self, i, ks, label):
        return discrepancy(self.axis_deps(i, ks, label))

    def kept_on(self, i):
        return [k for k, ci, _, _ in self.kept if ci == i]


def _static_notes(run):
    """A note per axis whose block means move more than a still gyro's would."""
    for i, a in enumerate(AXES):
        white_std_dps = run.base["axes"][a]["arw_dps_per_sqrt_hz"] * math.sqrt(run.sample_rate_hz)
        moved = not_static(axis_dps(run.rec, i), run.sample_rate_hz, white_std_dps)
        if moved:
            run.report["notes"].append(f"axis {a}: {moved}; the analysis models a still gyro, so its findings describe the motion")


def _baseline_spread(run):
    """Step 2: features of the measurement and of ``m`` baseline runs; departures and D before."""
    n, sample_rate_hz = run.n, run.sample_rate_hz
    run.say(f"baseline: {run.m} simulations of {n / sample_rate_hz:.0f} s at {sample_rate_hz:g} Hz")
    run.meas_feats = []
    for i in range(3):
        x = axis_dps(run.rec, i)  # the features may overwrite it unless it is the record's own column
        run.meas_feats.append(features(x, sample_rate_hz, run.taus, run.bands,
                                       overwrite=not np.shares_memory(x, run.rec.columns[GYRO_COLUMNS[i]])))
        del x
    sims = sim_features(run.base, n, sample_rate_hz, run.seeds, range(3), run.taus, run.bands, run.say,
                        "baseline simulations (runs x axes)")
    run.deps = [departures(run.meas_feats[i], sims[i], n) for i in range(3)]
    del sims
    run.before = [discrepancy(d) for d in run.deps]
    run.report["departures"] = {a: departure_summary(run.deps[i], run.meas_feats[i], run.taus, run.bands)
                                for i, a in enumerate(AXES)}


def _detect(run):
    """Step 3: the detectors per axis, in the decision order; the extended model's white noise
    and bias re-fitted on the series cleaned of the axis's findings, and that series' wavelet
    variance kept for the composite step."""
    for i, a in enumerate(AXES):
        run.say(f"detectors on {a}")
        x = axis_dps(run.rec, i)
        idle = ("constant signal" if not np.ptp(x) > 0 else
                f"noise below {MIN_NOISE_DPS:g} deg/s (too small for the detectors in float64)"
                if not np.std(x) >= MIN_NOISE_DPS else None)
        if idle:
            run.report["notes"].append(f"axis {a}: {idle}, nothing to analyse")
            run.ext_axes[a] = dict(run.base["axes"][a], effects=[])
            continue
        owned = not np.shares_memory(x, run.rec.columns[GYRO_COLUMNS[i]])  # a converted copy, not the column
        try:
            cands, xc, alt = _detect_axis(x, run.sample_rate_hz, run.temp, tails_z=float(run.deps[i]["tails"][0][0]),
                                          notes=run.report["notes"], axis=a, owned=owned)
        except (ValueError, FloatingPointError, np.linalg.LinAlgError) as exc:  # never crash
            run.report["notes"].append(f"axis {a}: detectors could not run ({exc})")
            cands, xc, alt = [], axis_dps(run.rec, i), None  # x may have been cleaned in place
        first = len(run.candidates)
        for c in cands:
            if c.effect == "temperature":
                c.extra["reference_c"] = float(np.mean(run.temp))
            run.candidates.append((i, c))
        if alt is not None:  # the time reading of a confounded temperature (gap_readings)
            alt_cands, xa = alt
            fast = [c for c in cands if c.effect not in SLOW_EFFECTS]
            run.readings[i] = {"covariate": [first + j for j, c in enumerate(cands) if c.effect in SLOW_EFFECTS],
                               "time": alt_cands,
                               "ext_axis": extended_axis(run.base["axes"][a], fast + alt_cands, xa, run.sample_rate_hz, run.q),
                               "wv": slow_wavelet_variance(xa, run.sample_rate_hz, fast)}
            del xa
        run.ext_axes[a] = extended_axis(run.base["axes"][a], cands, xc, run.sample_rate_hz, run.q)
        run.wvs[i] = slow_wavelet_variance(xc, run.sample_rate_hz, cands)
        del x, xc


def _detect_axis(x, sample_rate_hz, temp, tails_z=None, notes=None, axis="", owned=False):
    """Run the detectors of one axis in the decision order; returns (candidates, cleaned x,
    alternative): ``alternative`` is None or, where the slow effects have a covariate and a time
    reading (:func:`gyrofilter.analysis.detectors.detect_slow`), ``(time reading's candidates,
    x cleaned of those instead)``. Each finding's component is subtracted from a private copy of
    ``x`` (``x`` itself when ``owned``: the caller's to change) and then dropped, so the axis
    costs one series of memory besides the detectors' own (two without ``owned``, three with an
    alternative reading). ``tails_z``: the tail statistic's departure from the baseline
    simulations; ``notes``: where a note on tails that spikes explain as well goes."""
    cands = []
    c, mask = det.detect_outliers(x)
    tails, note = det.detect_heavy_tails(x, sample_rate_hz, spikes_found=c is not None, tails_z=tails_z)
    if note and notes is not None:
        notes.append(f"axis {axis}: {note}" + ("; they are analysed as outliers" if c is not None else ""))
    if tails is not None:  # the spikes are the noise's tails: nothing is cleaned
        cands.append(tails)
        c = None
    if c is not None:
        cands.append(c)
        x = det.clean_spikes(x, mask, in_place=owned)  # a copy unless owned
        owned = True
    del mask
    c = det.detect_sinusoid(x, sample_rate_hz)
    if c is not None:
        cands.append(c)
        x, owned = _subtract_component(x, c, owned), True
    band = det.detect_narrowband(x, sample_rate_hz)
    if band is not None:
        cands.append(band)
    colored = det.detect_colored(x, sample_rate_hz, band)
    slow, _ = det.detect_slow(x, sample_rate_hz, temp)
    wander = next((s for s in slow if s.effect in WANDERS), None)
    if colored is not None and wander is not None:  # the wander's high-frequency part is correlated too
        colored = det.detect_colored(x, sample_rate_hz, band,
                                     wander_highpassed(effect_entry(wander), sample_rate_hz, x.size))
        if colored is None and notes is not None:
            notes.append(f"axis {axis}: the lag-1 correlation is the {wander.effect}'s own (its high-frequency part); "
                         "no colored noise")
    if colored is not None:
        cands.append(colored)
    cands.extend(slow)
    alt = slow[0].extra.pop("alternative", None) if slow else None
    if alt is not None:
        xa = x.copy()
        for s in alt:
            if s.component is not None:
                xa = _subtract_component(xa, s, True)
        alt = (alt, xa)
    for s in slow:
        if s.component is not None:
            x, owned = _subtract_component(x, s, owned), True
    return cands, x, alt


def _subtract_component(x, cand, owned):
    """``x`` less the candidate's component, in place when ``x`` is the axis's own copy
    (``owned``); the component is dropped (it is N samples)."""
    if owned:
        x -= cand.component
    else:
        x = x - cand.component
    cand.component = None
    return x


def _keep_findings(run):
    """Step 4: gain per finding, the axis extended by this finding alone (the contract's gain);
    a finding that shows no gain alone is still kept when the axis has other candidates and
    leaving it out of the model with all of them raises the discrepancy (leave-one-out). Then D
    of each axis extended by all its kept findings."""
    cands, before, notes = run.candidates, run.before, run.report["notes"]
    run.single = single = {}
    for k, (i, c) in enumerate(cands):
        if k in run.excluded:
            continue
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
            why = "" if with_all < without else None
            if why is None and c.effect == "temperature" and np.isfinite(with_all):
                # the measured covariate is kept where D cannot tell (gap_readings)
                spread = det.CONFOUNDED_SPREADS * max(run.null_spread(i, others + [k], label), run.null_spread(i, others, label))
                if with_all <= without + spread:
                    why = (f", within the null spread of D ({spread:.2g}): the measured covariate is kept where D "
                           "cannot tell")
            if why is not None:
                run.kept.append((k, i, c, after))
                notes.append(f"{c.effect} on {AXES[i]}: no gain alone ({before[i]:.3g} -> {after:.3g}) but kept: with the "
                             f"axis's other findings D = {with_all:.3g}, without it {without:.3g}{why}")
                continue
        notes.append(f"{c.effect} on {AXES[i]} dropped: no gain (discrepancy {before[i]:.3g} -> {after:.3g})")
    run.after = list(before)
    if run.kept:
        run.say("overall gain of the extended model")
        for i in sorted({i for _, i, _, _ in run.kept}):
            run.after[i] = run.axis_discrepancy(i, run.kept_on(i), f"extended model on {AXES[i]}")


def _write_findings(run):
    """Step 5: the extended model, the findings with evidence and gain, the extended model's
    spread in the departure summaries, and the discrepancies."""
    report, kept, before = run.report, run.kept, run.before
    ext = copy.deepcopy(run.base)
    for i, a in enumerate(AXES):
        ks = run.kept_on(i)
        if ks:
            ext["axes"][a] = run.axis_spec(i, ks)
    if any(c.effect == "temperature" for _, _, c, _ in kept):
        ext["temperature"] = temperature_table(run.rec)
    report["extended_model"] = ext
    for _, i, c, after in kept:
        z_info = strongest(run.deps[i], run.taus, run.bands)
        report["findings"].append({
            "effect": c.effect, "axis": AXES[i],
            "params": {k: float(v) for k, v in c.params.items()},
            "evidence": c.evidence + (f"; baseline simulations: {z_info}" if z_info else ""),
            "gain": {"metric": "discrepancy D (" + METRIC + ")", "before": before[i], "after": after},
            "statistic": {"name": c.statistic_name, "value": float(c.statistic), "threshold": float(c.threshold)},
        })
        if c.extra.get("alternatives"):
            report["findings"][-1]["alternatives"] = alternatives_entry(c)
    if run.m < MIN_SIMS:  # the spread of a feature from so few runs is too uncertain to judge D by
        report["notes"].append(f"D from {run.m} simulations is not judged (pure white noise reads D up to 14-98 from "
                               f"2-3 of them): give {MIN_SIMS} or more")
    for i in range(3):
        if run.after[i] > det.OUTSIDE_NULL_D and run.m >= MIN_SIMS:
            deps_e = run.axis_deps(i, run.kept_on(i), f"extended model on {AXES[i]}") if run.kept_on(i) else run.deps[i]
            report["notes"].append(still_departs(AXES[i], run.after[i], deps_e, run.taus, run.bands))
            if AXES[i] in report.get("departures", {}):
                report["departures"][AXES[i]]["departs_most"] = departs_most(deps_e, run.taus, run.bands)
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
    n, sample_rate_hz = run.n, run.sample_rate_hz
    if n / sample_rate_hz < 300:
        report["notes"].append(f"record of {n / sample_rate_hz:.0f} s: slow bias effects (drift, random walk, bias instability) "
                               "cannot be told apart from white noise beyond tau ~ {:.0f} s".format(n / sample_rate_hz / 9))
