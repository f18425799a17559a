"""Gyro simulator: a noise model (JSON dict) in, a recording out.

The model is a JSON object (the gap report's ``extended_model``); its keys, defaults and the
effect table with every parameter are stated in docs/formats.md (section 2) and checked by
:func:`gyrofilter.sim.model.validate_model` (``EFFECTS`` there is the table in code).

Per axis and sample n (t = n / f_s), in deg/s:

    ω[n] = b + e[n] + Σ_effects x_k[n]                (b = ``bias_dps``; e = white noise, N sqrt(f_s) w[n],
                                                       or its low-passed form with ``colored_noise``;
                                                       w[n] of unit variance, heavy-tailed with ``heavy_tails``)
    ω[n] ← l[n] + g c(ω[n] - l[n])                   (``compression``: the fast terms compressed about the
                                                       slow level l, the bias and the slow effects)
    ω[n] ← ω[n] + spikes[n]                           (``outliers``)
    ω[n] ← clip(ω[n], -FS, +FS)                       (``full_scale_dps``: saturation)
    ω[n] ← round(ω[n] · lsb_per_dps) / lsb_per_dps    (quantization, when ``lsb_per_dps`` is given)

then the rate is written in ``gyro_unit`` (``lsb``: the integers round(ω · lsb_per_dps)). Last,
``repeated_samples`` (a top-level key: whole rows) makes some rows repeat the previous row on every
column, the temperature's and the accelerometer's too (:class:`gyrofilter.sim.noise_terms.RepeatedRows`); its stream is the
record's, not an axis's, so one axis simulated alone (:func:`simulate_axis_dps`) repeats the same rows.
Each effect term is documented, with its equation, in :mod:`gyrofilter.sim.noise_terms`
(``wandering_tone`` in :mod:`gyrofilter.sim.tone`, ``compression`` in :mod:`gyrofilter.sim.compression`).

``colored_noise`` low-passes the white noise: with ``preserve="arw"`` (default)
``arw_dps_per_sqrt_hz`` keeps its Allan meaning (the white level for τ well beyond the filter's
correlation time, as with the MPU6050's DLPF) and the per-sample std becomes
N sqrt(f_s) sqrt((1 - lag1)/(1 + lag1)); with ``preserve="std"`` the per-sample std stays
N sqrt(f_s). See :class:`gyrofilter.sim.noise_terms.WhiteNoise`. With ``lag2`` (the lag-2
autocorrelation; default lag1², the first-order low pass) the filter is the first-order ARMA with
both autocorrelations (:func:`gyrofilter.sim.noise_terms.colored_noise_filter`): ``lag2 = 0`` is a
two-tap average, the fast noise of the ADIS16405.

``heavy_tails`` makes the draws w[n] of the white noise (the innovations of a colored noise)
a Gaussian scale mixture of unit variance (:class:`gyrofilter.sim.noise_terms.ScaleMixtureNormal`):
a fraction ``fraction`` of the samples has ``scale_ratio`` times the others' standard deviation.
The variance is kept, so N keeps its meaning and the Allan deviation is unchanged in
expectation; only the distribution of every sample is heavier-tailed than a Gaussian (unlike
``outliers``, a few isolated spikes added on top).

The ``accelerometer`` key adds the columns ``ax, ay, az`` (:mod:`gyrofilter.sim.accel`, its equations),
written after the gyro's and ``temp`` in the model's ``accel_unit``.

The ``temperature`` key designs the ``temp`` column (an exponential self-heating profile with
an optional cycle, or a table interpolated linearly; read noise and resolution only on the
written column) and drives the ``temperature`` effect.

Randomness: only ``seed`` or ``rng``. Every random term draws from its own stream, derived
from the root seed and a fixed key (axis, effect name, occurrence; the accelerometer's axes have keys
of their own, so adding one leaves the gyro's samples unchanged bit for bit), so (1) a run cut into chunks
equals the one-shot run bit for bit, and (2) adding an effect to a model leaves the other terms'
random draws unchanged for the same seed (common random numbers: a baseline and its extension
share their white noise).
"""
from __future__ import annotations

