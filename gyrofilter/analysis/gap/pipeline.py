"""Model-gap analysis: what the baseline simulation gets wrong, the cause, and the gain.

``analyse_gap(rec)`` writes the gap report of docs/formats.md (section 3) in five steps, one
function each: :func:`prepare` and :func:`baseline_spread` make the
:class:`~gyrofilter.analysis.gap.state.GapInput` every step reads, the later steps each take a
:class:`~gyrofilter.analysis.gap.state.GapState` and return a new one, scoring the models they
weigh through one :class:`~gyrofilter.analysis.gap.scoring.Scorer`; the modules beside this one
hold the parts:

1. **Baseline fit** per axis (the package's plain simulation: constant bias, white noise,
   quantization of the recorded unit; :func:`gyrofilter.analysis.gap.baseline.baseline_model`).
2. **Simulated spread**: the baseline is simulated ``n_sims`` times (seeded; the commands use
   :data:`COMMAND_SEED` whatever their ``--seed``; common random
   numbers with the extended model; :func:`gyrofilter.analysis.gap.baseline.sim_features`),
   and the same features are computed on the measurement and on every run
   (:mod:`gyrofilter.analysis.gap.features`: the overlapping Allan deviation at log-spaced tau,
   band powers of the periodogram in log-spaced bands, the largest periodogram line over the
   local noise level, the lag-1 autocorrelation of the high-passed noise, the spike count and the tail
   statistic, a winsorized kurtosis).
   Each feature's departure is ``z = (f_meas - mean_sims) / max(sd_sims, floor)``.
3. **Causes**: :mod:`gyrofilter.analysis.gap.detectors` maps departures to effects of the table, in a fixed
   decision order (outliers or heavy tails, or shocks that ring; sinusoid, narrow-band noise or a wandering tone,
   a resonance's hump, colored noise, slow bias effects; see
   there for how ramp / random walk / warm-up / Gauss-Markov / bias instability / step /
   temperature are told apart), each with its own significance threshold, and estimates the
   parameters. A narrow band's or a hump's variance is taken out of the white noise (N'^2 = N^2 - rms^2 / f_s)
   and its lag-1 and lag-2 correlations out of the colored noise's (:func:`detectors.lags_from_highpassed`).
   Where the temperature and a shape in time (or a slow wander) explain a slow departure, both
   readings are simulated and the measured covariate is kept unless the other is clearly better
   on D (:mod:`gyrofilter.analysis.gap.confound`); one as good is listed as ``alternatives``. A
   bias instability and a Gauss-Markov wander that both fit are weighed the same way (the bias
   instability, one parameter fewer, is named unless the Gauss-Markov is clearly better), and so are
   a sinusoid and a narrow band at the same frequency, one spectral line named once.
4. **Gain**: the discrepancy ``D = mean_k z_k^2`` over the features of the axis (lower is
   better; about 1 when the model explains the measurement) is computed against the baseline's
   runs (``before``) and against runs of the baseline extended by one finding (``after``); a
   finding is kept only if ``after < before`` (a real gain). The overall figure uses the model
   extended by every kept finding. Where an axis's D after is still above
   :data:`~gyrofilter.analysis.gap.detectors.OUTSIDE_NULL_D` and its lag-1 departs most, a colored
   noise below the detector's threshold is weighed (:mod:`gyrofilter.analysis.gap.late_colored`);
   where D is still above it, a **composite stochastic part** is
   tried (:mod:`gyrofilter.analysis.gap.composite`: a GMWM-style fit of white noise, an optional
   rate random walk, an optional bias instability and 0-3 Gauss-Markov terms that replaces the axis's slow stochastic findings
   when it lowers D enough); then, where D is still above it and the axis's tails are lighter than its
   extended model's, a **compression** of its fast terms (:mod:`gyrofilter.analysis.gap.compression`),
   kept by the composite's rule.
5. The report: a JSON-ready dict with ``baseline``, ``findings`` (effect, axis, params,
   evidence, gain), ``extended_model`` (runs in ``gyrofilter simulate``), per-axis feature
   departures and the discrepancies; where an axis's D after is still above
   :data:`~gyrofilter.analysis.gap.detectors.OUTSIDE_NULL_D`, a note names the feature that departs
   most from the extended model and what its sign says
   (:func:`gyrofilter.analysis.gap.features.still_departs`); every parameter's 95 % interval
   (``params_ci95``), by parametric bootstrap of the extended model
   (:mod:`gyrofilter.analysis.gap.intervals`), computed before the findings are written: a
   finding whose defining parameter the record does not determine is listed in ``uncertain``
   instead, out of the extended model and of D after (:func:`~gyrofilter.analysis.gap.keep.set_aside_uncertain`). Last, rows
   repeated beyond chance (counted in step 2, every axis at once) are weighed on the mean D over
   the axes and, kept, join the extended model as its top-level ``repeated_samples``
   (:mod:`gyrofilter.analysis.gap.rows`).
"""
from __future__ import annotations

