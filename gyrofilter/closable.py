"""Closing once: what the live sources and the recording writer share.

``close()`` releases the object's resources the first time it is called and does nothing after;
leaving a ``with`` block closes, also on an exception (which is never swallowed).
"""


class Closable:
    """Base of :class:`gyrofilter.recording.RecordingWriter` and :class:`gyrofilter.sources.base.Source`.

    A subclass puts its clean-up (closing a file, a port, a bus) in :meth:`_close`.
    """

    _closed = False

    def _close(self):
        raise NotImplementedError

    def close(self):
        """Release the resources (the first call; later calls do nothing)."""
        if self._closed:
            return
        self._closed = True
        self._close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
