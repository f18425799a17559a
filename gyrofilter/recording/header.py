"""The header of a recording (format v1, docs/formats.md section 1): its keys and their rules,
the column names, and the one writer of a header as text (:func:`header_text`), which runs the
reader's own checks (:func:`check_header`, :func:`check_columns`) so that what is written reads
back. Also the text rules of header values and annotations (one line each) and of numbers in
the header (:func:`format_number`).
"""
from __future__ import annotations

import functools
import re
import unicodedata

from ..errors import RecordingError
from ..inputs import CONTROL_CHARACTER, escape_controls, invisible_character, json_string, parse_number, quote
from .statements import judge, key_unit, name_words, normal_text, stated_kind
from .unit_words import known_unit
from ..units import ACCEL_UNITS, AXES, GYRO_UNITS, check_lsb_per_dps, check_lsb_per_g, check_sample_rate_hz, utf8_text

#: the first header key of every recording; its value is the format version
VERSION_KEY = "gyrofilter-recording"
FORMAT_VERSION = "1"
#: the gyro columns every recording has, in the order of :data:`~gyrofilter.units.AXES`
GYRO_COLUMNS = tuple(f"g{axis}" for axis in AXES)
#: the accelerometer columns of a six-axis recording, all three or none, in the order of
#: :data:`~gyrofilter.units.AXES`, in the header's ``accel_unit`` (:func:`check_accelerometer`)
ACCEL_COLUMNS = tuple(f"a{axis}" for axis in AXES)
#: the columns every gyrofilter source and output starts with: time (s), then the gyro columns
COLUMNS = ("t", *GYRO_COLUMNS)
#: the start of the annotation with which ``record`` and ``run`` end their output (``# end: why; ...``):
#: how that output ended, so a replay of the file does not pass it on as its own
END_NOTE = "end: "
#: longest line (bytes, without its line end) of a recording: a data row is about 100 bytes, a
#: header line holding a model or the filter settings as JSON a few KB. A longer line is refused
#: once that many bytes are read (a gzip bomb of one endless line, /dev/zero): the reader holds
#: one block of text of this size at a time, so a line inside a block is never longer.
MAX_LINE_BYTES = 1 << 20
#: most bytes of blank and comment lines read before the first data row, of a recording (after
#: its header) or another tool's log: a file without rows (2 GiB of line ends, 2 MB of gzip, took
#: 64 s to refuse as a log and minutes as a recording) is refused once they are read, in a second
#: or two (:func:`refuse_rowless`)
MAX_BYTES_BEFORE_ROWS = 64 << 20
#: most lines before the column-name row (the header, with its blank ``#`` lines); together they
#: hold at most MAX_LINE_BYTES bytes as well
MAX_HEADER_LINES = 1000



def one_line_text(text):
    """``text`` as a header value or an annotation holds it: each control character (a line end,
    a tab, ...) written as its escape (``\\n``), and each lone surrogate (a file name that is not
    UTF-8) as :func:`~gyrofilter.units.utf8_text` writes it (``\\udcff``), spaces at both ends
    dropped; that is what the reader reads back."""
    return escape_controls(utf8_text(str(text))).strip()


#: the header key and value of a recording whose ``t`` is the device's sample counter over the rate
#: (``record`` from a serial device that sends ``counter``): a step of k sample intervals is k - 1
#: samples the device counted and lost, never a t at 1/k of the rate (:class:`~gyrofilter.recording.checks.TimeCheck`)
T_FROM_KEY, T_FROM_COUNTER = "t_from", "device counter"
#: the value of ``t_from`` whose ``t`` counts the lines of a sample the device sent (a serial device without
#: a counter: a refused line of the full width is a lost sample): its steps are lost samples as a counter's
T_FROM_LINES = "device lines"
#: the header key of a filtered output (``replay --out``, ``run --out``): the source its rows were
#: filtered from (:func:`filtered_from`); such a header also names ``input_sample_rate_hz``
FILTERED_FROM_KEY = "filtered_from"
#: the header key of a filtered output's input rate (Hz): its rows are blocks of that many samples
#: a second over ``sample_rate_hz`` (:func:`check_header`)
INPUT_RATE_KEY = "input_sample_rate_hz"


def filtered_from(header):
    """The source the rows of a recording with ``header`` (key -> value text) were filtered from
    (its ``filtered_from``, written by ``replay --out`` and ``run --out``), or None for a
    sensor's samples. A filtered output's rows are bias-removed block means at 1/L of the input
    rate, not the sensor's samples: replay and run refuse to filter it again, ``allan --kalibr``
    and the fleet write no imu.yaml of it, and its accelerometer is one raw sample per row
    (``analysis.still.decimated_accelerometer``). The one test of it; ``is not None`` is the predicate."""
    return header.get(FILTERED_FROM_KEY)


