"""What the commands tell the user on the console: messages and warnings on stderr (stdout stays
data), the start-up bias as printed, and the summary table of a filtered recording. Every message
(a line that may name a file) goes through :func:`~gyrofilter.inputs.escape_controls` (``\\n``, ``\\x1b``: a file
name cannot start a line of its own or colour the terminal)."""
import contextlib
import math
import os
import re
import sys
import textwrap
import time

from ..inputs import escape_controls
from ..units import AXES


#: the widest line the commands print on stdout (a terminal of 100 columns; every number is in --json)
MAX_LINE_CHARS = 100


class ReaderAwareStream:
    """stdout or stderr while a command runs: where its reader goes away (``| head``, a
    BrokenPipeError) what is left of it goes to the null device, silently, and the command carries
    on, its output files written (the error ended the command at its next print with exit 0 and no
    word: ``allan --json F | head`` left no F); ``reader_gone`` tells the commands that stop then
    (run, replay --realtime). ``lost``: the errors that mean so; stderr, which holds messages only,
    takes every OSError (``2>>LOG`` on a full disk, ENOSPC; a terminal gone, EIO: a message no
    one can read stopped ``record`` at its first status line, its recording cut short), stdout
    the BrokenPipeError only (another error lost the command's result, and is one, raised naming
    ``name`` once, the rest going nowhere: "[Errno 28] No space left on device" alone read as the
    failure of an output file the command had written whole; the command's last
    :meth:`flush` raises it too, where the buffer held the whole result: ``allan F > FULL``
    ended with exit 0). The null device lasts until :meth:`restore`, at the command's end (a
    program that runs the commands keeps its descriptor: a second command on a full stdout
    ended with exit 0, its result lost, and the program's own prints after it went nowhere).
    Everything else is the stream's."""

    def __init__(self, stream, name, lost=BrokenPipeError):
        self.stream, self.name, self.lost, self.reader_gone = stream, name, lost, False
        self._saved_fd = None  # a duplicate of the descriptor sent to the null device

    def write(self, text):
        with self._named():
            try:
                return self.stream.write(text)
            except self.lost:
                self._drop()
                return len(text)

    def flush(self):
        with self._named():
            try:
                self.stream.flush()
            except self.lost:
                self._drop()

    @contextlib.contextmanager
    def _named(self):
        try:
            yield
        except OSError as exc:
            self._to_null()
            raise OSError(exc.errno, exc.strerror or str(exc), exc.filename or self.name) from None

    def _drop(self):
        self.reader_gone = True
        self._to_null()

    def _to_null(self):
        try:
            fd = self.stream.fileno()
        except (AttributeError, OSError):  # a stream of no descriptor (io.StringIO): no flush at exit either
            return
        if self._saved_fd is None:
            self._saved_fd = os.dup(fd)
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, fd)  # what stays in the buffer goes nowhere
        os.close(devnull)

    def restore(self):
        """At the command's end: what stays in the buffer flushed (to the null device, if the stream
        was sent there), then the descriptor given back its own file."""
        with contextlib.suppress(OSError):  # (another error of stdout: as before, at the exit's flush)
            self.stream.flush()
        if self._saved_fd is not None:
            os.dup2(self._saved_fd, self.stream.fileno())
            os.close(self._saved_fd)
            self._saved_fd = None

    def __getattr__(self, name):
        return getattr(self.stream, name)


def stdout_reader_gone():
    """Whether stdout's reader went away while the command ran (:class:`ReaderAwareStream`)."""
    return getattr(sys.stdout, "reader_gone", False)


def tell(*lines):
    """Lines for the user on stdout (a command's result: "wrote FILE ..."), each :func:`~gyrofilter.inputs.escape_controls`."""
    for line in lines:
        print(escape_controls(line))


