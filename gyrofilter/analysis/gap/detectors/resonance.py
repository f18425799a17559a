"""Detector 2c, ``resonance``: a broad low hump of noise power, the board's resonance driven by
noise (see :mod:`gyrofilter.analysis.gap.detectors`).

**The fit.** The one-sided Welch PSD S(f) (:func:`~gyrofilter.analysis.gap.detectors.narrowband.welch_psd`,
segments of :data:`RESONANCE_SEGMENT` samples, fewer when the record holds less than 16 of them)
between :data:`RESONANCE_MIN_FRACTION` of the Nyquist frequency and the bin below it is fitted
by least squares on log S (its log-ordinates have a constant variance, about 1/K; Welch 1967) twice:

* the **smooth** null ``S₀(f) = c |1 + μ z|² / |1 - φ z|² + d / f`` (z = e^{-j2πf/f_s}: white
  noise through a first-order ARMA, the ``colored_noise`` effect's spectrum, and a 1/f floor, the
  high-frequency end of a bias instability), 4 parameters;
* the null **plus the hump** ``2 rms² |H(f)|² / (f_s Σ h²)`` of the ``resonance`` effect's
  resonator (:func:`gyrofilter.sim.resonance.band_pass`: centre f₀, quality Q, rms), 3 more,
  started from :data:`RESONANCE_STARTS` centres spread log-evenly over the band (the best fit kept).

**The statistic** is the drop of the residual sum of squares in units of its variance under
the hump, ``F = (RSS₀ - RSS₁) / (RSS₁ / (M - 7))`` over the M bins (a likelihood ratio, about
chi² with 3 degrees of freedom where f₀ is known; scanned over f₀ it is larger), against
:data:`~gyrofilter.analysis.gap.detectors.common.RESONANCE_THRESHOLD`.

**A hump, not a line.** A peak is a hump where it is broad: Q = f₀ / B (B its half-power full
width) at most :data:`~gyrofilter.analysis.gap.detectors.common.RESONANCE_MAX_Q`; a narrower peak
is a line, the ``narrowband`` effect (:func:`hump_or_line`); one broader than
:data:`~gyrofilter.analysis.gap.detectors.common.RESONANCE_MIN_Q` is a tilt of the background, and
one centred below :data:`~gyrofilter.analysis.gap.detectors.common.RESONANCE_LOWEST_FRACTION` of the
Nyquist frequency the rise of the slow effects' spectra (:func:`is_hump`). The Q rule decides
between the two readings where both detectors see the peak: a narrower peak that the narrow-band
detector does not find at the fit's centre is named a hump all the same, up to
:data:`~gyrofilter.analysis.gap.detectors.common.RESONANCE_UNSEEN_MAX_Q` (a hump of true Q 4 read
Q 5.3 fell between the two detectors and went unnamed, D after 3.0); and a band the narrow-band
detector finds with a Q in that overlap (its half-power width read off a noisy Welch peak) is the
hump where the hump's fit of the whole spectrum puts a hump (Q at most 5) at its centre (a hump of
Q 4 read as a band of Q 6.9, its fit Q 4.6). Where the narrow-band detector found a
line, its bins (within :data:`LINE_EXCLUDED_WIDTHS` widths of its centre) are left out of the
fit and its own PSD is part of the background, so a line beside a hump (the MPU-9250 of issue 36: a hump at 10.5-13.5 Hz beside a line at
20.37 Hz) leaves the hump's fit alone; where it found a broad peak, the same peak as the hump's is
one hump, named ``resonance``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ....effects import NARROWBAND, RESONANCE, RINGING, WANDERING_TONE
from .common import (RESONANCE_LOWEST_FRACTION, RESONANCE_MAX_Q, RESONANCE_MIN_Q, RESONANCE_THRESHOLD,
                     RESONANCE_UNSEEN_MAX_Q, Candidate)
from .narrowband import narrowband_lags, welch_psd
from .tone import tone_band
from ....sim.noise_terms import filter_psd, narrowband_filter
from ....sim.resonance import SHOCK_SPREAD_LN, band_pass, band_pass_energy, resonance_lags, ringing_variance
from ....units import check_sample_rate_hz

#: Welch segment (samples) of the fit: f_s / 1024 resolution, 0.1 Hz at 100 Hz, a tenth of the
#: narrowest hump the gap looks for (Q = 5 at 5 % of the Nyquist frequency)
RESONANCE_SEGMENT = 1024
#: the lowest frequency of the fit, as a fraction of the Nyquist frequency (below it the slow
#: effects' spectra rise)
RESONANCE_MIN_FRACTION = 0.02
#: number of starting centres of the hump's fit
RESONANCE_STARTS = 12
#: the quality factors the fit may take (a broader hump is a tilt of the background; a narrower
#: one a line, outside :data:`~gyrofilter.analysis.gap.detectors.common.RESONANCE_MAX_Q` anyway)
Q_RANGE = (0.5, 30.0)
#: half-widths (in line widths) about a narrow-band line that the hump's fit leaves out
LINE_EXCLUDED_WIDTHS = 3.0


def _welch(x, sample_rate_hz):
    seg = int(min(RESONANCE_SEGMENT, 2 ** int(math.log2(max(x.size // 16, 16)))))
    f, s, n_seg = welch_psd(x, sample_rate_hz, seg)
    return f, s, n_seg


class _Bins(NamedTuple):
    """The bins a fit evaluates its PSDs at hundreds of times, and what the PSDs take from them
    that no parameter changes, computed once per fit (:func:`_fit_bins`): the frequencies ``f``,
    ``z = e^{-j2πf/f_s}``, ``cos_t = Re z``, ``z2 = z²``, ``ends = |1 - z²|²``, ``rise = 1 - z²``."""

    f: np.ndarray
    z: np.ndarray
    cos_t: np.ndarray
    z2: np.ndarray
    ends: np.ndarray
    rise: np.ndarray


def _fit_bins(f, sample_rate_hz):
    """The :class:`_Bins` of the frequencies ``f``."""
    z = np.exp(-2j * math.pi * f / sample_rate_hz)
    z2 = z * z
    rise = 1.0 - z2
    return _Bins(f, z, np.ascontiguousarray(z.real), z2, np.abs(rise) ** 2, rise)


def _hump_psd(bins, centre, q, rms, sample_rate_hz, jacobian=False):
    """One-sided PSD of the resonance of rms ``rms`` at the :class:`_Bins` ``bins``,
    2 rms² |H|² / (f_s Σ h²) for the resonator :func:`gyrofilter.sim.resonance.band_pass`
    (b ∝ α (1, 0, -1), a ∝ (1 + α, -2 cos ω₀, 1 - α), α = sin ω₀ / (2Q), ω₀ = 2π f₀ / f_s) and its
    energy Σ h² = α / (1 + α) (:func:`~gyrofilter.sim.resonance.band_pass_energy`), which reduce to
    ``S = 2 rms² α (1 + α) |1 - z²|² / (f_s |D|²)``, ``D = 1 + α - 2 cos ω₀ z + (1 - α) z²``.
    With ``jacobian``: ``(S, dS/d(f₀, ln Q, ln rms))`` (N x 3), by the chain rule through α and
    ω₀ (dα/d ln Q = -α, dα/dω₀ = cos ω₀ / (2Q)), for the fit's least squares (a numerical
    Jacobian cost it seven PSDs an iteration)."""
    parts = _hump_parts(bins, centre, q, rms, sample_rate_hz)
    return _hump_jacobian(bins, q, sample_rate_hz, parts) if jacobian else parts[0]


def _hump_parts(bins, centre, q, rms, sample_rate_hz):
    """:func:`_hump_psd`'s ``S`` and what its Jacobian takes from the same step: ``(S, D, |D|², α,
    ω₀, k = 2 rms² / f_s, g = α (1 + α))``."""
    w = 2.0 * math.pi * centre / sample_rate_hz
    alpha, cos_w = math.sin(w) / (2.0 * q), math.cos(w)
    d = (1.0 + alpha) - 2.0 * cos_w * bins.z + (1.0 - alpha) * bins.z2
    dd = d.real ** 2 + d.imag ** 2
    k = 2.0 * rms * rms / sample_rate_hz
    g = alpha * (1.0 + alpha)
    return k * g * bins.ends / dd, d, dd, alpha, w, k, g


def _hump_jacobian(bins, q, sample_rate_hz, parts):
    """``(S, dS/d(f₀, ln Q, ln rms))`` of :func:`_hump_psd` from its :func:`_hump_parts` ``parts``."""
    psd, d, dd, alpha, w, k, g = parts
    cos_w = math.cos(w)
    conj_d = np.conj(d)
    d_alpha = k * bins.ends * ((1.0 + 2.0 * alpha) - g * 2.0 * (conj_d * bins.rise).real / dd) / dd
    d_w = -psd * 4.0 * math.sin(w) * (conj_d * bins.z).real / dd
    d_centre = (d_alpha * cos_w / (2.0 * q) + d_w) * (2.0 * math.pi / sample_rate_hz)
    return psd, np.column_stack([d_centre, -alpha * d_alpha, 2.0 * psd])


def _null_psd(p, bins, jacobian=False):
    """The smooth null's PSD (module docstring) at the :class:`_Bins` ``bins`` (frequencies ``f``),
    for ``p = (ln c, φ, μ, ln d)``: ``c A + d / f``, ``A = |1 + μ z|² / |1 - φ z|²`` with
    |1 + μ z|² = 1 + 2 μ cos θ + μ² and |1 - φ z|² = 1 - 2 φ cos θ + φ² on the unit circle
    (cos θ = Re z). With ``jacobian``: ``(S, dS/dp)`` (N x 4)."""
    parts = _null_parts(p, bins)
    return _null_jacobian(p, bins, parts) if jacobian else parts[0]


def _null_parts(p, bins):
    """:func:`_null_psd`'s ``S`` and what its Jacobian takes from the same step: ``(S, c, c A, |1 - φ z|², d / f)``."""
    c, phi, mu, d = math.exp(p[0]), p[1], p[2], math.exp(p[3])
    cos_t = bins.cos_t
    num, den = 1.0 + 2.0 * mu * cos_t + mu * mu, 1.0 - 2.0 * phi * cos_t + phi * phi
    coloured, floor = c * num / den, d / bins.f
    return coloured + floor, c, coloured, den, floor


