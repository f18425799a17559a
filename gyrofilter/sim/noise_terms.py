"""Per-effect generators of the gyro simulator, one class per term of the effect table (the
``bias_instability`` bank lives in :mod:`gyrofilter.sim.flicker`).

Every generator is *streaming*: it is built once per axis and then asked for consecutive blocks
of samples with :meth:`next(t_s, temp_c)`; it keeps the state it needs (filter memory, the last
value of a random walk) between blocks, so the output does not depend on how the run is cut
into blocks. Each generator draws from its own ``numpy.random.Generator`` and consumes it
strictly sequentially, which is what makes a chunked run equal to a one-shot run bit for bit.

All outputs are angular rate in deg/s (temperature in deg C); ``t_s`` is the sample time
``n / f_s`` with ``n`` the absolute sample index, ``f_s`` the sample rate.

The ``next`` protocol, shared by every term class: ``next(t_s, temp_c)`` takes ``t_s``, the
(n,) sample times (s) of the next block, consecutive with the previous block's, and
``temp_c``, the (n,) true sensor temperatures (deg C) at those times or None without a
temperature profile (only :class:`TemperatureCoefficient` uses it); it returns a new (n,)
float array, the term's contribution to the rate (deg/s), and advances the term's state and
random stream. Terms that are random take ``rng``, a ``numpy.random.Generator`` of their own.

Notation: ``f_s`` sample rate (Hz), ``w[n]`` independent standard normal draws, ``φ``
an AR(1) coefficient. References: IEEE Std 952-1997 annex C (Allan variance of the gyro error
terms), NIST SP 1065 (Riley 2008) section 5.2 (Allan variance), Kasdin 1995 (discrete
simulation of coloured noise by filtered white noise).
"""
from __future__ import annotations

import math

import numpy as np


def _lfilter_ar1(phi, gain, w, state):
    """y[n] = φ y[n-1] + gain · w[n], starting from y[-1] = state; returns (y, last y)."""
    from scipy.signal import lfilter

    y, _ = lfilter([gain], [1.0, -phi], w, zi=[phi * state])
    return y, (y[-1] if len(y) else state)


class Constant:
    """Constant bias: ω(t) = b (deg/s). Deterministic.

    ``value_dps``: b (deg/s), the axis's ``bias_dps``.
    """

    def __init__(self, value_dps):
        self.value_dps = float(value_dps)

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        return np.full(len(t_s), self.value_dps)


class WhiteNoise:
    """Angle random walk: white rate noise with Allan deviation σ(τ) = N / sqrt(τ).

    ω[n] = N · sqrt(f_s) · w[n], so the per-sample standard deviation is N·sqrt(f_s) and the
    two-sided PSD is N² (deg/s)²/Hz (IEEE Std 952-1997 C.1; N in deg/s/sqrt(Hz) = deg/sqrt(s)).

    With ``lag1`` (the ``colored_noise`` effect) the same white sequence is passed through a
    first-order low pass, like the MPU6050's digital low-pass filter:

    * ``preserve="arw"`` (default): e[n] = ρ e[n-1] + (1 - ρ) · N sqrt(f_s) w[n]. Unity gain at
      DC, so N keeps its Allan meaning (σ(τ) → N/sqrt(τ) for τ much longer than the
      correlation time 1/(f_s ln(1/ρ))) while the per-sample std drops to
      N sqrt(f_s) sqrt((1 - ρ)/(1 + ρ)). This is what a real low-pass stage does.
    * ``preserve="std"``: e[n] = ρ e[n-1] + sqrt(1 - ρ²) · N sqrt(f_s) w[n]. The per-sample
      std stays N sqrt(f_s); the long-τ Allan level rises to N sqrt((1 + ρ)/(1 - ρ)).

    In both, the lag-1 autocorrelation of the noise is ρ = ``lag1``; the process starts in its
    stationary state.

    ``arw_dps_per_sqrt_hz``: N (deg/s/sqrt(Hz)); ``sample_rate_hz``: f_s (Hz); ``rng``: the
    term's generator; ``lag1``: ρ in (-1, 1), 0 for white noise; ``preserve``: ``"arw"`` or
    ``"std"`` (any other value acts as ``"std"``; :func:`~gyrofilter.sim.model.validate_model`
    admits only these two).
    """

    def __init__(self, arw_dps_per_sqrt_hz, sample_rate_hz, rng, lag1=0.0, preserve="arw"):
        self.sigma_dps = float(arw_dps_per_sqrt_hz) * math.sqrt(sample_rate_hz)
        self.rng = rng
        self.lag1 = float(lag1)
        if preserve == "arw":
            self.gain = 1.0 - self.lag1
        else:
            self.gain = math.sqrt(1.0 - self.lag1**2)
        self.state = None

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        n = len(t_s)
        if self.lag1 == 0.0:
            return self.sigma_dps * self.rng.standard_normal(n)
        if self.state is None:
            # stationary start: Var(e) = gain² σ² / (1 - ρ²)
            self.state = self.gain * self.sigma_dps / math.sqrt(1.0 - self.lag1**2) * self.rng.standard_normal()
        y, self.state = _lfilter_ar1(self.lag1, self.gain * self.sigma_dps, self.rng.standard_normal(n), self.state)
        return y


