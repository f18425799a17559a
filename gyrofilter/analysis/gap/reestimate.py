"""The gap's estimators re-run on a bootstrap replicate, given the findings they are to estimate
(:mod:`gyrofilter.analysis.gap.intervals`).

:func:`reestimate_axis` takes one simulated run ``x`` of an axis of the extended model and the
axis's kept findings, and returns each finding's parameters estimated on ``x`` by the same code
and in the same decision order as :func:`gyrofilter.analysis.gap.pipeline._detect_axis` (spikes cleaned,
the line subtracted, the band, the colored noise corrected for the band, the slow effects on the
block means of the cleaned series, the composite stochastic part on its wavelet variance). What
the detectors decided on the record is not decided again: the estimator of each finding is run
whether or not its statistic passes the threshold on the replicate, on the parametrisation the
finding has (a colored noise with or without ``lag2``, a random walk or a Gauss-Markov wander,
the composite fit's terms), so that the replicates' spread is that of the estimator the finding
came from. Only where an estimator has nothing to estimate (fewer than
:data:`~gyrofilter.analysis.gap.detectors.OUTLIER_MIN_COUNT` spikes) is the parameter None.

The estimators, as in :mod:`gyrofilter.analysis.gap.detectors`:

* ``ringing``: :func:`~gyrofilter.analysis.gap.detectors.ringing_estimate` (the hump's centre and
  Q, the rings' count and median peak), its rings taken out of the replicate;
* ``heavy_tails``: the Gaussian scale mixture's maximum-likelihood fraction and scale ratio on
  the histogram of the high-passed, prewhitened residual
  (:func:`~gyrofilter.analysis.gap.detectors.tails.tail_fits`), nothing cleaned;
* ``outliers``: :func:`~gyrofilter.analysis.gap.detectors.detect_outliers` (the median magnitude
  corrected for the spikes below the threshold; rate = count / (N P_detect));
* ``sinusoid``: the least-squares amplitude maximised over ``f`` within one periodogram bin of
  the bin nearest the finding's frequency (:func:`~gyrofilter.analysis.gap.detectors.sinusoid.line_frequency`:
  golden-section search, f_s / 2 itself at Nyquist), then amplitude and phase by
  least squares (:func:`~gyrofilter.analysis.gap.detectors.sinusoid_fit`); the detector's own search
  around the largest line, started where that line is;
* ``narrowband``: :func:`~gyrofilter.analysis.gap.detectors.band_estimate` (the strongest band);
* ``resonance``: :func:`~gyrofilter.analysis.gap.detectors.resonance_fit` (the hump's centre, Q
  and rms), the finding's narrow band's bins left out as the detector leaves them;
* ``wandering_tone``: :func:`~gyrofilter.analysis.gap.detectors.tone_estimate` on the strongest
  band (centre, spread, correlation time and amplitude of its frequency track and variance); the
  colored noise is corrected for its spectrum (:func:`~gyrofilter.analysis.gap.detectors.tone_band`);
* ``colored_noise``: the high-passed lag-1 and lag-2 autocorrelations less the band's
  (:func:`~gyrofilter.analysis.gap.detectors.lags_from_highpassed`);
* ``temperature``: the coefficient by generalised least squares under the residual's noise
  (:func:`~gyrofilter.analysis.gap.detectors.covariate.temperature_first`), the detector's estimator;
  where its significance test fails on a replicate, the least-squares coefficient of the block
  means (the same estimator's first step) stands in;
* deterministic slow shapes: the block-mean fit of the shape (the warm-up's tau scanned) and the
  full-rate least-squares refit (``detectors.slow.deterministic_shapes`` and
  ``deterministic_candidate``); the stochastic spectra on the block means less that shape:
  ``bias_instability`` and ``rate_random_walk`` by the Whittle likelihood
  (:func:`~gyrofilter.analysis.gap.detectors.stochastic_fits`), ``gauss_markov`` by the exact
  Kalman-filter likelihood on at most 512 block means
  (:func:`~gyrofilter.analysis.gap.detectors.exact_stochastic_gain`);
* ``compression``: the linearised re-estimator of :mod:`gyrofilter.analysis.gap.compression` on the
  replicate as simulated (its tail statistic against the fit's calibration; gamma at or below 0
  is none: the replicate's tails are not lighter), its rms by
  :func:`~gyrofilter.analysis.gap.compression.fast_rms`;
* the composite stochastic part: the GMWM fit with the finding's terms
  (:func:`gyrofilter.analysis.noise.gmwm.fit_model`) to the wavelet variance of the cleaned series,
  its Gauss-Markov terms matched by increasing tau.
"""
from __future__ import annotations

import math

import numpy as np

