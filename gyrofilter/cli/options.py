"""The argparse types of the commands' options (plain decimal numbers, whole numbers, file names)
and the options several commands share: ``--sample-rate-hz``, ``--force``, a recording's ``--out``."""
import argparse

from ..errors import SettingsError
from ..inputs import parse_number


#: what --out FILE of a recording takes: any name, the format is CSV text (docs/formats.md, section 1)
RECORDING_FILE_HELP = "recording format v1: CSV text, compressed with gzip when the name ends in .gz, e.g. out.csv or out.csv.gz"


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