#: the spaces a wrapped line never breaks at: inside "95 %", after "D" and after "=" before a number
#: ("D 0.607", "tau_s = 5.565"): a new user read "D" at a line's end and its value on the next;
#: and between a number and its unit ("66.7 s", "12 Hz")
_KEEP_TOGETHER = re.compile(r"(?<=\d) (?=%)|(?<=\bD) (?=[-+]?\d)|(?<==) (?=[-+]?\d)|(?<=\d) (?=(?:s|Hz|min|h)\b)")
#: what such a space is while the text is wrapped (a private-use character: no text holds it)
_GLUE = "\ue000"


def paragraph(text, indent="", *, file=None):
    """Print ``text`` (:func:`~gyrofilter.inputs.escape_controls`) wrapped at :data:`MAX_LINE_CHARS`, its first line indented by
    ``indent`` and the others by two more spaces (stdout, or ``file``); never broken at the
    spaces of :data:`_KEEP_TOGETHER`."""
    glued = _KEEP_TOGETHER.sub(_GLUE, escape_controls(text))
    print(textwrap.fill(glued, MAX_LINE_CHARS, initial_indent=indent, subsequent_indent=indent + "  ",
                        break_on_hyphens=False, break_long_words=False).replace(_GLUE, " "), file=file)


def say(*lines, flush=False):
    """Messages for the user, one line each (:func:`~gyrofilter.inputs.escape_controls`), on stderr, so that stdout stays data."""
    for line in lines:
        print(escape_controls(line), file=sys.stderr, flush=flush)


#: in a log (stderr not a terminal: a pipe, a file, nohup, systemd) and without --progress: at most
#: one progress line per this many seconds, so that the log shows the command alive without filling
#: up (gap's simulations say their state every 2 s: 240 lines in 8 minutes)
LOG_PROGRESS_EVERY_S = 60.0

#: the help of every long command's --progress (:func:`add_progress_argument`)
PROGRESS_HELP = ("every progress line on stderr even when it is not a terminal (default: every line on a terminal; "
                 f"in a log a line every {LOG_PROGRESS_EVERY_S:g} s of a long run, and one per recording of a fleet)")


def add_progress_argument(parser):
    parser.add_argument("--progress", action="store_true", help=PROGRESS_HELP)


class ProgressLines:
    """The progress of a long command on stderr, one rule for every command: on a terminal, or
    with ``--progress`` (``forced``), every line (:attr:`every_line`); else (a log) the first
    line said at least :data:`LOG_PROGRESS_EVERY_S` after the last one shown (or the start: a
    short command, or one refused in its one line, says nothing more in a log than before), and
    every line said with ``always=True`` (a fleet's line per recording). ``prefix`` ("gap") heads
    each line with the seconds since the start: "gap [ 12.3 s] text"; ``clock``: seconds
    (``time.perf_counter``)."""

    def __init__(self, forced, prefix=None, *, clock=time.perf_counter):
        self.every_line = bool(forced) or sys.stderr.isatty()
        self.prefix, self.clock = prefix, clock
        self.t0 = self.last = clock()

    def __call__(self, text, *, always=False):
        now = self.clock()
        if not (self.every_line or always or now - self.last >= LOG_PROGRESS_EVERY_S):
            return
        self.last = now
        say(text if self.prefix is None else f"{self.prefix} [{now - self.t0:5.1f} s] {text}", flush=True)


#: how every refusal of a command starts, whichever part refuses (argparse, a command, the library):
#: one prefix, so that a script or a reader looks for one
ERROR_PREFIX = "gyrofilter: error: "


def error_line(text):
    """The one line of a refusal: :data:`ERROR_PREFIX` and ``text``, its whitespace collapsed."""
    return ERROR_PREFIX + " ".join(text.split())


def say_warning(text):
    """A warning for the user on stderr, "gyrofilter: warning: <text>", wrapped as a :func:`paragraph`
    (at :data:`MAX_LINE_CHARS`, the lines after the first indented by two spaces)."""
    paragraph(f"gyrofilter: warning: {text}", file=sys.stderr)


