"""A still sensor's recording, from the file to its noise coefficients: read the axes, warn about
missing samples, refuse gross errors, say when it moved (:func:`not_static`; when it was clipped:
:func:`~gyrofilter.analysis.clipping.clipped`), characterise each axis (papers 000, 002: the Allan
deviation and its coefficients, :mod:`gyrofilter.analysis.noise.fit`).

The one path from a file to the Allan results of ``gyrofilter allan``, ``gyrofilter arma`` and
a fleet run (:mod:`gyrofilter.analysis.fleet`). Warnings go to the caller's ``warn(text)``;
nothing here prints.
"""
import collections
import collections.abc
import math

import numpy as np

from ..errors import NotStillError, RecordingError
from ..filter.calibration import implausible_bias
from ..recording import ACCEL_COLUMNS, INPUT_RATE_KEY, collect_columns, filtered_from, filtered_words, iter_recording, warn_about_gaps
from ..units import AXES, MAX_ACCEL_MPS2, STANDARD_GRAVITY_MPS2, check_axes, one_value, to_dps, to_mps2
from .noise.allan import MIN_CLUSTERS, AllanInputError, ConstantAxisError
from .stats import block_means
from .noise.fit import characterise_axis
from .noise.model import ACCELEROMETER_TERMS, GYROSCOPE_TERMS
from .noise.screen import GROSS_LIMIT_DPS, GROSS_Z, gross_and_beside, gross_errors, residual_sigma
from .gap.detectors.repeats import repeats_warning
from .repeats import repeated_rows

#: block-mean excursion (deg/s) beyond which a recording is called not static
STATIC_LIMIT_DPS = 1.0
#: block-mean excursion (m/s^2) beyond which an accelerometer's record is called not static: 0.05 g, the
#: gravity a tilt of 3 degrees moves onto a level axis, and 6 times the drift of the MPU6050's zero-g level
#: over 10 deg C (its largest, 60 mg over 70 deg C: PS-MPU-6000A-00 rev 3.4, section 6.2)
STATIC_LIMIT_MPS2 = 0.5
#: the block means of the stillness check: at most this many blocks over the record
STATIC_BLOCKS = 512
#: the magnitude (in g) a still accelerometer's samples may have, ends included: it reads gravity, 1 g
#: (local gravity differs from g_n by 0.3 %), off by its scale and zero-g errors (the MPU6050: +-3 %,
#: +-80 mg; PS-MPU-6000A-00 rev 3.4, section 6.2). A factor 1.5 either way: the factor 2 of a full-scale
#: range read with another's lsb_per_g, 9.81 (g and m/s^2 swapped) or 2048+ (LSB read as g) lie beyond it
GRAVITY_RANGE_G = (1 / 1.5, 1.5)


#: how :func:`not_static` ends its reason: the mark of a record that moved in every warning that
#: carries the reason (the fleet's summary looks for it)
NOT_STATIC = "the recording does not look static"


#: fewest block means whose own spread may tighten :func:`not_static`'s limit (:func:`means_spread`): with
#: 64 or more, one turn's two edges add at most h / sqrt(63) to it (h: the turn's rate), an eighth of h
SPREAD_BLOCKS = 64
#: how far below the white prediction the block means' scatter must fall to tighten the limit: s_y counts
#: as SPREAD_MARGIN s_y, beyond its sampling scatter (heavy-tailed noise, 7 s at 100 Hz, blocks of 2:
#: 53 of 300 records read moved with s_y as it is, 45 as without it, 45 with the margin)
SPREAD_MARGIN = 1.25


#: block means in one mean of :func:`not_static`'s slow scale, and the fewest such means it judges (256 samples)
SLOW_MERGE = SLOW_BLOCKS = 16


def means_spread(y):
    """The scatter of the block means ``y`` as their own adjacent differences tell it,
    s_y = sd(y_{k+1} - y_k) / sqrt(2); infinite with fewer than :data:`SPREAD_BLOCKS` of them.

    White noise of any distribution gives the white prediction sigma / sqrt(L) (var(y_{k+1} - y_k) =
    2 sigma^2 / L); slow bias wander raises it little (it enters only as the change over one block);
    a vibration lowers it: a sinusoid of amplitude A at f leaves block means of amplitude
    A |sin(pi f L / f_s)| / (L |sin(pi f / f_s)|), falling as 1 / L, not 1 / sqrt(L), while it raises
    the first differences' sigma by A |sin(pi f / f_s)|. A turn of rate h over a few blocks adds its two
    edges: at most h sqrt(2 / (n - 1)) / sqrt(2) to s_y over n means. Not robust on purpose: a robust
    scale (1.4826 MAD) reads heavy-tailed noise's block means (examples/models/heavy_tails.json) far
    narrower than their largest, and called its 10- to 40-s records moved in 79 to 100 of 100 seeds
    (2 to 21 without s_y; as many with it, :data:`SPREAD_MARGIN`)."""
    if y.size < SPREAD_BLOCKS:
        return math.inf
    with np.errstate(over="ignore", invalid="ignore"):  # an overflowed record: nan, and the white level rules
        return float(np.std(np.diff(y))) / math.sqrt(2)


