"""Many recordings in one ``gyrofilter allan`` or ``gyrofilter gap`` command (``--fleet DIR``).

The shared command-line part of a fleet run (the work itself is :mod:`gyrofilter.analysis.fleet`):
expand the paths and globs, check every output before any work, run the files on local worker
processes (``--jobs``) or a Dask cluster (``--scheduler``), write each recording's reports as
it finishes, show progress over the files, then write ``fleet.csv`` and ``fleet.md`` and print
the units that stand out. Exit 0 when the command ran, even if some files failed (their rows
say why); 2 when nothing could be done (bad input before any work, or no recording analysed).
"""
import codecs
import contextlib
import csv
import glob
import gzip
import os
import time
import zlib

from ..analysis.fleet import runner, table, work
from ..analysis.still import NO_ACCEL_UNIT, NOT_STATIC
from ..errors import GyroFilterError, SettingsError
from ..recording import VERSION_KEY
from . import console, options, outputs

FLEET_CSV = "fleet.csv"
FLEET_MD = "fleet.md"
EXIT_NOTHING_DONE = 2


def add_arguments(parser):
    parser.add_argument("--fleet", "--out-dir", dest="fleet", metavar="DIR", type=options.file_name,
                        help="a fleet run: one report per recording in DIR, named after it, plus fleet.csv and "
                             "fleet.md (needed for more than one recording)")
    parser.add_argument("--jobs", type=options.whole_number, default=None, metavar="N",
                        help="with --fleet: recordings analysed at once on this machine (default: all cores; "
                             "each worker holds one recording in memory)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="with --fleet: run on the Dask cluster whose scheduler is at ADDRESS "
                             "(tcp://host:8786; needs the [cluster] extra)")


def expand(patterns):
    """The recordings named by ``patterns``, in order: a path as given, or, for a pattern with
    ``*``, ``?`` or ``[`` that is not itself a file, the files it matches (sorted; ``**`` spans
    folders). A pattern that matches nothing stays, so that its row says so. A file named twice
    is taken once."""
    paths, seen = [], set()
    for pattern in patterns:
        matches = [pattern]
        if glob.has_magic(pattern) and not os.path.exists(pattern):
            matches = sorted(glob.glob(pattern, recursive=True)) or [pattern]
        for path in matches:
            key = os.path.realpath(path)
            if key not in seen:
                seen.add(key)
                paths.append(path)
    return paths


#: the names a recording has (docs/formats.md section 1); another name is a recording only if its first line says so
RECORDING_SUFFIXES = (".csv", ".csv.gz")


def not_a_recording(path):
    """Why ``path`` is no recording, for a fleet to skip it (not counted, not failed), or None: a
    folder, or a file whose name ends in neither of :data:`RECORDING_SUFFIXES` and whose first line
    (gzip or not) is not the recording's version line ``# gyrofilter-recording:`` (a README, a
    licence beside the logs that ``recordings/*`` matches). A ``.csv`` or ``.csv.gz`` file that
    cannot be read, or a path that does not exist, is a recording that fails with its reason."""
    if os.path.isdir(path):
        return "a folder"
    if path.endswith(RECORDING_SUFFIXES) or not os.path.isfile(path):
        return None
    try:
        with open(path, "rb") as fh:
            start = fh.read(2)
        with (gzip.open if start == b"\x1f\x8b" else open)(path, "rb") as fh:
            first = fh.readline(200)
    except (OSError, EOFError, zlib.error):  # damaged gzip data raises zlib.error, no OSError
        return None  # the reader says what is wrong with it
    if first.removeprefix(codecs.BOM_UTF8).lstrip(b"# ").startswith(VERSION_KEY.encode()):  # a BOM: as the reader
        return None
    return f"not a recording (the name ends in neither {' nor '.join(RECORDING_SUFFIXES)} and the first line is not " \
           f"'# {VERSION_KEY}: 1')"


