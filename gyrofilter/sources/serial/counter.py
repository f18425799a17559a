"""The serial line protocol's sample counter (:mod:`gyrofilter.sources.serial.protocol`, whose module docstring
states the protocol): whether the first values of headerless lines count, and which lines of a chunk are corrupt
counters rather than gaps or restarts. Pure functions of the counters."""
from __future__ import annotations

import numpy as np

from ...recording import format_number
from .fields import KNOWN_FIELDS

#: lines whose first value must count (:func:`first_value_counts`) before inferred fields make rows
COUNTING_LINES = 8


def first_value_counts(first, counter_mod):
    """Whether ``first``, the first values of the first lines (at most :data:`COUNTING_LINES`), are a sample
    counter: integers in [0, counter_mod) stepping by exactly 1 (modulo the wrap) in every step but at most one
    (a loss, a duplicate, a restart) when there are 3 steps or more, in every step when fewer.

    Why 8 lines and one step spared (attack pass 37b: ``gx,gy,gz,temp`` lines read as ``counter,gx,gy,gz``): a
    gyro value's step is +1 with probability p, about 0.22 for a still gyro with 1 LSB of white noise (rounded;
    measured over 1e6 steps), so it passes with probability 7 p**6 (1 - p) + p**7 = 6e-4 (a noisier gyro far
    less: 6.5 LSB, an MPU6050 at 131 LSB/(deg/s) and 100 Hz, p = 0.043, 4e-8; a gyro toggling between
    two values steps +1 at most every other step and never passes); a real counter passes unless two of its first
    seven steps are not +1 (two losses, or one corrupt digit, which makes two), and then the stream is refused in one
    line naming the way through, never read wrong. 8 lines are 0.08 s at 100 Hz."""
    first = np.asarray(first, dtype=float)
    valid = (first == np.round(first)) & (first >= 0) & (first < counter_mod)
    steps = len(first) - 1
    ones = int(np.count_nonzero(valid[:-1] & valid[1:] & (np.mod(np.diff(first), counter_mod) == 1))) if steps > 0 else 0
    return steps > 0 and ones >= steps - (steps >= 3)


def not_counting(where, first, fields):
    """The refusal of a stream whose lines' ``first`` values do not count (:func:`first_value_counts`) while
    ``fields`` (:func:`.fields.inferred_fields`) were inferred from their width: what was seen and the way through."""
    shown = ", ".join(format_number(v) for v in first[:4]) + (", ..." if len(first) > 4 else "")
    seen = (f"the first value of the lines does not count ({shown}; a counter steps by 1)" if len(first) > 1 else
            f"the stream ended after one line ({shown} first): one value cannot show a counter counting")
    return (f"{where}: {seen}: without a header naming the fields, {len(fields)} values are {','.join(fields)}; a "
            "device sending other fields (e.g. gx,gy,gz,temp) must send a header line naming them first, "
            "`# gyrofilter-serial: 1 fields=gx,gy,gz,temp` (with gyro_unit=... sample_rate_hz=... in it, or the units "
            f"as options; the fields a header may name: {', '.join(KNOWN_FIELDS)}: a time stamp is not one, a device "
            "sends a sample counter)")


def out_of_sequence(counter, last_counter, mod):
    """Which lines of ``counter`` (valid counters in [0, ``mod``), in order; ``last_counter`` the one before them,
    None at the start) are corrupt: a counter that jumps from the last kept one while the next line's lies between
    the two (999, 1900, 1001; 999, 100, 1001; 999, 1901, 1002 with 1000 lost: a corrupt digit; a real gap or
    restart goes on from the counter it jumped to). Returns (keep: a bool mask, False for a corrupt line;
    the corrupt ones as (index, the counter before, the next counter), in order; whether the last line jumps
    (forwards or back), so that only the next line can tell). Jumps are rare: a loop over them only."""
    n = len(counter)
    keep = np.ones(n, dtype=bool)
    corrupt = []
    last_jumps = False
    before = np.empty(n, dtype=np.int64)
    before[0] = counter[0] - 1 if last_counter is None else last_counter
    before[1:] = counter[:-1]
    todo = sorted(np.flatnonzero((counter - before) % mod > 1).tolist())
    while todo:
        i = todo.pop(0)
        j = i - 1
        while j >= 0 and not keep[j]:
            j -= 1
        prev = int(counter[j]) if j >= 0 else last_counter
        jump = None if prev is None else (int(counter[i]) - prev) % mod
        if jump is None or jump <= 1:
            continue
        if i + 1 == n:
            last_jumps = True
        elif 0 < (int(counter[i + 1]) - prev) % mod < jump:
            keep[i] = False
            corrupt.append((i, prev, int(counter[i + 1])))
            if i + 1 not in todo:
                todo.insert(0, i + 1)
    return keep, corrupt, last_jumps
