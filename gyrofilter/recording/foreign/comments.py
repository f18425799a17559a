"""The comment lines of another tool's log before its first data row (``gyrofilter convert``).

A log's comments may state what the conversion is told otherwise: ``# sample_rate_hz: 200`` above a
log converted with ``--sample-rate-hz 100``, ``# gyro_unit: rad/s`` with ``--unit dps``. Skipped, the
file was written at the option's rate or unit without a word (attack pass 53, item 11). Each
``key: value`` of a comment (after ``#`` or ``//``; also ``key = value``, ``:=``, ``=>``, several in one
line, :func:`~gyrofilter.recording.statements.pairs`; NFKC first) before the first data row whose key states the sample rate, the gyro's unit or
sensitivity, or the accelerometer's unit (the one rule of a recording's header keys,
:func:`~gyrofilter.recording.header.contradicts`) must state the unit read (``mdps``, not the ``dps`` it
is written in) and the rate given exactly, or within :data:`~gyrofilter.units.RATE_TOLERANCE` of the one
the time column's steps give (a logger's nominal rate beside its clock's). A value that does not read
(``# Sampling rate: Fastest``, ``200,0 Hz``) is prose, as is a line of no key (``# logged at 200 Hz``) and a
comment after the first data row: a comment is a check, never a source of the conversion's facts. At most :data:`MAX_STATEMENTS`
different ones are kept (a preamble of millions is refused, not held).
"""
from __future__ import annotations

import functools
import re

from ...errors import RecordingError
from ...inputs import is_plain_number, quote
from ...units import RATE_TOLERANCE
from ..header import VERSION_KEY, contradicts, header_rates, statement
from ..statements import normal_text, pairs

#: the comment marks (``#``, ``//``, ``##``, ``# *``) before a comment's text
_MARK = re.compile(r"\s*(?:#|//)[#/!*\-=\s]*")
#: most different statements kept from a log's comments
MAX_STATEMENTS = 1000
#: the option that gives each header key a comment may contradict, and where it comes from without it
_SOURCES = {"sample_rate_hz": ("--sample-rate-hz", "the time column's steps"), "gyro_unit": ("--unit", "the column names"),
            "lsb_per_dps": ("--lsb-per-dps", "--lsb-per-dps"), "accel_unit": ("--accel-unit", "the column names"),
            "lsb_per_g": ("--lsb-per-g", "--lsb-per-g"), "temp_unit": ("--temp-unit", "the column's name, else deg C")}
#: how a sensitivity written without a unit is read (``# sensitivity: 0.0153``: 0.0153 LSB per deg/s, not 1 / 0.0153)
_BARE_SENSITIVITY = {"lsb_per_dps": ", a sensitivity without a unit read as LSB per deg/s",
                     "lsb_per_g": ", a sensitivity without a unit read as LSB per g"}


def refuse_recording(text, number, path):
    """Refuse the log ``path`` when ``text``, its line ``number`` before the column row, is a
    recording's version line (``# gyrofilter-recording: 1``, the header line of section 1): a
    recording's header would be skipped as comments, its ``gyro_unit`` and ``lsb_per_dps`` with
    it (``--unit dps`` on LSB: 131 times the rate) and a filtered output's ``filtered_from``, while
    every command reads the recording as it is."""
    body = text.lstrip()
    if body.startswith("#") and body[1:].partition(":")[0].strip() == VERSION_KEY:
        raise RecordingError(f"{path}: line {number}: already a gyrofilter recording (format v1; every command reads it "
                             "as it is): convert is for other tools' logs")


def _statements(text):
    """The ``(key, value)`` of comment ``text`` that state a fact (:func:`~gyrofilter.recording.header.statement`)."""
    return _short_statements(text) if len(text) <= 256 else _read_statements(text)


def _read_statements(text):
    """:func:`_statements`, each different pair read once."""
    body = _MARK.sub("", normal_text(text), count=1)
    return tuple((key, value) for key, value in dict.fromkeys(pairs(body)) if statement(key, value))


#: :func:`_read_statements` of a short line, cached: a preamble of one line repeated costs one reading
_short_statements = functools.lru_cache(maxsize=4096)(_read_statements)


class Comments:
    """The comments before a log's first data row that state a fact of the conversion (only those, each
    different one once), :meth:`check`-ed against the header written."""

    def __init__(self, path):
        self.path, self.stated = path, {}

    def add(self, number, text):
        """Keep the comment line ``number`` (``text``) if it states a fact."""
        for pair in _statements(text):
            if pair not in self.stated:
                if len(self.stated) == MAX_STATEMENTS:
                    raise RecordingError(f"{self.path}: line {number}: more than {MAX_STATEMENTS} different comments "
                                         "before the first data row state the rate or a unit; remove them")
                self.stated[pair] = number, text.strip()

    def check(self, header, given):
        """Refuse with RecordingError naming the file, line and option where a comment contradicts ``header`` (the
        conversion's, with the units read: ``mdps``, not ``dps``), whose keys ``given`` (a set) the options gave."""
        tolerance, rates = 1e-9 if "sample_rate_hz" in given else RATE_TOLERANCE, header_rates(header)
        for (key, value), (number, text) in self.stated.items():
            meant = contradicts(key, value, header, rates, tolerance)
            if meant and meant[1] is None:  # a value that does not read (Sampling rate: Fastest) is prose
                fact, read = meant[0], statement(key, value)[2]
                option, otherwise = _SOURCES[fact]
                read = f" (read as {quote(read)})" if read != normal_text(value) else ""  # sensitivity_mdps: 70 mdps/lsb
                raise RecordingError(f"{self.path}: line {number}: the comment {quote(text[:100])}{read} disagrees with the conversion's "
                                     f"{fact} {quote(header[fact])} (from {option if fact in given else otherwise})"
                                     + _BARE_SENSITIVITY.get(fact, "") * (not read and is_plain_number(normal_text(value)))
                                     + "; correct " + ("the option or " if fact in given else "") + "the comment line")