def _null_jacobian(p, bins, parts):
    """``(S, dS/dp)`` of :func:`_null_psd` from its :func:`_null_parts` ``parts``."""
    psd, c, coloured, den, floor = parts
    phi, mu, cos_t = p[1], p[2], bins.cos_t
    return psd, np.column_stack([coloured, coloured * 2.0 * (cos_t - phi) / den, c * 2.0 * (cos_t + mu) / den, floor])


def resonance_fit(x, sample_rate_hz, lines=()):
    """The two fits of the module docstring on the rate series ``x`` (deg/s), beside the narrow-band
    lines ``lines`` (their ``(center_hz, bandwidth_hz, rms_dps)``): the bins within
    :data:`LINE_EXCLUDED_WIDTHS` widths of a line's centre are left out, and its PSD (that of the
    ``narrowband`` effect, :func:`gyrofilter.sim.noise_terms.narrowband_filter`) is part of both
    fits' background, so a tall line's tails are not taken for a hump. Returns a dict with
    ``center_hz``, ``q``, ``rms_dps`` (the hump's), ``statistic`` (F), ``peak_ratio`` (the hump's
    PSD over the null's at f₀) and ``segments``; None where the record is too short (fewer than
    32 bins to fit) or its spectrum is 0 in most of them (a quiet sensor on one code, a few other
    samples: no background to fit a hump against; its log was a math domain error)."""
    from scipy.optimize import least_squares

    f, s, n_seg = _welch(x, sample_rate_hz)
    nyq = sample_rate_hz / 2.0
    sel = (f >= max(RESONANCE_MIN_FRACTION * nyq, f[1])) & (f < nyq - f[1] / 2)
    for centre, width, _ in lines:
        sel &= np.abs(f - centre) > LINE_EXCLUDED_WIDTHS * width
    if sel.sum() < 32:
        return None
    fw, logs = f[sel], np.log(np.maximum(s[sel], 1e-300))
    known = sum((2.0 * filter_psd(*narrowband_filter(rms, centre, width, sample_rate_hz), fw, sample_rate_hz)
                 for centre, width, rms in lines), np.zeros(fw.size))
    bins = _fit_bins(fw, sample_rate_hz)
    level = float(np.median(s[sel]))
    if not level > 0.0:
        return None
    p0 = np.array([math.log(level), 0.0, 0.0, math.log(level * 1e-3 * fw[0])])
    lo0, hi0 = [p0[0] - 10, -0.95, -0.95, p0[3] - 30], [p0[0] + 10, 0.95, 0.95, p0[3] + 10]

    def log_resid(psd):
        return np.log(np.maximum(psd, 1e-300)) - logs

    def log_jacobian(psd, d_psd):  # d log S / dp: 0 where the log's floor holds it
        return d_psd * np.where(psd > 1e-300, 1.0 / np.maximum(psd, 1e-300), 0.0)[:, None]

    def null_resid(p):
        return log_resid(_null_psd(p, bins) + known)

    def null_jac(p):
        psd, d_psd = _null_psd(p, bins, jacobian=True)
        return log_jacobian(psd + known, d_psd)

    null = least_squares(null_resid, p0, jac=null_jac, bounds=(lo0, hi0), max_nfev=400)
    rss0 = float(np.sum(null.fun ** 2))

    last = {}

    def parts(p):  # least squares asks for the Jacobian at the point it evaluated last: its terms are kept
        key = p.tobytes()
        if last.get("key") != key:
            last.update(key=key, null=_null_parts(p[:4], bins),
                        hump=_hump_parts(bins, p[4], math.exp(p[5]), math.exp(p[6]), sample_rate_hz))
        return last["null"], last["hump"]

    def psd_of(p):
        null, hump = parts(p)
        return null[0] + known + hump[0]

    def jac(p):
        null, hump = parts(p)
        null_psd, d_null = _null_jacobian(p[:4], bins, null)
        hump_psd, d_hump = _hump_jacobian(bins, math.exp(p[5]), sample_rate_hz, hump)
        return log_jacobian(null_psd + known + hump_psd, np.hstack([d_null, d_hump]))

    sd0 = math.sqrt(level * nyq)  # the rms of a hump as high as the level over the band
    best = None
    for centre in np.geomspace(fw[0] * 1.5, fw[-1] / 1.05, RESONANCE_STARTS):
        start = np.r_[null.x, centre, math.log(2.0), math.log(0.1 * sd0)]
        lower = lo0 + [fw[0], math.log(Q_RANGE[0]), math.log(sd0) - 12]
        upper = hi0 + [fw[-1], math.log(Q_RANGE[1]), math.log(sd0) + 4]
        try:
            res = least_squares(lambda p: log_resid(psd_of(p)), np.clip(start, np.add(lower, 1e-9), np.subtract(upper, 1e-9)),
                                jac=jac, bounds=(lower, upper), max_nfev=300)
        except (ValueError, FloatingPointError):
            continue
        if best is None or res.cost < best.cost:
            best = res
    if best is None:
        return None
    rss1 = float(np.sum(best.fun ** 2))
    dof = max(fw.size - 7, 1)
    centre, q, rms = float(best.x[4]), float(math.exp(best.x[5])), float(math.exp(best.x[6]))
    at = _fit_bins(np.array([centre]), sample_rate_hz)
    peak = _hump_psd(at, centre, q, rms, sample_rate_hz)[0] / _null_psd(best.x[:4], at)[0]
    return {"center_hz": centre, "q": q, "rms_dps": rms, "statistic": (rss0 - rss1) / (rss1 / dof) if rss1 > 0 else 0.0,
            "peak_ratio": float(peak), "segments": int(n_seg)}