def print_warnings(warnings):
    for text in warnings:
        say_warning(text)


def bias_text(bias_dps):
    """The start-up bias as the commands print it: "+0.1234, -0.5678, +0.0012 deg/s"."""
    return ", ".join(f"{b:+.4f}" for b in bias_dps) + " deg/s"


def gross_errors_text(rejected):
    """The calibration's gross errors left out per axis (``Calibration.rejected``) as the commands
    say them after its bias: ", gross errors left out: x 0, y 1, z 0", or "" when there were none."""
    if not any(rejected):
        return ""
    return ", gross errors left out: " + ", ".join(f"{axis} {k}" for axis, k in zip(AXES, rejected))


def print_summary(path, head, filt, raw, filtered, calibration_from=None, smoothed=False):
    """The per-axis table: raw and filtered mean/std (:class:`~gyrofilter.streamstats.RunningMoments`),
    std ratio, rejected samples. ``calibration_from``: the file the bias was loaded from, if any;
    ``smoothed``: the rows are the forward-backward smoother's."""
    tell(f"recording: {path}")
    print(f"  {head.rows} samples at {head.sample_rate_hz:g} Hz ({head.rows / head.sample_rate_hz:.1f} s), unit {head.gyro_unit}")
    cal = filt.calibration
    if cal is not None:
        source = f"loaded from {calibration_from}" if calibration_from else f"start-up calibration, {cal.samples} samples"
        source += gross_errors_text(cal.rejected)
        tell(f"  bias ({source}): " + ", ".join(_number(b, 0, sign=True) for b in cal.bias_dps) + " deg/s")
    how = ", smoothed forward-backward" if smoothed else ""
    if filt.compensates_temperature:
        how += ", temperature compensated (" + ", ".join(f"{c:g}" for c in filt.settings.temp_coefficients()) + " deg/s/degC)"
    print(f"  filter: preset {filt.preset}{how}, {filtered.count} output rows at {filt.output_rate_hz:g} Hz")
    if filt.pending_samples:
        print(f"  {filt.pending_samples} trailing sample(s) did not fill a block of {filt.settings.block_len} and produced no output")
    if filtered.count < 2:
        print("  too few filtered rows for statistics")
        return
    print("  axis   raw mean    raw std   filt mean   filt std  std ratio  rejected")
    raw_std, f_std = raw.std, filtered.std
    for a, name in enumerate(AXES):
        ratio = _number(raw_std[a] / f_std[a], 8, decimals=2) + "x" if raw_std[a] > 0 and f_std[a] > 0 else f"{'n/a':>9}"
        print(f"  {name}    {_number(raw.mean[a], 9, sign=True)}  {_number(raw_std[a], 9)}  {_number(filtered.mean[a], 9, sign=True)}"
              f"  {_number(f_std[a], 9)}  {ratio}  {int(filt.rejected[a]):8d}")
    removed = "bias removed" if cal is not None else "no calibration, so no bias removed"
    consumed = "after the calibration window " if cal is not None and not calibration_from else ""
    print(f"  (deg/s; raw = the samples {consumed}that the filter consumed, bias included;\n"
          f"   filt = the filtered rows, {removed}; n/a = undefined;\n"
          "   rejected = samples left out of their block's mean as gross errors: docs/filter.md, step 3)")


def _number(value, width, sign=False, decimals=4):
    """``value`` with ``decimals`` decimals, right-aligned in ``width``, or in 3 significant
    digits (1.23e+30) when that would take more than max(width, 12) characters; "n/a" when it
    is not a finite number (an undefined mean, std or ratio)."""
    if not math.isfinite(value):
        return f"{'n/a':>{width}}"
    plus = "+" if sign else ""
    text = f"{value:{plus}.{decimals}f}"
    if len(text) > max(width, 12):
        text = f"{value:{plus}.3g}"
    return f"{text:>{width}}"
