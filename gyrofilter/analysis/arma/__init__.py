"""ARMA and bias-state models of a static gyro (paper 003, Wang, Lyu and Wu 2016): ``identify``
selects the order and derives the bias model, ``fit`` fits an ARMA (statsmodels), ``checks``
tests the residuals (whiteness, normality, stationarity), ``bias_kf`` the bias-tracking Kalman
filter with zero-rate updates at rest."""