def filtered_words(header):
    """The words that say a recording with ``header`` is the filter's output, for every command's
    refusal or warning of one: ``"the filter's output (filtered_from 'SOURCE'), not the sensor's
    samples"``, or None for a sensor's samples (:func:`filtered_from`)."""
    source = filtered_from(header)
    return None if source is None else f"the filter's output (filtered_from {quote(source)}), not the sensor's samples"
#: header keys gyrofilter writes to say where a recording's samples came from and what was done
#: to them (docs/formats.md, section 1): a live device's header does not give them (the serial
#: source drops them with a note), or a raw recording could say it is a filtered one
#: (``filtered_from``, which replay refuses) or carry another time origin than its own
PROVENANCE_KEYS = frozenset({T_FROM_KEY, FILTERED_FROM_KEY, "filter_preset", "filter_settings", "bias_dps", "t_meaning",
                             "calibration_from", "calibration_rejected", INPUT_RATE_KEY, "converted_from", "converted_by",
                             "time_origin", "simulated_seed", "simulated_duration_s", "simulated_model",
                             "simulated_model_name", "live_source", "recorded_by", "serial_port", "start_time_utc"})


#: what a Markdown page must not take literally from a file's text: an HTML tag's or entity's start
#: (as an entity), and, backslash-escaped (CommonMark 0.31, section 2.4: any ASCII punctuation), a
#: backslash, a table cell's end, a code span's fence, emphasis, strikethrough, a link's or image's
#: brackets, a heading's closing ``#``; ``_`` is escaped unless both its neighbours are letters or
#: digits (inside a word it is no emphasis, and ``mpu6050_static`` stays as it reads)
_MARKDOWN_SPECIAL = {"&": "&amp;", "<": "&lt;", ">": "&gt;", **{c: "\\" + c for c in "\\|`*[]~!#"}}


def markdown_text(text):
    """``text`` from a file (a file name, a quoted cell, a header value) as a Markdown page shows
    it: the body of its JSON string (:func:`~gyrofilter.inputs.json_string`: one line, a backslash
    doubled, ``"`` as ``\\"``, a control character as ``\\n`` or ``\\u0085``), a space at either end as
    ``\\u0020`` (a table cell's or heading's ends are trimmed), and each character a Markdown viewer
    would take as markup written so that it is shown literally (:data:`_MARKDOWN_SPECIAL`). What
    the page shows reads back exactly: ``json.loads('"' + shown + '"') == text``; a plain name
    (``logs/unit 7.csv.gz``) is shown as it is."""
    body = json_string(text)[1:-1]
    shown = "".join(("_" if 0 < i < len(body) - 1 and body[i - 1].isalnum() and body[i + 1].isalnum() else "\\_")
                    if c == "_" else _MARKDOWN_SPECIAL.get(c, c) for i, c in enumerate(body))
    kept = shown.strip(" ")
    start = len(shown) - len(shown.lstrip(" "))
    return "\\u0020" * start + kept + "\\u0020" * (len(shown) - start - len(kept))


#: longest annotation text a writer writes (characters; a gap note is about 60)
MAX_NOTE_CHARS = 4000
#: most annotations a reader keeps (a day of a serial source that loses samples every second has
#: about 86400 gap notes); the lines after them are skipped with one warning: 15 million ``#``
#: lines, 30 KB of gzip, took 4.9 GB as notes
MAX_NOTES = 100_000


def note_text(text):
    """``text`` as an annotation line holds it: on one line (:func:`one_line_text`), cut at :data:`MAX_NOTE_CHARS`."""
    text = one_line_text(text)
    return text if len(text) <= MAX_NOTE_CHARS else f"{text[:MAX_NOTE_CHARS]}... (cut: {len(text)} characters)"


def note_line(text):
    """The annotation line of ``text`` as a writer writes it: ``# `` and :func:`note_text`, line end included."""
    return f"# {note_text(text)}\n"


def format_number(x):
    """``x`` as header text that reads back to the same float: ``100`` for 100.0, else ``repr``."""
    return repr(int(x)) if float(x).is_integer() and abs(x) < 1e15 else repr(float(x))