from ...effects import (BIAS_INSTABILITY, COLORED_NOISE, COMPRESSION, COVARIATES, GAUSS_MARKOV, HEAVY_TAILS, NARROWBAND,
                        OUTLIERS, RATE_RANDOM_WALK, RESONANCE, RINGING, SHAPES, SINUSOID, TEMPERATURE, WANDERING_TONE,
                        WANDERS)
from .. import stats
from . import detectors as det
from ..noise import gmwm
from .detectors.covariate import temperature_first
from .detectors.slow import deterministic_candidate, deterministic_shapes, stochastic_params
from .detectors.tails import tail_fits, tail_residual, tail_step
from .detectors.sinusoid import line_frequency
from .baseline import effect_entry, extended_axis, wander_highpassed
from .composite import COMPOSITE_TERMS, composite_lags, slow_wavelet_variance
from .compression import fast_rms

#: the slow deterministic shapes of :func:`gyrofilter.analysis.gap.detectors.detect_slow`
DETERMINISTIC = SHAPES + COVARIATES
#: the effects :func:`reestimate_axis` can estimate
SUPPORTED = ((RINGING, HEAVY_TAILS, OUTLIERS, SINUSOID, NARROWBAND, WANDERING_TONE, RESONANCE, COLORED_NOISE) + DETERMINISTIC
             + WANDERS + (COMPRESSION,))


def reestimate_axis(x, sample_rate_hz, temp_c, cands, resolved_lags=False, q_dps=0.0, owned=False, wanted=None):
    """Parameters of each finding of ``cands`` (the axis's kept
    :class:`~gyrofilter.analysis.gap.detectors.Candidate` s) estimated on the replicate ``x`` (deg/s);
    returns a list of dicts (or None where the estimator has nothing to estimate), in the order
    of ``cands``. ``temp_c`` is the record's temperature column (the regressor of a
    ``temperature`` finding) or None. ``resolved_lags``: the colored noise's lags were re-solved
    for a composite model (:func:`gyrofilter.analysis.gap.composite.composite_lags`), and are so
    on the replicate, from its extended white level (the quantization step ``q_dps``) and its
    composite fit's. ``owned``: ``x`` is the caller's to lose (a bootstrap replicate): the
    findings' components are taken out of it in place, else out of one copy. ``wanted``: the indices
    into ``cands`` whose estimates the caller reads (None: all); an estimator that neither they nor
    the series they are estimated on depend on (:func:`_needed`) is not run, its entry None (the
    intervals' test inversion reads one finding's; the others' estimators were half its time)."""
    x = x if owned else np.array(x, dtype=float)
    out = [None] * len(cands)
    by = {}
    for k, c in enumerate(cands):
        key = "composite" if c.composite and c.effect in WANDERS else c.effect
        by.setdefault(key, []).append(k)
    if wanted is not None:
        run = _needed({key for key, ks in by.items() if set(ks) & set(wanted)}, resolved_lags)
        by = {key: ks for key, ks in by.items() if key in run}
    if COMPRESSION in by:  # on the replicate as simulated, as the tail statistic of D reads it
        k = by[COMPRESSION][0]
        out[k] = _compression(x, sample_rate_hz, cands[k], q_dps)
    if RINGING in by and x.size >= 4096:
        found = det.ringing_estimate(x, sample_rate_hz)
        if found is not None:
            out[by[RINGING][0]] = found[0]
            x -= found[2]
    if HEAVY_TAILS in by:
        out[by[HEAVY_TAILS][0]] = _heavy_tails(x, sample_rate_hz)
    if OUTLIERS in by:
        cand, mask = det.detect_outliers(x, q_dps)
        out[by[OUTLIERS][0]] = None if cand is None else dict(cand.params)
        x = det.clean_spikes(x, mask, in_place=True)
    if SINUSOID in by:
        k = by[SINUSOID][0]
        params, fit = _sinusoid(x, sample_rate_hz, cands[k].params["frequency_hz"])
        out[k] = params
        x -= fit
    bands = []
    if NARROWBAND in by and x.size >= 4096:
        band = det.band_estimate(x, sample_rate_hz)
        out[by[NARROWBAND][0]] = {name: band[name] for name in ("center_hz", "bandwidth_hz", "rms_dps")}
        bands.append(det.Candidate(NARROWBAND, out[by[NARROWBAND][0]], 0.0, 0.0, ""))
    if WANDERING_TONE in by and x.size >= 4096:  # the band's reading as a tone, as the detector reads it
        band = det.band_estimate(x, sample_rate_hz)
        tone = det.tone_estimate(x, sample_rate_hz, band["center_hz"], band["bandwidth_hz"])
        out[by[WANDERING_TONE][0]] = {name: tone[name] for name in ("center_hz", "spread_hz", "wander_s", "amplitude_dps")}
        bands.append(det.Candidate(WANDERING_TONE, out[by[WANDERING_TONE][0]], 0.0, 0.0, ""))
    if RESONANCE in by and x.size >= 4096:
        lines = [(b.params["center_hz"], b.params["bandwidth_hz"], b.params["rms_dps"]) for b in bands
                 if b.effect == NARROWBAND and det.hump_or_line(b.params["center_hz"] / b.params["bandwidth_hz"]) == NARROWBAND]
        fit = det.resonance_fit(x, sample_rate_hz, lines)
        if fit is not None:
            out[by[RESONANCE][0]] = {name: fit[name] for name in ("center_hz", "q", "rms_dps")}
            bands.append(det.Candidate(RESONANCE, out[by[RESONANCE][0]], 0.0, 0.0, ""))
    if COLORED_NOISE in by:
        k = by[COLORED_NOISE][0]
        wander = next((c for c in cands if c.effect in WANDERS and not c.composite), None)
        out[k] = _colored(x, sample_rate_hz, "lag2" in cands[k].params, bands,
                          None if wander is None else wander_highpassed(effect_entry(wander), sample_rate_hz, x.size))
    slow_det = [k for name in DETERMINISTIC for k in by.get(name, [])]
    slow_sto = [k for name in WANDERS for k in by.get(name, [])]
    if slow_det or slow_sto:
        x = _slow(x, sample_rate_hz, temp_c, cands, slow_det, slow_sto, out)
    if "composite" in by:
        fit = _composite(x, sample_rate_hz, cands, by["composite"], out)
        k = by.get(COLORED_NOISE, [None])[0]
        if resolved_lags and k is not None and out[k] is not None and fit is not None:
            out[k] = _resolved(x, sample_rate_hz, cands, out, fit, q_dps)
    return out


