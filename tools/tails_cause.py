"""What makes a wandering tone's axis lighter-tailed than its extended model (issue 36, the
ADIS16405 z axes): the tail statistic's fourth moments split by band, the causes tried as
variants of the model's runs, and D with the one that reproduces the record.

    python tools/tails_cause.py --adis DIR [--records adis16405_static_2,adis16405_static_3]
                                [--sims 4] [--streams 0,1,2,3,4]

For every axis on which ``analyse_gap`` (the command's defaults, no intervals) names a
``wandering_tone``, on the residual ``u`` of the tail statistic
(:func:`gyrofilter.analysis.gap.detectors.tail_residual`, scaled to unit variance):

* ``stat``: the tail statistic (:func:`gyrofilter.analysis.gap.detectors.tails_statistic`);
  ``kurt``: the excess kurtosis of ``u``; ``tone``: the share of ``u``'s variance within 3 Hz of
  the tone's centre;
* its fourth moment split between ``L``, ``u`` below 0.7 times the tone's centre (no tone there),
  and ``H``, the rest (the tone and everything above): ``E u^4 = E L^4 + 4 E L^3 H + 6 E L^2 H^2
  + 4 E L H^3 + E H^4``. For a sum of independent terms whose spectra each lie in one of the two
  bands, or a Gaussian process whatever its spectrum, the cross terms are
  ``6 cum(L, L, H, H) = 6 (E L^2 H^2 - E L^2 E H^2) = 0`` and ``4 E L H^3 = 0`` (up to
  the spread of the runs): a departure says that the low band's noise and the rest are not
  independent;
* finer, H split into ``T``, the tone's band (within 3 Hz of its centre), and ``R``, above it:
  ``6 cum(T, T, R, R)`` and ``6 cum(L, L, R, R)`` (below 0 where R's power rises as the other's
  falls), R's own fourth cumulant ``E R^4 - 3 (E R^2)^2`` (above 0 where R's power comes in
  bursts), and the terms of all three, ``12 (E L T^2 R + E L T R^2)``: 0 unless the bands are
  locked in phase, R holding components at sums and differences of T's and L's frequencies
  (intermodulation: a product of the tone and the noise, as a nonlinear transfer makes).

The same for ``--sims`` runs of the extended model the analysis wrote, less the ``compression`` it
may hold (seeds 0, 1, ...), and
for its variants: the tone's amplitude 10 % higher (more tone in ``u``), the tone's excursion
found (:func:`gyrofilter.analysis.gap.detectors.tone_excursion`; with ``tools/tone_modulation.py``'s
``with_excursion``), no quantization, and a **cubic compression** of the rate about its slow
level ``l`` (the series less the tail statistic's high pass, ``e = x - l``):

    y = l + g (e - gamma e^3),   g = sd(e) / sd(e - gamma e^3)

(an odd, saturating transfer; g keeps the rate's variance, so the spectrum moves by
``O(gamma^2)``), applied before the quantizer: the run is drawn without the model's quantization,
compressed, then rounded to the model's step (compressing a quantized run and rounding it again
would put most samples back where they were); ``gamma`` (deg/s)^-2 fitted so that the runs'
mean tail statistic equals the record's (linear interpolation over 0.01-0.05). The compression is
applied to the runs here as a trial (the simulator's ``compression`` term, which ``gap`` now fits,
compresses the fast terms about the slow level before the quantizer as well). The record's other axes are the
control: the same ``gamma`` applied to their runs.

Then D of the tone's axis (:func:`gyrofilter.analysis.gap.features.discrepancy`, the mean
squared z-score over the features) against 6 runs of the extended model drawn as ``gap``'s from
each of ``--streams`` (``analyse_gap(seed=K)``'s, gap's own being 0), without and with the
fitted compression; the runs' spread is not pooled with the baseline's as ``gap`` pools it, so
D without reads close to, not exactly, ``gap``'s D after (docs/gap.md, "How stable").
"""
from __future__ import annotations

import argparse
import copy
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from gyrofilter.effects import WANDERING_TONE  # noqa: E402

#: the compressions over which gamma (deg/s)^-2 is interpolated
GAMMAS = (0.0, 0.01, 0.02, 0.03, 0.04, 0.05)
#: L is u below this fraction of the tone's centre
LOW_FRACTION = 0.7
#: the tone's share of u: within this many Hz of its centre
TONE_HALF_WIDTH_HZ = 3.0


