"""What the commands that analyse a still recording (``allan``, ``arma``, ``gap``, ``report``) share: the
``--keep-outliers`` option, the way past :func:`gyrofilter.analysis.still.refuse_gross_errors`, and
``--allow-large-mean``, the way past :func:`gyrofilter.analysis.still.refuse_large_mean`."""
from ..analysis.noise.screen import GROSS_LIMIT_DPS, GROSS_Z
from ..analysis.still import refuse_large_mean
from ..errors import SettingsError
from ..filter.calibration import MAX_BIAS_DPS
from ..units import AXES


def add_keep_outliers_argument(parser):
    parser.add_argument("--keep-outliers", action="store_true",
                        help=f"analyse the recording even when it has gross errors (spikes of more than {GROSS_Z:g} robust "
                             f"sigmas, or |rate| > {GROSS_LIMIT_DPS:g} deg/s), which are refused by default")


def add_allow_large_mean_argument(parser):
    parser.add_argument("--allow-large-mean", action="store_true",
                        help=f"analyse the recording even when an axis's mean rate is beyond {MAX_BIAS_DPS:g} deg/s, "
                             "the largest bias of a still MEMS gyro (refused by default: the sensor turned, or the rates "
                             "are in another unit, such as deg/s labelled rad/s)")


def check_mean(path, rec, allow, *, warn):
    """Refuse the recording ``path``, read as ``rec`` (a Recording) by the gap analysis, when an axis's
    mean rate is beyond any bias (:func:`~gyrofilter.analysis.still.refuse_large_mean`, RecordingError;
    with ``allow`` only ``warn(text)``): for the commands whose analysis reads the file itself (gap,
    report), after it, so that a file it cannot read or a moving record is refused in its words."""
    refuse_large_mean(path, rec.gyro_unit, {a: rec.gyro_dps[:, i] for i, a in enumerate(AXES)}, allow, warn=warn)


def refuse_allow_large_mean_in_fleet(args):
    """A fleet refuses each file whose mean rate is beyond any bias: ``--allow-large-mean`` is not
    taken there, and is refused rather than ignored."""
    if args.allow_large_mean:
        raise SettingsError("--allow-large-mean is for one recording; a fleet refuses each file whose mean rate is "
                            "beyond any bias (analyse that file alone)")
