"""The gross-error threshold that follows a vibration (ours, not paper 001's).

Paper 001 rejects a sample x_i of a block as a gross error when |x_i - m| > q, q = 1 deg/s
(:mod:`gyrofilter.filter.averaging`). A vibration that swings the rate by more than q within a
block (a motor, a fan, a loose mount) holds no gross error, but the rule takes its extremes: of
a still sensor on a 20-Hz, 3-deg/s vibration sampled at 100 Hz it kept a fifth of the samples,
and the means of what was left were biased (-0.74 deg/s through the default filter). With
``outlier_range_k`` = k_r > 0 each block k gets its own threshold, per axis,

    q_k = max(q, k_r * r_(k,low)),    r_j = max_i x_(j,i) - min_i x_(j,i)

r_j the range of block j's samples and r_(k,low) the lower quartile of the ranges of the last
N = ``outlier_range_blocks`` blocks, this one included: the (floor((N - 1) / 4) + 1)-th
smallest (the 4th of 15). Before the first block the last N - 1 blocks of the start-up
calibration's window stand in, repeated where it has fewer (:meth:`RangeThreshold.seed`: a
vibration from power-up is followed from the first block; without them, 12 blocks were judged
with q and their bias held at rest for seconds, a new user's trial), or zeros after a loaded
calibration.
k_r = 0 is paper 001's fixed q (``preset="paper"``).

Why it holds (measured: ``python tools/vibration.py``, docs/evaluate.md):

* a vibration raises every block's range, so its lower quartile too: a swing whose blocks'
  ranges vary by less than k_r = 2 (the presets') gets q_k above every block's range, and no
  sample lies farther from its block's mean than that range: none is cut;
* spikes raise only the ranges of the blocks that hold one: while fewer than 3/4 of the last
  N blocks do, the quartile is a clean block's, and the spikes are judged as by paper 001.
  (The median was tried first: spikes on 4 % of the samples, a block in five, put 8 of 15
  blocks over it often enough to let spikes through and knock the filter out of rest.)
* white noise of std sigma gives the 4th smallest of 15 ranges of 5 samples 1.68 sigma on
  average and 2.57 sigma in 1 block in 1000: with k_r = 2, q stays 1 deg/s for sensors
  quieter than 0.19 deg/s (the MPU6050 recordings at hand: 0.075-0.14).

:meth:`RangeThreshold.one` (a block at a time) and :meth:`RangeThreshold.many` (an array of
blocks) return the same numbers: a range and an order statistic are exact.
"""
import collections

import numpy as np

#: blocks :meth:`RangeThreshold.many` works through at a time (its temporaries: about 100 bytes a block, and N
#: doubles a block and axis that sorts: under 6 MB for N = 15)
_CHUNK_BLOCKS = 16_384