import json
from typing import NamedTuple

import numpy as np

from ..effects import (ARMA, BIAS_INSTABILITY, BIAS_STEP, COLORED_NOISE, COMPRESSION, GAUSS_MARKOV, HEAVY_TAILS,
                       NARROWBAND, OUTLIERS, RATE_RAMP, RATE_RANDOM_WALK, REPEATED_SAMPLES, RESONANCE, RINGING, SINUSOID,
                       SLOW, TEMPERATURE, WANDERING_TONE, WARMUP)
from . import noise_terms as nt
from .compression import Compression
from .resonance import Ringing, resonance_filter
from .tone import WanderingTone
from .accel import RANDOM_TERMS, Accelerometer
from .flicker import BiasInstability
from .model import ACCELEROMETER, EFFECTS, TEMPERATURE_PROFILE, validate_model
from ..errors import SettingsError
from ..inputs import check_number, python_value, scalar
from ..recording import ACCEL_COLUMNS, COLUMNS, EXACT_FORMAT, FORMAT_VERSION, VERSION_KEY, Recording, accel_units_header, format_number, units_header
from ..units import AXES, DEG_PER_RAD, check_duration_s, plain, to_dps

DEFAULT_CHUNK_SAMPLES = 65536
#: most samples a simulated recording holds, in memory (:func:`simulate`) or in a file (``gyrofilter
#: simulate``): 1e9 samples are 32 GB of t, gx, gy, gz as floats (about 40 GB of file), more than any
#: machine that runs gyrofilter holds and more than any analysis reads. The streams of
#: :func:`simulate_chunks` (the ``sim`` source runs a week) hold one block and are not bounded.
MAX_SAMPLES = 10**9
_EFFECT_ID = {name: i + 1 for i, name in enumerate(EFFECTS)}  # 0 = white noise; fixed stream keys


# ---------------------------------------------------------------------------------------------
# random streams


def _root_seed(seed, rng):
    if seed is not None and rng is not None:
        raise SettingsError("simulate: give seed or rng, not both")
    if rng is not None:
        if not isinstance(rng, np.random.Generator):
            raise SettingsError(f"simulate: rng must be a numpy.random.Generator, got {type(rng).__name__}")
        return np.random.SeedSequence(rng.integers(0, 2**63, size=4))
    if seed is not None:
        return np.random.SeedSequence(check_seed(seed))
    return np.random.SeedSequence()


#: the largest seed: a signed 64-bit integer, which every tool that repeats a run can hold
MAX_SEED = 2**63 - 1


def check_seed(seed, name="simulate: seed"):
    """``seed`` as an int, or SettingsError naming ``name``: a seed is an integer in [0, MAX_SEED]
    (numpy's SeedSequence takes any integer >= 0; the bound keeps it one that reads back). The
    one check of a seed: the library's, the ``sim`` source's and the ``--seed`` options'. A 0-d
    array is the integer it holds (:func:`~gyrofilter.inputs.scalar`)."""
    seed = scalar(seed)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed <= MAX_SEED:
        shown = plain(seed) if not isinstance(seed, (int, np.integer)) or abs(seed) < 10**20 else \
            f"an integer of {len(str(abs(int(seed))))} digits"
        raise SettingsError(f"{name} must be an integer in [0, 2^63 - 1], got {shown}")
    return int(seed)


def _stream(root, *key):
    """An independent generator for the fixed key (axis index, effect id, occurrence, part)."""
    return np.random.default_rng(np.random.SeedSequence(root.entropy, spawn_key=tuple(root.spawn_key) + key))


# ---------------------------------------------------------------------------------------------
# simulation


