"""Detector 1c, ``ringing``: the board's resonance rung by random shocks, spikes that ring and
decay (see :mod:`gyrofilter.analysis.gap.detectors`).

Shocks through a resonator leave two traces that the other detectors name apart: spikes (the
rings' peaks, taken for ``outliers`` or ``heavy_tails``) and a hump of power at the resonance
(the rings' spectrum, taken for a ``resonance``). This detector runs where the spike detectors
found something, before the spikes are cleaned, and names the one cause:

1. **The hump.** :func:`~gyrofilter.analysis.gap.detectors.resonance.resonance_fit` on the
   series as recorded; no hump (:func:`~gyrofilter.analysis.gap.detectors.resonance.is_hump`), no
   ringing (a ring may be narrower than a hump: Q up to the fit's largest).
2. **The events.** The series less its mean through the hump's own resonator (a matched filter
   of a ring, :func:`gyrofilter.sim.resonance.band_pass`), y; an event is the largest |y| of a
   run of samples beyond ``k`` robust sd of y, runs closer than a ring's length L merged
   (k = Phi^-1(1 - 0.025 / N), as the spike detector's; L: until the ring's envelope
   exp(-π f₀ n / (Q f_s)) falls below 1 %, at most :data:`RING_MAX_SAMPLES`).
3. **Ring or spike.** In the window from 2L samples before each event's y-peak to L after it
   (the ring's onset up to 2L before the peak of y, which lags it by about a decay time), the ring (the
   resonator's impulse response g, peak 1, over L samples) fitted by least squares at the
   best onset o, ``a_i = <x[o:o+L], g> / <g, g>``, explains ``a_i² <g, g>`` of the window's
   energy; an isolated spike at the window's largest sample explains ``max x²``. The statistic
   is ``Σ_i (a_i² <g, g> - max x_i²) / σ²`` (σ the robust sd of the series): the energy the rings
   explain beyond what isolated spikes would, in noise variances. An iid spike or a heavy-tailed
   sample projects on a ring by at most 1 / <g, g> of its energy, so the statistic falls below 0;
   a ring adds its tail, ``(<g, g> - 1) a²``.

Named where the statistic exceeds :data:`~gyrofilter.analysis.gap.detectors.common.RINGING_THRESHOLD`
with at least :data:`~gyrofilter.analysis.gap.detectors.common.OUTLIER_MIN_COUNT` events; then
the spike and tail findings are not named beside it (:func:`gyrofilter.analysis.gap.confound.one_cause_of_spikes`)
and the fitted rings are the finding's component, taken out of the series for the later
detectors. Parameters: the hump's centre and Q, ``shock_rate_hz`` = events / duration (the
shocks below the event threshold are not counted), ``shock_dps`` = the median |a_i|; the centre
and Q refined on the rings themselves (:func:`refine_ring`) and the rings fitted again with them.
"""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np

from ....effects import RINGING
from .common import OUTLIER_FALSE_PER_AXIS, OUTLIER_MIN_COUNT, RINGING_THRESHOLD, Candidate
from .resonance import Q_RANGE, is_hump, resonance_fit
from ...stats import robust_sigma
from ....sim.resonance import band_pass, impulse_response

#: the longest ring (samples) the fit spans
RING_MAX_SAMPLES = 256
#: the ring's length: until its envelope falls below this share of its peak
RING_END = 0.01
#: the passes of :func:`ring_fit` over what the rings fitted so far leave
RING_PASSES = 4


def ring_template(center_hz, q, sample_rate_hz, size=None):
    """The ring g of a unit shock (peak |g| = 1) over L samples (module docstring, 2.), or over
    exactly ``size`` samples."""
    h = impulse_response(center_hz, q, sample_rate_hz)
    if size is None:
        decay = math.pi * center_hz / (q * sample_rate_hz)
        size = int(min(RING_MAX_SAMPLES, max(4, math.ceil(-math.log(RING_END) / decay)), h.size))
    return np.r_[h[:size], np.zeros(max(0, size - h.size))] / float(np.max(np.abs(h)))


