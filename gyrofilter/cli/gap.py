"""``gyrofilter gap RECORDING [--json OUT.json] [--report DIR] [--seed N] [--sims N] [--bootstrap N]``.

Finds what the baseline noise model (constant bias + white noise + quantization) gets wrong
about a recording, names the cause (an effect of the effect table), extends the model and
measures the gain, with a 95 % interval for every parameter (``--bootstrap N`` runs per axis with
findings; 0: no intervals); prints the findings and, with ``--json``, writes the gap report
(docs/formats.md) to OUT.json; with ``--report``, a Markdown report with PNG figures. A one-line
summary per finding goes to stdout;
progress goes to stderr (on a terminal, or with ``--progress``).

Outputs that exist are refused unless ``--force``, and an output that is the recording always,
before any work; all outputs are written under temporary names and take their places together
when everything is written, so a failed run leaves none of them.
"""
import contextlib
import os
import time

from ..analysis.gap import report as gap_report
from ..analysis.fleet.work import FleetSettings
from ..analysis.gap.baseline import DEFAULT_SIMS, FEWEST_DEFAULT_SIMS, MAX_SIMS, MIN_SIMS, SIMS_IN_FULL_UP_TO
from ..analysis.gap.pipeline import analyse_file
from ..analysis.gap.intervals import DEFAULT_BOOTSTRAP, FEWER_BOOTSTRAP_FROM, MAX_BOOTSTRAP, MIN_REPLICATES
from ..errors import RecordingError, SettingsError
from ..plots import pyplot
from ..sim.simulate import check_seed
from ..units import AXES
from . import batch, console, options, outputs, still



def add_arguments(parser):
    parser.add_argument("recordings", nargs="+", metavar="RECORDING",
                        help="recording file (format v1, .csv or .csv.gz); several files or globs with --fleet")
    parser.add_argument("--json", metavar="OUT.json", type=options.file_name, help="also write the gap report (JSON, every number) here")
    parser.add_argument("--report", metavar="DIR", type=options.file_name, default=None, help="also write a Markdown report with PNG figures to DIR")
    parser.add_argument("--seed", type=options.whole_number, default=None, metavar="N",
                        help="no effect, kept for older scripts: the analysis draws its simulations from fixed "
                             "streams, so its answer does not depend on a seed (docs/gap.md, \"How stable\")")
    parser.add_argument("--sims", type=options.whole_number, default=None, metavar="N",
                        help=f"baseline simulations (default {DEFAULT_SIMS}; {FEWEST_DEFAULT_SIMS}-{DEFAULT_SIMS} above "
                             f"{SIMS_IN_FULL_UP_TO:,} samples per axis; {MIN_SIMS} to {MAX_SIMS})")
    parser.add_argument("--bootstrap", type=options.whole_number, default=None, metavar="N",
                        help=f"bootstrap runs per axis with findings for the parameters' 95 %% intervals (default "
                             f"{DEFAULT_BOOTSTRAP}; 10-{DEFAULT_BOOTSTRAP} above {FEWER_BOOTSTRAP_FROM:,} samples per axis; "
                             f"0: no intervals; else {MIN_REPLICATES} to {MAX_BOOTSTRAP})")
    parser.add_argument("--allow-motion", action="store_true",
                        help="analyse a recording that does not look still (refused by default: the analysis models a "
                             "still gyro, so its findings would describe the motion; a fleet skips such recordings, "
                             "and with this analyses them but keeps them out of its comparison)")
    still.add_allow_large_mean_argument(parser)
    console.add_progress_argument(parser)
    batch.add_arguments(parser)
    options.add_force_argument(parser)


def check_options(seed, sims, bootstrap=None):
    """Refuse a ``--seed``, ``--sims`` or ``--bootstrap`` (None: their defaults) that the analysis
    cannot take, naming the option; a ``--seed`` given is said to have no effect (a user who gives
    one expects the answer to change)."""
    if sims is not None and not MIN_SIMS <= sims <= MAX_SIMS:
        why = ("from fewer simulations D cannot be judged: pure white noise reads D up to 14-98 from 2-3" if sims < MIN_SIMS
               else f"more cost time and gain nothing: D's spread is known to +-3 % from {MAX_SIMS}")
        raise SettingsError(f"--sims must be in [{MIN_SIMS}, {MAX_SIMS}] ({why}), got {sims}")
    if bootstrap is not None and not (bootstrap == 0 or MIN_REPLICATES <= bootstrap <= MAX_BOOTSTRAP):
        raise SettingsError(f"--bootstrap must be 0 (no intervals) or in [{MIN_REPLICATES}, {MAX_BOOTSTRAP}] "
                            f"(an interval needs {MIN_REPLICATES} runs), got {bootstrap}")
    if seed is not None:
        check_seed(seed, "--seed")
        console.say_warning("--seed has no effect: gap's simulations use fixed streams, its answer does not depend on it")


