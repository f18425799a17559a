"""The effect registry: one record per effect that the simulator adds to a gyro's rate and the
gap analysis names, the one place where an effect's name, kind and parameters are stated.

An effect is a term of the model's axis (docs/formats.md, section 2): its **name** (the
``effect`` key of a model entry and of a gap finding; code spells it through the constants
below, never as a literal), its **kind**, its **parameters** (required, each with the check of
:data:`gyrofilter.sim.model._KINDS`; optional, each with its check and default) and the
**scale** on which the gap analysis computes each parameter's 95 % interval
(:mod:`gyrofilter.analysis.gap.intervals`: ``log`` for positive scale parameters, ``atanh`` for
autocorrelations, ``phase`` for radians, else linear) and its **defining** parameter, the one
whose size says the effect is there (a gap finding whose defining parameter the record does not
determine is listed as uncertain, not named).

The kinds, and the groups every module derives from them (never a list of its own):

- ``wander``: a slow stochastic wander of the bias (bias instability, rate random walk,
  Gauss-Markov), found by the slow detector's spectral fits (:data:`WANDERS`);
- ``shape``: a deterministic shape of the bias in time (ramp, step, warm-up; :data:`SHAPES`);
- ``covariate``: the bias following a measured quantity (the temperature; :data:`COVARIATES`);
- ``line``: a peak of the spectrum: a deterministic periodic rate (a sinusoid), noise in a narrow
  band around a centre frequency (a line of finite width), a broad low hump of noise (a
  resonance of the board driven by noise), the same resonance rung by random shocks (bursts
  that decay), or a tone of constant amplitude whose frequency wanders within a band (a line of
  finite width that is not Gaussian); the gap analysis names one reading of a peak, or two where
  both are there (:data:`LINES`);
- ``noise``: stationary noise with a broad spectrum other than white (colored noise, an ARMA
  process);
- ``tails``: the rate's distribution (isolated spikes, heavy tails; :data:`TAILS`);
- ``rows``: whole rows of the record, every axis (and the temperature) at once, after the
  quantization (rows that repeat the previous one: a driver polling faster than the sensor
  updates its registers; :data:`ROWS`). Not a term of an axis: a model gives it as a top-level
  key of its own name (docs/formats.md, section 2), because the axes are simulated
  independently and a per-axis term could not repeat the same rows on every axis.
- ``transfer``: a transfer acting on the sum of an axis's fast terms (a cubic compression about
  the slow level; :data:`TRANSFERS`): not a term added to the rate, a map of the others.

The registry's **order** is the simulator's: each effect's random stream is keyed by its place
(:mod:`gyrofilter.sim.simulate`), so a new effect is appended at the end.
"""
from __future__ import annotations

from dataclasses import dataclass, field

BIAS_INSTABILITY = "bias_instability"
RATE_RANDOM_WALK = "rate_random_walk"
RATE_RAMP = "rate_ramp"
GAUSS_MARKOV = "gauss_markov"
SINUSOID = "sinusoid"
TEMPERATURE = "temperature"
BIAS_STEP = "bias_step"
WARMUP = "warmup"
OUTLIERS = "outliers"
COLORED_NOISE = "colored_noise"
NARROWBAND = "narrowband"
ARMA = "arma"
HEAVY_TAILS = "heavy_tails"
REPEATED_SAMPLES = "repeated_samples"
RESONANCE = "resonance"
RINGING = "ringing"
WANDERING_TONE = "wandering_tone"
COMPRESSION = "compression"

KINDS = ("wander", "shape", "covariate", "line", "noise", "tails", "rows", "transfer")


@dataclass(frozen=True)
class Effect:
    """One effect of the registry (module docstring)."""

    name: str
    kind: str
    #: parameter -> its check (a kind of :data:`gyrofilter.sim.model._KINDS`)
    required: dict
    #: parameter -> (its check, its default; None: the effect's own rule)
    optional: dict = field(default_factory=dict)
    #: parameter -> the scale of its bootstrap interval (``log``, ``atanh``, ``phase``; absent: linear)
    interval_scales: dict = field(default_factory=dict)
    #: the required parameter whose size says the effect is there: a gap finding whose defining
    #: parameter the record does not determine is not named (:mod:`gyrofilter.analysis.gap.intervals`)
    defining: str = field(kw_only=True)

    def __post_init__(self):
        if self.defining not in self.required:
            raise ValueError(f"effect {self.name}: its defining parameter {self.defining!r} is not a required one")

    @property
    def n_params(self):
        """The parameters a fit of the effect estimates (its required ones): what an information
        criterion or a likelihood-ratio penalty counts."""
        return len(self.required)


