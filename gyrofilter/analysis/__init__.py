"""What a recording says about its gyro: Allan deviation and noise coefficients (``allan``;
``noise_model`` the five-term model, ``noise_fit`` its fit, ``noise_intervals``, ``noise_readoff``,
``noise_screen`` the gross errors, ``noise_export`` the JSON and Kalibr files; papers 000, 002),
ARMA and bias-state models (``arma``, ``arma_fit``, ``arma_checks``, ``bias_kf``; paper 003), the
composite wavelet-variance fit (``gmwm``), the model-gap analysis (``gap``, ``gap_features``,
``gap_baseline``, ``gap_composite``, ``gap_readings``, ``gap_intervals`` and ``gap_reestimate`` the
parameters' intervals, ``detectors``, ``gap_report``), still-sensor reading
(``still``), the Allan figure (``plots_allan``) and many recordings at once (``fleet``). Uses the
core, ``gyrofilter.filter`` and ``gyrofilter.sim``; nothing here is imported by ``import gyrofilter``."""
