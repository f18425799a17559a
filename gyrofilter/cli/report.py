"""gyrofilter report: one self-contained HTML file about a recording, to attach to a bug report or
to compare units with (docs/report.md).

    gyrofilter report RECORDING --out REPORT.html
    gyrofilter report --source SOURCE --duration S --out REPORT.html   # records first

The page (:mod:`gyrofilter.view.report`) shows the recording's summary, the warnings, the default
filter's effect, the Allan deviation with every coefficient and its interval, the gap
findings with their gain and the extended model, and where allan and gap disagree on a noise
term, why (:func:`gyrofilter.analysis.agreement.compare`). Its numbers are computed once, by the very
functions the commands call: :func:`gyrofilter.analysis.gap.pipeline.analyse_file` (``gap --json``'s document),
:func:`gyrofilter.cli.allan.analyse` (``allan --json``'s) and :class:`gyrofilter.cli.replay.Replay`
with replay's default options (its summary table); the page embeds those documents whole.

When allan refuses the record (gross errors without ``--keep-outliers``, too short) or the filter
cannot run on it (a filter's output, a record inside the calibration window), the report says so
in that section and among the warnings instead: the report of a moving or short record is still
a report. A recording that does not read is refused (exit 2), as every command refuses it.

With ``--source``, the source is recorded first (``record``'s loop and file: an interrupted recording
reads; Ctrl-C ends the recording early and the report covers what was recorded), to
``--recording-out`` or else beside the report (REPORT.csv for REPORT.html), and kept.
The report is written under a temporary name and takes its name when whole.
"""
import argparse
import contextlib
import os

from .. import __version__
from ..analysis.agreement import compare
from ..analysis.gap.pipeline import analyse_file
from ..analysis.noise.model import ACCELEROMETER_TERMS, GYROSCOPE_TERMS
from ..analysis.clipping import clipped
from ..errors import CalibrationError, GyroFilterError, SettingsError, one_line
from ..filter.calibration import without_settings
from ..inputs import parse_number
from ..recording import CHUNK_ROWS, iter_recording
from ..units import json_ready
from ..view.report import report_data, report_page
from . import allan, console, filtering, gap, live, options, outputs, record, replay, still

#: buckets of the filter's trace figure (:class:`~gyrofilter.streamstats.Envelope`: it keeps 100 to 200)
TRACE_BUCKETS = 200
#: what the source options other than --source mean only with it
_SOURCE_ONLY = {"duration": "--duration", "recording_out": "--recording-out", "gyro_unit": "--gyro-unit",
                "lsb_per_dps": "--lsb-per-dps", "sample_rate_hz": options.SAMPLE_RATE_OPTION}


def add_arguments(parser):
    parser.description = ("One self-contained HTML report of a recording (or of a source, recorded first): summary, "
                          "warnings, the default filter's effect, the Allan deviation and coefficients, the gap findings.")
    parser.add_argument("recording", nargs="?", metavar="RECORDING",
                        help="recording file (format v1, .csv or .csv.gz); or give --source to record one first")
    parser.add_argument("--out", required=True, metavar="REPORT.html", type=options.file_name,
                        help="the report to write (one HTML file, figures inline)")
    live.add_source_arguments(parser, required=False)
    parser.add_argument("--recording-out", metavar="FILE", type=options.file_name,
                        help="with --source: the recording to write and keep (default: beside --out, "
                             "REPORT.csv for REPORT.html; " + options.RECORDING_FILE_HELP + ")")
    parser.add_argument("--seed", type=options.whole_number, default=None, metavar="N",
                        help="no effect, kept for older scripts (as gap --seed)")
    parser.add_argument("--sims", type=options.whole_number, default=None, metavar="N",
                        help="baseline simulations of the gap analysis (as gap --sims)")
    still.add_keep_outliers_argument(parser)
    console.add_progress_argument(parser)
    options.add_force_argument(parser)


def default_recording_path(out):
    """Where ``report --source`` keeps its recording without --recording-out: beside the report,
    its name with ``.csv`` for the extension (``unit1.html`` -> ``unit1.csv``)."""
    return os.path.splitext(out)[0] + ".csv"


def run(args):
    gap.check_options(args.seed, args.sims)
    _check_source_options(args)
    progress = console.ProgressLines(args.progress, "report")
    if args.source is not None:
        path = args.recording_out or default_recording_path(args.out)
        live.check_duration(args.duration)
        live.check_outputs([args.out, path], args.source, force=args.force)  # before the recording
        status = _record_first(args, path, progress.every_line)
        if status:
            return status
    else:
        path = args.recording
        _check_read_again(path)
        outputs.check_outputs([args.out], [path], args.force)
    data, envelopes = compute(path, sims=args.sims, keep_outliers=args.keep_outliers,
                              warn=console.say_warning, progress=progress)
    page = report_page(data, *envelopes)
    with outputs.replacing(args.out) as tmp:
        outputs.write_text(tmp, page)
    console.say(f"wrote {args.out} ({len(page.encode('utf-8')) / 1024:.0f} kB, {len(data['warnings'])} warning(s)"
                + (f"; the recording is {path}" if args.source is not None else "") + ")")
    return 0