class ScaleMixtureNormal:
    """Unit-variance draws of a Gaussian scale mixture: the ``heavy_tails`` effect's white noise.

    w[n] = k[n] z[n], z[n] ~ N(0, 1), k[n] = c k₀ with probability p (the wide component), else
    k₀, independently per sample; k₀ = 1 / sqrt(1 - p + p c²), so Var w = 1 (a contaminated
    normal, Tukey 1960). Kurtosis 3 (1 - p + p c⁴) / (1 - p + p c²)²; beyond t core sd k₀ lie
    2 (1 - p) Φ(-t) + 2 p Φ(-t / c). In place of a noise term's generator it makes the white
    noise (a colored noise's innovations) heavy-tailed at the same variance: N and the Allan
    deviation keep. ``rng_normal``: the z's generator (the noise term's own stream: common random
    numbers); ``rng_scale``: the components'; ``fraction``: p in [0, 1); ``scale_ratio``: c >= 1.
    """

    def __init__(self, rng_normal, rng_scale, fraction, scale_ratio):
        self.rng_normal, self.rng_scale = rng_normal, rng_scale
        self.p, self.c = float(fraction), float(scale_ratio)
        self.k0 = 1.0 / math.sqrt(1.0 - self.p + self.p * self.c**2)

    def standard_normal(self, size=None):
        """``size`` draws (one float for None) of w, consuming both streams in order."""
        z = self.rng_normal.standard_normal(size)
        k = np.where(self.rng_scale.random(size) < self.p, self.c * self.k0, self.k0)
        return z * k if size is not None else float(z * k)


class GaussMarkov:
    """First-order Gauss-Markov bias: stationary std σ, correlation time T.

    Continuous: dx/dt = -x/T + sqrt(2σ²/T) η(t), autocovariance R(Δt) = σ² exp(-|Δt|/T).
    Exact discretisation (the sampled process has the same R at the sample times):
    x[n] = φ x[n-1] + σ sqrt(1 - φ²) w[n], φ = exp(-1 / (f_s T)); x[-1] ~ N(0, σ²) (stationary).
    (Gelb, Applied Optimal Estimation, table 3.8-1; IEEE Std 952-1997 C.5.)

    ``sigma_dps``: σ (deg/s); ``tau_s``: T (s), > 0; ``sample_rate_hz``: f_s (Hz); ``rng``: the
    term's generator.
    """

    def __init__(self, sigma_dps, tau_s, sample_rate_hz, rng):
        self.sigma_dps = float(sigma_dps)
        self.phi = math.exp(-1.0 / (sample_rate_hz * float(tau_s)))
        self.rng = rng
        self.state = None

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        if self.state is None:
            self.state = self.sigma_dps * self.rng.standard_normal()
        w = self.rng.standard_normal(len(t_s))
        y, self.state = _lfilter_ar1(self.phi, self.sigma_dps * math.sqrt(1.0 - self.phi**2), w, self.state)
        return y