def is_hump(fit, sample_rate_hz):
    """Whether the fit ``fit`` of :func:`resonance_fit` holds a hump: its statistic above
    :data:`~gyrofilter.analysis.gap.detectors.common.RESONANCE_THRESHOLD`, its Q at least
    :data:`~gyrofilter.analysis.gap.detectors.common.RESONANCE_MIN_Q` (a broader peak is a tilt) and
    its centre at least :data:`~gyrofilter.analysis.gap.detectors.common.RESONANCE_LOWEST_FRACTION`
    of the Nyquist frequency (a lower one sits on the slow effects' rise)."""
    return (fit["statistic"] > RESONANCE_THRESHOLD and fit["q"] >= RESONANCE_MIN_Q
            and fit["center_hz"] >= RESONANCE_LOWEST_FRACTION * sample_rate_hz / 2.0)


def hump_or_line(q):
    """The rule that tells a hump from a line (module docstring): ``RESONANCE`` where the peak's
    quality Q = f₀ / B is at most :data:`~gyrofilter.analysis.gap.detectors.common.RESONANCE_MAX_Q`,
    else ``NARROWBAND``."""
    return RESONANCE if q <= RESONANCE_MAX_Q else NARROWBAND


def _within_half_width(fit, band):
    """Whether the band candidate ``band``'s centre lies within the hump ``fit``'s half-power
    half-width, f0 / (2Q), of its centre: the same peak."""
    return abs(band.params["center_hz"] - fit["center_hz"]) <= fit["center_hz"] / (2.0 * fit["q"])