#: the key of the record's own streams (the axes are 0-2, the temperature 3): the whole-row effects
_RECORD_KEY = 4
#: the first key of the accelerometer's streams: its axes x, y, z are 5, 6, 7 (:func:`_accelerometer`)
_ACCEL_KEY = 5


def _repeats(spec, root):
    """The :class:`~gyrofilter.sim.noise_terms.RepeatedRows` of the model's ``repeated_samples``, or None."""
    rows = spec.get(REPEATED_SAMPLES)
    if rows is None:
        return None
    return nt.RepeatedRows(rows["fraction"], rows["pattern"], _stream(root, _RECORD_KEY, _EFFECT_ID[REPEATED_SAMPLES], 0, 0))


def _accelerometer(spec, sample_rate_hz, duration_s, root, temp_profile):
    """The :class:`~gyrofilter.sim.accel.Accelerometer` of the model's ``accelerometer``, or None
    without one. Its streams are keyed (5 + axis, term, 0, 0), term the index in
    :data:`~gyrofilter.sim.accel.RANDOM_TERMS`: apart from every gyro stream, so adding an
    accelerometer to a model leaves its gyro samples unchanged bit for bit."""
    accel = spec[ACCELEROMETER]
    if accel is None:
        return None
    rngs = [[_stream(root, _ACCEL_KEY + i, j, 0, 0) for j in range(len(RANDOM_TERMS))] for i in range(3)]
    return Accelerometer(accel, sample_rate_hz, duration_s, rngs, temp_profile.start_c() if temp_profile else None)


class AxisTerms(NamedTuple):
    """The generators of one axis: ``terms`` (additive; without a compression all of them, the
    bias first, in the model's order; with one only the slow level's: the bias and
    :data:`~gyrofilter.effects.SLOW`), ``noise`` (the white or colored noise), ``outliers``, the
    ``compression`` (:class:`~gyrofilter.sim.compression.Compression`, or None) and the ``fast``
    terms it compresses with the noise (empty without it)."""

    terms: list
    noise: object
    outliers: list
    compression: Compression | None = None
    fast: list = []