def _state_covariance(b, a):
    """Stationary covariance P of the lfilter state (transposed direct form II), unit white input.

    With a₀ = 1 and k = max(len(a), len(b)) - 1, the state z (k numbers) of
    y[n] = b₀ w[n] + z₀[n] evolves as z[n+1] = A z[n] + g w[n], A[i, 0] = -a_{i+1},
    A[i, i+1] = 1, g_i = b_{i+1} - a_{i+1} b₀ (scipy.signal.lfilter's recursion). For a stable
    filter P solves the discrete Lyapunov equation P = A P Aᵀ + g gᵀ.
    """
    from scipy.linalg import solve_discrete_lyapunov

    k = max(len(a), len(b)) - 1
    a = np.r_[a, np.zeros(k + 1 - len(a))]
    b = np.r_[b, np.zeros(k + 1 - len(b))]
    trans = np.zeros((k, k))
    trans[:, 0] = -a[1:]
    trans[np.arange(k - 1), np.arange(1, k)] = 1.0
    drive = b[1:] - a[1:] * b[0]
    return solve_discrete_lyapunov(trans, np.outer(drive, drive))


def filter_variance(b, a):
    """Stationary variance of y = (B(z)/A(z)) w for unit white w: b₀² + P₀₀ (P of
    :func:`_state_covariance`), i.e. Σ h[n]² of the impulse response.

    ``b``, ``a``: numerator and denominator coefficients in z⁻¹ (a₀ = 1, stable A). Returns
    the variance in the square of ``b``'s unit ((deg/s)² when ``b`` is in deg/s).
    """
    b = np.asarray(b, dtype=float)
    if max(len(a), len(b)) == 1:
        return float(b[0] ** 2)
    return float(b[0] ** 2 + _state_covariance(b, a)[0, 0])


class FilteredNoise:
    """Stationary coloured noise y = (B(z)/A(z)) w: white normal draws through a rational filter.

    y[n] = Σ_j b_j w[n-j] - Σ_{i≥1} a_i y[n-i] (a₀ = 1; Kasdin 1995, filtered white noise), the
    filter state started from its stationary law N(0, P) (:func:`_state_covariance`), so every sample
    has the stationary variance; streams block by block with the lfilter state. Two-sided PSD
    S(f) = |B(e^{-jω})|² / |A(e^{-jω})|² / f_s ((deg/s)²/Hz), ω = 2π f / f_s. The ``narrowband``
    and ``arma`` effects, and ``colored_noise`` with ``lag2``, are built on it.

    ``b``: numerator coefficients (deg/s: they scale the unit-variance draws); ``a``:
    denominator coefficients (a₀ = 1, stable); ``rng``: the term's generator.
    :func:`narrowband_filter` and :func:`arma_filter` make (b, a).
    """

    def __init__(self, b, a, rng):
        self.b = np.asarray(b, dtype=float)
        self.a = np.asarray(a, dtype=float)
        self.rng = rng
        self.state = None

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        from scipy.signal import lfilter

        if len(self.a) == 1 and len(self.b) == 1:
            return self.b[0] * self.rng.standard_normal(len(t_s))
        if self.state is None:  # z ~ N(0, P): stationary from the first sample, no burn-in
            vals, vecs = np.linalg.eigh(_state_covariance(self.b, self.a))
            self.state = vecs @ (np.sqrt(np.clip(vals, 0.0, None)) * self.rng.standard_normal(len(vals)))
        y, self.state = lfilter(self.b, self.a, self.rng.standard_normal(len(t_s)), zi=self.state)
        return y


