"""gyrofilter evaluate: one table and one Pareto figure comparing the filters on measured data.

Static std reduction on every static MPU6050 recording, RMSE and worst lag on synthetic
profiles added to real static noise, RMSE against the optical reference on the BROAD trials;
see :mod:`gyrofilter.evaluation.evaluate` for the definitions. The three files in ``--out`` are refused
when they exist (unless ``--force``), before any work, and are written into a temporary folder
from which they take their places once all three are written (:func:`outputs.replacing_in`).
"""
import os

from ..evaluation import evaluate as E
from ..plots import pyplot
from . import console, options, outputs

OUTPUT_NAMES = ("evaluate_table.md", "evaluate.json", "evaluate_pareto.png")


def add_arguments(parser):
    parser.add_argument("--out", metavar="DIR", type=options.file_name, default="evaluation",
                        help="directory for evaluate_table.md, evaluate.json and evaluate_pareto.png (default: ./evaluation)")
    parser.add_argument("--recordings", metavar="DIR",
                        help="directory of recordings (default: ./recordings, else the repository's recordings/)")
    parser.add_argument("--split", choices=("all", "tune", "holdout"), default="all",
                        help="evaluate on all data (default), or only the tuning or the held-out part (gyrofilter.evaluation.evaluate.TUNE_SPLIT)")
    parser.add_argument("--no-lag", action="store_true", help="skip the lag estimates (faster)")
    console.add_progress_argument(parser)
    options.add_force_argument(parser)


def _recordings_dir(arg):
    if arg:
        if not os.path.isdir(arg):
            raise ValueError(f"{arg}: not a directory of recordings")
        return arg
    if os.path.isdir("recordings"):
        return "recordings"
    repo = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "recordings")
    if os.path.isdir(repo):
        return repo
    raise ValueError("no recordings/ directory here; give --recordings DIR")


def run(args):
    outputs.check_output_folder(args.out, "--out")
    outputs.check_outputs([os.path.join(args.out, name) for name in OUTPUT_NAMES], force=args.force)
    rec_dir = _recordings_dir(args.recordings)
    pyplot()  # a missing matplotlib is said now, not after the evaluation
    progress = console.ProgressLines(args.progress)
    split = {"all": {}, "tune": E.TUNE_SPLIT, "holdout": E.HOLDOUT_SPLIT}[args.split]
    ev = E.evaluate(
        recordings_dir=rec_dir,
        profiles=split.get("profiles"),
        with_lag=not args.no_lag,
        progress=progress,
        static_names=split.get("static"),
        broad_names=split.get("broad"),
    )
    table = E.format_table(ev)
    verdicts = []
    for name in ev.filters:
        if name == "paper001":
            continue
        ok, fails = E.dominates(ev, name)
        verdicts.append(f"- {name}: {'dominates paper001' if ok else 'does not dominate: ' + '; '.join(fails[:3]) + (' ...' if len(fails) > 3 else '')}")
    data = (f"Data: {rec_dir} (split: {args.split}); static: {', '.join(ev.static_names)}; "
            f"profiles: {', '.join(ev.profiles)}; BROAD: {', '.join(ev.broad_names)}")
    dominance = ("Pareto dominance over the faithful paper001 (static >= 12.6x on every axis of every static recording, "
                 "RMSE <= paper001 on every profile and BROAD trial):")
    text = (
        data + "\n\n"
        "Columns: static std reduction (min over axes and recordings / geometric mean); "
        "profile RMSE (deg/s) / worst lag; BROAD RMSE vs optical reference (deg/s) in motion / at rest / lag behind the reference.\n\n"
        + table + "\n\n" + dominance + "\n"
        + "\n".join(verdicts)
        + "\n"
    )
    console.paragraph(data)
    print("\n" + E.console_table(ev) + "\n")
    console.paragraph("Columns: static std reduction (min over axes and recordings / geometric mean); profiles' RMSE "
                      "(deg/s, geometric mean) and worst lag; BROAD RMSE vs the optical reference (deg/s, geometric "
                      f"means) in motion / at rest. Every profile and trial: {os.path.join(args.out, OUTPUT_NAMES[0])}")
    console.paragraph(dominance)
    for line in verdicts:
        console.paragraph(line)
    doc = {"filters": ev.filters, "families": ev.families, "static_std_reduction": ev.static,
           "dynamic": ev.dynamic, "broad": ev.broad}
    table_name, json_name, png_name = OUTPUT_NAMES
    with outputs.replacing_in(args.out) as tmp:
        outputs.write_text(os.path.join(tmp, table_name), text)  # a full disk names the file (attack pass 59)
        outputs.write_json(os.path.join(tmp, json_name), doc)
        E.plot_pareto(ev, os.path.join(tmp, png_name))
    console.say(f"wrote {', '.join(os.path.join(args.out, name) for name in OUTPUT_NAMES)}")
    return 0
