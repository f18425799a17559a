"""Generator of recordings with one hidden effect, for the gap-analysis tests and battery.

A *case* is drawn from a seed: an effect of the table (or none), an axis, and parameters over
realistic MPU6050 ranges, on top of a baseline like a real MPU6050 (131 LSB per deg/s, white
noise 0.005-0.015 deg/s/sqrt(Hz), biases of a few deg/s, 100 Hz). ``scale`` shrinks every
effect size (1/3 for the harder set). :func:`check` says whether a gap report names the effect
on the right axis with its parameters inside the tolerances of :data:`TOLERANCES`.

Sizes (scale = 1), chosen from MPU6050 datasheets and logs (bias drift of tenths of deg/s per
hour, warm-up of a few tenths of deg/s, DLPF lag-1 0.3-0.8, the ADIS16405's two-tap average of
lag-1 0.17-0.20 and lag-2 about 0, paper 001's spikes of 1-3 deg/s):

=================  ============================================================================
bias_instability   b_dps 0.006-0.02
rate_random_walk   k_dps_per_sqrt_s 0.0008-0.003
rate_ramp          drift over the record 0.05-0.25 deg/s (either sign)
gauss_markov       sigma_dps 0.02-0.06, tau_s 10 to min(120, T/15)
sinusoid           frequency_hz 0.1-30 (log-uniform), amplitude_dps 0.01-0.04
temperature        coefficient 0.01-0.04 deg/s/deg C (either sign), warming by 3-8 deg C
bias_step          time 20-80 % of the record, size 0.03-0.1 deg/s (either sign)
warmup             amplitude 0.1-0.4 deg/s (either sign), tau_s 30-300
outliers           rate 2e-4 to 2e-3, magnitude_dps 1-3
colored_noise      half the cases a low pass, lag1 0.3-0.8; half a first-order ARMA, lag1 0.15-0.35
                   and lag2 = p lag1 with p -0.2 to 0.2
heavy_tails        fraction 0.01-0.1 (log-uniform; ``scale`` shrinks it: the excess kurtosis is
                   about proportional to it), scale_ratio 4-30 (log-uniform); 30 and 0.06
                   reproduce the Xsens MTi-G record of issue 24 (5 % beyond 6 robust sd)
repeated_samples   fraction 0.01-0.05 of the rows (uniform), half the cases the random pattern and
                   half the beat of the poll and output clocks; whole rows, so the case's axis is
                   ``xyz`` (issue 36: 1.8 % on MPU-9250 records)
resonance          center_hz 5-40 % of the Nyquist frequency, q 1-4 (log-uniform), the hump's
                   peak 0.4-1.5 times the white level (issue 36's MPU-9250: 0.5)
ringing            center_hz 5-40 % of the Nyquist frequency, q 1.5-5, shock_rate_hz 0.05-0.3
                   (log-uniform), shock_dps 10-30 per-sample white-noise sd
wandering_tone     center_hz 12-40 (the band detector looks above min(f_s / 10, 20 Hz)), spread_hz
                   0.3-1.2, wander_s 30-300 (log-uniform; the 5-s frames of the detector's track
                   resolve it), amplitude_dps 0.03-0.08 (where a frame's tone bin is not well
                   above the white noise's, the track is lost; the ADIS16405 z axes: about 0.34
                   at 19.7 Hz, spread 0.5-0.8 Hz, issue 36)
=================  ============================================================================
"""
from __future__ import annotations

import math

import numpy as np

from ..effects import (BIAS_INSTABILITY, BIAS_STEP, COLORED_NOISE, COMPRESSION, GAUSS_MARKOV, HEAVY_TAILS, OUTLIERS, RATE_RAMP,
                      RATE_RANDOM_WALK, REPEATED_SAMPLES, RESONANCE, RINGING, ROWS, SINUSOID, TEMPERATURE, WANDERING_TONE,
                      WARMUP)
from .compression import Compression
from .model import TEMPERATURE_PROFILE, validate_model
from .noise_terms import RepeatedRows, colored_noise_filter, filter_variance
from .resonance import band_pass
from .simulate import simulate
from ..recording import ACCEL_COLUMNS, GYRO_COLUMNS, Recording
from ..errors import SettingsError
from ..streamstats import moving_mean
from ..units import AXES, plain

