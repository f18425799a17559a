"""``gyrofilter convert IN --out REC.csv.gz [--unit dps|rad/s|lsb] [--lsb-per-dps X] [--columns A,B,C[,D]]
[--sample-rate-hz HZ] [--time-unit s|ms|us|ns] [--temp-unit c|mpu6050|none] [--accel-unit m/s^2|g|lsb|none]
[--lsb-per-g X]``: another tool's gyro log (and its temperature and accelerometer columns) (a phone logger's CSV,
a ROS bag export, an Arduino sketch's text) as a recording of format v1, the way to bring your
own data to every other command. The reading rules are :mod:`gyrofilter.recording.foreign`'s;
this module parses argv, writes the file a chunk at a time under a temporary name
(:class:`~gyrofilter.recording.RecordingWriter` in :func:`~gyrofilter.cli.outputs.replacing`: the
file takes its name only when whole) and says what it read.
"""
from .. import __version__
from ..recording import RecordingWriter
from ..recording.foreign import ACCEL_UNIT_CHOICES, TEMP_UNITS, TIME_UNITS, read_foreign
from ..recording.logtext import MAX_PIPE_COPY_BYTES
from ..recording.unit_words import known_unit, units_of
from . import console, options, outputs


def add_arguments(parser):
    parser.add_argument("input", metavar="IN", help="the log: CSV or blank-separated text (gzip too), time and gyro "
                                                    "columns; - reads the standard input (a pipe is read twice from a "
                                                    f"copy in TMPDIR, at most {MAX_PIPE_COPY_BYTES / 2**30:g} GiB and "
                                                    "half its free space)")
    parser.add_argument("--out", required=True, metavar="FILE", type=options.file_name,
                        help="output recording (" + options.RECORDING_FILE_HELP + ")")
    parser.add_argument("--unit", choices=units_of("rate"), default=None,
                        type=lambda text: known_unit("rate", text) or text,
                        help="unit of the gyro columns: dps (also deg/s), rad/s, mdps or mrad/s (converted to dps, rad/s) or lsb "
                             "(default: the one their names state, e.g. 'gyro_x (rad/s)'; never guessed)")
    parser.add_argument("--lsb-per-dps", type=options.lsb_per_dps, default=None, metavar="X",
                        help="LSB per deg/s, with --unit lsb (MPU6050: 131 at +-250 deg/s)")
    parser.add_argument("--columns", default=None, metavar="NAMES",
                        help="the gyro's x,y,z columns, or time,x,y,z: names of the column row or 1-based numbers "
                             "(default: found by their usual names, e.g. timestamp, gyro_x, wx, angular_velocity.x)")
    options.add_sample_rate_argument(parser, help="sample rate in Hz (default: from the time column's mean step, gaps aside; "
                                                  "required without a time column)")
    parser.add_argument("--time-unit", choices=tuple(TIME_UNITS), default=None,
                        help="unit of the time column (default: the one its name states, else the one in which the "
                             "median step gives --sample-rate-hz, else the first of s, ms, us, ns giving 5 Hz or more, "
                             "where no other gives a rate a gyro logs at, 1 Hz to 32 kHz)")
    parser.add_argument("--temp-unit", choices=TEMP_UNITS, default=None,
                        help="unit of the temperature column (TempC, temp_c, Temperature, TEMP ...), written as the "
                             "recording's temp in deg C: c, f or k (converted), or mpu6050 (raw counts: counts / 340 + 36.53); none leaves "
                             "it out (default: the one its name states, e.g. TempC; else it is left out, saying so)")
    parser.add_argument("--accel-unit", choices=ACCEL_UNIT_CHOICES, default=None,
                        help="unit of the accelerometer columns (ax, AccX, acc_x ...), written as ax, ay, az: m/s^2, g, "
                             "mg (converted to g) or lsb (with --lsb-per-g); none leaves them out (default: the one their names state, "
                             "e.g. 'AccX (g)'; else they are left out, saying so)")
    parser.add_argument("--lsb-per-g", type=options.decimal, default=None, metavar="X",
                        help="LSB per g of an accelerometer in lsb (MPU6050: 16384 at +-2 g)")
    options.add_force_argument(parser)


def run(args):
    outputs.check_outputs([args.out], [args.input], args.force)
    columns = None if args.columns is None else [c.strip() for c in args.columns.split(",")]
    with read_foreign(args.input, unit=args.unit, lsb_per_dps=args.lsb_per_dps, columns=columns,
                      sample_rate_hz=options.sample_rate_hz(args), time_unit=args.time_unit, temp_unit=args.temp_unit,
                      accel_unit=args.accel_unit, lsb_per_g=args.lsb_per_g) as foreign:
        header = {**foreign.header, "converted_by": f"gyrofilter {__version__} convert"}
        with outputs.replacing(args.out) as tmp, \
                RecordingWriter(tmp, header, foreign.columns, formats=foreign.formats, flush_interval_s=None,
                                fsync=False) as writer:
            for rows in foreign.chunks():
                writer.write(rows)
    for line in foreign.summary:
        console.say(f"  {line}")
    console.print_warnings(foreign.warnings)
    console.tell(f"wrote {args.out}: {foreign.rows} samples at {foreign.sample_rate_hz:g} Hz "
                 f"({foreign.rows / foreign.sample_rate_hz:g} s), gyro_unit {header['gyro_unit']}"
                 + ("; temp in deg C" if "temp" in foreign.columns else "")
                 + (f"; accel_unit {header['accel_unit']}" if "accel_unit" in header else ""))
    return 0
