"""Detector 2c, ``wandering_tone``: a band that is a tone of constant amplitude whose frequency
wanders, not Gaussian noise (see :mod:`gyrofilter.analysis.gap.detectors`; issue 36)."""

from __future__ import annotations

import math

import numpy as np

from ....effects import WANDERING_TONE
from ....units import check_sample_rate_hz
from .common import TONE_BLOCKS, TONE_KURTOSIS_Z, TONE_MIN_FRACTION, TONE_MIN_SPREAD_BINS, Candidate
from .narrowband import welch_psd

#: the length (s) of the short-time spectra that track the tone's frequency: the power of 2 of
#: samples nearest this many seconds (1024 at 100 Hz: 0.1-Hz bins, a frame every 5 s), fewer
#: where the record holds less than 16 of them
TONE_WINDOW_S = 10.0
#: the band around the line that is analysed: its half-width is this many times the line's
#: half-power full width (a Gaussian line of standard deviation σ has a full width of 2.35 σ,
#: so ±1.5 widths hold ±3.5 σ), at least :data:`TONE_MIN_HALF_BINS` bins of the short-time spectrum
TONE_HALF_WIDTHS = 1.5
TONE_MIN_HALF_BINS = 4
#: where the frequency track's standard deviation times :data:`TONE_TRACK_SDS` exceeds the band's
#: half-width (the line's half-power width underestimates a wandering tone's on a short record,
#: or catches the frequency it dwelt at longest), the band is widened to that, around the track's
#: mean, at most :data:`TONE_WIDENINGS` times
TONE_TRACK_SDS = 3.5
TONE_WIDENINGS = 3
#: the track is the running median over this many frames of the frames' peaks: a frame whose peak
#: is a noise bin (a weak tone, or one that moved across bins within the frame) is not followed
TONE_MEDIAN_FRAMES = 3
#: fixed-point steps of the correction of the track's variance and autocorrelation for the
#: record's length (:func:`_wander`)
TONE_LENGTH_ITERATIONS = 5
#: frames of the short-time spectrum transformed at once (bounded memory)
TONE_BATCH_FRAMES = 256