EFFECTS = (BIAS_INSTABILITY, RATE_RANDOM_WALK, RATE_RAMP, GAUSS_MARKOV, SINUSOID,
           TEMPERATURE, BIAS_STEP, WARMUP, OUTLIERS, COLORED_NOISE, HEAVY_TAILS, REPEATED_SAMPLES, RESONANCE, RINGING,
           WANDERING_TONE)

#: per parameter: ("rel", r) |est/true - 1| <= r; ("abs", a) |est - true| <= a;
#: ("factor", f) est/true in [1/f, f]; ("time", (a_s, frac)) |est - true| <= max(a_s, frac T)
TOLERANCES = {
    BIAS_INSTABILITY: {"b_dps": ("rel", 0.5)},
    RATE_RANDOM_WALK: {"k_dps_per_sqrt_s": ("rel", 0.5)},
    RATE_RAMP: {"r_dps_per_s": ("rel", 0.3)},
    GAUSS_MARKOV: {"sigma_dps": ("rel", 0.5), "tau_s": ("factor", 2.5)},
    SINUSOID: {"frequency_hz": ("rel", 0.01), "amplitude_dps": ("rel", 0.25)},
    TEMPERATURE: {"coefficient_dps_per_c": ("rel", 0.3)},
    BIAS_STEP: {"time_s": ("time", (5.0, 0.02)), "size_dps": ("rel", 0.35)},
    WARMUP: {"amplitude_dps": ("rel", 0.35), "tau_s": ("rel", 0.5)},
    OUTLIERS: {"rate": ("factor", 1.6), "magnitude_dps": ("rel", 0.35)},
    COLORED_NOISE: {"lag1": ("abs", 0.1), "lag2": ("abs", 0.05)},
    HEAVY_TAILS: {"fraction": ("factor", 1.5), "scale_ratio": ("rel", 0.3)},
    REPEATED_SAMPLES: {"fraction": ("rel", 0.15)},
    RESONANCE: {"center_hz": ("rel", 0.05), "q": ("factor", 2.0), "rms_dps": ("rel", 0.3)},
    RINGING: {"center_hz": ("rel", 0.05), "q": ("factor", 1.5), "shock_rate_hz": ("factor", 1.6), "shock_dps": ("rel", 0.35)},
    WANDERING_TONE: {"center_hz": ("abs", 0.75), "spread_hz": ("factor", 1.6), "wander_s": ("factor", 3.0),
                     "amplitude_dps": ("rel", 0.25)},
}


