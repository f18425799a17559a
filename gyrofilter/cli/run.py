"""gyrofilter run: filter a live source in real time.

The filtered rates (deg/s, one row per block of the pipeline, ``t`` = time of the block's last
sample on the sensor's clock) go to stdout (``--out -``), or to ``--out FILE``, as a format-v1 recording
(so ``gyrofilter run ... > out.csv`` is a readable recording too), whose header names the SOURCE
as ``filtered_from`` (so ``replay`` refuses to filter it again) and whose last line is the
note ``# end: why; N samples in, M filtered rows out``. A status line on stderr, at
most once per second, shows the sample rate achieved, lost samples, rejected outliers and the
CPU use of this process. On a terminal the screen stays readable: with ``--serve`` or ``--udp``
the rows are not printed there unless asked (``--rows`` or ``--out -``: they are watched in the
view), so the line that says where the view is stays in sight; and where rows are printed on the
terminal the status comes as whole lines between them, never inside one. Ctrl-C, SIGTERM or SIGHUP stops cleanly (exit 0). The --out file takes its name
at its first flush with a filtered row (:class:`~gyrofilter.cli.live.LiveOutput`): a run that fails
before it (the device failing, the calibration refused because the sensor moved, any error) leaves
no file and an existing one (--force) as it was, so that the same command can be run again.
"""
import contextlib
import json
import sys
import time

import numpy as np

from .. import __version__
from ..errors import FilterDiverged, SampleError, SettingsError
from ..recording import ACCEL_COLUMNS, COLUMNS, END_NOTE, FILTERED_FROM_KEY, INPUT_RATE_KEY, T_FROM_KEY, accel_header, dps_header, header_text, note_line
from ..recording.writer import exact_format
from . import console, filtering, live, options, outlets



def add_arguments(parser):
    parser.description = (
        "Filter a live source in real time: filtered rates (deg/s) as CSV (recording format v1) on "
        "stdout or to --out, a status line on stderr once per second."
    )
    live.add_source_arguments(parser)
    parser.add_argument("--out", metavar="FILE", type=options.file_name, help="write the filtered rates to this recording (" + options.RECORDING_FILE_HELP + ") instead of stdout; - for stdout")
    parser.add_argument("--rows", action="store_true", help="print the rows on stdout also when it is a terminal and "
                                                           "--serve or --udp show them (the default there: not printed)")
    options.add_force_argument(parser)
    parser.add_argument("--quiet", action="store_true", help="no status line")
    filtering.add_filter_arguments(parser)
    outlets.add_arguments(parser)


#: why a run whose rows go to stdout stopped when that stream's reader went away
READER_GONE = "stdout was closed by its reader"


class _TextOut:
    """Recording format v1 as text on a stream (stdout), flushed by the caller; with ``stream``
    None the rows are only counted (a terminal whose rows a view shows). A failed write (a disk
    that fills under ``run > out.csv``) is an OSError naming ``stdout``, and the close after it
    says how many rows went out whole (those of the flushes before it), as a file's does."""

    path = "stdout"  # what a failed write names; no file to keep or remove after a failure

    def __init__(self, stream, header, columns, formats):
        self.stream = stream
        self.formats = formats  # a %-format per column, None for exact (as RecordingWriter's)
        self.rows_written = self.rows_flushed = 0
        self.write_failed = False  # an error writing stdout ends the command as it is
        self.reader_gone = False  # stdout's reader went away (``| head``): the run stops, as at Ctrl-C
        self._write(header_text(header, columns, "stdout"))
        self.flush()

    def _write(self, text):
        if self.stream is not None:
            with self._named():
                self.stream.write(text)

    @contextlib.contextmanager
    def _named(self):
        """An OSError of the stream (the console's, :class:`~gyrofilter.cli.console.ReaderAwareStream`,
        which names ``stdout``) marks the write failed; a closed reader (``console.stdout_reader_gone``) sets
        ``reader_gone`` and ends the printing, so that the run stops as a user's stop does (the
        calibration saved, the summary said: it ended with exit 0 and no word, ``--save-calibration``
        not written)."""
        try:
            yield
        except OSError:
            self.write_failed = True
            raise
        if console.stdout_reader_gone():
            self.reader_gone, self.stream = True, None

    def write(self, rows):
        self.rows_written += len(rows)
        if self.stream is not None:
            fmt = ",".join(f if f is not None else exact_format(rows[:, i]) for i, f in enumerate(self.formats))
            self._write("".join(fmt % tuple(r) + "\n" for r in rows.tolist()))

    def note(self, text):
        self._write(note_line(text))

    def flush(self):
        if self.stream is not None:
            with self._named():
                self.stream.flush()
        self.rows_flushed = self.rows_written

    def close(self, failed):
        if self.write_failed:  # flushing again would fail again
            return f"kept the first {self.rows_flushed} filtered rows" if self.rows_flushed else "no filtered row was kept"
        self.flush()
        return ""


