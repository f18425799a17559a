"""Offline forward-backward smoothing of the adaptive Kalman filter, for recordings.

The real-time filter estimates the rate of block k from blocks 0..k only. With the whole
recording at hand, the blocks after k help too: the smoother runs the same filter
(:class:`gyrofilter.filter.adaptive_kalman.AdaptiveKalman`, the settings of ``preset="adaptive_kalman"``) a
second time over the reversed block means, and combines, per block and axis, the forward
posterior with the backward *prior* (the backward filter's prediction of block k from blocks
k+1..M-1, which has not seen y_k, so no measurement is counted twice):

    x^s_k = (x^f_k / P^f_k + x^b-_k / P^b-_k) / (1 / P^f_k + 1 / P^b-_k),
    P^s_k = (1 / P^f_k + 1 / P^b-_k)^-1

This is the two-filter form of the fixed-interval smoother (Fraser & Potter 1969, "The optimum
linear smoother as a combination of two optimum linear filters", IEEE Trans. Autom. Control 14),
which equals the Rauch-Tung-Striebel smoother (Rauch, Tung & Striebel 1965) when the model is
linear and Gaussian. We use it instead of RTS's backward recursion because the filter has no
state-transition matrix to run that recursion through: its prior is a least-squares
extrapolation of a FIFO of its own posteriors (paper 001, eqs. 8-10), its model switches between
constant-rate and LS per axis, and its noise statistics adapt; the two-filter form needs only the
filter itself, run in both directions, with the same R (sigma_b^2 of the forward calibration).

What it does in each model: at rest (constant-rate model) the forward posterior is the mean of
the blocks since the rest began and the backward prior the mean of the blocks until it ends, so
x^s_k is the mean of the whole rest phase (within the memory of ``hold_max_blocks`` on each
side; where a filter entered rest from motion, its rest mean starts from the latest half of its
window, :func:`gyrofilter.filter.hold.recent_mean`: the older half, 10 blocks, is left out); in
motion the forward filter's lag and the backward filter's lead cancel to first order.

The backward filter starts in the LS model with P = P0 (nothing is known of the motion at the
end of a recording), as the forward one does after a loaded calibration. Memory: the block means
and the forward results of the whole recording, 12 floats per block (about 69 MB per hour at
1 kHz, 7 MB at 100 Hz), and as much again for the smoothed rows; the backward pass runs in
chunks of :data:`BACKWARD_CHUNK` blocks.
"""
from __future__ import annotations

import numpy as np

from . import adaptive_kalman
from ..errors import SettingsError
from .pipeline import GyroFilter
from .presets import DEFAULT_PRESET, PRESETS

#: the presets the smoother takes: those with the adaptive Kalman stage and no hold stage
SMOOTHABLE_PRESETS = tuple(name for name, chosen in PRESETS.items()
                           if chosen.get("kalman_noise") == "adaptive" and chosen.get("tracker", "kalman") == "kalman"
                           and not chosen.get("hold", False))

#: blocks per call of the backward filter (its memory: 15 floats per block of the chunk)
BACKWARD_CHUNK = 65536


#: blocks a :class:`BlockLog` gathers before it keeps them as one chunk
LOG_CHUNK = 1024


class BlockLog:
    """What a forward filter handed its adaptive Kalman stage and got back: the block means y and
    y_motion (M, 3; see :func:`gyrofilter.filter.adaptive_kalman.run_blocks_adaptive`), the posteriors x and
    their variances P (M, 3), joined by :meth:`arrays`. A kernel call's blocks are gathered in a
    buffer of :data:`LOG_CHUNK` blocks and kept a buffer at a time (a call of that many or more
    as it is): 12 floats a block, also for a filter fed by ``update()``, one call a block (four
    arrays a call cost 640 bytes a block)."""

    def __init__(self):
        self._chunks = ([], [], [], [])
        self._buffer = np.empty((len(self._chunks), LOG_CHUNK, 3))
        self._filled = 0

    def append(self, y, y_motion, x, trace):
        """One call of the kernel: its inputs, outputs and trace (M, 3, 3)."""
        values = (y, y_motion, x, trace[:, adaptive_kalman.POST_VAR])
        n = len(y)
        if self._filled + n > LOG_CHUNK:
            self._keep_buffer()
        if n >= LOG_CHUNK:
            for chunks, v in zip(self._chunks, values):
                chunks.append(np.array(v))
            return
        for buffer, v in zip(self._buffer, values):
            buffer[self._filled : self._filled + n] = v
        self._filled += n

    def _keep_buffer(self):
        """The buffered blocks as a chunk of their own (in order: before any later call's)."""
        if self._filled:
            for chunks, buffer in zip(self._chunks, self._buffer):
                chunks.append(buffer[: self._filled].copy())
            self._filled = 0

    def arrays(self):
        """(y, y_motion, x, P) of every block so far, each joined into one array."""
        self._keep_buffer()
        if not self._chunks[0]:
            return tuple(np.empty((0, 3)) for _ in self._chunks)
        for chunks in self._chunks:
            chunks[:] = [np.concatenate(chunks)]  # one array at a time: the chunks go as it is made
        return tuple(chunks[0] for chunks in self._chunks)


