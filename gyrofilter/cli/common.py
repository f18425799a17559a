"""Pieces shared by the commands: output-file safety, filter options, warnings, the summary table."""
import argparse
import contextlib
import difflib
import json
import math
import os
import re
import shutil
import socket
import stat
import sys
import tempfile
import time

from ..errors import GyroFilterError, RecordingError, SettingsError
from ..inputs import parse_json, parse_number, quote
from ..filter.pipeline import GyroFilter
from ..filter.settings import SETTING_NAMES
from ..filter.presets import DEFAULT_PRESET, PRESETS
from ..recording import EXACT_FORMAT, FILTERED_FORMAT
from ..units import AXES, json_ready


#: what --out FILE of a recording takes: any name, the format is CSV text (docs/formats.md, section 1)
RECORDING_FILE_HELP = "recording format v1: CSV text, compressed with gzip when the name ends in .gz, e.g. out.csv or out.csv.gz"


#: the formats of a filtered row (t, gx, gy, gz): t exactly, the rates with 9 significant digits
ROW_FORMATS = [EXACT_FORMAT] + [FILTERED_FORMAT] * 3
#: a filtered row as text: run's output and replay --realtime's stdout
ROW_FORMAT = ",".join(ROW_FORMATS)


def bias_text(bias_dps):
    """The start-up bias as the commands print it: "+0.1234, -0.5678, +0.0012 deg/s"."""
    return ", ".join(f"{b:+.4f}" for b in bias_dps) + " deg/s"


def calibrated_note(bias_dps):
    """The note a live output gets when the start-up calibration is done (its header cannot have the bias)."""
    return "calibrated: bias " + bias_text(bias_dps)


def say(text):
    """A message for the user (stderr, so that stdout stays data)."""
    print(text, file=sys.stderr)


def add_sample_rate_argument(parser, *old_spellings, help):
    """``--sample-rate-hz HZ``, the commands' one spelling of a sample rate, with ``old_spellings``
    (e.g. ``--rate``) kept as aliases: ``args.sample_rate_hz`` holds the rate (Hz, None when not
    given), ``args.sample_rate_hz_option`` the spelling used, so a message names what was typed."""
    parser.add_argument("--sample-rate-hz", *old_spellings, type=decimal, default=None, metavar="HZ", dest="sample_rate_hz",
                        action=_SpellingKept, help=help)