def _axis_terms(ax_index, spec, sample_rate_hz, duration_s, root, temp_profile):
    """The :class:`AxisTerms` of one axis."""
    terms = [nt.Constant(spec["bias_dps"])]
    outliers = []
    colored = next((e for e in spec["effects"] if e["effect"] == COLORED_NOISE), None)
    tails = next((e for e in spec["effects"] if e["effect"] == HEAVY_TAILS), None)
    draws = _stream(root, ax_index, 0, 0, 0)
    if tails is not None:  # the same normals, scaled per sample: heavy-tailed at the same variance
        draws = nt.ScaleMixtureNormal(draws, _stream(root, ax_index, _EFFECT_ID[HEAVY_TAILS], 0, 0), tails["fraction"],
                                      tails["scale_ratio"])
    if colored is not None and colored["lag2"] is not None:
        noise = nt.FilteredNoise(*nt.colored_noise_filter(spec["arw_dps_per_sqrt_hz"], sample_rate_hz, colored["lag1"],
                                                          colored["lag2"], colored["preserve"]), draws)
    else:
        noise = nt.WhiteNoise(spec["arw_dps_per_sqrt_hz"], sample_rate_hz, draws,
                              lag1=colored["lag1"] if colored else 0.0,
                              preserve=colored["preserve"] if colored else "arw")
    seen, slow = {}, [True]  # per term of ``terms``: part of the slow level (the bias is)
    for eff in spec["effects"]:
        name = eff["effect"]
        occ = seen[name] = seen.get(name, -1) + 1
        key = (ax_index, _EFFECT_ID[name], occ)
        if name == BIAS_INSTABILITY:
            tau_min = eff["tau_min_s"] or 1.0 / sample_rate_hz
            tau_max = eff["tau_max_s"] or max(duration_s, tau_min)
            terms.append(BiasInstability(eff["b_dps"], sample_rate_hz, _stream(root, *key, 0), tau_min, tau_max,
                                         eff["per_decade"]))
        elif name == RATE_RANDOM_WALK:
            terms.append(nt.RateRandomWalk(eff["k_dps_per_sqrt_s"], sample_rate_hz, _stream(root, *key, 0)))
        elif name == RATE_RAMP:
            terms.append(nt.RateRamp(eff["r_dps_per_s"]))
        elif name == GAUSS_MARKOV:
            terms.append(nt.GaussMarkov(eff["sigma_dps"], eff["tau_s"], sample_rate_hz, _stream(root, *key, 0)))
        elif name == SINUSOID:
            terms.append(nt.Sinusoid(eff["amplitude_dps"], eff["frequency_hz"], eff["phase_rad"]))
        elif name == TEMPERATURE:
            ref = temp_profile.start_c() if eff["reference_c"] is None else eff["reference_c"]
            terms.append(nt.TemperatureCoefficient(eff["coefficient_dps_per_c"], ref))
        elif name == BIAS_STEP:
            terms.append(nt.BiasStep(eff["size_dps"], eff["time_s"]))
        elif name == WARMUP:
            terms.append(nt.Warmup(eff["amplitude_dps"], eff["tau_s"]))
        elif name == NARROWBAND:
            b, a = nt.narrowband_filter(eff["rms_dps"], eff["center_hz"], eff["bandwidth_hz"], sample_rate_hz)
            terms.append(nt.FilteredNoise(b, a, _stream(root, *key, 0)))
        elif name == ARMA:
            b, a = nt.arma_filter(eff["phi"], eff["theta"], eff["sigma_a_dps"])
            terms.append(nt.FilteredNoise(b, a, _stream(root, *key, 0)))
        elif name == RESONANCE:
            b, a = resonance_filter(eff["rms_dps"], eff["center_hz"], eff["q"], sample_rate_hz)
            terms.append(nt.FilteredNoise(b, a, _stream(root, *key, 0)))
        elif name == RINGING:
            terms.append(Ringing(eff["shock_rate_hz"], eff["shock_dps"], eff["center_hz"], eff["q"], sample_rate_hz,
                                 _stream(root, *key, 0), _stream(root, *key, 1), eff["spread_ln"]))
        elif name == WANDERING_TONE:
            terms.append(WanderingTone(eff["amplitude_dps"], eff["center_hz"], eff["spread_hz"], eff["wander_s"],
                                       sample_rate_hz, _stream(root, *key, 0), eff["excursion_hz"],
                                       eff["excursion_period_s"], eff["excursion_s"], _stream(root, *key, 1)))
        elif name == OUTLIERS:
            outliers.append(nt.Outliers(eff["rate"], eff["magnitude_dps"], _stream(root, *key, 0), _stream(root, *key, 1), eff["spread_ln"]))
        # colored_noise and heavy_tails are part of the noise term, compression acts on the fast terms
        slow += [name in SLOW] * (len(terms) - len(slow))
    compression = next((e for e in spec["effects"] if e["effect"] == COMPRESSION), None)
    if compression is None:
        return AxisTerms(terms, noise, outliers)
    return AxisTerms([t for t, s in zip(terms, slow) if s], noise, outliers,
                     Compression(compression["gamma_per_dps2"], compression["rms_dps"]),
                     [t for t, s in zip(terms, slow) if not s])


def sample_count(duration_s, sample_rate_hz):
    """Number of samples of a run: round(duration · f_s), at least 1.

    ``duration_s``: run length (s), in (0, MAX_DURATION_S] (:func:`~gyrofilter.units.check_duration_s`;
    else SettingsError); ``sample_rate_hz``: f_s (Hz). Returns an int.
    """
    duration_s = check_duration_s(duration_s, "simulate: duration_s")
    return max(1, int(round(duration_s * sample_rate_hz)))


