"""Export of the noise coefficients: the allan JSON (docs/formats.md, section 4) and Kalibr's imu.yaml.
"""
from __future__ import annotations

import math

from ...effects import BIAS_INSTABILITY, RATE_RAMP, RATE_RANDOM_WALK
from .allan import confidence_text
from .kalibr import ACCELEROMETER, DEFAULT_TAU_RANGE_S, GYROSCOPE, KalibrValues, kalibr_sensor, plain_values
from .model import (ACCELEROMETER_TERMS, ANGLE_RANDOM_WALK, GYROSCOPE_TERMS, QUANTIZATION, TERMS, TERM_SYMBOL, AxisNoise,
                    Coefficient, convert)
from ..gap.detectors.repeats import repeats_warning
from ...inputs import json_string
from ...recording import filtered_from
from ...errors import SettingsError
from ...units import AXES, utf8_text

#: JSON key of each coefficient (docs/formats.md, section 4), in its base unit
JSON_KEY = {QUANTIZATION: "quantization_deg", ANGLE_RANDOM_WALK: "arw_dps_per_sqrt_hz",
            BIAS_INSTABILITY: "bias_instability_dps", RATE_RANDOM_WALK: "rrw_dps_per_sqrt_s",
            RATE_RAMP: "rate_ramp_dps_per_s"}
#: the units of JSON_KEY (rate_ramp_dps_per_s is deg/s per s = deg/s^2)
JSON_UNIT = {QUANTIZATION: "deg", ANGLE_RANDOM_WALK: "deg/s/sqrt(Hz)", BIAS_INSTABILITY: "deg/s",
             RATE_RANDOM_WALK: "deg/s/sqrt(s)", RATE_RAMP: "deg/s/s"}
#: the accelerometer's JSON keys (the document's ``accelerometer`` block) and their units: Q the velocity step,
#: N the velocity random walk (m/s/sqrt(s) = m/s^2/sqrt(Hz)), B, K the acceleration random walk, R its ramp
ACCEL_JSON_KEY = {QUANTIZATION: "quantization_mps", ANGLE_RANDOM_WALK: "vrw_mps2_per_sqrt_hz",
                  BIAS_INSTABILITY: "bias_instability_mps2", RATE_RANDOM_WALK: "accel_rw_mps2_per_sqrt_s",
                  RATE_RAMP: "accel_ramp_mps2_per_s"}
ACCEL_JSON_UNIT = {QUANTIZATION: "m/s", ANGLE_RANDOM_WALK: "m/s^2/sqrt(Hz)", BIAS_INSTABILITY: "m/s^2",
                   RATE_RANDOM_WALK: "m/s^2/sqrt(s)", RATE_RAMP: "m/s^2/s"}


class JsonSensor:
    """How one sensor's axes are written in the allan JSON: ``keys`` and ``units`` of its coefficients,
    ``suffix`` of its curve's keys (``adev_<suffix>``), ``terms`` (its
    :class:`~gyrofilter.analysis.noise.model.SensorTerms`: the customary units) and ``kalibr`` (its
    :class:`~gyrofilter.analysis.noise.kalibr.KalibrSensor`)."""

    def __init__(self, keys, units, suffix, terms, kalibr):
        self.keys, self.units, self.suffix, self.terms, self.kalibr = keys, units, suffix, terms, kalibr


GYRO_JSON = JsonSensor(JSON_KEY, JSON_UNIT, "dps", GYROSCOPE_TERMS, GYROSCOPE)
ACCEL_JSON = JsonSensor(ACCEL_JSON_KEY, ACCEL_JSON_UNIT, "mps2", ACCELEROMETER_TERMS, ACCELEROMETER)


def _coef_json(c: Coefficient):
    if c.value is None:
        return None
    return {"value": c.value, "low": c.low, "high": c.high}


def _details_json(c: Coefficient, model_value=None, sensor=GYRO_JSON):
    d = {"symbol": TERM_SYMBOL[c.term], "unit": sensor.units[c.term], "resolved": c.resolved,
         "value": c.value, "low": c.low, "high": c.high, "upper_bound": c.upper, "tau_s": c.tau_s}
    if model_value is not None:
        d["model_value"] = model_value
    cu = sensor.terms.customary_unit[c.term]
    d["customary"] = {"unit": cu, "value": convert(c.value, c.term, cu), "low": convert(c.low, c.term, cu),
                      "high": convert(c.high, c.term, cu), "upper_bound": convert(c.upper, c.term, cu)}
    if c.note:
        d["note"] = c.note
    return d