import copy
import math
import time
import warnings
from dataclasses import replace

import numpy as np

from ...effects import SLOW, TEMPERATURE, WANDERS
from ...errors import GyroFilterError, RecordingError, SettingsError
from ...inputs import check_number
from ...recording import GYRO_COLUMNS, filtered_words, read_recording, warn_about_gaps
from ...sim.model import TEMPERATURE_PROFILE
from ...sim.simulate import check_seed
from ...tempscreen import screened_temp
from ...units import AXES, MAX_RATE_DPS, MIN_NOISE_DPS, TEMP_RANGE_C, check_sample_rate_hz, one_value, to_dps
from ..still import moved, not_static, refuse_moved
from . import detectors as det
from .advice import compensation_hint, mount_hint
from .baseline import (MAX_SIMS, MIN_SIMS, axis_dps, baseline_model, default_n_sims, effect_entry, extended_axis,
                       sim_features, temperature_table, wander_highpassed)
from .composite import composite_step, slow_wavelet_variance
from .compression import compression_step
from .confound import (alternatives_entry, one_cause_of_spikes, ring_or_hump, suggested_temperature, weigh_lines,
                       weigh_readings, weigh_tones, weigh_wanders)
from .features import (METRIC, departs_most, departure_summary, departures, discrepancy, feature_bands,
                       feature_taus, features, still_departs, strongest)
from .intervals import MAX_BOOTSTRAP, MIN_REPLICATES, bootstrap_intervals
from .rows import rows_findings, weigh_repeats
from .scoring import Scorer
from .keep import keep_findings, set_aside_uncertain
from .late_colored import late_colored_step
from .state import AxisModels, GapInput, GapState, OtherReading

#: minimum samples for any analysis
MIN_SAMPLES = 256
_BASELINE_DESCRIPTION = "constant bias + white noise (+ quantization of the recorded unit)"


def gap_columns(names):
    """The columns of a file (with column ``names``) that the gap analysis uses: the gyro axes,
    and, where the file has ``temp``, ``temp`` and ``t`` (the temperature table's times). For
    ``read_recording(path, columns=gap_columns, compact=True)``: a day at 100 Hz in ``lsb`` is
    held in 3 float32 columns (104 MB) instead of 4-5 float64 ones (276-346 MB)."""
    return list(GYRO_COLUMNS) + ([c for c in ("t", "temp") if c in names] if "temp" in names else [])


#: the seed of every simulation of the commands (``gap``, ``report``, the fleet): fixed, so that no
#: named cause, interval or D moves with a seed (common random numbers across runs; their
#: ``--seed`` is kept for older scripts and has no effect). How the answers hold on other streams
#: is measured by ``tools/gap_stability.py`` (docs/gap.md, "How stable the answers are")
COMMAND_SEED = 0