def _needed(keys, resolved_lags):
    """The estimators (keys of :func:`reestimate_axis`'s ``by``: effects, or ``composite``) that the
    estimates of ``keys`` read, ``keys`` included: a resonance the narrow band's line, a colored
    noise the bands' spectra (and, ``resolved_lags``, the composite fit); every estimator the
    series less the ringing's rings, the spikes and the line, and the slow stochastic ones and the
    composite the block means less the slow shapes."""
    keys = set(keys)
    if COLORED_NOISE in keys:
        keys |= {NARROWBAND, WANDERING_TONE, RESONANCE} | ({"composite"} if resolved_lags else set())
    if RESONANCE in keys:
        keys.add(NARROWBAND)
    if keys & set(DETERMINISTIC + WANDERS + ("composite",)):
        keys |= set(DETERMINISTIC)
    return keys | {RINGING, OUTLIERS, SINUSOID}


def _resolved(xc, sample_rate_hz, cands, out, fit, q_dps):
    """The colored noise's lags re-solved as in a composite model: the extended axis's white
    level re-fitted on the cleaned replicate ``xc`` with the replicate's band and colored noise
    (:func:`gyrofilter.analysis.gap.baseline.extended_axis`), against the composite fit's."""
    reps = [det.Candidate(c.effect, params, 0.0, 0.0, "") for c, params in zip(cands, out)
            if params is not None and c.effect in (NARROWBAND, RESONANCE, COLORED_NOISE, WANDERING_TONE)]
    ext = extended_axis({"bias_dps": 0.0, "arw_dps_per_sqrt_hz": 0.0}, reps, xc, sample_rate_hz, q_dps)
    lags = next(c.params for c in reps if c.effect == COLORED_NOISE)
    return composite_lags(ext, {"arw_dps_per_sqrt_hz": fit.arw_dps_per_sqrt_hz}, lags)


def _compression(x, sample_rate_hz, cand, q_dps):
    """A compression's gamma and rms on the replicate ``x`` (module docstring)."""
    t_gamma, slope = cand.calibration
    gamma = cand.params["gamma_per_dps2"] + (det.tails_statistic(x, sample_rate_hz) - t_gamma) / slope
    return {"gamma_per_dps2": gamma if gamma > 0 else None, "rms_dps": fast_rms(x, sample_rate_hz, q_dps)}


def _heavy_tails(x, sample_rate_hz):
    """The mixture's fraction and scale ratio as :func:`~gyrofilter.analysis.gap.detectors.detect_heavy_tails`
    fits them, without its thresholds."""
    u = tail_residual(x, sample_rate_hz)
    if u.size < 256:
        return None
    fits = tail_fits(u, tail_step(x, sample_rate_hz), models=("mixture",))
    return {"fraction": fits["fraction"], "scale_ratio": fits["scale_ratio"]}


