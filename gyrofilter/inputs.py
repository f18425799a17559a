"""What every reader of user input shares: one reader of numbers, one loader of JSON files and
one opener of input files.

The rules (docs/formats.md, section 8):

- **Numbers** in text (a recording's header, a ``--set`` value, a SOURCE string) are plain
  decimal syntax: an optional sign, ASCII digits with at most one decimal point, an optional
  exponent (``12``, ``-0.5``, ``1e-3``, ``.5``). Python's extras are refused: ``0.0_1``
  (underscores), other scripts' digits (``١٢``), ``nan``, ``inf``, ``0x10``, and text longer than
  :data:`MAX_NUMBER_CHARS`. Every number is finite, and where the caller gives bounds, inside them.
- **Numbers** in JSON or from Python code (a calibration file, a model, ``update()``) are an int
  or a float, never a bool, finite (an int too large for a float is refused, not an
  OverflowError), and inside the caller's bounds. numpy's numbers and 0-d arrays are the numbers
  (or bools) they hold (:func:`scalar`), kept and shown as Python's (:func:`python_value`).
- **JSON files** are read at most :data:`MAX_JSON_BYTES` bytes (a larger file or an endless
  one such as ``/dev/zero`` is refused), must be UTF-8, may nest at most :data:`MAX_JSON_DEPTH`
  levels, and hold no ``NaN``/``Infinity`` tokens and no key twice in one object (nor one
  holding an invisible character).
- **Input files** (a recording, a log, a JSON file) are opened by :func:`open_input` without
  blocking: a FIFO nobody writes to is refused after :data:`PIPE_WAIT_S`, never waited for forever.
- **Quoting** user text in an error: at most :data:`MAX_QUOTE_CHARS` characters (:func:`quote`).
- **A mistyped name** (a command, an option, a setting) is refused with the closest known one
  (:func:`closest`, :func:`did_you_mean`): one rule for the command line and the Python settings.
"""
from __future__ import annotations

import difflib
import errno
import io
import json
import math
import os
import re
import select
import stat
import time
import unicodedata

import numpy as np

from .errors import RecordingError, SettingsError

MAX_NUMBER_CHARS = 64
#: the blanks around a number or a cell (a CRLF line's CR, a value's line end): no other character is taken for one (Python's
#: ``str.strip`` and numpy's ``loadtxt`` take the controls 0x1c-0x1f, 0x0b, 0x0c, U+0085 and U+3000 for blanks:
#: a damaged gzip stream's ``\x1f5`` read as 5, attack pass 63)
BLANKS = " \t\r\n"
MAX_JSON_BYTES = 16 * 1024 * 1024
MAX_JSON_DEPTH = 32
MAX_QUOTE_CHARS = 80
#: bytes read from an input at a time
READ_BYTES = 1 << 20

#: how alike a mistyped name and a known one must be to be suggested (difflib's ratio; its own default cutoff)
SUGGEST_RATIO = 0.6

_INTEGER = re.compile(r"[+-]?[0-9]+")
_DECIMAL = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")  # [0-9]: \d takes any script's digits


#: the Unicode bidirectional formatting characters (Unicode Standard Annex #9, section 2: the
#: embeddings, overrides and isolates, the marks): shown as they are, U+202E reverses the text after
#: it on a terminal or a page ("Trojan Source", CVE-2021-42574), so a file name or a header value
#: can show another name than it holds
BIDI_FORMATTING = "\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069"

#: a control character: the C0 controls (line ends, tab, escape), DEL, the C1 controls (0x9b starts
#: a terminal's control sequence too), the Unicode line and paragraph separators, the bidirectional
#: formatting characters (:data:`BIDI_FORMATTING`)
CONTROL_CHARACTER = re.compile(f"[\x00-\x1f\x7f-\x9f\u2028\u2029{BIDI_FORMATTING}]")


def escape_controls(text):
    """``text`` on one line: each control character (:data:`CONTROL_CHARACTER`) written as its
    Python escape, as ``repr`` writes it inside a string (``\\n``, ``\\t``, ``\\x1b``,
    ``\\u2028``), every other character as it is. The one rule of the header values and notes a
    recording holds and of the lines the commands print."""
    return CONTROL_CHARACTER.sub(lambda m: repr(m.group())[1:-1], str(text))


