"""Named settings for :class:`gyrofilter.GyroFilter` (``preset=``).

:data:`DEFAULT_PRESET` is ``recommended``, the best measured filter, used by ``GyroFilter(sample_rate_hz)``,
``gyrofilter replay`` and ``gyrofilter run`` when no preset is named. Explicit keyword arguments
override a preset. All presets are measured in ``docs/evaluate.md``.

``paper`` is the faithful paper-001 pipeline (the defaults of ``FilterSettings``), without a
divergence guard: it reproduces the paper, including its divergence in fast motion.

``hold``: the block means of paper 001's averaging stage, followed by the constant-rate hold of
:mod:`gyrofilter.filter.hold`: while the rate is constant (at rest, or turning steadily) the output
is the mean of every block since the rate last changed; a CUSUM test on the block means
switches to the block means themselves within a block of a change, and a chi-square test on the
last 20 blocks switches back. No Kalman stage. Chosen on a tune / held-out split
(``tools/tune_recommended.py``); it was the recommended preset before ``adaptive_kalman``.

``adaptive_kalman`` (``tools/tune_adaptive_kalman.py``): paper 001's Kalman filter with its
least-squares prior over the FIFO of posteriors kept and its noise statistics replaced
(:func:`gyrofilter.filter.adaptive_kalman.run_blocks_adaptive`: R from the calibration, the prior variance by
covariance matching of the innovations, the gain kept where the loop is stable, a constant-rate
model at rest, the prior dropped when it is far worse than the measurement), the divergence
guard on (2 blocks beyond 10 sigma_b: re-seed from the block mean), and the gross-error rule
chosen by the model (``outlier_rule="by_model"``: paper 001's rule while an axis is in the
constant-rate model, ``median_slope`` while it is in the LS model, where the rate changes by more
than q within a block and the paper's rule would reject real samples). Every Kalman preset but
``paper`` has the guard, and every preset but ``paper`` a gross-error threshold that follows the
blocks' range (``outlier_range_k`` = :data:`VIBRATION_RANGE_K`, gyrofilter.filter.threshold): a
vibration that swings by more than q within a block is kept, not cut as gross errors.

``recommended`` is ``adaptive_kalman``: on both halves of the split it reduces the static std as
much as the hold (held out: >= 17.3x on every axis, 17.27x against the hold's 17.31x on the worst;
17.7x before the rest mean after motion started from the latest half of its window, which a turn
under a vibration needed: docs/evaluate.md), and its RMSE is no higher than the hold's on every
profile and BROAD trial: lower on the slow ``paper001`` profile
(the LS prior), on the 1-Hz sine, the chirp and every BROAD trial (the rule by model), equal on
the steps.
"""

#: k_r of every preset but paper (gyrofilter.filter.threshold): q follows a vibration's range
VIBRATION_RANGE_K = 2.0

PRESETS = {
    "paper": {},
    "hold": {"hold": True, "tracker": "block_mean", "outlier_range_k": VIBRATION_RANGE_K},
    "adaptive_kalman": {"kalman_noise": "adaptive", "guard_blocks": 2, "outlier_rule": "by_model",
                        "outlier_range_k": VIBRATION_RANGE_K},
}
PRESETS["recommended"] = PRESETS["adaptive_kalman"]

DEFAULT_PRESET = "recommended"
