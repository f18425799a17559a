"""The ``gyrofilter`` command: the only place that parses argv, prints and exits.

Each subcommand lives in its own module ``gyrofilter.cli.<name>`` with two functions:
``add_arguments(parser)`` and ``run(args) -> int``. Modules are imported only when their
command runs (or for ``--help``), so ``gyrofilter replay`` does not import the analysis code.
What several commands share has a module of its own: ``outputs`` (output files), ``options``
(option types, ``--sample-rate-hz``), ``console`` (messages, the summary table), ``filtering``
(the filter options of replay and run), ``still`` (``--keep-outliers``), ``batch`` (fleet runs)
and ``live`` (the read loop of record and run).
Library errors (:class:`gyrofilter.errors.GyroFilterError`), OS errors, running out of memory
and Ctrl-C become one line on stderr and a non-zero exit code; a traceback is a bug.
"""
import argparse
import importlib
import os
import re
import signal
import sys
import threading

from .. import __version__
from ..errors import GyroFilterError, one_line
from ..inputs import closest, escape_controls, quote
from ..inputs import did_you_mean as _did_you_mean
from . import console

# command name -> (module, one-line summary)
COMMANDS = {
    "replay": ("gyrofilter.cli.replay", "filter a recording with the real-time pipeline"),
    "record": ("gyrofilter.cli.record", "record a live source to a recording file"),
    "run": ("gyrofilter.cli.run", "filter a live source in real time"),
    "allan": ("gyrofilter.cli.allan", "Allan deviation and noise coefficients of a recording"),
    "simulate": ("gyrofilter.cli.simulate", "simulate a gyro recording from a noise model"),
    "gap": ("gyrofilter.cli.gap", "find what the baseline noise model gets wrong about a recording"),
    "arma": ("gyrofilter.cli.arma", "ARMA model of the bias (paper 003)"),
    "evaluate": ("gyrofilter.cli.evaluate", "compare filters on static, synthetic-motion and reference data"),
    "convert": ("gyrofilter.cli.convert", "another tool's gyro log (CSV or text) as a recording"),
    "report": ("gyrofilter.cli.report", "one self-contained HTML report of a recording, to attach or compare"),
}

EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130


class _OneLineParser(argparse.ArgumentParser):
    """argparse, with a refusal in one line (what every refusal of gyrofilter is, with the same
    prefix, :func:`console.error_line`) that says where the usage is, instead of the usage text
    and then the error. An option is taken only as spelled
    in full: each has one spelling, and a removed one is refused, not read as the prefix of
    another (``--sample-rate`` of ``--sample-rate-hz``)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def parse_known_args(self, args=None, namespace=None):
        args = sys.argv[1:] if args is None else list(args)
        self._refuse_repeated(args)
        self.argv = args  # for the error's hint (:meth:`error`)
        return super().parse_known_args(args, namespace)

    def _refuse_repeated(self, argv):
        """Refuse an option that takes one value given twice (argparse keeps the last one silently:
        ``--out a.csv --out b.csv`` wrote only b.csv, ``--preset paper --preset hold`` ran hold), as
        ``--set`` refuses a setting given twice. The top-level parser has no such option: a
        command's words are its own parser's to check."""
        single = {s: a for a in self._actions if isinstance(a, argparse._StoreAction) for s in a.option_strings}
        seen = {}
        for i, word in enumerate(argv):
            if word == "--":
                return
            option, equals, value = word.partition("=")
            if option in single:
                value = value if equals else (argv[i + 1] if i + 1 < len(argv) else "")
                action = single[option]  # --fleet and --out-dir are one option
                if action in seen:
                    self.error(f"argument {option}: given twice ({quote(seen[action])}, then {quote(value)}); give it once")
                seen[action] = value

    def error(self, message):
        choice = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if choice:  # a mistyped value of an option with choices (--preset papr): the closest one
            message += _did_you_mean(choice.group(1), [c.strip(" '\"") for c in choice.group(2).split(",")])
        message += self._dashed_value_hint(message)
        self.exit(EXIT_BAD_INPUT, escape_controls(console.error_line(f"{message} (see {self.prog} --help)")) + "\n")


    def _dashed_value_hint(self, message):
        """How to give the value of an option that argparse took for an option because it starts
        with "-" (``--kalibr-tau-s -1,10``: "expected one argument"; a plain negative number such as
        ``-5`` is taken, and an option of the command after it is a value forgotten): "; a value that starts with '-' goes after '=': --kalibr-tau-s=-1,10", else ""."""
        missing = re.match(r"argument (\S+): expected one argument$", message)
        argv = getattr(self, "argv", [])
        if missing:
            names = missing.group(1).split("/")  # --fleet/--out-dir: one option
            for word, value in zip(argv, argv[1:]):
                if word in names and value.startswith("-") and value.split("=")[0] not in self._option_string_actions \
                        and value != "--":  # not the next option (--kalibr --force: a value forgotten)
                    return f"; a value that starts with '-' goes after '=': {word}={value}"
        return ""


class _Parser(_OneLineParser):
    """The top-level parser. Arguments a command does not know are that command's error:
    "unrecognized arguments: ...", with "did you mean --out?" for an option
    close to one of its own (argparse would report them with the top-level usage)."""

    def parse_args(self, args=None, namespace=None):
        args, extras = self.parse_known_args(args, namespace)
        if extras:
            command = self.commands.get(getattr(args, "command", None), self)
            command.error(f"unrecognized arguments: {' '.join(extras)}{did_you_mean(command, extras)}")
        return args


def did_you_mean(parser, extras):
    """"; did you mean --out?" for the unknown option among ``extras`` (words of argv) that is
    closest to an option of ``parser`` (:func:`gyrofilter.inputs.closest`, without the dashes),
    else "". An option also qualifies when its words (split at "-") hold every word typed, as a
    removed spelling's do: ``--rate`` -> ``--sample-rate-hz``."""
    known = {s.lstrip("-"): s for action in parser._actions for s in action.option_strings if s.startswith("--")}
    best = (0.0, None)
    for word in extras:
        if word.startswith("-"):
            typed = word.split("=", 1)[0].lstrip("-")
            found = closest(typed, known, also=lambda name: set(typed.split("-")) <= set(name.split("-")))
            if found[1] is not None and (best[1] is None or found[0] > best[0]):
                best = found
    return f"; did you mean {known[best[1]]}?" if best[1] is not None else ""


