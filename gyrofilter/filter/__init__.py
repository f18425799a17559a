"""The real-time filter of paper 001 and its adaptive versions: one module per stage or algorithm.

    calibration      start-up bias and noise from a still window (001 section 2.1)
    averaging        non-sliding block means with the gross-error rule (2.2)
    predictor        least-squares extrapolation weights over the FIFO (2.3, eqs. 8-10)
    kalman           paper 001's Kalman filter (eqs. 4-7, 11-12) and the divergence guard
    adaptive_kalman  the same prior with covariance-matched noise and a constant-rate model
    hold             the constant-rate hold (CUSUM change detection)
    tempcomp         temperature compensation of the bias
    smoother         the offline forward-backward smoother
    presets          the named settings; "recommended" is the default
    settings         FilterSettings: every setting, its default, its range and their check
    samples          the checks of the samples, times and temperatures the filter is fed
    pipeline         GyroFilter: the stages in order
    jit              optional numba compilation of the per-block kernels

``from gyrofilter import GyroFilter`` is the way in; this package is for those who need a stage.
"""