def analyse_file(path, *, n_sims=None, bootstrap=None, warn, progress=None, refuse_motion=False):
    """The gap analysis of the recording file ``path``, the one way every command reads and
    analyses a file (``gap``, ``report``, the fleet): returns ``(the Recording, the gap report)``
    (:func:`analyse_gap` with :data:`COMMAND_SEED`, ``n_sims``, ``bootstrap``). The analysis models a still
    gyro: an axis that looks moved (:func:`gyrofilter.analysis.still.moved`, as ``allan`` judges
    it) raises NotStillError with ``refuse_motion``, else is the first warning. The reader's
    warnings and the gaps in ``t`` go to ``warn(text)``, the steps to ``progress(text)``. Only the
    columns the analysis uses are kept, integer (``lsb``) readings as float32, which holds them
    exactly (:func:`gap_columns`). The filter's output (``filtered_from``) is analysed, as ``allan``
    analyses it, with a first note saying that the findings describe it, not the sensor; the warning
    of gaps in ``t`` is a note too (after that one), as ``allan --json`` keeps it."""
    say = progress or (lambda text: None)
    rec = read_recording(path, columns=gap_columns, compact=True)
    motion = [(a, why) for i, a in enumerate(AXES) if (why := moved(axis_dps(rec, i), rec.sample_rate_hz))]
    if motion and refuse_motion:  # one short line: the warning of --allow-motion says the rest
        refuse_moved(path, motion[0][0], axis_dps(rec, AXES.index(motion[0][0])), rec.sample_rate_hz)
    for a, why in motion:
        warn(f"{path}: axis {a}: {why}; the gap analysis models a still gyro, so its findings describe the motion")
    for text in rec.warnings:
        warn(text)
    gaps = []  # said now, and kept as the report's first note (its findings are read later)
    warn_about_gaps(rec, "the gap analysis models uniform samples: its findings across the gaps are not meaningful",
                    gaps.append)
    for text in gaps:
        warn(text)
    say(f"read {len(rec)} samples at {rec.sample_rate_hz:g} Hz")
    report = analyse_gap(rec, seed=COMMAND_SEED, n_sims=n_sims, progress=progress, recording_name=path, bootstrap=bootstrap)
    report["notes"][:0] = gaps
    filtered = filtered_words(rec.header)
    if filtered:  # analysed, as allan analyses it, but said where the findings are read
        report["notes"].insert(0, f"the recording is {filtered}: the gap analysis models a sensor's samples, so its "
                                  "findings describe the filter's output")
    return rec, report


def analyse_gap(rec, *, seed=0, n_sims=None, progress=None, recording_name=None, bootstrap=None):
    """Run the gap analysis on a :class:`~gyrofilter.recording.Recording`; returns the report
    dict of docs/formats.md section 3 (with ``discrepancy``, ``departures``,
    ``runtime_s``). ``progress(text)`` is called with short status lines. ``seed``: the streams
    of every simulation (the decisions' and the intervals'). ``bootstrap``: runs
    per axis with findings for the parameters' intervals (:mod:`gyrofilter.analysis.gap.intervals`;
    0: none; None: :func:`~gyrofilter.analysis.gap.intervals.default_bootstrap` of the record's length).
    A ``seed``, ``n_sims`` or ``bootstrap`` it cannot take is refused (:func:`check_run_settings`)."""
    check_run_settings(seed, n_sims, bootstrap)
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
                    "baseline": {"description": _BASELINE_DESCRIPTION,
                                 "axes": {a: dict(base.get("axes", {}).get(a, {})) for a in AXES}, "model": base},
                    "findings": [], "uncertain": [], "extended_model": base,
                    "notes": [f"the analysis could not run ({type(exc).__name__}: {exc}); no findings reported"]}


def check_run_settings(seed, n_sims, bootstrap):
    """Refuse (SettingsError naming the keyword) a ``seed`` that is not
    :func:`~gyrofilter.sim.simulate.check_seed`'s, an ``n_sims`` that is not None or a whole number
    in [2, :data:`~gyrofilter.analysis.gap.baseline.MAX_SIMS`] (a spread needs 2 runs; below
    :data:`~gyrofilter.analysis.gap.baseline.MIN_SIMS` a note says D is not judged), a ``bootstrap``
    that is not None, 0 or a whole number in [:data:`~gyrofilter.analysis.gap.intervals.MIN_REPLICATES`,
    :data:`~gyrofilter.analysis.gap.intervals.MAX_BOOTSTRAP`]: an API call took ``n_sims=0`` (a
    TypeError deep in the spread), ``2.5`` (2 runs), ``10**9`` (a run without end) and ``seed=-1``
    (a report that "could not run")."""
    check_seed(seed, "seed")
    if n_sims is not None:
        check_number(n_sims, "n_sims (baseline simulations)", low=2, high=MAX_SIMS, integer=True)
    if bootstrap is not None:
        runs = check_number(bootstrap, "bootstrap (runs per axis)", low=0, high=MAX_BOOTSTRAP, integer=True)
        if 0 < runs < MIN_REPLICATES:
            raise SettingsError(f"bootstrap must be 0 (no intervals) or in [{MIN_REPLICATES}, {MAX_BOOTSTRAP}] (an "
                                f"interval needs {MIN_REPLICATES} runs), got {bootstrap}")