def run(args):
    check_options(args.seed, args.sims, args.bootstrap)
    paths = batch.expand(args.recordings)
    if args.fleet is not None:
        batch.refuse_single_file_outputs(args, ["--json", "--report"])
        still.refuse_allow_large_mean_in_fleet(args)
        return batch.run(args, FleetSettings("gap", sims=args.sims, allow_motion=args.allow_motion), paths)
    args.recording = batch.single(args, paths)
    report_files = [os.path.join(args.report, name) for name in gap_report.report_file_names()] if args.report else []
    json_files = [args.json] if args.json is not None else []
    outputs.check_output_folder(args.report, "--report", json_files)
    outputs.check_outputs(json_files + report_files, [args.recording], args.force)
    t0 = time.perf_counter()
    progress = console.ProgressLines(args.progress, "gap")
    if args.report:
        pyplot()  # a missing matplotlib is said now, not after the analysis
    rec, report = analyse_file(args.recording, n_sims=args.sims, bootstrap=args.bootstrap,
                               warn=console.say_warning, progress=progress, refuse_motion=not args.allow_motion)
    # --allow-motion: the sensor turned, so its mean is real
    still.check_mean(args.recording, rec, args.allow_large_mean or args.allow_motion, warn=console.say_warning)
    d, why = report.get("discrepancy"), gap_report.not_analysed_why(report)
    if why is not None:  # nothing analysed: not a result that exit 0 could vouch for
        raise RecordingError(f"{args.recording}: no axis analysed ({why}); nothing written")
    with contextlib.ExitStack() as files:
        if args.json is not None:
            outputs.write_json(files.enter_context(outputs.replacing(args.json)), report)
        if args.report:
            progress("report")
            folder = files.enter_context(outputs.replacing_in(args.report))
            gap_report.write_report(report, rec, folder)
            drawn = set(os.listdir(folder))
    if args.report:  # an earlier run's figures this report does not draw (a temperature column it lacks)
        outputs.remove_earlier(args.report, [name for name in gap_report.report_file_names() if name not in drawn])
    written = json_files + ([os.path.join(args.report, gap_report.REPORT_NAME)] if args.report else [])
    console.say(f"wrote {' and '.join(written)}" if written else "(every number of the analysis: --json OUT.json)")
    gain = (f"discrepancy {d['overall_before']:.3g} -> {d['overall_after']:.3g}"
            + (f" over {', '.join(a for a in AXES if a not in d['not_analysed'])}" if d["not_analysed"] else ""))
    console.paragraph(f"{args.recording}: {_count(len(report['findings']), 'finding')}; {gain} "
                      f"({report.get('runtime_s', time.perf_counter() - t0):.1f} s)")
    rows = [f for f in report["findings"] if f["axis"] not in AXES]  # whole rows: every axis at once
    for axis in AXES:
        found = [f for f in report["findings"] if f["axis"] == axis]
        if axis in d["not_analysed"]:
            console.paragraph(f"{axis}: not analysed ({d['not_analysed'][axis]})", "  ")
        else:
            before = gap_report.d_text(d["before"][axis], d.get("before_se", {}).get(axis, 0.0))
            after = gap_report.d_text(d["after"][axis], d.get("after_se", {}).get(axis, 0.0))
            console.paragraph(f"{axis}: D {before}" + (f" -> {after} with {_count(len(found), 'finding')}"
                                                       if found else f" -> {after} with the rows' finding, none of its "
                                                       "own" if rows else ", no finding"), "  ")
        for f in found:
            console.paragraph(f"{f['effect']} ({gap_report.params_text(f)}); alone D {f['gain']['before']:.3g} -> "
                              f"{f['gain']['after']:.3g}", "    ")
            if f.get("alternatives"):
                console.paragraph(gap_report.indistinguishable_text(f), "      ")
    for f in rows:
        console.paragraph(f"every axis: {f['effect']} ({gap_report.params_text(f)}); {f['evidence']}; mean D "
                          f"{f['gain']['before']:.3g} -> {f['gain']['after']:.3g}", "  ")
    if report.get("uncertain"):
        console.paragraph(f"{gap_report.UNCERTAIN_HEADING} (not in the extended model):", "  ")
        for entry in report["uncertain"]:
            console.paragraph(gap_report.uncertain_text(entry), "    ")
    for note in report.get("notes", []):
        console.paragraph(f"note: {note}", "  ")
    console.paragraph("(D: mean squared z-score of the record's features against the model's simulations; about 1 "
                      "where the model explains the record; +- its sampling error over the simulations)", "  ")
    return 0


def _count(n, noun):
    return f"{n} {noun}" + ("" if n == 1 else "s")
