"""Detector 4: slow bias effects on block means, deterministic shapes and stochastic spectra (see :mod:`gyrofilter.analysis.gap.detectors`)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ....effects import (BIAS_INSTABILITY, BIAS_STEP, BY_NAME, GAUSS_MARKOV, RATE_RAMP, RATE_RANDOM_WALK, SHAPES,
                             SLOW, TEMPERATURE, WANDERS, WARMUP)
from ..confound import CONFUSABLE_WANDERS
from .common import (DETERMINISTIC_THRESHOLD, EXACT_GM_MARGIN, FLICKER_ALPHA, FLICKER_REPLICATES, GM_MAX_TAU_DIVISOR,
                     JOINT_THRESHOLD, STOCHASTIC_PENALTY, STOCHASTIC_THRESHOLD, Candidate)
from .flicker import flicker_p_value
from ...stats import block_means, detrend_line, golden_max
from .sinusoid import least_squares, fitted


# ---------------------------------------------------------------------------------------------
# 4. slow bias effects on block means


PERIODOGRAM = "detrended"

_SHAPES = {}


def _detrended_shapes(n):
    """Exact expected periodogram shapes of the LS-detrended block means (cached per n):
    white noise ``w_j = |P f_j|^2 / n`` and a unit random walk (``cov = min(k, l) + 1``)
    ``g_j = sum_m |sum_{l >= m} (P f_j)_l|^2 / n``, with ``P`` the projection off
    ``[1, t]`` and ``f_j`` the Fourier vector of frequency ``omega_j`` (``M = L L^T``, ``L``
    lower-triangular ones, so ``v^H M v = |L^T v|^2``). The detrend takes power away from the
    lowest frequencies of a random walk; modelling that keeps a random walk from looking
    like a Gauss-Markov process."""
    if n in _SHAPES:
        return _SHAPES[n]
    t = np.arange(n, dtype=float)
    q_mat, _ = np.linalg.qr(np.column_stack([np.ones(n), t - t.mean()]))
    j = np.arange(1, (n + 1) // 2)
    j = j[j < n / 2]
    omega = 2 * math.pi * j / n
    out_w = np.empty(j.size)
    out_g = np.empty(j.size)
    for start in range(0, j.size, 256):
        om = omega[start:start + 256]
        f = np.exp(-1j * np.outer(t, om))
        v = f - q_mat @ (q_mat.T @ f)
        out_w[start:start + 256] = np.sum(np.abs(v) ** 2, axis=0) / n
        u = np.cumsum(v[::-1], axis=0)[::-1]
        out_g[start:start + 256] = np.sum(np.abs(u) ** 2, axis=0) / n
    if len(_SHAPES) > 8:
        _SHAPES.clear()
    _SHAPES[n] = (out_w, out_g)
    return out_w, out_g


def periodogram_detrended(y):
    """Periodogram of the least-squares detrended block means."""
    r = detrend_line(y)
    n = r.size
    spec = np.abs(np.fft.rfft(r)) ** 2 / n
    j = np.arange(spec.size)
    keep = (j >= 1) & (j < n / 2)
    return spec[keep], j[keep] * 2 * math.pi / n


def _periodogram(y):
    """Periodogram of the block means through their increments ("bridge" periodogram):
    ``I_j = |DFT(d - mean d)|^2 / m / (4 sin^2(omega_j / 2))`` with ``d = diff(y)``,
    ``m = n - 1``. For a random walk plus white noise its expectation is exactly
    ``q / (4 sin^2(omega/2)) + s0`` at every Fourier frequency (the increments are
    stationary, so no end-effect leakage; a least-squares detrend instead flattens the lowest
    frequencies and makes a random walk look like a Gauss-Markov process); for stationary
    noise it is the ordinary spectrum; a linear trend is removed with the mean increment."""
    d = np.diff(y)
    d = d - d.mean()
    m = d.size
    spec = np.abs(np.fft.rfft(d)) ** 2 / m
    j = np.arange(spec.size)
    keep = (j >= 1) & (j < m / 2)
    omega = j[keep] * 2 * math.pi / m
    return spec[keep] / (4 * np.sin(omega / 2) ** 2), omega


def slow_spectrum(model, theta, omega, delta_s):
    """Component spectrum of a stochastic bias model for block means (sampling delta_s)."""
    if model == RATE_RANDOM_WALK:
        q = theta[0]
        return q / (4 * np.sin(omega / 2) ** 2)
    if model == BIAS_INSTABILITY:
        h = theta[0]
        return h / omega
    if model == GAUSS_MARKOV:
        var, phi = theta
        return var * (1 - phi ** 2) / (1 - 2 * phi * np.cos(omega) + phi ** 2)
    raise ValueError(model)


def _whittle(spec, omega, model, delta_s, s0_start, white_shape=None, rw_shape=None):
    """Minimise the Whittle negative log-likelihood ``l = sum_j log S_j + I_j / S_j``
    (Whittle 1953) over the model's parameters and the white level ``s0`` (log / logit
    parametrisation, L-BFGS-B with the analytic gradient
    ``dl/dp = sum_j (1 / S_j - I_j / S_j^2) dS_j/dp``); returns (nll, theta, s0)."""
    from scipy.optimize import minimize

    low = max(float(spec[: max(4, spec.size // 16)].mean()), 1e-300)
    cos_w = np.cos(omega)
    if model == RATE_RANDOM_WALK:
        shape = 1.0 / (4 * np.sin(omega / 2) ** 2) if rw_shape is None else rw_shape
    elif model == BIAS_INSTABILITY:
        shape = 1.0 / omega
    wsh = np.ones_like(omega) if white_shape is None else white_shape

    def fun(p):
        s0 = math.exp(p[0])
        if model == GAUSS_MARKOV:
            var = math.exp(p[1])
            phi = 1.0 / (1.0 + math.exp(-p[2]))
            den = 1 - 2 * phi * cos_w + phi * phi
            comp = var * (1 - phi * phi) / den
            dphi = var * ((-2 * phi) * den - (1 - phi * phi) * (-2 * cos_w + 2 * phi)) / den ** 2
            derivs = (s0 * wsh, comp, dphi * phi * (1 - phi))
        else:
            comp = math.exp(p[1]) * shape
            derivs = (s0 * wsh, comp)
        s = s0 * wsh + comp
        w = 1.0 / s - spec / (s * s)
        grad = np.array([float(np.dot(w, d)) for d in derivs])
        return float(np.sum(np.log(s) + spec / s)), grad

    if model == RATE_RANDOM_WALK:
        starts = [[math.log(s0_start), math.log(low * 4 * math.sin(omega[1] / 2) ** 2 + 1e-300)]]
    elif model == BIAS_INSTABILITY:
        starts = [[math.log(s0_start), math.log(low * omega[2] + 1e-300)]]
    else:
        starts = [[math.log(s0_start), math.log(max(low, s0_start) * 0.2), math.log(phi / (1 - phi))]
                  for phi in (0.5, 0.9, 0.99)]
    best = None
    for p0 in starts:
        try:
            res = minimize(fun, np.asarray(p0, dtype=float), jac=True, method="BFGS",
                           options={"maxiter": 200})
        except (ValueError, FloatingPointError, OverflowError):
            continue
        if np.isfinite(res.fun) and (best is None or res.fun < best[0]):
            best = (float(res.fun), res.x)
    if best is None:
        s0 = float(spec.mean())
        return float(np.sum(np.log(s0) + spec / s0)), ((0.0,) if model != GAUSS_MARKOV else (0.0, 0.5)), s0
    p = best[1]
    s0 = math.exp(p[0])
    if model == GAUSS_MARKOV:
        theta = (math.exp(p[1]), 1.0 / (1.0 + math.exp(-p[2])))
    else:
        theta = (math.exp(p[1]),)
    return best[0], theta, s0


#: the parameters each slow effect's fit estimates (a penalty per parameter)
N_PARAMS = {name: BY_NAME[name].n_params for name in SLOW}


def stochastic_fits(y, delta_s, models=WANDERS):
    """Whittle fits of each stochastic model of ``models`` to the block means ``y`` (bridge periodogram,
    :func:`_periodogram`): each fit its own, so one asked for alone is the same as among the others.

    Returns ``{model: (two_delta_loglik, theta, s0)}`` and the white-only level. A fit no better
    than white noise alone (``2 Delta log L <= 0``) is the maximum likelihood estimate on the
    boundary: the term's level is 0 (the white fit is the model with it at 0), its ``theta``
    ``(0,)`` (``(0, phi)`` for a Gauss-Markov), with ``s0`` the white level. The optimiser,
    working on ``log`` of the level, only drifts towards that boundary and stops at an arbitrary
    tiny level (``b_dps`` ~ 1e-6 where a term the record holds at all is above ~1e-4); a bootstrap
    replicate's estimate there is a zero, not a value six decades down
    (:mod:`gyrofilter.analysis.gap.intervals` leaves it out as nothing to estimate).
    """
    n = y.size
    if PERIODOGRAM == "bridge":
        spec, omega = _periodogram(y)
        wsh, gsh = np.ones_like(spec), None
    else:
        spec, omega = periodogram_detrended(y)
        wsh, gsh = _detrended_shapes(n)
    s0_white = float(np.mean(spec / wsh))
    nll0 = float(np.sum(np.log(s0_white * wsh) + spec / (s0_white * wsh)))
    s0_hf = float(spec[spec.size // 2:].mean())
    out = {}
    for model in models:
        nll, theta, s0 = _whittle(spec, omega, model, delta_s, s0_hf, wsh, gsh)
        if nll >= nll0:
            theta, s0 = (0.0,) + tuple(theta[1:]), s0_white
        out[model] = (max(0.0, 2 * (nll0 - nll)), theta, s0)
    return out, s0_hf


def stochastic_params(model, theta, delta_s):
    """Table parameters from the block-mean model parameters."""
    if model == RATE_RANDOM_WALK:
        # q = K^2 delta  (random walk of the rate, increment variance per block)
        return {"k_dps_per_sqrt_s": math.sqrt(theta[0] / delta_s)}
    if model == BIAS_INSTABILITY:
        # S_d(omega) = h / omega = B^2 / (2 pi f delta) with omega = 2 pi f delta -> h = B^2
        return {"b_dps": math.sqrt(theta[0])}
    var, phi = theta
    return {"sigma_dps": math.sqrt(var), "tau_s": -delta_s / math.log(phi)}


def _amplitude_variance(w, model, theta, s0):
    """Variance of ``w^T y`` (``sum w = 0``) under white ``s0`` plus the stochastic model."""
    var = s0 * float(np.dot(w, w))
    if model is None:
        return var
    if model == RATE_RANDOM_WALK:
        # cov(y_i, y_j) = q min(i, j): w^T C w = q sum_k (sum_{i>=k} w_i)^2
        tail = np.cumsum(w[::-1])[::-1]
        return var + theta[0] * float(np.dot(tail, tail))
    # stationary: (1 / M) sum_j S(omega_j) |W(omega_j)|^2 over a padded grid
    m = 1 << int(math.ceil(math.log2(4 * w.size)))
    wf = np.abs(np.fft.fft(w, m)) ** 2
    omega = 2 * math.pi * np.arange(m) / m
    omega = np.minimum(omega, 2 * math.pi - omega)
    omega[0] = omega[1] / 2
    s = slow_spectrum(model, theta, omega, 1.0)
    return var + float(np.sum(s * wf) / m)


def deterministic_shapes(y, delta_s, temp_blocks=None):
    """Best fit of each deterministic shape: ``{effect: (delta_chi2_raw, params, shape_blocks,
    w)}`` with ``delta_chi2_raw = (w^T y)^2 / (w^T w)`` (divide by the white level) and
    ``shape_blocks`` the fitted component (mean-free) on the blocks."""
    n = y.size
    t = (np.arange(n) + 0.5) * delta_s
    yc = y - y.mean()
    out = {}

    def single(g):
        gc = g - g.mean()
        gg = float(np.dot(gc, gc))
        if gg <= 0:
            return 0.0, 0.0, gc
        a = float(np.dot(gc, yc)) / gg
        return a * a * gg, a, gc

    # ramp
    d, a, gc = single(t)
    out[RATE_RAMP] = (d, {"r_dps_per_s": a}, a * gc, gc / np.dot(gc, gc))
    # step: two-mean scan over split k (first k blocks vs the rest)
    if n >= 8:
        c = np.cumsum(yc)
        k = np.arange(2, n - 1)
        s_left = c[k - 1]
        stat = s_left ** 2 * n / (k * (n - k))
        i = int(np.argmax(stat))
        kk = int(k[i])
        g = (np.arange(n) >= kk).astype(float)
        d, a, gc = single(g)
        out[BIAS_STEP] = (d, {"time_s": kk * delta_s, "size_dps": a}, a * gc,
                            gc / np.dot(gc, gc))
    # warm-up: a exp(-t / tau) scanned over tau
    if n >= 8:
        taus = np.geomspace(max(1.5 * delta_s, 1e-9), max(n * delta_s, 2 * delta_s), 40)
        best = None
        for tau in taus:
            d, a, gc = single(np.exp(-t / tau))
            if best is None or d > best[0]:
                best = (d, a, tau, gc)
        # refine tau (golden search in log tau around the best grid point)
        log_tau = golden_max(lambda lt: single(np.exp(-t / math.exp(lt)))[0],
                             math.log(best[2] / 1.3), math.log(best[2] * 1.3), 20)
        tau = math.exp(log_tau)
        d, a, gc = single(np.exp(-t / tau))
        if d < best[0]:
            d, a, tau, gc = best
        out[WARMUP] = (d, {"amplitude_dps": a, "tau_s": tau}, a * gc, gc / np.dot(gc, gc))
    if temp_blocks is not None and np.ptp(temp_blocks) > 0:
        d, a, gc = single(temp_blocks)
        out[TEMPERATURE] = (d, {"coefficient_dps_per_c": a}, a * gc, gc / np.dot(gc, gc))
    return out


def _kf_nll(y, phi, q, s0, mean):
    """Exact Gaussian negative log-likelihood (x2, constants dropped) of
    ``y_k = b_k + v_k``, ``b_k = mean + phi (b_{k-1} - mean) + w_k``, ``var v = s0``,
    ``var w = q`` (scalar Kalman filter; Harvey 1989, sec. 3.4). ``phi = 1`` is the random
    walk (local level) with a diffuse start (the first observation initialises the level);
    ``phi < 1`` the Gauss-Markov process started in its stationary law. ``y``: a list of floats
    (the loop's arithmetic is the IEEE double of numpy's scalars, several times faster on them)."""
    if phi >= 1.0:
        b, p_var, start = y[0], s0, 1
    else:
        b, p_var, start = mean, q / (1 - phi * phi), 0
    total = 0.0
    log = math.log
    for k in range(start, len(y)):
        b = mean + phi * (b - mean)
        p_var = phi * phi * p_var + q
        f = p_var + s0
        e = y[k] - b
        total += log(f) + e * e / f
        gain = p_var / f
        b += gain * e
        p_var -= gain * p_var
    return total


def exact_stochastic_gain(y, sto, delta_s, models=(RATE_RANDOM_WALK, GAUSS_MARKOV)):
    """2 Delta log L of the exact (time-domain) random-walk and Gauss-Markov models (of ``models``) over
    white noise with a constant mean, on the block means *with* their trend, started from the Whittle
    estimates ``sto``. Used to compare a deterministic shape with a stochastic wander on the
    same data (the Whittle fits see the detrended series only)."""
    from scipy.optimize import minimize

    y = np.asarray(y, dtype=float)
    n = y.size
    mean = float(y.mean())
    var0 = float(np.var(y))
    base = n * math.log(var0) + n  # white noise, MLE variance
    values = y.tolist()  # the Kalman filters' loops run on floats (_kf_nll)
    out = {}
    if RATE_RANDOM_WALK in models:
        q0, s00 = max(sto[RATE_RANDOM_WALK][1][0], 1e-12 * var0), max(sto[RATE_RANDOM_WALK][2], 1e-12 * var0)
        res = minimize(lambda p: _kf_nll(values, 1.0, math.exp(p[0]), math.exp(p[1]), mean),
                       [math.log(q0), math.log(s00)], method="Nelder-Mead",
                       options={"xatol": 1e-2, "fatol": 0.05, "maxiter": 200})
        # the diffuse start drops one observation: add the white model's term for it back
        out[RATE_RANDOM_WALK] = (max(0.0, base - (res.fun + math.log(var0) + 1)), (math.exp(res.x[0]),), math.exp(res.x[1]))
    if GAUSS_MARKOV in models:
        var_g, phi_g = sto[GAUSS_MARKOV][1]
        s0g = max(sto[GAUSS_MARKOV][2], 1e-12 * var0)
        phi_g = min(max(phi_g, 0.5), 0.9999)
        res = minimize(lambda p: _kf_nll(values, 1 / (1 + math.exp(-p[1])), math.exp(p[0]), math.exp(p[2]), mean),
                       [math.log(max(var_g * (1 - phi_g ** 2), 1e-12 * var0)), math.log(phi_g / (1 - phi_g)), math.log(s0g)],
                       method="Nelder-Mead", options={"xatol": 1e-2, "fatol": 0.05, "maxiter": 300})
        phi = 1 / (1 + math.exp(-res.x[1]))
        qg = math.exp(res.x[0])
        out[GAUSS_MARKOV] = (max(0.0, base - res.fun), (qg / max(1 - phi * phi, 1e-12), phi), math.exp(res.x[2]))
    return out


def slow_reading(x, sample_rate_hz, shapes=SHAPES, temp_c=None, stats=None):
    """One reading of the slow bias effects of one axis ``x`` (deg/s), with the deterministic
    shapes ``shapes`` (names of :data:`N_PARAMS`; ``temperature`` needs ``temp_c``) and the
    stochastic spectra, by the decision rules of :mod:`gyrofilter.analysis.gap.detectors`.

    Returns ``(candidates, noise)``: at most one shape and one stochastic candidate, and the
    stochastic model of the series left by the shape as ``(model, theta, s0, delta_s)`` of
    the block means (``model`` None: white noise of variance ``s0``); ``stats`` (a dict) gets
    the raw statistics.
    """
    stats = {} if stats is None else stats
    y, length = block_means(x)
    n = y.size
    if n < 16 or not np.ptp(y) > 0:  # equal block means (a quiet quantized record, its spikes cleaned): nothing slow
        return [], None
    delta_s = length / sample_rate_hz
    temp_blocks = None
    if temp_c is not None and TEMPERATURE in shapes:
        tb, _ = block_means(np.asarray(temp_c, dtype=float))
        if tb.size == n and np.ptp(tb) > 0:
            temp_blocks = tb
    penalty = math.log(n)
    sto, s0 = stochastic_fits(y, delta_s)
    det = {k: v for k, v in deterministic_shapes(y, delta_s, temp_blocks).items() if k in shapes}
    for name, (d, *_rest) in det.items():
        stats[name] = d / s0
    for name, (d2, *_rest) in sto.items():
        stats[name] = d2

    def best_of_sto(table):
        # nested spectra: an extra parameter must buy STOCHASTIC_PENALTY in 2 Delta log L
        # (likelihood-ratio test, chi^2_1 at about 1.4 %); and a Gauss-Markov whose tau is
        # longer than a fifth of the record is a random walk as far as the data can tell
        items = []
        for k, v in table.items():
            if k == GAUSS_MARKOV and -delta_s / math.log(min(max(v[1][1], 1e-12), 1 - 1e-12)) > n * delta_s / GM_MAX_TAU_DIVISOR:
                continue
            items.append((v[0] - N_PARAMS[k] * STOCHASTIC_PENALTY, k))
        return max(items) if items else (-np.inf, None)

    def best_of(table, value):
        items = [(value(v) - N_PARAMS[k] * penalty, k) for k, v in table.items()]
        return max(items) if items else (-np.inf, None)

    _, det_name = best_of(det, lambda v: v[0] / s0)
    _, sto_name = best_of_sto(sto)
    det_sig = det_name is not None and det[det_name][0] / s0 > DETERMINISTIC_THRESHOLD
    sto_sig = sto_name is not None and sto[sto_name][0] > STOCHASTIC_THRESHOLD
    noise = (sto_name, sto[sto_name][1], sto[sto_name][2], delta_s) if sto_sig else (None, (), s0, delta_s)

    findings = []
    if det_sig:
        d, params, shape, w = det[det_name]
        resid = y - shape
        sto_r, s0_r = stochastic_fits(resid, delta_s)
        _, sto_r_name = best_of_sto(sto_r)
        sto_r_sig = sto_r[sto_r_name][0] > STOCHASTIC_THRESHOLD
        keep_det = True
        if sto_r_sig:
            two_dl, theta, s0_model = sto_r[sto_r_name]
            var = _amplitude_variance(w, sto_r_name, theta, s0_model)
            amp = float(np.dot(w, y))
            z2 = amp * amp / var
            keep_det = z2 > JOINT_THRESHOLD
            stats["joint_z2"] = z2
            # the stochastic model is re-fitted without the shape when the shape is dropped
            if keep_det:
                findings.append(_rw_or_gm(sto_r_name, sto_r, resid, delta_s))
                noise = (sto_r_name, theta, s0_model, delta_s)
            else:
                findings.append(_rw_or_gm(sto_name, sto, y, delta_s))
        if keep_det and not findings:
            # a wander that happens to look like the shape: compare exact likelihoods on the
            # same (undetrended) block means; the shape must beat the best stochastic model
            # by STOCHASTIC_PENALTY per extra parameter
            # (on at most 512 coarser blocks: the Kalman filter is a Python loop)
            group = max(1, int(math.ceil(n / 512)))
            m = n // group
            yg = y[: m * group].reshape(m, group).mean(axis=1)
            gg = shape[: m * group].reshape(m, group).mean(axis=1)
            gg = gg - gg.mean()
            ygc = yg - yg.mean()
            rss0 = float(np.dot(ygc, ygc))
            fit = float(np.dot(gg, ygc)) ** 2 / max(float(np.dot(gg, gg)), 1e-300)
            rss1 = max(rss0 - fit, 1e-300)
            two_dl_det = m * math.log(rss0 / rss1)
            sto_g, _ = stochastic_fits(yg, delta_s * group)
            exact = exact_stochastic_gain(yg, sto_g, delta_s * group)
            group_delta = delta_s * group
            score_det = two_dl_det - N_PARAMS[det_name] * STOCHASTIC_PENALTY
            best_exact = max((v[0] - N_PARAMS[k] * STOCHASTIC_PENALTY, k) for k, v in exact.items())
            stats["exact_det"] = two_dl_det
            stats.update({"exact_" + k: v[0] for k, v in exact.items()})
            if best_exact[0] > score_det:
                keep_det = False
                name = best_exact[1]
                if sto_sig and sto_name in (RATE_RANDOM_WALK, GAUSS_MARKOV, BIAS_INSTABILITY):
                    findings.append(_rw_or_gm(sto_name, sto, y, delta_s))
                else:
                    findings.append(_stochastic_candidate(name, exact[name], group_delta, m))
            else:
                noise = (None, (), s0, delta_s)
        if keep_det and det_name in (BIAS_STEP, RATE_RAMP, WARMUP):
            stats["flicker_p"] = p_value = flicker_p_value(y, det_name)
            if p_value > FLICKER_ALPHA:  # the wander named in its place, where its fit holds one at all
                keep_det = False
                findings = [_flicker_reading(det_name, p_value, sto, delta_s, n)] if sto[BIAS_INSTABILITY][0] > 0 else []
                noise = (BIAS_INSTABILITY, sto[BIAS_INSTABILITY][1], sto[BIAS_INSTABILITY][2], delta_s)
        if keep_det:
            findings.insert(0, deterministic_candidate(det_name, d / s0, params, x, sample_rate_hz,
                                                       length, temp_c))
    elif sto_sig:
        findings.append(_rw_or_gm(sto_name, sto, y, delta_s))
    return findings, noise


def _flicker_reading(shape, p_value, table, delta_s, n):
    """The bias instability named in the place of a shape that flicker draws as often as
    ``p_value`` (:func:`flicker_p_value`), its evidence saying so."""
    cand, shape = _stochastic_candidate(BIAS_INSTABILITY, table[BIAS_INSTABILITY], delta_s, n), shape.replace('_', ' ')
    return replace(cand, evidence=(
        f"the block means depart from white noise as a {shape} would, but white noise with flicker (1/f) draws "
        f"such a {shape} as clearly in {100 * p_value:.0f} % of records (parametric bootstrap, {FLICKER_REPLICATES} "
        f"records; a shape is named below {100 * FLICKER_ALPHA:g} %): the wander is the reading named" + (
            ", though its own test alone would not name it" if cand.statistic < cand.threshold else "") + f" ({cand.evidence})"))


def _rw_or_gm(name, table, y, delta_s):
    """Random walk or Gauss-Markov: decided on the exact (Kalman) likelihoods of the block
    means (at most 512), which keep the low-frequency information the detrended Whittle fit
    loses. Gauss-Markov needs ``EXACT_GM_MARGIN`` more than the random walk and a tau below a
    fifth of the record; on 30-minute and 10-minute test cases this told the two apart in 53
    of 56 cases against 49 of 56 for the Whittle comparison. A bias instability passes through.
    A bias instability or Gauss-Markov candidate carries the other wander where that one is
    significant too (:func:`_with_wander_alternative`)."""
    n = y.size
    if name == BIAS_INSTABILITY:
        return _with_wander_alternative(_stochastic_candidate(name, table[name], delta_s, n), table, delta_s, n)
    group = max(1, int(math.ceil(n / 512)))
    m = n // group
    yg = y[: m * group].reshape(m, group).mean(axis=1)
    sto_g, _ = stochastic_fits(yg, delta_s * group)
    exact = exact_stochastic_gain(yg, sto_g, delta_s * group)
    gm = exact[GAUSS_MARKOV]
    tau = stochastic_params(GAUSS_MARKOV, gm[1], delta_s * group)["tau_s"]
    if gm[0] - exact[RATE_RANDOM_WALK][0] > EXACT_GM_MARGIN and tau < n * delta_s / GM_MAX_TAU_DIVISOR:
        return _with_wander_alternative(_stochastic_candidate(GAUSS_MARKOV, gm, delta_s * group, m), table, delta_s, n)
    return _stochastic_candidate(RATE_RANDOM_WALK, table[RATE_RANDOM_WALK], delta_s, n)


def _with_wander_alternative(cand, table, delta_s, n):
    """``cand`` (a bias instability or a Gauss-Markov wander) with the other of :data:`~gyrofilter.analysis.gap.confound.CONFUSABLE_WANDERS`
    as its ``wander_alternative`` where that one is significant over white noise too (and,
    a Gauss-Markov, with its tau below a fifth of the record): the gap analysis weighs the two
    readings on D (:func:`gyrofilter.analysis.gap.confound.weigh_wanders`)."""
    other = CONFUSABLE_WANDERS[1 - CONFUSABLE_WANDERS.index(cand.effect)]
    two_dl, theta, _ = table[other]
    if two_dl <= STOCHASTIC_THRESHOLD:
        return cand
    if other == GAUSS_MARKOV and stochastic_params(other, theta, delta_s)["tau_s"] >= n * delta_s / GM_MAX_TAU_DIVISOR:
        return cand
    return replace(cand, wander_alternative=_stochastic_candidate(other, table[other], delta_s, n))


def _stochastic_candidate(name, fit, delta_s, n):
    two_dl, theta, s0 = fit
    params = stochastic_params(name, theta, delta_s)
    words = {RATE_RANDOM_WALK: "a 1/f^2 (random-walk) bias spectrum",
             BIAS_INSTABILITY: "a 1/f (flicker) bias spectrum",
             GAUSS_MARKOV: "an exponentially correlated (Lorentzian) bias spectrum"}[name]
    return Candidate(
        effect=name, params=params, statistic=two_dl, threshold=STOCHASTIC_THRESHOLD,
        statistic_name="2 Delta log-likelihood (Whittle) over white noise",
        evidence=(f"the spectrum of {n} block means ({delta_s:.3g} s each) rises at low "
                  f"frequency like {words}: likelihood ratio 2 Delta log L = {two_dl:.0f} over "
                  f"white noise (threshold {STOCHASTIC_THRESHOLD:.0f})"),
    )


def _refine_step(x, sample_rate_hz, length, time_s):
    """Sample-level step time: two-mean scan of the raw series within +-2 blocks (the cumulative
    sum only over the samples the scan's windows reach)."""
    k = int(round(time_s * sample_rate_hz))
    lo, hi = max(1, k - 2 * length), min(x.size - 1, k + 2 * length)
    w = max(4 * length, 50)
    base, top = max(0, lo - w), min(x.size, hi + w)
    c = np.concatenate(([0.0], np.cumsum(x[base:top])))  # c[i - base] = sum of x[base:i]
    best, best_i = -1.0, k
    for i in range(lo, hi + 1):
        a0, b1 = max(0, i - w), min(x.size, i + w)
        left = (c[i - base] - c[a0 - base]) / (i - a0)
        right = (c[b1 - base] - c[i - base]) / (b1 - i)
        s = (right - left) ** 2 * (i - a0) * (b1 - i) / (b1 - a0)
        if s > best:
            best, best_i = s, i
    return best_i / sample_rate_hz


def _first_sample_at(time_s, sample_rate_hz, n):
    """The first sample index ``i`` in ``0 .. n`` with ``i / sample_rate_hz >= time_s`` (n when none)."""
    i = min(max(0, int(math.floor(time_s * sample_rate_hz)) - 2), n)
    while i < n and i / sample_rate_hz < time_s:
        i += 1
    return i


def deterministic_candidate(name, d, params, x, sample_rate_hz, length, temp_c):
    """The candidate of a deterministic shape, its parameters re-fitted on the full-rate series
    ``x`` (deg/s, at ``sample_rate_hz`` Hz) and its component (zero mean) made a piece at a time
    (:func:`gyrofilter.analysis.gap.detectors.sinusoid.fitted`): one series of memory."""
    params = dict(params)
    n = x.size
    if name == BIAS_STEP:
        ts = _refine_step(x, sample_rate_hz, length, params["time_s"])
        first = _first_sample_at(ts, sample_rate_hz, n)  # the first sample with t = i / sample_rate_hz >= ts
        params["time_s"] = ts
        if 0 < first < n:
            params["size_dps"] = float(x[first:].mean() - x[:first].mean())
        comp = np.zeros(n)
        comp[first:] = params["size_dps"]
        what = f"the mean steps by {params['size_dps']:+.3g} deg/s at t = {ts:.1f} s"
    else:
        if name == RATE_RAMP:
            t_mean = 0.5 * (n - 1) / sample_rate_hz

            def columns(lo, hi):
                return (np.arange(lo, hi) / sample_rate_hz - t_mean,)
        elif name == WARMUP:
            tau = params["tau_s"]

            def columns(lo, hi):
                return (np.exp(-(np.arange(lo, hi) / sample_rate_hz) / tau),)
        else:  # temperature
            tc = np.asarray(temp_c, dtype=float)
            tc_mean = float(tc.mean())

            def columns(lo, hi):
                return (tc[lo:hi] - tc_mean,)
        coef = least_squares(columns, x)
        comp = fitted(columns, coef[:1], n)
        if name == RATE_RAMP:
            params["r_dps_per_s"] = float(coef[0])
            what = f"the bias drifts linearly by {params['r_dps_per_s']:+.3g} deg/s per s"
        elif name == WARMUP:
            params["amplitude_dps"] = float(coef[0])
            what = (f"the bias settles exponentially: {params['amplitude_dps']:+.3g} deg/s at t = 0, "
                    f"time constant {tau:.3g} s")
        else:
            params["coefficient_dps_per_c"] = float(coef[0])
            what = (f"the bias follows the temperature with {params['coefficient_dps_per_c']:+.3g} "
                    f"deg/s per deg C over {np.ptp(tc):.2f} deg C")
    comp -= comp.mean()
    params = {k: float(v) for k, v in params.items()}
    return Candidate(
        effect=name, params=params, statistic=d, threshold=DETERMINISTIC_THRESHOLD,
        statistic_name="Delta chi^2 of the block means over a constant bias",
        component=comp,
        evidence=(f"{what}; the fit lowers chi^2 of the block means by {d:.0f} (threshold "
                  f"{DETERMINISTIC_THRESHOLD:.0f}, white noise: chi^2_1 to chi^2_2 scan)"),
    )
