"""The comment lines of another tool's log before its first data row (``gyrofilter convert``).

A log's comments may state what the conversion is told otherwise: ``# sample_rate_hz: 200`` above a
log converted with ``--sample-rate-hz 100``, ``# gyro_unit: rad/s`` with ``--unit dps``. Skipped, the
file was written at the option's rate or unit without a word (attack pass 53, item 11). A comment
``key: value`` or ``key = value`` (after ``#`` or ``//``) before the first data row whose key states the
sample rate, the gyro's unit or sensitivity, or the accelerometer's unit (the one rule of a recording's
header keys, :func:`~gyrofilter.recording.header.contradicts`) must state what the conversion writes:
the rate given exactly, or within :data:`~gyrofilter.units.RATE_TOLERANCE` of the one the time column's
steps give (a logger's nominal rate beside its clock's). A comment whose value does not read as one
(``# rate: fast``) is prose and not judged, nor is a line of no key (``# logged at 200 Hz``) or a
comment after the first data row.
"""
from __future__ import annotations

import re

from ...errors import RecordingError
from ...inputs import quote
from ...units import RATE_TOLERANCE
from ..header import VERSION_KEY, contradicts, header_rates, statement

#: a comment line's ``key: value`` (or ``key = value``)
_KEY_VALUE = re.compile(r"\s*(?:#|//)[#/]*\s*(?P<key>[^:=]{1,64}?)\s*[:=]\s*(?P<value>.*?)\s*")
#: the option that gives each header key a comment may contradict, and where it comes from without it
_SOURCES = {"sample_rate_hz": ("--sample-rate-hz", "the time column's steps"), "gyro_unit": ("--unit", "the column names"),
            "lsb_per_dps": ("--lsb-per-dps", "--lsb-per-dps"), "accel_unit": ("--accel-unit", "the column names")}


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


class Comments:
    """The comments before a log's first data row that state a fact of the conversion (only those: a few
    tuples however long the preamble), :meth:`check`-ed against the header written."""

    def __init__(self):
        self.stated = []

    def add(self, number, text):
        """Keep the comment line ``number`` (``text``) if its ``key: value`` states a fact."""
        match = _KEY_VALUE.fullmatch(text)
        if match and statement(match["key"], match["value"]):
            self.stated.append((number, match["key"], match["value"]))

    def check(self, header, path, given):
        """Refuse with RecordingError naming the file, line and option where a comment contradicts ``header``, the
        conversion's, whose keys ``given`` (a set) the caller's options gave."""
        tolerance = 1e-9 if "sample_rate_hz" in given else RATE_TOLERANCE
        for number, key, value in self.stated:
            meant = contradicts(key, value, header, header_rates(header), tolerance)
            if meant and meant[1] is None:
                option, otherwise = _SOURCES[meant[0]]
                source = option if meant[0] in given else otherwise
                raise RecordingError(f"{path}: line {number}: the comment {quote(f'{key}: {value}')} disagrees with the "
                                     f"conversion's {meant[0]} {quote(header[meant[0]])} (from {source}); correct "
                                     + ("the option or " if meant[0] in given else "") + "the comment line")
