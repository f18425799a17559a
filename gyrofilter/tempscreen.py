"""Read glitches of a temperature column (:func:`temp_glitches`) and their replacement by the
interpolation of their good neighbours (:func:`replace_glitches`): the one rule for the gross errors
of a die's temperature, which the gap analysis and the start-up calibration's mean T0 share; and its
causal form for a stream, the running median of the latest temperatures (:func:`running_medians`),
which the filter's temperature compensation takes.

A die's temperature is smooth: a sample far from the median of its neighbours is a read glitch
(an MPU6050 TEMP_OUT of 0x8000 reads -32768 / 340 + 36.53 = -59.85 deg C, inside
``units.TEMP_RANGE_C``), never a temperature.
"""
from __future__ import annotations

import collections

import numpy as np

from .units import MAD_TO_SIGMA

#: half-width k of the median window (2k + 1 samples): runs of up to k glitches side by side are found
TEMP_GLITCH_HALF_WIDTH = 5
#: threshold on |T_i - median| in robust sigmas of those deviations (simulated Gaussian readout noise
#: reaches 6.6 of them in 60 000 samples, see the docstring)
TEMP_GLITCH_Z = 15.0
#: smallest threshold (deg C) whatever the robust sigma (0 for a column sitting on one code), far above
#: one MPU6050 code (1/340 deg C, register map section 4.18) and three codes of the coarse logs at hand
#: (32/340 deg C); a coarser column's floor is TEMP_GLITCH_CODES of its own codes
TEMP_GLITCH_FLOOR_C = 0.3
#: the floor in codes of a quantized column (its smallest nonzero |T_i - median|): a readout that toggles
#: by up to three codes around the die's temperature is no glitch (ADIS16405 TEMP_OUT: 0.14 deg C a code)
TEMP_GLITCH_CODES = 4
#: the coarsest code (deg C) a die's temperature output has: the L3GD20's OUT_TEMP, 1 LSB per deg C
#: (ST L3GD20 datasheet, table 4, TSDr); a smallest departure beyond it is a glitch's, not a code
MAX_CODE_C = 1.0
#: fastest a die's temperature moves (deg C/s), an assumption kept generous: the MPU6050's whole
#: operating range (-40 to +85 deg C, product specification section 6.2) crossed in about 6 s
MAX_DIE_RATE_C_PER_S = 20.0
#: the most that allowance grants (deg C): twice the fastest warm-up at hand (10 deg C in 20 s) over the 5
#: samples from an end at 1 Hz; uncapped it granted 100 deg C at 1 Hz, and a glitch of -59.85 deg C on the
#: first or last sample of a 1-Hz log went through (attack pass 37n)
MAX_END_ALLOWANCE_C = 5.0
#: a column with more glitches than this fraction is not screened into use but left out
MAX_GLITCH_FRACTION = 0.01
_BLOCK = 1 << 16


