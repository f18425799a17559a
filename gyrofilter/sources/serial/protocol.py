"""The line protocol of a gyro (and accelerometer) streamed over a serial port (``serial:/dev/ttyUSB0,baud=115200``),
and :class:`LineParser`, which turns its bytes into rows (pure: no I/O; the port is
:mod:`gyrofilter.sources.serial.port`).

Line protocol (``docs/live.md``; ``tools/arduino/gyrofilter_stream`` speaks it)::

    # gyrofilter-serial: 1 gyro_unit=lsb lsb_per_dps=131 sample_rate_hz=100 fields=counter,gx,gy,gz,temp temp_unit=mpu6050_raw
    0,12,-3,40,-1520
    1,15,-1,37,-1518

- A header line ``# gyrofilter-serial: 1`` followed by ``key=value`` words, sent at start-up
  and whenever the device receives ``?``. Keys: ``gyro_unit`` (dps, rad/s, lsb),
  ``lsb_per_dps`` (with lsb), ``sample_rate_hz``; optional ``fields`` (default
  ``counter,gx,gy,gz`` plus ``temp`` if the lines have five values), ``counter_bits`` (an
  integer in [8, 32], default 32: the counter wraps at 2**counter_bits), ``temp_unit`` (``c`` or ``mpu6050_raw``: T = raw/340 + 36.53
  deg C, MPU-6000/6050 register map rev 4.2 section 4.18); ``accel_unit`` (``m/s^2``, ``g`` or
  ``lsb``) and ``lsb_per_g`` (with lsb, a number > 0), required when ``fields`` names the
  accelerometer fields ``ax, ay, az`` (all three or none; only through ``fields``, so a stream
  with an accelerometer sends a header), and written into the recording header (without those fields: ignored,
  noted); any other key (``sensor``, ``chip_id``, ``full_scale_dps``, ``dlpf_cfg``, ...) goes into the recording header,
  except one that means a key gyrofilter reads, spelt otherwise (:func:`.fields.meant_key`: refused). The header
  line is printable ASCII; keys are names (letters, digits, ``_``), each given once, each with a
  value; numbers are plain decimals (:func:`gyrofilter.inputs.parse_number`), ``sample_rate_hz``
  in (0, 100000] Hz, ``lsb_per_dps`` > 0.
- Then one CSV line per sample, ``\\n`` or ``\\r\\n`` ended. Other lines starting with ``#`` are
  device messages (passed on as notes).
- The counter counts samples on the device: an integer in [0, 2**counter_bits). A jump of
  1 < k < 2**(counter_bits - 1) (modulo the wrap) means k - 1 samples were lost: ``t`` jumps with it
  and a gap note is made. A repeated counter is a duplicate (dropped, counted); a backwards jump
  is a device restart (noted; ``t`` continues). A line whose counter jumps (forwards or back)
  while the next line's lies between the one before it and the jump (999, 1900, 1001: a corrupt
  digit; a gap or restart goes on from where it jumped) is a corrupt line, refused (``bad_lines``): one bad digit is one sample, not 900 samples "lost"
  and every later ``t`` shifted by 9 s; a line whose counter jumps therefore waits for the next
  line (or :meth:`LineParser.finish`) before it is a row. A counter that is not such an integer (negative,
  fractional, too large) refuses its line (counted in ``bad_lines``), and so does a gyro value
  beyond +-``units.MAX_RATE_DPS`` (100000 deg/s) once converted to deg/s, or an accelerometer value
  beyond +-``units.MAX_ACCEL_MPS2`` once in m/s^2: no sensor reads it, and the recording would
  refuse it (a corrupt line must not end a recording). Without a counter, a refused line of the full
  width with a number among its cells is a sample the device sent: the next row's ``t`` keeps its
  place, the sample counted lost (a line of words alone is a message sent without its ``#``).
- Every line received is counted in ``stats["lines"]`` and in exactly one of
  :data:`LINE_OUTCOMES`: a sample delivered as a row (``samples``) or a line that is not one
  (a duplicate, a refused line, a header, ...). A run of more than :data:`MAX_LINE_BYTES` bytes
  without a line end is one refused line, however the bytes arrive.

Without a header, the units come from the source options (``unit=``, ``lsb_per_dps=``,
``rate=``; ``gyrofilter record --gyro-unit ...``) and the first line is discarded, since the
port may have been opened in the middle of a line. The fields are then inferred from the width
(``counter,gx,gy,gz[,temp]``), and the lines wait, no row made, until the first values of the first
:data:`.counter.COUNTING_LINES` (8) lines count (:func:`.counter.first_value_counts`: integers stepping
by 1, modulo the wrap, in all steps but one, a loss); else DeviceError, one line naming the values seen
and the header line that names the fields (``gx,gy,gz,temp`` lines read as ``counter,gx,gy,gz`` made the
temperature gz and gx a counter "lost" and "restarted": attack pass 37b). A header that comes while they
wait makes them rows if it names those fields or none, else lines before the header.

The parser splits each chunk of bytes into complete lines and converts them all at once with
numpy when they are all plain CSV; a chunk with anything else goes through a line-by-line parser
that counts and skips bad lines (partial lines, garbage bytes, cells that are not plain decimal
numbers). Nothing in the input makes it raise except an unreadable first header, a header that
changes the units mid-stream (``temp_unit`` too, once temperatures were read), or headerless lines whose first value does not count. The rows do not depend on how the bytes are split into chunks.
"""
from __future__ import annotations

