"""Non-sliding block averaging with gross-error rejection (paper 001, section 2.2).

For each block of L raw samples x_1..x_L (L = 5 in the paper):

    m = (1/L) * sum_i x_i                                                           (001, eq. 2)
    x_i is a gross error when |x_i - m| > q
    output = mean of the samples that are not gross errors

The output rate is the input rate / L. Two cases the paper leaves open, and our rule:

* every sample of a block is rejected (possible only when the block spans a change larger than
  about 2q, i.e. motion rather than isolated spikes, which the paper says never occur twice
  within 10 samples): the block is kept whole and the plain mean m is the output;
  such blocks are counted as ``fallback`` and their samples are not counted as rejected;
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
    mean = total / len(values)
    kept_sum = 0.0
    kept = 0
    for v in values:
        if abs(v - mean) <= q:
            kept_sum += v
            kept += 1
    if kept == 0:
        return mean, 0, True
    return kept_sum / kept, len(values) - kept, False


def average_blocks(blocks, q):
    """Vectorised :func:`average_block` over the first axis of ``blocks`` (M, L[, ...]).

    Returns (outputs (M[, ...]), rejected counts (M[, ...]), fallback mask (M[, ...])).
    """
    blocks = np.asarray(blocks, dtype=float)
    length = blocks.shape[1]
    total = np.zeros(blocks.shape[:1] + blocks.shape[2:])
    for i in range(length):
        total += blocks[:, i]
    mean = total / length
    kept_sum = np.zeros_like(mean)
    kept = np.zeros(mean.shape, dtype=np.int64)
    for i in range(length):
        ok = np.abs(blocks[:, i] - mean) <= q
        kept_sum += np.where(ok, blocks[:, i], 0.0)
        kept += ok
    fallback = kept == 0
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(fallback, mean, kept_sum / np.maximum(kept, 1))
    rejected = np.where(fallback, 0, length - kept)
    return out, rejected, fallback