class _SpellingKept(argparse.Action):
    """Stores the value, and in ``<dest>_option`` the option string the user typed."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        setattr(namespace, self.dest + "_option", option_string)


def decimal(text):
    """argparse type of a numeric option: a plain decimal number (:func:`gyrofilter.inputs.parse_number`:
    no ``1_0``, other scripts' digits, ``nan``, ``inf`` or hex), as a float; the option's own range
    is checked where it is used."""
    try:
        return parse_number(text, "")
    except SettingsError as exc:
        raise argparse.ArgumentTypeError(str(exc).strip()) from None


def whole_number(text):
    """argparse type of a count or seed: a plain decimal whole number, as an int, exact
    (:func:`gyrofilter.inputs.parse_number`: digits keep every digit of a seed beyond 2^53;
    another form, ``1e3`` or ``5.0``, must stay below 2^53, the whole numbers a float holds)."""
    try:
        return parse_number(text, "", integer=True)
    except SettingsError as exc:
        raise argparse.ArgumentTypeError(str(exc).strip()) from None


def file_name(text):
    """argparse type of an output option: any name but an empty one (the error names the option)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty name; give a file or folder name")
    return text


def add_force_argument(parser):
    parser.add_argument("--force", action="store_true", help="overwrite output files that exist (an input is never overwritten)")


def check_outputs(outputs, inputs=(), force=False):
    """Refuse, before any work, to write where a user's data would be lost.

    ``outputs`` and ``inputs`` are paths (None entries are skipped). An output that is one of
    the inputs is refused even with ``force``, and so is a name ending in a path separator (a
    folder's, existing or not); so is one that exists as anything but a regular
    file (a symbolic link, a device such as /dev/null, a FIFO, a socket): only regular files are
    replaced. An output that exists is refused without ``force``; two outputs naming one file are
    refused. Raises FileExistsError / SettingsError naming the file.
    """
    inputs = {_file_key(p) for p in inputs if p}
    seen = set()
    for out in (p for p in outputs if p):
        if os.path.isdir(out):
            raise SettingsError(f"{out}: is a folder; give a file name for the output")
        if out.endswith(tuple(filter(None, (os.sep, os.altsep)))):
            raise SettingsError(f"{out}: ends in {out[-1]}, so it names a folder; give a file name for the output")
        key = _file_key(out)
        if key in inputs:
            raise SettingsError(f"{out}: is an input of this command; write the output to another file")
        if key in seen:
            raise SettingsError(f"{out}: named for two outputs; give each output its own file")
        seen.add(key)
        parent = os.path.dirname(os.path.abspath(out))
        while not os.path.isdir(parent):
            if os.path.lexists(parent):
                raise SettingsError(f"{out}: {parent} is a file, not a folder")
            parent = os.path.dirname(parent)
        if not os.path.lexists(out):
            continue
        mode = os.lstat(out).st_mode
        if stat.S_ISLNK(mode):
            raise SettingsError(f"{out}: is a symbolic link; outputs replace only regular files: "
                                "name the file it points to, or another")
        if not stat.S_ISREG(mode):
            raise SettingsError(f"{out}: is not a regular file (a device, FIFO or socket); "
                                "outputs replace only regular files")
        if not force:
            raise FileExistsError(17, "exists (use --force to overwrite)", out)
        _replaceable.add(_identity(os.lstat(out)))


#: the files check_outputs let --force replace (:func:`_identity`): any other file found at an
#: output's name when it lands appeared while the command ran, and is not replaced
_replaceable = set()


def _identity(st):
    """What tells one state of a file from another: device, inode (reused at once after a delete),
    modification time and size."""
    return st.st_dev, st.st_ino, st.st_mtime_ns, st.st_size


#: the outputs whose temporary files wait to land (:func:`replacing`): every commit checks them
#: all first, so that a command's outputs land together or none of them does
_pending = []


def _may_land(path):
    """FileExistsError when a file at ``path`` is not one --force may replace (it appeared while
    the command ran)."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return
    if _identity(st) not in _replaceable:
        raise FileExistsError(17, "appeared or changed while this command ran and is left as it is (rerun with --force to "
                                  "overwrite)", path)


def commit(tmp, path):
    """Give the finished temporary file ``tmp`` the name ``path``: replace the file there only when
    :func:`check_outputs` let ``--force`` replace that very file; a file that appeared meanwhile
    (another command, the user) is left as it is: FileExistsError, raised before any of the
    command's pending outputs lands. The check and the rename are one step (``os.link`` fails on
    an existing name) where the file system has hard links."""
    for other in _pending:
        _may_land(other)
    _may_land(path)
    if os.path.lexists(path):  # the very file --force was given for
        os.replace(tmp, path)
        return
    try:
        os.link(tmp, path)
    except FileExistsError:  # it appeared between the look and the link
        _may_land(path)
        raise
    except OSError:  # no hard links here (vfat): the look above has to do
        os.replace(tmp, path)
    else:
        os.unlink(tmp)


def check_output_folder(folder, option):
    """Refuse, before any work, an output folder (``option`` DIR) that exists as a file."""
    if folder and os.path.exists(folder) and not os.path.isdir(folder):
        raise SettingsError(f"{option} {folder}: is a file; give a folder for the output files")


def _file_key(path):
    """What names one file: device and inode of a file that exists (links and bind mounts
    included), else the path with its symbolic links resolved. Keys, not pairwise
    comparisons, so that a fleet's thousands of outputs are checked in linear time."""
    try:
        st = os.stat(path)
    except OSError:  # does not exist yet
        return os.path.realpath(path)
    return (st.st_dev, st.st_ino)


@contextlib.contextmanager
def replacing(path):
    """Write a whole file at once: yields a temporary path beside ``path`` (its folder created if
    needed); on success it replaces ``path``; on any failure it is removed, with any folder this
    call created, so a failed command leaves nothing behind."""
    tmp = partial_path(path)
    with _folder(os.path.dirname(tmp)):
        _pending.append(path)
        try:
            with _naming(tmp, path):
                yield tmp
                commit(tmp, path)
        finally:
            _pending.remove(path)
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)


@contextlib.contextmanager
def replacing_in(folder):
    """:func:`replacing` for files whose names the writer chooses: yields a temporary folder inside
    ``folder`` (created if needed); on success every file written there replaces its namesake in
    ``folder``; on any failure the temporary folder goes, with any folder this call created."""
    with _folder(folder):
        tmp = tempfile.mkdtemp(prefix=f"{_PARTIAL_PREFIX}{_OWNER}-", dir=folder)
        try:
            with _naming(tmp, folder):
                yield tmp
                names = sorted(os.listdir(tmp))
                for name in names:  # all may land, or none does
                    _may_land(os.path.join(folder, name))
                for name in names:
                    commit(os.path.join(tmp, name), os.path.join(folder, name))
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


