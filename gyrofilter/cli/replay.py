"""gyrofilter replay: filter a recording with the real-time pipeline and summarise it.

The recording is read, filtered and written a chunk at a time (:func:`gyrofilter.recording.iter_recording`),
so memory does not grow with its length: the summary's means and standard deviations are
running ones (:class:`gyrofilter.streamstats.RunningMoments`) and ``--plot`` draws min/max
envelopes of at most 4000 buckets per series (:class:`gyrofilter.streamstats.Envelope`).
Every filtered row is time-stamped with the time of its block's last input sample (the
recording's ``t`` column when it has one), in ``--out`` and on stdout with ``--realtime`` alike;
stdout is then a format-v1 recording (the summary goes to stderr), and when its reader goes
away (``| head``) the rest is filtered without pacing, so that ``--out`` is still complete.

``--smooth`` replaces the real-time output by the forward-backward smoother
(:mod:`gyrofilter.filter.smoother`): the same rows, each estimated from the whole recording. It keeps
the block means of the recording in memory (12 floats per block, and 3 for the output) and writes once the end is read.
"""
import contextlib
import json
import sys
import time
from importlib import resources

import numpy as np

from .. import plots
from ..errors import FilterDiverged, RecordingError, SampleError, SettingsError
from ..filter.settings import SETTING_NAMES
from ..filter.smoother import SMOOTHABLE_PRESETS, Smoother
from ..recording import CHUNK_ROWS, COLUMNS, FILTERED_FROM_KEY, INPUT_RATE_KEY, T_FROM_KEY, RecordingWriter, dps_header, format_number, header_text, iter_recording, note_line, warn_about_gaps
from ..streamstats import Envelope, RunningMoments
from ..units import json_ready
from . import console, filtering, options, outputs

BUNDLED = "mpu6050_static_100s.csv.gz"
OUT_COLUMNS = list(COLUMNS)


def add_arguments(parser):
    parser.add_argument("recording", nargs="?", help=f"recording file (format v1, .csv or .csv.gz); default: the bundled {BUNDLED}")
    parser.add_argument("--out", metavar="FILE", type=options.file_name, help="write the filtered series as a recording (" + options.RECORDING_FILE_HELP + ")")
    parser.add_argument("--plot", metavar="PNG", type=options.file_name, help="draw raw and filtered rates per axis, as min/max bands on long recordings (needs matplotlib)")
    parser.add_argument("--realtime", action="store_true", help="pace the filter at the recording's sample rate and print each filtered row as it is produced "
                                                                    "(stdout is then a recording, format v1; the summary goes to stderr)")
    parser.add_argument("--smooth", action="store_true",
                        help="offline: smooth with the forward-backward smoother over the adaptive Kalman filter "
                             f"(each row from the whole recording; presets {', '.join(SMOOTHABLE_PRESETS)})")
    filtering.add_filter_arguments(parser)
    options.add_force_argument(parser)


