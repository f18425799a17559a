"""A wandering tone's periodic excursion (issue 36, the ADIS16405 z axes): where a ``wandering_tone``
is named, is the power beside its band modulated with a period, the tone's frequency stepping away
and back every few seconds (the simulator's ``excursion_*`` keys, :mod:`gyrofilter.sim.tone`)?

The tone's band is [lo, hi] = f_c ± :data:`~gyrofilter.analysis.gap.detectors.tone.TONE_TRACK_SDS`
σ_f, its **flanks** [lo - w, lo) and (hi, hi + w], w = 2 (hi - lo) (clipped to (0, f_s / 2)).
Cut out of the series by their DFT bins (the other bins zeroed), the flanks' signal y gives:

* its excess kurtosis, mean y⁴ / (mean y²)² - 3 (0 for Gaussian noise whatever its spectrum);
* its **envelope line**: the power y² averaged over blocks of :data:`EXCURSION_BLOCK_S`, mean
  removed, its periodogram over :data:`EXCURSION_MODULATION_HZ`, the largest ordinate over the
  median ordinate, R, and its frequency (or, where a line at f / k, k = 2 to
  :data:`EXCURSION_HARMONICS`, also reaches the threshold, the lowest such: the strongest line
  of a pulse train may be its second or third harmonic, :func:`fundamental`). The ordinates of
  a stationary band's envelope are about independent exponentials, whose median is ln 2 times
  their mean: over K ordinates R is about (ln K + 0.58) / ln 2 on average (15 at K = 20 000),
  and R > r has probability about K 2^-r (the largest of K exponential ordinates, as in Fisher's
  test of a periodogram's largest ordinate, Fisher 1929, Proc. R. Soc. A 125, 54, on the
  median's scale). An excursion that returns every P seconds
  puts a line at 1 / P.

An excursion is present where R >= :data:`~gyrofilter.analysis.gap.detectors.common.EXCURSION_LINE_RATIO`.
Its period is then refined by folding (epoch folding, Leahy et al. 1983, ApJ 266, 160): the
envelope folded in :data:`EXCURSION_BINS` phases over a grid of periods around 1 / f of the line
(± one periodogram bin, steps that move the last cycle by a tenth of a phase bin), the period
whose folded profile varies most. Its height and length come from the tone's frequency folded
on that period (:func:`excursion_size`): the peak frequency per short-time spectrum of about
:data:`EXCURSION_FRAME_S` (:func:`~gyrofilter.analysis.gap.detectors.tone.peak_track`, searched
over the band and its flanks) less its running median (the slow wander), per phase bin.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ....units import check_sample_rate_hz
from .common import EXCURSION_LINE_RATIO
from .tone import TONE_TRACK_SDS, peak_track

#: the envelope's block (s) and the band of modulation frequencies (Hz) searched
EXCURSION_BLOCK_S = 0.1
EXCURSION_MODULATION_HZ = (0.01, 2.0)
#: the harmonics of the envelope's strongest line searched for its fundamental
EXCURSION_HARMONICS = 5
#: the phases a cycle is folded in
EXCURSION_BINS = 20
#: the short-time spectra of the frequency track (s; the power of 2 of samples nearest it)
EXCURSION_FRAME_S = 1.3
#: the track's slow wander: its running median over this many periods
EXCURSION_BASE_PERIODS = 3.0
#: a frame of the excursion's phases has jumped where its deviation exceeds this many robust sd
#: of the other phases' frames
EXCURSION_JUMP_SDS = 3.0


def tone_flanks(center_hz, spread_hz, sample_rate_hz):
    """``((lo, hi), (lo - w, hi + w))`` (Hz): the tone's band f_c ± TONE_TRACK_SDS σ_f and the
    outer edges of its flanks, w = 2 (hi - lo), clipped to [0, f_s / 2] (module docstring)."""
    lo, hi = center_hz - TONE_TRACK_SDS * spread_hz, center_hz + TONE_TRACK_SDS * spread_hz
    w = 2.0 * (hi - lo)
    return (lo, hi), (max(lo - w, 0.0), min(hi + w, sample_rate_hz / 2.0))


def _cut(x, sample_rate_hz, keep):
    """``x`` (mean removed) with the DFT bins where ``keep(f)`` is False zeroed."""
    spec = np.fft.rfft(x - np.mean(x))
    spec[~keep(np.fft.rfftfreq(x.size, 1.0 / sample_rate_hz))] = 0.0
    return np.fft.irfft(spec, x.size)


def flank_envelope(x_dps, sample_rate_hz, center_hz, spread_hz):
    """The flanks of the tone's band in ``x_dps`` (module docstring): a dict of ``kurtosis``, the
    envelope line's ``ratio`` R and ``period_s`` 1 / f, ``ordinates`` K, ``envelope`` (the block
    powers, mean removed), ``block_s`` (their length, s) and ``flanks_hz`` (lo - w, lo, hi, hi + w)."""
    check_sample_rate_hz(sample_rate_hz)
    x = np.asarray(x_dps, dtype=float)
    (lo, hi), (outer_lo, outer_hi) = tone_flanks(center_hz, spread_hz, sample_rate_hz)
    y = _cut(x, sample_rate_hz, lambda f: ((f >= outer_lo) & (f < lo)) | ((f > hi) & (f <= outer_hi)))
    v = float(np.mean(y * y))
    block = max(1, int(round(EXCURSION_BLOCK_S * sample_rate_hz)))
    env = (y[: y.size // block * block] ** 2).reshape(-1, block).mean(axis=1)
    env -= env.mean()
    p = np.abs(np.fft.rfft(env)) ** 2
    fe = np.fft.rfftfreq(env.size, block / sample_rate_hz)
    sel = (fe >= EXCURSION_MODULATION_HZ[0]) & (fe <= EXCURSION_MODULATION_HZ[1])
    if v <= 0 or sel.sum() < 3:  # no flanks, or a record too short for the band of modulations
        return {"kurtosis": 0.0, "ratio": 0.0, "period_s": math.nan, "ordinates": int(sel.sum()), "envelope": env,
                "block_s": block / sample_rate_hz, "flanks_hz": (outer_lo, lo, hi, outer_hi)}
    ps, fs_ = p[sel], fe[sel]
    med = float(np.median(ps))
    j = fundamental(ps, fs_, int(np.argmax(ps)), EXCURSION_LINE_RATIO * med)
    return {"kurtosis": float(np.mean(y ** 4) / v ** 2 - 3.0), "ratio": float(ps[j] / med),
            "period_s": float(1.0 / fs_[j]), "ordinates": int(sel.sum()), "envelope": env,
            "block_s": block / sample_rate_hz, "flanks_hz": (outer_lo, lo, hi, outer_hi)}


def fundamental(power, freq_hz, j, level):
    """The index of the line whose harmonic the strongest ordinate ``j`` is: the lowest f_j / k,
    k = :data:`EXCURSION_HARMONICS` .. 2, whose largest ordinate within one bin reaches ``level``
    (a pulse of length D every P seconds has lines at k / P, the strongest not always the first),
    else ``j``."""
    for k in range(EXCURSION_HARMONICS, 1, -1):
        near = np.flatnonzero(np.abs(freq_hz - freq_hz[j] / k) <= 1.5 * (freq_hz[1] - freq_hz[0]))
        if near.size and power[near].max() >= level:
            return int(near[np.argmax(power[near])])
    return j


def fold(values, times_s, period_s, bins=EXCURSION_BINS):
    """The mean of ``values`` per phase bin, phase = (t mod P) / P in ``bins`` equal bins."""
    phase = np.minimum(((np.asarray(times_s) / period_s) % 1.0 * bins).astype(int), bins - 1)
    return np.bincount(phase, values, bins) / np.maximum(np.bincount(phase, None, bins), 1)


def refined_period(envelope, block_s, period_s):
    """The period (s) near ``period_s`` whose folded ``envelope`` varies most (module docstring)."""
    span_s = envelope.size * block_s
    half = period_s ** 2 / span_s  # one bin of the envelope's periodogram, as a period
    step = max(0.1 * period_s ** 2 / (EXCURSION_BINS * span_s), 1e-6)
    grid = np.arange(period_s - half, period_s + half + step / 2, step)
    t = (np.arange(envelope.size) + 0.5) * block_s
    return float(grid[int(np.argmax([np.var(fold(envelope, t, p)) for p in grid]))])


def folded_band(x_dps, sample_rate_hz, center_hz, spread_hz, period_s):
    """(least power of the tone's band over its median, share of the cycle below 0.9 of the
    median): the band's power folded on ``period_s`` in :data:`EXCURSION_BINS` phases."""
    (lo, hi), _ = tone_flanks(center_hz, spread_hz, sample_rate_hz)
    y = _cut(np.asarray(x_dps, dtype=float), sample_rate_hz, lambda f: (f >= lo) & (f <= hi))
    prof = fold(y * y, np.arange(y.size) / sample_rate_hz, period_s)
    prof /= np.median(prof)
    return float(prof.min()), float(np.mean(prof < 0.9))