def build_parser(command=None):
    parser = _Parser(
        prog="gyrofilter",
        description="Real-time filtering and error analysis for low-cost MEMS gyroscopes (MPU6050).",
    )
    parser.add_argument("--version", action="version", version=f"gyrofilter {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_OneLineParser)
    parser.commands = {}
    for name, (module_name, summary) in COMMANDS.items():
        p = parser.commands[name] = sub.add_parser(name, help=summary, description=summary)
        if command == name:
            importlib.import_module(module_name).add_arguments(p)
    return parser


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def main(argv=None):
    # SIGTERM and SIGHUP stop a command like Ctrl-C does, so its clean-up (no partial output
    # file) runs; record and run handle them themselves while their read loop runs
    signals = [getattr(signal, n) for n in ("SIGTERM", "SIGHUP") if hasattr(signal, n)]
    if threading.current_thread() is not threading.main_thread():
        signals = []
    saved = [(s, signal.signal(s, _interrupt)) for s in signals]
    streams = sys.stdout, sys.stderr
    # a descriptor closed at the start (`>&-`, `2>&-`: Python's stream None) is a console no one
    # reads: the null device (it ended every command with exit 1 or 120, its files not written)
    consoles = [stream if stream is not None else open(os.devnull, "w") for stream in streams]
    for stream in consoles:  # a file name that is not UTF-8 prints escaped, not as a crash
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    sys.stdout, sys.stderr = console.ReaderAwareStream(consoles[0], "stdout"), console.ReaderAwareStream(consoles[1], "stderr", lost=OSError)
    try:
        return _main(argv)
    finally:
        for stream in (sys.stdout, sys.stderr):
            stream.restore()
        sys.stdout, sys.stderr = streams
        for stream, used in zip(streams, consoles):
            if stream is None:
                used.close()
        for s, handler in saved:
            signal.signal(s, handler)


def _main(argv):
    argv = sys.argv[1:] if argv is None else list(argv)
    command = next((a for a in argv if not a.startswith("-")), None)
    try:
        os.getcwd()
    except FileNotFoundError:  # every relative path would fail with "[Errno 2] No such file or directory", naming nothing
        console.say(console.error_line("the current folder no longer exists (deleted?); cd to one that does"))
        return EXIT_BAD_INPUT
    try:
        if command is not None and command not in COMMANDS:
            build_parser().error(f"unknown command {quote(command)}{_did_you_mean(command, COMMANDS)}; "
                                 f"the commands: {', '.join(COMMANDS)}")
        parser = build_parser(command)
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help()
            return EXIT_BAD_INPUT
        module = importlib.import_module(COMMANDS[args.command][0])
        status = module.run(args) or 0
        sys.stdout.flush()  # a failure of stdout where the buffer held the whole result is an error too
        return status
    except KeyboardInterrupt as exc:
        unwritten = getattr(exc, "not_written", [])
        console.say(f"gyrofilter: interrupted{'; not written: ' + ', '.join(unwritten) if unwritten else ''}")
        return EXIT_INTERRUPTED
    except (GyroFilterError, OSError, ValueError) as exc:
        console.say(console.error_line(one_line(exc)))
        return EXIT_BAD_INPUT
    except MemoryError:  # an input too large to hold (the recording reader names its file itself)
        console.say(console.error_line(f"out of memory running {command}; give it a shorter input"))
        return EXIT_BAD_INPUT
