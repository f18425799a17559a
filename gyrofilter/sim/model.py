"""The simulator's model: a JSON object (the gap report's ``extended_model``) checked once.

Its keys, defaults and the effect table with every parameter are stated in docs/formats.md
(section 2); :data:`EFFECTS` is that table in code. :func:`validate_model` checks a model and
fills in its defaults, bounding every number so that no model gives a non-finite or absurd
signal; :func:`load_model` is the one reader of model files. The simulation itself is
:mod:`gyrofilter.sim.simulate`.
"""
from __future__ import annotations

import json
import math
import re

import numpy as np

from . import noise_terms as nt
from .accel import accel_unit
from .compression import MAX_COMPRESSION, compression_kappa, compression_too_strong
from ..effects import (ARMA, BIAS_INSTABILITY, COLORED_NOISE, COMPRESSION, HEAVY_TAILS, NARROWBAND, REGISTRY, RESONATORS,
                       ROWS, SINUSOID, TEMPERATURE, WANDERING_TONE)
from ..errors import SettingsError
from ..inputs import MAX_QUOTE_CHARS, closest, did_you_mean, load_json, quote, scalar
from ..recording.checks import first_step_back
from ..units import (AXES, GYRO_UNITS, LSB_PER_DPS_RANGE, LSB_PER_G_RANGE, MAX_RATE_DPS, MAX_SAMPLE_RATE_HZ, TEMP_RANGE_C,
                     check_sample_rate_hz, plain)

# Bounds of every model number, so that no model gives a non-finite or absurd signal. A number is
# bounded by its key's unit (the suffix of its name) and then checked by its kind below; every
# rate-like number (_dps, and deg/s per s, per sqrt(s), per sqrt(Hz), per deg C) by units.MAX_RATE_DPS.
MAX_TIME_S = 1e9  # times and time constants (s): about 32 years
#: every accelerometer number (m/s^2, and m/s^2 per sqrt(s), per deg C; m/s per sqrt(s)): 10^4 g, beyond
#: any accelerometer's range (MEMS parts read +-2 to +-400 g); tighter than a recording's units.MAX_ACCEL_MPS2
MAX_MODEL_ACCEL_MPS2 = 1e5
MIN_TIME_CONSTANT_S = 1e-6  # time constants and periods (s): far below any sample period
MAX_PHASE_RAD = 1000.0
MIN_RESOLUTION_C = 1e-6  # a temperature's quantization step: a finer one (5e-324) made the rounding infinite
MAX_FREQUENCY_HZ = MAX_SAMPLE_RATE_HZ
MIN_BANDWIDTH_PER_RATE = 1e-9  # narrowband: bandwidth_hz >= this times the sample rate (a resonator off the unit circle)
#: resonance and ringing: center_hz >= this times the sample rate. Below it the resonator's poles
#: sit on z = 1 in float64: at 1e-6 times the rate and Q 1000 the stationary start's Lyapunov solve
#: is ill-conditioned (scipy's LinAlgWarning on stderr), at 1e-302 singular (an error naming nothing)
MIN_RESONATOR_CENTER_PER_RATE = 1e-4
MAX_EFFECTS_PER_AXIS = 100
MAX_ARMA_COEFFICIENTS = 20  # each of phi and theta; `gyrofilter arma --max-n 10` fits ARMA(20, 19)
MAX_TABLE_POINTS = 100_000  # a temperature table's t_s and temp_c
#: bounds of the numbers whose key carries no unit, by key
_NAMED_LIMITS = {"lsb_per_dps": LSB_PER_DPS_RANGE, "lsb_per_g": LSB_PER_G_RANGE, "per_decade": (0.1, 10.0),
                 "spread_ln": (0.0, 5.0), "phi": (-1e6, 1e6), "theta": (-1e6, 1e6), "fraction": (0.0, 0.5),
                 "scale_ratio": (1.0, 1000.0), "q": (0.05, 1000.0)}

# kinds of parameter checks: (test, what is expected)
_KINDS = {
    "any": (lambda v: True, "a finite number"),
    "nonneg": (lambda v: v >= 0.0, "a number >= 0"),
    "pos": (lambda v: v > 0.0, "a number > 0"),
    "frac": (lambda v: 0.0 <= v <= 1.0, "a number in [0, 1]"),
    "lag": (lambda v: -1.0 < v < 1.0, "a number in (-1, 1)"),
    "step": (lambda v: v == 0.0 or v >= MIN_RESOLUTION_C, f"0 (none) or a number >= {MIN_RESOLUTION_C:g}"),
}

#: effect name -> (required {param: kind}, optional {param: (kind, default)}), in table order.
EFFECTS = {e.name: (e.required, e.optional) for e in REGISTRY}

