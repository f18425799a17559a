"""Reference angular rate from quaternions (gyrofilter.evaluation.reference)."""
import math

import numpy as np
import pytest

from gyrofilter.errors import SettingsError
from gyrofilter.recording import Recording
from gyrofilter.evaluation.reference import (
    block_mean_masked,
    body_rate_from_quaternions,
    estimate_time_offset_s,
    quat_conjugate,
    quat_from_rotvec,
    quat_multiply,
    reference_from_recording,
    rotvec_from_quat,
)

FS = 2000.0 / 7.0


def constant_rotation(omega_rads, n, fs=FS, q0=None):
    """q_k = q0 (x) exp(omega t_k / 2): a body turning at the constant body-frame rate omega."""
    t = np.arange(n) / fs
    q0 = np.array([1.0, 0, 0, 0]) if q0 is None else q0
    steps = quat_from_rotvec(np.outer(t, omega_rads))
    return quat_multiply(np.broadcast_to(q0, steps.shape), steps)


def test_quaternion_helpers_against_hand_values():
    # 90 deg about z: w = cos 45, z = sin 45; rotating x gives y
    q = quat_from_rotvec([0, 0, math.pi / 2])
    assert np.allclose(q, [math.sqrt(0.5), 0, 0, math.sqrt(0.5)])
    v = np.array([0, 1.0, 0, 0])
    rotated = quat_multiply(quat_multiply(q, v), quat_conjugate(q))
    assert np.allclose(rotated, [0, 0, 1, 0])
    assert np.allclose(rotvec_from_quat(q), [0, 0, math.pi / 2])
    # sign of q does not matter; tiny angles use the series
    assert np.allclose(rotvec_from_quat(-q), [0, 0, math.pi / 2])
    assert np.allclose(rotvec_from_quat(quat_from_rotvec([1e-10, -2e-10, 3e-10])), [1e-10, -2e-10, 3e-10], atol=1e-22)


@pytest.mark.parametrize("half_span", [1, 2, 5])
def test_constant_rotation_gives_its_rate(half_span):
    omega = np.array([0.7, -1.3, 2.9])  # rad/s, body frame
    rng = np.random.default_rng(3)
    q0 = rng.normal(size=4)
    q0 /= np.linalg.norm(q0)
    q = constant_rotation(omega, 400, q0=q0)
    q[::3] *= -1  # sign flips of the optical quaternions must not matter
    rate = body_rate_from_quaternions(q, FS, half_span=half_span)
    assert np.isnan(rate[:half_span]).all() and np.isnan(rate[-half_span:]).all()
    assert np.allclose(rate[half_span:-half_span], omega, atol=1e-9)


def test_rate_is_in_the_body_frame_not_the_world_frame():
    # start tilted 90 deg about x; turning about body z then shows up as body z only
    q0 = quat_from_rotvec([math.pi / 2, 0, 0])
    q = constant_rotation(np.array([0, 0, 1.0]), 50, q0=q0)
    rate = body_rate_from_quaternions(q, FS)
    assert np.allclose(rate[1:-1], [0, 0, 1.0], atol=1e-9)


def test_fast_rotation_beyond_pi_per_span_is_not_folded():
    # 25 rad/s at 285.7 Hz: 0.175 rad per span of 2 samples, well below pi: exact
    q = constant_rotation(np.array([25.0, 0, 0]), 100)
    assert np.allclose(body_rate_from_quaternions(q, FS)[1:-1], [25.0, 0, 0], atol=1e-8)


def test_nan_occlusion_is_not_bridged():
    omega = np.array([0.1, 0.2, -0.3])
    q = constant_rotation(omega, 100)
    q[40:43] = np.nan  # occlusion of 3 samples
    for h in (1, 2):
        rate = body_rate_from_quaternions(q, FS, half_span=h)
        bad = np.isnan(rate).any(axis=1)
        expected_bad = np.zeros(100, bool)
        expected_bad[:h] = expected_bad[-h:] = True
        expected_bad[40 - h : 43 + h] = True
        assert np.array_equal(bad, expected_bad)
        assert np.allclose(rate[~bad], omega, atol=1e-9)


def test_block_mean_masked_propagates_nan_and_counts_blocks():
    v = np.arange(12, dtype=float)
    v[7] = np.nan
    out = block_mean_masked(v, 3, start=1)
    assert out.shape == (3,)
    assert out[0] == 2.0 and out[1] == 5.0 and np.isnan(out[2])  # blocks 1-3, 4-6, 7-9
    with pytest.raises(SettingsError):
        block_mean_masked(v, 3, start=1, n_blocks=4)


def test_time_offset_found_by_cross_correlation():
    rng = np.random.default_rng(7)
    n = 4000
    # smooth random motion (low-passed noise), 3 axes
    white = rng.normal(size=(n + 200, 3))
    kernel = np.hanning(41)
    smooth = np.column_stack([np.convolve(white[:, a], kernel, "same") for a in range(3)])[100:-100]
    gyro = smooth + rng.normal(scale=0.05, size=smooth.shape)
    ref = np.full_like(smooth, np.nan)
    ref[3:] = smooth[:-3]  # the reference lags by 3 samples
    ref[1000:1100] = np.nan  # an occlusion
    offset_s, peak = estimate_time_offset_s(gyro, ref, FS, max_lag_s=0.05)
    assert offset_s * FS == pytest.approx(3.0, abs=0.1)
    assert peak > 0.9


def test_forward_difference_shows_half_sample_shift_central_does_not():
    # a sinusoidal rotation about z: the forward difference describes t + dt/2
    n = 3000
    t = np.arange(n) / FS
    angle = 0.5 * np.sin(2 * math.pi * 2.0 * t)
    q = quat_from_rotvec(np.column_stack([0 * t, 0 * t, angle]))
    true_rate = np.column_stack([0 * t, 0 * t, 0.5 * 2 * math.pi * 2.0 * np.cos(2 * math.pi * 2.0 * t)])
    central = body_rate_from_quaternions(q, FS, 1)
    off_c, _ = estimate_time_offset_s(true_rate[:, 2], central[:, 2], FS, 0.02)
    forward = np.full_like(central, np.nan)
    forward[:-1] = rotvec_from_quat(quat_multiply(quat_conjugate(q[:-1]), q[1:])) * FS
    off_f, _ = estimate_time_offset_s(true_rate[:, 2], forward[:, 2], FS, 0.02)
    assert abs(off_c) * FS < 0.02
    assert off_f * FS == pytest.approx(-0.5, abs=0.05)


def test_reference_from_recording_masks_invalid_rows():
    n = 6
    rec = Recording.from_dps(np.zeros((n, 3)), 100.0, extra={
        "ref_x": np.full(n, 0.01), "ref_y": np.zeros(n), "ref_z": np.zeros(n),
        "ref_valid": np.array([1, 1, 0, 1, 1, 1]),
    })
    ref = reference_from_recording(rec)  # gyro_unit dps here
    assert np.isnan(ref[2]).all()
    assert np.allclose(ref[[0, 1, 3, 4, 5], 0], 0.01)
    rec.header["gyro_unit"] = "rad/s"
    assert reference_from_recording(rec)[0, 0] == pytest.approx(0.01 * 180 / math.pi)


def test_bad_arguments_raise():
    with pytest.raises(SettingsError):
        body_rate_from_quaternions(np.zeros((5, 3)), FS)
    with pytest.raises(SettingsError):
        body_rate_from_quaternions(np.zeros((5, 4)), FS, half_span=0)
