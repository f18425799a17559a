"""What a recording says about its gyro: Allan deviation and noise coefficients (``allan``,
``noise_model``; papers 000, 002), ARMA and bias-state models (``arma``, ``bias_kf``; paper 003),
the composite wavelet-variance fit (``gmwm``), the model-gap analysis (``gap``, ``detectors``,
``gap_report``) and many recordings at once (``fleet``). Uses the core and ``gyrofilter.sim``;
nothing here is imported by ``import gyrofilter``."""