def units_header(sample_rate_hz, gyro_unit, lsb_per_dps=None, accel_unit=None, lsb_per_g=None):
    """The header keys that state a recording's units, as text (:func:`format_number`):
    ``sample_rate_hz`` (Hz), ``gyro_unit`` (``dps``, ``rad/s`` or ``lsb``) and, with ``lsb``,
    ``lsb_per_dps`` (LSB per deg/s); with ``accel_unit`` (a six-axis recording: ``m/s^2``, ``g``
    or ``lsb``) that key and, with ``lsb``, ``lsb_per_g`` (LSB per g). The rate is checked
    (:func:`~gyrofilter.units.check_sample_rate_hz`: ``Recording.from_dps(x, True)`` wrote 1 Hz)."""
    head = {"sample_rate_hz": format_number(check_sample_rate_hz(sample_rate_hz)), "gyro_unit": gyro_unit}
    if gyro_unit == "lsb":
        head["lsb_per_dps"] = format_number(float(lsb_per_dps))
    head.update(accel_units_header(accel_unit, lsb_per_g))
    return head


def accel_units_header(accel_unit, lsb_per_g=None):
    """The header keys that state the unit of the accelerometer columns, as text: ``accel_unit``
    and, with ``lsb``, ``lsb_per_g`` (LSB per g, :func:`format_number`); empty when ``accel_unit``
    is None (no accelerometer)."""
    if accel_unit is None:
        return {}
    head = {"accel_unit": accel_unit}
    if accel_unit == "lsb":
        head["lsb_per_g"] = format_number(float(lsb_per_g))
    return head


def accel_header(header):
    """The keys of ``header`` that state the unit of its accelerometer columns: ``accel_unit`` and,
    with it, ``lsb_per_g`` when given (empty without ``accel_unit``); what an output that carries
    the columns ``ax, ay, az`` of its source as they are copies into its own header."""
    return {k: header[k] for k in ("accel_unit", "lsb_per_g") if "accel_unit" in header and k in header}


def dps_header(header, sample_rate_hz):
    """``header`` with ``sample_rate_hz`` and ``gyro_unit: dps`` (no ``lsb_per_dps``), for rates in deg/s."""
    head = dict(header)
    head.update(units_header(sample_rate_hz, "dps"))
    head.pop("lsb_per_dps", None)
    return head


def header_text(header, columns, where):
    """The start of a recording as text: the version line, ``# key: value`` for each item of
    ``header`` in order (a ``gyrofilter-recording`` key is dropped), the column-name row.

    The one writer of recording headers (files, and stdout of ``run`` and ``replay --realtime``).
    Values are written as :func:`one_line_text` makes them. RecordingError naming ``where`` (the
    output) for what would not read back as written: a key that is empty, holds ``:``, spaces or
    control characters; a column name that is empty, holds ``,``, spaces or control characters
    (or the first one starting with ``#``); a line longer than :data:`MAX_LINE_BYTES`; and
    everything the reader refuses (:func:`check_header`, :func:`check_columns`,
    :func:`check_accelerometer`: the same checks, lines named as the file will have them).
    """
    head = {VERSION_KEY: FORMAT_VERSION}
    for key, value in header.items():
        if key == VERSION_KEY:
            continue
        if not isinstance(key, str) or not key or CONTROL_CHARACTER.search(key) or ":" in key or key.split() != [key]:
            raise RecordingError(f"{where}: header key {quote(key)} is not a name (no ':', spaces or control characters)")
        head[key] = one_line_text(value)
    check_header(head, where)
    columns = list(columns)
    for i, name in enumerate(columns):
        if (not isinstance(name, str) or CONTROL_CHARACTER.search(name) or "," in name or name.split() != [name]
                or (i == 0 and name.startswith("#"))):
            raise RecordingError(f"{where}: column name {quote(name)} is not a name (no ',', spaces or control characters)")
    check_columns(columns, where)
    check_accelerometer(head, columns, where, {key: i + 1 for i, key in enumerate(head)}, len(head) + 1)
    lines = [f"# {k}: {v}" for k, v in head.items()] + [",".join(columns)]
    for ln in lines:
        if len(ln.encode("utf-8")) > MAX_LINE_BYTES:
            raise RecordingError(f"{where}: header line {quote(ln)} is longer than {MAX_LINE_BYTES} bytes")
    return "\n".join(lines) + "\n"


#: what an error on a file that is not a recording adds: how one starts, and where another tool's log goes
NOT_A_RECORDING = ("a recording starts with '# gyrofilter-recording: 1', '# sample_rate_hz: RATE', "
                   "'# gyro_unit: dps|rad/s|lsb'; another tool's log: gyrofilter convert")