def arma11_from_lags(lag1, lag2):
    """(φ, μ) of the first-order ARMA e[n] = φ e[n-1] + a[n] + μ a[n-1] whose lag-1 and lag-2
    autocorrelations are ``lag1`` (ρ₁) and ``lag2`` (ρ₂); None when there is none.

    For this process ρ₁ = (1 + φμ)(φ + μ) / (1 + 2φμ + μ²) and ρ_k = φ ρ_{k-1} for k >= 2
    (Box, Jenkins & Reinsel, Time Series Analysis, sec. 3.4.3, with their θ = -μ). So φ = ρ₂ / ρ₁,
    and μ is the invertible (|μ| < 1) root of (ρ₁ - φ) μ² + (2φρ₁ - 1 - φ²) μ + (ρ₁ - φ) = 0,
    whose two roots are μ and 1/μ. ρ₂ = ρ₁² gives μ = 0 (an AR(1)), ρ₂ = 0 an MA(1) (|ρ₁| < 1/2);
    ρ₁ = ρ₂ = 0 is white noise. A pair exists only for |ρ₂| < |ρ₁| and
    1 + φ² - 2φρ₁ > 2 |ρ₁ - φ| (real roots of modulus other than 1).
    """
    lag1, lag2 = float(lag1), float(lag2)
    if lag1 == 0.0:
        return (0.0, 0.0) if lag2 == 0.0 else None
    phi = lag2 / lag1
    if not abs(phi) < 1.0:
        return None
    c, b = lag1 - phi, 2.0 * phi * lag1 - 1.0 - phi * phi
    if c == 0.0:
        return phi, 0.0
    disc = b * b - 4.0 * c * c
    if not disc > 0.0:
        return None
    return phi, (-b - math.sqrt(disc)) / (2.0 * c)


def arma11_long_run_ratio(phi, mu):
    """Spectrum at zero frequency over the variance of the first-order ARMA of
    :func:`arma11_from_lags`, 1 + 2 Σ_k ρ_k = (1 + μ)² (1 - φ²) / ((1 - φ)² (1 + 2φμ + μ²));
    (1 + φ) / (1 - φ) for an AR(1). The Allan variance of the noise tends to this ratio times
    that of white noise of the same variance at τ much longer than its correlation."""
    return (1.0 + mu) ** 2 * (1.0 - phi * phi) / ((1.0 - phi) ** 2 * (1.0 + 2.0 * phi * mu + mu * mu))


def arma11_lags(phi, mu):
    """(ρ₁, ρ₂) of the first-order ARMA of :func:`arma11_from_lags`:
    ρ₁ = (1 + φμ)(φ + μ) / (1 + 2φμ + μ²), ρ₂ = φ ρ₁."""
    rho1 = (1.0 + phi * mu) * (phi + mu) / (1.0 + 2.0 * phi * mu + mu * mu)
    return rho1, phi * rho1


def arma11_for_lag1_and_ratio(lag1, ratio, near_phi=0.0):
    """The first-order ARMA (φ, μ) with lag-1 autocorrelation ``lag1`` and long-run ratio
    ``ratio`` (:func:`arma11_long_run_ratio`), the root nearest ``near_phi``; None when there is
    none. Along ρ₁ = lag1, μ is a function of φ (:func:`arma11_from_lags` with ρ₂ = φ ρ₁); the
    ratio is scanned over φ in (-0.99, 0.99) and each sign change of L(φ) - ratio refined by
    Brent's method."""
    from scipy.optimize import brentq

    def excess(phi):
        pair = arma11_from_lags(lag1, phi * lag1)
        return None if pair is None else arma11_long_run_ratio(*pair) - ratio

    grid = np.linspace(-0.99, 0.99, 397)
    vals = [excess(p) for p in grid]
    roots = [brentq(excess, grid[j], grid[j + 1]) for j in range(grid.size - 1)
             if vals[j] is not None and vals[j + 1] is not None and vals[j] * vals[j + 1] <= 0.0
             and all(excess(p) is not None for p in np.linspace(grid[j], grid[j + 1], 5))]
    if not roots:
        return None
    phi = min(roots, key=lambda r: abs(r - near_phi))
    return arma11_from_lags(lag1, phi * lag1)