def draw_case(seed, *, effect=None, duration_s=None, scale=1.0, p_clean=None):
    """Draw one case. ``effect=None`` draws one of EFFECTS or 'none' (probability ``p_clean``,
    default 1/(len(EFFECTS) + 1)); ``effect='none'`` forces a clean case. Returns a dict with the model,
    duration, hidden effect/axis/params and the simulation seed."""
    rng = np.random.default_rng(seed)
    if duration_s is None:
        duration_s = float(rng.uniform(1800.0, 3600.0))
    if effect is None:
        p = 1.0 / (len(EFFECTS) + 1) if p_clean is None else p_clean
        effect = "none" if rng.random() < p else EFFECTS[rng.integers(len(EFFECTS))]
    axis = AXES[rng.integers(3)]
    model = {"sample_rate_hz": 100.0, "gyro_unit": "lsb", "lsb_per_dps": 131.0,
             "full_scale_dps": 250.0,
             "axes": {a: {"bias_dps": float(rng.uniform(-5, 5)),
                          "arw_dps_per_sqrt_hz": float(rng.uniform(0.005, 0.015)), "effects": []}
                      for a in AXES}}
    params = {}
    sign = 1.0 if rng.random() < 0.5 else -1.0
    T = duration_s
    if effect == BIAS_INSTABILITY:
        params = {"b_dps": scale * rng.uniform(0.006, 0.02)}
    elif effect == RATE_RANDOM_WALK:
        params = {"k_dps_per_sqrt_s": scale * rng.uniform(0.0008, 0.003)}
    elif effect == RATE_RAMP:
        params = {"r_dps_per_s": sign * scale * rng.uniform(0.05, 0.25) / T}
    elif effect == GAUSS_MARKOV:
        # a correlation time the record can resolve: at most a fifteenth of its length
        params = {"sigma_dps": scale * rng.uniform(0.02, 0.06), "tau_s": float(rng.uniform(10, min(120.0, T / 15)))}
    elif effect == SINUSOID:
        params = {"frequency_hz": float(math.exp(rng.uniform(math.log(0.1), math.log(30.0)))),
                  "amplitude_dps": scale * rng.uniform(0.01, 0.04),
                  "phase_rad": float(rng.uniform(0, 2 * math.pi))}
    elif effect == TEMPERATURE:
        params = {"coefficient_dps_per_c": sign * scale * rng.uniform(0.01, 0.04)}
    elif effect == BIAS_STEP:
        params = {"time_s": float(rng.uniform(0.2, 0.8) * T), "size_dps": sign * scale * rng.uniform(0.03, 0.1)}
    elif effect == WARMUP:
        params = {"amplitude_dps": sign * scale * rng.uniform(0.1, 0.4), "tau_s": float(rng.uniform(30, 300))}
    elif effect == OUTLIERS:
        params = {"rate": float(math.exp(rng.uniform(math.log(2e-4), math.log(2e-3)))),
                  "magnitude_dps": scale * rng.uniform(1.0, 3.0)}
    elif effect == COLORED_NOISE:
        if rng.uniform() < 0.5:
            params = {"lag1": scale * rng.uniform(0.3, 0.8)}
        else:
            lag1 = scale * rng.uniform(0.15, 0.35)
            params = {"lag1": lag1, "lag2": lag1 * rng.uniform(-0.2, 0.2)}
    elif effect == HEAVY_TAILS:
        params = {"fraction": scale * math.exp(rng.uniform(math.log(0.01), math.log(0.1))),
                  "scale_ratio": math.exp(rng.uniform(math.log(4.0), math.log(30.0)))}
    elif effect == REPEATED_SAMPLES:
        params = {"fraction": scale * rng.uniform(0.01, 0.05), "pattern": "beat" if rng.random() < 0.5 else "random"}
    elif effect == RESONANCE:
        params = _hump(rng, model, axis, scale)
    elif effect == RINGING:
        sigma = model["axes"][axis]["arw_dps_per_sqrt_hz"] * math.sqrt(model["sample_rate_hz"])
        params = {"center_hz": rng.uniform(0.05, 0.4) * model["sample_rate_hz"] / 2.0,
                  "q": math.exp(rng.uniform(math.log(1.5), math.log(5.0))),
                  "shock_rate_hz": math.exp(rng.uniform(math.log(0.05), math.log(0.3))),
                  "shock_dps": scale * rng.uniform(10.0, 30.0) * sigma}
    elif effect == WANDERING_TONE:
        params = {"center_hz": float(rng.uniform(12.0, 40.0)), "spread_hz": float(rng.uniform(0.3, 1.2)),
                  "wander_s": float(math.exp(rng.uniform(math.log(30.0), math.log(300.0)))),
                  "amplitude_dps": scale * rng.uniform(0.03, 0.08)}
    params = {k: v if isinstance(v, str) else float(v) for k, v in params.items()}
    # every case has a temperature column: a slow warming after power-on, MPU6050 resolution
    start = float(rng.uniform(22, 28))
    model[TEMPERATURE_PROFILE] = {"start_c": start,
                            "end_c": start + float(rng.uniform(3, 8) if effect == TEMPERATURE else rng.uniform(0, 1.5)),
                            "tau_s": float(rng.uniform(300, 900)), "noise_c": 0.01,
                            "resolution_c": 1.0 / 340.0}
    if effect in ROWS:  # whole rows: the model's top-level key, every axis
        model[effect], axis = dict(params), "".join(AXES)
    elif effect != "none":
        model["axes"][axis]["effects"].append({"effect": effect, **params})
    return {"seed": int(seed), "effect": effect, "axis": axis if effect != "none" else None,
            "params": params, "model": model, "duration_s": float(duration_s),
            "sim_seed": int(rng.integers(2**31))}


