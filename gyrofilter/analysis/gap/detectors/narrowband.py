"""Detector 2b, ``narrowband``: a band of noise with a resolved width (see :mod:`gyrofilter.analysis.gap.detectors`)."""

from __future__ import annotations

import math

import numpy as np

from ....effects import NARROWBAND
from .common import NARROWBAND_THRESHOLD, Candidate
from ...stats import dot, window_medians
from ....sim.noise_terms import filter_psd, narrowband_filter
from ....units import check_sample_rate_hz


# ---------------------------------------------------------------------------------------------
# 2b. narrow-band noise (a spectral line with a resolved width)

#: half-width (Hz) of the running-median background of :func:`band_estimate` (at most f_s / 10,
#: so 10 Hz at 100 Hz; 20 Hz since issue 12, where a 7-Hz band at 285.7 Hz filled half of a ±10-Hz window)
BAND_BACKGROUND_HZ = 20.0
#: the widest (Hz) the moving average of :func:`band_estimate`'s excess may span (fewer than
#: ``smooth_bins`` bins, at least 5, when the Welch bins are coarse: records shorter than 16
#: segments of 8192 at a high rate; 15 bins of 0.56 Hz spanned 8 Hz on the BROAD rest phases)
BAND_SMOOTH_MAX_HZ = 5.0
#: half-width (Hz) the background window of :func:`band_estimate` narrows to at the Nyquist
#: frequency, at most f_s / 40 (a spectrum's rise to f_s / 2, as AR(1) noise of negative lag1 has,
#: scales with f_s; at 10-50 Hz a 2.5-Hz edge window named it as a band)
BAND_EDGE_HZ = 2.5
#: samples of the input :func:`welch_psd` transforms at once (its working memory is a few times
#: this many float64 values, about 8 MB, whatever the record's length)
WELCH_BATCH_SAMPLES = 1 << 18