@contextlib.contextmanager
def _naming(tmp, path):
    """An error about the temporary ``tmp`` (or a file in it) names the user's ``path`` instead:
    an OSError's file name, and the text of a GyroFilterError (a writer's refusal, same class)."""
    try:
        yield
    except OSError as exc:
        if isinstance(exc.filename, str) and exc.filename.startswith(tmp):
            raise OSError(exc.errno, exc.strerror, path + exc.filename[len(tmp):]) from None
        raise
    except GyroFilterError as exc:
        exc.args = tuple(a.replace(tmp, path) if isinstance(a, str) else a for a in exc.args)
        raise


def partial_path(path):
    """The temporary name beside ``path`` under which a file is written until it may take its
    own name: ``.partial-PID.HOST-NAME`` in the same folder, so that the rename is atomic and the
    extension, by which writers choose the format, is kept. A process killed before the rename
    leaves it behind; :func:`remove_stale_partials` removes it later."""
    folder, name = os.path.split(os.path.abspath(path))
    return os.path.join(folder, f"{_PARTIAL_PREFIX}{_OWNER}-{name}")


_PARTIAL_PREFIX = ".partial-"
#: the host in a partial name: a folder shared over the network (a fleet's reports on NFS) holds
#: other machines' partials, whose process numbers mean nothing here
_HOST = re.sub(r"[^A-Za-z0-9_]", "_", socket.gethostname()) or "host"
_OWNER = f"{os.getpid()}.{_HOST}"
# what partial_path and replacing_in make: the process number and the host
_PARTIAL = re.compile(re.escape(_PARTIAL_PREFIX) + r"([0-9]+)\.([A-Za-z0-9_]+)-.+", re.DOTALL)
#: a partial untouched for this long (s) may be stale: record and run flush every 0.5 s, and the
#: other commands write theirs at the end, in seconds
STALE_AFTER_S = 600.0
_swept = set()  # folders whose stale partials this process removed already


def remove_stale_partials(folder):
    """Remove from ``folder`` the temporary files and folders (``.partial-PID-...``, see
    :func:`partial_path`) of processes that died before renaming them (SIGKILL, a power cut):
    only names of that exact pattern made on this host, untouched for :data:`STALE_AFTER_S`, whose
    PID runs no process (``os.kill(pid, 0)`` answers ProcessLookupError); a live process's,
    another user's or another machine's are never touched. Once per
    folder and process, so that a batch writing thousands of files lists its folder once."""
    folder = os.path.abspath(folder)
    if folder in _swept:
        return
    _swept.add(folder)
    with contextlib.suppress(OSError):
        for entry in os.scandir(folder):
            match = _PARTIAL.fullmatch(entry.name)
            if (not match or match.group(2) != _HOST or _process_runs(int(match.group(1)))
                    or time.time() - entry.stat(follow_symlinks=False).st_mtime < STALE_AFTER_S):
                continue
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path, ignore_errors=True)
            elif entry.is_file(follow_symlinks=False):
                with contextlib.suppress(OSError):
                    os.unlink(entry.path)


def _process_runs(pid):
    """Whether the process ``pid`` may exist (True when it cannot be told)."""
    if pid <= 0:
        return True  # not a process of its own: 0 and below name process groups
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (OSError, OverflowError):  # PermissionError: it runs as another user; a pid beyond the OS's range
        return True
    return True


@contextlib.contextmanager
def _folder(folder):
    """Make ``folder`` and its missing parents; on a failure inside the block, remove what was
    made. An existing folder first loses its stale partial files (:func:`remove_stale_partials`)."""
    top = None
    parent = os.path.abspath(folder)
    while not os.path.isdir(parent):
        top, parent = parent, os.path.dirname(parent)
    if top is not None:
        os.makedirs(folder)
    else:
        remove_stale_partials(folder)
    try:
        yield
    except BaseException:
        if top is not None:
            shutil.rmtree(top, ignore_errors=True)
        raise


def write_json(path, doc):
    """Write ``doc`` as JSON to ``path`` (no replacing: give it the path :func:`replacing` yields).

    Through :func:`gyrofilter.units.json_ready`: numpy values become plain numbers and lists, a
    non-finite number becomes ``null``.
    """
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(json_ready(doc), fh, indent=1, allow_nan=False)
        fh.write("\n")


def say_warning(text):
    """A warning for the user: one line on stderr, "gyrofilter: warning: <text>"."""
    say(f"gyrofilter: warning: {text}")


def print_warnings(warnings):
    for text in warnings:
        say_warning(text)


