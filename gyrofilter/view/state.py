"""What the live view shows, fed by the run loop and read by the server's threads.

The run loop calls :meth:`LiveState.feed` after every read: it copies the step into a bounded
inbox and returns (a lock held for an append, never for any I/O). The server's publisher thread
calls :meth:`LiveState.drain` a few times a second: it turns the steps into the new filtered rows
and raw block means, keeps the last :data:`HISTORY_S` seconds of both for a page that opens
later, the latest counters and temperature, and the Allan deviation of the still stretches
(:class:`~gyrofilter.view.still_allan.StillAllan`). When the publisher falls behind by more than
:data:`INBOX_STEPS` reads or :data:`INBOX_SAMPLES` samples, the oldest reads are dropped and
counted (``inbox_dropped``): the view loses them, the run does not.

Raw block means: the mean of each block of L (the filter's block length) consecutive input
samples, counted from the first sample of the run (deg/s, bias not removed, no outlier
rejection), stamped with the time of the block's last sample like a filtered row; they line up
with the filter's blocks when the start-up window is a whole number of blocks (2 s at 100 or
1000 Hz with blocks of 5).
"""
from __future__ import annotations

import collections
import math
import threading
from dataclasses import replace

import numpy as np

from .still_allan import StillAllan

#: seconds of rows kept for a page that opens during the run (the page shows 10 to 60 s)
HISTORY_S = 60.0
#: at most this many rows of each series in that history, whatever the rate
MAX_HISTORY_ROWS = 20000
#: reads, and samples in them, waiting for the publisher before the oldest reads are dropped
INBOX_STEPS = 2000
INBOX_SAMPLES = 200_000
#: digits kept in what the view sends: rates to 1e-6 deg/s, times to 1e-6 s
DECIMALS = 6


class _Ring:
    """The last ``capacity`` rows of ``width`` numbers (a fixed-size circular buffer)."""

    def __init__(self, capacity, width):
        self._data = np.zeros((capacity, width))
        self._next = 0
        self._count = 0

    def extend(self, rows):
        cap = len(self._data)
        rows = rows[-cap:]
        n = len(rows)
        first = min(n, cap - self._next)
        self._data[self._next : self._next + first] = rows[:first]
        self._data[: n - first] = rows[first:]
        self._next = (self._next + n) % cap
        self._count = min(cap, self._count + n)

    def rows(self):
        """The rows kept, oldest first (a copy)."""
        if self._count < len(self._data):
            return self._data[: self._count].copy()
        return np.concatenate([self._data[self._next :], self._data[: self._next]])


def rounded_rows(t_s, values):
    """``[[t, x, y, z], ...]`` as plain Python numbers, rounded to :data:`DECIMALS` decimals."""
    if not len(t_s):
        return []
    return np.round(np.column_stack([t_s, values]), DECIMALS).tolist()


