"""The real-time filter of ``replay`` and ``run``: its options (``--preset``, ``--set``,
``--temp-model``, ``--calibration-s``, ``--calibration``, ``--save-calibration``), the
:class:`~gyrofilter.filter.pipeline.GyroFilter` they make, the refusals of what it cannot be fed,
the saved calibration, and how a filtered row and the calibration note are written."""
import argparse

from ..errors import RecordingError, SettingsError
from ..filter.pipeline import GyroFilter
from ..filter.settings import SETTING_NAMES
from ..filter.presets import DEFAULT_PRESET, PRESETS, VIBRATION_RANGE_K
from ..filter.tempcomp import coefficients_from_model
from ..filter.threshold import onset_samples
from ..inputs import did_you_mean, parse_json, quote
from ..recording import EXACT_FORMAT, FILTERED_FORMAT, filtered_words
from ..sim.model import load_model, validate_model
from .console import bias_text, gross_errors_text, say_warning
from .options import decimal, file_name
from .outputs import replacing


#: the formats of a filtered row (t, gx, gy, gz): t exactly, the rates with 9 significant digits
ROW_FORMATS = [EXACT_FORMAT] + [FILTERED_FORMAT] * 3
#: a filtered row as text: run's output and replay --realtime's stdout
ROW_FORMAT = ",".join(ROW_FORMATS)


def calibrated_note(filt):
    """The note a live output gets when the start-up calibration of the filter ``filt`` is done (its
    header cannot have the bias): the bias and the gross errors its window left out."""
    return "calibrated: bias " + bias_text(filt.bias_dps) + gross_errors_text(filt.calibration.rejected)


#: the share of an axis's samples rejected as gross errors beyond which replay and run warn (:func:`rejected_warning`):
#: paper 001's gross errors are occasional (pure noise at 1 kHz: ~0.1 %), while a vibration that swings by more than
#: q within a block had 2-80 % rejected (20 Hz at 100 Hz, 1-3 deg/s), and the block means of what is left biased
REJECTED_WARN_FRACTION = 0.02


def rejected_warning(filt):
    """The warning of a run whose filter ``filt`` rejected more than :data:`REJECTED_WARN_FRACTION` of an axis's
    samples as gross errors, and more than the onset of a vibration costs where q follows it
    (:func:`gyrofilter.filter.threshold.onset_samples`: short records whose rows were right were warned of, attack
    pass 38; with paper 001's fixed q every such share counts, pass 39), or None. A rate that swings by more than q
    (``outlier_q_dps``) within a block (a vibration) loses its extremes to the rule, and the mean of what is left is not the block's: a still sensor on a
    20-Hz, 3-deg/s vibration sampled at 100 Hz read -0.74 deg/s with 80 % rejected and no word (a new user's trial);
    with q above the swing, 0.00. The default preset's q follows the swing (``outlier_range_k``,
    gyrofilter.filter.threshold) and reads 0.00; ``preset="paper"`` keeps paper 001's fixed q and this warning."""
    share = filt.rejected / max(filt.blocks_out * filt.settings.block_len, 1)
    onset = onset_samples(filt.settings)
    over = [f"{axis} {100 * v:.0f} %" for axis, v, n in zip("xyz", share, filt.rejected)
            if v > REJECTED_WARN_FRACTION and n > onset]
    if not over:
        return None
    q = filt.settings.outlier_q_dps
    remedy = "raise q above the swing (--set outlier_q_dps=VALUE)"
    q_text = f"{q:g} deg/s" if not filt.settings.outlier_range_k else f"{q:g} deg/s or more, following the blocks' range"
    if not filt.settings.outlier_range_k:
        remedy = (f"let q follow the swing (--set outlier_range_k={VIBRATION_RANGE_K:g}, as the default preset does) or "
                  f"{remedy}")
    if filt.preset == "paper":  # its Kalman stage can diverge on the swing's block means whatever q is (attack pass 38)
        remedy = (f"use the default preset (drop --preset paper), whose q follows the swing and whose Kalman stage does "
                  f"not diverge on it; or {remedy}")
    return (f"the filter rejected many samples as gross errors ({', '.join(over)} of them; beyond q = {q_text} of "
            f"their block): if they are spikes, the rows are right; if the rate swings by more than q within a block of "
            f"{filt.settings.block_len} samples (a vibration, which `gyrofilter gap` names, or motion faster than the "
            f"blocks), the block means of what is left are biased: {remedy}, and mount a vibrating sensor firmly")


def warn_if_many_rejected(filt):
    """Say :func:`rejected_warning` of the filter ``filt`` on stderr when it has one (replay's and run's ends)."""
    text = rejected_warning(filt)
    if text:
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
        raise SettingsError(f"--set {quote(name)}: not a filter setting{did_you_mean(name, SETTING_NAMES)} (--help lists them)")
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
    checked by the simulator's :func:`~gyrofilter.sim.model.validate_model` (for its numbers
    only: the sample rate and the temperature profile may be missing)."""
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
    The raw recording it came from is what to filter (``allan``, ``gap`` and ``arma`` take either:
    the noise of the output is a fair question, and ``gap`` and ``arma`` say whose noise they
    describe). RecordingError; None for a raw recording."""
    filtered = filtered_words(header)
    if filtered:
        raise RecordingError(f"{where} is {filtered}; filter the raw recording it came from (from a live source: "
                             "`record` it, then replay)")


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


def nothing_filtered(filt):
    """Where ``filt`` (a :class:`~gyrofilter.filter.pipeline.GyroFilter` fed a whole source) stopped
    when it gave no row, as words after "ended" or "stopped": inside the start-up calibration
    window, or fewer samples than a block after it (or after a saved calibration); None once it gave
    a row. The one rule of ``replay``'s and ``run``'s refusal of a source that filtered nothing:
    an output without rows is a header no reader takes ("no samples")."""
    if filt.blocks_out:
        return None
    window = f"the start-up calibration window ({filt.settings.calibration_s:g} s)"
    if filt.calibrating:
        return f"inside {window}"
    if filt.samples_in > filt.pending_samples:
        return f"{filt.pending_samples} sample(s) after {window}, fewer than a block of {filt.settings.block_len}"
    return f"before a block of {filt.settings.block_len} was full ({filt.pending_samples} sample(s))"  # a saved calibration