def add_filter_arguments(parser):
    parser.add_argument("--preset", default=DEFAULT_PRESET, choices=sorted(PRESETS),
                        help=f"filter settings preset (default: {DEFAULT_PRESET}, the best measured filter; "
                             "paper: the faithful paper-001 pipeline)")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", type=setting_text,
                        help="override one filter setting (repeatable), e.g. --set outlier_rule=median_slope; "
                             f"settings: {', '.join(SETTING_NAMES)}")
    parser.add_argument("--temp-model", metavar="JSON",
                        help="compensate temperature drift with the coefficients of a gap report or simulator model "
                             "(needs a temp column / a source with temperature)")
    parser.add_argument("--calibration-s", type=decimal, default=None, help="start-up calibration window in seconds (default 2; the sensor must be still)")
    parser.add_argument("--calibration", metavar="JSON", help="use a saved calibration instead of calibrating")
    parser.add_argument("--save-calibration", metavar="JSON", type=file_name, help="save the start-up calibration to this file")


def make_filter(args, sample_rate_hz):
    """The GyroFilter of the filter options; ``--set calibration_s=S`` is ``--calibration-s S``.
    A setting given twice with --set is refused, naming it; GyroFilter refuses --calibration with
    a calibration window."""
    settings = {}
    for text in args.set:
        name, value = _parse_setting(text)
        if name in settings:
            raise SettingsError(f"--set {name}: given twice; give each setting once")
        settings[name] = value
    calibration_s = args.calibration_s
    if "calibration_s" in settings:
        if calibration_s is not None:
            raise SettingsError("--set calibration_s and --calibration-s both given; give one")
        calibration_s = settings.pop("calibration_s")
    if args.temp_model:
        if "temp_coefficient_dps_per_c" in settings:
            raise SettingsError("--temp-model and --set temp_coefficient_dps_per_c both give the temperature "
                                "coefficients; give one")
        settings["temp_coefficient_dps_per_c"] = temperature_coefficients(args.temp_model)
    filt = GyroFilter(sample_rate_hz, calibration_s, preset=args.preset, calibration=args.calibration, **settings)
    if args.save_calibration and filt.calibration is None and filt.settings.calibration_s == 0:
        raise SettingsError(f"--save-calibration {args.save_calibration}: a calibration window of 0 s makes no "
                            "calibration to save")
    return filt


#: what --set cannot set, and where it comes from instead
_NOT_SETTINGS = {"sample_rate_hz": "the sample rate comes from the recording or source (--sample-rate-hz where a command takes one)",
                 "calibration": "use --calibration JSON"}


def _split_setting(text):
    """'name=value' -> (name, value text), or SettingsError: the one check of --set's shape."""
    name, sep, value = text.partition("=")
    name = name.strip()
    if not sep or not name:
        raise SettingsError(f"--set {quote(text)}: expected NAME=VALUE")
    return name, value


def setting_text(text):
    """argparse type of --set: NAME=VALUE, so that ``--set block_len 5`` is told so (it read 5 as
    the recording's name)."""
    try:
        _split_setting(text)
    except SettingsError:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE (e.g. block_len=5), got {quote(text)}") from None
    return text


def _parse_setting(text):
    """'name=value' -> (name, value); NAME must be a filter setting (``SETTING_NAMES``). The value is
    read as JSON (numbers, true/false, lists; :func:`gyrofilter.inputs.parse_json`, so no NaN or
    Infinity tokens and no deep nesting), else kept as text; numbers separated by commas
    (0.01,0.02,0) are a list; Python's True/False are bools; null is refused. Whether the value
    fits the setting (its type and range) is GyroFilter's check, whose error names the setting."""
    name, value = _split_setting(text)
    if name in _NOT_SETTINGS:
        raise SettingsError(f"--set {name}: not a filter setting; {_NOT_SETTINGS[name]}")
    if name not in SETTING_NAMES:
        close = difflib.get_close_matches(name, SETTING_NAMES, n=1)
        raise SettingsError(f"--set {quote(name)}: not a filter setting{f'; did you mean {close[0]}?' if close else ''} "
                            "(--help lists them)")
    if value.strip() in ("True", "False"):  # Python's spelling of a bool, as the settings' errors print it
        return name, value.strip() == "True"
    for candidate in (value, f"[{value}]") if "," in value else (value,):
        try:
            parsed = parse_json(candidate, f"--set {name}")
        except SettingsError:  # not JSON: text
            continue
        if parsed is None:
            raise SettingsError(f"--set {name}=null: every setting needs a value")
        return name, parsed
    return name, value


