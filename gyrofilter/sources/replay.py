"""A recording file as a live source (``replay:FILE[,realtime][,speed=2]``).

The whole recording is read at open (format v1, see :mod:`gyrofilter.recording`), then handed out
in chunks: as fast as the reader asks (default), or paced so that the sample with time ``t`` is
delivered ``t / speed`` seconds after the first ``read()`` (``realtime``). Gaps in the file's
``t`` column (lost samples) are counted in ``stats["lost_samples"]`` and reported as notes
at the sample where they occur, like a live device would; annotation lines of the file are
passed on as notes too.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..errors import SettingsError, SourceEnded
from ..recording import read_recording

CHUNK_SAMPLES = 1000  # rows per read() when not paced
MAX_WAIT_S = 0.1
POLL_S = 0.02  # paced reads return at most this often (batches, like a device's FIFO poll)


class ReplaySource:
    """Replay ``path`` (format v1) as a source; ``realtime`` paces it at ``speed`` x real time."""

    def __init__(self, path, realtime=False, speed=1.0, *, clock=time.monotonic, sleep=time.sleep):
        if not speed > 0 or not math.isfinite(speed):
            raise SettingsError(f"replay speed must be a positive number, got {speed!r}")
        rec = read_recording(path)
        self.path = str(path)
        self.warnings = list(rec.warnings)
        self.realtime = bool(realtime)
        self.speed = float(speed)
        self._clock = clock
        self._sleep = sleep
        rate = rec.sample_rate_hz
        n = len(rec)
        t = np.asarray(rec.t_s, dtype=float)
        names = ["t", "gx", "gy", "gz"]
        if rec.temp_c is not None:
            names.append("temp")
        names += [c for c in rec.columns if c not in names]
        cols = {name: (t if name == "t" else rec.columns[name]) for name in names}
        self.columns = names
        self._data = np.column_stack([cols[c] for c in names]) if n else np.empty((0, len(names)))
        self.header = {k: v for k, v in rec.header.items() if k != "gyrofilter-recording"}
        self.header.setdefault("source", f"replay of {self.path}")
        self.stats = {"samples": 0, "lost_samples": 0, "gaps": 0}
        # notes due before sample i: gaps in t, and the file's own annotation lines
        self._due = []
        if n > 1:
            step = np.rint(np.diff(t) * rate).astype(np.int64)
            for i in np.flatnonzero(step > 1):
                lost = int(step[i] - 1)
                self._due.append((int(i) + 1, lost, f"gap: {lost} samples lost before t={t[i + 1]:.6g} s (in the replayed file)"))
        for row, text in _note_rows(rec):
            self._due.append((row, 0, text))
        self._due.sort(key=lambda item: item[0])
        self._next = 0
        self._notes = []
        self._t0 = t[0] if n else 0.0
        self._start = None
        self._last = -math.inf
        self._closed = False

    def read(self):
        if self._closed:
            raise SourceEnded(f"replay of {self.path}: source closed")
        n = len(self._data)
        if self._next >= n:
            raise SourceEnded(f"end of {self.path} ({n} samples)")
        if not self.realtime:
            stop = min(n, self._next + CHUNK_SAMPLES)
        else:
            now = self._clock()
            if self._start is None:
                self._start = now
            # rows with (t - t0) / speed <= elapsed are due; wait for the next one at most MAX_WAIT_S
            t_next = (self._data[self._next, 0] - self._t0) / self.speed
            wait = max(t_next - (now - self._start), POLL_S - (now - self._last))
            if wait > 0:
                self._sleep(min(wait, MAX_WAIT_S))
                now = self._clock()
            elapsed_t = (now - self._start) * self.speed + self._t0
            stop = int(np.searchsorted(self._data[:, 0], elapsed_t, side="right"))
            stop = max(stop, self._next)
            self._last = now
        rows = self._data[self._next : stop]
        while self._due and (self._due[0][0] < stop or stop >= n):
            _, lost, text = self._due.pop(0)
            if lost:
                self.stats["lost_samples"] += lost
                self.stats["gaps"] += 1
            self._notes.append(text)
        self._next = stop
        self.stats["samples"] += len(rows)
        return rows.copy()

    def pop_notes(self):
        notes, self._notes = self._notes, []
        return notes

    def close(self):
        self._closed = True

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def _note_rows(rec):
    """(index of the data row the note precedes, text) for the annotation lines of ``rec``.

    Every line after the column-name row is a data row or a note, so a note on file line L,
    preceded by k other notes, comes before data row L - first_body_line - k.
    """
    if not rec.notes:
        return []
    n = len(rec)
    first_body = _first_body_line(rec)
    if first_body is None:
        return [(n, text) for _, text in rec.notes]
    return [(max(0, min(n, line - first_body - k)), text) for k, (line, text) in enumerate(sorted(rec.notes))]


def _first_body_line(rec):
    """1-based file line number of the first line after the column-name row."""
    import gzip

    try:
        with open(rec.path, "rb") as fh:
            magic = fh.read(2)
        opener = gzip.open if magic == b"\x1f\x8b" else open
        with opener(rec.path, "rt", encoding="utf-8", errors="replace") as fh:
            for number, line in enumerate(fh, start=1):
                if not line.startswith("#"):
                    return number + 1
    except (OSError, EOFError):
        return None
    return None