def detect_resonance(x, sample_rate_hz, band=None):
    """``(resonance candidate or None, band or None)``: the hump of :func:`resonance_fit`, and the
    narrow-band candidate ``band`` of the narrow-band detector as it stands beside it (None where
    it was the hump's own peak: a broad band, :func:`hump_or_line`, whose centre lies within the
    hump's half-power band). A sample rate that is no rate raises SettingsError."""
    check_sample_rate_hz(sample_rate_hz)
    if x.size < 4096:
        return None, band
    lines = ()
    band_q = band.params["center_hz"] / band.params["bandwidth_hz"] if band is not None else None
    if band is not None and hump_or_line(band_q) == NARROWBAND:
        lines = ((band.params["center_hz"], band.params["bandwidth_hz"], band.params["rms_dps"]),)
    fit = resonance_fit(x, sample_rate_hz, lines)
    if lines and band_q <= RESONANCE_UNSEEN_MAX_Q:  # a band a little narrow for a hump: the hump's fit of its peak decides
        whole = resonance_fit(x, sample_rate_hz)
        if (whole is not None and is_hump(whole, sample_rate_hz) and whole["q"] <= RESONANCE_MAX_Q
                and _within_half_width(whole, band)):
            fit, lines = whole, ()
    if fit is None or not is_hump(fit, sample_rate_hz):
        return None, band
    half = fit["center_hz"] / (2.0 * fit["q"])
    at_band = band is not None and _within_half_width(fit, band)
    if hump_or_line(fit["q"]) != RESONANCE and (at_band or fit["q"] > RESONANCE_UNSEEN_MAX_Q):
        return None, band  # a narrow peak: the narrow-band detector's line, or a line too weak for it
    if at_band and not lines:
        band = None  # the narrow-band detector's broad peak is the hump
    cand = Candidate(
        effect=RESONANCE,
        params={"center_hz": fit["center_hz"], "q": fit["q"], "rms_dps": fit["rms_dps"]},
        statistic=fit["statistic"],
        threshold=RESONANCE_THRESHOLD,
        statistic_name="drop of the Welch log-PSD residual sum of squares by a resonance hump, in residual variances",
        evidence=(f"a hump of noise power at {fit['center_hz']:.4g} Hz, half-power band {fit['center_hz'] - half:.3g}-"
                  f"{fit['center_hz'] + half:.3g} Hz (Q = {fit['q']:.2g}: "
                  + (f"broader than a line, Q <= {RESONANCE_MAX_Q:g}), " if fit["q"] <= RESONANCE_MAX_Q else
                     f"narrower than a hump's Q <= {RESONANCE_MAX_Q:g}, but the narrow-band detector finds no line "
                     f"there), ")
                  + f"{fit['peak_ratio'] + 1:.2g} times the neighbouring level at its peak, rms {fit['rms_dps']:.3g} deg/s "
                  f"(F = {fit['statistic']:.0f}, threshold {RESONANCE_THRESHOLD:g})"),
    )
    return cand, band


