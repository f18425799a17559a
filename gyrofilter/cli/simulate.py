"""``gyrofilter simulate --model MODEL.json --duration S [--sample-rate-hz HZ] [--seed N] --out FILE``.

Writes a format-v1 recording (gzip when FILE ends in .gz) from a noise model, streaming in
blocks so that hours at 1 kHz need bounded memory. The model schema is in docs/formats.md; a bad
model is reported in one line naming the key. FILE is refused when it exists (unless ``--force``)
or is the model itself; the recording is written beside it under a temporary name and takes
its place only when complete, so a failed or interrupted run leaves no file behind.
"""
import sys
import time

from ..errors import SettingsError
from ..recording import RecordingWriter
from ..sim.model import ACCELEROMETER, load_model, validate_model
from ..sim.simulate import (MAX_SAMPLES, block_rows, check_sample_count, check_seed, draw_seed, recording_columns,
                            recording_formats, recording_header, simulate_chunks)
from ..effects import REGISTRY, ROWS
from ..units import MAX_DURATION_S, check_duration_s
from . import console, options, outputs

MAX_CHUNK = 2**20  # samples per block; the flicker bank draws (block x components) numbers at once


def add_arguments(parser):
    parser.add_argument("--model", required=True, metavar="MODEL.json",
                        help="noise model (JSON; e.g. the gap report's extended_model, or examples/models/*.json); "
                             "the effects of an axis: " + ", ".join(e.name for e in REGISTRY if e.name not in ROWS)
                             + "; of whole rows (a top-level key): " + ", ".join(ROWS)
                             + "; an accelerometer (ax, ay, az): the top-level key " + ACCELEROMETER
                             + "; their parameters: docs/formats.md, section 2")
    parser.add_argument("--duration", required=True, type=options.decimal, metavar="S", help=f"length of the recording in seconds (at most {MAX_DURATION_S:g}, and {MAX_SAMPLES:.0e} samples)")
    options.add_sample_rate_argument(parser, help="sample rate in Hz (overrides the model's)")
    parser.add_argument("--seed", type=options.whole_number, default=None, metavar="N",
                        help="random seed (same seed, same recording; default: one drawn at random and written in the "
                             "header, simulated_seed, so the run can be repeated)")
    parser.add_argument("--out", required=True, metavar="FILE", type=options.file_name, help="output recording (" + options.RECORDING_FILE_HELP + ")")
    parser.add_argument("--chunk", type=options.whole_number, default=65536, metavar="N", help=f"samples per block written (default 65536, at most {MAX_CHUNK})")
    console.add_progress_argument(parser)
    options.add_force_argument(parser)


def run(args):
    outputs.check_outputs([args.out], [args.model], args.force)
    check_duration_s(args.duration, "--duration")
    sample_rate_hz = options.sample_rate_hz(args)
    if args.seed is not None:
        check_seed(args.seed, "--seed")
    if args.chunk < 1:
        raise SettingsError(f"--chunk must be at least 1 sample, got {args.chunk}")
    if args.chunk > MAX_CHUNK:
        raise SettingsError(f"--chunk must be at most {MAX_CHUNK} samples, got {args.chunk}")
    model = load_model(args.model)
    try:
        spec, warnings = validate_model(model, sample_rate_hz=sample_rate_hz)
    except SettingsError as exc:
        raise SettingsError(f"{args.model}: {exc}") from None
    n_total = check_sample_count(args.duration, spec["sample_rate_hz"], "--duration")
    for text in warnings:
        console.say_warning(f"{args.model}: {text}")
    seed = draw_seed() if args.seed is None else args.seed
    header = recording_header(model, args.duration, seed=seed, validated=spec)
    columns = recording_columns(spec)
    progress = console.ProgressLines(args.progress)
    show = progress.every_line  # a status line rewritten in place; in a log, a line now and then
    done = 0
    last = time.monotonic()
    with outputs.replacing(args.out) as tmp, \
            RecordingWriter(tmp, header, columns, formats=recording_formats(spec), flush_interval_s=None,
                            fsync=False) as writer:
        for block in simulate_chunks(model, args.duration, chunk_samples=args.chunk, seed=seed, validated=spec):
            writer.write(block_rows(block))
            done += len(block.t_s)
            if show and (time.monotonic() - last > 1.0 or done == n_total):
                last = time.monotonic()
                print(f"\rsimulate: {done}/{n_total} samples ({100.0 * done / n_total:.0f} %)", end="", file=sys.stderr)
            elif not show:
                progress(f"simulate: {done}/{n_total} samples ({100.0 * done / n_total:.0f} %)")
    if show:
        print(file=sys.stderr)
    accel = spec[ACCELEROMETER]
    console.tell(f"wrote {args.out}: {n_total} samples at {spec['sample_rate_hz']:g} Hz ({n_total / spec['sample_rate_hz']:g} s), "
                 f"gyro_unit {spec['gyro_unit']}" + (f", accel_unit {accel['accel_unit']}" if accel else "") + f", seed {seed}")
    return 0