def colored_noise_filter(arw_dps_per_sqrt_hz, sample_rate_hz, lag1, lag2, preserve="arw"):
    """(b, a) of the ``colored_noise`` effect given ``lag2``: the white noise N sqrt(f_s) w[n]
    through the first-order ARMA of :func:`arma11_from_lags`,
    e[n] = φ e[n-1] + g N sqrt(f_s) (w[n] + μ w[n-1]), for :class:`FilteredNoise`.

    ``preserve="arw"``: g = (1 - φ) / (1 + μ), unity gain at DC, so N keeps its Allan meaning at
    long τ (as :class:`WhiteNoise` with ``lag1`` alone); ``"std"``: g = sqrt((1 - φ²) / (1 + 2φμ
    + μ²)), the per-sample std stays N sqrt(f_s). Raises ValueError when no first-order ARMA has
    these autocorrelations.
    """
    pair = arma11_from_lags(lag1, lag2)
    if pair is None:
        raise ValueError(f"no first-order ARMA noise has lag-1 autocorrelation {lag1:g} and lag-2 {lag2:g}")
    phi, mu = pair
    if preserve == "arw":
        gain = (1.0 - phi) / (1.0 + mu)
    else:
        gain = math.sqrt((1.0 - phi * phi) / (1.0 + 2.0 * phi * mu + mu * mu))
    sigma = float(arw_dps_per_sqrt_hz) * math.sqrt(sample_rate_hz) * gain
    return np.array([sigma, sigma * mu]), np.array([1.0, -phi])


def narrowband_filter(rms_dps, center_hz, bandwidth_hz, sample_rate_hz):
    """(b, a) of the ``narrowband`` effect: a spectral line of given centre, width and rms.

    A two-pole resonator (AR(2)) y[n] = 2 r cos θ y[n-1] - r² y[n-2] + g w[n] with
    θ = 2π f₀ / f_s and r = exp(-π B / f_s): its poles r e^{±jθ} are the sampled poles
    -πB ± j2πf₀ of a continuous resonator whose peak has the half-power full width B (Hz)
    (Oppenheim & Schafer, Discrete-Time Signal Processing, 3rd ed., sec. 5.3.2; exact as
    B << f₀). The gain g sets the stationary std to ``rms_dps``: for an AR(2) with
    φ₁ = 2 r cos θ, φ₂ = -r², Var y = g² (1 - φ₂) / ((1 + φ₂)((1 - φ₂)² - φ₁²))
    (Box & Jenkins, Time Series Analysis, eq. 3.2.28).

    ``rms_dps``: stationary std of the line (deg/s); ``center_hz``: f₀ (Hz), below f_s / 2;
    ``bandwidth_hz``: B (Hz), > 0; ``sample_rate_hz``: f_s (Hz). Returns (b, a) as arrays
    for :class:`FilteredNoise` (b in deg/s).
    """
    theta = 2.0 * math.pi * float(center_hz) / sample_rate_hz
    r = math.exp(-math.pi * float(bandwidth_hz) / sample_rate_hz)
    phi1, phi2 = 2.0 * r * math.cos(theta), -r * r
    unit_var = (1.0 - phi2) / ((1.0 + phi2) * ((1.0 - phi2) ** 2 - phi1**2))
    return np.array([float(rms_dps) / math.sqrt(unit_var)]), np.array([1.0, -phi1, -phi2])


def arma_filter(phi, theta, sigma_a_dps):
    """(b, a) of the ``arma`` effect in the signs of :mod:`gyrofilter.analysis.arma.identify` (paper 003):
    x[n] - Σ φ_i x[n-i] = a[n] - Σ θ_j a[n-j], a ~ N(0, σ_a²), so A(z) = 1 - Σ φ_i z⁻ⁱ and
    B(z) = σ_a (1 - Σ θ_j z⁻ʲ) (Box & Jenkins, eq. 3.4.1).

    ``phi``: AR coefficients φ_1..φ_p (stationary); ``theta``: MA coefficients θ_1..θ_q;
    ``sigma_a_dps``: σ_a, the std of the innovations a[n] (deg/s). Returns (b, a) as arrays for
    :class:`FilteredNoise`.
    """
    b = float(sigma_a_dps) * np.r_[1.0, -np.asarray(theta, dtype=float)]
    return b, np.r_[1.0, -np.asarray(phi, dtype=float)]


