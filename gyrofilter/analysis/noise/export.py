"""Export of the noise coefficients: the allan JSON (docs/formats.md, section 4) and Kalibr's imu.yaml.
"""
from __future__ import annotations

import math

from ...effects import BIAS_INSTABILITY, RATE_RAMP, RATE_RANDOM_WALK
from .model import ANGLE_RANDOM_WALK, CUSTOMARY_UNIT, QUANTIZATION, TERMS, TERM_SYMBOL, AxisNoise, Coefficient, convert
from ..gap.detectors.repeats import repeats_warning
from ...inputs import json_string
from ...units import utf8_text

#: JSON key of each coefficient (docs/formats.md, section 4), in its base unit
JSON_KEY = {QUANTIZATION: "quantization_deg", ANGLE_RANDOM_WALK: "arw_dps_per_sqrt_hz",
            BIAS_INSTABILITY: "bias_instability_dps", RATE_RANDOM_WALK: "rrw_dps_per_sqrt_s",
            RATE_RAMP: "rate_ramp_dps_per_s"}
#: the units of JSON_KEY (rate_ramp_dps_per_s is deg/s per s = deg/s^2)
JSON_UNIT = {QUANTIZATION: "deg", ANGLE_RANDOM_WALK: "deg/s/sqrt(Hz)", BIAS_INSTABILITY: "deg/s",
             RATE_RANDOM_WALK: "deg/s/sqrt(s)", RATE_RAMP: "deg/s/s"}


def _coef_json(c: Coefficient):
    if c.value is None:
        return None
    return {"value": c.value, "low": c.low, "high": c.high}


def _details_json(c: Coefficient, model_value=None):
    d = {"symbol": TERM_SYMBOL[c.term], "unit": JSON_UNIT[c.term], "resolved": c.resolved,
         "value": c.value, "low": c.low, "high": c.high, "upper_bound": c.upper, "tau_s": c.tau_s}
    if model_value is not None:
        d["model_value"] = model_value
    cu = CUSTOMARY_UNIT[c.term]
    d["customary"] = {"unit": cu, "value": convert(c.value, c.term, cu), "low": convert(c.low, c.term, cu),
                      "high": convert(c.high, c.term, cu), "upper_bound": convert(c.upper, c.term, cu)}
    if c.note:
        d["note"] = c.note
    return d


def to_json(results, sample_rate_hz, *, recording=None, duration_s=None, repeated_rows=None):
    """The ``gyrofilter allan --json`` document (docs/formats.md, section 4) of ``results``
    ({axis name: AxisNoise}, from :func:`characterise`) for a record at ``sample_rate_hz`` (Hz);
    ``recording`` (its name), ``duration_s`` (s) and ``repeated_rows`` (the record's
    :class:`~gyrofilter.analysis.repeats.RepeatedRows`, its block with the warning where it holds more
    repeated rows than chance) are written when given."""
    doc = {"sample_rate_hz": float(sample_rate_hz)}
    if recording is not None:
        doc["recording"] = utf8_text(str(recording))
    if duration_s is not None:
        doc["duration_s"] = float(duration_s)
    any_axis = next(iter(results.values()))
    doc["method"] = {
        "deviation": "overlapping Allan deviation of the rate in deg/s (NIST SP 1065 eq. 11)",
        "coefficients": "weighted non-negative least squares of sigma^2 = 3Q^2/tau^2 + N^2/tau + "
                        "(2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2 over taus with >= 9 clusters",
        "interval": f"{any_axis.confidence:.0%} two-sided: chi-square interval with edf = 2 c^2 / var(c^2), "
                    "var from cov = G C G' of the linear fit (C: Allan-variance covariance from the NIST SP "
                    "1065 Table 5 EDFs and the Allan transfer function), times the fit's reduced chi-square "
                    "where it exceeds 1 (fit_reduced_chi2: the misfit widens every interval and bound by "
                    "its square root); low/high bound the value",
        "curve_interval": f"adev_low_dps/adev_high_dps: {any_axis.confidence:.0%} chi-square interval of each "
                          "point (NIST SP 1065 eq. 41, EDF for the fitted noise mixture); paper000_relative_error: "
                          "1/sqrt(2 (N/m - 1))",
        "null": "not resolved by the data (fitted to zero, or within its uncertainty of zero; then dropped "
                "from the fit); see details.<key>.upper_bound",
        "readoff": "slope read-offs of papers 000/002 (readoff.<key>): the curve at one tau, where every term adds "
                   "to it, so each is an upper estimate of its term; another estimator than the fit, for comparison",
        "units": {JSON_KEY[t]: JSON_UNIT[t] for t in TERMS},
    }
    doc["axes"] = {}
    for name, r in results.items():
        ax = {"tau_s": r.tau_s.tolist(), "adev_dps": r.adev.tolist(),
              "adev_low_dps": r.ci_low.tolist(), "adev_high_dps": r.ci_high.tolist(),
              "paper000_relative_error": [None if not math.isfinite(v) else v for v in r.simple_rel.tolist()],
              "n_clusters": r.n_clusters.tolist(), "edf": r.edf.tolist(),
              "coefficients": {JSON_KEY[t]: _coef_json(r.fitted[t]) for t in TERMS},
              "details": {JSON_KEY[t]: _details_json(r.fitted[t], float(v)) for t, v in zip(TERMS, r.fit_values)},
              "readoff": {JSON_KEY[t]: _details_json(r.readoff[t]) for t in TERMS},
              "kalibr": kalibr_values(r),
              "fit_consistency": r.fit_consistency(), "full_fit_consistency": r.full_fit_consistency(),
              "fit_reduced_chi2": r.fit_reduced_chi2, "fit_dof": r.fit_dof,
              "warnings": list(r.warnings)}
        doc["axes"][name] = ax
    if repeated_rows is not None:
        doc["repeated_rows"] = dict(repeated_rows.as_dict(), warning=repeats_warning(repeated_rows))
    return doc