def band_correlation(bands, sample_rate_hz):
    """``(lags, variance)`` of the noise of the band candidates ``bands`` (``narrowband``,
    ``wandering_tone``, ``resonance``, ``ringing``; none: ``(None, 0.0)``): each one's lag-1 and lag-2
    autocorrelations (:func:`~gyrofilter.analysis.gap.detectors.narrowband.narrowband_lags`,
    :func:`gyrofilter.sim.resonance.resonance_lags`) weighted by its variance (rms², or the
    ringing's :func:`gyrofilter.sim.resonance.ringing_variance`), and the sum of the variances:
    what the colored-noise detector takes out of the high-passed series' correlation."""
    parts = []
    for c in bands:
        p = c.params
        if c.effect in (NARROWBAND, WANDERING_TONE):  # a tone: the band of its spectrum (tone_band)
            p = p if c.effect == NARROWBAND else tone_band(p)
            parts.append((narrowband_lags(p["center_hz"], p["bandwidth_hz"], sample_rate_hz), p["rms_dps"] ** 2))
        elif c.effect == RESONANCE:
            parts.append((resonance_lags(p["center_hz"], p["q"], sample_rate_hz), p["rms_dps"] ** 2))
        elif c.effect == RINGING:
            parts.append((resonance_lags(p["center_hz"], p["q"], sample_rate_hz),
                          ringing_variance(p["shock_rate_hz"], p["shock_dps"], p["center_hz"], p["q"], sample_rate_hz,
                                           p.get("spread_ln", SHOCK_SPREAD_LN))))
    total = sum(v for _, v in parts)
    if not total > 0:
        return None, 0.0
    return (sum(r[0] * v for r, v in parts) / total, sum(r[1] * v for r, v in parts) / total), total