def filter_psd(b, a, f_hz, sample_rate_hz):
    """Two-sided PSD |B(e^{-jω})|² / |A(e^{-jω})|² / f_s of :class:`FilteredNoise`, ω = 2πf/f_s.

    ``b``, ``a``: the filter (b in deg/s); ``f_hz``: frequencies (Hz, scalar or array);
    ``sample_rate_hz``: f_s (Hz). Returns the PSD in (deg/s)²/Hz, the shape of ``f_hz``.
    """
    z = np.exp(-2j * math.pi * np.asarray(f_hz, dtype=float) / sample_rate_hz)
    num = np.polyval(np.asarray(b)[::-1], z)
    den = np.polyval(np.asarray(a)[::-1], z)
    return np.abs(num) ** 2 / np.abs(den) ** 2 / sample_rate_hz


class RateRandomWalk:
    """Rate random walk: the bias integrates white noise; Allan σ(τ) = K sqrt(τ / 3).

    x[n] = x[n-1] + (K / sqrt(f_s)) w[n], x[-1] = 0, so Var(x(t)) = K² t and the Allan
    deviation read at τ = 3 s equals K (IEEE Std 952-1997 C.4; K in deg/s/sqrt(s)).

    ``k_dps_per_sqrt_s``: K (deg/s/sqrt(s)); ``sample_rate_hz``: f_s (Hz); ``rng``: the term's
    generator.
    """

    def __init__(self, k_dps_per_sqrt_s, sample_rate_hz, rng):
        self.step_dps = float(k_dps_per_sqrt_s) / math.sqrt(sample_rate_hz)
        self.rng = rng
        self.state = 0.0

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        y = self.state + np.cumsum(self.step_dps * self.rng.standard_normal(len(t_s)))
        if len(y):
            self.state = y[-1]
        return y


class RateRamp:
    """Rate ramp: x(t) = R t; Allan σ(τ) = R τ / sqrt(2) (IEEE Std 952-1997 C.6).

    ``r_dps_per_s``: R (deg/s per s), signed.
    """

    def __init__(self, r_dps_per_s):
        self.r = float(r_dps_per_s)

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        return self.r * t_s


class Sinusoid:
    """Periodic disturbance: x(t) = A sin(2π f t + φ) with A the peak amplitude.

    ``amplitude_dps``: A (deg/s); ``frequency_hz``: f (Hz); ``phase_rad``: φ (rad).
    """

    def __init__(self, amplitude_dps, frequency_hz, phase_rad=0.0):
        self.a, self.f, self.phase = float(amplitude_dps), float(frequency_hz), float(phase_rad)

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        return self.a * np.sin(2.0 * math.pi * self.f * t_s + self.phase)


class TemperatureCoefficient:
    """Bias proportional to temperature: x(t) = c (T(t) - T_ref).

    T(t) is the true (noise-free) sensor temperature of the model's temperature profile; the
    recorded ``temp`` column adds the profile's read noise and resolution. T_ref defaults to
    the profile's temperature at t = 0, so ``bias_dps`` is the bias at the start temperature.

    ``coefficient_dps_per_c``: c (deg/s per deg C), signed; ``reference_c``: T_ref (deg C).
    Its ``next`` needs ``temp_c``.
    """

    def __init__(self, coefficient_dps_per_c, reference_c):
        self.c, self.ref = float(coefficient_dps_per_c), float(reference_c)

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        return self.c * (temp_c - self.ref)


class BiasStep:
    """Sudden bias jump: x(t) = s for t >= t_step, else 0.

    ``size_dps``: s (deg/s), signed; ``time_s``: t_step (s).
    """

    def __init__(self, size_dps, time_s):
        self.s, self.t0 = float(size_dps), float(time_s)

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        return np.where(t_s >= self.t0, self.s, 0.0)