#: what :func:`json_string` writes as ``\\uXXXX`` besides JSON's own escapes: DEL, the C1 controls,
#: the line and paragraph separators (JSON leaves them as they are; YAML 1.1 reads U+0085 as a line
#: end), the bidirectional formatting characters and lone surrogates (a file name that is not
#: UTF-8: no UTF-8 text holds them)
_NOT_LITERAL_IN_JSON = re.compile(f"[\x7f-\x9f\u2028\u2029{BIDI_FORMATTING}\ud800-\udfff]")


def json_string(text):
    """``text`` as a JSON string literal on one line, its quotes included, that reads back exactly:
    ``json.loads(json_string(t)) == t`` for every str, and the same as a YAML double-quoted
    scalar (YAML 1.2, section 7.3.1: JSON's strings are a subset). JSON's escapes (RFC 8259,
    section 7: ``\\"``, ``\\\\``, ``\\n``, ``\\u001b``), ``\\uXXXX`` for each character of
    :data:`_NOT_LITERAL_IN_JSON`, every other character as it is. The one rule of a name that a
    file written for a program to read holds as text (the Kalibr YAML's comment, the Markdown pages)."""
    return _NOT_LITERAL_IN_JSON.sub(lambda m: f"\\u{ord(m.group()):04x}", json.dumps(str(text), ensure_ascii=False))


def quote(text, limit=MAX_QUOTE_CHARS):
    """``repr(text)`` cut to at most ``limit`` characters inside its quotes (``...`` and the full
    length after a cut), for error messages that show what a user wrote. The cut counts the
    repr, whose escapes (``\\x00``) are longer than the characters they stand for."""
    text = str(text)
    if len(repr(text)) <= limit + 2:
        return repr(text)
    keep = min(len(text), limit)
    while len(repr(text[:keep])) > limit + 2:
        keep -= 1
    return f"{text[:keep]!r}... ({len(text)} characters)"


def closest(word, names, also=None):
    """``(ratio, name)``: the name of ``names`` most like ``word`` by difflib's ratio, taken when
    the ratio is at least :data:`SUGGEST_RATIO` or ``also(name)`` holds; ``(0.0, None)`` when no
    name is. The one rule of every "did you mean" (commands, options, settings)."""
    best = (0.0, None)
    for name in names:
        ratio = difflib.SequenceMatcher(None, word, name).ratio()
        if (ratio >= SUGGEST_RATIO or (also is not None and also(name))) and (best[1] is None or ratio > best[0]):
            best = (ratio, name)
    return best


def did_you_mean(word, names):
    """"; did you mean NAME?" for the name of ``names`` closest to ``word`` (:func:`closest`), else ""."""
    name = closest(word, names)[1]
    return f"; did you mean {name}?" if name is not None else ""


def _bounds_text(low, high, low_open, high_open):
    if low is not None and high is not None:
        return f"in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
    if low is not None:
        return f"{'>' if low_open else '>='} {low:g}"
    return f"{'<' if high_open else '<='} {high:g}"