def _hump(rng, model, axis, scale):
    """A resonance's parameters: centre 5-40 % of the Nyquist frequency, Q 1-4 (log-uniform), its
    peak 0.4-1.5 times the white level (``scale`` times that), so the spectrum there is 1.4-2.5
    times the neighbouring level (issue 36's hump: 1.5): rms = sqrt(L Σ h²) σ for the resonator
    of unit peak gain (Σ h² its energy) and the white noise's per-sample std σ."""
    rate = model["sample_rate_hz"]
    centre, q = rng.uniform(0.05, 0.4) * rate / 2.0, math.exp(rng.uniform(0.0, math.log(4.0)))
    sigma = model["axes"][axis]["arw_dps_per_sqrt_hz"] * math.sqrt(rate)
    level = scale * rng.uniform(0.4, 1.5)
    return {"center_hz": centre, "q": q, "rms_dps": math.sqrt(level * filter_variance(*band_pass(centre, q, rate))) * sigma}


def simulate_case(case):
    """The case's recording (in memory)."""
    return simulate(case["model"], case["duration_s"], seed=case["sim_seed"])


def hide_in_recording(rec, effect, axis, params, *, seed=0):
    """Add one effect to a real recording (real noise as the baseline): the effect is simulated
    alone (no white noise, no bias, no quantization) at the recording's rate and length and
    added to the rate in deg/s; the result is a deg/s recording with the recording's other
    columns (``t``, ``temp``, ``ax, ay, az`` with their unit, any other) and its notes as they
    were (``repeated_samples`` repeats whole rows of the sensor: ``temp`` and ``ax, ay, az`` with
    the rates, ``t`` and the others as they were: the logger's clock goes on).
    SettingsError for an ``axis`` that is none of x, y, z, or ``params`` the simulator's model
    refuses (:func:`~gyrofilter.sim.model.validate_model`; a colored noise of lag1 NaN made the
    axis NaN; ``repeated_samples``, a whole-row effect with no axis, as the model's top-level key:
    a fraction of 5 repeated every row); a parameter the effect does not take (a misspelt
    ``lag2`` or ``pattern`` was dropped without a word, the default's effect hidden), and a colored
    noise's ``preserve`` other than ``"std"`` (the recording's noise is filtered keeping its
    variance), and an ``"effect"`` in ``params`` other than ``effect`` (it replaced it), are refused.
    A ``compression`` compresses the recording's fast noise (the rate less its moving mean, as
    ``heavy_tails`` scales it) about that mean: the simulated part has no noise to compress; its
    ``rms_dps`` is that noise's rms (within :data:`FAST_RMS_TOLERANCE`, else refused naming it)."""
    if isinstance(params, dict) and params.get("effect", effect) != effect:  # a model's entry of another effect replaced it
        raise SettingsError(f"params name the effect {plain(params['effect'])}, not {plain(effect)} (nothing hidden)")
    sample_rate_hz = rec.sample_rate_hz
    n = len(rec)
    model = {"sample_rate_hz": sample_rate_hz, "gyro_unit": "dps",
             "axes": {a: {"bias_dps": 0.0, "arw_dps_per_sqrt_hz": 0.0, "effects": []} for a in AXES}}
    temp, accel = rec.temp_c, _accelerometer(rec)
    if effect == TEMPERATURE:
        if temp is None:
            raise SettingsError(f"{rec.path or 'recording'}: the effect {TEMPERATURE} needs a temp column (deg C), "
                                "which this recording has not")
        t = np.arange(n) / sample_rate_hz
        step = max(1, n // 500)
        model[TEMPERATURE_PROFILE] = {"t_s": t[::step].tolist(), "temp_c": np.asarray(temp)[::step].tolist()}
    if effect == REPEATED_SAMPLES:  # checked as the simulator checks it, also where it is not simulated
        _, ignored = validate_model({**model, REPEATED_SAMPLES: params})  # a whole-row effect: a top-level key
    else:
        if axis not in AXES:
            raise SettingsError(f"axis must be one of {', '.join(AXES)}, got {plain(axis)}")
        _, ignored = validate_model({**model, "axes": {**model["axes"], axis: {**model["axes"][axis],
                                                                              "effects": [{"effect": effect, **params}]}}})
    if ignored:  # no warning reaches a caller here: a misspelt optional parameter hid the default's effect
        raise SettingsError(f"{ignored[0].replace(' ignored', '', 1)} (nothing hidden)")
    if effect == COLORED_NOISE and params.get("preserve", "std") != "std":
        raise SettingsError(f"{rec.path or 'recording'}: a colored noise hidden in a recording keeps the "
                            f"recording's noise variance (preserve \"std\"), not {plain(params['preserve'])}")
    gyro = rec.gyro_dps.copy()
    if effect == COLORED_NOISE:
        # a property of the noise, not an additive term: filter the real noise of the axis by
        # the colored noise's own filter, keeping its variance (preserve "std")
        from scipy.signal import lfilter

        i = AXES.index(axis)
        rho = float(params["lag1"])
        if params.get("lag2") is not None:  # null: not given, as the model takes it
            b, a = colored_noise_filter(1.0, 1.0, rho, params["lag2"], preserve="std")
        else:  # y_k = rho y_{k-1} + sqrt(1 - rho^2) e_k
            b, a = [math.sqrt(1 - rho * rho)], [1.0, -rho]
        dev = gyro[:, i] - gyro[:, i].mean()
        gyro[:, i] = gyro[:, i].mean() + lfilter(b, a, dev)
    elif effect == HEAVY_TAILS:
        # a property of the noise too: the real fast noise (the rate less its moving mean over 64
        # samples) scaled per sample by the effect's k[n] (variance kept on average)
        i = AXES.index(axis)
        p, c = float(params["fraction"]), float(params["scale_ratio"])
        k0 = 1.0 / math.sqrt(1.0 - p + p * c * c)
        k = np.where(np.random.default_rng(seed).random(n) < p, c * k0, k0)
        fast = gyro[:, i] - moving_mean(gyro[:, i], _FAST_WINDOW)  # clipped at the ends: zeros beyond them scaled the bias
        gyro[:, i] += (k - 1.0) * fast
    elif effect == COMPRESSION:
        # a map of the fast terms about the slow level, of which the simulated part has none (no
        # white noise: the record came back unchanged): the real fast noise, as heavy tails take it
        i = AXES.index(axis)
        slow = moving_mean(gyro[:, i], _FAST_WINDOW)
        fast = gyro[:, i] - slow
        if n:
            _check_fast_rms(rec, axis, float(params["rms_dps"]), float(np.sqrt(np.mean(fast * fast))))
        gyro[:, i] = slow + Compression(params["gamma_per_dps2"], params["rms_dps"]).apply(fast)
    elif effect == REPEATED_SAMPLES:  # whole rows of the real record, the temperature's too
        repeats = RepeatedRows(params["fraction"], params.get("pattern", "random"), np.random.default_rng(seed))
        mask = repeats.next_mask(n)
        gyro = np.column_stack([repeats.apply(gyro[:, i], mask, None)[0] for i in range(3)])
        temp = None if temp is None else repeats.apply(np.asarray(temp, dtype=float), mask, None)[0]
        accel = None if accel is None else np.column_stack([repeats.apply(accel[:, i], mask, None)[0] for i in range(3)])
    else:
        model["axes"][axis]["effects"].append({"effect": effect, **params})
        sim = simulate(model, n / sample_rate_hz, seed=seed)
        gyro = gyro + sim.gyro_dps[:n]
    header = {k: v for k, v in rec.header.items() if k not in ("gyro_unit", "lsb_per_dps")}
    others = {name: values for name, values in rec.columns.items() if name not in ("t", "temp", *GYRO_COLUMNS, *ACCEL_COLUMNS)}
    hidden = Recording.from_dps(gyro, sample_rate_hz, t_s=rec.columns.get("t"), temp_c=temp, accel=accel,
                                accel_unit=rec.accel_unit if accel is not None else None,
                                lsb_per_g=rec.lsb_per_g if accel is not None else None, extra=others, header=header)
    hidden.notes = list(rec.notes)
    return hidden


#: the samples of the moving mean whose residual is a record's fast noise (heavy tails hidden in it)
_FAST_WINDOW = 64
#: how far a compression's stated ``rms_dps`` may be from the rms of the recording's fast noise it
#: compresses (relative): 5 % keeps gamma rms^2 within 0.033 of the model's 0.03 (the turning point
#: at 3.2 rms or beyond) and the variance within 2 %
FAST_RMS_TOLERANCE = 0.05


def _check_fast_rms(rec, axis, stated_dps, rms_dps):
    """Refuse (SettingsError) a compression whose stated rms ``stated_dps`` is not the rms
    ``rms_dps`` of the recording's fast noise on ``axis`` within :data:`FAST_RMS_TOLERANCE`: the
    gain g = 1 / sqrt(1 - 6 kappa + 15 kappa^2) and the bound kappa = gamma sigma^2 <= 0.03
    (:mod:`gyrofilter.sim.compression`) hold for the sigma of what is compressed, the recording's
    noise (stated 0.05 on a noise of 0.3: the turning point at 0.55 rms, the std 0.305 made 0.115)."""
    where = rec.path or "recording"
    if rms_dps == 0.0:
        raise SettingsError(f"{where}: no fast noise on {axis} (the rate less its moving mean over {_FAST_WINDOW} samples "
                            "is 0): nothing to compress")
    if abs(stated_dps / rms_dps - 1.0) > FAST_RMS_TOLERANCE:
        raise SettingsError(f"{where}: compression rms_dps {stated_dps:g} is not the rms of the recording's fast noise "
                            f"on {axis} (the rate less its moving mean over {_FAST_WINDOW} samples), which it compresses: "
                            f"give rms_dps={rms_dps:.4g} (deg/s)")


def _accelerometer(rec):
    """The columns ``ax, ay, az`` of ``rec`` as an (N, 3) array in their file unit, or None."""
    if not all(c in rec.columns for c in ACCEL_COLUMNS):
        return None
    return np.column_stack([np.asarray(rec.columns[c], dtype=float) for c in ACCEL_COLUMNS])


def _within(kind, tol, est, true, duration_s):
    if kind == "rel":
        return true != 0 and abs(est / true - 1.0) <= tol
    if kind == "abs":
        return abs(est - true) <= tol
    if kind == "factor":
        return true > 0 and est > 0 and 1.0 / tol <= est / true <= tol
    if kind == "time":
        a_s, frac = tol
        return abs(est - true) <= max(a_s, frac * duration_s)
    raise ValueError(kind)


def _value(params, name):
    """``params[name]``, or the simulator's default of an optional parameter (lag2: lag1²)."""
    if name == "lag2" and name not in params:
        return float(params["lag1"]) ** 2
    return float(params[name])


def check(case, report):
    """Score a gap report against the case: returns ``(named, in_tolerance, false_findings)``.

    named: the hidden effect is among the findings on the right axis, or it is listed in the
    ``alternatives`` of a finding there (the report says the record cannot tell the two readings
    apart, e.g. a warm-up under a temperature that settles alike: docs/gap.md, "Confounded
    causes"; that finding, and the findings of its reading that the alternative replaces as a
    whole, its ``in_place_of``, are then not false ones); in_tolerance: and all its listed parameters
    are within :data:`TOLERANCES` (an optional one compared at its default where absent:
    ``colored_noise``'s ``lag2`` is lag1² then); false_findings: findings other than the hidden one.
    """
    findings = report["findings"]
    mine = [f for f in findings if f["axis"] == case["axis"]]
    hit = [f for f in mine if f["effect"] == case["effect"]]
    hit += [alt for f in mine if not hit for alt in f.get("alternatives", []) if alt["effect"] == case["effect"]]
    carrier = [f for f in mine if any(alt in hit for alt in f.get("alternatives", []))]
    reading = {e for f in carrier for alt in f["alternatives"] for e in alt.get("in_place_of", [f["effect"]])}
    others = [f for f in findings if not (f["effect"] == case["effect"] and f["axis"] == case["axis"]) and f not in carrier
              and not (f["axis"] == case["axis"] and f["effect"] in reading)]
    if case["effect"] == "none" or not hit:
        return False, False, others
    params = hit[0]["params"]
    ok = all(_within(kind, tol, _value(params, name), _value(case["params"], name), case["duration_s"])
             for name, (kind, tol) in TOLERANCES[case["effect"]].items())
    return True, ok, others


def wilson(k, n, z=1.96):
    """95 % Wilson score interval of a binomial proportion k / n (a battery's rate: how sure it
    is on n cases); (nan, nan) for n = 0."""
    if n == 0:
        return float("nan"), float("nan")
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half