def single(args, paths):
    """The one recording of a single-file run; refuses several recordings, a glob that matches
    nothing, and ``--jobs`` or ``--scheduler`` without ``--fleet``."""
    if len(paths) > 1:
        raise SettingsError(f"{len(paths)} recordings: give --fleet DIR for one report per recording "
                            "plus the fleet table (fleet.csv, fleet.md)")
    for option in ("jobs", "scheduler"):
        if getattr(args, option) is not None:
            raise SettingsError(f"--{option} works on a fleet: give --fleet DIR")
    path = paths[0]
    if glob.has_magic(path) and not os.path.exists(path):
        raise SettingsError(f"{path}: no file matches")
    return path


def refuse_single_file_outputs(args, option_names):
    """Refuse the single-file output options (``--json`` ...) with ``--fleet``."""
    for option in option_names:
        if getattr(args, option.lstrip("-").replace("-", "_")):
            raise SettingsError(f"{option} names one file; with --fleet each recording's reports are written "
                                "to DIR, named after the recording")


def report_files(command):
    """The report files of one recording: (suffix, key of the result, writer of a path and the
    value); a fleet run of ``command`` writes each as DIR/NAME<suffix>."""
    allan = [(".allan.json", "allan", outputs.write_json_document), (".imu.yaml", "kalibr", outputs.write_text)]
    return ([(".gap.json", "gap", outputs.write_json)] if command == "gap" else []) + allan


def run(args, settings, paths):
    """Run the fleet (the module docstring); returns the exit code."""
    if args.jobs is not None and args.jobs < 1:
        raise SettingsError(f"--jobs must be at least 1, got {args.jobs}")
    if args.jobs is not None and args.scheduler:
        raise SettingsError("--jobs and --scheduler: give one (the cluster's workers set the parallelism)")
    outputs.check_output_folder(args.fleet, "--fleet")
    not_recordings = [(p, why) for p in paths if (why := not_a_recording(p))]
    paths = [p for p in paths if not any(p == q for q, _ in not_recordings)]
    if not paths:
        raise SettingsError(f"no recording among the {len(not_recordings)} path(s) given: "
                            f"{not_recordings[0][0]}: {not_recordings[0][1]}")
    names = table.unit_names(paths)
    files = report_files(settings.command)
    report_paths = [os.path.join(args.fleet, name + suffix) for name in names for suffix, _, _ in files]
    fleet_files = [os.path.join(args.fleet, FLEET_CSV), os.path.join(args.fleet, FLEET_MD)]
    outputs.check_outputs(report_paths + fleet_files, paths, args.force)
    earlier = _earlier_outputs(args.fleet, report_paths + fleet_files)
    outputs.may_remove(earlier)
    results = [work.failed(p, "no file matches") if glob.has_magic(p) and not os.path.exists(p) else None
               for p in paths]
    todo = [i for i, r in enumerate(results) if r is None]
    for i, r in enumerate(results):
        if r is not None:
            _drop_unwritten(args.fleet, names[i], files, r)
    if args.scheduler:
        where = f"the Dask cluster at {args.scheduler}"
        stream = runner.run_dask([paths[i] for i in todo], settings, args.scheduler)
    else:
        jobs = max(1, min(args.jobs or runner.default_jobs(), len(todo)))
        where = f"{jobs} worker process(es)"
        stream = runner.run_local([paths[i] for i in todo], settings, jobs)
    progress = console.ProgressLines(args.progress)  # in a log as well: the start and a line per recording
    t0 = time.perf_counter()
    unmatched = len(paths) - len(todo)
    progress(f"{settings.command}: {len(paths)} recording(s)" + (f", {unmatched} matching no file" if unmatched else "")
             + (f" ({len(not_recordings)} other path(s) skipped: not recordings)" if not_recordings else "")
             + f"; {len(todo)} on {where}", always=True)
    for r in results:
        if r is not None:
            progress(f"{settings.command}: FAILED: {r['error']}", always=True)
    finished = []  # (unit, whether it has reports) of the units whose reports this run put in place or removed
    try:
        written = _analyse_and_write(stream, todo, results, names, paths, files, args.fleet, settings.command,
                                     progress, t0, finished)
        rows = table.fleet_rows(names, results)
        stats = table.flag_units(rows)
        title = f"Fleet: gyrofilter {settings.command}, {len(paths)} recordings"
        outputs.remove_earlier(args.fleet, [os.path.basename(p) for p in earlier])  # DIR holds this run's outputs only
        with outputs.replacing(fleet_files[0]) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(table.fleet_csv(rows))
        with outputs.replacing(fleet_files[1]) as tmp, open(tmp, "w", encoding="utf-8") as fh:
            fh.write(table.fleet_markdown(rows, stats, title=title, not_recordings=not_recordings))
    except (OSError, GyroFilterError, KeyboardInterrupt) as exc:
        if not finished:  # the folder is as the earlier run left it
            raise
        done = {name for name, _ in finished}
        unreached = [os.path.join(args.fleet, name + suffix) for name in names if name not in done
                     for suffix, _, _ in files]
        raise _stopped(exc, args.fleet, finished, earlier + fleet_files + unreached) from None
    no_yaml = [f"{names[i]}: {w[len(work.NO_IMU_YAML):]}" for i, r in enumerate(results) for w in r["warnings"]
               if w.startswith(work.NO_IMU_YAML)]
    no_accel = [f"{names[i]}: {w[len(NO_ACCEL_UNIT):]}" for i, r in enumerate(results) for w in r["warnings"]
                if w.startswith(NO_ACCEL_UNIT)]
    return _summary(rows, fleet_files, written, time.perf_counter() - t0, no_yaml, no_accel, not_recordings)