#: the model's top-level key of its temperature profile (docs/formats.md, section 2; not the effect)
TEMPERATURE_PROFILE = "temperature"
#: the model's top-level key of its accelerometer (docs/formats.md, section 2; :mod:`gyrofilter.sim.accel`)
ACCELEROMETER = "accelerometer"
#: the model's top-level keys, among them each whole-row effect's (:data:`gyrofilter.effects.ROWS`: an object of
#: its parameters)
_TOP_KEYS = {"sample_rate_hz", "gyro_unit", "lsb_per_dps", "full_scale_dps", TEMPERATURE_PROFILE, ACCELEROMETER, "axes",
             *ROWS}
_META_KEYS = {"description", "name", "comment", "notes", "source", "sensor"}
_AXIS_KEYS = {"bias_dps", "arw_dps_per_sqrt_hz", "effects"}
#: the accelerometer's axis keys: {key: (kind, default)} (:mod:`gyrofilter.sim.accel`: b_a, N_v, B, K, c_a)
ACCEL_AXIS_KEYS = {"bias_mps2": ("any", 0.0), "vrw_mps_per_sqrt_s": ("nonneg", 0.0), "b_mps2": ("nonneg", 0.0),
                   "k_mps2_per_sqrt_s": ("nonneg", 0.0), "coefficient_mps2_per_c": ("any", 0.0)}
#: the values of the accelerometer's ``up``: the axis that points up, a leading ``-`` when it points down
UP_AXES = (*AXES, *(f"-{a}" for a in AXES))
_TEMP_EXP = {"start_c": ("any", None), "end_c": ("any", None), "tau_s": ("pos", 600.0),
             "cycle_amplitude_c": ("nonneg", 0.0), "cycle_period_s": ("pos", 3600.0),
             "noise_c": ("nonneg", 0.0), "resolution_c": ("step", 0.0)}


def _err(where, text):
    """SettingsError naming the key path ``where``, quoted when a user's key makes it unprintable or long."""
    raise SettingsError(f"model: {where if where.isprintable() and len(where) <= 120 else quote(where)}: {text}")


def _limits(key, kind):
    """(lowest, highest, unit) of the model number named ``key`` (a key of the model; list
    entries take their list's key): by the unit its name ends in, else :data:`_NAMED_LIMITS`."""
    if key in _NAMED_LIMITS:
        return (*_NAMED_LIMITS[key], "")
    if "_dps" in key:
        return -MAX_RATE_DPS, MAX_RATE_DPS, ""
    if "_mps" in key:
        return -MAX_MODEL_ACCEL_MPS2, MAX_MODEL_ACCEL_MPS2, ""
    if key.endswith("_s"):
        return (MIN_TIME_CONSTANT_S if kind == "pos" else -MAX_TIME_S), MAX_TIME_S, " s"
    if key.endswith("_hz"):
        return 0.0, MAX_FREQUENCY_HZ, " Hz"
    if key.endswith("_c"):
        return (*TEMP_RANGE_C, " deg C")  # temperatures, and temperature spreads up to the high end
    if key.endswith("_rad"):
        return -MAX_PHASE_RAD, MAX_PHASE_RAD, " rad"
    return -math.inf, math.inf, ""  # rate, lag1, lag2: their kind bounds them


#: the interval of each kind of parameter (:data:`_KINDS`), before the limits of its key
_KIND_BOUNDS = {"nonneg": (0.0, math.inf), "pos": (0.0, math.inf), "frac": (0.0, 1.0), "lag": (-1.0, 1.0)}


def param_bounds(effect, name):
    """``(lowest, highest)`` a model takes for the parameter ``name`` of ``effect`` (an entry of
    :data:`EFFECTS`): its kind's interval (:data:`_KINDS`) within the limits of its key
    (:func:`_limits`); the ends of ``pos`` and ``lag`` are open. The domain an estimate of the
    parameter, and its interval, lie in."""
    required, optional = EFFECTS.get(effect, ({}, {}))
    kind = required.get(name) or optional.get(name, ("any",))[0]
    low, high, _ = _limits(name, kind)
    kind_low, kind_high = _KIND_BOUNDS.get(kind, (-math.inf, math.inf))
    return max(low, kind_low), min(high, kind_high)


def _expected(key, kind):
    """What the parameter ``key`` of the kind ``kind`` takes, for an error message: the interval of
    :data:`_NAMED_LIMITS` where its key has one (narrower than its kind's: ``repeated_samples``'s
    ``fraction`` is a ``frac`` of at most 0.5), else its kind's (:data:`_KINDS`)."""
    if key in _NAMED_LIMITS:
        low, high = _NAMED_LIMITS[key]
        return f"a number in [{low:g}, {high:g}]"
    return _KINDS[kind][1]