def band(x, sample_rate_hz, lo_hz, hi_hz):
    """``x`` with its DFT bins outside [lo_hz, hi_hz] set to 0."""
    spec = np.fft.rfft(x)
    f = np.fft.rfftfreq(x.size, 1.0 / sample_rate_hz)
    spec[(f < lo_hz) | (f > hi_hz)] = 0.0
    return np.fft.irfft(spec, x.size)


def moments(x, sample_rate_hz, center_hz):
    """The columns of the moments' table for the series ``x`` (module docstring)."""
    from gyrofilter.analysis.gap.detectors import tail_residual, tails_statistic

    u = tail_residual(np.array(x, dtype=float), sample_rate_hz)
    stat = tails_statistic(x, sample_rate_hz, u=u)
    u = u / u.std()
    low = band(u, sample_rate_hz, 0.0, LOW_FRACTION * center_hz)
    high = u - low
    tone = band(u, sample_rate_hz, center_hz - TONE_HALF_WIDTH_HZ, center_hz + TONE_HALF_WIDTH_HZ)
    above = high - tone

    def pair(a, b):
        return 6.0 * float(np.mean(a * a * b * b) - a.var() * b.var())

    return {"stat": stat, "kurt": float(np.mean(u ** 4) - 3.0), "tone": float(tone.var()),
            "llhh": pair(low, high), "lhhh": 4.0 * float(np.mean(low * high ** 3)),
            "ttrr": pair(tone, above), "llrr": pair(low, above),
            "r4": float(np.mean(above ** 4) - 3.0 * above.var() ** 2),
            "ltr": 12.0 * float(np.mean(low * tone * above * (tone + above)))}


def compressed(x, sample_rate_hz, gamma, step_dps):
    """The unquantized run ``x`` through the cubic compression of the module docstring, then
    rounded to multiples of ``step_dps`` (not where 0)."""
    from gyrofilter.analysis.gap.detectors import highpassed

    if gamma > 0.0:
        e = highpassed(x, sample_rate_hz)[0]
        y = e - gamma * e ** 3
        y *= e.std() / y.std()
        x = y + (x - e)
    return np.round(x / step_dps) * step_dps if step_dps > 0 else x


def without_quantization(spec):
    """The model ``spec`` without its quantizer (``lsb_per_dps`` None)."""
    out = copy.deepcopy(spec)
    out["lsb_per_dps"] = None
    return out


def with_amplitude(spec, axis, factor):
    """The model ``spec`` with the wandering tone of ``axis`` ``factor`` times stronger."""
    out = copy.deepcopy(spec)
    for e in out["axes"][axis]["effects"]:
        if e["effect"] == WANDERING_TONE:
            e["amplitude_dps"] *= factor
    return out


def fitted_gamma(stats_by_gamma, target):
    """gamma where the runs' mean tail statistic (decreasing in gamma) reaches ``target``, by
    linear interpolation over :data:`GAMMAS` (clipped to their range)."""
    means = np.array([np.mean(stats_by_gamma[g]) for g in GAMMAS])
    return float(np.interp(-target, -means, GAMMAS))


def mean_row(rows):
    """The mean of each column of the runs' :func:`moments`."""
    return {k: float(np.mean([r[k] for r in rows])) for k in rows[0]}