def _analyse_gap(rec, *, seed, n_sims, progress, recording_name, bootstrap):
    """The five steps of the module docstring, in order."""
    t_start = time.perf_counter()
    say = progress or (lambda text: None)
    report, setup = prepare(rec, seed=seed, n_sims=n_sims, recording_name=recording_name)
    if setup is not None:
        inp = baseline_spread(setup, say)                               # 2.
        report["departures"] = {a: departure_summary(inp.deps[i], inp.meas_feats[i], inp.taus, inp.bands)
                                for i, a in enumerate(AXES)}
        scorer = Scorer(inp)
        state = detect(inp, report["notes"])                            # 3.
        state = weigh_readings(inp, state, scorer)                      # 3., covariate or time reading of a temperature
        state = weigh_wanders(inp, state, scorer)                       # 3., bias instability or Gauss-Markov
        state = weigh_lines(inp, state, scorer)                         # 3., one line: sinusoid or narrow band
        state = weigh_tones(inp, state, scorer)                         # 3., one line: a tone or a narrow band
        state = keep_findings(inp, state, scorer)                       # 4., gain per finding
        state = late_colored_step(inp, state, scorer)                   # 4., a weak colored noise where the lag-1 departs most
        state = composite_step(inp, state, scorer)                      # 4., composite stochastic part where D stays high
        state = compression_step(inp, state, scorer)                    # 4., a compression where the tails stay lighter
        found = bootstrap_intervals(inp, state, bootstrap, seed)        # 5., the parameters' intervals
        state = set_aside_uncertain(inp, state, scorer, found)          # 5., a finding the record does not determine
        state = weigh_repeats(inp, state, scorer)                       # 5., repeated rows: the whole record
        report["notes"] = list(state.notes)  # after the repeats' weighing: its notes were lost
        write_findings(inp, state, scorer, report, found)               # 5.
    report["runtime_s"] = time.perf_counter() - t_start
    return report