def ring_fit(x, sample_rate_hz, center_hz, q):
    """The events and rings of the module docstring (2., 3.) for the resonator (``center_hz``,
    ``q``) in ``x``: a dict with ``statistic``, ``events`` (count), ``amplitudes_dps`` (a_i),
    ``onsets`` (o_i), ``template`` (g), ``component`` (the fitted rings, per sample) and
    ``band_kurtosis`` (the excess kurtosis of the series through the resonator: about 0 for a
    Gaussian hump, large for shocks; the evidence's, not the decision's); None
    where there is no event. Each ring is taken out of the series as it is fitted, and the events
    are sought again on what is left, up to :data:`RING_PASSES` times: a ring that starts within
    another's is an event of the next pass."""
    from scipy.signal import lfilter

    resid = x - float(np.mean(x))
    g = ring_template(center_hz, q, sample_rate_hz)
    size, energy = g.size, float(np.dot(g, g))
    b, a = band_pass(center_hz, q, sample_rate_hz)
    y = lfilter(b, a, resid)
    sd_y = robust_sigma(y)
    var_y = float(np.mean(y * y))
    kurtosis = float(np.mean(y ** 4)) / var_y**2 - 3.0 if var_y > 0 else 0.0
    del y
    sigma = robust_sigma(resid)
    k = NormalDist().inv_cdf(1.0 - 0.5 * OUTLIER_FALSE_PER_AXIS / x.size)
    stat, amps, onsets = 0.0, [], []
    component = np.zeros(x.size)
    for _ in range(RING_PASSES):
        y = np.abs(lfilter(b, a, resid))
        over = np.flatnonzero(y > k * sd_y)
        if over.size == 0 or not sd_y > 0 or not sigma > 0:
            break
        starts = np.r_[0, np.flatnonzero(np.diff(over) > size) + 1]
        ends = np.r_[starts[1:], over.size]
        for p in [int(over[s + np.argmax(y[over[s:e]])]) for s, e in zip(starts, ends)]:
            lo = max(p - 2 * size, 0)
            w = resid[lo:min(p + size + 1, x.size)]
            if w.size < size:
                continue
            proj = np.correlate(w, g, mode="valid") / energy
            j = int(np.argmax(proj * proj))
            stat += (proj[j] ** 2 * energy - float(np.max(w * w))) / sigma**2
            amps.append(float(proj[j]))
            onsets.append(lo + j)
            end = min(lo + j + size, x.size)
            ring = proj[j] * g[:end - lo - j]
            resid[lo + j:end] -= ring
            component[lo + j:end] += ring
    if not amps:
        return None
    onsets, amps = _joint_amplitudes(x - float(np.mean(x)), g, np.array(onsets), k * sigma / math.sqrt(energy))
    component = np.zeros(x.size)
    for o, a_i in zip(onsets, amps):
        end = min(o + size, x.size)
        component[o:end] += a_i * g[:end - o]
    return {"statistic": float(stat), "events": int(amps.size), "amplitudes_dps": amps,
            "onsets": onsets, "template": g, "component": component, "band_kurtosis": kurtosis}


def _joint_amplitudes(x0, g, onsets, least_dps):
    """The rings' amplitudes fitted jointly by least squares at their onsets (overlapping rings
    apart: the normal equations G a = b, G_ij = Σ g[n] g[n + |o_i - o_j|], b_i = <x0[o_i:], g>),
    then the events whose amplitude is below ``least_dps`` (the event threshold in units of an
    amplitude's noise, σ / sqrt(<g, g>)) dropped and the rest fitted again: what is left of a
    ring fitted at a wrong onset is no shock."""
    size = g.size
    auto = np.array([float(np.dot(g[:size - d], g[d:])) for d in range(size)])
    onsets = np.unique(onsets)  # one shock found again on a later pass is one shock
    amps = np.zeros(0)
    for _ in range(2):
        if onsets.size == 0:
            break
        lag = np.abs(onsets[:, None] - onsets[None, :])
        gram = np.where(lag < size, auto[np.minimum(lag, size - 1)], 0.0)
        rhs = np.array([float(np.dot(x0[o:o + size], g[:min(size, x0.size - o)])) for o in onsets])
        amps = np.linalg.lstsq(gram, rhs, rcond=None)[0]
        keep = np.abs(amps) >= least_dps
        if keep.all():
            break
        onsets = onsets[keep]
        amps = amps[keep]
    return onsets, amps


