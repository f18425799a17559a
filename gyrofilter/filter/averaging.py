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

Opt-in rule ``"median_slope"`` (ours, not the paper's; measured in docs/evaluate.md). In fast
motion the rate changes by more than q within one block, so paper 001's test rejects real
samples and biases the block mean. This rule compares each sample with a robust straight line
through the block instead of with its mean::

    s = median_{i<j} (x_j - x_i) / (j - i)         (Theil-Sen slope)
    c = median(x_i - s o_i),  m_i = c + s o_i,  o_i = i - (L-1)/2
    r_i = |x_i - m_i|,  limit = max(q, 4 * 1.4826 * median(r))
    output = (1/L) * sum_i (x_i if r_i <= limit else m_i)

``outlier_rule="by_model"`` (the adaptive Kalman filter's rule) uses paper 001's rule while an
axis is in the filter's constant-rate model and, in its least-squares model, the block mean when
the paper's rule would keep every sample and ``median_slope`` when it would cut one
(:func:`average_block_line_if_cut`): the robust line is needed only where the rate moves more
than q within the block, and costs nothing elsewhere.

A single spike moves neither median (c is taken after removing the slope: on a ramp the plain
median of x shifts by a whole step when a spike reorders the block), so the spike is replaced
by the line's value; the threshold
scales with the block's own scatter (1.4826 * MAD estimates a Gaussian sigma), so a steady turn
is never cut. Samples replaced count as rejected; there is no fallback case.

The arithmetic order is fixed (left-to-right sums, then one division) so that the streaming
path (:func:`average_block`) and the vectorised path (:func:`average_blocks`) return the same
floating-point numbers; the same holds for the ``median_slope`` pair.
"""
import numpy as np

from ..units import MAD_TO_SIGMA

MAD_LIMIT = 4 * MAD_TO_SIGMA  # median_slope: threshold in robust-sigma units of the residuals
#: paper 001's gross-error threshold q (deg/s): the default of the filter's setting outlier_q_dps
#: (gyrofilter.filter.settings says why) and of the start-up calibration's gross errors
PAPER_Q_DPS = 1.0


def average_block(values, q):
    """Average one block ``values`` (a sequence of floats, deg/s) with gross-error threshold ``q``
    (deg/s; module docstring). Returns (output, number rejected, fallback)."""
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
    """Vectorised :func:`average_block` over the first axis of ``blocks`` (M, L[, ...]), deg/s,
    threshold ``q`` (deg/s; one, or one per block and axis, (M[, ...]): the vectorised averagers
    all take either).

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


def average_block_median_slope(values, q):
    """Average one block ``values`` (deg/s) with the ``median_slope`` rule, threshold ``q`` (deg/s).
    Returns (output, number replaced, False)."""
    n = len(values)
    slope = _median([(values[j] - values[i]) / (j - i) for i in range(n) for j in range(i + 1, n)]) if n > 1 else 0.0
    offsets = [slope * (i - (n - 1) / 2) for i in range(n)]
    center = _median([v - o for v, o in zip(values, offsets)])
    line = [center + o for o in offsets]
    resid = [abs(v - m) for v, m in zip(values, line)]
    limit = max(q, MAD_LIMIT * _median(resid))
    total = 0.0
    replaced = 0
    for v, m, r in zip(values, line, resid):
        if r <= limit:
            total += v
        else:
            total += m
            replaced += 1
    return total / n, replaced, False


def average_blocks_median_slope(blocks, q):
    """Vectorised :func:`average_block_median_slope` over the first axis of ``blocks`` (M, L[, ...]),
    threshold ``q`` (deg/s)."""
    blocks = np.asarray(blocks, dtype=float)
    n = blocks.shape[1]
    pairs = [(blocks[:, j] - blocks[:, i]) / (j - i) for i in range(n) for j in range(i + 1, n)]
    slope = np.median(np.stack(pairs, axis=1), axis=1) if n > 1 else np.zeros(blocks.shape[:1] + blocks.shape[2:])
    offsets = [slope * (i - (n - 1) / 2) for i in range(n)]
    center = np.median(np.stack([blocks[:, i] - offsets[i] for i in range(n)], axis=1), axis=1)
    total = np.zeros_like(center)
    replaced = np.zeros(center.shape, dtype=np.int64)
    lines = [center + offsets[i] for i in range(n)]
    resid = np.stack([np.abs(blocks[:, i] - lines[i]) for i in range(n)], axis=1)
    limit = np.maximum(q, MAD_LIMIT * np.median(resid, axis=1))
    for i in range(n):
        ok = resid[:, i] <= limit
        total += np.where(ok, blocks[:, i], lines[i])
        replaced += ~ok
    return total / n, replaced, np.zeros(center.shape, dtype=bool)


def average_block_line_if_cut(values, q, paper=None):
    """The motion rule of ``outlier_rule="by_model"``: the block mean when paper 001's rule keeps
    every sample, else :func:`average_block_median_slope`, threshold ``q`` (deg/s). ``paper``: the result of
    :func:`average_block` on the same values, if already computed. Returns (output, number
    rejected or replaced, False)."""
    mean, rejected, _ = average_block(values, q) if paper is None else paper
    if not rejected:
        return mean, 0, False
    return average_block_median_slope(values, q)


def average_blocks_line_if_cut(blocks, q, paper=None):
    """Vectorised :func:`average_block_line_if_cut` (threshold ``q``, deg/s); ``paper``: the result of
    :func:`average_blocks` on the same blocks, if already computed. The robust line is computed
    only for the blocks the paper's rule cuts."""
    blocks = np.asarray(blocks, dtype=float)
    out, rejected, _ = average_blocks(blocks, q) if paper is None else paper
    cut = rejected > 0
    out, rejected = out.copy(), rejected.copy()
    rows = np.flatnonzero(cut.reshape(len(cut), -1).any(axis=1))
    if rows.size:
        line, replaced, _ = average_blocks_median_slope(blocks[rows], q if np.ndim(q) == 0 else q[rows])
        out[rows] = np.where(cut[rows], line, out[rows])
        rejected[rows] = np.where(cut[rows], replaced, rejected[rows])
    return out, rejected, np.zeros(out.shape, dtype=bool)


AVERAGERS = {
    "paper": (average_block, average_blocks),
    "median_slope": (average_block_median_slope, average_blocks_median_slope),
}
