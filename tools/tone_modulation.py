"""What a named wandering tone still misses: is the power beside the tone's band modulated in time?

    python tools/tone_modulation.py --adis DIR [--sims 4] [--records adis16405_static_2,adis16405_static_3]

For every axis on which ``analyse_gap`` (the command's defaults, no intervals) names a
``wandering_tone``, the band beside the tone, the flanks ``[lo - w, lo)`` and ``(hi, hi + w]``
of the tone's band ``[lo, hi]`` = centre +- 3.5 spread (``w = 2 (hi - lo)``, clipped to
(0, f_s / 2)), is cut out of the series by its DFT bins, and:

* its excess kurtosis ``mean y^4 / (mean y^2)^2 - 3`` (0 for Gaussian noise, whatever its spectrum;
  above 0 where the band's power comes and goes);
* the envelope's strongest period: the flank power averaged over 0.1-s blocks, its periodogram
  over 0.01-2 Hz, the largest ordinate over the median ordinate (a stationary Gaussian band gives
  ``ln(K) / ln 2`` on average over K ordinates, about 14 here) and its period;

* the tail statistic of the whole axis (:func:`gyrofilter.analysis.gap.detectors.tails_statistic`,
  the feature that departs);
* on the record, the tone's band folded on that period: its power per twentieth of the cycle over
  its median, the least (how much of the band's power the excursion takes) and the share of the
  cycle below 0.9 of the median;

the same (but the folding) for ``--sims`` runs of the extended model the analysis wrote (seeds 0, 1, ...), which
holds the tone with its Gauss-Markov wander and no modulation. A flank whose kurtosis and
envelope line stand far outside the runs' is power the tone's model does not hold: an excursion
of the tone that returns with a period (docs/gap.md, "A tone whose frequency wanders").
"""
from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

#: the envelope's block (s) and the band of modulation frequencies (Hz) searched
ENVELOPE_BLOCK_S = 0.1
MODULATION_HZ = (0.01, 2.0)
#: the tone's band: its centre +- this many spreads (the detector's TONE_TRACK_SDS)
TONE_SDS = 3.5


def flank_statistics(x, sample_rate_hz, lo_hz, hi_hz):
    """(excess kurtosis, envelope line ratio, its period in s, the ordinates K searched) of the
    flanks of ``[lo_hz, hi_hz]`` in ``x`` (module docstring)."""
    n = x.size
    w = 2.0 * (hi_hz - lo_hz)
    f = np.fft.rfftfreq(n, 1.0 / sample_rate_hz)
    spec = np.fft.rfft(x - x.mean())
    keep = ((f >= max(lo_hz - w, 0.0)) & (f < lo_hz)) | ((f > hi_hz) & (f <= min(hi_hz + w, sample_rate_hz / 2)))
    y = np.fft.irfft(np.where(keep, spec, 0.0), n)
    v = float(np.mean(y * y))
    kurt = float(np.mean(y ** 4) / v ** 2 - 3.0)
    block = max(1, int(round(ENVELOPE_BLOCK_S * sample_rate_hz)))
    env = (y[: n // block * block] ** 2).reshape(-1, block).mean(axis=1)
    env -= env.mean()
    p = np.abs(np.fft.rfft(env)) ** 2
    fe = np.fft.rfftfreq(env.size, block / sample_rate_hz)
    sel = (fe >= MODULATION_HZ[0]) & (fe <= MODULATION_HZ[1])
    j = int(np.argmax(p[sel]))
    return kurt, float(p[sel][j] / np.median(p[sel])), float(1.0 / fe[sel][j]), int(sel.sum())


def tails(x, sample_rate_hz):
    """The gap analysis' tail statistic of ``x``."""
    from gyrofilter.analysis.gap.detectors import tail_residual, tails_statistic

    return tails_statistic(x, sample_rate_hz, u=tail_residual(x, sample_rate_hz))


def folded_band(x, sample_rate_hz, lo_hz, hi_hz, period_s, bins=20):
    """(least power of ``[lo_hz, hi_hz]`` over its median, share of the cycle below 0.9 of the
    median) of the band's power folded on ``period_s`` in ``bins`` phases."""
    n = x.size
    f = np.fft.rfftfreq(n, 1.0 / sample_rate_hz)
    spec = np.fft.rfft(x - x.mean())
    y = np.fft.irfft(np.where((f >= lo_hz) & (f <= hi_hz), spec, 0.0), n)
    phase = ((np.arange(n) / sample_rate_hz / period_s) % 1.0 * bins).astype(int)
    prof = np.bincount(phase, y * y, bins) / np.bincount(phase, None, bins)
    prof /= np.median(prof)
    return float(prof.min()), float(np.mean(prof < 0.9))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--adis", required=True, help="folder of the ADIS16405 records")
    ap.add_argument("--records", default="adis16405_static_2,adis16405_static_3")
    ap.add_argument("--sims", type=int, default=4)
    args = ap.parse_args(argv)

    from gyrofilter.analysis.gap.baseline import axis_dps, simulate_axis
    from gyrofilter.analysis.gap.pipeline import analyse_gap
    from gyrofilter.recording import read_recording
    from gyrofilter.sim.model import validate_model

    print("| record | axis | tone (centre, spread) | flanks | kurtosis: record / model runs | envelope line: record (period) / model runs "
          "| tone's band on that period: least power, cycle below 0.9 | tail statistic: record / model runs |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.records.split(","):
        rec = read_recording(os.path.join(args.adis, f"{name}.csv.gz"))
        fs = float(rec.sample_rate_hz)
        rep = analyse_gap(rec, bootstrap=0)
        spec, _ = validate_model(rep["extended_model"])
        for finding in rep["findings"]:
            if finding["effect"] != "wandering_tone":
                continue
            axis = finding["axis"]
            i = "xyz".index(axis)
            c, s = finding["params"]["center_hz"], finding["params"]["spread_hz"]
            lo, hi = c - TONE_SDS * s, c + TONE_SDS * s
            x = np.asarray(axis_dps(rec, i), dtype=float)
            k, ratio, period, ordinates = flank_statistics(x, fs, lo, hi)
            least, below = folded_band(x, fs, lo, hi, period)
            t_rec = tails(x, fs)
            runs = []
            for seed in range(args.sims):
                y = simulate_axis(spec, len(rec), fs, seed, i)
                runs.append(flank_statistics(y, fs, lo, hi)[:2] + (tails(y, fs),))
            ks, rs, ts = [r[0] for r in runs], [r[1] for r in runs], [r[2] for r in runs]
            w = 2.0 * (hi - lo)
            print(f"| {name} | {axis} | {c:.2f} Hz, {s:.2f} Hz | {max(lo - w, 0):.1f}-{lo:.1f} and {hi:.1f}-{min(hi + w, fs / 2):.1f} Hz "
                  f"| {k:+.2f} / {min(ks):+.3f} to {max(ks):+.3f} | {ratio:.0f} ({period:.2f} s) / {min(rs):.0f} to {max(rs):.0f} "
                  f"| {least:.2f}, {below:.0%} | {t_rec:+.4f} / {min(ts):+.4f} to {max(ts):+.4f} |")
    print(f"\nmodel runs: {args.sims} simulations of the extended model the analysis wrote (its tone's wander "
          f"Gauss-Markov); a stationary Gaussian band's envelope line is about ln(K)/ln 2 = "
          f"{math.log(ordinates) / math.log(2):.0f} on average over the K = {ordinates} ordinates of the last record")


if __name__ == "__main__":
    main()
