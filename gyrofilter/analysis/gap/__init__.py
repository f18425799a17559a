"""The model-gap analysis: what the baseline simulation gets wrong about a recording, the cause,
the extended model and the gain (docs/gap.md). ``pipeline`` runs the steps in order
(:func:`~gyrofilter.analysis.gap.pipeline.analyse_gap`); ``baseline`` fits and simulates the
models, ``features`` measures a record against its simulations (the discrepancy D),
``detectors/`` holds one statistic per effect and their decision order, ``confound`` decides the
confounded causes, ``composite`` the GMWM-style stochastic part, ``intervals`` and ``reestimate``
the parameters' bootstrap intervals, ``report`` the Markdown report and its figures."""
