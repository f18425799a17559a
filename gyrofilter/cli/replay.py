"""gyrofilter replay: filter a recording with the real-time pipeline and summarise it."""
import json
import time
from importlib import resources

import numpy as np

from ..pipeline import SETTING_NAMES
from ..recording import Recording, read_recording, write_recording
from . import common

BUNDLED = "mpu6050_static_100s.csv.gz"


def add_arguments(parser):
    parser.add_argument("recording", nargs="?", help=f"recording file (format v1, .csv or .csv.gz); default: the bundled {BUNDLED}")
    parser.add_argument("--out", metavar="FILE", help="write the filtered series as a recording (.csv or .csv.gz)")
    parser.add_argument("--plot", metavar="PNG", help="draw raw and filtered rates per axis (needs matplotlib)")
    parser.add_argument("--realtime", action="store_true", help="pace the filter at the recording's sample rate and print each filtered row as it is produced")
    common.add_filter_arguments(parser)


def run(args):
    path = args.recording or str(resources.files("gyrofilter") / "data" / BUNDLED)
    rec = read_recording(path)
    common.print_warnings(rec.warnings)
    common.warn_about_gaps(rec)
    filt = common.make_filter(args, rec.sample_rate_hz)
    gyro = rec.gyro_dps
    common.check_temperature(filt, rec.temp_c is not None, path)
    temps = rec.temp_c if filt.compensates_temperature else None
    if args.realtime:
        filtered = _paced(filt, gyro, rec.sample_rate_hz, temps)
    else:
        filtered = filt.filter(gyro, temps)
    start = len(gyro) - len(filtered) * filt.settings.block_len - filt.pending_samples
    raw = gyro[start : start + len(filtered) * filt.settings.block_len]
    common.print_summary(path, rec, filt, raw, filtered)
    common.save_calibration(args, filt)
    if args.out or args.plot:
        out_rec = _filtered_recording(path, rec, filt, filtered, start)
    if args.out:
        write_recording(args.out, out_rec)
        common.say(f"wrote {len(filtered)} filtered rows to {args.out}")
    if args.plot:
        from ..plots import plot_filtered

        bias = np.asarray(filt.bias_dps)
        plot_filtered(args.plot, rec.t_s, gyro - bias, out_rec.t_s, filtered, title=f"{path} (raw minus start-up bias)")
        common.say(f"drew {args.plot}")
    return 0


def _paced(filt, gyro, rate_hz, temps):
    """Feed samples one by one at the recording's rate, printing rows as they come."""
    rows = []
    t0 = time.monotonic()
    temps = [None] * len(gyro) if temps is None else temps.tolist()
    print("t_s,gx_dps,gy_dps,gz_dps", flush=True)
    for i, (sample, temp) in enumerate(zip(map(tuple, gyro.tolist()), temps)):
        delay = t0 + i / rate_hz - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        row = filt.update(sample, temp)
        if row is not None:
            rows.append(row)
            print(f"{(i + 1) / rate_hz:.4f},{row[0]:.6f},{row[1]:.6f},{row[2]:.6f}", flush=True)
    return np.array(rows).reshape(-1, 3)


def _filtered_recording(path, rec, filt, filtered, start):
    """The filtered rows as a recording; t = time of the last sample of each block."""
    length = filt.settings.block_len
    t_last = rec.t_s[start + length - 1 :: length][: len(filtered)]
    header = {
        "sensor": rec.header.get("sensor", "unknown"),
        "filtered_from": path,
        "filter_preset": filt.preset,
        "filter_settings": json.dumps({k: getattr(filt.settings, k) for k in SETTING_NAMES}, separators=(",", ":")),
        "bias_dps": json.dumps(list(filt.bias_dps or ())),
        "t_meaning": "time of the last input sample of each block (s)",
    }
    return Recording.from_dps(filtered, filt.output_rate_hz, t_s=t_last, header=header)