def temp_glitches(temp_c, sample_rate_hz, *, z=TEMP_GLITCH_Z, floor_c=TEMP_GLITCH_FLOOR_C):
    """Indices (sorted) of the samples of the temperature column ``temp_c`` (deg C, finite) that are
    read glitches rather than the die's temperature.

    With ``k = min(TEMP_GLITCH_HALF_WIDTH, (N - 1) // 2)``, sample i is compared with the median of
    the 2k + 1 samples ``T[s_i .. s_i + 2k]`` around it, ``s_i = clip(i - k, 0, N - 2k - 1)`` (the
    window is shifted inward at the ends): ``d_i = T_i - median``. It is a glitch when

        |d_i| > max(floor_c, TEMP_GLITCH_CODES * q, z * 1.4826 MAD(d)) + min(MAX_DIE_RATE_C_PER_S * e_i / sample_rate_hz,
                                                                       MAX_END_ALLOWANCE_C),

    ``e_i = |i - (s_i + k)|`` the samples from i to its window's centre (0 but within k of the ends),
    ``q`` the smallest nonzero ``|d_i|`` (one code of a quantized column), at most :data:`MAX_CODE_C`,
    and 0 unless more than :data:`MAX_GLITCH_FRACTION` of the samples depart at all: on a column sitting
    on one code, or a smooth staircase (the median passes it unchanged), the only departures are the
    glitches', and taking one as the code hid it (attack pass 37l).
    A median filter (Tukey 1977, running medians) passes a monotone series unchanged, so a warm-up or
    a cool-down of any rate gives d = 0 in the interior, and at the ends it moves by at most the
    die's fastest rate times e_i samples; a series that toggles between codes moves d by one code,
    under the floor. Up to k glitches side by side are found (the median is a good sample's), a
    longer run is not. ``sample_rate_hz`` None: no allowance at the ends (a caller to whom a good
    sample left out costs nothing, e.g. a regression). The MAD (Hampel 1974) makes the threshold follow the readout noise, the floor
    makes it hold when that noise is below one code (MAD 0).

    Checked on every temperature column at hand, no glitch in any: the MPU6050 logs with a temp
    column (4 raw sensorfusion logs, the 4 recordings/ made of them; 32/340 deg C codes, MAD 0,
    largest |d| two codes, 0.19 deg C) and simulated warm-ups and cool-downs (``simulate``'s
    temperature model, 10 Hz to 1 kHz, tau 5-100 s, 10-35 deg C, noise 0 to 0.05 deg C, codes 1/340
    and 0.14 deg C: largest |d| 6.6 robust sigmas, or two codes; tests/test_tempscreen.py holds some).
    """
    t = np.asarray(temp_c, dtype=np.float64).ravel()
    n = t.size
    k = min(TEMP_GLITCH_HALF_WIDTH, (n - 1) // 2)
    if k < 1:
        return np.zeros(0, dtype=np.intp)
    w = 2 * k + 1
    med = np.empty(n - w + 1)
    for lo in range(0, n - w + 1, _BLOCK):  # the median of each window, a block of windows at a time
        hi = min(n - w + 1, lo + _BLOCK)
        med[lo:hi] = np.median(np.lib.stride_tricks.sliding_window_view(t[lo:hi + w - 1], w), axis=1)
    d = np.empty(n)  # T_i - the median of its window: centred inside, shifted inward within k of the ends
    np.subtract(t[k:n - k], med, out=d[k:n - k])
    d[:k], d[n - k:] = t[:k] - med[0], t[n - k:] - med[-1]
    del med
    step = max(1, n // 100_000)
    some = np.abs(d[::step])
    sigma = MAD_TO_SIGMA * float(np.median(np.abs(d[::step] - np.median(d[::step]))))
    departs = some[some > 0]  # a code only where the column's own samples depart (a glitch's alone is no code)
    code = min(float(departs.min()), MAX_CODE_C) if departs.size > MAX_GLITCH_FRACTION * some.size else 0.0
    np.abs(d, out=d)
    limit = max(floor_c, TEMP_GLITCH_CODES * code, z * sigma)
    far = ~(d <= limit)
    if sample_rate_hz is not None:
        e = np.r_[np.arange(k, 0, -1), np.arange(1, k + 1)]  # e_i of the first k and the last k samples
        ends = np.r_[np.arange(k), np.arange(n - k, n)]
        allowance = np.minimum(MAX_DIE_RATE_C_PER_S * e / float(sample_rate_hz), MAX_END_ALLOWANCE_C)
        far[ends] = ~(d[ends] <= limit + allowance)
    return np.flatnonzero(far)


def replace_glitches(temp_c, glitches):
    """``temp_c`` (a new float array) with each sample of ``glitches`` replaced by the linear
    interpolation of its nearest good neighbours in sample index (the nearest good value beyond the
    first or last good sample); unchanged when there are none."""
    t = np.array(temp_c, dtype=np.float64).ravel()
    bad = np.zeros(t.size, dtype=bool)
    bad[np.asarray(glitches, dtype=np.intp)] = True
    if bad.any() and not bad.all():
        good = np.flatnonzero(~bad)
        t[bad] = np.interp(np.flatnonzero(bad), good, t[good])
    return t


def screened_temp(temp_c, sample_rate_hz):
    """``(temp, note)``: the temperature column ``temp_c`` (deg C, finite) with its read glitches
    (:func:`temp_glitches`) replaced by their neighbours' interpolation (:func:`replace_glitches`),
    and a note saying so (None without glitches); ``(None, note)`` when more than
    ``MAX_GLITCH_FRACTION`` of the samples are glitches (a column that broken is not the die's)."""
    t = np.asarray(temp_c, dtype=np.float64).ravel()
    found = temp_glitches(t, sample_rate_hz)
    if not found.size:
        return t, None
    first = f"first at sample {found[0] + 1} (value {t[found[0]]:.4g} C)"
    if found.size > MAX_GLITCH_FRACTION * t.size:
        return None, (f"temp column: {found.size} read glitches (more than {100 * MAX_GLITCH_FRACTION:g} % of its "
                      f"{t.size} samples; {first}): temperature not analysed")
    return replace_glitches(t, found), (f"temp column: {found.size} glitch(es) replaced by their neighbours' "
                                        f"interpolation, {first}")


#: the temperatures a stream's running median is taken over (:func:`running_medians`): a window of the
#: screen's width, so that runs of up to TEMP_GLITCH_HALF_WIDTH glitches move it by no glitch
TEMP_MEDIAN_SAMPLES = 2 * TEMP_GLITCH_HALF_WIDTH + 1


def temperature_history():
    """The latest temperatures of a stream, empty: what :func:`running_medians` and
    :func:`latest_median` keep between calls."""
    return collections.deque(maxlen=TEMP_MEDIAN_SAMPLES)


def latest_median(seen, temp_c, reference_c):
    """:func:`running_medians` of one temperature ``temp_c`` (deg C), pure Python (a stream fed a
    sample at a time): ``seen`` (:func:`temperature_history`) takes it, and the median of what it holds
    is returned; of an even count (at a stream's start, fewer than :data:`TEMP_MEDIAN_SAMPLES` seen: a
    run from a loaded calibration) the middle one nearer the reference ``reference_c`` (T0), not the
    lower: that one was a -59.85 deg C read on the first or second sample (2.5 deg/s on a row, attack
    pass 37n). The first sample alone is its own median."""
    seen.append(temp_c)
    ordered = sorted(seen)
    middle = len(ordered) // 2
    if len(ordered) % 2 == 0 and abs(ordered[middle - 1] - reference_c) <= abs(ordered[middle] - reference_c):
        middle -= 1
    return ordered[middle]


def running_medians(seen, temps_c, reference_c):
    """The running median of a stream's temperatures: for each of ``temps_c`` (deg C), the median of
    it and the :data:`TEMP_MEDIAN_SAMPLES` - 1 temperatures before it (Tukey 1977, running medians),
    fewer at the stream's start (those ``seen`` holds: :func:`temperature_history`, which takes
    ``temps_c`` too; of an even count the middle one nearer the reference T0 ``reference_c``,
    :func:`latest_median`). A run of up to :data:`TEMP_GLITCH_HALF_WIDTH` read glitches moves it by no
    glitch (the median is a good sample's), where a glitch of -59.85 deg C compensated as read moved
    the rate by c x 85 deg C (attack pass 37m); a monotone warm-up passes it unchanged, delayed by
    TEMP_GLITCH_HALF_WIDTH samples (0.05 s at 100 Hz: c x 0.01 deg C at the fastest warm-up at hand,
    10 deg C in 20 s). The same numbers as :func:`latest_median` fed one at a time: the median of an
    odd count is one of the temperatures, whichever way it is found."""
    t = np.asarray(temps_c, dtype=np.float64)
    out = np.empty(t.size)
    j = 0
    while j < t.size and len(seen) < TEMP_MEDIAN_SAMPLES - 1:
        out[j] = latest_median(seen, float(t[j]), reference_c)
        j += 1
    if j < t.size:
        z = np.concatenate([np.array(seen, dtype=np.float64)[-(TEMP_MEDIAN_SAMPLES - 1):], t[j:]])
        for lo in range(0, t.size - j, _BLOCK):
            hi = min(t.size - j, lo + _BLOCK)
            windows = np.lib.stride_tricks.sliding_window_view(z[lo:hi + TEMP_MEDIAN_SAMPLES - 1], TEMP_MEDIAN_SAMPLES)
            out[j + lo:j + hi] = np.median(windows, axis=1)
        seen.extend(t[j:][-TEMP_MEDIAN_SAMPLES:].tolist())
    return out