def tone_window(n, sample_rate_hz):
    """Samples L of the short-time spectra (:data:`TONE_WINDOW_S`): a power of 2, at most n / 16."""
    want = 2 ** int(round(math.log2(max(TONE_WINDOW_S * sample_rate_hz, 16.0))))
    return int(max(16, min(want, 2 ** int(math.log2(max(n // 16, 16))))))


def tone_estimate(x_dps, sample_rate_hz, center_hz, bandwidth_hz):
    """The band around a line of centre ``center_hz`` and half-power width ``bandwidth_hz`` (a
    ``narrowband`` candidate's) read as a tone whose frequency wanders.

    The band [f_c - h, f_c + h], h = max(:data:`TONE_HALF_WIDTHS` B, :data:`TONE_MIN_HALF_BINS`
    f_s / L) (widened to :data:`TONE_TRACK_SDS` standard deviations of the frequency track below
    where that is wider), is cut out of the series by a brick-wall filter (its DFT, the other bins zeroed):
    y. Its variance v = mean y², the white noise's share of it v_n = S_n · 2h (S_n the median of
    the Welch PSD, segments of L, over the flanks h to 2h beyond either edge), the line's share
    s = 1 - v_n / v, and y's excess kurtosis κ = mean y⁴ / v² - 3. Cumulants of independent
    parts add, so a line of share s in Gaussian noise has κ = s² κ_line: 0 for a Gaussian band,
    -3/2 s² for a tone of constant amplitude (the arcsine law of a sine, whose excess kurtosis is
    -3/2, whatever its frequency does). ``fraction`` = κ / (-3/2 s²): 0 for a Gaussian band, 1
    for a tone of constant amplitude. Its standard error: the spread of κ over
    :data:`TONE_BLOCKS` blocks of y, sd / sqrt(blocks).

    The frequency track: per frame of L samples (Hann, 50 % overlap) the peak of |Y|² within
    the band, refined by a parabola through the log powers of the peak bin and its neighbours,
    and its running median over :data:`TONE_MEDIAN_FRAMES` frames. The centre is the track's mean; the spread σ_f its variance less its estimation noise,
    sqrt(sd(f)² - sd(Δf)² / 2) (sd: 1.4826 MAD, robust to the frames where a noise bin beats the
    tone; the frame-to-frame differences of a track that wanders slowly are its estimation noise); the wander's correlation time T the lag at
    which the track's autocovariance over σ_f² falls to 1/e (interpolated on the log), else
    -m Δt / ln ρ(m) at the largest lag m = frames / 4 (Δt = L / 2 / f_s); σ_f and T corrected
    for the mean the record's length takes out (:func:`_wander`). The amplitude is
    A = sqrt(2 (v - v_n)). Returns a dict of these (``center_hz``, ``spread_hz``, ``wander_s``,
    ``amplitude_dps``, ``track_hz`` (the track's 5th and 95th percentiles), ``kurtosis``,
    ``kurtosis_se``, ``share``, ``fraction``, ``resolution_hz`` = f_s / L, ``low_hz``, ``high_hz``)."""
    from scipy.ndimage import median_filter

    x = np.asarray(x_dps, dtype=float)
    n = x.size
    nyquist = sample_rate_hz / 2.0
    seg = tone_window(n, sample_rate_hz)
    res = sample_rate_hz / seg
    half = max(TONE_HALF_WIDTHS * bandwidth_hz, TONE_MIN_HALF_BINS * res)
    center_hz = min(max(center_hz, res), nyquist - res)  # a replicate's band past an edge: the band at it
    xc = x - np.mean(x)
    for _ in range(TONE_WIDENINGS + 1):  # a band narrower than the track's excursions is widened
        lo, hi = max(center_hz - half, res), min(center_hz + half, nyquist - res)
        track = median_filter(peak_track(xc, sample_rate_hz, seg, lo, hi), size=TONE_MEDIAN_FRAMES, mode="nearest")
        wide = TONE_TRACK_SDS * _robust_sd(track)
        if not wide > 1.05 * half:
            break
        center_hz, half = min(max(float(np.mean(track)), res), nyquist - res), wide
    spec = np.fft.rfft(xc)
    del xc
    f = np.fft.rfftfreq(n, 1.0 / sample_rate_hz)
    spec[(f < lo) | (f > hi)] = 0.0
    y = np.fft.irfft(spec, n)
    del spec
    fw, psd, _ = welch_psd(x, sample_rate_hz, seg)
    flank = ((fw >= lo - half) & (fw < lo) & (fw > 0)) | ((fw > hi) & (fw <= hi + half) & (fw < nyquist))
    level = float(np.median(psd[flank])) if flank.any() else 0.0
    y2, y4 = y * y, y ** 4  # once: the record's moments and its blocks' are means of their slices
    del y
    v = float(np.mean(y2))
    share = min(max(1.0 - level * (hi - lo) / v, 0.0), 1.0) if v > 0 else 0.0
    kurt = float(np.mean(y4) / v ** 2 - 3.0) if v > 0 else 0.0
    per = np.array([np.mean(b4) / np.mean(b2) ** 2 - 3.0
                    for b4, b2 in zip(np.array_split(y4, TONE_BLOCKS), np.array_split(y2, TONE_BLOCKS))])
    se = float(np.std(per, ddof=1) / math.sqrt(len(per)))
    dev = track - track.mean()
    wander_s, spread2 = _wander(dev, max(_robust_sd(track) ** 2 - 0.5 * _robust_sd(np.diff(track)) ** 2, 0.0),
                                seg / 2.0 / sample_rate_hz)
    return {"center_hz": float(track.mean()), "spread_hz": math.sqrt(spread2), "wander_s": wander_s,
            "track_hz": (float(np.percentile(track, 5)), float(np.percentile(track, 95))),
            "amplitude_dps": math.sqrt(2.0 * max(v - level * (hi - lo), 0.0)),
            "kurtosis": kurt, "kurtosis_se": se, "share": share,
            "fraction": kurt / (-1.5 * share ** 2) if share > 0 else 0.0,
            "resolution_hz": res, "low_hz": lo, "high_hz": hi}


def _robust_sd(v):
    """1.4826 times the median absolute deviation of ``v`` (0 for no values): the standard
    deviation of a Gaussian, unmoved by the few frames where a noise bin beats the tone."""
    return 1.4826 * float(np.median(np.abs(v - np.median(v)))) if v.size else 0.0


def peak_track(y, sample_rate_hz, seg, lo, hi):
    """The peak frequency (Hz) of |Y|² within [lo, hi] per frame of ``seg`` samples of ``y``
    (mean removed; Hann, hop ``seg // 2``), parabola-refined on the log powers (:func:`tone_estimate`)."""
    step = seg // 2
    frames = (y.size - seg) // step + 1
    win = np.hanning(seg + 1)[:-1]
    f = np.fft.rfftfreq(seg, 1.0 / sample_rate_hz)
    inside = np.flatnonzero((f >= lo) & (f <= hi))
    if inside.size == 0:  # a band narrower than a bin, or pushed to an edge: its nearest bin within the edges
        inside = np.array([min(max(int(round(0.5 * (lo + hi) / f[1])), 1), f.size - 2)])
    first, last = int(inside[0]), int(inside[-1])
    out = np.empty(frames)
    for start in range(0, frames, TONE_BATCH_FRAMES):
        count = min(TONE_BATCH_FRAMES, frames - start)
        piece = y[start * step:start * step + (count - 1) * step + seg]
        segs = np.lib.stride_tricks.as_strided(piece, shape=(count, seg), strides=(step * piece.strides[0], piece.strides[0]))
        power = np.abs(np.fft.rfft(segs * win, axis=1)) ** 2
        logp = np.log(np.maximum(power[:, first - 1:last + 2], 1e-300))
        k = np.argmax(logp[:, 1:-1], axis=1) + 1
        rows = np.arange(count)
        a, b, c = logp[rows, k - 1], logp[rows, k], logp[rows, k + 1]
        den = a - 2.0 * b + c
        shift = np.where(den < 0, 0.5 * (a - c) / np.where(den < 0, den, -1.0), 0.0)
        out[start:start + count] = f[first - 1 + k] + np.clip(shift, -0.5, 0.5) * (f[1] - f[0])
    return out


def _wander(dev, spread2, hop_s):
    """``(T, σ_f²)``: the correlation time (s) of the track ``dev`` (mean removed) whose variance
    without the estimation noise is ``spread2``, and that variance, both corrected for the
    record's length (:func:`tone_estimate`). Removing the mean of F frames of a process of
    correlation time T removes its variance over the record, σ² b with b = 2 T / (F Δt), from
    the variance and from every autocovariance alike: σ² = s² / (1 - b), ρ(k) = ĉ(k) / σ² + b;
    solved by :data:`TONE_LENGTH_ITERATIONS` fixed-point steps from b = 0 (b at most 1/2)."""
    m = max(dev.size // 4, 1)
    if not spread2 > 0 or dev.size < 8:
        return hop_s, spread2
    padded = np.fft.rfft(dev, 2 * dev.size)
    acov = np.fft.irfft(padded * np.conj(padded))[:m + 1] / dev.size
    b, tau_s, var = 0.0, hop_s, spread2
    for _ in range(TONE_LENGTH_ITERATIONS):
        var = spread2 / (1.0 - b)
        tau_s = _one_over_e(acov / var + b, m, hop_s)
        b = min(2.0 * tau_s / (dev.size * hop_s), 0.5)
    return tau_s, var


def _one_over_e(rho, m, hop_s):
    """The lag (s) at which the autocorrelation ``rho`` (lags 0..m, frames of ``hop_s``) falls to
    1/e, interpolated on its log; else -m Δt / ln ρ(m)."""
    below = np.flatnonzero(rho[1:] < math.exp(-1.0))
    if below.size:
        k = int(below[0]) + 1
        r0, r1 = max(min(rho[k - 1], 1.0), 1e-12), max(rho[k], 1e-12)
        lag = (k - 1) + (math.log(r0) + 1.0) / max(math.log(r0) - math.log(r1), 1e-12)
        return float(max(lag, 0.5) * hop_s)
    return float(-m * hop_s / math.log(min(max(rho[m], 1e-3), 0.999)))


def tone_band(params):
    """The ``narrowband`` parameters of the same spectrum as the wandering tone of ``params``,
    for the corrections made for a band (the colored noise's lags, :func:`narrowband_lags`):
    ``center_hz`` f_c, ``rms_dps`` A / sqrt(2) (the tone's variance, well determined, where
    the band estimate of a tone that dwelt at a few frequencies is not), and ``bandwidth_hz``
    the half-power full width 2 sqrt(2 ln 2) σ_f of its Gaussian line (slow wander), at least
    a millihertz."""
    return {"center_hz": params["center_hz"], "rms_dps": params["amplitude_dps"] / math.sqrt(2.0),
            "bandwidth_hz": max(2.0 * math.sqrt(2.0 * math.log(2.0)) * params["spread_hz"], 1e-3)}


def detect_wandering_tone(x, sample_rate_hz, band, sinusoid=None):
    """The ``wandering_tone`` reading of the ``narrowband`` candidate ``band`` (:func:`tone_estimate`
    on its centre and width): returns ``(candidate or None, whether the sinusoid is part of it)``.

    A tone, where the band's excess kurtosis is below 0 by more than :data:`TONE_KURTOSIS_Z`
    standard errors, at least :data:`TONE_MIN_FRACTION` of a constant-amplitude tone's (its
    ``fraction``), and its frequency track spreads by at least :data:`TONE_MIN_SPREAD_BINS`
    bins (less keeps one frequency: a line the sinusoid detector names, and the band stays the
    band). A ``sinusoid`` candidate (already subtracted from ``x``) within the band is the tone
    dwelling at one frequency: one line, one finding (:mod:`gyrofilter.analysis.gap.confound`),
    the tone's amplitude with its power, A² = A_tone² + A_sin²."""
    check_sample_rate_hz(sample_rate_hz)
    params = band.params
    est = tone_estimate(x, sample_rate_hz, params["center_hz"], params["bandwidth_hz"])
    z = -est["kurtosis"] / est["kurtosis_se"] if est["kurtosis_se"] > 0 else 0.0
    if not (z > TONE_KURTOSIS_Z and est["fraction"] >= TONE_MIN_FRACTION
            and est["spread_hz"] >= TONE_MIN_SPREAD_BINS * est["resolution_hz"]):
        return None, False
    amplitude = est["amplitude_dps"]
    folded = sinusoid is not None and est["low_hz"] <= sinusoid.params["frequency_hz"] <= est["high_hz"]
    if folded:
        amplitude = math.hypot(amplitude, sinusoid.params["amplitude_dps"])
    evidence = (f"the band at {params['center_hz']:.4g} Hz ({est['low_hz']:.3g}-{est['high_hz']:.3g} Hz) is a tone of "
                f"nearly constant amplitude {amplitude:.3g} deg/s whose frequency wanders: its excess kurtosis "
                f"{est['kurtosis']:+.2f} (+- {est['kurtosis_se']:.2g}; a Gaussian band gives 0, a constant-amplitude "
                f"tone -1.5 s^2 = {-1.5 * est['share'] ** 2:+.2f} at its share s = {est['share']:.2f} of the band's "
                f"variance: {est['fraction']:.2f} of a tone's), its peak in short-time spectra of "
                f"{est['resolution_hz']:.2g}-Hz bins moving between {est['track_hz'][0]:.3g} and {est['track_hz'][1]:.3g} Hz "
                f"(5-95 %): a frequency wandering by sd {est['spread_hz']:.3g} Hz around {est['center_hz']:.4g} Hz with a "
                f"correlation time of {est['wander_s']:.3g} s (both corrected for the record's length)")
    if folded:
        evidence += (f"; the sinusoid at {sinusoid.params['frequency_hz']:.4g} Hz that the sinusoid detector took "
                     "out of it is the tone dwelling there, and is part of it")
    return Candidate(
        effect=WANDERING_TONE,
        params={"center_hz": est["center_hz"], "spread_hz": est["spread_hz"], "wander_s": est["wander_s"],
                "amplitude_dps": amplitude},
        statistic=z, threshold=TONE_KURTOSIS_Z,
        statistic_name="band's excess kurtosis below 0, in standard errors",
        evidence=evidence), folded
