"""The live loop that ``record`` and ``run`` share: the SOURCE options, opening the source,
reading it until a stop signal, its end, a device failure or ``--duration``, the status line on
stderr and the summary words, and the ``--out`` recording, which takes its name at its first
data row (:class:`LiveOutput`).
"""
import contextlib
import os
import signal
import sys
import time

import numpy as np

from ..errors import DeviceError, GyroFilterError, RecordingError, SourceEnded, one_line
from ..recording import RecordingWriter
from ..sources import SOURCE_HELP, open_source, parse_source, source_outputs
from ..sources.base import WARNING_PREFIX
from ..units import GYRO_UNITS, check_duration_s
from . import console, options, outputs

STATUS_INTERVAL_S = 1.0
FLUSH_INTERVAL_S = 0.5  # the --out recording is flushed at least this often: what a crash can lose
EXIT_DISCONNECTED = 1
DURATION_REACHED = "duration reached"  # LiveLoop.ended (and its reason) when --duration ran out


def add_source_arguments(parser, required=True):
    """--source (``required`` or not) and the unit options for devices that send no header (``record``,
    ``run`` and ``report``)."""
    parser.add_argument("--source", required=required, metavar="SOURCE", help=SOURCE_HELP)
    parser.add_argument("--duration", type=options.decimal, metavar="S",
                        help="stop after S seconds of samples (default: until Ctrl-C, SIGTERM, SIGHUP or the end of the source)")
    parser.add_argument("--gyro-unit", choices=GYRO_UNITS,
                        help="gyro unit of a serial device that sends no header line")
    parser.add_argument("--lsb-per-dps", type=options.lsb_per_dps, metavar="X", help="LSB per deg/s of such a device (with --gyro-unit lsb)")
    options.add_sample_rate_argument(parser, help="sample rate (Hz) of an mpu6050, a simulation or a serial device that sends no header")


def check_duration(duration_s):
    """``--duration`` is a number of seconds in (0, MAX_DURATION_S] (:func:`~gyrofilter.units.check_duration_s`),
    or not given (None)."""
    if duration_s is not None:
        check_duration_s(duration_s, "--duration")


def source_files(spec):
    """The files SOURCE reads (a replayed recording, a simulation model, a serial device): never outputs."""
    _, kwargs = parse_source(spec)
    return [kwargs.get(key) for key in ("path", "model", "port")]


def check_outputs(outs, spec, inputs=(), force=False):
    """:func:`outputs.check_outputs` of a command that reads SOURCE ``spec``: its outputs ``outs``
    and the files the source writes (:func:`~gyrofilter.sources.source_outputs`: a ``spy://`` URL's
    ``file=``, emptied as the port opens), never the source's files nor the other ``inputs``."""
    outputs.check_outputs([*outs, *source_outputs(spec)], [*source_files(spec), *inputs], force)