def prepare(rec, *, seed, n_sims, recording_name):
    """Step 1: the checks, the baseline fit and the report's head. Returns ``(report, setup)``:
    ``setup`` is the dict of :class:`~gyrofilter.analysis.gap.state.GapInput`'s fields known
    before the simulations, or None for a record too short to analyse."""
    where = rec.path or "recording"
    sample_rate_hz = check_sample_rate_hz(rec.sample_rate_hz, f"{where}: sample_rate_hz", RecordingError)
    n = len(rec)
    if n < 2:
        raise RecordingError(f"{where}: {n} sample(s) after the header: a gap analysis needs data rows")
    report = {
        "recording": recording_name if recording_name is not None else (rec.path or ""),
        "sample_rate_hz": sample_rate_hz, "duration_s": n / sample_rate_hz,
        "baseline": {"description": _BASELINE_DESCRIPTION, "axes": {a: {} for a in AXES}},
        "findings": [], "uncertain": [], "extended_model": {}, "notes": []}
    for c in GYRO_COLUMNS:  # in deg/s, a pass at a time: finite and within the simulator's range
        for lo in range(0, n, 1 << 16):
            v = to_dps(rec.columns[c][lo:lo + (1 << 16)], rec.gyro_unit, rec.lsb_per_dps)
            bad = ~(np.abs(v) <= MAX_RATE_DPS)
            if bad.any():
                k = int(np.flatnonzero(bad)[0])
                raise RecordingError(f"{where}: {c} sample {lo + k + 1}: {float(v[k]):g} deg/s is not a rate the gap "
                                     f"analysis can model (finite, within +-{MAX_RATE_DPS:g})")
    base = baseline_model(rec)
    report["baseline"]["model"] = base
    q = 1.0 / base["lsb_per_dps"] if base.get("lsb_per_dps") else None
    if q is not None and rec.gyro_unit != "lsb":
        report["notes"].append(f"values on a {q:.3g} deg/s grid: quantization step taken from them")
    for a in AXES:
        report["baseline"]["axes"][a] = {k: base["axes"][a][k] for k in ("bias_dps", "arw_dps_per_sqrt_hz")}
        report["baseline"]["axes"][a]["quantization_dps"] = q
    report["extended_model"] = copy.deepcopy(base)
    if n < MIN_SAMPLES:
        report["notes"].append(f"only {n} samples (< {MIN_SAMPLES}): too short to tell anything beyond the baseline")
        return report, None
    temp = rec.temp_c
    temp = None if temp is None else np.asarray(temp, dtype=float)
    if temp is not None and not np.all((temp >= TEMP_RANGE_C[0]) & (temp <= TEMP_RANGE_C[1])):
        # a value no die reaches (replay refuses it): the covariate's fit would be that one value's
        row = int(np.flatnonzero(~((temp >= TEMP_RANGE_C[0]) & (temp <= TEMP_RANGE_C[1])))[0])
        report["notes"].append(f"temp column has values outside [{TEMP_RANGE_C[0]:g}, {TEMP_RANGE_C[1]:g}] deg C "
                               f"(sample {row + 1}: {temp[row]:g}): temperature not analysed")
        temp = None
    if temp is not None:  # read glitches (a die's temperature is smooth) replaced, or the column left out
        temp, note = screened_temp(temp, sample_rate_hz)
        report["notes"] += [note] if note else []
    report["notes"] += _static_notes(rec, base, sample_rate_hz)
    m = default_n_sims(n) if n_sims is None else int(n_sims)
    return report, {"rec": rec, "sample_rate_hz": sample_rate_hz, "n": n, "temp": temp, "base": base, "q": q,
                    "taus": feature_taus(n, sample_rate_hz), "bands": feature_bands(n, sample_rate_hz), "n_sims": m,
                    "seeds": np.random.default_rng(seed).integers(0, 2**31, size=m), "n_ext": max(6, m // 2)}


def _static_notes(rec, base, sample_rate_hz):
    """A note per axis whose block means move more than a still gyro's would."""
    notes = []
    for i, a in enumerate(AXES):
        white_std_dps = base["axes"][a]["arw_dps_per_sqrt_hz"] * math.sqrt(sample_rate_hz)
        moved = not_static(axis_dps(rec, i), sample_rate_hz, white_std_dps)
        if moved:
            notes.append(f"axis {a}: {moved}; the analysis models a still gyro, so its findings describe the motion")
    return notes


def baseline_spread(setup, say):
    """Step 2: features of the measurement and of ``n_sims`` baseline runs; departures and D
    before. Returns the :class:`~gyrofilter.analysis.gap.state.GapInput`."""
    rec, n, sample_rate_hz, taus, bands = setup["rec"], setup["n"], setup["sample_rate_hz"], setup["taus"], setup["bands"]
    say(f"baseline: {setup['n_sims']} simulations of {n / sample_rate_hz:.0f} s at {sample_rate_hz:g} Hz")
    meas_feats, idle = [], {}
    for i in range(3):
        x = axis_dps(rec, i)  # the features may overwrite it unless it is the record's own column
        why = nothing_to_analyse(x)
        if why:
            idle[AXES[i]] = why
        meas_feats.append(features(x, sample_rate_hz, taus, bands,
                                   overwrite=not np.shares_memory(x, rec.columns[GYRO_COLUMNS[i]])))
        del x
    sims = sim_features(setup["base"], n, sample_rate_hz, setup["seeds"], range(3), taus, bands, say,
                        "baseline simulations (runs x axes)")
    deps = [departures(meas_feats[i], sims[i], n) for i in range(3)]
    return GapInput(**setup, meas_feats=meas_feats, deps=deps, before=[discrepancy(d) for d in deps], base_sims=sims,
                    repeats=det.detect_repeats((axis_dps(rec, i) for i in range(3)), setup["q"]), idle=idle, say=say)


def nothing_to_analyse(x_dps):
    """Why the axis samples ``x_dps`` have nothing for the detectors (a constant signal, a square
    wave at the Nyquist frequency: samples alternating between two values, c + a (-1)^n, whose
    spectrum is one line at f_s / 2 and whose averages over any even number of samples are all
    equal, so the detectors' spectra and wavelet variances are 0 and their logs undefined; or a
    standard deviation below :data:`~gyrofilter.units.MIN_NOISE_DPS`), or None."""
    if one_value(x_dps.min(), x_dps.max()):
        return "constant signal"
    if x_dps.size >= 4 and not np.ptp(x_dps[0::2]) > 0 and not np.ptp(x_dps[1::2]) > 0:
        return (f"a square wave at the Nyquist frequency, the samples alternating between {float(x_dps[0]):.6g} and "
                f"{float(x_dps[1]):.6g} deg/s: no noise")
    if not np.std(x_dps) >= MIN_NOISE_DPS:
        return f"noise below {MIN_NOISE_DPS:g} deg/s (too small for the detectors in float64)"
    return None


def detect(inp, notes):
    """Step 3: the detectors per axis, in the decision order; the extended model's white noise
    and bias re-fitted on the series cleaned of the axis's findings, and that series' wavelet
    variance kept for the composite step. ``notes``: the notes so far (the state's first)."""
    notes = list(notes)
    candidates, axes, readings, uncertain = [], [], {}, []
    repeated_fraction = inp.repeats[1].params["fraction"] if inp.repeats[1] is not None else 0.0
    for i, a in enumerate(AXES):
        inp.say(f"detectors on {a}")
        if a in inp.idle:
            notes.append(f"axis {a}: {inp.idle[a]}, nothing to analyse")
            axes.append(AxisModels(ext=dict(inp.base["axes"][a], effects=[])))
            continue
        x = axis_dps(inp.rec, i)
        owned = not np.shares_memory(x, inp.rec.columns[GYRO_COLUMNS[i]])  # a converted copy, not the column
        try:
            cands, xc, alt, slow_stats, reserve = _detect_axis(
                x, inp.sample_rate_hz, inp.temp, tails_z=float(inp.deps[i]["tails"][0][0]), notes=notes, axis=a,
                owned=owned, q_dps=inp.q or 0.0, repeated_fraction=repeated_fraction)
        except (ValueError, FloatingPointError, np.linalg.LinAlgError) as exc:  # never crash
            notes.append(f"axis {a}: detectors could not run ({exc})")
            cands, xc, alt, slow_stats, reserve = [], axis_dps(inp.rec, i), None, {}, None  # x may have been cleaned in place
        suggested = suggested_temperature(slow_stats, a)
        if suggested is not None:
            uncertain.append(suggested)
        cands = _with_reference(cands, inp.temp)
        first = len(candidates)
        candidates += [(i, c) for c in cands]
        if alt is not None:  # the other reading of a confounded temperature (gap.confound)
            alt_cands, xa = alt
            alt_cands = _with_reference(alt_cands, inp.temp)
            fast = [c for c in cands if c.effect not in SLOW]
            readings[i] = OtherReading(first=[first + j for j, c in enumerate(cands) if c.effect in SLOW],
                                       other=alt_cands,
                                       ext_axis=extended_axis(inp.base["axes"][a], fast + alt_cands, xa,
                                                              inp.sample_rate_hz, inp.q),
                                       wv=slow_wavelet_variance(xa, inp.sample_rate_hz, fast))
            del xa
        axes.append(AxisModels(ext=extended_axis(inp.base["axes"][a], cands, xc, inp.sample_rate_hz, inp.q),
                               wv=slow_wavelet_variance(xc, inp.sample_rate_hz, cands), reserve=reserve))
        del x, xc
    return GapState(candidates=tuple(candidates), axes=tuple(axes), readings=readings, after=tuple(inp.before),
                    notes=tuple(notes), uncertain=tuple(uncertain))


def _with_reference(cands, temp):
    """The candidates, a temperature's with the record's mean temperature as its reference."""
    return [replace(c, reference_c=float(np.mean(temp))) if c.effect == TEMPERATURE else c for c in cands]


def _detect_axis(x, sample_rate_hz, temp, tails_z=None, notes=None, axis="", owned=False, q_dps=0.0, repeated_fraction=0.0):
    """Run the detectors of one axis in the decision order; returns (candidates, cleaned x,
    alternative, the slow detector's statistics, reserve): ``reserve`` is a colored noise below
    :data:`~gyrofilter.analysis.gap.detectors.COLORED_Z` but at
    :data:`~gyrofilter.analysis.gap.detectors.COLORED_LATE_Z` or more (not beside a wandering tone,
    whose readings carry their own), for the late step (:mod:`gyrofilter.analysis.gap.late_colored`),
    or None; ``alternative`` is None or, where the slow
    effects have a covariate and a time reading (:func:`gyrofilter.analysis.gap.detectors.detect_slow`),
    ``(the other reading's candidates, x cleaned of those instead)``. Each finding's component is subtracted from a private copy of
    ``x`` (``x`` itself when ``owned``: the caller's to change) and then dropped, so the axis costs
    one series besides the detectors' own (two without ``owned``, three with an alternative
    reading; the colored noise is sought before the slow shapes, which hold one each). ``tails_z``:
    the tail statistic's departure from the baseline simulations; ``notes``: where a note on tails
    that spikes explain as well goes; ``repeated_fraction``: the record's rows repeated beyond chance."""
    cands = []
    c, mask = det.detect_outliers(x, q_dps)
    tails, note = det.detect_heavy_tails(x, sample_rate_hz, spikes_found=c is not None, tails_z=tails_z)
    ring = det.detect_ringing(x, sample_rate_hz) if c is not None or tails is not None else None
    c, tails, note = one_cause_of_spikes(ring, c, tails, note)
    if ring is not None:  # the shocks ring: their rings are taken out, not the spikes cleaned
        cands.append(ring)
        x, owned = _subtract_component(x, ring, owned), True
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
    line = det.detect_sinusoid(x, sample_rate_hz)
    if line is not None:
        cands.append(line)
        x, owned = _subtract_component(x, line, owned), True
    hump, band = det.detect_resonance(x, sample_rate_hz, det.detect_narrowband(x, sample_rate_hz))
    hump = ring_or_hump(ring, hump)
    measured = [c for c in (band, hump) if c is not None]  # the bands as measured: the band reading's correction
    tone = None
    if band is not None:  # the band, or the tone that wanders in it (with the sinusoid it holds)
        tone, folded = det.detect_wandering_tone(x, sample_rate_hz, band, line)
        if tone is not None:
            tone = det.excursion_note(tone, x, sample_rate_hz)
            cands = [k for k in cands if not (folded and k is line)]
            rms = math.hypot(band.params["rms_dps"], line.params["amplitude_dps"] / math.sqrt(2.0)) if folded else None
            band = band if rms is None else replace(band, params=dict(band.params, rms_dps=rms))  # the sinusoid's power too
    cands.extend(c for c in (tone or band, hump) if c is not None)
    readings = [measured] + ([[replace(band, params=det.tone_band(tone.params))] + measured[1:]] if tone else [])
    plain = [det.detect_colored(x, sample_rate_hz, b, repeated_fraction=repeated_fraction) for b in readings]
    slow, slow_stats = det.detect_slow(x, sample_rate_hz, temp)
    wander = next((s for s in slow if s.effect in WANDERS), None)

    def colored_beside(found, bands, say, z_min=det.COLORED_Z):  # and beside the wander's own correlation (its high-frequency part)
        if found is not None and wander is not None:
            found = det.detect_colored(x, sample_rate_hz, bands, wander_highpassed(effect_entry(wander), sample_rate_hz, x.size),
                                       repeated_fraction, z_min=z_min)
            if found is None and say and notes is not None:
                notes.append(f"axis {axis}: the lag-1 correlation is the {wander.effect}'s own (its high-frequency "
                             "part); no colored noise")
        return found

    colored = colored_beside(plain[0], measured, tone is None)
    if tone is not None:  # each reading of the line with the colored noise left beside it: weighed on D (gap.confound)
        band_reading = [band] + ([colored] if colored is not None else [])
        colored = colored_beside(plain[1], readings[1], True)
        cands = [replace(c, band_alternative=band_reading) if c is tone else c for c in cands]
    if colored is not None:
        cands.append(colored)
    reserve = None if colored is not None or tone is not None else colored_beside(
        det.detect_colored(x, sample_rate_hz, measured, repeated_fraction=repeated_fraction, z_min=det.COLORED_LATE_Z),
        measured, False, det.COLORED_LATE_Z)
    cands.extend(slow)
    alt = slow[0].other_reading if slow else None
    if alt is not None:
        slow[0].other_reading = None  # the detectors' own candidate: the reading is returned apart
        xa = x.copy()
        for s in alt:
            if s.component is not None:
                xa = _subtract_component(xa, s, True)
        alt = (alt, xa)
    for s in slow:
        if s.component is not None:
            x, owned = _subtract_component(x, s, owned), True
    return cands, x, alt, slow_stats, reserve


def _subtract_component(x, cand, owned):
    """``x`` less the candidate's component, in place when ``x`` is the axis's own copy
    (``owned``); the component is dropped (it is N samples)."""
    if owned:
        x -= cand.component
    else:
        x = x - cand.component
    cand.component = None
    return x


def write_findings(inp, state, scorer, report, found):
    """Step 5: the extended model, the findings with evidence, gain and intervals (``found``: the
    :class:`~gyrofilter.analysis.gap.intervals.Intervals`), the uncertain ones, the extended
    model's spread in the departure summaries, the discrepancies, and the intervals' block and
    notes, into ``report``."""
    kept, before, after = state.kept, inp.before, state.after
    ext = copy.deepcopy(inp.base)
    for i, a in enumerate(AXES):
        ks = state.kept_on(i)
        if ks:
            ext["axes"][a] = state.spec(inp, i, ks)
    if any(row.cand.effect == TEMPERATURE for row in kept):
        ext[TEMPERATURE_PROFILE] = temperature_table(inp.rec, inp.temp)
    if state.rows is not None:
        ext.update(state.rows.entry)
    report["extended_model"] = ext
    for row in kept:
        i, c = row.axis, row.cand
        z_info = strongest(inp.deps[i], inp.taus, inp.bands, AXES[i])
        report["findings"].append({
            "effect": c.effect, "axis": AXES[i],
            "params": c.plain_params(),
            "evidence": c.evidence_text(*([z_info] if z_info else [])),
            "gain": {"metric": "discrepancy D (" + METRIC + ")", "before": before[i], "after": row.after},
            "statistic": {"name": c.statistic_name, "value": float(c.statistic), "threshold": float(c.threshold)},
            "alternatives": alternatives_entry(c, {r.cand.effect for r in kept if r.axis == i}),
        })
        if found.block["bootstrap_runs"] > 0:
            report["findings"][-1]["params_ci95"] = found.findings.get(row.k, dict.fromkeys(c.params))
    report["findings"] += rows_findings(state)
    report["uncertain"] = [dict(entry) for entry in state.uncertain]
    report["notes"] += compensation_hint(report["findings"]) + mount_hint(report["findings"])

    def extended_deps(i):
        return scorer.departures(i, state.extended(inp, i), f"extended model on {AXES[i]}")

    if inp.n_sims < MIN_SIMS:  # the spread of a feature from so few runs is too uncertain to judge D by
        report["notes"].append(f"D from {inp.n_sims} simulations is not judged (pure white noise reads D up to 14-98 from "
                               f"2-3 of them): give {MIN_SIMS} or more")
    for i in range(3):
        if after[i] > det.OUTSIDE_NULL_D and inp.n_sims >= MIN_SIMS and AXES[i] not in inp.idle:
            deps_e = extended_deps(i) if state.extended(inp, i) else inp.deps[i]
            report["notes"].append(still_departs(AXES[i], after[i], deps_e, inp.taus, inp.bands))
            if AXES[i] in report.get("departures", {}):
                report["departures"][AXES[i]]["departs_most"] = departs_most(deps_e, inp.taus, inp.bands)
    for i in [i for i in range(3) if state.extended(inp, i) and AXES[i] not in inp.idle]:
        deps_e = extended_deps(i)
        summ = report["departures"][AXES[i]]
        summ["extended_adev_sim_mean_log"] = [float(v) for v in deps_e["adev"][1]]
        summ["extended_adev_sim_sd_log"] = [float(v) for v in deps_e["adev"][2]]
        summ["extended_band_sim_mean_log"] = [float(v) for v in deps_e["band"][1]]
        summ["extended_band_sim_sd_log"] = [float(v) for v in deps_e["band"][2]]
        summ["extended_discrepancy"] = after[i]
    analysed = [i for i, a in enumerate(AXES) if a not in inp.idle]  # an idle axis's D ~ 0 says nothing
    report["discrepancy"] = {"metric": METRIC,
                             "definition": "D = mean over features of z^2, z = (measured - mean of simulations) / max(sd of simulations, floor)",
                             "before": {a: before[i] for i, a in enumerate(AXES)},
                             "after": {a: after[i] for i, a in enumerate(AXES)},
                             "overall_before": _mean_or_none([before[i] for i in analysed]),
                             "overall_after": _mean_or_none([after[i] for i in analysed]),
                             "not_analysed": dict(inp.idle),
                             "before_se": {a: scorer.discrepancy_error(i, None, "") for i, a in enumerate(AXES)},
                             "after_se": {a: scorer.discrepancy_error(i, state.extended(inp, i), f"extended model on {a}")
                                          for i, a in enumerate(AXES)}}
    report["n_simulations"] = inp.n_sims
    report["intervals"] = found.block
    for a, ci in found.baseline.items():
        if ci is not None:
            report["baseline"]["axes"][a]["params_ci95"] = ci
    n, sample_rate_hz = inp.n, inp.sample_rate_hz
    if n / sample_rate_hz < 300:
        length_s, tau_s = n / sample_rate_hz, n / sample_rate_hz / 9
        report["notes"].append(f"record of {length_s:.0f} s: slow bias effects (drift, random walk, bias instability) "
                               f"cannot be told apart from white noise beyond tau ~ {tau_s:.0f} s" if tau_s >= 1 else
                               f"record of {length_s:.2g} s: too short to tell slow bias effects (drift, random walk, "
                               f"bias instability) from white noise at any tau (beyond {tau_s:.1g} s)")
    report["notes"] += found.notes


def _mean_or_none(values):
    """The mean of ``values`` (the D of the axes analysed), None when there is none."""
    return float(np.mean(values)) if values else None
