"""The Allan deviation of a rate series and the five IEEE-952 noise coefficients read from it
(papers 000 and 002): ``allan`` the deviation and its confidence intervals, ``model`` the
five-term model (Q, N, B, K, R with their units and slopes), ``fit`` its weighted fit,
``intervals`` the coefficients' intervals, ``readoff`` the classical slope read-off, ``screen``
the gross-error screen before the fit, ``export`` the JSON and Kalibr files, ``plots`` the
figure; ``gmwm`` and ``wv_robust`` fit a composite model to the Haar wavelet variance
(Guerrier et al. 2013)."""