def number_array(values, name, unit="", first_row=0):
    """The one rule for an array of numbers handed to the API (the filter's samples, the Allan
    functions' and ARMA's rates, a Recording built in code) and its words: ``(array, None)``,
    ``array`` float64 (not copied when it is one already), where ``values`` holds ints or floats;
    else ``(None, (words, row))``, the refusal naming the argument ``name`` (and ``unit``, if
    given) for the caller's own error: a masked array with a masked value (converting it would
    drop the mask and take the value behind it as data; ``row`` the first such row's index, else
    None; the words count rows from ``first_row``),
    what numpy cannot make an array of (a ragged list), complex numbers (converting drops the
    imaginary part), booleans, strings or objects, and a list of numbers holding a bool (numpy
    takes ``[25.0, True]`` as ``[25.0, 1.0]``: a temperature of 1 deg C, where ``update`` refuses
    True; ``row`` its row): a list, a tuple, a deque, whatever has no dtype of its own."""
    in_unit = f" in {unit}" if unit else ""
    mask = np.ma.getmask(values)
    if mask is not np.ma.nomask and mask.any():
        row = int(np.flatnonzero(mask.reshape(len(mask), -1).any(axis=1))[0]) if mask.ndim else 0
        return None, (f"{name} row {row + first_row} is masked; a masked value is no measurement: give the measured values only "
                      "(cut the record at it, or fill it with np.ma.filled if a value is meant)", row)
    try:
        array = np.asarray(values)
    except (ValueError, TypeError):  # a ragged list
        return None, (f"{name} must be an array of numbers{in_unit}, got {_short(values)}", None)
    if array.dtype.kind not in "iuf":
        return None, (f"{name} must be numbers{in_unit}, got an array of {array.dtype}", None)
    if _of_python_objects(values) and array.size:  # numpy takes a True among numbers as 1 (a deque's too)
        held = np.asarray(values, dtype=object)
        if not {bool, np.bool_, np.ndarray}.isdisjoint(map(type, held.flat)):  # the types once each: fast
            is_bool = np.frompyfunc(lambda v: isinstance(v, (bool, np.bool_)) or isinstance(v, np.ndarray) and v.dtype.kind == "b",
                                    1, 1)(held).astype(bool)  # a 0-d array of a bool too
            if is_bool.any():
                at = np.argwhere(is_bool)[0]
                row = int(at[0])
                return None, (f"{name} row {row + first_row} holds {_short(held[tuple(at)])}, a bool: give numbers{in_unit}", row)
    return array.astype(np.float64, copy=False), None


def _of_python_objects(values):
    """Whether ``values`` holds Python objects, one of which may be a bool (a list, a tuple, a
    deque): not an array (a dtype of its own), a buffer of numbers (``array.array``, a
    memoryview) or a range, whose numbers are no bools (made objects, 1e6 of them took 2 s)."""
    if hasattr(values, "dtype") or isinstance(values, range):
        return False
    try:
        memoryview(values)
    except TypeError:
        return True
    return False


def check_number(value, what, *, low=None, high=None, low_open=False, high_open=False, integer=False,
                 error=SettingsError):
    """``value`` (from JSON or Python code) as a float (an int when ``integer``), or ``error`` whose
    message names ``what``: a bool, a string, None, NaN, +-inf, an int beyond a float's range, a
    fraction where ``integer`` is asked for, or a value outside [low, high] (open ends with
    ``low_open``/``high_open``) is refused. An int stays that int (exact beyond 2**53: a seed). A
    0-d array is the number it holds (:func:`scalar`)."""
    value = scalar(value)
    ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
    number = math.nan
    if ok:
        try:
            number = float(value)
        except OverflowError:
            ok = False
    if ok and not math.isfinite(number):
        ok = False
    if not ok:
        shown = quote(value) if isinstance(value, str) else _short(value)
        raise error(f"{what} must be a finite number{' (a whole number)' if integer else ''}, got {shown}")
    if integer and not number.is_integer():
        raise error(f"{what} must be a whole number, got {_short(value)}")
    if integer:
        number = int(value) if isinstance(value, (int, np.integer)) else int(number)
    below = low is not None and (number <= low if low_open else number < low)
    above = high is not None and (number >= high if high_open else number > high)
    if below or above:
        raise error(f"{what} must be {_bounds_text(low, high, low_open, high_open)}, got {_short(value)}")
    return number


def scalar(value):
    """The number or bool a 0-d numpy array of them holds (``np.array(25.0)``, what ``x[()]`` or a
    reduction with ``keepdims`` gives: numpy's scalars in all but type), else ``value`` as it is.
    A bool stays a bool (``np.bool_``), refused where a number is asked (:func:`check_number`)."""
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "biuf":
        return value[()]
    return value


def python_value(value):
    """``value`` with numpy scalars as the Python int or float they hold (lists and tuples element
    by element, as plain lists and tuples: a namedtuple of 3 coefficients ended in a TypeError);
    anything else as it is. A ``longdouble`` is the float nearest it (its ``item()`` is itself,
    which ``json`` does not write; a ``clongdouble`` the complex); a 0-d array of numbers or bools
    as what it holds (:func:`scalar`: ``np.array(0.5)`` is 0.5, not an array)."""
    value = scalar(value)
    if isinstance(value, np.generic):
        item = value.item()
        return float(item) if isinstance(item, np.floating) else complex(item) if isinstance(item, np.complexfloating) else item
    if isinstance(value, (list, tuple)):  # a plain list or tuple: a namedtuple's type takes no generator
        plain_values = [python_value(v) for v in value]
        return plain_values if isinstance(value, list) else tuple(plain_values)
    return value