def row_text(label, m, spread=None):
    stat = f"{m['stat']:+.4f}" if spread is None else f"{spread[0]:+.4f} to {spread[1]:+.4f}"
    return (f"| {label} | {stat} | {m['kurt']:+.4f} | {m['tone']:.3f} | {m['llhh']:+.4f} | {m['lhhh']:+.4f} "
            f"| {m['ttrr']:+.4f} | {m['llrr']:+.4f} | {m['r4']:+.4f} | {m['ltr']:+.4f} |")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--adis", required=True, help="folder of the ADIS16405 records")
    ap.add_argument("--records", default="adis16405_static_2,adis16405_static_3")
    ap.add_argument("--sims", type=int, default=4)
    ap.add_argument("--streams", default="0,1,2,3,4")
    args = ap.parse_args(argv)

    from tone_modulation import tone_axes, with_excursion, without_compression

    from gyrofilter.analysis.gap.baseline import axis_dps, default_n_sims, simulate_axis
    from gyrofilter.analysis.gap.detectors import tone_excursion
    from gyrofilter.analysis.gap.features import departures, discrepancy, feature_bands, feature_taus, features
    from gyrofilter.sim.model import validate_model

    streams = [int(s) for s in args.streams.split(",")]
    head = ("| run | tail statistic | kurtosis of u | tone's share of u | 6 cum(L, L, H, H) | 4 E L H^3 "
            "| 6 cum(T, T, R, R) | 6 cum(L, L, R, R) | cum4(R) | 12 E L T R (T + R) |\n"
            "|---|---|---|---|---|---|---|---|---|---|")
    d_lines, gamma_lines = [], []
    for name, rec, rep, i, c, s, x in tone_axes(args.adis, args.records):
        fs, n, axis = float(rec.sample_rate_hz), len(rec), "xyz"[i]
        model = without_compression(rep["extended_model"])
        step = 1.0 / model["lsb_per_dps"] if model.get("lsb_per_dps") else 0.0
        bare, _ = validate_model(without_quantization(model))
        meas = moments(x, fs, c)

        def runs(variant, gamma=0.0, k=i):
            vstep = 1.0 / variant["lsb_per_dps"] if variant.get("lsb_per_dps") else 0.0
            vspec, _ = validate_model(without_quantization(variant))
            return [moments(compressed(simulate_axis(vspec, n, fs, seed, k), fs, gamma, vstep), fs, c)
                    for seed in range(args.sims)]

        by_gamma = {g: runs(model, g) for g in GAMMAS}
        gamma = fitted_gamma({g: [r["stat"] for r in rows] for g, rows in by_gamma.items()}, meas["stat"])
        exc = tone_excursion(x, fs, c, s)
        variants = [("extended model", by_gamma[0.0]),
                    ("tone's amplitude x 1.1", runs(with_amplitude(model, axis, 1.1))),
                    ("excursion found" if exc["present"] else "excursion (none found)",
                     runs(with_excursion(model, i, exc)) if exc["present"] else by_gamma[0.0]),
                    ("no quantization", runs(without_quantization(model))),
                    (f"compressed, gamma = {gamma:.3f}", runs(model, gamma))]
        print(f"\n{name}, axis {axis}: wandering tone at {c:.2f} Hz; L: u below {LOW_FRACTION * c:.1f} Hz, "
              f"T: {c - TONE_HALF_WIDTH_HZ:.1f}-{c + TONE_HALF_WIDTH_HZ:.1f} Hz, R: above\n")
        print(head)
        print(row_text("record", meas))
        for label, rows in variants:
            stats = [r["stat"] for r in rows]
            print(row_text(f"runs: {label}", mean_row(rows), (min(stats), max(stats))))
        for k, other in enumerate("xyz"):
            if k == i:
                continue
            rec_o = moments(np.asarray(axis_dps(rec, k), dtype=float), fs, c)["stat"]
            plain = [r["stat"] for r in runs(model, 0.0, k)]
            comp = [r["stat"] for r in runs(model, gamma, k)]
            gamma_lines.append(f"{name} {other}: record {rec_o:+.4f}, runs {min(plain):+.4f} to {max(plain):+.4f}, "
                               f"compressed by gamma = {gamma:.3f}: {min(comp):+.4f} to {max(comp):+.4f}")
        taus, bands = feature_taus(n, fs), feature_bands(n, fs)
        meas_f = features(x, fs, taus, bands)
        ds = {0.0: [], gamma: []}
        for stream in streams:
            seeds = np.random.default_rng(stream).integers(0, 2**31, size=default_n_sims(n))[:6]
            for g in ds:
                sims = [features(compressed(simulate_axis(bare, n, fs, int(seed), i), fs, g, step), fs, taus, bands,
                                 overwrite=True) for seed in seeds]
                ds[g].append(discrepancy(departures(meas_f, sims, n)))
        d_lines.append(f"| {name} | {axis} | {' / '.join(f'{d:.2f}' for d in ds[0.0])} "
                       f"| {gamma:.3f} | {' / '.join(f'{d:.2f}' for d in ds[gamma])} |")
    print("\nthe other axes, the control (tail statistic; runs of the extended model, without and with the tone "
          "axis's compression):\n")
    for line in gamma_lines:
        print(f"- {line}")
    print(f"\nD of the tone's axis against 6 runs of the extended model per stream ({', '.join(map(str, streams))}):\n")
    print("| record | axis | D, extended model | gamma (deg/s)^-2 | D, compressed |\n|---|---|---|---|---|")
    for line in d_lines:
        print(line)


if __name__ == "__main__":
    main()
