"""Non-sliding block averaging with gross-error rejection (paper 001, section 2.2).

For each block of L raw samples x_1..x_L (L = 5 in the paper):

    m = (1/L) * sum_i x_i                                                           (001, eq. 2)
    x_i is a gross error when |x_i - m| > q
    output = mean of the samples that are not gross errors

The output rate is the input rate / L. Two cases the paper leaves open, and our rule:

* every sample of a block is rejected. This happens when one spike is larger than about L*q:
  it drags the mean so far that the normal samples fail the test too (with q = 1 deg/s, any
  spike over 5 deg/s), or when the block spans fast motion. Then the block is re-centred on
  its median (which a single spike cannot move) and the output is the mean of the samples
  within q of the median, or the median itself if none is (only possible for even L);
  such blocks are counted as ``fallback`` and the samples farther than q from the median as
  rejected. For a linear ramp the median equals the mean, so motion is not distorted;
* a block cut short at the end of the data (fewer than L samples) produces no output; the
  streaming filter holds those samples until the block is full, and the batch filter reports
  how many trailing samples were left over (``GyroFilter.pending_samples``).

The arithmetic order is fixed (left-to-right sums, then one division) so that the streaming
path (:func:`average_block`) and the vectorised path (:func:`average_blocks`) return the same
floating-point numbers.
"""
import numpy as np


def average_block(values, q):
    """Average one block (a sequence of floats). Returns (output, number rejected, fallback)."""
    total = 0.0
    for v in values:
        total += v
    center = total / len(values)
    fallback = False
    for _ in range(2):
        kept_sum = 0.0
        kept = 0
        for v in values:
            if abs(v - center) <= q:
                kept_sum += v
                kept += 1
        if kept or fallback:
            break
        fallback = True
        center = _median(values)
    if kept == 0:
        return center, len(values), True
    return kept_sum / kept, len(values) - kept, fallback


def _median(values):
    ordered = sorted(values)
    mid = len(ordered) // 2
    return ordered[mid] if len(ordered) % 2 else (ordered[mid - 1] + ordered[mid]) / 2


def average_blocks(blocks, q):
    """Vectorised :func:`average_block` over the first axis of ``blocks`` (M, L[, ...]).

    Returns (outputs (M[, ...]), rejected counts (M[, ...]), fallback mask (M[, ...])).
    """
    blocks = np.asarray(blocks, dtype=float)
    length = blocks.shape[1]
    total = np.zeros(blocks.shape[:1] + blocks.shape[2:])
    for i in range(length):
        total += blocks[:, i]
    center = total / length
    kept_sum, kept = _kept(blocks, center, q)
    fallback = kept == 0
    if fallback.any():
        center = np.where(fallback, np.median(blocks, axis=1), center)
        kept_sum2, kept2 = _kept(blocks, center, q)
        kept_sum = np.where(fallback, kept_sum2, kept_sum)
        kept = np.where(fallback, kept2, kept)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(kept == 0, center, kept_sum / np.maximum(kept, 1))
    return out, length - kept, fallback


def _kept(blocks, center, q):
    """Sum (left to right) and count of the samples within q of ``center``."""
    kept_sum = np.zeros_like(center)
    kept = np.zeros(center.shape, dtype=np.int64)
    for i in range(blocks.shape[1]):
        ok = np.abs(blocks[:, i] - center) <= q
        kept_sum += np.where(ok, blocks[:, i], 0.0)
        kept += ok
    return kept_sum, kept