def _number(value, where, kind="any"):
    """``value`` as a float, or SettingsError naming ``where``: a number (not a bool) of the kind
    ``kind`` (:data:`_KINDS`) inside the limits of its key (:func:`_limits`); a 0-d array the
    number it holds (:func:`~gyrofilter.inputs.scalar`)."""
    value = scalar(value)
    number = math.nan
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_)):
        try:
            number = float(value)
        except OverflowError:  # an int beyond a float's range
            pass
    key = re.sub(r"\[\d+\]$", "", where.rsplit(".", 1)[-1])
    if math.isnan(number) and not isinstance(value, (float, np.floating)):
        _err(where, f"expected {_expected(key, kind)}, got {_show(value)}")
    if not math.isfinite(number) or not _KINDS[kind][0](number):
        _err(where, f"expected {_expected(key, kind)}, got {plain(number)}")
    low, high, unit = _limits(key, kind)
    if number > high:
        _err(where, f"expected a number <= {high:g}{unit}, got {number:g}")
    if number < low:
        _err(where, f"expected a number >= {low:g}{unit}, got {number:g}")
    return number


def _show(value, limit=MAX_QUOTE_CHARS):
    """JSON text of a bad value for an error message (repr when it is not JSON), cut to ``limit``
    characters (with the full length) when longer."""
    try:
        text = json.dumps(value)
    except (TypeError, ValueError):
        text = plain(value)
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"


def _is_ignored(key):
    return isinstance(key, str) and key.startswith("_")