class LiveOutput:
    """The ``--out`` recording of ``record`` and ``run``, written while the loop runs.

    It is written under a temporary name beside ``path`` (:func:`outputs.partial_path`) and takes
    its own name (``os.replace``, atomic) at the first flush that holds a data row, or when the
    command ends without failing. So an interrupted recording reads under its name (a file the
    writer refuses at its close, whose ``t`` would not read back, is removed, as its error says), and a file
    that exists (``--force``) is left as it was by any failure before the first row (a bad
    source, a refused calibration, a device failing): the temporary file goes instead, and the
    folders made for it. A failed write (disk full, file size limit) keeps the file as it was at
    its last flush, whole lines that read (:class:`~gyrofilter.recording.RecordingWriter`). ``row_name``: what a data row
    is, for the messages ("sample", "filtered row").
    """

    def __init__(self, path, header, columns, formats, row_name):
        self.path = path
        self.row_name = row_name
        self.published = False
        self._folder = outputs.output_folder(path)
        self._made = outputs.make_folders(self._folder)  # removed again when no file is kept
        outputs.remove_stale_partials(self._folder)
        self._tmp = outputs.partial_path(path)
        try:
            outputs.start_partial(self._tmp, path)
            self._writer = RecordingWriter(self._tmp, header, columns, formats=formats, flush_interval_s=None, name=path)
        except OSError as exc:  # named by the user's name, not the temporary one
            self._discard()
            raise OSError(exc.errno, f"{exc.strerror or exc}; not written", path) from None
        except BaseException:
            self._discard()
            raise

    @property
    def rows_written(self):
        return self._writer.rows_written

    @property
    def write_failed(self):
        return self._writer.write_failed

    def write(self, rows):
        self._writer.write(rows)

    def note(self, text):
        self._writer.note(text)

    def flush(self):
        self._writer.flush()
        if not self.published and self._writer.rows_flushed:
            self._publish()

    def _publish(self):
        outputs.commit(self._tmp, self.path)
        self.published = True
        self._inode = os.stat(self.path).st_ino

    def close(self, failed):
        """Close the file; after a failure (``failed``) keep it only when it holds a data row.
        Returns what the user must be told about the file (for "PATH: ..."), else "". A failure
        of the close itself (the last flush on a disk that fills now) is a failed write: the file
        keeps its last flush, and the OSError says so ("PATH: No space left on device; kept the
        first N samples", or "not written, ...")."""
        try:
            self._writer.close()
        except OSError as exc:
            raise OSError(exc.errno, f"{exc.strerror or exc}; {self._keep(True)}", self.path) from None
        except RecordingError:  # its t refused at the close (its last window, a file shorter than one): not readable
            self._withdraw()
            raise
        return self._keep(failed)

    def _withdraw(self):
        """Remove the file the writer refused at its close (the refusal says "not written"): the temporary
        one, or the published one when it is still this command's (the same inode)."""
        if self.published and _inode(self.path) == self._inode:
            _remove(self.path)
            outputs.remove_made_folders(self._folder, self._made)
        elif not self.published:
            self._discard()

    def _keep(self, failed):
        """Publish or discard the closed file; what the user must be told (see :meth:`close`)."""
        kept = self._writer.rows_flushed
        if failed and not kept:
            if not self.published:
                self._discard()
                return f"not written, no {self.row_name} was kept"
        elif not self.published:
            try:
                self._publish()
            except BaseException:
                self._discard()
                raise
        elif _inode(self.path) != self._inode:  # another command replaced it (--force): our rows went with it
            raise FileExistsError(17, f"was replaced by another program while this command wrote it: its "
                                      f"{kept} {self.row_name}s are not in it", self.path)
        return f"kept the first {kept} {self.row_name}s" if failed else ""

    def _discard(self):
        """Remove the temporary file, and the folders made for it (the file never took its name)."""
        _remove(self._tmp)
        outputs.remove_made_folders(self._folder, self._made)


def _inode(path):
    """The inode of ``path``, or None when there is no file."""
    try:
        return os.stat(path).st_ino
    except OSError:
        return None


def _remove(path):
    with contextlib.suppress(FileNotFoundError):
        os.unlink(path)


def close_after_failure(output, exc, command):
    """Close ``output`` (a :class:`LiveOutput`, or run's stdout) after ``exc`` stopped ``command``.
    A failed write of the output (an OSError) is raised again as the command's one error line,
    saying what the file kept; otherwise what the failure left goes on stderr and the caller
    raises ``exc``."""
    try:
        line = output.close(failed=True)
    except OSError as closing:  # the close failed too (a disk full): its line says what the file kept
        if isinstance(exc, GyroFilterError):
            raise GyroFilterError(f"{one_line(exc)}; {one_line(closing)}") from None
        raise closing from None
    if output.write_failed and isinstance(exc, OSError):
        raise OSError(exc.errno, f"{exc.strerror or exc}; {line}", output.path) from None
    if line and isinstance(exc, GyroFilterError):  # one error line that also says what the file kept
        raise GyroFilterError(f"{one_line(exc)}; {output.path}: {line}") from None
    if line:
        console.say(f"{command}: {output.path}: {line}")


def open_from_args(args):
    """Open ``args.source`` with the unit options and ``--duration`` as defaults (a simulation
    then runs for that duration, so that it equals ``simulate --duration``); a bad
    ``--sample-rate-hz`` is refused naming the option, whichever source it was meant for; a unit
    option the source cannot take, or that its SOURCE text gives too, is refused naming the option."""
    named = {"gyro_unit": "--gyro-unit", "lsb_per_dps": "--lsb-per-dps", "sample_rate_hz": options.SAMPLE_RATE_OPTION}
    return open_source(args.source, options=named, gyro_unit=args.gyro_unit, lsb_per_dps=args.lsb_per_dps,
                       sample_rate_hz=options.sample_rate_hz(args), duration_s=args.duration)


