"""The checks of a recording's data that the reader and the writers share, so that nothing is
written that would not read back: every gyro value within +-MAX_RATE_DPS once in deg/s, and
every accelerometer value of a six-axis recording within +-MAX_ACCEL_MPS2 once in m/s^2
(:func:`check_rates`), and the ``t`` column increasing with its typical step agreeing with
``sample_rate_hz`` in every window (:class:`TimeCheck`). Both are vectorised, chunk by chunk.
"""
from __future__ import annotations

import numpy as np

from ..errors import RecordingError
from ..units import MAX_ACCEL_MPS2, MAX_RATE_DPS, RATE_TOLERANCE
from .header import ACCEL_COLUMNS, GYRO_COLUMNS, T_FROM_COUNTER, T_FROM_KEY, T_FROM_LINES, format_number


def check_rates(data, head, where):
    """Refuse a gyro value beyond +-MAX_RATE_DPS once in deg/s (1e308 rad/s, a tiny lsb_per_dps):
    no gyro reads it, and it would overflow every analysis. One vectorised pass over ``data``, a
    chunk in ``head``'s columns and units; ``where(row)`` names a row ("line 12"). The reader and
    the writers share it, so that nothing is written that would not read back. With ``accel_unit``
    in the header (a six-axis recording) the same for ``ax, ay, az`` beyond +-MAX_ACCEL_MPS2 once
    in m/s^2 (about 1e6 g); without it they are carried along unchecked (their unit unknown)."""
    with np.errstate(over="ignore"):
        ok = np.abs(head.gyro_dps(data)) <= MAX_RATE_DPS
    _refuse_beyond(ok, data, head, where, GYRO_COLUMNS, head.gyro_unit, f"+-{MAX_RATE_DPS:g} deg/s any gyro reads")
    if head.accel_unit is not None:
        with np.errstate(over="ignore"):
            ok = np.abs(head.accel_mps2(data)) <= MAX_ACCEL_MPS2
        _refuse_beyond(ok, data, head, where, ACCEL_COLUMNS, head.accel_unit,
                       f"+-{MAX_ACCEL_MPS2:g} m/s^2 any accelerometer reads")


def _refuse_beyond(ok, data, head, where, names, unit, limit):
    """RecordingError naming the first value of the columns ``names`` (in ``unit``) whose ``ok`` is False."""
    if not ok.all():
        row, axis = (int(i[0]) for i in np.nonzero(~ok))
        name = names[axis]
        raise RecordingError(f"{head.path}: {where(row)}: column {name!r} is "
                             f"{format_number(data[row, head.names.index(name)])} {unit}, beyond the {limit}")


def first_step_back(step_s):
    """The index of the first of the steps ``step_s`` (each time minus the one before it, s) that is
    not positive, or None: times increase strictly, a repeated time being a step back as a
    decreasing one is (two samples at one instant, or rows out of order). The rule of the ``t``
    column (:class:`TimeCheck`), of the times given to ``GyroFilter.filter_timed`` and of a
    simulator model's temperature table (``t_s``)."""
    bad = np.flatnonzero(np.asarray(step_s) <= 0)
    return int(bad[0]) if bad.size else None


#: the number of consecutive steps of ``t`` in each window whose median is compared with ``1 / sample_rate_hz``
RATE_CHECK_STEPS = 1000


def gap_step_s(head):
    """The longest step of ``t`` (s) that spans no lost sample in a recording of ``head`` (its
    ``sample_rate_hz`` and ``input_sample_rate_hz``): one sample interval plus half an input sample
    interval (:class:`TimeCheck`); a longer step is a gap, counted in ``head.t_gaps``."""
    return 1.0 / head.sample_rate_hz + 0.5 / head.input_sample_rate_hz