def check_sample_count(duration_s, sample_rate_hz, name="simulate: duration_s"):
    """:func:`sample_count` of a run that is held whole (in memory or in a file), at most
    :data:`MAX_SAMPLES`, else SettingsError (a ValueError) naming ``name``, the count and the limit."""
    n_total = sample_count(duration_s, sample_rate_hz)
    if n_total > MAX_SAMPLES:
        raise SettingsError(f"{name}: {float(duration_s):g} s at {sample_rate_hz:g} Hz is {n_total:.3g} samples; "
                            f"a simulated recording holds at most {MAX_SAMPLES:.0e} (MAX_SAMPLES; simulate_chunks "
                            "streams longer runs block by block)")
    return n_total


def _check_chunk_samples(chunk_samples):
    """``chunk_samples`` as an int >= 1, else SettingsError."""
    return check_number(chunk_samples, "simulate: chunk_samples", low=1, integer=True)


class Block(NamedTuple):
    """One block of a simulation (:func:`simulate_chunks`): ``t_s`` (n,) seconds; ``gyro`` (n, 3)
    in the model's ``gyro_unit`` (integers as floats for ``lsb``); ``temp_c`` (n,) deg C, or None
    without a temperature profile; ``accel`` (n, 3) in the model's ``accel_unit`` (m/s^2, or LSB
    as floats), or None without an accelerometer."""

    t_s: np.ndarray
    gyro: np.ndarray
    temp_c: np.ndarray | None
    accel: np.ndarray | None


def block_rows(block):
    """The rows of a :class:`Block`, shape (n, len(columns)), in the order of :func:`recording_columns`:
    t, the gyro, temp (when present), the accelerometer (when present)."""
    parts = [block.t_s[:, None], block.gyro]
    if block.temp_c is not None:
        parts.append(block.temp_c[:, None])
    if block.accel is not None:
        parts.append(block.accel)
    return np.hstack(parts)


def simulate_chunks(model, duration_s, *, sample_rate_hz=None, chunk_samples=DEFAULT_CHUNK_SAMPLES, rng=None, seed=None,
                    validated=None):
    """Simulate in blocks of ``chunk_samples``: yields a :class:`Block` ``(t_s, gyro, temp_c, accel)``
    per block.

    ``t_s`` (n,) seconds, ``gyro`` (n, 3) in the model's ``gyro_unit`` (integers as floats for
    ``lsb``), ``temp_c`` (n,) or None without a temperature profile, ``accel`` (n, 3) in the
    model's ``accel_unit`` (:mod:`gyrofilter.sim.accel`) or None without an accelerometer. Memory
    is bounded by the block size (and the flicker banks' ~3 numbers per decade); the concatenated
    blocks equal :func:`simulate`'s output for the same seed, whatever the block size.

    ``model``: the model dict (:func:`validate_model`); ``duration_s``: run length (s), rounded
    to whole samples (:func:`sample_count`); ``sample_rate_hz``: rate (Hz) overriding the
    model's; ``chunk_samples``: samples per block (>= 1); ``seed`` (int >= 0) or ``rng`` (a
    ``numpy.random.Generator``), not both; neither draws fresh entropy; ``validated``: the
    ``normalized`` dict of :func:`validate_model` when the caller already has it (then
    ``sample_rate_hz`` is not used). A generator: nothing is computed until iterated.
    """
    spec = validated if validated is not None else validate_model(model, sample_rate_hz=sample_rate_hz)[0]
    chunk_samples = _check_chunk_samples(chunk_samples)
    sample_rate_hz = spec["sample_rate_hz"]
    n_total = sample_count(duration_s, sample_rate_hz)
    duration_s = n_total / sample_rate_hz
    root = _root_seed(seed, rng)
    temp = nt.TemperatureProfile(spec[TEMPERATURE_PROFILE], _stream(root, 3, 0, 0, 0)) if spec[TEMPERATURE_PROFILE] else None
    axes = [_axis_terms(i, spec["axes"][a], sample_rate_hz, duration_s, root, temp) for i, a in enumerate(AXES)]
    accel_model = _accelerometer(spec, sample_rate_hz, duration_s, root, temp)
    repeats, last = _repeats(spec, root), [None] * 7  # gx, gy, gz, temp, ax, ay, az
    for start in range(0, n_total, chunk_samples):
        n = min(chunk_samples, n_total - start)
        t_s = np.arange(start, start + n) / sample_rate_hz
        true_c = temp.true_c(t_s) if temp else None
        gyro = np.empty((n, 3))
        for i, terms in enumerate(axes):
            gyro[:, i] = _axis_rate(terms, t_s, true_c, spec)
        temp_c = temp.recorded_c(true_c) if temp else None
        accel = accel_model.next(t_s, true_c) if accel_model else None
        if repeats is not None:
            mask = repeats.next_mask(n)
            for i in range(3):
                gyro[:, i], last[i] = repeats.apply(gyro[:, i], mask, last[i])
            if temp_c is not None:
                temp_c, last[3] = repeats.apply(temp_c, mask, last[3])
            for i in range(3 if accel is not None else 0):
                accel[:, i], last[4 + i] = repeats.apply(accel[:, i], mask, last[4 + i])
        yield Block(t_s, gyro, temp_c, accel)