def kalibr_values(r: AxisNoise):
    """Kalibr's continuous-time ``gyroscope_noise_density`` (rad/s/sqrt(Hz)) = N and
    ``gyroscope_random_walk`` (rad/s^2/sqrt(Hz)) = K for one axis. When K is not resolved its
    upper bound is used (stated in ``random_walk_is_upper_bound``); B is *not* K. ``r``: the
    axis's AxisNoise."""
    n = r.fitted[ANGLE_RANDOM_WALK]
    k = r.fitted[RATE_RANDOM_WALK]
    nd = n.value if n.value is not None else n.upper
    rw = k.value if k.value is not None else k.upper
    return {"gyroscope_noise_density": convert(nd, ANGLE_RANDOM_WALK, "rad/s/sqrt(Hz)"),
            "gyroscope_random_walk": convert(rw, RATE_RANDOM_WALK, "rad/s^2/sqrt(Hz)"),
            "noise_density_is_upper_bound": n.value is None,
            "random_walk_is_upper_bound": k.value is None}


def kalibr_yaml(results, sample_rate_hz, *, recording=None, rostopic="/imu0"):
    """Kalibr ``imu.yaml`` gyroscope entries: the largest value over the axes (Kalibr takes one
    number for all three), continuous time, SI units. Accelerometer lines are not written (this
    package characterises the gyro only); Kalibr needs them, so fill them in from your own
    accelerometer analysis. ``results``, ``sample_rate_hz`` (Hz) and ``recording`` as for
    :func:`to_json`; ``rostopic``: the IMU topic written. The recording's name goes into a comment
    as a JSON string (:func:`~gyrofilter.inputs.json_string`, also a YAML double-quoted scalar): on
    one line, so that a line end in a file name cannot add a key, and reading back exactly (a
    backslash doubled: a name holding the two characters ``\\n`` is not one holding a line end)."""
    per_axis = {a: kalibr_values(r) for a, r in results.items()}
    nd = max(v["gyroscope_noise_density"] for v in per_axis.values())
    rw = max(v["gyroscope_random_walk"] for v in per_axis.values())
    lines = ["# Kalibr IMU noise model (gyroscope), written by gyrofilter allan",
             f"# recording: {json_string(recording)}" if recording else "# recording: (array)",
             "# continuous-time densities; the maximum over the axes is used:"]
    for a, v in per_axis.items():
        lines.append(f"#   {a}: noise_density {v['gyroscope_noise_density']:.6e} rad/s/sqrt(Hz)"
                     f"{' (upper bound)' if v['noise_density_is_upper_bound'] else ''}, random_walk "
                     f"{v['gyroscope_random_walk']:.6e} rad/s^2/sqrt(Hz)"
                     f"{' (upper bound: K not resolved)' if v['random_walk_is_upper_bound'] else ''}")
    lines += ["# Kalibr recommends inflating these for real-world conditions (e.g. x10 for the random walk).",
              "# accelerometer_noise_density and accelerometer_random_walk: not estimated here",
              f"gyroscope_noise_density: {nd:.6e}   # rad/s/sqrt(Hz)",
              f"gyroscope_random_walk: {rw:.6e}   # rad/s^2/sqrt(Hz)",
              f"rostopic: {rostopic}",
              f"update_rate: {float(sample_rate_hz):g}   # Hz", ""]
    return "\n".join(lines)
