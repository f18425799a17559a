"""A recording file as a live source (``replay:FILE[,realtime][,speed=2]``).

The recording (format v1, see :mod:`gyrofilter.recording`) is read in chunks as the reader asks
for samples, so a replay of hours at 1 kHz needs the memory of one chunk, not of the file. The
samples are handed out as fast as the reader asks (default), or paced so that the sample with
time ``t`` is delivered ``t / speed`` seconds after the first ``read()`` (``realtime``). Gaps in
the file's ``t`` column (lost samples) are counted in ``stats["lost_samples"]`` and reported as
notes, like a live device would; annotation lines of the file are passed on as notes (but for
its ``# end: ...`` note: how that recording ended is not how the replay ends), and the
reader's warnings (a recording cut short) as notes when they arise. A note is handed out with
the read whose first row is the sample it precedes, and no read runs past a note, so that a
recording of the replay (``record``, which writes a read's notes before its rows) keeps every
note at its place. A gap the file already notes (a ``gap:`` line before that sample) is counted
but not noted again, so a recording of a recording does not repeat it.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..errors import SourceEnded
from ..inputs import check_number
from ..recording import CHUNK_ROWS, COLUMNS, END_NOTE, VERSION_KEY, format_number, iter_recording
from .base import WARNING_PREFIX, Source

CHUNK_SAMPLES = 1000  # rows per read() when not paced
MAX_WAIT_S = 0.1
POLL_S = 0.02  # paced reads return at most this often (batches, like a device's FIFO poll)


#: the slowest pace of a replay: a thousand times slower than recorded (a speed of 1e-300 waited 1e298 s for the
#: first sample without a word, attack pass 59)
MIN_SPEED = 1e-3


class ReplaySource(Source):
    """Replay ``path`` (format v1) as a source; ``realtime`` paces it at ``speed`` x real time.

    Parameters
    ----------
    path : str or path-like
        The recording (``.csv`` or ``.csv.gz``, :mod:`gyrofilter.recording` format v1).
    realtime : bool
        Pace the samples: the sample with time ``t`` (s) is delivered ``(t - t0) / speed``
        seconds after the first ``read()``; False hands them out as fast as they are read.
    speed : float
        Pace factor with ``realtime`` (at least :data:`MIN_SPEED`, finite; 2 = twice as fast as recorded).
    clock, sleep : callable
        Monotonic clock (s) and sleep(s) for the pacing (test seams).
    chunk_rows : int
        Rows read from the file at a time (memory bound; does not change the output).

    ``columns`` are ``t, gx, gy, gz`` (+ ``temp``) then the file's other columns; units, rate
    and header are the file's. SettingsError for a bad ``speed``; the reader's errors for a bad
    file.
    """

    def __init__(self, path, realtime=False, speed=1.0, *, clock=time.monotonic, sleep=time.sleep, chunk_rows=CHUNK_ROWS):
        speed = check_number(speed, "replay speed", low=MIN_SPEED)  # numpy's numbers too (a float32 was refused)
        self._chunks = iter_recording(path, chunk_rows)
        head = self._head = next(self._chunks)
        self.path = str(path)
        self.realtime = bool(realtime)
        self.speed = float(speed)
        self._clock = clock
        self._sleep = sleep
        names = [*COLUMNS] + (["temp"] if "temp" in head.names else [])
        names += [c for c in head.names if c not in names]
        self.columns = names
        # file column of each output column (t may be made from the rate: -1)
        self._where = [head.names.index(c) if c in head.names else -1 for c in names]
        self.header = {k: v for k, v in head.header.items() if k != VERSION_KEY}
        self.header.setdefault("source", f"replay of {self.path}")
        self.sample_rate_hz, self.gyro_unit, self.lsb_per_dps = head.sample_rate_hz, head.gyro_unit, head.lsb_per_dps
        self.stats = {"samples": 0, "lost_samples": 0, "gaps": 0}
        self._buf = np.empty((0, len(names)))  # rows read from the file, not yet handed out
        self._pos = 0
        self._rows_read = 0  # rows taken from the file so far
        self._t_last = None  # t of the last row taken from the file
        self._due = []  # (row before which the note is due, lost samples, text), in row order
        self._notes_seen = self._warnings_seen = 0
        self._exhausted = False
        self._notes = []
        self._start = None
        self._t0 = None
        self._last = -math.inf
        self._fill()

    @property
    def warnings(self):
        """The reader's warnings so far (a last line cut short, a gzip stream without its end)."""
        return list(self._head.warnings)

    def _fill(self):
        """Take the next chunk from the file into the buffer (or mark the file exhausted)."""
        head = self._head
        try:
            chunk = next(self._chunks)
        except StopIteration:
            self._exhausted = True
            chunk = None
        if chunk is not None:
            r0 = self._rows_read
            t = head.t_s(chunk, r0)
            rows = np.empty((len(chunk), len(self.columns)))
            for j, i in enumerate(self._where):
                rows[:, j] = t if i < 0 else chunk[:, i]
            # gaps in t: a step of more than one sample interval (also across chunks)
            prev = np.concatenate(([self._t_last], t[:-1])) if self._t_last is not None else t[:-1]
            cur = t if self._t_last is not None else t[1:]
            step = np.rint((cur - prev) * head.sample_rate_hz).astype(np.int64)
            first = r0 if self._t_last is not None else r0 + 1
            noted = {note.row for note in head.notes[self._notes_seen:] if note.text.startswith("gap:")}
            for k in np.flatnonzero(step > 1).tolist():
                lost = int(step[k] - 1)
                text = f"gap: {lost} samples lost before t={format_number(cur[k])} s (in the replayed file)"
                self._due.append((first + k, lost, None if first + k in noted else text))
            self._t_last = float(t[-1])
            self._rows_read = r0 + len(chunk)
            self._buf = np.concatenate([self._buf[self._pos:], rows]) if self._pos < len(self._buf) else rows
            self._pos = 0
        # the file's annotation lines read since the last chunk: due before the sample that follows them;
        # its end note says how that recording ended, not this replay (whose reader notes its own end)
        for note in head.notes[self._notes_seen:]:
            if not note.text.startswith(END_NOTE):
                self._due.append((note.row, 0, note.text))
        self._notes_seen = len(head.notes)
        self._due.sort(key=lambda item: item[0])
        for text in head.warnings[self._warnings_seen:]:
            self._notes.append(WARNING_PREFIX + text)
        self._warnings_seen = len(head.warnings)

    def _available(self):
        return len(self._buf) - self._pos

    def read(self):
        """Next rows of the file, shape (n, len(columns)): t (s), gyro in the file's
        ``gyro_unit``, then the file's other columns (``temp`` in deg C).

        Up to :data:`CHUNK_SAMPLES` rows when not paced; with ``realtime`` the rows due by now,
        waiting at most :data:`MAX_WAIT_S` (0.1 s). May return no rows when only notes are due.
        Raises :class:`gyrofilter.errors.SourceEnded` at the end of the file or once closed.
        """
        if self._closed:
            raise SourceEnded(f"replay of {self.path}: source closed")
        while not self._exhausted and self._available() < CHUNK_SAMPLES:
            self._fill()
        if not self._available():
            if self._due:  # notes after the last sample
                self._release(math.inf)
                return self._buf[:0].copy()
            raise SourceEnded(f"end of {self.path} ({self.stats['samples']} samples)")
        first_row = self.stats["samples"]
        if self._due and self._due[0][0] <= first_row:  # notes due before the next row: hand them out first
            self._release(first_row)
            return self._buf[:0].copy()
        buf, pos = self._buf, self._pos
        if not self.realtime:
            stop = pos + min(self._available(), CHUNK_SAMPLES)
        else:
            now = self._clock()
            if self._start is None:
                self._start, self._t0 = now, buf[pos, 0]
            # rows with (t - t0) / speed <= elapsed are due; wait for the next one at most MAX_WAIT_S
            t_next = (buf[pos, 0] - self._t0) / self.speed
            wait = max(t_next - (now - self._start), POLL_S - (now - self._last))
            if wait > 0:
                self._sleep(min(wait, MAX_WAIT_S))
                now = self._clock()
            elapsed_t = (now - self._start) * self.speed + self._t0
            stop = max(pos, int(np.searchsorted(buf[pos:, 0], elapsed_t, side="right")) + pos)
            self._last = now
        if self._due:  # no read runs past a note: it goes out with the read that starts at its row
            stop = min(stop, pos + self._due[0][0] - first_row)
        rows = buf[pos:stop].copy()
        self._pos = stop
        self.stats["samples"] += len(rows)
        return rows

    def _release(self, row):
        """Move the notes due before rows up to ``row`` (the next to deliver) into the notes,
        counting their lost samples."""
        while self._due and self._due[0][0] <= row:
            _, lost, text = self._due.pop(0)
            if lost:
                self.stats["lost_samples"] += lost
                self.stats["gaps"] += 1
            if text is not None:
                self._notes.append(text)

    def _close(self):
        self._chunks.close()