def validate_model(model, *, sample_rate_hz=None, coefficients_only=False):
    """Check a model once and return ``(normalized, warnings)``.

    ``normalized`` is a new dict with every default filled in (floats, all three axes, effect
    parameters complete); ``warnings`` lists ignored unknown effect parameters. Anything else
    wrong raises :class:`SettingsError` with one line naming the key path and what was expected,
    e.g. ``model: axes.z.effects[0] (gauss_markov): missing parameter 'tau_s' (expected a number > 0)``.
    Keys starting with ``_`` and top-level metadata (description, name, comment, notes, source,
    sensor) are ignored. A whole-row effect (``repeated_samples``) is a top-level key holding its
    parameters, checked as an effect's; ``normalized`` holds it (with ``effect``) or None. The
    ``accelerometer`` (:mod:`gyrofilter.sim.accel`) is checked likewise, its numbers within
    ±:data:`MAX_MODEL_ACCEL_MPS2` and ``lsb_per_g`` in ``units.LSB_PER_G_RANGE``; ``normalized`` holds it
    with its defaults and its ``accel_unit`` (``lsb`` when ``gyro_unit`` is, else ``m/s^2``), or None.

    Every number is bounded, so that no model makes a non-finite or absurd signal: the sample
    rate by :func:`~gyrofilter.units.check_sample_rate_hz`; others by its
    key's unit (:func:`_limits`: rates |x| <= :data:`MAX_RATE_DPS` deg/s, the same for deg/s per s,
    per sqrt(s), per sqrt(Hz) and per deg C; times |t| <= :data:`MAX_TIME_S`, time constants and
    periods in [:data:`MIN_TIME_CONSTANT_S`, :data:`MAX_TIME_S`] s; frequencies <= the highest
    sample rate; temperatures in ``units.TEMP_RANGE_C``; phases |p| <= :data:`MAX_PHASE_RAD`;
    ``lsb_per_dps``, ``per_decade``, ``spread_ln``, the ARMA coefficients and ``heavy_tails``'s
    ``fraction`` (at most 0.5) and ``scale_ratio`` (1 to 1000), a resonator's ``q`` (0.05 to 1000)
    by :data:`_NAMED_LIMITS`), a narrowband line's width in [:data:`MIN_BANDWIDTH_PER_RATE` f_s, f_s]
    and its centre, and a resonance's, ringing's or wandering tone's centre, below Nyquist; and every list: at most :data:`MAX_EFFECTS_PER_AXIS` effects per axis (one
    ``colored_noise`` and one ``heavy_tails``), :data:`MAX_ARMA_COEFFICIENTS` coefficients each in
    ``phi`` and ``theta``, :data:`MAX_TABLE_POINTS` points in a temperature table.

    ``model``: the model dict (docs/formats.md, section 2; e.g. from :func:`load_model`);
    ``sample_rate_hz``: sample rate (Hz) overriding the model's. In ``normalized`` the units are
    the keys' own: ``sample_rate_hz`` Hz, ``lsb_per_dps`` LSB per deg/s (or None),
    ``full_scale_dps`` deg/s (or None), per axis ``bias_dps`` deg/s and ``arw_dps_per_sqrt_hz``
    deg/s/sqrt(Hz), temperatures deg C and times s (the ``temperature`` profile's lists as arrays).

    ``coefficients_only``: the model is read for its numbers, not simulated (``--temp-model``
    takes its temperature coefficients): the sample rate and the temperature profile may then be
    missing (``sample_rate_hz`` None, and the checks that need the rate are skipped); every
    value that is there is checked all the same.
    """
    warnings = []
    if not isinstance(model, dict):
        _err("top level", f"expected a JSON object, got {type(model).__name__}")
    for key in model:
        if key not in _TOP_KEYS and key not in _META_KEYS and not _is_ignored(key):
            _err(key, f"unknown key (expected {', '.join(sorted(_TOP_KEYS))})")
    out = {}
    rate = model.get("sample_rate_hz") if sample_rate_hz is None else sample_rate_hz
    if rate is None and not coefficients_only:
        _err("sample_rate_hz", "missing (expected the sample rate in Hz, > 0; or give --sample-rate-hz)")
    out["sample_rate_hz"] = None if rate is None else check_sample_rate_hz(rate, "model: sample_rate_hz")
    unit = model.get("gyro_unit", "dps")
    if unit not in GYRO_UNITS:
        _err("gyro_unit", f"expected one of {', '.join(GYRO_UNITS)}, got {_show(unit)}")
    out["gyro_unit"] = unit
    lsb = model.get("lsb_per_dps")
    if lsb is None and unit == "lsb":
        _err("lsb_per_dps", "missing: gyro_unit 'lsb' needs lsb_per_dps (LSB per deg/s, > 0)")
    out["lsb_per_dps"] = None if lsb is None else _number(lsb, "lsb_per_dps", "pos")
    full_scale_dps = model.get("full_scale_dps")
    out["full_scale_dps"] = None if full_scale_dps is None else _number(full_scale_dps, "full_scale_dps", "pos")
    out[TEMPERATURE_PROFILE] = (None if model.get(TEMPERATURE_PROFILE) is None
                                else _validate_temperature(model[TEMPERATURE_PROFILE]))
    out[ACCELEROMETER] = (None if model.get(ACCELEROMETER) is None
                          else _validate_accelerometer(model[ACCELEROMETER], out, coefficients_only))
    for name in ROWS:  # a whole-row effect: its parameters at the top level, None when absent
        spec = model.get(name)
        if spec is not None and (not isinstance(spec, dict) or spec.get("effect", name) != name):
            _err(name, f"expected an object of {name}'s parameters, got {_show(spec)}")
        out[name] = None if spec is None else _validate_effect({**spec, "effect": name}, name, out, warnings,
                                                                coefficients_only)

    axes = model.get("axes", {})
    if not isinstance(axes, dict):
        _err("axes", f"expected an object with keys x, y, z, got {_show(axes)}")
    for name in axes:
        if name not in AXES and not _is_ignored(name):
            _err(f"axes.{name}", "unknown axis (expected x, y or z)")
    out["axes"] = {}
    for name in AXES:
        out["axes"][name] = _validate_axis(axes.get(name, {}), f"axes.{name}", out, warnings, coefficients_only)
    warnings += _per_sample_at_another_rate(out, model.get("sample_rate_hz"))
    return out, warnings


#: effects whose parameters are per sample (an autocorrelation, an ARMA coefficient): the time
#: scale they describe is the model's sample rate's, so at another rate it changes by the ratio
PER_SAMPLE_PARAMETERS = {COLORED_NOISE: "lag1 and lag2 are autocorrelations", ARMA: "phi and theta are coefficients"}


def _per_sample_at_another_rate(spec, stated_rate):
    """Warnings for the effects of :data:`PER_SAMPLE_PARAMETERS` of the checked model ``spec`` when its
    sample rate (an override: ``simulate --sample-rate-hz``, a source's ``rate=``) is not the model's
    ``stated_rate`` (Hz, as the model file gives it, or None): per sample of the new rate they
    describe a time scale stated / new times the model's (a colored noise's correlation time
    -1 / (f_s ln lag1); an AR pole's likewise)."""
    rate = spec["sample_rate_hz"]
    per_sample = [(axis, i, eff["effect"]) for axis in AXES for i, eff in enumerate(spec["axes"][axis]["effects"])
                  if eff["effect"] in PER_SAMPLE_PARAMETERS]
    if stated_rate is None or rate is None or not per_sample:
        return []
    try:
        stated = check_sample_rate_hz(stated_rate, "model: sample_rate_hz")
    except SettingsError:  # not a rate: the override is the only one (as before)
        return []
    if stated == rate:
        return []
    return [f"model: axes.{axis}.effects[{i}] ({name}): {PER_SAMPLE_PARAMETERS[name]} per sample, stated at the model's "
            f"sample_rate_hz {stated:g} Hz: at {rate:g} Hz they describe a time scale {stated / rate:.3g} times the model's"
            for axis, i, name in per_sample]