def to_json(results, sample_rate_hz, *, recording=None, duration_s=None, repeated_rows=None, accelerometer=None,
            accelerometer_left_out=None, t_gaps=None, warnings=None):
    """The ``gyrofilter allan --json`` document (docs/formats.md, section 4) of ``results``
    ({axis name: AxisNoise}, from :func:`characterise`) for a record at ``sample_rate_hz`` (Hz);
    ``recording`` (its name), ``duration_s`` (s) and ``repeated_rows`` (the record's
    :class:`~gyrofilter.analysis.repeats.RepeatedRows`, its block with the warning where it holds more
    repeated rows than chance) are written when given. ``accelerometer``: the accelerometer's
    {axis name: AxisNoise} (m/s^2), written as the block ``accelerometer`` (its axes as the gyro's, in
    the m/s units of :data:`ACCEL_JSON_KEY`); None: no such block. ``accelerometer_left_out``: why the
    record's accelerometer was left out whole (it does not read gravity, a gross error, every axis
    constant), written as ``accelerometer_left_out``; None: no such key. ``t_gaps``: ``(count, warning)``
    of the steps of ``t`` that span lost samples, written as the block ``t_gaps`` where the count is
    above 0 (the deviation assumes uniform samples: a reader of the document alone must see it).
    ``warnings``: the record's own warnings (sentences: the reader's, gross errors kept, a mean allowed),
    written as the list ``warnings`` when given; an axis's own are its ``warnings``."""
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
        "interval": f"{confidence_text(any_axis.confidence)} two-sided: the test of c^2 inverted with var(c^2) at each "
                    "value (the others' share normal, c's own chi-square with edf = 2 c^2 / var_own), "
                    "var from cov = G C G' of the linear fit (C: Allan-variance covariance from the NIST SP "
                    "1065 Table 5 EDFs and the Allan transfer function), times the fit's reduced chi-square "
                    "where it exceeds 1 (fit_reduced_chi2: the misfit widens every interval and bound by "
                    "its square root); low/high bound the value",
        "curve_interval": f"adev_low_dps/adev_high_dps: {confidence_text(any_axis.confidence)} chi-square interval of each "
                          "point (NIST SP 1065 eq. 41, EDF for the fitted noise mixture); paper000_relative_error: "
                          "1/sqrt(2 (N/m - 1))",
        "null": "not resolved by the data (fitted to zero, or within its uncertainty of zero; then dropped "
                "from the fit); see details.<key>.upper_bound",
        "readoff": "slope read-offs of papers 000/002 (readoff.<key>): the curve at one tau, where every term adds "
                   "to it, so each is an upper estimate of its term; another estimator than the fit, for comparison",
        "units": {JSON_KEY[t]: JSON_UNIT[t] for t in TERMS},
    }
    doc["axes"] = {name: _axis_json(r, GYRO_JSON) for name, r in results.items()}
    if repeated_rows is not None:
        doc["repeated_rows"] = dict(repeated_rows.as_dict(), warning=repeats_warning(repeated_rows))
    if accelerometer is not None:
        doc["accelerometer"] = {
            "deviation": "overlapping Allan deviation of the acceleration in m/s^2 (NIST SP 1065 eq. 11) of the "
                         "mean-removed series: gravity, a constant, does not enter; fit, intervals, null and "
                         "read-offs as the gyro's (method), with velocity in the place of the angle",
            "units": {ACCEL_JSON_KEY[t]: ACCEL_JSON_UNIT[t] for t in TERMS},
            "axes": {name: _axis_json(r, ACCEL_JSON) for name, r in accelerometer.items()}}
    if accelerometer_left_out is not None:
        doc["accelerometer_left_out"] = utf8_text(str(accelerometer_left_out))
    if t_gaps is not None and t_gaps[0] > 0:
        doc["t_gaps"] = {"count": int(t_gaps[0]), "warning": utf8_text(str(t_gaps[1]))}
    if warnings is not None:
        doc["warnings"] = [utf8_text(str(w)) for w in warnings]
    return doc