def _sinusoid(x, sample_rate_hz, f_hz):
    """The line near ``f_hz``: (params, fitted component)."""
    df = sample_rate_hz / det.periodogram_length(x.size)
    f = line_frequency(x, sample_rate_hz, max(round(f_hz / df), 1) * df)
    amplitude, phase, fit = det.sinusoid_fit(x, sample_rate_hz, f)
    return {"frequency_hz": f, "amplitude_dps": amplitude, "phase_rad": phase}, fit


def _colored(x, sample_rate_hz, with_lag2, bands, wander=None):
    """The colored noise's lags as :func:`~gyrofilter.analysis.gap.detectors.detect_colored` computes
    them, on the parametrisation of the finding (``with_lag2``), without its thresholds (less
    the correlation of the replicate's bands, ``bands``, and of the finding's wander, ``wander`` =
    its ``(v, r1, r2)``)."""
    n = x.size
    e, w = det.highpassed(x, sample_rate_hz)
    den = float(stats.dot(e, e))
    if not den > 0:
        return None
    r1, r2 = float(stats.dot(e[1:], e[:-1]) / den), float(stats.dot(e[2:], e[:-2]) / den)
    band_lags, band_share = det.other_correlation(den / n, *det.band_correlation(bands, sample_rate_hz), wander)
    lags = det.lags_from_highpassed(r1, r2 if with_lag2 else None, w, band_lags, band_share)
    if lags is None:
        return None
    return {"lag1": lags[0], "lag2": lags[1]} if with_lag2 else {"lag1": lags[0]}


def _slow(x, sample_rate_hz, temp_c, cands, slow_det, slow_sto, out):
    """The slow findings (indices ``slow_det``, ``slow_sto`` into ``cands``) on the block means of
    ``x``; fills ``out`` and returns ``x`` less the deterministic components."""
    y, length = stats.block_means(x)
    n = y.size
    if n < 16:
        return x
    delta_s = length / sample_rate_hz
    temp_blocks = None
    if temp_c is not None:
        tb, _ = stats.block_means(np.asarray(temp_c, dtype=float))
        if tb.size == n and np.ptp(tb) > 0:
            temp_blocks = tb
    series = y
    k_temp = next((k for k in slow_det if cands[k].effect == TEMPERATURE), None)
    covariate = temperature_first(x, sample_rate_hz, temp_c, {}) if k_temp is not None else None
    if covariate is not None:  # the detector's GLS coefficient; the shapes in time on what it leaves
        out[k_temp] = dict(covariate[0].params)
        x -= covariate[0].component
        series = series - stats.block_means(covariate[0].component)[0][:n]
        slow_det = [k for k in slow_det if k != k_temp]
        temp_blocks = None
    if slow_det:
        shapes = deterministic_shapes(series, delta_s, temp_blocks)
        for k in slow_det:
            name = cands[k].effect
            if name not in shapes:
                continue
            d, params, shape, _ = shapes[name]
            cand = deterministic_candidate(name, d, params, x, sample_rate_hz, length, temp_c)
            out[k] = dict(cand.params)
            x -= cand.component
            series = series - shape
    for k in slow_sto:
        name = cands[k].effect
        if name == GAUSS_MARKOV:
            group = max(1, int(math.ceil(n / 512)))
            m = n // group
            yg = series[: m * group].reshape(m, group).mean(axis=1)
            fits_g, _ = det.stochastic_fits(yg, delta_s * group, (name,))  # its fits alone: the others' are not read
            exact = det.exact_stochastic_gain(yg, fits_g, delta_s * group, (name,))
            out[k] = stochastic_params(name, exact[name][1], delta_s * group)
        else:
            fits, _ = det.stochastic_fits(series, delta_s, (name,))
            out[k] = stochastic_params(name, fits[name][1], delta_s)
    return x


def _composite(x, sample_rate_hz, cands, ks, out):
    """The composite stochastic part's terms (indices ``ks``): the GMWM fit with the same terms
    to the wavelet variance of the cleaned ``x``; returns the fit (None when too short)."""
    wv = slow_wavelet_variance(x, sample_rate_hz, cands)
    if wv is None:
        return None
    gm = sorted((k for k in ks if cands[k].effect == GAUSS_MARKOV), key=lambda k: cands[k].params["tau_s"])
    terms = {term: [k for k in ks if cands[k].effect == term] for term in COMPOSITE_TERMS}
    fit = gmwm.fit_model(wv, tuple(term for term, k in terms.items() if k), len(gm), starts=3, seed=0)
    for k, (sigma_dps, tau_s) in zip(gm, fit.gauss_markov):
        out[k] = {"sigma_dps": sigma_dps, "tau_s": tau_s}
    for k in terms[RATE_RANDOM_WALK]:
        out[k] = {"k_dps_per_sqrt_s": fit.rrw_dps_per_sqrt_s}
    for k in terms[BIAS_INSTABILITY]:
        out[k] = {"b_dps": fit.bias_instability_dps}
    return fit