def _analyse_and_write(stream, todo, results, names, paths, files, folder, command, progress, t0, finished):
    """Take each recording's result from ``stream`` as it comes, put its reports in ``folder`` (together) and
    say so; append (its unit name, whether it has reports) to ``finished`` once they are in place. Returns the
    number of reports written."""
    written = 0
    with contextlib.closing(stream):
        for done, (k, result) in enumerate(stream, 1):
            i = todo[k]
            results[i] = result
            before = written
            with contextlib.ExitStack() as reports:  # a recording's reports take their places together
                for suffix, key, write in files:
                    if result[key] is not None:
                        write(reports.enter_context(outputs.replacing(os.path.join(folder, names[i] + suffix))),
                              result[key])
                        written += 1
            _drop_unwritten(folder, names[i], files, result)
            finished.append((names[i], written > before))
            state = (f"{paths[i]}: done in {result['runtime_s']:.1f} s" if result["error"] is None
                     else f"NOT STILL, skipped: {result['error']}" if result["skipped"] else f"FAILED: {result['error']}")
            progress(f"{command} [{done}/{len(todo)}, {time.perf_counter() - t0:.0f} s] {state}", always=True)
    return written


def _stopped(exc, folder, finished, stale):
    """``exc``, a failure or Ctrl-C after this run put in place (or removed: a failed file's) the reports of the
    units ``finished`` ((unit, whether it has reports)) in ``folder``, with what the folder then holds: the earlier
    run's files that would stand beside them (``stale``: its fleet.csv and fleet.md, whose numbers are not these
    reports', and its reports of the units this run did not reach; there only under --force) are removed, so that
    the folder holds this run's finished reports alone, as a new folder would (attack pass 45: a rerun whose second
    unit's report hit a file-size limit left the first unit's new reports beside the earlier fleet.csv, 5x off, and
    the earlier reports of the rest, without a word). A file that appeared or changed meanwhile stays
    (:func:`~gyrofilter.cli.outputs.remove_earlier`)."""
    outputs.remove_earlier(folder, [os.path.basename(p) for p in stale])
    reported = [name for name, has_reports in finished if has_reports]
    holds = (f"{folder} holds this run's reports of {len(reported)} unit(s) only ({', '.join(reported[:3])}"
             f"{', ...' if len(reported) > 3 else ''})" if reported else f"{folder} holds no report of this run")
    tables = " and ".join(t for t in (FLEET_CSV, FLEET_MD) if not os.path.lexists(os.path.join(folder, t)))
    if isinstance(exc, KeyboardInterrupt):
        exc.not_written = [*getattr(exc, "not_written", []), f"{tables} ({holds}; run it again to finish)"]
        return exc
    said = f"{holds}{', without ' + tables if tables else ''}: run it again to finish"
    if isinstance(exc, OSError):
        return OSError(exc.errno, f"{exc.strerror or exc}; {said}", exc.filename)
    exc.args = (f"{exc.args[0] if exc.args else exc}; {said}", *exc.args[1:])
    return exc