def axis_values(value):
    """``value`` as :func:`python_value` gives it, a 1-d numpy array of numbers (3 per-axis
    values, ``np.array([0.01, 0.02, 0.5])``) as the tuple of the Python numbers it holds, as a
    tuple of them is taken: the one rule of a setting that is one number or one per axis
    (``temp_coefficient_dps_per_c``; ``BiasKalmanFilter``'s ``bias_tau_s``, ... : an array of 3
    was refused as "an array of shape (3,)", or ended in numpy's "truth value ... ambiguous")."""
    value = python_value(value)
    if isinstance(value, np.ndarray) and value.ndim == 1 and value.dtype.kind in "iuf":
        return tuple(value.tolist())
    return value


def refuse_unordered(values, what, error=SettingsError):
    """Refuse, with ``error`` whose message is ``what`` and the reason, a set (or frozenset) where
    an order is meant (columns by position): its order is the hash seed's, so that the columns
    were written or read in another order from run to run without a word."""
    if isinstance(values, (set, frozenset)):
        raise error(f"{what}, got a set, which has no order")


def _short(value):
    """A value for a message, long ints and floats included, at most MAX_QUOTE_CHARS characters."""
    text = repr(python_value(value))
    return text if len(text) <= MAX_QUOTE_CHARS else f"{text[:MAX_QUOTE_CHARS]}... ({len(text)} characters)"


def parse_number(text, what, *, error=SettingsError, **bounds):
    """``text`` in plain decimal syntax as a float (see the module's rules), or ``error`` naming
    ``what``; ``bounds`` as :func:`check_number` takes them (``low``, ``high``, ``integer`` ...)."""
    stripped = str(text).strip(BLANKS)
    if len(stripped) > MAX_NUMBER_CHARS or not _DECIMAL.fullmatch(stripped):
        raise error(f"{what} must be a plain decimal number (like 12, -0.5 or 1e-3), got {quote(text)}")
    number = float(stripped)
    if not math.isfinite(number):
        raise error(f"{what} must be a finite number, got {quote(text)}")
    if bounds.get("integer"):
        if _INTEGER.fullmatch(stripped):
            number = int(stripped)  # exact: float() rounds 9007199254740993 to ...992
        elif abs(number) >= 2.0**53:  # 9007199254740993.0 or 9.007199254740993e15 was rounded already
            raise error(f"{what} must be written in digits when it is 2^53 or more, got {quote(text)}")
    return check_number(number, what, error=error, **bounds)


def is_plain_number(text) -> bool:
    """Whether ``text`` is a number in plain decimal syntax (no bounds checked)."""
    stripped = str(text).strip(BLANKS)
    return len(stripped) <= MAX_NUMBER_CHARS and _DECIMAL.fullmatch(stripped) is not None


def _refuse_constant(name):
    raise ValueError(f"{name} is not a JSON number")


#: characters that show as nothing or as a blank but are neither controls nor format characters:
#: the default-ignorable code points of other categories (Unicode's DerivedCoreProperties: the
#: combining grapheme joiner, the Hangul fillers, the Khmer inherent vowels, the Mongolian free
#: variation selectors, the variation selectors) and the Braille pattern blank U+2800
BLANK_LOOKING = re.compile("[\u034f\u115f\u1160\u17b4\u17b5\u180b-\u180d\u2800\u3164\ufe00-\ufe0f\uffa0"
                           "\U000e0100-\U000e01ef]")


def _invisible(c):
    """Whether the character ``c`` shows as nothing or as another blank than the space: Unicode
    categories Cc, Cf, Zl, Zp, a space separator (Zs) other than U+0020, or :data:`BLANK_LOOKING`."""
    category = unicodedata.category(c)
    return category in ("Cc", "Cf", "Zl", "Zp") or (category == "Zs" and c != " ") or bool(BLANK_LOOKING.match(c))