def compute(path, *, sims, keep_outliers, warn, progress):
    """The report's data (:func:`gyrofilter.view.report.report_data`) and the filter's (raw,
    filtered) envelopes ((None, None) when it did not run) of the recording ``path``: the gap
    analysis (a recording that does not read raises here), allan and replay's default filter,
    each computed by its command's function. ``warn(text)``: each warning as it is found (also
    collected, in order, in the data); ``progress(text)``: the steps."""
    found = []

    def warned(text):
        if text not in found:
            found.append(text)
            warn(text)

    rec, gap_doc = analyse_file(path, n_sims=sims, warn=warned, progress=progress)
    still.check_mean(path, rec, True, warn=warned)  # a moving record's report is made too: its page says so
    clip = clipped(rec.gyro_dps, _full_scale_dps(rec.header, warned), rec.lsb_per_dps if rec.gyro_unit == "lsb" else None)
    if clip:
        warned(clip)
    recording = {"name": path, "header": dict(rec.header), "samples": len(rec), "duration_s": rec.duration_s,
                 "t_gaps": rec.t_gaps}
    del rec  # the analyses below read the file again, in chunks
    progress("allan")
    allan_doc = allan_error = None
    try:
        _, results, allan_doc, accel = allan.analyse(path, keep_outliers=keep_outliers, warn=warned, allow_large_mean=True,
                                                        skip_constant=True)
    except GyroFilterError as exc:
        allan_error = one_line(exc)
        warned(f"no Allan deviation: {allan_error}")
    else:
        for prefix, sensor, terms in (("", results, GYROSCOPE_TERMS), ("a", accel or {}, ACCELEROMETER_TERMS)):
            for a, r in sensor.items():
                for text in r.warnings:
                    warned(text)
                unresolved = allan.unresolved_text(r, allan.MIN_CLUSTERS, terms)
                if unresolved:
                    warned(f"axis {prefix}{a}: {unresolved} (the table gives their upper bounds)")
    progress("filter")
    filtered, filter_error = _filter(path)
    if filter_error:
        warned(f"not filtered: {filter_error}")
    gap_doc = json_ready(gap_doc)
    data = report_data(recording=json_ready(recording), allan=allan_doc, gap=gap_doc,
                       filter_summary=filtered.summary() if filtered else None, warnings=found,
                       options={"sims": sims, "keep_outliers": keep_outliers}, version=__version__,
                       allan_error=allan_error, filter_error=filter_error,
                       allan_and_gap=compare(allan_doc, gap_doc) if allan_doc is not None else [])
    envelopes = (filtered.raw_envelope, filtered.filtered_envelope) if filtered else (None, None)
    return data, envelopes


def _filter(path):
    """(the finished :class:`~gyrofilter.cli.replay.Replay` of ``path`` with replay's default filter
    options, None) or (None, why the filter could not run on it)."""
    defaults = argparse.ArgumentParser(add_help=False)
    filtering.add_filter_arguments(defaults)
    chunks = iter_recording(path, chunk_rows=CHUNK_ROWS)
    try:
        with contextlib.closing(chunks):
            head = next(chunks)
            filtering.refuse_filtered_output(head.header, path)
            filt = filtering.make_filter(defaults.parse_args([]), head.sample_rate_hz)
            run = replay.Replay(path, head, filt, plot=True, plot_buckets=TRACE_BUCKETS)
            replay.feed_recording(run, chunks, way_through=f"report filters with the default settings; replay takes "
                                                           f"{replay.CALIBRATION_WAYS}")
    except CalibrationError as exc:  # its way through a setting is replay's and run's (--set): a report takes none
        return None, one_line(without_settings(exc, "report filters with the default settings"))
    except GyroFilterError as exc:
        return None, one_line(exc)
    return run, None


def _full_scale_dps(header, warn):
    """The header's ``full_scale_dps`` (deg/s), or None when it has none or one that is not a
    positive number (said through ``warn``: clipping is then not checked)."""
    text = header.get("full_scale_dps")
    if text is None:
        return None
    try:
        return parse_number(text, "the header's full_scale_dps", low=0.0, low_open=True)
    except SettingsError as exc:
        warn(f"{exc}; clipping not checked")
        return None


def _check_read_again(path):
    """Refuse a RECORDING that is no regular file: the report reads it three times (gap, allan,
    the filter), and a pipe (``<(zcat rec.csv.gz)``) gives its text once: the later readers found
    it empty and the report lost its Allan and filter sections to warnings saying 'empty file'."""
    if os.path.exists(path) and not os.path.isfile(path):
        raise SettingsError(f"{path}: not a regular file (a pipe?): the report reads the recording three times "
                            "(gap, allan, the filter); save it to a file first")


def _check_source_options(args):
    """RECORDING or --source, one of them; the recording options only with --source."""
    if (args.recording is None) == (args.source is None):
        raise SettingsError("give a RECORDING or --source SOURCE (to record one first), one of them")
    if args.source is None:
        for key, option in _SOURCE_ONLY.items():
            if getattr(args, key) is not None:
                raise SettingsError(f"{option} records a source first: it needs --source (a RECORDING is read as it is)")


def _record_first(args, path, show):
    """Record ``args.source`` to ``path`` (``record``'s loop). Returns 0, or the exit status when
    the device failed (what it gave is kept, and said)."""
    length = f"for {args.duration:g} s" if args.duration is not None else "until Ctrl-C"
    console.say(f"gyrofilter report: recording {args.source} {length} to {path}: keep the sensor still (do not touch "
                "it or what it stands on); Ctrl-C ends the recording early")
    source = live.open_from_args(args)
    try:  # no sample recorded: record says so (SettingsError), and there is nothing to report
        status = record.record(source, args.source, path, args.duration, show_status=show,
                               command="gyrofilter report: recording")
    finally:
        source.close()
    if status:
        console.say(f"gyrofilter report: no report: the recording stopped on a device failure; what it holds is in "
                    f"{path} (gyrofilter report {path} --out {args.out})")
    return status