class StopSignals:
    """SIGINT/SIGTERM/SIGHUP set a flag that the loop checks (within ~0.1 s, a source's longest wait).
    SIGHUP is what a dropped SSH session sends: it ends the file as cleanly as Ctrl-C.

    Stopping between reads, never inside a write, keeps the file consistent (a KeyboardInterrupt
    raised inside gzip's write could leave a stream whose checksum does not match). A second
    signal raises KeyboardInterrupt for an immediate exit.
    """

    NAMES = {signal.SIGINT: "SIGINT (Ctrl-C)", signal.SIGTERM: "SIGTERM",
             **({signal.SIGHUP: "SIGHUP (hang-up)"} if hasattr(signal, "SIGHUP") else {})}

    def __init__(self):
        self.received = None
        self._old = {}

    def _handler(self, signum, frame):
        if self.received is not None:
            raise KeyboardInterrupt
        self.received = self.NAMES.get(signum, str(signum))

    def __enter__(self):
        for sig in self.NAMES:
            self._old[sig] = signal.signal(sig, self._handler)
        return self

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)
        return False


class Status:
    """A status line on stderr at most once per ``STATUS_INTERVAL_S``: the rate achieved beside the
    source's nominal ``sample_rate_hz``, losses, CPU use. On a terminal one line rewritten in
    place, unless ``whole_lines`` (rows are printed on that terminal too: a line left open there
    would take the next row into it), then a whole line each time, as to a file."""

    def __init__(self, enabled, sample_rate_hz, stream=None, whole_lines=False):
        self.enabled = enabled
        self.sample_rate_hz = sample_rate_hz
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty() and not whole_lines
        self._wall = time.monotonic()
        self._cpu = time.process_time()
        self._samples = 0
        self._shown = False

    def due(self):
        return self.enabled and time.monotonic() - self._wall >= STATUS_INTERVAL_S

    def show(self, samples, text, first_sample_wall=None):
        """``samples`` = total so far; ``text`` = the rest of the line; ``first_sample_wall``: when
        (time.monotonic) the first sample came, where the first rate is measured from: a source's
        start-up (a simulator's first block, a device's reset) is no rate it delivers at. Where
        that start-up made the line due less than half a STATUS_INTERVAL_S after the first sample,
        this call only starts the measurement (a few samples over milliseconds, and the start-up's
        CPU over them, read 500 samples/s and CPU 100000 %): the first line comes an interval later."""
        wall, cpu = time.monotonic(), time.process_time()
        if self._samples == 0 and first_sample_wall is not None:
            if wall - first_sample_wall < STATUS_INTERVAL_S / 2:
                self._wall, self._cpu, self._samples = wall, cpu, samples
                return
            self._wall = max(self._wall, first_sample_wall)
        dt = max(wall - self._wall, 1e-9)
        rate = (samples - self._samples) / dt
        cpu_pct = 100.0 * (cpu - self._cpu) / dt
        self._wall, self._cpu, self._samples = wall, cpu, samples
        line = f"{rate:7.1f} samples/s (nominal {self.sample_rate_hz:g}), {text}, CPU {cpu_pct:4.1f}%"
        if self.tty:  # rewritten in place: a line wider than the terminal would wrap, and the next rewrite garble it
            self.stream.write("\r" + line[:max(_columns(self.stream) - 1, 20)] + "\x1b[K")
        else:
            self.stream.write(line + "\n")
        self.stream.flush()
        self._shown = True

    def end(self):
        if self._shown and self.tty:
            self.stream.write("\n")
            self.stream.flush()


def _columns(stream):
    """The width of the terminal ``stream`` writes to (100 where it cannot be told)."""
    try:
        return os.get_terminal_size(stream.fileno()).columns or 100
    except (OSError, ValueError, AttributeError):
        return 100


def source_summary(stats):
    """The source's non-zero counters as 'name N' words (samples first)."""
    return ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in stats.items() if v and k != "samples")


