"""The argparse types of the commands' options (plain decimal numbers, whole numbers, file names)
and the options several commands share: ``--sample-rate-hz``, ``--force``, a recording's ``--out``."""
import argparse

from ..errors import SettingsError
from ..inputs import parse_number, quote
from ..units import check_lsb_per_dps, check_sample_rate_hz
from . import outputs


#: what --out FILE of a recording takes: any name, the format is CSV text (docs/formats.md, section 1)
RECORDING_FILE_HELP = "recording format v1: CSV text, compressed with gzip when the name ends in .gz, e.g. out.csv or out.csv.gz"


#: the one spelling of a sample rate on the command line (0.2.0 removed ``--rate`` and ``--sample-rate``)
SAMPLE_RATE_OPTION = "--sample-rate-hz"


def add_sample_rate_argument(parser, *, help):
    """:data:`SAMPLE_RATE_OPTION` HZ: ``args.sample_rate_hz`` holds the rate as typed (Hz, None when
    not given); :func:`sample_rate_hz` checks it."""
    parser.add_argument(SAMPLE_RATE_OPTION, type=decimal, default=None, metavar="HZ", dest="sample_rate_hz", help=help)


def sample_rate_hz(args):
    """The rate of :data:`SAMPLE_RATE_OPTION` (Hz), checked by :func:`gyrofilter.units.check_sample_rate_hz`
    with a message that names the option; None when it was not given."""
    return None if args.sample_rate_hz is None else check_sample_rate_hz(args.sample_rate_hz, SAMPLE_RATE_OPTION)


def decimal(text):
    """argparse type of a numeric option: a plain decimal number (:func:`gyrofilter.inputs.parse_number`:
    no ``1_0``, other scripts' digits, ``nan``, ``inf`` or hex), as a float; the option's own range
    is checked where it is used."""
    try:
        return parse_number(text, "")
    except SettingsError as exc:
        raise argparse.ArgumentTypeError(str(exc).strip()) from None


def lsb_per_dps(text):
    """argparse type of ``--lsb-per-dps``: a plain decimal number within
    :data:`gyrofilter.units.LSB_PER_DPS_RANGE` (:func:`gyrofilter.units.check_lsb_per_dps`), as a float."""
    try:
        return check_lsb_per_dps(parse_number(text, ""), "")
    except SettingsError as exc:
        raise argparse.ArgumentTypeError(str(exc).strip()) from None


def number_pair(text):
    """argparse type of an option of two numbers ``LOW,HIGH`` (e.g. ``--kalibr-tau-s 0.1,100``): two
    plain decimal numbers (:func:`gyrofilter.inputs.parse_number`) separated by a comma, as a tuple of
    floats; their range is checked where they are used."""
    parts = text.split(",")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"two numbers LOW,HIGH separated by a comma, got {quote(text)}")
    try:
        return tuple(parse_number(part, "") for part in parts)
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
    """argparse type of an output option: any name but an empty one, or one whose last part is
    longer than the file systems take (:data:`~gyrofilter.files.NAME_MAX_BYTES`: refused
    before any work, not after it); the error names the option."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty name; give a file or folder name")
    too_long = outputs.long_name(text)
    if too_long:
        raise argparse.ArgumentTypeError(too_long)
    return text


def add_force_argument(parser):
    parser.add_argument("--force", action="store_true", help="overwrite output files that exist (an input is never overwritten)")