def tone_excursion(x_dps, sample_rate_hz, center_hz, spread_hz):
    """The periodic excursion of the wandering tone of centre ``center_hz`` and spread
    ``spread_hz`` in ``x_dps`` (module docstring): a dict of the envelope's ``ratio``, its
    ``period_s`` and ``kurtosis``, and, where the ratio reaches :data:`EXCURSION_LINE_RATIO`,
    ``present`` True and the excursion's ``excursion_period_s`` (refined), ``excursion_hz`` h
    and ``excursion_s`` D (``present`` False and those None below it, or where the folded track
    shows no rise)."""
    env = flank_envelope(x_dps, sample_rate_hz, center_hz, spread_hz)
    out = {"ratio": env["ratio"], "period_s": env["period_s"], "kurtosis": env["kurtosis"], "present": False,
           "excursion_period_s": None, "excursion_hz": None, "excursion_s": None}
    if not env["ratio"] >= EXCURSION_LINE_RATIO:
        return out
    period_s = refined_period(env["envelope"], env["block_s"], env["period_s"])
    height, length_s = excursion_size(x_dps, sample_rate_hz, env["flanks_hz"], period_s)
    if height is not None:
        out.update(present=True, excursion_period_s=period_s, excursion_hz=height, excursion_s=length_s)
    return out