class Warmup:
    """Warm-up settling of the bias after power-on: x(t) = a exp(-t / τ) (a signed, at t = 0).

    ``amplitude_dps``: a (deg/s); ``tau_s``: τ (s), > 0.
    """

    def __init__(self, amplitude_dps, tau_s):
        self.a, self.tau = float(amplitude_dps), float(tau_s)

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        return self.a * np.exp(-t_s / self.tau)


class Outliers:
    """Isolated gross errors (paper 001: single wild samples, e.g. -233 among 20-70 LSB).

    Each sample independently carries a spike with probability p = ``rate``; a spike is
    s · m · exp(σ_ln z) with s = ±1 equally likely, z ~ N(0, 1), so |spike| is log-normal with
    median m = ``magnitude_dps`` (and log-spread σ_ln = ``spread_ln``, default 0.25). Expected
    spike count p·N. Spikes are added after the noise and before saturation and quantization.

    ``rate``: p, probability per sample (0..1); ``magnitude_dps``: m (deg/s); ``rng_where``:
    generator of the spike positions, ``rng_size``: of their signs and sizes (two streams, so
    the positions do not depend on the sizes); ``spread_ln``: σ_ln (natural-log units).
    """

    def __init__(self, rate, magnitude_dps, rng_where, rng_size, spread_ln=0.25):
        self.p, self.m, self.spread = float(rate), float(magnitude_dps), float(spread_ln)
        self.rng_where, self.rng_size = rng_where, rng_size

    def next(self, t_s, temp_c):
        """The next block, (n,) deg/s, at times ``t_s`` (s); see the module docstring."""
        out = np.zeros(len(t_s))
        hit = np.flatnonzero(self.rng_where.random(len(t_s)) < self.p)
        if hit.size:
            draws = self.rng_size.standard_normal((hit.size, 2))
            sign = np.where(draws[:, 0] < 0.0, -1.0, 1.0)
            out[hit] = sign * self.m * np.exp(self.spread * draws[:, 1])
        return out


class RepeatedRows:
    """Rows that repeat the previous row exactly, every column at once (``repeated_samples``): the
    mark of a driver that polls the sensor faster than the sensor updates its output registers
    (an MPU6050 read without its data-ready flag or FIFO reads the same registers twice).

    Not an additive term: it acts on whole rows after the quantization. Row n (n >= 1) is a
    repeat, ``y[n] = y[n-1]`` on every column (so a run of repeats holds one row), where

    - ``pattern="random"``: independently with probability f = ``fraction`` (u[n] < f, u uniform);
    - ``pattern="beat"``: the poll clock (the sample rate f_s) beating against the sensor's output
      clock at f_out = (1 - f) f_s: the poll n reads output number j[n] = floor(n (1 - f) + φ),
      φ uniform in [0, 1) once per run, and repeats where j[n] = j[n-1]: a repeat every 1/f rows,
      at regular intervals, a fraction f of the rows.

    The expected fraction of repeated rows is f in both. ``fraction``: f in [0, 1); ``pattern``:
    ``random`` or ``beat``; ``rng``: the generator of u (or of φ). :meth:`next_mask` gives the
    repeats of the next block of rows and :meth:`apply` repeats them in a column, keeping the
    column's last row between blocks (a chunked run equals a one-shot run).
    """

    def __init__(self, fraction, pattern, rng):
        self.f, self.pattern, self.rng = float(fraction), pattern, rng
        self.phase = float(rng.random()) if pattern == "beat" else 0.0
        self.start = 0

    def next_mask(self, n):
        """(n,) bool: which of the next ``n`` rows repeat the row before them (row 0 never does)."""
        idx = np.arange(self.start, self.start + n)
        self.start += n
        if self.pattern == "beat":
            j = np.floor(idx * (1.0 - self.f) + self.phase)
            mask = j == np.floor((idx - 1) * (1.0 - self.f) + self.phase)
        else:
            mask = self.rng.random(n) < self.f
        return mask & (idx > 0)

    @staticmethod
    def apply(values, mask, last):
        """``values`` (n,) with each row of ``mask`` replaced by the row before it (``last``: the
        previous block's last value, used by a repeat at the block's first row; None for the first
        block). Returns ``(new values, this block's last value)``."""
        src = np.maximum.accumulate(np.where(mask, -1, np.arange(mask.size)))
        first = last if last is not None else values[0] if values.size else 0.0  # no rows: none repeated (an IndexError)
        out = np.where(src >= 0, values[np.maximum(src, 0)], first)
        return out, (out[-1] if out.size else last)