def check_header(header, where):
    """Refuse a header (key -> value text) that is not one of format v1, with RecordingError
    naming ``where`` (the file): the version, the required keys, ``sample_rate_hz`` a plain
    decimal number (:func:`~gyrofilter.inputs.parse_number`) checked by
    :func:`~gyrofilter.units.check_sample_rate_hz`, ``gyro_unit`` one of :data:`GYRO_UNITS`,
    ``lsb_per_dps`` with ``lsb``, checked by :func:`~gyrofilter.units.check_lsb_per_dps`; ``input_sample_rate_hz``,
    when given, as ``sample_rate_hz`` and a whole multiple of it (a row per block of input samples),
    and only with ``filtered_from`` (:func:`filtered_from`): a file of samples that names an input
    rate lies about its rows (the check of its ``t`` would take its steps for blocks of samples,
    its accelerometer for one raw sample per row), so the key without it is refused, not ignored.
    A key holding an invisible character is refused (:func:`refuse_invisible`).
    The one check of a header: the reader's and the writers' (:func:`header_text`); the facts
    without the version are :func:`check_facts`, a :class:`~gyrofilter.recording.Recording`'s."""
    for key in header:
        refuse_invisible(key, "header key", where)
        meant = misspelt_key(key)
        if meant is not None:
            raise RecordingError(f"{where}: header key {quote(key)}: gyrofilter reads {quote(meant)}, spelt exactly so"
                                 f"{' (the file has both)' if meant in header else ''}; rename or remove it")
    missing = [key for key in (VERSION_KEY, *FACT_KEYS) if key not in header]
    if missing:
        raise RecordingError(f"{where}: line 1: missing header key(s) {', '.join(map(repr, missing))}; {NOT_A_RECORDING}")
    version = header[VERSION_KEY]
    if version != FORMAT_VERSION:
        raise RecordingError(f"{where}: unsupported recording version {quote(version)} (this gyrofilter reads version {FORMAT_VERSION})")
    check_facts(header, where)
    if (stated := contradiction(header)) is not None:
        raise RecordingError(f"{where}: {stated}; correct or remove it")


#: the header keys every recording states, a file's and one built in code (:func:`check_facts`)
FACT_KEYS = ("sample_rate_hz", "gyro_unit")


def _key_shape(key):
    """``key`` in the form :func:`misspelt_key` compares: NFKC, case folded, accents dropped (NFKD's combining
    marks: ``gyró_unit``, and the dot of the ``İ`` a Turkish keyboard gives), only its letters and digits
    (``Gyro-Unit``, ``gyro unit``, ``GYRO_UNIT``, ``GyroUnit`` all read ``gyrounit``, attack pass 48), and
    ``temperature`` read ``temp`` (``temperature_unit=mpu6050_raw``, pass 49)."""
    folded = unicodedata.normalize("NFKD", unicodedata.normalize("NFKC", key).casefold())
    return re.sub(r"[\W_]+", "", "".join(c for c in folded if not unicodedata.combining(c))).replace("temperature", "temp")


def _reads_as(shape, known, floor=8):
    """Whether a key of :func:`_key_shape` ``shape`` reads as the known key's ``known``: each letter outside ASCII
    may stand for any one (a look-alike: ``gyrо_unit`` with a Cyrillic о, ``τ_from``, pass 47), when at least a
    third of its letters are ASCII (``温度`` is a key of its own); and a known key of ``floor`` letters or more with
    one letter more, fewer or other, or two swapped (``temp_units``, ``gyro_unt``, pass 49; ``full_scale_dsp``, pass
    50), not a digit more or other (``gyro2_unit``: a second sensor's)."""
    if not shape.isascii():
        foreign = sum(not c.isascii() for c in shape)
        return 2 * (len(shape) - foreign) >= foreign > 0 and len(shape) == len(known) and all(
            a == b or not a.isascii() for a, b in zip(shape, known))
    if len(known) < floor or abs(len(shape) - len(known)) > 1:
        return False
    i = next((i for i, (a, b) in enumerate(zip(shape, known)) if a != b), min(len(shape), len(known)))
    if shape[i:i + 1].isdigit():
        return False
    swapped = shape[i:i + 2] == known[i:i + 2][::-1] and shape[i + 2:] == known[i + 2:]
    return swapped or shape[i + 1:] in (known[i + 1:], known[i:]) or shape[i:] == known[i + 1:]


