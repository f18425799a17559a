"""What a recording says about its gyro. One folder per family, the folder name says where a
decision lives:

- ``noise/``: the Allan deviation and the five noise coefficients (papers 000, 002): ``allan``
  (the deviation and its intervals), ``model`` (the five-term model), ``fit`` (its fit),
  ``intervals``, ``readoff`` (the slope read-off), ``screen`` (gross errors), ``export`` (the JSON
  and Kalibr files), ``plots`` (the Allan figure), ``gmwm`` and ``wv_robust`` (the wavelet-variance
  fit of a composite model).
- ``gap/``: the model-gap analysis, what the plain simulation gets wrong and why: ``pipeline``
  (the steps in order), ``baseline``, ``features``, ``detectors/`` (one statistic per effect),
  ``confound`` (the confounded causes), ``composite``, ``intervals`` and ``reestimate`` (the
  parameters' intervals), ``report`` (Markdown and figures).
- ``arma/``: ARMA and bias-state models (paper 003): ``identify`` (order selection, the bias
  model), ``fit``, ``checks`` (the residual tests), ``bias_kf`` (the bias-tracking filter).
- ``fleet/``: many recordings at once: ``work`` (one file), ``runner`` (worker processes, Dask),
  ``table`` (the rows, the units that stand out, fleet.csv and fleet.md).
- ``stats``: the statistics the families share; ``still``: is the record still, and the Allan
  analysis of a file.

Uses the core, ``gyrofilter.filter`` and ``gyrofilter.sim``; nothing here is imported by
``import gyrofilter``."""