def excursion_size(x_dps, sample_rate_hz, flanks_hz, period_s):
    """``(h, D)`` of an excursion of period ``period_s`` (module docstring), or ``(None, None)``
    where the folded track shows no rise. The track's frames, less its running median over
    :data:`EXCURSION_BASE_PERIODS` periods (the slow wander), are the deviations; the phase
    bins whose mean deviation exceeds half the largest are the excursion's. h is the median
    deviation of the excursion's frames that stand above :data:`EXCURSION_JUMP_SDS` robust sd of
    the other frames' (the jump where it happens: on a real source it may not every cycle); D the
    mean deviation summed over the bins above a quarter of the largest, times P / bins, over h
    (the area h D of the step), at most P / 2."""
    from scipy.ndimage import median_filter

    x = np.asarray(x_dps, dtype=float)
    seg = 2 ** int(round(math.log2(max(EXCURSION_FRAME_S * sample_rate_hz, 8.0))))
    res = sample_rate_hz / seg
    track = peak_track(x - np.mean(x), sample_rate_hz, seg, max(flanks_hz[0], res), min(flanks_hz[3], sample_rate_hz / 2 - res))
    hop_s = (seg // 2) / sample_rate_hz
    dev = track - median_filter(track, size=int(round(EXCURSION_BASE_PERIODS * period_s / hop_s)) | 1, mode="nearest")
    centres_s = np.arange(track.size) * hop_s + seg / 2.0 / sample_rate_hz
    excess = fold(dev, centres_s, period_s)
    excess -= np.median(excess)
    if not excess.max() > 0:
        return None, None
    phase = np.minimum(((centres_s / period_s) % 1.0 * EXCURSION_BINS).astype(int), EXCURSION_BINS - 1)
    on = np.isin(phase, np.flatnonzero(excess > excess.max() / 2))
    off = dev[~on]
    jumped = dev[on][dev[on] > EXCURSION_JUMP_SDS * 1.4826 * np.median(np.abs(off - np.median(off)))]
    height = float(np.median(jumped)) if jumped.size else float(excess.max())
    area = float(excess[excess > excess.max() / 4].sum() * period_s / EXCURSION_BINS)
    return height, min(area / height, 0.5 * period_s)


def excursion_note(tone, x_dps, sample_rate_hz):
    """The ``wandering_tone`` candidate ``tone`` with a note on the periodic excursion of its
    frequency (:func:`tone_excursion` at its centre and spread) in its evidence where one is
    present, else ``tone`` itself. A note, not a term of the extended model: on the ADIS16405
    z axes the excursion in the model lowered D after on some of the simulations' streams and
    raised it on others (docs/gap.md, "What the tone's model does not yet hold"), so the model
    keeps the tone without it; the simulator takes it (``excursion_*``, :mod:`gyrofilter.sim.tone`)."""
    p = tone.params
    exc = tone_excursion(x_dps, sample_rate_hz, p["center_hz"], p["spread_hz"])
    if not exc["present"]:
        return tone
    note = (f"the power beside its band comes and goes with a period of {exc['excursion_period_s']:.4g} s (the flanks' "
            f"envelope line {exc['ratio']:.0f} times its median ordinate, at least {EXCURSION_LINE_RATIO:g} for an "
            f"excursion): the tone's frequency steps up by about {exc['excursion_hz']:.2g} Hz for {exc['excursion_s']:.2g} s "
            "every period (its short-time peak folded on the period; the simulator's excursion_hz, excursion_period_s, "
            "excursion_s), which the extended model does not hold")
    return replace(tone, evidence_notes=tone.evidence_notes + (note,))