def temperature_coefficients(path):
    """(cx, cy, cz) in deg/s per deg C from a gap report (its extended_model) or a simulator model,
    checked by the simulator's :func:`~gyrofilter.sim.simulate.validate_model` (for its numbers
    only: the sample rate and the temperature profile may be missing)."""
    from ..sim.simulate import load_model, validate_model
    from ..filter.tempcomp import coefficients_from_model

    model = load_model(path)
    if not isinstance(model, dict) or not isinstance(model.get("axes"), dict):
        raise SettingsError(f"{path}: neither a gap report (extended_model) nor a simulator model (axes)")
    try:
        spec, _ = validate_model(model, coefficients_only=True)
    except SettingsError as exc:
        raise SettingsError(f"{path}: {exc}") from None
    coefficients = coefficients_from_model(spec)
    if not any(coefficients):
        raise SettingsError(f"{path}: the model has no temperature effect, so there is nothing to compensate")
    return coefficients


def refuse_filtered_output(header, where):
    """Refuse to filter a filter's output: a recording whose ``header`` (a dict) has
    ``filtered_from`` (written by ``replay --out`` and ``run``) holds bias-removed block means at
    the output rate, not a sensor's samples, so the start-up calibration would call the sensor
    moved, or a second filter would average the averages. ``where`` names the file or source.
    The raw recording it came from is what to filter (``allan`` and ``gap`` take either: the
    noise of the output is a fair question). RecordingError; None for a raw recording."""
    if "filtered_from" in header:
        raise RecordingError(f"{where} is a filtered output of gyrofilter (filtered_from: "
                             f"{quote(header['filtered_from'])}), not a sensor's samples; filter the raw recording "
                             "it came from")


def check_temperature(filt, available, where):
    """Refuse a filter that compensates temperature when ``where`` gives no temperatures."""
    if filt.compensates_temperature and not available:
        raise SettingsError(f"{where} has no temperature (temp column), which temperature compensation "
                            "(--temp-model or --set temp_coefficient_dps_per_c) needs")


def save_calibration(path, filt, outputs):
    """Write ``filt``'s calibration to ``path`` (``--save-calibration``) through :func:`replacing`
    entered on the ExitStack ``outputs``, so that it lands with the command's other outputs or
    not at all. Returns whether it was asked for; SettingsError when there is none to save
    (the data ended inside the start-up window)."""
    if not path:
        return False
    if filt.calibration is None:
        raise SettingsError(f"--save-calibration {path}: the data ended inside the start-up calibration window, "
                            "so there is no calibration to save")
    filt.calibration.save(outputs.enter_context(replacing(path)))
    return True


def print_summary(path, head, filt, raw, filtered, calibration_from=None, smoothed=False):
    """The per-axis table: raw and filtered mean/std (:class:`~gyrofilter.streamstats.RunningMoments`),
    std ratio, rejected samples. ``calibration_from``: the file the bias was loaded from, if any;
    ``smoothed``: the rows are the forward-backward smoother's."""
    print(f"recording: {path}")
    print(f"  {head.rows} samples at {head.sample_rate_hz:g} Hz ({head.rows / head.sample_rate_hz:.1f} s), unit {head.gyro_unit}")
    cal = filt.calibration
    if cal is not None:
        source = f"loaded from {calibration_from}" if calibration_from else f"start-up calibration, {cal.samples} samples"
        print(f"  bias ({source}): " + ", ".join(_number(b, 0, sign=True) for b in cal.bias_dps) + " deg/s")
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
        ratio = _number(raw_std[a] / f_std[a], 8, decimals=2) + "x" if f_std[a] > 0 else f"{'n/a':>9}"
        print(f"  {name}    {_number(raw.mean[a], 9, sign=True)}  {_number(raw_std[a], 9)}  {_number(filtered.mean[a], 9, sign=True)}"
              f"  {_number(f_std[a], 9)}  {ratio}  {int(filt.rejected[a]):8d}")
    removed = "bias removed" if cal is not None else "no calibration, so no bias removed"
    print("  (deg/s; raw = the samples after the calibration window that the filter consumed, bias included;\n"
          f"   filt = the filtered rows, {removed}; n/a = undefined)")


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


# ---------------------------------------------------------------------------- still-sensor analyses


def add_keep_outliers_argument(parser):
    from ..analysis.noise_model import GROSS_LIMIT_DPS, GROSS_Z

    parser.add_argument("--keep-outliers", action="store_true",
                        help=f"analyse the recording even when it has gross errors (spikes of more than {GROSS_Z:g} robust "
                             f"sigmas, or |rate| > {GROSS_LIMIT_DPS:g} deg/s), which are refused by default")
