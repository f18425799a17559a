"""Synthetic motion profiles (gyrofilter.sim.profiles)."""
import math

import numpy as np
import pytest

from gyrofilter.errors import SettingsError
from gyrofilter.sim.profiles import PROFILES, get_profile, profile_samples_dps


def test_paper001_profile_values_by_hand():
    p = get_profile("paper001")
    t = np.array([0, 5, 9.999, 10, 15, 20, 25, 30, 30 + 1.25, 30 + 3.75, 59.999, 60, 65, 70, 75, 80, 85, 90])
    expected = [0, 0, 0, 0, 10, 20, 20, 20, 30, 10, 20, 20, 20, 20, 10, 0, 0, 0]
    assert np.allclose(p.rate_dps(t), expected, atol=0.02)
    assert p.duration_s == 90.0
    # the sine part: 20 + 10 sin(2 pi 0.2 (t - 30))
    ts = np.linspace(30, 59.9, 50)
    assert np.allclose(p.rate_dps(ts), 20 + 10 * np.sin(2 * math.pi * 0.2 * (ts - 30)))


def test_profiles_are_continuous_where_claimed_and_rest_at_start():
    for name, p in PROFILES.items():
        t, w = profile_samples_dps(p, 100.0)
        assert len(t) == 9000
        assert np.all(w[t < 10] == 0), name  # calibration needs rest
        assert np.all(p.rate_dps(np.array([-1.0, p.duration_s + 1])) == 0)
    # paper001 has no jumps larger than a ramp step
    t, w = profile_samples_dps("paper001", 100.0)
    assert np.max(np.abs(np.diff(w))) < 0.13  # sine slope 10 * 2 pi 0.2 = 12.6 deg/s^2


def test_steps_profile_levels():
    p = get_profile("steps")
    assert p.rate_dps(np.array([9.9, 10.0, 25.0, 35.0, 50.0, 65.0, 75.0, 85.0])).tolist() == [0, 20, 0, -30, 10, 0, 50, 0]


def test_sine_and_chirp_frequencies():
    t, w = profile_samples_dps("sine_1hz", 1000.0)
    seg = w[(t >= 10) & (t < 80)]
    spectrum = np.abs(np.fft.rfft(seg))
    freq = np.fft.rfftfreq(len(seg), 1e-3)
    assert freq[np.argmax(spectrum)] == pytest.approx(1.0, abs=0.02)
    assert seg.max() == pytest.approx(30.0, abs=1e-3)
    # chirp: instantaneous frequency 0.1 Hz at 10 s, 2 Hz at 80 s (zero-crossing spacing)
    t, w = profile_samples_dps("chirp", 1000.0)
    zc = t[1:][np.diff(np.sign(w)) != 0]
    zc = zc[(zc > 10.001) & (zc < 80)]
    assert 1 / (2 * (zc[-1] - zc[-2])) == pytest.approx(2.0, rel=0.05)


def test_unknown_profile_is_a_settings_error():
    with pytest.raises(SettingsError):
        get_profile("nope")