def refine_ring(x, sample_rate_hz, rings, center_hz, q):
    """``(centre, Q)`` refined on the rings themselves: each event's window ``w_i`` (its ring plus
    the noise, the other rings taken out: what :func:`ring_fit` leaves at its onset, with its own
    ring back) fitted by ``a_i g(f₀, Q)`` with ``a_i`` profiled out, least squares over f₀ (within
    10 %) and log Q (within a factor 2), from the hump's values. The rings stand far above the
    noise, so the time domain pins the resonance better than the spectrum of a few shocks."""
    from scipy.optimize import least_squares

    g0 = rings["template"]
    resid = x - float(np.mean(x)) - rings["component"]
    size = g0.size
    wins = np.array([np.r_[resid[o:o + size], np.zeros(max(0, o + size - x.size))] + a * g0
                     for o, a in zip(rings["onsets"], rings["amplitudes_dps"])])

    def res(p):
        g = ring_template(p[0], math.exp(p[1]), sample_rate_hz, size)
        amp = wins @ g / float(np.dot(g, g))
        return (wins - amp[:, None] * g[None, :]).ravel()

    lower, upper = [0.9 * center_hz, math.log(q / 2.0)], [min(1.1 * center_hz, 0.499 * sample_rate_hz), math.log(2.0 * q)]
    try:
        fit = least_squares(res, [center_hz, math.log(q)], bounds=(lower, upper), x_scale=[0.01 * center_hz, 0.05],
                            max_nfev=100)
    except (ValueError, FloatingPointError):
        return center_hz, q
    return float(fit.x[0]), float(math.exp(fit.x[1]))


def ringing_estimate(x, sample_rate_hz, hump=None):
    """The ringing's parameters on ``x`` without the thresholds (the re-estimator's): ``(params,
    rings, component)`` from the hump ``hump`` (:func:`~gyrofilter.analysis.gap.detectors.resonance.resonance_fit`'s,
    fitted here when None) and :func:`ring_fit`; None where there is no event."""
    hump = resonance_fit(x, sample_rate_hz) if hump is None else hump
    rings = None if hump is None else ring_fit(x, sample_rate_hz, hump["center_hz"], hump["q"])
    if rings is None:
        return None
    centre, q = refine_ring(x, sample_rate_hz, rings, hump["center_hz"], hump["q"])
    refit = ring_fit(x, sample_rate_hz, centre, q)
    if refit is not None:
        rings, hump = refit, dict(hump, center_hz=centre, q=q)
    amps = rings["amplitudes_dps"]
    params = {"center_hz": hump["center_hz"], "q": hump["q"], "shock_rate_hz": rings["events"] * sample_rate_hz / x.size,
              "shock_dps": float(np.median(np.abs(amps)))}
    return params, rings, rings.pop("component")


def detect_ringing(x, sample_rate_hz):
    """The ``ringing`` candidate of the module docstring, or None (too short a record: fewer than
    4096 samples; no hump; no rings beyond the spikes)."""
    if x.size < 4096:
        return None
    hump = resonance_fit(x, sample_rate_hz)
    if hump is None or not is_hump(hump, sample_rate_hz) or not hump["q"] < Q_RANGE[1]:
        return None
    found = ringing_estimate(x, sample_rate_hz, hump)
    if found is None:
        return None
    params, rings, component = found
    if rings["events"] < OUTLIER_MIN_COUNT or not rings["statistic"] > RINGING_THRESHOLD:
        return None
    centre, q, shock = params["center_hz"], params["q"], params["shock_dps"]
    return Candidate(
        effect=RINGING,
        params=params,
        statistic=rings["statistic"],
        threshold=RINGING_THRESHOLD,
        statistic_name="energy the rings explain beyond isolated spikes, in noise variances",
        evidence=(f"{rings['events']} shocks that ring at {centre:.4g} Hz (Q = {q:.2g}, decaying in "
                  f"{q / (math.pi * centre):.2g} s), median peak {shock:.3g} deg/s: their rings explain "
                  f"{rings['statistic']:.0f} noise variances beyond isolated spikes (threshold {RINGING_THRESHOLD:g}), "
                  f"and the series through the resonator has an excess kurtosis of {rings['band_kurtosis']:+.1f} "
                  f"(a hump of Gaussian noise: 0); "
                  f"the spikes and the hump of power at {centre:.4g} Hz are one cause"),
        component=component,
    )