def welch_psd(x, sample_rate_hz, nperseg):
    """One-sided Welch PSD of ``x`` (Welch 1967), equal to ``scipy.signal.welch(x - x.mean(),
    fs=sample_rate_hz, nperseg=nperseg)`` (periodic Hann window, 50 % overlap, each segment's
    mean removed, density scaling S = 2 |X|² / (f_s Σ w²), the DC and Nyquist bins not doubled,
    the mean over the K = (N - nperseg // 2) // (nperseg - nperseg // 2) segments) but built over
    batches of about :data:`WELCH_BATCH_SAMPLES` samples, so its memory beyond the input is
    bounded (scipy's holds about five arrays of the input's size). Returns ``(f, S, K)``."""
    from scipy.signal import get_window

    x = np.asarray(x, dtype=float)
    seg = int(nperseg)
    step = seg - seg // 2
    n_seg = (x.size - seg // 2) // step if x.ndim == 1 else 0
    if seg < 2 or n_seg < 1:
        raise ValueError(f"welch_psd: needs a 1-D series of at least nperseg = {seg} samples, got shape {x.shape}")
    win = get_window("hann", seg)
    scale = 1.0 / (sample_rate_hz * float(np.sum(win * win)))
    mean = float(np.mean(x))
    per_batch = max(1, WELCH_BATCH_SAMPLES // seg)
    acc = np.zeros(seg // 2 + 1)
    for first in range(0, n_seg, per_batch):
        count = min(per_batch, n_seg - first)
        start = first * step
        piece = x[start:start + (count - 1) * step + seg] - mean
        segs = np.lib.stride_tricks.as_strided(piece, shape=(count, seg),
                                               strides=(step * piece.strides[0], piece.strides[0]))
        segs = segs - segs.mean(axis=1, keepdims=True)
        segs *= win
        spec = np.fft.rfft(segs, axis=1)
        del segs
        acc += np.sum(spec.real ** 2 + spec.imag ** 2, axis=0)
        del spec
    psd = acc * (scale / n_seg)
    psd[1:-1 if seg % 2 == 0 else None] *= 2.0
    f = np.fft.rfftfreq(seg, 1.0 / sample_rate_hz)
    return f, psd, n_seg


def band_estimate(x_dps, sample_rate_hz, *, nperseg=8192, smooth_bins=15, fit=True):
    """Centre, half-power full width and rms of the strongest band of a rate series.

    One-sided Welch PSD S(f) (Hann, 50 % overlap, segments of ``nperseg`` samples, fewer when
    the record holds less than 16 of them: the largest power of 2 up to N / 16; Welch 1967;
    :func:`welch_psd`, in bounded memory);
    background b(f) = running median of S over ±W, W = min(f_s / 10, :data:`BAND_BACKGROUND_HZ`);
    excess e = S - b, and ē its moving average over ``smooth_bins`` bins (the Welch bins are
    noisy), fewer (odd, at least 5) where those would span more than :data:`BAND_SMOOTH_MAX_HZ`.
    The peak is the bin of largest R = 1 + ē / b among the bins above W (near 0 the median of a spectrum rising to 0 Hz is
    biased); within W of f_s / 2 the window narrows to the bins left and is mirrored about
    f_s / 2 for the last min(:data:`BAND_EDGE_HZ`, f_s / 40) (:func:`_edge_background`; the
    Nyquist bin, which the one-sided PSD does not double, is doubled first, and ē is mirrored
    there too); the band is the contiguous run of bins around it with ē > ē_peak / 2 (its
    width is the half-power full width, at least about ``smooth_bins`` bins: a pure line shows that width), the centre the e-weighted mean
    frequency of that run, and rms² = Σ e Δf over the contiguous run with ē > 0 (a one-sided
    PSD integrates to the variance). Returns a dict with ``center_hz``, ``bandwidth_hz``,
    ``rms_dps``, ``peak_ratio`` (R at the peak), ``resolution_hz`` (the width a pure line
    shows, ``smooth_bins`` Δf) and ``segments`` (K, the number of Welch segments). With ``fit``
    the centre, width and rms are then refined by :func:`_resonator_fit`.
    """
    from scipy.ndimage import uniform_filter1d

    x = np.asarray(x_dps, dtype=float)
    seg = int(min(nperseg, 2 ** int(math.log2(max(x.size // 16, 16)))))
    f, s, n_seg = welch_psd(x, sample_rate_hz, seg)
    df = f[1] - f[0]
    smooth_bins = int(max(5, min(smooth_bins, (int(BAND_SMOOTH_MAX_HZ / df) - 1) | 1)))
    background_hz = min(sample_rate_hz / 10.0, BAND_BACKGROUND_HZ)
    width = max(3, int(round(2 * background_hz / df)) | 1)
    s_fit = s
    if seg % 2 == 0:
        s = s.copy()
        s[-1] *= 2.0  # the one-sided Nyquist bin is not doubled: make S continuous there
    half = min(width // 2, s.size - 1)
    back = np.empty(s.size)
    edge_hz = min(BAND_EDGE_HZ, sample_rate_hz / 40.0)
    back[s.size - half:] = _edge_background(s, half, min(half, max(4, int(round(edge_hz / df)))))
    back[:s.size - half] = _running_median(s, width, s.size - half)
    excess = s - back
    smooth = uniform_filter1d(excess, smooth_bins, mode="mirror")
    ratio = 1.0 + smooth / np.maximum(back, 1e-300)
    ratio[f < background_hz] = 0.0
    k = int(np.argmax(ratio))

    def run(mask):
        lo = hi = k
        while lo > 0 and mask[lo - 1]:
            lo -= 1
        while hi < mask.size - 1 and mask[hi + 1]:
            hi += 1
        return lo, hi

    lo, hi = run(smooth > smooth[k] / 2.0)
    w = excess[lo:hi + 1]
    total = float(w.sum())
    centre = float(dot(w, f[lo:hi + 1]) / total) if total > 0 else float(f[k])
    plo, phi = run(smooth > 0.0)
    rms = math.sqrt(max(float(excess[plo:phi + 1].sum()), 0.0) * df)
    out = {"center_hz": centre, "bandwidth_hz": float((hi - lo + 1) * df), "rms_dps": rms,
           "peak_ratio": float(ratio[k]), "resolution_hz": float(smooth_bins * df),
           "segments": int(n_seg)}
    if fit and rms > 0:
        out.update(_resonator_fit(f, s_fit, out, sample_rate_hz))
    return out


def _running_median(s, width, count):
    """The running median of ``s`` over ``width`` (odd) bins, ``s`` extended by its end bins, for
    its first ``count`` bins: ``scipy.ndimage.median_filter(s, size=width, mode="nearest")[:count]``,
    exactly (:func:`~gyrofilter.analysis.stats.window_medians`)."""
    h = width // 2
    if not np.isfinite(s).all():  # no order to keep: the filter's own
        from scipy.ndimage import median_filter
        return median_filter(s, size=width, mode="nearest")[:count]
    padded = np.concatenate((np.full(h, s[0]), s, np.full(h, s[-1])))
    return window_medians(padded, [(i, i + width) for i in range(count)])


def _edge_background(s, half, edge_half):
    """Running median of ``s`` for its last ``half`` bins, whose ±``half`` window would pass the
    Nyquist bin: the window narrows to the bins left, ±max(d, ``edge_half``) at d bins from the
    top, and the bins beyond the top are mirrored about it (the PSD of a sampled series is even
    about f_s / 2; ``edge_half`` is at most ``half``). A centred window gives the spectrum's own value wherever it is monotone;
    the mirrored part is at most ±``edge_half`` bins, so the bias of a spectrum that peaks at
    f_s / 2 (an AR(1) with negative lag1) is that of a median over ``edge_half`` bins."""
    top = s.size - 1
    if half < 1:
        return np.empty(0)
    centres = np.arange(top - half + 1, top + 1)
    h = np.maximum(top - centres, edge_half)
    first = int(centres[0] - h[0])
    idx = np.arange(first, top + edge_half + 1)
    idx = np.abs(np.where(idx > top, 2 * top - idx, idx))  # mirrored about f_s / 2 (and 0 Hz)
    if not np.isfinite(s).all():  # no order to keep: each window's median anew
        return np.array([np.median(s[idx[c - w - first:c + w + 1 - first]]) for c, w in zip(centres, h)])
    return window_medians(s[idx], list(zip((centres - h - first).tolist(), (centres + h + 1 - first).tolist())))


def _resonator_fit(f, s, band, sample_rate_hz):
    """Refine centre, width and rms by fitting the ``narrowband`` effect's own PSD (the AR(2)
    resonator of :func:`gyrofilter.sim.noise_terms.narrowband_filter`, one-sided 2 |B|² / |A|² / f_s)
    on a local linear background, ``S(f) = b0 + b1 (f - f_c) + S_L(f; f_c, B, rms)``, to the Welch
    PSD within ±max(5 B, 1 Hz) of the centre, by least squares on log S (the Welch log-ordinates
    have a constant variance, about 1/K). The nonparametric estimate is the start; the result is
    kept only if it fits better. The resonator's Lorentzian tails hold power outside the
    half-power run that the nonparametric rms misses."""
    from scipy.optimize import least_squares

    c0, b0w, rms0 = band["center_hz"], band["bandwidth_hz"], band["rms_dps"]
    half = max(5.0 * b0w, 1.0)
    sel = (f >= max(c0 - half, f[1])) & (f <= min(c0 + half, sample_rate_hz / 2 - f[1]))
    if sel.sum() < 8:
        return {}
    fw, logs = f[sel], np.log(np.maximum(s[sel], 1e-300))
    edge = np.r_[s[sel][:3], s[sel][-3:]]
    start = np.array([c0, math.log(b0w), math.log(rms0), math.log(max(float(np.median(edge)), 1e-300)), 0.0])

    def model(p):
        centre, bw, rms, level, slope = p[0], math.exp(p[1]), math.exp(p[2]), math.exp(p[3]), p[4]
        b, a = narrowband_filter(rms, centre, bw, sample_rate_hz)
        line = 2.0 * filter_psd(b, a, fw, sample_rate_hz)
        return np.log(np.maximum(level * (1.0 + slope * (fw - centre)) + line, 1e-300))

    def resid(p):
        return model(p) - logs

    lower = [c0 - half / 2, math.log(b0w / 20), start[2] - 3, start[3] - 5, -1.0 / half]
    upper = [c0 + half / 2, math.log(min(4 * b0w, sample_rate_hz / 4)), start[2] + 3, start[3] + 5, 1.0 / half]
    try:
        res = least_squares(resid, np.clip(start, np.add(lower, 1e-9), np.subtract(upper, 1e-9)),
                            bounds=(lower, upper), max_nfev=200)
    except (ValueError, FloatingPointError, np.linalg.LinAlgError):
        return {}
    if not (res.success and res.cost < 0.5 * float(np.sum(resid(start) ** 2))):
        return {}
    return {"center_hz": float(res.x[0]), "bandwidth_hz": float(math.exp(res.x[1])), "rms_dps": float(math.exp(res.x[2]))}


def detect_narrowband(x, sample_rate_hz):
    """Narrow-band noise candidate (the ``narrowband`` effect: centre, half-power width, rms)
    from :func:`band_estimate`.

    Statistic ``(R - 1) sqrt(K)``: the Welch estimate averages K segments, so the excess over
    the background at one bin has a relative sampling error of about 1 / sqrt(K) (chi-square
    with about 2K degrees of freedom; Welch 1967), and smoothing only lowers it; the threshold
    :data:`NARROWBAND_THRESHOLD` sits well above its largest value on white and AR(1) noise.
    Runs after the sinusoid detector, so a pure line is already subtracted; the evidence says
    whether the fitted width exceeds the estimator's resolution (``resolution_hz``) by half
    again, i.e. whether the width is resolved. A sample rate that is no rate raises SettingsError
    (:func:`~gyrofilter.units.check_sample_rate_hz`)."""
    check_sample_rate_hz(sample_rate_hz)
    if x.size < 4096:
        return None
    band = band_estimate(x, sample_rate_hz)
    stat = (band["peak_ratio"] - 1.0) * math.sqrt(band["segments"])
    if not stat > NARROWBAND_THRESHOLD or band["rms_dps"] <= 0:
        return None
    resolved = band["bandwidth_hz"] > 1.5 * band["resolution_hz"]
    return Candidate(
        effect=NARROWBAND,
        params={"center_hz": band["center_hz"], "bandwidth_hz": band["bandwidth_hz"], "rms_dps": band["rms_dps"]},
        statistic=stat,
        threshold=NARROWBAND_THRESHOLD,
        statistic_name="Welch band excess over the running-median background, in sampling errors",
        evidence=(f"a band of noise at {band['center_hz']:.4g} Hz, half-power width {band['bandwidth_hz']:.3g} Hz "
                  + ("(resolved: the Welch resolution is " if resolved else "(not resolved: the Welch resolution is ")
                  + f"{band['resolution_hz']:.2g} Hz), rms {band['rms_dps']:.3g} deg/s; its peak is "
                  f"{band['peak_ratio']:.2g} times the background PSD ({stat:.0f} sampling errors, threshold "
                  f"{NARROWBAND_THRESHOLD:g})"),
    )


def narrowband_lags(center_hz, bandwidth_hz, sample_rate_hz):
    """Lag-1 and lag-2 autocorrelations of the ``narrowband`` effect's AR(2) resonator,
    r₁ = φ₁ / (1 - φ₂), r₂ = φ₁ r₁ + φ₂ (Yule-Walker; Box & Jenkins, eq. 3.2.26),
    φ₁ = 2 r cos θ, φ₂ = -r² (:func:`gyrofilter.sim.noise_terms.narrowband_filter`)."""
    theta = 2.0 * math.pi * center_hz / sample_rate_hz
    r = math.exp(-math.pi * bandwidth_hz / sample_rate_hz)
    phi1, phi2 = 2.0 * r * math.cos(theta), -r * r
    r1 = phi1 / (1.0 - phi2)
    return r1, phi1 * r1 + phi2
