"""Named settings for :class:`gyrofilter.GyroFilter` (``preset=``).

``paper`` is the faithful paper-001 pipeline and the default. Explicit keyword arguments
override a preset.

``recommended`` (measured in ``docs/evaluate.md``, made by ``gyrofilter evaluate``): the
block means of paper 001's averaging stage, followed by the constant-rate hold of
:mod:`gyrofilter.adaptive`: while the rate is constant (at rest, or turning steadily) the output
is the mean of every block since the rate last changed; a CUSUM test on the block means
switches to the block means themselves within a block of a change, and a chi-square test on the
last 20 blocks switches back. The paper's Kalman filter is not used: with its quadratic
extrapolation (white-noise gain sum(w^2) = 1.38) it keeps a third of the block-mean noise at
rest, and in motion its measurement variance R (the variance of the last 10 block means)
grows with the motion, the gain collapses and the extrapolation runs away. Chosen on a
tune / held-out split (``tools/tune_recommended.py``); on the held-out data it still reduces
the static std by at least 17x on every axis and has a lower RMSE than the faithful filter on
every motion profile and BROAD trial.

``adaptive_kalman`` (``tools/tune_adaptive_kalman.py``, ``docs/evaluate.md``): paper 001's Kalman
filter with its least-squares prior kept and its noise statistics replaced
(:func:`gyrofilter.kalman.run_blocks_adaptive`: R from the calibration, Q by covariance matching
of the innovations, the gain kept where the loop is stable, a constant-rate model at rest) and
the divergence guard on (2 blocks beyond 10 sigma_b: re-seed from the block mean). Every Kalman
preset but ``paper`` has the guard.
"""

PRESETS = {
    "paper": {},
    "recommended": {"hold": True, "tracker": "block_mean"},
    "adaptive_kalman": {"kalman_noise": "adaptive", "guard_blocks": 2},
}