def _axis_json(r, sensor):
    """One axis ``r`` (an AxisNoise) of the allan JSON, its keys those of ``sensor`` (a :class:`JsonSensor`)."""
    keys, suffix = sensor.keys, sensor.suffix
    return {"tau_s": r.tau_s.tolist(), f"adev_{suffix}": r.adev.tolist(),
            f"adev_low_{suffix}": r.ci_low.tolist(), f"adev_high_{suffix}": r.ci_high.tolist(),
            "paper000_relative_error": [None if not math.isfinite(v) else v for v in r.simple_rel.tolist()],
            "n_clusters": r.n_clusters.tolist(), "edf": r.edf.tolist(),
            "coefficients": {keys[t]: _coef_json(r.fitted[t]) for t in TERMS},
            "details": {keys[t]: _details_json(r.fitted[t], float(v), sensor) for t, v in zip(TERMS, r.fit_values)},
            "readoff": {keys[t]: _details_json(r.readoff[t], sensor=sensor) for t in TERMS},
            "kalibr": kalibr_values(r, sensor.kalibr),
            "fit_consistency": r.fit_consistency(), "full_fit_consistency": r.full_fit_consistency(),
            "fit_reduced_chi2": r.fit_reduced_chi2, "fit_dof": r.fit_dof,
            "warnings": list(r.warnings)}


def kalibr_values(r: AxisNoise, sensor=GYROSCOPE):
    """The ``kalibr`` block of one axis ``r`` (an AxisNoise) in the allan JSON: Kalibr's plain
    ``gyroscope_noise_density`` (rad/s/sqrt(Hz)) = N and ``gyroscope_random_walk``
    (rad/s^2/sqrt(Hz)) = K, with their upper-bound flags (:func:`~gyrofilter.analysis.noise.kalibr.plain_values`);
    for ``sensor`` :data:`~gyrofilter.analysis.noise.kalibr.ACCELEROMETER` the ``accelerometer_`` keys in
    m/s^2/sqrt(Hz) and m/s^3/sqrt(Hz)."""
    v = plain_values(r, sensor)
    return {f"{sensor.name}_noise_density": v["noise_density"], f"{sensor.name}_random_walk": v["random_walk"],
            "noise_density_is_upper_bound": v["noise_density_is_upper_bound"],
            "random_walk_is_upper_bound": v["random_walk_is_upper_bound"]}


def _e(value):
    return "-" if value is None else f"{value:.6e}"


def _times(factor):
    return "-" if factor is None else f"x{factor:.3g}"


#: the end of a key's comment whose value is the record's bound (KalibrValues.held)
_RECORD_BOUND = ", the record's bound"


def _sensor_lines(k: KalibrValues, confidence):
    """The comment lines and the two keys of one sensor's :class:`~gyrofilter.analysis.noise.kalibr.KalibrValues`."""
    name, s, b = k.sensor.name, k.sensor, k.bound
    lines = [f"# {name}, plain values per axis (the fit's N and K; B is not Kalibr's random walk):"]
    for a, v in k.per_axis.items():
        lines.append(f"#   {a}: noise_density {_e(v['noise_density'])} {s.density_unit}"
                     f"{' (upper bound)' if v['noise_density_is_upper_bound'] else ''}, random_walk "
                     f"{_e(v['random_walk'])} {s.walk_unit}"
                     f"{' (upper bound: K not resolved)' if v['random_walk_is_upper_bound'] else ''}")
    f_nd, f_rw = k.factors()
    touch = ", ".join(f"{t:.3g}" for t in b.touch_tau_s)
    upper = "" if b.upper_ratio is None else f", at least {b.upper_ratio:.3g}x its {confidence_text(confidence)} upper confidence bound"
    lines += [f"# {name}, plain (largest over the axes): noise_density {_e(k.plain[0])}, random_walk {_e(k.plain[1])}",
              f"# {name}, bounding pair over tau {k.tau_range_s[0]:g} .. {k.tau_range_s[1]:g} s ({len(b.tau_s)} taus): "
              f"its model lies at {b.least:.3g} .. {b.excess:.3g}x the largest",
              f"#   axis's Allan deviation ({b.least:.3g} at tau {touch} s){upper}",
              *(f"# {name}_{key}: {held}" for key, held in zip(("noise_density", "random_walk"), k.held_texts()) if held),
              f"{name}_noise_density: {k.noise_density:.6e}   # {s.density_unit}, bounding (plain {_times(f_nd)}"
              f"{_RECORD_BOUND if k.held[0] is not None else ''})",
              f"{name}_random_walk: {k.random_walk:.6e}   # {s.walk_unit}, bounding (plain {_times(f_rw)}"
              f"{_RECORD_BOUND if k.held[1] is not None else ''})"]
    return lines


