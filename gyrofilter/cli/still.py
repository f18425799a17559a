"""What the commands that analyse a still recording (``allan``, ``arma``) share: the
``--keep-outliers`` option, the way past :func:`gyrofilter.analysis.still.refuse_gross_errors`."""
from ..analysis.noise.screen import GROSS_LIMIT_DPS, GROSS_Z


def add_keep_outliers_argument(parser):
    parser.add_argument("--keep-outliers", action="store_true",
                        help=f"analyse the recording even when it has gross errors (spikes of more than {GROSS_Z:g} robust "
                             f"sigmas, or |rate| > {GROSS_LIMIT_DPS:g} deg/s), which are refused by default")