import math
import re
import warnings

import numpy as np

from ...errors import DeviceError, SettingsError
from ...inputs import is_plain_number, parse_number, quote
from ...recording import ACCEL_COLUMNS, COLUMNS, PROVENANCE_KEYS, contradiction, format_number
from ...units import MAX_ACCEL_MPS2, MAX_RATE_DPS, TEMP_RANGE_C
from ..mpu6050.chip import temperature_c
from .counter import COUNTING_LINES, first_value_counts, not_counting, out_of_sequence
from .fields import (ACCEL_IGNORED_NOTE, HEADER_PREFIX, PROTOCOL_KEYS, UnitsConflict, accel_units, header_words,
                     in_range, inferred_fields, make_units, meant_key, other_keys_note, parse_fields, temp_unit_raw)

MAX_LINE_BYTES = 256  # a longer line (bytes before its "\n") is refused
MAX_DETAILED_NOTES = 20  # bad-line notes per source; later ones are only counted
COUNTER_BITS = (8, 32)  # the counter_bits a header may give: a byte counter up to a 32-bit one
DEFAULT_COUNTER_BITS = 32
#: every line received (``stats["lines"]``) is counted in exactly one of these
LINE_OUTCOMES = ("samples", "duplicates", "partial_lines", "bad_lines", "empty_lines", "device_messages",
                 "headers", "lines_before_header")
_UNIT_KEYS = ("sample_rate_hz", "gyro_unit", "lsb_per_dps", "accel_unit", "lsb_per_g")  # a repeated header keeps them
# a cell of the numpy path (:func:`_plain_cell`): a plain decimal of at most 2 d + 2 characters
# (sign, d digits, a point, d digits; d = 24 up to 5 fields, fewer for more), so that a line of
# its cells, commas and "\r" stays within MAX_LINE_BYTES, and strictly one: numpy 1.24's
# fromstring reads "1.2.3" as 1.2 and stops, unnoticed where it is the block's last cell; every
# other cell ("1.2.3", "+-4", "1e3", a longer one) goes the line-by-line way, which names it
_PLAIN_LINES = {}  # field count -> compiled pattern of a block of plain CSV number lines
# bytes a data line may hold at all (the rest is garbage): also exponents, blanks, nan/inf
_TEXT = b"0123456789+-.,eEnaifNAIF \t"


