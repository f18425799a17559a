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

from ..errors import SettingsError


def extrapolation_weights(n: int, order: int) -> np.ndarray:
    """Weights w (oldest first) so that sum(w * x[-n:]) is the LS polynomial fit at t = n.

    Uses order min(order, n - 1), so that 1 point predicts itself and 2 points a line.
    """
    if n < 1:
        raise SettingsError(f"extrapolation needs at least 1 point, got n={n}")
    if order < 0:
        raise SettingsError(f"fit order must be >= 0, got {order}")
    order = min(order, n - 1)
    # the fit on u = (t - c) / s, c the middle and s the half-width of t = 0..n-1: the same weights (a
    # polynomial in t is one in u), but the powers stay within [-1, 1] (1.02 at the next step); on t
    # itself 99^10 made V^T V too ill-conditioned for pinv: sum(w) = 0.26 for n = 100, order 10
    center = (n - 1) / 2.0
    half_width = max(center, 1.0)
    u = (np.arange(n, dtype=float) - center) / half_width
    vander = np.vander(u, order + 1, increasing=True)
    v_next = ((n - center) / half_width) ** np.arange(order + 1)
    return v_next @ np.linalg.pinv(vander)


def weight_table(depth: int, order: int) -> np.ndarray:
    """The LS extrapolation weights of a fit of ``order`` (0 constant, 1 linear, 2 quadratic) to
    the last k posteriors: row k-1 holds those for k points (k = 1..``depth``), zero-padded on
    the right."""
    table = np.zeros((depth, depth))
    for k in range(1, depth + 1):
        table[k - 1, :k] = extrapolation_weights(k, order)
    return table


def closed_loop_radius(depth: int, order: int, gain: float) -> float:
    """Largest root modulus of the Kalman loop x_k = (1 - K) sum_i w_i x_(k-n+i) + K y_k, n = depth.

    ``depth``: n, the FIFO depth; ``order``: the LS fit's order (w = :func:`weight_table`);
    ``gain``: K, constant.

    Characteristic polynomial z^n - (1 - K) sum_i w_i z^i (w oldest first, i = 0..n-1); the loop
    is stable for a constant gain K when the radius is < 1. With the 10-point quadratic
    weights: 1.048 at K = 0.1, 1.009 at 0.3, 0.982 at 0.4, 0.950 at 0.5, 0.914 at 0.6, 0.871 at
    0.7; the threshold is K = 0.335 (:func:`stable_gain_threshold`). At K = 0 the quadratic fit
    has a triple root at z = 1 (it continues any quadratic forever).
    """
    w = extrapolation_weights(depth, order)
    coeffs = np.zeros(depth + 1)
    coeffs[0] = 1.0
    coeffs[1:] = -(1.0 - gain) * w[::-1]
    return float(np.max(np.abs(np.roots(coeffs))))


def stable_gain_threshold(depth: int, order: int, tol: float = 1e-6) -> float:
    """Smallest constant gain K in [0, 1] above which the loop of :func:`closed_loop_radius` is
    stable for ``depth`` points and a fit of ``order`` (bisection to within ``tol``; assumes the
    radius falls with K, as it does for the LS weights); 0 if it is stable for every K."""
    if closed_loop_radius(depth, order, 0.0) < 1.0:
        return 0.0
    lo, hi = 0.0, 1.0
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if closed_loop_radius(depth, order, mid) < 1.0:
            hi = mid
        else:
            lo = mid
    return hi