def not_static(x_dps, sample_rate_hz, white_std_dps, *, brief=False, limit=STATIC_LIMIT_DPS, unit="deg/s",
               what="rate", gross=None):
    """Why a still gyro's record ``x_dps`` (deg/s) looks moved, or None when it looks still
    (``brief``: only how far it moves, for a refusal that must stay one short line).

    The means of at most 512 consecutive blocks of L samples; the largest distance of one from their median is the
    excursion. A still gyro's block means scatter by its white noise sigma / sqrt(L) (``white_std_dps``: the
    per-sample sigma, deg/s) plus slow bias wander; more than max(1 deg/s, 8 min(sigma / sqrt(L), 1.25 s_y)) is
    motion (or a bias far beyond any MEMS gyro's instability). s_y: the block means' own scatter
    (:func:`means_spread`; 1.25: :data:`SPREAD_MARGIN`), below sigma / sqrt(L) when a vibration raises sigma but
    averages out in the blocks: 10 deg/s at 23.7 Hz sampled at 100 Hz raised 8 sigma / sqrt(L) to 11.1 deg/s over
    120 s, and a 50-degree turn at 10 deg/s read still (8 s_y: 4.9). Never more permissive than sigma / sqrt(L).
    The same rule judges the means of :data:`SLOW_MERGE` consecutive blocks (16 L samples, at least
    :data:`SLOW_BLOCKS` of them; at most 32, fewer than SPREAD_BLOCKS, so there the limit is max(limit, 8 sigma /
    sqrt(16 L))) too: a vibration's leftover falls as 1 / L, the limit as 1 / sqrt(L), and a turn over several
    blocks keeps its height (100 Hz, 30 s, 20 deg/s at 12.4 Hz: a 5-s turn of 20 deg/s read still at L = 6, 8 min(3.10,
    5.82) = 24.8 deg/s; 6.2 at 16 L). An accelerometer is judged so with ``limit`` = :data:`STATIC_LIMIT_MPS2` in m/s^2.

    The record is judged without its spikes and the samples beside them
    (:func:`~gyrofilter.analysis.noise.screen.gross_and_beside`, or ``gross``: their indices when the
    caller has them): a block's mean is that of its other samples. A spike is a gross error, not
    motion: one of 150 deg/s moved a 117-sample block's mean by 1.28 deg/s, and a still 600-s record
    at 100 Hz with 1 to 10 spikes of 5 to 500 deg/s read "moved" in 157 of 200 seeds (0 without).
    Only isolated ones (:func:`isolated`): a longer run of them is motion, judged with its samples."""
    x = np.asarray(x_dps, dtype=float)
    y, length = block_means(x, STATIC_BLOCKS)
    if y.size == 0:
        return None
    gross = isolated(x, gross_and_beside(x) if gross is None else gross)
    gross = gross[gross < y.size * length]
    if gross.size:  # each block's mean over its other samples: sum(x) - sum(spikes) over L - count
        block = gross // length
        kept = length - np.bincount(block, minlength=y.size)
        with np.errstate(over="ignore", invalid="ignore"):
            y = (y * length - np.bincount(block, weights=x[gross], minlength=y.size)) / np.maximum(kept, 1)
        y = y[kept > 0]
        if y.size == 0:  # every block all spikes (a square wave at f_s / 2 reads so): nothing to judge here
            return None
    scales = [(y, length)]
    if y.size >= SLOW_MERGE * SLOW_BLOCKS:  # the slow scale: means of SLOW_MERGE blocks
        scales.append((y[:y.size // SLOW_MERGE * SLOW_MERGE].reshape(-1, SLOW_MERGE).mean(axis=1), length * SLOW_MERGE))
    for y, length in scales:
        excursion = float(np.max(np.abs(y - np.median(y))))
        if excursion > max(limit, 8 * min(white_std_dps / math.sqrt(length), SPREAD_MARGIN * means_spread(y))):
            break
    else:
        return None
    if brief:
        return f"it moves by up to {excursion:.3g} {unit}"
    return (f"the {what} moves by up to {excursion:.3g} {unit} (averages over {length / sample_rate_hz:.2g} s): "
            f"{NOT_STATIC}")


#: the longest run of consecutive samples an isolated spike or pair leaves out (:func:`isolated`): a pair's
#: four residuals alike (its two samples and one beside each, :func:`gross_errors` finds any of them) and
#: two samples beside either end
SPIKE_RUN = 8
#: how far (in robust sigmas of the second-difference residual, :func:`residual_sigma`) a sample of a longer
#: run must stand from the samples around the run to be raised (:func:`isolated`): a fifth of the spike
#: threshold GROSS_Z. White noise reaches it (12 sigma) never; the plateau of a turn whose edges the screen
#: found stands at least 2 GROSS_Z from it (an edge's residual is half the turn's rate)
RAISED_Z = GROSS_Z / 5
#: samples on each side of a run whose median is the baseline its samples are judged against
BASELINE_SAMPLES = SPIKE_RUN


def isolated(x_dps, gross):
    """The indices of ``gross`` (sorted: spikes and the samples beside them,
    :func:`~gyrofilter.analysis.noise.screen.gross_and_beside`) that are isolated spikes and pairs, not
    motion made of them; ``x_dps``: the record (deg/s, or any unit) they index.

    ``gross`` falls into runs of consecutive samples. A run of at most :data:`SPIKE_RUN` is a spike or a
    pair (a 3- or 4-sample turn may look like one: a detection limit). A longer run is judged by its
    content: its raised samples, |x_i - m| > :data:`RAISED_Z` sigma_r (m: the median of the
    :data:`BASELINE_SAMPLES` samples on either side of the run; sigma_r: :func:`residual_sigma`), come
    in groups of at most two consecutive samples (spikes and pairs, at the baseline between them:
    two spikes 4 or 5 samples apart make a run of 9 or 10), or it is motion: a turn in 5 samples or
    more raises them all (its edges are the spikes the screen found), and so does a turn under a
    vibration of f_s/10 or faster (a 5-s turn at 10 deg/s under 100 deg/s at 10 Hz)."""
    gross = np.asarray(gross)
    if gross.size == 0:
        return gross
    ends = np.flatnonzero(np.diff(gross) != 1) + 1
    starts = np.r_[0, ends]
    runs = np.diff(np.r_[starts, gross.size])
    spikes = runs <= SPIKE_RUN
    if not spikes.all():
        spikes[~spikes] = _raised_alone(np.asarray(x_dps, dtype=float), gross[starts[~spikes]], runs[~spikes])
    return gross[np.repeat(spikes, runs)]


def _raised_alone(x, first, length):
    """For each run of samples ``first[k] .. first[k] + length[k] - 1`` of ``x``: True when its raised
    samples (:func:`isolated`) come in groups of at most two."""
    side = np.arange(1, BASELINE_SAMPLES + 1)
    around = np.clip(np.c_[first[:, None] - side, (first + length - 1)[:, None] + side], 0, x.size - 1)
    with np.errstate(over="ignore", invalid="ignore"):
        base = np.median(x[around], axis=1)
        run = np.repeat(np.arange(first.size), length)
        at = np.repeat(first - np.r_[0, np.cumsum(length)[:-1]], length) + np.arange(length.sum())
        raised = ~(np.abs(x[at] - base[run]) <= RAISED_Z * residual_sigma(x))
    # three raised in a row within one run: x_i, x_{i+1}, x_{i+2} of the same run
    three = raised[:-2] & raised[1:-1] & raised[2:] & (run[:-2] == run[2:])
    return np.bincount(run[:-2][three], minlength=first.size) == 0


def moved(x_dps, sample_rate_hz, *, brief=False, **sensor):
    """:func:`not_static` of the series ``x_dps`` (deg/s) with its white level from the first
    differences, ``sd(diff x) / sqrt(2)``, as every still-sensor analysis (allan, gap, report)
    judges it: why it looks moved, or None; both without the spikes (:func:`not_static`: the
    differences beside one are left out). ``sensor``: :func:`not_static`'s ``limit``, ``unit``
    and ``what`` for another sensor than the gyro."""
    x = np.asarray(x_dps, dtype=float)
    gross = gross_and_beside(x)
    with np.errstate(over="ignore", invalid="ignore"):  # values too large for float64: the analyses say so
        d = np.diff(x)
        if gross.size and d.size:
            d = np.delete(d, np.unique(np.clip(np.r_[gross - 1, gross], 0, d.size - 1)))  # beside one
        return not_static(x, sample_rate_hz, _spent_sd(d) / math.sqrt(2) if d.size else 0.0,
                          brief=brief, gross=gross, **sensor)


def refuse_moved(path, axis, x_dps, sample_rate_hz, *, gross_refused=False):
    """Raise NotStillError, one short line naming ``path`` and ``axis``, when the gyro axis's record
    ``x_dps`` (deg/s) looks moved (:func:`moved`): the refusal of ``gap`` and of a fleet's records
    (``--allow-motion`` analyses them anyway). With ``gross_refused`` (the caller refuses gross errors
    next, :func:`refuse_gross_errors`: allan's fleet) the advice names ``--keep-outliers`` too when the
    record has them (:func:`gross_errors`: a turn's fast edges read as spikes)."""
    x = np.asarray(x_dps, dtype=float)
    why = moved(x, sample_rate_hz, brief=True)
    if why:
        advice = "--allow-motion analyses it anyway"
        if gross_refused and gross_errors(x).size:
            advice = "--allow-motion --keep-outliers analyses it anyway (its motion reads as gross errors)"
        raise NotStillError(f"{path}: axis {axis} is not still ({why}); {advice}")


def _spent_sd(d):
    """``np.std(d)`` (ddof 0) by numpy's own steps (the mean, the deviations, the mean of their
    squares, its square root), the deviations formed in ``d`` itself: the same number without
    np.std's copy of ``d`` (29 MB for an hour at 1 kHz). ``d`` is spent."""
    d -= d.mean()
    np.multiply(d, d, out=d)
    return math.sqrt(d.sum() / d.size)


class HeldColumns(collections.abc.Mapping):
    """Columns held as the file gave them, each converted to float64 in the analysis' unit only when
    taken, one at a time: {name: array} (``convert(column)``, e.g. :func:`~gyrofilter.units.to_dps`).
    Held as :func:`gyrofilter.recording.collect_columns` keeps them with ``compact``: float32 where
    every value of the column is a float32 exactly (the integers of an ``lsb`` column), so
    float64(held) is the file's value and a taken column holds the numbers of a float64 column
    converted at once: the results are the same, the memory half the held columns' plus the one
    taken; a float32 column whose values are all int16 integers (an ``lsb`` column: the sensor's
    16-bit registers) is held as int16, a quarter. Each taking converts anew; :meth:`pop` frees the
    column."""

    def __init__(self, columns, convert):
        self._columns, self._convert = {name: narrowed(c) for name, c in columns.items()}, convert

    def __getitem__(self, name):
        return self._convert(self._columns[name])

    def __iter__(self):
        return iter(self._columns)

    def __len__(self):
        return len(self._columns)

    def pop(self, name):
        """The column ``name`` converted, no longer held."""
        return self._convert(self._columns.pop(name))

    def part(self, name, start, stop):
        """The rows ``start:stop`` of the column ``name``, converted (the same numbers as those rows of
        the whole column's: the conversions are element-wise)."""
        return self._convert(self._columns[name][start:stop])

    def rows(self):
        """The columns' length."""
        return len(next(iter(self._columns.values()))) if self._columns else 0

    def renamed(self, names):
        """The columns of ``names`` ({new name: name}) taken out of this one into a new HeldColumns."""
        return HeldColumns({new: self._columns.pop(old) for new, old in names.items()}, self._convert)


def narrowed(column):
    """``column`` as int16 when it is float32 and every value is an int16 integer exactly (float64 of
    either is the same number; a -0 keeps the column float32), else as it is."""
    if column.dtype != np.float32:
        return column
    with np.errstate(invalid="ignore"):  # a value beyond int16 casts to another: then not equal
        small = column.astype(np.int16)
    exact = np.array_equal(small, column) and not np.signbit(column[small == 0]).any()
    return small if exact else column


def read_axes(path, axes, with_t=False, with_accel=False, held=False):
    """The rates of ``axes`` (deg/s), one float64 array per axis, read in chunks
    (:func:`gyrofilter.recording.collect_columns`). Returns (head, {axis: array}), and with
    ``with_t`` (head, {axis: array}, t): the ``t`` column (s), or None when the file has none.
    With ``with_accel`` the accelerations of all three axes follow (a still one's gravity is their
    magnitude: :func:`gravity_unlike`), a :class:`HeldColumns` {column: array} taken in m/s^2
    (columns ``ax``...; :func:`gyrofilter.units.to_mps2` from the header's ``accel_unit``), or None
    when the file has no accelerometer it can read (:func:`accelerometer_note` says why).

    ``path``: a format-v1 recording (``.csv`` or ``.csv.gz``); ``axes``: axis letters, e.g.
    :data:`~gyrofilter.units.AXES` or ``"z"`` (columns ``gx``...). ``head`` is the
    :class:`~gyrofilter.recording.RecordingHead` after the whole file was read (its warnings,
    notes, ``t_gaps`` and ``sample_rate_hz`` in Hz); the arrays are converted from the file's
    ``gyro_unit``. RecordingError for a bad file or one without samples. With ``held`` the rates
    are a :class:`HeldColumns` too, and both are held as read (int16 or float32 where exact: the
    same numbers when taken, a quarter to half the memory until then), ``t`` float64 as always.
    """
    axes = check_axes(axes)
    chunks = iter_recording(path)
    head = next(chunks)
    times = ["t"] if with_t and "t" in head.names else []
    accel = list(ACCEL_COLUMNS) if with_accel and has_accelerometer(head) else []
    columns = collect_columns(head, chunks, [f"g{a}" for a in axes] + times + accel, compact=held)
    if head.rows == 0:
        raise RecordingError(f"{path}: no samples (the file has a header only)")

    def dps(x):
        return to_dps(x, head.gyro_unit, head.lsb_per_dps)

    def mps2(x):
        return to_mps2(x, head.accel_unit, head.lsb_per_g)

    if held:
        series = HeldColumns({a: columns.pop(f"g{a}") for a in axes}, dps)
    else:
        series = {a: dps(columns.pop(f"g{a}")) for a in axes}
    accel_columns = HeldColumns({c: columns.pop(c) for c in accel}, mps2) if accel else None
    out = (head, series) + ((None if not times else np.asarray(columns.pop("t"), dtype=float),) if with_t else ())
    return out + ((accel_columns,) if with_accel else ())


def has_accelerometer(head):
    """True when the recording ``head`` (a RecordingHead) has an accelerometer an analysis can read:
    the columns ``ax, ay, az`` and the header's ``accel_unit``."""
    return all(c in head.names for c in ACCEL_COLUMNS) and head.accel_unit is not None


#: rows of the accelerometer's magnitude formed at a time (:func:`gravity_unlike`)
GRAVITY_BLOCK_ROWS = 1 << 16


def gravity_unlike(accel_mps2, head):
    """Why the accelerometer's samples ``accel_mps2`` (:class:`HeldColumns` of ``ax, ay, az`` in m/s^2) cannot be a
    still sensor's in the unit its header states, or None. A still accelerometer reads gravity: the
    median over the samples of |a| = sqrt(ax^2 + ay^2 + az^2) lies within :data:`GRAVITY_RANGE_G`
    (motion and tilts move gravity between the axes, not its magnitude). A magnitude beyond them is
    a wrong ``accel_unit`` or ``lsb_per_g`` (every coefficient scaled by the same wrong factor, none
    of them the sensor's) or an output with gravity removed. All three axes, whichever are analysed;
    |a| formed :data:`GRAVITY_BLOCK_ROWS` rows at a time (one float64 column in memory)."""
    magnitude = np.empty(accel_mps2.rows())
    with np.errstate(over="ignore"):
        for start in range(0, magnitude.size, GRAVITY_BLOCK_ROWS):
            stop = start + GRAVITY_BLOCK_ROWS
            magnitude[start:stop] = np.sqrt(sum(np.square(accel_mps2.part(c, start, stop)) for c in ACCEL_COLUMNS))
    g = float(np.median(magnitude)) / STANDARD_GRAVITY_MPS2
    low, high = GRAVITY_RANGE_G
    if low <= g <= high:
        return None
    unit = head.accel_unit + (f" (lsb_per_g {head.lsb_per_g:g})" if head.accel_unit == "lsb" else "")
    return (f"{head.path}: the accelerometer reads {g:.3g} g at rest (the median |a|), but a "
            f"still one reads gravity, 1 g (within {low:.2g} .. {high:g} g): is accel_unit {unit} right? (an output "
            "with gravity removed is not the sensor's)")


def decimated_accelerometer(head):
    """Why the accelerometer of the recording ``head`` is not the sensor's samples, or None: the
    filter's output (``filtered_from``; ``run --out`` keeps the source's ``ax, ay, az``) keeps one raw
    accelerometer sample per output row, every k-th of the sensor's (k = ``input_sample_rate_hz`` /
    ``sample_rate_hz``): white noise kept every k-th sample at 1/k the rate reads a density
    ``sigma / sqrt(f_s / k)``, sqrt(k) times the sensor's (a new user read 900 ug/sqrt(Hz) for the
    sensor's 390 at k = 5)."""
    if filtered_from(head.header) is None:
        return None
    rate_in = head.header.get(INPUT_RATE_KEY)
    k = float(rate_in) / head.sample_rate_hz if rate_in else None
    every = f"1 in {k:.3g} of the sensor's samples" if k else "one of each block"
    times = f"sqrt({k:.3g}) = {math.sqrt(k):.3g} times it" if k else "sqrt(block length) times it"
    return (f"{head.path}: the filter's output keeps one raw accelerometer sample per row ({every}): its noise is not "
            f"the sensor's (the density reads {times}); analyse the recording it was filtered from")


#: the start of :func:`accelerometer_note` (a fleet's console names the units it holds for)
NO_ACCEL_UNIT = f"the accelerometer ({', '.join(ACCEL_COLUMNS)}) is not analysed: "


def accelerometer_note(head):
    """Why the accelerometer of the recording ``head`` is not analysed although it has the columns
    ``ax, ay, az`` (no ``accel_unit`` in its header: their unit is not known), or None (it has
    none, or it is analysed). It starts with :data:`NO_ACCEL_UNIT`."""
    if all(c in head.names for c in ACCEL_COLUMNS) and head.accel_unit is None:
        return (f"{NO_ACCEL_UNIT}the header has no accel_unit, so its unit is not known (add "
                "'# accel_unit: m/s^2|g|lsb' to analyse it)")
    return None


def refuse_gross_errors(head, series, keep, *, warn, first_row=0, unit="deg/s", limit=GROSS_LIMIT_DPS):
    """Refuse a still-sensor analysis (allan, arma) of data with gross errors, naming the first
    by file, line, sample, axis and value and counting them per axis
    (:func:`~gyrofilter.analysis.noise.screen.gross_errors`); with ``keep`` only warn (``warn(text)``).
    Samples are never dropped. ``series`` start at the file's sample ``first_row``.

    ``head``: the file's :class:`~gyrofilter.recording.RecordingHead` (for its path and line
    numbers); ``series``: axis letter -> rates (deg/s); ``keep``: True to warn instead of
    refusing (``--keep-outliers``); ``first_row``: file sample index (0-based) of ``series[...][0]``.
    A gross error is a spike beyond ``GROSS_Z`` robust sigmas or beyond ``limit`` (default
    ``GROSS_LIMIT_DPS``, deg/s; an accelerometer's series in ``unit`` m/s^2 take
    :data:`~gyrofilter.units.MAX_ACCEL_MPS2`). A filter's output (``filtered_from``) is named so: its jumps may be
    the filter's own. Returns None; raises RecordingError when refusing.
    """
    found = {a: idx for a, idx in ((a, gross_errors(x, limit_dps=limit)) for a, x in series.items()) if idx.size}
    if not found:
        return
    axis = min(found, key=lambda a: found[a][0])
    row = int(found[axis][0])
    counts = ", ".join(f"{a}: {idx.size}" for a, idx in found.items())
    text = (f"{head.path}: line {head.line_of_row(first_row + row)} (sample {first_row + row}): {axis} = "
            f"{series[axis][row]:.6g} {unit} is a gross "
            f"error (a spike beyond {GROSS_Z:g} robust sigmas of the noise, or beyond {limit:g} {unit}), and "
            f"{sum(idx.size for idx in found.values())} such sample(s) in all ({counts}); the analysis assumes a still "
            "sensor without spikes (if the sensor moved, record it at rest)")
    filtered = filtered_words(head.header)
    if filtered and not keep:  # attack pass 60: six example models' replay outputs refused so, unexplained
        raise RecordingError(f"{text}; this is {filtered}, whose jumps may be the filter's own (following the bias, "
                             "passing a vibration) or the sensor's: analyse the recording it was filtered from, or rerun "
                             "with --keep-outliers to analyse the output as it is")
    if not keep:
        raise RecordingError(f"{text}: fix the data, or rerun with --keep-outliers to analyse them as they are")
    warn(f"{text}: analysed as they are (--keep-outliers)")


def not_analysed(axes):
    """The axes of :data:`~gyrofilter.units.AXES` not in ``axes``, in order: the ones whose means
    :func:`refuse_large_mean` checks too (a unit mistake is the whole file's: ``allan --axes x`` of
    deg/s labelled rad/s passed on x at 11.5 "deg/s" while z read 229)."""
    return tuple(a for a in AXES if a not in axes)


def refuse_large_mean(path, gyro_unit, series, allow, *, warn):
    """Refuse a still-sensor analysis (allan, arma, gap, report) of data whose mean rate on an axis is
    beyond any MEMS bias (:func:`gyrofilter.filter.calibration.implausible_bias`, the rule replay's
    start-up calibration applies): a still gyro's mean rate is its bias, so such a mean says the
    sensor turned or the rates are in another unit (deg/s labelled rad/s reads 57.3 times too large),
    and every coefficient would be as wrong. With ``allow`` (``--allow-large-mean``: the mean is
    real; ``report``, whose page lists its warnings) only warn (``warn(text)``). ``path``: the file;
    ``gyro_unit``: the unit it states; ``series``: axis letter -> rates (deg/s). Returns None;
    raises RecordingError naming the file when refusing. The callers give every gyro axis of the
    file (:func:`not_analysed`), not only the ones analysed."""
    for axis in sorted(series):  # one converted column at a time
        text = implausible_bias(axis, float(np.mean(series[axis])), unit=gyro_unit)
        if text is None:
            continue
        if not allow:
            raise RecordingError(f"{path}: {text}? Fix the unit (the header's gyro_unit or lsb_per_dps, or convert the "
                                 "log again with its --unit), or analyse the file alone with --allow-large-mean "
                                 "if the mean is real")
        warn(f"{path}: {text}? Analysed as it is: its coefficients hold only if the mean is real")


#: what ends the warning of an axis :func:`characterise_recording` leaves out ("axis x: ...")
LEFT_OUT = ": left out of the Allan analysis"


#: what lost samples (the t column's gaps) mean for the Allan deviation: the end of their warning
GAPS_CONSEQUENCE = "the Allan deviation assumes uniform samples"


def characterise_recording(path, *, axes=AXES, confidence=0.95, min_clusters=MIN_CLUSTERS, keep_outliers=False, warn,
                           progress=None, skip_constant=False, allow_large_mean=False, refuse_motion=False):
    """Read a still recording and characterise each of ``axes`` of every sensor it holds: (head,
    {axis: AxisNoise}, the count of its repeated rows, the accelerometer's {axis: AxisNoise} or None,
    why the record's accelerometer was left out whole or None).

    The one path from a file to its Allan results, for one recording and for a fleet
    (:mod:`gyrofilter.analysis.fleet`). The reader's warnings, missing samples and gross errors kept with
    ``keep_outliers`` go to ``warn(text)`` as they are found; gross errors otherwise raise
    RecordingError, as does a mean rate beyond any bias unless ``allow_large_mean``
    (:func:`refuse_large_mean`), and a result that is not finite raises AllanInputError (both name the file).
    ``progress(text)``, if given, is told each axis as it starts; the axes' own warnings (a record
    that does not look static, :func:`not_static`; a poor fit) stay in their results
    (``AxisNoise.warnings``, the JSON document's ``warnings``); with ``refuse_motion`` (a fleet's
    records) a gyro axis that looks moved raises NotStillError instead (:func:`refuse_moved`).

    ``path``: the recording; ``axes``: axis letters (default all, :data:`~gyrofilter.units.AXES`); ``confidence``: level of the
    Allan deviation's confidence intervals (0 to MAX_CONFIDENCE 0.9999, 0.95 = 95 %); ``min_clusters``: fewest
    clusters an averaging time tau needs to be used; ``keep_outliers``: analyse gross errors
    instead of refusing. Each :class:`~gyrofilter.analysis.noise.model.AxisNoise` holds the
    Allan deviation (deg/s) against tau (s) and the fitted coefficients (N in deg/sqrt(s) = deg/s/sqrt(Hz),
    B in deg/s, K in deg/s/sqrt(s); :mod:`gyrofilter.analysis.noise.model`).
    An axis whose samples are all equal (stuck) raises ConstantAxisError; with ``skip_constant``
    it is left out instead, said through ``warn``, while another axis is analysed (a sensor
    report, a fleet: one stuck axis does not cost the others' results). The rows of ``axes``
    that repeat the previous one (:func:`gyrofilter.analysis.repeats.repeated_rows`, a
    :class:`~gyrofilter.analysis.repeats.RepeatedRows`) are counted before any axis, and said
    through ``warn`` when more than chance (they bias the short-tau deviation low and the fitted N).

    Where the record has an accelerometer (:func:`has_accelerometer`), the same ``axes`` of it are
    characterised the same way in m/s^2 (coefficients in the units of
    :data:`~gyrofilter.analysis.noise.model.ACCELEROMETER_TERMS`), its gross errors refused or
    warned of as the gyro's (beyond :data:`~gyrofilter.units.MAX_ACCEL_MPS2`; refused, it is left
    out with the refusal as a warning, the gyro's results kept), its stillness judged
    against :data:`STATIC_LIMIT_MPS2`; its messages name the axes by their columns (``az``). Gravity,
    a constant on the axis that points up, does not enter: the Allan deviation is formed of the
    mean-removed series (:mod:`gyrofilter.analysis.noise.allan`, ``_phase``), so a 9.81 m/s^2 offset
    costs no float64 precision. A constant accelerometer axis is left out, said through ``warn``,
    whatever ``skip_constant`` says: it never costs the gyro's results (None when every axis is);
    so is the whole accelerometer when its samples do not read gravity (:func:`gravity_unlike`).
    The last item says why the whole accelerometer was left out (the warning's text without
    :data:`LEFT_OUT`; ``allan --json``'s ``accelerometer_left_out``), None when it was not.
    Columns ``ax, ay, az`` without the header's ``accel_unit`` are not analysed: a warning says so
    (:func:`accelerometer_note`), after the reader's, for ``allan``, ``report`` and the fleet alike.
    """
    axes = check_axes(axes)
    head, series, accel = read_axes(path, axes + not_analysed(axes), with_accel=True, held=True)  # converted when taken
    others = {a: series.pop(a) for a in not_analysed(axes)}  # their means too: a unit mistake is the file's
    filtered = filtered_words(head.header)  # a new user read the output's N of 2.8e-5, a resolved K, as the sensor's
    notes = [accelerometer_note(head), filtered and (f"{path}: is {filtered}: its Allan deviation is the filter's "
                                                     "(block means, bias removed, smoothed), not the sensor's noise; "
                                                     "analyse the recording it was filtered from")]
    for text in head.warnings + [note for note in notes if note]:
        warn(text)
    warn_about_gaps(head, GAPS_CONSEQUENCE, warn)
    if refuse_motion:  # before the spikes and the mean: a turning gyro's are the motion's
        for a in axes:
            refuse_moved(path, a, series[a], head.sample_rate_hz, gross_refused=not keep_outliers)
    refuse_gross_errors(head, series, keep_outliers, warn=warn)
    refuse_large_mean(head.path, head.gyro_unit, collections.ChainMap(series, others), allow_large_mean, warn=warn)
    del others
    left_out = None
    if accel is not None:
        unlike = decimated_accelerometer(head) or gravity_unlike(accel, head)
        accel = accel.renamed({f"a{a}": f"a{a}" for a in axes})  # the axes analysed
        try:
            refuse_gross_errors(head, accel, keep_outliers, warn=warn, unit="m/s^2", limit=MAX_ACCEL_MPS2)
        except RecordingError as exc:  # the accelerometer's spikes cost it alone, not the gyro's results
            unlike = str(exc)
        if unlike:  # or its unit is wrong: every coefficient would be off by the same factor
            warn(f"{unlike}{LEFT_OUT}")
            accel, left_out = None, unlike
    repeats = repeated_rows((series[a] for a in axes), 1.0 / head.lsb_per_dps if head.gyro_unit == "lsb" else None,
                            axes=axes)
    said = repeats_warning(repeats)
    if said:
        warn(f"{path}: {said}")
    settings = {"path": path, "head": head, "confidence": confidence, "min_clusters": min_clusters, "warn": warn,
                "progress": progress}
    results = _characterise_sensor(series, GYRO_SENSOR, skip_constant=skip_constant, **settings)
    accel_results = None
    if accel is not None:
        accel_results = _characterise_sensor(accel.renamed({a: f"a{a}" for a in axes}), ACCEL_SENSOR, skip_constant=True,
                                             **settings) or None
        if accel_results is None:
            left_out = f"{path}: every accelerometer axis analysed ({', '.join('a' + a for a in axes)}) is constant"
    return head, results, repeats, accel_results, left_out


#: how :func:`characterise_recording` treats each sensor: the prefix of its axis names in messages,
#: its unit, the word for it and its stillness limit (:func:`not_static`)
GYRO_SENSOR = {"prefix": "", "unit": GYROSCOPE_TERMS.unit, "word": "gyro", "still": {}}
ACCEL_SENSOR = {"prefix": "a", "unit": ACCELEROMETER_TERMS.unit, "word": "accelerometer",
                "still": {"limit": STATIC_LIMIT_MPS2, "unit": ACCELEROMETER_TERMS.unit, "what": "acceleration"}}


def _characterise_sensor(series, sensor, *, path, head, confidence, min_clusters, warn, progress, skip_constant):
    """{axis: AxisNoise} of one sensor's ``series`` ({axis letter: values in ``sensor``'s unit}, emptied
    as it goes), as :func:`characterise_recording` states."""
    axes = "".join(series)
    results = {}
    for a in axes:
        x = series.pop(a)
        name = sensor["prefix"] + a
        motion = moved(x, head.sample_rate_hz, **sensor["still"])
        if progress:
            progress(f"allan: {'' if not sensor['prefix'] else sensor['word'] + ' '}axis {a} ({head.rows} samples)...")
        try:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # check_finite names an overflow
                results[a] = characterise_axis(x, head.sample_rate_hz, axis=name, confidence=confidence,
                                               min_clusters=min_clusters, unit=sensor["unit"])
        except ConstantAxisError as exc:
            if not skip_constant or (a == axes[-1] and not results and not sensor["prefix"]):
                exc.varying = "".join(results) + "".join(b for b in axes[axes.index(a) + 1:] if not one_value(series[b].min(), series[b].max()))
                raise
            warn(f"{exc}{LEFT_OUT}")
            continue
        check_finite(results[a], name, path)
        if motion:
            results[a].warnings.insert(0, f"axis {name}: {motion}; the Allan deviation of a moving {sensor['word']} "
                                          "describes the motion, not the sensor's noise")
    return results


def check_finite(result, axis, path):
    """Raise AllanInputError unless every number of ``result`` is finite (numbers too large
    for float64 overflow to inf/NaN).

    ``result``: one axis's AxisNoise; ``axis``: its letter and ``path`` the file, both for the
    message. Returns None when all is finite.
    """
    arrays = (result.adev, result.ci_low, result.ci_high, result.edf, result.fit_values)
    values = [v for c in (*result.fitted.values(), *result.readoff.values())
              for v in (c.value, c.low, c.high, c.upper) if v is not None]
    if not all(np.isfinite(a).all() for a in arrays) or not np.isfinite(values).all():
        raise AllanInputError(
            f"{path}: axis {axis}: the Allan deviation overflows (values too large for float64 arithmetic); "
            "no output written")