#: the keys that decide how a file's numbers read or are checked, by their :func:`_key_shape`: a key spelt another
#: way (``Gyro_Unit: rad/s`` beside ``gyro_unit: dps``, attack pass 45; ``gyro unit``, pass 46; ``Full-Scale-DPS``,
#: which report's clipping check reads, pass 47) would be kept as an unrelated key without a word. Descriptive keys
#: (``sensor``, ...) are not among them: a device's ``Sensor=MPU6050`` is its own key (pass 46)
_READ_KEYS = {_key_shape(k): k for k in (VERSION_KEY, *FACT_KEYS, "lsb_per_dps", "accel_unit", "lsb_per_g", INPUT_RATE_KEY,
                                         FILTERED_FROM_KEY, T_FROM_KEY, "full_scale_dps")}


def misspelt_key(key, also=()):
    """The header key gyrofilter reads (or of ``also``: a serial device's protocol keys) that ``key`` spells
    otherwise, or None: another case, blanks, dashes or nothing for ``_``, accents (:func:`_key_shape`), a few
    look-alike letters outside ASCII, a letter more, fewer or other (:func:`_reads_as`; in a key of ``also`` of
    5 letters or more: ``Field``, ``feilds``, attack pass 51). The one check of a header's keys
    (:func:`check_header`) and of a serial device's."""
    also = {_key_shape(k): k for k in also}
    known = {**_READ_KEYS, **also}
    shape = _key_shape(key)
    meant = known.get(shape) or next((k for s, k in known.items() if _reads_as(shape, s, 5 if s in also else 8)), None)
    return meant if meant is not None and meant != key else None


def contradiction(header):
    """What a key of ``header`` (text values, with ``sample_rate_hz`` and ``gyro_unit`` checked) states of the sample
    rate, the gyro's unit or sensitivity, the accelerometer's unit, or the temperature's (``temp_unit: F``: a
    recording's ``temp`` is in deg C), otherwise than the key gyrofilter reads it from, as a phrase naming both, or
    None.

    Kept as an unrelated key, ``# unit: rad/s`` beside ``gyro_unit: dps`` or ``# rate: 200`` beside
    ``sample_rate_hz: 100`` (or a device's ``unit=rad/s`` beside the source's option ``unit=dps``) read the file in
    the other without a word (attack passes 52, 53: ``rate: 200 Hz``, ``dt: 0.005``, ``gyro_scale: rad/s``,
    ``lsb_per_deg: 65.5`` beside ``lsb_per_dps: 131``, ``acc_unit: m/s^2`` beside ``accel_unit: g``): each key but
    the read ones is judged by :func:`contradicts`."""
    rates = header_rates(header)
    facts = {**header, "temp_unit": "c"}
    for key, value in header.items():
        meant = None if key in _READ_KEYS.values() else contradicts(key, value, facts, rates)
        if meant:
            meant, unread = meant
            if meant == "temp_unit":  # temp_unit: F (attack pass 59)
                return f"header key {quote(key)} says {quote(value)}, but a recording's temp column is in deg C, whatever a key says"
            read = key_unit(normal_text(key), normal_text(value))[1]  # mdps_per_lsb: 70 says 70 mdps/lsb
            return (f"header key {quote(key)} says {quote(value)}" + (f" ({read})" if read != normal_text(value) else "")
                    + (f", which gyrofilter does not read as {unread};" if unread else ", but")
                    + f" {meant} is {quote(header[meant])}: gyrofilter reads it only from {meant}")
    return None


def header_rates(header):
    """The rates in Hz a ``header`` (checked) states: ``sample_rate_hz`` and ``input_sample_rate_hz``."""
    return [float(parse_number(header[k], k, error=RecordingError)) for k in ("sample_rate_hz", INPUT_RATE_KEY) if k in header]


#: what each key gyrofilter reads of :data:`~gyrofilter.recording.statements.STATES` states (a foreign log's comment ``# sample_rate_hz: 200``)
_READ_KINDS = {"sample_rate_hz": "rate", "gyro_unit": "unit", "lsb_per_dps": "sensitivity", "accel_unit": "accel_unit",
               "lsb_per_g": "accel_sensitivity"}


def contradicts(key, value, header, rates, tolerance=1e-9):
    """``(the key of ``header`` that ``key: value`` contradicts, what ``value`` does not read as or None)``, or None.

    A key that states the sample rate, the gyro's unit or sensitivity or the accelerometer's unit
    (:func:`statement`) must state the same (:func:`~gyrofilter.recording.statements.judge`): a rate within
    ``tolerance`` (relative) of one of ``rates``, a period of one over it, the unit, ``lsb_per_dps`` (where
    ``gyro_unit`` is lsb), ``accel_unit`` (where the header has one); one that does not, or whose rate or sensitivity
    does not read so (``0xC8``, ``200,0``), contradicts it."""
    stated = statement(key, value)
    return judge(*stated, header, rates, tolerance) if stated else None


