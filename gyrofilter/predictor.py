"""Least-squares polynomial extrapolation as a fixed linear combination (paper 001, 2.3).

Paper 001 fits x_i = a t_i^2 + b t_i + c to the last n = 10 posterior estimates by least squares
(eqs. 8-9) and evaluates the fit at the next time step (eq. 10) to get the prior. With equally
spaced t_i = 0, 1, ..., n-1 and the prediction at t = n, the prior is a fixed weighted sum

    x_prior = sum_i w_i x_i,   w = v^T (V^T V)^-1 V^T,

where V is the n x (order+1) Vandermonde matrix of t_i and v = (1, n, n^2, ...) the row at the
next step. The weights sum to 1 (a constant is reproduced) and reproduce any polynomial up to
``order`` exactly. Their white-noise gain sum(w_i^2) (about 1.38 for n = 10, order 2) is how
much the prediction amplifies independent noise in the FIFO.

Time units cancel: the weights do not depend on the sample rate.
"""
import numpy as np

from .errors import SettingsError


def extrapolation_weights(n: int, order: int) -> np.ndarray:
    """Weights w (oldest first) so that sum(w * x[-n:]) is the LS polynomial fit at t = n.

    Uses order min(order, n - 1), so that 1 point predicts itself and 2 points a line.
    """
    if n < 1:
        raise SettingsError(f"extrapolation needs at least 1 point, got n={n}")
    if order < 0:
        raise SettingsError(f"fit order must be >= 0, got {order}")
    order = min(order, n - 1)
    t = np.arange(n, dtype=float)
    vander = np.vander(t, order + 1, increasing=True)
    v_next = np.array([float(n) ** k for k in range(order + 1)])
    return v_next @ np.linalg.pinv(vander)


def weight_table(depth: int, order: int) -> np.ndarray:
    """Row k-1 holds the weights for k points (k = 1..depth), zero-padded on the right."""
    table = np.zeros((depth, depth))
    for k in range(1, depth + 1):
        table[k - 1, :k] = extrapolation_weights(k, order)
    return table