def run(args):
    path = args.recording or str(resources.files("gyrofilter") / "data" / BUNDLED)
    outputs.check_outputs([args.out, args.plot, args.save_calibration], [path, args.calibration, args.temp_model], args.force)
    if args.plot:
        plots.check_figure_path(args.plot)
    if args.smooth and args.realtime:
        raise SettingsError("--smooth needs the whole recording before the first row; it cannot run with --realtime")
    chunks = iter_recording(path, chunk_rows=CHUNK_ROWS)
    head = next(chunks)
    filtering.refuse_filtered_output(head.header, path)
    filt = filtering.make_filter(args, head.sample_rate_hz)
    filtering.check_temperature(filt, "temp" in head.names, path)
    replay = Replay(path, head, filt, plot=bool(args.plot), smoother=Smoother(filt) if args.smooth else None,
                    calibration_from=args.calibration)
    with contextlib.ExitStack() as files:
        if args.out:
            replay.out_path, replay.out_name = files.enter_context(outputs.replacing(args.out)), args.out
            files.callback(replay.close)
        if args.realtime:  # stdout is a recording (format v1) too
            replay.print_rows(header_text(replay.stdout_header(), OUT_COLUMNS, "stdout").rstrip("\n"))
        feed_recording(replay, chunks, args.realtime)
        replay.close()
        # every output goes through replacing(): all land when the command succeeds, none when it fails
        if args.plot:
            plots.plot_filtered(files.enter_context(outputs.replacing(args.plot)), replay.raw_envelope,
                                replay.filtered_envelope, title=f"{args.recording or BUNDLED + ' (bundled)'} ({raw_words(filt, args.calibration)})")
        saved = filtering.save_calibration(args.save_calibration, filt, files)
    console.print_warnings(head.warnings)
    warn_about_gaps(head, "the filter treats the samples as uniform", console.say_warning)
    with contextlib.redirect_stdout(sys.stderr) if args.realtime else contextlib.nullcontext():  # stdout has the rows
        console.print_summary(path, head, filt, replay.raw, replay.filtered, calibration_from=args.calibration, smoothed=args.smooth)
    filtering.warn_if_many_rejected(filt)
    if args.realtime and not replay.stdout_open:
        console.say_warning(f"stdout was closed by its reader; {replay.lines_printed} lines were written to it "
                            f"({replay.rows_printed} of them filtered rows): the rest of the rows were filtered (the "
                            "summary counts them) but not printed")
    if saved:
        console.say(f"saved the calibration to {args.save_calibration}")
    if args.out:
        console.say(f"wrote {replay.filtered.count} filtered rows to {args.out}")
    if args.plot:
        console.say(f"drew {args.plot}")
    return 0


#: the options that let a recording shorter than the start-up calibration window be filtered
CALIBRATION_WAYS = "a shorter --calibration-s or a saved calibration (--calibration FILE)"


def feed_recording(replay, chunks, realtime=False, way_through=f"give {CALIBRATION_WAYS}"):
    """Feed the rest of the recording's ``chunks`` (:func:`~gyrofilter.recording.iter_recording`
    after its head) through ``replay`` (a :class:`Replay`, paced with ``realtime``) and finish it.
    RecordingError naming the file's line of a sample the filter refuses, and when nothing was
    filtered (:func:`_refuse_nothing_filtered`; ``way_through``: what its message advises where the
    calibration window took the samples, the words of the caller's command)."""
    path, head, filt = replay.path, replay.head, replay.filt
    for chunk in chunks:
        try:
            replay.feed(head.gyro_dps(chunk), head.t_s(chunk, filt.samples_in), head.column(chunk, "temp"), realtime)
        except SampleError as exc:  # the filter refused a sample (beyond its range): name the file's line
            raise RecordingError(f"{path}: line {head.line_of_row(filt.samples_in + exc.row)}: {exc.reason}") from None
        except FilterDiverged as exc:  # the filter's row of the block that ends on this line
            raise RecordingError(f"{path}: line {head.line_of_row(exc.sample)}: {exc.reason}") from None
    _refuse_nothing_filtered(path, head, filt, way_through)
    replay.finish()


def _refuse_nothing_filtered(path, head, filt, way_through):
    """A recording without samples, or one that ends before the filter's first row (inside the
    start-up calibration window, or less than a block after it: :func:`filtering.nothing_filtered`),
    has nothing to filter: an error (no output is kept), not an empty result."""
    if filt.samples_in == 0:
        raise RecordingError(f"{path}: no samples (the file has a header only); nothing to filter")
    where = filtering.nothing_filtered(filt)
    if where:
        advice = (f": {way_through}" if filt.calibrating or filt.samples_in > filt.pending_samples else "")  # a window took samples
        raise RecordingError(f"{path}: its {filt.samples_in} samples ({filt.samples_in / head.sample_rate_hz:.2f} s) end "
                             f"{where}; nothing filtered{advice}")


def raw_words(filt, calibration_from):
    """What replay's plot calls its raw curve: the samples minus the bias the filter ``filt`` removed (from its start-up
    calibration, or loaded from ``calibration_from``), or the plain samples without a calibration."""
    if filt.calibration is None:
        return "raw"
    return "raw minus " + ("the bias loaded from " + calibration_from if calibration_from else "start-up bias")