def _axis_rate(axis_terms, t_s, true_c, spec):
    """One block of one axis in the model's ``gyro_unit``: the sum of the terms, saturation,
    quantization and the unit (the equations of the module docstring)."""
    terms, noise, outliers, compression, fast = axis_terms
    rate = noise.next(t_s, true_c)
    if compression is not None:
        for term in fast:
            rate += term.next(t_s, true_c)
        compression.apply(rate)
    for term in terms:
        rate += term.next(t_s, true_c)
    for term in outliers:
        rate += term.next(t_s, true_c)
    if spec["full_scale_dps"] is not None:
        np.clip(rate, -spec["full_scale_dps"], spec["full_scale_dps"], out=rate)
    lsb = spec["lsb_per_dps"]
    if lsb is not None:  # in place: ``rate`` is this block's own array
        np.multiply(rate, lsb, out=rate)
        np.round(rate, out=rate)
        if spec["gyro_unit"] != "lsb":
            rate /= lsb
    if spec["gyro_unit"] == "rad/s":
        rate /= DEG_PER_RAD
    if not np.isfinite(rate).all():  # the last guard: validate_model's bounds should make this unreachable
        raise SettingsError(f"simulate: the model gives a non-finite rate at t = {t_s[~np.isfinite(rate)][0]:g} s")
    return rate


def simulate_axis_dps(model, duration_s, axis, *, seed=None, chunk_samples=DEFAULT_CHUNK_SAMPLES, validated=None):
    """One axis of :func:`simulate` in deg/s, block by block: yields 1-D arrays of at most
    ``chunk_samples`` samples whose concatenation equals ``simulate(model, duration_s,
    seed=seed).gyro_dps[:, axis]`` bit for bit (every random term draws from its own stream,
    keyed by the axis, so the other axes need not be generated). For analyses that simulate
    one axis many times (:mod:`gyrofilter.analysis.gap.pipeline`): no time column, no other axes, memory bounded
    by the block.

    ``model``: the model dict; ``duration_s``: run length (s); ``axis``: 0, 1 or 2 (x, y, z);
    ``seed``: int >= 0 (None: fresh entropy); ``chunk_samples``: samples per block;
    ``validated``: the already validated model (:func:`validate_model`), if at hand. The rates
    are the model's output converted to deg/s, so quantization and saturation are kept.
    """
    spec = validated if validated is not None else validate_model(model)[0]
    chunk_samples = _check_chunk_samples(chunk_samples)
    sample_rate_hz = spec["sample_rate_hz"]
    n_total = sample_count(duration_s, sample_rate_hz)
    root = _root_seed(seed, None)
    temp = nt.TemperatureProfile(spec[TEMPERATURE_PROFILE], _stream(root, 3, 0, 0, 0)) if spec[TEMPERATURE_PROFILE] else None
    axis = check_number(axis, "simulate: axis (0, 1 or 2: x, y, z)", low=0, high=len(AXES) - 1, integer=True)
    terms = _axis_terms(axis, spec["axes"][AXES[axis]], sample_rate_hz, n_total / sample_rate_hz, root, temp)
    repeats, last = _repeats(spec, root), None
    for start in range(0, n_total, chunk_samples):
        t_s = np.arange(start, min(start + chunk_samples, n_total)) / sample_rate_hz
        rate = _axis_rate(terms, t_s, temp.true_c(t_s) if temp else None, spec)
        if repeats is not None:
            rate, last = repeats.apply(rate, repeats.next_mask(rate.size), last)
        yield to_dps(rate, spec["gyro_unit"], spec["lsb_per_dps"])