def _validate_temperature(spec):
    where = TEMPERATURE_PROFILE
    if not isinstance(spec, dict):
        _err(where, f"expected an object, got {_show(spec)}")
    out = {}
    if "t_s" in spec or "temp_c" in spec:
        allowed = {"t_s", "temp_c", "noise_c", "resolution_c"}
        for key in spec:
            if key not in allowed and not _is_ignored(key):
                _err(f"{where}.{key}", f"unknown key for a table profile (expected {', '.join(sorted(allowed))})")
        for key in ("t_s", "temp_c"):
            if not isinstance(spec.get(key), list) or not spec[key]:
                _err(f"{where}.{key}", "expected a non-empty list of numbers (table profile needs t_s and temp_c)")
            _check_length(spec[key], f"{where}.{key}", MAX_TABLE_POINTS, "points")
        t = [_number(v, f"{where}.t_s[{i}]") for i, v in enumerate(spec["t_s"])]
        temp = [_number(v, f"{where}.temp_c[{i}]") for i, v in enumerate(spec["temp_c"])]
        if len(t) != len(temp):
            _err(where, f"t_s has {len(t)} values but temp_c has {len(temp)}")
        back = first_step_back(np.diff(t))  # the rule of a recording's t
        if back is not None:
            _err(f"{where}.t_s[{back + 1}]", f"expected strictly increasing times, got {t[back + 1]:g} after {t[back]:g}")
        out["t_s"], out["temp_c"] = np.array(t), np.array(temp)
        out["noise_c"] = _number(spec.get("noise_c", 0.0), f"{where}.noise_c", "nonneg")
        out["resolution_c"] = _number(spec.get("resolution_c", 0.0), f"{where}.resolution_c", "step")
        return out
    for key in spec:
        if key not in _TEMP_EXP and not _is_ignored(key):
            _err(f"{where}.{key}", f"unknown key (expected {', '.join(_TEMP_EXP)}, or t_s and temp_c for a table)")
    if spec.get("start_c") is None:
        _err(f"{where}.start_c", "missing (expected the temperature at t = 0 in deg C)")
    for key, (kind, default) in _TEMP_EXP.items():
        value = spec.get(key, default)
        out[key] = None if value is None and default is None else _number(value, f"{where}.{key}", kind)
    if out["end_c"] is None:
        out["end_c"] = out["start_c"]
    return out


def _validate_accelerometer(spec, model, coefficients_only):
    """The ``accelerometer`` object checked, its defaults filled in and its unit added
    (``accel_unit``: :func:`gyrofilter.sim.accel.accel_unit` of the model's ``gyro_unit``).
    ``model``: the top-level keys checked so far (``gyro_unit``, ``temperature``)."""
    where = ACCELEROMETER
    if not isinstance(spec, dict):
        _err(where, f"expected an object with lsb_per_g, up, axes; got {_show(spec)}")
    for key in spec:
        if key not in ("lsb_per_g", "up", "axes") and not _is_ignored(key):
            _err(f"{where}.{key}", "unknown key (expected axes, lsb_per_g, up)")
    lsb = spec.get("lsb_per_g")
    if lsb is None and model["gyro_unit"] == "lsb":
        _err(f"{where}.lsb_per_g", "missing: gyro_unit 'lsb' writes the accelerometer in LSB too and needs lsb_per_g "
                                   "(LSB per g, > 0)")
    up = spec.get("up", "z")
    if up not in UP_AXES:
        _err(f"{where}.up", f"expected one of {', '.join(UP_AXES)} (the axis that points up), got {_show(up)}")
    axes = spec.get("axes", {})
    if not isinstance(axes, dict):
        _err(f"{where}.axes", f"expected an object with keys x, y, z, got {_show(axes)}")
    out = {"lsb_per_g": None if lsb is None else _number(lsb, f"{where}.lsb_per_g", "pos"), "up": up,
           "accel_unit": accel_unit(model["gyro_unit"]), "axes": {}}
    for name, axis in axes.items():
        if name not in AXES and not _is_ignored(name):
            _err(f"{where}.axes.{name}", "unknown axis (expected x, y or z)")
        if name in AXES and not isinstance(axis, dict):
            _err(f"{where}.axes.{name}", f"expected an object with {', '.join(ACCEL_AXIS_KEYS)}; got {_show(axis)}")
    for name in AXES:
        axis, path = axes.get(name, {}), f"{where}.axes.{name}"
        for key in axis:
            if key not in ACCEL_AXIS_KEYS and not _is_ignored(key):
                _err(f"{path}.{key}", f"unknown key (expected {', '.join(ACCEL_AXIS_KEYS)})")
        out["axes"][name] = {key: _number(axis.get(key, default), f"{path}.{key}", kind)
                             for key, (kind, default) in ACCEL_AXIS_KEYS.items()}
        if out["axes"][name]["coefficient_mps2_per_c"] and model[TEMPERATURE_PROFILE] is None and not coefficients_only:
            _err(f"{path}.coefficient_mps2_per_c", "needs the model's 'temperature' profile (the top-level 'temperature' key)")
    return out