def _key_words(key):
    """``(the key gyrofilter reads that ``key`` is or spells otherwise, or None; the words of that or of ``key``)``."""
    read = key if key in _READ_KEYS.values() else misspelt_key(key)
    return read, frozenset(name_words(read or key))


#: :func:`_key_words` of a short key, cached: a log's comments repeat their keys
_short_key_words = functools.lru_cache(maxsize=4096)(_key_words)


def statement(key, value):
    """``(the kind of fact ``key: value`` states, the key's words, the value as read)`` or None: a key gyrofilter
    reads, or one spelt otherwise (:func:`misspelt_key`), states its own; another by its words
    (:func:`~gyrofilter.recording.statements.stated_kind`; :func:`~gyrofilter.recording.statements.normal_text` first:
    ``ＳａｍｐｌｅＲａｔｅ``, ``º/s``; a unit in brackets
    at its end read as the value's: ``Sample period (µs): 5000``). A key with a digit (``rate2_hz``: another
    sensor's) states nothing. Runs of blanks read as one (a regular expression over 300 kB of blanks took minutes)."""
    key, value = key_unit(normal_text(key), normal_text(value))
    read, words = (_short_key_words if len(key) <= 64 else _key_words)(key)
    if read is not None:
        kind = _READ_KINDS.get(read)
    else:
        kind = None if not words or any(c.isdigit() for c in key) else stated_kind(words, value)
    return (kind, words, value) if kind else None


def check_facts(header, where):
    """Refuse a ``header`` whose sample rate and units are missing or not a recording's, with
    RecordingError naming ``where``: the keys :data:`FACT_KEYS` present, and each, and
    ``input_sample_rate_hz`` and ``lsb_per_dps``, as :func:`check_header` says. What a
    :class:`~gyrofilter.recording.Recording` built in code needs (its header carries no version)."""
    missing = [key for key in FACT_KEYS if key not in header]
    if missing:
        raise RecordingError(f"{where}: header key(s) {', '.join(map(repr, missing))} missing: a recording's header "
                             "states 'sample_rate_hz' (Hz) and 'gyro_unit' (dps, rad/s or lsb)")
    sample_rate_hz = parse_number(header["sample_rate_hz"], f"{where}: sample_rate_hz", error=RecordingError)
    check_sample_rate_hz(sample_rate_hz, f"{where}: sample_rate_hz", RecordingError)
    if INPUT_RATE_KEY in header:  # a filtered output's: its rows are blocks of input samples, never more of them
        if filtered_from(header) is None:
            raise RecordingError(f"{where}: header key {INPUT_RATE_KEY!r} without {FILTERED_FROM_KEY!r}: only a filtered "
                                 "output (run --out, replay --out) has rows that are blocks of input samples; remove "
                                 f"the {INPUT_RATE_KEY} line of a file of samples")
        input_hz = parse_number(header[INPUT_RATE_KEY], f"{where}: {INPUT_RATE_KEY}", error=RecordingError)
        check_sample_rate_hz(input_hz, f"{where}: {INPUT_RATE_KEY}", RecordingError)
        block = input_hz / sample_rate_hz  # input samples a row: a whole number (filter.pipeline's block_len)
        if input_hz < sample_rate_hz or abs(block - round(block)) > 1e-9 * block:
            raise RecordingError(f"{where}: input_sample_rate_hz {header['input_sample_rate_hz']} is "
                                 f"{'below' if input_hz < sample_rate_hz else 'not a whole multiple of'} sample_rate_hz "
                                 f"{header['sample_rate_hz']}; a filtered output has one row per block of input samples")
    if header["gyro_unit"] not in GYRO_UNITS:
        meant = known_unit("rate", header["gyro_unit"])  # the one table of spellings (convert's)
        meant = meant if meant in GYRO_UNITS else None
        raise RecordingError(f"{where}: gyro_unit {quote(header['gyro_unit'])} is not one of {', '.join(GYRO_UNITS)}"
                             + (f" (write {quote(header['gyro_unit'])} as {meant})" if meant else ""))
    if header["gyro_unit"] == "lsb":
        if "lsb_per_dps" not in header:
            raise RecordingError(f"{where}: gyro_unit is lsb but header key 'lsb_per_dps' is missing")
        check_lsb_per_dps(parse_number(header["lsb_per_dps"], f"{where}: lsb_per_dps", error=RecordingError),
                          f"{where}: lsb_per_dps", RecordingError)


