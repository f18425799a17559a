"""Detectors for the model-gap analysis: one statistic per effect of the effect table.

Every detector works on one axis, a 1-D rate series ``x_dps`` (deg/s) sampled at
``sample_rate_hz``, and returns a :class:`Candidate` (or None): the effect name, its parameter
estimates in the units of the effect table (docs/formats.md, section 2), the detector's statistic, the
threshold it had to pass and an evidence sentence. :mod:`gyrofilter.analysis.gap.pipeline` runs the same
statistic on the baseline simulations to show the simulated spread, and keeps a candidate only
when the extended model lowers the discrepancy.

The detectors run in a fixed **decision order**, each on the series cleaned of what the earlier
ones found, because the effects are confusable:

0. ``repeated_samples`` -- rows equal to the previous one on every axis beyond chance at the
   record's quantization (:mod:`~gyrofilter.analysis.gap.detectors.repeats`): the one detector of the
   whole record, counted before the axes' detectors (repeats add about f to the lag-1
   correlation: ``colored_noise`` solves its lags for under them, :func:`lags_without_repeats`)
   and weighed on D after their findings
   (:mod:`gyrofilter.analysis.gap.rows`). Nothing is cleaned.

1. ``outliers`` -- isolated spikes. Statistic: the second-difference residual
   ``r_i = x_i - (x_{i-1} + x_{i+1}) / 2`` (white noise: ``sd(r) = sigma sqrt(3/2)``) against a
   robust (MAD) scale; a spike is ``|r_i| > k sd(r)`` with ``k`` set so that white Gaussian noise
   gives 0.05 expected false spikes per axis (``k = Phi^-1(1 - 0.025 / N)``, about 5.0 for
   N = 360 000), and a finding needs at least 3 spikes (white noise: probability 2e-5).
   Paper 001 (gross errors: isolated, much larger than the noise). Found spikes are replaced
   by their neighbours' median before the next detectors run.
1b. ``heavy_tails`` -- the noise is heavier-tailed than a Gaussian at every sample (a Gaussian
   scale mixture), told apart from isolated spikes by the shape of the high-passed, prewhitened
   residual's distribution: a winsorized kurtosis departing from the baseline's simulations, a
   scale mixture beating a Gaussian and beating isolated spikes by likelihood (see
   :mod:`~gyrofilter.analysis.gap.detectors.tails` for the rule). When named, the outlier candidate is
   dropped (its spikes are the tails) and the series is not cleaned.
1c. ``ringing`` -- shocks that ring the board's resonance (bursts that decay): where spikes or
   heavy tails were found, a hump of the ``resonance`` detector's fit on the series as recorded,
   the events of the series through the hump's own resonator, and at each the resonator's ring
   fitted against an isolated spike: the energy the rings explain beyond isolated spikes, in
   noise variances, is the statistic. When named, the spike and tail candidates are dropped (the
   spikes are the rings' peaks: one cause, :func:`gyrofilter.analysis.gap.confound.one_cause_of_spikes`),
   the fitted rings are taken out of the series, and a hump at the ring's resonance is not named
   beside it.
2. ``sinusoid`` -- a line in the periodogram. The periodogram ordinate divided by the local
   noise level (median over a +-5 % frequency band / ln 2) is Exp(1) under any smooth noise
   spectrum, so the largest of ``M`` ordinates exceeds ``t`` with probability about
   ``M exp(-t)`` (Fisher's test, the max-periodogram form; Priestley 1981, sec. 6.1.4); the
   Nyquist bin's ordinate (one degree of freedom) is halved, which keeps its tail below
   ``exp(-t)``, so a line at f_s / 2 (a, -a, a, ...) is one too, fitted at f_s / 2 itself. The line
   is fitted by least squares (amplitude, phase) at the refined frequency and subtracted.
2b. ``narrowband`` -- a band of noise with a resolved width (a resonance): the Welch PSD over a
   running-median background (±min(f_s / 10, 20 Hz), narrowed and mirrored at f_s / 2, so the
   search reaches the Nyquist frequency), the peak excess in units of its sampling error
   ``(R - 1) sqrt(K)`` (K Welch segments; Welch 1967), centre, half-power width and rms refined
   by a least-squares fit of the effect's own AR(2) resonator PSD (:func:`band_estimate`). Runs
   on the series with the sinusoid removed; a band cannot be subtracted (it is noise), so the
   later detectors see it, and the colored noise's lag-1 is corrected for it.
2c. ``resonance`` -- a broad low hump of noise power (the board's resonance driven by noise): the
   Welch log-PSD fitted by a smooth spectrum (white through a first-order ARMA, and a 1/f floor)
   with and without the ``resonance`` effect's resonator hump; the drop of the residual sum of
   squares in residual variances is the statistic. A peak of quality Q = f0 / B at most
   ``RESONANCE_MAX_Q`` is a hump, a narrower one a line (``narrowband``) where the narrow-band
   detector finds it (up to ``RESONANCE_UNSEEN_MAX_Q`` an unseen one is the hump): a narrow-band
   line's bins are left out of the hump's fit, a broad band at the hump's centre is the hump
   (:func:`~gyrofilter.analysis.gap.detectors.resonance.hump_or_line`). Like a band, the hump is
   noise and stays in the series; the colored noise's lag-1 is corrected for it.
2d. ``wandering_tone`` -- the band read as a tone of constant amplitude whose frequency wanders
   (:mod:`~gyrofilter.analysis.gap.detectors.tone`): the same spectrum, another distribution. The
   band cut out of the series has an excess kurtosis of 0 when Gaussian and -3/2 s² when a
   constant-amplitude tone holds a share s of its variance; a kurtosis below 0 by
   :data:`TONE_KURTOSIS_Z` block standard errors and at least :data:`TONE_MIN_FRACTION` of a
   tone's names the tone instead of the band, provided the peak of its short-time spectra moves
   (else it keeps one frequency: a sinusoid's). A sinusoid found within the band is the tone
   dwelling at one frequency and joins it (one line, one finding). The tone carries the band as its
   Gaussian reading, and the two are weighed on D
   (:func:`gyrofilter.analysis.gap.confound.weigh_tones`), each with the colored noise left beside
   its own line (:func:`tone_band`: the tone's variance A² / 2 in a line of its width; or the band as
   measured). A named tone's flanks are searched for a periodic excursion of its frequency
   (:mod:`~gyrofilter.analysis.gap.detectors.excursion`: the envelope line of the power beside
   its band at :data:`EXCURSION_LINE_RATIO` times its median ordinate or more); one found is a note
   of the tone's evidence (its period, height and length), not a term of the extended model.
3. ``colored_noise`` -- the lag-1 autocorrelation ``r1 = sum e_i e_{i+1} / sum e_i^2`` of the
   high-passed noise ``e = x - moving_mean(x, W)``; white noise: ``r1 ~ N(-1/W, 1/N)``
   (Box & Jenkins). Slow effects barely move ``r1`` because ``W`` is short. Its lag-2 ``r2``
   tells a first-order low pass (AR(1): ``rho_2 = rho_1^2``) from other short correlations (a
   two-tap average: ``rho_2 = 0``); where it is clearly lower the finding carries ``lag2`` and the noise
   is the first-order ARMA with both autocorrelations.
4. Slow bias effects, on block means ``y_k`` of the cleaned series (at most 2048 blocks of
   ``Delta`` seconds): deterministic shapes (``rate_ramp``: LS line; ``bias_step``: two-mean
   scan; ``warmup``: ``a exp(-t/tau)`` scanned over tau; ``temperature``: regression on the
   block-mean temperature) are scored by the drop of the residual sum of squares in units of
   the block white-noise variance (``Delta chi^2``); stochastic spectra
   (``rate_random_walk`` ``S = K^2 / (4 pi^2 f^2 Delta)``, ``bias_instability``
   ``S = B^2 / (2 pi f Delta)``, ``gauss_markov`` AR(1); IEEE Std 952-1997 annex C for the
   PSD forms) by the Whittle likelihood ratio over white noise (Whittle 1953) on the
   LS-detrended block means, the random walk's expected periodogram taking the detrend into
   account (:func:`_detrended_shapes`). Decision rules, in order:

   * the best deterministic shape is the largest ``Delta chi^2 - k ln n`` (k free
     parameters: BIC), so a warm-up with a very long tau loses to a ramp;
   * the best stochastic spectrum is the largest ``2 Delta log L - 6 k``: an extra parameter
     (Gauss-Markov's tau) must buy 6 (likelihood-ratio test at about 1.4 %), and a
     Gauss-Markov process whose tau exceeds a fifth of the record is a random walk as far as
     the data can tell;
   * a shape above its threshold is tested against the stochastic spectra of its residual:
     if one is still significant, the shape is kept only if its amplitude is significant
     against that fitted noise (the variance of the amplitude estimate under it, e.g.
     ``q sum_k (sum_{i>=k} w_i)^2`` for a random walk), giving both findings; otherwise the
     shape must also beat the *exact* Kalman-filter likelihood of a random-walk and of a
     Gauss-Markov wander on the same (undetrended) block means, so a wander that happens to
     look like a ramp or a step is called a wander;
   * a step, ramp or warm-up that passes is named only where white noise with flicker (1/f,
     the bias instability every MEMS gyro has) fitted to the record draws its likelihood ratio
     over flicker in at most 1 % of records (a parametric bootstrap of 1000 records from a fixed
     stream, :func:`~gyrofilter.analysis.gap.detectors.flicker.flicker_p_value`); else the bias
     instability is named in its place. In ten minutes a bias instability's excursions passed
     the rules above as a shape on 37 of 200 axes, against it on 5;
   * with no shape, the best stochastic spectrum is reported if above its threshold; a bias
     instability or Gauss-Markov finding carries the other of the two where that one is
     significant too, and the gap weighs the two on D (the bias instability, one parameter
     fewer, unless the Gauss-Markov is clearly better: :func:`gyrofilter.analysis.gap.confound.weigh_wanders`);
   * where a temperature is recorded, the temperature coefficient is fitted first and the rules
     above run on what it leaves (``covariate``: the coefficient by generalised least squares
     under the residual's stochastic model, significant jointly with any time shape there); the
     reading without the temperature rides along as its alternative, and the gap weighs the two
     on D (:mod:`gyrofilter.analysis.gap.confound`).

Not a detector of this order: ``compression`` (lighter tails than the extended model's, a
transfer of the fast terms) is fitted after the composite stochastic part, against the extended
model's runs, where an axis's D stays high (:mod:`gyrofilter.analysis.gap.compression`; its
threshold :data:`COMPRESSION_TAILS_Z` lives in ``common`` with the others).

The package holds one module per concern: ``common`` (every threshold of the gap analysis,
:class:`Candidate`, helpers), ``repeats``, ``outliers``, ``tails``, ``ringing``, ``sinusoid``, ``narrowband``,
``resonance``, ``tone``, ``colored``
and ``slow`` (+ ``covariate``, the temperature first, and ``flicker``, a shape against a bias instability); every name is importable from
``gyrofilter.analysis.gap.detectors`` as before.
"""
from .common import (  # noqa: F401
    COLORED_LATE_Z,
    COLORED_MIN_LAG1,
    COLORED_MIN_LAG2_GAP,
    COLORED_Z,
    COMPOSITE_MIN_GAIN,
    COMPRESSION_TAILS_Z,
    Candidate,
    DETERMINISTIC_THRESHOLD,
    EXACT_GM_MARGIN,
    EXCURSION_LINE_RATIO,
    GM_MAX_TAU_DIVISOR,
    HEAVY_TAILS_THRESHOLD,
    HEAVY_TAILS_Z,
    JOINT_THRESHOLD,
    NARROWBAND_THRESHOLD,
    RESONANCE_LOWEST_FRACTION,
    RESONANCE_MAX_Q,
    RESONANCE_MIN_Q,
    RESONANCE_THRESHOLD,
    RINGING_THRESHOLD,
    OUTLIER_FALSE_PER_AXIS,
    OUTLIER_MIN_COUNT,
    OUTSIDE_NULL_D,
    REPEATS_ALPHA,
    REPEATS_MAX_STATISTIC,
    REPORTED_DEPARTURE_Z,
    SINUSOID_ALPHA,
    STOCHASTIC_PENALTY,
    STOCHASTIC_THRESHOLD,
    TAILS_MAX_STEP_SD,
    TAILS_WINSOR_SD,
    TONE_KURTOSIS_Z,
    TONE_MIN_FRACTION,
)
from .outliers import (  # noqa: F401
    OUTLIER_SPREAD_LN,
    clean_spikes,
    detect_outliers,
    outlier_statistic,
)
from .tails import (  # noqa: F401
    detect_heavy_tails,
    tail_fits,
    tail_residual,
    tails_sd,
    tails_statistic,
)
from .sinusoid import (  # noqa: F401
    CHUNK_SAMPLES,
    DFT_BLOCKS,
    dft_amplitude,
    least_squares,
    detect_sinusoid,
    fitted,
    periodogram_length,
    sinusoid_fit,
    periodogram,
    sinusoid_statistic,
)
from .narrowband import (  # noqa: F401
    BAND_BACKGROUND_HZ,
    band_estimate,
    detect_narrowband,
    narrowband_lags,
)
from .resonance import (  # noqa: F401
    band_correlation,
    detect_resonance,
    hump_or_line,
    resonance_fit,
)
from .ringing import (  # noqa: F401
    detect_ringing,
    ring_fit,
    ringing_estimate,
)
from .tone import (  # noqa: F401
    detect_wandering_tone,
    tone_band,
    tone_estimate,
)
from .excursion import (  # noqa: F401
    excursion_note,
    flank_envelope,
    folded_band,
    tone_excursion,
)
from .colored import (  # noqa: F401
    colored_window,
    detect_colored,
    highpassed,
    lag1_statistic,
    lags_from_highpassed,
    lags_without_repeats,
    other_correlation,
    long_run_ratio,
)
from .slow import (  # noqa: F401
    PERIODOGRAM,
    exact_stochastic_gain,
    slow_reading,
    stochastic_fits,
)
from .repeats import (  # noqa: F401
    beyond_model,
    beyond_model_text,
    detect_repeats,
    max_fraction,
    repeats_warning,
)
from .covariate import (  # noqa: F401
    detect_slow,
    gls,
    temperature_first,
)