def _validate_axis(spec, where, model, warnings, coefficients_only):
    if not isinstance(spec, dict):
        _err(where, f"expected an object with bias_dps, arw_dps_per_sqrt_hz, effects; got {_show(spec)}")
    for key in spec:
        if key not in _AXIS_KEYS and not _is_ignored(key):
            _err(f"{where}.{key}", f"unknown key (expected {', '.join(sorted(_AXIS_KEYS))})")
    out = {"bias_dps": _number(spec.get("bias_dps", 0.0), f"{where}.bias_dps"),
           "arw_dps_per_sqrt_hz": _number(spec.get("arw_dps_per_sqrt_hz", 0.0), f"{where}.arw_dps_per_sqrt_hz", "nonneg"),
           "effects": []}
    effects = spec.get("effects", [])
    if not isinstance(effects, list):
        _err(f"{where}.effects", f"expected a list of effect objects, got {_show(effects)}")
    _check_length(effects, f"{where}.effects", MAX_EFFECTS_PER_AXIS, "effects")
    for i, eff in enumerate(effects):
        out["effects"].append(_validate_effect(eff, f"{where}.effects[{i}]", model, warnings, coefficients_only))
    for single in (COLORED_NOISE, HEAVY_TAILS, COMPRESSION):  # properties of the one white noise, the one transfer
        if sum(e["effect"] == single for e in out["effects"]) > 1:
            _err(f"{where}.effects", f"at most one {single} per axis")
    return out


def _closest_parameter(key, names):
    """The parameter of ``names`` that an unknown parameter ``key`` of an effect is most like
    (:func:`~gyrofilter.inputs.closest`, the one rule of every "did you mean", or the same name in
    another case: ``Q`` for ``q``), else None."""
    return closest(key, names, also=lambda name: name.casefold() == key.casefold())[1]


