"""Does a spectral line with a width close the gap on an axis? D of the gap's extended model with
and without a ``narrowband`` term estimated from the spectrum.

    python tools/gap_narrowband.py RECORDING AXIS [--seed 0] [--sims 12]

Runs ``analyse_gap`` on RECORDING, estimates the strongest band of AXIS (x, y or z) from the Welch
PSD (:func:`gyrofilter.analysis.gap.detectors.band_estimate`) and prints the gap's discrepancy D (docs/gap.md) against the recording,
from the same simulation seeds, of: the extended model; the extended model plus the band as a
``narrowband`` effect, white noise reduced to keep the per-sample variance (N'² = N² - rms² / f_s);
and the same with the white level read off the Allan deviation at τ = 1 s (N = σ(1 s), IEEE Std
952-1997 C.1) and a ``colored_noise`` term switched to ``preserve: arw`` (so N is the long-τ level);
and that with the colored noise's lag1 re-solved so that noise plus line have the measured lag-1
autocorrelation (:func:`with_narrowband`).
The gap now proposes ``narrowband`` itself (:func:`gyrofilter.analysis.gap.detectors.detect_narrowband`); this
tool measures the steps one by one.
"""
from __future__ import annotations

import argparse
import copy
import math

from gyrofilter.analysis.gap.detectors import band_estimate, narrowband_lags


def with_narrowband(model, axis, band, arw_dps_per_sqrt_hz=None, lag1=None):
    """A copy of ``model`` with the band added to ``axis`` as a ``narrowband`` effect. White noise:
    without ``arw_dps_per_sqrt_hz`` reduced to keep the per-sample variance (N'² = N² - rms² / f_s,
    floor 0); with it, set to it and any ``colored_noise`` of the axis switched to ``preserve: arw``.
    With ``lag1`` (the measured lag-1 autocorrelation) as well, the colored noise's ρ is re-solved
    so that the sum of the colored noise and the line has that lag-1 autocorrelation:
    r₁ (v_c + rms²) = ρ v_c + r_L rms², v_c = N² f_s (1 - ρ)/(1 + ρ) (the ``preserve: arw``
    variance), r_L = φ₁ / (1 - φ₂) the line's lag-1 autocorrelation (AR(2), Box & Jenkins eq. 3.2.26)."""
    out = copy.deepcopy(model)
    spec = out["axes"][axis]
    fs = out["sample_rate_hz"]
    if arw_dps_per_sqrt_hz is None:
        spec["arw_dps_per_sqrt_hz"] = math.sqrt(max(spec["arw_dps_per_sqrt_hz"] ** 2 - band["rms_dps"] ** 2 / fs, 0.0))
    else:
        spec["arw_dps_per_sqrt_hz"] = float(arw_dps_per_sqrt_hz)
        for eff in spec.get("effects", []):
            if eff["effect"] == "colored_noise":
                eff["preserve"] = "arw"
                if lag1 is not None:
                    eff["lag1"] = _colored_lag1(lag1, arw_dps_per_sqrt_hz, fs, band, eff["lag1"])
    spec.setdefault("effects", []).append({"effect": "narrowband", "center_hz": band["center_hz"],
                                           "bandwidth_hz": band["bandwidth_hz"], "rms_dps": band["rms_dps"]})
    return out


def _colored_lag1(r1, arw_dps_per_sqrt_hz, fs, band, current):
    """ρ of :func:`with_narrowband`'s lag-1 equation (``current`` when it has no root in (-0.99, 0.99))."""
    from scipy.optimize import brentq

    r_line = narrowband_lags(band["center_hz"], band["bandwidth_hz"], fs)[0]
    v_line = band["rms_dps"] ** 2

    def excess(rho):
        v_c = arw_dps_per_sqrt_hz**2 * fs * (1.0 - rho) / (1.0 + rho)
        return rho * v_c + r_line * v_line - r1 * (v_c + v_line)

    lo, hi = -0.99, 0.99
    if excess(lo) * excess(hi) > 0:
        return current
    return float(brentq(excess, lo, hi))


def axis_discrepancy(x_dps, sample_rate_hz, models, axis_index, seeds):
    """The gap's D (:func:`gyrofilter.analysis.gap.features.discrepancy`) of each model's axis against ``x_dps``,
    every model simulated with the same ``seeds``. Returns a list of floats."""
    import numpy as np

    from gyrofilter.analysis.gap import features as gap_features
    from gyrofilter.sim.model import validate_model
    from gyrofilter.sim.simulate import simulate_axis_dps

    n = x_dps.size
    taus, bands = gap_features.feature_taus(n, sample_rate_hz), gap_features.feature_bands(n, sample_rate_hz)
    meas = gap_features.features(x_dps, sample_rate_hz, taus, bands)
    out = []
    for model in models:
        spec = validate_model(model)[0]
        sims = [gap_features.features(np.concatenate(list(simulate_axis_dps(spec, n / sample_rate_hz, axis_index, seed=int(s),
                                                                   validated=spec)))[:n], sample_rate_hz, taus, bands)
                for s in seeds]
        out.append(gap_features.discrepancy(gap_features.departures(meas, sims, n)))
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("recording")
    p.add_argument("axis", choices=["x", "y", "z"])
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--sims", type=int, default=12)
    args = p.parse_args(argv)

    import numpy as np

    from gyrofilter.analysis.noise.allan import overlapping_adev
    from gyrofilter.analysis.gap.pipeline import analyse_gap
    from gyrofilter.recording import read_recording

    rec = read_recording(args.recording)
    i = "xyz".index(args.axis)
    rep = analyse_gap(rec, seed=args.seed)
    x = np.asarray(rec.gyro_dps[:, i], dtype=float)
    band = band_estimate(x, rec.sample_rate_hz)
    ext = rep["extended_model"]
    seeds = range(5000 + args.seed, 5000 + args.seed + args.sims)
    n_1s = float(overlapping_adev(x, rec.sample_rate_hz, [1.0])[1][0])
    xc = x - x.mean()
    r1 = float(np.einsum("i,i->", xc[1:], xc[:-1]) / np.einsum("i,i->", xc, xc))
    models = [ext, with_narrowband(ext, args.axis, band), with_narrowband(ext, args.axis, band, n_1s),
              with_narrowband(ext, args.axis, band, n_1s, r1)]
    d_ext, d_nb, d_nb_arw, d_nb_lag = axis_discrepancy(x, rec.sample_rate_hz, models, i, seeds)
    print(f"{args.recording} {args.axis}: gap D {rep['discrepancy']['before'][args.axis]:.2f} -> "
          f"{rep['discrepancy']['after'][args.axis]:.2f} (findings: "
          f"{', '.join(f['effect'] for f in rep['findings'] if f['axis'] == args.axis) or 'none'})")
    print(f"band: centre {band['center_hz']:.2f} Hz, half-power width {band['bandwidth_hz']:.2f} Hz, "
          f"rms {band['rms_dps']:.4g} deg/s, peak {band['peak_ratio']:.1f} x background")
    print(f"D with {args.sims} simulations: extended {d_ext:.2f}; + narrowband {d_nb:.2f}; "
          f"+ narrowband with N = sigma(1 s) = {n_1s:.4g} deg/s/sqrt(Hz) {d_nb_arw:.2f}; "
          f"and the colored noise's lag1 re-solved for the measured {r1:.3f}: {d_nb_lag:.2f}")


if __name__ == "__main__":
    main()