class Replay:
    """Feeds chunks to the filter and passes its rows on: to the output file, the running
    statistics and the plot envelopes (with ``plot``: at most ``plot_buckets`` buckets each, or
    :class:`~gyrofilter.streamstats.Envelope`'s default). ``raw`` are the samples of the blocks that
    produced a row (calibration and an unfinished last block left out). With a ``smoother`` the
    rows are passed on by :meth:`finish`, smoothed, with the time stamps collected on the way."""

    def __init__(self, path, head, filt, plot, smoother=None, calibration_from=None, plot_buckets=None):
        self.path, self.head, self.filt, self.smoother = path, head, filt, smoother
        self.calibration_from = calibration_from
        self._row_times = []
        self.raw = RunningMoments(3)
        self.filtered = RunningMoments(3)
        self.raw_envelope = self._envelope(plot_buckets) if plot else None
        self.filtered_envelope = self._envelope(plot_buckets) if plot else None
        self.out_path = None  # the temporary file written, for the user's out_name
        self.out_name = None
        self._writer = None
        self._tail = np.empty((0, 3))  # the samples waiting in the filter's unfinished block
        self._t_tail = np.empty(0)
        self._wall_start = None
        self.stdout_open = True  # False once the reader of --realtime's rows went away (| head)
        self.lines_printed = self.rows_printed = 0  # lines written to stdout, header lines included; of them, rows

    @staticmethod
    def _envelope(buckets):
        return Envelope(3) if buckets is None else Envelope(3, buckets)

    def summary(self):
        """The numbers of replay's summary table (:func:`~gyrofilter.cli.console.print_summary`),
        JSON-ready: the preset, rates (Hz), the start-up bias (deg/s, None without a calibration) and
        the gross errors its window left out per axis,
        rows, and per axis the raw and filtered mean and standard deviation (deg/s; None where
        undefined), their std ratio and the rejected samples."""
        filt, raw, filtered = self.filt, self.raw, self.filtered
        cal = filt.calibration
        with np.errstate(divide="ignore", invalid="ignore"):  # undefined (None) where either does not vary
            ratio = np.where((raw.std > 0) & (filtered.std > 0), raw.std / filtered.std, np.nan)
        return json_ready({
            "preset": filt.preset, "sample_rate_hz": filt.sample_rate_hz, "output_rate_hz": filt.output_rate_hz,
            "samples_in": filt.samples_in, "rows_out": filtered.count,
            "bias_dps": None if cal is None else list(cal.bias_dps),
            "calibration_samples": None if cal is None else cal.samples,
            "calibration_rejected": None if cal is None else list(cal.rejected),
            "raw_mean_dps": raw.mean, "raw_std_dps": raw.std, "filtered_mean_dps": filtered.mean,
            "filtered_std_dps": filtered.std, "std_ratio": ratio, "rejected": [int(n) for n in filt.rejected]})

    def feed(self, gyro, t_s, temps, realtime):
        filt = self.filt
        if realtime:
            t_rows, rows = self._paced(gyro, t_s, temps)
        else:
            t_rows, rows = filt.filter_timed(gyro, t_s, temps)
        window = np.concatenate([self._tail, gyro])
        plotting = self.raw_envelope is not None
        t_window = np.concatenate([self._t_tail, t_s]) if plotting else None
        keep = filt.pending_samples
        if len(rows):
            # the rows' blocks: the len(rows) * block_len samples before those still pending
            used_at = slice(len(window) - keep - len(rows) * filt.settings.block_len, len(window) - keep)
            used = window[used_at]
            self.raw.add(used)
            if plotting:
                self.raw_envelope.add(t_window[used_at], used - np.asarray(filt.bias_dps))
            if self.smoother is None:
                self._pass_on(t_rows, rows)
            else:
                self._row_times.append(t_rows)
        self._tail = window[len(window) - keep:].copy()
        if plotting:
            self._t_tail = t_window[len(window) - keep:].copy()

    def _paced(self, gyro, t_s, temps):
        """Feed samples one by one at the recording's rate, printing rows as they come:
        (t_rows_s, rows) as :meth:`GyroFilter.filter_timed` returns them."""
        filt = self.filt
        rows, t_rows = [], []
        if self._wall_start is None:
            self._wall_start = time.monotonic()
        sample_rate_hz = filt.sample_rate_hz
        temps = [None] * len(gyro) if temps is None else temps.tolist()
        for sample, temp, t in zip(map(tuple, gyro.tolist()), temps, t_s.tolist()):
            delay = self._wall_start + filt.samples_in / sample_rate_hz - time.monotonic()
            if delay > 0 and self.stdout_open:
                time.sleep(delay)
            calibrating = filt.calibrating
            row = filt.update(sample, temp)
            if calibrating and not filt.calibrating:  # the bias the --out header has, as run notes it
                self.print_rows(note_line(filtering.calibrated_note(filt)).rstrip("\n"))
            if row is not None:  # a row comes out when its block's last sample, this one, goes in
                rows.append(row)
                t_rows.append(t)
                self.print_rows(filtering.ROW_FORMAT % (t, *row), rows=1)
        return np.array(t_rows, dtype=float), np.array(rows).reshape(-1, 3)

    def print_rows(self, text, rows=0):
        """Print ``text`` (one line or several, ``rows`` of them filtered rows) on stdout at once; when its
        reader went away (``| head``), stop printing and pacing, and finish the rest (the --out file,
        the summary) without them. The lines and rows written while the reader was there are counted."""
        if not self.stdout_open:
            return
        try:
            print(text, flush=True)
        except OSError as exc:  # a full disk under `> out.csv`: named, as run names it ("[Errno 28]" alone named nothing)
            raise OSError(exc.errno, f"{exc.strerror or exc}; {self.lines_printed} lines printed before it",
                          "stdout") from None
        if console.stdout_reader_gone():
            self.stdout_open = False
        else:
            self.lines_printed += text.count("\n") + 1
            self.rows_printed += rows

    def _pass_on(self, t_s, rows):
        self.filtered.add(rows)
        self._write(t_s, rows)
        if self.filtered_envelope is not None:
            self.filtered_envelope.add(t_s, rows)

    def _write(self, t_s, rows):
        if self.out_path is None:
            return
        if self._writer is None:  # the header names the bias, known once the calibration is done
            self._writer = RecordingWriter(self.out_path, self._out_header(), OUT_COLUMNS, formats=filtering.ROW_FORMATS,
                                           flush_interval_s=None, fsync=False, name=self.out_name)
        self._writer.write(np.column_stack([t_s, rows]))

    def _out_header(self):
        filt = self.filt
        return dps_header({
            "sensor": self.head.header.get("sensor", "unknown"),
            FILTERED_FROM_KEY: self.path,
            "filter_preset": filt.preset,
            **({"smoothed": "forward-backward (two-filter) smoother over the whole recording"} if self.smoother else {}),
            "filter_settings": json.dumps({k: getattr(filt.settings, k) for k in SETTING_NAMES}, separators=(",", ":")),
            "bias_dps": json.dumps(list(filt.bias_dps or ())),
            **({"calibration_rejected": json.dumps([int(r) for r in filt.calibration.rejected])}
               if filt.calibration is not None else {}),
            **({"calibration_from": self.calibration_from} if self.calibration_from else {}),
            "t_meaning": "time of the last input sample of each block (s)",
            INPUT_RATE_KEY: format_number(filt.sample_rate_hz),
            **({T_FROM_KEY: self.head.header[T_FROM_KEY]} if T_FROM_KEY in self.head.header else {}),
        }, filt.output_rate_hz)

    def stdout_header(self):
        """The header of the --out file but the bias, which is known only once the calibration is done."""
        return {k: v for k, v in self._out_header().items() if k not in ("bias_dps", "calibration_rejected")}

    def finish(self):
        """Smooth and pass on the rows (with a smoother); write the output's header even when no
        row came out."""
        if self.smoother is not None and self._row_times:
            t_s, rows = np.concatenate(self._row_times), self.smoother.smooth()
            for start in range(0, len(rows), CHUNK_ROWS):  # formatted a chunk at a time, as without --smooth
                self._pass_on(t_s[start:start + CHUNK_ROWS], rows[start:start + CHUNK_ROWS])
        self._write(np.empty(0), np.empty((0, 3)))

    def close(self):
        if self._writer is not None:
            self._writer.close()