def kalibr_yaml(results, sample_rate_hz, *, recording=None, rostopic="/imu0", tau_range_s=None, accelerometer=None,
                header=None, warnings=()):
    """Kalibr ``imu.yaml``: one white + random-walk pair per sensor (Kalibr takes one pair for all
    three axes), continuous time, SI units. The values written are the **bounding** pair of
    :func:`~gyrofilter.analysis.noise.kalibr.bounding_pair` over ``tau_range_s`` ((low, high) in s;
    None: 0.1-100 s cut to the record), whose model lies on or above every axis's measured Allan
    deviation there; the plain values (the fit's N and K per axis and their largest) and the
    factor between the two are comments. ``results``: the gyroscope's {axis: AxisNoise} (deg/s);
    ``accelerometer``: the accelerometer's (m/s^2), or None: then its keys are not written and a
    comment says so. ``sample_rate_hz`` (Hz) and ``recording`` as for :func:`to_json`;
    ``rostopic``: the IMU topic written. The recording's name goes into a comment as a JSON
    string (:func:`~gyrofilter.inputs.json_string`, also a YAML double-quoted scalar): on one
    line, so that a line end in a file name cannot add a key, and reading back exactly (a
    backslash doubled: a name holding the two characters ``\\n`` is not one holding a line end).
    Raises SettingsError for a ``tau_range_s`` outside a record's taus (:func:`~gyrofilter.analysis.noise.kalibr.tau_range`).

    ``header``: the recording's header; one that is the filter's output (``filtered_from``: block
    means of bias-removed rates, 1/L of the rate) raises SettingsError: its noise is not the
    sensor's (a new user's yaml said 3.8e-7 rad/s/sqrt(Hz) for the sensor's 2.4e-4). What would
    make the values wrong goes into the yaml, beside them: the axes of a sensor not analysed and
    every warning of the analysis (``warnings``: the recording's sentences, e.g. an axis left out
    or an acceleration that moves; and each axis result's own), one comment line each."""
    source = None if header is None else filtered_from(header)
    if source is not None:
        raise SettingsError(f"--kalibr: {json_string(recording) if recording else 'the recording'} is the filter's output (filtered_from: "
                            f"{json_string(source)}), not the sensor's samples: Kalibr's noise model "
                            "describes the sensor; give the recording it was made from")
    sensors = [kalibr_sensor(results, "deg/s", tau_range_s)]
    if accelerometer is not None:
        sensors.insert(0, kalibr_sensor(accelerometer, "m/s^2", tau_range_s))
    confidence = next(iter(results.values())).confidence
    low, high = DEFAULT_TAU_RANGE_S
    lines = ["# Kalibr IMU noise model, written by gyrofilter allan",
             f"# recording: {json_string(recording)}" if recording else "# recording: (array)",
             "# continuous-time densities, SI units. Written: the bounding pair, the white + random-walk pair whose",
             "# Kalibr model sigma^2(tau) = nd^2/tau + rw^2 tau/3 lies on or above the measured Allan deviation of",
             "# every axis over the range, with the least largest excess over it (docs/allan.md, \"Kalibr\"). The",
             "# plain values, the fit's N and K, are too optimistic where bias instability lifts the curve; they",
             "# are the pair's floor."]
    for k in sensors:
        if k.cut:
            lines.append(f"# {k.sensor.name}: the default range {low:g} .. {high:g} s cut to the record's "
                         f"{k.tau_range_s[0]:g} .. {k.tau_range_s[1]:g} s; a longer record covers longer times")
    if accelerometer is None:
        lines.append("# accelerometer_noise_density and accelerometer_random_walk: not estimated here")
    for name, sensor in (("gyroscope", results), ("accelerometer", accelerometer)):
        if sensor is not None and tuple(sensor) != AXES:
            lines.append(f"# {name}: only axes {', '.join(sensor)} analysed (of {', '.join(AXES)}): the values bound those")
    said = list(dict.fromkeys([*warnings, *(f"{name}: {w}" for name, sensor in (("gyroscope", results),
                                                                               ("accelerometer", accelerometer or {}))
                                            for r in sensor.values() for w in r.warnings)]))
    lines += [f"# warning: {' '.join(str(w).split())}" for w in said]
    for k in sensors:
        lines += _sensor_lines(k, confidence)
    lines += [f"rostopic: {rostopic}", f"update_rate: {float(sample_rate_hz):g}   # Hz", ""]
    return "\n".join(lines)