class Smoother:
    """Forward-backward smoother over a :class:`gyrofilter.GyroFilter` (recordings, offline).

    >>> from gyrofilter import GyroFilter
    >>> f = GyroFilter(100.0)
    >>> s = Smoother(f)           # before the first sample: it records every block
    >>> rows = f.filter(samples_dps)          # doctest: +SKIP
    >>> smoothed = s.smooth()                 # doctest: +SKIP  (same rows, smoothed)

    ``filt``: the :class:`gyrofilter.GyroFilter` to smooth, before its first sample.
    The filter is fed as usual (``update()`` or ``filter()``, in chunks of any size);
    :meth:`smooth` returns one row per output row the filter produced so far, in deg/s. It
    needs the adaptive Kalman stage (``kalman_noise="adaptive"``: the presets of
    :data:`SMOOTHABLE_PRESETS`) and no hold stage.
    """

    def __init__(self, filt):
        if not isinstance(filt, GyroFilter):
            raise SettingsError(f"Smoother needs a GyroFilter, got {type(filt).__name__}")
        if filt.block_log is not None:
            raise SettingsError("this filter already has a Smoother; use that one")
        s = filt.settings
        if s.tracker != "kalman" or s.kalman_noise != "adaptive" or s.hold:
            raise SettingsError(f"smoothing needs the adaptive Kalman filter (preset {' or '.join(map(repr, SMOOTHABLE_PRESETS))}), "
                                f"not preset {filt.preset!r} with tracker={s.tracker!r}, kalman_noise={s.kalman_noise!r}, "
                                f"hold={s.hold}")
        if filt.blocks_out:
            raise SettingsError(f"the smoother must be attached before the filter's first block; "
                                f"this filter has produced {filt.blocks_out}")
        self.filter = filt
        self.log = BlockLog()
        filt.block_log = self.log

    def smooth(self) -> np.ndarray:
        """The smoothed rates (M, 3), deg/s, of the M blocks the filter has produced.

        The backward filter runs over the reversed block means ``BACKWARD_CHUNK`` blocks at a
        time, each chunk combined with the forward results as it comes, so the backward pass
        adds a fixed amount of memory."""
        y, y_motion, x_f, p_f = self.log.arrays()
        backward = adaptive_kalman.AdaptiveKalman(self.filter.settings)
        backward.start(np.sqrt(self.filter._akf.r_dps2), still_blocks=0)
        smoothed = np.empty_like(x_f)
        for end in range(len(y), 0, -BACKWARD_CHUNK):
            start = max(end - BACKWARD_CHUNK, 0)
            rows = slice(start, end)
            trace = np.empty((end - start, 3, 3))
            backward.run(y[rows][::-1].copy(), np.empty((end - start, 3)), trace, y_motion[rows][::-1].copy())
            trace = trace[::-1]
            smoothed[rows] = combine(x_f[rows], p_f[rows], trace[:, adaptive_kalman.PRIOR], trace[:, adaptive_kalman.PRIOR_VAR])
        return smoothed


def combine(x_f, p_f, x_b, p_b):
    """Two-filter combination (Fraser & Potter 1969): the inverse-variance weighted mean of the
    forward posterior (``x_f`` deg/s, variance ``p_f`` (deg/s)^2) and the backward prior (``x_b``,
    ``p_b``), elementwise: x = w x_f + (1 - w) x_b, w = p_b / (p_f + p_b)."""
    w = p_b / (p_f + p_b)
    return w * x_f + (1.0 - w) * x_b


def smooth(samples_dps, sample_rate_hz, calibration_s=None, *, temp_c=None, preset=DEFAULT_PRESET, calibration=None,
           **settings) -> np.ndarray:
    """Smoothed rates (M, 3) in deg/s of a whole recording ``samples_dps`` (N, 3), deg/s.

    The rows are those of ``GyroFilter(sample_rate_hz, calibration_s, preset=..., **settings)
    .filter(samples_dps)`` (one per complete block after the calibration), smoothed by
    :class:`Smoother`. ``sample_rate_hz`` (Hz), ``calibration_s`` (s), ``preset``,
    ``calibration`` and ``settings`` as for :class:`gyrofilter.GyroFilter`; ``temp_c``: N
    temperatures (deg C) when the settings compensate temperature, as for its ``filter``.
    """
    filt = GyroFilter(sample_rate_hz, calibration_s, preset=preset, calibration=calibration, **settings)
    smoother = Smoother(filt)
    filt.filter(samples_dps, temp_c)
    return smoother.smooth()
