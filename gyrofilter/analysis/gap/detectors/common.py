"""Shared by the detectors: the thresholds of the gap analysis (the detectors' significance
levels and the gap's decision rules; those of the confounded causes are in
:mod:`gyrofilter.analysis.gap.confound`), :class:`Candidate` (the shared statistics are in
:mod:`gyrofilter.analysis.stats`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: expected number of false spikes per axis on white Gaussian noise (with at least
#: OUTLIER_MIN_COUNT spikes required: P(Poisson(0.05) >= 3) = 2e-5 per axis)
OUTLIER_FALSE_PER_AXIS = 0.05
#: minimum number of spikes for an outlier finding
OUTLIER_MIN_COUNT = 3
#: heavy tails (detectors.tails): the winsorizing level (robust sd) of the tail statistic, the
#: z its value must reach against the baseline's simulations (or its Gaussian sampling sd) and the
#: 2 Delta log L a Gaussian scale mixture must gain over a Gaussian (the margin over isolated
#: spikes is a rule of the confounded causes: gap.confound.HEAVY_TAILS_OVER_SPIKES). The mixture's threshold is set from clean records
#: only: on 100 simulated ones (white, AR(1) lag1 0.3-0.85, a two-tap average, a narrow band, a
#: large sinusoid, 1 kHz; 10-60 min, MPU6050 quantization) its largest value was 7.4, on the
#: real MPU6050 and ADIS16405 static records (15 axes) 11.3, so 30 sits 2.7-4 times above
TAILS_WINSOR_SD = 6.0
#: a rate quantized in steps above this many noise sd has the quantizer's distribution, not the
#: noise's: its tails are not judged without the baseline's simulations, which carry the same
#: quantizer (the MPU6050 at 131 LSB per deg/s: 0.06-0.11)
TAILS_MAX_STEP_SD = 0.5
HEAVY_TAILS_Z = 4.0
HEAVY_TAILS_THRESHOLD = 30.0
#: false-alarm probability per axis for the periodogram line test
SINUSOID_ALPHA = 1e-4
#: z-score (in units of 1/sqrt(N)) the lag-1 autocorrelation must exceed, and the smallest
#: |lag1| reported (smaller correlations are real but immaterial)
COLORED_Z = 6.0
COLORED_MIN_LAG1 = 0.03
#: the z (units of 1/sqrt(N)) of a colored noise proposed late (:mod:`gyrofilter.analysis.gap.late_colored`):
#: on an axis that does not close (D after above OUTSIDE_NULL_D) whose largest departure from the
#: extended model is the lag-1 autocorrelation, by at least this many sd of its runs
COLORED_LATE_Z = 3.0
#: the colored noise's lag-2 is reported (a first-order ARMA instead of the low pass) when it
#: falls below lag1^2 (the AR(1) value) by COLORED_Z standard errors and by at least this much
COLORED_MIN_LAG2_GAP = 0.01
#: Delta chi^2 / 2 Delta log L thresholds of the slow-effect tests, set from clean recordings
#: only (white noise + quantization + a temperature column, 10 and 40 min, 60 runs): the
#: largest null values were 10.6 (step scan), 6.9 (warm-up scan, ramp, temperature) and 4.4
#: (Gauss-Markov), so the thresholds sit 2-4 times above the null maxima
DETERMINISTIC_THRESHOLD = 25.0
STOCHASTIC_THRESHOLD = 16.0
#: 2 Delta log L an extra spectral parameter must buy (chi^2_1: about 1.4 %)
STOCHASTIC_PENALTY = 6.0
#: z^2 a deterministic shape must reach against the fitted stochastic noise to be kept with it
JOINT_THRESHOLD = 25.0
#: a shape in time (step, ramp, warm-up) is named only where white noise with flicker fitted to the
#: record draws its likelihood ratio over flicker as clearly in at most this share of records
#: (:func:`~gyrofilter.analysis.gap.detectors.flicker.flicker_p_value`); a temperature under a bias
#: instability, and a ramp or step in the place of a temperature, are held to the same test
FLICKER_ALPHA = 0.01
#: records of that parametric bootstrap, their block means (at most) and their fixed stream
FLICKER_REPLICATES = 1000
FLICKER_BLOCKS = 128
#: the flicker-to-white ratios (flicker variance of a block mean over the white level) over which
#: :func:`~gyrofilter.analysis.gap.detectors.flicker.flicker_p_value` profiles its likelihoods, with 0 (no flicker)
FLICKER_RATIOS = np.geomspace(1e-3, 1e3, 25)
FLICKER_STREAM = 20261129
#: 2 Delta log L (exact likelihood) a Gauss-Markov process must gain over a random walk
EXACT_GM_MARGIN = 8.0
#: a Gauss-Markov process whose tau exceeds the record length over this is a random walk as far
#: as the data can tell
GM_MAX_TAU_DIVISOR = 5
#: the band statistic (peak excess over the background in units of its sampling error,
#: ``(R - 1) sqrt(K)``) a band must exceed; on white and AR(1) noise (white + 0.3 white, lag1
#: -0.7 to 0.7, 4096 to 10^6 samples at 99.37, 100 and 285.7 Hz, 240 runs, issue 12) its
#: largest value was 2.16 (at 4096 samples and 285.7 Hz; 1.5-1.7 from 7 500 samples up), its
#: 99th percentile 1.73; on 400 more of 4096-12 000 samples 2.31 (2.29 within W of f_s / 2);
#: at the Nyquist edge of AR(1) lag1 -0.7 (a PSD peaking at f_s / 2) 2.2 on 10^6 and 2.4 on
#: 8.64 * 10^6 samples at 100 Hz
NARROWBAND_THRESHOLD = 4.0
#: a band is a wandering tone when its excess kurtosis is below 0 by this many standard errors
#: (block standard error over :data:`TONE_BLOCKS` blocks, a t with 31 degrees of freedom: a
#: Gaussian band passes with probability about 2e-4; on 40 Gaussian bands of 0.2-4 Hz at 12-45 Hz,
#: 10-60 min at 100 Hz, the statistic's sd was 1.3 and its largest value 2.76) ...
TONE_KURTOSIS_Z = 4.0
#: ... and nearer a tone's than a Gaussian's: at least this fraction of the -3/2 s² of a
#: constant-amplitude tone whose share of the band's variance is s (detectors/tone.py)
TONE_MIN_FRACTION = 0.5
#: the blocks the band's kurtosis is computed in for its standard error
TONE_BLOCKS = 32
#: a tone whose frequency track spreads less than this many bins of its short-time spectrum
#: (f_s / L) keeps one frequency: a sinusoid, not a wandering tone
TONE_MIN_SPREAD_BINS = 0.5
#: a named wandering tone carries a periodic excursion of its frequency where the envelope line of
#: the power beside its band (detectors/excursion.py) reaches this many times the median ordinate:
#: a stationary band's is about 15 on average at 20 000 ordinates and passes 50 with probability
#: about K 2^-50 (2e-11). Measured without excursion (tools/tone_modulation.py): on 40 hidden-effect
#: wandering tones (10-60 min) the largest was 19, on 8 runs of the ADIS16405 z axes' extended
#: models 17, so 50 sits 2.6 times above; the two ADIS16405 z axes read 427 and 1175
EXCURSION_LINE_RATIO = 50.0
#: repeated rows: the level of the one-sided binomial test of the rows equal to the previous one
#: against their chance level (:mod:`gyrofilter.analysis.repeats`), for the gap's finding and for
#: the warnings of ``allan`` and ``report``. Clean quantized 16-min records at 43 Hz (0.5-10 LSB of
#: white noise, and lag-1 0.4 and 0.7): 0 of 220 below it, the smallest p-value 0.013; the 50 of
#: tests/test_repeats.py: smallest 0.064
REPEATS_ALPHA = 1e-3
#: the statistic of a repeated-rows finding, -log10 p, is capped here (a p-value underflows to 0)
REPEATS_MAX_STATISTIC = 300.0
#: colored noise under repeated rows (:func:`~gyrofilter.analysis.gap.detectors.colored.lags_without_repeats`):
#: the least weight 1 - 2f of the noise's lag-2 in the measured one for which it is solved from it; above
#: f = 0.45 (a record of half its rows repeated: 1 - 2f = 0, the division failed) the lag-2 is taken as a
#: first-order low pass's, rho1^2
REPEATS_LAG2_MIN_WEIGHT = 0.1
#: the hump statistic (the drop of the Welch log-PSD residual sum of squares by a resonance, in
#: residual variances: detectors.resonance) a hump must exceed, set from clean records only: on
#: 120 simulated axes without a hump (white, AR(1) and ARMA colored noise, bias instability,
#: Gauss-Markov, heavy tails, outliers, sinusoids; 10-60 min at 100 Hz, MPU6050 quantization)
#: its largest value with Q in the hump's range was 26 (43 with a narrower or broader peak), so
#: 60 sits more than twice above; a hump 1.5 times the level (issue 36) reads 100-1200 in 15 min
RESONANCE_THRESHOLD = 60.0
#: the quality factors Q = f0 / B of a hump: a narrower peak (Q above the largest) is a line
#: (narrowband), a broader one (below the smallest: more than an octave and a half between its
#: half-power points) a tilt of the background. The board resonance of issue 36 is a hump of Q
#: about 4 (10.5-13.5 Hz at 12 Hz); the narrow bands of the tests and of the DLPF's ringing are Q 8-60
RESONANCE_MIN_Q = 0.7
RESONANCE_MAX_Q = 5.0
#: the narrowest peak named a hump where the narrow-band detector finds no line at it: a hump read
#: a little narrow (a hump of Q 4, 1.5 times the level, read Q 5.3 [3.4, 8.7] on a 10-min record and
#: fell between the two detectors); a narrower peak the narrow-band detector does not take is a weak
#: line, not named (one of Q 30 at 22.5 Hz on the shipped 123-s log's z)
RESONANCE_UNSEEN_MAX_Q = 8.0
#: the lowest centre of a hump, as a fraction of the Nyquist frequency: twice the lowest
#: frequency of the hump's fit (detectors.resonance.RESONANCE_MIN_FRACTION); a peak below it sits on
#: the rise of the slow effects' spectra (two Gauss-Markov terms at 10 Hz read a hump at 0.11 Hz)
RESONANCE_LOWEST_FRACTION = 0.04
#: the ringing statistic (the energy fitted rings explain beyond isolated spikes, in noise
#: variances: detectors.ringing) shocks that ring must exceed; isolated spikes and heavy tails read
#: below 0 (a spike projects on a ring by at most 1 / <g, g> of its energy), set from them (below)
RINGING_THRESHOLD = 50.0
#: D above which an axis is clearly outside the null band (its 95th percentile is 1.06-1.96 on
#: clean records of 27 s to 2.8 h, docs/gap_closure.md): an extended axis is then tried with a
#: composite stochastic part, and the report says which feature still departs
OUTSIDE_NULL_D = 2.0
#: the factor a composite stochastic part must lower D by (and a compression: gap.compression)
COMPOSITE_MIN_GAIN = 0.8
#: the tail statistic's departure (z) from the extended model's runs below which an axis still
#: outside the null band is tried with a ``compression`` (gap.compression): lighter tails than the
#: model's by 4 sd of its runs, the mirror of HEAVY_TAILS_Z; a Gaussian record's z is about N(0, 1)
#: against its own model (the ADIS16405 z axes: about -10)
COMPRESSION_TAILS_Z = -4.0
#: each finding's evidence names the feature where its axis (as a whole, not the finding) departs
#: most from the baseline simulations when it is at least this many standard deviations of their
#: spread away
REPORTED_DEPARTURE_Z = 3


@dataclass
class Candidate:
    """A departure from the baseline, mapped to an effect of the table: a detector's finding, and
    what the later steps of the gap analysis decide about it (they replace a candidate with
    :func:`dataclasses.replace`, never change it)."""

    effect: str
    params: dict
    statistic: float
    threshold: float
    #: the detector's sentence; :attr:`evidence_notes` are what later steps add to it
    evidence: str
    statistic_name: str = ""
    #: model component to subtract from the series (deterministic effects), per sample, or None
    component: object = None
    #: a temperature's reference (deg C): the record's mean temperature
    reference_c: float | None = None
    #: the slow detector's other reading beside it, for the confounded causes to weigh
    #: (:mod:`gyrofilter.analysis.gap.confound`): the other reading of a confounded temperature
    #: (candidates: the time reading on a temperature candidate, the covariate reading on the time
    #: reading's first candidate where that reading is the simpler), a bias instability's or
    #: Gauss-Markov's other wander
    other_reading: list | None = None
    wander_alternative: Candidate | None = None
    #: a wandering tone's band read as Gaussian noise (candidates: the narrow band it was read from
    #: and the colored noise left beside it), for :func:`gyrofilter.analysis.gap.confound.weigh_tones`
    band_alternative: list | None = None
    #: "other" for a candidate of the other reading of a confounded temperature (its axis spec is
    #: :attr:`~gyrofilter.analysis.gap.state.AxisModels.other`)
    reading: str = ""
    #: part of a composite stochastic model (its white level, ``preserve: arw``)
    composite: bool = False
    #: the other reading that explains the record about as well: ``[(candidate, D of the axis with it)]``
    alternatives: tuple = ()
    #: the effects of the reading named that the other reading replaces as a whole (the covariate
    #: reading's temperature and the wander beside it); empty: this candidate's alone
    in_place_of: tuple = ()
    #: what later steps add to the evidence, in order
    evidence_notes: tuple = ()
    #: a compression's calibration (:mod:`gyrofilter.analysis.gap.compression`): the mean tail
    #: statistic of the model's runs at its gamma and the slope of that mean in gamma, the
    #: linearised re-estimator of its bootstrap (:mod:`gyrofilter.analysis.gap.reestimate`)
    calibration: tuple = ()

    def plain_params(self):
        """The parameters as plain floats, as the report writes them."""
        return {k: float(v) for k, v in self.params.items()}

    def evidence_text(self, *more):
        """The evidence as the report writes it: the detector's sentence, the later steps'
        notes and ``more``, joined by "; "."""
        return "; ".join((self.evidence,) + tuple(self.evidence_notes) + more)