def _plain_cell(n_fields):
    """The numpy path's cell pattern for lines of ``n_fields`` cells: d digits either side of the
    point, d = min(24, the most that keeps n (2 d + 2) + (n - 1) commas + "\r" within MAX_LINE_BYTES)."""
    digits = min(24, ((MAX_LINE_BYTES - n_fields) // n_fields - 2) // 2)
    return rb"[-+]?(?:[0-9]{1,%d}(?:\.[0-9]{0,%d})?|\.[0-9]{1,%d})" % (digits, digits, digits)


class LineParser:
    """Turn the bytes of the line protocol into rows ``t, gx, gy, gz[, temp][, ax, ay, az]``.

    Pure (no I/O): :meth:`feed` takes any bytes (split anywhere) and returns the rows its
    complete lines made; the rows and the counts do not depend on the split. ``header`` is None
    until the units are known (from a header line or the constructor), and so is
    ``sample_rate_hz`` (float). Counters are in :attr:`stats` (each line in ``lines`` and in one
    of :data:`LINE_OUTCOMES`; ``lost_samples`` from the counter's jumps), events in :attr:`notes`.

    Parameters
    ----------
    gyro_unit : str, optional
        Unit of the gyro fields when the device sends no header: ``dps``, ``rad/s`` or ``lsb``.
    lsb_per_dps : float, optional
        LSB per deg/s (> 0), needed with ``gyro_unit="lsb"``.
    sample_rate_hz : float, optional
        The device's sample rate (Hz), in (0, 100000]: ``t = sample index / sample_rate_hz``.
    where : str
        Name used in messages and notes (the port name).

    Giving any of the three units makes them the source options: a header line must then agree
    with them (else :class:`UnitsConflict`), and the first line is discarded. SettingsError
    when an option is missing or out of range.
    """

    def __init__(self, gyro_unit=None, lsb_per_dps=None, sample_rate_hz=None, *, where="serial"):
        self.where = where
        self.stats = {
            "lines": 0, "samples": 0, "lost_samples": 0, "counter_jumps": 0, "duplicates": 0,
            "restarts": 0, "partial_lines": 0, "bad_lines": 0, "garbage_bytes": 0,
            "empty_lines": 0, "device_messages": 0, "headers": 0, "lines_before_header": 0,
        }
        self.notes = []
        self._detailed = 0
        self._buf = b""
        self._overlong = False  # the bytes up to the next line end belong to a line already refused
        self.header = None
        self.fields = None  # list of names per line once known
        self._inferred = None  # the fields a line's width implies while its first value has not yet shown it counts
        self._waiting = []  # those lines' values (:meth:`_made`)
        self._counter_mod = 2 ** DEFAULT_COUNTER_BITS
        self._temp_raw = False
        self.sample_rate_hz = None
        self._last_counter = None
        self._held = None  # a line whose counter jumped, waiting for the next to judge it (_out_of_sequence)
        self._unsent = 0  # without a counter: refused lines of the full width since the last row (_uncounted)
        self._last_index = -1
        self._options = None
        self.device_header = None  # the first header the device sent, once it has: the recording's (the port)
        self._changed_headers = 0
        if gyro_unit is not None or sample_rate_hz is not None or lsb_per_dps is not None:
            self._options = make_units({"gyro_unit": gyro_unit, "lsb_per_dps": lsb_per_dps, "sample_rate_hz": sample_rate_hz},
                                        f"{where}: source options")
            self._apply(dict(self._options))
            self._skip_first_line = True
        else:
            self._skip_first_line = False

    # ------------------------------------------------------------------ header

    def _apply(self, header):
        units = {k: header[k] for k in _UNIT_KEYS if k in header}
        if self.header is not None:
            old = {k: self.header[k] for k in _UNIT_KEYS if k in self.header}
            if old != units:
                changed = ", ".join(f"{k} {old.get(k, '(none)')} -> {units.get(k, '(none)')}"
                                    for k in _UNIT_KEYS if old.get(k) != units.get(k))
                raise UnitsConflict(f"{self.where}: the device's header changed the units mid-stream ({changed}); "
                                    "start a new recording")
        self.header = dict(header)
        self.sample_rate_hz = float(header["sample_rate_hz"])

    def _note_other_keys(self, previous, header):
        """Note a repeated header's other keys (:func:`.fields.other_keys_note`), :data:`MAX_DETAILED_NOTES` times at most."""
        note = None if previous is None else other_keys_note(previous, header, self.device_header, _UNIT_KEYS,
                                                             self.stats["samples"], (self._changed_headers, MAX_DETAILED_NOTES))
        self.device_header = self.device_header or dict(header)
        self._changed_headers += note is not None
        if note is not None and self._changed_headers <= MAX_DETAILED_NOTES + 1:  # the last: the rest go unnoted
            self.notes.append(note)

    def _header_line(self, line):
        """Read a header line and apply it, all or nothing: DeviceError/SettingsError (nothing
        changed) when it is unreadable, :class:`UnitsConflict` when it changes the units."""
        values = header_words(line, self.where)
        where = "header line"
        for key, value in values.items():  # a recording's header would refuse it, naming the output file (pass 46)
            if (meant := meant_key(key, value)) is not None:  # Fields= swapped axes (pass 47)
                raise DeviceError(f"{self.where}: {where}: key {quote(key)}: gyrofilter reads {quote(meant)}, spelt "
                                  "exactly so; the device must send it so")
        if "gyro_unit" not in values and self._options is not None:
            values = {**self._options, **values}
        units = make_units(values, f"{self.where}: {where}")
        if self._options is not None:
            for key, value in self._options.items():
                if key == "gyro_unit":
                    same = units.get(key) == value
                else:
                    same = key in units and float(units[key]) == float(value)
                if not same:
                    raise UnitsConflict(f"{self.where}: the device's header says {key}={units.get(key)} but the options say {value}")
        header = {k: v for k, v in values.items() if k not in PROTOCOL_KEYS and k not in PROVENANCE_KEYS}
        ignored = [f"serial: the device's header key {key} is gyrofilter's own (where the samples came from): ignored"
                   for key in sorted(PROVENANCE_KEYS & values.keys())]
        header.update(units)
        if (stated := contradiction(header)) is not None:  # unit=rad/s beside the option unit=dps (attack pass 52)
            raise DeviceError(f"{self.where}: {where}: {stated}; the device must not send it so")
        fields = self.fields
        if "fields" in values:
            fields = parse_fields(values["fields"], self.where)
            if self.fields is not None and fields != self.fields:
                raise UnitsConflict(f"{self.where}: the device's header changed the fields mid-stream ({self.fields} -> {fields})")
        counter_mod = self._counter_mod
        if "counter_bits" in values:
            low, high = COUNTER_BITS
            bits = parse_number(values["counter_bits"], f"{self.where}: header line: counter_bits",
                                low=low, high=high, integer=True, error=DeviceError)
            counter_mod = 2 ** bits
        sampled = self.stats["samples"] and "temp" in (self.fields or ())  # temperatures read: their unit stays
        temp_raw = temp_unit_raw(values, self.where, self._temp_raw if sampled else None)
        header.update(accel := accel_units(values, fields, self.where))
        ignored += [] if accel or "accel_unit" not in values else [ACCEL_IGNORED_NOTE]
        previous = self.header if self.device_header else None
        self._apply(header)  # a repeated header must agree; the counter tells restarts
        self._note_other_keys(previous, header)
        self.notes += [note for note in ignored if note not in self.notes]
        self.fields, self._counter_mod, self._temp_raw = fields, counter_mod, temp_raw
        self._skip_first_line = False

    # ------------------------------------------------------------------ lines

    @property
    def columns(self):
        """Names of the row columns, ``["t", "gx", "gy", "gz"]`` plus ``"temp"`` (deg C) and
        ``"ax", "ay", "az"`` (in the header's ``accel_unit``) when the lines carry them; None until
        the fields are known (from a header or the first data line)."""
        if self.fields is None:
            return None
        return ([*COLUMNS] + (["temp"] if "temp" in self.fields else [])
                + ([*ACCEL_COLUMNS] if ACCEL_COLUMNS[0] in self.fields else []))

    def _bad(self, shown, kind, reason, *, count=1, garbage_bytes=None):
        """Count ``count`` refused lines as ``kind`` (``bad_lines`` or ``partial_lines``) and their
        bytes (default: ``len(shown)``); the first :data:`MAX_DETAILED_NOTES` get a note."""
        self.stats[kind] += count
        self.stats["garbage_bytes"] += len(shown) if garbage_bytes is None else garbage_bytes
        if self._detailed < MAX_DETAILED_NOTES:
            self._detailed += 1
            text = shown[:40].decode("ascii", "backslashreplace")
            more = "" if self._detailed < MAX_DETAILED_NOTES else " (further bad lines are only counted)"
            many = f"{count} lines, the first " if count > 1 else ""
            self.notes.append(f"serial: skipped {many}{kind[:-1].replace('_', ' ')} ({reason}): {text}{more}")

    def feed(self, data: bytes) -> np.ndarray:
        """Add received bytes; returns the rows of the complete lines, shape (n, len(columns)).

        ``data``: bytes as received, split anywhere (an incomplete last line is kept for the next
        call). Rows are ``t, gx, gy, gz[, temp][, ax, ay, az]``: t (s) from the device's sample
        counter and ``sample_rate_hz``, gyro in the header's ``gyro_unit``, temp in deg C (converted
        from TEMP_OUT with ``temp_unit=mpu6050_raw``), accelerometer as sent (``accel_unit``). Raises only for a header line: DeviceError or
        SettingsError when the first one is unreadable or lacks a unit, :class:`UnitsConflict`
        when one changes the units (its ``rows``: those of the lines before it; and DeviceError when a tiny ``sample_rate_hz`` and the
        counter's jumps carry ``t`` beyond a float; DeviceError when lines without a header do not count: :meth:`_made`); other lines are counted in :attr:`stats`
        (the module docstring) and the bad ones noted.
        """
        if self._overlong:  # the tail of a line refused as too long: up to its line end
            end = data.find(b"\n")
            self.stats["garbage_bytes"] += len(data) if end < 0 else end
            if end < 0:
                return self._empty()
            data, self._overlong = data[end + 1:], False
        buf = self._buf + data
        end = buf.rfind(b"\n")
        block, self._buf = buf[: end + 1], buf[end + 1 :]
        rows = self._empty()
        if block:
            rows = self._fast(block)
            if rows is None:
                rows = self._slow(block)
        if len(self._buf) > MAX_LINE_BYTES:  # already too long for a line: refused, whatever follows
            self.stats["lines"] += 1
            self._bad(self._buf, "bad_lines", f"longer than {MAX_LINE_BYTES} bytes")
            self._buf, self._overlong = b"", True
        return rows

    def finish(self):
        """The connection ended: a line without its end is a cut line (counted, not used); returns
        the row of a last line whose counter jumped (it waited for a next line that will not come)."""
        if self._buf:
            self.stats["lines"] += 1
            self._bad(self._buf, "partial_lines", "cut off at the end of the stream")
        self._buf, self._overlong = b"", False
        if self.fields is None:
            return self._made([], final=True)
        return self._released()

    def _released(self):
        """The row of a line whose counter jumped, held for the next line to judge it (:meth:`_out_of_sequence`),
        judged as the stream's last: the stream ends (:meth:`finish`) or ends in its units (a header changing
        them: attack pass 37e, that line was dropped with the UnitsConflict)."""
        held, self._held = self._held, None
        return self._rows(held[None, :], final=True) if held is not None else self._empty()

    @property
    def waiting_lines(self):
        """Lines received whose fields were inferred from their width, waiting until their first values show
        they count (:meth:`_made`); no rows until then."""
        return len(self._waiting)

    def _made(self, pending, final=False):
        """The rows of ``pending`` lines (values in fields order). While the fields are inferred from a line's
        width (no header named them), the lines wait until :data:`.counter.COUNTING_LINES` have come (or the
        stream ended: ``final``) and the first values of those lines count (:func:`.counter.first_value_counts`):
        else DeviceError (:func:`.counter.not_counting`), before any row is made."""
        if self.fields is None:
            self._waiting.extend(pending)
            if not self._waiting or (len(self._waiting) < COUNTING_LINES and not final):
                return self._empty()
            first = [line[0] for line in self._waiting[:COUNTING_LINES]]
            if not first_value_counts(first, self._counter_mod):
                self.stats["bad_lines"] += len(self._waiting)
                raise DeviceError(not_counting(self.where, first, self._inferred))
            self.fields, pending, self._waiting = self._inferred, self._waiting, []
        return self._rows(np.array(pending), final=final) if len(pending) else self._empty()

    def _header_named_fields(self):
        """After a header: the lines waiting (:meth:`_made`) are rows if it named the fields their width implied or
        none (its default: those), else counted as lines before the header (read with no fields known)."""
        if not self._waiting:
            return self._empty()
        waiting, self._waiting = self._waiting, []
        if self.fields is None or self.fields == self._inferred:
            self.fields = self._inferred
            return self._rows(np.array(waiting))
        self.stats["lines_before_header"] += len(waiting)
        self.notes.append(f"serial: {len(waiting)} lines before the header named the fields dropped (fields unknown)")
        return self._empty()

    def _empty(self):
        cols = self.columns
        return np.empty((0, len(cols) if cols else 4))

    def _fast(self, block):
        """All lines plain CSV with the known field count (cells of :func:`_plain_cell`, which the
        line-by-line path reads alike): one regular-expression check, one numpy conversion.
        Anything else (headers, messages, bad lines) returns None."""
        if self.header is None or self.fields is None or self._skip_first_line:
            return None
        nf = len(self.fields)
        pattern = _PLAIN_LINES.get(nf)
        if pattern is None:
            cell = _plain_cell(nf)
            pattern = _PLAIN_LINES[nf] = re.compile(rb"(?:%s(?:,%s){%d}\r?\n)*" % (cell, cell, nf - 1))
        if pattern.fullmatch(block) is None:
            return None
        n_lines = block.count(b"\n")
        if b"\r" in block:
            block = block.replace(b"\r", b"")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # numpy 1.24 warns (and stops) at a malformed number
                values = np.fromstring(block.replace(b"\n", b",").decode("ascii"), sep=",")
        except ValueError:  # numpy 2.4 raises there instead
            return None
        if values.size != n_lines * nf:  # e.g. "--4": let the slow path name it
            return None
        self.stats["lines"] += n_lines
        return self._rows(values.reshape(n_lines, nf))

    def _slow(self, block):
        """Line by line: headers, device messages, and bad lines counted and skipped."""
        out = []
        pending = []
        for line in block.split(b"\n")[:-1]:
            self.stats["lines"] += 1
            if len(line) > MAX_LINE_BYTES:
                self._bad(line, "bad_lines", f"longer than {MAX_LINE_BYTES} bytes")
                continue
            if line.endswith(b"\r"):
                line = line[:-1]
            if not line.strip():
                self.stats["empty_lines"] += 1
                continue
            if line.startswith(HEADER_PREFIX):
                if pending:
                    out.append(self._made(pending))
                    pending = []
                try:
                    self._header_line(line)
                except (DeviceError, SettingsError) as exc:
                    if self.header is None:
                        raise
                    if isinstance(exc, UnitsConflict) or self.device_header is None:  # the device's first, the units
                        out.append(self._released())  # the options': it ends the stream (unit=rad/s, attack pass 52)
                        conflict = exc if isinstance(exc, UnitsConflict) else UnitsConflict(str(exc))
                        conflict.rows = np.concatenate(out)
                        raise conflict from None
                    self._bad(line, "bad_lines", f"unreadable repeated header: {exc}")
                    continue
                self.stats["headers"] += 1
                out.append(self._header_named_fields())
                continue
            if line.startswith(b"#"):
                self.stats["device_messages"] += 1
                if self._detailed < MAX_DETAILED_NOTES:
                    self._detailed += 1
                    self.notes.append("device: " + line[1:].strip().decode("ascii", "backslashreplace")[:120])
                continue
            if self.header is None:
                self.stats["lines_before_header"] += 1
                continue
            if self._skip_first_line:
                self._skip_first_line = False
                self.stats["partial_lines"] += 1
                self.notes.append("serial: first line discarded (the port may have opened mid-line)")
                continue
            if line.translate(None, _TEXT):
                self._refused(line, "bad_lines", "garbage bytes", out, pending)
                continue
            cells = line.decode("ascii").split(",")  # ASCII: the bytes were checked above
            if self.fields is None and self._inferred is None:
                self._inferred = inferred_fields(len(cells))
                if self._inferred is None:
                    self._bad(line, "bad_lines", f"{len(cells)} values before the field count is known, expected 4 or 5: "
                                                        "counter,gx,gy,gz[,temp]; without a counter a header names the "
                                                        "fields, e.g. fields=gx,gy,gz")
                    continue
            if self.fields is None and self.device_header is not None:  # a header's default (no fields=)
                self.fields = self._inferred
            nf = len(self.fields or self._inferred)
            if len(cells) != nf:
                kind = "partial_lines" if len(cells) < nf else "bad_lines"
                self._bad(line, kind, f"{len(cells)} values, expected {nf}")
                continue
            if any(not c.strip() for c in cells):
                self._refused(line, "partial_lines", "empty value", out, pending)
                continue
            if not all(map(is_plain_number, cells)):
                self._refused(line, "bad_lines", "not a plain decimal number", out, pending)
                continue
            values = list(map(float, cells))
            if not all(map(math.isfinite, values)):
                self._refused(line, "bad_lines", "not a finite number", out, pending)
                continue
            pending.append(values)
        if pending:
            out.append(self._made(pending))
        out = [rows for rows in out if len(rows)]
        if not out:
            return self._empty()
        return np.concatenate(out) if len(out) > 1 else out[0]

    def _refused(self, line, kind, reason, out, pending):
        """Count the refused ``line`` (:meth:`_bad`); without a counter one of the full width with a
        number among its cells is a sample the device sent: the rows of the lines before it are made
        (into ``out``) and it is counted in ``_unsent``, so that the next row's t keeps its place
        (:meth:`_uncounted`). A line of words alone (``ERR,i2c,timeout``) is a message sent without its
        ``#`` (attack pass 35), not a sample."""
        self._bad(line, kind, reason)
        cells = line.decode("latin-1").split(",")
        if (self.fields and "counter" not in self.fields and len(cells) == len(self.fields)
                and any(map(is_plain_number, cells))):
            if pending:
                out.append(self._rows(np.array(pending)))
                pending.clear()
            self._unsent += 1

    def _uncounted(self, ok):
        """Sample indices of the rows of a chunk of lines without a counter, ``ok`` the lines not refused.
        Each line of the full width is a sample the device sent: t = index / sample_rate_hz counts the
        refused ones (``~ok`` and ``_unsent``) as lost samples, a gap noted at the next row, as a counter's
        jump is; before the first row none is (t starts at the first row, as with a counter)."""
        index = self._last_index + 1 + self._unsent + np.flatnonzero(ok)
        if self._last_index < 0 and len(index):
            index -= index[0]
        step = np.diff(index, prepend=self._last_index)
        for i in np.flatnonzero(step > 1):
            lost = int(step[i] - 1)
            self.stats["lost_samples"] += lost
            self.notes.append(f"gap: {lost} samples lost before t={index[i] / self.sample_rate_hz:.6g} s (refused lines)")
        self._unsent = len(ok) - 1 - int(np.flatnonzero(ok)[-1]) if ok.any() else self._unsent + len(ok)
        return index

    def _consecutive(self, counter):
        """True when the counters continue the last one by exactly 1 each (in range, no wrap)."""
        first, last = counter[0], counter[-1]
        if self._last_counter is not None and first != self._last_counter + 1:
            return False
        if not (0 <= first and last < self._counter_mod and float(first).is_integer()):
            return False
        n = len(counter)
        return last - first == n - 1 and (n < 3 or bool((np.diff(counter) == 1).all()))

    def _rows(self, values, final=False):
        """Values per line (fields order) -> rows t, gx, gy, gz[, temp][, ax, ay, az]; counter bookkeeping.
        A line held by the last call comes first; ``final``: the stream ended, no line is held.

        A gyro value beyond +-MAX_RATE_DPS in deg/s, a temperature outside TEMP_RANGE_C, or a counter that is not an integer in
        [0, 2**counter_bits), refuses its line (``bad_lines``). Counters are at most 2**32 and the
        sample index an int64, so no step overflows."""
        fields = self.fields
        ok = self._in_range(values)
        index = None if "counter" in fields else self._uncounted(ok)
        values = values[ok]
        if self._held is not None and len(values):  # judged with the next line in range
            values, self._held = np.vstack((self._held, values)), None
        n = len(values)
        if "counter" in fields and n and self._consecutive(values[:, fields.index("counter")]):
            index = self._last_index + 1 + np.arange(n)  # the common case: no gap, no duplicate
            self._last_counter = int(values[-1, fields.index("counter")])
            self._last_index = int(index[-1])
        elif "counter" in fields:
            counter = values[:, fields.index("counter")]
            ok = (counter == np.round(counter)) & (counter >= 0) & (counter < self._counter_mod)
            if not ok.all():
                bad = counter[~ok]
                self._bad(repr(float(bad[0])).encode(), "bad_lines",
                          f"counter is not an integer in [0, {self._counter_mod})", count=len(bad), garbage_bytes=0)
                values, counter = values[ok], counter[ok]
                n = len(values)
            counter = counter.astype(np.int64)
            if n:
                keep = self._out_of_sequence(counter, values, final)
                values, counter = values[keep], counter[keep]
                n = len(values)
            prev = np.empty(n, dtype=np.int64)
            if n:
                prev[0] = counter[0] - 1 if self._last_counter is None else self._last_counter
                prev[1:] = counter[:-1]
            step = (counter - prev) % self._counter_mod
            keep = step != 0
            if not keep.all():
                self.stats["duplicates"] += int((~keep).sum())
                values, counter, prev, step = values[keep], counter[keep], prev[keep], step[keep]
                n = len(values)
            if n:
                restart = step >= self._counter_mod // 2
                jump = (step > 1) & ~restart
                step = np.where(restart, 1, step)
                index = self._last_index + np.cumsum(step)
                t = index / self.sample_rate_hz
                for i in np.flatnonzero(jump | restart):
                    if restart[i]:
                        self.stats["restarts"] += 1
                        self.notes.append(f"serial: device counter went back ({int(prev[i])} -> {int(counter[i])}); device restarted? t continues")
                    else:
                        lost = int(step[i] - 1)
                        self.stats["counter_jumps"] += 1
                        self.stats["lost_samples"] += lost
                        self.notes.append(f"gap: {lost} samples lost before t={t[i]:.6g} s (counter {int(prev[i])} -> {int(counter[i])})")
                self._last_counter = int(counter[-1])
                self._last_index = int(index[-1])
        elif n:
            self._last_index = int(index[-1])
        if n == 0:
            return self._empty()
        columns = self.columns
        rows = np.empty((n, len(columns)))
        rows[:, 0] = index / self.sample_rate_hz  # finite: a rate >= MIN_SAMPLE_RATE_HZ, an int64 index
        for j, name in enumerate(columns[1:], start=1):
            rows[:, j] = values[:, fields.index(name)]
        if "temp" in fields and self._temp_raw:
            rows[:, 4] = temperature_c(rows[:, 4])
        self.stats["samples"] += n
        return rows

    def _out_of_sequence(self, counter, values, final):
        """The lines to keep of ``counter`` (valid counters, in order: :func:`.counter.out_of_sequence`): the
        corrupt ones refused (``bad_lines``), and the last line, when its counter jumps and ``final`` is False,
        held (``_held``) until the next line tells."""
        keep, corrupt, last_jumps = out_of_sequence(counter, self._last_counter, self._counter_mod)
        for i, prev, after in corrupt:
            self._bad(str(int(counter[i])).encode(), "bad_lines",
                      f"out of sequence between {prev} and {after}: a corrupt counter", garbage_bytes=0)
        if last_jumps and not final:
            keep[-1], self._held = False, values[-1].copy()
        return keep

    def _in_range(self, values):
        """Which lines of ``values`` (per line, fields order) to keep (:func:`.fields.in_range`): the others are
        counted in ``bad_lines``, the first noted; one vectorised check per chunk. A glitched line then costs
        one sample, not the recording (the writers and the filter refuse such values)."""
        ok = in_range(values, self.fields, self.header, self._temp_raw)
        if not ok.all():
            shown = ",".join(map(format_number, values[np.argmin(ok)])).encode()
            self._bad(shown, "bad_lines", f"a gyro value beyond +-{MAX_RATE_DPS:g} deg/s, a temperature outside "
                      f"[{TEMP_RANGE_C[0]:g}, {TEMP_RANGE_C[1]:g}] deg C or an acceleration beyond +-{MAX_ACCEL_MPS2:g} m/s^2",
                      count=int(np.count_nonzero(~ok)), garbage_bytes=0)
        return ok

    def pop_notes(self):
        """Events since the last call (gaps, restarts, skipped lines, device messages), as a list
        of one-line strings; empties :attr:`notes`."""
        notes, self.notes = self.notes, []
        return notes