def _validate_effect(eff, where, model, warnings, coefficients_only):
    if not isinstance(eff, dict) or "effect" not in eff:
        _err(where, f"expected an object with an 'effect' name, got {_show(eff)}")
    name = eff["effect"]
    if not isinstance(name, str) or name not in EFFECTS:
        hint = did_you_mean(name, EFFECTS) if isinstance(name, str) else ""
        _err(f"{where}.effect", f"unknown effect {_show(name, 20)}{hint} (`gyrofilter simulate --help` lists the effects)")
    if name in ROWS and where != name:
        _err(f"{where}.effect", f"{name} acts on whole rows, every axis at once: give it as the model's top-level key "
                                f"'{name}' (an object of its parameters), not as an effect of an axis")
    required, optional = EFFECTS[name]
    label = where if where == name else f"{where} ({name})"  # a whole-row effect's top-level key names it
    out = {"effect": name}
    unknown = {key: _closest_parameter(key, {**required, **optional}) for key in eff
               if key != "effect" and key not in required and key not in optional and not _is_ignored(key)}
    for key, kind in required.items():
        if key not in eff:
            like = [k for k, near in unknown.items() if near == key]
            hint = f"; the unknown {quote(like[0])} is ignored: did you mean {key}?" if like else ""
            _err(label, f"missing parameter '{key}' (expected {_expected(key, kind)}){hint}")
        out[key] = _number(eff[key], f"{label}.{key}", kind)
    for key, (kind, default) in optional.items():
        value = eff.get(key, default)
        if kind.startswith("choice:"):
            choices = kind.split(":", 1)[1].split(",")
            if value not in choices:
                _err(f"{label}.{key}", f"expected one of {', '.join(choices)}, got {_show(value)}")
            out[key] = value
        elif kind == "coefs":
            if not isinstance(value, (list, tuple)):
                _err(f"{label}.{key}", f"expected a list of numbers, got {_show(value)}")
            _check_length(value, f"{label}.{key}", MAX_ARMA_COEFFICIENTS, "coefficients")
            out[key] = [_number(v, f"{label}.{key}[{i}]") for i, v in enumerate(value)]
        else:  # null stands for "not given" only where the default is derived (None)
            out[key] = None if value is None and default is None else _number(value, f"{label}.{key}", kind)
    for key, near in unknown.items():
        warnings.append(f"model: {label}: unknown parameter {quote(key)} ignored"
                        + (f"; did you mean {near}?" if near is not None else ""))
    if name == TEMPERATURE and model[TEMPERATURE_PROFILE] is None and not coefficients_only:
        _err(label, "needs the model's 'temperature' profile (the top-level 'temperature' key)")
    rate = model["sample_rate_hz"]
    top_hz = highest_frequency_hz(name, out)
    if top_hz is not None and rate is not None and top_hz > rate / 2.0:
        what = _HIGHEST_FREQUENCY[name][1] + (" + excursion_hz" if out.get("excursion_hz") else "")
        warnings.append(f"model: {label}: {what} {top_hz:g} Hz is above the Nyquist frequency "
                        f"{rate / 2.0:g} Hz and will alias")
    elif name == SINUSOID and rate is not None and top_hz == rate / 2.0:  # sin(pi n + phi) = (-1)^n sin(phi)
        peak = abs(out["amplitude_dps"] * math.sin(out["phase_rad"]))
        warnings.append(f"model: {label}: frequency_hz {top_hz:g} Hz is the Nyquist frequency: its samples are "
                        f"amplitude_dps sin(phase_rad) (-1)^n, {peak:.3g} deg/s peak, not {out['amplitude_dps']:g}")
    if name in (NARROWBAND, WANDERING_TONE) + RESONATORS and rate is not None:
        if out["center_hz"] >= rate / 2.0:
            _err(f"{label}.center_hz", f"expected a frequency below the Nyquist frequency {rate / 2.0:g} Hz, "
                                       f"got {out['center_hz']:g}")
        if name in RESONATORS and out["center_hz"] < MIN_RESONATOR_CENTER_PER_RATE * rate:
            _err(f"{label}.center_hz", f"expected a frequency >= {MIN_RESONATOR_CENTER_PER_RATE * rate:g} Hz "
                                       f"({MIN_RESONATOR_CENTER_PER_RATE:g} times the sample rate), got {out['center_hz']:g}")
        if name == NARROWBAND and not MIN_BANDWIDTH_PER_RATE * rate <= out["bandwidth_hz"] <= rate:
            _err(f"{label}.bandwidth_hz", f"expected a width in [{MIN_BANDWIDTH_PER_RATE * rate:g}, {rate:g}] Hz "
                                          f"({MIN_BANDWIDTH_PER_RATE:g} to 1 times the sample rate), got {out['bandwidth_hz']:g}")
    if name == WANDERING_TONE:
        _check_excursion(out, label, rate)
    if name == COMPRESSION and compression_too_strong(out["gamma_per_dps2"], out["rms_dps"]):
        _err(f"{label}.gamma_per_dps2", f"expected gamma_per_dps2 * rms_dps^2 <= {MAX_COMPRESSION:g} (the cubic's turning "
                                        f"point at 3.3 rms or beyond), got {out['gamma_per_dps2']:g} * {out['rms_dps']:g}^2 = "
                                        f"{compression_kappa(out['gamma_per_dps2'], out['rms_dps']):.3g}")
    if name == ARMA and out["phi"] and np.abs(np.roots(np.r_[1.0, -np.asarray(out["phi"])])).max() >= 1.0:
        _err(f"{label}.phi", "expected a stationary AR part (every root of z^p - phi_1 z^(p-1) - ... - phi_p inside the unit circle)")
    if name == COLORED_NOISE and out["lag2"] is not None and nt.arma11_from_lags(out["lag1"], out["lag2"]) is None:
        _err(f"{label}.lag2", f"no first-order ARMA noise has lag-1 autocorrelation {out['lag1']:g} and lag-2 "
                              f"{out['lag2']:g} (expected |lag2| < |lag1| and 1 + p^2 - 2 p lag1 > 2 |lag1 - p|, p = lag2 / lag1)")
    if name == BIAS_INSTABILITY and out["tau_min_s"] and out["tau_max_s"] and out["tau_max_s"] < out["tau_min_s"]:
        _err(f"{label}.tau_max_s", "expected tau_max_s >= tau_min_s")
    return out


