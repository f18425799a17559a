import numpy as np
import pytest

from gyrofilter.filter.averaging import average_block, average_blocks

PAPER_RAW = [67, 49, 55, -233, 21, 17, 23, 63]  # paper 001 section 1.2, raw LSB


def test_paper_example_rejects_the_gross_error():
    # block of 5 from the paper's sequence: mean -8.2; |-233 - -8.2| = 224.8 > q, the others < 76
    out, rejected, fallback = average_block(PAPER_RAW[:5], q=100)
    assert rejected == 1 and not fallback
    assert out == pytest.approx((67 + 49 + 55 + 21) / 4)
    # a threshold below the normal spread rejects normal samples too: q matters
    out_tight, rejected_tight, _ = average_block(PAPER_RAW[:5], q=60)
    assert rejected_tight == 3 and out_tight == pytest.approx((49 + 21) / 2)


def test_a_spike_larger_than_L_times_q_falls_back_to_the_median():
    # the spike drags the mean by 10: every sample fails |x - mean| <= 1; the median does not move
    out, rejected, fallback = average_block([0.1, -0.1, 50.0, 0.2, 0.0], q=1.0)
    assert fallback and rejected == 1 and out == pytest.approx(0.05)


def test_fallback_averages_the_samples_around_the_median():
    fast = [0.0, 3.0, 8.0, 9.0, 12.0]  # mean 6.4: every sample is more than q = 1 away
    out, rejected, fallback = average_block(fast, q=1.0)
    assert fallback and rejected == 3 and out == pytest.approx(8.5)
    # a linear ramp keeps its middle sample at the mean: no fallback, no distortion
    assert average_block([0.0, 3.0, 6.0, 9.0, 12.0], q=1.0) == (6.0, 4, False)


def test_vectorised_equals_scalar_bit_for_bit():
    rng = np.random.default_rng(3)
    blocks = rng.normal(size=(2000, 5, 3)) * 0.3
    spikes = rng.random(blocks.shape) < 0.05
    blocks[spikes] += rng.choice([-3, 3], spikes.sum())
    blocks[:50] = np.array([0, 0, 10, 10, 10.0])[None, :, None]  # fallback blocks
    blocks[50:60, 2, :] += 40.0  # big spikes: fallback to the median
    out, rejected, fallback = average_blocks(blocks, 1.0)
    for k in range(len(blocks)):
        for a in range(3):
            o, r, f = average_block(tuple(blocks[k, :, a].tolist()), 1.0)
            assert o == out[k, a] and r == rejected[k, a] and f == fallback[k, a]
    assert fallback[:50].all() and rejected.sum() > 100