def run(args):
    live.check_duration(args.duration)
    live.check_outputs([_out_file(args), args.save_calibration], args.source, [args.calibration, args.temp_model],
                       args.force)
    with outlets.Outlets.open(args) as sinks:  # --serve, --udp: a bad value is refused before any output
        source = live.open_from_args(args)
        try:
            return _run(args, source, sinks)
        finally:
            source.close()


def _run(args, source, sinks):
    head = source.header
    filtering.refuse_filtered_output(head, f"source {args.source}")
    cols = source.columns
    t_idx = cols.index("t")
    filt = filtering.make_filter(args, source.sample_rate_hz)
    temp_idx = cols.index("temp") if "temp" in cols else None
    filtering.check_temperature(filt, temp_idx is not None, f"source {args.source}")
    block = filt.settings.block_len
    sinks.start(args.source, source.sample_rate_hz, filt)
    out_header = dps_header({
        "description": f"gyrofilter {__version__} run: filtered rates, preset {filt.preset}, block of {block} samples; t = time of the block's last sample",
        "live_source": args.source,
        FILTERED_FROM_KEY: args.source,
    }, filt.output_rate_hz)
    for key in ("sensor", "chip_id", "full_scale_dps", "dlpf_cfg", "start_time_utc", T_FROM_KEY,
                "simulated_seed", "simulated_duration_s", "simulated_model"):
        if key in head:
            out_header[key] = head[key]
    out_header[INPUT_RATE_KEY] = head["sample_rate_hz"]
    if args.calibration is not None:  # the bias is known from the start: the header names it and its file, as replay's
        out_header["bias_dps"] = json.dumps(list(filt.bias_dps))
        out_header["calibration_from"] = args.calibration
    # the source's accelerometer, carried along raw (the filter is a gyro filter): each row gets the
    # ax, ay, az of its block's last sample, the one whose t it has, exactly as the source gave them
    accel_idx = [cols.index(c) for c in ACCEL_COLUMNS] if all(c in cols for c in ACCEL_COLUMNS) else []
    out_header.update(accel_header(head) if accel_idx else {})
    columns = list(COLUMNS) + (list(ACCEL_COLUMNS) if accel_idx else [])
    formats = filtering.ROW_FORMATS + [None] * len(accel_idx)  # None: exact, as record writes them
    out_file = _out_file(args)
    rows_on_terminal = out_file is None and sys.stdout.isatty()
    if out_file:
        writer = live.LiveOutput(out_file, out_header, columns, formats, "filtered row")
    elif rows_on_terminal and sinks.show_rows and args.out is None and not args.rows:
        writer = _TextOut(None, out_header, columns, formats)
        console.say(f"gyrofilter run: the rows are not printed on this terminal ({sinks.show_rows} shows them); "
                    "--rows or --out - prints them, --out FILE keeps them")
        rows_on_terminal = False
    else:
        writer = _TextOut(sys.stdout, out_header, columns, formats)
    loop = live.LiveLoop(source, args.duration)
    status = live.Status(not args.quiet, source.sample_rate_hz, whole_lines=rows_on_terminal)
    last_flush = time.monotonic()
    try:
        with loop:
            while (step := loop.next()) is not None:
                rows, notes = step
                for text in notes:
                    writer.note(text)
                if len(rows):
                    was_calibrating = filt.calibrating
                    temps = None if temp_idx is None else rows[:, temp_idx]
                    gyro = source.gyro_dps(rows)
                    blocks_out, diverged = filt.blocks_out, None
                    try:
                        t_out, out = filt.filter_timed(gyro, rows[:, t_idx], temps)
                    except SampleError as exc:  # a sample beyond the filter's range: name the source and the sample
                        raise SettingsError(f"source {args.source}: sample {filt.samples_in + exc.row}: {exc.reason}") from None
                    except FilterDiverged as exc:  # its rows before that one go out, then the run stops
                        t_out, out, diverged = exc.t_rows_s, exc.rows, exc
                    if was_calibrating and not filt.calibrating and filt.bias_dps is not None:
                        writer.note(filtering.calibrated_note(filt))
                    if len(out):
                        ends = filt.block_end_indices(filt.blocks_out - blocks_out)[:len(out)] - (filt.samples_in - len(rows))
                        writer.write(np.column_stack([t_out, out, rows[ends][:, accel_idx]]))
                    sinks.feed(rows[:, t_idx], gyro, temps, t_out, out, samples_in=loop.samples,
                               rows_out=writer.rows_written, source=source, filt=filt)
                    if diverged is not None:
                        raise SettingsError(f"source {args.source}: sample {diverged.sample}: {diverged.reason}")
                now = time.monotonic()
                if now - last_flush >= live.FLUSH_INTERVAL_S or not out_file:
                    writer.flush()
                    last_flush = now
                if isinstance(writer, _TextOut) and writer.reader_gone:
                    loop.stop(READER_GONE)
                if status.due():
                    state = "calibrating" if filt.calibrating else f"{writer.rows_written} filtered rows"
                    status.show(loop.samples, f"{state}, lost {loop.lost_samples}, "
                                              f"rejected outliers {int(filt.rejected.sum())}", loop.first_wall)
            status.end()
            for text in loop.pop_notes():
                writer.note(text)
            writer.note(f"{END_NOTE}{loop.reason()}; {loop.samples} samples in, {writer.rows_written} filtered rows out")
        with contextlib.ExitStack() as files:  # the live output stays even if this fails: its rows are the data
            saved = filtering.save_calibration(args.save_calibration, filt, files)
        if saved:
            console.say(f"saved the calibration to {args.save_calibration}")
    except BaseException as exc:
        live.close_after_failure(writer, exc, "gyrofilter run")
        raise
    nothing = filtering.nothing_filtered(filt)  # it stopped before the first row: an output without rows goes
    left = writer.close(loop.failed() or nothing is not None)
    reason = loop.reason()
    bias = "" if filt.bias_dps is None else f" bias {console.bias_text(filt.bias_dps)};"
    console.say(
        f"gyrofilter run: {reason}",
        f"  {loop.samples} samples in, {writer.rows_written} filtered rows out ({filt.output_rate_hz:g} Hz);{bias} "
        f"rejected outliers {int(filt.rejected.sum())} (x, y, z: {', '.join(str(int(v)) for v in filt.rejected)})",
        f"  lost {loop.lost_samples} samples" + (f"; {live.source_summary(loop.stats)}" if live.source_summary(loop.stats) else ""),
        *([f"  {out_file}: {left}"] if left else []),
        *([f"  nothing filtered: it stopped {nothing}"] if nothing is not None else []),
    )
    filtering.warn_if_many_rejected(filt)
    if loop.failed():
        return live.EXIT_DISCONNECTED
    # a source that ended by itself before the first row is an error, as in replay; a user's stop is not
    return 2 if nothing is not None and not (loop.interrupted or loop.ended == READER_GONE) else 0


def _out_file(args):
    """The file of ``--out``, or None for stdout (no ``--out``, or ``--out -``)."""
    return None if args.out in (None, "-") else args.out