class LiveState:
    """The state of the live view; see the module docstring. ``start(info)`` once (a
    :class:`~gyrofilter.view.sink.RunInfo`), then ``feed(step)`` from the run loop; ``drain()``,
    ``status()`` and ``history()`` from the server's threads."""

    def __init__(self):
        self._inbox = collections.deque()
        self._inbox_samples = 0
        self._inbox_lock = threading.Lock()
        self._lock = threading.Lock()  # what drain() builds, read by status() and history()
        self.inbox_dropped = 0
        self._dropped_seen = 0
        self.info = None
        self._latest = None  # the last step drained
        self._temp_c = None
        self._carry_t, self._carry_dps, self._carry_known = np.empty(0), np.empty((0, 3)), np.empty(0, dtype=bool)
        self._rows = self._raw = self._allan = None

    def start(self, info):
        self.info = info
        capacity = max(1, min(MAX_HISTORY_ROWS, int(math.ceil(HISTORY_S * info.output_rate_hz))))
        self._rows = _Ring(capacity, 4)
        self._raw = _Ring(capacity, 4)
        self._allan = StillAllan(info.block_len / info.sample_rate_hz)

    def feed(self, step):
        """Take one read of the run loop (a :class:`~gyrofilter.view.sink.Step`): copied, queued,
        never waiting for anything but a short lock."""
        copied = _copied(step)
        with self._inbox_lock:
            self._inbox.append(copied)
            self._inbox_samples += len(copied.t_s)
            while len(self._inbox) > INBOX_STEPS or (self._inbox_samples > INBOX_SAMPLES and len(self._inbox) > 1):
                self._inbox_samples -= len(self._inbox.popleft().t_s)
                self.inbox_dropped += 1

    def drain(self):
        """The steps queued since the last call, processed: ``(rows, raw)``, the new filtered rows
        and raw block means as (M, 4) arrays of t, x, y, z (deg/s); both empty when nothing came."""
        with self._inbox_lock:
            steps, self._inbox, self._inbox_samples = list(self._inbox), collections.deque(), 0
            dropped = self.inbox_dropped
        with self._lock:
            if dropped != self._dropped_seen:  # reads were lost between two drains: no block spans them
                self._dropped_seen = dropped
                self._carry_t, self._carry_dps, self._carry_known = np.empty(0), np.empty((0, 3)), np.empty(0, dtype=bool)
                self._allan.cut()
            if not steps:
                return np.empty((0, 4)), np.empty((0, 4))
            self._latest = steps[-1]
            rows = np.concatenate([np.column_stack([s.rows_t_s, s.rows_dps]) for s in steps])
            raw, known = self._block_means(steps)
            self._rows.extend(rows)
            self._raw.extend(raw)
            if known.any():  # the blocks read once the bias was known (the start-up window is not one)
                self._allan.add(raw[known, 0], raw[known, 1:], self._latest.bias_dps)
            temps = [s.temp_c for s in steps if s.temp_c is not None and len(s.temp_c)]
            if temps:
                last = np.concatenate(temps)
                last = last[np.isfinite(last)]
                if len(last):
                    self._temp_c = float(last[-1])
            return rows, raw

    def _block_means(self, steps):
        """``(raw, known)``: the raw block means completed by ``steps`` (M, 4: t, x, y, z) and, per
        block, whether the bias was known when its last sample was read."""
        length = self.info.block_len
        t = np.concatenate([self._carry_t, *(s.t_s for s in steps)])
        dps = np.concatenate([self._carry_dps, *(s.gyro_dps for s in steps)])
        known = np.concatenate([self._carry_known, *(np.full(len(s.t_s), s.bias_dps is not None) for s in steps)])
        whole = len(t) // length * length
        self._carry_t, self._carry_dps, self._carry_known = t[whole:], dps[whole:], known[whole:]
        means = dps[:whole].reshape(-1, length, 3).mean(axis=1)
        return np.column_stack([t[length - 1 : whole : length], means]), known[length - 1 : whole : length]

    def status(self):
        """The run's counters and state as plain JSON values (see docs/live.md, "The live view")."""
        with self._lock:
            step, info = self._latest, self.info
            allan = self._allan.result() if self._allan is not None else None
            temp_c = self._temp_c
        bias = None if step is None or step.bias_dps is None else [float(b) for b in step.bias_dps]
        return {
            "source": None if info is None else info.source,
            "preset": None if info is None else info.preset,
            "sample_rate_hz": None if info is None else info.sample_rate_hz,
            "output_rate_hz": None if info is None else info.output_rate_hz,
            "block_len": None if info is None else info.block_len,
            "samples_in": 0 if step is None else step.samples_in,
            "rows_out": 0 if step is None else step.rows_out,
            "lost_samples": 0 if step is None else step.lost_samples,
            "rejected_outliers": [0, 0, 0] if step is None else [int(r) for r in step.rejected_outliers],
            "calibration": "starting" if step is None else step.calibration,
            "bias_dps": bias,
            "temp_c": temp_c,
            "t_s": None if step is None or not len(step.t_s) else float(step.t_s[-1]),
            "allan": allan,
            "view_dropped_reads": self.inbox_dropped,
        }

    def history(self):
        """The history kept (the last :data:`HISTORY_S` s at most): ``{"rows": [...], "raw": [...]}``,
        each ``[[t, x, y, z], ...]``."""
        with self._lock:
            if self._rows is None:
                return {"rows": [], "raw": []}
            rows, raw = self._rows.rows(), self._raw.rows()
        return {"rows": _recent(rows), "raw": _recent(raw)}


def _recent(rows):
    if len(rows):
        rows = rows[rows[:, 0] > rows[-1, 0] - HISTORY_S]
    return rounded_rows(rows[:, 0], rows[:, 1:])


def _copied(step):
    """``step`` with arrays of its own (the run loop's may be reused)."""
    return replace(step, t_s=np.array(step.t_s, dtype=float), gyro_dps=np.array(step.gyro_dps, dtype=float),
                   temp_c=None if step.temp_c is None else np.array(step.temp_c, dtype=float),
                   rows_t_s=np.array(step.rows_t_s, dtype=float), rows_dps=np.array(step.rows_dps, dtype=float))