def onset_samples(settings):
    """The samples per axis a vibration that begins after the calibration can have rejected before q follows it:
    (N - rank) blocks of L with k_r > 0 (60 for the presets), 0 with paper 001's fixed q. ``settings``: a
    :class:`gyrofilter.filter.settings.FilterSettings`."""
    if not settings.outlier_range_k:
        return 0
    n = settings.outlier_range_blocks
    return (n - (n - 1) // 4) * settings.block_len


class RangeThreshold:
    """The gross-error threshold of each block of a three-axis stream (module docstring): ``q``
    (deg/s), ``k`` (k_r, 0: q itself), ``n_blocks`` (N).

    Most blocks (every block at rest) get q itself, and are told apart without sorting: k_r r_low > q
    exactly when at least N - rank of the N ranges r have k_r r > q (k_r r is monotone in r), so a
    count of those (``_over``) decides, and only the other blocks sort their ranges."""

    def __init__(self, q, k, n_blocks):
        self.q = float(q)
        self.k = float(k)
        # the latest N - 1 ranges per axis, oldest first (zeros: not yet seen), and how many of them have k r > q
        self._seen = [collections.deque([0.0] * (n_blocks - 1), maxlen=n_blocks - 1) for _ in range(3)]
        self._over = [0, 0, 0]
        self._rank = (n_blocks - 1) // 4  # the lower quartile, counted from 0
        self._needed = n_blocks - self._rank  # ranges with k r > q that put the quartile's k r over q

    def seed(self, window_dps, block_len):
        """Take the ranges of the last N - 1 blocks of ``block_len`` samples of ``window_dps`` ((n, 3), deg/s:
        the calibration window, gross errors left out) as the blocks seen before the first; where it has fewer
        blocks, they stand in again, oldest first (zeros left for N = 60 and more of a 2-s window: a vibration from
        power-up was cut for 28 s at N = 999, attack pass 39)."""
        n_seen = self._seen[0].maxlen
        count = min(n_seen, len(window_dps) // block_len)
        if not count:
            return
        blocks = np.asarray(window_dps[len(window_dps) - count * block_len:], dtype=float).reshape(count, block_len, 3)
        ranges = _ranges(blocks)[np.arange(-n_seen, 0) % count]
        for a, seen in enumerate(self._seen):
            seen.extend(ranges[:, a].tolist())
            self._over[a] = sum(self.k * r > self.q for r in seen)

    def one(self, columns):
        """``columns``: one block's L samples per axis (3 sequences, deg/s) -> its threshold per axis (3 floats)."""
        q, k = self.q, self.k
        if not k:
            return (q, q, q)
        out = []
        for a, values in enumerate(columns):
            seen = self._seen[a]
            r = max(values) - min(values)
            over = self._over[a] + (k * r > q)
            out.append(max(q, k * sorted((*seen, r))[self._rank]) if over >= self._needed else q)
            if seen.maxlen:  # N = 1 keeps no range: its count stays 0
                self._over[a] = over - (k * seen[0] > q)
                seen.append(r)
        return tuple(out)

    def many(self, blocks):
        """``blocks``: (M, L, 3) samples in deg/s -> the threshold of each block, (M, 3), or q alone
        when k = 0. Worked through :data:`_CHUNK_BLOCKS` blocks at a time (the temporaries of an hour at
        1 kHz in one call were 70 MB)."""
        if not self.k:
            return self.q
        out = np.empty((len(blocks), 3))
        for start in range(0, len(blocks), _CHUNK_BLOCKS):
            out[start : start + _CHUNK_BLOCKS] = self._many(blocks[start : start + _CHUNK_BLOCKS])
        return out

    def _many(self, blocks):
        """:meth:`many` of at most a chunk of blocks."""
        ranges = _ranges(blocks)
        joined = np.concatenate((np.array(self._seen).T.reshape(-1, 3), ranges))  # (N - 1 + M, 3)
        n = len(joined) - len(ranges) + 1
        over = np.cumsum(np.concatenate((np.zeros((1, 3), dtype=np.int64), self.k * joined > self.q)), axis=0)
        sort = over[n:] - over[:-n] >= self._needed  # (M, 3): the blocks whose quartile puts k r over q
        out = np.full(ranges.shape, self.q)
        rows, axes = np.nonzero(sort)
        windows = joined[rows[:, None] + np.arange(n), axes[:, None]]  # (K, N): each such block's last N ranges
        out[rows, axes] = np.maximum(self.q, self.k * np.partition(windows, self._rank, axis=1)[:, self._rank])
        for a, seen in enumerate(self._seen):
            seen.extend(joined[len(joined) - (n - 1):, a].tolist())
            self._over[a] = int(over[-1, a] - over[len(over) - n, a])
        return out


def _ranges(blocks):
    """max - min of each block's samples, (M, L, 3) -> (M, 3); sample by sample, as numpy reduces a short middle
    axis 10x slower."""
    high, low = blocks[:, 0].copy(), blocks[:, 0].copy()
    for i in range(1, blocks.shape[1]):
        np.maximum(high, blocks[:, i], out=high)
        np.minimum(low, blocks[:, i], out=low)
    return high - low