class LiveLoop:
    """The read loop shared by ``record`` and ``run``: reads ``source`` until a stop signal, its
    end, a device failure or ``duration_s`` seconds of samples (sensor clock).

    ``with LiveLoop(source, duration_s) as loop: while (step := loop.next()) is not None: ...``
    where a step is ``(rows, notes)``; afterwards :meth:`reason` says why it stopped.
    """

    def __init__(self, source, duration_s=None):
        self.source = source
        self.duration_s = duration_s
        self.sample_rate_hz = source.sample_rate_hz
        self.t_col = source.columns.index("t")
        self.first_t = self.last_t = None
        self.first_wall = None  # when (time.monotonic) the first sample came
        self._t_end = None  # samples at t >= this are beyond the duration (half a sample of margin)
        self.samples = 0
        self.lost_samples = self.gaps = 0  # in the t of the samples kept (see stats)
        self.ended = None  # SourceEnded, DeviceError or DURATION_REACHED
        self._finished = False  # a stop signal came and the source's held rows were taken
        self._signals = StopSignals()

    def __enter__(self):
        self._signals.__enter__()
        return self

    def __exit__(self, *exc):
        return self._signals.__exit__(*exc)

    def next(self):
        """The next ``(rows, notes)``, or None when the loop is over. A stop signal ends the
        source's stream: its last step is the rows the source held back (``source.finish()``, a
        serial line whose counter jumped, written as at a disconnect), within ``duration_s``."""
        if self.ended is not None or self._finished:
            return None
        try:
            if self._signals.received is not None:
                self._finished = True
                rows = self.source.finish()
            else:
                rows = self.source.read()
        except SourceEnded as exc:
            self.ended = exc
            return None
        except (DeviceError, OSError) as exc:  # the device failed for good: keep what we have
            self.ended = DeviceError(f"device error: {' '.join(str(exc).split())}")
            return None
        notes = self.pop_notes()
        if len(rows):
            t = rows[:, self.t_col]
            if self.first_t is None:
                self.first_t = float(t[0])
                self.first_wall = time.monotonic()
                if self.duration_s is not None:
                    self._t_end = self.first_t + self.duration_s - 0.5 / self.sample_rate_hz
            if self._t_end is not None:
                # cut at the first sample beyond the duration (t never goes back: a prefix, no splice);
                # when the next sample would be beyond it anyway, stop now instead of waiting for it
                beyond = np.flatnonzero(t >= self._t_end)
                if len(beyond):
                    rows, self.ended = rows[: beyond[0]], DURATION_REACHED
                elif t[-1] + 1.0 / self.sample_rate_hz >= self._t_end:
                    self.ended = DURATION_REACHED
            if len(rows):
                self._count_gaps(rows[:, self.t_col])
                self.last_t = float(rows[-1, self.t_col])
                self.samples += len(rows)
        return rows, notes

    def _count_gaps(self, t):
        """Count the samples lost within the kept samples of times ``t`` (s) (after ``last_t``): a step of
        k = rint(dt * sample_rate_hz) > 1 intervals is a gap of k - 1 lost samples, as replay counts them
        in the file (``sources.replay``) and as every source makes its t (a sample index over the rate)."""
        prev = t[0] if self.last_t is None else self.last_t
        step = np.rint(np.diff(t, prepend=prev) * self.sample_rate_hz)
        gap = step > 1
        self.lost_samples += int((step[gap] - 1).sum())
        self.gaps += int(gap.sum())

    @property
    def stats(self):
        """The source's counters, with its samples and lost samples (and its gap counters, ``gaps`` or
        ``counter_jumps``) those of the samples kept: lines read past a ``duration_s`` cut (whose samples
        are not written) count in the source's, not in what a summary or the file states."""
        stats = dict(self.source.stats, samples=self.samples, lost_samples=self.lost_samples)
        for key in ("gaps", "counter_jumps"):
            if key in stats:
                stats[key] = self.gaps
        return stats

    def stop(self, reason):
        """End the loop for ``reason`` (words for :meth:`reason`): the next :meth:`next` is None."""
        self.ended = reason

    def pop_notes(self):
        """The source's notes; its warnings (a replayed file cut short) also go to stderr, since
        they are otherwise seen only inside the output."""
        notes = self.source.pop_notes()
        for text in notes:
            if text.startswith(WARNING_PREFIX):
                console.say(f"gyrofilter: {text}")
        return notes

    @property
    def span_s(self):
        """Sensor time covered, first to last sample plus one sample interval."""
        return 0.0 if self.last_t is None else self.last_t - self.first_t + 1.0 / self.sample_rate_hz

    def reason(self):
        if self.interrupted:
            return f"stopped by {self._signals.received}"
        if isinstance(self.ended, SourceEnded):
            return f"source ended: {self.ended}"
        if isinstance(self.ended, DeviceError):
            return f"stopped: {self.ended}"
        return self.ended or "stopped"

    @property
    def interrupted(self):
        """True when a signal (Ctrl-C, SIGTERM) stopped the loop."""
        return self._signals.received is not None

    def failed(self):
        """True when the device went away or failed (exit status 1)."""
        return isinstance(self.ended, DeviceError) or (
            isinstance(self.ended, SourceEnded) and bool(self.source.stats.get("disconnects")))