#: words that make a column name one of time stamps (:func:`name_words`), as ``t`` alone does (``T``) or with a unit
#: of time (``t_s``, ``t(s)``, ``t[ms]``); such a column, where none is ``t``, is refused, so that a user's own file
#: with a ``time`` column (``time_ms``, ``TimeStamp_ns``, ``elapsed_s``, attack pass 52; ``t(s)``, ``zeit``,
#: ``tstamp``, pass 53) is not read as uniform samples at the header's rate with its times, and its gaps, ignored.
#: ``t`` after another word is not one (``host_t``: an arrival time, kept unread)
TIME_WORDS = frozenset({"time", "times", "timestamp", "timestamps", "stamp", "stamps", "ts", "tstamp", "elapsed", "sec",
                        "secs", "second", "seconds", "ms", "us", "ns", "millis", "micros", "epoch", "uptime", "tick",
                        "ticks", "dt", "zeit", "zeitstempel", "tiempo", "horodatage"})
_TIME_UNITS = frozenset({"s", "sec", "secs", "ms", "us", "ns"})

#: words that make a column name one of a temperature, as ``degC``, ``°...`` and a unit of one after ``t`` (``t_c``,
#: ``T_imu``) do, not a letter alone (``k``, ``c``: an index, a counter, pass 54); such a column, where none is
#: ``temp``, is refused as the time-like ones are, so that a user's own ``temp_c`` (``imu_temp``, ``TempF``,
#: ``Temperature(C)``, pass 52; ``temperatura``, pass 53) is not carried along unread (no compensation, the gap analysis reading a temperature drift as a drift in time)
TEMPERATURE_WORDS = frozenset({"temp", "temps", "tmp", "temperature", "temperatures", "celsius", "degc", "degf",
                               "fahrenheit", "kelvin", "temperatura", "temperatur", "thermistor", "tdie"})
_TEMPERATURE_UNITS = frozenset({"c", "f", "k", "degc", "degf"})


def looks_like(name):
    """``"t"`` when a column ``name`` looks like time stamps (:data:`TIME_WORDS`), ``"temp"`` when like a
    temperature (:data:`TEMPERATURE_WORDS`), else None."""
    words = name_words(name)
    if TIME_WORDS.intersection(words) or words[:1] == ["t"] and _TIME_UNITS.issuperset(words[1:]):
        return "t"
    if TEMPERATURE_WORDS.intersection(words) or "°" in name or words in (["deg", "c"], ["deg", "f"]) or (
            words[:1] == ["t"] and (_TEMPERATURE_UNITS | {"imu", "die", "chip", "mpu", "sensor", "board"}).issuperset(words[1:])):
        return "temp"
    return None


#: the names ``convert`` takes for a temperature column, as it normalises them (:mod:`.foreign.extras`)
TEMPERATURE_LIKE_NAMES = frozenset({"temp", "temps", "temp_c", "tempc", "temp_degc", "temp_deg_c", "temperature",
                                    "temperature_c", "temperature_degc", "die_temp", "die_temp_c", "celsius",
                                    "tmp"})  # the Arduino MPU6050 sketch's Tmp (raw counts)


def refuse_invisible(name, what, where):
    """Refuse a column name or header key (``what``) that holds an invisible character
    (:func:`~gyrofilter.inputs.invisible_character`), with RecordingError naming ``where`` (the
    file and line), the name and the character: ``\\ufefft`` is not ``t``; ``lsb_per_dps\\u200b``
    is not ``lsb_per_dps``, a repeated key that was not refused as one."""
    hidden = invisible_character(name)
    if hidden:
        raise RecordingError(f"{where}: {what} {quote(name)} {hidden}; remove it (a byte-order mark "
                             "there comes from a file joined on after the header)")