REGISTRY = (
    Effect(BIAS_INSTABILITY, "wander", {"b_dps": "nonneg"},
           {"tau_min_s": ("pos", None), "tau_max_s": ("pos", None), "per_decade": ("pos", 2.0)}, {"b_dps": "log"},
           defining="b_dps"),
    Effect(RATE_RANDOM_WALK, "wander", {"k_dps_per_sqrt_s": "nonneg"}, {}, {"k_dps_per_sqrt_s": "log"},
           defining="k_dps_per_sqrt_s"),
    Effect(RATE_RAMP, "shape", {"r_dps_per_s": "any"}, defining="r_dps_per_s"),
    Effect(GAUSS_MARKOV, "wander", {"sigma_dps": "nonneg", "tau_s": "pos"}, {}, {"sigma_dps": "log", "tau_s": "log"},
           defining="sigma_dps"),
    Effect(SINUSOID, "line", {"frequency_hz": "nonneg", "amplitude_dps": "nonneg"}, {"phase_rad": ("any", 0.0)},
           {"amplitude_dps": "log", "phase_rad": "phase"}, defining="amplitude_dps"),
    Effect(TEMPERATURE, "covariate", {"coefficient_dps_per_c": "any"}, {"reference_c": ("any", None)},
           defining="coefficient_dps_per_c"),
    Effect(BIAS_STEP, "shape", {"time_s": "nonneg", "size_dps": "any"}, defining="size_dps"),
    Effect(WARMUP, "shape", {"amplitude_dps": "any", "tau_s": "pos"}, {}, {"tau_s": "log"}, defining="amplitude_dps"),
    Effect(OUTLIERS, "tails", {"rate": "frac", "magnitude_dps": "nonneg"}, {"spread_ln": ("nonneg", 0.25)},
           {"rate": "log", "magnitude_dps": "log"}, defining="magnitude_dps"),
    Effect(COLORED_NOISE, "noise", {"lag1": "lag"}, {"lag2": ("lag", None), "preserve": ("choice:arw,std", "arw")},
           {"lag1": "atanh", "lag2": "atanh"}, defining="lag1"),
    Effect(NARROWBAND, "line", {"center_hz": "pos", "bandwidth_hz": "pos", "rms_dps": "nonneg"}, {},
           {"bandwidth_hz": "log", "rms_dps": "log"}, defining="rms_dps"),
    Effect(ARMA, "noise", {"sigma_a_dps": "nonneg"}, {"phi": ("coefs", []), "theta": ("coefs", [])},
           defining="sigma_a_dps"),
    Effect(HEAVY_TAILS, "tails", {"fraction": "frac", "scale_ratio": "pos"}, {}, {"fraction": "log", "scale_ratio": "log"},
           defining="scale_ratio"),
    Effect(REPEATED_SAMPLES, "rows", {"fraction": "frac"}, {"pattern": ("choice:random,beat", "random")},
           {"fraction": "log"}, defining="fraction"),
    Effect(RESONANCE, "line", {"center_hz": "pos", "q": "pos", "rms_dps": "nonneg"}, {},
           {"q": "log", "rms_dps": "log"}, defining="rms_dps"),
    Effect(RINGING, "line", {"center_hz": "pos", "q": "pos", "shock_rate_hz": "pos", "shock_dps": "nonneg"},
           {"spread_ln": ("nonneg", 0.25)}, {"q": "log", "shock_rate_hz": "log", "shock_dps": "log"},
           defining="shock_dps"),
    Effect(WANDERING_TONE, "line", {"center_hz": "pos", "spread_hz": "nonneg", "wander_s": "pos", "amplitude_dps": "nonneg"},
           {"excursion_hz": ("nonneg", 0.0), "excursion_period_s": ("pos", None), "excursion_s": ("pos", None)},
           {"spread_hz": "log", "wander_s": "log", "amplitude_dps": "log"}, defining="amplitude_dps"),
    Effect(COMPRESSION, "transfer", {"gamma_per_dps2": "nonneg", "rms_dps": "pos"}, {},
           {"gamma_per_dps2": "log", "rms_dps": "log"}, defining="gamma_per_dps2"),
)
#: name -> record, in the registry's order
BY_NAME = {e.name: e for e in REGISTRY}


def of_kind(*kinds):
    """The names of the effects of these kinds, in the registry's order."""
    return tuple(e.name for e in REGISTRY if e.kind in kinds)


#: the slow stochastic wanders of the bias
WANDERS = of_kind("wander")
#: the deterministic shapes of the bias in time
SHAPES = of_kind("shape")
#: the effects that follow a measured covariate
COVARIATES = of_kind("covariate")
#: everything slow: the wanders, the shapes in time and the covariates (the slow detector's effects)
SLOW = of_kind("wander", "shape", "covariate")
#: the effects of the rate's distribution
TAILS = of_kind("tails")
#: the effects on whole rows (every axis at once): a model's top-level keys, not terms of an axis
ROWS = of_kind("rows")
#: the transfers acting on an axis's fast terms (a map of the terms, not a term)
TRANSFERS = of_kind("transfer")
#: the peaks of the spectrum: a sinusoid, a narrow band, a resonance's hump and its ringing, a
#: wandering tone, alternative readings of one peak of the spectrum
LINES = of_kind("line")
#: the parameter that holds each line's frequency (Hz)
LINE_FREQUENCY = {SINUSOID: "frequency_hz", NARROWBAND: "center_hz", RESONANCE: "center_hz", RINGING: "center_hz",
                  WANDERING_TONE: "center_hz"}
#: the resonator's effects: its hump (white noise through it) and its ringing (shocks through it)
RESONATORS = (RESONANCE, RINGING)
