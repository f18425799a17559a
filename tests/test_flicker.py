"""The flicker bank of the ``bias_instability`` effect (gyrofilter/sim/flicker.py): the exact Allan
variance of the bank as drawn (slow components at knots, interpolated) against the full-rate
bank's, with an exact oracle of an interpolated AR(1); the levels; block-by-block streaming."""
import math

import numpy as np
import pytest
from scipy.signal import lfilter

from gyrofilter.sim import noise_terms as nt
from gyrofilter.sim.flicker import (FLICKER_ADEV_PER_B, KNOT_PERIODS, KNOT_STEP, BiasInstability, bank_levels, flicker_bank,
                                   sum_of_ar1_filter)


def interpolated_ar1_allan_variance(phi, variance, step, m):
    """Exact overlapping Allan variance, averaged over the start sample, of an AR(1) (lag-1 φ per
    sample, variance v) kept at knots every ``step`` samples and linearly interpolated between them.

    A sample is Σ_j hat(n - j·step) K_j with hat(d) = max(0, 1 - |d|/step) and Cov(K_a, K_b) =
    v ψ^|a-b|, ψ = φ^step. The contrast of two adjacent clusters of m samples starting at p puts the
    weight W_j = C(p - j·step) - 2 C(p + m - j·step) + C(p + 2m - j·step) on knot j, C(t) = Σ_{d<t}
    hat(d); σ²(m) = mean over p = 0..step-1 of Wᵀ Σ W / (2 m²), Wᵀ Σ W = v (2 Σ W_j u_j - Σ W_j²)
    with u_j = Σ_{k<=j} ψ^(j-k) W_k. ``step`` = 1 is the AR(1) itself."""
    psi = phi**step
    d = np.arange(-step, step + 1)
    cum = np.r_[0.0, np.cumsum(np.maximum(0.0, 1.0 - np.abs(d) / step))]  # cum[i] = C(-step + i)

    def c(t):
        return cum[np.clip(t + step, 0, 2 * step + 1)]

    out = []
    for mm in np.atleast_1d(m).astype(int):
        p = np.arange(step)[:, None]
        j = np.arange(-1, (step - 1 + 2 * mm) // step + 3)[None, :]
        w = c(p - j * step) - 2.0 * c(p + mm - j * step) + c(p + 2 * mm - j * step)
        u = lfilter([1.0], [1.0, -psi], w, axis=1)
        quad = variance * (2.0 * np.sum(w * u, axis=1) - np.sum(w * w, axis=1))
        out.append(quad.mean() / (2.0 * mm * mm))
    return np.array(out)


def brute_interpolated_allan_variance(phi, variance, step, m):
    """The same by listing every sample's two knot weights (slow; a second derivation)."""
    psi, out = phi**step, []
    for mm in np.atleast_1d(m).astype(int):
        tot = 0.0
        for p in range(step):
            n = np.arange(p, p + 2 * mm)
            sign = np.where(n < p + mm, -1.0, 1.0)
            j = n // step
            f = (n - j * step) / step
            w = np.bincount(j, sign * (1 - f), minlength=j[-1] + 2) + np.bincount(j + 1, sign * f, minlength=j[-1] + 2)
            cov = variance * psi ** np.abs(np.subtract.outer(np.arange(len(w)), np.arange(len(w))))
            tot += w @ cov @ w
        out.append(tot / step / (2 * mm * mm))
    return np.array(out)


def bank_allan_variance(taus_s, q_dps, sample_rate_hz, m, levels=None):
    """Exact Allan variance of the bank: each component the AR(1) oracle at full rate (``levels``
    None) or interpolated from knots every KNOT_STEP**level samples."""
    total = np.zeros(len(m))
    for i, tau_s in enumerate(taus_s):
        phi = math.exp(-1.0 / (sample_rate_hz * tau_s))
        step = 1 if levels is None else KNOT_STEP ** int(levels[i])
        total += (nt.ar1_allan_variance(phi, q_dps**2, m) if step == 1
                  else interpolated_ar1_allan_variance(phi, q_dps**2, step, m))
    return total


def test_oracle_is_the_ar1_at_step_1_and_agrees_with_the_listing():
    m = np.array([1, 2, 3, 7, 30])
    assert np.allclose(interpolated_ar1_allan_variance(0.97, 2.0, 1, m), nt.ar1_allan_variance(0.97, 2.0, m), rtol=1e-10)
    for step in (2, 4, 16):
        assert np.allclose(interpolated_ar1_allan_variance(0.995, 1.5, step, m),
                           brute_interpolated_allan_variance(0.995, 1.5, step, m), rtol=1e-9)


def test_interpolation_loses_at_most_019_q2_over_k():
    # the per-component bound of the module docstring, at the least period of a level (P = K S)
    phi = math.exp(-1.0 / (KNOT_PERIODS * KNOT_STEP))
    m = np.unique(np.round(np.logspace(0, 3, 40)).astype(int))
    loss = nt.ar1_allan_variance(phi, 1.0, m) - interpolated_ar1_allan_variance(phi, 1.0, KNOT_STEP, m)
    assert loss.max() <= 0.19 / KNOT_PERIODS
    assert loss.max() > 0.1 / KNOT_PERIODS  # the bound is not loose by orders


def test_bank_levels_at_their_boundaries():
    k, s = KNOT_PERIODS, KNOT_STEP
    periods = np.array([0.5, 1.0, k * s - 1e-9, k * s, k * s * s * (1 - 1e-12), k * s * s, k * s**5 * 1.5])
    assert list(bank_levels(periods)) == [0, 0, 0, 1, 1, 2, 5]


@pytest.mark.parametrize("sample_rate_hz, duration_s, per_decade", [(100.0, 3600.0, 2.0), (1000.0, 600.0, 2.0),
                                                                     (100.0, 3600.0, 5.0)])
def test_drawn_bank_allan_variance_within_1_percent_of_the_full_rate_bank_and_flat(sample_rate_hz, duration_s, per_decade):
    b = 0.02
    term = BiasInstability(b, sample_rate_hz, np.random.default_rng(0), 1 / sample_rate_hz, duration_s, per_decade)
    assert term.levels.max() >= 4  # several levels interpolated
    m = np.unique(np.round(np.logspace(0, np.log10(duration_s * sample_rate_hz / 9), 30)).astype(int))
    full = bank_allan_variance(term.taus_s, term.q_dps, sample_rate_hz, m)
    drawn = bank_allan_variance(term.taus_s, term.q_dps, sample_rate_hz, m, term.levels)
    assert np.all(np.abs(drawn / full - 1) < 0.01), drawn / full
    flat = m >= 0.3 * sample_rate_hz  # 0.3 s .. T/9: the floor at 0.664 B within 2 %, as the full-rate bank
    ratio = np.sqrt(drawn[flat]) / (FLICKER_ADEV_PER_B * b)
    assert np.all(np.abs(ratio - 1) < 0.02), ratio


def test_full_rate_bank_is_flat_at_0664_b_exactly():
    # exact Allan variance of the Gauss-Markov bank (sum of AR(1) oracles), no sampling error
    fs, duration, b = 100.0, 3600.0, 0.02
    taus, q = flicker_bank(b, fs, 1 / fs, duration, 2.0)
    m = np.unique(np.round(np.logspace(np.log10(0.3 * fs), np.log10(duration * fs / 9), 30)).astype(int))
    ratio = np.sqrt(bank_allan_variance(taus, q, fs, m)) / (FLICKER_ADEV_PER_B * b)
    assert np.log10(m[-1] / m[0]) > 3  # 0.3 s .. 400 s
    assert np.all(np.abs(ratio - 1) < 0.02)
    assert abs(FLICKER_ADEV_PER_B - 0.664) < 5e-4


def test_blocks_equal_one_shot_bit_for_bit():
    def term():
        return BiasInstability(0.01, 100.0, np.random.default_rng(7), 0.01, 5000.0)

    n = 20000
    whole = term().next(np.zeros(n), None)
    rng, t, parts = np.random.default_rng(1), term(), []
    sizes = [0, 1, 3, 4, 5, 17, 64, 1023]
    while sum(map(len, parts)) < n:
        parts.append(t.next(np.zeros(min(int(rng.choice(sizes)), n - sum(map(len, parts)))), None))
    assert np.array_equal(np.concatenate(parts), whole)


def test_drawn_bank_variance_and_knot_law():
    # the sample variance of many samples of a short bank: the components' q² (all stationary)
    term = BiasInstability(0.05, 10.0, np.random.default_rng(3), 0.1, 100.0)
    x = term.next(np.zeros(400_000), None)
    assert term.levels.max() >= 1
    assert abs(np.var(x) / (len(term.taus_s) * term.q_dps**2) - 1) < 0.05


def test_joint_filter_has_the_law_of_the_sum_of_its_components():
    # level 0 of the default bank (P = 1 .. 100 samples): one ARMA(5, 4) for five AR(1)s; its
    # stationary variance and spectrum are those of the sum (oracles: noise_terms' Lyapunov
    # variance and the AR(1) spectra); close poles fail the check and are drawn one by one
    periods = 10.0 ** (np.arange(5) / 2.0)
    phis, gains = np.exp(-1.0 / periods), 0.3 * np.sqrt(1.0 - np.exp(-2.0 / periods))
    b, a = sum_of_ar1_filter(phis, gains)
    assert len(b) == 5 and len(a) == 6
    assert abs(nt.filter_variance(b, a) / np.sum(gains**2 / (1.0 - phis**2)) - 1.0) < 1e-5
    f_hz = np.linspace(0.0, 50.0, 101)
    ar1 = sum(nt.filter_psd([g], [1.0, -p], f_hz, 100.0) for p, g in zip(phis, gains))
    assert np.allclose(nt.filter_psd(b, a, f_hz, 100.0), ar1, rtol=1e-5)
    close = np.exp(-1.0 / (20.0 * 10.0 ** (np.arange(5) / 10.0)))
    assert sum_of_ar1_filter(close, np.full(5, 0.1)) is None
    term = BiasInstability(0.01, 100.0, np.random.default_rng(0), 0.2, 0.5, per_decade=10.0)
    assert len(term.bank.filters) == len(term.taus_s)  # the fallback: a filter per component


def test_a_zero_bias_instability_is_zero_and_warns_nothing():
    """B = 0 (a model may say so): every gain is 0, the joint filter's spectral check has nothing
    to compare and falls back without a 0/0 warning (the fuzzed model files caught one)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        bank = BiasInstability(0.0, 100.0, np.random.default_rng(0), 0.01, 3600.0)
        assert not np.any(bank.next(np.arange(1000) / 100.0, None))
