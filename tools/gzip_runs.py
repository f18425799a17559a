#!/usr/bin/env python3
"""Runs of one byte, 0x00 or 0xFF, in the deflate data of recordings: what ``gyrofilter.recording.gzipped`` may
take for padding (``RUN_BYTES``). A power cut pads a gzip file with zeros (an SD card) or 0xFF (erased flash);
from such a run on, the reader uses a stream's text only once the stream ends whole: a stream cut short after a run
in its own data is read to the run. So no run in the compressed data of a recording with a time column may be as
long; constant rows without one hold long runs (zeros are deflate's code for "the same again").

    python tools/gzip_runs.py [--rows 300000]

For seven kinds of recording text (constant rates, noise, raw counts with a temperature, six axes: all with a time
column; constant rates and counts without one), gzip levels 1, 6 and 9, and a sync flush (as ``gyrofilter record`` does each second) every
1, 10, 100, 1000 lines or none: how many runs of each byte and length the reader's pieces hold (the gzip header's,
a flush's marker and a member header's zeros aside, as the reader sets them aside). Today: with a time column, runs
of 4 zeros in the block headers of constant text, none longer (``RUN_BYTES`` is 5); without one, constant rows hold
runs of hundreds to thousands of zeros.
"""
import argparse
import collections
import io
import os
import random
import sys
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from gyrofilter.recording.gzip_bytes import RUN_BYTES, pieces  # noqa: E402

HEADER = "# gyrofilter-recording: 1\n# sample_rate_hz: 1000\n# gyro_unit: dps\n"
FLUSHES = (1, 10, 100, 1000, None)
#: the length of the gzip header zlib writes (RFC 1952: no optional fields)
HEADER_BYTES = 10
LEVELS = (1, 6, 9)


def kinds(seed=1):
    """name -> (column row, row maker of the sample index)."""
    rng = random.Random(seed)
    small = lambda n: rng.randint(-n, n)  # noqa: E731
    return {
        "constant": ("t,gx,gy,gz", lambda i: f"{i / 1000:.3f},-3.3,0.0,1.2"),
        "constant, counts": ("t,gx,gy,gz", lambda i: f"{i / 1000:.3f},12,-3,40"),
        "noise": ("t,gx,gy,gz", lambda i: f"{i / 1000:.3f},{rng.gauss(0, 0.05):.4f},{rng.gauss(0, 0.05):.4f},"
                                          f"{rng.gauss(0, 0.05):.4f}"),
        "counts, temp": ("t,gx,gy,gz,temp", lambda i: f"{i / 1000:.3f},{small(3)},{small(3)},{small(3)},"
                                                      f"{36.5 + rng.randint(0, 2) / 340:.4f}"),
        "six axes": ("t,gx,gy,gz,ax,ay,az", lambda i: f"{i / 1000:.3f},{small(30)},{small(3)},{small(3)},{small(100)},"
                                                      f"{small(100)},{16384 + small(100)}"),
        "constant, no time": ("gx,gy,gz", lambda i: "-3.3,0.0,1.2"),
        "counts, no time": ("gx,gy,gz", lambda i: "11,-1,-1"),
    }


def timed(name, seed=1):
    """Whether the kind ``name`` has a time column."""
    return kinds(seed)[name][0].startswith("t,")


def compressed(lines, level, every):
    """The gzip bytes of ``lines`` (bytes, no line ends) at ``level``, sync-flushed every ``every`` lines (None:
    never)."""
    z = zlib.compressobj(level, zlib.DEFLATED, 16 + zlib.MAX_WBITS)
    step, out = every or len(lines), []
    for k in range(0, len(lines), step):
        out.append(z.compress(b"\n".join(lines[k:k + step]) + b"\n"))
        if every:
            out.append(z.flush(zlib.Z_SYNC_FLUSH))
    return b"".join(out) + z.flush()


def runs(rows, seed=1, shortest=2):
    """Counter of (kind, byte, length) of the runs of at least ``shortest`` bytes that the reader's pieces hold (not
    set aside as a flush's marker or a member header's zeros) in every kind's gzip data, every level and flush."""
    found = collections.Counter()
    for name, (columns, row) in kinds(seed).items():
        lines = (HEADER + columns).encode().split(b"\n") + [row(i).encode() for i in range(rows)]
        for level in LEVELS:
            for every in FLUSHES:
                data = compressed(lines, level, every)[HEADER_BYTES:]  # (a member's header is parsed, its zeros no padding)
                for kind, byte, count in pieces(io.BytesIO(b""), data, shortest):
                    if kind == "run":
                        found[name, byte, count] += 1
    return found


def longest_runs(rows, seed=1):
    """kind -> the longest run of 0x00 or 0xFF in its gzip data (0: none of 2 bytes or more)."""
    longest = dict.fromkeys(kinds(seed), 0)
    for name, _, count in runs(rows, seed):
        longest[name] = max(longest[name], count)
    return longest


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=300000, help="rows of each kind (default 300000)")
    args = parser.parse_args()
    longest = longest_runs(args.rows)
    print(f"runs of 0x00 or 0xFF in deflate data of recordings ({args.rows} rows each, levels {LEVELS}, "
          f"sync flush every {FLUSHES} lines), flush markers and member headers aside")
    for name in kinds():
        print(f"  {name:18s} longest run: {longest[name] or 'none'}")
    print(f"with a time column, the longest: {max(n for k, n in longest.items() if timed(k))}; without: "
          f"{min(n for k, n in longest.items() if not timed(k))} or more")
    print(f"the reader's RUN_BYTES (the shortest run from which a stream is on trial): {RUN_BYTES}")


if __name__ == "__main__":
    main()