def check_columns(names, where):
    """Refuse column names (as read: split at commas, spaces dropped) that are empty, repeated,
    lack ``gx, gy, gz``, look like time stamps where none is named ``t`` (:func:`looks_like`, any
    case: ``T`` too; beside ``t`` such a column is an extra one, ``ref_time_offset``) or like a temperature where
    none is named ``temp`` (``board_temp_c`` beside ``temp``),
    or hold an invisible character (:func:`refuse_invisible`: a byte-order mark of a file joined
    on after the header made ``\ufefft`` an extra column, its times ignored); ``where`` is the
    file and line."""
    if any(not n for n in names):
        raise RecordingError(f"{where}: empty column name in {quote(','.join(names))}")
    for n in names:
        refuse_invisible(n, "column", where)
    seen = set()
    dupes = sorted({n for n in names if n in seen or seen.add(n)})
    if dupes:
        raise RecordingError(f"{where}: duplicate column(s) {quote(', '.join(dupes))}")
    missing = [c for c in GYRO_COLUMNS if c not in seen]
    if missing:
        hint = ("; columns are separated by commas" if len(names) == 1 and any(c in names[0] for c in ";\t ") else
                "; names are lower case" if all(c.upper() in map(str.upper, names) for c in missing) else
                "; another tool's log: gyrofilter convert")
        raise RecordingError(f"{where}: missing column(s) {', '.join(missing)} (have {quote(', '.join(names))}){hint}")
    times = [n for n in names if "t" not in names and looks_like(n) == "t"]
    if times:
        raise RecordingError(f"{where}: column {quote(times[0])} looks like time stamps, which a recording holds "
                             "in a column named 't' (seconds); rename it t to use them, or to something else to keep "
                             "it as an extra column; another tool's log: gyrofilter convert")
    temps = [n for n in names if "temp" not in names and looks_like(n) == "temp"]
    if temps:
        raise RecordingError(f"{where}: column {quote(temps[0])} looks like a temperature, which a recording holds "
                             "in a column named 'temp' (deg C); rename it temp to use it, or to something else to "
                             "keep it as an extra column")


def check_accelerometer(header, names, where, line_of, columns_line):
    """Refuse what a six-axis recording's ``header`` and column ``names`` say of its
    accelerometer, when the header has ``accel_unit`` (docs/formats.md, section 1), with
    RecordingError naming ``where`` (the file), the line and the key or columns: an
    ``accel_unit`` not in :data:`~gyrofilter.units.ACCEL_UNITS`; with ``lsb``, a missing
    ``lsb_per_g`` or one that is not a number in :data:`~gyrofilter.units.LSB_PER_G_RANGE`
    (:func:`~gyrofilter.units.check_lsb_per_g`); no column of ``ax, ay, az``
    (:data:`ACCEL_COLUMNS`), or only some of them. ``line_of``: each key's line, ``columns_line``
    the column row's. Without ``accel_unit`` nothing is checked: columns ``ax, ay, az`` are then
    carried along as any other column (the v1 files written before the key), and only an
    analysis of the accelerometer refuses them (:meth:`~gyrofilter.recording.Recording.accel_mps2`)."""
    if "accel_unit" not in header:
        return
    unit_line = f"{where}: line {line_of['accel_unit']}"
    unit = header["accel_unit"]
    if unit not in ACCEL_UNITS:
        raise RecordingError(f"{unit_line}: accel_unit {quote(unit)} is not one of {', '.join(ACCEL_UNITS)}")
    if unit == "lsb":
        if "lsb_per_g" not in header:
            raise RecordingError(f"{unit_line}: accel_unit is lsb but header key 'lsb_per_g' is missing")
        name = f"{where}: line {line_of['lsb_per_g']}: lsb_per_g"
        check_lsb_per_g(parse_number(header["lsb_per_g"], name, error=RecordingError), name, RecordingError)
    present = [c for c in ACCEL_COLUMNS if c in names]
    if not present:
        raise RecordingError(f"{unit_line}: header key 'accel_unit' is given but the column row (line {columns_line}) "
                             f"has no accelerometer columns {', '.join(ACCEL_COLUMNS)}; drop the key or add the columns")
    if len(present) < len(ACCEL_COLUMNS):
        missing = [c for c in ACCEL_COLUMNS if c not in present]
        raise RecordingError(f"{where}: line {columns_line}: accelerometer column(s) {', '.join(missing)} missing "
                             f"(have {', '.join(present)}); with accel_unit (line {line_of['accel_unit']}) a recording "
                             f"has all of {', '.join(ACCEL_COLUMNS)}")


def refuse_rowless(path, bytes_before_rows):
    """Refuse the file ``path`` once ``bytes_before_rows``, the bytes of the blank and comment lines
    read before its first data row, pass :data:`MAX_BYTES_BEFORE_ROWS`."""
    if bytes_before_rows > MAX_BYTES_BEFORE_ROWS:
        raise RecordingError(f"{path}: no data rows in the first {MAX_BYTES_BEFORE_ROWS >> 20} MB "
                             "(only blank or comment lines); not a log of rates")