class TemperatureProfile:
    """Sensor temperature (deg C): the true T(t) and the recorded column.

    Exponential kind (default): T(t) = T_end + (T_start - T_end) exp(-t / τ) + A sin(2π t / P)
    (self-heating after power-on towards T_end with time constant τ; an optional room cycle of
    amplitude A and period P). Table kind: linear interpolation of given (t_s, temp_c) points,
    held constant outside them. Recorded: T_rec = round((T + n_c w) / r) r with read noise
    std n_c and resolution r (MPU6050: 1/340 deg C, datasheet register map 4.18).

    ``spec``: the validated ``temperature`` object of the model
    (:func:`~gyrofilter.sim.model.validate_model`: ``start_c``, ``end_c`` in deg C, ``tau_s``,
    ``cycle_period_s`` in s, ``cycle_amplitude_c``, ``noise_c``, ``resolution_c`` in deg C; or
    ``t_s`` (s) and ``temp_c`` (deg C) arrays); ``rng``: generator of the read noise.
    """

    def __init__(self, spec, rng):
        self.spec = spec
        self.rng = rng

    def true_c(self, t_s):
        """True temperature T(t) (deg C) at times ``t_s`` (s, array); deterministic."""
        s = self.spec
        if "t_s" in s:
            return np.interp(t_s, s["t_s"], s["temp_c"])
        temp = s["end_c"] + (s["start_c"] - s["end_c"]) * np.exp(-t_s / s["tau_s"])
        if s["cycle_amplitude_c"]:
            temp = temp + s["cycle_amplitude_c"] * np.sin(2.0 * math.pi * t_s / s["cycle_period_s"])
        return temp

    def start_c(self):
        """T(0) (deg C), the default reference of :class:`TemperatureCoefficient`."""
        return float(self.true_c(np.zeros(1))[0])

    def recorded_c(self, true_c):
        """The ``temp`` column (deg C) for true temperatures ``true_c`` (deg C, array): read noise
        added and rounded to the resolution; draws ``len(true_c)`` numbers when ``noise_c`` > 0."""
        s = self.spec
        rec = true_c + s["noise_c"] * self.rng.standard_normal(len(true_c)) if s["noise_c"] else true_c.copy()
        if s["resolution_c"]:
            rec = np.round(rec / s["resolution_c"]) * s["resolution_c"]
        return rec


def ar1_allan_variance(phi, variance, m):
    """Exact overlapping Allan variance of a stationary discrete AR(1) series at cluster size m.

    For autocovariance R(k) = v φ^|k| and cluster sums S of m samples:
    Var(S) = v [m + 2 φ (m (1-φ) - (1-φ^m)) / (1-φ)²], Cov(S₁, S₂) = v φ (1-φ^m)² / (1-φ)²,
    σ²(m) = (Var(S) - Cov(S₁, S₂)) / m² (NIST SP 1065 eq. 11 with ȳ = S/m).
    Used by the tests as an oracle for the Gauss-Markov and flicker-bank terms.

    ``phi``: φ, the lag-1 coefficient (|φ| < 1); ``variance``: v, the series' variance
    ((deg/s)²); ``m``: cluster size(s) in samples (τ = m / f_s). Returns σ²(m) in (deg/s)², the
    shape of ``m``.
    """
    m = np.asarray(m, dtype=float)
    phi = float(phi)
    if phi == 0.0:
        return variance / m
    one = 1.0 - phi
    pm = phi**m
    var_s = m + 2.0 * phi * (m * one - (1.0 - pm)) / one**2
    cov = phi * (1.0 - pm) ** 2 / one**2
    return variance * (var_s - cov) / m**2
