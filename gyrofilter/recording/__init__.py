"""Recording format version 1: reader and writers.

The format (docs/formats.md, section 1) is CSV text, optionally gzip-compressed::

    # gyrofilter-recording: 1
    # sample_rate_hz: 100
    # gyro_unit: lsb            (dps, rad/s or lsb)
    # lsb_per_dps: 131          (required when gyro_unit is lsb)
    # accel_unit: lsb           (m/s^2, g or lsb: with columns ax, ay, az)
    # lsb_per_g: 16384          (required when accel_unit is lsb)
    t,gx,gy,gz,temp,ax,ay,az
    0.00,12,-3,40,25.31,-120,88,16390

Header lines start with ``#`` and hold ``key: value``, each key once; unknown keys are kept;
numbers are plain decimal text (:func:`~gyrofilter.inputs.parse_number`). Columns ``gx, gy,
gz`` are required; ``t`` (s, strictly increasing, its typical step ``1 / sample_rate_hz`` within
5 %) and ``temp`` (deg C) are optional; ``ax, ay, az`` (a six-axis recording) are all three or
none, and with ``accel_unit`` in the header they are its accelerometer (without it they are
carried along as any other column, their unit unknown); any other column is carried along unchanged. Lines
starting with ``#`` after the column row are annotations (for example a gap note written by
``gyrofilter record``); they are kept in :attr:`Recording.notes` and are not samples, and
neither are blank lines. No line is longer than :data:`MAX_LINE_BYTES`.

Bad input never shifts, drops or invents samples: an empty cell, ``nan``, a short or long row, a
cell that is not a plain decimal number (``0.0_1``), damaged gzip data (a failed checksum too)
raise :class:`~gyrofilter.errors.RecordingError` naming the file, the line and the reason (user
text quoted short). The one tolerated defect is the one an interrupted recording leaves: a last
line without its line end, or a gzip stream that ends before its end marker. Those are reported
in :attr:`Recording.warnings` and every complete line is used. A UTF-8 byte-order mark before
the first line is ignored.

The writers (:class:`RecordingWriter`, :func:`write_recording`) write only what reads back:
one header writer (:func:`header_text`) checked by the reader's own checks, finite values only,
``t`` and raw data exactly (the shortest text of each float), header values and annotations on
one line.

:func:`iter_recording` reads a file in chunks of lines (memory: one chunk, whatever the
length of the file); :func:`read_recording` collects its chunks into a :class:`Recording`.

The modules, one concern each: ``header`` (keys, rules, column names, :func:`header_text`),
``content`` (:class:`Recording`, :class:`RecordingHead`, :class:`Note`), ``lines`` (the file
as lines of text, gzip or not), ``checks`` (the gyro values and the ``t`` column, shared by the
reader and the writers), ``reader`` and ``writer``. This package presents their public API.
"""
from .content import Note, Recording, RecordingHead, convert_gyro, warn_about_gaps
from .header import (ACCEL_COLUMNS, COLUMNS, END_NOTE, FORMAT_VERSION, GYRO_COLUMNS, MAX_HEADER_LINES, MAX_LINE_BYTES,
                     MAX_NOTE_CHARS, PROVENANCE_KEYS, FILTERED_FROM_KEY, INPUT_RATE_KEY, T_FROM_COUNTER, T_FROM_KEY, T_FROM_LINES,
                     TIME_WORDS, VERSION_KEY,
                     accel_header, accel_units_header,
                     contradiction, dps_header, filtered_from, filtered_words, format_number, header_text, misspelt_key, name_words, note_line, note_text, one_line_text, units_header)
from .reader import CHUNK_ROWS, collect_columns, iter_recording, read_recording
from .writer import EXACT_FORMAT, FILTERED_FORMAT, RecordingWriter, write_recording

__all__ = ["ACCEL_COLUMNS", "CHUNK_ROWS", "COLUMNS", "END_NOTE", "EXACT_FORMAT", "FILTERED_FORMAT", "FILTERED_FROM_KEY", "FORMAT_VERSION", "GYRO_COLUMNS",
           "INPUT_RATE_KEY", "MAX_HEADER_LINES", "MAX_LINE_BYTES", "MAX_NOTE_CHARS", "Note", "PROVENANCE_KEYS", "Recording", "RecordingHead",
           "RecordingWriter", "T_FROM_COUNTER", "T_FROM_KEY", "T_FROM_LINES", "TIME_WORDS", "VERSION_KEY", "accel_header", "accel_units_header", "collect_columns",
           "contradiction", "convert_gyro", "dps_header", "filtered_from", "filtered_words", "format_number", "header_text", "iter_recording", "misspelt_key", "name_words", "note_line", "note_text", "one_line_text",
           "read_recording", "units_header", "warn_about_gaps", "write_recording"]