def _earlier_outputs(folder, own):
    """The files in ``folder`` that an earlier fleet run wrote and this run (its outputs ``own``)
    does not: reports of the units the earlier fleet.csv lists (there only under --force, which
    its fleet.csv needs), removed when this run's fleet.csv is written, so that no report stands
    beside a table that does not list it. Any other file (a file of one's own, a recording, a
    folder, a link) is never removed: refused, named, before any work; partials aside."""
    try:
        names = sorted(os.listdir(folder))
    except (FileNotFoundError, NotADirectoryError):
        return []
    listed = set()
    with contextlib.suppress(OSError, UnicodeDecodeError, csv.Error):
        with open(os.path.join(folder, FLEET_CSV), encoding="utf-8", newline="") as fh:
            listed = table.listed_units(fh)
    own = {os.path.basename(p) for p in own}
    suffixes = [suffix for suffix, _, _ in report_files("gap")]  # every command's reports
    earlier = []
    for name in names:
        if name in own or outputs.is_partial(name):
            continue
        path = os.path.join(folder, name)
        unit = next((name[:-len(s)] for s in suffixes if name.endswith(s)), None)
        if unit is None or not table.lists_unit(listed, unit) or os.path.islink(path) or not os.path.isfile(path):
            raise SettingsError(f"{path}: not an output of this run, nor a report of a unit the {FLEET_CSV} there lists; "
                                "--fleet DIR holds the run's own files only, and no other file is removed: give a new "
                                "or empty folder, or move it")
        earlier.append(path)
    return earlier


def _drop_unwritten(folder, name, files, result):
    """Remove the reports of the recording ``name`` in ``folder`` that this run writes none of
    (``result[key]`` None: a failed file, an imu.yaml whose range its record does not reach): an
    earlier run's (there only under --force, checked with the rest), which would stand beside this
    run's reports and fleet.csv as if they were its (another range's imu.yaml, a failed file's old
    Allan document)."""
    outputs.remove_earlier(folder, [name + suffix for suffix, key, _ in files if result[key] is None])


def _summary(rows, fleet_files, written, elapsed_s, no_yaml=(), no_accel=(), not_recordings=()):
    """Print the fleet's outcome on stdout; the exit code. ``no_yaml``: "UNIT: why" of each unit
    analysed whose imu.yaml was not written (its Allan document was); ``no_accel``: "UNIT: why"
    of each unit whose accelerometer columns were not analysed (no ``accel_unit``: allan's
    warning, :func:`~gyrofilter.analysis.still.accelerometer_note`), one line each as well;
    ``not_recordings``: (path, why) of the paths skipped as no recordings, one line each."""
    failed, left_out = table.failed_rows(rows), table.left_out_rows(rows)
    done = len({r["unit"] for r in rows if r["status"] == "ok"})
    flagged = [r for r in rows if r["flag"]]
    console.tell(f"fleet: {table.outcome_text(rows)} ({elapsed_s:.1f} s)")
    for r in table.skipped_rows(rows):
        console.tell(f"  not still: {r['status']}")
    moving = table.moved_units(rows)
    if moving:
        console.tell(f"  moving, analysed (--allow-motion) but kept out of the comparison: {', '.join(moving)}")
    for path, why in not_recordings:
        console.tell(f"  skipped, not a recording: {path}: {why}")
    for r in failed:
        console.tell(f"  failed: {r['status']}")
    for r in left_out:
        console.tell(f"  left out: {r['status']}")
    for text in no_yaml:
        console.tell(f"  no imu.yaml: {text}")
    for text in no_accel:
        console.tell(f"  accelerometer not analysed: {text}")
    for r in flagged:
        moved = any(NOT_STATIC in w for w in r["warnings"])
        for f in r["flag"]:
            console.tell(f"  stands out: {r['unit']} {r['axis']}: {f['text']}"
                         + ("; it moved: this describes the motion, not the sensor" if moved else ""))
    console.say(f"wrote {fleet_files[0]}, {fleet_files[1]} and {written} report file(s)")
    return EXIT_NOTHING_DONE if not done else 0