def invisible_character(name):
    """What makes ``name`` (a key, a column name) differ from the name it shows, as words: "holds
    the invisible character U+200B (ZERO WIDTH SPACE)" for its first character that shows as
    nothing or as another blank (:func:`_invisible`: controls, format characters, no-break and
    other spaces, Hangul fillers, the Braille blank), None when it holds none. ``bias_dps\u200b``
    is not ``bias_dps``: a second key of that name, shown as a repeat, was read as another one.
    The one rule of the names a file's keys and columns may not hold."""
    hidden = next((c for c in str(name) if _invisible(c)), None)
    if hidden is None:
        return None
    return f"holds the invisible character U+{ord(hidden):04X} ({unicodedata.name(hidden, 'a control character')})"


def _unique_keys(pairs):
    """An object's pairs as a dict, or ValueError for a key given twice (json keeps the last one
    silently: a second bias_dps would win unseen) or holding an invisible character
    (:func:`invisible_character`: a key that shows as another one)."""
    doc = {}
    for key, value in pairs:
        hidden = invisible_character(key)
        if hidden:
            raise ValueError(f"key {quote(key)} {hidden}")
        if key in doc:
            raise ValueError(f"key {quote(key)} given twice")
        doc[key] = value
    return doc


def parse_json(text, what, error=SettingsError):
    """The JSON document ``text`` (str), or ``error`` naming ``what``: invalid JSON, ``NaN``/
    ``Infinity`` tokens, a key given twice in one object, or nesting deeper than
    :data:`MAX_JSON_DEPTH`."""
    try:
        doc = json.loads(text, parse_constant=_refuse_constant, object_pairs_hook=_unique_keys)
    except json.JSONDecodeError as exc:
        raise error(f"{what}: not valid JSON: line {exc.lineno} column {exc.colno}: {exc.msg}") from None
    except RecursionError:
        raise error(f"{what}: JSON nested more than {MAX_JSON_DEPTH} levels deep") from None
    except ValueError as exc:  # NaN/Infinity, a repeated key, an integer of more digits than Python converts
        raise error(f"{what}: not valid JSON: {' '.join(str(exc).split())[:MAX_QUOTE_CHARS]}") from None
    if _depth(doc) > MAX_JSON_DEPTH:
        raise error(f"{what}: JSON nested more than {MAX_JSON_DEPTH} levels deep")
    return doc


def _depth(doc):
    """Nesting depth of a parsed JSON document (a scalar is 0), without recursion."""
    deepest, stack = 0, [(doc, 0)]
    while stack:
        node, level = stack.pop()
        if isinstance(node, dict):
            node = node.values()
        elif not isinstance(node, list):
            continue
        level += 1
        deepest = max(deepest, level)
        if deepest > MAX_JSON_DEPTH:
            return deepest
        stack.extend((child, level) for child in node)
    return deepest


def load_json(path, what, error=SettingsError):
    """The JSON document in the file ``path``, or ``error`` whose message starts with the path and
    names ``what`` (e.g. "calibration", "model"): unreadable, larger than :data:`MAX_JSON_BYTES`
    (read no further, so an endless file such as /dev/zero ends at once), not UTF-8 (a UTF-8
    byte-order mark at the start is ignored, as a recording's and a log's are), or refused
    by :func:`parse_json`. ``path`` is a file name (str, bytes or os.PathLike): an int would be
    taken by open() as a file descriptor, and closed. The one loader of the JSON files a user
    hands to gyrofilter."""
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise error(f"the {what} must be a file name, got {_short(path)}")
    try:
        with open_input(path, error=error, what=what) as fh:  # a FIFO nobody writes to: refused, not waited for
            data = fh.read(MAX_JSON_BYTES + 1)
    except OSError as exc:
        raise error(f"{path}: cannot read the {what} file: {exc.strerror or exc}") from None
    if len(data) > MAX_JSON_BYTES:
        raise error(f"{path}: not a {what} file: larger than {MAX_JSON_BYTES // (1024 * 1024)} MiB")
    try:
        text = data.decode("utf-8").removeprefix("\ufeff")  # a byte-order mark (Windows editors) is ignored, RFC 8259 section 8.1
    except UnicodeDecodeError:
        raise error(f"{path}: not a {what} file: not UTF-8 text") from None
    return parse_json(text, f"{path}", error)