class TimeCheck:
    """The checks of a recording's ``t`` column, chunk by chunk (:meth:`add`), cheap and vectorised;
    the reader and the writer share them, so that what is written reads back:

    - ``t`` increases strictly, also across chunks;
    - steps longer than one sample interval plus half an input sample interval are gaps, counted
      in ``head.t_gaps`` (lost samples: legal). The input is the file's own samples (1.5 sample
      intervals) unless the header names ``input_sample_rate_hz``, the rate of the samples a
      filtered output's rows come from (``run``/``replay --out``: a row per block of
      L = input_sample_rate_hz / sample_rate_hz delivered samples, at the time of the block's
      last one): a row whose block spans lost samples comes at least L + 1 input intervals
      after the one before;
    - the typical step of every window of :data:`RATE_CHECK_STEPS` consecutive steps is
      ``1 / sample_rate_hz`` within :data:`~gyrofilter.units.RATE_TOLERANCE`, in both directions: a ``t``
      that runs faster or slower than the header says, anywhere in the file, would make every
      time constant and Allan cluster time wrong. The windows start every half window (steps
      1-1000, 501-1500, 1001-2000, ...), so a stretch at the wrong rate as long as a window is
      caught wherever it lies; at the end, the last window, the :data:`RATE_CHECK_STEPS` steps
      that end the file (the steps after the last whole window judged with those before them, as
      any window's), and a file shorter than one window on all its steps (:meth:`finish`). The
      typical step is the lower median of the window's steps that are not gaps
      (:func:`typical_steps`): a device that lost most samples still shows the rate in the
      steps between samples it delivered in a row, and its recording reads, its gaps counted. A
      window of gaps only holds no such step: in a file of samples its median of all steps is
      compared (a ``t`` at half the header's rate looks just so: every other sample lost); in a
      filtered output it is compared when it is two row intervals or more (less
      RATE_TOLERANCE): half the input samples or more lost, as in a file of samples, or a ``t``
      at half the rate or less (a file of samples whose header names an input rate was so read
      at any rate). A shorter one shows no rate and passes (every block of the window lost a
      few samples: each step is longer than a row interval by the input samples lost, which
      says nothing of the rate). A window of gaps only whose typical step is a whole number of
      input sample intervals is lost samples where another window of the file showed the rate
      (most of its steps one sample interval), and refused at the end where none did
      (:meth:`_wrong`): a device's counter gaps over 1000 steps or more at the start or the end
      of a recording no longer look like a t at half the rate. Where the header says ``t`` is the
      device's sample counter (``t_from: device counter``, :data:`~gyrofilter.recording.header.T_FROM_KEY`:
      ``record`` from a serial device; ``device lines`` without a counter, its refused lines of a sample
      counted), such a window is lost samples whatever the other windows
      show: the device counted the samples it lost (one that lost every other sample from its
      first line was refused at the close and its recording removed whole);
    - the rows of every such window (and of the last window) are not denser than the rate: its
      steps span at least (1 - RATE_TOLERANCE) times their number of sample intervals
      (:meth:`_dense`), or, with the half window of steps before it, the steps of both do (samples
      that catch up after a stall, stamped close together, follow the gap of the stall: a window
      that starts among them lacks the stall's time, which the steps before it hold: 17 of 50
      stalls of 2 s at 100 Hz, at random places, were refused). Lost samples make a window span
      more, never less; a window that spans less holds rows the rate has no room for (a copy of
      a row stamped 1 ulp after it, inserted rows: up to half the rows so inserted leave the
      typical step as it was, and a file 86 s long read as 60 s of t).

    ``head``: what the messages name (``head.path``) and where gaps are counted; ``why``: the
    advice a refusal ends with (the writer says why its rows would come out so).
    """

    def __init__(self, head, why="is sample_rate_hz or t wrong, or were most samples lost here?"):
        self.head = head
        self.why = why
        self.max_step_s = gap_step_s(head)
        # the typical step of a window of gaps only that is compared: any (a file of samples), or
        # half the input samples lost or more (a filtered output, whose rows are blocks)
        self.min_gaps_step_s = 0.0 if head.input_sample_rate_hz == head.sample_rate_hz else \
            (2.0 - RATE_TOLERANCE) / head.sample_rate_hz
        self.t_last = None
        self.last_where = None  # where the last sample of the previous chunk is
        self.steps_seen = 0  # the steps of the chunks added so far
        self.rate_shown = False  # a window showed the rate (:meth:`_note_rate_shown`)
        self.deferred = None  # the refusal of the first window of gaps only judged at the end (:meth:`_wrong`)
        self.counted = head.header.get(T_FROM_KEY) in (T_FROM_COUNTER, T_FROM_LINES)  # t counts the device's samples
        self.phases = [_WindowPhase(0), _WindowPhase(RATE_CHECK_STEPS // 2)]
        self.last_steps = np.empty(0)  # the last 1.5 RATE_CHECK_STEPS steps (:meth:`finish`'s last window and before it)

    def add(self, t, where):
        """Check the times ``t`` of a chunk; ``where(i)`` names its row ``i`` ("line 12")."""
        head = self.head
        if self.t_last is None:
            prev, cur, row0 = t[:-1], t[1:], 1
        else:
            prev, cur, row0 = np.concatenate(([self.t_last], t[:-1])), t, 0
        with np.errstate(over="ignore"):  # -1e308 to 1e308 steps by inf: a step off the rate, refused below
            step = cur - prev
        k = first_step_back(step)
        if k is not None:
            raise RecordingError(f"{head.path}: {where(k + row0)}: t does not increase "
                                 f"({float(cur[k])!r} after {float(prev[k])!r})")
        gaps = step > self.max_step_s
        head.t_gaps += int(np.count_nonzero(gaps))
        self._note_rate_shown(step)
        last_where = self.last_where

        def step_start(i):  # where the sample a step of this chunk starts from is
            return where(i + row0 - 1) if i + row0 >= 1 else last_where

        for phase in self.phases:
            phase.add(step, step_start, self)
        keep = RATE_CHECK_STEPS + RATE_CHECK_STEPS // 2
        self.last_steps = np.concatenate((self.last_steps, step[-keep:]))[-keep:]
        self.steps_seen += len(step)
        self.t_last = float(t[-1])
        self.last_where = where(len(t) - 1)

    def _note_rate_shown(self, step):
        """Note whether the file showed its rate (``rate_shown``): a window of RATE_CHECK_STEPS steps,
        ending at a multiple of half a window, whose lower median of all its steps, gaps included,
        is the rate's step within RATE_TOLERANCE (most of its steps one sample interval).
        ``step``: the steps of the chunk being added."""
        if self.rate_shown:
            return
        half = RATE_CHECK_STEPS // 2
        start, end = self.steps_seen, self.steps_seen + len(step)
        ends = np.arange(max(RATE_CHECK_STEPS, (start // half + 1) * half), end + 1, half)
        if not len(ends):
            return
        before = self.last_steps[-RATE_CHECK_STEPS:]
        steps = np.concatenate((before, step))
        first = start - len(before)  # the file's step index of steps[0]
        windows = np.lib.stride_tricks.sliding_window_view(steps, RATE_CHECK_STEPS)[ends - RATE_CHECK_STEPS - first]
        self.rate_shown = bool((~self._off(_lower_medians(windows))).any())

    def finish(self):
        """At the end: a file shorter than one window on all its steps (their span only when half
        a window or more); a longer one on its last window, the RATE_CHECK_STEPS steps that end it.
        The steps after the last whole window are so judged with the ones before them, as any
        window's: a tail of 700 steps of which every other sample was lost is gaps, as it is inside
        the file (checked alone it showed half the rate, and a live recording whose device lost
        every other line over its last 7 s was refused at its close and removed whole). The last
        window may show the rate too; a window of gaps only whose refusal waited (:meth:`_wrong`)
        is refused now when no window showed it."""
        phase = self.phases[0]
        before = np.empty(0)
        if phase.windows == 0:
            steps, start, n = phase.pending, phase.pending_where, len(phase.pending)
            if not n:
                return
        else:
            steps, before = self.last_steps[-RATE_CHECK_STEPS:], self.last_steps[:-RATE_CHECK_STEPS]
            n, start = RATE_CHECK_STEPS, f"up to {self.last_where}"
        median = typical_steps(steps[None, :], self.max_step_s, self.min_gaps_step_s)
        self.rate_shown = self.rate_shown or not self._off(_lower_medians(steps[None, :]))[0]  # the last window's
        off, deferred = self._wrong(median, steps[None, :])
        if deferred[0] and self.deferred is None:
            self.deferred = (float(median[0]), n, start, phase.windows == 0, phase.windows > 0)
        if off[0]:
            self._refuse(float(median[0]), n, start, first=phase.windows == 0, last=phase.windows > 0)
        if self.deferred is not None and not self.rate_shown and not self.counted:  # t at 1/k of the rate
            self._refuse(*self.deferred[:3], first=self.deferred[3], last=self.deferred[4])
        if (n >= RATE_CHECK_STEPS // 2 and self._dense(steps.sum(), n)
                and self._dense(steps.sum() + before.sum(), n + len(before))):
            self._refuse_dense(float(steps.sum()), n, start)

    def _wrong(self, typical_s, windows):
        """(whether each window is off the rate, whether it is a window of gaps only judged at the
        end): ``typical_s`` the windows' typical steps (of :func:`typical_steps`), ``windows`` (2-D)
        their steps. A window of gaps only whose typical step is a whole number of input sample
        intervals, within RATE_TOLERANCE of each (:meth:`_off_whole`), is lost samples where the
        file shows its rate (:meth:`_note_rate_shown`: a window whose steps are mostly one sample
        interval, before or after it): a device that lost every other sample over its first or
        last 10 s (counter gaps) looks just like a t at half the rate, but the rest of the file
        shows the rate. Where it is off the rate as any window is, its refusal waits for the end
        (:meth:`finish`: refused there when no window showed the rate: a t at half the rate, a
        few steps of one interval among its steps or not). One that is no whole number of
        intervals (2.5: t at 40 Hz in a 100-Hz file) is refused at once."""
        off = self._off(typical_s)
        gaps_only = (windows > self.max_step_s).all(axis=1)
        whole = gaps_only & ~self._off_whole(typical_s)
        deferred = whole & off
        off = off & ~whole
        return off, deferred

    def _off_whole(self, typical_s):
        """Whether each typical step is no whole number k of input sample intervals, more than
        RATE_TOLERANCE off per interval (|typical_s / k - 1 / input_sample_rate_hz|, k the nearest),
        or longer than 1 / (2 RATE_TOLERANCE) = 10 row intervals (1 / sample_rate_hz), where every
        step of a file of samples is within RATE_TOLERANCE of some k (a step beyond a float's range too).
        Where ``t`` is the device's sample counter (``counted``) a longer one is whole too: each of
        its steps is the whole number of samples the device counted (one that lost 10 of every 11
        samples from its first line was refused at the close and its recording removed whole)."""
        input_s = 1.0 / self.head.input_sample_rate_hz
        with np.errstate(over="ignore", invalid="ignore"):
            k = np.round(typical_s / input_s)
            per_s = typical_s / np.maximum(k, 1.0)
            whole = ((self.counted | (np.round(typical_s * self.head.sample_rate_hz) <= 0.5 / RATE_TOLERANCE))
                     & (np.abs(per_s - input_s) <= RATE_TOLERANCE * input_s))
        return ~whole

    def _off(self, typical_s):
        """Whether each typical step is more than RATE_TOLERANCE off the rate's (NaN, no rate shown: not off)."""
        expected_s = 1.0 / self.head.sample_rate_hz
        return np.abs(typical_s - expected_s) > RATE_TOLERANCE * expected_s

    def _dense(self, span_s, n):
        """Whether steps spanning ``span_s`` (s) in all are too short for ``n`` sample intervals:
        more than RATE_TOLERANCE under them (jitter moves only a window's two ends)."""
        return span_s < (1.0 - RATE_TOLERANCE) * n / self.head.sample_rate_hz

    def _refuse_dense(self, span_s, n, start):
        head = self.head
        raise RecordingError(
            f"{head.path}: t's {n} steps {_from(start)} span {span_s:.6g} s, but {n} sample intervals at "
            f"sample_rate_hz {head.sample_rate_hz:g} take {n / head.sample_rate_hz:.6g} s: more rows than the "
            f"rate has room for (rows repeated or inserted with their own t, or is sample_rate_hz wrong?)")

    def _refuse(self, typical_s, n, start, first, last=False):
        head = self.head
        which = "its first" if first else "the last" if last else "the"
        raise RecordingError(
            f"{head.path}: t steps by {typical_s:.6g} s (median of {which} {n} steps {_from(start)}), "
            f"but sample_rate_hz {head.sample_rate_hz:g} means {1.0 / head.sample_rate_hz:.6g} s: more than "
            f"{RATE_TOLERANCE:.0%} apart ({self.why})")


def _from(start):
    """Where steps start as a message says it: "from line 12", or ``start`` as it is when it says "up to"."""
    return start if start.startswith("up to ") else f"from {start}"


class _WindowPhase:
    """The whole windows of :data:`RATE_CHECK_STEPS` steps that start ``skip`` steps into the file."""

    def __init__(self, skip):
        self.skip = skip  # steps still to pass before the first window
        self.pending = np.empty(0)  # the steps after the last whole window
        self.pending_where = None  # where the first of them starts
        self.windows = 0  # the whole windows checked
        self.before = np.empty(0)  # up to half a window of the steps just before the next window

    def add(self, step, step_start, check):
        first = min(self.skip, len(step))
        self.skip -= first
        self.before = np.concatenate((self.before, step[:first]))[-(RATE_CHECK_STEPS // 2):]
        step = step[first:]
        if len(self.pending) == 0 and len(step):
            self.pending_where = step_start(first)
        steps = np.concatenate((self.pending, step))
        whole = len(steps) // RATE_CHECK_STEPS * RATE_CHECK_STEPS
        if whole:
            windows = steps[:whole].reshape(-1, RATE_CHECK_STEPS)
            medians = typical_steps(windows, check.max_step_s, check.min_gaps_step_s)
            spans = windows.sum(axis=1)
            half = RATE_CHECK_STEPS // 2  # each window with the half window before it (a stall's)
            before_s = np.concatenate(([self.before.sum()], windows[:-1, half:].sum(axis=1)))
            before_n = np.concatenate(([len(self.before)], np.full(len(windows) - 1, half)))
            dense = check._dense(spans, RATE_CHECK_STEPS) & check._dense(spans + before_s, RATE_CHECK_STEPS + before_n)
            off, deferred = check._wrong(medians, windows)
            if deferred.any() and check.deferred is None:
                j = int(np.argmax(deferred))
                start = j * RATE_CHECK_STEPS - len(self.pending)
                check.deferred = (float(medians[j]), RATE_CHECK_STEPS,
                                  self.pending_where if start < 0 else step_start(first + start),
                                  self.windows + j == 0 and self.skip == 0 and first == 0, False)
            wrong = np.flatnonzero(off | dense)
            if wrong.size:
                j = int(wrong[0])
                start = j * RATE_CHECK_STEPS - len(self.pending)
                where = self.pending_where if start < 0 else step_start(first + start)
                if not off[j]:
                    check._refuse_dense(float(spans[j]), RATE_CHECK_STEPS, where)
                check._refuse(float(medians[j]), RATE_CHECK_STEPS, where,
                              first=self.windows + j == 0 and self.skip == 0 and first == 0)
            self.windows += len(medians)
            self.before = windows[-1, RATE_CHECK_STEPS // 2:]
            if whole < len(steps):
                self.pending_where = step_start(first + whole - len(self.pending))
        self.pending = steps[whole:]


def typical_steps(windows, max_step_s, min_gaps_step_s=0.0):
    """The typical step of each row of ``windows`` (2-D, steps of ``t`` in s): the lower median of
    its steps of at most ``max_step_s`` (the longer ones are gaps, lost samples: :class:`TimeCheck`),
    or, when every one is a gap, of all its steps when that is ``min_gaps_step_s`` or more, else
    NaN (no rate shown)."""
    typical = _lower_medians(windows)
    gappy = np.flatnonzero((windows > max_step_s).any(axis=1))
    for row in gappy:  # rare: sorted one by one, the gaps left out
        kept = windows[row][windows[row] <= max_step_s]
        if len(kept):
            typical[row] = _lower_medians(kept[None, :])[0]
        elif typical[row] < min_gaps_step_s:
            typical[row] = np.nan
    return typical


def _lower_medians(windows):
    """The lower median of each row of ``windows`` (2-D)."""
    k = (windows.shape[1] - 1) // 2
    return np.partition(windows, k, axis=1)[:, k]
