"""Exceptions raised by gyrofilter.

Library code raises these; only the command line catches them and prints one line.
Every message names what was wrong and where (file and line, register, setting).
"""
import contextlib
import os


class GyroFilterError(Exception):
    """Base class: a problem the user can act on (bad input, bad setting, device fault)."""


class SettingsError(GyroFilterError, ValueError):
    """A setting or an argument (a sample, an array) is out of range, mis-shaped or inconsistent."""


class SampleError(SettingsError):
    """A sample (or its temperature) refused by ``GyroFilter.update()`` / ``filter()``, which leave
    the filter as it was. ``row``: its index in the call's samples (0 for ``update()``), so that
    the caller's own index of it is ``filter.samples_in + row``; ``reason``: the message without
    the row, for a caller that names the file and line instead."""

    def __init__(self, reason, row=0, where="sample"):
        super().__init__(f"{where}: {reason}")
        self.row = row
        self.reason = reason


class FilterDiverged(GyroFilterError):
    """The filter's output left the rates any gyro reads (beyond +-MAX_RATE_DPS deg/s, or not finite) on
    samples it took (the paper's filter on fast motion: attack pass 68), raised by ``GyroFilter.update()`` /
    ``filter()`` / ``filter_timed()`` once they have taken the call's samples. ``rows``: the call's rows before
    that one, good (``t_rows_s``: their times, from ``filter_timed()``; else None); ``sample``: the index of that
    row's block's last sample among all the filter took (0 for its first); ``reason``: the message without where;
    ``rows_computed``: every row the call computed, that one and those after it too: what a diverged filter gave, to
    measure how far it went (the evaluation's RMSE, ``gyrofilter.evaluation.filters``), never an output's."""

    def __init__(self, reason, rows, sample, rows_computed):
        super().__init__(f"sample {sample}: {reason}")
        self.reason, self.rows, self.sample, self.t_rows_s = reason, rows, sample, None
        self.rows_computed = rows_computed


class RecordingError(GyroFilterError, ValueError):
    """A recording file is malformed: the message names the file, the line and the reason."""


class NotStillError(RecordingError):
    """A still-sensor analysis refused a recording whose gyro moved
    (:func:`gyrofilter.analysis.still.refuse_moved`): a fleet skips it as not still, not as failed."""


class CalibrationError(GyroFilterError):
    """Start-up bias calibration failed (for example the sensor moved while calibrating).
    ``max_bias_dps``: the value of the filter setting that takes a bias refused as beyond it (the message's
    way through, :func:`gyrofilter.filter.calibration.raise_max_bias`), or None."""

    def __init__(self, message, max_bias_dps=None):
        super().__init__(message)
        self.max_bias_dps = max_bias_dps


class MissingExtraError(GyroFilterError):
    """An optional package is not installed: the message names the extra that installs it."""


class DeviceError(GyroFilterError):
    """A sensor or port could not be opened, identified or read."""


class SourceEnded(Exception):
    """A finite source (replay file, simulation, closed port) has delivered its last sample."""


@contextlib.contextmanager
def naming_file(path):
    """Writing the file ``path``: an OSError that names no file (a full disk or a file size limit
    met at a write or a close, or inside a writer such as an image library) names ``path``, so that
    the one-line error says which file could not be written, not only the folder it was in."""
    try:
        yield
    except OSError as exc:
        if exc.filename is None:
            raise OSError(exc.errno, exc.strerror or str(exc), os.fspath(path)) from None
        raise


def one_line(exc):
    """An exception as one line: "FILE: reason" for an OSError that names a file, else its text."""
    if isinstance(exc, OSError) and exc.filename:
        text = f"{exc.filename}: {exc.strerror or exc}"
    else:
        text = str(exc) or type(exc).__name__
    return " ".join(text.split())