def sibling_hint(path, exc):
    """"; there is NAME" when ``exc`` says ``path`` does not exist but its sibling with or without
    ``.gz`` does (``rec.csv`` for ``rec.csv.gz``, and the other way round); for ``-`` (no such file), how to give
    the standard input (``cat rec.csv | gyrofilter replay -`` said only "No such file", attack pass 59); else ""."""
    if not isinstance(exc, FileNotFoundError):
        return ""
    path = os.fspath(path)
    if path == "-":
        return "; to read the standard input give /dev/stdin (convert alone reads it as -)"
    sibling = path[:-3] if path.endswith(".gz") else path + ".gz"
    return f"; there is {sibling}" if os.path.isfile(sibling) else ""


#: seconds an input that is a pipe (a FIFO made by ``mkfifo``, ``<(zcat log.gz)``) is waited for:
#: its writer's first bytes, or the writer itself
PIPE_WAIT_S = 5.0


def open_input(path, *, fd=None, error=RecordingError, what=None):
    """The input file ``path`` open for reading (binary), the one place inputs are opened (a
    recording, another tool's log, a JSON file: :func:`load_json`). Opening never blocks
    (``O_NONBLOCK``: a FIFO that nobody writes to would block ``open`` forever): a regular file or a device is read as it is; a
    pipe (a FIFO, ``<(zcat log.gz)``, the standard input given as ``fd``) is read once, as it
    comes, when within :data:`PIPE_WAIT_S` s its writer is there (a read that would wait) or its
    first bytes come, and refused as "not a regular file" otherwise, the bytes read meanwhile
    kept; a folder is refused. ``fd``: the input open already (the standard input, whose writer
    is the shell's pipeline: read as it is). ``error`` (RecordingError by default) naming ``path``
    and, when given, ``what`` it was to be ("cannot read the calibration file: ...").""" 
    given = fd is not None
    cannot = f"{path}: cannot read" + (f" the {what} file" if what else "")
    try:
        if not given:
            fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
        mode = os.fstat(fd).st_mode
    except OSError as exc:
        raise error(f"{cannot}: {exc.strerror or exc}{sibling_hint(path, exc)}") from None
    if stat.S_ISDIR(mode):
        os.close(fd)
        raise error(f"{cannot}: {os.strerror(errno.EISDIR)}")
    if given or not stat.S_ISFIFO(mode):
        os.set_blocking(fd, True)
        return open(fd, "rb")
    try:
        first = _first_pipe_bytes(fd, path, error)
    except BaseException:
        os.close(fd)
        raise
    os.set_blocking(fd, True)
    return io.BufferedReader(_Prefixed(fd, first), READ_BYTES)


def _first_pipe_bytes(fd, path, error):
    """What the pipe ``fd`` (non-blocking) holds first: its first bytes, or b"" when its writer is
    there but has written nothing yet; waited for :data:`PIPE_WAIT_S` s (a read that finds no
    writer returns at once with nothing: the writer of a FIFO may come later), then refused."""
    deadline = time.monotonic() + PIPE_WAIT_S
    while True:
        try:
            first = os.read(fd, READ_BYTES)
        except BlockingIOError:
            return b""
        if first:
            return first
        left = deadline - time.monotonic()
        if left <= 0:
            raise error(f"{path}: not a regular file (a pipe or FIFO) and nothing was written to it in "
                                 f"{PIPE_WAIT_S:g} s; give the file itself")
        select.select([fd], [], [], min(left, 0.05))


class _Prefixed(io.RawIOBase):
    """The pipe ``fd`` read as a raw stream, ``first`` (its bytes read already) ahead of the rest."""

    def __init__(self, fd, first):
        self.fd, self.first = fd, first

    def readable(self):
        return True

    def readinto(self, buffer):
        if self.first:
            n = min(len(buffer), len(self.first))
            buffer[:n], self.first = self.first[:n], self.first[n:]
            return n
        data = os.read(self.fd, len(buffer))
        buffer[:len(data)] = data
        return len(data)

    def fileno(self):
        return self.fd

    def close(self):
        if not self.closed:
            os.close(self.fd)
        super().close()