def draw_seed():
    """A fresh random seed in [0, 2^31) from the OS entropy, for a run without one: written in the
    header (``simulated_seed``) so that the run can be repeated."""
    return int(np.random.SeedSequence().entropy % (2 ** 31))


def recording_header(model, duration_s, *, sample_rate_hz=None, seed=None, validated=None):
    """Header for a simulated recording: units, ``sensor: simulated`` and the model as compact JSON.

    ``model``: the model as given (written back as ``simulated_model``, with the rate used);
    ``duration_s``: the run length (s; written as ``simulated_duration_s``, rounded to whole
    samples); ``sample_rate_hz``: rate (Hz) overriding the model's; ``seed``: written as
    ``simulated_seed`` (``none`` when None); ``validated``: the validated model, if at hand.
    Returns a dict of text values (``sample_rate_hz`` in Hz, ``gyro_unit``, ``lsb_per_dps`` with
    ``lsb``, ``full_scale_dps`` in deg/s when the model has one, ``accel_unit`` and, with ``lsb``,
    ``lsb_per_g`` when it has an accelerometer) for :class:`~gyrofilter.recording.RecordingWriter`.
    """
    spec = validated if validated is not None else validate_model(model, sample_rate_hz=sample_rate_hz)[0]
    given = dict(model)
    given["sample_rate_hz"] = spec["sample_rate_hz"]
    header = {VERSION_KEY: FORMAT_VERSION, "sensor": "simulated",
              **units_header(spec["sample_rate_hz"], spec["gyro_unit"], spec.get("lsb_per_dps"))}
    if spec["full_scale_dps"] is not None:
        header["full_scale_dps"] = format_number(spec["full_scale_dps"])
    accel = spec[ACCELEROMETER]
    if accel is not None:
        header.update(accel_units_header(accel["accel_unit"], accel.get("lsb_per_g")))
    header["simulated_duration_s"] = format_number(sample_count(duration_s, spec["sample_rate_hz"]) / spec["sample_rate_hz"])
    header["simulated_seed"] = "none" if seed is None else str(int(seed))
    header["simulated_model"] = json.dumps(given, separators=(",", ":"), sort_keys=False, default=_json_default)
    return header


def _json_default(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):  # a longdouble's item() is itself: json_default recursed without end
        return python_value(value)
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def recording_columns(model_or_spec):
    """Column names of a simulated recording: t, gx, gy, gz (+ temp with a temperature profile,
    + ax, ay, az with an accelerometer).

    ``model_or_spec``: the model dict or its validated form. Returns a list of names: ``t`` in
    s, the gyro columns in the model's ``gyro_unit``, ``temp`` in deg C, the accelerometer's in its
    ``accel_unit`` (:func:`block_rows` orders a block's values so).
    """
    has_temp = model_or_spec.get(TEMPERATURE_PROFILE) is not None
    has_accel = model_or_spec.get(ACCELEROMETER) is not None
    return list(COLUMNS) + (["temp"] if has_temp else []) + (list(ACCEL_COLUMNS) if has_accel else [])


