"""The base of every live source: the protocol of :mod:`gyrofilter.sources` in one class."""
from __future__ import annotations

import numpy as np

from ..closable import Closable
from ..recording import GYRO_COLUMNS
from ..units import to_dps

WARNING_PREFIX = "warning: "  # starts a note that is a warning (a replayed file cut short)


class Source(Closable):
    """A live source (see :mod:`gyrofilter.sources` for the protocol).

    A subclass sets, once the units are known: ``sample_rate_hz`` (float, Hz: the number the
    source's ``t`` is made from, not its header text), ``gyro_unit`` (``dps``, ``rad/s`` or
    ``lsb``) and ``lsb_per_dps`` (float with ``lsb``, else None); ``header``, ``columns`` and
    ``stats``; ``read()``; it appends its events to ``self._notes`` and puts its clean-up in
    ``_close()``.
    """

    sample_rate_hz: float
    gyro_unit: str
    lsb_per_dps: float | None = None

    def finish(self):
        """The rows held back waiting for more input, given out at a stop as at the end of the
        stream (shape (n, len(columns))); none unless a subclass holds some."""
        return np.empty((0, len(self.columns)))

    def pop_notes(self):
        """Events since the last call (gaps, restarts, device messages), as one-line strings."""
        notes, self._notes = self._notes, []
        return notes

    def gyro_dps(self, rows):
        """Angular rate of ``rows`` (as ``read()`` returns them), shape (n, 3), in deg/s."""
        return to_dps(rows[:, [self.columns.index(c) for c in GYRO_COLUMNS]], self.gyro_unit, self.lsb_per_dps)