def _check_excursion(tone, label, rate):
    """A wandering tone's periodic excursion (:mod:`gyrofilter.sim.tone`): ``excursion_period_s``
    P and ``excursion_s`` D given together or not at all, D < P, and an ``excursion_hz`` above 0
    needs them (SettingsError naming the key). With the sample rate f_s (``rate``, Hz; None: not
    known yet), the excursion and the rest of its cycle each last a sample interval or more,
    D >= 1 / f_s and P - D >= 1 / f_s (so P >= 2 / f_s): the term samples the cycle at
    k / f_s (``((k / f_s + t_0) mod P) < D``), so a shorter excursion is missed in most cycles
    and a period below a sample interval is aliased into another one (P = 1 ms at 100 Hz)."""
    period_s, length_s = tone["excursion_period_s"], tone["excursion_s"]
    if (period_s is None) != (length_s is None):
        _err(f"{label}.{'excursion_s' if length_s is None else 'excursion_period_s'}",
             "missing: excursion_period_s and excursion_s are given together (the excursion's period and length, s)")
    if tone["excursion_hz"] > 0 and period_s is None:
        _err(f"{label}.excursion_period_s", "missing: an excursion_hz above 0 needs excursion_period_s and excursion_s "
                                            "(the excursion's period and length, s)")
    if period_s is not None and not length_s < period_s:
        _err(f"{label}.excursion_s", f"expected a length below excursion_period_s {period_s:g} s, got {length_s:g}")
    if period_s is not None and rate is not None:
        step_s = 1.0 / rate
        slack = 1.0 - 1e-9  # in sample intervals: 0.03 - 0.02 s is 0.99999... of 0.01 s, one interval as written
        if period_s * rate < 2.0 * slack:
            _err(f"{label}.excursion_period_s", f"expected two sample intervals or more ({2.0 * step_s:g} s at "
                                                f"{rate:g} Hz: a sample in the excursion and one out of it), got {period_s:g}")
        if length_s * rate < slack or (period_s - length_s) * rate < slack:
            _err(f"{label}.excursion_s", f"expected a length from one sample interval ({step_s:g} s at {rate:g} Hz) to "
                                         f"excursion_period_s less one ({period_s - step_s:g} s), got {length_s:g}")


#: a wandering tone's frequency reaches its centre plus this many spread_hz (its instantaneous
#: frequency is Gaussian: 3 standard deviations hold 99.7 % of the record)
TONE_REACH_SPREADS = 3.0
#: effect -> (its highest frequency (Hz) from its checked parameters, how a warning names it): the
#: effects whose frequency can pass the Nyquist frequency and alias. A sinusoid's frequency; a
#: wandering tone's centre plus :data:`TONE_REACH_SPREADS` spreads and its excursion; a narrowband line's upper
#: half-power edge (centre plus half its full width). The centres of these lines and of the
#: resonators are refused at or above Nyquist (:func:`validate_model`).
_HIGHEST_FREQUENCY = {
    SINUSOID: (lambda p: p["frequency_hz"], "frequency_hz"),
    WANDERING_TONE: (lambda p: p["center_hz"] + TONE_REACH_SPREADS * p["spread_hz"] + p.get("excursion_hz", 0.0),
                     f"center_hz + {TONE_REACH_SPREADS:g} spread_hz"),
    NARROWBAND: (lambda p: p["center_hz"] + 0.5 * p["bandwidth_hz"], "center_hz + bandwidth_hz / 2"),
}


def highest_frequency_hz(name, params):
    """The highest frequency (Hz) of the effect ``name`` with the checked parameters ``params``
    (:data:`_HIGHEST_FREQUENCY`), or None for an effect without one. The one rule of the
    Nyquist warning: above f_s / 2 a frequency aliases (Oppenheim & Schafer, sec. 4.2)."""
    rule = _HIGHEST_FREQUENCY.get(name)
    return None if rule is None else rule[0](params)


def _check_length(values, where, most, what):
    if len(values) > most:
        _err(where, f"at most {most} {what}, got {len(values)}")


def load_model(path):
    """The simulator model (docs/formats.md, section 2) in the JSON file ``path``, unchecked
    (:func:`validate_model` checks it). A gap report (section 3) is accepted: its
    ``extended_model`` is the model. The one reader of model files (``simulate --model``, the
    ``sim:MODEL.json`` source, ``--temp-model``); its errors name the file. Read through
    :func:`gyrofilter.inputs.load_json` (size cap, UTF-8, nesting depth, no NaN tokens)."""
    model = load_json(path, "model")
    if isinstance(model, dict) and "axes" not in model and isinstance(model.get("extended_model"), dict):
        model = model["extended_model"]
    return model