def recording_formats(spec):
    """The %-formats of :func:`recording_columns` for a writer fed in blocks: ``%d`` for the
    columns in LSB (integers by construction), :data:`~gyrofilter.recording.EXACT_FORMAT` for the
    others, so that the text does not depend on the block size (a writer left to choose per block
    wrote a one-row block's t of 0 as ``0``, the next block's as ``0.0``). ``spec``: the
    validated model (:func:`validate_model`)."""
    def fmt(unit):
        return "%d" if unit == "lsb" else EXACT_FORMAT

    accel = spec.get(ACCELEROMETER)
    return [EXACT_FORMAT] + [fmt(spec["gyro_unit"])] * 3 + ([EXACT_FORMAT] if spec.get(TEMPERATURE_PROFILE) is not None
                                                             else []) + ([fmt(accel["accel_unit"])] * 3 if accel else [])


def simulate(model: dict, duration_s: float, *, sample_rate_hz=None, rng=None, seed=None,
             chunk_samples=DEFAULT_CHUNK_SAMPLES, accelerometer=True) -> Recording:
    """Simulate ``duration_s`` seconds of ``model`` in memory and return a :class:`Recording`.

    Columns t, gx, gy, gz (model's ``gyro_unit``), temp (with a temperature profile) and ax, ay,
    az (with an accelerometer, in its ``accel_unit``); the header carries ``sensor: simulated``,
    ``simulated_model`` (compact JSON) and the seed. ``sample_rate_hz`` overrides the model's
    rate. Same seed, same numbers.

    ``model``: the model dict (:func:`validate_model`); ``duration_s``: run length (s), rounded
    to whole samples; ``sample_rate_hz``: Hz; ``seed`` (int >= 0) or ``rng``
    (``numpy.random.Generator``), not both (neither: fresh entropy, and the header's
    ``simulated_seed`` is ``none``); ``chunk_samples``: block size of the computation (does not
    change the numbers); ``accelerometer``: False leaves the model's accelerometer out (no ax,
    ay, az, nothing of it computed; the other columns are the same). Memory: the whole run, 32
    bytes a sample (40 with a temperature, 24 more with an accelerometer), at most
    :data:`MAX_SAMPLES` samples (more: SettingsError, a ValueError; :func:`simulate_chunks` streams them).
    """
    spec, _ = validate_model(model, sample_rate_hz=sample_rate_hz)
    if not accelerometer:
        spec = {**spec, ACCELEROMETER: None}
    n_total = check_sample_count(duration_s, spec["sample_rate_hz"])
    columns = {name: np.empty(n_total) for name in recording_columns(spec)}
    start = 0
    for block in simulate_chunks(model, duration_s, chunk_samples=chunk_samples, rng=rng, seed=seed, validated=spec):
        stop = start + len(block.t_s)
        for column, values in zip(columns.values(), block_rows(block).T):
            column[start:stop] = values
        start = stop
    header = recording_header(model, duration_s, seed=seed, validated=spec)
    return Recording(columns=columns, header=header)


def simulate_dps(model, duration_s, *, sample_rate_hz=None, rng=None, seed=None):
    """Convenience for analyses: ``(gyro_dps (N, 3), temp_c or None)`` of a run.

    Same parameters as :func:`simulate` (``duration_s`` in s, ``sample_rate_hz`` in Hz, ``seed``
    or ``rng``). Returns the rates in deg/s whatever the model's ``gyro_unit`` (after its
    quantization and saturation) and the recorded temperature (deg C) or None.
    """
    rec = simulate(model, duration_s, sample_rate_hz=sample_rate_hz, rng=rng, seed=seed, accelerometer=False)
    return rec.gyro_dps, rec.temp_c
