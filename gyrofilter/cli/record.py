"""gyrofilter record: log a live source to a recording file (format v1) that survives interruptions.

The file gets the source's header (sensor, chip id, full scale, LSB per deg/s, DLPF, sample
rate, start time, ...), then the samples; gaps and other events of the source become annotation
lines (``# gap: 37 samples lost before t=12.34 s ...``). Data are flushed (and fsync'ed) at
least every ``live.FLUSH_INTERVAL_S``: after a crash or a pulled plug at most that much is lost and
the file still reads. Ctrl-C (SIGINT), SIGTERM and SIGHUP stop the recording cleanly (exit 0); a second
signal aborts at once (the file is still readable up to the last flush). The file takes its name
at its first flush with a sample (:class:`~gyrofilter.cli.live.LiveOutput`): a recording that fails
before its first sample (the device failing, any error) leaves no file and an existing one (--force)
as it was, so that the same command can be run again; a failed write (disk full, file size limit)
keeps the samples of the last flush, a file that reads, and exits with status 2 saying how many.
The output is never one of the source's files, and overwrites only a regular file, only with --force.
"""
import os
import sys
import time

from .. import __version__
from ..errors import SettingsError
from ..recording import END_NOTE
from . import console, live, options

# header keys first in this order, the rest as the source gives them
_HEADER_ORDER = ("sample_rate_hz", "gyro_unit", "lsb_per_dps", "accel_unit", "lsb_per_g", "sensor", "chip_id",
                 "full_scale_dps", "dlpf_cfg", "start_time_utc")


def add_arguments(parser):
    parser.description = (
        "Record a live source to a recording file (format v1, .csv or .csv.gz). Data are flushed "
        "at least twice a second; Ctrl-C, SIGTERM or SIGHUP ends the file cleanly (exit 0)."
    )
    live.add_source_arguments(parser)
    parser.add_argument("--out", required=True, metavar="FILE", type=options.file_name, help="recording to write (" + options.RECORDING_FILE_HELP + ")")
    options.add_force_argument(parser)
    shown = parser.add_mutually_exclusive_group()
    shown.add_argument("--progress", action="store_true", help="status line on stderr every second even when stderr is not a terminal")
    shown.add_argument("--quiet", action="store_true", help="no status line, even on a terminal (as run --quiet)")


def recording_header(source, spec):
    head = dict(source.header)
    head.setdefault("start_time_utc", time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
    head["live_source"] = spec
    head["recorded_by"] = f"gyrofilter {__version__} record"
    ordered = {k: head.pop(k) for k in _HEADER_ORDER if k in head}
    ordered.update(head)
    return ordered


def run(args):
    live.check_duration(args.duration)
    live.check_outputs([args.out], args.source, force=args.force)
    source = live.open_from_args(args)
    try:
        return record(source, args.source, args.out, args.duration,
                      show_status=args.progress or (sys.stderr.isatty() and not args.quiet))
    finally:
        source.close()


def record(source, spec, out, duration_s, *, show_status, command="gyrofilter record"):
    """Record the open ``source`` (opened from the SOURCE text ``spec``) to the recording ``out``
    until a stop signal, its end, a device failure or ``duration_s`` seconds (None: no limit),
    with a status line on stderr when ``show_status``; the summary goes to stderr, headed ``command``. Returns the
    exit status: 0, or ``live.EXIT_DISCONNECTED`` when the device failed (what it gave is kept).
    A recording of no sample (a ``duration_s`` shorter than one, a source that ends at once, a
    stop signal before the first) is not written, a file at ``out`` (``--force``) stays as it
    was, and SettingsError says so, naming the duration only where it ran out (else why the loop
    stopped): a header without data is not a recording any command reads."""
    header = recording_header(source, spec)
    columns = list(source.columns)
    loop = live.LiveLoop(source, duration_s)
    status = live.Status(show_status, loop.sample_rate_hz)
    wall0 = time.monotonic()
    writer = live.LiveOutput(out, header, columns, None, "sample")  # every value exactly as the source gave it
    try:
        with loop:
            last_flush = time.monotonic()
            dirty = False
            while (step := loop.next()) is not None:
                rows, notes = step
                for text in notes:
                    writer.note(text)
                if len(rows):
                    writer.write(rows)
                dirty = dirty or bool(notes) or bool(len(rows))
                now = time.monotonic()
                if dirty and now - last_flush >= live.FLUSH_INTERVAL_S:
                    writer.flush()
                    last_flush, dirty = now, False
                if status.due():
                    status.show(loop.samples, f"{loop.samples} recorded, {loop.lost_samples} lost",
                                loop.first_wall)
            status.end()
            for text in loop.pop_notes():
                writer.note(text)
            reason = loop.reason()
            writer.note(f"{END_NOTE}{reason}; {loop.samples} samples; " + (live.source_summary(loop.stats) or "no losses"))
    except BaseException as exc:
        live.close_after_failure(writer, exc, command)
        raise
    existed = os.path.lexists(out)
    empty = loop.samples == 0 and not loop.failed()
    left = writer.close(loop.failed() or empty)
    if empty:
        within = f" in --duration {duration_s:g} s" if loop.ended == live.DURATION_REACHED else f" ({reason})"
        counts = live.source_summary(loop.stats)  # lines received and refused: the notes saying why go with the file
        raise SettingsError(f"{spec}: no sample was recorded{within}{'; ' + counts if counts else ''}; "
                            + (f"{out} is left as it was" if existed else f"the empty {out} is not kept"))
    stats = loop.stats
    console.say(
        f"{command}: {reason}",
        f"  wrote {loop.samples} samples ({loop.span_s:.2f} s at {loop.sample_rate_hz:g} Hz, {time.monotonic() - wall0:.1f} s wall) to {out}",
        f"  lost {stats.get('lost_samples', 0)} samples" + (f"; {live.source_summary(stats)}" if live.source_summary(stats) else ""),
        *([f"  {out}: {left}"] if left else []),
    )
    return live.EXIT_DISCONNECTED if loop.failed() else 0
